//! The exact lowerings of `ngcflat::controller::lower` against rs274: seeded
//! random programs using a construct are run through rs274 as written and
//! as lowered (the lowering functions' blocks formatted as G-code here),
//! and the machine motion of the two runs must agree: every traverse, feed,
//! dwell and spindle event in order, numbers within 1e-4, arcs by their
//! path (centre, direction, end point, helix end, total turn).
//!
//! `NGCFLAT_LOWER_CASES=N` sets the number of programs per construct,
//! `NGCFLAT_LOWER_SEED=S` the first seed.

use ngcflat::block::{Distance, Plane, Retract, SpindleDir, Units};
use ngcflat::controller::lower::{CycleBlock, CycleKind, CycleModal, CycleState, PlainLine};

use crate::oracle;
use crate::rng::Rng;

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

/// A random block of the cycle `kind` (`code`): the block as the lowering
/// reads it, and the line as written. `same`: the previous block was a
/// cycle of the same kind (its words may be left out).
fn random_cycle_block(
    rng: &mut Rng,
    kind: CycleKind,
    code: &str,
    same: bool,
    plane: Plane,
    distance: Distance,
    depth_axis: usize,
) -> (CycleBlock, String) {
    let letters = [b'X', b'Y', b'Z'];
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
            rng.milli(-5.0, 5.0)
        } else {
            rng.milli(-2.0, 2.0)
        };
        block.axes[i] = Some(v);
        put(&mut words, letter as char, v);
    }
    if polar {
        if rng.chance(0.7) {
            let v = if distance == Distance::Absolute {
                rng.milli(0.5, 6.0)
            } else {
                rng.milli(-1.0, 1.0)
            };
            block.radius = Some(v);
            words.push(format!("@{}", num(v)));
        }
        if rng.chance(0.7) {
            let v = rng.milli(-180.0, 180.0);
            block.angle = Some(v);
            words.push(format!("^{}", num(v)));
        }
    }
    let (r, depth) = if distance == Distance::Absolute {
        let r = rng.milli(-3.0, 6.0);
        (r, r - rng.milli(0.0, 4.0))
    } else {
        (rng.milli(-4.0, 3.0), -rng.milli(0.0, 4.0))
    };
    if !same || rng.chance(0.6) {
        block.r = Some(r);
        put(&mut words, 'R', r);
    }
    let no_axis =
        block.axes.iter().all(Option::is_none) && block.radius.is_none() && block.angle.is_none();
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
            let p = rng.milli(0.0, 2.0);
            block.p = Some(p);
            put(&mut words, 'P', p);
        }
        CycleKind::G73 | CycleKind::G83 if !same || rng.chance(0.5) => {
            let q = rng.milli(0.3, 2.5);
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
                    rng.milli(-1.0, 1.0)
                };
                block.ijk[n] = Some(v);
                put(&mut words, letter, v);
            }
        }
        _ => {}
    }
    (block, words.join(" "))
}

/// Something between two cycle blocks, at random: a move, G80, a change
/// of retract or distance mode (written to both programs as needed).
/// `after_cycle`: the last block was a cycle. True when it ends the cycle.
fn interlude(
    rng: &mut Rng,
    after_cycle: bool,
    pos: &mut [f64; 3],
    distance: &mut Distance,
    retract: &mut Retract,
    orig: &mut String,
    low: &mut String,
) -> bool {
    let mut ended = false;
    match rng.below(8) {
        0 => {
            *pos = [
                rng.milli(-5.0, 5.0),
                rng.milli(-5.0, 5.0),
                rng.milli(-5.0, 10.0),
            ];
            let l = format!(
                "G90 G0 X{} Y{} Z{}\n",
                num(pos[0]),
                num(pos[1]),
                num(pos[2])
            );
            orig.push_str(&l);
            low.push_str(&l);
            *distance = Distance::Absolute;
            ended = true;
        }
        1 => {
            orig.push_str("G80\n");
            ended = true;
        }
        2 => {
            *retract = if *retract == Retract::Initial {
                Retract::R
            } else {
                Retract::Initial
            };
            orig.push_str(if *retract == Retract::Initial {
                "G98\n"
            } else {
                "G99\n"
            });
        }
        4 if after_cycle => {
            // An incremental move from where LinuxCNC has the tool after
            // the cycle (written absolute in the lowered program).
            let d = [
                rng.milli(-2.0, 2.0),
                rng.milli(-2.0, 2.0),
                rng.milli(-1.0, 3.0),
            ];
            orig.push_str(&format!(
                "G91 G0 X{} Y{} Z{}\n",
                num(d[0]),
                num(d[1]),
                num(d[2])
            ));
            *pos = [pos[0] + d[0], pos[1] + d[1], pos[2] + d[2]];
            low.push_str(&format!(
                "G0 X{} Y{} Z{}\n",
                num(pos[0]),
                num(pos[1]),
                num(pos[2])
            ));
            *distance = Distance::Incremental;
            ended = true;
        }
        3 => {
            *distance = if *distance == Distance::Absolute {
                Distance::Incremental
            } else {
                Distance::Absolute
            };
            orig.push_str(if *distance == Distance::Absolute {
                "G90\n"
            } else {
                "G91\n"
            });
        }
        _ => {}
    }
    ended
}

/// One program of canned cycles, written both ways.
fn cycle_program(seed: u64) -> Result<(String, String), String> {
    let mut rng = Rng::new(seed);
    let units = if rng.chance(0.3) {
        Units::Inch
    } else {
        Units::Mm
    };
    let plane = *rng.pick(&[Plane::XY, Plane::XY, Plane::XZ, Plane::YZ]);
    let (g_units, g_plane) = (
        if units == Units::Inch { "G20" } else { "G21" },
        plane_code(plane),
    );
    let spindle = if rng.chance(0.7) {
        SpindleDir::Cw
    } else {
        SpindleDir::Ccw
    };
    let m_spindle = if spindle == SpindleDir::Cw {
        "M3"
    } else {
        "M4"
    };
    let header = format!("{g_units} {g_plane} G90 G94 F100 S1000 {m_spindle}\n");
    let mut orig = header.clone();
    let mut low = header;
    let mut pos = [
        rng.milli(-5.0, 5.0),
        rng.milli(-5.0, 5.0),
        rng.milli(-5.0, 10.0),
    ];
    let start = format!("G0 X{} Y{} Z{}\n", num(pos[0]), num(pos[1]), num(pos[2]));
    orig.push_str(&start);
    low.push_str(&start);
    let mut state = CycleState::default();
    let mut distance = Distance::Absolute;
    let mut retract = if rng.chance(0.5) {
        Retract::Initial
    } else {
        Retract::R
    };
    orig.push_str(if retract == Retract::Initial {
        "G98\n"
    } else {
        "G99\n"
    });
    let mut last: Option<CycleKind> = None;
    let depth_axis = arc_axes(plane)[2];
    for _ in 0..(3 + rng.below(6)) {
        // Something between the cycle blocks now and then.
        if interlude(
            &mut rng,
            last.is_some(),
            &mut pos,
            &mut distance,
            &mut retract,
            &mut orig,
            &mut low,
        ) {
            state.end();
            last = None;
        }
        let (kind, code) = if last.is_some() && rng.chance(0.4) {
            let k = last.unwrap_or(CycleKind::G81);
            (
                k,
                KINDS.iter().find(|(c, _)| *c == k).map_or("G81", |x| x.1),
            )
        } else {
            *rng.pick(KINDS)
        };
        // Constructs LinuxCNC runs but no target block expresses.
        if (kind == CycleKind::G84 && (plane != Plane::XY || spindle != SpindleDir::Cw))
            || (kind == CycleKind::G87 && spindle != SpindleDir::Cw)
        {
            continue;
        }
        let same = last == Some(kind);
        let (block, line) =
            random_cycle_block(&mut rng, kind, code, same, plane, distance, depth_axis);
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

/// Which of I/J/K (0, 1, 2) is the G87 back-bore level, counted from K:
/// K in G17, J in G18, I in G19.
fn depth_axis_slot(plane: Plane) -> usize {
    2 - arc_axes(plane)[2]
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
        Plane::UV | Plane::WU | Plane::VW => unreachable!("the programs here use G17-G19"),
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
        // LinuxCNC moves a spiral when the end is off the start's
        // distance from the centre: the distance is linear in the angle.
        let radius = (pa[q] - arc.centre[1]).hypot(pa[p] - arc.centre[0]);
        let spiral = (arc.end[q] - arc.centre[1]).hypot(arc.end[p] - arc.centre[0]) - radius;
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
            let r = radius + spiral * (acc / total).min(1.0);
            let want_p = arc.centre[0] + r * angle.cos();
            let want_q = arc.centre[1] + r * angle.sin();
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
        Plane::UV | Plane::WU | Plane::VW => unreachable!("the programs here use G17-G19"),
    }
}

/// Full circles without end point, P-turn arcs and spiral arcs, written
/// both ways.
fn arc_program(seed: u64) -> (String, String, Plane) {
    use ngcflat::controller::lower::arc::{ArcInput, lower_arc};
    let mut rng = Rng::new(seed);
    let plane = *rng.pick(&[Plane::XY, Plane::XZ, Plane::YZ]);
    let [p, q, n] = arc_axes(plane);
    let units = if rng.chance(0.3) { "G20" } else { "G21" };
    let header = format!("{units} {} G90 G94 F120\n", plane_code(plane));
    let (mut orig, mut low) = (header.clone(), header);
    let letters = ['X', 'Y', 'Z'];
    let offset_letter = ['I', 'J', 'K'];
    let mut pos = [
        rng.milli(-5.0, 5.0),
        rng.milli(-5.0, 5.0),
        rng.milli(-5.0, 5.0),
    ];
    let start = format!("G0 X{} Y{} Z{}\n", num(pos[0]), num(pos[1]), num(pos[2]));
    orig.push_str(&start);
    low.push_str(&start);
    for _ in 0..(2 + rng.below(5)) {
        if rng.chance(0.3) {
            pos = [
                rng.milli(-5.0, 5.0),
                rng.milli(-5.0, 5.0),
                rng.milli(-5.0, 5.0),
            ];
            let l = format!("G1 X{} Y{} Z{}\n", num(pos[0]), num(pos[1]), num(pos[2]));
            orig.push_str(&l);
            low.push_str(&l);
        }
        let clockwise = rng.chance(0.5);
        let g = if clockwise { "G2" } else { "G3" };
        // Centre offsets, radius at least 0.5.
        let (mut op, mut oq) = (0.0f64, 0.0f64);
        while op.hypot(oq) < 0.5 {
            op = rng.milli(-4.0, 4.0);
            oq = rng.milli(-4.0, 4.0);
        }
        let mut centre = pos;
        centre[p] += op;
        centre[q] += oq;
        let mut end = pos;
        let mut words = vec![g.to_string()];
        let with_end = rng.chance(0.5);
        if with_end {
            // Some arcs end a little off the start's distance from the
            // centre (within LinuxCNC's tolerance): a spiral.
            let spiral = if rng.chance(0.3) {
                rng.milli(-0.015, 0.015) / if units == "G20" { 25.4 } else { 1.0 }
            } else {
                0.0
            };
            let r = op.hypot(oq) + spiral;
            let phi = rng.milli(-3.2, 3.2);
            end[p] = centre[p] + r * phi.cos();
            end[q] = centre[q] + r * phi.sin();
            words.push(format!("{}{}", letters[p], num(end[p])));
            words.push(format!("{}{}", letters[q], num(end[q])));
        }
        if rng.chance(0.5) {
            end[n] = pos[n] + rng.milli(-3.0, 3.0);
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
            radius_step: 0.004 / if units == "G20" { 25.4 } else { 1.0 },
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

// ---------------------------------------------------------------- polar words

/// G0/G1 moves with `@`/`^` in G90 and G91, written both ways (the lowered
/// program in absolute X Y).
fn polar_program(seed: u64) -> Result<(String, String), String> {
    use ngcflat::controller::lower::polar::{PolarInput, polar_target};
    let mut rng = Rng::new(seed);
    let header = "G21 G17 G90 G94 F150\n".to_string();
    let (mut orig, mut low) = (header.clone(), header);
    let mut pos = [
        rng.milli(-5.0, 5.0),
        rng.milli(-5.0, 5.0),
        rng.milli(-5.0, 5.0),
    ];
    let start = format!("G0 X{} Y{} Z{}\n", num(pos[0]), num(pos[1]), num(pos[2]));
    orig.push_str(&start);
    low.push_str(&start);
    let mut distance = Distance::Absolute;
    for _ in 0..(3 + rng.below(8)) {
        if rng.chance(0.3) {
            distance = if distance == Distance::Absolute {
                orig.push_str("G91\n");
                Distance::Incremental
            } else {
                orig.push_str("G90\n");
                Distance::Absolute
            };
        }
        if rng.chance(0.05) {
            // The origin, where incremental polar motion is undefined.
            pos = [0.0, 0.0, pos[2]];
            let l = "G90 G0 X0 Y0\n";
            orig.push_str(l);
            low.push_str(l);
            distance = Distance::Absolute;
        }
        let g = if rng.chance(0.3) { "G0" } else { "G1" };
        let mut words = vec![g.to_string()];
        let (mut radius, mut angle) = (None, None);
        if rng.chance(0.7) {
            let v = if distance == Distance::Absolute {
                rng.milli(0.0, 8.0)
            } else {
                rng.milli(-2.0, 2.0)
            };
            radius = Some(v);
            words.push(format!("@{}", num(v)));
        }
        if radius.is_none() || rng.chance(0.7) {
            let v = rng.milli(-400.0, 400.0);
            angle = Some(v);
            words.push(format!("^{}", num(v)));
        }
        let mut z = pos[2];
        if rng.chance(0.3) {
            let v = rng.milli(-3.0, 3.0);
            z = if distance == Distance::Absolute {
                v
            } else {
                pos[2] + v
            };
            words.push(format!("Z{}", num(v)));
        }
        let line = words.join(" ");
        let target = polar_target(&PolarInput {
            distance,
            current: [pos[0], pos[1]],
            radius,
            angle,
        });
        let xy = match target {
            Ok(xy) => xy,
            Err(e) => {
                let probe = format!("{orig}{line}\nM2\n");
                if oracle::run(probe.as_bytes(), "", None).ok {
                    return Err(format!("`{line}` refused ({e}) but rs274 runs it\n{probe}"));
                }
                continue;
            }
        };
        orig.push_str(&line);
        orig.push('\n');
        low.push_str(&format!(
            "{g} X{} Y{} Z{}\n",
            num(xy[0]),
            num(xy[1]),
            num(z)
        ));
        pos = [xy[0], xy[1], z];
    }
    orig.push_str("M2\n");
    low.push_str("M2\n");
    Ok((orig, low))
}

#[test]
fn polar_moves_as_rs274() {
    if !oracle::available("polar_moves_as_rs274") {
        return;
    }
    let seed0 = first_seed();
    let mut failures = Vec::new();
    for seed in seed0..seed0 + cases() {
        match polar_program(seed) {
            Err(e) => failures.push(format!("polar seed {seed}: {e}")),
            Ok((orig, low)) => {
                if let Err(why) = compare_runs(&orig, &low) {
                    failures.push(report("polar", seed, &orig, &low, &why));
                }
            }
        }
        if failures.len() >= 3 {
            break;
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

// ---------------------------------------------------------------- G7

/// Lathe programs in G7 (X words are diameters): moves and centre-format
/// arcs in G90 and G91, against the same program in G8 with its X words
/// rewritten by `radius_words`.
fn diameter_program(seed: u64) -> (String, String) {
    use ngcflat::controller::lower::Word;
    use ngcflat::controller::lower::diameter::radius_words;
    let mut rng = Rng::new(seed);
    let ijk = if rng.chance(0.3) { "G90.1" } else { "G91.1" };
    let mut orig = format!("G21 G18 G7 G90 {ijk} G94 F90\n");
    let mut low = format!("G21 G18 G8 G90 {ijk} G94 F90\n");
    // Position (radius X, Z).
    let mut pos = [rng.milli(0.0, 10.0), rng.milli(-5.0, 5.0)];
    let mut distance = Distance::Absolute;
    let mut lines: Vec<Vec<(u8, f64)>> =
        vec![vec![(b'G', 0.0), (b'X', 2.0 * pos[0]), (b'Z', pos[1])]];
    let mut modes: Vec<Option<&str>> = vec![None];
    for _ in 0..(3 + rng.below(6)) {
        let mut mode = None;
        if rng.chance(0.3) {
            distance = if distance == Distance::Absolute {
                mode = Some("G91");
                Distance::Incremental
            } else {
                mode = Some("G90");
                Distance::Absolute
            };
        }
        let (g, end, centre) = if rng.chance(0.5) {
            let g = if rng.chance(0.3) { 0.0 } else { 1.0 };
            (g, [rng.milli(0.0, 10.0), rng.milli(-5.0, 5.0)], None)
        } else {
            let (mut ox, mut oz) = (0.0f64, 0.0f64);
            while ox.hypot(oz) < 0.5 {
                ox = rng.milli(-3.0, 3.0);
                oz = rng.milli(-3.0, 3.0);
            }
            let c = [pos[0] + ox, pos[1] + oz];
            let r = ox.hypot(oz);
            let phi = rng.milli(-3.2, 3.2);
            let end = [c[0] + r * phi.cos(), c[1] + r * phi.sin()];
            (if rng.chance(0.5) { 2.0 } else { 3.0 }, end, Some((ox, oz)))
        };
        let (x, z) = match distance {
            Distance::Absolute => (2.0 * end[0], end[1]),
            Distance::Incremental => (2.0 * (end[0] - pos[0]), end[1] - pos[1]),
        };
        let mut words = vec![(b'G', g), (b'X', x), (b'Z', z)];
        if let Some((ox, oz)) = centre {
            if ijk == "G90.1" {
                words.push((b'I', pos[0] + ox));
                words.push((b'K', pos[1] + oz));
            } else {
                words.push((b'I', ox));
                words.push((b'K', oz));
            }
        }
        lines.push(words);
        modes.push(mode);
        pos = end;
    }
    for (words, mode) in lines.iter().zip(&modes) {
        if let Some(m) = mode {
            orig.push_str(m);
            orig.push('\n');
            low.push_str(m);
            low.push('\n');
        }
        let mut l = PlainLine {
            words: words
                .iter()
                .map(|&(letter, value)| Word { letter, value })
                .collect(),
        };
        orig.push_str(&format_line(&l));
        orig.push('\n');
        radius_words(&mut l);
        low.push_str(&format_line(&l));
        low.push('\n');
    }
    orig.push_str("M2\n");
    low.push_str("M2\n");
    (orig, low)
}

#[test]
fn diameter_mode_moves_as_rs274() {
    if !oracle::available("diameter_mode_moves_as_rs274") {
        return;
    }
    let seed0 = first_seed();
    let mut failures = Vec::new();
    for seed in seed0..seed0 + cases() {
        let (orig, low) = diameter_program(seed);
        if let Err(why) = compare_runs(&orig, &low) {
            failures.push(report("G7", seed, &orig, &low, &why));
        }
        if failures.len() >= 3 {
            break;
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

// ---------------------------------------------------------------- splines

/// Bernstein-form evaluation of a Bézier curve.
fn bezier_point(ctrl: &[[f64; 2]], t: f64) -> [f64; 2] {
    let n = ctrl.len() - 1;
    let mut binom = 1.0;
    let mut p = [0.0; 2];
    for (i, c) in ctrl.iter().enumerate() {
        if i > 0 {
            binom = binom * (n + 1 - i) as f64 / i as f64;
        }
        let b = binom * t.powi(i as i32) * (1.0 - t).powi((n - i) as i32);
        p[0] += b * c[0];
        p[1] += b * c[1];
    }
    p
}

/// Cox–de Boor basis function N(i, k) at u (half-open spans; the last span
/// closed at the end of the knot vector).
fn basis(i: usize, k: usize, u: f64, knots: &[f64]) -> f64 {
    if k == 1 {
        let last = knots[knots.len() - 1];
        let inside = knots[i] <= u && u < knots[i + 1];
        let at_end = u == last && knots[i] < knots[i + 1] && knots[i + 1] == last;
        return if inside || at_end { 1.0 } else { 0.0 };
    }
    let mut v = 0.0;
    let d1 = knots[i + k - 1] - knots[i];
    if d1 > 0.0 {
        v += (u - knots[i]) / d1 * basis(i, k - 1, u, knots);
    }
    let d2 = knots[i + k] - knots[i + 1];
    if d2 > 0.0 {
        v += (knots[i + k] - u) / d2 * basis(i + 1, k - 1, u, knots);
    }
    v
}

/// Rational evaluation of a NURBS with LinuxCNC's clamped uniform knots.
fn nurbs_point(pts: &[[f64; 3]], order: usize, u: f64) -> [f64; 2] {
    let n = pts.len() - 1;
    let knots: Vec<f64> = (0..=n + order)
        .map(|i| {
            if i < order {
                0.0
            } else if i <= n {
                (i + 1 - order) as f64
            } else {
                (n + 2 - order) as f64
            }
        })
        .collect();
    let (mut x, mut y, mut w) = (0.0, 0.0, 0.0);
    for (i, p) in pts.iter().enumerate() {
        let b = basis(i, order, u, &knots) * p[2];
        x += b * p[0];
        y += b * p[1];
        w += b;
    }
    [x / w, y / w]
}

fn dist_to_polyline(p: [f64; 2], poly: &[[f64; 2]]) -> f64 {
    poly.windows(2)
        .map(|s| {
            let (a, b) = (s[0], s[1]);
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let len2 = dx * dx + dy * dy;
            let t = if len2 > 0.0 {
                (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            (p[0] - a[0] - t * dx).hypot(p[1] - a[1] - t * dy)
        })
        .fold(f64::INFINITY, f64::min)
}

/// The polyline a lowering writes, from `start`.
fn polyline(start: [f64; 2], lines: &[PlainLine]) -> Vec<[f64; 2]> {
    let mut poly = vec![start];
    for l in lines {
        assert_eq!(l.words[0].letter, b'G');
        assert_eq!(l.words[0].value, 1.0);
        let get = |c: u8| l.words.iter().find(|w| w.letter == c).map(|w| w.value);
        poly.push([get(b'X').expect("X"), get(b'Y').expect("Y")]);
    }
    poly
}

/// Every sampled curve point within the tolerance of the polyline, and
/// every polyline vertex on the curve's side of it (within the tolerance of
/// a sampled curve point plus the sampling step).
fn check_curve(
    name: &str,
    curve: impl Fn(f64) -> [f64; 2],
    umax: f64,
    poly: &[[f64; 2]],
    tol: f64,
) -> Result<(), String> {
    const N: usize = 2000;
    let samples: Vec<[f64; 2]> = (0..=N).map(|i| curve(umax * i as f64 / N as f64)).collect();
    for (i, p) in samples.iter().enumerate() {
        let d = dist_to_polyline(*p, poly);
        if d > tol * (1.0 + 1e-9) + 1e-12 {
            return Err(format!(
                "{name}: curve point {i}/{N} {p:?} is {d} from the polyline (tolerance {tol}, {} segments)",
                poly.len() - 1
            ));
        }
    }
    let step = samples
        .windows(2)
        .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
        .fold(0.0, f64::max);
    for v in poly {
        let d = samples
            .iter()
            .map(|s| (s[0] - v[0]).hypot(s[1] - v[1]))
            .fold(f64::INFINITY, f64::min);
        if d > step + 1e-9 {
            return Err(format!("{name}: vertex {v:?} is {d} away from the curve"));
        }
    }
    Ok(())
}

#[test]
fn splines_stay_within_tolerance() {
    use ngcflat::controller::lower::spline::{NurbsPoint, lower_g5, lower_g5_1, lower_nurbs};
    let seed0 = first_seed();
    for seed in seed0..seed0 + cases() {
        let mut rng = Rng::new(seed);
        let tol = *rng.pick(&[0.001, 0.01, 0.0004, 0.05]);
        let mut pt = || [rng.milli(-20.0, 20.0), rng.milli(-20.0, 20.0)];
        let (start, a, b, end) = (pt(), pt(), pt(), pt());
        let ij = [a[0] - start[0], a[1] - start[1]];
        let pq = [b[0] - end[0], b[1] - end[1]];
        let lines = lower_g5(start, ij, pq, end, tol).expect("G5 lowers");
        let poly = polyline(start, &lines);
        assert_eq!(poly.last(), Some(&end), "G5 seed {seed}: end point");
        let ctrl = [start, a, b, end];
        check_curve("G5", |t| bezier_point(&ctrl, t), 1.0, &poly, tol)
            .unwrap_or_else(|e| panic!("seed {seed}: {e}"));

        let lines = lower_g5_1(start, ij, end, tol).expect("G5.1 lowers");
        let poly = polyline(start, &lines);
        assert_eq!(poly.last(), Some(&end), "G5.1 seed {seed}: end point");
        let ctrl = [start, a, end];
        check_curve("G5.1", |t| bezier_point(&ctrl, t), 1.0, &poly, tol)
            .unwrap_or_else(|e| panic!("seed {seed}: {e}"));

        let order = 2 + rng.below(4);
        let count = order + rng.below(6);
        let pts: Vec<[f64; 3]> = (0..count)
            .map(|_| {
                [
                    rng.milli(-20.0, 20.0),
                    rng.milli(-20.0, 20.0),
                    rng.milli(0.3, 3.0),
                ]
            })
            .collect();
        let input: Vec<NurbsPoint> = pts
            .iter()
            .map(|p| NurbsPoint {
                x: p[0],
                y: p[1],
                weight: p[2],
            })
            .collect();
        let lines = lower_nurbs(&input, order, tol).expect("NURBS lowers");
        let first = [pts[0][0], pts[0][1]];
        let poly = polyline(first, &lines);
        let last = pts[count - 1];
        assert_eq!(
            poly.last(),
            Some(&[last[0], last[1]]),
            "NURBS seed {seed}: end"
        );
        let umax = (count + 1 - order) as f64;
        check_curve(
            &format!("NURBS order {order}, {count} points"),
            |u| nurbs_point(&pts, order, u),
            umax,
            &poly,
            tol,
        )
        .unwrap_or_else(|e| panic!("seed {seed}: {e}"));
    }
}

/// rs274 prints no spline geometry, but where a spline leaves the tool
/// shows: an incremental move after the spline must start from the same
/// point in both programs.
#[test]
fn splines_end_where_rs274_ends_them() {
    use ngcflat::controller::lower::spline::{NurbsPoint, lower_g5, lower_g5_1, lower_nurbs};
    if !oracle::available("splines_end_where_rs274_ends_them") {
        return;
    }
    let seed0 = first_seed();
    for seed in seed0..seed0 + cases() / 4 + 1 {
        let mut rng = Rng::new(seed);
        let mut pt = || [rng.milli(-20.0, 20.0), rng.milli(-20.0, 20.0)];
        let (start, a, b, end) = (pt(), pt(), pt(), pt());
        let n1 = [pt(), pt(), pt()];
        let head = format!(
            "G21 G17 G90 F200\nG0 X{} Y{} Z1\n",
            num(start[0]),
            num(start[1])
        );
        let ij = [a[0] - start[0], a[1] - start[1]];
        let pq = [b[0] - end[0], b[1] - end[1]];
        let tail = "G91 G1 X0.5 Y0.25\nM2\n";
        let g5 = format!(
            "G5 X{} Y{} I{} J{} P{} Q{}\n",
            num(end[0]),
            num(end[1]),
            num(ij[0]),
            num(ij[1]),
            num(pq[0]),
            num(pq[1])
        );
        let g51 = format!(
            "G5.1 X{} Y{} I{} J{}\n",
            num(start[0]),
            num(start[1]),
            num(b[0] - end[0]),
            num(b[1] - end[1])
        );
        let nurbs = format!(
            "G5.2 X{} Y{} P1.5 L3\nX{} Y{} P0.7\nX{} Y{} P1\nG5.3\n",
            num(n1[0][0]),
            num(n1[0][1]),
            num(n1[1][0]),
            num(n1[1][1]),
            num(n1[2][0]),
            num(n1[2][1])
        );
        let orig = format!("{head}{g5}{g51}{nurbs}{tail}");
        let mut low = head.clone();
        let mut add = |lines: Vec<PlainLine>| {
            for l in &lines {
                low.push_str(&format_line(l));
                low.push('\n');
            }
        };
        add(lower_g5(start, ij, pq, end, 0.001).expect("G5"));
        add(lower_g5_1(end, [b[0] - end[0], b[1] - end[1]], start, 0.001).expect("G5.1"));
        let pts = [
            NurbsPoint {
                x: start[0],
                y: start[1],
                weight: 1.0,
            },
            NurbsPoint {
                x: n1[0][0],
                y: n1[0][1],
                weight: 1.5,
            },
            NurbsPoint {
                x: n1[1][0],
                y: n1[1][1],
                weight: 0.7,
            },
            NurbsPoint {
                x: n1[2][0],
                y: n1[2][1],
                weight: 1.0,
            },
        ];
        add(lower_nurbs(&pts, 3, 0.001).expect("NURBS"));
        low.push_str(tail);
        let ra = oracle::run(orig.as_bytes(), "", None);
        let rb = oracle::run(low.as_bytes(), "", None);
        assert!(
            ra.ok && rb.ok,
            "seed {seed}: {}{}\n{orig}",
            ra.stderr,
            rb.stderr
        );
        let last_move = |r: &oracle::Run| {
            r.lines
                .iter()
                .rev()
                .find(|l| l.starts_with("STRAIGHT_FEED("))
                .cloned()
                .unwrap_or_default()
        };
        oracle::compare(&[last_move(&ra)], &[last_move(&rb)], 1e-4)
            .unwrap_or_else(|e| panic!("seed {seed}: {e}\n{orig}---\n{low}"));
    }
}

/// The G1 points of a written program after the line that starts with
/// `from` (absolute X Y; a missing word keeps its value).
fn written_points(out: &str, from: &str, to: &str) -> Vec<[f64; 2]> {
    let mut on = false;
    let mut at = [f64::NAN; 2];
    let mut pts = Vec::new();
    for l in out.lines() {
        if l.starts_with(from) {
            on = true;
            continue;
        }
        if on && l.starts_with(to) {
            break;
        }
        let word = |c: char| {
            l.split(' ')
                .find(|w| w.starts_with(c))
                .and_then(|w| w[1..].parse::<f64>().ok())
        };
        if on && l.starts_with("G1 ") {
            at = [word('X').unwrap_or(at[0]), word('Y').unwrap_or(at[1])];
            pts.push(at);
        }
    }
    pts
}

/// G5.2/G5.3 through the driver: the control points are taken as LinuxCNC
/// takes them (the current point first, with the P of a first block that
/// has no X Y; G91 points from the point the curve starts at; L above 3
/// raises the order), and every point of the curve, evaluated here from
/// those points, lies within the tolerance of the written segments, which
/// end exactly at the last control point.
#[test]
fn nurbs_blocks_are_lowered_within_tolerance() {
    let program = "G21 G17 G90 G0 X1 Y2 Z1\nF300\n\
        G5.2 X0 Y10 P1 L3\nX10 Y10 P2\nX10 Y0 P1\nX20 Y0 P0.5\nG5.3\n\
        G0 X5 Y5\n\
        G5.2 P2 L4\nG91 X5 Y5 P1\nX10 Y0 P1\nX0 Y-5 P3\nX-5 Y-5 P1\nG5.3\n\
        G90 G0 X0 Y0\nM2\n";
    let dir = crate::tmp();
    crate::put(dir.path(), "n.ngc", program);
    for tol in [0.05, 0.001] {
        let t = tol.to_string();
        let (code, out, err) = crate::run(
            dir.path(),
            &[
                "--target",
                "grbl",
                "--zero-start",
                "--tolerance",
                &t,
                "n.ngc",
            ],
        );
        assert_eq!(code, 0, "{err}");
        // (segments after, until, start, control points X Y P, order)
        type Curve = (&'static str, &'static str, [f64; 2], Vec<[f64; 3]>, usize);
        let curves: [Curve; 2] = [
            (
                "F300",
                "G0 X5 Y5",
                [1.0, 2.0],
                vec![
                    [1.0, 2.0, 1.0],
                    [0.0, 10.0, 1.0],
                    [10.0, 10.0, 2.0],
                    [10.0, 0.0, 1.0],
                    [20.0, 0.0, 0.5],
                ],
                3,
            ),
            (
                "G0 X5 Y5",
                "G90 G0",
                [5.0, 5.0],
                vec![
                    [5.0, 5.0, 2.0],
                    [10.0, 10.0, 1.0],
                    [15.0, 5.0, 1.0],
                    [5.0, 0.0, 3.0],
                    [0.0, 0.0, 1.0],
                ],
                4,
            ),
        ];
        for (from, to, start, pts, order) in curves {
            let mut poly = vec![start];
            poly.extend(written_points(&out, from, to));
            assert!(poly.len() > 3, "segments after {from}:\n{out}");
            let last = pts[pts.len() - 1];
            assert_eq!(poly.last(), Some(&[last[0], last[1]]), "end point\n{out}");
            let umax = (pts.len() + 1 - order) as f64;
            // The written numbers are rounded to 4 decimals.
            check_curve(
                &format!("NURBS from {from}"),
                |u| nurbs_point(&pts, order, u),
                umax,
                &poly,
                tol + 0.00008,
            )
            .unwrap_or_else(|e| panic!("{e}\n{out}"));
        }
    }
}

/// Random G5.2/G5.3 programs through the driver (G90 or G91 points, a
/// first block with only P, orders 3 to 5, inches or millimetres): the
/// written segments follow the curve evaluated here from the control
/// points LinuxCNC takes, within the tolerance, ending exactly at the last
/// point; the move after the curve starts there.
#[test]
fn random_nurbs_programs_are_lowered_within_tolerance() {
    let dir = crate::tmp();
    for seed in first_seed()..first_seed() + cases() {
        let mut rng = Rng::new(seed);
        let inch = rng.chance(0.3);
        let tol_mm = *rng.pick(&[0.001, 0.01, 0.05]);
        let tol = if inch { tol_mm / 25.4 } else { tol_mm };
        let start = [rng.milli(-10.0, 10.0), rng.milli(-10.0, 10.0)];
        let order = rng.int(3, 5);
        let count = order + rng.int(0, 4);
        let incremental = rng.chance(0.4);
        let first_weight = rng.chance(0.3).then(|| rng.milli(0.5, 2.0));
        let mut prog = format!(
            "{} G17 G90 G0 X{} Y{} Z1\nF100\n",
            if inch { "G20" } else { "G21" },
            num(start[0]),
            num(start[1])
        );
        let mut pts = vec![[start[0], start[1], first_weight.unwrap_or(1.0)]];
        if let Some(w) = first_weight {
            prog.push_str(&format!("G5.2 P{} L{order}\n", num(w)));
        }
        if incremental {
            prog.push_str("G91\n");
        }
        for i in 1..count {
            let p = [
                rng.milli(-10.0, 10.0),
                rng.milli(-10.0, 10.0),
                rng.milli(0.3, 3.0),
            ];
            let head = if i == 1 && first_weight.is_none() {
                format!("G5.2 L{order} ")
            } else {
                String::new()
            };
            prog.push_str(&format!(
                "{head}X{} Y{} P{}\n",
                num(p[0]),
                num(p[1]),
                num(p[2])
            ));
            let at = if incremental {
                [start[0] + p[0], start[1] + p[1], p[2]]
            } else {
                p
            };
            pts.push(at);
        }
        prog.push_str("G5.3\nG90 G0 Z2\nM2\n");
        crate::put(dir.path(), "r.ngc", &prog);
        let t = tol_mm.to_string();
        let (code, out, err) = crate::run(
            dir.path(),
            &[
                "--target",
                "grbl",
                "--zero-start",
                "--tolerance",
                &t,
                "r.ngc",
            ],
        );
        assert_eq!(code, 0, "seed {seed}: {err}\n{prog}");
        let mut poly = vec![start];
        poly.extend(written_points(&out, "F100", "G90 G0 Z2"));
        let last = pts[pts.len() - 1];
        let end = poly.last().copied().unwrap_or(start);
        let quantum = if inch { 0.000005 } else { 0.00005 };
        assert!(
            (end[0] - last[0]).abs() <= quantum && (end[1] - last[1]).abs() <= quantum,
            "seed {seed}: ends at {end:?}, not {last:?}\n{prog}---\n{out}"
        );
        let umax = (pts.len() + 1 - order) as f64;
        check_curve(
            &format!("seed {seed}"),
            |u| nurbs_point(&pts, order, u),
            umax,
            &poly,
            tol + 2.0 * quantum,
        )
        .unwrap_or_else(|e| panic!("{e}\n{prog}---\n{out}"));
    }
}
