//! A typed block: one executed (flat) line decoded once. After evaluation
//! every word's value is a number, so decoding is reading letters and
//! numbers; G and M codes become enums per modal group, the other words
//! values by letter. Comments and messages are kept with their spans.
//!
//! The decoder is lenient about what the evaluator already checked (one
//! word per modal group, value ranges) but never panics: a line it cannot
//! read is an [`DecodeError`] with the span of the trouble.

use std::fmt;

pub use crate::codes::{
    ArcDistance, CoordSystem, CutterComp, Distance, FeedMode, GCode, LatheMode, MCode, MotionMode,
    NonModal, PathMode, Plane, Retract, SpindleDir, SpindleMode, ToolLength, Units,
};
use crate::number::{Digits, POW10, digits_at};

/// A span of the decoded line (byte offsets).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Span {
    pub start: u16,
    pub end: u16,
}

/// What a word is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum WordKind {
    G(GCode),
    M(MCode),
    /// Any other letter (upper case), `@` or `^`.
    Value,
}

/// One word as written on the line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Word {
    /// Upper-case letter, or `@` / `^` (polar words).
    pub letter: u8,
    pub value: f64,
    pub kind: WordKind,
    pub span: Span,
    /// How its number is written.
    pub shape: Shape,
}

/// How a word's number is written, for a writer that may copy it as is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Shape {
    /// Written `[-]digits[.digits]` with no blank, no `+`, no leading zero
    /// but the lone one before the point, a point only before digits, no
    /// trailing zero after it, not `-0`, and at most 15 digits besides a
    /// lone leading zero.
    pub plain: bool,
    /// Written as `plain` says but for zeros ending the digits after the
    /// point (`1.2500`, `3.000`): the same number without them may be.
    pub trail: bool,
    pub neg: bool,
    /// Digits before the point (0 for a lone zero).
    pub int: u8,
    /// Digits after the point.
    pub frac: u8,
}

impl Shape {
    /// How the number `d` (read at `line[start..]`, after its sign) is
    /// written: one rule for every reader that hands words to a block.
    #[inline(always)]
    pub(crate) fn of(d: &Digits, line: &[u8], start: usize, neg: bool, plus: bool) -> Shape {
        let first = line[start];
        let last = line[d.end - 1];
        let lone_zero = d.int == 1 && first == b'0';
        let lead = !plus && d.int > 0 && (d.int == 1 || first != b'0');
        Shape {
            plain: lead
                && (!d.point || d.frac > 0 && last != b'0')
                && !(neg && lone_zero && d.frac == 0),
            trail: lead && d.frac > 0 && last == b'0',
            neg,
            int: if lone_zero { 0 } else { d.int as u8 },
            frac: d.frac as u8,
        }
    }
}

/// Whether a number written with `shape` is exactly what the target's
/// rules write for its value (`code`: a G or M number, whole or with one
/// decimal; otherwise a target's number format with `decimals` and
/// `max_digits`, `crate::controller::format::format_number`).
///
/// So it is when it is written plainly (see [`Shape::plain`]: the form
/// those rules write, at most 15 significant digits) with no more decimals
/// than the rules keep for a number with its digits before the point. Then
/// the double read from it is within 2^-52 of it relatively; scaled by
/// `10^d` it is within a quarter of the integer the number scaled is
/// (below 10^15), so rounding gives back exactly its digits, which are
/// written without trailing zeros: the number as written. The digits
/// before the point of the double are those written, since the number is
/// at least 10^-15 relatively below the next power of ten.
pub(crate) fn written_as_is(shape: Shape, code: bool, decimals: u8, max_digits: u8) -> bool {
    if !shape.plain {
        return false;
    }
    if code {
        return !shape.neg && shape.frac <= 1;
    }
    shape.frac <= max_digits.saturating_sub(shape.int).min(decimals)
}

/// The number `text` (of a value word, written as `shape` says) without
/// the zeros ending its digits after the point (and the point, when no
/// digit is left after it), when that is how the target's rules write its
/// value: [`written_as_is`] of the number so shortened (same value, fewer
/// decimals). `None` when it is not, or `shape` is not such a number.
pub(crate) fn without_trailing_zeros(
    shape: Shape,
    text: &[u8],
    decimals: u8,
    max_digits: u8,
) -> Option<&[u8]> {
    if !shape.trail {
        return None;
    }
    let zeros = text.iter().rev().take_while(|&&c| c == b'0').count();
    let frac = usize::from(shape.frac).checked_sub(zeros)?;
    // `-0.00` is 0, which the rules write without the sign.
    if shape.neg && shape.int == 0 && frac == 0 {
        return None;
    }
    let short = Shape {
        plain: true,
        trail: false,
        frac: frac as u8,
        ..shape
    };
    if !written_as_is(short, false, decimals, max_digits) {
        return None;
    }
    let end = text.len() - zeros - usize::from(frac == 0);
    Some(&text[..end])
}

/// [`Shape::of`] with [`written_as_is`] or [`without_trailing_zeros`] in
/// one step, for a value word (not G or M) read as `d` at `line[start..]`
/// after its sign byte `sign` (`-`, `+` or any other for none): `Some(n)`
/// when the target's rules write its value as the number written without
/// its last `n` bytes (0: as written; else its trailing zeros, and the
/// point when no digit is left after it), `None` when they write it
/// otherwise. The straight-line reader decides each word of a line of
/// moves alone with it (`block::tests` checks it against the three).
#[inline(always)]
pub(crate) fn kept_digits(
    d: &Digits,
    line: &[u8],
    start: usize,
    sign: u8,
    decimals: u8,
    max_digits: u8,
) -> Option<usize> {
    // A `+`, no digit before the point, or a point with none after it.
    if sign == b'+' || d.int == 0 || d.point && d.frac == 0 {
        return None;
    }
    let lone_zero = line[start] == b'0';
    if lone_zero && d.int > 1 {
        // A leading zero.
        return None;
    }
    let int = if lone_zero { 0 } else { d.int };
    let zeros = trailing_zeros(line, d.end, d.frac);
    let kept = d.frac - zeros;
    // `-0`, `-0.00`: 0, which the rules write without the sign.
    if sign == b'-' && int == 0 && kept == 0 {
        return None;
    }
    if kept
        > u32::from(max_digits)
            .saturating_sub(int)
            .min(u32::from(decimals))
    {
        return None;
    }
    Some((zeros + u32::from(zeros > 0 && kept == 0)) as usize)
}

/// How many of the `frac` digits ending at `line[end - 1]` are zeros at
/// their end (the point before them ends the count): eight bytes at once
/// where eight precede `end`.
#[inline(always)]
fn trailing_zeros(line: &[u8], end: usize, frac: u32) -> u32 {
    if frac == 0 {
        return 0;
    }
    let Some(bytes) = end.checked_sub(8).and_then(|a| line.get(a..end)) else {
        return line[..end].iter().rev().take_while(|&&c| c == b'0').count() as u32;
    };
    let mut b = [0u8; 8];
    b.copy_from_slice(bytes);
    // Zero bytes where the text has `0`; the last byte is the highest. At
    // most seven digits follow the point, so the eight bytes reach it.
    let x = u64::from_le_bytes(b) ^ 0x3030_3030_3030_3030;
    x.leading_zeros() / 8
}

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
    pub span: Span,
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
    line_number: Option<(f64, Span)>,
    comment: Option<Span>,
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

    pub fn set_line_number(&mut self, value: f64, span: Span) {
        self.line_number = Some((value, span));
    }

    pub fn set_comment(&mut self, span: Span) {
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

/// What a comment is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CommentKind {
    /// `( … )` or `; …` with nothing special.
    Plain,
    /// `(MSG, …)`: shown to the operator.
    Message,
    /// `(DEBUG, …)`, `(PRINT, …)`, `(LOG…)`, `(PROBEOPEN …)` and the like:
    /// for the interpreter's own logs.
    Log,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Comment {
    pub kind: CommentKind,
    /// The whole comment, parentheses or `;` included.
    pub span: Span,
    /// The text inside (after `MSG,` for a message).
    pub text: Span,
}

/// Why a line could not be decoded.
#[derive(Debug, Clone, PartialEq)]
pub struct DecodeError {
    pub span: Span,
    pub what: DecodeProblem,
}

#[derive(Debug, Clone, PartialEq)]
pub enum DecodeProblem {
    /// A byte that is not a word letter.
    BadCharacter(u8),
    /// A letter without a number.
    BadNumber,
    /// An unknown G code.
    UnknownG(f64),
    UnclosedComment,
    /// More than one word of a modal group.
    GroupConflict,
}

impl fmt::Display for DecodeProblem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DecodeProblem::BadCharacter(b) => write!(f, "unexpected byte 0x{b:02x}"),
            DecodeProblem::BadNumber => f.write_str("a word without a number"),
            DecodeProblem::UnknownG(v) => write!(f, "unknown G code {v}"),
            DecodeProblem::UnclosedComment => f.write_str("unclosed comment"),
            DecodeProblem::GroupConflict => f.write_str("two G codes of one modal group"),
        }
    }
}

/// A decoded flat line.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Block {
    /// `/` at the start.
    pub block_delete: bool,
    /// A `%` line.
    pub percent: bool,
    /// The N word.
    pub line_number: Option<(f64, Span)>,
    /// Every word in order (G, M and value words, not N).
    pub words: Vec<Word>,
    pub comments: Vec<Comment>,
    /// Index into `words` of each letter's value word (A = 0 … Z = 25),
    /// and of `@` (26) and `^` (27).
    value_at: [u8; 28],
    /// The value of each slot's word where `present` has its bit (0
    /// elsewhere).
    vals: [f64; 28],
    /// M words on the line.
    m_words: u8,
    /// The slots of `value_at` that hold a word, as bits.
    present: u32,
    /// The line's G code of each modal group, by [`GCode::group`] (a G80
    /// beside another motion code gives way to it): one code a group, and
    /// nothing here to add for a new group.
    gs: [Option<GCode>; 16],
    /// The groups of `gs` that hold a code, as bits.
    groups: u16,
}

const NO_WORD: u8 = u8::MAX;

/// The motion group ([`GCode::group`]).
const MOTION: u8 = 1;

fn slot(letter: u8) -> usize {
    match letter {
        b'@' => 26,
        b'^' => 27,
        l => (l - b'A') as usize,
    }
}

/// Axis letters in order X Y Z A B C U V W.
pub const AXIS_LETTERS: [u8; 9] = *b"XYZABCUVW";

impl Block {
    /// The value of a non-G/M word (`letter` upper case, or `@`/`^`).
    #[inline]
    pub fn value(&self, letter: u8) -> Option<f64> {
        let s = match letter {
            b'A'..=b'Z' => letter - b'A',
            b'@' => 26,
            b'^' => 27,
            _ => return None,
        };
        (self.present >> s & 1 != 0).then(|| self.vals[s as usize])
    }

    /// The non-G/M word with this letter.
    pub fn word(&self, letter: u8) -> Option<&Word> {
        if !(letter.is_ascii_uppercase() || letter == b'@' || letter == b'^') {
            return None;
        }
        let i = *self.value_at.get(slot(letter))?;
        if i == NO_WORD {
            None
        } else {
            self.words.get(i as usize)
        }
    }

    /// Axis words by axis index (X Y Z A B C U V W).
    pub fn axes(&self) -> [Option<f64>; 9] {
        if !self.has_axis() {
            return [None; 9];
        }
        std::array::from_fn(|i| self.value(AXIS_LETTERS[i]))
    }

    /// Whether the line is a move and nothing else: no code but G0–G3 (if
    /// any), no words but axis words, F, S and I, J, K, R; not a `%` line.
    pub fn is_plain_move(&self) -> bool {
        const ALLOWED: u32 = {
            let mut bits = 0;
            let mut i = 0;
            let letters = *b"XYZABCUVWFSIJKR";
            while i < letters.len() {
                bits |= 1 << (letters[i] - b'A');
                i += 1;
            }
            bits
        };
        !self.percent
            && self.present & !ALLOWED == 0
            && self.m_words == 0
            && self.groups & !(1 << MOTION) == 0
            && matches!(
                self.motion(),
                None | Some(
                    MotionMode::Rapid | MotionMode::Linear | MotionMode::ArcCw | MotionMode::ArcCcw
                )
            )
    }

    /// The line's code of modal group `group` ([`GCode::group`]).
    #[inline]
    pub fn code(&self, group: u8) -> Option<GCode> {
        *self.gs.get(group as usize)?
    }

    /// The motion code (group 1).
    #[inline]
    pub fn motion(&self) -> Option<MotionMode> {
        match self.gs[MOTION as usize] {
            Some(GCode::Motion(m)) => Some(m),
            _ => None,
        }
    }

    /// The units code (group 6).
    pub fn units(&self) -> Option<Units> {
        match self.gs[6] {
            Some(GCode::Units(u)) => Some(u),
            _ => None,
        }
    }

    /// The feed mode code (group 5).
    pub fn feed_mode(&self) -> Option<FeedMode> {
        match self.gs[5] {
            Some(GCode::FeedMode(f)) => Some(f),
            _ => None,
        }
    }

    /// The cutter compensation code (group 7).
    pub fn cutter_comp(&self) -> Option<CutterComp> {
        match self.gs[7] {
            Some(GCode::CutterComp(c)) => Some(c),
            _ => None,
        }
    }

    /// The tool length code (group 8).
    pub fn tool_length(&self) -> Option<ToolLength> {
        match self.gs[8] {
            Some(GCode::ToolLength(t)) => Some(t),
            _ => None,
        }
    }

    /// The retract code (group 10).
    pub fn retract(&self) -> Option<Retract> {
        match self.gs[10] {
            Some(GCode::Retract(r)) => Some(r),
            _ => None,
        }
    }

    /// The coordinate system code (group 12).
    pub fn coord(&self) -> Option<CoordSystem> {
        match self.gs[12] {
            Some(GCode::Coord(c)) => Some(c),
            _ => None,
        }
    }

    /// The non-modal code (group 0).
    pub fn non_modal(&self) -> Option<NonModal> {
        match self.gs[0] {
            Some(GCode::NonModal(n)) => Some(n),
            _ => None,
        }
    }

    /// The line's G codes of the modal groups, one a group, in the order
    /// of the groups (a G80 beside another motion code left out).
    pub fn modal_codes(&self) -> impl Iterator<Item = GCode> + '_ {
        self.gs.iter().flatten().copied()
    }

    /// Whether any axis word is present.
    pub fn has_axis(&self) -> bool {
        const AXES: u32 = {
            let mut bits = 0;
            let mut i = 0;
            while i < AXIS_LETTERS.len() {
                bits |= 1 << (AXIS_LETTERS[i] - b'A');
                i += 1;
            }
            bits
        };
        self.present & AXES != 0
    }

    /// The M codes of the line in order.
    pub fn m_codes(&self) -> impl Iterator<Item = (MCode, &Word)> {
        self.words.iter().filter_map(|w| match w.kind {
            WordKind::M(m) => Some((m, w)),
            _ => None,
        })
    }

    /// The G codes of the line in order.
    pub fn g_codes(&self) -> impl Iterator<Item = (GCode, &Word)> {
        self.words.iter().filter_map(|w| match w.kind {
            WordKind::G(g) => Some((g, w)),
            _ => None,
        })
    }

    /// Whether the line has nothing but comments (or nothing).
    pub fn is_empty(&self) -> bool {
        self.words.is_empty() && !self.percent
    }

    /// Decodes one flat line (no terminator; trailing `\r` and blanks are
    /// fine). Blanks may appear anywhere outside comments, as in RS274NGC.
    pub fn decode(line: &[u8]) -> Result<Block, DecodeError> {
        let mut b = Block {
            value_at: [NO_WORD; 28],
            vals: [0.0; 28],
            m_words: 0,
            ..Block::default()
        };
        b.decode_into(line)?;
        Ok(b)
    }

    /// Decodes into `self`, reusing its room.
    pub fn decode_into(&mut self, line: &[u8]) -> Result<(), DecodeError> {
        self.clear();
        read_flat_line(line, self)
    }

    /// The block of a line the straight-line reader read into `raw` (the
    /// same words, line number and comment, in the same order, through the
    /// same steps as [`Block::decode_into`]); `line` is the line's text.
    pub fn replay(&mut self, raw: &RawLine, line: &[u8]) -> Result<(), DecodeError> {
        self.clear();
        if let Some((v, s)) = raw.line_number {
            self.line_number = Some((v, s));
        }
        self.push_words(raw.words())?;
        if let Some(c) = raw.comment {
            self.comment(line, c.start as usize, c.end as usize);
        }
        Ok(())
    }

    /// [`Block::replay`] of a line of these words alone.
    pub fn replay_words(&mut self, words: &[RawWord]) -> Result<(), DecodeError> {
        self.clear();
        self.push_words(words)
    }

    fn push_words(&mut self, words: &[RawWord]) -> Result<(), DecodeError> {
        for w in words {
            self.push_word(w.letter.to_ascii_uppercase(), w.value, w.span, w.shape)?;
        }
        Ok(())
    }

    fn clear(&mut self) {
        self.block_delete = false;
        self.percent = false;
        self.line_number = None;
        self.words.clear();
        self.comments.clear();
        self.value_at = [NO_WORD; 28];
        let mut p = self.present;
        while p != 0 {
            self.vals[p.trailing_zeros() as usize] = 0.0;
            p &= p - 1;
        }
        self.present = 0;
        self.m_words = 0;
        if self.groups != 0 {
            self.gs = [None; 16];
            self.groups = 0;
        }
    }

    fn comment(&mut self, line: &[u8], start: usize, end: usize) {
        let semi = line[start] == b';';
        let inner_start = start + 1;
        let inner_end = if semi { end } else { end - 1 };
        let inner = &line[inner_start..inner_end];
        let lead = inner
            .iter()
            .position(|b| !matches!(b, b' ' | b'\t'))
            .unwrap_or(inner.len());
        let body = &inner[lead..];
        let starts = |w: &[u8]| body.len() >= w.len() && body[..w.len()].eq_ignore_ascii_case(w);
        let (kind, text_start) = if semi {
            (CommentKind::Plain, inner_start)
        } else if starts(b"msg,") {
            (CommentKind::Message, inner_start + lead + 4)
        } else if starts(b"debug,")
            || starts(b"print,")
            || starts(b"log")
            || starts(b"probe")
            || starts(b"abort,")
            || starts(b"py")
        {
            (CommentKind::Log, inner_start + lead)
        } else {
            (CommentKind::Plain, inner_start)
        };
        self.comments.push(Comment {
            kind,
            span: Span {
                start: start as u16,
                end: end as u16,
            },
            text: Span {
                start: text_start.min(inner_end) as u16,
                end: inner_end as u16,
            },
        });
    }

    fn push_word(
        &mut self,
        letter: u8,
        value: f64,
        span: Span,
        shape: Shape,
    ) -> Result<(), DecodeError> {
        let kind = match letter {
            b'N' if self.words.is_empty() && self.line_number.is_none() => {
                self.line_number = Some((value, span));
                return Ok(());
            }
            b'G' => {
                let g = GCode::decode(value).ok_or(DecodeError {
                    span,
                    what: DecodeProblem::UnknownG(value),
                })?;
                let group = g.group() as usize;
                let bit = 1 << group;
                // One code a group; a G80 beside another motion code is
                // allowed (the other one acts), as in LinuxCNC.
                let keep = self.groups & bit != 0
                    && match (self.gs[group], g) {
                        (Some(GCode::Motion(MotionMode::CancelCycle)), _) => false,
                        (_, GCode::Motion(MotionMode::CancelCycle)) => true,
                        _ => {
                            return Err(DecodeError {
                                span,
                                what: DecodeProblem::GroupConflict,
                            });
                        }
                    };
                if !keep {
                    self.gs[group] = Some(g);
                    self.groups |= bit;
                }
                WordKind::G(g)
            }
            b'M' => {
                self.m_words = self.m_words.saturating_add(1);
                WordKind::M(MCode::decode(value))
            }
            l => {
                let s = slot(l);
                if self.value_at[s] != NO_WORD {
                    return Err(DecodeError {
                        span,
                        what: DecodeProblem::GroupConflict,
                    });
                }
                self.value_at[s] = self.words.len().min(NO_WORD as usize - 1) as u8;
                self.vals[s] = value;
                self.present |= 1 << s;
                WordKind::Value
            }
        };
        self.words.push(Word {
            letter,
            value,
            kind,
            span,
            shape,
        });
        Ok(())
    }
}

/// What [`read_flat_line`] hands over as it reads a line, in line order.
pub(crate) trait LineSink {
    /// What stops the reading: a [`DecodeError`] of the text, or the
    /// sink's own.
    type Error: From<DecodeError>;
    /// Whether it takes the shapes of numbers ([`Shape::default`] for each
    /// if not).
    const SHAPES: bool;
    /// Whether the words written the usual way are read by [`read_words`]
    /// first (the same words, spans and shapes: only the tests read
    /// without it, to compare).
    const USUAL: bool = true;
    /// A `%` line (nothing but comments follow).
    fn on_percent(&mut self) -> Result<(), Self::Error>;
    /// `/` at the start.
    fn on_block_delete(&mut self);
    /// A word: its upper-case letter (or `@`, `^`), value, span and shape,
    /// and whether its number has blanks before or inside it (false: it
    /// follows the letter and holds none).
    fn on_word(
        &mut self,
        letter: u8,
        value: f64,
        span: Span,
        shape: Shape,
        spaced: bool,
    ) -> Result<(), Self::Error>;
    /// The comment `line[start..end]` (`(…)`, or `;` to the end).
    fn on_comment(&mut self, line: &[u8], start: usize, end: usize) -> Result<(), Self::Error>;
}

/// The one reader of a flat line's text (no terminator; trailing `\r` and
/// blanks are fine; blanks may appear anywhere outside comments, as in
/// RS274NGC): its words, comments, `%` and `/`, handed to `sink` as read.
/// [`Block::decode_into`] types what it reads; the evaluator's plain-line
/// path keeps the words alone.
#[inline(always)]
pub(crate) fn read_flat_line<S: LineSink>(line: &[u8], sink: &mut S) -> Result<(), S::Error> {
    read_flat_line_in(line, line.len(), sink)
}

/// [`read_flat_line`] of the line `buf[..len]`, where the bytes after it
/// in `buf` (the rest of the file, say) may be loaded but are not read:
/// numbers are read eight bytes at a time where eight bytes follow them
/// in `buf`, however short the line.
#[inline(always)]
pub(crate) fn read_flat_line_in<S: LineSink>(
    buf: &[u8],
    len: usize,
    sink: &mut S,
) -> Result<(), S::Error> {
    let n = len.min(buf.len()).min(u16::MAX as usize);
    let line = &buf[..n];
    // A number is read in `buf` (its digits and point) only where it ends
    // in the line: where the line is followed by neither.
    let buf = match buf.get(n) {
        Some(c) if c.is_ascii_digit() || *c == b'.' => line,
        _ => buf,
    };
    let span = |a: usize, b: usize| Span {
        start: a as u16,
        end: b as u16,
    };
    let mut i = skip_blanks(line, 0);
    if line.get(i) == Some(&b'%') {
        let j = skip_blanks(line, i + 1);
        if j >= n || line[j] == b';' || line[j] == b'(' {
            sink.on_percent()?;
            return comments_only(line, j, sink);
        }
    }
    if line.get(i) == Some(&b'/') {
        sink.on_block_delete();
        i = skip_blanks(line, i + 1);
    }
    if S::USUAL {
        // The words written the usual way first, then the rest.
        match read_words(buf, i, n, &mut Usual { sink: &mut *sink })? {
            WordsEnd::Line { .. } => return Ok(()),
            WordsEnd::At(k) => i = k,
        }
    }
    while i < n {
        let c = line[i];
        match c {
            b' ' | b'\t' | b'\r' | b'\n' => i += 1,
            b'(' | b';' => i = comment_at(line, i, sink)?,
            _ => {
                let letter = c.to_ascii_uppercase();
                if !(letter.is_ascii_uppercase() || letter == b'@' || letter == b'^') {
                    return Err(DecodeError {
                        span: span(i, i + 1),
                        what: DecodeProblem::BadCharacter(c),
                    }
                    .into());
                }
                let num = read_number(line, buf, i + 1, S::SHAPES).ok_or(DecodeError {
                    span: span(i, i + 1),
                    what: DecodeProblem::BadNumber,
                })?;
                sink.on_word(letter, num.value, span(i, num.end), num.shape, num.spaced)?;
                i = num.next;
            }
        }
    }
    Ok(())
}

/// No letter: [`WordSink::LETTERS`] of a byte that does not start a word.
pub(crate) const NO_LETTER: u8 = 0xff;

/// What [`read_words`] hands on as it reads the words of a line written
/// the usual way: a letter, a sign maybe, the digits with no blank among
/// them, then blanks maybe.
pub(crate) trait WordSink {
    /// What stops the reading besides the end of the words.
    type Error;
    /// What each byte is as a word's letter: [`NO_LETTER`] where it starts
    /// no word the reading takes.
    const LETTERS: &'static [u8; 256];
    /// Whether the line ends at the length given (else at a newline, which
    /// [`WordSink::ends`] tells).
    const BOUNDED: bool;
    /// Whether each word is handed on as soon as its number is read, before
    /// the bytes after it show it complete: for a sink that drops the line
    /// whole where the reading stops with [`WordsEnd::At`] at anything but
    /// the comment it reads (a number going on after blanks then stops it
    /// at the digit or point that follows them).
    const EARLY: bool;
    /// The digits at `buf[i..]` read eight bytes at a time, if they are
    /// there ([`crate::number::digits_in`] or [`digits_at`]).
    fn digits(buf: &[u8], i: usize) -> Option<Digits>;
    /// A number [`WordSink::digits`] did not read, at `buf[i..]`: its value
    /// and end, or `None` to stop before its word.
    fn slow_number(buf: &[u8], i: usize) -> Option<(f64, usize)>;
    /// Whether the byte `c` at `buf[k]`, after a word and its blanks, ends
    /// the line (unbounded lines only).
    fn ends(&self, buf: &[u8], k: usize, c: u8) -> bool;
    /// A word: its letter's offset and [`WordSink::LETTERS`] value, the
    /// byte after the letter (its sign, if `-` or `+`), where its digits
    /// start, its value and end, and its digits as read eight bytes at a
    /// time (`None`: read by [`WordSink::slow_number`]).
    #[allow(clippy::too_many_arguments)]
    fn word(
        &mut self,
        buf: &[u8],
        at: usize,
        letter: u8,
        sign: u8,
        num: usize,
        value: f64,
        end: usize,
        digits: Option<&Digits>,
    ) -> Result<(), Self::Error>;
}

/// Where [`read_words`] stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum WordsEnd {
    /// The line ended: its text ends at `text_end` (after the last word),
    /// its blanks at `end` (the newline, or the length given).
    Line { text_end: usize, end: usize },
    /// At `buf[i]`, something else: a byte that starts no word, or a word
    /// not handed on (its number is not written the usual way, or goes on
    /// after blanks).
    At(usize),
}

/// The one reader of words written the usual way, from `buf[i..]` (the
/// line `buf[..n]` for a [`WordSink::BOUNDED`] sink, else up to the newline
/// [`WordSink::ends`] takes): each word is handed to `sink` once the
/// bytes after it show it complete, until the line ends or something else
/// comes. The straight-line loop reads its lines' words with it (its own
/// letters, to a newline); the flat-line reader ([`read_flat_line_in`])
/// starts with it (every letter, to the line's length) and reads the rest
/// of a line (numbers with blanks, comments, any byte) itself.
#[inline(always)]
pub(crate) fn read_words<S: WordSink>(
    buf: &[u8],
    mut i: usize,
    n: usize,
    sink: &mut S,
) -> Result<WordsEnd, S::Error> {
    let text = if S::BOUNDED {
        &buf[..n.min(buf.len())]
    } else {
        buf
    };
    let at = |j: usize| text.get(j).copied().unwrap_or(0);
    loop {
        let letter = S::LETTERS[usize::from(at(i))];
        if letter == NO_LETTER {
            return Ok(WordsEnd::At(i));
        }
        let letter_at = i;
        i += 1;
        let sign = at(i);
        let neg = sign == b'-';
        if matches!(sign, b'-' | b'+') {
            i += 1;
        }
        let num = i;
        // The blanks after the number, and whether it goes on after them.
        let after = |end: usize| {
            let mut k = end;
            while matches!(at(k), b' ' | b'\t' | b'\r') {
                k += 1;
            }
            let c = at(k);
            (k, c, c.is_ascii_digit() || c == b'.')
        };
        let (k, c) = match S::digits(buf, i) {
            Some(d) => {
                let v = d.value();
                let value = if neg { -v } else { v };
                if S::EARLY {
                    sink.word(buf, letter_at, letter, sign, num, value, d.end, Some(&d))?;
                }
                let (k, c, goes_on) = after(d.end);
                if goes_on && !S::EARLY {
                    return Ok(WordsEnd::At(letter_at));
                }
                if !S::EARLY {
                    sink.word(buf, letter_at, letter, sign, num, value, d.end, Some(&d))?;
                }
                i = d.end;
                (k, c)
            }
            None => {
                let Some((v, end)) = S::slow_number(buf, i) else {
                    return Ok(WordsEnd::At(letter_at));
                };
                let value = if neg { -v } else { v };
                if S::EARLY {
                    sink.word(buf, letter_at, letter, sign, num, value, end, None)?;
                }
                let (k, c, goes_on) = after(end);
                if goes_on && !S::EARLY {
                    return Ok(WordsEnd::At(letter_at));
                }
                if !S::EARLY {
                    sink.word(buf, letter_at, letter, sign, num, value, end, None)?;
                }
                i = end;
                (k, c)
            }
        };
        let ended = if S::BOUNDED {
            k >= n
        } else {
            sink.ends(buf, k, c)
        };
        if ended {
            return Ok(WordsEnd::Line {
                text_end: i,
                end: k,
            });
        }
        i = k;
    }
}

/// Every letter (upper case) and `@`, `^`: the words of a flat line.
static FLAT_LETTERS: [u8; 256] = {
    let mut t = [NO_LETTER; 256];
    let mut c = 0;
    while c < 256 {
        let b = c as u8;
        if b.is_ascii_alphabetic() || b == b'@' || b == b'^' {
            t[c] = b.to_ascii_uppercase();
        }
        c += 1;
    }
    t
};

/// The flat-line reader's words read the usual way by [`read_words`],
/// handed to its sink as it hands them.
struct Usual<'s, S> {
    sink: &'s mut S,
}

impl<S: LineSink> WordSink for Usual<'_, S> {
    type Error = S::Error;
    const LETTERS: &'static [u8; 256] = &FLAT_LETTERS;
    const BOUNDED: bool = true;
    const EARLY: bool = false;

    #[inline(always)]
    fn digits(buf: &[u8], i: usize) -> Option<Digits> {
        digits_at(buf, i)
    }

    #[inline(always)]
    fn slow_number(_: &[u8], _: usize) -> Option<(f64, usize)> {
        None
    }

    #[inline(always)]
    fn ends(&self, _: &[u8], _: usize, _: u8) -> bool {
        false
    }

    #[inline(always)]
    fn word(
        &mut self,
        buf: &[u8],
        at: usize,
        letter: u8,
        sign: u8,
        num: usize,
        value: f64,
        end: usize,
        digits: Option<&Digits>,
    ) -> Result<(), S::Error> {
        let shape = match digits {
            Some(d) if S::SHAPES => Shape::of(d, buf, num, sign == b'-', sign == b'+'),
            _ => Shape::default(),
        };
        let span = Span {
            start: at as u16,
            end: end as u16,
        };
        self.sink.on_word(letter, value, span, shape, false)
    }
}

fn comments_only<S: LineSink>(line: &[u8], mut i: usize, sink: &mut S) -> Result<(), S::Error> {
    while i < line.len() {
        i = match line[i] {
            b'(' | b';' => comment_at(line, i, sink)?,
            _ => i + 1,
        };
    }
    Ok(())
}

/// Hands over the comment starting at `line[i]` (`(` or `;`); the offset
/// after it.
fn comment_at<S: LineSink>(line: &[u8], i: usize, sink: &mut S) -> Result<usize, S::Error> {
    let n = line.len();
    if line[i] == b';' {
        sink.on_comment(line, i, n)?;
        return Ok(n);
    }
    let close = line[i..]
        .iter()
        .position(|&b| b == b')')
        .ok_or(DecodeError {
            span: Span {
                start: i as u16,
                end: n as u16,
            },
            what: DecodeProblem::UnclosedComment,
        })?;
    sink.on_comment(line, i, i + close + 1)?;
    Ok(i + close + 1)
}

impl LineSink for Block {
    type Error = DecodeError;
    const SHAPES: bool = true;

    fn on_percent(&mut self) -> Result<(), DecodeError> {
        self.percent = true;
        Ok(())
    }

    fn on_block_delete(&mut self) {
        self.block_delete = true;
    }

    #[inline(always)]
    fn on_word(
        &mut self,
        letter: u8,
        value: f64,
        span: Span,
        shape: Shape,
        _: bool,
    ) -> Result<(), DecodeError> {
        self.push_word(letter, value, span, shape)
    }

    fn on_comment(&mut self, line: &[u8], start: usize, end: usize) -> Result<(), DecodeError> {
        self.comment(line, start, end);
        Ok(())
    }
}

fn skip_blanks(line: &[u8], mut i: usize) -> usize {
    while i < line.len() && matches!(line[i], b' ' | b'\t' | b'\r') {
        i += 1;
    }
    i
}

/// A number [`read_number`] read.
struct Num {
    value: f64,
    /// The offset just after it.
    end: usize,
    /// How it is written ([`Shape::default`] unless asked for).
    shape: Shape,
    /// Read with blanks before or inside it (false: it starts where it was
    /// looked for and holds none).
    spaced: bool,
    /// Where the line goes on: after the blanks that follow it.
    next: usize,
}

/// Reads `[+-]digits[.digits]` with blanks allowed between its characters.
/// The shape is worked out only if `shapes` asks for it.
///
/// `tail` is `line` and maybe bytes after it, the first of which is
/// neither a digit nor a point: they may be loaded, but no number runs
/// into them.
///
/// A number of at most 15 significant digits without blanks (every number
/// the evaluator writes, and the usual CAM number) is read in one pass:
/// its digits as an integer, exact below 2^53, divided by an exact power of
/// ten. One correctly rounded division of two exact values is the correctly
/// rounded value of the decimal, which is what `str::parse` returns too.
/// Longer numbers without blanks are parsed where they are written; the
/// rest (blanks inside) is gathered first.
#[inline(always)]
fn read_number(line: &[u8], tail: &[u8], start: usize, shapes: bool) -> Option<Num> {
    let mut i = start;
    let (neg, plus) = match line.get(i) {
        Some(b'-') => {
            i += 1;
            (true, false)
        }
        Some(b'+') => {
            i += 1;
            (false, true)
        }
        _ => (false, false),
    };
    let body = i;
    let first = line.get(i).copied().unwrap_or(b' ');
    // The usual number, read eight bytes at a time.
    if let Some(d) = digits_at(tail, i) {
        let after = skip_blanks(line, d.end);
        if !matches!(line.get(after), Some(c) if c.is_ascii_digit() || *c == b'.') {
            let shape = if shapes {
                Shape::of(&d, line, i, neg, plus)
            } else {
                Shape::default()
            };
            let v = d.value();
            return Some(Num {
                value: if neg { -v } else { v },
                end: d.end,
                shape,
                spaced: false,
                next: after,
            });
        }
    }
    let mut mant: u64 = 0;
    // Significant digits (leading zeros not counted), digits before the
    // point, digits after it, the last character.
    let mut digits = 0u32;
    let mut int = 0u32;
    let mut frac: Option<u32> = None;
    let mut last = b' ';
    while let Some(&c) = line.get(i) {
        if c.is_ascii_digit() {
            if digits < 19 {
                mant = mant * 10 + u64::from(c - b'0');
            }
            if mant != 0 {
                digits += 1;
            }
            match frac.as_mut() {
                Some(f) => *f += 1,
                None => int += 1,
            }
        } else if c == b'.' && frac.is_none() {
            frac = Some(0);
        } else {
            break;
        }
        last = c;
        i += 1;
    }
    let point = frac.is_some();
    let frac = frac.unwrap_or(0);
    // What follows must end the number for certain: not a second point,
    // not blanks before more of it.
    let after = skip_blanks(line, i);
    let ends = !matches!(line.get(after), Some(c) if c.is_ascii_digit() || *c == b'.');
    if int + frac > 0 && ends {
        let whole = |v: f64, shape| {
            Some(Num {
                value: if neg { -v } else { v },
                end: i,
                shape,
                spaced: false,
                next: after,
            })
        };
        if digits <= 15 && frac <= 22 {
            // Below 10^15: exact through i64 (one instruction, unlike u64).
            let v = mant as i64 as f64 / POW10[frac as usize];
            if !shapes {
                return whole(v, Shape::default());
            }
            let lone_zero = int == 1 && first == b'0';
            let int_digits = if lone_zero { 0 } else { int };
            let lead = !plus && int > 0 && (int == 1 || first != b'0') && int_digits + frac <= 15;
            let shape = Shape {
                plain: lead
                    && (!point || frac > 0 && last != b'0')
                    && !(neg && lone_zero && frac == 0),
                trail: lead && frac > 0 && last == b'0',
                neg,
                int: int_digits.min(255) as u8,
                frac: frac.min(255) as u8,
            };
            return whole(v, shape);
        }
        // Up to 19 digits (all kept in `mant`) that make an integer of at
        // most 2^53 (the numbers of 16 or 17 digits the evaluator writes
        // for values such as 0.07500000000000001): exact as a double too,
        // so one division again.
        if digits <= 19 && mant <= 1 << 53 && frac <= 22 {
            return whole(mant as i64 as f64 / POW10[frac as usize], Shape::default());
        }
        // Long, but in one piece: read where it is written.
        if let Some(v) = std::str::from_utf8(&line[body..i])
            .ok()
            .and_then(|t| t.parse::<f64>().ok())
        {
            return whole(v, Shape::default());
        }
    }
    read_number_slow(line, start).map(|(value, end)| Num {
        value,
        end,
        shape: Shape::default(),
        spaced: true,
        next: end,
    })
}

/// [`read_number`] for numbers with blanks inside or many digits.
#[cold]
fn read_number_slow(line: &[u8], start: usize) -> Option<(f64, usize)> {
    let mut buf = [0u8; 64];
    let mut len = 0;
    let mut i = skip_blanks(line, start);
    let mut end = i;
    if let Some(&c) = line.get(i)
        && (c == b'-' || c == b'+')
    {
        buf[0] = c;
        len = 1;
        i += 1;
        end = i;
    }
    let mut digits = 0;
    loop {
        i = skip_blanks(line, i);
        match line.get(i) {
            Some(&c) if c.is_ascii_digit() || c == b'.' => {
                if len < buf.len() {
                    buf[len] = c;
                    len += 1;
                }
                digits += c.is_ascii_digit() as usize;
                i += 1;
                end = i;
            }
            _ => break,
        }
    }
    if digits == 0 || len >= buf.len() {
        return None;
    }
    let text = std::str::from_utf8(&buf[..len]).ok()?;
    let text = text.strip_prefix('+').unwrap_or(text);
    let v: f64 = text.parse().ok()?;
    Some((v, end))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The block sink reading every word itself, without [`read_words`].
    struct Unusual(Block);

    impl LineSink for Unusual {
        type Error = DecodeError;
        const SHAPES: bool = true;
        const USUAL: bool = false;

        fn on_percent(&mut self) -> Result<(), DecodeError> {
            self.0.on_percent()
        }

        fn on_block_delete(&mut self) {
            self.0.on_block_delete();
        }

        fn on_word(
            &mut self,
            letter: u8,
            value: f64,
            span: Span,
            shape: Shape,
            spaced: bool,
        ) -> Result<(), DecodeError> {
            self.0.on_word(letter, value, span, shape, spaced)
        }

        fn on_comment(&mut self, line: &[u8], start: usize, end: usize) -> Result<(), DecodeError> {
            self.0.on_comment(line, start, end)
        }
    }

    proptest::proptest! {
        /// The words written the usual way, read by `read_words`, make
        /// the block (or the error) the flat-line reader makes reading
        /// every word itself, with or without bytes after the line.
        #[test]
        fn usual_words_read_as_the_whole_reader_reads_them(
            parts in proptest::collection::vec(
                proptest::prop_oneof![
                    "[gGxXyYzZmMnNfF@^][+-]?[0-9]{0,5}(\\.[0-9]{0,4})?",
                    "[gGxXyYzZmMnNfF@^]",
                    "[ \t\r]{0,2}[0-9.]{1,3}",
                    "[+-]?[0-9]{14,20}",
                    "[ \t\r]{0,2}",
                    "[/%;()#\n.]",
                    "\\([a-z ,]{0,5}\\)",
                ],
                0..12,
            ),
            tail in "[\n0-9. X]{0,20}",
        ) {
            let line = parts.concat();
            let buf = format!("{line}{tail}");
            for b in [line.as_bytes(), buf.as_bytes()] {
                let mut usual = Block::default();
                usual.clear();
                let got = read_flat_line_in(b, line.len(), &mut usual);
                let mut whole = Unusual(Block::default());
                whole.0.clear();
                let want = read_flat_line_in(b, line.len(), &mut whole);
                proptest::prop_assert_eq!(&got, &want, "{:?}", buf);
                if want.is_ok() {
                    proptest::prop_assert_eq!(&usual, &whole.0, "{:?}", buf);
                }
            }
        }

        /// The one-step rule of the straight-line reader gives what the
        /// shape of the number and the writer's two tests give, for value
        /// words at any place in a line (the eight-byte read of their end
        /// and the byte-by-byte one).
        #[test]
        fn kept_digits_is_the_shape_rule(
            lead in 0usize..10,
            sign in "[-+]?",
            text in "[0-9]{0,8}(\\.[0-9]{0,8})?",
            decimals in 0u8..7,
            max_digits in 1u8..10,
        ) {
            let line = format!("{}X{sign}{text} Y1{}", " ".repeat(lead), " ".repeat(16));
            let b = line.as_bytes();
            let num = lead + 1 + sign.len();
            if let Some(d) = digits_at(b, num) {
                let (neg, plus) = (sign == "-", sign == "+");
                let shape = Shape::of(&d, b, num, neg, plus);
                let want = if written_as_is(shape, false, decimals, max_digits) {
                    Some(0)
                } else {
                    let number = &b[lead + 1..d.end];
                    without_trailing_zeros(shape, number, decimals, max_digits)
                        .map(|kept| number.len() - kept.len())
                };
                let sign_byte = sign.bytes().next().unwrap_or(b'X');
                proptest::prop_assert_eq!(
                    kept_digits(&d, b, num, sign_byte, decimals, max_digits),
                    want,
                    "{:?} decimals {} digits {}", line, decimals, max_digits
                );
            }
        }

        /// The one-pass number reader gives what the general one gives
        /// (value, end, or no number) on any text of number characters.
        #[test]
        fn number_reader_fast_path_is_exact(
            text in "[-+ .0-9]{0,24}[XY; (]?",
            at in 0usize..3,
        ) {
            let line = format!("X{text}");
            let start = at.min(line.len());
            let fast = read_number(line.as_bytes(), line.as_bytes(), start, true).map(|n| (n.value, n.end));
            let slow = read_number_slow(line.as_bytes(), start);
            proptest::prop_assert_eq!(
                fast.map(|(v, e)| (v.to_bits(), e)),
                slow.map(|(v, e)| (v.to_bits(), e)),
                "{:?}", line
            );
        }

        /// A line read with the bytes after it reads as the line alone:
        /// the same block, or the same error.
        #[test]
        fn line_reads_the_same_with_bytes_after_it(
            line in "[GXYM ]{0,3}[-+]?[0-9]{0,9}(\\.[0-9]{0,9})?( [XY][0-9.]{1,12})?",
            tail in "[\r\n0-9.X ]{0,20}",
        ) {
            let buf = format!("{line}{tail}");
            let mut alone = Block::default();
            let want = alone.decode_into(line.as_bytes());
            let mut within = Block::default();
            within.clear();
            let got = read_flat_line_in(buf.as_bytes(), line.len(), &mut within);
            proptest::prop_assert_eq!(&got, &want, "{:?}", buf);
            if want.is_ok() {
                proptest::prop_assert_eq!(&within, &alone, "{:?}", buf);
            }
        }

        /// Numbers of 16 to 20 digits, near and past 2^53 as an integer,
        /// read as `str::parse` reads them, wherever the point is.
        #[test]
        fn number_reader_reads_long_numbers_exactly(
            mant in proptest::prop_oneof![
                1_000_000_000_000_000u64..(1 << 53) + 2,
                (1u64 << 53) - 2..100_000_000_000_000_000,
                10_000_000_000_000_000_000u64..u64::MAX,
            ],
            lead in 0usize..3,
            point in 0usize..21,
            neg in proptest::bool::ANY,
        ) {
            let digits = format!("{}{mant}", "0".repeat(lead));
            let at = point.min(digits.len());
            let text = format!(
                "{}{}.{}",
                if neg { "-" } else { "" },
                &digits[..at],
                &digits[at..],
            );
            let line = format!("X{text} Y1");
            let got = read_number(line.as_bytes(), line.as_bytes(), 1, true)
                .map(|n| (n.value.to_bits(), n.end));
            let want: f64 = text.parse().unwrap();
            proptest::prop_assert_eq!(got, Some((want.to_bits(), 1 + text.len())), "{}", line);
        }

        #[test]
        fn number_reader_reads_decimals_exactly(
            int in 0u64..100_000_000,
            frac in 0u64..10_000_000,
            width in 0usize..12,
            neg in proptest::bool::ANY,
        ) {
            let line = format!(
                "X{}{int}.{frac:0width$} Y1",
                if neg { "-" } else { "" },
            );
            let got = read_number(line.as_bytes(), line.as_bytes(), 1, true).map(|n| (n.value, n.end));
            let want: f64 = line[1..line.len() - 3].parse().unwrap();
            proptest::prop_assert_eq!(got.map(|g| g.0.to_bits()), Some(want.to_bits()));
            proptest::prop_assert_eq!(got.map(|g| g.1), Some(line.len() - 3));
        }
    }

    #[test]
    fn g80_beside_another_motion_code() {
        for (line, want) in [
            ("G80 G0 X1", MotionMode::Rapid),
            ("G1 G80 X2", MotionMode::Linear),
            ("G80 G81 X3 R1 Z-1", MotionMode::Cycle(81)),
        ] {
            let b = Block::decode(line.as_bytes()).unwrap();
            assert_eq!(b.motion(), Some(want), "{line}");
        }
        assert!(Block::decode(b"G0 G1 X1").is_err());
    }

    #[test]
    fn decodes_groups_words_and_comments() {
        let b = Block::decode(b"N10 g20 G64 P0.01 g1 x1.5 Y - 2 f300 (MSG, hi) ; rest").unwrap();
        assert_eq!(b.units(), Some(Units::Inch));
        assert_eq!(b.code(13), Some(GCode::Path(PathMode::Blend)));
        assert_eq!(b.code(99), None);
        assert_eq!(b.motion(), Some(MotionMode::Linear));
        assert_eq!(b.value(b'X'), Some(1.5));
        assert_eq!(b.value(b'Y'), Some(-2.0));
        assert_eq!(b.value(b'P'), Some(0.01));
        assert_eq!(b.line_number.map(|l| l.0), Some(10.0));
        assert_eq!(b.comments.len(), 2);
        assert_eq!(b.comments[0].kind, CommentKind::Message);
        assert_eq!(b.words.len(), 7);
        assert!(b.has_axis());
        assert_eq!(b.axes()[..3], [Some(1.5), Some(-2.0), None]);
        let f = Block::decode(b"G1 F300 I2 J1").unwrap();
        assert!(!f.has_axis());
        assert_eq!(f.axes(), [None; 9]);
        assert!(Block::decode(b"G1 W-1").unwrap().has_axis());
    }

    /// Any two G codes on a line: refused when of one group (but a G80
    /// beside another motion code, which gives way), kept by group
    /// otherwise; a line of one code and an axis word is a plain move for
    /// G0-G3 alone.
    #[test]
    fn one_code_a_group() {
        let all: Vec<GCode> = (0..=1000u16).filter_map(GCode::from_code10).collect();
        let name = |g: GCode| g.name();
        let g80 = GCode::Motion(MotionMode::CancelCycle);
        for &a in &all {
            let one = Block::decode(format!("{} X1", name(a)).as_bytes()).unwrap();
            assert_eq!(one.code(a.group()), Some(a));
            let plain = matches!(
                a,
                GCode::Motion(
                    MotionMode::Rapid | MotionMode::Linear | MotionMode::ArcCw | MotionMode::ArcCcw
                )
            );
            assert_eq!(one.is_plain_move(), plain, "{a:?}");
            for &b in &all {
                let line = format!("{} {}", name(a), name(b));
                let got = Block::decode(line.as_bytes());
                if a.group() != b.group() {
                    let got = got.unwrap();
                    assert_eq!(
                        (got.code(a.group()), got.code(b.group())),
                        (Some(a), Some(b))
                    );
                    let mut want = vec![a, b];
                    want.sort_by_key(|g| g.group());
                    assert_eq!(got.modal_codes().collect::<Vec<_>>(), want, "{line}");
                } else if a == g80 || b == g80 {
                    let other = if a == g80 { b } else { a };
                    let got = got.unwrap();
                    assert_eq!(got.code(1), Some(other), "{line}");
                    assert_eq!(got.modal_codes().count(), 1);
                } else {
                    assert_eq!(
                        got.unwrap_err().what,
                        DecodeProblem::GroupConflict,
                        "{line}"
                    );
                }
            }
        }
        // The room is cleared between lines.
        let mut b = Block::decode(b"G20 G91 G1 X1").unwrap();
        b.decode_into(b"X2").unwrap();
        assert_eq!(
            (b.units(), b.motion(), b.modal_codes().count()),
            (None, None, 0)
        );
        assert!(b.is_plain_move());
    }

    #[test]
    fn decodes_codes() {
        let b = Block::decode(b"G59.1 G43.2 H2 G98 G83 M6 T3 M61 Q1").unwrap();
        assert_eq!(b.coord(), Some(CoordSystem(7)));
        assert_eq!(b.coord().map(|c| c.code10()), Some(591));
        assert_eq!(b.tool_length(), Some(ToolLength::Add));
        assert_eq!(b.retract(), Some(Retract::Initial));
        assert_eq!(b.motion(), Some(MotionMode::Cycle(83)));
        let ms: Vec<MCode> = b.m_codes().map(|m| m.0).collect();
        assert_eq!(ms, vec![MCode::ToolChange, MCode::SetTool]);
        assert!(Block::decode(b"%").unwrap().percent);
        assert!(Block::decode(b"/G0 X1").unwrap().block_delete);
        assert_eq!(
            Block::decode(b"G0 X1 X2").unwrap_err().what,
            DecodeProblem::GroupConflict
        );
        assert!(Block::decode(b"G0 X").is_err());
        assert!(Block::decode(b"G0 (x").is_err());
        assert!(Block::decode(b"G12.5").is_err());
        assert_eq!(Block::decode(b"G54").unwrap().coord(), Some(CoordSystem(1)));
        assert_eq!(Block::decode(b"G59").unwrap().coord(), Some(CoordSystem(6)));
    }
}
