//! `ngcflat plot`: the toolpath as SVG, or an HTML page with the statistics.

use crate::diag::SetupError;
use std::path::PathBuf;
use std::process::ExitCode;

use super::args::ViewArg;
use crate::config::Config;
use crate::diag::{Diagnostic, ErrorKind, report};
use crate::view::plot::View;
use crate::view::run::{Observer, program_name, run_for_view, target_name, write_atomic};

/// What `plot` was asked for.
pub(super) struct Job {
    /// The program; stdin when absent or `-`.
    file: Option<PathBuf>,
    /// The picture: FILE.svg, or FILE.html.
    output: PathBuf,
    /// Which way to look at the toolpath.
    view: View,
    /// Open the written file in the desktop's browser or viewer.
    open: bool,
}

impl From<super::args::PlotArgs> for Job {
    fn from(a: super::args::PlotArgs) -> Job {
        let view = match a.view {
            ViewArg::Xy => View::Xy,
            ViewArg::Xz => View::Xz,
            ViewArg::Yz => View::Yz,
            ViewArg::Iso => View::Iso,
        };
        Job {
            file: a.file,
            output: a.output,
            view,
            open: a.open,
        }
    }
}

pub(super) fn run(job: &Job, cfg: &Config) -> ExitCode {
    let (file, output) = (job.file.as_deref(), job.output.as_path());
    if crate::flatten::same_file(output, file) {
        report(
            &[*Diagnostic::error(
                ErrorKind::Setup(SetupError::OutputIsInput {
                    output: output.to_path_buf(),
                }),
                None,
            )],
            cfg.format,
        );
        return ExitCode::from(2);
    }
    let html = output
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("html") || e.eq_ignore_ascii_case("htm"));
    let observer = if html {
        Observer::scene(&cfg.machine, target_name(cfg))
    } else {
        Observer::stats(&cfg.machine, target_name(cfg), Some(job.view))
    };
    let (obs, warnings) = match run_for_view(file, cfg, observer) {
        Ok(o) => o,
        Err(code) => return code,
    };
    let name = program_name(file);
    let data = match (obs.stats, obs.plot, obs.scene) {
        (Some(stats), _, Some(mut scene)) if html => {
            scene.finish();
            crate::view::html::page(&stats.report(&name), &scene, &warnings)
        }
        (Some(_), Some(plot), _) => plot.svg(&name),
        _ => return ExitCode::from(2),
    };
    let io_error = |message: String| {
        report(
            &[*Diagnostic::error(
                ErrorKind::Setup(SetupError::Io {
                    path: output.to_path_buf(),
                    message,
                }),
                None,
            )],
            cfg.format,
        );
        ExitCode::from(2)
    };
    if let Err(e) = write_atomic(output, data.as_bytes()) {
        return io_error(e.to_string());
    }
    if job.open {
        // An absolute path: the openers take a leading '-' for an option.
        let opened = std::path::absolute(output).and_then(open::that_detached);
        if let Err(e) = opened {
            return io_error(format!(
                "written, but no browser or viewer could be started for it ({e})"
            ));
        }
    }
    ExitCode::SUCCESS
}
