//! Line parser throughput on a deterministic mix of typical CAM lines.
//!
//! `cargo bench --bench parse` prints time per iteration and MB/s (bytes of
//! raw G-code parsed per second).

use divan::counter::BytesCount;
use divan::{Bencher, black_box};
use ngcflat::parse::LineParser;

fn main() {
    divan::main();
}

/// Small deterministic generator (xorshift64*), so runs are comparable.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }

    /// Uniform in [lo, hi).
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * ((self.next() >> 11) as f64 / (1u64 << 53) as f64)
    }
}

/// CAM-style motion lines: mostly G1 X Y (Z) with occasional F, arcs with
/// I J, rapids, comments and N numbers.
fn cam_lines(n: usize) -> Vec<String> {
    let mut r = Rng(0x9E37_79B9_7F4A_7C15);
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        let p = r.range(0.0, 1.0);
        let x = r.range(-500.0, 500.0);
        let y = r.range(-500.0, 500.0);
        let line = if p < 0.05 {
            format!("G0 Z{:.4}", r.range(-10.0, 5.0))
        } else if p < 0.10 {
            format!(
                "G2 X{x:.4} Y{y:.4} I{:.4} J{:.4}",
                r.range(-3.0, 3.0),
                r.range(-3.0, 3.0)
            )
        } else if p < 0.14 {
            format!(
                "G3 X{x:.4} Y{y:.4} I{:.4} J{:.4} F{}",
                r.range(-3.0, 3.0),
                r.range(-3.0, 3.0),
                600 + 300 * (i % 4)
            )
        } else if p < 0.16 {
            format!("(pass {i}: contour at depth {:.3})", r.range(-5.0, 0.0))
        } else if p < 0.18 {
            format!("N{} G1 X{x:.4} Y{y:.4}", i * 10)
        } else if p < 0.45 {
            format!("G1 X{x:.4} Y{y:.4} Z{:.4}", r.range(-10.0, 5.0))
        } else if p < 0.50 {
            format!("G1 X{x:.4} Y{y:.4} F{}", 300 * (1 + i % 5))
        } else if p < 0.80 {
            format!("G1 X{x:.4} Y{y:.4}")
        } else {
            format!("X{x:.4} Y{y:.4}")
        };
        out.push(line);
    }
    out
}

/// Lines with parameters and expressions, as found in hand-written macros.
fn expr_lines(n: usize) -> Vec<String> {
    let pool = [
        "#<depth> = [#<depth> - 0.25]",
        "G1 X[#1 * #<pitch>] Y[#2 * #<pitch>] Z[-0.1 - 0.001 * [#2 MOD 7]]",
        "o100 while [#1 LT #<rows>]",
        "o110 if [[#1 MOD 2] EQ 0]",
        "#2 = [#2 + 1]",
        "G2 X[#5 + COS[#6] * #7] Y[#8 + SIN[#6] * #7] I[-#7] J0",
        "o<pocket> call [10] [20] [#<depth>] [0.5]",
        "(debug, depth=#<depth> pass=#1)",
    ];
    (0..n).map(|i| pool[i % pool.len()].to_string()).collect()
}

fn run(bencher: Bencher, lines: &[String]) {
    let bytes: usize = lines.iter().map(|l| l.len() + 1).sum();
    let mut parser = LineParser::default();
    bencher.counter(BytesCount::new(bytes)).bench_local(|| {
        for l in lines {
            let r = parser.parse(black_box(l.as_bytes()), true);
            black_box(&r);
        }
    });
}

#[divan::bench(sample_count = 30, max_time = 4)]
fn cam_mix_10k_lines(bencher: Bencher) {
    run(bencher, &cam_lines(10_000));
}

#[divan::bench(sample_count = 30, max_time = 3)]
fn expressions_2k_lines(bencher: Bencher) {
    run(bencher, &expr_lines(2_000));
}

/// The most common line on its own.
#[divan::bench(sample_count = 50, max_time = 2)]
fn single_g1_xyz(bencher: Bencher) {
    let mut parser = LineParser::default();
    let line = b"G1 X123.4567 Y-45.6789 Z-1.2500";
    bencher
        .counter(BytesCount::new(line.len() + 1))
        .bench_local(|| black_box(parser.parse(black_box(line), true)));
}
