//! Exact lowerings: constructs a simple controller lacks, rewritten into
//! blocks it has (G0/G1/G2/G3/G4 and spindle words), with the motion
//! LinuxCNC would make. Pure functions of typed inputs; the target profile
//! decides which of them apply.
//!
//! Every function takes positions in program coordinates and units (the
//! active work offsets in effect, X as a radius even in G7), and returns
//! [`PlainLine`]s written for **absolute distance mode (G90), units per
//! minute feed (G94), the same units, plane and work offsets** as the
//! original block: the caller switches G91 off around them and back on
//! after, as its output needs. Each line starts with its G or M word;
//! cycle and arc lines carry all of X, Y and Z, even when unchanged, so
//! they do not depend on the modal motion of the target; spline lines
//! carry X and Y (splines are XY only). Feeds (F) and spindle speeds (S)
//! are not written: the original's stay in effect. The words used are G0,
//! G1, G2, G3 (with I/J/K offsets from the block's start, G91.1), G4 P,
//! M3, M4, M5, and for G87 and G88 only M19 R0 P2 and M0: a target without
//! those refuses the cycle.
//!
//! | function | construct | inputs |
//! |---|---|---|
//! | [`CycleState::lower`] | canned cycles G73, G81–G89 with G98/G99, L, G91, polar words | [`CycleBlock`] (cycle, its words), [`CycleModal`] (plane, distance mode, units, retract mode, spindle), current X Y Z; the state keeps what LinuxCNC keeps between cycle blocks |
//! | [`arc::lower_arc`] | full circle without end point, arcs with P turns | [`arc::ArcInput`]: plane, direction, start, end, centre, helix end, turns |
//! | [`polar::polar_target`] | `@` radius / `^` angle words | [`polar::PolarInput`]: distance mode, current X Y, words |
//! | [`diameter::radius_words`] | G7 diameter mode | X (and I) words of a block |
//! | [`comp::lower_comp_moves`] | cutter radius compensation G41/G42, G41.1/G42.1 | the moves released by [`crate::geom::cutter_comp::Comp`], the plane, the position before them |
//! | [`spline::lower_g5`], [`spline::lower_g5_1`], [`spline::lower_nurbs`] | G5, G5.1, G5.2/G5.3 splines | control points, tolerance |
//!
//! Errors are [`LowerError`]s with their own codes (E1100–E1149); the
//! caller adds the position of the block.

pub mod arc;
pub mod cutter_moves;
pub mod cycle;
pub mod diameter;
pub mod polar;
pub mod spline;

pub use cycle::{CycleBlock, CycleKind, CycleModal, CycleOutput, CycleState};

use std::fmt;

use crate::codes::Plane;

/// One word of a plain block.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Word {
    /// Upper-case letter.
    pub letter: u8,
    pub value: f64,
}

/// A block to write: words in order, values in program units, absolute
/// distance mode unless a lowering says otherwise.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PlainLine {
    pub words: Vec<Word>,
}

impl PlainLine {
    fn new(words: &[(u8, f64)]) -> Self {
        PlainLine {
            words: words
                .iter()
                .map(|&(letter, value)| Word { letter, value })
                .collect(),
        }
    }

    /// `G0`/`G1` to an XYZ point.
    fn motion(g: f64, p: [f64; 3]) -> Self {
        PlainLine::new(&[(b'G', g), (b'X', p[0]), (b'Y', p[1]), (b'Z', p[2])])
    }
}

/// Why a construct could not be lowered. Codes E1100–E1149.
#[derive(Debug, Clone, PartialEq)]
pub enum LowerError {
    /// The current position on an axis is needed and not known (a cycle's
    /// start, an arc's start).
    PositionUnknown { axis: char },
    /// The lowering would write more than [`MAX_LINES`] blocks.
    TooManyLines,
    /// A word the construct needs is missing and no earlier block supplies
    /// it (`G83` without Q on entry, `G81` without R).
    MissingWord {
        construct: &'static str,
        letter: char,
    },
    /// A value is out of the range the construct accepts (Q ≤ 0, L 0, R
    /// below the depth, a tolerance ≤ 0, a weight ≤ 0).
    BadValue {
        construct: &'static str,
        what: &'static str,
    },
    /// The spindle is not turning as the cycle needs (G84 clockwise,
    /// G86/G87/G88 turning at all).
    Spindle { construct: &'static str },
    /// LinuxCNC's own motion cannot be written with the target's words:
    /// G87 with the spindle counter-clockwise (its orientation mode 3 has
    /// no M19 form), G84 outside G17 (LinuxCNC 2.9 swaps the axes of its
    /// moves there), polar words outside G17; and what the lowerings do
    /// not write: arcs and cycles in the UVW planes, cutter compensation
    /// outside G17 and G18 (which LinuxCNC refuses too).
    NotExpressible {
        construct: &'static str,
        why: &'static str,
    },
    /// Incremental polar motion from the origin (angle undefined).
    PolarAtOrigin,
    /// The arc's start and end are not on one circle about its centre
    /// (within LinuxCNC's tolerance), or its radius is zero.
    BadArc,
}

/// The most blocks one lowering writes (a runaway guard: a G83 with a tiny
/// Q, a huge L, a spline with a tiny tolerance).
pub const MAX_LINES: usize = 1_000_000;

impl LowerError {
    /// The error code (E1100–E1149).
    pub fn code(&self) -> &'static str {
        match self {
            LowerError::PositionUnknown { .. } => "E1100",
            LowerError::TooManyLines => "E1101",
            LowerError::MissingWord { .. } => "E1102",
            LowerError::BadValue { .. } => "E1103",
            LowerError::Spindle { .. } => "E1104",
            LowerError::NotExpressible { .. } => "E1105",
            LowerError::PolarAtOrigin => "E1106",
            LowerError::BadArc => "E1107",
        }
    }
}

impl fmt::Display for LowerError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LowerError::PositionUnknown { axis } => write!(
                f,
                "the current {axis} position is not known here, and lowering this block needs it"
            ),
            LowerError::TooManyLines => write!(
                f,
                "lowering this block would write more than {MAX_LINES} lines"
            ),
            LowerError::MissingWord { construct, letter } => {
                write!(f, "{construct} needs a {letter} word")
            }
            LowerError::BadValue { construct, what } => write!(f, "{construct}: {what}"),
            LowerError::Spindle { construct } => write!(
                f,
                "{construct} needs the spindle turning in the direction of the cycle"
            ),
            LowerError::NotExpressible { construct, why } => {
                write!(f, "{construct} cannot be lowered: {why}")
            }
            LowerError::PolarAtOrigin => write!(
                f,
                "incremental motion with polar coordinates is indeterminate at the origin"
            ),
            LowerError::BadArc => write!(
                f,
                "the arc's start and end are not on one circle about its centre"
            ),
        }
    }
}

impl std::error::Error for LowerError {}

/// The X Y Z indices of `plane`'s first, second and normal axis
/// ([`Plane::axes`]); `construct` is refused in the UVW planes, whose axes
/// the lowerings do not move.
fn xyz_axes(plane: Plane, construct: &'static str) -> Result<[usize; 3], LowerError> {
    plane.xyz_axes().ok_or(LowerError::NotExpressible {
        construct,
        why: "the UVW planes (G17.1, G18.1, G19.1) are not lowered",
    })
}

/// Pushes a line, failing when the guard is reached.
fn push(out: &mut Vec<PlainLine>, line: PlainLine) -> Result<(), LowerError> {
    if out.len() >= MAX_LINES {
        return Err(LowerError::TooManyLines);
    }
    out.push(line);
    Ok(())
}
