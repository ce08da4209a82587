//! Machine-motion comparison for programs lowered to a target: rs274 runs
//! the original and the lowered program, each canon stream is replayed into
//! the tool path in machine coordinates and millimetres (G5x and G92
//! offsets, tool length offset and units applied, arcs sampled), cut into
//! runs of one move kind and feed, interleaved with the spindle, coolant,
//! dwell and program-end events; the two are compared within a tolerance.
//! Lowering legitimately changes the canon text (a cycle becomes G0/G1, a
//! dropped G64 loses its canon call), not this.
//!
//! Tool changes and pauses are not compared (M6 becomes M0 or disappears
//! for a controller without a tool changer, as the tool-change option says).

use std::path::Path;
use std::process::{Command, Stdio};

use crate::fixtures;
use crate::oracle;

type P3 = [f64; 3];

#[derive(Debug, Clone, PartialEq)]
enum Item {
    Run {
        kind: &'static str,
        feed: f64,
        pts: Vec<P3>,
    },
    Event(String),
}

/// rs274's canon lines for `program` (with tool table `tbl`, and the folder
/// of the program as its working folder).
fn rs274(program: &[u8], tbl: Option<&Path>) -> Result<Vec<String>, String> {
    rs274_with(program, tbl, None)
}

/// As [`rs274`], with a parameter file (a fresh copy: rs274 rewrites it).
fn rs274_with(
    program: &[u8],
    tbl: Option<&Path>,
    var: Option<&Path>,
) -> Result<Vec<String>, String> {
    let dir = tempfile::tempdir().map_err(|e| e.to_string())?;
    let prog = dir.path().join("prog.ngc");
    std::fs::write(&prog, program).map_err(|e| e.to_string())?;
    let ini = dir.path().join("empty.ini");
    std::fs::write(&ini, "").map_err(|e| e.to_string())?;
    let mut cmd = Command::new("rs274");
    cmd.current_dir(dir.path()).env("HOME", dir.path());
    cmd.arg("-g").arg("-i").arg(&ini);
    if let Some(t) = tbl {
        cmd.arg("-t").arg(t);
    }
    if let Some(v) = var {
        let copy = dir.path().join("params.var");
        std::fs::copy(v, &copy).map_err(|e| e.to_string())?;
        cmd.arg("-v").arg(copy);
    }
    let out = cmd
        .arg(&prog)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .output()
        .map_err(|e| e.to_string())?;
    if !out.status.success() {
        return Err(String::from_utf8_lossy(&out.stderr).into_owned());
    }
    Ok(String::from_utf8_lossy(&out.stdout)
        .lines()
        .map(str::to_string)
        .collect())
}

/// Name and numbers of a canon line (`   12 N..... NAME(1, 2 3, X)`).
fn canon(line: &str) -> Option<(&str, Vec<f64>, &str)> {
    let open = line.find('(')?;
    let head = line[..open].trim_end();
    let name = head.rsplit(' ').next()?;
    let args = line[open + 1..].trim_end().trim_end_matches(')');
    let nums = args
        .split([',', ' '])
        .filter_map(|t| t.trim().parse::<f64>().ok())
        .collect();
    Some((name, nums, args))
}

struct Replay {
    scale: f64,
    g5x: [f64; 3],
    g92: [f64; 3],
    tlo: [f64; 3],
    /// Program position, mm.
    pos: P3,
    plane: u8,
    feed: f64,
    items: Vec<Item>,
    spindle: (i32, f64),
    dwell: f64,
    /// Feed per revolution (G95): compared as the feed per minute at the
    /// spindle speed, which is what a lowering to G94 writes.
    per_rev: bool,
    /// Inverse time (G93): rs274 prints each move's feed per minute, worked
    /// out from its 4-decimal ends, so the moves a block is lowered into
    /// differ by some 1e-5 of it.
    inverse: bool,
    /// The item that is the last event and a speed change of the turning
    /// spindle, if it is.
    speed_change: Option<usize>,
    /// Mist and flood coolant on.
    coolant: [bool; 2],
}

impl Replay {
    fn machine(&self, p: P3) -> P3 {
        std::array::from_fn(|i| p[i] + self.g5x[i] + self.g92[i] + self.tlo[i])
    }

    /// The program position that is machine position `at`.
    fn keep_machine(&mut self, at: P3) {
        self.pos = std::array::from_fn(|i| at[i] - self.g5x[i] - self.g92[i] - self.tlo[i]);
    }

    fn event(&mut self, e: String) {
        if self.dwell > 0.0 {
            let d = format!("dwell {:.3}", self.dwell);
            self.dwell = 0.0;
            self.items.push(Item::Event(d));
        }
        self.items.push(Item::Event(e));
    }

    fn segment(&mut self, kind: &'static str, pts: Vec<P3>) {
        if self.dwell > 0.0 {
            self.event(String::new());
            self.items.pop();
        }
        let feed = match kind {
            "rapid" => 0.0,
            _ if self.per_rev => self.feed * self.spindle.1,
            _ => self.feed,
        };
        let pts: Vec<P3> = pts.into_iter().map(|p| self.machine(p)).collect();
        let start = self.machine(self.pos);
        if let Some(Item::Run {
            kind: k,
            feed: f,
            pts: run,
        }) = self.items.last_mut()
            && *k == kind
            && (*f - feed).abs() <= if self.inverse { 1e-4 } else { 1e-6 } * feed.abs().max(1.0)
        {
            run.extend(pts);
            return;
        }
        let mut run = vec![start];
        run.extend(pts);
        self.items.push(Item::Run {
            kind,
            feed,
            pts: run,
        });
    }

    fn line(&mut self, kind: &'static str, n: &[f64]) {
        let to = [n[0] * self.scale, n[1] * self.scale, n[2] * self.scale];
        self.segment(kind, vec![to]);
        self.pos = to;
    }

    fn arc(&mut self, n: &[f64]) {
        let s = self.scale;
        // first end, second end, first centre, second centre, rotation,
        // normal-axis end.
        let (f, sec, nrm) = match self.plane {
            0 => (0, 1, 2),
            1 => (2, 0, 1),
            _ => (1, 2, 0),
        };
        let (e1, e2, c1, c2, rot, en) = (n[0] * s, n[1] * s, n[2] * s, n[3] * s, n[4], n[5] * s);
        let p = self.pos;
        let r = (p[f] - c1).hypot(p[sec] - c2);
        // An end off the start's distance from the centre: LinuxCNC moves
        // a spiral, the distance linear in the angle.
        let spiral = (e1 - c1).hypot(e2 - c2) - r;
        let a0 = (p[sec] - c2).atan2(p[f] - c1);
        let a1 = (e2 - c2).atan2(e1 - c1);
        let ccw = rot > 0.0;
        let turns = rot.abs().max(1.0) - 1.0;
        let mut sweep = if ccw { a1 - a0 } else { a0 - a1 };
        while sweep <= 1e-12 {
            sweep += std::f64::consts::TAU;
        }
        sweep += turns * std::f64::consts::TAU;
        let steps = ((sweep / 0.02).ceil() as usize).max(2);
        let mut pts = Vec::with_capacity(steps);
        for k in 1..=steps {
            let t = k as f64 / steps as f64;
            let a = if ccw { a0 + sweep * t } else { a0 - sweep * t };
            let mut q = p;
            let rt = r + spiral * t;
            q[f] = c1 + rt * a.cos();
            q[sec] = c2 + rt * a.sin();
            q[nrm] = p[nrm] + (en - p[nrm]) * t;
            pts.push(q);
        }
        let mut end = p;
        end[f] = e1;
        end[sec] = e2;
        end[nrm] = en;
        if let Some(last) = pts.last_mut() {
            *last = end;
        }
        self.segment("feed", pts);
        self.pos = end;
    }

    fn run(lines: &[String]) -> Vec<Item> {
        let mut r = Replay {
            scale: 1.0,
            g5x: [0.0; 3],
            g92: [0.0; 3],
            tlo: [0.0; 3],
            pos: [0.0; 3],
            plane: 0,
            feed: 0.0,
            items: Vec::new(),
            spindle: (0, 0.0),
            dwell: 0.0,
            per_rev: false,
            inverse: false,
            speed_change: None,
            coolant: [false; 2],
        };
        for l in lines {
            let Some((name, n, args)) = canon(l) else {
                continue;
            };
            let s = r.scale;
            match name {
                "USE_LENGTH_UNITS" => r.scale = if args.contains("INCH") { 25.4 } else { 1.0 },
                // An offset change does not move the tool: its program
                // position changes instead.
                "SET_G5X_OFFSET" if n.len() >= 4 => {
                    let at = r.machine(r.pos);
                    r.g5x = [n[1] * s, n[2] * s, n[3] * s];
                    r.keep_machine(at);
                }
                "SET_G92_OFFSET" if n.len() >= 3 => {
                    let at = r.machine(r.pos);
                    r.g92 = [n[0] * s, n[1] * s, n[2] * s];
                    r.keep_machine(at);
                }
                "USE_TOOL_LENGTH_OFFSET" if n.len() >= 3 => {
                    let at = r.machine(r.pos);
                    r.tlo = [n[0] * s, n[1] * s, n[2] * s];
                    r.keep_machine(at);
                }
                "SELECT_PLANE" => {
                    r.plane = if args.contains("XZ") {
                        1
                    } else if args.contains("YZ") {
                        2
                    } else {
                        0
                    }
                }
                "SET_FEED_RATE" if !n.is_empty() => r.feed = n[0] * s,
                "COMMENT" if args.contains("feed mode set to") => {
                    r.inverse = args.contains("inverse time");
                }
                "STRAIGHT_TRAVERSE" if n.len() >= 3 => r.line("rapid", &n),
                "STRAIGHT_FEED" if n.len() >= 3 => r.line("feed", &n),
                "STRAIGHT_PROBE" if n.len() >= 3 => r.line("probe", &n),
                "ARC_FEED" if n.len() >= 6 => r.arc(&n),
                "DWELL" if !n.is_empty() => r.dwell += n[0],
                // Starting the spindle the way it already turns changes
                // nothing (a firmware that reads S only with M3/M4 gets
                // its speed changes that way).
                "START_SPINDLE_CLOCKWISE" if r.spindle.0 != 1 => {
                    r.spindle.0 = 1;
                    let sp = r.spindle;
                    r.event(format!("spindle {} {:.3}", sp.0, sp.1));
                }
                "START_SPINDLE_COUNTERCLOCKWISE" if r.spindle.0 != -1 => {
                    r.spindle.0 = -1;
                    let sp = r.spindle;
                    r.event(format!("spindle {} {:.3}", sp.0, sp.1));
                }
                "STOP_SPINDLE_TURNING" if r.spindle.0 != 0 => {
                    r.spindle.0 = 0;
                    // A speed set and the spindle stopped at once (`M5
                    // S800`, which a firmware reading S only with M3/M4
                    // gets as M5 and a later `M3 S800`): the stop alone.
                    if r.speed_change.is_some_and(|i| i + 1 == r.items.len()) {
                        r.items.pop();
                    }
                    r.event("spindle off".into());
                }
                "SET_SPINDLE_SPEED" if n.len() >= 2 && r.spindle.1 != n[1] => {
                    r.spindle.1 = n[1];
                    if r.spindle.0 != 0 {
                        let sp = r.spindle;
                        r.event(format!("spindle {} {:.3}", sp.0, sp.1));
                        r.speed_change = Some(r.items.len() - 1);
                    }
                }
                // Coolant switched to the state it is in changes nothing
                // (an M9 with the coolant off is not written for a
                // firmware without M9).
                "FLOOD_ON" | "FLOOD_OFF" | "MIST_ON" | "MIST_OFF" => {
                    let (i, on) = match name {
                        "MIST_ON" => (0, true),
                        "MIST_OFF" => (0, false),
                        "FLOOD_ON" => (1, true),
                        _ => (1, false),
                    };
                    if r.coolant[i] != on {
                        r.coolant[i] = on;
                        r.event(name.to_string());
                    }
                }
                // A program ended by `%` finishes without PROGRAM_END.
                "PROGRAM_END" | "FINISH" => r.event("end".into()),
                "SET_FEED_MODE" if !n.is_empty() => r.per_rev = n[n.len() - 1] != 0.0,
                _ => {}
            }
        }
        if r.dwell > 0.0 {
            r.event(String::new());
            r.items.pop();
        }
        // Moves that go nowhere are not motion.
        r.items.retain(|i| match i {
            Item::Run { pts, .. } => pts.windows(2).any(|w| dist(w[0], w[1]) > 1e-9),
            Item::Event(_) => true,
        });
        r.items
    }
}

fn dist(a: P3, b: P3) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// Distance from `p` to the polyline `line`: the segments near `*hint`
/// first (the points come in path order), all of them when that finds
/// nothing within `tol`; the hint moves to the nearest segment.
fn to_polyline(p: P3, line: &[P3], hint: &mut usize, tol: f64) -> f64 {
    // Windows growing around the hint: the next point is nearly always
    // within a few segments of the last one.
    for window in [4, 64, 1024] {
        let near = near_polyline(p, line, hint, window);
        if near <= tol {
            return near;
        }
    }
    near_polyline(p, line, hint, usize::MAX)
}

fn near_polyline(p: P3, line: &[P3], hint: &mut usize, window: usize) -> f64 {
    let mut best = f64::INFINITY;
    let from = hint.saturating_sub(window);
    let to = from
        .saturating_add(window.saturating_mul(2))
        .min(line.len());
    let mut best_i = *hint;
    for (j, w) in line[from..to].windows(2).enumerate() {
        let (a, b) = (w[0], w[1]);
        let d: P3 = std::array::from_fn(|i| b[i] - a[i]);
        let len2 = d.iter().map(|v| v * v).sum::<f64>();
        let t = if len2 == 0.0 {
            0.0
        } else {
            ((0..3).map(|i| (p[i] - a[i]) * d[i]).sum::<f64>() / len2).clamp(0.0, 1.0)
        };
        let q: P3 = std::array::from_fn(|i| a[i] + t * d[i]);
        if dist(p, q) < best {
            best = dist(p, q);
            best_i = from + j;
        }
    }
    *hint = best_i;
    if line.len() == 1 {
        best = dist(p, line[0]);
    }
    best
}

/// Points of a polyline, with extra points so none is farther than `step`
/// from the next.
fn densify(line: &[P3], step: f64) -> Vec<P3> {
    let mut out = Vec::new();
    for w in line.windows(2) {
        let n = ((dist(w[0], w[1]) / step).ceil() as usize).clamp(1, 10_000);
        for k in 0..n {
            let t = k as f64 / n as f64;
            out.push(std::array::from_fn(|i| w[0][i] + t * (w[1][i] - w[0][i])));
        }
    }
    out.extend(line.last().copied());
    out
}

/// Two dwell events within a millisecond of each other.
fn same_dwell(x: &str, y: &str) -> bool {
    let secs = |e: &str| e.strip_prefix("dwell ")?.parse::<f64>().ok();
    match (secs(x), secs(y)) {
        (Some(a), Some(b)) => (a - b).abs() <= 0.001 + 1e-9,
        _ => false,
    }
}

fn compare(a: &[Item], b: &[Item], tol: f64) -> Result<(), String> {
    for (i, pair) in a.iter().zip(b.iter()).enumerate() {
        match pair {
            (Item::Event(x), Item::Event(y)) if x == y => {}
            // A firmware that reads G4's P in whole milliseconds gets it
            // rounded up: it waits at most 1 ms longer than the program.
            (Item::Event(x), Item::Event(y)) if same_dwell(x, y) => {}
            (
                Item::Run {
                    kind: ka,
                    feed: fa,
                    pts: pa,
                },
                Item::Run {
                    kind: kb,
                    feed: fb,
                    pts: pb,
                },
            ) => {
                if ka != kb || (fa - fb).abs() > 1e-3 * fa.abs().max(1.0) {
                    return Err(format!("item {i}: {ka} F{fa} against {kb} F{fb}"));
                }
                let ends = dist(pa[0], pb[0]).max(dist(pa[pa.len() - 1], pb[pb.len() - 1]));
                // The first point off the other path is enough: a search
                // of the whole path for every point of a long differing
                // run would take quadratic time.
                let off = |from: &[P3], to: &[P3]| {
                    let mut hint = 0;
                    densify(from, 0.5)
                        .into_iter()
                        .map(|p| to_polyline(p, to, &mut hint, tol))
                        .find(|d| *d > tol)
                };
                let worst = if ends > tol {
                    Some(ends)
                } else {
                    off(pa, pb).or_else(|| off(pb, pa))
                };
                if let Some(worst) = worst {
                    return Err(format!(
                        "item {i}: {ka} paths differ by {worst:.5} mm (from {:?} to {:?} against {:?} to {:?})",
                        pa[0],
                        pa[pa.len() - 1],
                        pb[0],
                        pb[pb.len() - 1]
                    ));
                }
            }
            (x, y) => return Err(format!("item {i}: {x:?} against {y:?}")),
        }
    }
    if a.len() != b.len() {
        return Err(format!(
            "{} items against {}; first extra: {:?}",
            a.len(),
            b.len(),
            a.get(b.len()).or(b.get(a.len()))
        ));
    }
    Ok(())
}

/// Flattens `path` for its target and compares the motion with the
/// original's.
fn motion_check(path: &Path) -> Result<(), String> {
    let args = fixtures::read_args(path);
    let dir = path.parent().expect("dir");
    let tbl = args
        .iter()
        .position(|a| a == "--tool-table")
        .and_then(|i| args.get(i + 1))
        .map(|t| dir.join(t));
    let zero: &[&str] = if args
        .iter()
        .any(|a| a == "--zero-start" || a == "--var-file")
    {
        &[]
    } else {
        &["--zero-start"]
    };
    let (code, stdout, stderr) = fixtures::run_fixture(path, zero);
    if code != 0 {
        return Err(format!("ngcflat refuses it: {stderr}"));
    }
    let mut original = std::fs::read(path).map_err(|e| e.to_string())?;
    if args
        .windows(2)
        .any(|w| w[0] == "--block-delete" && w[1] == "on")
    {
        // rs274's switch is off: the original with its / lines removed.
        let text = String::from_utf8_lossy(&original).into_owned();
        original = text
            .lines()
            .filter(|l| !l.trim_start().starts_with('/'))
            .map(|l| format!("{l}\n"))
            .collect::<String>()
            .into_bytes();
    }
    let var = args
        .iter()
        .position(|a| a == "--var-file")
        .and_then(|i| args.get(i + 1))
        .map(|v| dir.join(v));
    let a = rs274_with(&original, tbl.as_deref(), var.as_deref())
        .map_err(|e| format!("rs274 on the original: {e}"))?;
    let stdout = match fixtures::target_of(path) {
        Some(t) => crate::as_rs274_reads(&t, &stdout),
        None => stdout,
    };
    let b = rs274_with(stdout.as_bytes(), tbl.as_deref(), var.as_deref())
        .map_err(|e| format!("rs274 rejects the lowered output: {e}\n{stdout}"))?;
    compare(&Replay::run(&a), &Replay::run(&b), 0.002)
}

/// Whether two canon streams of rs274 (its stdout lines, COMMENT lines
/// kept) move the machine the same within `tol` mm; Err says where not.
pub fn same_canon_motion(a: &[String], b: &[String], tol: f64) -> Result<(), String> {
    compare(&Replay::run(a), &Replay::run(b), tol)
}

/// Whether rs274 moves the machine the same for `original` and `lowered`
/// (no tool table; the same tolerance as the fixtures'). Err says where
/// they differ, or that rs274 refuses one of them.
pub fn same_motion(original: &[u8], lowered: &[u8]) -> Result<(), String> {
    let a = rs274(original, None).map_err(|e| format!("rs274 on the original: {e}"))?;
    let b = rs274(lowered, None).map_err(|e| format!("rs274 rejects the lowered output: {e}"))?;
    compare(&Replay::run(&a), &Replay::run(&b), 0.002)
}

#[test]
fn lowered_fixtures_move_as_the_originals() {
    if !oracle::available("lowered_fixtures_move_as_the_originals") {
        return;
    }
    let files: Vec<_> = fixtures::all_fixtures()
        .into_iter()
        .filter(|p| {
            let s = p.to_string_lossy();
            // Splines: rs274 prints no control points (snapshots only).
            fixtures::target_of(p).is_some() && !s.contains("/refuse/") && !s.contains("/spline/")
        })
        .collect();
    assert!(!files.is_empty());
    let failures: Vec<String> = files
        .iter()
        .filter_map(|f| {
            motion_check(f)
                .err()
                .map(|e| format!("{}: {e}", f.display()))
        })
        .collect();
    assert!(
        failures.is_empty(),
        "{} of {} lowered fixtures move differently:\n{}",
        failures.len(),
        files.len(),
        failures.join("\n")
    );
}

#[test]
fn the_comparison_sees_a_different_path() {
    // A program against one whose second move ends elsewhere, and against
    // one that is the same motion written differently (a split move).
    let a = [
        "1 N..... STRAIGHT_TRAVERSE(1.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)".to_string(),
        "2 N..... SET_FEED_RATE(100.0000)".into(),
        "3 N..... STRAIGHT_FEED(2.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)".into(),
    ];
    let mut b = a.clone();
    b[2] = "3 N..... STRAIGHT_FEED(2.0000, 0.0100, 0.0000, 0.0000, 0.0000, 0.0000)".into();
    assert!(compare(&Replay::run(&a), &Replay::run(&b), 0.002).is_err());
    let mut c = a.to_vec();
    c.insert(
        2,
        "3 N..... STRAIGHT_FEED(1.5000, 0.0000, 0.0000, 0.0000, 0.0000, 0.0000)".into(),
    );
    assert_eq!(compare(&Replay::run(&a), &Replay::run(&c), 0.002), Ok(()));
    let mut d = a.to_vec();
    d[1] = "2 N..... SET_FEED_RATE(200.0000)".into();
    assert!(compare(&Replay::run(&a), &Replay::run(&d), 0.002).is_err());
}

/// A random program of offset changes and moves: G52, G92, G92.1, G92.2,
/// G92.3, G10 L2/L20 on any of the nine systems, G54–G59.3, units and
/// distance mode, G0/G1 with some axes.
fn offsets_program(seed: u64) -> String {
    use std::fmt::Write;
    let mut rng = crate::rng::Rng::new(seed);
    let mut p = String::from("G21 G90 G17 F500\nG0 X1 Y2 Z3\n");
    let mut incremental = false;
    let axes = |rng: &mut crate::rng::Rng, lo: f64, hi: f64| {
        let mut s = String::new();
        let mask = 1 + rng.below(7);
        for (i, l) in ['X', 'Y', 'Z'].into_iter().enumerate() {
            if mask & (1 << i) != 0 {
                let _ = write!(s, " {l}{}", rng.milli(lo, hi));
            }
        }
        s
    };
    let systems = [
        "G54", "G55", "G56", "G57", "G58", "G59", "G59.1", "G59.2", "G59.3",
    ];
    for _ in 0..rng.int(10, 24) {
        let line = match rng.below(12) {
            0..=2 => {
                let g = if rng.chance(0.5) { "G0" } else { "G1" };
                let (lo, hi) = if incremental {
                    (-3.0, 3.0)
                } else {
                    (-20.0, 20.0)
                };
                format!("{g}{}", axes(&mut rng, lo, hi))
            }
            3 => format!("G52{}", axes(&mut rng, -5.0, 5.0)),
            4 => format!("G92{}", axes(&mut rng, -5.0, 5.0)),
            5 => rng.pick(&["G92.1", "G92.2", "G92.3"]).to_string(),
            6 => format!("G10 L2 P{}{}", rng.int(1, 9), axes(&mut rng, -10.0, 10.0)),
            7 => format!("G10 L20 P{}{}", rng.int(0, 9), axes(&mut rng, -10.0, 10.0)),
            8 | 9 => rng.pick(&systems).to_string(),
            10 => rng.pick(&["G20", "G21"]).to_string(),
            _ => {
                incremental = !incremental;
                if incremental { "G91" } else { "G90" }.to_string()
            }
        };
        p.push_str(&line);
        p.push('\n');
    }
    p.push_str("G90 G0 X0 Y0 Z0\nM2\n");
    p
}

/// G52, G92.1/G92.2/G92.3 and G59.1–G59.3 lowered for targets that lack
/// them move as the originals under rs274 (random programs;
/// `NGCFLAT_OFFSETS_CASES`, `NGCFLAT_OFFSETS_SEED`).
#[test]
fn lowered_offsets_move_as_rs274() {
    if !oracle::available("lowered_offsets_move_as_rs274") {
        return;
    }
    let seeds = oracle::suite_seeds("NGCFLAT_OFFSETS", 30);
    let results = oracle::on_threads(seeds, 1, |seed| {
        let program = offsets_program(seed);
        let target = random_target(seed);
        let (code, out, err) = lower(&program, target);
        if code != 0 {
            return Err(format!("{target}: ngcflat refuses it: {err}"));
        }
        let a =
            rs274(program.as_bytes(), None).map_err(|e| format!("rs274 on the original: {e}"))?;
        moves_as(&a, &program, target, &out)
    });
    all_pass(results, offsets_program);
}

/// The target a random program `seed` is lowered for.
fn random_target(seed: u64) -> &'static str {
    const TARGETS: [&str; 6] = ["grbl", "grblhal", "fluidnc", "g2core", "klipper", "marlin"];
    TARGETS[(seed % TARGETS.len() as u64) as usize]
}

/// `program` lowered for `target` with `--zero-start`: exit code, output,
/// diagnostics.
fn lower(program: &str, target: &str) -> (i32, String, String) {
    let dir = crate::tmp();
    crate::put(dir.path(), "p.ngc", program);
    crate::run(dir.path(), &["--target", target, "--zero-start", "p.ngc"])
}

/// Whether `out`, `program` lowered for `target`, moves under rs274 as
/// the original's canon `a` does.
fn moves_as(a: &[String], program: &str, target: &str, out: &str) -> Result<(), String> {
    let b = rs274(crate::as_rs274_reads(target, out).as_bytes(), None)
        .map_err(|e| format!("{target}: rs274 rejects the output: {e}\n{out}"))?;
    // rs274 prints offsets and positions with 4 decimals in the current
    // units: 0.00254 mm in inches.
    let tol = if program.contains("G20") {
        0.004
    } else {
        0.002
    };
    compare(&Replay::run(a), &Replay::run(&b), tol)
        .map_err(|e| format!("{target}: {e}\n--- lowered:\n{out}"))
}

/// Fails with every seed of a random suite whose check failed, and its
/// program (written again by `program`).
fn all_pass(results: Vec<(u64, Result<(), String>)>, program: fn(u64) -> String) {
    let failures: Vec<String> = results
        .into_iter()
        .filter_map(|(seed, r)| {
            r.err()
                .map(|e| format!("seed {seed}: {e}\n--- program:\n{}", program(seed)))
        })
        .collect();
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

/// The state a random arc program is written from: the position in
/// machine millimetres, the systems' offsets and the modes.
struct ArcGen {
    rng: crate::rng::Rng,
    machine: [f64; 3],
    offsets: [[f64; 3]; 9],
    system: usize,
    inch: bool,
    incremental: bool,
    absolute_centres: bool,
    /// The plane of the last arc (0 = G17).
    plane: usize,
    out: String,
}

impl ArcGen {
    fn scale(&self) -> f64 {
        if self.inch { 25.4 } else { 1.0 }
    }

    /// The position in program units and coordinates.
    fn pos(&self) -> [f64; 3] {
        let (o, k) = (self.offsets[self.system], self.scale());
        std::array::from_fn(|a| (self.machine[a] - o[a]) / k)
    }

    fn set_pos(&mut self, p: [f64; 3]) {
        let (o, k) = (self.offsets[self.system], self.scale());
        self.machine = std::array::from_fn(|a| p[a] * k + o[a]);
    }

    fn line(&mut self, l: &str) {
        self.out.push_str(l);
        self.out.push('\n');
    }

    /// Axis words to `end` (program units), as written in the distance
    /// mode; the position becomes what LinuxCNC reads from them.
    fn axis_words(&mut self, end: [f64; 3], axes: &[usize]) -> String {
        let at = self.pos();
        let mut p = at;
        let mut s = String::new();
        for &a in axes {
            let v = if self.incremental {
                end[a] - at[a]
            } else {
                end[a]
            };
            let v = (v * 1e4).round() / 1e4;
            p[a] = if self.incremental { at[a] + v } else { v };
            s.push_str(&format!(" {}{v}", ['X', 'Y', 'Z'][a]));
        }
        self.set_pos(p);
        s
    }

    fn arc(&mut self) {
        let plane = self.rng.below(3);
        let [p, q, n] = [[0, 1, 2], [2, 0, 1], [1, 2, 0]][plane];
        let g = ["G17", "G18", "G19"][plane];
        let at = self.pos();
        let r = if self.inch {
            self.rng.float(0.05, 0.4)
        } else {
            self.rng.float(1.0, 10.0)
        };
        let phi = self.rng.float(0.0, std::f64::consts::TAU);
        let mut centre = at;
        centre[p] = ((at[p] + r * phi.cos()) * 1e4).round() / 1e4;
        centre[q] = ((at[q] + r * phi.sin()) * 1e4).round() / 1e4;
        let r = (at[p] - centre[p]).hypot(at[q] - centre[q]);
        let ccw = self.rng.chance(0.5);
        let form = self.rng.below(10);
        let radius_form = form < 3;
        // (LinuxCNC refuses polar words unless the plane before the line
        // is G17.)
        let polar = form == 3 && plane == 0 && self.plane == 0 && !self.incremental;
        self.plane = plane;
        // A full circle only from a point rs274 prints exactly (4
        // decimals): its canon's end is the start as printed, which a
        // point off those decimals would make a short arc of it.
        let exact = at
            .iter()
            .all(|v| ((v * 1e4).round() - v * 1e4).abs() < 1e-6);
        let full = form == 4 && exact;
        let sweep = if radius_form {
            *self.rng.pick(&[1.0, -1.0]) * self.rng.float(20.0, 160.0) + 180.0
        } else {
            self.rng.float(10.0, 350.0)
        }
        .to_radians();
        let a0 = (at[q] - centre[q]).atan2(at[p] - centre[p]);
        let a1 = if ccw { a0 + sweep } else { a0 - sweep };
        let mut end = at;
        end[p] = centre[p] + r * a1.cos();
        end[q] = centre[q] + r * a1.sin();
        let helix = self.rng.chance(0.4);
        if helix {
            end[n] += self.rng.float(-2.0, 2.0) / self.scale();
        }
        let mut l = format!("{g} {}", if ccw { "G3" } else { "G2" });
        if full {
            // A full circle: no end point in the plane.
            if helix {
                l.push_str(&self.axis_words(end, &[n]));
            }
        } else if polar {
            let e = [(end[0] * 1e4).round() / 1e4, (end[1] * 1e4).round() / 1e4];
            l.push_str(&format!(
                " @{} ^{}",
                (e[0].hypot(e[1]) * 1e4).round() / 1e4,
                (e[1].atan2(e[0]).to_degrees() * 1e4).round() / 1e4
            ));
            let mut p3 = at;
            (p3[0], p3[1]) = (e[0], e[1]);
            self.set_pos(p3);
            if helix {
                l.push_str(&self.axis_words(end, &[n]));
            }
        } else {
            let axes: Vec<usize> = if helix { vec![p, q, n] } else { vec![p, q] };
            l.push_str(&self.axis_words(end, &axes));
        }
        if radius_form && !full && !polar {
            let big = sweep > std::f64::consts::PI;
            l.push_str(&format!(
                " R{}",
                if big { -1.0 } else { 1.0 } * (r * 1e4).round() / 1e4
            ));
        } else {
            for a in [p, q] {
                let v = if self.absolute_centres {
                    centre[a]
                } else {
                    centre[a] - at[a]
                };
                l.push_str(&format!(
                    " {}{}",
                    ['I', 'J', 'K'][a],
                    (v * 1e4).round() / 1e4
                ));
            }
        }
        if self.rng.chance(0.3) {
            l.push_str(&format!(" P{}", self.rng.int(1, 3)));
        }
        self.line(&l);
    }

    fn step(&mut self) {
        match self.rng.below(12) {
            0..=5 => self.arc(),
            6 => {
                self.system = self.rng.below(9);
                let s = [
                    "G54", "G55", "G56", "G57", "G58", "G59", "G59.1", "G59.2", "G59.3",
                ][self.system];
                self.line(s);
            }
            7 => {
                self.inch = !self.inch;
                self.line(if self.inch { "G20" } else { "G21" });
            }
            8 => {
                self.incremental = !self.incremental;
                self.line(if self.incremental { "G91" } else { "G90" });
            }
            9 => {
                self.absolute_centres = !self.absolute_centres;
                self.line(if self.absolute_centres {
                    "G90.1"
                } else {
                    "G91.1"
                });
            }
            _ => {
                let k = self.scale();
                let end: [f64; 3] = std::array::from_fn(|_| self.rng.float(-20.0, 20.0) / k);
                let w = self.axis_words(end, &[0, 1, 2]);
                self.line(&format!("G0{w}"));
            }
        }
    }
}

/// A random program of arcs (G2/G3 by centre, radius, polar end point,
/// full circles, P turns, helices) in the three planes, under G90.1 and
/// G91.1, G90 and G91, millimetres and inches, in any of the nine
/// coordinate systems.
fn arcs_program(seed: u64) -> String {
    let mut g = ArcGen {
        rng: crate::rng::Rng::new(seed),
        machine: [0.0; 3],
        offsets: [[0.0; 3]; 9],
        system: 0,
        inch: false,
        incremental: false,
        absolute_centres: seed.is_multiple_of(2),
        plane: 0,
        out: String::from("G21 G90 G17 F500\n"),
    };
    for k in 0..9 {
        let o: [f64; 3] = std::array::from_fn(|_| g.rng.milli(-10.0, 10.0));
        g.offsets[k] = o;
        g.line(&format!("G10 L2 P{} X{} Y{} Z{}", k + 1, o[0], o[1], o[2]));
    }
    g.line(if g.absolute_centres { "G90.1" } else { "G91.1" });
    g.line("G54 G0 X0 Y0 Z0");
    g.set_pos([0.0; 3]);
    for _ in 0..g.rng.int(10, 24) {
        g.step();
    }
    g.line("G90 G0 X0 Y0 Z0\nM2");
    g.out
}

/// Arcs written for targets that lack G90.1, polar words and P turns
/// move as the originals under rs274 (random programs;
/// `NGCFLAT_ARCS_CASES`, `NGCFLAT_ARCS_SEED`).
#[test]
fn lowered_arcs_move_as_rs274() {
    if !oracle::available("lowered_arcs_move_as_rs274") {
        return;
    }
    let seeds = oracle::suite_seeds("NGCFLAT_ARCS", 20);
    let results = oracle::on_threads(seeds, 1, |seed| {
        let program = arcs_program(seed);
        let target = random_target(seed);
        let (code, out, err) = lower(&program, target);
        match (rs274(program.as_bytes(), None), code) {
            (Ok(a), 0) => moves_as(&a, &program, target, &out),
            (Ok(_), _) => Err(format!("{target}: ngcflat refuses it: {err}")),
            // LinuxCNC refuses it (an R arc it cannot place, say): so
            // must the lowering.
            (Err(_), 0) => Err(format!(
                "{target}: rs274 refuses it, ngcflat writes:\n{out}"
            )),
            (Err(_), _) => Ok(()),
        }
    });
    all_pass(results, arcs_program);
}
