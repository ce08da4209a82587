//! The consumer on a second core. Once a run has handed its consumer many
//! lines (`Settings::format_thread_after`), the consumer and the output move
//! to a thread of their own: the evaluator then only copies each line, its
//! origin and the count of its warnings so far into a batch, full batches
//! travel through a short queue, and emptied ones come back for reuse. The
//! consumer gets the same lines with the same origins in the same order.
//!
//! A consumer error stops the run as before: the thread keeps the first
//! one and raises a flag, the evaluator stops at its next line, and the
//! error replaces whatever the evaluator ran into afterwards; the warnings
//! the evaluator gave after the failed line are dropped, so the
//! diagnostics are those of a run that stopped at that line.

use crate::diag::SetupError;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{Receiver, Sender, SyncSender};

use super::hook::{LineConsumer, Origin};
use crate::diag::{Diagnostic, Error, ErrorKind};
use crate::emit::{Edit, Output, write_edited};
use crate::eval::flow::Calls;
use crate::eval::write::place_limit;
use crate::program::SourceFile;

/// Batches on their way to the thread, at most; the evaluator waits when
/// the consumer is this far behind.
pub(in crate::eval) const QUEUE: usize = 4;

/// Text bytes or lines at which a batch goes to the thread.
const BATCH_BYTES: usize = 32 << 10;
const BATCH_LINES: usize = 1024;

/// What the evaluator hands the thread, in order.
enum Msg {
    /// A line: its text is the batch's next `len` bytes.
    Line {
        len: u32,
        line_start: u32,
        verbatim: bool,
        /// The file of this line and the ones after it, when it changed.
        file: Option<Arc<SourceFile>>,
        /// The call chain, inside a call.
        stack: Option<Arc<Calls>>,
        /// Warnings the evaluator had given when it handed the line over.
        warnings: usize,
        /// The values of its words, the batch's next `known` of them (see
        /// [`LineConsumer::known_line`]); none: not known.
        known: u8,
        /// The text is a source line to write with the batch's next
        /// `edits` numbers in place of their spans (shortest form, see
        /// [`crate::emit::write_edited`]); none: the text is the line.
        edits: u8,
    },
    /// See [`LineConsumer::comp_position`].
    CompPosition([f64; 2]),
}

#[derive(Default)]
pub(in crate::eval) struct Batch {
    msgs: Vec<Msg>,
    text: Vec<u8>,
    known: Vec<(u8, f64)>,
    edits: Vec<(crate::source::Span, Edit)>,
}

/// The first consumer error, and the warnings given before its line.
pub(in crate::eval) struct Failure {
    pub(in crate::eval) error: Error,
    pub(in crate::eval) warnings: usize,
}

/// What the thread gives back when the run is over.
pub(in crate::eval) type Served<'s> = (Box<dyn LineConsumer + 's>, Output, Option<Failure>);

/// The evaluator's end of the queue.
pub(in crate::eval) struct Apart {
    to: SyncSender<Batch>,
    back: Receiver<Batch>,
    batch: Batch,
    failed: Arc<AtomicBool>,
    /// The file of the last line sent.
    file: Option<Arc<SourceFile>>,
    /// The consumer's answer, asked before it moved.
    pub(in crate::eval) computes_comp: bool,
}

/// The error the evaluator stops with once the consumer failed (replaced
/// by the consumer's own when the thread is joined).
fn stopped() -> Error {
    output_error("the consumer stopped")
}

/// The error of a run whose consumer and output did not come back from
/// the thread (see `run_apart`).
pub(in crate::eval) fn lost() -> Error {
    output_error("the output thread lost the output")
}

fn output_error(message: &str) -> Error {
    Diagnostic::error(
        ErrorKind::Setup(SetupError::Io {
            path: "<output>".into(),
            message: message.into(),
        }),
        None,
    )
}

impl Apart {
    pub(in crate::eval) fn new(
        to: SyncSender<Batch>,
        back: Receiver<Batch>,
        failed: Arc<AtomicBool>,
        computes_comp: bool,
    ) -> Apart {
        Apart {
            to,
            back,
            batch: Batch::default(),
            failed,
            file: None,
            computes_comp,
        }
    }

    /// Queues a line for the consumer, with the values of its words if
    /// `known` has them (see [`LineConsumer::known_line`]).
    #[allow(clippy::too_many_arguments)]
    pub(in crate::eval) fn line(
        &mut self,
        file: &Arc<SourceFile>,
        line_start: u32,
        text: &[u8],
        verbatim: bool,
        stack: Option<Arc<Calls>>,
        warnings: usize,
        known: &[(u8, f64)],
    ) -> Result<(), Error> {
        self.edited_line(
            file,
            line_start,
            (text, &[]),
            verbatim,
            stack,
            warnings,
            known,
        )
    }

    /// [`Apart::line`] of the line `raw` once `edits` are made (numbers
    /// only, at least one, at most 255, shortest form; `raw`'s trailing blanks dropped,
    /// as [`crate::emit::write_edited`] writes it): put together on the
    /// consumer's thread. The line cannot fail to be written: its numbers
    /// have a G-code form and its length a bound within the limit.
    #[allow(clippy::too_many_arguments)]
    pub(in crate::eval) fn edited_line(
        &mut self,
        file: &Arc<SourceFile>,
        line_start: u32,
        (text, edits): (&[u8], &[(crate::source::Span, Edit)]),
        verbatim: bool,
        stack: Option<Arc<Calls>>,
        warnings: usize,
        known: &[(u8, f64)],
    ) -> Result<(), Error> {
        debug_assert!(edits.len() <= usize::from(u8::MAX));
        debug_assert!(edits.iter().all(|(_, e)| matches!(e, Edit::Number(_))));
        if self.failed.load(Ordering::Relaxed) {
            return Err(stopped());
        }
        let file = match &self.file {
            Some(f) if Arc::ptr_eq(f, file) => None,
            _ => {
                self.file = Some(file.clone());
                Some(file.clone())
            }
        };
        self.batch.text.extend_from_slice(text);
        // At most 255 values (a line has far fewer words); more: none.
        let known = match u8::try_from(known.len()) {
            Ok(n) => {
                self.batch.known.extend_from_slice(known);
                n
            }
            Err(_) => 0,
        };
        self.batch.edits.extend_from_slice(edits);
        self.batch.msgs.push(Msg::Line {
            len: text.len() as u32,
            line_start,
            verbatim,
            file,
            stack,
            warnings,
            known,
            edits: edits.len() as u8,
        });
        if self.batch.text.len() >= BATCH_BYTES || self.batch.msgs.len() >= BATCH_LINES {
            self.send()?;
        }
        Ok(())
    }

    pub(in crate::eval) fn comp_position(&mut self, p: [f64; 2]) {
        self.batch.msgs.push(Msg::CompPosition(p));
    }

    /// Sends the batch; the thread gone (it panicked) stops the run too.
    fn send(&mut self) -> Result<(), Error> {
        let fresh = self.back.try_recv().unwrap_or_default();
        let full = std::mem::replace(&mut self.batch, fresh);
        self.to.send(full).map_err(|_| stopped())
    }

    /// Sends what is left; the thread ends when the queue closes.
    pub(in crate::eval) fn close(mut self) {
        if !self.batch.msgs.is_empty() {
            let _ = self.send();
        }
    }
}

/// The thread: runs the consumer on every line of every batch until the
/// queue closes (after a failure, batches are only given back).
pub(in crate::eval) fn serve<'s>(
    mut consumer: Box<dyn LineConsumer + 's>,
    mut out: Output,
    from: Receiver<Batch>,
    back: Sender<Batch>,
    failed: &AtomicBool,
) -> Served<'s> {
    let mut failure = None;
    let mut file: Option<Arc<SourceFile>> = None;
    for mut batch in from {
        if failure.is_none() {
            failure = run_batch(&mut *consumer, &mut out, &batch, &mut file);
            if failure.is_some() {
                failed.store(true, Ordering::Relaxed);
            }
        }
        batch.msgs.clear();
        batch.text.clear();
        batch.known.clear();
        batch.edits.clear();
        let _ = back.send(batch);
    }
    (consumer, out, failure)
}

fn run_batch(
    consumer: &mut dyn LineConsumer,
    out: &mut Output,
    batch: &Batch,
    file: &mut Option<Arc<SourceFile>>,
) -> Option<Failure> {
    let mut at = 0;
    let mut known_at = 0;
    let mut edits_at = 0;
    let mut edited = Vec::new();
    for m in &batch.msgs {
        match m {
            Msg::CompPosition(p) => consumer.comp_position(*p),
            Msg::Line {
                len,
                line_start,
                verbatim,
                file: changed,
                stack,
                warnings,
                known,
                edits,
            } => {
                if let Some(f) = changed {
                    *file = Some(f.clone());
                }
                let text = &batch.text[at..at + *len as usize];
                at += *len as usize;
                let known = &batch.known[known_at..known_at + usize::from(*known)];
                known_at += known.len();
                let edits = &batch.edits[edits_at..edits_at + usize::from(*edits)];
                edits_at += edits.len();
                let text = if edits.is_empty() {
                    text
                } else {
                    edited.clear();
                    // Numbers with a G-code form only (checked when sent).
                    let _ = write_edited(&mut edited, text, edits, None);
                    &edited[..]
                };
                let Some(f) = file.as_ref() else {
                    continue;
                };
                let calls = || stack.as_deref().map(Calls::sites).unwrap_or_default();
                let origin = Origin {
                    file: f,
                    line_start: *line_start,
                    verbatim: *verbatim,
                    stack: &calls,
                };
                let r = if known.is_empty() {
                    consumer.line(text, &origin, out)
                } else {
                    consumer.known_line(text, known, &origin, out)
                };
                if let Err(e) = r {
                    return Some(Failure {
                        error: place_limit(e, f, *line_start, calls),
                        warnings: *warnings,
                    });
                }
            }
        }
    }
    None
}
