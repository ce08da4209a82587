//! The run-time model on hand-computed cases, each figure worked out in
//! its comment.

use super::*;
use crate::codes::Plane;
use crate::machine::motion::Feed as MoveFeed;

fn p(x: f64, y: f64) -> Point {
    let mut work = [0.0; 9];
    work[0] = x;
    work[1] = y;
    Point {
        work,
        offset: Some([0.0; 9]),
    }
}

fn feed(f: f64) -> MoveFeed {
    MoveFeed {
        rate: f,
        mode: FeedMode::PerMinute,
    }
}

fn line(from: Point, to: Point, f: f64) -> Motion {
    Motion::Line {
        kind: MoveKind::Feed,
        from,
        to,
        feed: feed(f),
    }
}

fn grbl(listing: &str) -> RunTime {
    let settings = GrblSettings::from_listing(listing).unwrap();
    RunTime::new(TimeModel::Grbl {
        settings,
        window: GRBL_WINDOW,
        firmware: "GRBL 1.1h",
    })
}

fn total(mut rt: RunTime) -> f64 {
    rt.finish();
    rt.totals().total
}

#[test]
fn one_move_is_a_trapezoid() {
    // GRBL's defaults: 500 mm/min (8.333 mm/s) caps F600, 10 mm/s². Up to
    // speed in 0.8333 s over 3.472 mm, the same down, 93.056 mm at
    // 8.333 mm/s take 11.1667 s: 12.8333 s, and the 25 ms wait after the
    // stop.
    let mut rt = grbl("");
    rt.motion(&line(p(0.0, 0.0), p(100.0, 0.0), 600.0));
    let t = total(rt);
    assert!((t - (12.0 + 0.8333333333 + 0.025)).abs() < 1e-9, "{t}");
}

#[test]
fn collinear_moves_do_not_slow_down() {
    // The same 100 mm in two and in ten pieces: no junction between
    // blocks in line, so the same 12.8583 s.
    let mut two = grbl("");
    two.motion(&line(p(0.0, 0.0), p(40.0, 0.0), 600.0));
    two.motion(&line(p(40.0, 0.0), p(100.0, 0.0), 600.0));
    let mut ten = grbl("");
    for i in 0..10 {
        let x = f64::from(i) * 10.0;
        ten.motion(&line(p(x, 0.0), p(x + 10.0, 0.0), 600.0));
    }
    let expect = 12.0 + 0.8333333333 + 0.025;
    assert!((total(two) - expect).abs() < 1e-9);
    assert!((total(ten) - expect).abs() < 1e-9);
}

#[test]
fn a_corner_at_the_junction_deviation() {
    // 10 mm along X, then 10 mm along Y at F300 (5 mm/s), 10 mm/s²,
    // $11 = 0.01: the corner is passed at v = 0.58431 mm/s (see
    // grbl::tests). Each leg: from 0 (or v) up to 5 mm/s, cruise, down to
    // v (or 0): (5 − 0)/10 + (5 − v)/10 + (10 − 1.25 − (25 − v²)/20)/5 s.
    let v2: f64 = 10.0 * 2f64.sqrt() * 0.01 * 0.5f64.sqrt() / (1.0 - 0.5f64.sqrt());
    let v = v2.sqrt();
    let leg = 0.5 + (5.0 - v) / 10.0 + (10.0 - 1.25 - (25.0 - v2) / 20.0) / 5.0;
    let mut rt = grbl("");
    rt.motion(&line(p(0.0, 0.0), p(10.0, 0.0), 300.0));
    rt.motion(&line(p(10.0, 0.0), p(10.0, 10.0), 300.0));
    let t = total(rt);
    assert!((t - (2.0 * leg + 0.025)).abs() < 1e-9, "{t} {leg}");
}

#[test]
fn arc_chords_run_at_their_own_axis_limit() {
    // A quarter circle of radius 10 from (10, 0) to (0, 10) at F6000, each
    // axis at most 600 mm/min (10 mm/s), accelerations so high that ramps
    // take no time, 1000 steps/mm. $12 = 0.5: floor(0.5·(π/2)·10 /
    // sqrt(0.5·19.5)) = floor(2.515) = 2 chords of 2·10·sin(22.5°) =
    // 7.6537 mm, headed at 112.5° and 157.5°: each axis's share is at most
    // sin(67.5°) = 0.92388 of the speed, so each chord runs at
    // 10/0.92388 = 10.824 mm/s: 2·7.6537/10.824 = 1.41421 s, where the
    // slowest axis alone (10 mm/s) would take 1.5307 s.
    let mut rt =
        grbl("$12=0.5\n$100=1000\n$101=1000\n$110=600\n$111=600\n$120=1e9\n$121=1e9\n$1=0\n");
    rt.motion(&Motion::Arc {
        from: p(10.0, 0.0),
        to: p(0.0, 10.0),
        center: [0.0, 0.0],
        plane: Plane::XY,
        ccw: true,
        turns: 1,
        feed: feed(6000.0),
    });
    let t = total(rt);
    assert!((t - 2f64.sqrt()).abs() < 2e-3, "{t}");
}

#[test]
fn a_dense_circle_is_limited_by_the_look_ahead() {
    // 2000 chords of a circle of radius 20 (L = 2·20·sin(π/2000) =
    // 0.0628318 mm) at F1000, 10 mm/s², rounding to steps made negligible.
    // The corners (0.18°) allow ~280 mm/s; the 15-block window does not:
    // a chord leaves at the speed from which the 14 chords behind it can
    // still stop, v² = 2·10·14·L = 17.593 (4.1944 mm/s), and peaks at
    // sqrt(v² + 10·L) = 4.2686 mm/s: 2·(4.2686 − 4.1944)/10 = 0.014843 s
    // per chord, where 0.0628 mm at F1000 would take 0.0038 s. Chords
    // heading along X (the top of the circle) have exactly 10 mm/s².
    let mut rt = grbl("$100=1e6\n$101=1e6\n$110=6000\n$111=6000\n");
    let n = 2000;
    let at = |i: u32| {
        let a = std::f64::consts::TAU * f64::from(i) / f64::from(n);
        p(20.0 * a.cos(), 20.0 * a.sin())
    };
    let mut times = std::collections::HashMap::new();
    for i in 0..n {
        rt.line(u64::from(i) + 1);
        rt.motion(&line(at(i), at(i + 1), 1000.0));
        while let Some(t) = rt.next_line() {
            times.insert(t.line, t.seconds);
        }
    }
    rt.finish();
    while let Some(t) = rt.next_line() {
        times.insert(t.line, t.seconds);
    }
    let l = 40.0 * (std::f64::consts::PI / 2000.0).sin();
    let v2 = 2.0 * 10.0 * 14.0 * l;
    let expect = 2.0 * ((v2 + 10.0 * l).sqrt() - v2.sqrt()) / 10.0;
    // The chord from 90° on heads along -X.
    let top = times[&501];
    assert!((top - expect).abs() < 1e-3 * expect, "{top} {expect}");
}

#[test]
fn dwells_in_50_ms_steps_after_a_stop() {
    // G4 P0.12 after a move: the move runs to a stop, GRBL waits its 25 ms
    // idle delay, then ceil(0.12/0.05) = 3 steps of 50 ms. The line's own
    // time is 0.175 s; a second dwell finds the machine at rest: 0.15 s.
    let mut rt = grbl("");
    rt.line(1);
    rt.motion(&line(p(0.0, 0.0), p(1.0, 0.0), 600.0));
    rt.line(2);
    rt.motion(&Motion::Dwell { seconds: 0.12 });
    rt.line(3);
    rt.motion(&Motion::Dwell { seconds: 0.12 });
    rt.finish();
    let lines: Vec<LineTime> = std::iter::from_fn(|| rt.next_line()).collect();
    assert_eq!(lines.len(), 3);
    // 1 mm at 10 mm/s² never reaches 8.333 mm/s: 2·sqrt(1/10) s.
    let first = 2.0 * 0.1f64.sqrt();
    assert!((lines[0].seconds - first).abs() < 1e-9);
    assert!((lines[1].seconds - 0.175).abs() < 1e-9);
    assert!((lines[1].start - first).abs() < 1e-9);
    assert!((lines[2].seconds - 0.15).abs() < 1e-9);
    assert!((rt.totals().dwell - 0.3).abs() < 1e-9);
    assert_eq!(rt.totals().stops, 1);
}

#[test]
fn time_per_tool_and_syncs() {
    // Spindle on, 10 mm at F600 (8.333 mm/s cap) with tool 2, coolant on,
    // the same back with tool 2: the coolant change stops the machine
    // between the moves; each leg is 10/8.333 + 0.8333 = 2.0333 s, each
    // stop adds 25 ms (after the first move, and at the end).
    let mut rt = grbl("");
    rt.motion(&Motion::ToolChange { tool: 2 });
    rt.motion(&Motion::Spindle {
        dir: crate::codes::SpindleDir::Cw,
        speed: 1000.0,
        mode: crate::codes::SpindleMode::Rpm,
    });
    rt.motion(&line(p(0.0, 0.0), p(10.0, 0.0), 600.0));
    rt.motion(&Motion::Coolant {
        mist: false,
        flood: true,
    });
    rt.motion(&line(p(10.0, 0.0), p(0.0, 0.0), 600.0));
    rt.finish();
    let t = rt.totals();
    let leg = 1.2 + 0.8333333333;
    assert_eq!(t.stops, 2);
    assert!((t.total - 2.0 * (leg + 0.025)).abs() < 1e-9, "{}", t.total);
    assert!((t.per_tool[&Some(2)] - t.total).abs() < 1e-12);
}

/// LinuxCNC's model: every axis at 100 mm/s and 100 mm/s², a 1 ms cycle.
fn linuxcnc(exact: bool, tolerance: f64) -> RunTime {
    let mut rt = RunTime::new(TimeModel::LinuxCnc {
        limits: Box::new(linuxcnc::Limits {
            vel: [100.0; 9],
            acc: [100.0; 9],
            traj_vel: f64::INFINITY,
            traj_acc: f64::INFINITY,
            cycle: 0.001,
            depth: 50,
            source: linuxcnc::LimitSource::Ini,
        }),
    });
    rt.motion(&Motion::PathMode { exact, tolerance });
    rt
}

/// The time of a block of `mm` at cruise `v` with acceleration `a`,
/// entered at `v0` and left at `v1`, when it reaches `v`.
fn trapezoid(mm: f64, v: f64, a: f64, v0: f64, v1: f64) -> f64 {
    let up = (v * v - v0 * v0) / (2.0 * a);
    let down = (v * v - v1 * v1) / (2.0 * a);
    (v - v0) / a + (v - v1) / a + (mm - up - down) / v
}

#[test]
fn linuxcnc_exact_stop_is_a_trapezoid_per_side() {
    // G61: a 10 mm square at F600 (10 mm/s) with 100 mm/s². Each side
    // stops: 0.1 s and 0.5 mm up to speed, the same down, 9 mm at 10 mm/s
    // in 0.9 s: 1.1 s a side, 4.4 s. No waits after the stop (a GRBL
    // thing).
    let mut rt = linuxcnc(true, 0.0);
    let c = [
        (0.0, 0.0),
        (10.0, 0.0),
        (10.0, 10.0),
        (0.0, 10.0),
        (0.0, 0.0),
    ];
    for w in c.windows(2) {
        rt.motion(&line(p(w[0].0, w[0].1), p(w[1].0, w[1].1), 600.0));
    }
    let t = total(rt);
    assert!((t - 4.4).abs() < 1e-9, "{t}");
}

#[test]
fn linuxcnc_blends_a_corner_within_the_tolerance() {
    // G64 P0.1: 10 mm along X then 10 mm along Y at 10 mm/s, 100 mm/s².
    // The kink test fails (a_inst = 10/0.001 + 100 = 10100 mm/s² against
    // 100: far above a tenth), so a blend arc: θ = 45°, φ = 90°, a_max =
    // 100 in the XY plane, a_n = 86.603. d_tol = cos 45°·0.1/(1 − sin 45°)
    // = 0.24142 (under half a side, 5 mm), R = tan 45°·0.24142 = 0.24142,
    // v_plan = sqrt(86.603·0.24142) = 4.5725 mm/s; R_plan = max(v²/a_n,
    // R_blend) = 0.24142, so the arc is 0.24142·π/2 = 0.37922 mm, each
    // side gives up 0.24142 mm. Side 1 (9.7586 mm): up to 10 mm/s
    // (0.1 s), down to 4.5725 (0.054275 s), 8.8631 mm cruising: 1.04059 s.
    // The arc at 4.5725 mm/s: 0.082935 s. Side 2 as side 1: 2.16411 s in
    // all, where G61 takes 2.2 s.
    let mut rt = linuxcnc(false, 0.1);
    rt.motion(&line(p(0.0, 0.0), p(10.0, 0.0), 600.0));
    rt.motion(&line(p(10.0, 0.0), p(10.0, 10.0), 600.0));
    let t = total(rt);
    let r = 0.1 * (0.5f64).sqrt() / (1.0 - (0.5f64).sqrt());
    let v = (100.0 * 0.75f64.sqrt() * r).sqrt();
    let side = trapezoid(10.0 - r, 10.0, 100.0, 0.0, v);
    let expect = 2.0 * side + r * std::f64::consts::FRAC_PI_2 / v;
    assert!((v - 4.5725).abs() < 1e-4, "{v}");
    assert!((expect - 2.16411).abs() < 1e-5, "{expect}");
    assert!((t - expect).abs() < 1e-9, "{t} against {expect}");
}

#[test]
fn linuxcnc_g64_without_tolerance_runs_the_corner_at_the_feed() {
    // G64 P0: the tolerance is a quarter of a side, 2.5 mm: d_tol =
    // 6.0355, over half a side, so d = 5, R_geom = 5 and v_plan =
    // min(sqrt(86.603·5) = 20.8, 10) = 10 mm/s. R_blend: a parabolic blend
    // at a_max/2 = 50 takes 10/50 = 0.2 s and 2 mm, over φ = π/2: R =
    // 1.27324; R_plan = max(10²/86.603 = 1.1547, 1.27324) = 1.27324. The
    // arc is 2 mm at 10 mm/s: 0.2 s; each side 8.72676 mm, from rest to
    // 10 mm/s (0.1 s, 0.5 mm) then 8.22676 mm cruising: 0.922676 s.
    // 2.045352 s in all, less than P0.1's 2.16411 s.
    let mut rt = linuxcnc(false, 0.0);
    rt.motion(&line(p(0.0, 0.0), p(10.0, 0.0), 600.0));
    rt.motion(&line(p(10.0, 0.0), p(10.0, 10.0), 600.0));
    let t = total(rt);
    let r = 2.0 / std::f64::consts::FRAC_PI_2;
    let side = trapezoid(10.0 - r, 10.0, 100.0, 0.0, 10.0);
    let expect = 2.0 * side + 0.2;
    assert!((expect - 2.045352).abs() < 1e-6, "{expect}");
    assert!((t - expect).abs() < 1e-9, "{t} against {expect}");
}

#[test]
fn linuxcnc_arc_at_the_centripetal_limit() {
    // A half circle of radius 1 mm at F6000 (100 mm/s), 100 mm/s²: v²/r
    // would be 10000 mm/s², over 0.866·100, so v = sqrt(86.603·1) =
    // 9.3060 mm/s and half of 100 mm/s² is left along the path. π mm
    // from rest to rest: 0.18612 s and 0.86603 mm up, the same down,
    // 1.40954 mm at 9.3060 mm/s (0.151466 s): 0.523707 s.
    let mut rt = linuxcnc(false, 0.0);
    rt.motion(&Motion::Arc {
        from: p(1.0, 0.0),
        to: p(-1.0, 0.0),
        center: [0.0, 0.0],
        plane: Plane::XY,
        ccw: true,
        turns: 1,
        feed: feed(6000.0),
    });
    let t = total(rt);
    let v = (100.0 * 0.75f64.sqrt()).sqrt();
    let expect = trapezoid(std::f64::consts::PI, v, 50.0, 0.0, 0.0);
    assert!((expect - 0.523707).abs() < 1e-6, "{expect}");
    assert!((t - expect).abs() < 1e-9, "{t} against {expect}");
}
