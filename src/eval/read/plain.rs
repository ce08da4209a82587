//! Plain lines: a line of literal words, with an optional block delete and
//! line number, needs no evaluation and is written exactly as read. On the
//! general path such a line is read by the flat-line reader,
//! [`crate::block::read_flat_line`] (the one [`crate::block::Block::decode_into`] reads
//! with), and kept to the lines the grammar reads the same way (a property
//! test checks every line it takes against the grammar); any other goes to
//! the grammar.

use crate::block::{BlockSpan, DecodeError, LineSink, RawLine, RawWord, Shape, read_flat_line_in};
use crate::parse::MAX_LINE;

/// Room for a plain line's words: as the straight-line reader keeps them
/// (`raw`), or as [`read_plain_in`] reads them (`words`).
#[derive(Default)]
pub(in crate::eval) struct PlainRoom {
    pub(in crate::eval) raw: RawLine,
    pub(in crate::eval) words: Vec<RawWord>,
}

/// Reads the line `buf[..len]` (without its terminator) into `words` (letters upper case)
/// if it is a plain line with at least one word: blanks, an optional `/`,
/// an optional line number `N` with digits first and no sign, then words
/// of any letter but N and O, upper or lower case, each a number
/// `[+-]digits[.digits]` that may follow blanks but holds none, no
/// comment. False sends the line to the grammar (the flat-line reader
/// reads more: comments, `%`, polar words, blanks inside numbers, N and O
/// words).
/// The bytes of `buf` after the line (the rest of the file) are not read,
/// but let its numbers be read eight bytes at a time (see
/// [`read_flat_line_in`]).
#[inline]
pub(in crate::eval) fn read_plain_in(buf: &[u8], len: usize, words: &mut Vec<RawWord>) -> bool {
    words.clear();
    if len > MAX_LINE || len > buf.len() {
        return false;
    }
    let mut sink = Plain {
        line: &buf[..len],
        words,
        numbered: false,
    };
    read_flat_line_in(buf, len, &mut sink).is_ok() && !sink.words.is_empty()
}

/// Why a line is not plain (or does not read).
struct NotPlain;

impl From<DecodeError> for NotPlain {
    fn from(_: DecodeError) -> NotPlain {
        NotPlain
    }
}

/// Keeps the words of a plain line, and stops at anything else.
struct Plain<'a> {
    line: &'a [u8],
    words: &'a mut Vec<RawWord>,
    /// Whether the line number was read.
    numbered: bool,
}

impl LineSink for Plain<'_> {
    type Error = NotPlain;
    const SHAPES: bool = false;

    fn on_percent(&mut self) -> Result<(), NotPlain> {
        Err(NotPlain)
    }

    fn on_block_delete(&mut self) {}

    #[inline(always)]
    fn on_word(
        &mut self,
        letter: u8,
        value: f64,
        span: BlockSpan,
        shape: Shape,
        spaced: bool,
    ) -> Result<(), NotPlain> {
        let plain = match letter {
            b'N' => {
                // The line number: first, once.
                let first = self.words.is_empty() && !self.numbered;
                self.numbered = true;
                first && written_plainly(self.line, span, true)
            }
            b'O' | b'@' | b'^' => false,
            // A number that follows its letter and holds no blank is
            // written plainly; one with blanks is looked at.
            _ => !spaced || written_plainly(self.line, span, false),
        };
        if !plain {
            return Err(NotPlain);
        }
        if letter != b'N' {
            self.words.push(RawWord {
                letter,
                value,
                span,
                shape,
            });
        }
        Ok(())
    }

    fn on_comment(&mut self, _: &[u8], _: usize, _: usize) -> Result<(), NotPlain> {
        Err(NotPlain)
    }
}

/// Whether the word at `span` of `line` is its letter, blanks maybe, and a
/// number without blanks inside: an optional sign then digits and a point
/// (for a line number, no sign and a digit first). The reader has read
/// the number, so it has a digit and at most one point.
#[inline(always)]
fn written_plainly(line: &[u8], span: BlockSpan, line_number: bool) -> bool {
    let Some(t) = line.get(span.start as usize + 1..span.end as usize) else {
        return false;
    };
    let lead = t
        .iter()
        .take_while(|c| matches!(c, b' ' | b'\t' | b'\r'))
        .count();
    let mut t = &t[lead..];
    if let [b'-' | b'+', rest @ ..] = t
        && !line_number
    {
        t = rest;
    }
    let first_ok = match t.first() {
        Some(c) if line_number => c.is_ascii_digit(),
        Some(_) => true,
        None => false,
    };
    first_ok && t.iter().all(|c| c.is_ascii_digit() || *c == b'.')
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::parse::ast::{ExprKind, Item, LineKind};
    use proptest::prelude::*;

    fn read_plain(line: &[u8], words: &mut Vec<RawWord>) -> bool {
        read_plain_in(line, line.len(), words)
    }

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

    /// The words `exec_plain` runs for a line `read_plain` takes: lower
    /// case letters and values, as the grammar hands them over.
    fn plain_words(line: &[u8]) -> Option<Vec<(u8, f64)>> {
        let mut words = Vec::new();
        read_plain(line, &mut words).then(|| {
            words
                .iter()
                .map(|w| (w.letter.to_ascii_lowercase(), w.value))
                .collect()
        })
    }

    proptest! {
        /// Every line the plain path takes reads the same through the
        /// grammar: same letters, same values, bit for bit; each word's
        /// span is its text.
        #[test]
        fn plain_path_agrees_with_grammar(
            parts in proptest::collection::vec(
                prop_oneof![
                    "[gGxXyYzZfFsSmMtTiIjJkKpPrRuUhHdDqQlLeE]",
                    "[+-]?[0-9]{0,6}(\\.[0-9]{0,8})?",
                    "[+-]?[0-9]{14,20}(\\.[0-9]{0,25})?",
                    "[ \t\r]{0,2}",
                    "[nN][0-9]{1,4}(\\.[0-9]?)?",
                    "[nNoO]",
                    "/",
                    "[#\\[\\]()oO%;@^.]",
                    "\\([a-zA-Z ,]{0,6}\\)",
                ],
                0..14,
            )
        ) {
            let line: String = parts.concat();
            let mut words = Vec::new();
            if read_plain(line.as_bytes(), &mut words) {
                let ours: Vec<(u8, u64)> = words
                    .iter()
                    .map(|w| (w.letter.to_ascii_lowercase(), w.value.to_bits()))
                    .collect();
                let theirs = grammar_words(line.as_bytes());
                prop_assert!(theirs.is_some(), "plain path took {line:?}, grammar did not");
                let theirs: Vec<(u8, u64)> =
                    theirs.unwrap().iter().map(|&(l, v)| (l, v.to_bits())).collect();
                prop_assert_eq!(ours, theirs, "{:?}", line);
                for w in &words {
                    let text = &line.as_bytes()[w.span.start as usize..w.span.end as usize];
                    prop_assert_eq!(text[0].to_ascii_uppercase(), w.letter, "{:?}", line);
                    prop_assert!(text.last().is_some_and(|c| c.is_ascii_digit() || *c == b'.'));
                }
            }
        }
    }

    #[test]
    fn plain_lines() {
        let w = |l: &str| plain_words(l.as_bytes());
        assert_eq!(
            w("G1 X10.5 Y-2 F300"),
            Some(vec![(b'g', 1.0), (b'x', 10.5), (b'y', -2.0), (b'f', 300.0)])
        );
        assert_eq!(w("N10 g0 x 1"), Some(vec![(b'g', 0.0), (b'x', 1.0)]));
        assert_eq!(
            w("/G0X1Y2\r"),
            Some(vec![(b'g', 0.0), (b'x', 1.0), (b'y', 2.0)])
        );
        assert_eq!(w(" / n 5. m3 t +.5"), Some(vec![(b'm', 3.0), (b't', 0.5)]));
        assert_eq!(w("G1 X -1"), Some(vec![(b'g', 1.0), (b'x', -1.0)]));
        // Lines of no word go to the grammar.
        for l in ["", "N10", "  ", "/"] {
            assert_eq!(w(l), None, "{l:?}");
        }
        // So do lines the decoder reads but the plain path does not take.
        for l in [
            "G1 X#1", "G1 X[1]", "G0 (c)", "G0 ; c", "o1 if", "O100", "G0 X1 0", "G0 X1\r0",
            "G0 X- 1", "G0 X1 .5", "%", "X--1", "G0 X.", "N-5 G0", "N.5 G0", "N1 0 G0", "G0 N5",
            "N1 N2", "G0 @1 ^2", "N1 /G0",
        ] {
            assert_eq!(w(l), None, "{l:?}");
        }
        let long = format!("G1 X1{}", " ".repeat(MAX_LINE));
        assert_eq!(w(&long), None);
    }
}
