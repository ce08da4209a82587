//! `ngcflat completions SHELL`: a shell completion script on stdout.

use std::process::ExitCode;

use clap::CommandFactory;

use super::Cli;

pub(super) fn run(shell: clap_complete::Shell) -> ExitCode {
    super::write_stdout(|out| {
        clap_complete::generate(shell, &mut Cli::command(), "ngcflat", out);
        Ok(())
    })
}
