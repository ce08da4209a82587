//! The travel-limit check: every move's end point and, for arcs, their
//! extreme points must stay inside the machine's envelope (machine
//! coordinates).

use super::geom::{ArcGeom, arc_point};
use crate::diag::ErrorKind;
use crate::diag::LimitError;
use crate::machine::axes::{LETTERS, MachineAxes};
use crate::machine::motion::{Axes, Motion};

/// Checks moves against a machine envelope.
#[derive(Debug, Clone)]
pub(crate) struct LimitCheck {
    axes: MachineAxes,
}

impl LimitCheck {
    /// `None` when no axis has a limit.
    pub(crate) fn new(axes: &MachineAxes) -> Option<LimitCheck> {
        axes.has_limits().then(|| LimitCheck { axes: axes.clone() })
    }

    /// The first violation of one motion event, if any.
    pub(crate) fn check(&self, m: &Motion) -> Result<(), ErrorKind> {
        let (from, to) = match m {
            Motion::Line { from, to, .. } | Motion::Arc { from, to, .. } => (from, to),
            _ => return Ok(()),
        };
        let Some(off) = to.offset else {
            return Err(ErrorKind::Limit(LimitError::LimitNeedsOffsets));
        };
        // Work positions along the move where an axis is extreme, in the
        // order the tool reaches them (so the first violation is the first
        // one on the path), the end point last.
        let mut points: Vec<Axes> = Vec::new();
        if let Motion::Arc {
            center,
            plane,
            ccw,
            turns,
            ..
        } = m
        {
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
                points.push(arc_point(&g, &from.work, &to.work, t));
            }
        }
        points.push(to.work);
        for p in &points {
            for (i, a) in self.axes.axes.iter().enumerate() {
                let v = p[i] + off[i];
                if (a.min.is_some() || a.max.is_some()) && !v.is_finite() {
                    return Err(ErrorKind::Limit(LimitError::LimitNeedsOffsets));
                }
                let tol = |b: f64| 1e-9 * b.abs().max(1.0);
                let source = || a.limit_source.clone().unwrap_or_default();
                if let Some(lo) = a.min
                    && v < lo - tol(lo)
                {
                    return Err(ErrorKind::Limit(LimitError::TravelLimit {
                        axis: LETTERS[i],
                        value: v,
                        bound: lo,
                        above: false,
                        source: source(),
                    }));
                }
                if let Some(hi) = a.max
                    && v > hi + tol(hi)
                {
                    return Err(ErrorKind::Limit(LimitError::TravelLimit {
                        axis: LETTERS[i],
                        value: v,
                        bound: hi,
                        above: true,
                        source: source(),
                    }));
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::codes::{FeedMode, Plane};
    use crate::machine::motion::{Feed, MoveKind, Point};

    fn pt(x: f64, y: f64, off: Option<f64>) -> Point {
        let mut w = [0.0; 9];
        w[0] = x;
        w[1] = y;
        Point {
            work: w,
            offset: off.map(|o| [o; 9]),
        }
    }
    const F: Feed = Feed {
        rate: 100.0,
        mode: FeedMode::PerMinute,
    };

    fn check() -> LimitCheck {
        let mut a = MachineAxes::default();
        a.add_limits("X0:100,Y0:50").unwrap();
        LimitCheck::new(&a).unwrap()
    }

    #[test]
    fn line_inside_and_outside() {
        let c = check();
        let line = |x, off| Motion::Line {
            kind: MoveKind::Feed,
            from: pt(0.0, 0.0, Some(off)),
            to: pt(x, 0.0, Some(off)),
            feed: F,
        };
        assert!(c.check(&line(100.0, 0.0)).is_ok());
        // Work 95 + offset 10 is machine 105.
        match c.check(&line(95.0, 10.0)) {
            Err(ErrorKind::Limit(LimitError::TravelLimit {
                axis: 'X',
                value,
                bound,
                above: true,
                ..
            })) => assert_eq!((value, bound), (105.0, 100.0)),
            other => panic!("{other:?}"),
        }
        let unknown = Motion::Line {
            kind: MoveKind::Feed,
            from: pt(0.0, 0.0, None),
            to: pt(1.0, 0.0, None),
            feed: F,
        };
        assert_eq!(
            c.check(&unknown),
            Err(ErrorKind::Limit(LimitError::LimitNeedsOffsets))
        );
    }

    #[test]
    fn arc_bulge_leaves_although_ends_are_inside() {
        let c = check();
        // From (10,45) to (30,45) clockwise about (20,45): bulges to Y=55.
        let arc = |ccw| Motion::Arc {
            from: pt(10.0, 45.0, Some(0.0)),
            to: pt(30.0, 45.0, Some(0.0)),
            center: [20.0, 45.0],
            plane: Plane::XY,
            ccw,
            turns: 1,
            feed: F,
        };
        match c.check(&arc(false)) {
            Err(ErrorKind::Limit(LimitError::TravelLimit {
                axis: 'Y', value, ..
            })) => {
                assert!((value - 55.0).abs() < 1e-9)
            }
            other => panic!("{other:?}"),
        }
        // Counter-clockwise it dips to Y=35: inside.
        assert!(c.check(&arc(true)).is_ok());
    }
}
