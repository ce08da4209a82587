//! Finds the lines the O-word index must look at without looking at every
//! line: newlines and marked bytes (`o`, `O`, `%`, `m`, `M`) are found with
//! `memchr`, and only lines holding a mark, overlong lines and the leading
//! blank lines are handed on. Every O-line, `%` line, `M98` and `M99` holds a
//! mark.

/// `o`, `O`, `m`, `M` or `%`: every O-line, `%` line, M98 and M99 holds one.
#[inline(always)]
pub(crate) fn is_mark(b: u8) -> bool {
    matches!(b | 0x20, b'o' | b'm') || b == b'%'
}

/// A line handed on: index, start offset, end offset (its newline, or the
/// end of the file), whether a newline ends it, and whether it is the
/// file's first non-blank line (told here because the raw bytes handed on
/// with a line are cut, and its first non-blank byte may lie past the cut).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Marked {
    pub idx: u32,
    pub start: u64,
    pub end: u64,
    pub terminated: bool,
    pub first_nonblank: bool,
}

/// Scanner state carried from one chunk of a file to the next.
pub(super) struct MarkedLines {
    idx: u32,
    line_start: u64,
    marked: bool,
    /// Still in the leading blank lines (all handed on).
    leading: bool,
    nonblank: bool,
    /// Lines longer than this (with their newline) are handed on.
    long: u64,
}

impl MarkedLines {
    pub(super) fn new(long: usize) -> MarkedLines {
        MarkedLines {
            idx: 0,
            line_start: 0,
            marked: false,
            leading: true,
            nonblank: false,
            long: long as u64,
        }
    }

    /// A scanner starting at the line start `start` of a file whose leading
    /// blank lines lie before it (line indices count from `start`).
    pub(super) fn after_leading(long: usize, start: u64) -> MarkedLines {
        MarkedLines {
            line_start: start,
            leading: false,
            ..MarkedLines::new(long)
        }
    }

    /// Still in the leading blank lines.
    pub(super) fn leading(&self) -> bool {
        self.leading
    }

    /// Start of the line being read (it may continue in the next chunk).
    pub(super) fn line_start(&self) -> u64 {
        self.line_start
    }

    /// Reads the next chunk of the file, which starts at offset `base`.
    pub(super) fn feed(&mut self, chunk: &[u8], base: u64, hit: &mut impl FnMut(Marked)) {
        let mut k = 0;
        // The leading blank lines, a byte at a time (they are all handed on).
        while self.leading && k < chunk.len() {
            let b = chunk[k];
            if b == b'\n' {
                self.end_line(base + k as u64, hit);
            } else {
                self.marked |= is_mark(b);
                self.nonblank |= !b.is_ascii_whitespace();
            }
            k += 1;
        }
        if k < chunk.len() {
            self.feed_lines(&chunk[k..], base + k as u64, hit);
        }
    }

    /// After the leading lines: newlines and marks are found with `memchr`
    /// (vector instructions where the machine has them), so a line costs a
    /// few steps, not one per byte.
    fn feed_lines(&mut self, chunk: &[u8], base: u64, hit: &mut impl FnMut(Marked)) {
        let mut letters = memchr::memchr3_iter(b'o', b'O', b'%', chunk);
        let mut ms = memchr::memchr2_iter(b'm', b'M', chunk);
        let (mut a, mut b) = (letters.next(), ms.next());
        for nl in memchr::memchr_iter(b'\n', chunk) {
            // Marks before this newline belong to the line it ends.
            while a.is_some_and(|m| m < nl) {
                self.marked = true;
                a = letters.next();
            }
            while b.is_some_and(|m| m < nl) {
                self.marked = true;
                b = ms.next();
            }
            self.end_line(base + nl as u64, hit);
        }
        // The line that goes on into the next chunk.
        self.marked |= a.is_some() || b.is_some();
    }

    #[inline(always)]
    fn end_line(&mut self, nl: u64, hit: &mut impl FnMut(Marked)) {
        if self.marked || self.leading || nl - self.line_start + 1 > self.long {
            hit(Marked {
                idx: self.idx,
                start: self.line_start,
                end: nl,
                terminated: true,
                first_nonblank: self.leading && self.nonblank,
            });
        }
        if self.nonblank {
            self.leading = false;
        }
        self.idx += 1;
        self.line_start = nl + 1;
        self.marked = false;
    }

    /// Ends the file at offset `len`: a last line without a newline is
    /// always handed on. Returns the number of lines.
    pub(super) fn finish(&mut self, len: u64, hit: &mut impl FnMut(Marked)) -> u32 {
        if self.line_start < len {
            hit(Marked {
                idx: self.idx,
                start: self.line_start,
                end: len,
                terminated: false,
                first_nonblank: self.leading && self.nonblank,
            });
            self.idx += 1;
        }
        self.idx
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The lines a byte-by-byte reading hands on.
    fn naive(data: &[u8], long: usize) -> (Vec<Marked>, u32) {
        let mut out = Vec::new();
        let mut leading = true;
        let mut start = 0usize;
        let mut idx = 0u32;
        while start < data.len() {
            let (end, terminated) = match data[start..].iter().position(|&b| b == b'\n') {
                Some(i) => (start + i, true),
                None => (data.len(), false),
            };
            let line = &data[start..end];
            let nonblank = line.iter().any(|b| !b.is_ascii_whitespace());
            if !terminated || leading || line.iter().any(|&b| is_mark(b)) || line.len() + 1 > long {
                out.push(Marked {
                    idx,
                    start: start as u64,
                    end: end as u64,
                    terminated,
                    first_nonblank: leading && nonblank,
                });
            }
            if nonblank {
                leading = false;
            }
            idx += 1;
            start = end + 1;
        }
        (out, idx)
    }

    fn fast(data: &[u8], long: usize, chunk: usize) -> (Vec<Marked>, u32) {
        let mut out = Vec::new();
        let mut s = MarkedLines::new(long);
        let mut hit = |m: Marked| out.push(m);
        for (i, c) in data.chunks(chunk.max(1)).enumerate() {
            s.feed(c, (i * chunk.max(1)) as u64, &mut hit);
        }
        let n = s.finish(data.len() as u64, &mut hit);
        (out, n)
    }

    proptest! {
        #[test]
        fn agrees_with_a_byte_by_byte_reading(
            parts in proptest::collection::vec(
                prop_oneof![
                    "[gG0-9. xXyY-]{0,40}",
                    Just("\n".to_string()),
                    "[oOmM%\n \t\r]",
                    "[\u{80}-\u{ff}]{1,3}",
                ],
                0..60,
            ),
            long in prop_oneof![1usize..50, 60usize..140],
            chunk in 1usize..200,
        ) {
            let data = parts.concat().into_bytes();
            prop_assert_eq!(fast(&data, long, chunk), naive(&data, long));
        }
    }

    #[test]
    fn long_plain_files() {
        let mut data = b"\n  \n".to_vec();
        for i in 0..5000 {
            data.extend_from_slice(format!("G1 X{i}.5 Y-{i}\n").as_bytes());
            if i % 777 == 0 {
                data.extend_from_slice(b"o100 if [1]\n");
            }
        }
        for chunk in [64, 1000, 1 << 20] {
            assert_eq!(fast(&data, 253, chunk), naive(&data, 253));
        }
    }
}
