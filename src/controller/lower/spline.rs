//! Splines (G5 cubic, G5.1 quadratic, G5.2/G5.3 NURBS) as G1 segments.
//!
//! The curves (LinuxCNC 2.9, XY plane only):
//!
//! * **G5** `X Y I J P Q` from the current point S to E = (X, Y): the cubic
//!   Bézier with control points S, S + (I, J), E + (P, Q), E. Without I J
//!   after another G5, (I, J) is −(P, Q) of that block (the curve goes on
//!   in the direction it ended in): the caller resolves that.
//! * **G5.1** `X Y I J`: the quadratic Bézier S, S + (I, J), E.
//! * **G5.2 … G5.3** with order L (k) and weights P: the NURBS whose control
//!   points are the current point followed by the block's points, with the
//!   clamped uniform knot vector LinuxCNC builds (k zeros, then 1, 2, …,
//!   then k times n − k + 2 for n + 1 points), rational with the weights.
//!
//! The lowering: the curve is cut into rational Bézier pieces (knot
//! insertion), each piece halved (de Casteljau, in homogeneous
//! coordinates) until its control polygon lies within `tolerance` of the
//! chord between its ends; then, since the piece lies in the convex hull
//! of its control points (positive weights), every point of it is within
//! `tolerance` of that chord. Each chord is one `G1 X Y` block (Z and the
//! other axes unchanged); the last block ends exactly at the curve's end.
//! The tolerance is in program units: 0.001 mm is 0.001/25.4 in G20.

use super::{LowerError, PlainLine, push};

/// A point with weight, in homogeneous form (w·x, w·y, w).
type H = [f64; 3];

fn project(h: &H) -> [f64; 2] {
    [h[0] / h[2], h[1] / h[2]]
}

fn lerp(a: &H, b: &H, t: f64) -> H {
    [
        a[0] + (b[0] - a[0]) * t,
        a[1] + (b[1] - a[1]) * t,
        a[2] + (b[2] - a[2]) * t,
    ]
}

/// Distance from `p` to the segment `a`–`b`.
fn dist_to_segment(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p[0] - (a[0] + t * dx)).hypot(p[1] - (a[1] + t * dy))
}

/// Halving depth limit: 2^-50 of a piece is far below any tolerance.
const MAX_DEPTH: u32 = 50;

/// Writes G1 blocks for one rational Bézier piece.
fn flatten(
    ctrl: &[H],
    tolerance: f64,
    depth: u32,
    out: &mut Vec<PlainLine>,
) -> Result<(), LowerError> {
    let (first, last) = match (ctrl.first(), ctrl.last()) {
        (Some(f), Some(l)) => (project(f), project(l)),
        _ => return Ok(()),
    };
    let flat = ctrl[1..ctrl.len() - 1]
        .iter()
        .all(|c| dist_to_segment(project(c), first, last) <= tolerance);
    if flat || depth >= MAX_DEPTH {
        return push(
            out,
            PlainLine::new(&[(b'G', 1.0), (b'X', last[0]), (b'Y', last[1])]),
        );
    }
    // de Casteljau at 1/2.
    let n = ctrl.len();
    let mut left = Vec::with_capacity(n);
    let mut right = vec![[0.0; 3]; n];
    let mut work = ctrl.to_vec();
    left.push(work[0]);
    right[n - 1] = work[n - 1];
    for level in 1..n {
        for i in 0..n - level {
            work[i] = lerp(&work[i], &work[i + 1], 0.5);
        }
        left.push(work[0]);
        right[n - 1 - level] = work[n - 1 - level];
    }
    flatten(&left, tolerance, depth + 1, out)?;
    flatten(&right, tolerance, depth + 1, out)
}

fn check_tolerance(construct: &'static str, tolerance: f64) -> Result<(), LowerError> {
    if tolerance.is_nan() || tolerance <= 0.0 || !tolerance.is_finite() {
        return Err(LowerError::BadValue {
            construct,
            what: "the tolerance is not a positive number",
        });
    }
    Ok(())
}

/// Replaces the last block's end by the exact end point.
fn exact_end(out: &mut [PlainLine], end: [f64; 2]) {
    if let Some(l) = out.last_mut() {
        for w in &mut l.words {
            match w.letter {
                b'X' => w.value = end[0],
                b'Y' => w.value = end[1],
                _ => {}
            }
        }
    }
}

/// G5: the cubic Bézier from `start` through the control points
/// `start + ij` and `end + pq` to `end`, as G1 blocks within `tolerance`.
pub fn lower_g5(
    start: [f64; 2],
    ij: [f64; 2],
    pq: [f64; 2],
    end: [f64; 2],
    tolerance: f64,
) -> Result<Vec<PlainLine>, LowerError> {
    check_tolerance("G5", tolerance)?;
    let ctrl = [
        [start[0], start[1], 1.0],
        [start[0] + ij[0], start[1] + ij[1], 1.0],
        [end[0] + pq[0], end[1] + pq[1], 1.0],
        [end[0], end[1], 1.0],
    ];
    let mut out = Vec::new();
    flatten(&ctrl, tolerance, 0, &mut out)?;
    exact_end(&mut out, end);
    Ok(out)
}

/// G5.1: the quadratic Bézier from `start` through `start + ij` to `end`,
/// as G1 blocks within `tolerance`.
pub fn lower_g5_1(
    start: [f64; 2],
    ij: [f64; 2],
    end: [f64; 2],
    tolerance: f64,
) -> Result<Vec<PlainLine>, LowerError> {
    check_tolerance("G5.1", tolerance)?;
    let ctrl = [
        [start[0], start[1], 1.0],
        [start[0] + ij[0], start[1] + ij[1], 1.0],
        [end[0], end[1], 1.0],
    ];
    let mut out = Vec::new();
    flatten(&ctrl, tolerance, 0, &mut out)?;
    exact_end(&mut out, end);
    Ok(out)
}

/// A NURBS control point: X, Y and weight P.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NurbsPoint {
    pub x: f64,
    pub y: f64,
    pub weight: f64,
}

/// LinuxCNC's knot vector for `count` control points of order `order`.
pub fn knot_vector(count: usize, order: usize) -> Vec<f64> {
    let n = count.saturating_sub(1);
    (0..=n + order)
        .map(|i| {
            if i < order {
                0.0
            } else if i <= n {
                (i + 1 - order) as f64
            } else {
                (n + 2 - order) as f64
            }
        })
        .collect()
}

/// G5.2/G5.3: the NURBS of `order` (L) through `points` (the current
/// point first, with its weight), as G1 blocks within `tolerance`.
pub fn lower_nurbs(
    points: &[NurbsPoint],
    order: usize,
    tolerance: f64,
) -> Result<Vec<PlainLine>, LowerError> {
    const NAME: &str = "G5.2";
    check_tolerance(NAME, tolerance)?;
    if order < 2 || points.len() < order {
        return Err(LowerError::BadValue {
            construct: NAME,
            what: "fewer control points than the order, or an order below 2",
        });
    }
    if points
        .iter()
        .any(|p| p.weight.is_nan() || p.weight <= 0.0 || !p.weight.is_finite())
    {
        return Err(LowerError::BadValue {
            construct: NAME,
            what: "a weight (P) is not above zero",
        });
    }
    let p = order - 1;
    let mut knots = knot_vector(points.len(), order);
    let mut ctrl: Vec<H> = points
        .iter()
        .map(|c| [c.x * c.weight, c.y * c.weight, c.weight])
        .collect();
    // Raise every interior knot to multiplicity p (Boehm insertion).
    let interior: Vec<f64> = {
        let mut v: Vec<f64> = knots[order..knots.len() - order].to_vec();
        v.dedup();
        v
    };
    for &u in &interior {
        let mult = knots.iter().filter(|&&k| k == u).count();
        for _ in mult..p {
            // Span: the last index s with knots[s] <= u.
            let s = knots.iter().rposition(|&k| k <= u).unwrap_or(0);
            let mut next = Vec::with_capacity(ctrl.len() + 1);
            for i in 0..=ctrl.len() {
                let q = if i + p <= s {
                    ctrl[i]
                } else if i > s {
                    ctrl[i - 1]
                } else {
                    let a = (u - knots[i]) / (knots[i + p] - knots[i]);
                    lerp(&ctrl[i - 1], &ctrl[i], a)
                };
                next.push(q);
            }
            ctrl = next;
            knots.insert(s + 1, u);
        }
    }
    let mut out = Vec::new();
    let mut i = 0;
    while i + p < ctrl.len() {
        flatten(&ctrl[i..=i + p], tolerance, 0, &mut out)?;
        i += p;
    }
    if let Some(last) = points.last() {
        exact_end(&mut out, [last.x, last.y]);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn knots_as_linuxcnc_builds_them() {
        assert_eq!(knot_vector(4, 4), [0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0]);
        assert_eq!(knot_vector(5, 3), [0.0, 0.0, 0.0, 1.0, 2.0, 3.0, 3.0, 3.0]);
    }

    #[test]
    fn straight_bezier_is_one_line() {
        let out = lower_g5([0.0, 0.0], [1.0, 0.0], [-1.0, 0.0], [3.0, 0.0], 0.001).unwrap();
        assert_eq!(out.len(), 1);
        assert_eq!(out[0].words[1].value, 3.0);
    }

    #[test]
    fn bad_inputs_refused() {
        assert!(lower_g5_1([0.0; 2], [1.0, 1.0], [2.0, 0.0], 0.0).is_err());
        let pts = [
            NurbsPoint {
                x: 0.0,
                y: 0.0,
                weight: 1.0,
            },
            NurbsPoint {
                x: 1.0,
                y: 1.0,
                weight: -1.0,
            },
            NurbsPoint {
                x: 2.0,
                y: 0.0,
                weight: 1.0,
            },
        ];
        assert_eq!(lower_nurbs(&pts, 3, 0.01).unwrap_err().code(), "E1103");
        assert_eq!(lower_nurbs(&pts[..2], 3, 0.01).unwrap_err().code(), "E1103");
    }
}
