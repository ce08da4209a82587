//! Program text as read: source files (in memory or streamed in windows),
//! their lines, and places in them (byte spans, line and column). The lowest
//! layer: it knows nothing of G-code.

mod file;
mod locate;
mod marked_lines;

pub use file::{IN_MEMORY_LIMIT, InputLimits, SourceFile, Window, WindowLine, next_line};
pub(crate) use marked_lines::{Marked, is_mark};

/// `start..end` in bytes, relative to the start of the raw line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Span {
    pub start: u32,
    pub end: u32,
}

impl Span {
    pub fn new(start: u32, end: u32) -> Span {
        Span { start, end }
    }
}
