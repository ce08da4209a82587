//! Absolute arc centres (G90.1) on a target that reads I J K only as
//! offsets from the arc's start (GRBL, grblHAL and FluidNC all refuse
//! G90.1: `gcode.c`, `GCode.cpp`).
//!
//! The rule (LinuxCNC 2.9, checked against rs274): under G90.1 the I J K
//! words of the arc's plane are the centre's coordinates in the work
//! coordinate system the block runs in (in G7 the I word is a radius, not
//! halved), whatever the distance mode (G90/G91); both words of the plane
//! must be given. The same arc is written with each of them less the start
//! point's coordinate on that axis: the offset a G91.1 target reads. G90.1
//! and G91.1 themselves are dropped. Arcs that are lowered (full circles,
//! P turns, spirals, cutter compensation) work out the centre from the
//! mode and write offsets already.

use crate::block::{Block, MotionMode, NonModal, ToolLength};
use crate::codes::ArcDistance;
use crate::diag::ErrorKind;
use crate::diag::TargetError;
use crate::machine::FlatMachine;

use super::Lowering;

impl Lowering {
    /// Whether the program's arc centres are absolute and the target
    /// lacks G90.1: arcs written as they are get their I J K rewritten.
    pub(super) fn centres_rewritten(&self) -> bool {
        self.m.modes.arc_distance == ArcDistance::Absolute && !self.p.has_g(901)
    }

    /// The offsets from the start to write for the I J K words of block
    /// `b` (run from `before` to the model's state) whose arc is written
    /// as it is, by the index of the letter (0 = I); `None` when the
    /// block writes no such arc or its centre words are offsets already.
    pub(super) fn centre_offsets(
        &self,
        b: &Block,
        before: &FlatMachine,
    ) -> Result<Option<[Option<f64>; 3]>, ErrorKind> {
        let motion = b.motion().unwrap_or(before.modes.motion);
        let other_axis_use = b.non_modal().is_some_and(|n| !matches!(n, NonModal::Dwell))
            || b.tool_length() == Some(ToolLength::Dynamic);
        if !self.centres_rewritten()
            || !matches!(motion, MotionMode::ArcCw | MotionMode::ArcCcw)
            || !b.has_axis()
            || other_axis_use
            || b.value(b'R').is_some()
        {
            return Ok(None);
        }
        let Some([p, q, _]) = self.m.modes.plane.xyz_axes() else {
            return Ok(None);
        };
        // The start in the coordinate system, units and offsets the
        // block's words are read in.
        let after = self.m.offset();
        let same_offsets = before.offset() == after;
        let from_machine = before.machine_pos();
        let mut out = [None; 3];
        for a in [p, q] {
            let Some(v) = b.value(b"IJK"[a]) else {
                continue;
            };
            let start = if same_offsets {
                before.pos[a]
            } else {
                from_machine[a].zip(after[a]).map(|(m, o)| m - o)
            };
            let start = start.ok_or_else(|| {
                ErrorKind::Target(TargetError::TargetNeedsValue {
                    target: self.name(),
                    what: "an arc's absolute centre (G90.1) as offsets from its start".into(),
                    value: format!("the current {} position", ['X', 'Y', 'Z'][a]),
                    option: "--start-position (or --zero-start), or an absolute move first".into(),
                })
            })?;
            out[a] = Some(v - start / self.m.scale());
        }
        Ok(Some(out))
    }
}
