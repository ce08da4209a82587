//! Generated cutter-compensation programs against rs274.
//!
//! A seeded generator writes programs that turn compensation on (G41/G42
//! with a tool from a tool table, or G41.1/G42.1 with a D diameter), enter
//! with a line or an arc, follow a random open or closed contour of lines
//! and arcs (inside and outside corners, arcs near the tool radius, moves
//! off the plane, rapids), and leave with G40 or end with M2, in G17 and
//! G18 (lathe tools with orientations), in millimetres and inches. Each
//! program runs through rs274 (with the tool table, `-t`) and through
//! [`ngcflat::geom::cutter_comp`]; the moves (STRAIGHT_TRAVERSE, STRAIGHT_FEED,
//! ARC_FEED) must agree within 1e-4 and an error must be raised at the same
//! line. Each program is also checked with `ngcflat check`, which must
//! refuse it at the same line, or accept it.
//!
//! `NGCFLAT_COMP_CASES=N` sets the number of programs (default 300),
//! `NGCFLAT_COMP_SEED=S` the first seed.

use ngcflat::block::{ArcDistance, Units};
use ngcflat::geom::cutter_comp::{Arc, ArcCenter, Comp, CompError, Out, Side, Tolerances};

use crate::oracle;
use crate::rng::Rng;

/// What a program line does, for the model run.
#[derive(Debug, Clone)]
enum Step {
    Plain {
        rapid: bool,
        end: [f64; 3],
    },
    On {
        side: Side,
        radius: f64,
        orientation: i32,
    },
    Straight {
        rapid: bool,
        end: [f64; 3],
    },
    ArcMove {
        arc: Arc,
        end: [f64; 3],
    },
    Off,
    Stop {
        end: bool,
    },
}

struct Case {
    lines: Vec<String>,
    /// (line index, step); several steps may share a line.
    steps: Vec<(usize, Step)>,
    tools: String,
    xz: bool,
    mm: bool,
}

impl Case {
    fn units(&self) -> Units {
        if self.mm { Units::Mm } else { Units::Inch }
    }

    fn text(&self) -> String {
        let mut s = self.lines.join("\n");
        s.push('\n');
        s
    }
}

/// A number with `d` decimals, as written and as read back.
fn num(v: f64, d: usize) -> (String, f64) {
    let s = format!("{v:.d$}");
    let s = if s
        .trim_start_matches('-')
        .trim_start_matches(['0', '.'])
        .is_empty()
    {
        format!("{:.d$}", 0.0)
    } else {
        s
    };
    let back = s.parse().unwrap_or(0.0);
    (s, back)
}

struct Gen {
    rng: Rng,
    xz: bool,
    lines: Vec<String>,
    steps: Vec<(usize, Step)>,
    /// Programmed position (plane coordinates).
    pos: [f64; 3],
    n: usize,
}

impl Gen {
    fn line(&mut self, text: String) -> usize {
        self.n += 1;
        self.lines.push(format!("N{} {text}", self.n * 10));
        self.lines.len() - 1
    }

    /// Axis words for a point in plane coordinates (4 decimals), and the
    /// point as read back.
    fn axes(&self, p: [f64; 3]) -> (String, [f64; 3]) {
        let (a, av) = num(p[0], 4);
        let (b, bv) = num(p[1], 4);
        let (c, cv) = num(p[2], 4);
        let s = if self.xz {
            format!("X{b} Y{c} Z{a}")
        } else {
            format!("X{a} Y{b} Z{c}")
        };
        (s, [av, bv, cv])
    }

    fn straight(&mut self, g: &str, to: [f64; 3], comp: bool) {
        let (w, p) = self.axes(to);
        let l = self.line(format!("{g} {w}"));
        let rapid = g == "G0";
        let step = if comp {
            Step::Straight { rapid, end: p }
        } else {
            Step::Plain { rapid, end: p }
        };
        self.steps.push((l, step));
        self.pos = p;
    }

    /// An arc from the current position to `to` with a centre on the
    /// bisector at `k` half-chords from the middle (or an R word).
    fn arc(&mut self, to: [f64; 3], k: f64, ccw: bool, prefix: &str) {
        let (w, p) = self.axes(to);
        let s = self.pos;
        let mid = [(s[0] + p[0]) / 2.0, (s[1] + p[1]) / 2.0];
        let half = [(p[0] - s[0]) / 2.0, (p[1] - s[1]) / 2.0];
        // Perpendicular to the chord (left of it).
        let c = [mid[0] - half[1] * k, mid[1] + half[0] * k];
        let g = if ccw { "G3" } else { "G2" };
        let turns = if self.rng.chance(0.03) { 2 } else { 1 };
        let pw = if turns > 1 { " P2" } else { "" };
        let (center, words) = if self.rng.chance(0.35) {
            let r = (half[0].hypot(half[1])) * (1.0 + k * k).sqrt();
            // The arc is more than half a circle when the centre is on the
            // side it turns away from.
            let big = (k > 0.0) != ccw;
            let (rs, rv) = num(if big { -r } else { r }, 6);
            (ArcCenter::Radius(rv), format!("R{rs}"))
        } else {
            let (i, iv) = num(c[0] - s[0], 6);
            let (j, jv) = num(c[1] - s[1], 6);
            let words = if self.xz {
                format!("I{j} K{i}")
            } else {
                format!("I{i} J{j}")
            };
            (
                ArcCenter::Offsets {
                    i: iv,
                    j: jv,
                    distance: ArcDistance::Incremental,
                },
                words,
            )
        };
        let l = self.line(format!("{prefix}{g} {w} {words}{pw}"));
        self.steps.push((
            l,
            Step::ArcMove {
                arc: Arc { ccw, center, turns },
                end: p,
            },
        ));
        self.pos = p;
    }

    /// The tool: in the table (and loaded) or as G41.1/G42.1's D word, its
    /// side, radius and orientation, and the words that turn compensation on.
    fn tool(&mut self, xz: bool, mm: bool, scale: f64) -> ToolSetup {
        let g = self;
        let rel = match g.rng.below(4) {
            0 => g.rng.float(0.01, 0.05),
            1 => g.rng.float(0.05, 0.2),
            2 => g.rng.float(0.2, 0.5),
            _ => g.rng.float(0.4, 0.9),
        };
        let tool_r_prog = rel * scale;
        let mut tools = String::new();
        let orientation = if xz && g.rng.chance(0.6) {
            g.rng.below(10) as i32
        } else {
            0
        };
        let negative = g.rng.chance(0.08);
        let side = if g.rng.chance(0.5) {
            Side::Left
        } else {
            Side::Right
        };
        let gside = if side == Side::Left { "G41" } else { "G42" };
        let use_d = g.rng.chance(0.3);
        let radius;
        let on_line;
        if use_d {
            let (d, dv) = num(
                if negative {
                    -2.0 * tool_r_prog
                } else {
                    2.0 * tool_r_prog
                },
                4,
            );
            radius = dv / 2.0;
            let lw = if xz && orientation != 0 {
                format!(" L{orientation}")
            } else {
                String::new()
            };
            on_line = format!("{gside}.1 D{d}{lw}");
        } else {
            let inch = tool_r_prog * 2.0 / if mm { 25.4 } else { 1.0 };
            let (d, dv) = num(if negative { -inch } else { inch }, 4);
            tools.push_str(&format!("T1 P1 D{d} Q{orientation}\n"));
            // As the reference converts it: through millimetres.
            let mm_len = dv / 0.03937007874016;
            radius = if mm { mm_len } else { mm_len / 25.4 } / 2.0;
            g.line("T1 M6".to_string());
            on_line = if g.rng.chance(0.5) {
                format!("{gside} D1")
            } else {
                gside.to_string()
            };
        }
        let orientation = if use_d && !(xz && orientation != 0) {
            0
        } else {
            orientation
        };
        ToolSetup {
            tools,
            side,
            radius,
            on_line,
            orientation,
        }
    }

    /// Contour: vertices around a centre, some pulled in (inside corners);
    /// a closed one comes back to its first vertex (and maybe its second).
    fn contour(&mut self, scale: f64) -> Vec<[f64; 2]> {
        let g = self;
        let n = 2 + g.rng.below(7);
        let closed = g.rng.chance(0.6);
        let center = [
            g.rng.float(-1.0, 1.0) * scale,
            g.rng.float(-1.0, 1.0) * scale,
        ];
        let size = g.rng.float(0.3, 2.0) * scale;
        let dir = if g.rng.chance(0.5) { 1.0 } else { -1.0 };
        let mut verts = Vec::new();
        let mut ang = g.rng.float(0.0, std::f64::consts::TAU);
        for _ in 0..n {
            let r = size
                * if g.rng.chance(0.3) {
                    g.rng.float(0.2, 0.6)
                } else {
                    g.rng.float(0.8, 1.2)
                };
            verts.push([center[0] + r * ang.cos(), center[1] + r * ang.sin()]);
            ang += dir * std::f64::consts::TAU / n as f64 * g.rng.float(0.5, 1.3);
        }
        if closed {
            let v0 = verts[0];
            verts.push(v0);
            if g.rng.chance(0.3) {
                let v1 = verts[1];
                verts.push(v1);
            }
        }
        verts
    }

    /// The moves along the contour after the entry: lines and arcs, now
    /// and then a move off the plane or an optional stop.
    fn contour_moves(&mut self, verts: &[[f64; 2]], scale: f64) {
        let g = self;
        for v in verts {
            let to = [v[0], v[1], g.pos[2]];
            let roll = g.rng.unit();
            if roll < 0.06 {
                // A move off the plane.
                let dz = g.rng.float(-0.2, 0.2) * scale;
                let gm = if g.rng.chance(0.5) { "G0" } else { "G1" };
                let p = [g.pos[0], g.pos[1], g.pos[2] + dz];
                g.straight(gm, p, true);
            } else if roll < 0.08 {
                let l = g.line("M1".to_string());
                g.steps.push((l, Step::Stop { end: false }));
            }
            if g.rng.chance(0.45) {
                let k = match g.rng.below(4) {
                    0 => g.rng.float(-0.3, 0.3),
                    1 => g.rng.float(-3.0, 3.0),
                    _ => g.rng.float(-1.2, 1.2),
                };
                let ccw = g.rng.chance(0.5);
                g.arc(to, k, ccw, "");
            } else {
                let gm = if g.rng.chance(0.1) { "G0" } else { "G1" };
                g.straight(gm, to, true);
            }
        }
    }

    /// Leaves the contour: M2 with compensation on, G40 alone then a move,
    /// or G40 on a move's line.
    fn leave(&mut self, scale: f64) {
        let g = self;
        match g.rng.below(5) {
            0 => {
                // M2 with compensation still on.
            }
            1 => {
                let l = g.line("G40".to_string());
                g.steps.push((l, Step::Off));
                if g.rng.chance(0.2) {
                    let to = [g.pos[0] + scale, g.pos[1] + scale, g.pos[2]];
                    g.arc(to, 0.5, true, "");
                } else {
                    let to = [g.pos[0] + scale, g.pos[1], g.pos[2] + scale];
                    g.straight("G0", to, false);
                }
            }
            _ => {
                let to = [
                    g.pos[0] + g.rng.float(-1.0, 1.0) * scale,
                    g.pos[1] + g.rng.float(-1.0, 1.0) * scale,
                    g.pos[2],
                ];
                let (w, p) = g.axes(to);
                let l = g.line(format!("G40 G1 {w}"));
                g.steps.push((l, Step::Off));
                g.steps.push((
                    l,
                    Step::Plain {
                        rapid: false,
                        end: p,
                    },
                ));
                g.pos = p;
            }
        }
    }
}

/// What `Gen::tool` chose.
struct ToolSetup {
    tools: String,
    side: Side,
    radius: f64,
    on_line: String,
    orientation: i32,
}

fn generate(seed: u64) -> Case {
    let mut rng = Rng::new(seed);
    let xz = rng.chance(0.3);
    let mm = rng.chance(0.6);
    let scale = if mm { 20.0 } else { 1.0 };
    let mut g = Gen {
        rng,
        xz,
        lines: Vec::new(),
        steps: Vec::new(),
        pos: [0.0; 3],
        n: 0,
    };
    let units = if mm { "G21" } else { "G20" };
    let plane = if xz { "G18" } else { "G17" };
    g.line(format!("{units} {plane} G90 G94 F100"));
    // Tool: diameter in inches in the table.
    let ToolSetup {
        tools,
        side,
        radius,
        on_line,
        orientation,
    } = g.tool(xz, mm, scale);
    // Start position.
    let start = [
        g.rng.float(-2.0, 2.0) * scale,
        g.rng.float(-2.0, 2.0) * scale,
        g.rng.float(0.0, 0.5) * scale,
    ];
    g.straight("G0", start, false);
    // Contour: vertices around a centre, some pulled in (inside corners).
    let mut verts = g.contour(scale);
    let z = start[2];
    // Compensation on: alone, or on the entry move's line.
    let together = g.rng.chance(0.4);
    let prefix = if together {
        format!("{on_line} ")
    } else {
        let l = g.line(on_line);
        g.steps.push((
            l,
            Step::On {
                side,
                radius,
                orientation,
            },
        ));
        String::new()
    };
    let on_step = Step::On {
        side,
        radius,
        orientation,
    };
    let mut first_target = verts[0];
    if g.rng.chance(0.1) {
        // An entry move close to the tool radius.
        let d = radius * g.rng.float(0.8, 1.3);
        let a = g.rng.float(0.0, std::f64::consts::TAU);
        first_target = [g.pos[0] + d * a.cos(), g.pos[1] + d * a.sin()];
        verts[0] = first_target;
    }
    let entry_arc = g.rng.chance(0.15);
    let entry_rapid = !entry_arc && g.rng.chance(0.15);
    let to = [first_target[0], first_target[1], z];
    if together {
        let idx_before = g.steps.len();
        if entry_arc {
            let k = g.rng.float(-2.0, 2.0);
            let ccw = g.rng.chance(0.5);
            g.arc(to, k, ccw, &prefix);
        } else {
            let (w, p) = g.axes(to);
            let gm = if entry_rapid { "G0" } else { "G1" };
            let l = g.line(format!("{prefix}{gm} {w}"));
            g.steps.push((
                l,
                Step::Straight {
                    rapid: entry_rapid,
                    end: p,
                },
            ));
            g.pos = p;
        }
        let l = g.steps[idx_before].0;
        g.steps.insert(idx_before, (l, on_step));
    } else if entry_arc {
        let k = g.rng.float(-2.0, 2.0);
        let ccw = g.rng.chance(0.5);
        g.arc(to, k, ccw, "");
    } else {
        g.straight(if entry_rapid { "G0" } else { "G1" }, to, true);
    }
    g.contour_moves(&verts[1..], scale);
    // Leave.
    g.leave(scale);
    let l = g.line("M2".to_string());
    g.steps.push((l, Step::Stop { end: true }));
    Case {
        lines: g.lines,
        steps: g.steps,
        tools,
        xz,
        mm,
    }
}

/// The model's moves as canon text, and the line of its error.
fn model(case: &Case) -> (Vec<String>, Option<(usize, CompError)>) {
    let (err, out) = model_moves(case);
    (canon(case, &out), err)
}

/// The moves the model releases (up to an error), and the error's line.
#[allow(clippy::type_complexity)]
fn model_moves(case: &Case) -> (Option<(usize, CompError)>, Vec<Out<usize>>) {
    let mut comp: Comp<usize> = Comp::new(Tolerances::default_for(case.units()));
    let mut out: Vec<Out<usize>> = Vec::new();
    let mut pos = [0.0f64; 3];
    let mut straight_next = false;
    let mut err = None;
    for (line, step) in &case.steps {
        let r = match step {
            Step::Plain { rapid, end } => {
                out.push(Out::Line {
                    rapid: *rapid,
                    end: *end,
                    tag: *line,
                });
                pos = *end;
                straight_next = false;
                Ok(())
            }
            Step::On {
                side,
                radius,
                orientation,
            } => {
                comp.start(*side, *radius, *orientation, case.xz, pos);
                Ok(())
            }
            Step::Straight { rapid, end } => {
                straight_next = false;
                comp.straight(*rapid, *end, *line, &mut out)
            }
            Step::ArcMove { arc, end } => {
                if straight_next {
                    // The reference refuses an arc right after G40; the
                    // evaluator reports it (not the geometry).
                    err = Some((*line, CompError::ArcSamePoint)); // stands for "arc after G40"
                    break;
                }
                if comp.is_on() {
                    comp.arc(*arc, *end, *line, &mut out)
                } else {
                    let c = Comp::<usize>::new(Tolerances::default_for(case.units()));
                    let mut c = c;
                    c.start(Side::Left, 0.0, 0, case.xz, pos);
                    c.arc(*arc, *end, *line, &mut out)
                }
            }
            Step::Off => comp.off(&mut out).map(|s| {
                straight_next = s;
                pos = comp.programmed();
            }),
            Step::Stop { end } => comp.stop(*end, &mut out),
        };
        if let Err(e) = r {
            err = Some((*line, e));
            break;
        }
        if comp.is_on() && !comp.is_first() {
            pos = comp.programmed();
        } else if comp.is_on() {
            pos = comp.current();
        }
    }
    (err, out)
}

fn canon(case: &Case, out: &[Out<usize>]) -> Vec<String> {
    let f = |v: f64| format!("{v:.6}");
    out.iter()
        .map(|o| match o {
            Out::Line { rapid, end, .. } => {
                let name = if *rapid {
                    "STRAIGHT_TRAVERSE"
                } else {
                    "STRAIGHT_FEED"
                };
                let [x, y, z] = if case.xz {
                    [end[1], end[2], end[0]]
                } else {
                    *end
                };
                format!("{name}({}, {}, {}, 0, 0, 0)", f(x), f(y), f(z))
            }
            Out::Arc {
                end,
                center,
                turn,
                end3,
                ..
            } => format!(
                "ARC_FEED({}, {}, {}, {}, {turn}, {}, 0, 0, 0)",
                f(end[0]),
                f(end[1]),
                f(center[0]),
                f(center[1]),
                f(*end3)
            ),
        })
        .collect()
}

fn motion(lines: &[String]) -> Vec<String> {
    lines
        .iter()
        .filter(|l| {
            l.starts_with("STRAIGHT_FEED(")
                || l.starts_with("STRAIGHT_TRAVERSE(")
                || l.starts_with("ARC_FEED(")
        })
        .cloned()
        .collect()
}

/// The program line rs274 names in its error (stderr: `executing`, the
/// message, the line).
fn error_line(case: &Case, stderr: &str) -> Option<usize> {
    // The message may span lines: the offending line is the last one that
    // is a program line.
    stderr
        .lines()
        .rev()
        .find_map(|t| case.lines.iter().position(|l| l.trim() == t.trim()))
}

enum Verdict {
    /// `refused`: rs274's first message line when it refuses the program;
    /// `lowered`: the path for controllers without compensation was
    /// written and compared.
    Agree {
        refused: Option<String>,
        lowered: bool,
    },
    Differ(String),
}

fn check(case: &Case) -> Verdict {
    let text = case.text();
    let tools = if case.tools.is_empty() {
        "T99 P99 D0\n".to_string()
    } else {
        case.tools.clone()
    };
    let run = oracle::run_with(text.as_bytes(), "", None, Some(&tools));
    let theirs = motion(&run.lines);
    let (mine, err) = model(case);
    let rs_err = if run.ok {
        None
    } else {
        Some(error_line(case, &run.stderr))
    };
    match (&rs_err, &err) {
        (None, None) => {}
        (Some(l), Some((ml, e))) => {
            if *l != Some(*ml) {
                return Verdict::Differ(format!(
                    "rs274 refuses line {:?} ({}), the model line {} ({e})",
                    l.map(|i| i + 1),
                    run.stderr.trim(),
                    ml + 1
                ));
            }
        }
        (Some(_), None) => {
            return Verdict::Differ(format!(
                "rs274 refuses ({}), the model accepts",
                run.stderr.trim()
            ));
        }
        (None, Some((ml, e))) => {
            return Verdict::Differ(format!(
                "rs274 accepts, the model refuses line {} ({e})",
                ml + 1
            ));
        }
    }
    if let Err(d) = oracle::compare(&theirs, &mine, 1.01e-4) {
        return Verdict::Differ(format!("moves differ: {d}"));
    }
    // ngcflat itself: refused at the same line, or accepted.
    let dir = crate::tmp();
    crate::put(dir.path(), "prog.ngc", &text);
    crate::put(dir.path(), "tools.tbl", &tools);
    let (code, _, stderr) = crate::run(
        dir.path(),
        &[
            "check",
            "--zero-start",
            "--tool-table",
            "tools.tbl",
            "--message-format",
            "short",
            "prog.ngc",
        ],
    );
    let flat_line = stderr.lines().find_map(|l| {
        l.strip_prefix("prog.ngc:")?
            .split(':')
            .next()?
            .parse::<usize>()
            .ok()
    });
    match (rs_err, code) {
        (None, 0) => {}
        (Some(l), 1) if l.map(|i| i + 1) == flat_line => {}
        (r, _) => {
            return Verdict::Differ(format!(
                "rs274 {} but ngcflat check exits {code}: {stderr}",
                match r {
                    None => "accepts".to_string(),
                    Some(l) => format!("refuses line {:?}", l.map(|i| i + 1)),
                }
            ));
        }
    }
    let mut lowered = false;
    if rs_err.is_none() {
        match lowered_matches(case, &theirs) {
            Ok(l) => lowered = l,
            Err(d) => return Verdict::Differ(format!("the lowered path differs: {d}")),
        }
    }
    let refused = rs_err.map(|_| {
        let m = run
            .stderr
            .lines()
            .find(|l| *l != "executing")
            .unwrap_or("")
            .to_string();
        // The arc messages carry numbers: keep their words.
        m.split(':').next().unwrap_or("").to_string()
    });
    Verdict::Agree { refused, lowered }
}

/// The path written for a controller without compensation (the model's
/// moves through the target lowering), run through rs274: the same moves as
/// the original's, arcs possibly in several parts around the same centre.
fn lowered_matches(case: &Case, original: &[String]) -> Result<bool, String> {
    use ngcflat::block::Plane;
    use ngcflat::controller::lower::cutter_moves::lower_comp_moves;
    let (_, out) = model_moves(case);
    let plane = if case.xz { Plane::XZ } else { Plane::XY };
    let tolerance = ngcflat::controller::lower::cutter_moves::arc_radius_tolerance(case.units());
    let lines = match lower_comp_moves(plane, [0.0; 3], &out, tolerance) {
        Ok((lines, _)) => lines,
        // An arc released off its circle (a stop in a concave corner):
        // refused for controllers without compensation.
        Err(ngcflat::controller::lower::LowerError::BadArc) => return Ok(false),
        Err(e) => return Err(e.to_string()),
    };
    let header = case.lines[0].split_once(' ').map_or("", |x| x.1);
    let mut text = format!("{header}\n");
    for (l, _) in &lines {
        let words: Vec<String> = l
            .words
            .iter()
            .map(|w| format!("{}{:.10}", w.letter as char, w.value))
            .collect();
        text.push_str(&words.join(" "));
        text.push('\n');
    }
    text.push_str("M2\n");
    let run = oracle::run_with(text.as_bytes(), "", None, None);
    if !run.ok {
        return Err(format!("rs274 refuses it: {}\n{text}", run.stderr.trim()));
    }
    let lowered = motion(&run.lines);
    let parse = |l: &str| -> (String, Vec<f64>) {
        let (name, rest) = l.split_once('(').unwrap_or((l, ""));
        let nums = rest
            .trim_end_matches(')')
            .split(',')
            .filter_map(|n| n.trim().parse().ok())
            .collect();
        (name.to_string(), nums)
    };
    let close = |a: &[f64], b: &[f64]| {
        a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() <= 2e-4)
    };
    let mut j = 0;
    for (i, a) in original.iter().enumerate() {
        let (na, va) = parse(a);
        let fail = |why: &str| Err(format!("move {}: `{a}` {why}\n{text}", i + 1));
        if na != "ARC_FEED" {
            let Some(b) = lowered.get(j) else {
                return fail("missing");
            };
            let (nb, vb) = parse(b);
            if nb != na || !close(&va, &vb) {
                return fail(&format!("vs `{b}`"));
            }
            j += 1;
            continue;
        }
        // Parts around the same centre, in the same direction, up to the
        // same end.
        loop {
            let Some(b) = lowered.get(j) else {
                return fail("missing");
            };
            let (nb, vb) = parse(b);
            j += 1;
            if nb != "ARC_FEED" || vb.len() < 6 || va.len() < 6 {
                return fail(&format!("vs `{b}`"));
            }
            if !close(&va[2..4], &vb[2..4]) || (va[4] > 0.0) != (vb[4] > 0.0) {
                return fail(&format!("vs part `{b}`"));
            }
            if close(&va[0..2], &vb[0..2]) && close(&va[5..6], &vb[5..6]) {
                break;
            }
        }
    }
    if j != lowered.len() {
        return Err(format!("extra moves from {}\n{text}", j + 1));
    }
    Ok(true)
}

#[test]
fn comp_generator_is_deterministic() {
    for seed in 0..100 {
        assert_eq!(generate(seed).text(), generate(seed).text());
        let c = generate(seed);
        assert!(c.steps.iter().any(|s| matches!(s.1, Step::On { .. })));
    }
}

#[test]
fn generated_comp_programs_match_rs274() {
    if !oracle::available("generated_comp_programs_match_rs274") {
        return;
    }
    let seeds = oracle::suite_seeds("NGCFLAT_COMP", 300);
    let (cases, start) = (seeds.end - seeds.start, seeds.start);
    let results = oracle::on_threads(seeds, 1, |seed| {
        let case = generate(seed);
        match check(&case) {
            Verdict::Agree { refused, lowered } => Ok((refused, lowered)),
            Verdict::Differ(d) => Err(format!("{}---- tools\n{}---- {d}", case.text(), case.tools)),
        }
    });
    let (mut agreed, mut refused, mut lowered) = (0, 0, 0);
    let mut messages = std::collections::BTreeMap::<String, usize>::new();
    let mut failures = Vec::new();
    for (seed, r) in results {
        match r {
            Ok((r, l)) => {
                agreed += 1;
                if let Some(m) = r {
                    refused += 1;
                    *messages.entry(m).or_default() += 1;
                }
                lowered += l as usize;
            }
            Err(d) => failures.push((seed, d)),
        }
    }
    eprintln!(
        "generated compensation programs: {cases} from seed {start}: {} agree ({} refused by both at the same line, {} paths lowered for controllers without compensation and run the same), {} differ",
        agreed,
        refused,
        lowered,
        failures.len()
    );
    for (m, n) in messages {
        eprintln!("  {n:6}  refused: {m}");
    }
    if failures.is_empty() {
        return;
    }
    let seeds: Vec<String> = failures.iter().map(|f| f.0.to_string()).collect();
    let mut report = format!(
        "{} of {cases} compensation programs differ: seeds {}\n",
        failures.len(),
        seeds.join(", ")
    );
    for (seed, d) in failures.iter().take(3) {
        report.push_str(&format!(
            "\n==== seed {seed} (NGCFLAT_COMP_SEED={seed} NGCFLAT_COMP_CASES=1)\n{d}\n"
        ));
    }
    panic!("{report}");
}
