//! An arc or helix in its plane: centre, start angle, signed sweep and
//! radii, worked out once from a move's end points and centre. The view
//! (statistics, plot, travel limits) and the run-time model both measure
//! arcs with it; the only difference between them, how close to zero a
//! sweep may come before it is a full circle, is the [`FullCircle`] rule
//! each passes.

use std::f64::consts::{FRAC_PI_2, TAU};

use crate::codes::Plane;

/// When a sweep that comes out as (nearly) zero is a full circle.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum FullCircle {
    /// Only when start and end coincide (to 1e-12 rad), as LinuxCNC moves
    /// it.
    Exact,
    /// Within GRBL's `ARC_ANGULAR_TRAVEL_EPSILON` (5e-7 rad), as
    /// `mc_arc()` cuts it (gnea/grbl `bfb67f0c`, `config.h`).
    Grbl,
}

impl FullCircle {
    fn epsilon(self) -> f64 {
        match self {
            FullCircle::Exact => 1e-12,
            FullCircle::Grbl => 5e-7,
        }
    }
}

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
    /// Start angle and signed sweep (positive counter-clockwise), radians,
    /// full turns included.
    pub start: f64,
    pub sweep: f64,
    /// Radius at the start and at the end (an arc whose end point is not
    /// on the start circle is a spiral between them, as LinuxCNC moves it).
    pub r0: f64,
    pub r1: f64,
}

impl ArcGeom {
    /// The arc from `from` to `to` (axes in parameter order, X Y Z A B C U
    /// V W) about `center`, the centre's coordinates on the plane's axes
    /// in ascending axis order (X before Y before Z); `turns` is 1 for less
    /// than one turn.
    pub(crate) fn new(
        from: &[f64; 9],
        to: &[f64; 9],
        center: [f64; 2],
        plane: Plane,
        ccw: bool,
        turns: u32,
        rule: FullCircle,
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
        let extra = TAU * f64::from(turns.max(1) - 1);
        let eps = rule.epsilon();
        let sweep = if ccw {
            let mut d = end - start;
            if d <= eps {
                d += TAU;
            }
            d + extra
        } else {
            let mut d = start - end;
            if d <= eps {
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
            r0: sa.hypot(sb),
            r1: ea.hypot(eb),
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

    /// Length of the arc or helix over its plane and helix axis.
    pub(crate) fn length(&self, from: &[f64; 9], to: &[f64; 9]) -> f64 {
        let p = self.plane_length();
        let dh = to[self.h] - from[self.h];
        (p * p + dh * dh).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ax(x: f64, y: f64, z: f64) -> [f64; 9] {
        let mut a = [0.0; 9];
        a[0] = x;
        a[1] = y;
        a[2] = z;
        a
    }

    /// An end point 1e-8 rad short of the start, counter-clockwise: an arc
    /// of 1e-8 rad by the exact rule, a full circle by GRBL's.
    #[test]
    fn the_full_circle_rule() {
        let e = 1e-8f64;
        let from = ax(1.0, 0.0, 0.0);
        let to = ax(e.cos(), e.sin(), 0.0);
        let new = |rule| ArcGeom::new(&from, &to, [0.0, 0.0], Plane::XY, true, 1, rule);
        assert!((new(FullCircle::Exact).sweep - e).abs() < 1e-15);
        assert!((new(FullCircle::Grbl).sweep - (TAU + e)).abs() < 1e-12);
        // Start and end the same: a full circle either way.
        for rule in [FullCircle::Exact, FullCircle::Grbl] {
            let g = ArcGeom::new(&from, &from, [0.0, 0.0], Plane::XY, false, 1, rule);
            assert!((g.sweep + TAU).abs() < 1e-12);
        }
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
            FullCircle::Exact,
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
            FullCircle::Exact,
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
            FullCircle::Exact,
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
            FullCircle::Exact,
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
            FullCircle::Exact,
        );
        // Three turns: the first and the last pass in each direction.
        assert_eq!(g.quadrant_crossings().len(), 8);
    }

    #[test]
    fn helix_length() {
        let (from, to) = (ax(1.0, 0.0, 0.0), ax(1.0, 0.0, 2.0));
        let g = ArcGeom::new(
            &from,
            &to,
            [0.0, 0.0],
            Plane::XY,
            true,
            1,
            FullCircle::Exact,
        );
        assert!((g.length(&from, &to) - (TAU * TAU + 4.0).sqrt()).abs() < 1e-12);
    }
}
