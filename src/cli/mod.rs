//! The command line: the arguments are resolved once into an [`Action`],
//! what this run does, and [`run`] dispatches it. Clap types stop here:
//! `args.rs` holds them, `options.rs` turns them into a
//! [`crate::config::Config`], and each command has its own file.

mod args;
mod check;
mod completions;
mod flatten;
mod man;
mod options;
mod plot;
mod stats;
mod targets;

use std::process::ExitCode;

pub use args::Cli;

use crate::config::Config;
use crate::diag::{Diagnostic, ErrorKind, MessageFormat, report, report_summary, write_stderr};

/// What one run does, resolved from the arguments.
enum Action {
    /// `ngcflat targets`, or `--target list`.
    Targets,
    /// `ngcflat targets --show NAME`.
    ShowTarget(String),
    /// `ngcflat completions SHELL`.
    Completions(clap_complete::Shell),
    /// `ngcflat man`.
    Man,
    /// Flattening one program (no subcommand).
    Flatten(flatten::Job, Box<Config>),
    /// `ngcflat check`.
    Check(check::Job, Box<Config>),
    /// `ngcflat stats`.
    Stats(stats::Job, Box<Config>),
    /// `ngcflat plot`.
    Plot(plot::Job, Box<Config>),
    /// The configuration is wrong: reported as a diagnostic, exit status 2.
    SetupError {
        kind: ErrorKind,
        format: MessageFormat,
        /// Whether the summary is `check`'s.
        check: bool,
    },
}

/// The command-line program: the process's arguments.
pub fn main() -> ExitCode {
    run(Cli::from_env())
}

/// The command-line program.
pub fn run(cli: Cli) -> ExitCode {
    crate::emit::interrupt::install();
    match resolve(cli) {
        Ok(action) => dispatch(action),
        Err(e) => {
            // Usage and configuration problems: exit status 2.
            write_stderr(&format!("error: {e:#}\n"));
            ExitCode::from(2)
        }
    }
}

/// The CLI edge: configuration problems become `anyhow` errors with context;
/// program problems are diagnostics.
fn resolve(cli: Cli) -> anyhow::Result<Action> {
    use args::Command;
    let env_path = std::env::var("NGCFLAT_SUBROUTINE_PATH").ok();
    let list = |name: Option<String>| name.is_some_and(|n| n.eq_ignore_ascii_case("list"));
    match &cli.command {
        Some(Command::Check(a)) if list(a.common.target_name()) => return Ok(Action::Targets),
        None if list(cli.flatten.common.target_name()) => return Ok(Action::Targets),
        _ => {}
    }
    let setup_error = |kind, common: &args::CommonArgs, check| Action::SetupError {
        kind,
        format: common.format(),
        check,
    };
    Ok(match cli.command {
        Some(Command::Targets(a)) => a.show.clone().map_or(Action::Targets, Action::ShowTarget),
        Some(Command::Completions { shell }) => Action::Completions(shell),
        Some(Command::Man) => Action::Man,
        Some(Command::Check(args)) => match args.common.to_config(env_path) {
            Ok(cfg) => Action::Check(check::Job::from(*args), Box::new(cfg)),
            Err(k) => setup_error(k, &args.common, true),
        },
        Some(Command::Stats(args)) => match args.common.to_config(env_path) {
            Ok(cfg) => Action::Stats(stats::Job::from(args), Box::new(cfg)),
            Err(k) => setup_error(k, &args.common, false),
        },
        Some(Command::Plot(args)) => match args.common.to_config(env_path) {
            Ok(cfg) => Action::Plot(plot::Job::from(args), Box::new(cfg)),
            Err(k) => setup_error(k, &args.common, false),
        },
        None => match cli.flatten.common.to_config(env_path) {
            Ok(cfg) => Action::Flatten(flatten::Job::from(cli.flatten), Box::new(cfg)),
            Err(k) => setup_error(k, &cli.flatten.common, false),
        },
    })
}

/// Runs what the arguments asked for.
fn dispatch(action: Action) -> ExitCode {
    match action {
        Action::Targets => targets::run(),
        Action::ShowTarget(name) => targets::show(&name),
        Action::Completions(shell) => completions::run(shell),
        Action::Man => man::run(),
        Action::Flatten(job, cfg) => flatten::run(job, *cfg),
        Action::Check(job, cfg) => check::run(&job, &cfg),
        Action::Stats(job, cfg) => stats::run(&job, &cfg),
        Action::Plot(job, cfg) => plot::run(&job, &cfg),
        Action::SetupError {
            kind,
            format,
            check,
        } => setup_error(kind, format, check),
    }
}

/// A configuration problem found before any program ran: exit status 2.
fn setup_error(k: ErrorKind, format: MessageFormat, check: bool) -> ExitCode {
    report(&[*Diagnostic::error(k, None)], format);
    report_summary(0, 1, 0, 2, format, check);
    ExitCode::from(2)
}

/// Writes generated text (a completion script, the manual page) to stdout;
/// a closed pipe is success.
fn write_stdout(write: impl FnOnce(&mut dyn std::io::Write) -> std::io::Result<()>) -> ExitCode {
    let mut out = std::io::stdout().lock();
    match write(&mut out) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => ExitCode::SUCCESS,
        Err(e) => {
            write_stderr(&format!("ngcflat: writing to stdout: {e}\n"));
            ExitCode::from(2)
        }
    }
}
