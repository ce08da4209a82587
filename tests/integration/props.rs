//! Property tests: arbitrary input never panics; flattening is idempotent;
//! the number formatter round-trips. Robustness table: hostile inputs (huge
//! lines, deep nesting, many labels, runaway loops and recursion, bad bytes)
//! end with a clear result within bounded time.

use std::sync::mpsc;
use std::time::{Duration, Instant};

use proptest::prelude::*;

use ngcflat::diag::{Error, MessageFormat, render};
use ngcflat::emit::{Destination, number_string};
use ngcflat::parse::LineParser;
use ngcflat::program::{SearchPath, SourceFile};
use ngcflat::settings::Settings;

/// Small limits, so that runaway programs stop quickly.
fn small_limits() -> Settings {
    Settings {
        max_steps: 10_000,
        max_output_lines: 10_000,
        ..Settings::default()
    }
}

/// Flattens raw bytes (not necessarily UTF-8) and throws the output away. The
/// source is named like stdin so that no folder is searched for subroutines.
fn flatten_bytes(data: Vec<u8>, settings: &Settings) -> Result<(), Error> {
    let src = SourceFile::new("<stdin>".into(), "<stdin>".into(), data);
    ngcflat::flatten(src, settings, &SearchPath::default(), Destination::Discard).map(|_| ())
}

/// Renders a result in every format (rendering must not panic either).
fn render_all(r: &Result<(), Error>) {
    if let Err(e) = r {
        for f in [
            MessageFormat::Human,
            MessageFormat::Short,
            MessageFormat::Json,
            MessageFormat::Github,
        ] {
            let _ = render(e, f, false);
        }
    }
}

/// Pieces of G-code for the structured never-panic property.
const TOKENS: &[&str] = &[
    "G0",
    "G1",
    "G2",
    "G3",
    "G4",
    "G10",
    "L2",
    "L20",
    "G17",
    "G18",
    "G20",
    "G21",
    "G28",
    "G38.2",
    "G40",
    "G41",
    "G43",
    "G53",
    "G54",
    "G64",
    "G81",
    "G90",
    "G91",
    "G92",
    "G93",
    "M2",
    "M3",
    "M6",
    "M30",
    "M66",
    "M70",
    "M72",
    "M98",
    "M99",
    "X",
    "Y",
    "Z",
    "I",
    "J",
    "K",
    "R",
    "P",
    "Q",
    "L",
    "F",
    "S",
    "T",
    "N10",
    "E",
    "@",
    "^",
    "$",
    "/",
    "%",
    "1",
    "0",
    "-1",
    ".5",
    "1e9",
    "99999999999",
    "5400",
    "5601",
    "5602",
    "#",
    "#1",
    "#5063",
    "#<a>",
    "#<_value>",
    "#<_x>",
    "#<_hal[x]>",
    "#<_ini[a]b>",
    "#<",
    ">",
    "##1",
    "=",
    "[",
    "]",
    "[1]",
    "[0]",
    "**",
    "*",
    "/",
    "+",
    "-",
    "MOD",
    "EQ",
    "NE",
    "GT",
    "LT",
    "AND",
    "OR",
    "XOR",
    "ABS",
    "ACOS",
    "ASIN",
    "SQRT",
    "LN",
    "EXP",
    "ROUND",
    "FIX",
    "FUP",
    "ATAN[1]/[0]",
    "EXISTS[#<a>]",
    "o100",
    "o<s>",
    "o#1",
    "o[1]",
    "sub",
    "endsub",
    "call",
    "do",
    "while",
    "endwhile",
    "repeat",
    "endrepeat",
    "if",
    "elseif",
    "else",
    "endif",
    "break",
    "continue",
    "return",
    "(",
    ")",
    ";",
    "(debug,",
    "(print,",
    "(log,",
    "(logopen,x)",
    "(abort,",
    "(msg,",
    "%d",
    "%lf",
    " ",
    "\t",
    "\r",
];

fn token_line() -> impl Strategy<Value = String> {
    proptest::collection::vec((proptest::sample::select(TOKENS), any::<bool>()), 0..12).prop_map(
        |toks| {
            let mut s = String::new();
            for (t, space) in toks {
                s.push_str(t);
                if space {
                    s.push(' ');
                }
            }
            s
        },
    )
}

// ---------------------------------------------------------------- simple valid programs

const VARS: usize = 3;

#[derive(Debug, Clone)]
enum Expr {
    Num(i32, u8),
    Var(usize),
    Bin(&'static str, Box<Expr>, Box<Expr>),
    /// `[a / [ABS[b] + 1]]`: never divides by zero.
    SafeDiv(Box<Expr>, Box<Expr>),
    Fn(&'static str, Box<Expr>),
}

impl Expr {
    fn text(&self) -> String {
        match self {
            Expr::Num(n, d) => {
                if *d == 0 {
                    n.to_string()
                } else {
                    format!("{n}.{d}")
                }
            }
            Expr::Var(v) => format!("#<v{v}>"),
            Expr::Bin(op, a, b) => format!("[{} {op} {}]", a.text(), b.text()),
            Expr::SafeDiv(a, b) => format!("[{} / [ABS[{}] + 1]]", a.text(), b.text()),
            Expr::Fn(f, a) => format!("{f}[{}]", a.text()),
        }
    }
}

fn expr() -> impl Strategy<Value = Expr> {
    let leaf = prop_oneof![
        (-50i32..50, 0u8..10).prop_map(|(n, d)| Expr::Num(n, d)),
        (0..VARS).prop_map(Expr::Var),
    ];
    leaf.prop_recursive(2, 8, 2, |inner| {
        prop_oneof![
            (
                proptest::sample::select(&["+", "-", "*", "MOD", "GT", "AND"][..]),
                inner.clone(),
                inner.clone()
            )
                .prop_map(|(op, a, b)| Expr::Bin(op, Box::new(a), Box::new(b))),
            (inner.clone(), inner.clone())
                .prop_map(|(a, b)| Expr::SafeDiv(Box::new(a), Box::new(b))),
            (
                proptest::sample::select(&["ABS", "ROUND", "FIX", "FUP", "SIN", "COS"][..]),
                inner
            )
                .prop_map(|(f, a)| Expr::Fn(f, Box::new(a))),
        ]
    })
}

#[derive(Debug, Clone)]
enum Stmt {
    Assign(usize, Expr),
    Move(bool, Expr, Expr),
    Comment(String),
    Debug(usize),
    If(Expr, Vec<Stmt>, Vec<Stmt>),
    While(u8, Vec<Stmt>),
    Repeat(u8, Vec<Stmt>),
}

fn stmt() -> impl Strategy<Value = Stmt> {
    let leaf = prop_oneof![
        (0..VARS, expr()).prop_map(|(v, e)| Stmt::Assign(v, e)),
        (any::<bool>(), expr(), expr()).prop_map(|(g0, x, y)| Stmt::Move(g0, x, y)),
        "[a-zA-Z0-9 ,.]{0,20}".prop_map(Stmt::Comment),
        (0..VARS).prop_map(Stmt::Debug),
    ];
    leaf.prop_recursive(3, 24, 4, |inner| {
        let body = proptest::collection::vec(inner, 0..4);
        prop_oneof![
            (expr(), body.clone(), body.clone()).prop_map(|(c, t, e)| Stmt::If(c, t, e)),
            (0u8..4, body.clone()).prop_map(|(n, b)| Stmt::While(n, b)),
            (0u8..4, body).prop_map(|(n, b)| Stmt::Repeat(n, b)),
        ]
    })
}

fn render_stmts(stmts: &[Stmt], label: &mut u32, out: &mut String) {
    for s in stmts {
        match s {
            Stmt::Assign(v, e) => out.push_str(&format!("#<v{v}> = {}\n", e.text())),
            Stmt::Move(g0, x, y) => out.push_str(&format!(
                "G{} X{} Y{}\n",
                if *g0 { 0 } else { 1 },
                x.text(),
                y.text()
            )),
            Stmt::Comment(c) => out.push_str(&format!("({c})\n")),
            Stmt::Debug(v) => out.push_str(&format!("(debug, v is #<v{v}>)\n")),
            Stmt::If(c, then, els) => {
                *label += 1;
                let l = *label;
                out.push_str(&format!("o{l} if [{}]\n", c.text()));
                render_stmts(then, label, out);
                if !els.is_empty() {
                    out.push_str(&format!("o{l} else\n"));
                    render_stmts(els, label, out);
                }
                out.push_str(&format!("o{l} endif\n"));
            }
            Stmt::While(n, body) => {
                *label += 1;
                let l = *label;
                out.push_str(&format!("#<w{l}> = 0\no{l} while [#<w{l}> LT {n}]\n"));
                render_stmts(body, label, out);
                out.push_str(&format!("#<w{l}> = [#<w{l}> + 1]\no{l} endwhile\n"));
            }
            Stmt::Repeat(n, body) => {
                *label += 1;
                let l = *label;
                out.push_str(&format!("o{l} repeat [{n}]\n"));
                render_stmts(body, label, out);
                out.push_str(&format!("o{l} endrepeat\n"));
            }
        }
    }
}

fn program() -> impl Strategy<Value = String> {
    proptest::collection::vec(stmt(), 0..8).prop_map(|stmts| {
        let mut out = String::from("G21 G90 F300\n");
        for v in 0..VARS {
            out.push_str(&format!("#<v{v}> = {v}\n"));
        }
        render_stmts(&stmts, &mut 100, &mut out);
        out.push_str("M2\n");
        out
    })
}

proptest! {
    #[test]
    fn numbers_round_trip(v in proptest::num::f64::NORMAL | proptest::num::f64::SUBNORMAL | proptest::num::f64::ZERO) {
        let s = number_string(v, None);
        prop_assert!(!s.contains(['e', 'E', 'i', 'N']), "{s}");
        prop_assert!(s != "-0");
        let back: f64 = s.parse().unwrap();
        prop_assert_eq!(back, if v == 0.0 { 0.0 } else { v });
    }

    #[test]
    fn fixed_precision_matches_format(v in -1.0e9f64..1.0e9, p in 0u8..8) {
        let s = number_string(v, Some(p));
        let want: f64 = format!("{v:.prec$}", prec = p as usize).parse().unwrap();
        let got: f64 = s.parse().unwrap();
        prop_assert!((got - want).abs() <= 10f64.powi(-(p as i32)) * 1.0001, "{v} {p}: {s} vs {want}");
    }

    #[test]
    fn arbitrary_bytes_never_panic(data in proptest::collection::vec(any::<u8>(), 0..400)) {
        let text = String::from_utf8_lossy(&data);
        let _ = ngcflat::flatten_str(&text, &small_limits());
        // The same bytes unmodified (invalid UTF-8 included), line by line
        // and as a program.
        let mut parser = LineParser::default();
        for line in data.split(|&b| b == b'\n') {
            let _ = parser.parse(line, true);
            let _ = parser.parse(line, false);
        }
        render_all(&flatten_bytes(data, &small_limits()));
    }

    #[test]
    fn token_lines_never_panic(lines in proptest::collection::vec(token_line(), 0..10)) {
        let mut parser = LineParser::default();
        for line in &lines {
            let _ = parser.parse(line.as_bytes(), true);
        }
        let text = lines.join("\n");
        let settings = Settings { zero_start: true, ..small_limits() };
        render_all(&flatten_bytes(text.clone().into_bytes(), &settings));
        render_all(&flatten_bytes(text.into_bytes(), &small_limits()));
    }

}

proptest! {
    // Each case flattens twice through temporary files: fewer cases keep the
    // suite fast.
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn flattening_is_idempotent(prog in program()) {
        let settings = small_limits();
        // Programs that go wrong (an over-long line, a value too large to
        // print) are not what this property is about.
        if let Ok(once) = ngcflat::flatten_str(&prog, &settings) {
            let twice = ngcflat::flatten_str(&once, &settings);
            prop_assert!(twice.is_ok(), "output of\n{prog}\nis refused: {twice:?}\noutput:\n{once}");
            let twice = twice.unwrap();
            prop_assert_eq!(&twice, &once, "program:\n{}", prog);
        }
    }
}

/// Simple valid programs flatten in the vast majority of cases, so that the
/// idempotence property tests something.
#[test]
fn generated_programs_mostly_flatten() {
    use proptest::strategy::ValueTree;
    use proptest::test_runner::TestRunner;
    let mut runner = TestRunner::deterministic();
    let strategy = program();
    let mut ok = 0;
    let mut failures = Vec::new();
    for _ in 0..40 {
        let prog = strategy.new_tree(&mut runner).unwrap().current();
        match ngcflat::flatten_str(&prog, &small_limits()) {
            Ok(_) => ok += 1,
            Err(e) => failures.push(format!("{}\n{prog}", e.message())),
        }
    }
    assert!(ok >= 36, "only {ok} of 40 flattened; e.g.\n{}", failures[0]);
}

// ---------------------------------------------------------------- robustness table

#[derive(Debug, Clone, Copy, PartialEq)]
enum Want {
    Ok,
    Err,
    /// Err with this diagnostic code.
    Code(&'static str),
}

fn repeat_lines(n: usize, f: impl Fn(usize) -> String) -> Vec<u8> {
    let mut s = String::new();
    for i in 0..n {
        s.push_str(&f(i));
    }
    s.into_bytes()
}

/// Deterministic pseudo-random bytes.
fn noise(n: usize, seed: u64) -> Vec<u8> {
    let mut x = seed;
    (0..n)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x as u8
        })
        .collect()
}

type Input = fn() -> Vec<u8>;

/// (name, input, max_steps, expected). Each case must finish in well under
/// `CASE_TIMEOUT` and must not panic.
#[rustfmt::skip]
const CASES: &[(&str, Input, u64, Want)] = &[
    ("empty input", || Vec::new(), 10_000, Want::Code("E0319")),
    ("only blanks and newlines", || b"\n \t\r\n\n".to_vec(), 10_000, Want::Code("E0319")),
    ("only percent", || b"%\n".to_vec(), 10_000, Want::Code("E0318")),
    ("percent-delimited empty program", || b"%\n%\n".to_vec(), 10_000, Want::Ok),
    ("1 MB single line", || [b"G1 X".as_slice(), &vec![b'1'; 1 << 20]].concat(), 10_000, Want::Code("E0001")),
    ("1 MB comment line", || [b"(".as_slice(), &vec![b'a'; 1 << 20], b")\nM2\n"].concat(), 10_000, Want::Code("E0001")),
    ("1 MB line, no newline at all", || vec![b'G'; 1 << 20], 10_000, Want::Code("E0001")),
    ("100 000 empty lines", || vec![b'\n'; 100_000], 10_000, Want::Code("E0319")),
    ("10 000-deep brackets", || [b"#1 = ".as_slice(), &vec![b'['; 10_000], b"1", &vec![b']'; 10_000], b"\nM2\n"].concat(), 10_000, Want::Code("E0001")),
    ("10 000 unclosed brackets", || [b"G1 X".as_slice(), &vec![b'['; 10_000]].concat(), 10_000, Want::Code("E0001")),
    ("deepest brackets that fit a line", || [b"#1=".as_slice(), &[b'['; 120], b"1", &[b']'; 120], b"\nM2\n"].concat(), 10_000, Want::Ok),
    ("deep unary minus chain", || [b"#1=".as_slice(), &vec![b'-'; 240], b"1\nM2\n"].concat(), 10_000, Want::Ok),
    ("deep function nesting", || [b"#1=".as_slice(), &b"abs[".repeat(40), b"1", &[b']'; 40], b"\nM2\n"].concat(), 10_000, Want::Ok),
    ("deep parameter indirection", || [b"#1=1\n#2=".as_slice(), &vec![b'#'; 240], b"1\nM2\n"].concat(), 10_000, Want::Ok),
    ("2 000 distinct if/endif labels", || [repeat_lines(2_000, |i| format!("o{i} if [0]\no{i} endif\n")), b"M2\n".to_vec()].concat(), 10_000_000, Want::Ok),
    ("2 000 distinct sub definitions and calls", || [repeat_lines(2_000, |i| format!("o{i} sub\no{i} endsub\no{i} call\n")), b"M2\n".to_vec()].concat(), 10_000_000, Want::Ok),
    ("2 000-deep nested ifs", || [repeat_lines(2_000, |i| format!("o{i} if [1]\n")), repeat_lines(2_000, |i| format!("o{} endif\n", 1_999 - i)), b"M2\n".to_vec()].concat(), 10_000_000, Want::Ok),
    ("2 000-deep nested repeats", || [repeat_lines(2_000, |i| format!("o{i} repeat [1]\n")), repeat_lines(2_000, |i| format!("o{} endrepeat\n", 1_999 - i)), b"M2\n".to_vec()].concat(), 10_000_000, Want::Ok),
    ("2 000 named parameters", || [repeat_lines(2_000, |i| format!("#<p{i}> = {i}\n")), b"M2\n".to_vec()].concat(), 10_000_000, Want::Ok),
    // Straight code is not counted by the step limit (only O-lines are).
    ("20 000 straight lines pass a 10 000 step limit", || repeat_lines(20_000, |i| format!("#<p{i}> = {i}\n")), 10_000, Want::Code("E0318")),
    ("repeat [1e9] (an E word, not an exponent)", || b"o1 repeat [1e9]\nG1 X1\no1 endrepeat\nM2\n".to_vec(), 10_000, Want::Err),
    ("repeat a billion times", || b"o1 repeat [1000000000]\no1 endrepeat\nM2\n".to_vec(), 10_000, Want::Code("E0402")),
    ("repeat a billion times, with output", || b"o1 repeat [1000000000]\nG1 X1 F100\no1 endrepeat\nM2\n".to_vec(), 10_000_000, Want::Code("E0403")),
    ("repeat 1e300 times", || [b"o1 repeat [1".as_slice(), &vec![b'0'; 240], b"]\no1 endrepeat\nM2\n"].concat(), 10_000, Want::Err),
    ("infinite while [1]", || b"o1 while [1]\no1 endwhile\nM2\n".to_vec(), 10_000, Want::Code("E0402")),
    ("infinite do-while", || b"o1 do\no1 while [1]\nM2\n".to_vec(), 10_000, Want::Code("E0402")),
    ("infinite while with a continue", || b"o1 while [1]\no1 continue\no1 endwhile\nM2\n".to_vec(), 10_000, Want::Code("E0402")),
    ("runaway recursion", || b"o<r> sub\no<r> call\no<r> endsub\no<r> call\nM2\n".to_vec(), 10_000, Want::Err),
    ("runaway recursion through numbered subs", || b"o100 sub\no100 call\no100 endsub\no100 call\nM2\n".to_vec(), 10_000, Want::Err),
    ("runaway M98 recursion", || b"M98 P100\nM30\nO100\nM98 P100\nM99\n".to_vec(), 10_000, Want::Err),
    ("mutual recursion", || b"o1 sub\no2 call\no1 endsub\no2 sub\no1 call\no2 endsub\no1 call\nM2\n".to_vec(), 10_000, Want::Err),
    ("call of an unknown file sub", || b"o<no_such_sub_file> call\nM2\n".to_vec(), 10_000, Want::Err),
    ("call with a path-like name", || b"o<../../etc/passwd> call\nM2\n".to_vec(), 10_000, Want::Err),
    // Regression guard for fuzz.md F3: comment bytes were refused as being
    // "outside a comment".
    ("invalid UTF-8 in a comment", || b"(\xff\xfe\xc3)\nG1 X1 F100\nM2\n".to_vec(), 10_000, Want::Ok),
    ("invalid UTF-8 in a debug comment", || b"#1=2\n(debug,\xff #1 \xc3)\nM2\n".to_vec(), 10_000, Want::Ok),
    ("invalid UTF-8 in a named parameter", || b"#<\xff\xfe>=1\nM2\n".to_vec(), 10_000, Want::Err),
    ("invalid UTF-8 outside comments", || b"G1 X\xff1\nM2\n".to_vec(), 10_000, Want::Err),
    ("truncated UTF-8 at end of file", || b"G1 X1 (\xe2\x82".to_vec(), 10_000, Want::Err),
    ("NUL bytes", || b"G1\0X1\nM2\n".to_vec(), 10_000, Want::Err),
    ("NUL in a comment", || b"(a\0b)\nM2\n".to_vec(), 10_000, Want::Ok),
    ("CR-only line endings", || b"G0 X1\rG1 Y2\rM2\r".to_vec(), 10_000, Want::Err),
    ("CR-only line endings, 1 000 lines", || repeat_lines(1_000, |i| format!("G1 X{i}\r")), 10_000, Want::Code("E0001")),
    ("CRLF line endings", || b"G0 X1\r\nG1 Y2 F100\r\nM2\r\n".to_vec(), 10_000, Want::Ok),
    ("64 KB of binary noise", || noise(1 << 16, 0x9e37_79b9_7f4a_7c15), 10_000, Want::Err),
    ("64 KB of short noise lines", || noise(1 << 16, 7).chunks(40).flat_map(|c| [c, b"\n"].concat()).collect(), 10_000, Want::Err),
    ("240-digit number", || [b"G1 F100 X".as_slice(), &vec![b'9'; 240], b"\nM2\n"].concat(), 10_000, Want::Ok),
    ("number too long to print", || b"#1 = [10 ** 300]\nG1 F100 X#1\nM2\n".to_vec(), 10_000, Want::Err),
    ("overflow to infinity", || b"#1 = [10 ** 400]\nG1 X#1\nM2\n".to_vec(), 10_000, Want::Err),
    ("NaN from sqrt of negative", || b"G1 X[SQRT[-1]]\nM2\n".to_vec(), 10_000, Want::Err),
    ("division by zero", || b"G1 X[1/0]\nM2\n".to_vec(), 10_000, Want::Err),
    ("parameter number out of range", || b"#99999999999999999999 = 1\nM2\n".to_vec(), 10_000, Want::Err),
    ("negative parameter number", || b"#-1 = 1\nM2\n".to_vec(), 10_000, Want::Err),
    ("unclosed named parameter", || b"#<abc = 1\nM2\n".to_vec(), 10_000, Want::Err),
    ("unclosed comment", || b"G1 X1 (abc\nM2\n".to_vec(), 10_000, Want::Err),
    ("nested comment", || b"G1 X1 (a (b) c)\nM2\n".to_vec(), 10_000, Want::Err),
    ("endsub without sub", || b"o1 endsub\nM2\n".to_vec(), 10_000, Want::Err),
    ("endwhile without while", || b"o1 endwhile\nM2\n".to_vec(), 10_000, Want::Err),
    ("dynamic label loop", || b"#1=1\no#1 while [1]\no#1 endwhile\nM2\n".to_vec(), 10_000, Want::Err),
    ("abort comment", || b"(abort, stop here)\nM2\n".to_vec(), 10_000, Want::Err),
    // Last: a case that times out leaves its thread running, which would
    // slow the cases after it. Quadratic index building took minutes here.
    // Regression guard for fuzz.md F1: quadratic sub-definition scan.
    ("20 000 subs without endsub", || repeat_lines(20_000, |i| format!("o{i} sub\n")), 10_000, Want::Err),
    // Regression guards for fuzz.md F2: quadratic loop-body scan.
    ("30 000 whiles with one label, no endwhile", || repeat_lines(30_000, |_| "o1 while [0]\n".to_string()), 10_000, Want::Err),
    ("50 000 dos with one label", || repeat_lines(50_000, |_| "o1 do\n".to_string()), 10_000, Want::Err),
    ("30 000 repeats with one label, one endrepeat", || [repeat_lines(30_000, |_| "o1 repeat [0]\n".to_string()), b"o1 endrepeat\nM2\n".to_vec()].concat(), 10_000, Want::Err),
];

/// Generous for a loaded CI machine, yet well below what the quadratic index
/// building of fuzz.md F1/F2 took on the last cases (minutes in a debug
/// build, 15–40 s in a release build).
const CASE_TIMEOUT: Duration = Duration::from_secs(if cfg!(debug_assertions) { 30 } else { 10 });

fn outcome(r: &Result<(), Error>) -> String {
    match r {
        Ok(()) => "Ok".to_string(),
        Err(e) => format!("Err {}: {}", e.code(), e.message()),
    }
}

#[test]
fn hostile_inputs_end_cleanly() {
    let mut failures = Vec::new();
    for &(name, input, max_steps, want) in CASES {
        let (tx, rx) = mpsc::channel();
        let started = Instant::now();
        // A thread of its own: a hang is reported as such instead of stalling
        // the suite, and the (smaller) stack of a spawned thread must suffice.
        std::thread::Builder::new()
            .name(name.to_string())
            .spawn(move || {
                let settings = Settings {
                    max_steps,
                    max_output_lines: 10_000,
                    ..Settings::default()
                };
                let r = flatten_bytes(input(), &settings);
                render_all(&r);
                let _ = tx.send(r);
            })
            .expect("spawn");
        let r = match rx.recv_timeout(CASE_TIMEOUT) {
            Ok(r) => r,
            Err(mpsc::RecvTimeoutError::Timeout) => {
                failures.push(format!("{name}: no result after {CASE_TIMEOUT:?} (hang)"));
                continue;
            }
            Err(mpsc::RecvTimeoutError::Disconnected) => {
                failures.push(format!("{name}: panicked"));
                continue;
            }
        };
        let elapsed = started.elapsed();
        let good = match (want, &r) {
            (Want::Ok, Ok(())) | (Want::Err, Err(_)) => true,
            (Want::Code(c), Err(e)) => e.code() == c,
            _ => false,
        };
        if !good {
            failures.push(format!("{name}: want {want:?}, got {}", outcome(&r)));
        }
        if std::env::var_os("NGCFLAT_PRINT_CASES").is_some() {
            eprintln!("{elapsed:>10.2?}  {name}: {}", outcome(&r));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The full-size version of the label case above (fuzz.md F5: about 30 s in
/// a release build): `cargo test --release -- --ignored a_million_labels`.
#[test]
#[ignore]
fn a_million_labels() {
    let data = [
        repeat_lines(1_000_000, |i| format!("o{i} if [0]\no{i} endif\n")),
        b"M2\n".to_vec(),
    ]
    .concat();
    let settings = Settings {
        max_steps: 100_000_000,
        ..small_limits()
    };
    assert!(flatten_bytes(data, &settings).is_ok());
}

/// A line of the kind the straight-line loop reads (mostly valid), a line
/// that changes a mode it depends on, or a near miss that must take the
/// general path.
fn plain_line() -> impl Strategy<Value = String> {
    let num = (-40i32..40, 0u32..10_000, 0usize..6).prop_map(|(a, f, d)| match d {
        0 => format!("{a}"),
        1 => format!("{a}."),
        _ => format!("{a}.{:0width$}", f % 10u32.pow(d as u32 - 1), width = d - 1),
    });
    let motion = prop_oneof![
        6 => Just(""), 6 => Just("G1"), 4 => Just("G0"), 1 => Just("G2"), 1 => Just("G3"),
        1 => Just("g01"), 1 => Just("G00"), 1 => Just("G1.0"),
    ];
    let axes = proptest::sample::subsequence(vec!["X", "Y", "Z", "A", "x", "z"], 0..=4);
    let axes = (axes, proptest::collection::vec(num.clone(), 4)).prop_map(|(ls, ns)| {
        let mut seen = String::new();
        let mut out = Vec::new();
        for (l, n) in ls.iter().zip(ns) {
            let up = l.to_ascii_uppercase();
            if !seen.contains(&up) {
                seen.push_str(&up);
                out.push(format!("{l}{n}"));
            }
        }
        out
    });
    let arc = prop_oneof![
        1 => Just(Vec::new()),
        6 => Just(vec!["R100".to_string()]),
        1 => (num.clone(), num.clone()).prop_map(|(i, j)| vec![format!("I{i}"), format!("J{j}")]),
        1 => num.clone().prop_map(|i| vec![format!("i{i}")]),
        1 => (num.clone(), num.clone()).prop_map(|(i, j)| vec![format!("I{i}"), format!("j{j}"), "P1".into()]),
    ];
    let feed = prop_oneof![
        3 => Just(String::new()),
        8 => (1u32..3000).prop_map(|f| format!("F{f}")),
        1 => Just("F0".to_string()),
    ];
    let speed = prop_oneof![
        4 => Just(String::new()),
        1 => (0u32..20000).prop_map(|s| format!("S{s}")),
    ];
    let number = prop_oneof![
        4 => Just(String::new()),
        2 => (1u32..99_999).prop_map(|n| format!("N{n}")),
        1 => (100_000u32..200_000).prop_map(|n| format!("N{n}")),
    ];
    let blank = prop_oneof![4 => Just(" "), 2 => Just(""), 1 => Just("  "), 1 => Just("\t")];
    let ending = prop_oneof![8 => Just(""), 1 => Just(" "), 1 => Just("\r"), 1 => Just(" \t\r")];
    let line = (motion, axes, arc, feed, speed, any::<bool>())
        .prop_flat_map(|(m, axes, arc, f, s, shuffle)| {
            let mut ws: Vec<String> = vec![m.to_string()];
            ws.extend(axes);
            if m.starts_with("G2") || m.starts_with("G3") {
                ws.extend(arc);
            }
            ws.push(f);
            ws.push(s);
            ws.retain(|w| !w.is_empty());
            let n = ws.len();
            let ws = Just(ws);
            if shuffle {
                ws.prop_shuffle().boxed()
            } else {
                ws.boxed()
            }
            .prop_map(move |ws| (ws, n))
        })
        .prop_flat_map(move |(ws, n)| (Just(ws), proptest::collection::vec(blank.clone(), n)))
        .prop_map(|(ws, bs)| {
            ws.iter()
                .zip(bs)
                .map(|(w, b)| format!("{w}{b}"))
                .collect::<String>()
        });
    prop_oneof![
        40 => (number, line, ending).prop_map(|(n, w, e)| {
            let sep = if n.is_empty() { "" } else { " " };
            format!("{n}{sep}{}{e}", w.trim_end())
        }),
        4 => prop_oneof![
            Just("G91"), Just("G90"), Just("G20"), Just("G21"), Just("G18"), Just("G17"),
            Just("G93"), Just("G94"), Just("G41 D0"), Just("G40"), Just("G10 L2 P1 R30"),
            Just("G10 L2 P1 X1"), Just("G92 X3"), Just("G55"), Just("G54"), Just("G80"),
            Just("M3 S100"), Just(""), Just("G2.5"), Just("G4 P0"),
            // Comments alone, which a target drops.
            Just("(note)"), Just("(z at -1.5, pass 2)  "),
            // Words the loop reads but leaves to the block checks, with a
            // comment the plain-line scanner does not take.
            Just("G4 P0 (wait)"), Just("G17 (xy plane)"), Just("G92.1 (cancel)"),
            Just("G2 X1 Y1 R100 (round)"), Just("G1 F0 (zero feed)"), Just("G90 (back)"),
        ].prop_map(String::from),
        1 => prop_oneof![
            Just("G1 X1 (c)"), Just(" G1 X1"), Just("G1 X1 0"), Just("G1 X1 X2"), Just("#1 = 2"),
            Just("G1 X#1"), Just("G1 X[#1 + 1] Y2"), Just("G0 X[#1] F[#1 * 100]"),
            Just("G2 X[#1] Y1 R[#1 + 5]"), Just("G91 G1 X[1]"), Just("G1 X[-1] F[0]"),
            Just("G3 X[2] I[#1] J0"), Just("G1 X[1] A[2] S[-1]"), Just("o1 if [1]"), Just("o1 endif"), Just("F-1"), Just("S-2"),
            Just("X1.1234567890123456"), Just("X-.5 Y+2"), Just("G1 K1"), Just("G1 I1"),
            Just("(segment 3, depth -1.5)"), Just("G0 X1 ( note ) "), Just("G1 X2 (msg, m)"),
            Just("(debug, #5420)"), Just("N5 (c)"), Just("G1 X1 (a (b))"), Just("(c) G1"),
            // Numbers a target writes shortened, or not as written at all.
            Just("G1 X-0.000 Y1.50"), Just("G1 X1.5000 Y-2.10 F300.0"), Just("X0.0 Y-0.10"),
            Just("G0 X1.23456789 Y2"), Just("G1 X+1.0"), Just("G1 X01.5"), Just("G1 X.50"),
            Just("G2 X1.000 Y0 I0.50 J0"), Just("G3 X0 Y1.0 I-1.00 J0.0"), Just("G1 X1 F1.0"),
            Just("G1 X12345678.9"), Just("G1 X1.25 Y2.5 Z-3.75 F1200 "),
        ].prop_map(String::from),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// The straight-line loop and the line-by-line path give the same
    /// output, the same state (read back at the end) and the same errors.
    #[test]
    fn straight_line_loop_matches_line_by_line(
        lines in proptest::collection::vec(plain_line(), 0..24),
        zero_start in any::<bool>(),
    ) {
        let mut prog = format!("F500\n{}", lines.join("\n"));
        prog.push_str(
            "\n(debug, #5420 #5421 #5422 #5423 #<_feed> #<_rpm> #<_motion_mode> #<_plane>)\nM2\n",
        );
        let on = Settings { zero_start, ..small_limits() };
        let off = Settings { plain_runs: false, ..on.clone() };
        let show = |r: Result<String, Error>| match r {
            Ok(s) => s,
            Err(e) => format!("error: {}", render(&e, MessageFormat::Short, false)),
        };
        // Tiny chunks: runs of a few lines already read ahead on a second
        // thread.
        let ahead = Settings { scan_ahead: 8, ..on.clone() };
        let fast = show(ngcflat::flatten_str(&prog, &on));
        let slow = show(ngcflat::flatten_str(&prog, &off));
        let split = show(ngcflat::flatten_str(&prog, &ahead));
        prop_assert_eq!(&fast, &slow, "program:\n{}", prog);
        prop_assert_eq!(&split, &slow, "program:\n{}", prog);
        // For a target the lines read ahead arrive decoded (one reading of
        // each line for its record and its block): the same output and
        // diagnostics as lines decoded one at a time.
        let grbl = |s: &Settings| flatten_for_target(&prog, s, "grbl", false);
        let slow = grbl(&off);
        prop_assert_eq!(&grbl(&on), &slow, "program:\n{}", prog);
        prop_assert_eq!(&grbl(&ahead), &slow, "program:\n{}", prog);
    }
}

/// Lines of moves alone read ahead are written by the rule of the units in
/// effect when their run started; a change of units within the run (G21
/// after G20 here, where millimetres keep fewer decimals than inches) makes
/// the consumer write the lines after it by its own rule again: the same
/// output as without the straight-line loop, for runs cut anywhere.
#[test]
fn lines_read_ahead_under_other_units_are_written_by_the_present_ones() {
    let mut prog = String::from("F500\nG20\n");
    for k in 0..40 {
        prog.push_str(&format!("G1 X1.{k:02}456 Y-0.{k:02}500\nG0 X0 Y0\n"));
        prog.push_str("G2 X2.0000 Y0 I1.00001 J0\n");
        if k == 20 {
            prog.push_str("G21\n");
        }
    }
    prog.push_str("M2\n");
    let off = Settings {
        plain_runs: false,
        ..small_limits()
    };
    let want = flatten_for_target(&prog, &off, "grbl", false);
    assert!(want.1.contains("X1.20456"), "{}", want.1);
    assert!(want.1.contains("X1.2146 Y-0.215"), "{}", want.1);
    assert!(want.1.contains("G2 X2 Y0 I1.00001 J0"), "{}", want.1);
    assert!(want.1.contains("G2 X2 Y0 I1 J0"), "{}", want.1);
    for chunk in [1, 8, 24, 64, 200] {
        let on = Settings {
            scan_ahead: chunk,
            ..small_limits()
        };
        assert_eq!(
            flatten_for_target(&prog, &on, "grbl", false),
            want,
            "chunks of {chunk}"
        );
    }
}

/// Lines of moves alone handed over together leave the target's machine
/// model where they would one by one: the lowerings that start from the
/// current position (a full circle, a canned cycle's clear plane) after
/// them write the same lines, with positions absolute and incremental.
#[test]
fn lines_handed_over_together_leave_the_model_where_they_would_one_by_one() {
    let mut prog = String::from("G21 G90 G17 F500\nG0 X0 Y0 Z5\n");
    for (k, mode) in ["G90", "G91", "G90"].iter().enumerate() {
        prog.push_str(&format!("{mode}\n"));
        for j in 0..30 {
            let line = match j % 6 {
                0 => format!("G1 X{}.5 Y{}.25 F{}", j + k, j, 300 + j),
                1 => format!("X{}.10", j + 1),
                2 => format!("G0 Z{}.500", j % 4 + 1),
                3 => format!("G0 X10 Y-{}.75", j),
                // An arc from there, in either mode.
                4 if k == 1 => "G2 X1 Y0 I0.5 J0".to_string(),
                4 => format!("G2 X11 Y-{}.75 I0.5 J0", j - 1),
                _ => format!("G1 Y{}", j + 2),
            };
            prog.push_str(&line);
            prog.push('\n');
            // Comments alone among them, after an arc (in its motion) too.
            if j % 6 == 4 || j % 9 == 0 {
                prog.push_str("(one comment alone)\n");
            }
        }
        // From the current position: a full circle, a drilling cycle with
        // its initial level, and the cycle again after moves.
        prog.push_str("G2 I1 J0\nG98 G81 X3 Y3 Z-1 R1 F100\nG80\nG1 Z2.5 F200\n");
        prog.push_str("G81 X4 Y4 Z-1 R1\nG80\n");
    }
    prog.push_str("M2\n");
    let off = Settings {
        plain_runs: false,
        zero_start: true,
        ..small_limits()
    };
    let want = flatten_for_target(&prog, &off, "grbl", false);
    assert!(want.0.is_empty(), "{:?}", want.0);
    assert!(!want.1.starts_with("error"), "{}", want.1);
    for chunk in [1, 8, 40, 200] {
        let on = Settings {
            plain_runs: true,
            scan_ahead: chunk,
            ..off.clone()
        };
        assert_eq!(
            flatten_for_target(&prog, &on, "grbl", false),
            want,
            "chunks of {chunk}"
        );
    }
}

/// A value expression over every operator, function and kind of parameter
/// reading, including ones that fail (division by zero, domain errors,
/// undefined names, unset parameters).
fn any_value() -> impl Strategy<Value = String> {
    let leaf = prop_oneof![
        12 => proptest::sample::select(
            &[
                "0", "1", "-1", "0.5", "2", "-0.25", "3", "1000000", "0.0001", "-0", "#1", "#2",
                "#3", "#<a>", "#<b>", "#<_g>", "##1", "#[#1 + 1]", "EXISTS[#<a>]",
            ][..]
        )
        .prop_map(String::from),
        1 => proptest::sample::select(
            &["#4", "#<undef>", "#5220", "#5420", "#<_x>", "EXISTS[#<nope>]", "#31"][..]
        )
        .prop_map(String::from),
    ];
    leaf.prop_recursive(3, 12, 2, |inner| {
        prop_oneof![
            (
                proptest::sample::select(
                    &[
                        "+", "-", "*", "/", "MOD", "**", "EQ", "NE", "GT", "GE", "LT", "LE", "AND",
                        "OR", "XOR",
                    ][..]
                ),
                inner.clone(),
                inner.clone()
            )
                .prop_map(|(op, a, b)| format!("[{a} {op} {b}]")),
            (
                proptest::sample::select(
                    &[
                        "ABS", "ACOS", "ASIN", "COS", "EXP", "FIX", "FUP", "LN", "ROUND", "SIN",
                        "SQRT", "TAN",
                    ][..]
                ),
                inner.clone()
            )
                .prop_map(|(f, a)| format!("{f}[{a}]")),
            (inner.clone(), inner.clone()).prop_map(|(y, x)| format!("ATAN[{y}]/[{x}]")),
            inner.clone().prop_map(|a| format!("-{a}")),
            inner.prop_map(|a| format!("#[ABS[FIX[{a}]] MOD 40 + 1]")),
        ]
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    /// Compiled expressions give what the tree evaluation gives: the same
    /// output, and the same error at the same place when there is one.
    #[test]
    fn compiled_expressions_match_the_tree(
        e in proptest::collection::vec(any_value(), 4),
        v in proptest::collection::vec(
            proptest::sample::select(&["0", "1", "-1", "0.5", "2", "-3.75", "1e6"][..]),
            5,
        ),
        zero_start in any::<bool>(),
    ) {
        let v: Vec<&str> = v.iter().map(|s| if *s == "1e6" { "1000000" } else { s }).collect();
        let prog = format!(
            "#1 = {}\n#2 = {}\n#3 = {}\n#<a> = {}\n#<b> = {}\n#<_g> = 2\n\
             o<s> sub\n#<a> = [#1 * 2]\nG1 X{} Y{}\n#10 = {}\n(debug, #10)\no<s> endsub\n\
             G1 X{} Y{} Z{}\n#11 = {}\n(debug, #11)\no<s> call [{}] [2]\n\
             o1 if [{}]\nG0 X1\no1 endif\nM2\n",
            v[0], v[1], v[2], v[3], v[4],
            e[0], e[1], e[2],
            e[0], e[1], e[2], e[3], e[3], e[2],
        );
        let on = Settings { zero_start, ..small_limits() };
        let off = Settings { compiled_exprs: false, ..on.clone() };
        let show = |r: Result<String, Error>| match r {
            Ok(s) => s,
            Err(e) => format!("error: {}", render(&e, MessageFormat::Short, false)),
        };
        let fast = show(ngcflat::flatten_str(&prog, &on));
        let slow = show(ngcflat::flatten_str(&prog, &off));
        prop_assert_eq!(&fast, &slow, "program:\n{}", prog);
    }
}

/// Edge cases of the stack machine, one per line: each is flattened with
/// compiled expressions and with the tree alone, and both must give the
/// same output or the same error.
#[test]
fn compiled_expression_edges_match_the_tree() {
    let cases: &[&str] = &[
        "[#<big> ** #<big>]",
        "[[#<big> ** #<big>] - 1]",
        "[1 / #<zero>]",
        "[#<zero> / #<zero>]",
        "[#1 MOD #<zero>]",
        "[-1 ** 0.5]",
        "[#<neg> ** 0.5]",
        "SQRT[#<neg>]",
        "LN[#<zero>]",
        "ACOS[#<big>]",
        "[#<undef> + 1]",
        "[#77 + 1]",
        "[#<_x> * 2]",
        "[##<zero> + 1]",
        "[#[#1 + 0.5] + 1]",
        "[EXP[#<big>] + 1]",
        "[#<big> * #<big> * #<big> * #<big> * #<big> * #<big>]",
        "-[#<neg> * 2]",
        "[#1 EQ 1.00001]",
        "[#1 NE 1.00001]",
    ];
    for e in cases {
        let prog = format!(
            "#1 = 1\n#<big> = 1000000\n#<zero> = 0\n#<neg> = -4\n#10 = {e}\n(debug, #10)\nG0 X{e}\nM2\n"
        );
        let on = small_limits();
        let off = Settings {
            compiled_exprs: false,
            ..on.clone()
        };
        let show = |r: Result<String, Error>| match r {
            Ok(s) => s,
            Err(e) => format!("error: {}", render(&e, MessageFormat::Short, false)),
        };
        let fast = show(ngcflat::flatten_str(&prog, &on));
        let slow = show(ngcflat::flatten_str(&prog, &off));
        assert_eq!(fast, slow, "{e}");
    }
}

/// A value that changes with the pass `#<k>` of a loop: short, long, tiny
/// and huge numbers, and ones that fail (a division by zero, a value with
/// no G-code form).
fn pass_value() -> impl Strategy<Value = &'static str> {
    proptest::sample::select(
        &[
            "#<k>",
            "[#<k> * 0.05]",
            "[#<k> / 3]",
            "[0 - #<k> / 7]",
            "[#<k> * 1000000000000]",
            "[#<k> * 123456789.123]",
            "[#<k> / 10000000]",
            "[10 ** [#<k> + 10]]",
            "[10 ** [#<k> * 40]]",
            "[1 / [#<k> - 30]]",
            "SIN[#<k>]",
            "[#<k> * 0.1 + 0.2]",
            // Short names of long numbers (set in the loop).
            "#<t>",
            "#<u>",
            "#<w>",
        ][..],
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    /// Output written on the output thread, from the first line or from a
    /// later one, is the output written without it, errors included (an
    /// over-long line, a value with no G-code form, the output line limit).
    #[test]
    fn output_thread_matches_direct_output(
        prog in program(),
        values in proptest::collection::vec(pass_value(), 1..7),
        end in proptest::sample::select(
            &["", "  ", " #<j> = 2", " (msg, k #<k>) ", " (debug, k #<k>)", " (note)\t"][..]
        ),
        len in 100usize..260,
        passes in 0u32..60,
        precision in proptest::option::of(0u8..7),
        max_lines in prop_oneof![Just(10_000u64), 1u64..100],
        strip_comments in any::<bool>(),
    ) {
        let mut line = String::from("G1");
        for (letter, v) in "XYZABC".chars().zip(&values) {
            line.push_str(&format!(" {letter}{v}"));
        }
        line.push_str(end);
        // A comment brings the line to about `len` bytes: some lines are
        // written later, some are checked here, some are too long.
        let pad = len.saturating_sub(line.len() + 3);
        if pad > 0 {
            line.push_str(&format!(" ({})", "p".repeat(pad)));
        }
        let body = prog.strip_suffix("M2\n").unwrap_or(&prog);
        let prog = format!(
            "{body}#<k> = 0\no900 repeat [{passes}]\n\
             #<t> = [#<k> / 3 - 0.1]\n#<u> = [#<k> * 1000000 + 1 / 7]\n#<w> = [0 - #<k> / 70000]\n\
             {line}\n#<k> = [#<k> + 1]\no900 endrepeat\nG0 X[#<k> * 0.3]\nM2\n"
        );
        let never = Settings {
            precision,
            strip_comments,
            max_output_lines: max_lines,
            format_thread_after: usize::MAX,
            ..small_limits()
        };
        let show = |r: Result<String, Error>| match r {
            Ok(s) => s,
            Err(e) => format!("error: {}", render(&e, MessageFormat::Short, false)),
        };
        let direct = ngcflat::flatten_str(&prog, &never);
        if let Ok(text) = &direct {
            // Lines whose numbers are written later must not escape the
            // length check.
            let long = text.lines().find(|l| l.len() > ngcflat::parse::MAX_LINE);
            prop_assert!(long.is_none(), "{:?}", long);
        }
        let direct = show(direct);
        for after in [0, 5] {
            let on = Settings { format_thread_after: after, ..never.clone() };
            let threaded = show(ngcflat::flatten_str(&prog, &on));
            prop_assert_eq!(&threaded, &direct, "thread after {} lines, program:\n{}", after, prog);
        }
    }
}

/// One line of a program for the target property: modal codes a GRBL-class
/// controller may or may not have, moves with numbers of any size,
/// comments with bytes the firmware acts on in real time, and parameters.
fn target_line() -> impl Strategy<Value = String> {
    let num = prop_oneof![
        (-1000i32..1000).prop_map(|v| format!("{v}")),
        (-1.0e6f64..1.0e6).prop_map(|v| format!("{v:.9}")),
        (0.0f64..1.0e-3).prop_map(|v| format!("{v:.12}")),
    ];
    let comment = proptest::collection::vec(
        prop_oneof![
            Just('!'),
            Just('?'),
            Just('~'),
            Just('\u{18}'),
            Just('ü'),
            Just('a'),
            Just(' ')
        ],
        0..6,
    )
    .prop_map(|c| c.into_iter().collect::<String>());
    prop_oneof![
        Just("G20".to_string()),
        Just("G21".to_string()),
        Just("G64 P0.01 G17".to_string()),
        Just("G61.1 G90".to_string()),
        Just("G91".to_string()),
        Just("G90".to_string()),
        Just("G8 G97 G94 M48".to_string()),
        Just("M3 S1000".to_string()),
        Just("M5 M9".to_string()),
        Just("M8".to_string()),
        Just("T1 M6".to_string()),
        Just("M61 Q0".to_string()),
        Just("N123 G1 X1 F10".to_string()),
        num.clone().prop_map(|v| format!("G0 X{v}")),
        (num.clone(), num.clone(), num).prop_map(|(a, b, c)| format!("G1 X{a} Y{b} Z{c} F100")),
        comment.clone().prop_map(|c| format!("(c {c})")),
        comment.clone().prop_map(|c| format!("(MSG, {c})")),
        comment.prop_map(|c| format!("G0 X1 ; {c}")),
        (1i32..100).prop_map(|v| format!("#1=[{v}/7]\nG0 Y#1")),
    ]
}

/// Flattens `lines` for the target `name` and checks every written line:
/// only the profile's codes and words, within its line buffer as the
/// firmware counts it, no byte it acts on in real time, no exponent.
fn target_output_fits(name: &str, lines: &[String]) -> Result<(), TestCaseError> {
    use ngcflat::block::{Block, WordKind};
    use ngcflat::controller::{LineCount, TargetOptions, find, significant_len};
    let program = format!("{}\nM2\n", lines.join("\n"));
    let profile = find(name).expect("profile");
    let settings = Settings {
        zero_start: true,
        ..Settings::default()
    };
    let dir = tempfile::tempdir().expect("dir");
    let out = dir.path().join("out");
    let src = SourceFile::new(
        "<stdin>".into(),
        "<stdin>".into(),
        program.clone().into_bytes(),
    );
    let consumer = ngcflat::lowering(&settings, Some(TargetOptions::new(profile)));
    let (_, err) = ngcflat::flatten_with(
        src,
        &settings,
        &SearchPath::default(),
        Destination::File(out.clone()),
        consumer,
    );
    if err.is_some() {
        return Ok(());
    }
    let (limit, how) = profile
        .line_limit
        .expect("GRBL-class targets have a line buffer");
    let text = std::fs::read(&out).expect("output");
    for line in text.split(|&b| b == b'\n').filter(|l| !l.is_empty()) {
        let shown = String::from_utf8_lossy(line);
        prop_assert!(
            !line.iter().any(|&b| profile.is_realtime(b)),
            "real-time byte in {shown}"
        );
        let len = match how {
            LineCount::AllBytes => line.len(),
            LineCount::Significant => significant_len(line),
        };
        prop_assert!(len < limit, "too long for {name}: {shown}");
        let b = Block::decode(line).expect("decodes");
        prop_assert!(
            !b.block_delete && (profile.percent || !b.percent),
            "{shown}"
        );
        for w in &b.words {
            let ok = match w.kind {
                WordKind::G(_) => profile.has_g((w.value * 10.0).round() as u16),
                WordKind::M(_) => profile.has_m(w.value as u16),
                WordKind::Value => profile.has_word(w.letter),
            };
            prop_assert!(
                ok,
                "{shown}: {} not in the {name} profile",
                w.letter as char
            );
        }
        prop_assert!(
            !shown.contains('e') && !shown.contains('E'),
            "exponent in {shown}"
        );
    }
    Ok(())
}

/// Lines for the grblHAL and FluidNC profiles on top of [`target_line`]:
/// cycles, splines, probes, coordinate systems and long messages.
fn hal_line() -> impl Strategy<Value = String> {
    prop_oneof![
        3 => target_line(),
        1 => Just("G0 Z5\nG98 G81 X1 Y1 Z-2 R1\nG80".to_string()),
        1 => Just("G0 Z5\nG99 G83 X2 Y1 Z-3 R1 Q0.7\nG80".to_string()),
        1 => Just("G0 Z5\nG85 X1 Y2 Z-1 R2\nG89 X3 P0.5\nG80".to_string()),
        1 => Just("G17 G1 F100\nG5 I1 J1 P-1 Q1 X3 Y3\nG5 P1 Q-1 X6 Y0".to_string()),
        1 => Just("G17 G5.1 I0 J2 X2 Y0 F100".to_string()),
        1 => Just("G59.1 G0 X1\nG54".to_string()),
        1 => Just("M7 M8".to_string()),
        1 => (0usize..300).prop_map(|n| format!("(MSG, {})", "x".repeat(n))),
        1 => Just("G0 Z5\nG38.3 Z-1 F50".to_string()),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Every line written for GRBL uses only its codes and words, fits its
    /// line buffer and holds no byte it acts on in real time.
    #[test]
    fn grbl_output_uses_only_what_grbl_has(lines in proptest::collection::vec(target_line(), 1..12)) {
        target_output_fits("grbl", &lines)?;
    }

    /// The same for grblHAL and FluidNC.
    #[test]
    fn grblhal_and_fluidnc_output_uses_only_what_they_have(lines in proptest::collection::vec(hal_line(), 1..12)) {
        target_output_fits("grblhal", &lines)?;
        target_output_fits("fluidnc", &lines)?;
    }
}

/// Diagnostics and output (or error) of `prog` flattened for `target`,
/// with the consumer moving to its own thread after `after` lines.
fn run_for_target(prog: &str, target: &str, check: bool, after: usize) -> (Vec<String>, String) {
    let settings = Settings {
        zero_start: true,
        format_thread_after: after,
        ..small_limits()
    };
    flatten_for_target(prog, &settings, target, check)
}

/// Diagnostics and output (or error) of `prog` flattened with `settings`
/// for `target` (in check mode with `check`).
fn flatten_for_target(
    prog: &str,
    settings: &Settings,
    target: &str,
    check: bool,
) -> (Vec<String>, String) {
    use ngcflat::controller::{TargetOptions, find};
    let mut opts = TargetOptions::new(find(target).expect("profile"));
    opts.check = check;
    let consumer = ngcflat::lowering(settings, Some(opts));
    let (diags, r) = ngcflat::flatten_memory(
        prog.as_bytes().to_vec(),
        Default::default(),
        settings,
        consumer,
    );
    let shown = diags
        .iter()
        .map(|d| render(d, MessageFormat::Short, false))
        .collect();
    let out = match r {
        Ok(o) => String::from_utf8_lossy(&o).into_owned(),
        Err(e) => format!("error: {}", render(&e, MessageFormat::Short, false)),
    };
    (shown, out)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    /// The consumer on its own thread (from the first line, or after a
    /// few) gives the output, the diagnostics and the error it gives on the
    /// evaluator's thread: lines it refuses stop the run at the same line,
    /// with the evaluator's later warnings and errors not reported, and in
    /// check mode every problem is kept.
    #[test]
    fn consumer_apart_matches_consumer_here(
        lines in proptest::collection::vec(target_line(), 1..16),
        repeat in 0u32..40,
        tail in proptest::collection::vec(
            prop_oneof![
                3 => target_line(),
                // A warning of the evaluator (a parameter read unset).
                1 => Just("#2 = [#55 + 1]".to_string()),
            ],
            0..4,
        ),
        check in any::<bool>(),
        computed in any::<bool>(),
    ) {
        // A loop makes many lines; the tail may warn or fail after it. Its
        // body may compute numbers of up to 17 digits (0.07500000000000001)
        // in a line of words alone, which the consumer apart puts together
        // and decodes with their values known.
        let body = if computed {
            "#3 = [#3 + 0.025]\nG1 X#3 Y[#3 * 3 - 0.002] Z[0 - #3 / 7]\n  G0 x[#3 * 1000000 + 1 / 7]"
        } else {
            ""
        };
        let prog = format!(
            "#3 = 0\n{}\no9 repeat [{repeat}]\n{}\n{body}\no9 endrepeat\n{}\nM2\n",
            lines.join("\n"),
            lines.last().map_or("", String::as_str),
            tail.join("\n"),
        );
        let here = run_for_target(&prog, "grbl", check, usize::MAX);
        for after in [0, 3] {
            let apart = run_for_target(&prog, "grbl", check, after);
            prop_assert_eq!(&apart, &here, "apart after {} lines, program:\n{}", after, prog);
        }
    }
}

/// A line refused inside nested calls is reported with the same call
/// stack whichever thread the target runs on, after lines run in other
/// calls at the same depth and in the calls around them.
#[test]
fn consumer_apart_reports_the_calls_of_a_refused_line() {
    let prog = "G21 F100\no<inner> sub\n  G1 X#1\n  o1 if [#1 GT 6]\n    G1 A#1\n  o1 endif\no<inner> endsub\n\
                o<outer> sub\n  G1 Y#1\n  o<inner> call [#1 * 2]\n  o<inner> call [#1 * 2 + 1]\no<outer> endsub\n\
                o<outer> call [1]\no<outer> call [2]\no<outer> call [3]\nM2\n";
    for check in [false, true] {
        let here = run_for_target(prog, "grbl", check, usize::MAX);
        let shown = format!("{here:?}");
        assert!(
            shown.contains(":5:8:") && shown.contains(":11:3)") && shown.contains(":15:1)"),
            "{shown}"
        );
        for after in [0, 1, 3] {
            assert_eq!(
                run_for_target(prog, "grbl", check, after),
                here,
                "check {check}, after {after}"
            );
        }
    }
}

/// A refused line stops the run where it is, whichever thread the target
/// runs on: warnings and errors of the evaluator after it are not reported.
#[test]
fn consumer_apart_stops_at_the_refused_line() {
    // Line 3 is refused for grbl (an axis it lacks); line 5 reads an unset
    // parameter (an evaluator warning), line 6 divides by zero (an
    // evaluator error).
    let prog = "G21 G90\nG1 X1 F100\nG1 A5\nG1 X2\n#1 = [#55 + 1]\n#1 = [1 / 0]\nM2\n";
    let here = run_for_target(prog, "grbl", false, usize::MAX);
    assert!(here.1.contains(":3:"), "{here:?}");
    for after in [0, 1, 2] {
        assert_eq!(
            run_for_target(prog, "grbl", false, after),
            here,
            "after {after}"
        );
    }
    // In check mode both problems are reported.
    let here = run_for_target(prog, "grbl", true, usize::MAX);
    for after in [0, 1, 2] {
        assert_eq!(
            run_for_target(prog, "grbl", true, after),
            here,
            "after {after}"
        );
    }
}
