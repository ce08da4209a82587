//! Byte tricks on eight bytes at a time in a `u64` (first byte lowest), for
//! the number reader of the straight-line loop.

/// `b` in every byte.
pub(crate) const fn splat(b: u8) -> u64 {
    0x0101_0101_0101_0101 * b as u64
}

/// The low seven bits of every byte.
pub(crate) const LO7: u64 = splat(0x7f);
