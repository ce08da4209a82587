//! What the machine model refuses besides a block's own checks (see [`super::BlockError`]) and lathe cycles ([`super::LatheError`]): cutter compensation's state, M72, user M-codes.

use std::fmt;

super::phase! {
    /// What the machine model refuses besides a block's own checks (see [`super::BlockError`]) and lathe cycles ([`super::LatheError`]): cutter compensation's state, M72, user M-codes.
    pub enum MachineError {
        /// `M72` with no `M70`/`M73` before it in this call level.
        "E0328" NoSavedContext,
        /// `G41` then `G54`: something the reference refuses while
        /// compensation is on (`action` says what).
        "E1170" CompForbids { action: &'static str },
        /// `G41` then `G42` without `G40`.
        "E1171" CompAlreadyOn,
        /// `G19 G41`: compensation in a plane other than XY or XZ.
        "E1172" CompPlane,
        /// `G41` in G17, then `G18`.
        "E1173" CompPlaneChange,
        /// `G40` then `G2 ...`: the move after compensation ends must be
        /// straight.
        "E1174" CompArcAfterOff,
        /// `G41.1` without a D word.
        "E1175" CompNoDiameter { g: &'static str },
        /// `G41` with a lathe tool (orientation 1-8), or `G41.1 L3`, outside
        /// G18.
        "E1176" CompLatheTool { what: &'static str },
        /// `M100`-`M199` that neither --user-m nor the INI's folders declare.
        "E0805" UndeclaredUserM { m: i64 },
    }
}

impl fmt::Display for MachineError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use MachineError::*;
        match self {
            NoSavedContext => write!(
                f,
                "M72 without a state saved by M70 or M73 at this call level"
            ),
            CompForbids { action } => {
                write!(f, "cannot {action} with cutter radius compensation on")
            }
            CompAlreadyOn => write!(
                f,
                "cutter radius compensation is already on (turn it off with G40 first)"
            ),
            CompPlane => write!(
                f,
                "cutter radius compensation works only in the XY (G17) and XZ (G18) planes"
            ),
            CompPlaneChange => {
                write!(f, "cannot change planes with cutter radius compensation on")
            }
            CompArcAfterOff => write!(
                f,
                "the move right after turning cutter compensation off (G40) must be straight, not an arc"
            ),
            CompNoDiameter { g } => write!(f, "{g} without a D word (the tool diameter)"),
            CompLatheTool { what } => write!(f, "{what}, but the plane is not G18"),
            UndeclaredUserM { m } => write!(
                f,
                "M{m} is a user M-code (an external program on the LinuxCNC machine) that is not declared: give --user-m {m}, or --ini with an [RS274NGC]USER_M_PATH or [DISPLAY]PROGRAM_PREFIX folder holding an executable file M{m}"
            ),
        }
    }
}
