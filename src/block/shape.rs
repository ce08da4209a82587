//! How a word's number is written (its shape), and whether a target's
//! rules write its value the same way, so that a writer may copy it.

use crate::number::Digits;

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
