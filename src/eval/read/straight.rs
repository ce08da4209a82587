//! The straight-line loop: runs of the commonest CAM lines (`G0`–`G3` with
//! axis, `F` and `S` words, `I`/`J`/`R` arcs in the XY plane, a line number,
//! an inert comment at the end) go through one tight loop that finds line
//! ends, reads numbers, makes the block checks, updates the state model and
//! copies the input bytes to the output in blocks. Any line it does not
//! fully understand ends the run and takes the general path, which gives the
//! same result line by line; a property test and a fuzz target compare the
//! two.
//!
//! Its words are read by the flat-line reader's word reader,
//! [`crate::block::read_words`], through a sink of the loop's letters
//! ([`Slots`]); the line number before them and the inert comment after
//! them are the loop's own steps.

use crate::block::{
    BlockSpan, Cuts, MoveValues, MovesRule, RawLine, RawWord, Shape, Spacing,
    WordSink as ReadWords, WordsEnd, kept_digits, read_words,
};
use crate::number::{Digits, POW10, digits_in};

use crate::codes::{FeedMode, MotionMode, Plane};
use crate::eval::read::plain::{PlainRoom, read_plain_in};
use crate::eval::state::Machine;
use crate::settings::Settings;

/// Word slots: G, X, Y, Z, A, B, C, F, S (the fast set), then I, J, K, R, P
/// (lines with these take the block checks).
const G: usize = 0;
const F: usize = 7;
const S: usize = 8;
const NONE: u8 = 0xff;
const AXIS_MASK: u32 = 0b111_1110;
const FAST_MASK: u32 = 0b1_1111_1111;
const I: usize = 9;
const J: usize = 10;
const K: usize = 11;
const R: usize = 12;
/// Words a G2/G3 line in the XY plane may have on the fast path.
const ARC_MASK: u32 =
    1 << G | 1 << 1 | 1 << 2 | 1 << 3 | 1 << F | 1 << S | 1 << I | 1 << J | 1 << R;
const LETTERS: [u8; 14] = *b"gxyzabcfsijkrp";

const fn slot_table() -> [u8; 256] {
    let mut t = [NONE; 256];
    let mut i = 0;
    while i < LETTERS.len() {
        t[LETTERS[i] as usize] = i as u8;
        t[LETTERS[i].to_ascii_uppercase() as usize] = i as u8;
        i += 1;
    }
    t
}

static SLOT: [u8; 256] = slot_table();

/// Output bytes gathered before they are handed to the output.
pub(in crate::eval) const BATCH: usize = 1 << 16;

/// One line read by [`read_line`].
#[derive(Clone, Copy, Default)]
pub(in crate::eval) struct Plain {
    pub(in crate::eval) mask: u32,
    /// Values by slot.
    pub(in crate::eval) vals: [f64; 14],
    pub(in crate::eval) count: usize,
    /// End of the text to write (without trailing blanks and terminator).
    pub(in crate::eval) text_end: usize,
    /// Start of the next line.
    pub(in crate::eval) next: usize,
}

#[inline(always)]
fn is_blank(c: u8) -> bool {
    matches!(c, b' ' | b'\t' | b'\r')
}

/// [`digits_in`] as a value and end (for the tests).
#[cfg(test)]
fn number(buf: &[u8], i: usize) -> Option<(f64, usize)> {
    digits_in(buf, i).map(|d| (d.value(), d.end))
}

/// Reads `digits[.digits]` at `buf[i..]` a byte at a time; exact for up to
/// 15 digits, `None` beyond (the general path then reads it).
fn number_slow(buf: &[u8], mut i: usize) -> Option<(f64, usize)> {
    let mut mant = 0u64;
    let mut digits = 0u32;
    let mut frac = 0u32;
    let mut dot = 0u32;
    while let Some(&c) = buf.get(i) {
        let d = c.wrapping_sub(b'0');
        if d < 10 {
            mant = mant.wrapping_mul(10).wrapping_add(d as u64);
            digits += 1;
            frac += dot;
        } else if c == b'.' && dot == 0 {
            dot = 1;
        } else {
            break;
        }
        i += 1;
    }
    if digits == 0 || digits > 15 || frac > 22 {
        return None;
    }
    Some((mant as f64 / POW10[frac as usize], i))
}

/// Reads the line at `buf[line..]` into `p` if it is a line of slot words,
/// each at most once, ending in a newline. False sends the line to the
/// general path.
#[inline(always)]
pub(in crate::eval) fn read_line(buf: &[u8], line: usize, p: &mut Plain, comments: bool) -> bool {
    read_line_into(buf, line, p, comments, &mut ())
}

/// What a straight-line read hands on besides its record: the words as they
/// are read, in order (offsets into the buffer).
pub(in crate::eval) trait WordSink {
    /// The N word: its letter's offset, its value and end.
    fn line_number(&mut self, at: usize, value: f64, end: usize);
    /// A word: the letter's offset, its sign, the digits read at `num`.
    fn word(&mut self, buf: &[u8], at: usize, sign: u8, num: usize, d: &Digits);
    /// A word whose number the byte-at-a-time reader read.
    fn slow_word(&mut self);
    /// The comment `buf[start..end]` ending the line.
    fn comment(&mut self, buf: &[u8], start: usize, end: usize);
}

/// No sink: the record alone.
impl WordSink for () {
    #[inline(always)]
    fn line_number(&mut self, _: usize, _: f64, _: usize) {}
    #[inline(always)]
    fn word(&mut self, _: &[u8], _: usize, _: u8, _: usize, _: &Digits) {}
    #[inline(always)]
    fn slow_word(&mut self) {}
    #[inline(always)]
    fn comment(&mut self, _: &[u8], _: usize, _: usize) {}
}

/// Keeps the words read (with their spans and shapes) in a [`RawLine`],
/// so that each number is read once for the record and for the line's
/// block, which [`crate::block::Block::replay`] makes from it where one is needed. A
/// number the byte-at-a-time reader took leaves the line to
/// [`crate::block::Block::decode_into`] (see [`ToRaw::finish`]).
pub(in crate::eval) struct ToRaw<'a> {
    raw: &'a mut RawLine,
    /// Offset of the line's start.
    start: usize,
    slow: bool,
}

impl<'a> ToRaw<'a> {
    #[inline(always)]
    pub(in crate::eval) fn new(raw: &'a mut RawLine, start: usize) -> ToRaw<'a> {
        raw.clear();
        ToRaw {
            raw,
            start,
            slow: false,
        }
    }

    /// After a successful read of the line: whether the raw line holds it
    /// (false: decode its text instead).
    #[inline(always)]
    pub(in crate::eval) fn finish(self) -> bool {
        !self.slow
    }

    #[inline(always)]
    fn span(&self, a: usize, b: usize) -> BlockSpan {
        BlockSpan {
            start: (a - self.start) as u16,
            end: (b - self.start) as u16,
        }
    }
}

impl WordSink for ToRaw<'_> {
    #[inline(always)]
    fn line_number(&mut self, at: usize, value: f64, end: usize) {
        let span = self.span(at, end);
        self.raw.set_line_number(value, span);
    }

    #[inline(always)]
    fn word(&mut self, buf: &[u8], at: usize, sign: u8, num: usize, d: &Digits) {
        if self.slow {
            return;
        }
        let (neg, plus) = (sign == b'-', sign == b'+');
        let v = d.value();
        let w = RawWord {
            letter: buf[at],
            value: if neg { -v } else { v },
            span: self.span(at, d.end),
            shape: Shape::of(d, buf, num, neg, plus),
        };
        self.raw.push(w);
    }

    #[inline(always)]
    fn slow_word(&mut self) {
        self.slow = true;
    }

    #[inline(always)]
    fn comment(&mut self, _buf: &[u8], start: usize, end: usize) {
        let span = self.span(start, end);
        self.raw.set_comment(span);
    }
}

/// Works out, as a line is read, how a consumer writing by `rule` writes
/// it, if it is a line of moves alone as [`RawLine::moves_only`] has it
/// (G0 or G1, X, Y, Z, F, upper case, one blank apart, no line number or
/// comment) and the rule keeps each of its numbers as written or without
/// its trailing zeros: the writer's own tests on the shape of each number
/// (`written_as_is` and `without_trailing_zeros` after [`Shape::of`], in
/// one step: [`kept_digits`]), as for a word handed to a block.
pub(in crate::eval) struct ToForm {
    rule: MovesRule,
    /// Offset of the line's start.
    start: usize,
    /// Its words' layout so far (broken off once it is not such a line).
    spacing: Spacing,
    cuts: Cuts,
}

/// What a letter is to [`ToForm`]: not taken, G, X Y Z F, or I J K.
const FORM_NONE: u8 = 0;
const FORM_G: u8 = 1;
const FORM_VALUE: u8 = 2;
const FORM_ARC: u8 = 3;

static FORM_LETTER: [u8; 256] = {
    let mut t = [FORM_NONE; 256];
    t[b'G' as usize] = FORM_G;
    t[b'X' as usize] = FORM_VALUE;
    t[b'Y' as usize] = FORM_VALUE;
    t[b'Z' as usize] = FORM_VALUE;
    t[b'F' as usize] = FORM_VALUE;
    t[b'I' as usize] = FORM_ARC;
    t[b'J' as usize] = FORM_ARC;
    t[b'K' as usize] = FORM_ARC;
    t
};

impl ToForm {
    #[inline(always)]
    pub(in crate::eval) fn new(start: usize, rule: MovesRule) -> ToForm {
        ToForm {
            rule,
            start,
            spacing: Spacing::new(start),
            cuts: Cuts::default(),
        }
    }

    /// Whether the line at `buf[i..]` may be one (its first word is G0–G3,
    /// X, Y, Z, F, I, J or K, or it starts with a comment `rule` drops):
    /// lines that are not are left to [`ToRaw`] at once.
    #[inline(always)]
    pub(in crate::eval) fn may_take(buf: &[u8], i: usize, rule: &MovesRule) -> bool {
        match buf.get(i) {
            Some(b'G') => matches!(buf.get(i + 1), Some(b'0'..=b'3')),
            Some(b'X' | b'Y' | b'Z' | b'F' | b'I' | b'J' | b'K') => true,
            Some(b'(') => rule.drops_comments,
            _ => false,
        }
    }

    /// After a successful read of the line ending its text at `text_end`:
    /// where it is written otherwise than as its text, if it is such a line
    /// (its last word ends the text), or an inert comment alone that the
    /// rule drops ([`Cuts::whole`]).
    #[inline(always)]
    pub(in crate::eval) fn finish(&self, text_end: usize) -> Option<Cuts> {
        if self.cuts.is_whole() {
            return Some(self.cuts);
        }
        let fits = text_end - self.start - self.cuts.dropped() < self.rule.max_len;
        (self.spacing.ends_at(text_end) && fits).then_some(self.cuts)
    }

    /// Whether the word at `at` (in its place: see [`Spacing`]) keeps the
    /// line one: a letter the rule takes, and its number as the rule
    /// writes it.
    #[inline(always)]
    fn take(&mut self, buf: &[u8], at: usize, sign: u8, num: usize, d: &Digits) -> bool {
        let kind = FORM_LETTER[usize::from(buf[at])];
        if kind == FORM_NONE || kind == FORM_ARC && !self.rule.arcs {
            return false;
        }
        if kind == FORM_G {
            // G0–G3 as the rules write them (G2 and G3 where the rule
            // takes arcs): one digit, no sign, no point.
            let top = if self.rule.arcs { 3 } else { 1 };
            if matches!(sign, b'-' | b'+') || d.point || d.int != 1 || d.mant > top {
                return false;
            }
        } else {
            let (decimals, digits) = (self.rule.decimals, self.rule.max_digits);
            match kept_digits(d, buf, num, sign, decimals, digits) {
                Some(0) => {}
                Some(n) => {
                    if !self.cuts.push(d.end - self.start, n) {
                        return false;
                    }
                }
                None => return false,
            }
        }
        true
    }
}

impl WordSink for ToForm {
    #[inline(always)]
    fn line_number(&mut self, _: usize, _: f64, _: usize) {
        self.spacing.break_off();
    }

    #[inline(always)]
    fn word(&mut self, buf: &[u8], at: usize, sign: u8, num: usize, d: &Digits) {
        if !self.spacing.word(buf, at, d.end) || !self.take(buf, at, sign, num, d) {
            self.spacing.break_off();
        }
    }

    #[inline(always)]
    fn slow_word(&mut self) {
        self.spacing.break_off();
    }

    #[inline(always)]
    fn comment(&mut self, _: &[u8], open: usize, _: usize) {
        // The comment is the line (nothing can follow it).
        if self.rule.drops_comments && open == self.start && self.spacing.is_fresh() {
            self.cuts = Cuts::whole();
        } else {
            self.spacing.break_off();
        }
    }
}

/// [`read_line`], handing the words to `sink` as they are read.
#[inline(always)]
pub(in crate::eval) fn read_line_into(
    buf: &[u8],
    line: usize,
    p: &mut Plain,
    comments: bool,
    sink: &mut impl WordSink,
) -> bool {
    let at = |j: usize| buf.get(j).copied().unwrap_or(0);
    let mut i = line;
    p.mask = 0;
    p.count = 0;
    // Optional line number: N and 1–5 digits, then blanks.
    if at(i) | 0x20 == b'n' {
        i += 1;
        let s = i;
        let mut n = 0u32;
        while at(i).is_ascii_digit() {
            n = n.wrapping_mul(10).wrapping_add(u32::from(at(i) - b'0'));
            i += 1;
        }
        if i == s || i - s > 5 || !matches!(at(i), b' ' | b'\t') {
            return false;
        }
        sink.line_number(s - 1, f64::from(n), i);
        while matches!(at(i), b' ' | b'\t') {
            i += 1;
        }
    }
    let mut words = Slots {
        p: &mut *p,
        sink: &mut *sink,
        line,
    };
    match read_words(buf, i, buf.len(), &mut words) {
        Ok(WordsEnd::Line { text_end, end }) => {
            p.text_end = text_end;
            p.next = end + 1;
            true
        }
        Ok(WordsEnd::At(k)) => comments && at(k) == b'(' && read_comment(buf, line, k, p, sink),
        Err(Refused) => false,
    }
}

/// A word the loop does not take (a letter twice).
struct Refused;

/// The loop's words as [`read_words`] reads them: its letters (by slot),
/// its record of the line, and `sink`.
struct Slots<'a, W> {
    p: &'a mut Plain,
    sink: &'a mut W,
    /// Offset of the line's start.
    line: usize,
}

impl<W: WordSink> ReadWords for Slots<'_, W> {
    type Error = Refused;
    const LETTERS: &'static [u8; 256] = &SLOT;
    const BOUNDED: bool = false;
    const EARLY: bool = true;

    #[inline(always)]
    fn digits(buf: &[u8], i: usize) -> Option<Digits> {
        digits_in(buf, i)
    }

    #[inline(always)]
    fn slow_number(buf: &[u8], i: usize) -> Option<(f64, usize)> {
        number_slow(buf, i)
    }

    #[inline(always)]
    fn ends(&self, _: &[u8], k: usize, c: u8) -> bool {
        c == b'\n' && k - self.line <= crate::parse::MAX_LINE
    }

    #[inline(always)]
    fn word(
        &mut self,
        buf: &[u8],
        at: usize,
        slot: u8,
        sign: u8,
        num: usize,
        value: f64,
        _: usize,
        digits: Option<&Digits>,
    ) -> Result<(), Refused> {
        let bit = 1u32 << slot;
        if self.p.mask & bit != 0 {
            return Err(Refused);
        }
        self.p.mask |= bit;
        self.p.vals[usize::from(slot)] = value;
        self.p.count += 1;
        match digits {
            Some(d) => self.sink.word(buf, at, sign, num, d),
            None => self.sink.slow_word(),
        }
        Ok(())
    }
}

/// Reads an inert comment ending the line at `buf[i..]` (on `(`): printable
/// ASCII without a nested `(`, not starting like an active comment (`msg`,
/// `debug`, `print`, `log...`, `abort`, `py...`), then blanks and a newline.
#[inline(always)]
fn read_comment(
    buf: &[u8],
    line: usize,
    mut i: usize,
    p: &mut Plain,
    sink: &mut impl WordSink,
) -> bool {
    let at = |j: usize| buf.get(j).copied().unwrap_or(0);
    let open = i;
    i += 1;
    let mut first = i;
    while matches!(at(first), b' ' | b'\t') {
        first += 1;
    }
    if matches!(at(first) | 0x20, b'm' | b'd' | b'p' | b'l' | b'a') {
        return false;
    }
    loop {
        match at(i) {
            b')' => break,
            b'(' => return false,
            b'\t' | b' '..=b'~' => i += 1,
            _ => return false,
        }
    }
    i += 1;
    let text_end = i;
    while is_blank(at(i)) {
        i += 1;
    }
    if at(i) != b'\n' || i - line > crate::parse::MAX_LINE {
        return false;
    }
    sink.comment(buf, open, text_end);
    p.text_end = text_end;
    p.next = i + 1;
    true
}

/// The values of a line of moves alone (G0–G3, X, Y, Z, F, I, J, K) read
/// into `p`.
#[inline(always)]
pub(in crate::eval) fn move_values(p: &Plain) -> MoveValues {
    let motion = (p.mask & 1 << G != 0).then(|| match p.vals[G] {
        0.0 => MotionMode::Rapid,
        1.0 => MotionMode::Linear,
        2.0 => MotionMode::ArcCw,
        _ => MotionMode::ArcCcw,
    });
    // Slots 1–3 are X, Y, Z: their bits, and F's as the fourth.
    let has = (p.mask >> 1 & 0b111 | (p.mask >> F & 1) << 3) as u8;
    let vals = [p.vals[1], p.vals[2], p.vals[3], p.vals[F]];
    let ijk = p.mask & (1 << I | 1 << J | 1 << K) != 0;
    let word = |k: usize| if p.mask & 1 << k != 0 { p.vals[k] } else { 0.0 };
    let centre = if ijk {
        [word(I), word(J), word(K)]
    } else {
        [0.0; 3]
    };
    MoveValues::from_parts(motion, vals, has, ijk, centre)
}

/// The words, with their spans, of the line at `buf[i..]` (its text ending
/// at `text_end`) the loop read and takes on the general checks: as this
/// reader reads them into `room`'s raw line, or where a number took the
/// byte-at-a-time reader (see [`ToRaw::finish`]), as the general path
/// reads them. `None` leaves the line to the general path: a line with a
/// comment, as there.
pub(in crate::eval) fn plain_words<'r>(
    buf: &[u8],
    i: usize,
    text_end: usize,
    room: &'r mut PlainRoom,
) -> Option<&'r [RawWord]> {
    let mut sink = ToRaw::new(&mut room.raw, i);
    // The line was read already (with or without its comment).
    if !read_line_into(buf, i, &mut Plain::default(), true, &mut sink) {
        return None;
    }
    if !sink.finish() {
        return read_plain_in(&buf[i..], text_end - i, &mut room.words).then_some(&room.words[..]);
    }
    let words = room.raw.words();
    (!room.raw.has_comment() && !words.is_empty()).then_some(words)
}

/// Runs a line of G0–G3, axis, F and S words (arcs in the XY plane with
/// I, J or R) if the block checks would accept it, updating the state
/// model; false leaves it untouched for the general path.
#[inline(always)]
pub(in crate::eval) fn fast_line(mach: &mut Machine, p: &Plain) -> bool {
    if p.mask == 0 {
        // A comment (and line number) only.
        return true;
    }
    let g = p.mask & 1 != 0;
    let motion = if !g {
        mach.modal.motion
    } else {
        match p.vals[G] {
            0.0 => MotionMode::Rapid,
            1.0 => MotionMode::Linear,
            2.0 => MotionMode::ArcCw,
            3.0 => MotionMode::ArcCcw,
            _ => return false,
        }
    };
    let feed = if p.mask & (1 << F) != 0 {
        p.vals[F]
    } else {
        mach.modal.feed
    };
    let moves = g || p.mask & AXIS_MASK != 0;
    // Per revolution a feed move also needs a spindle speed: the general
    // path checks it.
    let speed_ok = mach.modal.feed_mode != FeedMode::PerRev
        || (p.mask & (1 << S) == 0 && mach.modal.speed != 0.0)
        || (p.mask & (1 << S) != 0 && p.vals[S] != 0.0);
    let feed_ok = mach.modal.feed_mode != FeedMode::InverseTime && feed != 0.0 && speed_ok;
    let accepted = match motion {
        MotionMode::Rapid => p.mask & !FAST_MASK == 0,
        MotionMode::Linear => p.mask & !FAST_MASK == 0 && (!moves || feed_ok),
        MotionMode::ArcCw | MotionMode::ArcCcw => {
            p.mask & !ARC_MASK == 0
                && mach.modal.plane == Plane::XY
                && p.mask & (1 << I | 1 << J | 1 << R) != 0
                && feed_ok
                && arc_ok(mach, p, motion)
        }
        _ => false,
    };
    if !accepted || feed < 0.0 || (p.mask & (1 << S) != 0 && p.vals[S] < 0.0) {
        return false;
    }
    let speed = (p.mask & (1 << S) != 0).then_some(p.vals[S]);
    mach.set_plain_modes(motion, feed, speed);
    let mut axes = p.mask & AXIS_MASK;
    while axes != 0 {
        let slot = axes.trailing_zeros() as usize;
        axes &= axes - 1;
        mach.move_axis(slot - 1, p.vals[slot]);
    }
    true
}

/// `fast_line` for the evaluated words of a line: true if it ran them
/// (the block checks accept them and the state model is updated), false
/// to leave them to the general checks.
pub(in crate::eval) fn fast_words(mach: &mut Machine, s: &Settings, words: &[(u8, f64)]) -> bool {
    if !mach.is_plain() || !s.plain_runs {
        return false;
    }
    let mut p = Plain::default();
    for &(l, v) in words {
        let slot = SLOT[l as usize];
        if slot == NONE || p.mask & (1 << slot) != 0 {
            return false;
        }
        p.mask |= 1 << slot;
        p.vals[slot as usize] = v;
    }
    fast_line(mach, &p)
}

/// The arc geometry checks of the general path, on an XY arc line.
fn arc_ok(mach: &mut Machine, p: &Plain, motion: MotionMode) -> bool {
    if p.mask & (AXIS_MASK | 1 << I | 1 << J | 1 << R) == 0 {
        // No arc on the line (a full circle `G2 I5` is one).
        return true;
    }
    // The words by letter (each at most once, so order is not needed).
    let mut words = [(0u8, 0.0f64); 14];
    let mut count = 0;
    let mut all = p.mask;
    while all != 0 {
        let slot = all.trailing_zeros() as usize;
        all &= all - 1;
        words[count] = (LETTERS[slot], p.vals[slot]);
        count += 1;
    }
    let mut axes = [(0usize, 0.0f64); 6];
    let mut n = 0;
    let mut m = p.mask & AXIS_MASK;
    while m != 0 {
        let slot = m.trailing_zeros() as usize;
        m &= m - 1;
        axes[n] = (slot - 1, p.vals[slot]);
        n += 1;
    }
    // The checks read the motion mode the line sets.
    mach.check_motion_as(motion, &words[..count], &axes[..n])
        .is_ok()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::block::Block;

    fn read(l: &[u8]) -> Option<Plain> {
        let mut p = Plain {
            mask: 0,
            vals: [0.0; 14],
            count: 0,
            text_end: 0,
            next: 0,
        };
        read_line(l, 0, &mut p, true).then_some(p)
    }

    /// How lines are written by a rule with 4 decimals and 8 digits (GRBL's
    /// in millimetres), as the reader works it out: `None` for lines left
    /// to their words.
    fn formed(line: &str, arcs: bool, max_len: usize) -> Option<String> {
        formed_by(
            line,
            MovesRule {
                decimals: 4,
                max_digits: 8,
                max_len,
                arcs,
                drops_comments: false,
            },
        )
    }

    fn formed_by(line: &str, rule: MovesRule) -> Option<String> {
        // Room after the line for the eight-byte number reads.
        let buf = format!("{line}\n{}", " ".repeat(32));
        let buf = buf.as_bytes();
        let mut p = Plain::default();
        let mut sink = ToForm::new(0, rule);
        if !ToForm::may_take(buf, 0, &rule) || !read_line_into(buf, 0, &mut p, true, &mut sink) {
            return None;
        }
        let cuts = sink.finish(p.text_end)?;
        let mut out = Vec::new();
        cuts.write(&buf[..p.text_end], &mut out);
        Some(String::from_utf8(out).expect("ASCII"))
    }

    #[test]
    fn lines_of_moves_alone_are_written_by_the_rule() {
        let cases: &[(&str, Option<&str>)] = &[
            ("G1 X1.5 Y-2 F300", Some("G1 X1.5 Y-2 F300")),
            ("G1 X1.2500 Y2.0 Z-0.10", Some("G1 X1.25 Y2 Z-0.1")),
            ("X0.000 Y5", Some("X0 Y5")),
            ("F1000", Some("F1000")),
            ("G0 Z5.", None),
            ("G1 X1234567.80", Some("G1 X1234567.8")),
            ("G2 X1 Y1 I0.50 J0", Some("G2 X1 Y1 I0.5 J0")),
            ("G3 X1 Z-1 K0.25", Some("G3 X1 Z-1 K0.25")),
            // Numbers the rule does not keep as written or shortened.
            ("G1 X-0.000", None),
            ("G1 X1.23456", None),
            ("G1 X123456789", None),
            ("G1 X+1", None),
            ("G1 X01", None),
            ("G1 X.5", None),
            // Codes, letters and layouts the writer does not copy.
            ("G01 X1", None),
            ("G1.0 X1", None),
            ("g1 x1", None),
            ("G1 x1", None),
            ("G1  X1", None),
            ("G1\tX1", None),
            ("G1 X1\tY2", None),
            ("G1 X1 (c)", None),
            ("N1 G1 X1", None),
            ("G4 P1", None),
            ("G1 X1 A2", None),
            ("G1 X1 S100", None),
            ("G2 X1 Y1 R1", None),
            ("(only a comment)", None),
        ];
        for &(line, want) in cases {
            assert_eq!(formed(line, true, 80).as_deref(), want, "{line}");
        }
        // Without arcs in the rule, arc lines are left to their words.
        assert_eq!(formed("G2 X1 Y1 I0.5 J0", false, 80), None);
        assert_eq!(formed("I0.5 J0", false, 80), None);
        assert_eq!(formed("G1 X1", false, 80).as_deref(), Some("G1 X1"));
        // Shorter than the line limit as written (after the cuts).
        assert_eq!(
            formed("G1 X1.2500 Y2.0000", true, 12).as_deref(),
            Some("G1 X1.25 Y2")
        );
        assert_eq!(formed("G1 X1.2500 Y2.0000", true, 11), None);
    }

    /// A rule that drops comments writes a line of an inert comment alone
    /// as nothing; any other line with a comment is left to its words.
    #[test]
    fn comments_alone_go_where_the_rule_drops_comments() {
        let rule = MovesRule {
            decimals: 4,
            max_digits: 8,
            max_len: 80,
            arcs: true,
            drops_comments: true,
        };
        let cases: &[(&str, Option<&str>)] = &[
            ("(only a comment)", Some("")),
            ("(segment 25, depth -1.435)   ", Some("")),
            ("( spaced )", Some("")),
            ("()", Some("")),
            // Active comments, and comments after something else.
            ("(msg, shown)", None),
            ("(debug, x)", None),
            ("(print, x)", None),
            ("(logopen,f)", None),
            (" (after a blank)", None),
            ("N10 (numbered)", None),
            ("G1 X1 (c)", None),
            ("(a) (b)", None),
            ("(nested (no))", None),
            // Moves are written as without the flag.
            ("G1 X1.50", Some("G1 X1.5")),
        ];
        for &(line, want) in cases {
            assert_eq!(formed_by(line, rule).as_deref(), want, "{line}");
        }
        // Without the flag, a comment alone is left to its words.
        let keeping = MovesRule {
            drops_comments: false,
            ..rule
        };
        assert_eq!(formed_by("(only a comment)", keeping), None);
    }

    #[test]
    fn reads_plain_lines() {
        let p = read(b"G1 X1.5 Y-2 F300\n").expect("plain");
        assert_eq!(p.mask, 0b1000_0111);
        assert_eq!(p.count, 4);
        assert_eq!((p.vals[1], p.vals[2], p.vals[F]), (1.5, -2.0, 300.0));
        assert_eq!((p.text_end, p.next), (16, 17));
        let p = read(b"G0 X1 (to the start: 5 mm) \n").expect("comment");
        assert_eq!((p.count, p.text_end, p.next), (2, 26, 28));
        let p = read(b"(segment 25, depth -1.435)\n").expect("comment");
        assert_eq!((p.mask, p.count, p.text_end), (0, 0, 26));
        let p = read(b"N10 g0z5 \r\nX1\n").expect("plain");
        assert_eq!((p.text_end, p.next), (8, 11));
        for l in [
            "G1 X1",
            "G1 X1 X2\n",
            "G1 X#1\n",
            "M3\n",
            "G1 U1\n",
            " G1\n",
            "G1 X1 0\n",
            "N123456 G1\n",
            "G1 X.\n",
            "G1 X1.2.3\n",
            "G1 X1234567890123456\n",
            "\n",
            "G1 X1 (msg, hi)\n",
            "(debug, #1)\n",
            "( print,x)\n",
            "(Log,x)\n",
            "(abort,x)\n",
            "(py,x)\n",
            "(a (b) c)\n",
            "(unclosed\n",
            "G1 (c) X1\n",
            "(c) x\n",
            "(caf\u{e9})\n",
        ] {
            assert!(read(l.as_bytes()).is_none(), "{l:?}");
        }
    }

    use proptest::prelude::*;

    proptest! {
        /// Both number readers give what `str::parse` gives, bit for bit,
        /// or leave the number to the general path.
        #[test]
        fn numbers_read_exactly(
            t in "[0-9]{0,17}(\\.[0-9]{0,17})?",
            tail in "[ .\n+A-Z0-9]{0,20}",
        ) {
            let text = format!("{t}{tail}");
            let b = text.as_bytes();
            let want = t.parse::<f64>().ok().map(f64::to_bits);
            for got in [number(b, 0), number_slow(b, 0)].into_iter().flatten() {
                let end = if tail.starts_with(|c: char| c.is_ascii_digit() || c == '.') {
                    // The tail continues the number: compare with all of it.
                    got.1
                } else {
                    t.len()
                };
                prop_assert_eq!(got.1, end);
                let read = text[..got.1].parse::<f64>().ok().map(f64::to_bits);
                prop_assert_eq!(Some(got.0.to_bits()), read, "{:?}", text);
                if end == t.len() {
                    prop_assert_eq!(Some(got.0.to_bits()), want);
                }
            }
        }
    }

    /// The words of a line as the grammar reads them (letter, value bits).
    fn grammar_words(line: &[u8]) -> Option<Vec<(u8, u64)>> {
        use crate::parse::ast::{ExprKind, Item, LineKind};
        let parsed = crate::parse::LineParser::default().parse(line, true).ok()?;
        let LineKind::Items(items) = parsed.kind else {
            return Some(Vec::new());
        };
        items
            .iter()
            .filter_map(|i| match i {
                Item::Word(w) => Some(match w.value.kind {
                    ExprKind::Num(v) => Some((w.letter, v.to_bits())),
                    _ => None,
                }),
                _ => None,
            })
            .collect()
    }

    fn raw_words(raw: &RawLine) -> Option<Vec<(u8, u64)>> {
        Some(
            raw.words()
                .iter()
                .map(|w| (w.letter.to_ascii_lowercase(), w.value.to_bits()))
                .collect(),
        )
    }

    /// The block made from a straight read's words, and whether it holds
    /// the line, against the block decoder's on the same text; a line of
    /// moves alone gives that block from its words alone.
    fn same_block_both_ways(text: &str) -> Result<(), TestCaseError> {
        let buf = text.as_bytes();
        let mut p = Plain::default();
        let mut raw = RawLine::default();
        let mut sink = ToRaw::new(&mut raw, 0);
        if !read_line_into(buf, 0, &mut p, true, &mut sink) {
            return Ok(());
        }
        let line = &buf[..p.text_end];
        let mut built = Block::default();
        let kept = sink.finish();
        let ok = if kept {
            built.replay(&raw, line).is_ok()
        } else {
            built.decode_into(line).is_ok()
        };
        let mut decoded = Block::default();
        let want = decoded.decode_into(line).is_ok();
        prop_assert_eq!(ok, want, "{:?}", text);
        if kept {
            // The grammar reads the same words.
            prop_assert_eq!(raw_words(&raw), grammar_words(line), "{:?}", text);
        }
        if want {
            prop_assert_eq!(&built, &decoded, "{:?}", text);
        }
        if let Some(words) = raw.moves_only(line) {
            let mut alone = Block::default();
            prop_assert!(alone.replay_words(words).is_ok(), "{:?}", text);
            prop_assert_eq!(&alone, &decoded, "{:?}", text);
            // Nothing but a motion code and value words.
            prop_assert!(
                decoded.is_plain_move() && decoded.value(b'I').is_none(),
                "{:?}",
                text
            );
        }
        Ok(())
    }

    proptest! {
        /// Lines the straight reader takes give the block the decoder
        /// gives: words in order with their spans and shapes, the line
        /// number, the comment, and the same refusals (an unknown G).
        #[test]
        fn straight_reads_decode_as_the_block_decoder(
            n in "([Nn][0-9]{1,6}[ \t]{0,2})?",
            words in prop::collection::vec(
                ("[GgXxYyZzAaFfSsIiJjRrPpKk]", "[-+]?", "0{0,2}[0-9]{0,9}(\\.[0-9]{0,9})?", "[ \t]{0,2}"),
                0..7,
            ),
            comment in "(\\([ a-zA-Z0-9,.()]{0,12}\\))?",
            end in "[ \t\r]{0,2}\n[ -~]{0,20}",
        ) {
            let mut text = n.clone();
            for (l, sign, num, blank) in &words {
                text.push_str(&format!("{l}{sign}{num}{blank}"));
            }
            text.push_str(&comment);
            text.push_str(&end);
            same_block_both_ways(&text)?;
        }
    }

    #[test]
    fn straight_reads_build_blocks() {
        for l in [
            "G1 X1.5 Y-2 F300\n",
            "N0010 g2 x+1.25 y-0.500 i0 j.5 (cut)\n",
            "G1 X123456789.5 Y2\n",
            "G0 X1 Y2 Z3 A4 B5 C6 F7 S8 I9 J10 K11 R12 P13\n",
            "G7.5 X1\n",
            "(only a comment)   \n",
        ] {
            same_block_both_ways(l).expect("same");
        }
    }

    #[test]
    fn moves_alone_are_told_apart() {
        let moves = |l: &str| {
            // Bytes after the line: the numbers are read eight at a time.
            let buf = format!("{l}{}", " ".repeat(24));
            let mut p = Plain::default();
            let mut raw = RawLine::default();
            let mut sink = ToRaw::new(&mut raw, 0);
            assert!(
                read_line_into(buf.as_bytes(), 0, &mut p, true, &mut sink),
                "{l:?}"
            );
            assert!(sink.finish());
            raw.moves_only(&buf.as_bytes()[..p.text_end])
                .map(<[RawWord]>::len)
        };
        assert_eq!(moves("G1 X1.5 Y-2 Z3 F300\n"), Some(5));
        assert_eq!(moves("X1 Y2   \n"), Some(2));
        assert_eq!(moves("G0 Z5\n"), Some(2));
        for l in [
            "G2 X1 Y2 I1\n",
            "G1 X1 S100\n",
            "g1 X1\n",
            "G1  X1\n",
            "G1\tX1\n",
            "N1 G1 X1\n",
            "G1 X1 (c)\n",
            "G1.5 X1\n",
            "G1X1\n",
        ] {
            assert_eq!(moves(l), None, "{l:?}");
        }
    }

    #[test]
    fn short_numbers_take_the_word_path() {
        let b = b"12.5 X3.25 F1000 0.0001 7. .5 -------------------";
        assert_eq!(number(b, 0), Some((12.5, 4)));
        assert_eq!(number(b, 6), Some((3.25, 10)));
        assert_eq!(number(b, 12), Some((1000.0, 16)));
        assert_eq!(number(b, 17), Some((0.0001, 23)));
        assert_eq!(number(b, 24), Some((7.0, 26)));
        assert_eq!(number(b, 27), Some((0.5, 29)));
        assert_eq!(number(b"123456789.5 ------------", 0), None);
        assert_eq!(number_slow(b"123456789.5", 0), Some((123456789.5, 11)));
    }
}
