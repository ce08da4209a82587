//! The output: lines written, their count against the limits, progress, and
//! the consumer that may take them instead.

pub(super) mod apart;
pub(super) mod hook;
pub(super) mod progress;

use crate::diag::{LimitError, SetupError};
use std::sync::Arc;

use crate::diag::{Diagnostic, Error, ErrorKind, Kind, Site};
use crate::emit::{Output, Sink};
use crate::program::SourceFile;

use crate::settings::Settings;

/// Where the executed lines go, and how many went.
pub(super) struct Writer<'s> {
    pub(super) output: Output,
    /// The line being built.
    pub(super) buf: Vec<u8>,
    /// Lines written.
    pub(super) lines: u64,
    /// Output lines allowed: `--max-output-lines` plus the main file's own
    /// line count, so that the guard counts generated lines, not lines
    /// copied from the input.
    pub(super) budget: u64,
    /// Line count at which `count_line` looks further: the output limit,
    /// or earlier, the next progress update.
    pub(super) check: u64,
    pub(super) progress: Option<progress::Progress>,
    /// The program has ended (M2/M30 or the closing `%`).
    pub(super) ended: bool,
    /// Reads every output line instead of the output (see [`hook`]).
    pub(super) consumer: Option<Box<dyn hook::LineConsumer + 's>>,
    /// The consumer moved to a second thread: lines go to it through this
    /// queue (see [`apart`]).
    pub(super) apart: Option<apart::Apart>,
    /// Lines handed to the consumer on this thread, but for those of
    /// straight runs (see `Interp::step`).
    pub(super) handed: usize,
    /// Lines handed after which the consumer moves to a thread
    /// (`usize::MAX`: never, or not again).
    pub(super) apart_after: usize,
    /// Lines of moves alone a straight run holds back to hand over at once.
    pub(in crate::eval) forms: hook::FormBatch,
}

impl<'s> Writer<'s> {
    /// `main_lines`: the main file's line count.
    pub(super) fn new(sink: Sink, s: &Settings, main_lines: u32) -> Writer<'s> {
        let budget = s.max_output_lines.saturating_add(u64::from(main_lines));
        Writer {
            output: Output::new(sink, s.precision, s.format_thread_after),
            buf: Vec::with_capacity(256),
            lines: 0,
            budget,
            check: if s.progress.is_some() {
                budget.min(progress::EVERY)
            } else {
                budget
            },
            progress: s.progress.map(progress::Progress::new),
            ended: false,
            consumer: None,
            apart: None,
            handed: 0,
            apart_after: usize::MAX,
            forms: hook::FormBatch::default(),
        }
    }

    /// Lines go to a consumer (on this thread or apart), not the output.
    #[inline]
    pub(super) fn consuming(&self) -> bool {
        self.consumer.is_some() || self.apart.is_some()
    }

    /// Counts a line about to be written; true when the limit or a
    /// progress update is due (see [`Writer::checkpoint`]).
    #[inline]
    pub(super) fn count_line(&mut self) -> bool {
        self.count_lines(1)
    }

    /// Lines that may still be written before the output's limit.
    pub(super) fn lines_left(&self) -> u64 {
        self.budget.saturating_sub(self.lines)
    }

    /// Counts `n` lines written at once (see [`Writer::count_line`]).
    #[inline]
    pub(super) fn count_lines(&mut self, n: u64) -> bool {
        self.lines += n;
        self.lines > self.check
    }

    /// At a due check: false when the output is past its limit, else
    /// updates the progress (`line`: 1-based line being run in `file`).
    #[cold]
    pub(super) fn checkpoint(&mut self, line: u32, file: &str) -> bool {
        if self.lines > self.budget {
            return false;
        }
        if let Some(p) = &mut self.progress {
            p.tick(self.lines, line, file);
            self.check = self.budget.min(self.lines + progress::EVERY);
        }
        true
    }
}

/// The output grew past `--max-output-bytes`: the sink's account of it.
pub(super) fn too_large(e: &std::io::Error) -> Option<&crate::emit::OutputTooLarge> {
    e.get_ref()
        .and_then(|i| i.downcast_ref::<crate::emit::OutputTooLarge>())
}

/// An error writing the output (without a place: see
/// `Interp::output_error_at`; a consumer's output error is placed at the
/// line it was given).
pub(crate) fn output_error(e: std::io::Error) -> Error {
    if let Some(t) = too_large(&e) {
        return Diagnostic::error(
            ErrorKind::Limit(LimitError::OutputBytesLimit { limit: t.limit }),
            None,
        );
    }
    Diagnostic::error(
        ErrorKind::Setup(SetupError::Io {
            path: "<output>".into(),
            message: e.to_string(),
        }),
        None,
    )
}

/// `e` placed at the line starting at `at` in `file` with the calls
/// `stack`, if it is the output byte limit without a place.
pub(in crate::eval) fn place_limit(
    mut e: Error,
    file: &Arc<SourceFile>,
    at: u32,
    stack: impl FnOnce() -> Vec<Site>,
) -> Error {
    if e.site.is_none()
        && matches!(
            e.kind,
            Kind::Error(ErrorKind::Limit(LimitError::OutputBytesLimit { .. }))
        )
    {
        e.site = Some(Site::new(file, at, at));
        e.stack = stack();
    }
    e
}
