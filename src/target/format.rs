//! Writing lines for a target: numbers at the target's precision and never
//! with an exponent, comments stripped or cleaned, every line measured as
//! the firmware measures it and checked for bytes it acts on in real time.

use crate::diag::ErrorKind;
use crate::machine::block::{Block, CommentKind, Units, WordKind};

use super::lower::PlainLine;
use super::profile::{Comments, LineCount, Profile};

/// Puts one target line together.
pub struct LineWriter {
    p: &'static Profile,
    buf: Vec<u8>,
    units: Units,
    num: String,
}

impl LineWriter {
    pub fn new(p: &'static Profile) -> LineWriter {
        LineWriter {
            p,
            buf: Vec::with_capacity(128),
            units: Units::Mm,
            num: String::with_capacity(32),
        }
    }

    /// Starts a line for block `b` (its units decide the decimals).
    pub fn begin(&mut self, b: &Block, units: Units) {
        self.buf.clear();
        self.units = units;
        if let Some((n, _)) = b.line_number
            && n <= self.p.max_line_number
        {
            self.push_word(b'N', n, true);
        }
    }

    fn push_word(&mut self, letter: u8, v: f64, code: bool) {
        if !self.buf.is_empty() {
            self.buf.push(b' ');
        }
        self.buf.push(letter);
        self.num.clear();
        if code {
            let t = (v * 10.0).round();
            use std::fmt::Write;
            let _ = if t % 10.0 == 0.0 {
                write!(self.num, "{}", (t / 10.0) as i64)
            } else {
                write!(self.num, "{:.1}", t / 10.0)
            };
        } else {
            let d = self.decimals();
            format_number(&mut self.num, v, d, self.p.max_digits);
        }
        self.buf.extend_from_slice(self.num.as_bytes());
    }

    fn decimals(&self) -> u8 {
        match self.units {
            Units::Mm => self.p.decimals_mm,
            Units::Inch => self.p.decimals_inch,
        }
    }

    /// Appends a word.
    pub fn word(&mut self, letter: u8, value: f64, kind: WordKind) {
        let code = matches!(kind, WordKind::G(_) | WordKind::M(_)) || matches!(letter, b'G' | b'M');
        self.push_word(letter, value, code);
    }

    /// Appends the comments of `b` (read from `text`) the target keeps.
    pub fn comments(&mut self, b: &Block, text: &[u8]) {
        for c in &b.comments {
            let keep = match self.p.comments {
                Comments::Keep => true,
                Comments::Strip => c.kind == CommentKind::Message && self.p.messages,
            };
            if !keep {
                continue;
            }
            let whole = &text[c.span.start as usize..c.span.end as usize];
            if !self.buf.is_empty() {
                self.buf.push(b' ');
            }
            if self.p.comments == Comments::Keep {
                self.buf.extend_from_slice(whole);
                continue;
            }
            let inner = &text[c.text.start as usize..c.text.end as usize];
            self.buf.extend_from_slice(b"(MSG,");
            for &ch in inner {
                if (b' '..=b'~').contains(&ch)
                    && ch != b'('
                    && ch != b')'
                    && !self.p.is_realtime(ch)
                {
                    self.buf.push(ch);
                }
            }
            self.buf.push(b')');
        }
    }

    /// Finishes the line into `out` (nothing for an empty line); an error
    /// if it does not fit the target's line buffer.
    pub fn finish_line(&mut self, out: &mut Vec<u8>) -> Option<ErrorKind> {
        if self.buf.is_empty() {
            return None;
        }
        if let Some(k) = self.check() {
            return Some(k);
        }
        out.clear();
        out.extend_from_slice(&self.buf);
        None
    }

    fn check(&self) -> Option<ErrorKind> {
        debug_assert!(!self.buf.iter().any(|&b| self.p.is_realtime(b)));
        let (limit, how) = self.p.line_limit?;
        let len = match how {
            LineCount::AllBytes => self.buf.len() + 1,
            LineCount::Significant => significant_len(&self.buf) + 1,
        };
        (len > limit).then(|| ErrorKind::TargetLineTooLong {
            target: self.p.name,
            len: len - 1,
            limit: limit - 1,
        })
    }

    /// Writes a lowered block into `out`.
    pub fn plain(&mut self, l: &PlainLine, units: Units, out: &mut Vec<u8>) -> Option<ErrorKind> {
        self.buf.clear();
        self.units = units;
        for w in &l.words {
            let code = matches!(w.letter, b'G' | b'M');
            self.push_word(w.letter, w.value, code);
        }
        self.finish_line(out)
    }
}

/// Bytes of a line without blanks and comments.
pub fn significant_len(line: &[u8]) -> usize {
    let mut n = 0;
    let mut in_comment = false;
    for &c in line {
        match c {
            b'(' => in_comment = true,
            b')' if in_comment => in_comment = false,
            b';' if !in_comment => break,
            b' ' | b'\t' | b'\r' => {}
            _ if !in_comment => n += 1,
            _ => {}
        }
    }
    n
}

/// Writes `v` with at most `decimals` decimals and `max_digits`
/// significant digits (zeros after the point count), trailing zeros
/// dropped, never an exponent or `-0`.
pub fn format_number(out: &mut String, v: f64, decimals: u8, max_digits: u8) {
    use std::fmt::Write;
    let a = v.abs();
    if v.fract() == 0.0 && a < 1e15 {
        let _ = write!(out, "{}", v as i64);
        return;
    }
    let int_digits = if a < 1.0 {
        0
    } else {
        (a.log10().floor() as i32 + 1).max(1)
    };
    let d = (max_digits as i32 - int_digits).clamp(0, decimals as i32) as usize;
    let start = out.len();
    let scale = 10f64.powi(d as i32);
    let scaled = (a * scale).round();
    if d <= 12 && scaled < 9.0e15 {
        // Fixed point through an integer: no float formatting.
        let n = scaled as u64;
        let p = 10u64.pow(d as u32);
        let (int, mut frac) = (n / p, n % p);
        if n != 0 && v < 0.0 {
            out.push('-');
        }
        let _ = write!(out, "{int}");
        if frac != 0 {
            let mut digits = d;
            while frac % 10 == 0 {
                frac /= 10;
                digits -= 1;
            }
            let _ = write!(out, ".{frac:0digits$}");
        }
        return;
    }
    let _ = write!(out, "{:.*}", d, v);
    if out[start..].contains('.') {
        while out.ends_with('0') {
            out.pop();
        }
        if out.ends_with('.') {
            out.pop();
        }
    }
    if out[start..]
        .trim_start_matches('-')
        .bytes()
        .all(|b| b == b'0')
    {
        out.truncate(start);
        out.push('0');
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn f(v: f64, d: u8, m: u8) -> String {
        let mut s = String::new();
        format_number(&mut s, v, d, m);
        s
    }

    #[test]
    fn numbers_fit_the_target() {
        assert_eq!(f(1.23456789, 4, 8), "1.2346");
        assert_eq!(f(-0.00001, 4, 8), "0");
        assert_eq!(f(12345.678912, 4, 8), "12345.679");
        assert_eq!(f(1e20, 4, 8), "100000000000000000000");
        assert_eq!(f(2.0, 4, 8), "2");
        assert_eq!(f(-2.5, 4, 8), "-2.5");
        assert_eq!(f(-0.05, 4, 8), "-0.05");
        assert_eq!(f(0.00012, 5, 8), "0.00012");
        assert_eq!(f(-1234.56789, 4, 8), "-1234.5679");
        assert_eq!(f(1.99999, 4, 8), "2");
    }

    #[test]
    fn significant_length() {
        assert_eq!(significant_len(b"G1 X1 (a comment) Y2"), 6);
        assert_eq!(significant_len(b"G1 X1 ; rest"), 4);
    }
}
