//! Arcs the target would not run as LinuxCNC does from the numbers written
//! for them, found so that they are lowered (`lower::arc`) instead:
//!
//! * a centre-form arc whose end is not at its start's distance from the
//!   centre: LinuxCNC takes a difference up to its tolerance (0.002 in or
//!   0.02 mm, more on a large radius) and moves a spiral; GRBL refuses a
//!   difference over 0.005 mm that is also over 0.5 mm or 0.1 % of the
//!   radius (error 33), and the controllers derived from it check alike;
//! * an R-form arc whose centre, as the target works it out from the
//!   numbers as written (rounded to the target's decimals), is more than
//!   the tolerance from LinuxCNC's, or which the target cannot place at
//!   all: a half circle whose R, once rounded, is short of half the
//!   rounded chord (error 33). Near a half circle the centre moves far for
//!   a small change of R or of the end points.
//!
//! Both are checked in millimetres, on the exact positions with a margin
//! for the rounding of the written numbers. Arcs whose positions are not
//! known are written as they are.

use crate::block::{Block, MotionMode, NonModal, ToolLength};
use crate::codes::{ArcDistance, Units};
use crate::controller::format::format_number;
use crate::controller::lower;
use crate::diag::ErrorKind;
use crate::geom::cutter_comp::{Arc as CompArc, ArcCenter, Tolerances, arc_center};
use crate::machine::{FlatMachine, radius_center};

use super::Lowering;
use crate::eval::arc_refusal;

/// GRBL's check of a centre-form arc (gcode.c): the end may be off the
/// start's distance from the centre by 0.005 mm, or by more if that is
/// at most 0.5 mm and 0.1 % of the radius.
const ARC_ABS_MM: f64 = 0.005;
const ARC_MAX_MM: f64 = 0.5;
const ARC_REL: f64 = 0.001;

/// LinuxCNC's smallest arc radius (0.00005 in), in mm.
const MIN_RADIUS_MM: f64 = 0.00005 * 25.4;

/// The largest change of the distance from the centre over one part of a
/// lowered spiral arc (mm): below [`ARC_ABS_MM`] whatever the rounding.
pub(super) const SPIRAL_STEP_MM: f64 = 0.004;

impl Lowering {
    /// Whether the arc of block `b`, run from `before` to the model's
    /// present state, must be lowered (see the module doc). `motion` is
    /// the block's motion (G2 or G3).
    pub(super) fn arc_off_target(
        &self,
        b: &Block,
        before: &FlatMachine,
        after: &FlatMachine,
        motion: MotionMode,
    ) -> bool {
        let ccw = motion == MotionMode::ArcCcw;
        let xyz = |m: &FlatMachine| [m.pos[0], m.pos[1], m.pos[2]];
        match b.value(b'R') {
            Some(r) => self.r_arc_off(after, xyz(before), xyz(after), r, ccw),
            None => {
                let words = [b'I', b'J', b'K'].map(|l| b.value(l).unwrap_or(0.0));
                self.ijk_off(after, xyz(before), xyz(after), words, ccw)
            }
        }
    }

    /// [`Lowering::arc_refused`] for a block whose arc is written or
    /// lowered from its end point (G2/G3 with an axis word, no other use of
    /// the axis words), run from `before` to the model's state.
    pub(super) fn linuxcnc_arc_refusal(
        &self,
        b: &Block,
        before: &FlatMachine,
    ) -> Option<ErrorKind> {
        let motion = b.motion().unwrap_or(before.modes.motion);
        let other_axis_use = b.non_modal().is_some_and(|n| !matches!(n, NonModal::Dwell))
            || b.tool_length() == Some(ToolLength::Dynamic);
        let polar = b.value(b'@').is_some() || b.value(b'^').is_some();
        if !matches!(motion, MotionMode::ArcCw | MotionMode::ArcCcw)
            || !(b.has_axis() || polar)
            || other_axis_use
        {
            return None;
        }
        self.arc_refused(b, before, &self.m, motion)
    }

    /// LinuxCNC's own refusal of the arc of block `b` (run from `before`
    /// to `after`), where the positions are known: the evaluator checks
    /// arcs only where it knows them (not after a canned cycle, say), the
    /// model here knows more. The error rs274 gives, at the same line.
    pub(super) fn arc_refused(
        &self,
        b: &Block,
        before: &FlatMachine,
        after: &FlatMachine,
        motion: MotionMode,
    ) -> Option<ErrorKind> {
        let [p, q, _] = after.modes.plane.xyz_axes()?;
        let s = after.scale();
        let at = |m: &FlatMachine, a: usize| m.pos[a].map(|v| v / s);
        let (start, end) = (
            [at(before, p)?, at(before, q)?],
            [at(after, p)?, at(after, q)?],
        );
        let letters = [b'I', b'J', b'K'];
        let block = arc_refusal(
            motion == MotionMode::ArcCcw,
            b.value(b'R'),
            [b.value(letters[p]), b.value(letters[q])],
            after.modes.arc_distance,
            after.modes.units,
            start,
            end,
        )?;
        Some(ErrorKind::Block(block))
    }

    /// Whether an arc of a line of moves alone (G2/G3 with X Y Z and I J
    /// K), run from the model's position to the program values `xyz` with
    /// centre words `words`, must be lowered (as for its block).
    pub(super) fn form_arc_off(
        &self,
        start: [Option<f64>; 3],
        xyz: [Option<f64>; 3],
        words: [f64; 3],
        ccw: bool,
    ) -> bool {
        let s = self.m.scale();
        let mut end = start;
        for (a, v) in xyz.iter().enumerate() {
            if let Some(v) = *v {
                end[a] = self.m.axis_target(a, v, s);
            }
        }
        self.ijk_off(&self.m, start, end, words, ccw)
    }

    /// The centre-form check: `start` and `end` are X Y Z in mm, `words`
    /// I J K in program units, `m` the state the arc runs in. Also true
    /// for an arc LinuxCNC refuses for its radius (the block's way then
    /// refuses it).
    fn ijk_off(
        &self,
        m: &FlatMachine,
        start: [Option<f64>; 3],
        end: [Option<f64>; 3],
        words: [f64; 3],
        ccw: bool,
    ) -> bool {
        let Some([p, q, _]) = m.modes.plane.xyz_axes() else {
            return false;
        };
        let (Some(s0), Some(s1), Some(e0), Some(e1)) = (start[p], start[q], end[p], end[q]) else {
            return false;
        };
        let scale = m.scale();
        let centre = match m.modes.arc_distance {
            ArcDistance::Incremental => [s0 + words[p] * scale, s1 + words[q] * scale],
            ArcDistance::Absolute => [words[p] * scale, words[q] * scale],
        };
        // LinuxCNC refuses an arc with no radius (E0653): the block's way
        // refuses it too, where the evaluator did not.
        let (start, end) = ([s0, s1], [e0, e1]);
        let no_radius = |p: [f64; 2]| (p[0] - centre[0]).hypot(p[1] - centre[1]) < MIN_RADIUS_MM;
        no_radius(start)
            || no_radius(end)
            || ijk_refused(start, end, centre, 6.0 * self.quantum(m))
            || self.barely_turns(m, start, end, centre, ccw)
    }

    /// Whether the arc from `start` to `end` about `centre` (plane
    /// coordinates, mm; turning counter-clockwise when `ccw`; `m` the
    /// state it runs in) turns so
    /// little that the target could take it for a full circle: under
    /// GRBL's least angle, or its ends may be written as one point (see
    /// [`lower::arc::barely_turns`]); lowered into a line. An arc whose
    /// ends are written apart stays an arc.
    fn barely_turns(
        &self,
        m: &FlatMachine,
        start: [f64; 2],
        end: [f64; 2],
        centre: [f64; 2],
        ccw: bool,
    ) -> bool {
        if start == end {
            // A full circle, as written.
            return false;
        }
        // Most arcs: a chord longer than both bounds below can be neither
        // (it is at most the radius times the angle), without the angles.
        let unit = 2.0 * self.quantum(m);
        let chord2 = (end[0] - start[0]).powi(2) + (end[1] - start[1]).powi(2);
        let radius2 = (start[0] - centre[0]).powi(2) + (start[1] - centre[1]).powi(2);
        if chord2 > (1.5 * unit).powi(2) && chord2 > radius2 * 1e-10 {
            return false;
        }
        let (_, sweep) = turn(centre, start, end, ccw);
        // Ends that may be written as one point: within one and a half
        // units of the last decimal (each coordinate rounds by half a unit).
        lower::arc::barely_turns(sweep, chord2.sqrt(), 1.5 * unit)
    }

    /// Half a unit of the last decimal the target is written with, in mm.
    fn quantum(&self, m: &FlatMachine) -> f64 {
        0.5 * 10f64.powi(-i32::from(self.decimals(m))) * m.scale()
    }

    fn decimals(&self, m: &FlatMachine) -> u8 {
        match m.modes.units {
            Units::Mm => self.p.decimals_mm,
            Units::Inch => self.p.decimals_inch,
        }
    }

    /// The R-form half of [`Lowering::arc_off_target`] (`start` and `end`
    /// X Y Z in mm, `r` in program units, `m` the state the arc runs in).
    fn r_arc_off(
        &self,
        m: &FlatMachine,
        start: [Option<f64>; 3],
        end: [Option<f64>; 3],
        r: f64,
        ccw: bool,
    ) -> bool {
        let Some([p, q, _]) = m.modes.plane.xyz_axes() else {
            return false;
        };
        let (Some(s0), Some(s1), Some(e0), Some(e1)) = (start[p], start[q], end[p], end[q]) else {
            return false;
        };
        let (start, end) = ([s0, s1], [e0, e1]);
        let decimals = self.decimals(m);
        let scale = m.scale();
        let arc = CompArc {
            ccw,
            center: ArcCenter::Radius(r * scale),
            turns: 1,
        };
        let Ok((exact, _)) = arc_center(&Tolerances::default_for(Units::Mm), arc, start, end)
        else {
            return false;
        };
        // The numbers as the target reads them: each rounded as written.
        let digits = self.p.max_digits;
        let written = |v: f64| {
            let mut s = String::new();
            format_number(&mut s, v / scale, decimals, digits);
            s.parse::<f64>().map_or(v, |w| w * scale)
        };
        let (ws, we) = (start.map(written), end.map(written));
        let wr = written(r * scale);
        let chord2 = (we[0] - ws[0]).powi(2) + (we[1] - ws[1]).powi(2);
        if chord2 == 0.0 || 4.0 * wr * wr - chord2 <= single_precision_slack(ws, we, wr) {
            // The target cannot place the centre (or LinuxCNC's is the
            // chord's middle and the target's would be found otherwise),
            // or it may not, working in single precision.
            return true;
        }
        // The arcs share their ends (but for the rounding): they are
        // furthest apart about their middles.
        let target = radius_center(ws, we, wr, ccw);
        let (a, b) = (middle(exact, start, end, ccw), middle(target, ws, we, ccw));
        (a[0] - b[0]).hypot(a[1] - b[1]) > self.opts.tolerance_mm
            || self.barely_turns(m, start, end, exact, ccw)
    }

    /// The most the distance from the centre may change over one part of
    /// a lowered arc (program units).
    pub(super) fn radius_step(&self) -> f64 {
        self.opts.tolerance_mm.min(SPIRAL_STEP_MM) / self.m.scale()
    }
}

/// Whether a centre-form arc from `start` to `end` about `centre` (plane
/// coordinates, mm) is off by more than GRBL takes, less `margin` for the
/// rounding of the written numbers.
pub(super) fn ijk_refused(start: [f64; 2], end: [f64; 2], centre: [f64; 2], margin: f64) -> bool {
    let dist = |p: [f64; 2]| ((p[0] - centre[0]).powi(2) + (p[1] - centre[1]).powi(2)).sqrt();
    let (r0, r1) = (dist(start), dist(end));
    let delta = (r1 - r0).abs();
    delta > ARC_ABS_MM - margin && (delta > ARC_MAX_MM - margin || delta > ARC_REL * r0 - margin)
}

/// How far below zero GRBL-class firmwares may find `4 r² - d²` (mm²) for
/// an R arc of radius `r` whose chord `d` runs from `start` to `end`
/// (plane coordinates, mm, as written), where it is not: they work in
/// single precision (`float`) from positions in mm, so a half circle by R
/// (`G20 G0 X.1` then `G2 X.3 R.1`) may be refused (GRBL's error 34). A
/// bound on that arithmetic's error: each difference of coordinates is off
/// by a few units of the last place of the largest of them, R by a few of
/// its own.
fn single_precision_slack(start: [f64; 2], end: [f64; 2], r: f64) -> f64 {
    let largest = start
        .iter()
        .chain(&end)
        .fold(r.abs(), |m, v| m.max(v.abs()));
    let chord = (end[0] - start[0]).hypot(end[1] - start[1]);
    16.0 * f64::from(f32::EPSILON) * largest * (chord + 2.0 * r.abs())
}

/// The angle of `start` about `centre` and the angle (above 0, at most a
/// turn) the arc from `start` to `end` turns through, counter-clockwise
/// when `ccw` (plane coordinates).
fn turn(centre: [f64; 2], start: [f64; 2], end: [f64; 2], ccw: bool) -> (f64, f64) {
    let angle = |p: [f64; 2]| (p[1] - centre[1]).atan2(p[0] - centre[0]);
    let (a0, a1) = (angle(start), angle(end));
    let sweep = if ccw { a1 - a0 } else { a0 - a1 };
    // atan2 differences lie within a turn either way.
    let sweep = if sweep <= 0.0 {
        sweep + std::f64::consts::TAU
    } else {
        sweep
    };
    (a0, sweep)
}

/// The point halfway along the arc from `start` to `end` about `centre`
/// (plane coordinates, turning counter-clockwise when `ccw`).
fn middle(centre: [f64; 2], start: [f64; 2], end: [f64; 2], ccw: bool) -> [f64; 2] {
    let (a0, sweep) = turn(centre, start, end, ccw);
    let mid = if ccw {
        a0 + sweep / 2.0
    } else {
        a0 - sweep / 2.0
    };
    let r = (start[0] - centre[0]).hypot(start[1] - centre[1]);
    [centre[0] + r * mid.cos(), centre[1] + r * mid.sin()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grbl_arc_check() {
        // 0.02 mm off on a radius of 1: LinuxCNC moves it, GRBL refuses.
        assert!(ijk_refused([0.0, 0.0], [2.0, 0.0], [1.01, 0.0], 0.0003));
        // 0.004 mm off: GRBL takes it.
        assert!(!ijk_refused([0.0, 0.0], [2.004, 0.0], [1.0, 0.0], 0.0003));
        // 0.02 mm off on a radius of 100 is 0.02 %: GRBL takes it.
        assert!(!ijk_refused(
            [0.0, 0.0],
            [200.02, 0.0],
            [100.0, 0.0],
            0.0003
        ));
        // Over 0.5 mm is refused on any radius.
        assert!(ijk_refused(
            [0.0, 0.0],
            [2000.6, 0.0],
            [1000.0, 0.0],
            0.0003
        ));
    }

    /// GRBL's test of an R arc (gcode.c), in its single precision: the
    /// positions and R as read in program units, made mm, then `4 r² - x²
    /// - y²`; below zero is its error 34.
    fn grbl_places_r_arc(start: [f64; 2], end: [f64; 2], r: f64, mm_per_unit: f32) -> bool {
        let mm = |v: f64| v as f32 * mm_per_unit;
        let (x, y) = (mm(end[0]) - mm(start[0]), mm(end[1]) - mm(start[1]));
        let r = mm(r);
        4.0 * r * r - x * x - y * y >= 0.0
    }

    #[test]
    fn half_circles_grbl_may_refuse_are_found() {
        // Half circles by R, written with 4 decimals (inch and mm),
        // anywhere on a 1 m table: wherever GRBL's arithmetic refuses one
        // (as `G20 G1 X.1` then `G2 X.3 R.1` on the first case), the
        // slack covers it.
        let mut refused = 0;
        for (unit, scale) in [(25.4f32, 25.4), (1.0, 1.0)] {
            for i in 0..4000u32 {
                let at = f64::from(i % 400) * 0.1 * f64::from(i % 7 + 1) / scale;
                let r = f64::from(i % 97 + 1) * 0.05 / scale;
                let round = |v: f64| (v * 1e4).round() / 1e4;
                let (start, r) = ([round(at), round(at / 3.0)], round(r));
                let end = if i % 2 == 0 {
                    [start[0] + 2.0 * r, start[1]]
                } else {
                    [start[0], start[1] - 2.0 * r]
                };
                let end = end.map(round);
                if !grbl_places_r_arc(start, end, r, unit) {
                    refused += 1;
                    let mm = |p: [f64; 2]| p.map(|v| v * scale);
                    let (ws, we, wr) = (mm(start), mm(end), r * scale);
                    let chord2 = (we[0] - ws[0]).powi(2) + (we[1] - ws[1]).powi(2);
                    assert!(
                        4.0 * wr * wr - chord2 <= single_precision_slack(ws, we, wr),
                        "{start:?} {end:?} R{r}"
                    );
                }
            }
        }
        assert!(refused > 100, "the cases test nothing: {refused}");
    }

    #[test]
    fn middle_of_an_arc() {
        let close = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]) < 1e-12;
        // A half turn from (1, 0) to (-1, 0) about the origin.
        assert!(close(
            middle([0.0; 2], [1.0, 0.0], [-1.0, 0.0], true),
            [0.0, 1.0]
        ));
        assert!(close(
            middle([0.0; 2], [1.0, 0.0], [-1.0, 0.0], false),
            [0.0, -1.0]
        ));
        // Three quarters clockwise from (0, 1) to (-1, 0).
        let m = middle([0.0; 2], [0.0, 1.0], [-1.0, 0.0], false);
        let h = std::f64::consts::FRAC_1_SQRT_2;
        assert!(close(m, [h, -h]));
    }
}
