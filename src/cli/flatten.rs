//! Flattening one program: the command without a subcommand.

use crate::diag::SetupError;
use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;

use crate::config::Config;
use crate::diag::{self, Diagnostic, ErrorKind, MessageFormat, report, report_summary};
use crate::emit::Destination;
use crate::flatten::{lowering, read_source_limited, refuse_binary};

/// What flattening was asked for.
pub(super) struct Job {
    /// The program; stdin when absent or `-`.
    file: Option<PathBuf>,
    /// Where the result goes; stdout when absent.
    output: Option<PathBuf>,
    /// Where the source map goes, if one is asked for.
    source_map: Option<PathBuf>,
    /// Whether each line names its origin in a comment.
    annotate: bool,
}

impl From<super::args::FlattenArgs> for Job {
    fn from(a: super::args::FlattenArgs) -> Job {
        Job {
            file: a.file,
            output: a.output,
            source_map: a.source_map,
            annotate: a.annotate,
        }
    }
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
        Some(
            ErrorKind::Setup(SetupError::Io { .. }) | ErrorKind::Setup(SetupError::NotText { .. }),
        ) => 2,
        _ => 1,
    }
}

/// Reports the outcome of flattening one program and gives its exit code.
fn finish(diags: &[Diagnostic], code: u8, format: MessageFormat) -> ExitCode {
    report(diags, format);
    let errors = diags
        .iter()
        .filter(|d| d.level() == diag::Level::Error)
        .count();
    report_summary(1, errors, diags.len() - errors, code, format, false);
    ExitCode::from(code)
}

pub(super) fn run(job: Job, mut cfg: Config) -> ExitCode {
    // Configuration warnings come first, counted in the summary.
    let with_config = |mut d: Vec<Diagnostic>| {
        let mut all = cfg.warnings.clone();
        all.append(&mut d);
        all
    };
    let source = match read_source_limited(job.file.as_deref(), cfg.settings.input)
        .and_then(|s| refuse_binary(&s).map(|()| s))
    {
        Ok(s) => s,
        Err(e) => return finish(&with_config(vec![*e]), 2, cfg.format),
    };
    cfg.settings.progress = progress_delay();
    let dest = match job.output {
        Some(p) => {
            if crate::flatten::same_file(&p, job.file.as_deref()) {
                let k = ErrorKind::Setup(SetupError::OutputIsInput { output: p });
                return super::setup_error(k, cfg.format, false);
            }
            Destination::File(p)
        }
        None => Destination::Stdout,
    };
    let consumer = lowering(&cfg.settings, cfg.target.clone());
    let extras = crate::view::run::Extras {
        source_map: job.source_map,
        annotate: job.annotate,
    };
    let r = crate::view::run::flatten_chained(
        source,
        &cfg.settings,
        &cfg.search,
        dest,
        &cfg,
        &extras,
        consumer,
    );
    match r {
        (warnings, None) => finish(&with_config(warnings), 0, cfg.format),
        (_, Some(e)) => {
            let code = exit_for(&e);
            finish(&with_config(vec![*e]), code, cfg.format)
        }
    }
}
