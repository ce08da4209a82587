//! Number formatting: `ngcflat::emit::write_number` against the standard
//! library's `format!("{}")` (and `write!` into a reused buffer) on the same
//! values in the same run.

use std::io::Write as _;

use divan::counter::ItemsCount;
use divan::{Bencher, black_box};

fn main() {
    divan::main();
}

const N: usize = 10_000;

/// Values like those a flattener prints: 4-decimal CAM coordinates, small
/// integers, and computed values with long shortest round-trip forms
/// (`0.1 * 3` = 0.30000000000000004, trig results).
fn values() -> Vec<f64> {
    let mut v = Vec::with_capacity(N);
    let mut s: u64 = 0x1234_5678_9ABC_DEF1;
    for i in 0..N {
        s = s
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        let u = (s >> 11) as f64 / (1u64 << 53) as f64;
        let x = match i % 4 {
            0 => ((u * 1000.0 - 500.0) * 10_000.0).round() / 10_000.0,
            1 => (i % 2000) as f64,
            2 => (i % 1000) as f64 * 0.05,
            _ => 25.0 * (u * std::f64::consts::TAU).cos(),
        };
        v.push(x);
    }
    v
}

#[divan::bench(sample_count = 50, max_time = 3)]
fn write_number_shortest(bencher: Bencher) {
    let vals = values();
    let mut out = Vec::with_capacity(1 << 20);
    bencher.counter(ItemsCount::new(N)).bench_local(|| {
        out.clear();
        for &v in &vals {
            ngcflat::emit::write_number(&mut out, black_box(v), None);
            out.push(b' ');
        }
        black_box(out.len())
    });
}

#[divan::bench(sample_count = 50, max_time = 3)]
fn write_number_precision_4(bencher: Bencher) {
    let vals = values();
    let mut out = Vec::with_capacity(1 << 20);
    bencher.counter(ItemsCount::new(N)).bench_local(|| {
        out.clear();
        for &v in &vals {
            ngcflat::emit::write_number(&mut out, black_box(v), Some(4));
            out.push(b' ');
        }
        black_box(out.len())
    });
}

/// Baseline: `format!("{}")`, allocating a String per number.
#[divan::bench(sample_count = 50, max_time = 3)]
fn baseline_format_macro(bencher: Bencher) {
    let vals = values();
    let mut out = Vec::with_capacity(1 << 20);
    bencher.counter(ItemsCount::new(N)).bench_local(|| {
        out.clear();
        for &v in &vals {
            let s = format!("{}", black_box(v));
            out.extend_from_slice(s.as_bytes());
            out.push(b' ');
        }
        black_box(out.len())
    });
}

/// Baseline: `write!("{}")` into the reused buffer (no allocation).
#[divan::bench(sample_count = 50, max_time = 3)]
fn baseline_write_macro(bencher: Bencher) {
    let vals = values();
    let mut out = Vec::with_capacity(1 << 20);
    bencher.counter(ItemsCount::new(N)).bench_local(|| {
        out.clear();
        for &v in &vals {
            write!(out, "{} ", black_box(v)).expect("vec write");
        }
        black_box(out.len())
    });
}
