//! The consumer path: when a consumer is configured (a target controller,
//! statistics, a toolpath picture, a source map), each output line is put
//! together on the evaluator's thread and handed to it with its origin
//! instead of going to the output; the consumer writes what it wants to
//! the output itself. Without a consumer nothing here runs: each of the
//! three places the evaluator writes lines tests one `Option`.

use std::sync::Arc;

use crate::block::{Block, MoveValues, MovesRule, RawWord};

/// What comes with a line handed over besides its text.
enum Payload<'a> {
    Text,
    Block(&'a Block),
    Moves(&'a [RawWord]),
    Known(&'a [(u8, f64)]),
}
use crate::diag::{Diagnostic, Error, Site};
use crate::emit::Output;
use crate::program::SourceFile;

use crate::eval::flow::{Frame, calls_of, stack_of};
use crate::eval::write::{Writer, place_limit};

/// Where an output line came from.
#[derive(Clone, Copy)]
pub struct Origin<'a> {
    /// The file holding the line that produced it.
    pub file: &'a Arc<SourceFile>,
    /// Byte offset of that line's start in `file`.
    pub line_start: u32,
    /// The output line is that line's text as written (same columns; only
    /// trailing blanks dropped). Otherwise it was put together from it
    /// (numbers substituted) or made up (M70–M73 restores, `%`).
    pub verbatim: bool,
    /// The call chain (innermost caller first), worked out on demand.
    pub stack: &'a dyn Fn() -> Vec<Site>,
}

/// Reads the flattened program line by line. It may run on a second
/// thread once a run has handed it many lines (see `apart`).
pub trait LineConsumer: Send {
    /// One output line (no terminator). An error stops the run, unless the
    /// consumer keeps it to report at the end (check mode).
    fn line(&mut self, text: &[u8], origin: &Origin<'_>, out: &mut Output) -> Result<(), Error>;

    /// Whether the consumer reads lines as typed blocks: the straight-line
    /// loop then decodes its lines ahead, on its second thread, and hands
    /// them over through [`LineConsumer::decoded_line`].
    fn reads_blocks(&self) -> bool {
        false
    }

    /// One output line and `block`, its text decoded (no error): what
    /// [`LineConsumer::line`] does with the line, without decoding it again.
    fn decoded_line(
        &mut self,
        text: &[u8],
        block: &Block,
        origin: &Origin<'_>,
        out: &mut Output,
    ) -> Result<(), Error> {
        let _ = block;
        self.line(text, origin, out)
    }

    /// One output line that is a move and nothing else (see
    /// [`crate::block::RawLine::moves_only`]), and its words: a block of
    /// them alone is the line decoded. What [`LineConsumer::line`] does.
    fn moves_line(
        &mut self,
        text: &[u8],
        words: &[RawWord],
        origin: &Origin<'_>,
        out: &mut Output,
    ) -> Result<(), Error> {
        let _ = words;
        self.line(text, origin, out)
    }

    /// One output line written by the evaluator, and the values of its
    /// words as it wrote them (see [`Block::decode_known`]: in line order,
    /// upper-case letter and value, NaN where not known): what
    /// [`LineConsumer::line`] does with the line; a consumer that decodes
    /// it may take the values instead of reading long numbers again.
    fn known_line(
        &mut self,
        text: &[u8],
        known: &[(u8, f64)],
        origin: &Origin<'_>,
        out: &mut Output,
    ) -> Result<(), Error> {
        let _ = known;
        self.line(text, origin, out)
    }

    /// How the consumer writes lines of moves alone, in its present state,
    /// if it writes them by such a rule: the straight-line loop then works
    /// out their output where it reads them and hands them over in batches
    /// through [`LineConsumer::form_lines`].
    fn moves_rule(&self) -> Option<MovesRule> {
        None
    }

    /// Lines of moves alone handed over at once, in order, each with its
    /// values and as written by the batch's [`MovesRule`] (the consumer's
    /// when their run started; its state may have changed since): what
    /// [`LineConsumer::line`] does with each (`origin` with each line's
    /// start). An error comes with the index of its line.
    fn form_lines(
        &mut self,
        batch: &FormLines<'_>,
        origin: &Origin<'_>,
        out: &mut Output,
    ) -> Result<(), (usize, Error)> {
        for (k, l) in batch.lines.iter().enumerate() {
            let o = Origin {
                line_start: l.line_start,
                ..*origin
            };
            self.line(batch.text(l), &o, out).map_err(|e| (k, e))?;
        }
        Ok(())
    }

    /// The program ended; returns diagnostics gathered on the way (warnings,
    /// and in check mode errors kept to report them all).
    fn finish(&mut self, out: &mut Output) -> Result<Vec<Diagnostic>, Error>;

    /// Whether the consumer computes cutter radius compensation into the
    /// path (rather than writing G41/G42 for the controller to apply).
    fn computes_comp(&self) -> bool {
        false
    }

    /// LinuxCNC's G70 has put the position its cutter radius compensation
    /// reads at `p` (plane coordinates: Z, X in G18) without a move, before
    /// the cycle's moves (the lines that follow).
    fn comp_position(&mut self, _p: [f64; 2]) {}
}

/// A line of moves alone a straight run holds back (in a `FormBatch`)
/// to hand over with others.
#[derive(Clone, Copy)]
pub struct FormLine {
    /// Offset of its start in its file.
    pub line_start: u32,
    /// Its text: offsets in the batch's input.
    pub text: (u32, u32),
    pub values: MoveValues,
    /// End of its written bytes, and their newline, in the batch's
    /// `written`.
    pub written_end: u32,
}

/// Lines of moves alone handed over at once (see
/// [`LineConsumer::form_lines`]): all read from `input` and written by
/// `rule` (the consumer's rule when their run started), their written
/// bytes one after another, each with its newline.
pub struct FormLines<'a> {
    pub rule: MovesRule,
    pub input: &'a [u8],
    pub lines: &'a [FormLine],
    pub written: &'a [u8],
}

impl FormLines<'_> {
    /// The text of `line`.
    pub fn text(&self, line: &FormLine) -> &[u8] {
        &self.input[line.text.0 as usize..line.text.1 as usize]
    }
}

/// Lines of moves alone a straight-line run has read and not yet handed
/// over: handed over together, before any other line.
#[derive(Default)]
pub(in crate::eval) struct FormBatch {
    rule: Option<MovesRule>,
    lines: Vec<FormLine>,
    written: Vec<u8>,
}

/// Lines a batch holds at most.
const FORM_BATCH: usize = 256;

impl FormBatch {
    pub(in crate::eval) fn is_empty(&self) -> bool {
        self.lines.is_empty()
    }

    /// Adds a line (text at `text` in the run's input) written as
    /// `written` by `rule` (no bytes: nothing, not even an empty line, as
    /// for a comment alone the rule drops); true when the batch is full.
    #[inline]
    pub(in crate::eval) fn push(
        &mut self,
        line_start: u32,
        text: (usize, usize),
        values: MoveValues,
        (rule, written): (MovesRule, &[u8]),
    ) -> bool {
        // One rule for the batch: lines read under another (a new run)
        // come after it is handed over.
        debug_assert!(self.lines.is_empty() || self.rule == Some(rule));
        if self.lines.is_empty() {
            self.rule = Some(rule);
        }
        if !written.is_empty() {
            self.written.extend_from_slice(written);
            self.written.push(b'\n');
        }
        self.lines.push(FormLine {
            line_start,
            text: (text.0 as u32, text.1 as u32),
            values,
            written_end: self.written.len() as u32,
        });
        self.lines.len() >= FORM_BATCH
    }
}

/// What a line handed to the consumer takes from the rest of the run: the
/// calls that led to it (its origin's call stack, made on demand) and the
/// number of warnings given before it (a consumer on its own thread that
/// fails at the line drops those given after).
#[derive(Clone, Copy)]
pub(in crate::eval) struct RunAt<'a> {
    pub(in crate::eval) frames: &'a [Box<Frame>],
    pub(in crate::eval) warnings: usize,
}

impl RunAt<'_> {
    /// `e` placed at the line starting at `line_start` in `file` with the
    /// calls, if it is the output byte limit without a place.
    #[cold]
    fn placed(&self, e: Error, file: &Arc<SourceFile>, line_start: u32) -> Error {
        place_limit(e, file, line_start, || stack_of(self.frames))
    }
}

impl Writer<'_> {
    /// Hands the lines of `batch`, read from `input` (`file`'s text), to
    /// the consumer, and empties it.
    pub(in crate::eval) fn flush_forms(
        &mut self,
        at: RunAt<'_>,
        batch: &mut FormBatch,
        file: &Arc<SourceFile>,
        input: &[u8],
    ) -> Result<(), Error> {
        let Some(rule) = batch.rule.filter(|_| !batch.lines.is_empty()) else {
            return Ok(());
        };
        let lines = FormLines {
            rule,
            input,
            lines: &batch.lines,
            written: &batch.written,
        };
        let r = match self.consumer.take() {
            Some(mut c) if self.apart.is_none() => {
                self.handed += batch.lines.len();
                let stack = || stack_of(at.frames);
                let origin = Origin {
                    file,
                    line_start: 0,
                    verbatim: true,
                    stack: &stack,
                };
                let r = c.form_lines(&lines, &origin, &mut self.output);
                self.consumer = Some(c);
                r
            }
            c => {
                // No consumer on this thread: each line as any other.
                self.consumer = c;
                let mut r = Ok(());
                for (k, l) in batch.lines.iter().enumerate() {
                    let text = lines.text(l);
                    let line = (file, l.line_start, text);
                    if let Err(e) = self.hand_over(at, line, true, Payload::Text) {
                        r = Err((k, e));
                        break;
                    }
                }
                r
            }
        };
        let placed = r.map_err(|(k, e)| at.placed(e, file, batch.lines[k].line_start));
        batch.lines.clear();
        batch.written.clear();
        placed
    }

    /// Hands a line (`text`, made from the line at `line_start` in `file`;
    /// `verbatim`: its text as written) to the consumer (there is one).
    #[cold]
    pub(in crate::eval) fn consume(
        &mut self,
        at: RunAt<'_>,
        file: &Arc<SourceFile>,
        line_start: u32,
        text: &[u8],
        verbatim: bool,
    ) -> Result<(), Error> {
        self.hand_over(at, (file, line_start, text), verbatim, Payload::Text)
    }

    /// Hands a line and its decoded block to the consumer (there is one).
    #[cold]
    pub(in crate::eval) fn consume_decoded(
        &mut self,
        at: RunAt<'_>,
        file: &Arc<SourceFile>,
        line_start: u32,
        text: &[u8],
        block: &Block,
    ) -> Result<(), Error> {
        let line = (file, line_start, text);
        self.hand_over(at, line, true, Payload::Block(block))
    }

    /// Hands a line the evaluator wrote, with the values of its words (see
    /// [`LineConsumer::known_line`]), to the consumer (there is one).
    pub(in crate::eval) fn consume_known(
        &mut self,
        at: RunAt<'_>,
        file: &Arc<SourceFile>,
        line_start: u32,
        text: &[u8],
        verbatim: bool,
        known: &[(u8, f64)],
    ) -> Result<(), Error> {
        let line = (file, line_start, text);
        self.hand_over(at, line, verbatim, Payload::Known(known))
    }

    /// Whether the consumer runs on a thread of its own, where a line may
    /// be put together (see [`Writer::consume_edited`]).
    pub(in crate::eval) fn consumer_apart(&self) -> bool {
        self.apart.is_some()
    }

    /// Hands the line `raw` with `edits` made (numbers alone, each with a
    /// G-code form, shortest form, the line's length bounded within the
    /// limit) to the consumer on its own thread, which puts it together;
    /// with the values of its words if `known` has them.
    pub(in crate::eval) fn consume_edited(
        &mut self,
        at: RunAt<'_>,
        (file, line_start): (&Arc<SourceFile>, u32),
        raw: &[u8],
        edits: &[(crate::source::Span, crate::emit::Edit)],
        known: &[(u8, f64)],
    ) -> Result<(), Error> {
        let Some(a) = self.apart.as_mut() else {
            unreachable!("a line is put together apart only with the consumer apart")
        };
        let stack = calls_of(at.frames);
        let verbatim = edits.is_empty();
        a.edited_line(
            file,
            line_start,
            (raw, edits),
            verbatim,
            stack,
            at.warnings,
            known,
        )
    }

    /// Hands a line that is a move alone, and its words, to the consumer.
    pub(in crate::eval) fn consume_moves(
        &mut self,
        at: RunAt<'_>,
        file: &Arc<SourceFile>,
        line_start: u32,
        text: &[u8],
        words: &[RawWord],
    ) -> Result<(), Error> {
        let line = (file, line_start, text);
        self.hand_over(at, line, true, Payload::Moves(words))
    }

    /// [`LineConsumer::line`], or with `block` [`LineConsumer::decoded_line`],
    /// with the line's origin; an error is placed at the line.
    fn hand_over(
        &mut self,
        at: RunAt<'_>,
        (file, line_start, text): (&Arc<SourceFile>, u32, &[u8]),
        verbatim: bool,
        payload: Payload<'_>,
    ) -> Result<(), Error> {
        if let Some(a) = self.apart.as_mut() {
            // A block decoded ahead is the same line: the text carries it.
            let stack = calls_of(at.frames);
            let known = match payload {
                Payload::Known(k) => k,
                _ => &[],
            };
            return a.line(file, line_start, text, verbatim, stack, at.warnings, known);
        }
        let Some(mut c) = self.consumer.take() else {
            return Ok(());
        };
        self.handed += 1;
        let stack = || stack_of(at.frames);
        let origin = Origin {
            file,
            line_start,
            verbatim,
            stack: &stack,
        };
        let out = &mut self.output;
        let r = match payload {
            Payload::Text => c.line(text, &origin, out),
            Payload::Block(b) => c.decoded_line(text, b, &origin, out),
            Payload::Moves(w) => c.moves_line(text, w, &origin, out),
            Payload::Known(k) => c.known_line(text, k, &origin, out),
        };
        self.consumer = Some(c);
        r.map_err(|e| at.placed(e, file, line_start))
    }

    /// Whether the consumer computes cutter radius compensation into the
    /// path.
    pub(in crate::eval) fn consumer_computes_comp(&self) -> bool {
        match &self.apart {
            Some(a) => a.computes_comp,
            None => self.consumer.as_ref().is_some_and(|c| c.computes_comp()),
        }
    }

    /// Tells the consumer where LinuxCNC's compensation now reads the
    /// tool's position (see [`LineConsumer::comp_position`]).
    pub(in crate::eval) fn consumer_comp_position(&mut self, p: [f64; 2]) {
        if let Some(a) = self.apart.as_mut() {
            a.comp_position(p);
        } else if let Some(c) = self.consumer.as_mut() {
            c.comp_position(p);
        }
    }

    /// Hands each line of `bytes` (the file's bytes from offset `start`,
    /// whole lines) to the consumer.
    #[cold]
    pub(in crate::eval) fn consume_input(
        &mut self,
        at: RunAt<'_>,
        file: &Arc<SourceFile>,
        start: u64,
        bytes: &[u8],
    ) -> Result<(), Error> {
        let mut i = 0;
        // One search over the whole range (not one call per line).
        let ends = memchr::memchr_iter(b'\n', bytes).chain(std::iter::once(bytes.len()));
        for end in ends {
            if i >= bytes.len() {
                break;
            }
            let line = &bytes[i..end];
            let trimmed = line
                .iter()
                .rposition(|b| !b.is_ascii_whitespace())
                .map_or(0, |p| p + 1);
            if trimmed > 0 {
                self.consume(at, file, (start + i as u64) as u32, &line[..trimmed], true)?;
            }
            i = end + 1;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::emit::Destination;
    use crate::program::SearchPath;

    /// Writes each line as `offset verbatim text`.
    struct Tag;

    impl LineConsumer for Tag {
        fn line(&mut self, text: &[u8], o: &Origin<'_>, out: &mut Output) -> Result<(), Error> {
            let mut l = format!("{} {} ", o.line_start, o.verbatim as u8).into_bytes();
            l.extend_from_slice(text);
            l.extend(format!(" {}", (o.stack)().len()).bytes());
            out.line(&l).map_err(crate::eval::output_error)
        }

        fn finish(&mut self, out: &mut Output) -> Result<Vec<Diagnostic>, Error> {
            out.line(b"end").map_err(crate::eval::output_error)?;
            Ok(Vec::new())
        }
    }

    fn run(text: &str, settings: &crate::settings::Settings) -> String {
        let dir = tempfile::tempdir().expect("dir");
        let out = dir.path().join("out");
        let src = SourceFile::new("<t>".into(), "<t>".into(), text.as_bytes().to_vec());
        let (_, e) = crate::flatten::flatten_with(
            src,
            settings,
            &SearchPath::default(),
            Destination::File(out.clone()),
            Some(Box::new(Tag)),
        );
        assert!(e.is_none(), "{e:?}");
        std::fs::read_to_string(out).expect("out")
    }

    #[test]
    fn every_line_reaches_the_consumer_with_its_origin() {
        let text = "%\nG0 X1 \n(c)\nG1 X2 F3\n\n#1=2\nG1 X#1 (v)\no1 sub\nG0 Y1\no1 endsub\no1 call\nM70\nM72\n%\n";
        let s = crate::settings::Settings::default();
        let want =
            "0 0 % 0\n2 1 G0 X1 0\n9 1 (c) 0\n13 1 G1 X2 F3 0\n28 0 G1 X2 (v) 0\n46 1 G0 Y1 1\n";
        let got = run(text, &s);
        // The restore lines of M72 depend on the state; look at the frame
        // of the test: the first six lines and the end.
        let first: Vec<&str> = got.lines().take(6).collect();
        assert_eq!(first, want.lines().take(6).collect::<Vec<_>>());
        assert!(got.ends_with("% 0\nend\n"), "{got}");
        // The straight-line loop and the line-by-line path agree.
        let slow = crate::settings::Settings {
            plain_runs: false,
            ..crate::settings::Settings::default()
        };
        assert_eq!(run(text, &slow), got);
    }
}
