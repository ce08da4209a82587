//! Reading plain lines on a second core while the straight-line loop applies
//! them. The buffer is cut at line starts into chunks; both threads claim
//! chunks in order from one counter and read their lines (`read_line`, the
//! pure half of the loop's work), and the loop takes the chunks in order.
//! The loop thread reads chunks itself whenever the next one is not ready,
//! so the two threads share the reading and neither waits for long. A chunk
//! holds the same results the loop would get reading the lines itself;
//! reading stops at the first line that is not plain, where the loop stops
//! anyway. The loop never waits for the other thread: a chunk the other is
//! still reading is read again in place. The other thread, once far enough
//! ahead, sleeps on a condition variable until the loop moves on; nothing
//! spins.
//!
//! When a consumer reads the output as typed blocks (a target controller),
//! each chunk's lines are also decoded into [`Block`]s where the chunk is
//! read, so that decoding, which depends on a line's text alone, is done on
//! the second core too; the consumer gets the same block it would decode.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Condvar, Mutex};

use crate::block::{Block, Cuts, MovesRule, RawLine, RawWord};
use crate::eval::read::straight::{Plain, ToForm, ToRaw, read_line, read_line_into};

/// Chunks read ahead of the one being applied, at most.
const AHEAD: usize = 4;

/// What the loop finds at a line start.
#[derive(Clone, Copy)]
pub(in crate::eval) enum Read<'p> {
    /// An empty line (a newline only).
    Blank,
    /// A plain line, and its text decoded when the source decodes lines
    /// and could.
    Line(&'p Plain, Option<Decoded<'p>>),
    /// Not a plain line (or the end of the buffer): the run ends here.
    Stop,
    /// The source has no more lines for this run; another one goes on.
    Pause,
}

/// A source of lines for the straight-line loop, read at line starts in
/// order.
pub(in crate::eval) trait Lines {
    fn read(&mut self, i: usize) -> Read<'_>;
}

/// Reads each line when the loop asks for it, up to a byte offset; for a
/// consumer that reads blocks (`decode`), decodes it as a chunk read ahead
/// does (see [`decode_line`]), into room of its own.
pub(in crate::eval) struct InPlace<'b> {
    pub buf: &'b [u8],
    pub comments: bool,
    /// Lines starting here or later are left to another source.
    pub limit: usize,
    pub line: Plain,
    pub decode: bool,
    /// The consumer's rule for lines of moves alone (with `decode` only).
    pub rule: Option<MovesRule>,
    pub room: LineRoom,
}

/// Room to decode one line at a time in: its words, its block, and its
/// output where a rule writes it otherwise than as its text.
#[derive(Default)]
pub(in crate::eval) struct LineRoom {
    raw: RawLine,
    block: Block,
    out: Vec<u8>,
}

impl Lines for InPlace<'_> {
    #[inline(always)]
    fn read(&mut self, i: usize) -> Read<'_> {
        if i >= self.limit {
            Read::Pause
        } else if self.buf.get(i) == Some(&b'\n') {
            Read::Blank
        } else if !self.decode {
            if read_line(self.buf, i, &mut self.line, self.comments) {
                Read::Line(&self.line, None)
            } else {
                Read::Stop
            }
        } else {
            self.read_decoded(i)
        }
    }
}

impl InPlace<'_> {
    fn read_decoded(&mut self, i: usize) -> Read<'_> {
        let room = &mut self.room;
        room.out.clear();
        let p = &mut self.line;
        let read = decode_line(
            self.buf,
            i,
            p,
            self.comments,
            self.rule,
            &mut room.raw,
            &mut room.out,
        );
        let decoded = match read {
            None => return Read::Stop,
            Some(LineRead::Form(kind)) => Decoded::form(kind, self.rule, &room.out),
            Some(LineRead::Words { kept }) => {
                let text = &self.buf[i..p.text_end];
                match kept.then(|| room.raw.moves_only(text)).flatten() {
                    Some(words) => Some(Decoded::Moves(words)),
                    None => block_of(&room.raw, text, kept, &mut room.block)
                        .then_some(Decoded::Block(&room.block)),
                }
            }
        };
        Read::Line(&self.line, decoded)
    }
}

/// How a plain line read for a consumer that reads blocks came out.
enum LineRead {
    /// A line of moves alone the rule writes: [`Kind::Form`] or
    /// [`Kind::FormOut`] into the room's output.
    Form(Kind),
    /// Any other: its words are in the room's [`RawLine`] if `kept` (see
    /// [`ToRaw::finish`]).
    Words { kept: bool },
}

/// Reads the plain line at `buf[i..]` into `p` for a consumer that reads
/// blocks: a line of moves alone its `rule` writes is worked out to the
/// bytes written (appended to `out` where they are not its text); any
/// other keeps its words in `raw` from the same reading. `None`: not a
/// plain line. The one step
/// chunks read ahead and lines read in place share.
#[inline(always)]
fn decode_line(
    buf: &[u8],
    i: usize,
    p: &mut Plain,
    comments: bool,
    rule: Option<MovesRule>,
    raw: &mut RawLine,
    out: &mut Vec<u8>,
) -> Option<LineRead> {
    if let Some(rule) = rule.filter(|r| ToForm::may_take(buf, i, r)) {
        let mut sink = ToForm::new(i, rule);
        if !read_line_into(buf, i, p, comments, &mut sink) {
            return None;
        }
        if let Some(cuts) = sink.finish(p.text_end) {
            return Some(LineRead::Form(written(out, &buf[i..p.text_end], &cuts)));
        }
    }
    // The words from the same reading of the line (again for a line that
    // might have been one of moves alone).
    let mut sink = ToRaw::new(raw, i);
    if !read_line_into(buf, i, p, comments, &mut sink) {
        return None;
    }
    Some(LineRead::Words {
        kept: sink.finish(),
    })
}

/// The block of a line [`decode_line`] read as [`LineRead::Words`] (text
/// `text`): made from its words where they were kept, else decoded from
/// its text. False if it does not decode.
#[inline(always)]
fn block_of(raw: &RawLine, text: &[u8], kept: bool, block: &mut Block) -> bool {
    if kept {
        block.replay(raw, text).is_ok()
    } else {
        block.decode_into(text).is_ok()
    }
}

/// A line read ahead, decoded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(in crate::eval) enum Decoded<'p> {
    Block(&'p Block),
    /// A move and nothing else (see [`RawLine::moves_only`]): its words,
    /// for a consumer that takes such a line without a block.
    Moves(&'p [RawWord]),
    /// A move and nothing else that the consumer's `rule` writes as
    /// `written` (`None`: as the line's text; no bytes: as nothing, for a
    /// comment alone the rule drops).
    Form {
        written: Option<&'p [u8]>,
        rule: MovesRule,
    },
}

impl<'p> Decoded<'p> {
    /// A line of moves alone of kind `kind`, its bytes (for
    /// [`Kind::FormOut`]) in `out`, written by `rule`.
    #[inline(always)]
    fn form(kind: Kind, rule: Option<MovesRule>, out: &'p [u8]) -> Option<Decoded<'p>> {
        let written = match kind {
            Kind::Form => None,
            Kind::FormOut(at, n) => Some(&out[at as usize..at as usize + n as usize]),
            _ => return None,
        };
        rule.map(|rule| Decoded::Form { written, rule })
    }
}

/// How a chunk's line was decoded.
#[derive(Clone, Copy)]
enum Kind {
    No,
    /// Its block is the chunk's `blocks[k]`.
    Block,
    /// Its words are the chunk's `moves[at..at + len]`.
    Moves(u32, u8),
    /// A line of moves alone written as its text, or as the chunk's
    /// `out[at..at + len]`.
    Form,
    FormOut(u32, u16),
}

/// One line of a chunk read ahead.
#[derive(Clone, Copy)]
enum Rec {
    Blank,
    Line(Plain),
    Stop,
}

/// The lines of a chunk read ahead, and with `decode` how each decoded
/// (`kinds[k]` for `recs[k]`).
#[derive(Default)]
struct Chunk {
    recs: Vec<Rec>,
    blocks: Vec<Block>,
    moves: Vec<RawWord>,
    kinds: Vec<Kind>,
    /// Lines of moves alone as the consumer writes them, where that is not
    /// their text.
    out: Vec<u8>,
    /// The words of the line being read.
    raw: RawLine,
}

/// Spent chunks kept between straight runs: a long file read in windows
/// makes a run per window, and chunks made anew each time grew their lists
/// (and each block its words) from nothing again.
#[derive(Default)]
pub(in crate::eval) struct ChunkPool(Vec<Chunk>);

/// Chunk boundaries: line starts about `size` bytes apart, from the line
/// start `from` to the buffer's end.
pub(in crate::eval) fn cut(buf: &[u8], from: usize, size: usize) -> Vec<usize> {
    let size = size.max(1);
    let mut cuts = vec![from];
    let mut at = from + size;
    while at < buf.len() {
        match memchr::memchr(b'\n', &buf[at..]) {
            Some(k) if at + k + 1 < buf.len() => {
                cuts.push(at + k + 1);
                at += k + 1 + size;
            }
            _ => break,
        }
    }
    cuts.push(buf.len());
    cuts
}

/// A line of moves alone, `text`, as its consumer writes it (see
/// [`Cuts`]): as its text, or as bytes put at the end of `out`.
fn written(out: &mut Vec<u8>, text: &[u8], cuts: &Cuts) -> Kind {
    if cuts.is_whole() {
        return Kind::FormOut(out.len() as u32, 0);
    }
    if cuts.is_empty() {
        return Kind::Form;
    }
    let at = out.len();
    cuts.write(text, out);
    Kind::FormOut(at as u32, (out.len() - at) as u16)
}

/// State both threads share.
pub(in crate::eval) struct Shared<'b> {
    buf: &'b [u8],
    comments: bool,
    /// Decode each plain line into a block too.
    decode: bool,
    /// How the consumer writes lines of moves alone, if it says.
    rule: Option<MovesRule>,
    cuts: Vec<usize>,
    /// Next chunk to claim.
    next: AtomicUsize,
    /// Chunk the loop is applying.
    applied: AtomicUsize,
    /// The loop is done: stop reading.
    done: AtomicBool,
    /// The second thread has stopped (also if it failed): the loop waits
    /// for no chunk it claimed.
    helper_gone: AtomicBool,
    slots: Vec<Mutex<Option<Chunk>>>,
    /// Spent chunks, for reuse (their blocks keep their room for words).
    pool: Mutex<Vec<Chunk>>,
    /// Counts changes a waiting thread may be waiting for (a chunk stored,
    /// the loop moving to the next chunk, the loop done).
    changes: Mutex<u64>,
    changed: Condvar,
}

impl<'b> Shared<'b> {
    /// Chunks of `buf` from the line start `from` on; `decode`: plain lines
    /// are decoded into blocks as well.
    pub(in crate::eval) fn new(
        buf: &'b [u8],
        from: usize,
        comments: bool,
        decode: bool,
        rule: Option<MovesRule>,
        chunk: usize,
        pool: ChunkPool,
    ) -> Shared<'b> {
        let cuts = cut(buf, from, chunk);
        let n = cuts.len() - 1;
        Shared {
            buf,
            comments,
            decode,
            rule: rule.filter(|_| decode),
            cuts,
            next: AtomicUsize::new(0),
            applied: AtomicUsize::new(0),
            done: AtomicBool::new(false),
            helper_gone: AtomicBool::new(false),
            slots: (0..n).map(|_| Mutex::new(None)).collect(),
            pool: Mutex::new(pool.0),
            changes: Mutex::new(0),
            changed: Condvar::new(),
        }
    }

    /// The spent chunks, for the next run.
    pub(in crate::eval) fn into_pool(self) -> ChunkPool {
        ChunkPool(self.pool.into_inner().unwrap_or_default())
    }

    /// The change count, read before testing what a wait would wait for.
    fn seen(&self) -> u64 {
        self.changes.lock().map_or(0, |g| *g)
    }

    /// Wakes the other thread: something it may wait for happened.
    fn signal(&self) {
        if let Ok(mut g) = self.changes.lock() {
            *g += 1;
        }
        self.changed.notify_all();
    }

    /// Sleeps until the change count moves past `seen`.
    fn wait(&self, seen: u64) {
        let Ok(mut g) = self.changes.lock() else {
            return;
        };
        while *g == seen {
            match self.changed.wait(g) {
                Ok(next) => g = next,
                Err(_) => return,
            }
        }
    }

    fn chunks(&self) -> usize {
        self.slots.len()
    }

    /// Reads the lines of chunk `c`, up to the first one that is not plain.
    fn read_chunk(&self, c: usize) -> Chunk {
        let mut chunk = self
            .pool
            .lock()
            .ok()
            .and_then(|mut p| p.pop())
            .unwrap_or_default();
        let v = &mut chunk.recs;
        v.clear();
        chunk.kinds.clear();
        chunk.moves.clear();
        chunk.out.clear();
        let (mut i, end) = (self.cuts[c], self.cuts[c + 1]);
        while i < end {
            if self.buf[i] == b'\n' {
                v.push(Rec::Blank);
                i += 1;
                continue;
            }
            // Read straight into the record (no copy of the line).
            let k = v.len();
            v.push(Rec::Line(Plain::default()));
            let Some(Rec::Line(p)) = v.last_mut() else {
                unreachable!("just pushed")
            };
            if !self.decode {
                if !read_line(self.buf, i, p, self.comments) {
                    *v.last_mut().expect("pushed") = Rec::Stop;
                    return chunk;
                }
                i = p.next;
                continue;
            }
            let (raw, out) = (&mut chunk.raw, &mut chunk.out);
            let read = decode_line(self.buf, i, p, self.comments, self.rule, raw, out);
            let kept = match read {
                None => {
                    *v.last_mut().expect("pushed") = Rec::Stop;
                    return chunk;
                }
                Some(LineRead::Form(kind)) => {
                    i = p.next;
                    if chunk.kinds.len() < k {
                        chunk.kinds.resize(k, Kind::No);
                    }
                    chunk.kinds.push(kind);
                    continue;
                }
                Some(LineRead::Words { kept }) => kept,
            };
            let text = &self.buf[i..p.text_end];
            i = p.next;
            if chunk.kinds.len() < k {
                chunk.kinds.resize(k, Kind::No);
            }
            let moves = if kept {
                chunk.raw.moves_only(text)
            } else {
                None
            };
            let kind = if let Some(words) = moves {
                let at = chunk.moves.len() as u32;
                chunk.moves.extend_from_slice(words);
                Kind::Moves(at, words.len() as u8)
            } else {
                if chunk.blocks.len() <= k {
                    chunk.blocks.resize_with(k + 1, Block::default);
                }
                if block_of(&chunk.raw, text, kept, &mut chunk.blocks[k]) {
                    Kind::Block
                } else {
                    Kind::No
                }
            };
            chunk.kinds.push(kind);
        }
        chunk
    }

    fn store(&self, c: usize, v: Chunk) {
        if let Ok(mut s) = self.slots[c].lock() {
            *s = Some(v);
        }
        self.signal();
    }

    fn take(&self, c: usize) -> Option<Chunk> {
        self.slots[c].lock().ok().and_then(|mut s| s.take())
    }

    /// Claims the next chunk if it is at most `AHEAD` past the one applied.
    fn claim(&self) -> Option<usize> {
        let c = self.next.load(Ordering::Acquire);
        if c >= self.chunks() || c > self.applied.load(Ordering::Acquire) + AHEAD {
            return None;
        }
        self.next
            .compare_exchange(c, c + 1, Ordering::AcqRel, Ordering::Acquire)
            .ok()
    }

    /// The second thread: reads chunks until all are read or the loop is
    /// done.
    pub(in crate::eval) fn help(&self) {
        /// Marks the thread gone however it ends.
        struct Gone<'a, 'b>(&'a Shared<'b>);
        impl Drop for Gone<'_, '_> {
            fn drop(&mut self) {
                self.0.helper_gone.store(true, Ordering::Release);
                self.0.signal();
            }
        }
        let _gone = Gone(self);
        loop {
            let seen = self.seen();
            if self.done.load(Ordering::Acquire)
                || self.next.load(Ordering::Acquire) >= self.chunks()
            {
                return;
            }
            match self.claim() {
                Some(c) => {
                    let v = self.read_chunk(c);
                    self.store(c, v);
                }
                // Far enough ahead, or the loop took the chunk: sleep until
                // the loop moves on or stores it.
                None => self.wait(seen),
            }
        }
    }

    fn finish(&self) {
        self.done.store(true, Ordering::Release);
        self.signal();
    }
}

/// Lines from chunks read by either thread, in order.
pub(in crate::eval) struct Ahead<'s, 'b> {
    shared: &'s Shared<'b>,
    /// Chunk being applied (`usize::MAX` before the first).
    chunk: usize,
    lines: Chunk,
    pos: usize,
}

impl<'s, 'b> Ahead<'s, 'b> {
    pub(in crate::eval) fn new(shared: &'s Shared<'b>) -> Ahead<'s, 'b> {
        Ahead {
            shared,
            chunk: usize::MAX,
            lines: Chunk::default(),
            pos: 0,
        }
    }

    /// Chunk `c`, read by whichever thread gets to it first (or by both).
    fn obtain(&self, c: usize) -> Chunk {
        let s = self.shared;
        loop {
            let seen = s.seen();
            if let Some(v) = s.take(c) {
                return v;
            }
            // Lines that are decoded too are the larger share of the work:
            // the loop leaves reading to the other thread while that one
            // is at it, and sleeps until the chunk is stored (reading it
            // here too would only do the work twice, and reading chunks
            // further on would take the loop's time from its own work).
            if s.decode
                && s.next.load(Ordering::Acquire) > c
                && !s.helper_gone.load(Ordering::Acquire)
            {
                if let Some(k) = s.claim() {
                    let v = s.read_chunk(k);
                    s.store(k, v);
                } else {
                    s.wait(seen);
                }
                continue;
            }
            match s.claim() {
                Some(k) => {
                    let v = s.read_chunk(k);
                    if k == c {
                        return v;
                    }
                    s.store(k, v);
                }
                // The other thread is reading it. It may have lost its core
                // to other work: read the chunk here rather than wait (its
                // copy, stored later, is never read).
                None if s.next.load(Ordering::Acquire) > c => return s.read_chunk(c),
                // Lost a race to claim: try again.
                None => {}
            }
        }
    }
}

/// The loop is done with its lines, also when it fails or panics: the other
/// thread stops (a scope waiting for it would otherwise wait forever).
impl Drop for Ahead<'_, '_> {
    fn drop(&mut self) {
        self.shared.finish();
    }
}

impl Lines for Ahead<'_, '_> {
    #[inline]
    fn read(&mut self, _i: usize) -> Read<'_> {
        loop {
            let k = self.pos;
            if k < self.lines.recs.len() {
                self.pos += 1;
                let l = &self.lines;
                return match &l.recs[k] {
                    Rec::Blank => Read::Blank,
                    Rec::Line(q) => {
                        let decoded = match l.kinds.get(k) {
                            Some(Kind::Block) => Some(Decoded::Block(&l.blocks[k])),
                            Some(&Kind::Moves(at, n)) => {
                                let at = at as usize;
                                Some(Decoded::Moves(&l.moves[at..at + n as usize]))
                            }
                            Some(Kind::Form) => self.shared.rule.map(|rule| Decoded::Form {
                                written: None,
                                rule,
                            }),
                            Some(&Kind::FormOut(at, n)) => {
                                let at = at as usize;
                                self.shared.rule.map(|rule| Decoded::Form {
                                    written: Some(&l.out[at..at + n as usize]),
                                    rule,
                                })
                            }
                            _ => None,
                        };
                        Read::Line(q, decoded)
                    }
                    Rec::Stop => Read::Stop,
                };
            }
            let next = self.chunk.wrapping_add(1);
            if next >= self.shared.chunks() {
                return Read::Stop;
            }
            let spent = std::mem::take(&mut self.lines);
            if let Ok(mut pool) = self.shared.pool.lock() {
                pool.push(spent);
            }
            self.chunk = next;
            self.shared.applied.store(next, Ordering::Release);
            self.shared.signal();
            self.lines = self.obtain(next);
            self.pos = 0;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn chunks_start_at_line_starts_and_cover_the_buffer() {
        let buf = b"G1 X1\nG1 X2\n\nG1 X3\nG1 X4";
        for (from, size) in (0..buf.len() + 2).map(|s| (0, s)).chain([(6, 1), (12, 3)]) {
            let cuts = cut(buf, from, size);
            assert_eq!(cuts.first(), Some(&from));
            assert_eq!(cuts.last(), Some(&buf.len()));
            for w in cuts.windows(2) {
                assert!(w[0] < w[1], "{size}: {cuts:?}");
            }
            for &c in &cuts[1..cuts.len() - 1] {
                assert_eq!(buf[c - 1], b'\n', "{size}: {cuts:?}");
            }
        }
    }

    /// A decoded line as the bytes written by a rule or as its block.
    #[derive(Debug, PartialEq)]
    enum Terms {
        Written(Vec<u8>),
        Block(Box<Block>),
    }

    fn same_terms(d: Option<Decoded<'_>>, text: &[u8]) -> Option<Terms> {
        d.map(|d| match d {
            Decoded::Form { written, .. } => Terms::Written(written.unwrap_or(text).to_vec()),
            Decoded::Block(b) => Terms::Block(Box::new(b.clone())),
            Decoded::Moves(w) => {
                let mut b = Block::default();
                b.replay_words(w).expect("replays");
                Terms::Block(Box::new(b))
            }
        })
    }

    /// Lines read through chunks on two threads are the lines read in
    /// place, in order, with the same stop, decoded alike.
    #[test]
    fn chunks_give_the_lines_read_in_place() {
        let mut text = String::new();
        for k in 0..3000 {
            text.push_str(&format!("G1 X{k}.5 Y-{}\n", k + 1));
            if k % 5 == 0 {
                text.push_str(&format!("X{k}.50\n"));
            }
            if k % 7 == 0 {
                text.push('\n');
            }
            if k % 11 == 0 {
                text.push_str("(note)\n");
            }
        }
        // Lines far enough from the end for numbers read eight bytes at a
        // time.
        text.push_str("M2\nG1 X1\n(the end of the buffer is some way off)\n");
        let buf = text.as_bytes();
        // Without a helper thread too (when none can be started); with and
        // without blocks.
        // With a rule, the moves come as written by it: as their text, or
        // (with one decimal) without the trailing zero of `.50`.
        // A rule that drops comments writes a comment alone as nothing.
        let rule = Some(MovesRule {
            decimals: 1,
            max_digits: 8,
            max_len: 80,
            arcs: false,
            drops_comments: false,
        });
        let dropping = rule.map(|r| MovesRule {
            drops_comments: true,
            ..r
        });
        for (chunk, helper, decode, rule) in [1, 64, 1000, 1 << 20].into_iter().flat_map(|c| {
            [
                (c, true, false, None),
                (c, false, false, None),
                (c, true, true, None),
                (c, false, true, None),
                (c, true, true, rule),
                (c, false, true, rule),
                (c, true, true, dropping),
                (c, false, true, dropping),
            ]
        }) {
            let shared = Shared::new(buf, 0, true, decode, rule, chunk, ChunkPool::default());
            std::thread::scope(|s| {
                if helper {
                    s.spawn(|| shared.help());
                }
                let mut ahead = Ahead::new(&shared);
                // Lines read in place are decoded alike.
                let mut here = InPlace {
                    buf,
                    comments: true,
                    limit: usize::MAX,
                    line: Plain::default(),
                    decode,
                    rule: rule.filter(|_| decode),
                    room: LineRoom::default(),
                };
                let mut i = 0;
                let mut lines = 0;
                loop {
                    match (ahead.read(i), here.read(i)) {
                        (Read::Blank, Read::Blank) => i += 1,
                        (Read::Line(p, block), Read::Line(q, mine)) => {
                            assert_eq!((p.mask, p.next, p.text_end), (q.mask, q.next, q.text_end));
                            let text = &buf[i..p.text_end];
                            assert_eq!(same_terms(block, text), same_terms(mine, text));
                            // Only the slots of the line's words are read.
                            for s in (0..14).filter(|s| p.mask >> s & 1 == 1) {
                                assert_eq!(p.vals[s].to_bits(), q.vals[s].to_bits());
                            }
                            // The block is the line's text decoded; a move
                            // alone comes as its words, which make it.
                            let mut want = Block::default();
                            want.decode_into(&buf[i..p.text_end]).expect("decodes");
                            let text = &buf[i..p.text_end];
                            if rule.is_some_and(|r| r.drops_comments) && text[0] == b'(' {
                                let Some(Decoded::Form { written, .. }) = block else {
                                    panic!("comment not dropped by the rule");
                                };
                                assert_eq!(written, Some(&b""[..]));
                                i = p.next;
                                lines += 1;
                                continue;
                            }
                            if rule.is_some() && text[0] != b'(' {
                                let want = String::from_utf8_lossy(text).replace(".50", ".5");
                                let Some(Decoded::Form { written, .. }) = block else {
                                    panic!("not written by the rule: {want}");
                                };
                                let got = String::from_utf8_lossy(written.unwrap_or(text));
                                assert_eq!(got, want);
                                i = p.next;
                                lines += 1;
                                continue;
                            }
                            let got = block.map(|d| match d {
                                Decoded::Form { .. } => panic!("no rule"),
                                Decoded::Block(b) => b.clone(),
                                Decoded::Moves(w) => {
                                    let mut b = Block::default();
                                    b.replay_words(w).expect("replays");
                                    b
                                }
                            });
                            assert_eq!(got.as_ref(), decode.then_some(&want), "{chunk} {decode}");
                            i = p.next;
                        }
                        (Read::Stop, Read::Stop) => break,
                        _ => panic!("chunk {chunk}: lines differ at byte {i}"),
                    }
                    lines += 1;
                }
                drop(ahead);
                assert_eq!(&buf[i..i + 2], b"M2");
                assert!(lines > 3000);
            });
        }
    }
}
