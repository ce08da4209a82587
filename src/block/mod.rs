//! A typed block: one executed (flat) line decoded once. After evaluation
//! every word's value is a number, so decoding is reading letters and
//! numbers; G and M codes become enums per modal group, the other words
//! values by letter. Comments and messages are kept with their spans.
//!
//! The decoder is lenient about what the evaluator already checked (one
//! word per modal group, value ranges) but never panics: a line it cannot
//! read is an [`DecodeError`] with the span of the trouble.

use std::fmt;

pub use crate::codes::{
    ArcDistance, CoordSystem, CutterComp, Distance, FeedMode, GCode, LatheMode, MCode, MotionMode,
    NonModal, PathMode, Plane, Retract, SpindleDir, SpindleMode, ToolLength, Units,
};

mod moves;
mod read;
mod shape;
#[cfg(test)]
mod tests;

pub(crate) use moves::Spacing;
pub use moves::{Cuts, MoveValues, MovesRule, RawLine, RawWord};
pub(crate) use read::{
    LineSink, WordSink, WordsEnd, read_flat_line, read_flat_line_in, read_words,
};
pub use shape::Shape;
pub(crate) use shape::{kept_digits, without_trailing_zeros, written_as_is};

/// A span of the decoded line (byte offsets).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct BlockSpan {
    pub start: u16,
    pub end: u16,
}

/// What a word is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum WordKind {
    G(GCode),
    M(MCode),
    /// Any other letter (upper case), `@` or `^`.
    Value,
}

/// One word as written on the line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Word {
    /// Upper-case letter, or `@` / `^` (polar words).
    pub letter: u8,
    pub value: f64,
    pub kind: WordKind,
    pub span: BlockSpan,
    /// How its number is written.
    pub shape: Shape,
}

/// What a comment is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CommentKind {
    /// `( … )` or `; …` with nothing special.
    Plain,
    /// `(MSG, …)`: shown to the operator.
    Message,
    /// `(DEBUG, …)`, `(PRINT, …)`, `(LOG…)`, `(PROBEOPEN …)` and the like:
    /// for the interpreter's own logs.
    Log,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Comment {
    pub kind: CommentKind,
    /// The whole comment, parentheses or `;` included.
    pub span: BlockSpan,
    /// The text inside (after `MSG,` for a message).
    pub text: BlockSpan,
}

/// Why a line could not be decoded.
#[derive(Debug, Clone, PartialEq)]
pub struct DecodeError {
    pub span: BlockSpan,
    pub what: DecodeProblem,
}

#[derive(Debug, Clone, PartialEq)]
pub enum DecodeProblem {
    /// A byte that is not a word letter.
    BadCharacter(u8),
    /// A letter without a number.
    BadNumber,
    /// An unknown G code.
    UnknownG(f64),
    UnclosedComment,
    /// More than one word of a modal group.
    GroupConflict,
}

impl fmt::Display for DecodeProblem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            DecodeProblem::BadCharacter(b) => write!(f, "unexpected byte 0x{b:02x}"),
            DecodeProblem::BadNumber => f.write_str("a word without a number"),
            DecodeProblem::UnknownG(v) => write!(f, "unknown G code {v}"),
            DecodeProblem::UnclosedComment => f.write_str("unclosed comment"),
            DecodeProblem::GroupConflict => f.write_str("two G codes of one modal group"),
        }
    }
}

/// A decoded flat line.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Block {
    /// `/` at the start.
    pub block_delete: bool,
    /// A `%` line.
    pub percent: bool,
    /// The N word.
    pub line_number: Option<(f64, BlockSpan)>,
    /// Every word in order (G, M and value words, not N).
    pub words: Vec<Word>,
    pub comments: Vec<Comment>,
    /// Index into `words` of each letter's value word (A = 0 … Z = 25),
    /// and of `@` (26) and `^` (27).
    value_at: [u8; 28],
    /// The value of each slot's word where `present` has its bit (0
    /// elsewhere).
    vals: [f64; 28],
    /// M words on the line.
    m_words: u8,
    /// The slots of `value_at` that hold a word, as bits.
    present: u32,
    /// The line's G code of each modal group, by [`GCode::group`] (a G80
    /// beside another motion code gives way to it): one code a group, and
    /// nothing here to add for a new group.
    gs: [Option<GCode>; 16],
    /// The groups of `gs` that hold a code, as bits.
    groups: u16,
}

const NO_WORD: u8 = u8::MAX;

/// The motion group ([`GCode::group`]).
const MOTION: u8 = 1;

fn slot(letter: u8) -> usize {
    match letter {
        b'@' => 26,
        b'^' => 27,
        l => (l - b'A') as usize,
    }
}

/// Axis letters in order X Y Z A B C U V W.
pub const AXIS_LETTERS: [u8; 9] = *b"XYZABCUVW";

impl Block {
    /// The value of a non-G/M word (`letter` upper case, or `@`/`^`).
    #[inline]
    pub fn value(&self, letter: u8) -> Option<f64> {
        let s = match letter {
            b'A'..=b'Z' => letter - b'A',
            b'@' => 26,
            b'^' => 27,
            _ => return None,
        };
        (self.present >> s & 1 != 0).then(|| self.vals[s as usize])
    }

    /// The non-G/M word with this letter.
    pub fn word(&self, letter: u8) -> Option<&Word> {
        if !(letter.is_ascii_uppercase() || letter == b'@' || letter == b'^') {
            return None;
        }
        let i = *self.value_at.get(slot(letter))?;
        if i == NO_WORD {
            None
        } else {
            self.words.get(i as usize)
        }
    }

    /// Axis words by axis index (X Y Z A B C U V W).
    pub fn axes(&self) -> [Option<f64>; 9] {
        if !self.has_axis() {
            return [None; 9];
        }
        std::array::from_fn(|i| self.value(AXIS_LETTERS[i]))
    }

    /// Whether the line is a move and nothing else: no code but G0–G3 (if
    /// any), no words but axis words, F, S and I, J, K, R; not a `%` line.
    pub fn is_plain_move(&self) -> bool {
        const ALLOWED: u32 = {
            let mut bits = 0;
            let mut i = 0;
            let letters = *b"XYZABCUVWFSIJKR";
            while i < letters.len() {
                bits |= 1 << (letters[i] - b'A');
                i += 1;
            }
            bits
        };
        !self.percent
            && self.present & !ALLOWED == 0
            && self.m_words == 0
            && self.groups & !(1 << MOTION) == 0
            && matches!(
                self.motion(),
                None | Some(
                    MotionMode::Rapid | MotionMode::Linear | MotionMode::ArcCw | MotionMode::ArcCcw
                )
            )
    }

    /// The line's code of modal group `group` ([`GCode::group`]).
    #[inline]
    pub fn code(&self, group: u8) -> Option<GCode> {
        *self.gs.get(group as usize)?
    }

    /// The motion code (group 1).
    #[inline]
    pub fn motion(&self) -> Option<MotionMode> {
        match self.gs[MOTION as usize] {
            Some(GCode::Motion(m)) => Some(m),
            _ => None,
        }
    }

    /// The units code (group 6).
    pub fn units(&self) -> Option<Units> {
        match self.gs[6] {
            Some(GCode::Units(u)) => Some(u),
            _ => None,
        }
    }

    /// The feed mode code (group 5).
    pub fn feed_mode(&self) -> Option<FeedMode> {
        match self.gs[5] {
            Some(GCode::FeedMode(f)) => Some(f),
            _ => None,
        }
    }

    /// The cutter compensation code (group 7).
    pub fn cutter_comp(&self) -> Option<CutterComp> {
        match self.gs[7] {
            Some(GCode::CutterComp(c)) => Some(c),
            _ => None,
        }
    }

    /// The tool length code (group 8).
    pub fn tool_length(&self) -> Option<ToolLength> {
        match self.gs[8] {
            Some(GCode::ToolLength(t)) => Some(t),
            _ => None,
        }
    }

    /// The retract code (group 10).
    pub fn retract(&self) -> Option<Retract> {
        match self.gs[10] {
            Some(GCode::Retract(r)) => Some(r),
            _ => None,
        }
    }

    /// The coordinate system code (group 12).
    pub fn coord(&self) -> Option<CoordSystem> {
        match self.gs[12] {
            Some(GCode::Coord(c)) => Some(c),
            _ => None,
        }
    }

    /// The non-modal code (group 0).
    pub fn non_modal(&self) -> Option<NonModal> {
        match self.gs[0] {
            Some(GCode::NonModal(n)) => Some(n),
            _ => None,
        }
    }

    /// The line's G codes of the modal groups, one a group, in the order
    /// of the groups (a G80 beside another motion code left out).
    pub fn modal_codes(&self) -> impl Iterator<Item = GCode> + '_ {
        self.gs.iter().flatten().copied()
    }

    /// Whether any axis word is present.
    pub fn has_axis(&self) -> bool {
        const AXES: u32 = {
            let mut bits = 0;
            let mut i = 0;
            while i < AXIS_LETTERS.len() {
                bits |= 1 << (AXIS_LETTERS[i] - b'A');
                i += 1;
            }
            bits
        };
        self.present & AXES != 0
    }

    /// The M codes of the line in order.
    pub fn m_codes(&self) -> impl Iterator<Item = (MCode, &Word)> {
        self.words.iter().filter_map(|w| match w.kind {
            WordKind::M(m) => Some((m, w)),
            _ => None,
        })
    }

    /// The G codes of the line in order.
    pub fn g_codes(&self) -> impl Iterator<Item = (GCode, &Word)> {
        self.words.iter().filter_map(|w| match w.kind {
            WordKind::G(g) => Some((g, w)),
            _ => None,
        })
    }

    /// Whether the line has nothing but comments (or nothing).
    pub fn is_empty(&self) -> bool {
        self.words.is_empty() && !self.percent
    }

    /// Decodes one flat line (no terminator; trailing `\r` and blanks are
    /// fine). Blanks may appear anywhere outside comments, as in RS274NGC.
    pub fn decode(line: &[u8]) -> Result<Block, DecodeError> {
        let mut b = Block {
            value_at: [NO_WORD; 28],
            vals: [0.0; 28],
            m_words: 0,
            ..Block::default()
        };
        b.decode_into(line)?;
        Ok(b)
    }

    /// Decodes into `self`, reusing its room.
    pub fn decode_into(&mut self, line: &[u8]) -> Result<(), DecodeError> {
        self.clear();
        read_flat_line(line, self)
    }

    /// [`Block::decode_into`] of a line whose writer knows the values of
    /// its words: `known` holds, in line order, each word's upper-case
    /// letter and the value its number reads as (NaN: not known). The line
    /// is read by the same reader; a long number whose word is the next
    /// known one (same letter) takes the known value instead of going
    /// through the general float reader. A word the list does not name
    /// (a line number, say) is read as usual.
    ///
    /// The caller vouches that each known value is the one its text reads
    /// as: the shortest text that reads back as exactly the value, as
    /// [`crate::number::write_number`] writes it without a precision.
    pub fn decode_known(&mut self, line: &[u8], known: &[(u8, f64)]) -> Result<(), DecodeError> {
        self.clear();
        let mut sink = read::Known {
            block: self,
            known,
            next: 0,
        };
        read_flat_line(line, &mut sink)
    }

    /// The block of a line the straight-line reader read into `raw` (the
    /// same words, line number and comment, in the same order, through the
    /// same steps as [`Block::decode_into`]); `line` is the line's text.
    pub fn replay(&mut self, raw: &RawLine, line: &[u8]) -> Result<(), DecodeError> {
        self.clear();
        if let Some((v, s)) = raw.line_number {
            self.line_number = Some((v, s));
        }
        self.push_words(raw.words())?;
        if let Some(c) = raw.comment {
            self.comment(line, c.start as usize, c.end as usize);
        }
        Ok(())
    }

    /// [`Block::replay`] of a line of these words alone.
    pub fn replay_words(&mut self, words: &[RawWord]) -> Result<(), DecodeError> {
        self.clear();
        self.push_words(words)
    }

    fn push_words(&mut self, words: &[RawWord]) -> Result<(), DecodeError> {
        for w in words {
            self.push_word(w.letter.to_ascii_uppercase(), w.value, w.span, w.shape)?;
        }
        Ok(())
    }

    fn clear(&mut self) {
        self.block_delete = false;
        self.percent = false;
        self.line_number = None;
        self.words.clear();
        self.comments.clear();
        self.value_at = [NO_WORD; 28];
        let mut p = self.present;
        while p != 0 {
            self.vals[p.trailing_zeros() as usize] = 0.0;
            p &= p - 1;
        }
        self.present = 0;
        self.m_words = 0;
        if self.groups != 0 {
            self.gs = [None; 16];
            self.groups = 0;
        }
    }

    fn comment(&mut self, line: &[u8], start: usize, end: usize) {
        let semi = line[start] == b';';
        let inner_start = start + 1;
        let inner_end = if semi { end } else { end - 1 };
        let inner = &line[inner_start..inner_end];
        let lead = inner
            .iter()
            .position(|b| !matches!(b, b' ' | b'\t'))
            .unwrap_or(inner.len());
        let body = &inner[lead..];
        let starts = |w: &[u8]| body.len() >= w.len() && body[..w.len()].eq_ignore_ascii_case(w);
        let (kind, text_start) = if semi {
            (CommentKind::Plain, inner_start)
        } else if starts(b"msg,") {
            (CommentKind::Message, inner_start + lead + 4)
        } else if starts(b"debug,")
            || starts(b"print,")
            || starts(b"log")
            || starts(b"probe")
            || starts(b"abort,")
            || starts(b"py")
        {
            (CommentKind::Log, inner_start + lead)
        } else {
            (CommentKind::Plain, inner_start)
        };
        self.comments.push(Comment {
            kind,
            span: BlockSpan {
                start: start as u16,
                end: end as u16,
            },
            text: BlockSpan {
                start: text_start.min(inner_end) as u16,
                end: inner_end as u16,
            },
        });
    }

    fn push_word(
        &mut self,
        letter: u8,
        value: f64,
        span: BlockSpan,
        shape: Shape,
    ) -> Result<(), DecodeError> {
        let kind = match letter {
            b'N' if self.words.is_empty() && self.line_number.is_none() => {
                self.line_number = Some((value, span));
                return Ok(());
            }
            b'G' => {
                let g = GCode::decode(value).ok_or(DecodeError {
                    span,
                    what: DecodeProblem::UnknownG(value),
                })?;
                let group = g.group() as usize;
                let bit = 1 << group;
                // One code a group; a G80 beside another motion code is
                // allowed (the other one acts), as in LinuxCNC.
                let keep = self.groups & bit != 0
                    && match (self.gs[group], g) {
                        (Some(GCode::Motion(MotionMode::CancelCycle)), _) => false,
                        (_, GCode::Motion(MotionMode::CancelCycle)) => true,
                        _ => {
                            return Err(DecodeError {
                                span,
                                what: DecodeProblem::GroupConflict,
                            });
                        }
                    };
                if !keep {
                    self.gs[group] = Some(g);
                    self.groups |= bit;
                }
                WordKind::G(g)
            }
            b'M' => {
                self.m_words = self.m_words.saturating_add(1);
                WordKind::M(MCode::decode(value))
            }
            l => {
                let s = slot(l);
                if self.value_at[s] != NO_WORD {
                    return Err(DecodeError {
                        span,
                        what: DecodeProblem::GroupConflict,
                    });
                }
                self.value_at[s] = self.words.len().min(NO_WORD as usize - 1) as u8;
                self.vals[s] = value;
                self.present |= 1 << s;
                WordKind::Value
            }
        };
        self.words.push(Word {
            letter,
            value,
            kind,
            span,
            shape,
        });
        Ok(())
    }
}

impl LineSink for Block {
    type Error = DecodeError;
    const SHAPES: bool = true;

    fn on_percent(&mut self) -> Result<(), DecodeError> {
        self.percent = true;
        Ok(())
    }

    fn on_block_delete(&mut self) {
        self.block_delete = true;
    }

    #[inline(always)]
    fn on_word(
        &mut self,
        letter: u8,
        value: f64,
        span: BlockSpan,
        shape: Shape,
        _: bool,
    ) -> Result<(), DecodeError> {
        self.push_word(letter, value, span, shape)
    }

    fn on_comment(&mut self, line: &[u8], start: usize, end: usize) -> Result<(), DecodeError> {
        self.comment(line, start, end);
        Ok(())
    }
}
