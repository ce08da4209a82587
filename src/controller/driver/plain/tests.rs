//! Tests of the driver on random lines: the short way against the general
//! one (output, state and diagnostics compared), which lines take the
//! short way, and arcs that barely turn not written as full circles.

use std::path::PathBuf;
use std::sync::Arc;

use proptest::prelude::*;

use crate::controller::{TargetOptions, profiles};
use crate::emit::{Destination, Output, Sink};
use crate::eval::{LineConsumer, Origin};
use crate::program::SourceFile;
use crate::settings::Settings;

use super::Lowering;

/// Output, state after each line and diagnostics of `lines` run
/// through a lowering for profile `p`, the short way on or off.
fn run(lines: &[String], p: usize, zero_start: bool, plain: bool) -> (String, Vec<String>) {
    run_with(lines, p, zero_start, plain, false)
}

/// The words of `line` as the straight-line reader keeps them, if it
/// is a move alone (see `RawLine::moves_only`).
fn moves_of(line: &str) -> Option<Vec<crate::block::RawWord>> {
    let b = crate::block::Block::decode(line.as_bytes()).ok()?;
    let mut raw = crate::block::RawLine::default();
    if let Some((v, s)) = b.line_number {
        raw.set_line_number(v, s);
    }
    if let Some(c) = b.comments.first() {
        raw.set_comment(c.span);
    }
    for w in &b.words {
        raw.push(crate::block::RawWord {
            letter: line.as_bytes()[w.span.start as usize],
            value: w.value,
            span: w.span,
            shape: w.shape,
        });
    }
    let text = line.trim_end_matches([' ', '\t', '\r']);
    raw.moves_only(text.as_bytes()).map(<[_]>::to_vec)
}

/// [`run`]; with `moves`, each line that is a move alone goes the
/// way of lines read ahead (`moves_line`, its words without a block).
fn run_with(
    lines: &[String],
    p: usize,
    zero_start: bool,
    plain: bool,
    moves: bool,
) -> (String, Vec<String>) {
    let settings = Settings {
        zero_start,
        ..Settings::default()
    };
    let mut opts = TargetOptions::new(&profiles()[p]);
    opts.check = true;
    let mut l = Lowering::new(&settings, opts);
    l.plain = plain;
    let dir = tempfile::tempdir().expect("dir");
    let path = dir.path().join("out");
    let sink = Sink::new(Destination::File(path.clone())).expect("sink");
    let mut out = Output::new(sink, None, usize::MAX);
    let text = lines.join("\n");
    let file = Arc::new(SourceFile::new(
        PathBuf::from("<t>"),
        "<t>".into(),
        text.clone().into_bytes(),
    ));
    let stack = Vec::new;
    let mut states = Vec::new();
    let mut at = 0;
    for line in lines {
        let origin = Origin {
            file: &file,
            line_start: at,
            verbatim: true,
            stack: &stack,
        };
        at += line.len() as u32 + 1;
        let r = match moves.then(|| moves_of(line)).flatten() {
            Some(words) => {
                let text = line.trim_end_matches([' ', '\t', '\r']);
                l.moves_line(text.as_bytes(), &words, &origin, &mut out)
            }
            None => l.line(line.as_bytes(), &origin, &mut out),
        };
        states.push(format!(
            "{r:?} {:?} {:?} {:?} {} {:?} {:?} {:?}",
            l.m, l.last_f, l.f_before, l.percent_open, l.cycles, l.written_feed, l.last_pq
        ));
    }
    let diags = l.finish(&mut out).expect("finish");
    states.push(format!("{diags:?}"));
    out.finish().expect("written");
    (std::fs::read_to_string(path).expect("read"), states)
}

/// The G2/G3 lines of `out` (absolute, G17) as (start, end, centre),
/// each as the target reads it from the numbers written.
fn written_arcs(out: &str) -> Vec<([f64; 2], [f64; 2], [f64; 2])> {
    let (mut at, mut arcs, mut motion) = ([0.0f64; 2], Vec::new(), 0.0);
    for line in out.lines() {
        let (mut end, mut ij) = (at, [0.0; 2]);
        for w in line.split(' ') {
            let v: f64 = w[1..].parse().unwrap_or(f64::NAN);
            match w.as_bytes()[0] {
                b'G' if matches!(v as u32, 0..=3) => motion = v,
                b'X' => end[0] = v,
                b'Y' => end[1] = v,
                b'I' => ij[0] = v,
                b'J' => ij[1] = v,
                _ => {}
            }
        }
        if motion >= 2.0 && line.contains(['X', 'Y']) {
            arcs.push((at, end, [at[0] + ij[0], at[1] + ij[1]]));
        }
        at = end;
    }
    arcs
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    /// An arc that turns very little (a corner of a compensated path,
    /// CAM output in fine steps) is never written so that the target
    /// takes it for a full circle: its end written on its start, or an
    /// angle under GRBL's 5e-7 rad. Each way (the block's, the short
    /// way, the line of moves alone).
    #[test]
    fn arcs_that_barely_turn_are_not_written_as_full_circles(
        radius in 0.05f64..2000.0,
        from in -3.2f64..3.2,
        sweep_exp in -12.0f64..-3.0,
        ccw in proptest::bool::ANY,
        ways in 0usize..3,
    ) {
        let sweep = 10f64.powf(sweep_exp);
        let to = if ccw { from + sweep } else { from - sweep };
        let (cx, cy) = (3.0, -7.0);
        let point = |a: f64| [cx + radius * a.cos(), cy + radius * a.sin()];
        let (s, e) = (point(from), point(to));
        let lines = vec![
            "G21 G90 G17 F100".to_string(),
            format!("G0 X{} Y{}", s[0], s[1]),
            format!("G{} X{} Y{} I{} J{}", if ccw { 3 } else { 2 }, e[0], e[1], cx - s[0], cy - s[1]),
            "G1 X0 Y0".to_string(),
        ];
        let (out, _) = run_with(&lines, 1, true, ways > 0, ways == 2);
        for (start, end, centre) in written_arcs(&out) {
            prop_assert!(start != end, "{out}");
            let angle = |p: [f64; 2]| (p[1] - centre[1]).atan2(p[0] - centre[0]);
            let turned = (angle(end) - angle(start)).abs();
            prop_assert!(turned > 5e-7 && turned < std::f64::consts::TAU - 5e-7, "{out}");
        }
    }
}

/// A number as a program or the evaluator may write it.
fn number() -> impl Strategy<Value = String> {
    prop_oneof![
        (-300i32..300).prop_map(|v| v.to_string()),
        (-3000.0f64..3000.0, 0usize..7).prop_map(|(v, d)| format!("{v:.d$}")),
        (-2.0f64..2.0).prop_map(|v| v.to_string()),
        Just("+1.5".to_string()),
        Just("-0".to_string()),
        Just("0.00001".to_string()),
        Just("12345678.9".to_string()),
        Just("007.50".to_string()),
        Just(".5".to_string()),
    ]
}

/// A word: mostly what the short way takes, and its near misses.
fn word() -> impl Strategy<Value = String> {
    let codes = prop_oneof![
        Just("G0"),
        Just("G1"),
        Just("G2"),
        Just("G3"),
        Just("G17"),
        Just("G18"),
        Just("G19"),
        Just("G20"),
        Just("G21"),
        Just("G90"),
        Just("G91"),
        Just("G7"),
        Just("G8"),
        Just("G80"),
        Just("G81"),
        Just("G94"),
        Just("G95"),
        Just("G64"),
        Just("G41"),
        Just("G40"),
        Just("G43"),
        Just("G5"),
        Just("G38.2"),
        Just("M3"),
        Just("M5"),
        Just("M8"),
        Just("M9"),
        Just("M7"),
        Just("M0"),
        Just("M2"),
        Just("M6"),
        Just("g1"),
    ]
    .prop_map(str::to_string);
    let values = (
        prop_oneof![
            8 => proptest::sample::select(b"XYZF".to_vec()),
            3 => proptest::sample::select(b"IJKS".to_vec()),
            1 => proptest::sample::select(b"ARPTDHLQxz".to_vec()),
        ],
        number(),
    )
        .prop_map(|(l, v)| format!("{}{v}", l as char));
    // Whole blocks of what is lowered, to have its state around.
    let blocks = proptest::sample::select(vec![
        "G81 X1 Y1 Z-1 R2",
        "G83 Z-3 R1 Q1",
        "G99 G82 X2 Z-1 R1 P0.5",
        "G95 S1000",
        "G41.1 D2",
        "G43.1 Z2",
        "G2 X2 Y1 R0.4",
        "G38.2 Z-5",
        "G5 X3 Y3 I1 J0 P1 Q1",
        "G59.1",
        "G55",
        "G54",
        "G10 L2 P7 X5 Y-1",
        "G10 L20 P2 X1",
        "G52 X2 Y1",
        "G92 X0 Y0",
        "G92.2",
        "G92.3",
        "G92.1",
        "G5.2 X1 Y1 P1 L3",
        "G5.3",
    ])
    .prop_map(str::to_string);
    prop_oneof![4 => codes, 10 => values, 1 => blocks]
}

fn line() -> impl Strategy<Value = String> {
    (
        proptest::option::weighted(0.1, (1u32..200).prop_map(|n| format!("N{n} "))),
        proptest::collection::vec(word(), 0..6),
        proptest::sample::select(vec!["", " ", "  "]),
        proptest::option::weighted(
            0.15,
            proptest::sample::select(vec![
                "(plain)",
                "(MSG, tool ? now!)",
                "; rest",
                "(debug, x)",
            ]),
        ),
    )
        .prop_map(|(n, words, sep, comment)| {
            let mut l = n.unwrap_or_default();
            l.push_str(&words.join(sep));
            if let Some(c) = comment {
                l.push(' ');
                l.push_str(c);
            }
            l
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    /// Lines taken the short way give the same output, state and
    /// diagnostics as through the general lowering.
    #[test]
    fn short_way_matches_the_general_lowering(
        lines in proptest::collection::vec(line(), 1..30),
        p in 1usize..4,
        zero_start in any::<bool>(),
    ) {
        let mut lines = lines;
        // Start where most lines are plain: feed moves in millimetres.
        lines.insert(0, "G21 G1 F100".into());
        let fast = run(&lines, p, zero_start, true);
        let slow = run(&lines, p, zero_start, false);
        prop_assert_eq!(&fast.0, &slow.0, "output of {:?}", lines);
        for (i, (a, b)) in fast.1.iter().zip(slow.1.iter()).enumerate() {
            prop_assert_eq!(a, b, "state after line {} of {:?}", i, lines);
        }
        // Moves alone taken without their block: the same again.
        let moves = run_with(&lines, p, zero_start, true, true);
        prop_assert_eq!(&moves.0, &slow.0, "output of {:?} (moves)", lines);
        for (i, (a, b)) in moves.1.iter().zip(slow.1.iter()).enumerate() {
            prop_assert_eq!(a, b, "state after line {} of {:?} (moves)", i, lines);
        }
    }
}

/// The random lines do take the short way (the test above compares
/// something).
#[test]
fn common_lines_are_plain() {
    let settings = Settings::default();
    let mut l = Lowering::new(&settings, TargetOptions::new(&profiles()[1]));
    let mut b = crate::block::Block::default();
    for (text, want) in [
        ("G1 X1.5000 Y-2 F300", true),
        ("G2 X1 Y2 I1 J0", true),
        ("G21 G90 G17 M3 S1000", true),
        ("(a comment)", true),
        ("G2 I1 J0", false),
        ("G1 X1 A2", false),
        ("G64 P0.01", false),
        ("G2 X1 Y2 R5", false),
        ("M6 T1", false),
        ("M2", false),
    ] {
        b.decode_into(text.as_bytes()).expect("decodes");
        l.m.modes.motion = crate::block::MotionMode::Linear;
        assert_eq!(l.is_plain(&b), want, "{text}");
    }
}
