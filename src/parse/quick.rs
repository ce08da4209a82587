//! A subroutine call whose arguments are plain numbers
//! (`o<hole> call [12.5] [-3] [0.2]`, the usual call of generated and
//! hand-written programs), read without the grammar: the same [`Line`] the
//! grammar and its lowering make of it (the tests compare both ways on
//! random lines), found in one pass over the processed text. Anything else
//! (another label, an expression, a comment, a bad number, more than 30
//! arguments) is left to the grammar.

use super::ast::{Expr, ExprKind, Label, Line, LineKind, OKind, OLine, Span};
use super::normalize::Normalized;
use super::{Name, parse_number};

/// The line of the processed text `norm` if it is such a call.
pub(super) fn call_line(norm: &Normalized) -> Option<Line> {
    let t = norm.text.as_bytes();
    let rest = t.strip_prefix(b"o<")?;
    let close = rest.iter().position(|&b| b == b'>')?;
    let name = &rest[..close];
    if name.is_empty()
        || !name
            .iter()
            .all(|&b| b.is_ascii_lowercase() || b.is_ascii_digit() || b == b'_')
    {
        return None;
    }
    // Offsets in the processed text: `<` at 1, `>` at `gt`.
    let gt = 2 + close;
    let mut i = gt + 1;
    if t.get(i..i + 4)? != b"call" {
        return None;
    }
    i += 4;
    // Tight spans, as the lowering makes them: from the raw offset of the
    // first byte to just after the raw offset of the last.
    let span =
        |first: usize, last: usize| Span::new(norm.raw_offset(first), norm.raw_offset(last) + 1);
    let mut args = Vec::new();
    while i < t.len() {
        if t[i] != b'[' || args.len() == 30 {
            return None;
        }
        let open = i;
        let start = i + 1;
        let mut j = start;
        if matches!(t.get(j), Some(b'+' | b'-')) {
            j += 1;
        }
        let digits = j;
        while t.get(j).is_some_and(|c| c.is_ascii_digit() || *c == b'.') {
            j += 1;
        }
        if j == digits || t.get(j) != Some(&b']') {
            return None;
        }
        let v = parse_number(std::str::from_utf8(&t[start..j]).ok()?).ok()?;
        args.push(Expr {
            kind: ExprKind::Num(v),
            span: span(open, j),
        });
        i = j + 1;
    }
    let name = std::str::from_utf8(name).ok()?;
    Some(Line {
        kind: LineKind::O(OLine {
            label: Label::Static(Name::new(name)),
            label_span: span(1, gt),
            kind: OKind::Call,
            expr: None,
            args,
            active_comment: false,
            exec_error: None,
        }),
        block_delete: false,
        line_number: None,
    })
}
