//! What canned cycles (G73, G74, G81–G89) keep between blocks: the R plane
//! and the depth of the last one, which a repeat of the same cycle reuses
//! when its line leaves them out.

use crate::codes::Plane;
use crate::eval::state::Machine;

/// The depth axis of cycles in a plane (G17 → Z, G18 → Y, G19 → X), as a
/// letter and a name.
pub(crate) fn depth_axis(plane: Plane) -> (u8, &'static str) {
    match plane {
        Plane::XZ | Plane::WU => (b'y', "Y"),
        Plane::YZ | Plane::VW => (b'x', "X"),
        Plane::XY | Plane::UV => (b'z', "Z"),
    }
}

/// R plane and depth of the last cycle block, as written (incremental values
/// in G91).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Cycle {
    pub r: f64,
    pub depth: f64,
}

impl Machine {
    /// A cycle block ran (checked by `check_block`): keeps its R and depth
    /// for repeats.
    pub(in crate::eval) fn note_cycle(&mut self, words: &[(u8, f64)]) {
        let (depth, _) = depth_axis(self.modal.plane);
        for &(l, v) in words {
            if l == b'r' {
                self.cycle.r = v;
            } else if l == depth {
                self.cycle.depth = v;
            }
        }
    }
}
