//! A small, fast, non-cryptographic hasher for the maps of the evaluator and
//! the file index (parameter names, labels, line cache). Inputs come from the program being
//! flattened, not from an adversary who gains anything by collisions; the
//! step limit bounds any pathological case.
//!
//! The `rustc-hash` crate (2.1: the same multiply-rotate step plus a final
//! rotation that spreads pointer keys better) was measured in its place
//! with callgrind on release builds and costs slightly more everywhere:
//! the loop benchmark (100 k moves) 482.18 M -> 482.97 M instructions
//! (+0.16 %), the recursion benchmark (436 905 calls) 1 796.6 M ->
//! 1 797.6 M (+0.06 %), a loop over 2 000 interned names 130.89 M ->
//! 131.01 M (+0.09 %). So this hasher stays.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

#[derive(Default, Clone, Copy)]
pub(crate) struct FxHasher {
    hash: u64,
}

const SEED: u64 = 0x51_7c_c1_b7_27_22_0a_95;

impl FxHasher {
    #[inline]
    fn add(&mut self, word: u64) {
        self.hash = (self.hash.rotate_left(5) ^ word).wrapping_mul(SEED);
    }
}

impl Hasher for FxHasher {
    #[inline]
    fn write(&mut self, bytes: &[u8]) {
        let mut chunks = bytes.chunks_exact(8);
        for c in &mut chunks {
            self.add(u64::from_le_bytes(c.try_into().expect("8 bytes")));
        }
        let rest = chunks.remainder();
        if !rest.is_empty() {
            // Byte by byte: a copy of a variable length would call memcpy.
            let w = rest
                .iter()
                .enumerate()
                .fold(0u64, |w, (k, &b)| w | (b as u64) << (8 * k));
            self.add(w);
        }
    }

    #[inline]
    fn write_u8(&mut self, i: u8) {
        self.add(i as u64);
    }

    #[inline]
    fn write_u32(&mut self, i: u32) {
        self.add(i as u64);
    }

    #[inline]
    fn write_u64(&mut self, i: u64) {
        self.add(i);
    }

    #[inline]
    fn write_usize(&mut self, i: usize) {
        self.add(i as u64);
    }

    #[inline]
    fn finish(&self) -> u64 {
        self.hash
    }
}

pub(crate) type FxMap<K, V> = HashMap<K, V, BuildHasherDefault<FxHasher>>;
pub(crate) type FxSet<K> = std::collections::HashSet<K, BuildHasherDefault<FxHasher>>;
