//! Byte offsets to lines and columns, for diagnostics. A file's line starts
//! are sampled once (every [`STRIDE`]th line), on the first diagnostic that
//! needs them; each diagnostic then reads only from the nearest sample to
//! the line it points at, so warnings on a large streamed file cost about
//! the lines they point at, not the file.

use std::fs::File;
use std::io::{self, Read};

/// Every this many lines, a line start is kept.
const STRIDE: usize = 256;
/// Bytes handed to [`LineSamples::locate`] at a time: about the distance
/// from a sample to a line, so that a diagnostic costs what it reads (a
/// larger piece made a million warnings copy a million times its size).
const PIECE: usize = 4096;
/// Most bytes of a line kept for showing it.
const SHOWN: usize = 1024;

/// Sampled line starts: `starts[k]` is the offset of line `k * STRIDE`
/// (0-based).
#[derive(Debug, Default)]
pub(super) struct LineSamples {
    starts: Vec<u64>,
}

/// Where a byte offset is: 1-based line and column (in characters), and the
/// start of that line's text (at most [`SHOWN`] bytes, without terminator).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LineCol {
    pub line: u32,
    pub col: u32,
    pub text: Vec<u8>,
}

impl LineSamples {
    /// Samples the line starts of bytes read from `input`.
    pub(super) fn read(mut input: impl Read) -> io::Result<LineSamples> {
        let mut starts = vec![0u64];
        let mut buf = vec![0u8; 1 << 16];
        let (mut pos, mut line) = (0u64, 0usize);
        loop {
            let n = input.read(&mut buf)?;
            if n == 0 {
                break;
            }
            for i in memchr::memchr_iter(b'\n', &buf[..n]) {
                line += 1;
                if line % STRIDE == 0 {
                    starts.push(pos + i as u64 + 1);
                }
            }
            pos += n as u64;
        }
        Ok(LineSamples { starts })
    }

    /// The sample at or before `offset`: (0-based line, its start).
    fn before(&self, offset: u64) -> (usize, u64) {
        let k = self.starts.partition_point(|&s| s <= offset).max(1) - 1;
        (k * STRIDE, self.starts.get(k).copied().unwrap_or(0))
    }

    /// Locates `offset` in bytes available as `read_at(from)` (the bytes
    /// from an offset on, in pieces).
    pub(super) fn locate(
        &self,
        offset: u64,
        text: &mut dyn FnMut(u64, &mut Vec<u8>) -> bool,
    ) -> LineCol {
        let (mut line, mut start) = self.before(offset);
        let mut chunk = Vec::new();
        let mut pos = start;
        // Find the start of the line holding `offset`.
        'find: while pos < offset {
            chunk.clear();
            if !text(pos, &mut chunk) || chunk.is_empty() {
                break;
            }
            let stop = ((offset - pos) as usize).min(chunk.len());
            for i in memchr::memchr_iter(b'\n', &chunk[..stop]) {
                line += 1;
                start = pos + i as u64 + 1;
            }
            pos += chunk.len() as u64;
            if pos >= offset {
                break 'find;
            }
        }
        // The line's text from its start.
        let mut shown = Vec::new();
        let mut at = start;
        while shown.len() < SHOWN.max((offset - start) as usize + 1).min(1 << 20) {
            chunk.clear();
            if !text(at, &mut chunk) || chunk.is_empty() {
                break;
            }
            match memchr::memchr(b'\n', &chunk) {
                Some(e) => {
                    shown.extend_from_slice(&chunk[..e]);
                    break;
                }
                None => shown.extend_from_slice(&chunk),
            }
            at += chunk.len() as u64;
        }
        let upto = ((offset - start) as usize).min(shown.len());
        let col = String::from_utf8_lossy(&shown[..upto]).chars().count() as u32 + 1;
        let mut keep = shown.len().min(SHOWN.max(upto + 1));
        while keep > 0 && !is_char_boundary(&shown, keep) {
            keep -= 1;
        }
        shown.truncate(keep);
        while shown.last() == Some(&b'\r') {
            shown.pop();
        }
        LineCol {
            line: line as u32 + 1,
            col,
            text: shown,
        }
    }
}

/// Whether `i` does not cut a UTF-8 sequence of `b`.
fn is_char_boundary(b: &[u8], i: usize) -> bool {
    i >= b.len() || (b[i] as i8) >= -0x40
}

/// Reads pieces of a file on disk for [`LineSamples::locate`] (positional
/// reads: the handle's cursor is not moved).
pub(super) fn file_pieces(file: &File) -> impl FnMut(u64, &mut Vec<u8>) -> bool + '_ {
    use std::os::unix::fs::FileExt;
    move |at, out| {
        out.resize(PIECE, 0);
        match file.read_at(out, at) {
            Ok(n) => {
                out.truncate(n);
                true
            }
            Err(_) => false,
        }
    }
}

/// Bytes of a file read at once for diagnostics.
const BLOCK: usize = 1 << 16;

/// A block of a file on disk kept between diagnostics: (offset, bytes).
#[derive(Debug, Default)]
pub(super) struct Block {
    at: u64,
    bytes: Vec<u8>,
}

/// Pieces of a file on disk for [`LineSamples::locate`], from the kept
/// block when it holds them (diagnostics near each other read the file
/// once), else read as a new block from the piece's offset.
pub(super) fn block_pieces<'a>(
    file: &'a File,
    block: &'a mut Block,
) -> impl FnMut(u64, &mut Vec<u8>) -> bool + 'a {
    use std::os::unix::fs::FileExt;
    move |at, out| {
        let inside = |b: &Block| at >= b.at && at - b.at < b.bytes.len() as u64;
        if !inside(block) {
            block.bytes.resize(BLOCK, 0);
            let mut got = 0;
            while got < BLOCK {
                match file.read_at(&mut block.bytes[got..], at + got as u64) {
                    Ok(0) => break,
                    Ok(n) => got += n,
                    Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                    Err(_) => {
                        block.bytes.clear();
                        return false;
                    }
                }
            }
            block.bytes.truncate(got);
            block.at = at;
        }
        let from = (at - block.at) as usize;
        let to = (from + PIECE).min(block.bytes.len());
        out.extend_from_slice(block.bytes.get(from..to).unwrap_or(&[]));
        true
    }
}

/// Pieces of bytes in memory for [`LineSamples::locate`].
pub(super) fn memory_pieces(data: &[u8]) -> impl FnMut(u64, &mut Vec<u8>) -> bool + '_ {
    move |at, out| {
        let at = (at as usize).min(data.len());
        let end = (at + PIECE).min(data.len());
        out.extend_from_slice(&data[at..end]);
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Line, column and text agree with a plain count over every offset,
    /// across sample boundaries and multi-byte characters.
    #[test]
    fn locate_agrees_with_counting() {
        let mut text = Vec::new();
        for k in 0..700 {
            match k % 5 {
                0 => text.extend_from_slice(b"\n"),
                1 => text.extend_from_slice("G1 X1 (\u{e4}\u{f6})\r\n".as_bytes()),
                _ => text.extend_from_slice(format!("G0 X{k} Y{}\n", k * 3).as_bytes()),
            }
        }
        text.extend_from_slice(b"M2");
        let samples = LineSamples::read(&text[..]).expect("read");
        for offset in (0..=text.len()).step_by(7).chain([text.len()]) {
            let before = &text[..offset];
            let line = before.iter().filter(|&&b| b == b'\n').count() as u32 + 1;
            let start = before
                .iter()
                .rposition(|&b| b == b'\n')
                .map_or(0, |p| p + 1);
            let col = String::from_utf8_lossy(&text[start..offset])
                .chars()
                .count() as u32
                + 1;
            let end = text[start..]
                .iter()
                .position(|&b| b == b'\n')
                .map_or(text.len(), |p| start + p);
            let mut want = text[start..end].to_vec();
            while want.last() == Some(&b'\r') {
                want.pop();
            }
            let got = samples.locate(offset as u64, &mut memory_pieces(&text));
            assert_eq!(
                got,
                LineCol {
                    line,
                    col,
                    text: want
                },
                "offset {offset}"
            );
        }
    }

    /// A very long line is shown cut, at a character boundary.
    #[test]
    fn long_lines_are_cut() {
        let text = "\u{e4}".repeat(5000);
        let samples = LineSamples::read(text.as_bytes()).expect("read");
        let got = samples.locate(4, &mut memory_pieces(text.as_bytes()));
        assert_eq!((got.line, got.col), (1, 3));
        assert!(got.text.len() <= SHOWN);
        assert!(std::str::from_utf8(&got.text).is_ok());
    }
}
