//! The flat-line reader: the one reader of a flat line's text
//! ([`read_flat_line`]), and of the words written the usual way
//! ([`read_words`]), which the straight-line loop reads its lines with too.

use super::{Block, BlockSpan, DecodeError, DecodeProblem, Shape};
use crate::number::{Digits, POW10, digits_at};

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
        span: BlockSpan,
        shape: Shape,
        spaced: bool,
    ) -> Result<(), Self::Error>;
    /// The comment `line[start..end]` (`(…)`, or `;` to the end).
    fn on_comment(&mut self, line: &[u8], start: usize, end: usize) -> Result<(), Self::Error>;
    /// The value of the next word, if the sink knows it already and it has
    /// `letter`: its number then is not converted again where that takes
    /// the general float reader (see [`Block::decode_known`]).
    #[inline(always)]
    fn known(&self, letter: u8) -> Option<f64> {
        let _ = letter;
        None
    }
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
    let span = |a: usize, b: usize| BlockSpan {
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
                let known = sink.known(letter);
                let num = read_number(line, buf, i + 1, S::SHAPES, known).ok_or(DecodeError {
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
        let span = BlockSpan {
            start: at as u16,
            end: end as u16,
        };
        self.sink.on_word(letter, value, span, shape, false)
    }
}

/// A block decoded with the values of its words known (see
/// [`Block::decode_known`]).
pub(super) struct Known<'a> {
    pub(super) block: &'a mut Block,
    pub(super) known: &'a [(u8, f64)],
    /// The next entry of `known`.
    pub(super) next: usize,
}

impl LineSink for Known<'_> {
    type Error = DecodeError;
    const SHAPES: bool = true;

    fn on_percent(&mut self) -> Result<(), DecodeError> {
        self.block.on_percent()
    }

    fn on_block_delete(&mut self) {
        self.block.on_block_delete();
    }

    fn on_word(
        &mut self,
        letter: u8,
        value: f64,
        span: BlockSpan,
        shape: Shape,
        spaced: bool,
    ) -> Result<(), DecodeError> {
        if self.known.get(self.next).is_some_and(|k| k.0 == letter) {
            self.next += 1;
        }
        self.block.on_word(letter, value, span, shape, spaced)
    }

    fn on_comment(&mut self, line: &[u8], start: usize, end: usize) -> Result<(), DecodeError> {
        self.block.on_comment(line, start, end)
    }

    #[inline(always)]
    fn known(&self, letter: u8) -> Option<f64> {
        match self.known.get(self.next) {
            Some(&(l, v)) if l == letter && v.is_finite() => Some(v),
            _ => None,
        }
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
            span: BlockSpan {
                start: i as u16,
                end: n as u16,
            },
            what: DecodeProblem::UnclosedComment,
        })?;
    sink.on_comment(line, i, i + close + 1)?;
    Ok(i + close + 1)
}

fn skip_blanks(line: &[u8], mut i: usize) -> usize {
    while i < line.len() && matches!(line[i], b' ' | b'\t' | b'\r') {
        i += 1;
    }
    i
}

/// A number [`read_number`] read.
pub(super) struct Num {
    pub(super) value: f64,
    /// The offset just after it.
    pub(super) end: usize,
    /// How it is written ([`Shape::default`] unless asked for).
    pub(super) shape: Shape,
    /// Read with blanks before or inside it (false: it starts where it was
    /// looked for and holds none).
    pub(super) spaced: bool,
    /// Where the line goes on: after the blanks that follow it.
    pub(super) next: usize,
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
/// Longer numbers without blanks are parsed where they are written, unless
/// their value is `known` (the value the text reads as, which the caller
/// vouches for); the rest (blanks inside) is gathered first.
#[inline(always)]
pub(super) fn read_number(
    line: &[u8],
    tail: &[u8],
    start: usize,
    shapes: bool,
    known: Option<f64>,
) -> Option<Num> {
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
        // Long, but in one piece: its value as the writer of the text
        // knows it, or read where it is written.
        if let Some(v) = known {
            return whole(v.abs(), Shape::default());
        }
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
pub(super) fn read_number_slow(line: &[u8], start: usize) -> Option<(f64, usize)> {
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
