//! Geometry of moves: arc sweeps, extreme points, path lengths and sampled
//! points, shared by the statistics, the travel-limit check and the plot.

use std::f64::consts::{FRAC_PI_2, TAU};

use crate::codes::Plane;
use crate::machine::motion::{Axes, Motion};

/// An arc or helix in its plane, ready for measuring.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ArcGeom {
    /// In-plane axes and helix axis (see [`Plane::axes`]).
    pub a: usize,
    pub b: usize,
    pub h: usize,
    /// Centre in (a, b).
    pub ca: f64,
    pub cb: f64,
    /// Start angle and signed sweep (positive counter-clockwise), radians.
    pub start: f64,
    pub sweep: f64,
    /// Radius at the start and at the end (an arc whose end point is not
    /// on the start circle is a spiral between them, as LinuxCNC moves it).
    pub r0: f64,
    pub r1: f64,
}

impl ArcGeom {
    /// `center` holds the centre's coordinates on the plane's axes in
    /// ascending axis order (X before Y before Z).
    pub(crate) fn new(
        from: &Axes,
        to: &Axes,
        center: [f64; 2],
        plane: Plane,
        ccw: bool,
        turns: u32,
    ) -> ArcGeom {
        let [a, b, h] = plane.axes();
        let (ca, cb) = if a < b {
            (center[0], center[1])
        } else {
            (center[1], center[0])
        };
        let (sa, sb) = (from[a] - ca, from[b] - cb);
        let (ea, eb) = (to[a] - ca, to[b] - cb);
        let start = sb.atan2(sa);
        let end = eb.atan2(ea);
        let r0 = sa.hypot(sb);
        let r1 = ea.hypot(eb);
        let extra = TAU * f64::from(turns.max(1) - 1);
        let sweep = if ccw {
            let mut d = end - start;
            if d <= 1e-12 {
                d += TAU;
            }
            d + extra
        } else {
            let mut d = start - end;
            if d <= 1e-12 {
                d += TAU;
            }
            -(d + extra)
        };
        ArcGeom {
            a,
            b,
            h,
            ca,
            cb,
            start,
            sweep,
            r0,
            r1,
        }
    }

    /// The in-plane point at fraction `t` (0..1) of the sweep.
    pub(crate) fn at(&self, t: f64) -> (f64, f64) {
        let ang = self.start + self.sweep * t;
        let r = self.r0 + (self.r1 - self.r0) * t;
        (self.ca + r * ang.cos(), self.cb + r * ang.sin())
    }

    /// Fractions of the sweep (strictly inside it) where the arc crosses an
    /// axis direction of its plane: its in-plane extreme points.
    pub(crate) fn quadrant_crossings(&self) -> Vec<f64> {
        let mut out = Vec::new();
        let total = self.sweep.abs();
        if total <= 0.0 || !total.is_finite() {
            return out;
        }
        let dir = self.sweep.signum();
        // First multiple of pi/2 strictly beyond the start in the direction of travel.
        let k0 = if dir > 0.0 {
            (self.start / FRAC_PI_2).floor() + 1.0
        } else {
            (self.start / FRAC_PI_2).ceil() - 1.0
        };
        // Distance (radians) from the start to the first crossing, then one
        // every quarter turn. Extremes lie on the first or the last pass of
        // each direction (the radius changes monotonically along a spiral),
        // so the first four and the last four crossings are enough.
        let d0 = (k0 * FRAC_PI_2 - self.start) * dir;
        let room = total - 1e-12 - d0;
        if room <= 0.0 {
            return out;
        }
        let n = (room / FRAC_PI_2).floor() as u64 + 1;
        for j in (0..n.min(4)).chain(n.saturating_sub(4).max(4)..n) {
            let d = d0 + j as f64 * FRAC_PI_2;
            if d < total - 1e-12 {
                out.push(d / total);
            }
        }
        out
    }

    /// Length of the path in the plane (spiral approximated by the mean radius).
    pub(crate) fn plane_length(&self) -> f64 {
        0.5 * (self.r0 + self.r1) * self.sweep.abs()
    }
}

/// Length of a straight move over X, Y and Z (rotary and UVW axes do not
/// count).
pub(crate) fn line_length(from: &Axes, to: &Axes) -> f64 {
    let dx = to[0] - from[0];
    let dy = to[1] - from[1];
    let dz = to[2] - from[2];
    (dx * dx + dy * dy + dz * dz).sqrt()
}

/// Length of an arc or helix over X, Y and Z.
pub(crate) fn arc_length(g: &ArcGeom, from: &Axes, to: &Axes) -> f64 {
    let p = g.plane_length();
    let dh = to[g.h] - from[g.h];
    (p * p + dh * dh).sqrt()
}

/// The points of a move where an axis can take its extreme value: the end
/// points, and for an arc the quadrant crossings (work coordinates). Calls
/// `f` with each point; the start point is included.
pub(crate) fn extreme_points(m: &Motion, mut f: impl FnMut(&Axes)) {
    match m {
        Motion::Line { from, to, .. } => {
            f(&from.work);
            f(&to.work);
        }
        Motion::Arc {
            from,
            to,
            center,
            plane,
            ccw,
            turns,
            ..
        } => {
            f(&from.work);
            f(&to.work);
            let g = ArcGeom::new(&from.work, &to.work, *center, *plane, *ccw, *turns);
            for t in g.quadrant_crossings() {
                f(&arc_point(&g, &from.work, &to.work, t));
            }
        }
        _ => {}
    }
}

/// The full position at fraction `t` of an arc: in-plane from the circle,
/// every other axis linearly between the end points.
pub(crate) fn arc_point(g: &ArcGeom, from: &Axes, to: &Axes, t: f64) -> Axes {
    let (pa, pb) = g.at(t);
    let mut p: Axes = std::array::from_fn(|i| from[i] + (to[i] - from[i]) * t);
    p[g.a] = pa;
    p[g.b] = pb;
    p
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ax(x: f64, y: f64, z: f64) -> Axes {
        let mut a = [0.0; 9];
        a[0] = x;
        a[1] = y;
        a[2] = z;
        a
    }

    #[test]
    fn ccw_quarter_crosses_nothing_inside() {
        // From (1,0) to (0,1) about the origin, counter-clockwise: no
        // crossing strictly inside.
        let g = ArcGeom::new(
            &ax(1.0, 0.0, 0.0),
            &ax(0.0, 1.0, 0.0),
            [0.0, 0.0],
            Plane::XY,
            true,
            1,
        );
        assert!((g.sweep - FRAC_PI_2).abs() < 1e-12);
        assert!(g.quadrant_crossings().is_empty());
    }

    #[test]
    fn cw_half_crosses_minus_y() {
        // From (-1,0) to (1,0) clockwise goes over the top (+Y).
        let g = ArcGeom::new(
            &ax(-1.0, 0.0, 0.0),
            &ax(1.0, 0.0, 0.0),
            [0.0, 0.0],
            Plane::XY,
            false,
            1,
        );
        let c = g.quadrant_crossings();
        assert_eq!(c.len(), 1);
        let p = g.at(c[0]);
        assert!(p.0.abs() < 1e-12 && (p.1 - 1.0).abs() < 1e-12, "{p:?}");
        // Counter-clockwise goes under it.
        let g = ArcGeom::new(
            &ax(-1.0, 0.0, 0.0),
            &ax(1.0, 0.0, 0.0),
            [0.0, 0.0],
            Plane::XY,
            true,
            1,
        );
        let p = g.at(g.quadrant_crossings()[0]);
        assert!((p.1 + 1.0).abs() < 1e-12, "{p:?}");
    }

    #[test]
    fn full_circle_has_four_crossings() {
        let g = ArcGeom::new(
            &ax(1.0, 0.0, 0.0),
            &ax(1.0, 0.0, 0.0),
            [0.0, 0.0],
            Plane::XY,
            true,
            1,
        );
        assert!((g.sweep - TAU).abs() < 1e-12);
        assert_eq!(g.quadrant_crossings().len(), 3);
        let g = ArcGeom::new(
            &ax(0.5, 0.5, 0.0),
            &ax(0.5, 0.5, 0.0),
            [0.0, 0.0],
            Plane::XY,
            false,
            3,
        );
        // Three turns: the first and the last pass in each direction.
        assert_eq!(g.quadrant_crossings().len(), 8);
    }

    #[test]
    fn xz_plane_orders_z_first() {
        // G18 counter-clockwise works in the (Z, X) frame: the start
        // (z=0, x=1) is at 90 degrees; half way to x=-1 it is at 180: z=-1.
        let g = ArcGeom::new(
            &ax(1.0, 0.0, 0.0),
            &ax(-1.0, 0.0, 0.0),
            [0.0, 0.0],
            Plane::XZ,
            true,
            1,
        );
        let p = arc_point(&g, &ax(1.0, 0.0, 0.0), &ax(-1.0, 0.0, 0.0), 0.5);
        assert!((p[2] + 1.0).abs() < 1e-12 && p[0].abs() < 1e-12, "{p:?}");
    }

    #[test]
    fn helix_length() {
        let g = ArcGeom::new(
            &ax(1.0, 0.0, 0.0),
            &ax(1.0, 0.0, 2.0),
            [0.0, 0.0],
            Plane::XY,
            true,
            1,
        );
        let l = arc_length(&g, &ax(1.0, 0.0, 0.0), &ax(1.0, 0.0, 2.0));
        assert!((l - (TAU * TAU + 4.0).sqrt()).abs() < 1e-12);
    }
}
