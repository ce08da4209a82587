//! Splines: G5 and G5.1 lowered into G1 segments within the tolerance,
//! G5.2/G5.3 NURBS collected and lowered at G5.3, and the I J written on
//! every G5 the target runs itself.

use crate::block::{Block, Distance, FeedMode, LatheMode, MotionMode, Plane};
use crate::controller::lower::{self, PlainLine};
use crate::diag::ErrorKind;
use crate::machine::FlatMachine;

use super::Lowering;

/// A NURBS being collected (G5.2 blocks), in program units.
pub(super) struct NurbsCurve {
    points: Vec<lower::spline::NurbsPoint>,
    order: usize,
    /// The current point when the first G5.2 came (G91 points are
    /// relative to it: LinuxCNC moves nothing until G5.3).
    start: [f64; 2],
}

impl Lowering {
    /// A G5 the target runs itself: its I J are written on every block,
    /// since the target would take a missing pair as minus the block's own
    /// P Q, where LinuxCNC reflects the previous block's P Q.
    pub(super) fn native_g5_words(
        &mut self,
        b: &Block,
        before: &FlatMachine,
        extra: &mut Vec<(u8, f64)>,
    ) {
        let motion = b.motion().unwrap_or(before.modes.motion);
        if motion != MotionMode::CubicSpline || !self.p.has_g(50) || !b.has_axis() {
            return;
        }
        let (i, j) = (b.value(b'I'), b.value(b'J'));
        match (i, j) {
            (None, None) => {
                let [p, q] = self.last_pq.unwrap_or([0.0, 0.0]);
                extra.push((b'I', -p));
                extra.push((b'J', -q));
            }
            (Some(_), None) => extra.push((b'J', 0.0)),
            (None, Some(_)) => extra.push((b'I', 0.0)),
            (Some(_), Some(_)) => {}
        }
        self.last_pq = Some([b.value(b'P').unwrap_or(0.0), b.value(b'Q').unwrap_or(0.0)]);
    }

    /// G5/G5.1 as G1 segments within the tolerance.
    pub(super) fn lower_spline(
        &mut self,
        b: &Block,
        before: &FlatMachine,
        motion: MotionMode,
    ) -> Result<Vec<PlainLine>, ErrorKind> {
        if self.m.modes.plane != Plane::XY {
            return Err(self.refuse("a spline outside G17", "LinuxCNC draws them only in XY"));
        }
        let name = if motion == MotionMode::CubicSpline {
            "G5"
        } else {
            "G5.1"
        };
        if self.m.modes.feed_mode == FeedMode::InverseTime {
            return Err(ErrorKind::TargetLowering {
                target: self.name(),
                code: "E1004",
                message: format!(
                    "a spline ({name}) in G93 is not lowered; its segments would each need their own inverse-time feed"
                ),
            });
        }
        let start = self.xy_known(before, &format!("{name} (spline)"))?;
        let end = self.xy_known(&self.m, &format!("{name} (spline)"))?;
        let tol = self.opts.tolerance_mm / self.m.scale();
        let ij = match (b.value(b'I'), b.value(b'J')) {
            (None, None) if motion == MotionMode::CubicSpline => {
                // After a G5, the previous P Q reflected.
                self.last_pq.map(|[p, q]| [-p, -q]).unwrap_or([0.0, 0.0])
            }
            (i, j) => [i.unwrap_or(0.0), j.unwrap_or(0.0)],
        };
        let r = if motion == MotionMode::CubicSpline {
            let pq = [b.value(b'P').unwrap_or(0.0), b.value(b'Q').unwrap_or(0.0)];
            self.last_pq = Some(pq);
            lower::spline::lower_g5(start, ij, pq, end, tol)
        } else {
            lower::spline::lower_g5_1(start, ij, end, tol)
        };
        r.map_err(|e| self.lower_error(e))
    }

    /// G5.2 blocks collect control points (nothing is written for them:
    /// LinuxCNC moves only at G5.3); G5.3 writes the curve as G1 segments
    /// within the tolerance, with the feed in effect. The control points
    /// are the current point (weight P of a first block without X Y, or
    /// one) and each block's X Y (G91: from the point the curve starts at)
    /// with its weight P; the order is 3, or an L above 3.
    pub(super) fn lower_nurbs_block(
        &mut self,
        b: &Block,
        before: &FlatMachine,
        motion: MotionMode,
    ) -> Result<Option<Vec<PlainLine>>, ErrorKind> {
        let not_lowered = |s: &Self, message: &str| ErrorKind::TargetLowering {
            target: s.name(),
            code: "E1004",
            message: message.into(),
        };
        if motion == MotionMode::NurbsEnd {
            if b.motion() != Some(MotionMode::NurbsEnd) {
                return Ok(None);
            }
            let Some(curve) = self.nurbs.take() else {
                return Err(not_lowered(self, "G5.3 without control points (G5.2)"));
            };
            let tol = self.opts.tolerance_mm / self.m.scale();
            let mut lines = lower::spline::lower_nurbs(&curve.points, curve.order, tol)
                .map_err(|e| self.lower_error(e))?;
            if let Some(first) = lines.first_mut() {
                // The feed the curve runs at (a G5.2 block may have set it).
                first.words.push(lower::Word {
                    letter: b'F',
                    value: self.m.modes.feed,
                });
            }
            if let Some(last) = curve.points.last() {
                let s = self.m.scale();
                self.m.pos[0] = Some(last.x * s);
                self.m.pos[1] = Some(last.y * s);
            }
            return Ok(Some(lines));
        }
        let pending = before.modes.motion == MotionMode::Nurbs && self.nurbs.is_some();
        if pending && b.units().is_some_and(|u| u != before.modes.units) {
            return Err(not_lowered(
                self,
                "G20/G21 between G5.2 and G5.3 is not lowered (LinuxCNC keeps the points already given in the old units)",
            ));
        }
        if b.motion() != Some(MotionMode::Nurbs) && !b.has_axis() {
            return Ok(None);
        }
        // Nothing moves until G5.3.
        self.m.pos = before.pos;
        if self.m.modes.plane != Plane::XY {
            return Err(self.refuse("a NURBS outside G17", "LinuxCNC draws them only in XY"));
        }
        if self.feed_rewrite || self.m.modes.feed_mode != FeedMode::PerMinute {
            return Err(not_lowered(
                self,
                "a NURBS (G5.2) in G93 or G95 is not lowered; the segments are written with a feed per minute",
            ));
        }
        if self.m.modes.lathe == LatheMode::Diameter {
            return Err(not_lowered(
                self,
                "a NURBS (G5.2) in G7 (diameter mode) is not lowered",
            ));
        }
        let fresh = !pending;
        let (x, y) = (b.value(b'X'), b.value(b'Y'));
        if fresh {
            let start = self.xy_known(before, "G5.2 (NURBS)")?;
            let weight = match (x, y, b.value(b'P')) {
                (None, None, Some(p)) if p > 0.0 => p,
                _ => 1.0,
            };
            self.nurbs = Some(NurbsCurve {
                points: vec![lower::spline::NurbsPoint {
                    x: start[0],
                    y: start[1],
                    weight,
                }],
                order: 3,
                start,
            });
        }
        let incremental = self.m.modes.distance == Distance::Incremental;
        if let Some(c) = self.nurbs.as_mut() {
            if let Some(l) = b.value(b'L').map(f64::round)
                && l > 3.0
            {
                c.order = l.min(1000.0) as usize;
            }
            if let (Some(x), Some(y)) = (x, y) {
                let (x, y) = if incremental {
                    (c.start[0] + x, c.start[1] + y)
                } else {
                    (x, y)
                };
                c.points.push(lower::spline::NurbsPoint {
                    x,
                    y,
                    // LinuxCNC takes a missing P as -1 (refused when lowered).
                    weight: b.value(b'P').unwrap_or(-1.0),
                });
            }
        }
        Ok(Some(Vec::new()))
    }
}
