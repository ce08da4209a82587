//! The evaluator's way to the [`Sink`]. At first every write goes straight to
//! the sink. Once a program has written many lines with computed numbers
//! (loops, subroutine calls), the sink moves to a second thread, which puts
//! those lines together, formats their numbers and does the sink's work while
//! the evaluator goes on: the evaluator then only appends compact commands
//! (text, a source line with its edits, a range of the input file) to a
//! chunk, full chunks travel to the thread through a short queue, and emptied
//! chunks come back for reuse. Either way the sink receives the same bytes in
//! the same order, and nothing is released before [`Output::finish`].

use std::io;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{self, Receiver, Sender, SyncSender};
use std::thread::JoinHandle;

use super::edit::{Edit, EditRef, max_edited_len, write_edited, write_edits};
use super::sink::{Destination, Sink};
use crate::source::SourceFile;
use crate::source::Span;

/// Chunk length at which the commands go to the thread.
const CHUNK: usize = 1 << 16;

/// Chunks on their way to the thread, at most; the evaluator waits when the
/// thread is this far behind.
const QUEUE: usize = 4;

/// Command tags, their fields little-endian. Text: a `u32` length and the
/// bytes. Edited line: the source line's length and the number of edits
/// (`u32`s), the source line, and each edit: a tag, its span (`u32` start
/// and end) and a `u64` (for a number, the `f64`'s bits; for text, its
/// length, the bytes following). Range of the input file: `u64` start and
/// length.
const TEXT: u8 = 0;
const LINE: u8 = 1;
const RANGE: u8 = 2;

/// Edit tags.
const NUMBER: u8 = 0;
const REMOVE: u8 = 1;
const REPLACE: u8 = 2;

/// Writes flattened output into a [`Sink`], on this thread or on a second
/// one.
pub struct Output {
    mode: Mode,
    precision: Option<u8>,
    /// Edited lines written so far, while on this thread.
    lines: usize,
    /// Edited lines after which the sink moves to a thread (`usize::MAX`:
    /// never).
    thread_after: usize,
    /// An edited line being put together, on this thread.
    line: Vec<u8>,
    /// The sink throws everything away: edited lines are not even put
    /// together.
    discard: bool,
}

enum Mode {
    /// The sink is written on this thread.
    Direct(Sink),
    /// The sink is on a second thread.
    Threaded(Writer),
    /// The thread stopped with an error (already returned): writes fail.
    Stopped,
}

/// A length as a field of a command (text commands stay under two chunks,
/// lines and their edits under a few hundred bytes).
fn short(n: usize) -> [u8; 4] {
    u32::try_from(n).expect("a short length").to_le_bytes()
}

/// The error of an edited line with a number that has no G-code form (the
/// evaluator never writes one).
#[cold]
fn unprintable(v: f64) -> io::Error {
    io::Error::other(format!("{v} has no G-code form"))
}

/// The error of writes after the thread stopped.
fn stopped() -> io::Error {
    io::Error::other("the output was stopped by an earlier error")
}

impl Output {
    /// Output into `sink`, numbers written with `precision` (see
    /// [`super::write_number`]). After `thread_after` edited lines the sink
    /// moves to a second thread (0: from the start; `usize::MAX`: never).
    /// Output that is thrown away never moves.
    pub fn new(sink: Sink, precision: Option<u8>, thread_after: usize) -> Output {
        let discard = sink.discards();
        let mut out = Output {
            mode: Mode::Direct(sink),
            precision,
            lines: 0,
            thread_after: if discard { usize::MAX } else { thread_after },
            line: Vec::with_capacity(256),
            discard,
        };
        if out.thread_after == 0 {
            out.start_thread();
        }
        out
    }

    /// An output that throws everything away: the stand-in while the real
    /// one is on another thread.
    pub(crate) fn discarding() -> Option<Output> {
        Sink::new(Destination::Discard)
            .ok()
            .map(|s| Output::new(s, None, usize::MAX))
    }

    /// Takes the lines written so far to a memory destination on this
    /// thread (see [`Sink::drain_memory`]).
    pub(crate) fn drain_memory(&mut self) -> Vec<u8> {
        match &mut self.mode {
            Mode::Direct(sink) => sink.drain_memory(),
            _ => Vec::new(),
        }
    }

    /// Moves the sink to a second thread; if none can be started, output
    /// stays on this thread. Tried once.
    fn start_thread(&mut self) {
        self.thread_after = usize::MAX;
        if let Mode::Direct(sink) = std::mem::replace(&mut self.mode, Mode::Stopped) {
            self.mode = Writer::start(sink, self.precision);
        }
    }

    /// Takes the thread down after it failed; its error.
    #[cold]
    fn stop(&mut self) -> io::Error {
        match std::mem::replace(&mut self.mode, Mode::Stopped) {
            Mode::Threaded(w) => match w.close() {
                Err(e) => e,
                Ok(_) => io::Error::other("the output thread stopped"),
            },
            other => {
                self.mode = other;
                stopped()
            }
        }
    }

    /// The result of handing something to the thread: false means it
    /// stopped, and its error is returned.
    fn sent(&mut self, ok: bool) -> io::Result<()> {
        if ok { Ok(()) } else { Err(self.stop()) }
    }

    /// While on the thread: counts `bound` more bytes (at least those the
    /// next write adds) against the room the sink had left. When they may
    /// not fit, the sink comes back to this thread first, so that a write
    /// past `--max-output-bytes` fails in the call that makes it (the
    /// evaluator knows that line) and never later on the thread.
    #[inline]
    fn make_room(&mut self, bound: u64) -> io::Result<()> {
        if let Mode::Threaded(w) = &mut self.mode
            && !w.reserve(bound)
        {
            return self.come_back();
        }
        Ok(())
    }

    /// Takes the sink back from the thread (everything sent so far
    /// written), to go on here.
    #[cold]
    fn come_back(&mut self) -> io::Result<()> {
        match std::mem::replace(&mut self.mode, Mode::Stopped) {
            Mode::Threaded(mut w) => {
                // If the chunk cannot be sent, closing gives the reason.
                w.send();
                self.mode = Mode::Direct(w.close()?);
                Ok(())
            }
            other => {
                self.mode = other;
                Ok(())
            }
        }
    }

    /// Appends bytes (whole lines).
    pub fn write(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.make_room(bytes.len() as u64)?;
        match &mut self.mode {
            Mode::Direct(sink) => sink.write(bytes),
            Mode::Threaded(w) => {
                let ok = w.write(bytes);
                self.sent(ok)
            }
            Mode::Stopped => Err(stopped()),
        }
    }

    /// Appends a finished line and its newline.
    pub fn line(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.make_room(bytes.len() as u64 + 1)?;
        match &mut self.mode {
            Mode::Direct(sink) => sink.write(bytes).and_then(|_| sink.write(b"\n")),
            Mode::Threaded(w) => {
                let ok = w.line(bytes);
                self.sent(ok)
            }
            Mode::Stopped => Err(stopped()),
        }
    }

    /// Appends bytes that are `file`'s bytes from offset `start` on (see
    /// [`Sink::write_input`]).
    pub fn write_input(
        &mut self,
        file: &Arc<SourceFile>,
        start: u64,
        bytes: &[u8],
    ) -> io::Result<()> {
        self.make_room(bytes.len() as u64)?;
        match &mut self.mode {
            Mode::Direct(sink) => sink.write_input(file, start, bytes),
            Mode::Threaded(w) => {
                let ok = w.write_input(file, start, bytes);
                self.sent(ok)
            }
            Mode::Stopped => Err(stopped()),
        }
    }

    /// Appends the source line `raw` with `edits` made (see
    /// [`write_edited`]) and a newline. Every number must have a G-code form
    /// (see [`super::max_edited_len`]); the caller checks the line's length
    /// with that bound too.
    #[inline]
    pub fn edited_line(&mut self, raw: &[u8], edits: &[(Span, Edit)]) -> io::Result<()> {
        self.lines += 1;
        if self.lines >= self.thread_after {
            self.start_thread();
        }
        if matches!(self.mode, Mode::Threaded(_)) {
            let bound =
                max_edited_len(raw.len(), edits, self.precision).map_or(u64::MAX, |n| n as u64 + 1);
            self.make_room(bound)?;
        }
        match &mut self.mode {
            Mode::Direct(_) if self.discard => Ok(()),
            Mode::Direct(sink) => {
                self.line.clear();
                write_edited(&mut self.line, raw, edits, self.precision)
                    .map_err(|(v, _)| unprintable(v))?;
                self.line.push(b'\n');
                sink.write(&self.line)
            }
            Mode::Threaded(w) => {
                w.edited_line(raw, edits);
                let ok = w.send_if_full();
                self.sent(ok)
            }
            Mode::Stopped => Err(stopped()),
        }
    }

    /// The sink with everything written so far (the thread has finished).
    fn into_sink(mut self) -> io::Result<Sink> {
        match std::mem::replace(&mut self.mode, Mode::Stopped) {
            Mode::Direct(sink) => Ok(sink),
            // If the last chunk cannot be sent, closing gives the reason.
            Mode::Threaded(mut w) => {
                w.send();
                w.close()
            }
            Mode::Stopped => Err(stopped()),
        }
    }

    /// Releases everything to the destination (see [`Sink::finish`]).
    /// Dropping an `Output` instead releases nothing: a thread is stopped
    /// and the sink dropped.
    pub fn finish(self) -> io::Result<()> {
        self.into_sink()?.finish()
    }
}

/// The evaluator's end of the output thread: the chunk being filled and the
/// queues.
struct Writer {
    chunk: Vec<u8>,
    /// Start of the bytes of the chunk's last command if that is text still
    /// open for more bytes (its length is written when it closes).
    open: Option<usize>,
    /// Full chunks to the thread, each with a bound of the bytes it
    /// writes; `None` once closed.
    queue: Option<SyncSender<(Vec<u8>, u64)>>,
    /// Emptied chunks back from the thread.
    spent: Receiver<Vec<u8>>,
    /// The thread failed and stopped.
    failed: Arc<AtomicBool>,
    thread: Option<JoinHandle<io::Result<Sink>>>,
    /// The input file the sink checks, if any.
    input: Option<Arc<SourceFile>>,
    /// Bytes the sink surely has room for: its room when the thread
    /// started, less a bound of every command since, plus `slack` as the
    /// thread hands it over.
    room: u64,
    /// Bound of the chunk being filled.
    chunk_bound: u64,
    /// What the thread found its chunks to write less than their bounds.
    slack: Arc<AtomicU64>,
}

impl Writer {
    /// Starts the thread and hands it the sink; the sink stays here if no
    /// thread can be started.
    fn start(sink: Sink, precision: Option<u8>) -> Mode {
        let input = sink.input().cloned();
        let room = sink.room();
        let slack = Arc::new(AtomicU64::new(0));
        let slack_there = slack.clone();
        let (queue, chunks) = mpsc::sync_channel(QUEUE);
        let (give_back, spent) = mpsc::channel();
        // The sink goes over a channel of its own once the thread runs: a
        // thread that cannot be started would drop what it was given.
        let (give_sink, take_sink) = mpsc::channel();
        let failed = Arc::new(AtomicBool::new(false));
        let flag = failed.clone();
        let spawned = std::thread::Builder::new()
            .name("ngcflat-output".into())
            .spawn(move || serve(take_sink, chunks, give_back, &flag, &slack_there, precision));
        let Ok(thread) = spawned else {
            return Mode::Direct(sink);
        };
        if let Err(mpsc::SendError(sink)) = give_sink.send(sink) {
            let _ = thread.join();
            return Mode::Direct(sink);
        }
        Mode::Threaded(Writer {
            chunk: Vec::with_capacity(2 * CHUNK),
            open: None,
            queue: Some(queue),
            spent,
            failed,
            thread: Some(thread),
            input,
            room,
            chunk_bound: 0,
            slack,
        })
    }

    /// Counts `bound` bytes against the room; false when they may not
    /// fit.
    #[inline]
    fn reserve(&mut self, bound: u64) -> bool {
        if bound > self.room {
            self.room = self
                .room
                .saturating_add(self.slack.swap(0, Ordering::AcqRel));
            if bound > self.room {
                return false;
            }
        }
        self.room -= bound;
        self.chunk_bound += bound;
        true
    }

    /// Appends text, to the open text command if there is one.
    #[inline]
    fn text(&mut self, bytes: &[u8]) {
        if self.open.is_none() {
            self.chunk.push(TEXT);
            self.chunk.extend_from_slice(&[0; 4]);
            self.open = Some(self.chunk.len());
        }
        self.chunk.extend_from_slice(bytes);
    }

    /// Writes the length of the open text command.
    #[inline]
    fn close_text(&mut self) {
        if let Some(at) = self.open.take() {
            let len = short(self.chunk.len() - at);
            self.chunk[at - 4..at].copy_from_slice(&len);
        }
    }

    /// Appends an edited line (see [`Output::edited_line`]).
    #[inline]
    fn edited_line(&mut self, raw: &[u8], edits: &[(Span, Edit)]) {
        self.close_text();
        self.chunk.reserve(9 + raw.len() + 17 * edits.len());
        let mut head = [LINE; 9];
        head[1..5].copy_from_slice(&short(raw.len()));
        head[5..].copy_from_slice(&short(edits.len()));
        self.chunk.extend_from_slice(&head);
        self.chunk.extend_from_slice(raw);
        for (span, e) in edits {
            // Each edit in one piece: fewer checks of the chunk's room.
            let (tag, value, text) = match e {
                Edit::Number(v) => (NUMBER, v.to_bits(), &[][..]),
                Edit::Remove => (REMOVE, 0, &[][..]),
                Edit::Text(t) => (REPLACE, t.len() as u64, t.as_bytes()),
            };
            let mut rec = [tag; 17];
            rec[1..5].copy_from_slice(&span.start.to_le_bytes());
            rec[5..9].copy_from_slice(&span.end.to_le_bytes());
            rec[9..].copy_from_slice(&value.to_le_bytes());
            self.chunk.extend_from_slice(&rec);
            if !text.is_empty() {
                self.chunk.extend_from_slice(text);
            }
        }
    }

    /// Appends bytes of any length, sending full chunks. False: the thread
    /// stopped.
    fn write(&mut self, bytes: &[u8]) -> bool {
        for piece in bytes.chunks(CHUNK) {
            self.text(piece);
            if !self.send_if_full() {
                return false;
            }
        }
        true
    }

    /// Appends a finished line and its newline. False: the thread stopped.
    fn line(&mut self, bytes: &[u8]) -> bool {
        if !self.write(bytes) {
            return false;
        }
        self.text(b"\n");
        self.send_if_full()
    }

    /// Appends input bytes: with their offset when they are bytes of the
    /// file the sink checks (their CRC is taken on the thread), else as
    /// text. False: the thread stopped.
    fn write_input(&mut self, file: &Arc<SourceFile>, start: u64, bytes: &[u8]) -> bool {
        if !matches!(&self.input, Some(f) if Arc::ptr_eq(f, file)) {
            return self.write(bytes);
        }
        let mut at = start;
        for piece in bytes.chunks(CHUNK) {
            self.close_text();
            self.chunk.push(RANGE);
            self.chunk.extend_from_slice(&at.to_le_bytes());
            self.chunk.extend_from_slice(&short(piece.len()));
            self.chunk.extend_from_slice(piece);
            at += piece.len() as u64;
            if !self.send_if_full() {
                return false;
            }
        }
        true
    }

    #[inline]
    fn send_if_full(&mut self) -> bool {
        self.chunk.len() < CHUNK || self.send()
    }

    /// Sends the chunk to the thread and starts another, an emptied one if
    /// one came back. False: the thread stopped.
    fn send(&mut self) -> bool {
        self.close_text();
        if self.chunk.is_empty() {
            return true;
        }
        if self.failed.load(Ordering::Acquire) {
            return false;
        }
        let next = self
            .spent
            .try_recv()
            .unwrap_or_else(|_| Vec::with_capacity(2 * CHUNK));
        let full = std::mem::replace(&mut self.chunk, next);
        let bound = std::mem::take(&mut self.chunk_bound);
        self.queue
            .as_ref()
            .is_some_and(|q| q.send((full, bound)).is_ok())
    }

    /// Closes the queue and waits for the thread; the sink with everything
    /// sent, or the thread's error.
    fn close(mut self) -> io::Result<Sink> {
        self.queue = None;
        match self.thread.take().map(JoinHandle::join) {
            Some(Ok(r)) => r,
            Some(Err(_)) => Err(io::Error::other("the output thread panicked")),
            None => Err(stopped()),
        }
    }
}

/// A thread is never left running: closing the queue ends it, and the sink
/// it gives back is dropped unreleased (its temporary file removed).
impl Drop for Writer {
    fn drop(&mut self) {
        self.queue = None;
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// The output thread: applies chunks to the sink until the queue closes.
/// At the first error it sets `failed` and stops.
fn serve(
    sink: Receiver<Sink>,
    chunks: Receiver<(Vec<u8>, u64)>,
    give_back: Sender<Vec<u8>>,
    failed: &AtomicBool,
    slack: &AtomicU64,
    precision: Option<u8>,
) -> io::Result<Sink> {
    let mut sink = sink
        .recv()
        .map_err(|_| io::Error::other("the output thread was given no sink"))?;
    let mut text = Vec::with_capacity(2 * CHUNK);
    for (mut chunk, bound) in chunks {
        let before = sink.used();
        if let Err(e) = apply(&mut sink, &chunk, &mut text, precision) {
            failed.store(true, Ordering::Release);
            return Err(e);
        }
        slack.fetch_add(bound.saturating_sub(sink.used() - before), Ordering::AcqRel);
        chunk.clear();
        // The evaluator may be gone already (it is closing).
        let _ = give_back.send(chunk);
    }
    Ok(sink)
}

/// Reads the commands of a chunk in order.
struct Reader<'c> {
    chunk: &'c [u8],
    at: usize,
}

impl<'c> Reader<'c> {
    fn bytes(&mut self, n: usize) -> &'c [u8] {
        let b = &self.chunk[self.at..self.at + n];
        self.at += n;
        b
    }

    fn field<const N: usize>(&mut self) -> [u8; N] {
        self.bytes(N).try_into().expect("N bytes")
    }

    fn byte(&mut self) -> u8 {
        self.field::<1>()[0]
    }

    fn u32(&mut self) -> usize {
        u32::from_le_bytes(self.field()) as usize
    }

    fn u64(&mut self) -> u64 {
        u64::from_le_bytes(self.field())
    }
}

/// The edits of an edited line, read from its command.
struct Edits<'r, 'c> {
    reader: &'r mut Reader<'c>,
    left: usize,
}

impl<'c> Iterator for Edits<'_, 'c> {
    type Item = (Span, EditRef<'c>);

    fn next(&mut self) -> Option<Self::Item> {
        if self.left == 0 {
            return None;
        }
        self.left -= 1;
        let r = &mut *self.reader;
        let tag = r.byte();
        let span = Span::new(r.u32() as u32, r.u32() as u32);
        let value = r.u64();
        let edit = match tag {
            NUMBER => EditRef::Number(f64::from_bits(value)),
            REMOVE => EditRef::Remove,
            REPLACE => EditRef::Text(r.bytes(value as usize)),
            tag => unreachable!("edit {tag}"),
        };
        Some((span, edit))
    }
}

/// Decodes the commands of a chunk and writes them into the sink, text and
/// edited lines gathered in `text` first.
fn apply(
    sink: &mut Sink,
    chunk: &[u8],
    text: &mut Vec<u8>,
    precision: Option<u8>,
) -> io::Result<()> {
    text.clear();
    let mut r = Reader { chunk, at: 0 };
    while r.at < chunk.len() {
        match r.byte() {
            TEXT => {
                let n = r.u32();
                text.extend_from_slice(r.bytes(n));
            }
            LINE => {
                let (n, left) = (r.u32(), r.u32());
                let raw = r.bytes(n);
                let mut edits = Edits {
                    reader: &mut r,
                    left,
                };
                write_edits(text, raw, &mut edits, precision).map_err(|(v, _)| unprintable(v))?;
                text.push(b'\n');
            }
            RANGE => {
                let (start, len) = (r.u64(), r.u32());
                if !text.is_empty() {
                    sink.write(text)?;
                    text.clear();
                }
                sink.write_checked(start, r.bytes(len))?;
            }
            tag => unreachable!("output command {tag}"),
        }
    }
    if text.is_empty() {
        Ok(())
    } else {
        sink.write(text)
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use super::*;
    use crate::emit::{Destination, MemoryOut, OutputTooLarge};

    /// One step of a test's output.
    enum Op {
        Write(Vec<u8>),
        Line(Vec<u8>),
        /// Bytes `start..end` of the test's source file.
        Input(usize, usize),
        /// A source line and its edits.
        Edited(&'static str, Vec<(Span, Edit)>),
    }

    fn edit(start: u32, end: u32, e: Edit) -> (Span, Edit) {
        (Span::new(start, end), e)
    }

    /// Every kind of step, `n` times over, with numbers short and long, text
    /// to trim and lines of blanks only, and input ranges that follow each
    /// other (merged by the sink) or not.
    fn ops(n: usize, src_len: usize) -> Vec<Op> {
        let mut ops = Vec::new();
        let mut at = 0;
        for i in 0..n {
            let x = i as f64 * 0.05;
            ops.push(Op::Edited(
                "G1 X[#1] Y#2 Z[trailing] \t ",
                vec![
                    edit(4, 8, Edit::Number(x)),
                    edit(10, 12, Edit::Number(-(i as f64) / 3.0)),
                ],
            ));
            match i % 7 {
                0 => ops.push(Op::Edited(
                    "#1",
                    vec![edit(0, 2, Edit::Number(1e-4 * i as f64))],
                )),
                1 => ops.push(Op::Edited("  \t", vec![])),
                2 => ops.push(Op::Line(format!("(line {i}) ").into_bytes())),
                3 => ops.push(Op::Write(b"%\nM2\n".to_vec())),
                4 => ops.push(Op::Edited(
                    "F#3 #4=1 (debug,#3)\t",
                    vec![
                        edit(1, 3, Edit::Number(123456789012345.6)),
                        edit(4, 8, Edit::Remove),
                        edit(9, 19, Edit::Text(format!("(MSG,{i})"))),
                    ],
                )),
                5 => ops.push(Op::Edited("G0 X1 #5=2 ", vec![edit(6, 10, Edit::Remove)])),
                _ => {}
            }
            let len = 1 + i % 50;
            if at + len >= src_len {
                at = 0;
            }
            ops.push(Op::Input(at, at + len));
            // Every other range follows the one before.
            at += len + i % 2;
        }
        ops.push(Op::Write(vec![b'x'; 3 * CHUNK + 5]));
        ops.push(Op::Input(0, src_len));
        ops
    }

    fn run(out: &mut Output, ops: &[Op], src: &Arc<SourceFile>, data: &[u8]) {
        for op in ops {
            match op {
                Op::Write(b) => out.write(b).unwrap(),
                Op::Line(b) => out.line(b).unwrap(),
                Op::Input(a, b) => out.write_input(src, *a as u64, &data[*a..*b]).unwrap(),
                Op::Edited(raw, edits) => out.edited_line(raw.as_bytes(), edits).unwrap(),
            }
        }
    }

    /// A streamed source file (ranges of it can be recorded).
    fn streamed(dir: &Path) -> (Arc<SourceFile>, Vec<u8>) {
        let path = dir.join("in.ngc");
        let text: String = (0..800_000)
            .map(|i| format!("G1 X{i} Y{}\n", i % 7))
            .collect();
        std::fs::write(&path, &text).unwrap();
        let f = SourceFile::open(&path).unwrap();
        assert!(f.memory().is_none(), "test file must be streamed");
        (Arc::new(f), text.into_bytes())
    }

    fn threaded(out: &Output) -> bool {
        matches!(out.mode, Mode::Threaded(_))
    }

    /// Released to a file, output written on a thread (from the start or
    /// from a later line) is the output written directly, with and without
    /// a precision.
    #[test]
    fn a_thread_writes_what_is_written_directly() {
        let dir = tempfile::tempdir().unwrap();
        let src = Arc::new(SourceFile::new(
            "m.ngc".into(),
            "m.ngc".into(),
            b"G0 X1\nG1 Y2 (c)\n".repeat(100),
        ));
        let data = src.memory().unwrap().to_vec();
        let ops = ops(20_000, data.len());
        for precision in [None, Some(3)] {
            let mut outs = Vec::new();
            for after in [usize::MAX, 0, 1000] {
                let path = dir.path().join(format!("out-{after}.ngc"));
                let mut out = Output::new(
                    Sink::new(Destination::File(path.clone())).unwrap(),
                    precision,
                    after,
                );
                assert_eq!(threaded(&out), after == 0);
                run(&mut out, &ops, &src, &data);
                assert_eq!(threaded(&out), after != usize::MAX);
                out.finish().unwrap();
                outs.push(std::fs::read(&path).unwrap());
            }
            assert!(outs[0].len() > 20 * CHUNK);
            let text = String::from_utf8_lossy(&outs[0]);
            assert!(
                text.starts_with("G1 X0 Y0 Z[trailing]\n0\n"),
                "{precision:?}"
            );
            assert!(text.contains("\nG0 X1\n"), "{precision:?}");
            if precision.is_none() {
                assert!(text.contains("G1 X0.15000000000000002 Y-1 Z[trailing]\n"));
                assert!(text.contains("\nF123456789012345.6 (MSG,4)\n"));
            } else {
                assert!(text.contains("\nF123456789012345.594 (MSG,4)\n"));
            }
            assert!(outs[1] == outs[0], "thread from the start, {precision:?}");
            assert!(outs[2] == outs[0], "thread from line 1000, {precision:?}");
        }
    }

    /// On a thread, input bytes go with their offsets, checked by the sink
    /// until its list is full; released, they are the bytes written
    /// directly.
    #[test]
    fn input_ranges_on_the_thread_are_the_bytes_written_directly() {
        let dir = tempfile::tempdir().unwrap();
        let (src, data) = streamed(dir.path());
        let ops = ops(40_000, data.len());
        let mut outs = Vec::new();
        for after in [usize::MAX, 0] {
            let mut sink = Sink::new(Destination::Stdout).unwrap();
            sink.refer_to(src.clone());
            let mut out = Output::new(sink, None, after);
            run(&mut out, &ops, &src, &data);
            let mut sink = out.into_sink().unwrap();
            assert_eq!(sink.check_room(), 0, "ranges were checked until full");
            let mut released = Vec::new();
            sink.release(&mut released).unwrap();
            outs.push(released);
        }
        assert!(outs[0].len() > 20 * CHUNK);
        assert!(outs[1] == outs[0]);
    }

    /// A folder, a source file in memory, its bytes, and output on a thread
    /// to a file in that folder.
    fn threaded_to_file() -> (tempfile::TempDir, Arc<SourceFile>, Vec<u8>, Output) {
        let dir = tempfile::tempdir().unwrap();
        let data = b"G0 X1\n".repeat(100);
        let src = Arc::new(SourceFile::new(
            "m.ngc".into(),
            "m.ngc".into(),
            data.clone(),
        ));
        let path = dir.path().join("out.ngc");
        let out = Output::new(Sink::new(Destination::File(path)).unwrap(), None, 0);
        (dir, src, data, out)
    }

    /// Dropped before the end (the program failed), output on a thread
    /// leaves nothing behind: no output file, no temporary file.
    #[test]
    fn dropped_output_leaves_nothing() {
        let (dir, src, data, mut out) = threaded_to_file();
        assert!(threaded(&out));
        run(&mut out, &ops(20_000, data.len()), &src, &data);
        drop(out);
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }

    /// An error on the thread reaches the evaluator at a later write, every
    /// write after it fails, and nothing is released.
    #[test]
    fn a_failure_on_the_thread_stops_the_output() {
        let (dir, src, data, out) = threaded_to_file();
        drop(out);
        let mut sink = Sink::new(Destination::File(dir.path().join("out.ngc"))).unwrap();
        sink.limit_bytes(100_000, 0);
        let mut out = Output::new(sink, None, 0);
        // Taking the output past the sink's byte bound fails the thread
        // once the evaluator no longer counts it (it would take the sink
        // back before).
        let Mode::Threaded(w) = &mut out.mode else {
            panic!("no output thread")
        };
        w.room = u64::MAX;
        out.write_input(&src, 0, &data[..6]).unwrap();
        let e = (0..10_000)
            .find_map(|_| out.write(&[b'x'; 1000]).err())
            .expect("the failure reaches the evaluator");
        assert!(e.to_string().contains("the output grew past"), "{e}");
        assert!(matches!(out.mode, Mode::Stopped));
        assert!(out.line(b"G0").is_err());
        assert!(out.finish().is_err());
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    }

    /// Output thrown away never starts a thread.
    #[test]
    fn discarded_output_stays_here() {
        let mut out = Output::new(Sink::new(Destination::Discard).unwrap(), None, 0);
        out.edited_line(b"X#1", &[edit(1, 3, Edit::Number(1.5))])
            .unwrap();
        assert!(!threaded(&out));
        out.finish().unwrap();
    }

    /// With output on the thread, the write that takes the output past
    /// the byte limit is the one that fails, whatever its kind, and the
    /// bytes before it all fit: the sink comes back to this thread in time.
    #[test]
    fn the_byte_limit_fails_the_write_that_crosses_it() {
        let data = b"G0 X1\n".repeat(1000);
        let src = Arc::new(SourceFile::new(
            "m.ngc".into(),
            "m.ngc".into(),
            data.clone(),
        ));
        let ops = ops(3000, data.len());
        // The bytes each op writes.
        let mut sizes = Vec::new();
        for op in &ops {
            let buf = MemoryOut::default();
            let sink = Sink::new(Destination::Memory(buf.clone())).unwrap();
            let mut o = Output::new(sink, None, usize::MAX);
            run(&mut o, std::slice::from_ref(op), &src, &data);
            o.finish().unwrap();
            sizes.push(buf.take().len() as u64);
        }
        let total: u64 = sizes.iter().sum();
        for limit in [total / 3, total / 2 + 7, total - 1] {
            // The first op whose bytes do not fit.
            let (mut sum, mut cross) = (0, None);
            for (i, n) in sizes.iter().enumerate() {
                sum += n;
                if sum > limit {
                    cross = Some(i);
                    break;
                }
            }
            let cross = cross.unwrap();
            let mut sink = Sink::new(Destination::Memory(MemoryOut::default())).unwrap();
            sink.limit_bytes(limit, 0);
            let mut out = Output::new(sink, None, 0);
            assert!(threaded(&out));
            for (i, op) in ops.iter().enumerate() {
                let r = match op {
                    Op::Edited(raw, edits) => out.edited_line(raw.as_bytes(), edits),
                    Op::Line(l) => out.line(l),
                    Op::Write(b) => out.write(b),
                    Op::Input(a, b) => out.write_input(&src, *a as u64, &data[*a..*b]),
                };
                if i < cross {
                    r.unwrap();
                } else {
                    let e = r.unwrap_err();
                    let t = e.get_ref().and_then(|x| x.downcast_ref::<OutputTooLarge>());
                    let sum: u64 = sizes[..i].iter().sum();
                    assert_eq!(t.map(|t| t.room), Some(limit - sum), "{e}");
                    break;
                }
            }
        }
    }
}
