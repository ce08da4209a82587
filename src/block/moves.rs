//! Lines of moves alone: the words the straight-line reader keeps of a
//! plain line ([`RawLine`]), the layout a writer may copy ([`Spacing`]), and
//! what a consumer that writes such lines by a rule needs ([`MovesRule`],
//! [`MoveValues`], [`Cuts`]).

use super::{BlockSpan, MotionMode, Shape};

/// Where a line of moves alone is written otherwise than as its text: the
/// `n` bytes ending at `end` (offsets in the line) are dropped for each of
/// the first `count` cuts (a number's trailing zeros), or the whole line
/// goes.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Cuts {
    at: [(u16, u8); 5],
    count: u8,
    /// The whole line goes, its newline too.
    whole: bool,
}

impl Cuts {
    /// The whole line is cut: nothing is written for it, not even an
    /// empty line.
    pub fn whole() -> Cuts {
        Cuts {
            whole: true,
            ..Cuts::default()
        }
    }

    /// Written as its text.
    pub fn is_empty(&self) -> bool {
        self.count == 0 && !self.whole
    }

    /// Written as nothing (see [`Cuts::whole`]).
    pub fn is_whole(&self) -> bool {
        self.whole
    }

    /// Adds a cut; false if there is no room (a line of moves alone has
    /// at most five words).
    #[inline(always)]
    pub fn push(&mut self, end: usize, n: usize) -> bool {
        match self.at.get_mut(usize::from(self.count)) {
            Some(slot) => {
                *slot = (end as u16, n as u8);
                self.count += 1;
                true
            }
            None => false,
        }
    }

    /// Bytes dropped.
    pub fn dropped(&self) -> usize {
        self.at[..usize::from(self.count)]
            .iter()
            .map(|&(_, n)| usize::from(n))
            .sum()
    }

    /// Appends `text` so written to `out`.
    pub fn write(&self, text: &[u8], out: &mut Vec<u8>) {
        if self.whole {
            return;
        }
        let mut from = 0;
        for &(end, n) in &self.at[..usize::from(self.count)] {
            let end = usize::from(end);
            out.extend_from_slice(&text[from..end - usize::from(n)]);
            from = end;
        }
        out.extend_from_slice(&text[from..]);
    }
}

/// What a writer of lines of moves alone (G0 or G1 with X, Y, Z, F, as
/// [`RawLine::moves_only`] has them; with `arcs` also G2 or G3 with I, J,
/// K) needs to know to write one as its own rules would, from the line's
/// words as they are read: numbers of at most `decimals` decimals and
/// `max_digits` digits are kept as written (`written_as_is`) or without
/// their trailing zeros (`without_trailing_zeros`), and a line so written
/// shorter than `max_len` bytes fits its line limit however it is counted.
/// With `drops_comments`, a line holding an inert comment alone (one the
/// straight-line reader takes: not a message, log or other active comment)
/// is written as nothing, not even an empty line.
/// A consumer gives it when a straight run starts; the reader then works
/// out each such line's output, and the consumer checks that the rule is
/// still its own when it takes the line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MovesRule {
    pub decimals: u8,
    pub max_digits: u8,
    pub max_len: usize,
    pub arcs: bool,
    pub drops_comments: bool,
}

/// The values of a line of moves alone: its motion code (G0–G3), X, Y, Z,
/// F, whether it has arc centre words (I, J, K) and their values. Kept
/// small: a batch of such lines holds one per line.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MoveValues {
    pub motion: Option<MotionMode>,
    /// X, Y, Z and F, each where `has` has its bit (1, 2, 4, 8).
    vals: [f64; 4],
    has: u8,
    pub ijk: bool,
    /// I, J and K, 0 where the line has none (all 0 without `ijk`).
    pub centre: [f64; 3],
}

impl MoveValues {
    pub fn new(
        motion: Option<MotionMode>,
        xyz: [Option<f64>; 3],
        f: Option<f64>,
        ijk: bool,
    ) -> MoveValues {
        let mut v = MoveValues {
            motion,
            ijk,
            ..MoveValues::default()
        };
        for (k, x) in xyz.into_iter().chain([f]).enumerate() {
            if let Some(x) = x {
                v.vals[k] = x;
                v.has |= 1 << k;
            }
        }
        v
    }

    /// From X, Y, Z and F as `vals` and which of them there are as the
    /// bits of `has` (1, 2, 4, 8; the others are ignored), and I, J, K as
    /// `centre`.
    #[inline(always)]
    pub(crate) fn from_parts(
        motion: Option<MotionMode>,
        vals: [f64; 4],
        has: u8,
        ijk: bool,
        centre: [f64; 3],
    ) -> MoveValues {
        MoveValues {
            motion,
            vals,
            has: has & 0b1111,
            ijk,
            centre,
        }
    }

    /// No word at all (a line of a comment alone).
    #[inline(always)]
    pub fn is_blank(&self) -> bool {
        self.motion.is_none() && self.has == 0 && !self.ijk
    }

    #[inline(always)]
    fn value(&self, k: usize) -> Option<f64> {
        (self.has >> k & 1 != 0).then(|| self.vals[k])
    }

    /// X, Y and Z.
    #[inline(always)]
    pub fn xyz(&self) -> [Option<f64>; 3] {
        [self.value(0), self.value(1), self.value(2)]
    }

    /// X (0), Y (1) or Z (2); `None` for any other `k`.
    #[inline(always)]
    pub fn axis(&self, k: usize) -> Option<f64> {
        if k < 3 { self.value(k) } else { None }
    }

    #[inline(always)]
    pub fn f(&self) -> Option<f64> {
        self.value(3)
    }

    /// An axis word is on the line.
    #[inline(always)]
    pub fn has_axis(&self) -> bool {
        self.has & 0b111 != 0
    }
}

/// A word as the straight-line reader read it (letter as written), kept
/// for a block made only where one is needed (see [`RawLine`]).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct RawWord {
    pub letter: u8,
    pub value: f64,
    pub span: BlockSpan,
    pub shape: Shape,
}

/// A plain line's words, line number and comment as the straight-line
/// reader read them: [`Block::replay`] makes the block [`Block::decode_into`]
/// makes of the line; a line of moves alone may be taken without one (see
/// [`RawLine::moves_only`]).
#[derive(Debug, Clone, Default)]
pub struct RawLine {
    words: [RawWord; 14],
    len: u8,
    pub(super) line_number: Option<(f64, BlockSpan)>,
    pub(super) comment: Option<BlockSpan>,
}

impl RawLine {
    pub fn clear(&mut self) {
        self.len = 0;
        self.line_number = None;
        self.comment = None;
    }

    /// Keeps a word (at most 14, as a plain line has at most one of each
    /// of its 14 letters; a 15th is dropped and the line never replays).
    #[inline(always)]
    pub fn push(&mut self, w: RawWord) {
        if let Some(slot) = self.words.get_mut(self.len as usize) {
            *slot = w;
            self.len += 1;
        }
    }

    pub fn set_line_number(&mut self, value: f64, span: BlockSpan) {
        self.line_number = Some((value, span));
    }

    pub fn set_comment(&mut self, span: BlockSpan) {
        self.comment = Some(span);
    }

    pub fn words(&self) -> &[RawWord] {
        &self.words[..self.len as usize]
    }

    /// Whether the line ends in a comment.
    pub fn has_comment(&self) -> bool {
        self.comment.is_some()
    }

    /// The words of a line of `text_len` bytes if it is a move and nothing
    /// else, written the plainest way: at most G X Y Z F, each letter upper
    /// case, G0 or G1, one blank between words and none around them, no
    /// line number, no comment. Such a line decodes into a block of those
    /// words alone (no other modal group), so it can be taken without one.
    #[inline]
    pub fn moves_only(&self, text: &[u8]) -> Option<&[RawWord]> {
        if self.line_number.is_some() || self.comment.is_some() || self.len == 0 || self.len > 5 {
            return None;
        }
        let words = self.words();
        let mut spacing = Spacing::new(0);
        for w in words {
            let ok = match w.letter {
                b'G' => w.value == 0.0 || w.value == 1.0,
                b'X' | b'Y' | b'Z' | b'F' => true,
                _ => false,
            };
            if !ok || !spacing.word(text, w.span.start as usize, w.span.end as usize) {
                return None;
            }
        }
        spacing.ends_at(text.len()).then_some(words)
    }
}

/// The plainest layout of a line's words, which a writer may copy: from
/// the line's start, each word one blank (a space) after the one before,
/// the last ending the line. Fed the words' offsets in order, it keeps
/// where the next must start; the reader of lines of moves alone, the
/// straight-line reader's [`RawLine::moves_only`] and the target's
/// writer all test the layout with it.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Spacing {
    start: usize,
    next: usize,
}

impl Spacing {
    /// `next` once a word is out of place: no word starts there.
    const OFF: usize = usize::MAX;

    /// For a line starting at `start` in its text.
    #[inline(always)]
    pub(crate) fn new(start: usize) -> Spacing {
        Spacing { start, next: start }
    }

    /// The word `text[start..end]` is where the layout has it; if not,
    /// no later word is.
    #[inline(always)]
    pub(crate) fn word(&mut self, text: &[u8], start: usize, end: usize) -> bool {
        let ok = start == self.next && (start == self.start || text[start - 1] == b' ');
        self.next = if ok { end + 1 } else { Spacing::OFF };
        ok
    }

    /// The line is out of the layout, whatever follows.
    #[inline(always)]
    pub(crate) fn break_off(&mut self) {
        self.next = Spacing::OFF;
    }

    /// No word has been read, and none was out of place.
    #[inline(always)]
    pub(crate) fn is_fresh(&self) -> bool {
        self.next == self.start
    }

    /// The words read are in place and the last ends the line at `end`.
    #[inline(always)]
    pub(crate) fn ends_at(&self, end: usize) -> bool {
        self.next == end + 1
    }
}
