//! Output steps: a line handed to the consumer takes the calls that led to
//! it and the warnings given so far from the other parts (see
//! [`RunAt`]); the handing over is the writer's.

use std::sync::Arc;

use crate::block::{Block, RawWord};
use crate::diag::Error;
use crate::program::SourceFile;

use crate::eval::Interp;
use crate::eval::write::hook::{FormBatch, RunAt};

/// The run where a line is handed over: the calls of `$i`'s control flow,
/// the count of its warnings (a macro, so that the writer stays free to
/// borrow beside them).
macro_rules! run_at {
    ($i:expr) => {
        RunAt {
            frames: &$i.flow.frames,
            warnings: $i.diags.warnings.len(),
        }
    };
}

impl Interp<'_> {
    /// Hands the lines of `batch`, read from `input` (`file`'s text), to
    /// the consumer, and empties it.
    pub(in crate::eval) fn flush_forms(
        &mut self,
        batch: &mut FormBatch,
        file: &Arc<SourceFile>,
        input: &[u8],
    ) -> Result<(), Error> {
        self.out.flush_forms(run_at!(self), batch, file, input)
    }

    /// Hands a line to the consumer (there is one).
    #[cold]
    pub(in crate::eval) fn consume(
        &mut self,
        file: &Arc<SourceFile>,
        line_start: u32,
        text: &[u8],
        verbatim: bool,
    ) -> Result<(), Error> {
        let at = run_at!(self);
        self.out.consume(at, file, line_start, text, verbatim)
    }

    /// Hands a line the evaluator wrote, with the values of its words, to
    /// the consumer (there is one).
    #[cold]
    pub(in crate::eval) fn consume_known(
        &mut self,
        file: &Arc<SourceFile>,
        line_start: u32,
        text: &[u8],
        verbatim: bool,
        known: &[(u8, f64)],
    ) -> Result<(), Error> {
        let at = run_at!(self);
        self.out
            .consume_known(at, file, line_start, text, verbatim, known)
    }

    /// Hands the line `raw` with `edits` to the consumer on its own thread
    /// (see [`crate::eval::out::Writer::consume_edited`]).
    pub(in crate::eval) fn consume_edited(
        &mut self,
        file: &Arc<SourceFile>,
        line_start: u32,
        raw: &[u8],
        edits: &[(crate::source::Span, crate::emit::Edit)],
        known: &[(u8, f64)],
    ) -> Result<(), Error> {
        let at = run_at!(self);
        self.out
            .consume_edited(at, (file, line_start), raw, edits, known)
    }

    /// Hands a line and its decoded block to the consumer (there is one).
    #[cold]
    pub(in crate::eval) fn consume_decoded(
        &mut self,
        file: &Arc<SourceFile>,
        line_start: u32,
        text: &[u8],
        block: &Block,
    ) -> Result<(), Error> {
        let at = run_at!(self);
        self.out.consume_decoded(at, file, line_start, text, block)
    }

    /// Hands a line that is a move alone, and its words, to the consumer.
    pub(in crate::eval) fn consume_moves(
        &mut self,
        file: &Arc<SourceFile>,
        line_start: u32,
        text: &[u8],
        words: &[RawWord],
    ) -> Result<(), Error> {
        let at = run_at!(self);
        self.out.consume_moves(at, file, line_start, text, words)
    }

    /// Hands each line of `bytes` (the file's bytes from offset `start`,
    /// whole lines) to the consumer.
    #[cold]
    pub(in crate::eval) fn consume_input(
        &mut self,
        file: &Arc<SourceFile>,
        start: u64,
        bytes: &[u8],
    ) -> Result<(), Error> {
        self.out.consume_input(run_at!(self), file, start, bytes)
    }
}
