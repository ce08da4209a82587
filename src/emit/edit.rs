//! Lines written as their source line with edits: spans replaced by
//! computed numbers or by text, or removed. The evaluator writes a line this
//! way on its own thread when it must check the line's length, and hands the
//! source line and its edits to the output otherwise (see
//! [`super::Output::edited_line`]); both go through [`write_edits`].

use crate::number::{max_len, write_number};
use crate::source::Span;

/// How a span of a source line is rewritten.
#[derive(Debug, Clone, PartialEq)]
pub enum Edit {
    /// Replaced by a computed value.
    Number(f64),
    /// Removed, with the blanks after it.
    Remove,
    /// Replaced by text.
    Text(String),
}

/// An edit with its text borrowed (as read back from a chunk, too).
#[derive(Debug, Clone, Copy)]
pub(super) enum EditRef<'a> {
    Number(f64),
    Remove,
    Text(&'a [u8]),
}

impl Edit {
    pub(super) fn as_ref(&self) -> EditRef<'_> {
        match self {
            Edit::Number(v) => EditRef::Number(*v),
            Edit::Remove => EditRef::Remove,
            Edit::Text(t) => EditRef::Text(t.as_bytes()),
        }
    }
}

/// An upper bound of the length of the line `raw_len` bytes long once
/// `edits` are made, known without writing it; `None` if a number has none
/// (see [`max_len`]).
#[inline]
pub fn max_edited_len(
    raw_len: usize,
    edits: &[(Span, Edit)],
    precision: Option<u8>,
) -> Option<usize> {
    let mut n = raw_len;
    for (_, e) in edits {
        n += match e {
            Edit::Number(v) => max_len(*v, precision)?,
            Edit::Text(t) => t.len(),
            Edit::Remove => 0,
        };
    }
    Some(n)
}

/// Appends `raw` with `edits` made (sorted by start; one that starts
/// inside an earlier one is skipped) and its trailing blanks dropped. A
/// number with no G-code form is an error, with the span it replaces.
pub fn write_edited(
    out: &mut Vec<u8>,
    raw: &[u8],
    edits: &[(Span, Edit)],
    precision: Option<u8>,
) -> Result<(), (f64, Span)> {
    write_edits(
        out,
        raw,
        edits.iter().map(|(s, e)| (*s, e.as_ref())),
        precision,
    )
}

/// [`write_edited`] with the edits from an iterator, which is read to its
/// end unless a number fails.
pub(super) fn write_edits<'a>(
    out: &mut Vec<u8>,
    raw: &[u8],
    edits: impl Iterator<Item = (Span, EditRef<'a>)>,
    precision: Option<u8>,
) -> Result<(), (f64, Span)> {
    let base = out.len();
    let trimmed_len = raw
        .iter()
        .rposition(|b| !b.is_ascii_whitespace())
        .map_or(0, |p| p + 1);
    let mut last = 0usize;
    for (span, e) in edits {
        let (a, b) = (span.start as usize, span.end as usize);
        if a < last {
            continue;
        }
        out.extend_from_slice(&raw[last..a]);
        last = b;
        match e {
            EditRef::Number(v) => {
                if !write_number(out, v, precision) {
                    return Err((v, span));
                }
            }
            EditRef::Text(t) => out.extend_from_slice(t),
            EditRef::Remove => {
                while last < raw.len() && matches!(raw[last], b' ' | b'\t') {
                    last += 1;
                }
            }
        }
    }
    if last < trimmed_len {
        out.extend_from_slice(&raw[last..trimmed_len]);
    }
    while out.len() > base && out.last().is_some_and(u8::is_ascii_whitespace) {
        out.pop();
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn edited(raw: &str, edits: &[(Span, Edit)]) -> String {
        let mut out = b"G0\n".to_vec();
        write_edited(&mut out, raw.as_bytes(), edits, None).unwrap();
        String::from_utf8(out).unwrap()
    }

    #[test]
    fn edits_replace_remove_and_trim() {
        let raw = "G1 X[#1*2] #2=3 Y#<a> (c)  ";
        let edits = [
            (Span::new(4, 10), Edit::Number(0.5)),
            (Span::new(11, 15), Edit::Remove),
            (Span::new(17, 21), Edit::Number(-3.0)),
            (Span::new(22, 25), Edit::Text("(d)".into())),
        ];
        assert_eq!(edited(raw, &edits), "G0\nG1 X0.5 Y-3 (d)");
        // A removal at the end leaves no blanks; those before the line stay.
        let edits = [(Span::new(6, 10), Edit::Remove)];
        assert_eq!(edited("G1 X1 #1=2 \t", &edits), "G0\nG1 X1");
        assert_eq!(edited("  ", &[]), "G0\n");
        let bound = max_edited_len(raw.len(), &[(Span::new(4, 10), Edit::Number(0.5))], None);
        assert_eq!(bound, Some(raw.len() + 25));
        let tiny = [(Span::new(4, 10), Edit::Number(1e-300))];
        assert_eq!(max_edited_len(raw.len(), &tiny, None), None);
    }

    #[test]
    fn a_number_without_a_gcode_form_is_an_error() {
        let edits = [(Span::new(1, 2), Edit::Number(f64::NAN))];
        let mut out = Vec::new();
        let e = write_edited(&mut out, b"X1", &edits, None).unwrap_err();
        assert!(e.0.is_nan());
        assert_eq!(e.1, Span::new(1, 2));
    }
}
