//! Arcs a simple controller cannot take as written: a full circle without
//! end point (`G2 I5`: GRBL wants an axis word) and arcs with P turns (no P
//! word on GRBL-class controllers), as several G2/G3 arcs on the same
//! helix.
//!
//! The rule (LinuxCNC 2.9's motion for an arc with centre C, start S, end E
//! and P turns): the tool turns about C in the arc's direction from S's
//! angle to E's angle — a whole turn when E is S in the plane — plus P − 1
//! whole turns; the axis normal to the plane moves linearly with the angle
//! turned. The lowering cuts that sweep into `n = floor(sweep / π) + 1`
//! equal parts, each less than a half turn (so that no controller has to
//! decide which way a part goes between two opposite points: a full circle
//! is three arcs of 120°), each ending on the
//! circle at its angle and at the helix height for that angle; the last
//! ends exactly at E. Each part is written `G2|G3 X Y Z` with the centre as
//! offsets from the part's start (I J in G17, I K in G18, J K in G19;
//! incremental arc centres, G91.1, the default of LinuxCNC and the only
//! form of GRBL). Axes other than X Y Z must not move during the arc.
//!
//! An arc whose end is not quite at its start's distance from the centre
//! (LinuxCNC accepts up to 0.002 in, or 0.02 mm, and more on a large
//! radius) is a spiral there: the distance from the centre, like the
//! height, moves linearly with the angle turned. The parts' ends are on
//! that spiral, and there are enough parts that the distance changes by
//! at most [`ArcInput::radius_step`] over each: a controller turns each
//! part about the centre at its start's distance and checks that its end
//! is about as far (GRBL refuses a difference over 0.005 mm and 0.1 % of
//! the radius, error 33).

use super::{LowerError, PlainLine, push};
use crate::codes::Plane;
use std::f64::consts::PI;

/// An arc as LinuxCNC would run it. Coordinates are X, Y, Z in program
/// units (absolute, X a radius in G7).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArcInput {
    pub plane: Plane,
    /// G2 (true) or G3.
    pub clockwise: bool,
    pub start: [f64; 3],
    /// The end point (the start again for a full circle written without
    /// end point; the helix axis may differ).
    pub end: [f64; 3],
    /// The centre; its component along the plane's normal is ignored.
    pub centre: [f64; 3],
    /// P turns (1 without P).
    pub turns: u32,
    /// The most the distance from the centre may change over one part
    /// (program units, above 0).
    pub radius_step: f64,
}

/// The in-plane axes (first, second) and the normal axis, as indices into
/// X Y Z, in LinuxCNC's order for the plane (G17 X Y, G18 Z X, G19 Y Z),
/// so that G3 turns from the first axis toward the second; an arc in a UVW
/// plane is refused.
fn axes(plane: Plane) -> Result<[usize; 3], LowerError> {
    super::xyz_axes(plane, "an arc")
}

/// The angle the arc turns through (radians, positive), as LinuxCNC moves
/// it.
pub fn sweep(a: &ArcInput) -> Result<f64, LowerError> {
    let [p, q, _] = axes(a.plane)?;
    let a0 = (a.start[q] - a.centre[q]).atan2(a.start[p] - a.centre[p]);
    let a1 = (a.end[q] - a.centre[q]).atan2(a.end[p] - a.centre[p]);
    let same = a.start[p] == a.end[p] && a.start[q] == a.end[q];
    let mut base = if a.clockwise { a0 - a1 } else { a1 - a0 };
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
    Ok(base + 2.0 * PI * f64::from(a.turns.max(1) - 1))
}

/// GRBL's smallest angle an arc turns (radians): one that turns less, or
/// whose end is written on its start, is a full circle there (LinuxCNC
/// takes an end on the start for a full circle too). Ten times its
/// `ARC_ANGULAR_TRAVEL_EPSILON`, for its single precision.
const LEAST_SWEEP: f64 = 5e-6;

/// Whether an arc turning `sweep` radians with chord `chord` is to be
/// written as a line: it turns so little that a controller may take it for
/// a full circle (less than GRBL's smallest angle, `LEAST_SWEEP`), or its
/// end is within `least_chord` of its start on less than half a turn,
/// where the line is off the arc by at most half the chord.
pub fn barely_turns(sweep: f64, chord: f64, least_chord: f64) -> bool {
    sweep < LEAST_SWEEP || sweep < PI && chord < least_chord
}

/// The points an arc is cut at: `parts` equal angles along its sweep, the
/// distance from the centre and the helix axis changing evenly with them.
struct ArcPath {
    axes: [usize; 3],
    a0: f64,
    sign: f64,
    total: f64,
    radius: f64,
    spiral: f64,
    parts: usize,
}

impl ArcPath {
    fn new(
        a: &ArcInput,
        axes: [usize; 3],
        radius: f64,
        spiral: f64,
        total: f64,
        parts: usize,
    ) -> ArcPath {
        let [p, q, _] = axes;
        ArcPath {
            axes,
            a0: (a.start[q] - a.centre[q]).atan2(a.start[p] - a.centre[p]),
            sign: if a.clockwise { -1.0 } else { 1.0 },
            total,
            radius,
            spiral,
            parts,
        }
    }

    /// The end of part `k` (1 to `parts`): the arc's own end for the last.
    fn point(&self, a: &ArcInput, k: usize) -> [f64; 3] {
        if k == self.parts {
            return a.end;
        }
        let [p, q, n] = self.axes;
        let t = k as f64 / self.parts as f64;
        let angle = self.a0 + self.sign * self.total * t;
        let r = self.radius + self.spiral * t;
        let mut pt = [0.0; 3];
        pt[p] = a.centre[p] + r * angle.cos();
        pt[q] = a.centre[q] + r * angle.sin();
        pt[n] = a.start[n] + (a.end[n] - a.start[n]) * t;
        pt
    }
}

/// Lowers a full circle, a P-turn arc or a spiral arc into arcs of less
/// than half a turn without P (see the module doc for the rule); an arc
/// that [`barely_turns`] (with `radius_step` as its least chord) is one
/// G1 to its end.
pub fn lower_arc(a: &ArcInput) -> Result<Vec<PlainLine>, LowerError> {
    let [p, q, n] = axes(a.plane)?;
    let radius = (a.start[q] - a.centre[q]).hypot(a.start[p] - a.centre[p]);
    if radius.is_nan() || radius <= 0.0 || !radius.is_finite() {
        return Err(LowerError::BadArc);
    }
    let total = sweep(a)?;
    let chord = (a.end[q] - a.start[q]).hypot(a.end[p] - a.start[p]);
    if barely_turns(total, chord, a.radius_step) {
        return Ok(vec![PlainLine::motion(1.0, a.end)]);
    }
    // The change of the distance from the centre over the whole sweep.
    let spiral = (a.end[q] - a.centre[q]).hypot(a.end[p] - a.centre[p]) - radius;
    let mut parts_f = (total / PI).floor() + 1.0;
    if spiral.abs() > a.radius_step {
        parts_f = parts_f.max((spiral.abs() / a.radius_step).ceil());
    }
    if parts_f > super::MAX_LINES as f64 {
        return Err(LowerError::TooManyLines);
    }
    let parts = parts_f as usize;
    let path = ArcPath::new(a, [p, q, n], radius, spiral, total, parts);
    let g = if a.clockwise { 2.0 } else { 3.0 };
    // Offset letters of the plane's first and second axes.
    let letters = [b'I', b'J', b'K'];
    let mut out = Vec::with_capacity(parts);
    let mut from = a.start;
    for k in 1..=parts {
        let to = path.point(a, k);
        let (first, second) = if p < q { (p, q) } else { (q, p) };
        push(
            &mut out,
            PlainLine::new(&[
                (b'G', g),
                (b'X', to[0]),
                (b'Y', to[1]),
                (b'Z', to[2]),
                (letters[first], a.centre[first] - from[first]),
                (letters[second], a.centre[second] - from[second]),
            ]),
        )?;
        from = to;
    }
    Ok(out)
}

/// An arc as G1 chords (for a target without arcs, or without arcs in its
/// plane): points on the arc (on the helix and spiral [`lower_arc`] follows)
/// at equal angles, close enough that no chord is further than
/// `tolerance` (program units, above 0) from the arc; an arc that
/// [`barely_turns`] is one G1 to its end.
pub fn lower_arc_chords(a: &ArcInput, tolerance: f64) -> Result<Vec<PlainLine>, LowerError> {
    let [p, q, n] = axes(a.plane)?;
    let radius = (a.start[q] - a.centre[q]).hypot(a.start[p] - a.centre[p]);
    if radius.is_nan()
        || radius <= 0.0
        || !radius.is_finite()
        || tolerance.is_nan()
        || tolerance <= 0.0
    {
        return Err(LowerError::BadArc);
    }
    let total = sweep(a)?;
    let chord = (a.end[q] - a.start[q]).hypot(a.end[p] - a.start[p]);
    if barely_turns(total, chord, a.radius_step) {
        return Ok(vec![PlainLine::motion(1.0, a.end)]);
    }
    let spiral = (a.end[q] - a.centre[q]).hypot(a.end[p] - a.centre[p]) - radius;
    // A chord over angle t of radius r is r (1 - cos(t / 2)) off the arc at
    // its middle: the largest angle within the tolerance at the largest
    // radius the arc reaches.
    let r = radius.max(radius + spiral);
    let step = if tolerance >= r {
        PI / 2.0
    } else {
        (2.0 * (1.0 - tolerance / r).acos()).min(PI / 2.0)
    };
    let parts_f = (total / step).ceil().max(1.0);
    if parts_f > super::MAX_LINES as f64 {
        return Err(LowerError::TooManyLines);
    }
    let parts = parts_f as usize;
    let path = ArcPath::new(a, [p, q, n], radius, spiral, total, parts);
    let mut out = Vec::with_capacity(parts);
    for k in 1..=parts {
        let to = path.point(a, k);
        push(&mut out, PlainLine::motion(1.0, to))?;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn words(l: &PlainLine) -> Vec<(char, f64)> {
        l.words
            .iter()
            .map(|w| (w.letter as char, w.value))
            .collect()
    }

    #[test]
    fn chords_stay_within_the_tolerance() {
        for (r, tol, clockwise) in [
            (5.0, 0.001, true),
            (0.5, 0.01, false),
            (100.0, 0.0001, true),
        ] {
            let a = ArcInput {
                plane: Plane::XZ,
                clockwise,
                start: [r, 7.0, 0.0],
                end: [-r, 9.0, 0.0],
                centre: [0.0, 0.0, 0.0],
                turns: 1,
                radius_step: 0.001,
            };
            let out = lower_arc_chords(&a, tol).unwrap();
            let mut from = a.start;
            for l in &out {
                let w = words(l);
                assert_eq!(w[0], ('G', 1.0));
                let to = [w[1].1, w[2].1, w[3].1];
                // Every end on the circle, the middle of every chord
                // within the tolerance of it (and not much closer: no
                // more chords than needed).
                assert!((to[0].hypot(to[2]) - r).abs() < 1e-9);
                let mid = (to[0] + from[0]).hypot(to[2] + from[2]) / 2.0;
                assert!(r - mid <= tol * (1.0 + 1e-9), "{r} {tol}: {}", r - mid);
                assert!(r - mid > tol * 0.25, "{r} {tol}: {}", r - mid);
                from = to;
            }
            assert_eq!(
                words(out.last().unwrap())[1..4],
                [('X', -r), ('Y', 9.0), ('Z', 0.0)]
            );
            // Half a turn: the Y of the helix half way at the middle.
            let half = &out[out.len() / 2 - 1];
            assert!(words(half)[2].1 > 7.0 && words(half)[2].1 < 9.0);
        }
    }

    #[test]
    fn full_circle_is_three_thirds() {
        let a = ArcInput {
            plane: Plane::XY,
            clockwise: true,
            start: [0.0, 0.0, 1.0],
            end: [0.0, 0.0, -2.0],
            centre: [5.0, 0.0, 0.0],
            turns: 1,
            radius_step: 0.001,
        };
        let out = lower_arc(&a).unwrap();
        assert_eq!(out.len(), 3);
        // Clockwise from (0, 0) about (5, 0): a third of a turn ends at
        // 180° - 120° = 60° from the centre.
        let w = words(&out[0]);
        assert_eq!(w[0], ('G', 2.0));
        assert!((w[1].1 - 7.5).abs() < 1e-12);
        assert!((w[2].1 - 5.0 * (PI / 3.0).sin()).abs() < 1e-12);
        assert!(w[3].1.abs() < 1e-12);
        assert_eq!((w[4], w[5]), (('I', 5.0), ('J', 0.0)));
        let w = words(&out[2]);
        assert_eq!(&w[1..4], &[('X', 0.0), ('Y', 0.0), ('Z', -2.0)]);
    }

    #[test]
    fn turns_add_whole_circles() {
        let mut a = ArcInput {
            plane: Plane::XZ,
            clockwise: false,
            start: [1.0, 0.0, 0.0],
            end: [0.0, 0.0, 1.0],
            centre: [0.0, 0.0, 0.0],
            turns: 1,
            radius_step: 0.001,
        };
        // G18: G3 turns from Z toward X; from X to Z is three quarters.
        assert!((sweep(&a).unwrap() - 1.5 * PI).abs() < 1e-12);
        a.turns = 3;
        assert!((sweep(&a).unwrap() - 5.5 * PI).abs() < 1e-12);
        assert_eq!(lower_arc(&a).unwrap().len(), 6);
        // I and K, in that order, in G18.
        let l = &lower_arc(&a).unwrap()[0];
        assert_eq!(l.words[4].letter, b'I');
        assert_eq!(l.words[5].letter, b'K');
    }

    #[test]
    fn spiral_parts_end_on_the_spiral() {
        // A half turn about (1, 0) from (0, 0) to (2.02, 0): the distance
        // from the centre goes from 1 to 1.02, 0.006 per part at most: four
        // parts of 0.005.
        let a = ArcInput {
            plane: Plane::XY,
            clockwise: true,
            start: [0.0, 0.0, 0.0],
            end: [2.02, 0.0, 0.0],
            centre: [1.0, 0.0, 0.0],
            turns: 1,
            radius_step: 0.006,
        };
        let out = lower_arc(&a).unwrap();
        assert_eq!(out.len(), 4);
        let mut from = a.start;
        for (k, l) in out.iter().enumerate() {
            let w = words(l);
            let to = [w[1].1, w[2].1, w[3].1];
            let r = (to[0] - 1.0).hypot(to[1]);
            assert!((r - (1.0 + 0.02 * (k + 1) as f64 / 4.0)).abs() < 1e-12);
            // Each part's centre is the arc's, as offsets from its start.
            assert!((w[4].1 - (1.0 - from[0])).abs() < 1e-12);
            assert!((w[5].1 + from[1]).abs() < 1e-12);
            from = to;
        }
        // Clockwise from the left of the centre: over the top (Y > 0).
        assert!(words(&out[1])[2].1 > 0.0);
        assert_eq!(words(&out[3])[1].1, 2.02);
    }

    #[test]
    fn runaway_turns_refused() {
        let a = ArcInput {
            plane: Plane::YZ,
            clockwise: true,
            start: [0.0, 1.0, 0.0],
            end: [0.0, 1.0, 0.0],
            centre: [0.0, 0.0, 0.0],
            turns: u32::MAX,
            radius_step: 0.001,
        };
        assert_eq!(lower_arc(&a), Err(LowerError::TooManyLines));
    }

    #[test]
    fn zero_radius_refused() {
        let a = ArcInput {
            plane: Plane::XY,
            clockwise: false,
            start: [1.0, 1.0, 0.0],
            end: [1.0, 1.0, 0.0],
            centre: [1.0, 1.0, 0.0],
            turns: 1,
            radius_step: 0.001,
        };
        assert_eq!(lower_arc(&a), Err(LowerError::BadArc));
    }

    #[test]
    fn uvw_planes_refused() {
        for plane in [Plane::UV, Plane::WU, Plane::VW] {
            let a = ArcInput {
                plane,
                clockwise: false,
                start: [1.0, 0.0, 0.0],
                end: [0.0, 1.0, 0.0],
                centre: [0.0, 0.0, 0.0],
                turns: 2,
                radius_step: 0.001,
            };
            assert_eq!(lower_arc(&a).map_err(|e| e.code()), Err("E1105"));
            assert_eq!(sweep(&a).map_err(|e| e.code()), Err("E1105"));
        }
    }
}
