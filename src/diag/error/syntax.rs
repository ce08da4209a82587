//! Reading a line: characters, comments, words and numbers.

use std::fmt;

super::phase! {
    /// Reading a line: characters, comments, words and numbers.
    pub enum SyntaxError {
        /// A line of 253 characters or more.
        "E0001" CommandTooLong,
        /// `(a (b))`
        "E0002" NestedComment,
        /// `G0 (open`
        "E0003" UnclosedComment,
        /// `G0 X1 {` or a UTF-8 byte outside a comment.
        "E0004" BadCharacter { ch: char, byte: u8 },
        /// `G1 X[1+2` and other shapes the grammar does not accept.
        "E0005" Syntax { expected: String },
        /// `X.` or `[1+]`
        "E0006" BadNumber { text: String },
        /// `X1.2.3`
        "E0007" TrailingNumber { text: String },
        /// `#1.5=0` or `G1.5`-style integer contexts.
        "E0008" NonInteger { value: f64 },
        /// `%` line in a program that did not start with `%`.
        "E0009" StrayPercent,
        /// `G0 X1 X2`
        "E0010" DuplicateWord { letter: char },
        /// `M3 M8 M7 M9 M5`: more than four M words.
        "E0011" TooManyMWords,
    }
}

impl fmt::Display for SyntaxError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use SyntaxError::*;
        match self {
            CommandTooLong => write!(f, "line is longer than 252 characters"),
            NestedComment => write!(f, "comment opened inside a comment"),
            UnclosedComment => write!(f, "comment is not closed before the end of the line"),
            BadCharacter { ch, byte } => {
                if ch.is_ascii_graphic() {
                    write!(f, "character '{ch}' is not allowed here")
                } else {
                    write!(f, "byte 0x{byte:02x} is not allowed outside a comment")
                }
            }
            Syntax { expected } => write!(f, "expected {expected}"),
            BadNumber { text } => write!(f, "'{text}' is not a number"),
            TrailingNumber { text } => {
                write!(f, "'{text}' is not a number (more than one decimal point)")
            }
            NonInteger { value } => write!(f, "{value} is not an integer"),
            StrayPercent => write!(f, "'%' line in a program that does not start with '%'"),
            DuplicateWord { letter } => write!(
                f,
                "more than one {} word on the line",
                letter.to_ascii_uppercase()
            ),
            TooManyMWords => write!(f, "more than four M words on the line"),
        }
    }
}
