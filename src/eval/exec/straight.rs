//! The straight-line loop's run: the lines the loop reads
//! (`eval/read/straight.rs`) checked, applied to the machine model and
//! written, in runs, with the chunks read ahead on the second thread
//! (`eval/read/scan_ahead.rs`) taken in order.

use std::rc::Rc;

use crate::diag::Error;
use crate::program::FileIndex;

use crate::block::MovesRule;
use crate::eval::Interp;
use crate::eval::read::scan_ahead::{Ahead, Decoded, InPlace, LineRoom, Lines, Read, Shared};
use crate::eval::read::straight::{
    BATCH, Plain, fast_line, fast_words, move_values, plain_words, read_line,
};
use crate::eval::write::hook::FormBatch;

/// The bytes a straight-line run reads: `buf` is the file's text from
/// offset `base`, whose first line is `first_line`; at most `max_lines` are
/// run.
struct Stretch<'a> {
    file: &'a Rc<FileIndex>,
    buf: &'a [u8],
    base: u32,
    first_line: u32,
    max_lines: u32,
}

/// Where a straight-line run stands.
#[derive(Default)]
struct Run {
    /// Start of the next line in the buffer.
    i: usize,
    lines: u32,
    /// Lines written and not yet counted in `out_lines`.
    emitted: u64,
    /// Input bytes [batch_start, i) are output as they are.
    batch_start: usize,
    last_start: usize,
}

impl Interp<'_> {
    /// Runs plain lines from `buf` (the file's bytes from offset `base`),
    /// stopping before line `stop_line`. Returns the number of lines run; 0
    /// means the first line needs the general path.
    pub(in crate::eval) fn straight_run(
        &mut self,
        file: &Rc<FileIndex>,
        buf: &[u8],
        base: u32,
        first_line: u32,
        stop_line: u32,
    ) -> Result<u32, Error> {
        if !self.s.plain_runs || !self.mach.is_plain() || self.out.ended {
            return Ok(0);
        }
        let max_lines = stop_line.saturating_sub(first_line);
        // Comments are copied unless they are to be stripped.
        let comments = !self.s.strip_comments;
        if buf.first() != Some(&b'\n') && !read_line(buf, 0, &mut Plain::default(), comments) {
            // The first line is not one the loop reads: what the loop would
            // find at once, without setting it up (the general path runs
            // such lines one at a time, each asking here first).
            if self.out.count_lines(0) {
                self.line_checkpoint()?;
            }
            return Ok(0);
        }
        let mut run = Run::default();
        let chunk = self.s.scan_ahead;
        // The first bytes are read in place; a run that goes on past them
        // reads the rest on two cores (a short run does not start a thread).
        let limit = if chunk == 0 { usize::MAX } else { 2 * chunk };
        // A consumer that reads blocks gets its lines decoded where they
        // are read, in place as ahead.
        let (decode, rule) = self.consumer_reading();
        let mut here = InPlace {
            buf,
            comments,
            limit,
            line: Plain::default(),
            decode,
            rule,
            room: LineRoom::default(),
        };
        let at = Stretch {
            file,
            buf,
            base,
            first_line,
            max_lines,
        };
        let paused = self.run_lines(&at, &mut here, &mut run)?;
        if paused {
            // The consumer's state now, after the lines read in place.
            let (decode, rule) = self.consumer_reading();
            let pool = std::mem::take(&mut self.reader.chunks);
            let shared = Shared::new(buf, run.i, comments, decode, rule, chunk, pool);
            let r = std::thread::scope(|s| {
                // Without a second thread (none can be started) the loop
                // reads every chunk itself.
                let _ = std::thread::Builder::new().spawn_scoped(s, || shared.help());
                let mut ahead = Ahead::new(&shared);
                self.run_lines(&at, &mut ahead, &mut run)
            });
            self.reader.chunks = shared.into_pool();
            r?;
        }
        self.flush_input(file, base, &buf[run.batch_start..run.i], run.batch_start)?;
        if self.out.count_lines(run.emitted) {
            self.line_checkpoint()?;
        }
        let lines = run.lines;
        if lines > 0 {
            self.reader
                .at(base + run.last_start as u32, first_line + lines - 1);
            self.flow.cur.pos = base + run.i as u32;
            self.flow.cur.line = first_line + lines;
        }
        Ok(lines)
    }

    /// Whether the consumer reads lines as blocks (then they are decoded
    /// where they are read), and its rule for lines of moves alone, if it
    /// has one then.
    fn consumer_reading(&self) -> (bool, Option<MovesRule>) {
        let consumer = self.out.consumer.as_ref();
        let decode = consumer.is_some_and(|c| c.reads_blocks());
        let rule = consumer.and_then(|c| c.moves_rule()).filter(|_| decode);
        (decode, rule)
    }

    /// The loop over lines from `src`, from where `run` stands. True: `src`
    /// paused (the run goes on with another source). Lines of moves alone
    /// are held back and handed over together (see [`FormBatch`]), all
    /// before the loop ends.
    #[inline(always)]
    fn run_lines(
        &mut self,
        at: &Stretch<'_>,
        src: &mut impl Lines,
        run: &mut Run,
    ) -> Result<bool, Error> {
        let mut forms = std::mem::take(&mut self.out.forms);
        let r = self.run_lines_with(at, src, run, &mut forms);
        let flushed = self.flush_forms(&mut forms, &at.file.file, at.buf);
        self.out.forms = forms;
        let paused = r?;
        flushed?;
        Ok(paused)
    }

    #[inline(always)]
    fn run_lines_with(
        &mut self,
        at: &Stretch<'_>,
        src: &mut impl Lines,
        run: &mut Run,
        forms: &mut FormBatch,
    ) -> Result<bool, Error> {
        let &Stretch {
            file,
            buf,
            base,
            first_line,
            max_lines,
        } = at;
        let Run {
            i,
            lines,
            emitted,
            batch_start,
            last_start,
        } = run;
        while *lines < max_lines && self.out.lines + *emitted < self.out.budget {
            let read = src.read(*i);
            if !forms.is_empty() && !matches!(read, Read::Line(_, Some(Decoded::Form { .. }))) {
                // Any other line after those held back.
                self.flush_forms(forms, &file.file, buf)?;
            }
            let (p, block) = match read {
                Read::Pause => return Ok(true),
                Read::Stop => break,
                Read::Blank => {
                    // Blank line: nothing to write.
                    self.flush_input(file, base, &buf[*batch_start..*i], *batch_start)?;
                    *last_start = *i;
                    *i += 1;
                    *batch_start = *i;
                    *lines += 1;
                    continue;
                }
                Read::Line(p, block) => (p, block),
            };
            if !fast_line(&mut self.mach, p) {
                // Other words or modes: the block checks and the full
                // state update, still without the grammar.
                self.flush_forms(forms, &file.file, buf)?;
                self.flush_input(file, base, &buf[*batch_start..*i], *batch_start)?;
                *batch_start = *i;
                self.out.lines += *emitted;
                *emitted = 0;
                self.reader.at(base + *i as u32, first_line + *lines);
                match self.exec_read(file, base, buf, *i, p) {
                    None => break,
                    Some(r) => r?,
                }
                *batch_start = p.next;
                if self.out.ended || !self.mach.is_plain() {
                    *last_start = *i;
                    *i = p.next;
                    *lines += 1;
                    break;
                }
            } else if let Some(decoded) = block {
                // Decoded ahead for the consumer: handed over line by line.
                *emitted += 1;
                if *batch_start < *i {
                    self.flush_forms(forms, &file.file, buf)?;
                    self.flush_input(file, base, &buf[*batch_start..*i], *batch_start)?;
                }
                let start = base + *i as u32;
                let text = &buf[*i..p.text_end];
                match decoded {
                    Decoded::Block(b) => self.consume_decoded(&file.file, start, text, b)?,
                    Decoded::Moves(w) => self.consume_moves(&file.file, start, text, w)?,
                    Decoded::Form { written, rule } => {
                        let written = (rule, written.unwrap_or(text));
                        if forms.push(start, (*i, p.text_end), move_values(p), written) {
                            self.flush_forms(forms, &file.file, buf)?;
                        }
                    }
                }
                *batch_start = p.next;
            } else {
                *emitted += 1;
                if p.text_end + 1 != p.next {
                    // Trailing blanks: the line is written trimmed.
                    self.flush_input(file, base, &buf[*batch_start..*i], *batch_start)?;
                    if self.out.consuming() {
                        let start = base + *i as u32;
                        self.consume(&file.file, start, &buf[*i..p.text_end], true)?;
                    } else {
                        let at = base + *i as u32;
                        self.out
                            .output
                            .line(&buf[*i..p.text_end])
                            .map_err(|e| self.output_error_at(e, &file.file, at))?;
                    }
                    *batch_start = p.next;
                } else if p.next - *batch_start >= BATCH {
                    self.flush_input(file, base, &buf[*batch_start..p.next], *batch_start)?;
                    *batch_start = p.next;
                }
            }
            *last_start = *i;
            *i = p.next;
            *lines += 1;
        }
        Ok(false)
    }

    /// Runs the line at `buf[i..]` (the file's bytes from offset `base`)
    /// that the loop read into `p` but does not run itself: its words, with
    /// their spans for messages, on the general checks. `None` leaves it to
    /// the general path. Kept out of the loop's code, as few lines take it.
    #[inline(never)]
    fn exec_read(
        &mut self,
        file: &Rc<FileIndex>,
        base: u32,
        buf: &[u8],
        i: usize,
        p: &Plain,
    ) -> Option<Result<(), Error>> {
        let raw = &buf[i..p.next - 1];
        let mut room = self.reader.plain.take().unwrap_or_default();
        let r = match plain_words(buf, i, p.text_end, &mut room) {
            Some(words) => self.exec_plain(file, base + i as u32, raw, words),
            None => None,
        };
        self.reader.plain = Some(room);
        r
    }

    /// Writes input bytes unchanged (`at`: their offset in `buf`, which
    /// starts at file offset `base`).
    fn flush_input(
        &mut self,
        file: &Rc<FileIndex>,
        base: u32,
        bytes: &[u8],
        at: usize,
    ) -> Result<(), Error> {
        if bytes.is_empty() {
            return Ok(());
        }
        let start = base as u64 + at as u64;
        if self.out.consuming() {
            return self.consume_input(&file.file, start, bytes);
        }
        self.out
            .output
            .write_input(&file.file, start, bytes)
            .map_err(|e| self.output_error_in(e, &file.file, start, bytes))
    }

    /// Runs the evaluated words of a line the straight way if the block
    /// checks would accept them (see `read::straight::fast_words`).
    pub(in crate::eval) fn fast_words(&mut self, words: &[(u8, f64)]) -> bool {
        fast_words(&mut self.mach, self.s, words)
    }
}
