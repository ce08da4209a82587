//! Reading the source: lines, words and blocks, the plain-line fast paths
//! (the straight-line reader, and plain lines decoded as blocks).

pub(super) mod block;
pub(super) mod plain;
pub(super) mod scan_ahead;
pub(super) mod straight;
pub(super) mod validate;

use crate::parse::LineParser;
use crate::program::Window;

/// Reading the source: the line being run and the buffers the readers
/// reuse.
#[derive(Default)]
pub(super) struct Reader {
    pub(super) parser: LineParser,
    /// Lines of a streamed file.
    pub(super) window: Window,
    /// Room for a plain line's words and block.
    pub(super) plain: Option<Box<plain::PlainRoom>>,
    pub(super) words_buf: Vec<(u8, f64)>,
    pub(super) scratch: Option<Box<block::Scratch>>,
    /// Chunks of lines read ahead, kept from one straight run to the next.
    pub(super) chunks: scan_ahead::ChunkPool,
    /// Byte offset and 0-based index of the line being run.
    pub(super) line_start: u32,
    pub(super) line_idx: u32,
}

impl Reader {
    /// `named2007`: lines are read in the 2007 named-parameter syntax too.
    pub(super) fn new(named2007: bool) -> Reader {
        Reader {
            parser: LineParser::new(named2007),
            plain: Some(Box::default()),
            words_buf: Vec::with_capacity(16),
            scratch: Some(Box::default()),
            ..Reader::default()
        }
    }

    /// Notes the line about to run.
    #[inline]
    pub(super) fn at(&mut self, start: u32, idx: u32) {
        self.line_start = start;
        self.line_idx = idx;
    }
}
