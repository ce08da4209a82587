//! Parameter substitution in `(debug,…)`, `(print,…)`, `(log,…)` and
//! `(abort,…)` texts, with the reference's `%d`, `%f` and `%.Nf` directives.

use crate::parse::ast::Span;

use crate::eval::expr::named::{named_exists, read_named};
use crate::eval::expr::params::MAX_PARAM;
use crate::eval::expr::{Fault, Scope, read_numbered};

#[derive(Clone, Copy)]
enum Fmt {
    Decimals(usize),
}

fn push_value(out: &mut String, v: f64, fmt: Fmt) {
    // LinuxCNC 2.9 prints values closer to 0 than 0.0001 as 0.
    let v = if v.abs() < 1e-4 { 0.0 } else { v };
    let Fmt::Decimals(n) = fmt;
    let s = format!("{v:.n$}");
    if s.len() >= 30 {
        out.push_str("######");
    } else {
        out.push_str(&s);
    }
}

/// Substitutes parameters in a message body. `base` is the body's offset
/// in the line, for error positions.
pub(in crate::eval) fn substitute(
    scope: &mut impl Scope,
    text: &str,
    base: u32,
) -> Result<String, Fault> {
    let bytes = text.as_bytes();
    let mut out = String::with_capacity(text.len() + 16);
    let mut fmt = Fmt::Decimals(6);
    let mut i = 0;
    while i < bytes.len() {
        let c = bytes[i];
        if c == b'%' {
            match bytes.get(i + 1) {
                Some(b'd') => {
                    fmt = Fmt::Decimals(0);
                    i += 2;
                }
                Some(b'f') => {
                    fmt = Fmt::Decimals(4);
                    i += 2;
                }
                Some(b'.') => match (bytes.get(i + 2), bytes.get(i + 3)) {
                    (Some(d), Some(b'f')) if d.is_ascii_digit() => {
                        fmt = Fmt::Decimals((d - b'0') as usize);
                        i += 4;
                    }
                    _ => {
                        // The '%' is dropped and the '.' printed.
                        out.push('.');
                        i += 2;
                    }
                },
                _ => {
                    out.push('%');
                    i += 1;
                }
            }
            continue;
        }
        if c != b'#' {
            let ch = text[i..].chars().next().unwrap_or('?');
            out.push(ch);
            i += ch.len_utf8();
            continue;
        }
        let at = Span::new(base + i as u32, base + i as u32 + 1);
        match bytes.get(i + 1) {
            // LinuxCNC 2.9 drops a '#' at the very end.
            None => break,
            Some(d) if d.is_ascii_digit() => {
                let mut j = i + 1;
                let mut n: u64 = 0;
                while j < bytes.len() && bytes[j].is_ascii_digit() {
                    n = n
                        .saturating_mul(10)
                        .saturating_add((bytes[j] - b'0') as u64);
                    j += 1;
                }
                let span = Span::new(base + i as u32, base + j as u32);
                if (n as usize) < MAX_PARAM {
                    let v = if n == 0 {
                        0.0
                    } else {
                        read_numbered(scope, n as usize, span)?
                    };
                    push_value(&mut out, v, fmt);
                } else {
                    out.push_str("######");
                }
                i = j;
            }
            Some(b'<') => {
                let Some(close) = text[i..].find('>') else {
                    // LinuxCNC 2.9 ends the message at an unterminated name.
                    let _ = at;
                    break;
                };
                let raw_name = &text[i + 2..i + close];
                let name: String = raw_name
                    .chars()
                    .filter(|c| !c.is_whitespace())
                    .flat_map(|c| c.to_lowercase())
                    .collect();
                let name = crate::parse::Name::new(&name);
                let span = Span::new(base + i as u32, base + (i + close + 1) as u32);
                if named_exists(scope, &name, span)? {
                    let v = read_named(scope, &name, span)?;
                    push_value(&mut out, v, fmt);
                } else {
                    out.push_str("######");
                }
                i += close + 1;
            }
            Some(_) => {
                out.push('#');
                i += 1;
            }
        }
    }
    Ok(out)
}

/// Whether a substituted text reads back unchanged (no directives left).
/// Makes a substituted text read back unchanged: a `#` that would start a
/// parameter (or end the text, which LinuxCNC mishandles) is followed by a
/// `%d` directive, which prints nothing and keeps the `#` literal.
pub(crate) fn stabilize(text: &str) -> String {
    let b = text.as_bytes();
    let mut out = String::with_capacity(text.len() + 4);
    for (i, ch) in text.char_indices() {
        out.push(ch);
        if ch == '#' && matches!(b.get(i + 1), None | Some(b'<') | Some(b'0'..=b'9')) {
            out.push_str("%d");
        }
    }
    out
}

pub(crate) fn is_stable(text: &str) -> bool {
    let b = text.as_bytes();
    for (i, &c) in b.iter().enumerate() {
        match c {
            // A directive right after a '#' is the neutraliser of `stabilize`.
            b'%' if i > 0 && b[i - 1] == b'#' => {}
            b'%' if matches!(b.get(i + 1), Some(b'd' | b'f' | b'.')) => return false,
            b'#' if matches!(b.get(i + 1), None | Some(b'<') | Some(b'0'..=b'9')) => return false,
            _ => {}
        }
    }
    true
}
