//! The modal state the flattened program puts the machine in, line by line,
//! starting from LinuxCNC's power-on state; it answers the predefined named
//! parameters and the position parameters.

pub(super) mod arc;
pub(super) mod checked;
pub(super) mod cutter_check;
pub(super) mod cycle;
pub(super) mod lathe;
pub(super) mod modal;
pub(super) mod nurbs;
pub(super) mod restore;
mod tools;

use crate::diag::ExprError;
use std::collections::HashSet;

use crate::codes::CoordSystem;
use crate::diag::ErrorKind;
use crate::parse::ast::Span;
use crate::rules::Modes;

use crate::eval::expr::params::Params;
use crate::eval::expr::{EvalResult, fault};
use crate::rules::tools::Tools;
use crate::settings::{Define, Settings};

pub(crate) use crate::eval::expr::params::AXES;

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
// Fields in declaration order: with the modal state ahead of the position,
// the fast path's per-axis loop keeps the distance and diameter modes out
// of the loop (in the order rustc chose it reloaded them for every axis:
// 0.5% more instructions on a loop-heavy program).
#[repr(C)]
pub(super) struct Machine {
    pub(super) modal: Modes,
    pub(super) pos: Position,
    /// The tool table, the tool in the spindle and the selected one.
    pub(super) tools: Tools,
    /// RETAIN_G43 changed the tool length offset on this line: the output
    /// line to add after it (G43 or G49).
    pub(super) retain_line: Option<bool>,
    /// Pockets of the current and the selected tool, known as the standalone
    /// reference numbers them (by tool number) under `--zero-start`.
    pub(super) pockets: Option<(f64, f64)>,
    /// Applied tool length offset, machine units.
    pub(super) tlo: Option<[f64; 9]>,
    /// An XY rotation was set (not modelled).
    pub(super) rotated: bool,
    /// Control points of the NURBS block being read.
    pub(super) nurbs: nurbs::Nurbs,
    /// R plane and depth of the last canned cycle.
    pub(super) cycle: cycle::Cycle,
    /// The axes whose tool length offset changed since the last move (a
    /// bit each).
    pub(super) tlo_moved: u16,
    /// Line of the last G38 probe that left the results unknown.
    pub(super) probed_at: Option<u32>,
    /// Why and since which line the standalone reference's position
    /// differs from the machine's (see W0110).
    pub(super) standalone_drift: Option<(&'static str, u32)>,
    /// The axes (a bit each) on which the standalone reference's position
    /// is off after a tool change: an absolute move on each puts it right
    /// again. 0 with a drift: one no move ends (a change of units).
    pub(super) drift_axes: u16,
    /// The line of an M61 not followed by a tool change, and the tool the
    /// standalone reference still has as current (see W0110).
    pub(super) m61: Option<(u32, Option<f64>)>,
    /// Cutter compensation, once a program turns it on.
    pub(super) comp: Option<Box<cutter_check::CompRun>>,
    /// G40 ended an offset path: the next move must be straight (the fast
    /// paths leave such lines to the general one).
    pub(super) comp_pending: bool,
    /// A G70 whose compensated path the evaluator writes itself (see
    /// [`cutter_check::Written`]).
    pub(super) comp_written: cutter_check::Written,
    /// A lathe cycle whose contour subroutine is running.
    pub(super) lathe: Option<Box<lathe::LatheRun>>,
    /// Tools whose data a G10 left unknown (a tool-data read of one is
    /// unknown, whatever the table held).
    pub(super) unknown_tools: HashSet<i64>,
}

/// What an update of the machine model reads and changes besides the
/// machine: the settings (read only), the numbered parameters (where the
/// offsets are kept, as in LinuxCNC, and the probe's results: an update
/// writes them), and the number of the line it runs for (a position that
/// becomes unknown names it).
pub(in crate::eval) struct Env<'a> {
    pub(in crate::eval) s: &'a Settings,
    pub(in crate::eval) params: &'a mut Params,
    pub(in crate::eval) line: u32,
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
        // The active coordinate system a parameter file or -D gives (the
        // last value of #5220), as the machine model after evaluation
        // starts.
        let coord = s.defines.iter().rev().find_map(|d| match d {
            Define::Numbered(5220, v) => Some(CoordSystem::from_parameter(*v)),
            _ => None,
        });
        Machine {
            modal: Modes {
                coord: coord.unwrap_or(CoordSystem::G54),
                ..Modes::default()
            },
            pos,
            tools: Tools::new(s),
            retain_line: None,
            pockets: s.zero_start.then_some((1.0, -1.0)),
            tlo: Some([0.0; 9]),
            rotated: false,
            nurbs: nurbs::Nurbs::default(),
            cycle: cycle::Cycle::default(),
            tlo_moved: 0,
            probed_at: None,
            standalone_drift: None,
            drift_axes: 0,
            m61: None,
            comp: None,
            comp_pending: false,
            comp_written: cutter_check::Written::No,
            lathe: None,
            unknown_tools: HashSet::new(),
        }
    }

    /// Current position on an axis, or why it is unknown.
    pub(in crate::eval) fn position(&self, axis: usize, span: Span) -> EvalResult {
        if self.modal.cutter_comp != crate::codes::CutterComp::Off {
            let why = "cutter radius compensation is on".to_string();
            return Err(fault(
                ErrorKind::Expr(ExprError::UnknownPosition {
                    axis: AXES[axis] as char,
                    why,
                }),
                span,
            ));
        }
        self.programmed_position(axis, span)
    }

    /// The position model's value on an axis (with compensation on, the
    /// programmed position), or why it is unknown.
    pub(in crate::eval) fn programmed_position(&self, axis: usize, span: Span) -> EvalResult {
        match &self.pos.axes[axis] {
            Ok(v) => Ok(*v),
            Err(why) => {
                let why = match why {
                    Unknown::Start => {
                        "the program has not moved it to an absolute position yet".to_string()
                    }
                    Unknown::After(what, line) => format!("{what} at line {line} made it unknown"),
                };
                Err(fault(
                    ErrorKind::Expr(ExprError::UnknownPosition {
                        axis: AXES[axis] as char,
                        why,
                    }),
                    span,
                ))
            }
        }
    }
}
