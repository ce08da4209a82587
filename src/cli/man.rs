//! `ngcflat man`: the manual page (roff) on stdout.

use std::process::ExitCode;

use clap::CommandFactory;

use super::Cli;

pub(super) fn run() -> ExitCode {
    super::write_stdout(|out| clap_mangen::Man::new(Cli::command()).render(out))
}
