//! ngcflat: LinuxCNC-dialect G-code in, straight-line G-code out.
//!
//! Pipeline: `source` (program text) → [`parse`] (typed line AST) →
//! [`program`] (file index, subroutine loader) → [`eval`] (machine state,
//! control flow, parameters and expressions) → [`emit`] (numbers, output
//! sink), or a consumer: [`controller`] lowering, `view`. The `flatten` module ties
//! them together; [`diag`] holds every error and warning. The modules form
//! layers without cycles, listed in the README's Design section.

#![deny(unreachable_pub)]

pub mod block;
mod check;
mod codes;
pub mod config;
pub mod controller;
pub mod diag;
pub mod emit;
pub mod eval;
mod flatten;
mod fx_hasher;
pub mod geom;
mod library;
mod machine;
mod modes;
mod number;
pub mod parse;
pub mod program;
mod source;
mod view;

use std::io::IsTerminal;

pub use diag::{report, report_summary, write_stderr};
pub use flatten::{
    flatten, flatten_memory, flatten_str, flatten_with, lowering, read_source, read_source_limited,
    refuse_binary,
};
use std::process::ExitCode;

use diag::{Diagnostic, ErrorKind, MessageFormat};
use emit::Destination;

/// `ngcflat targets`: the profiles with their limits.
fn print_targets() -> ExitCode {
    let mut s = String::new();
    for p in controller::PROFILES {
        s.push_str(&p.describe());
        s.push('\n');
    }
    print!("{s}");
    ExitCode::SUCCESS
}

/// Progress is shown only when stderr is a terminal that is not `dumb`
/// (never in pipes, files or CI logs), after one second of work.
fn progress_delay() -> Option<std::time::Duration> {
    let term_ok = std::env::var_os("TERM").is_none_or(|t| t != "dumb");
    if !(std::io::stderr().is_terminal() && term_ok) {
        return None;
    }
    let ms = std::env::var("NGCFLAT_TEST_PROGRESS_MS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1000);
    Some(std::time::Duration::from_millis(ms))
}

fn exit_for(e: &Diagnostic) -> u8 {
    match e.error_kind() {
        Some(ErrorKind::Io { .. } | ErrorKind::NotText { .. }) => 2,
        _ => 1,
    }
}

/// The command-line program.
pub fn run(cli: config::Cli) -> ExitCode {
    emit::interrupt::install();
    match run_cli(cli) {
        Ok(code) => code,
        Err(e) => {
            // Usage and configuration problems: exit status 2.
            write_stderr(&format!("error: {e:#}\n"));
            ExitCode::from(2)
        }
    }
}

fn setup_error(k: ErrorKind, format: MessageFormat, check: bool) -> ExitCode {
    report(&[*Diagnostic::error(k, None)], format);
    report_summary(0, 1, 0, 2, format, check);
    ExitCode::from(2)
}

/// Reports the outcome of flattening one program and gives its exit code.
fn finish_flatten(diags: &[Diagnostic], code: u8, format: MessageFormat) -> ExitCode {
    report(diags, format);
    let errors = diags
        .iter()
        .filter(|d| d.level() == diag::Level::Error)
        .count();
    report_summary(1, errors, diags.len() - errors, code, format, false);
    ExitCode::from(code)
}

/// The CLI edge: configuration problems become `anyhow` errors with context;
/// program problems are diagnostics.
fn run_cli(cli: config::Cli) -> anyhow::Result<ExitCode> {
    let env_path = std::env::var("NGCFLAT_SUBROUTINE_PATH").ok();
    let common = match &cli.command {
        Some(config::Command::Check(args)) => &args.common,
        Some(config::Command::Stats(args)) => &args.common,
        Some(config::Command::Plot(args)) => &args.common,
        Some(config::Command::Targets) => return Ok(print_targets()),
        _ => &cli.flatten.common,
    };
    parse::named2007::enable(common.named_params_2007);
    let list = |name: Option<String>| name.is_some_and(|n| n.eq_ignore_ascii_case("list"));
    match &cli.command {
        Some(config::Command::Targets) => return Ok(print_targets()),
        Some(config::Command::Check(a)) if list(a.common.target_name()) => {
            return Ok(print_targets());
        }
        None if list(cli.flatten.common.target_name()) => return Ok(print_targets()),
        _ => {}
    }
    Ok(match cli.command {
        Some(config::Command::Targets) => print_targets(),
        Some(cmd @ (config::Command::Completions { .. } | config::Command::Man)) => {
            write_generated(&cmd)
        }
        Some(config::Command::Check(args)) => match args.common.to_config(env_path) {
            Ok(cfg) => check::run(&args.paths, &args.ext, args.deny_warnings, &cfg),
            Err(k) => setup_error(k, args.common.format(), true),
        },
        Some(config::Command::Stats(args)) => match args.common.to_config(env_path) {
            Ok(cfg) => view::run::stats_command(args.file.as_deref(), args.json, &cfg),
            Err(k) => setup_error(k, args.common.format(), false),
        },
        Some(config::Command::Plot(args)) => match args.common.to_config(env_path) {
            Ok(cfg) => plot_command(&args, &cfg),
            Err(k) => setup_error(k, args.common.format(), false),
        },
        None => {
            let args = cli.flatten;
            match args.common.to_config(env_path) {
                Ok(cfg) => flatten_command(args, cfg),
                Err(k) => setup_error(k, args.common.format(), false),
            }
        }
    })
}

/// `ngcflat completions SHELL` and `ngcflat man`: the generated text on
/// stdout.
fn write_generated(cmd: &config::Command) -> ExitCode {
    let mut out = std::io::stdout().lock();
    match config::write_generated(cmd, &mut out) {
        Ok(_) => ExitCode::SUCCESS,
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => ExitCode::SUCCESS,
        Err(e) => {
            write_stderr(&format!("ngcflat: writing to stdout: {e}\n"));
            ExitCode::from(2)
        }
    }
}

/// `ngcflat plot`.
fn plot_command(args: &config::PlotArgs, cfg: &config::Config) -> ExitCode {
    let view = match args.view {
        config::ViewArg::Xy => view::plot::View::Xy,
        config::ViewArg::Xz => view::plot::View::Xz,
        config::ViewArg::Yz => view::plot::View::Yz,
        config::ViewArg::Iso => view::plot::View::Iso,
    };
    view::run::plot_command(args.file.as_deref(), &args.output, view, cfg)
}

/// Flattening one program (the command without a subcommand).
fn flatten_command(args: config::FlattenArgs, mut cfg: config::Config) -> ExitCode {
    // Configuration warnings come first, counted in the summary.
    let with_config = |mut d: Vec<Diagnostic>| {
        let mut all = cfg.warnings.clone();
        all.append(&mut d);
        all
    };
    let source = match read_source_limited(args.file.as_deref(), cfg.settings.input)
        .and_then(|s| refuse_binary(&s).map(|()| s))
    {
        Ok(s) => s,
        Err(e) => return finish_flatten(&with_config(vec![*e]), 2, cfg.format),
    };
    cfg.settings.progress = progress_delay();
    let dest = match args.output {
        Some(p) => {
            if flatten::same_file(&p, args.file.as_deref()) {
                let k = ErrorKind::OutputIsInput { output: p };
                return setup_error(k, cfg.format, false);
            }
            Destination::File(p)
        }
        None => Destination::Stdout,
    };
    let consumer = lowering(&cfg.settings, cfg.target.clone());
    if consumer.is_some() && (args.source_map.is_some() || args.annotate) {
        let k = ErrorKind::SourceMapNeedsLinuxcnc;
        return setup_error(k, cfg.format, false);
    }
    let extras = view::run::Extras {
        source_map: args.source_map,
        annotate: args.annotate,
    };
    let r = view::run::flatten_chained(
        source,
        &cfg.settings,
        &cfg.search,
        dest,
        &cfg,
        &extras,
        consumer,
    );
    match r {
        (warnings, None) => finish_flatten(&with_config(warnings), 0, cfg.format),
        (_, Some(e)) => {
            let code = exit_for(&e);
            finish_flatten(&with_config(vec![*e]), code, cfg.format)
        }
    }
}
