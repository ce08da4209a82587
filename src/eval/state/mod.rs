//! The modal state the flattened program puts the machine in, line by line,
//! starting from LinuxCNC's power-on state; it answers the predefined named
//! parameters and the position parameters.

pub(super) mod ccomp;
pub(super) mod cycle;
pub(super) mod lathe;
pub(super) mod modal;
pub(super) mod nurbs;
pub(super) mod restore;
pub mod tools;

use crate::codes::{
    ArcDistance, CoordSystem, CutterComp, Distance, FeedMode, LatheMode, MotionMode, PathMode,
    Plane, Retract, SpindleDir, SpindleMode, ToolLength, Units,
};
use crate::eval::Settings;
use crate::fx_hasher::FxMap;

/// Axis letters in parameter order (X Y Z A B C U V W).
pub(crate) const AXES: [u8; 9] = *b"xyzabcuvw";

#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Modal {
    pub units: Units,
    pub distance: Distance,
    pub arc_distance: ArcDistance,
    pub plane: Plane,
    pub feed_mode: FeedMode,
    pub feed: f64,
    pub speed: f64,
    /// The motion mode; G5.3 (`NurbsEnd`) is none, as G5.3 leaves it.
    pub motion: MotionMode,
    pub coord: CoordSystem,
    /// G49 (`Cancel`) or the code that put the offset in effect.
    pub tool_length: ToolLength,
    pub retract: Retract,
    pub spindle_mode: SpindleMode,
    pub spindle: SpindleDir,
    pub mist: bool,
    pub flood: bool,
    pub path: PathMode,
    pub path_p: Option<f64>,
    pub path_q: Option<f64>,
    /// Off, Left or Right (G41.1 and G42.1 are kept as the side they
    /// compensate on, as `#<_ccomp>` reads them).
    pub ccomp: CutterComp,
    pub lathe: LatheMode,
    pub speed_override: bool,
    pub feed_override: bool,
    pub adaptive_feed: bool,
    pub feed_hold: bool,
}

impl Default for Modal {
    fn default() -> Modal {
        Modal {
            units: Units::Mm,
            distance: Distance::Absolute,
            arc_distance: ArcDistance::Incremental,
            plane: Plane::XY,
            feed_mode: FeedMode::PerMinute,
            feed: 0.0,
            speed: 0.0,
            motion: MotionMode::CancelCycle,
            coord: CoordSystem::G54,
            tool_length: ToolLength::Cancel,
            // LinuxCNC starts in G99 (`#<_retract_r_plane>` reads 1).
            retract: Retract::R,
            spindle_mode: SpindleMode::Rpm,
            spindle: SpindleDir::Off,
            mist: false,
            flood: false,
            path: PathMode::Blend,
            path_p: None,
            path_q: None,
            ccomp: CutterComp::Off,
            lathe: LatheMode::Radius,
            speed_override: true,
            feed_override: true,
            adaptive_feed: false,
            feed_hold: true,
        }
    }
}

impl Modal {
    /// The state after M2/M30.
    pub(crate) fn reset_at_end(&mut self) {
        self.coord = CoordSystem::G54;
        self.plane = Plane::XY;
        self.distance = Distance::Absolute;
        self.feed_mode = FeedMode::PerMinute;
        self.feed = 0.0;
        self.spindle = SpindleDir::Off;
        self.mist = false;
        self.flood = false;
        self.ccomp = CutterComp::Off;
        self.motion = MotionMode::Linear;
        self.speed_override = true;
        self.feed_override = true;
    }
}

/// Why a position became unknown.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Unknown {
    Start,
    After(&'static str, u32),
}

#[derive(Debug, Clone)]
pub(crate) struct Position {
    /// Current position in program coordinates and program units.
    pub axes: [Result<f64, Unknown>; 9],
}

impl Position {
    pub(crate) fn unknown() -> Position {
        Position {
            axes: std::array::from_fn(|_| Err(Unknown::Start)),
        }
    }

    pub(crate) fn zero() -> Position {
        Position {
            axes: std::array::from_fn(|_| Ok(0.0)),
        }
    }
}

/// The machine model: what the program has done to the machine so far
/// (modal state, position, offsets, tools, the cycles and paths in progress).
pub(super) struct Machine {
    pub(super) modal: Modal,
    pub(super) pos: Position,
    pub(super) current_tool: Option<f64>,
    /// RETAIN_G43 changed the tool length offset on this line: the output
    /// line to add after it (G43 or G49).
    pub(super) retain_line: Option<bool>,
    pub(super) selected_tool: Option<f64>,
    /// Pockets of the current and the selected tool, known as the standalone
    /// reference numbers them (by tool number) under `--zero-start`.
    pub(super) pockets: Option<(f64, f64)>,
    pub(super) tools: FxMap<i64, tools::ToolData>,
    pub(super) tools_known: bool,
    /// Applied tool length offset, machine units.
    pub(super) tlo: Option<[f64; 9]>,
    /// An XY rotation was set (not modelled).
    pub(super) rotated: bool,
    /// Control points of the NURBS block being read.
    pub(super) nurbs: nurbs::Nurbs,
    /// R plane and depth of the last canned cycle.
    pub(super) cycle: cycle::Cycle,
    /// The tool length offset changed since the last move.
    pub(super) tlo_moved: bool,
    /// Line of the last G38 probe that left the results unknown.
    pub(super) probed_at: Option<u32>,
    /// Why and since which line the standalone reference's position
    /// differs from the machine's (see W0110).
    pub(super) standalone_drift: Option<(&'static str, u32)>,
    /// The line of an M61 not followed by a tool change, and the tool the
    /// standalone reference still has as current (see W0110).
    pub(super) m61: Option<(u32, Option<f64>)>,
    /// Cutter compensation, once a program turns it on.
    pub(super) comp: Option<Box<ccomp::CompRun>>,
    /// G40 ended an offset path: the next move must be straight (the fast
    /// paths leave such lines to the general one).
    pub(super) comp_pending: bool,
    /// A G70 whose compensated path the evaluator writes itself (see
    /// [`ccomp::Written`]).
    pub(super) comp_written: ccomp::Written,
    /// A lathe cycle whose contour subroutine is running.
    pub(super) lathe: Option<Box<lathe::LatheRun>>,
}

impl Machine {
    /// The machine at the start: LinuxCNC's power-on modal state, the
    /// position, tool and table the settings give.
    pub(super) fn new(s: &Settings) -> Machine {
        let mut pos = if s.zero_start {
            Position::zero()
        } else {
            Position::unknown()
        };
        for &(axis, v) in &s.start_position {
            pos.axes[axis] = Ok(v);
        }
        Machine {
            modal: Modal::default(),
            pos,
            current_tool: if s.zero_start || !s.tool_table.is_empty() {
                Some(0.0)
            } else {
                None
            },
            retain_line: None,
            selected_tool: if s.zero_start { Some(0.0) } else { None },
            pockets: s.zero_start.then_some((1.0, -1.0)),
            tools: s.tool_table.iter().copied().collect(),
            tools_known: s.zero_start,
            tlo: Some([0.0; 9]),
            rotated: false,
            nurbs: nurbs::Nurbs::default(),
            cycle: cycle::Cycle::default(),
            tlo_moved: false,
            probed_at: None,
            standalone_drift: None,
            m61: None,
            comp: None,
            comp_pending: false,
            comp_written: ccomp::Written::No,
            lathe: None,
        }
    }
}
