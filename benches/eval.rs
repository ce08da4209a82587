//! Whole-pipeline flattening in memory (output discarded): loop-heavy,
//! recursive and straight programs.

use std::path::PathBuf;

use divan::counter::ItemsCount;
use divan::{Bencher, black_box};
use ngcflat::emit::Destination;
use ngcflat::program::{SearchPath, SourceFile};
use ngcflat::settings::Settings;

fn main() {
    divan::main();
}

/// Nested while loops with an if/else and expressions: `rows * cols` moves.
fn loop_program(rows: u32, cols: u32) -> String {
    format!(
        "G21 G90 G17 G94\nF800\n#<rows> = {rows}\n#<cols> = {cols}\n#<step> = 0.1\n\
         #10 = 0\n\
         o1 while [#10 LT #<rows>]\n\
         \x20 #11 = 0\n\
         \x20 o2 while [#11 LT #<cols>]\n\
         \x20   o3 if [[#10 MOD 2] EQ 1]\n\
         \x20     G1 X[[#<cols> - #11] * #<step>] Y[#10 * #<step>] Z[-0.2 - 0.01 * [#11 MOD 3]]\n\
         \x20   o3 else\n\
         \x20     G1 X[#11 * #<step>] Y[#10 * #<step>] Z[-0.2 - 0.01 * [#11 MOD 4]]\n\
         \x20   o3 endif\n\
         \x20   #11 = [#11 + 1]\n\
         \x20 o2 endwhile\n\
         \x20 #10 = [#10 + 1]\n\
         o1 endwhile\nG0 Z5\nM2\n"
    )
}

/// A 4-ary call tree `depth` levels deep; returns the program and the number
/// of calls.
fn recursion_program(depth: u32) -> (String, usize) {
    let calls: usize = (0..=depth).map(|d| 4usize.pow(d)).sum();
    let text = format!(
        "G21 G90 G17 G94\nF1200\n\
         o<quad> sub\n\
         \x20 G1 X#2 Y#3 Z[#1 * -0.05]\n\
         \x20 o10 if [#1 GT 0]\n\
         \x20   o<quad> call [#1 - 1] [#2 + #4] [#3 + #4] [#4 / 2]\n\
         \x20   o<quad> call [#1 - 1] [#2 - #4] [#3 + #4] [#4 / 2]\n\
         \x20   o<quad> call [#1 - 1] [#2 - #4] [#3 - #4] [#4 / 2]\n\
         \x20   o<quad> call [#1 - 1] [#2 + #4] [#3 - #4] [#4 / 2]\n\
         \x20 o10 endif\n\
         o<quad> endsub\n\
         o<quad> call [{depth}] [0] [0] [64]\nM2\n"
    );
    (text, calls)
}

/// Straight CAM-style lines (no O-words), `n` moves.
fn straight_program(n: usize) -> String {
    let mut s = String::from("G21 G90 G17\nG0 Z5\nF1000\n");
    for i in 0..n {
        let x = (i % 977) as f64 * 0.1234;
        let y = (i % 613) as f64 * 0.4321;
        match i % 10 {
            0 => s.push_str(&format!("G3 X{x:.4} Y{y:.4} I1.5000 J-0.2500\n")),
            1..=3 => s.push_str(&format!("G1 X{x:.4} Y{y:.4} Z-{:.4}\n", x / 100.0)),
            _ => s.push_str(&format!("G1 X{x:.4} Y{y:.4}\n")),
        }
    }
    s.push_str("M2\n");
    s
}

fn flatten_discard(text: &str, settings: &Settings) {
    let src = SourceFile::new(
        PathBuf::from("<bench>"),
        "<bench>".into(),
        text.as_bytes().to_vec(),
    );
    let r = ngcflat::flatten(src, settings, &SearchPath::default(), Destination::Discard);
    black_box(r.expect("bench program flattens"));
}

#[divan::bench(sample_count = 20, max_time = 5)]
fn loops_20k_moves(bencher: Bencher) {
    let text = loop_program(100, 200);
    let settings = Settings::default();
    bencher
        .counter(ItemsCount::new(20_000usize))
        .bench_local(|| flatten_discard(&text, &settings));
}

#[divan::bench(sample_count = 20, max_time = 5)]
fn recursion_depth5(bencher: Bencher) {
    let (text, calls) = recursion_program(5);
    let settings = Settings::default();
    bencher
        .counter(ItemsCount::new(calls))
        .bench_local(|| flatten_discard(&text, &settings));
}

#[divan::bench(sample_count = 20, max_time = 5)]
fn straight_20k_lines(bencher: Bencher) {
    let text = straight_program(20_000);
    let settings = Settings::default();
    bencher
        .counter(divan::counter::BytesCount::new(text.len()))
        .bench_local(|| flatten_discard(&text, &settings));
}

/// The public string API, which also writes and reads back the output file.
#[divan::bench(sample_count = 20, max_time = 5)]
fn loops_5k_moves_flatten_str(bencher: Bencher) {
    let text = loop_program(50, 100);
    let settings = Settings::default();
    bencher
        .counter(ItemsCount::new(5_000usize))
        .bench_local(|| black_box(ngcflat::flatten_str(&text, &settings).expect("flattens")));
}
