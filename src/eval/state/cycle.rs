//! What canned cycles (G73, G74, G81–G89) keep between blocks: the R plane
//! and the depth of the last one, which a repeat of the same cycle reuses
//! when its line leaves them out.

use super::Machine;
use crate::codes::Plane;
use crate::rules::CycleLine;

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
/// in G91), and the level of the last series of cycles, program units
/// ([`Modes::cycle_end`](crate::rules::Modes::cycle_end)).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Cycle {
    pub r: f64,
    pub depth: f64,
    pub level: Option<f64>,
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

    /// A cycle block ran (after [`Machine::note_cycle`]; `series`: the
    /// motion mode was a cycle before its line): the tool is where
    /// [`Modes::cycle_end`](crate::rules::Modes::cycle_end) leaves it, in
    /// program units. An axis it cannot tell keeps why it was unknown.
    pub(in crate::eval) fn cycle_end(
        &mut self,
        axis_words: &[(usize, f64)],
        l: Option<f64>,
        series: bool,
    ) {
        let axes = self.modal.plane.cycle_axes();
        let at = [0, 1].map(|k| {
            let a = axes[k];
            let v = axis_words.iter().rev().find(|w| w.0 == a)?.1;
            Some(self.modal.radius_word(a, v))
        });
        let line = CycleLine {
            at,
            r: Some(self.cycle.r),
            repeats: l.map_or(1, |l| l.round().max(1.0) as u32),
        };
        let start = axes.map(|a| self.pos.axes[a].as_ref().ok().copied());
        let end = self
            .modal
            .cycle_end(start, &mut self.cycle.level, series, line);
        for (k, a) in axes.into_iter().enumerate() {
            if let Some(v) = end[k] {
                self.pos.axes[a] = Ok(v);
            }
        }
    }
}
