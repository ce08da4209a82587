//! Fast path for plain lines: words made of a letter and a literal number,
//! optional block delete and line number, blanks between items. Such lines
//! need no evaluation and are written exactly as read. Anything else goes to
//! the grammar. A property test checks this scanner against the grammar on
//! every line it accepts.

use crate::number::POW10;

/// A word of a plain line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct FastWord {
    pub letter: u8,
    pub value: f64,
    pub start: u16,
    pub end: u16,
}

/// Parses `[+-]digits[.digits]` exactly as `str::parse::<f64>` would.
pub(crate) fn parse_decimal(t: &[u8]) -> Option<f64> {
    let (neg, body) = match t.first()? {
        b'-' => (true, &t[1..]),
        b'+' => (false, &t[1..]),
        _ => (false, t),
    };
    let mut mant: u64 = 0;
    let mut digits = 0u32;
    let mut frac = 0i32;
    let mut seen_dot = false;
    let mut any = false;
    for &c in body {
        match c {
            b'0'..=b'9' => {
                any = true;
                if mant == 0 && c == b'0' {
                    if seen_dot {
                        frac += 1;
                    }
                    continue;
                }
                digits += 1;
                if digits > 19 {
                    return slow(t);
                }
                mant = mant * 10 + (c - b'0') as u64;
                if seen_dot {
                    frac += 1;
                }
            }
            b'.' if !seen_dot => seen_dot = true,
            _ => return None,
        }
    }
    if !any {
        return None;
    }
    if mant > (1u64 << 53) || frac > 22 {
        return slow(t);
    }
    let v = mant as f64 / POW10[frac as usize];
    Some(if neg { -v } else { v })
}

fn slow(t: &[u8]) -> Option<f64> {
    std::str::from_utf8(t).ok()?.parse().ok()
}

/// Scans a plain line into `out`. Returns false when the line needs the
/// grammar (expressions, parameters, comments, O-words, unusual forms).
pub(crate) fn scan(raw: &[u8], out: &mut Vec<FastWord>) -> bool {
    out.clear();
    if raw.len() > crate::parse::MAX_LINE || raw.len() >= u16::MAX as usize {
        return false;
    }
    let n = raw.len();
    let mut i = 0;
    let skip = |i: &mut usize| {
        while *i < n && matches!(raw[*i], b' ' | b'\t' | b'\r') {
            *i += 1;
        }
    };
    skip(&mut i);
    if i < n && raw[i] == b'/' {
        i += 1;
        skip(&mut i);
    }
    if i < n && (raw[i] | 0x20) == b'n' {
        i += 1;
        skip(&mut i);
        let s = i;
        while i < n && raw[i].is_ascii_digit() {
            i += 1;
        }
        if i == s {
            return false;
        }
        if i < n && raw[i] == b'.' {
            i += 1;
            while i < n && raw[i].is_ascii_digit() {
                i += 1;
            }
        }
        if i < n && matches!(raw[i], b' ' | b'\t') {
            // Blanks inside a line number: leave it to the grammar.
            let mut j = i;
            while j < n && matches!(raw[j], b' ' | b'\t' | b'\r') {
                j += 1;
            }
            if j < n && (raw[j].is_ascii_digit() || raw[j] == b'.') {
                return false;
            }
        }
        skip(&mut i);
    }
    while i < n {
        let c = raw[i] | 0x20;
        if !c.is_ascii_lowercase() || c == b'n' || c == b'o' || !raw[i].is_ascii_alphabetic() {
            return false;
        }
        let start = i;
        i += 1;
        skip(&mut i);
        let s = i;
        let neg = i < n && raw[i] == b'-';
        if i < n && matches!(raw[i], b'+' | b'-') {
            i += 1;
        }
        // Digits are accumulated while scanning; unusual numbers are
        // re-read by the exact parser.
        let mut mant: u64 = 0;
        let mut frac: u32 = 0;
        let mut digits = 0u32;
        let mut dots = 0u32;
        while i < n {
            let c = raw[i];
            if c.is_ascii_digit() {
                mant = mant.wrapping_mul(10).wrapping_add((c - b'0') as u64);
                digits += 1;
                frac += dots;
            } else if c == b'.' {
                dots += 1;
            } else {
                break;
            }
            i += 1;
        }
        let value = if digits == 0 || dots > 1 {
            return false;
        } else if digits <= 15 && frac <= 22 {
            let v = mant as f64 / POW10[frac as usize];
            if neg { -v } else { v }
        } else {
            match parse_decimal(&raw[s..i]) {
                Some(v) => v,
                None => return false,
            }
        };
        let end = i;
        let after = i;
        skip(&mut i);
        if i > after && i < n && (raw[i].is_ascii_digit() || raw[i] == b'.') {
            // Blanks inside a number.
            return false;
        }
        out.push(FastWord {
            letter: c,
            value,
            start: start as u16,
            end: end as u16,
        });
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimals_match_std() {
        for t in [
            "0",
            "-0",
            "1.5",
            "+.5",
            "5.",
            "-12.3456",
            "0.1",
            "123456789.123456789",
            "0.000000000000000000000001",
        ] {
            assert_eq!(parse_decimal(t.as_bytes()), t.parse::<f64>().ok(), "{t}");
        }
        for t in [".", "", "1.2.3", "-", "1e3"] {
            assert_eq!(parse_decimal(t.as_bytes()), None, "{t}");
        }
    }

    use crate::parse::ast::{ExprKind, Item, LineKind};
    use proptest::prelude::*;

    /// Words of a line as the grammar reads them (None if it is not a
    /// line of literal words).
    fn grammar_words(raw: &[u8]) -> Option<Vec<(u8, f64)>> {
        let line = crate::parse::LineParser::default().parse(raw, true).ok()?;
        match line.kind {
            LineKind::Blank => Some(Vec::new()),
            LineKind::Items(items) => items
                .iter()
                .map(|i| match i {
                    Item::Word(w) => match w.value.kind {
                        ExprKind::Num(v) => Some((w.letter, v)),
                        _ => None,
                    },
                    _ => None,
                })
                .collect(),
            _ => None,
        }
    }

    proptest! {
        /// Every line the fast path accepts reads the same through the
        /// grammar: same letters, same values, bit for bit.
        #[test]
        fn fast_path_agrees_with_grammar(
            parts in proptest::collection::vec(
                prop_oneof![
                    "[gGxXyYzZfFsSmMtTiIjJkKpPrR]",
                    "[+-]?[0-9]{0,6}(\\.[0-9]{0,8})?",
                    "[ \t]{0,2}",
                    "[nN][0-9]{1,4}",
                    "/",
                    "[#\\[\\]()oO%;]",
                ],
                0..14,
            )
        ) {
            let line: String = parts.concat();
            let mut out = Vec::new();
            if scan(line.as_bytes(), &mut out) {
                let fast: Vec<(u8, u64)> = out.iter().map(|w| (w.letter, w.value.to_bits())).collect();
                let slow = grammar_words(line.as_bytes());
                prop_assert!(slow.is_some(), "fast path accepted {line:?}, grammar did not");
                let slow: Vec<(u8, u64)> = slow.unwrap().iter().map(|&(l, v)| (l, v.to_bits())).collect();
                prop_assert_eq!(fast, slow, "{:?}", line);
            }
        }

        #[test]
        fn decimal_parser_is_exact(t in "[+-]?[0-9]{1,20}(\\.[0-9]{0,25})?") {
            prop_assert_eq!(parse_decimal(t.as_bytes()).map(f64::to_bits), t.parse::<f64>().ok().map(f64::to_bits));
        }
    }

    #[test]
    fn plain_lines() {
        let mut v = Vec::new();
        assert!(scan(b"G1 X10.5 Y-2 F300", &mut v));
        assert_eq!(v.len(), 4);
        assert_eq!((v[1].letter, v[1].value), (b'x', 10.5));
        assert!(scan(b"N10 g0 x 1", &mut v));
        assert!(scan(b"/G0X1Y2\r", &mut v));
        assert!(scan(b"", &mut v) && v.is_empty());
        for l in [
            "G1 X#1", "G1 X[1]", "G0 (c)", "G0 ; c", "o1 if", "G0 X1 0", "%", "X--1", "G0 X.",
        ] {
            assert!(!scan(l.as_bytes(), &mut v), "{l}");
        }
    }
}
