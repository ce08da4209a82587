//! NURBS blocks: G5.2 lines collect control points without moving, G5.3
//! moves to the last point and leaves no motion mode (`#<_motion_mode>` reads
//! -1). The points survive a switch to another motion until the next G5.2,
//! as in the reference, whose checks depend on how many are pending.

use super::{Machine, Unknown};
use crate::codes::{CutterComp, MotionMode};

/// Motion mode of a NURBS block (G5.2).
pub(crate) const NURBS: MotionMode = MotionMode::Nurbs;
/// What G5.3 leaves: no motion mode (kept as G5.3, read as -1).
pub(crate) const NO_MOTION: MotionMode = MotionMode::NurbsEnd;

/// Control points collected since the last G5.3.
#[derive(Debug, Clone)]
pub(crate) struct Nurbs {
    points: u32,
    order: u32,
    /// X and Y of the last point.
    last: [Result<f64, Unknown>; 2],
}

impl Default for Nurbs {
    fn default() -> Nurbs {
        Nurbs {
            points: 0,
            order: 3,
            last: [Err(Unknown::Start), Err(Unknown::Start)],
        }
    }
}

impl Nurbs {
    /// Points are pending (a G5.2 block was started and not ended).
    pub(crate) fn pending(&self) -> bool {
        self.points > 0
    }

    /// The order, if fewer points than it are pending.
    pub(crate) fn short_of_order(&self) -> Option<u32> {
        (self.points < self.order).then_some(self.order)
    }
}

impl Machine {
    /// G5.3 on `line` (checked by `check_block`): the move to the last
    /// control point.
    pub(in crate::eval) fn nurbs_end(&mut self, line: u32) {
        let [x, y] = std::mem::replace(
            &mut self.nurbs.last,
            [Err(Unknown::Start), Err(Unknown::Start)],
        );
        self.nurbs.points = 0;
        self.modal.motion = NO_MOTION;
        if self.rotated || self.modal.cutter_comp != CutterComp::Off {
            self.forget(&[0, 1], "a NURBS block", line);
        } else {
            self.pos.axes[0] = x;
            self.pos.axes[1] = y;
        }
    }

    /// A G5.2 block (on the line, or modal with axis words; checked by
    /// `check_block`): the control point. `motion_before` is the motion mode
    /// the line found.
    pub(in crate::eval) fn nurbs_point(
        &mut self,
        motion_before: MotionMode,
        axis_words: &[(usize, f64)],
        l_word: Option<f64>,
    ) {
        let word = |a: usize| axis_words.iter().rev().find(|w| w.0 == a).map(|w| w.1);
        if motion_before != NURBS {
            self.nurbs.points = 0;
        }
        if self.nurbs.points == 0 {
            self.nurbs.points = 1;
            self.nurbs.order = 3;
            self.nurbs.last = [self.pos.axes[0].clone(), self.pos.axes[1].clone()];
        }
        if let Some(l) = l_word
            && l > 3.0
        {
            self.nurbs.order = l.round() as u32;
        }
        if let (Some(x), Some(y)) = (word(0), word(1)) {
            self.nurbs.points += 1;
            // The position does not move until G5.3: incremental points are
            // all relative to where the block started.
            self.nurbs.last = [self.axis_end(0, x), self.axis_end(1, y)];
        }
        self.modal.motion = NURBS;
    }
}
