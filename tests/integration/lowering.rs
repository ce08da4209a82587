//! The exact lowerings of `ngcflat::target::lower` against rs274: seeded
//! random programs using a construct are run through rs274 as written and
//! as lowered (the lowering functions' blocks formatted as G-code here),
//! and the machine motion of the two runs must agree: every traverse, feed,
//! dwell and spindle event in order, numbers within 1e-4, arcs by their
//! path (centre, direction, end point, helix end, total turn).
//!
//! `NGCFLAT_LOWER_CASES=N` sets the number of programs per construct,
//! `NGCFLAT_LOWER_SEED=S` the first seed.

use ngcflat::target::lower::{
    CycleBlock, CycleKind, CycleModal, CycleState, Distance, PlainLine, Plane, Retract, Spindle,
    Units,
};

use crate::oracle;

struct Rng(u64);

impl Rng {
    fn new(seed: u64) -> Self {
        Rng(seed.wrapping_mul(0x2545_F491_4F6C_DD1D) ^ 0x9E37_79B9_7F4A_7C15)
    }
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
    fn chance(&mut self, p: f64) -> bool {
        ((self.next() >> 11) as f64 / (1u64 << 53) as f64) < p
    }
    /// A value in [lo, hi] with three decimals.
    fn val(&mut self, lo: f64, hi: f64) -> f64 {
        let (lo, hi) = ((lo * 1000.0).round() as i64, (hi * 1000.0).round() as i64);
        (lo + self.below((hi - lo + 1) as usize) as i64) as f64 / 1000.0
    }
    fn pick<T: Copy>(&mut self, xs: &[T]) -> T {
        xs[self.below(xs.len())]
    }
}

fn cases() -> u64 {
    std::env::var("NGCFLAT_LOWER_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(40)
}

fn first_seed() -> u64 {
    std::env::var("NGCFLAT_LOWER_SEED")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1)
}

/// A number as G-code: shortest round-trip form, never an exponent.
fn num(v: f64) -> String {
    let v = if v == 0.0 { 0.0 } else { v };
    format!("{v}")
}

fn format_line(l: &PlainLine) -> String {
    l.words
        .iter()
        .map(|w| format!("{}{}", w.letter as char, num(w.value)))
        .collect::<Vec<_>>()
        .join(" ")
}

/// The motion-relevant canon lines of a run.
fn motion(lines: &[String]) -> Vec<String> {
    const KEEP: &[&str] = &[
        "STRAIGHT_TRAVERSE(",
        "STRAIGHT_FEED(",
        "ARC_FEED(",
        "DWELL(",
        "START_SPINDLE_",
        "STOP_SPINDLE_TURNING(",
        "ORIENT_SPINDLE(",
        "PROGRAM_STOP(",
        "SET_FEED_RATE(",
        "SET_SPINDLE_SPEED(",
    ];
    lines
        .iter()
        .filter(|l| KEEP.iter().any(|k| l.starts_with(k)))
        .cloned()
        .collect()
}

/// Runs both programs through rs274 and compares their motion.
fn compare_runs(original: &str, lowered: &str) -> Result<(), String> {
    let a = oracle::run(original.as_bytes(), "", None);
    if !a.ok {
        return Err(format!("rs274 rejected the original: {}", a.stderr));
    }
    let b = oracle::run(lowered.as_bytes(), "", None);
    if !b.ok {
        return Err(format!("rs274 rejected the lowered program: {}", b.stderr));
    }
    let (ma, mb) = (motion(&a.lines), motion(&b.lines));
    if ma.len() < 3 {
        return Err("the original made almost no motion".into());
    }
    oracle::compare(&ma, &mb, 1e-4)
}

fn report(name: &str, seed: u64, original: &str, lowered: &str, why: &str) -> String {
    format!("{name} seed {seed}: {why}\n--- original\n{original}--- lowered\n{lowered}",)
}

// ---------------------------------------------------------------- canned cycles

const KINDS: &[(CycleKind, &str)] = &[
    (CycleKind::G73, "G73"),
    (CycleKind::G81, "G81"),
    (CycleKind::G82, "G82"),
    (CycleKind::G83, "G83"),
    (CycleKind::G84, "G84"),
    (CycleKind::G85, "G85"),
    (CycleKind::G86, "G86"),
    (CycleKind::G87, "G87"),
    (CycleKind::G88, "G88"),
    (CycleKind::G89, "G89"),
];

/// One program of canned cycles, written both ways.
fn cycle_program(seed: u64) -> Result<(String, String), String> {
    let mut rng = Rng::new(seed);
    let units = if rng.chance(0.3) {
        Units::Inch
    } else {
        Units::Mm
    };
    let plane = rng.pick(&[Plane::XY, Plane::XY, Plane::XZ, Plane::YZ]);
    let (g_units, g_plane) = (
        if units == Units::Inch { "G20" } else { "G21" },
        match plane {
            Plane::XY => "G17",
            Plane::XZ => "G18",
            Plane::YZ => "G19",
        },
    );
    let spindle = if rng.chance(0.7) {
        Spindle::Cw
    } else {
        Spindle::Ccw
    };
    let m_spindle = if spindle == Spindle::Cw { "M3" } else { "M4" };
    let header = format!("{g_units} {g_plane} G90 G94 F100 S1000 {m_spindle}\n");
    let mut orig = header.clone();
    let mut low = header;
    let mut pos = [rng.val(-5.0, 5.0), rng.val(-5.0, 5.0), rng.val(-5.0, 10.0)];
    let start = format!("G0 X{} Y{} Z{}\n", num(pos[0]), num(pos[1]), num(pos[2]));
    orig.push_str(&start);
    low.push_str(&start);
    let mut state = CycleState::default();
    let mut distance = Distance::Absolute;
    let mut retract = if rng.chance(0.5) {
        Retract::OldZ
    } else {
        Retract::RPlane
    };
    orig.push_str(if retract == Retract::OldZ {
        "G98\n"
    } else {
        "G99\n"
    });
    let mut last: Option<CycleKind> = None;
    let depth_axis = match plane {
        Plane::XY => 2,
        Plane::XZ => 1,
        Plane::YZ => 0,
    };
    let letters = [b'X', b'Y', b'Z'];
    for _ in 0..(3 + rng.below(6)) {
        // Something between the cycle blocks now and then.
        match rng.below(8) {
            0 => {
                pos = [rng.val(-5.0, 5.0), rng.val(-5.0, 5.0), rng.val(-5.0, 10.0)];
                let l = format!(
                    "G90 G0 X{} Y{} Z{}\n",
                    num(pos[0]),
                    num(pos[1]),
                    num(pos[2])
                );
                orig.push_str(&l);
                low.push_str(&l);
                distance = Distance::Absolute;
                state.end();
                last = None;
            }
            1 => {
                orig.push_str("G80\n");
                state.end();
                last = None;
            }
            2 => {
                retract = if retract == Retract::OldZ {
                    Retract::RPlane
                } else {
                    Retract::OldZ
                };
                orig.push_str(if retract == Retract::OldZ {
                    "G98\n"
                } else {
                    "G99\n"
                });
            }
            3 => {
                distance = if distance == Distance::Absolute {
                    Distance::Incremental
                } else {
                    Distance::Absolute
                };
                orig.push_str(if distance == Distance::Absolute {
                    "G90\n"
                } else {
                    "G91\n"
                });
            }
            _ => {}
        }
        let (kind, code) = if last.is_some() && rng.chance(0.4) {
            let k = last.unwrap_or(CycleKind::G81);
            (
                k,
                KINDS.iter().find(|(c, _)| *c == k).map_or("G81", |x| x.1),
            )
        } else {
            rng.pick(KINDS)
        };
        // Constructs LinuxCNC runs but no target block expresses.
        if (kind == CycleKind::G84 && (plane != Plane::XY || spindle != Spindle::Cw))
            || (kind == CycleKind::G87 && spindle != Spindle::Cw)
        {
            continue;
        }
        let same = last == Some(kind);
        let mut block = CycleBlock::default();
        let mut words = vec![code.to_string()];
        let put = |words: &mut Vec<String>, letter: char, v: f64| {
            words.push(format!("{letter}{}", num(v)));
        };
        let polar = plane == Plane::XY && rng.chance(0.2);
        for (i, letter) in letters.into_iter().enumerate() {
            if i == depth_axis {
                continue;
            }
            if polar || rng.chance(0.3) {
                continue;
            }
            let v = if distance == Distance::Absolute {
                rng.val(-5.0, 5.0)
            } else {
                rng.val(-2.0, 2.0)
            };
            block.axes[i] = Some(v);
            put(&mut words, letter as char, v);
        }
        if polar {
            if rng.chance(0.7) {
                let v = if distance == Distance::Absolute {
                    rng.val(0.5, 6.0)
                } else {
                    rng.val(-1.0, 1.0)
                };
                block.radius = Some(v);
                words.push(format!("@{}", num(v)));
            }
            if rng.chance(0.7) {
                let v = rng.val(-180.0, 180.0);
                block.angle = Some(v);
                words.push(format!("^{}", num(v)));
            }
        }
        let (r, depth) = if distance == Distance::Absolute {
            let r = rng.val(-3.0, 6.0);
            (r, r - rng.val(0.0, 4.0))
        } else {
            (rng.val(-4.0, 3.0), -rng.val(0.0, 4.0))
        };
        if !same || rng.chance(0.6) {
            block.r = Some(r);
            put(&mut words, 'R', r);
        }
        let no_axis = block.axes.iter().all(Option::is_none)
            && block.radius.is_none()
            && block.angle.is_none();
        if !same || no_axis || rng.chance(0.6) {
            block.axes[depth_axis] = Some(depth);
            put(&mut words, letters[depth_axis] as char, depth);
        }
        if rng.chance(0.3) {
            let l = 1 + rng.below(3) as u32;
            block.l = Some(l);
            words.push(format!("L{l}"));
        }
        match kind {
            CycleKind::G82 | CycleKind::G86 | CycleKind::G88 | CycleKind::G89 | CycleKind::G84
                if (!same || rng.chance(0.5)) && (kind != CycleKind::G84 || rng.chance(0.5)) =>
            {
                let p = rng.val(0.0, 2.0);
                block.p = Some(p);
                put(&mut words, 'P', p);
            }
            CycleKind::G73 | CycleKind::G83 if !same || rng.chance(0.5) => {
                let q = rng.val(0.3, 2.5);
                block.q = Some(q);
                put(&mut words, 'Q', q);
            }
            CycleKind::G87 if !same || rng.chance(0.5) => {
                for (n, letter) in ['I', 'J', 'K'].into_iter().enumerate() {
                    // The back-bore level: between the depth and R.
                    let v = if n == 2 - depth_axis_slot(plane) {
                        if distance == Distance::Absolute {
                            depth + 0.5
                        } else {
                            0.5
                        }
                    } else {
                        rng.val(-1.0, 1.0)
                    };
                    block.ijk[n] = Some(v);
                    put(&mut words, letter, v);
                }
            }
            _ => {}
        }
        let line = words.join(" ");
        let modal = CycleModal {
            plane,
            distance,
            units,
            retract,
            spindle,
        };
        let out = match state.lower(kind, &block, &modal, pos.map(Some)) {
            Ok(out) => out,
            Err(e) => {
                // Refused: LinuxCNC must refuse the block too. The block
                // is left out of both programs.
                let probe = format!("{orig}{line}\nM2\n");
                if oracle::run(probe.as_bytes(), "", None).ok {
                    return Err(format!(
                        "lowering `{line}` failed ({e}) but rs274 runs it\n{probe}"
                    ));
                }
                continue;
            }
        };
        orig.push_str(&line);
        orig.push('\n');
        low.push_str(&format!("({line})\n"));
        for l in &out.lines {
            low.push_str(&format_line(l));
            low.push('\n');
        }
        pos = out.end;
        last = Some(kind);
    }
    orig.push_str("G80\nM2\n");
    low.push_str("M2\n");
    Ok((orig, low))
}

/// Which of I/J/K (0, 1, 2) is the G87 back-bore level, counted from K.
fn depth_axis_slot(plane: Plane) -> usize {
    match plane {
        Plane::XY => 0, // K
        Plane::XZ => 1, // J
        Plane::YZ => 2, // I
    }
}

#[test]
fn canned_cycles_move_as_rs274() {
    if !oracle::available("canned_cycles_move_as_rs274") {
        return;
    }
    let seed0 = first_seed();
    let mut failures = Vec::new();
    for seed in seed0..seed0 + cases() {
        let (orig, low) = match cycle_program(seed) {
            Ok(p) => p,
            Err(e) => {
                failures.push(format!("cycles seed {seed}: {e}"));
                continue;
            }
        };
        if let Err(why) = compare_runs(&orig, &low) {
            failures.push(report("cycles", seed, &orig, &low, &why));
        }
        if failures.len() >= 3 {
            break;
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

// ---------------------------------------------------------------- arcs

/// A canon motion line: its name and numbers.
fn parse_canon(line: &str) -> (String, Vec<f64>) {
    let name = line.split('(').next().unwrap_or("").to_string();
    let (_, nums) = oracle::split_numbers(line);
    (name, nums)
}

/// In-plane axes (first, second) and normal, as indices into X Y Z, in
/// the canon's ARC_FEED order.
fn arc_axes(plane: Plane) -> [usize; 3] {
    match plane {
        Plane::XY => [0, 1, 2],
        Plane::XZ => [2, 0, 1],
        Plane::YZ => [1, 2, 0],
    }
}

struct CanonArc {
    centre: [f64; 2],
    rotation: f64,
    end: [f64; 3],
}

fn canon_arc(nums: &[f64], plane: Plane) -> Option<CanonArc> {
    let [p, q, n] = arc_axes(plane);
    let mut end = [0.0; 3];
    end[p] = *nums.first()?;
    end[q] = *nums.get(1)?;
    end[n] = *nums.get(5)?;
    Some(CanonArc {
        centre: [*nums.get(2)?, *nums.get(3)?],
        rotation: *nums.get(4)?,
        end,
    })
}

/// Angle turned by a canon arc from `from` (positive).
fn canon_sweep(from: [f64; 3], arc: &CanonArc, plane: Plane) -> f64 {
    use std::f64::consts::PI;
    let [p, q, _] = arc_axes(plane);
    let a0 = (from[q] - arc.centre[1]).atan2(from[p] - arc.centre[0]);
    let a1 = (arc.end[q] - arc.centre[1]).atan2(arc.end[p] - arc.centre[0]);
    let same = (from[p] - arc.end[p]).abs() < 1e-9 && (from[q] - arc.end[q]).abs() < 1e-9;
    let mut base = if arc.rotation < 0.0 { a0 - a1 } else { a1 - a0 };
    if same {
        base = 2.0 * PI;
    } else {
        while base <= 0.0 {
            base += 2.0 * PI;
        }
        while base > 2.0 * PI {
            base -= 2.0 * PI;
        }
    }
    base + 2.0 * PI * (arc.rotation.abs() - 1.0)
}

/// Compares motion where the lowered program may cut an arc into several
/// on the same helix: every other line as text (numbers within 1e-4), an
/// arc of the original against a run of lowered arcs with the same centre
/// and direction, each ending on the original helix at its angle, their
/// turns adding up to the original's and the last ending at its end.
fn compare_with_arcs(a: &[String], b: &[String], plane: Plane) -> Result<(), String> {
    let [p, q, n] = arc_axes(plane);
    let (mut pa, mut pb) = ([0.0; 3], [0.0; 3]);
    let mut j = 0;
    let end_of = |name: &str, nums: &[f64]| -> Option<[f64; 3]> {
        if name.starts_with("STRAIGHT_") {
            Some([*nums.first()?, *nums.get(1)?, *nums.get(2)?])
        } else if name == "ARC_FEED" {
            canon_arc(nums, plane).map(|a| a.end)
        } else {
            None
        }
    };
    for (i, la) in a.iter().enumerate() {
        let (name, nums) = parse_canon(la);
        if name != "ARC_FEED" {
            let lb = b
                .get(j)
                .ok_or_else(|| format!("line {}: `{la}` missing from the lowered run", i + 1))?;
            oracle::compare(std::slice::from_ref(la), std::slice::from_ref(lb), 1e-4)
                .map_err(|e| format!("original line {}: {e}", i + 1))?;
            if let Some(e) = end_of(&name, &nums) {
                pa = e;
                pb = e;
            }
            j += 1;
            continue;
        }
        let arc = canon_arc(&nums, plane).ok_or("bad ARC_FEED")?;
        let total = canon_sweep(pa, &arc, plane);
        let radius = (pa[q] - arc.centre[1]).hypot(pa[p] - arc.centre[0]);
        let a0 = (pa[q] - arc.centre[1]).atan2(pa[p] - arc.centre[0]);
        let dir = arc.rotation.signum();
        let mut acc = 0.0;
        let mut parts = 0;
        while acc < total - 1e-3 {
            let lb = b.get(j).ok_or_else(|| {
                format!("original line {}: lowered run ends inside `{la}`", i + 1)
            })?;
            let (nb, numsb) = parse_canon(lb);
            let piece = (nb == "ARC_FEED")
                .then(|| canon_arc(&numsb, plane))
                .flatten()
                .ok_or_else(|| format!("original line {}: `{la}` vs lowered `{lb}`", i + 1))?;
            if (piece.centre[0] - arc.centre[0]).abs() > 1e-4
                || (piece.centre[1] - arc.centre[1]).abs() > 1e-4
                || piece.rotation.signum() != dir
            {
                return Err(format!(
                    "original line {}: `{la}`: lowered arc `{lb}` has another centre or direction",
                    i + 1
                ));
            }
            acc += canon_sweep(pb, &piece, plane);
            let angle = a0 + dir * acc;
            let want_p = arc.centre[0] + radius * angle.cos();
            let want_q = arc.centre[1] + radius * angle.sin();
            let want_n = pa[n] + (arc.end[n] - pa[n]) * (acc / total).min(1.0);
            let e = piece.end;
            if (e[p] - want_p).abs() > 3e-4
                || (e[q] - want_q).abs() > 3e-4
                || (e[n] - want_n).abs() > 3e-4
            {
                return Err(format!(
                    "original line {}: `{la}`: lowered arc `{lb}` leaves the helix \
                     (at {acc} rad of {total}: want {want_p} {want_q} {want_n})",
                    i + 1
                ));
            }
            pb = e;
            j += 1;
            parts += 1;
        }
        if (acc - total).abs() > 1e-3
            || (0..3).any(|k| (pb[k] - arc.end[k]).abs() > 1e-4)
            || parts == 0
        {
            return Err(format!(
                "original line {}: `{la}` turns {total} rad, the lowered arcs {acc} ending at {pb:?}",
                i + 1
            ));
        }
        pa = arc.end;
    }
    if j != b.len() {
        return Err(format!("the lowered run has extra lines from `{}`", b[j]));
    }
    Ok(())
}

fn plane_code(plane: Plane) -> &'static str {
    match plane {
        Plane::XY => "G17",
        Plane::XZ => "G18",
        Plane::YZ => "G19",
    }
}

/// Full circles without end point and P-turn arcs, written both ways.
fn arc_program(seed: u64) -> (String, String, Plane) {
    use ngcflat::target::lower::arc::{ArcInput, lower_arc};
    let mut rng = Rng::new(seed);
    let plane = rng.pick(&[Plane::XY, Plane::XZ, Plane::YZ]);
    let [p, q, n] = arc_axes(plane);
    let units = if rng.chance(0.3) { "G20" } else { "G21" };
    let header = format!("{units} {} G90 G94 F120\n", plane_code(plane));
    let (mut orig, mut low) = (header.clone(), header);
    let letters = ['X', 'Y', 'Z'];
    let offset_letter = ['I', 'J', 'K'];
    let mut pos = [rng.val(-5.0, 5.0), rng.val(-5.0, 5.0), rng.val(-5.0, 5.0)];
    let start = format!("G0 X{} Y{} Z{}\n", num(pos[0]), num(pos[1]), num(pos[2]));
    orig.push_str(&start);
    low.push_str(&start);
    for _ in 0..(2 + rng.below(5)) {
        if rng.chance(0.3) {
            pos = [rng.val(-5.0, 5.0), rng.val(-5.0, 5.0), rng.val(-5.0, 5.0)];
            let l = format!("G1 X{} Y{} Z{}\n", num(pos[0]), num(pos[1]), num(pos[2]));
            orig.push_str(&l);
            low.push_str(&l);
        }
        let clockwise = rng.chance(0.5);
        let g = if clockwise { "G2" } else { "G3" };
        // Centre offsets, radius at least 0.5.
        let (mut op, mut oq) = (0.0f64, 0.0f64);
        while op.hypot(oq) < 0.5 {
            op = rng.val(-4.0, 4.0);
            oq = rng.val(-4.0, 4.0);
        }
        let mut centre = pos;
        centre[p] += op;
        centre[q] += oq;
        let mut end = pos;
        let mut words = vec![g.to_string()];
        let with_end = rng.chance(0.5);
        if with_end {
            let r = op.hypot(oq);
            let phi = rng.val(-3.2, 3.2);
            end[p] = centre[p] + r * phi.cos();
            end[q] = centre[q] + r * phi.sin();
            words.push(format!("{}{}", letters[p], num(end[p])));
            words.push(format!("{}{}", letters[q], num(end[q])));
        }
        if rng.chance(0.5) {
            end[n] = pos[n] + rng.val(-3.0, 3.0);
            words.push(format!("{}{}", letters[n], num(end[n])));
        }
        // Offsets written in axis order (I before J before K).
        let mut offs = [(p, op), (q, oq)];
        offs.sort_by_key(|o| o.0);
        for (axis, v) in offs {
            words.push(format!("{}{}", offset_letter[axis], num(v)));
        }
        let turns = if !with_end || rng.chance(0.7) {
            if rng.chance(0.5) || with_end {
                2 + rng.below(3) as u32
            } else {
                1
            }
        } else {
            1
        };
        if turns > 1 || rng.chance(0.2) {
            words.push(format!("P{turns}"));
        }
        let line = words.join(" ");
        orig.push_str(&line);
        orig.push('\n');
        let lowered = lower_arc(&ArcInput {
            plane,
            clockwise,
            start: pos,
            end,
            centre,
            turns,
        })
        .expect("arc lowers");
        low.push_str(&format!("({line})\n"));
        for l in &lowered {
            low.push_str(&format_line(l));
            low.push('\n');
        }
        pos = end;
    }
    orig.push_str("M2\n");
    low.push_str("M2\n");
    (orig, low, plane)
}

#[test]
fn full_circles_and_turns_move_as_rs274() {
    if !oracle::available("full_circles_and_turns_move_as_rs274") {
        return;
    }
    let seed0 = first_seed();
    let mut failures = Vec::new();
    for seed in seed0..seed0 + cases() {
        let (orig, low, plane) = arc_program(seed);
        let a = oracle::run(orig.as_bytes(), "", None);
        let b = oracle::run(low.as_bytes(), "", None);
        let why = if !a.ok {
            Some(format!("rs274 rejected the original: {}", a.stderr))
        } else if !b.ok {
            Some(format!("rs274 rejected the lowered program: {}", b.stderr))
        } else {
            compare_with_arcs(&motion(&a.lines), &motion(&b.lines), plane).err()
        };
        if let Some(why) = why {
            failures.push(report("arcs", seed, &orig, &low, &why));
        }
        if failures.len() >= 3 {
            break;
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}
