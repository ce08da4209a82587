//! The named-parameter syntax of the 2007 proposal on the LinuxCNC wiki,
//! which some old programs and notes follow (opt-in: it is not LinuxCNC
//! syntax). A processed line (blanks removed, lower-cased) is rewritten onto
//! today's forms before it is parsed, keeping each byte's raw offset:
//!
//! * `#[name]`, a bracket holding only a name, is `#<name>` (a name followed
//!   by `[` is a function, so `#[sqrt[9]]` keeps its meaning);
//! * `#$name$` (local) is `#<name>`, `#name$` (global) is `#<_name>`;
//! * the O-word names `oname$` and `o$name$` are `o<name>` (labels of loops
//!   and conditionals are local to their subroutine, subroutine names
//!   global, as for `o<name>`).
//!
//! Comments are left alone.

fn name_start(b: u8) -> bool {
    b.is_ascii_alphabetic() || b == b'_'
}

fn name_char(b: u8) -> bool {
    b.is_ascii_alphanumeric() || b == b'_'
}

fn label_char(b: u8) -> bool {
    b.is_ascii_alphanumeric() || matches!(b, b'_' | b'-' | b'.')
}

struct Out {
    text: Vec<u8>,
    map: Vec<u32>,
}

impl Out {
    fn push(&mut self, b: u8, at: u32) {
        self.text.push(b);
        self.map.push(at);
    }

    /// Copies bytes `s..e` of the line with their offsets.
    fn copy(&mut self, t: &[u8], map: &[u32], s: usize, e: usize) {
        for (k, &b) in t.iter().enumerate().take(e).skip(s) {
            self.push(b, offset(map, k));
        }
    }
}

/// Raw offset of processed byte `i` (the end for anything past it).
fn offset(map: &[u32], i: usize) -> u32 {
    map.get(i).or(map.last()).copied().unwrap_or(0)
}

/// Where the O-word of a processed line starts, if the line has one: after
/// an optional block delete and line number.
fn o_word_at(t: &[u8]) -> Option<usize> {
    let mut i = 0;
    if t.first() == Some(&b'/') {
        i += 1;
    }
    if t.get(i) == Some(&b'n') {
        i += 1;
        while t.get(i).is_some_and(|b| b.is_ascii_digit() || *b == b'.') {
            i += 1;
        }
    }
    (t.get(i) == Some(&b'o')).then_some(i)
}

/// The 2007-style parameter reference at the `#` at `i`, if there is one:
/// `#[name]` and `#$name$` (local) or `#name$` (global). Gives the name's
/// start and end (the offset of its closing byte) and whether it is global.
fn named_form(t: &[u8], i: usize) -> Option<(usize, usize, bool)> {
    let (s, close, global) = match *t.get(i + 1)? {
        b'[' => (i + 2, b']', false),
        b'$' => (i + 2, b'$', false),
        c if name_start(c) => (i + 1, b'$', true),
        _ => return None,
    };
    if !t.get(s).is_some_and(|&c| name_start(c)) {
        return None;
    }
    let e = s + t[s..].iter().take_while(|&&c| name_char(c)).count();
    (t.get(e) == Some(&close)).then_some((s, e, global))
}

/// Rewrites a processed line (`map`: raw offset of each byte, plus one for
/// the end); `None` when nothing in it uses the syntax.
pub(crate) fn rewrite(text: &str, map: &[u32]) -> Option<(String, Vec<u32>)> {
    let t = text.as_bytes();
    if !t.iter().any(|&b| b == b'#' || b == b'$') {
        return None;
    }
    let at = |i: usize| offset(map, i);
    let mut out = Out {
        text: Vec::with_capacity(t.len() + 8),
        map: Vec::with_capacity(t.len() + 9),
    };
    let mut changed = false;
    let mut i = 0;
    if let Some(o) = o_word_at(t) {
        out.copy(t, map, 0, o + 1);
        i = o + 1;
        let dollar = t.get(i) == Some(&b'$');
        let s = i + dollar as usize;
        let mut e = s;
        while t.get(e).is_some_and(|&b| label_char(b)) {
            e += 1;
        }
        if e > s && t.get(e) == Some(&b'$') && (dollar || t[s].is_ascii_alphabetic()) {
            out.push(b'<', at(i));
            out.copy(t, map, s, e);
            out.push(b'>', at(e));
            i = e + 1;
            changed = true;
        }
    }
    while i < t.len() {
        let b = t[i];
        match b {
            b'(' => {
                while i < t.len() {
                    out.push(t[i], at(i));
                    i += 1;
                    if t[i - 1] == b')' {
                        break;
                    }
                }
                continue;
            }
            b';' => {
                while i < t.len() {
                    out.push(t[i], at(i));
                    i += 1;
                }
                continue;
            }
            b'#' => {
                if let Some((s, e, global)) = named_form(t, i) {
                    out.push(b'#', at(i));
                    out.push(b'<', at(if global { s } else { i + 1 }));
                    if global && t[s] != b'_' {
                        out.push(b'_', at(s));
                    }
                    out.copy(t, map, s, e);
                    out.push(b'>', at(e));
                    i = e + 1;
                    changed = true;
                    continue;
                }
                out.push(b, at(i));
            }
            _ => out.push(b, at(i)),
        }
        i += 1;
    }
    if !changed {
        return None;
    }
    out.map.push(at(t.len()));
    let text = String::from_utf8(out.text).ok()?;
    Some((text, out.map))
}

#[cfg(test)]
mod tests {
    use super::rewrite;

    fn rw(s: &str) -> String {
        let map: Vec<u32> = (0..=s.len() as u32).collect();
        match rewrite(s, &map) {
            Some((t, m)) => {
                assert_eq!(m.len(), t.len() + 1, "{s}");
                assert!(m.windows(2).all(|w| w[0] <= w[1]), "{s}: offsets ascend");
                t
            }
            None => s.to_string(),
        }
    }

    #[test]
    fn forms() {
        assert_eq!(rw("#[feedrate]=#[abc]"), "#<feedrate>=#<abc>");
        assert_eq!(rw("g1x#[sqrt[9]]"), "g1x#[sqrt[9]]");
        assert_eq!(rw("g1x#[1+2]"), "g1x#[1+2]");
        assert_eq!(rw("g1x#[a+b]"), "g1x#[a+b]");
        assert_eq!(rw("#$depth$=2"), "#<depth>=2");
        assert_eq!(rw("#depth$=2"), "#<_depth>=2");
        assert_eq!(rw("#_depth$=2"), "#<_depth>=2");
        assert_eq!(rw("odrill$sub"), "o<drill>sub");
        assert_eq!(rw("n10o$loop$while[#$i$lt3]"), "n10o<loop>while[#<i>lt3]");
        assert_eq!(rw("/o$x$endif"), "/o<x>endif");
        assert_eq!(rw("o100sub"), "o100sub");
        assert_eq!(rw("g1x1(#[a] #b$)"), "g1x1(#[a] #b$)");
        assert_eq!(rw("#1=2;#[a]"), "#1=2;#[a]");
        assert_eq!(rw("#<a>=#5"), "#<a>=#5");
    }

    #[test]
    fn offsets_point_into_the_raw_line() {
        let s = "#ab$=1";
        let map: Vec<u32> = (0..=s.len() as u32).collect();
        let (t, m) = rewrite(s, &map).unwrap();
        assert_eq!(t, "#<_ab>=1");
        // '=' keeps its raw offset 4; the end stays at 6.
        assert_eq!(m[t.find('=').unwrap()], 4);
        assert_eq!(*m.last().unwrap(), 6);
    }
}
