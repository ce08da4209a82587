//! `ngcflat stats`: the statistics of a program's motion.

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

use crate::config::Config;
use crate::view::run::{Observer, program_name, run_for_view, target_name};

/// What `stats` was asked for.
pub(super) struct Job {
    /// The program; stdin when absent or `-`.
    file: Option<PathBuf>,
    /// JSON instead of text.
    json: bool,
    /// No run-time estimate.
    no_time: bool,
}

impl From<super::args::StatsArgs> for Job {
    fn from(a: super::args::StatsArgs) -> Job {
        Job {
            file: a.file,
            json: a.json,
            no_time: a.no_time,
        }
    }
}

pub(super) fn run(job: &Job, cfg: &Config) -> ExitCode {
    let file = job.file.as_deref();
    let mut observer = Observer::stats(&cfg.machine, target_name(cfg), None);
    if job.no_time
        && let Some(s) = &mut observer.stats
    {
        s.run_time = crate::runtime::RunTime::new(crate::runtime::TimeModel::Off);
    }
    let obs = match run_for_view(file, cfg, observer) {
        Ok((o, _)) => o,
        Err(code) => return code,
    };
    let Some(stats) = obs.stats else {
        return ExitCode::from(2);
    };
    let report = stats.report(&program_name(file));
    let text = if job.json {
        report.json()
    } else {
        report.text()
    };
    let mut out = std::io::stdout().lock();
    if out
        .write_all(text.as_bytes())
        .and_then(|_| out.flush())
        .is_err()
    {
        return ExitCode::from(2);
    }
    ExitCode::SUCCESS
}
