//! Geometry of moves: arc sweeps, extreme points, path lengths and sampled
//! points, shared by the statistics, the travel-limit check and the plot.

use crate::machine::motion::{Axes, Motion};

pub(crate) use crate::geom::arc::ArcGeom;

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
    g.length(from, to)
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
            let g = ArcGeom::new(
                &from.work,
                &to.work,
                *center,
                *plane,
                *ccw,
                *turns,
                crate::geom::arc::FullCircle::Exact,
            );
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
    use crate::codes::Plane;
    use crate::geom::arc::FullCircle;

    fn ax(x: f64, y: f64, z: f64) -> Axes {
        let mut a = [0.0; 9];
        a[0] = x;
        a[1] = y;
        a[2] = z;
        a
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
            FullCircle::Exact,
        );
        let p = arc_point(&g, &ax(1.0, 0.0, 0.0), &ax(-1.0, 0.0, 0.0), 0.5);
        assert!((p[2] + 1.0).abs() < 1e-12 && p[0].abs() < 1e-12, "{p:?}");
    }
}
