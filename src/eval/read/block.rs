//! One ordinary line as the reader sees it: the buffers a line's words,
//! assignments and edits are gathered in, the checks on its words' letters
//! made while reading it, and where its program-flow M words are. Running
//! it (evaluating, assigning, writing, updating the machine model) is a
//! step of `eval/exec/line.rs`.

use crate::block::RawWord;
use crate::codes::MCode;
use crate::diag::ErrorKind;
use crate::diag::SyntaxError;
use crate::emit::Edit;
use crate::parse::ast::{ExprKind, Item, Span, Word};

use crate::eval::state::checked::Checked;

/// Evaluated words of the line: (letter, value).
pub(crate) type Words = Vec<(u8, f64)>;

/// Per-line buffers kept between lines.
#[derive(Default)]
pub(crate) struct Scratch {
    pub(in crate::eval) words: Words,
    pub(in crate::eval) repl: Vec<(Span, Edit)>,
    pub(in crate::eval) num_set: Vec<(usize, f64)>,
    pub(in crate::eval) named_set: Vec<(crate::parse::Name, f64)>,
    pub(in crate::eval) context_ops: Vec<(u8, Span)>,
    pub(in crate::eval) word_spans: Vec<Span>,
    /// The words' values as written for a consumer (see
    /// [`crate::block::Block::decode_known`]).
    pub(in crate::eval) known: Vec<(u8, f64)>,
}

impl Scratch {
    pub(in crate::eval) fn clear(&mut self) {
        self.words.clear();
        self.repl.clear();
        self.num_set.clear();
        self.named_set.clear();
        self.context_ops.clear();
        self.word_spans.clear();
        self.known.clear();
    }
}

/// What the words read so far on a line count against the per-line limits.
#[derive(Default)]
pub(in crate::eval) struct WordCounts {
    /// Letters seen (bit per letter), G and M words aside.
    seen: u32,
    m_words: u32,
}

impl WordCounts {
    /// Counts the word `w` (read after its value); false if it is a fifth
    /// M word or a letter given twice (see [`WordCounts::refusal`]).
    #[inline(always)]
    pub(in crate::eval) fn count(&mut self, w: &Word) -> bool {
        if w.letter == b'm' {
            self.m_words += 1;
            if self.m_words > 4 {
                return false;
            }
        } else if w.letter != b'g' && w.letter.is_ascii_lowercase() {
            let bit = 1u32 << (w.letter.wrapping_sub(b'a') as u32 & 31);
            if self.seen & bit != 0 {
                return false;
            }
            self.seen |= bit;
        }
        true
    }

    /// The error of a word [`WordCounts::count`] refused, at the word.
    #[cold]
    pub(in crate::eval) fn refusal(w: &Word) -> ErrorKind {
        if w.letter == b'm' {
            ErrorKind::Syntax(SyntaxError::TooManyMWords)
        } else {
            ErrorKind::Syntax(SyntaxError::DuplicateWord {
                letter: w.letter as char,
            })
        }
    }
}

/// Whether the word `w` is refused before its value is read: a U, V or W
/// word without those axes (`uvw_axes` off; see [`letter_refusal`]).
#[inline(always)]
pub(in crate::eval) fn letter_refused(w: &Word, uvw_axes: bool) -> bool {
    matches!(w.letter, b'u' | b'v' | b'w') && !uvw_axes
}

/// The error of a word [`letter_refused`] refused, and where: its letter.
#[cold]
pub(in crate::eval) fn letter_refusal(w: &Word) -> (ErrorKind, Span) {
    let k = ErrorKind::Syntax(SyntaxError::BadCharacter {
        ch: w.letter as char,
        byte: w.letter,
    });
    (k, Span::new(w.span.start, w.span.start + 1))
}

/// The words of a plain line (`read`, literal words only) as the general
/// path evaluates them, into `words`; false if the line needs the grammar
/// (a U, V or W word without `uvw_axes`, an M code that acts on the flow or
/// the context, a fifth M word, a letter given twice: the grammar's path
/// reports them).
#[inline(always)]
pub(in crate::eval) fn plain_words(
    read: &[RawWord],
    uvw_axes: bool,
    words: &mut Vec<(u8, f64)>,
) -> bool {
    let mut seen = 0u32;
    let mut m_count = 0;
    for w in read {
        let letter = w.letter.to_ascii_lowercase();
        match letter {
            b'u' | b'v' | b'w' if !uvw_axes => return false,
            b'm' => {
                if matches!(w.value, 70.0 | 71.0 | 72.0 | 73.0 | 98.0 | 99.0) {
                    return false;
                }
                m_count += 1;
                if m_count > 4 {
                    return false;
                }
            }
            b'g' => {}
            l => {
                let bit = 1u32 << ((l - b'a') as u32 & 31);
                if seen & bit != 0 {
                    return false;
                }
                seen |= bit;
            }
        }
        words.push((letter, w.value));
    }
    true
}

/// The length of `raw` without its trailing blanks.
pub(in crate::eval) fn trimmed_len(raw: &[u8]) -> usize {
    raw.iter()
        .rposition(|b| !b.is_ascii_whitespace())
        .map_or(0, |p| p + 1)
}

/// A word that `exec_words` can run: not an M-code it would have to act on
/// (M70 to M73, M98, M99, or an M-code computed by an expression).
pub(in crate::eval) fn plain_word(item: &Item) -> bool {
    match item {
        Item::Word(w) => {
            w.letter != b'm'
                || (w.literal
                    && matches!(w.value.kind, ExprKind::Num(v)
                        if !matches!(v, 70.0 | 71.0 | 72.0 | 73.0 | 98.0 | 99.0)))
        }
        _ => false,
    }
}

/// Where the line's M98 is, if its checked codes hold one (the whole
/// line, of length `len`, if its word is not found).
pub(in crate::eval) fn m98_word(c: &Checked, items: &[Item], len: u32) -> Option<Span> {
    let k = c.ms().iter().position(|&m| m == MCode::Other(98))?;
    Some(m_word(items, k).map_or(Span::new(0, len), |w| w.span))
}

/// The line's `k`-th M word (the one of its `k`-th M code: the checks
/// decode every M word they accept, in line order).
pub(in crate::eval) fn m_word(items: &[Item], k: usize) -> Option<&Word> {
    items
        .iter()
        .filter_map(|i| match i {
            Item::Word(w) if w.letter == b'm' => Some(w),
            _ => None,
        })
        .nth(k)
}

#[cfg(test)]
mod tests {
    use crate::flatten::flatten_str;
    use crate::settings::Settings;

    fn flat(text: &str) -> String {
        flatten_str(text, &Settings::default()).unwrap_or_else(|e| panic!("{text}: {e:?}"))
    }

    /// A subprogram called with M98 whose middle line is `line`.
    fn sub(line: &str) -> String {
        format!("M98 P100\nG0 X3\nM2\nO100\n  G0 X1\n{line}\n  G0 X2\nM99\n")
    }

    /// M99 is found in the line's checked codes, written or computed, and
    /// nothing else is taken for it: it ends an M98 subprogram (or, in the
    /// main program, is written M2 in its place); the other codes of its
    /// group and other M codes do not.
    #[test]
    fn m99_is_found_in_the_checked_codes() {
        let back = "  G0 X1\nG0 X3\nM2\n";
        let cases: &[(String, &str)] = &[
            (sub("  M99"), back),
            (sub("  #1=99\n  M#1"), back),
            (sub("  #1=1\n  M#1"), "  G0 X1\n  M1\n  G0 X2\nG0 X3\nM2\n"),
            (
                sub("  #1=0\n  M8 M#1"),
                "  G0 X1\n  M8 M0\n  G0 X2\nG0 X3\nM2\n",
            ),
            (sub("  #1=2\n  M#1"), "  G0 X1\n  M2\n"),
            (sub("  #1=9\n  M#1"), "  G0 X1\n  M9\n  G0 X2\nG0 X3\nM2\n"),
            ("#1=99\nG0 X1\nM5 M#1\nG0 X2\n".into(), "G0 X1\nM5 M2\n"),
            ("#1=99\nG0 X1\nM5 M#1 (c)\n".into(), "G0 X1\nM5 M2 (c)\n"),
            ("#1=99\nG0 X1 M5 M#1\n".into(), "G0 X1 M5 M2\n"),
        ];
        for (text, want) in cases {
            assert_eq!(flat(text), *want, "{text}");
        }
    }

    /// M70 to M73 are found in the checked codes, written or computed:
    /// each word leaves the line, and its save or restore acts.
    #[test]
    fn context_codes_are_found_in_the_checked_codes() {
        let call = |line: &str| format!("o1 sub\n{line}\n  G20\no1 endsub\no1 call\nG0 X1\nM2\n");
        let restored = "  G20\nG21\nG0 X1\nM2\n";
        let cases: &[(String, &str)] = &[
            (call("  M73"), restored),
            (call("  #2=73\n  M#2"), restored),
            (call("  #2=73\n  M8 M#2"), "  M8\n  G20\nG21\nG0 X1\nM2\n"),
            (call("  #2=70\n  M8 M#2"), "  M8\n  G20\nG0 X1\nM2\n"),
            (
                call("  #2=73\n  S100 M8 M#2"),
                "  S100 M8\n  G20\nG21\nG0 X1\nM2\n",
            ),
            (call("  #2=5\n  M8 M#2"), "  M8 M5\n  G20\nG0 X1\nM2\n"),
        ];
        for (text, want) in cases {
            assert_eq!(flat(text), *want, "{text}");
        }
    }
}
