//! Byte tricks on eight bytes at a time in a `u64` (first byte lowest), for
//! the scanners that look at every byte of large programs.

/// `b` in every byte.
pub(crate) const fn splat(b: u8) -> u64 {
    0x0101_0101_0101_0101 * b as u64
}

/// The low seven bits of every byte.
pub(crate) const LO7: u64 = splat(0x7f);

/// 0x80 in every byte of `t` that is zero, nothing elsewhere.
#[inline(always)]
pub(crate) fn zero_bytes(t: u64) -> u64 {
    !(((t & LO7).wrapping_add(LO7)) | t | LO7)
}
