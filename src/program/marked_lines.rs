//! Finds the lines the O-word index must look at without looking at every
//! line: newline positions and marked bytes (`o`, `O`, `%`, `m`, `M`) are
//! turned into bit masks eight bytes at a time, and only lines holding a
//! mark, overlong lines and the leading blank lines are handed on. Every
//! O-line, `%` line, `M98` and `M99` holds a mark.

use super::swar::{splat, zero_bytes};

/// The high bits of the eight bytes of `m`, as the low eight bits.
#[inline(always)]
fn gather(m: u64) -> u64 {
    ((m >> 7).wrapping_mul(0x0102_0408_1020_4080)) >> 56
}

#[inline(always)]
fn is_mark(b: u8) -> bool {
    matches!(b | 0x20, b'o' | b'm') || b == b'%'
}

/// Newline and mark masks of 64 bytes (bit k is byte k).
#[inline(always)]
fn masks(blk: &[u8; 64]) -> (u64, u64) {
    let mut nl = 0u64;
    let mut mk = 0u64;
    for (j, w) in blk.as_chunks::<8>().0.iter().enumerate() {
        let w = u64::from_le_bytes(*w);
        let folded = w | splat(0x20);
        let n = zero_bytes(w ^ splat(b'\n'));
        let m = zero_bytes(folded ^ splat(b'o'))
            | zero_bytes(folded ^ splat(b'm'))
            | zero_bytes(w ^ splat(b'%'));
        nl |= gather(n) << (j * 8);
        mk |= gather(m) << (j * 8);
    }
    (nl, mk)
}

/// A line handed on: index, start offset, end offset (its newline, or the
/// end of the file), and whether a newline ends it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Marked {
    pub idx: u32,
    pub start: u64,
    pub end: u64,
    pub terminated: bool,
}

/// Scanner state carried from one chunk of a file to the next.
pub struct MarkedLines {
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
    pub fn new(long: usize) -> MarkedLines {
        MarkedLines {
            idx: 0,
            line_start: 0,
            marked: false,
            leading: true,
            nonblank: false,
            long: long as u64,
        }
    }

    /// Start of the line being read (it may continue in the next chunk).
    pub fn line_start(&self) -> u64 {
        self.line_start
    }

    /// Reads the next chunk of the file, which starts at offset `base`.
    pub fn feed(&mut self, chunk: &[u8], base: u64, hit: &mut impl FnMut(Marked)) {
        let mut k = 0;
        while k < chunk.len() {
            if self.leading || chunk.len() - k < 64 {
                let b = chunk[k];
                if b == b'\n' {
                    self.end_line(base + k as u64, hit);
                } else {
                    self.marked |= is_mark(b);
                    self.nonblank |= !b.is_ascii_whitespace();
                }
                k += 1;
                continue;
            }
            let blk: &[u8; 64] = chunk[k..k + 64].try_into().expect("64 bytes");
            let (mut nl, mut mk) = masks(blk);
            let blk_base = base + k as u64;
            if nl == 0 {
                self.marked |= mk != 0;
                k += 64;
                continue;
            }
            let first = nl.trailing_zeros();
            let before = (1u64 << first) - 1;
            if self.long >= 64 && mk & !before == 0 {
                // No mark after the first line end: the lines that start in
                // this block are short and unmarked, so only counted.
                self.marked |= mk & before != 0;
                self.end_line(blk_base + first as u64, hit);
                let rest = nl & (nl - 1);
                if rest != 0 {
                    self.idx += rest.count_ones();
                    self.line_start = blk_base + 64 - rest.leading_zeros() as u64;
                }
                k += 64;
                continue;
            }
            while nl != 0 {
                let t = nl.trailing_zeros();
                let before = (1u64 << t) - 1;
                self.marked |= mk & before != 0;
                mk &= !before;
                self.end_line(blk_base + t as u64, hit);
                nl &= nl - 1;
            }
            self.marked |= mk != 0;
            k += 64;
        }
    }

    #[inline(always)]
    fn end_line(&mut self, nl: u64, hit: &mut impl FnMut(Marked)) {
        if self.marked || self.leading || nl - self.line_start + 1 > self.long {
            hit(Marked {
                idx: self.idx,
                start: self.line_start,
                end: nl,
                terminated: true,
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
    pub fn finish(mut self, len: u64, hit: &mut impl FnMut(Marked)) -> u32 {
        if self.line_start < len {
            hit(Marked {
                idx: self.idx,
                start: self.line_start,
                end: len,
                terminated: false,
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
            if !terminated || leading || line.iter().any(|&b| is_mark(b)) || line.len() + 1 > long {
                out.push(Marked {
                    idx,
                    start: start as u64,
                    end: end as u64,
                    terminated,
                });
            }
            if line.iter().any(|b| !b.is_ascii_whitespace()) {
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

    #[test]
    fn gathers_high_bits() {
        for x in 0..256u64 {
            let m = (0..8)
                .filter(|b| x >> b & 1 == 1)
                .fold(0u64, |m, b| m | 0x80 << (8 * b));
            assert_eq!(gather(m), x);
        }
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
