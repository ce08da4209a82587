//! What a program makes the machine do, in order: the stream that target
//! lowering, statistics, the toolpath picture and the travel-limit check
//! read. Produced by the machine model from executed (flat) blocks.
//!
//! Units: linear axes in millimetres, rotary axes in degrees, feeds in
//! mm/min (or mm/rev, see [`FeedMode`]), times in seconds, whatever units
//! the program was written in.

use crate::codes::{FeedMode, Plane, SpindleDir, SpindleMode};

/// Axis values in parameter order: X Y Z A B C U V W.
pub(crate) type Axes = [f64; 9];

/// A tool-tip position in the active work coordinate system (G5x, G92 and
/// G52 offsets in effect), and the offset that takes it to the machine's
/// controlled point (work + offset = machine coordinates, tool length offset
/// included) when every offset is known.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Point {
    pub work: Axes,
    pub offset: Option<Axes>,
}

impl Point {
    /// Machine coordinates of the controlled point, when known.
    #[cfg(test)]
    pub(crate) fn machine(&self) -> Option<Axes> {
        self.offset
            .map(|o| std::array::from_fn(|i| self.work[i] + o[i]))
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum MoveKind {
    Rapid,
    Feed,
    /// G38.x: the end point is where the probe would stop at the latest.
    Probe,
    /// Rigid tapping or spindle-synchronised motion.
    SpindleSync,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Feed {
    /// mm/min, mm/rev, or 1/min in inverse time.
    pub rate: f64,
    pub mode: FeedMode,
}

#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Motion {
    /// A straight move (all axes together).
    Line {
        kind: MoveKind,
        from: Point,
        to: Point,
        feed: Feed,
    },
    /// An arc or helix in `plane` (G17, G18 or G19: the model records no
    /// arc in the UVW planes): `center` holds the two in-plane work
    /// coordinates of its centre, in ascending axis order; `turns` is 1 for an arc of less than one
    /// turn, more for P turns (a full circle written without end point is
    /// one turn with `from == to`).
    Arc {
        from: Point,
        to: Point,
        center: [f64; 2],
        plane: Plane,
        ccw: bool,
        turns: u32,
        feed: Feed,
    },
    Dwell {
        seconds: f64,
    },
    Spindle {
        dir: SpindleDir,
        /// rev/min (G97), or surface speed (G96).
        speed: f64,
        mode: SpindleMode,
    },
    Coolant {
        mist: bool,
        flood: bool,
    },
    ToolChange {
        tool: i64,
    },
    /// G61, G61.1 (`exact`) or G64 with its P tolerance (mm; 0: none
    /// given), as it comes into effect.
    PathMode {
        exact: bool,
        tolerance: f64,
    },
    /// The program sets offsets or stored positions, or selects another
    /// coordinate system (G10, G28.1, G30.1, G52, G92, G92.1, G92.2, G92.3,
    /// G54…G59.3 other than the one in effect), whether or not a value
    /// changes: GRBL waits for its motion to finish there.
    Offsets,
    /// M0 (`optional: false`) or M1.
    Pause {
        optional: bool,
    },
    /// M2, M30, or the `%` that ends the program.
    End,
}
