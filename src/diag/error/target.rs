//! What a target controller cannot run (a lowering that fails has its own code: `ErrorKind::TargetLowering`).

use std::fmt;

super::phase! {
    /// What a target controller cannot run (a lowering that fails has its own code: `ErrorKind::TargetLowering`).
    pub enum TargetError {
        /// `G33 Z-1 K1` with `--target grbl`: a construct the target cannot run
        /// and no exact lowering exists.
        "E1000" TargetRefused {
            target: &'static str,
            what: String,
            why: String,
        },
        /// `G43` with `--target grbl` and the tool's length unknown: the
        /// lowering needs a value only the machine knows.
        "E1001" TargetNeedsValue {
            target: &'static str,
            what: String,
            value: String,
            option: String,
        },
        /// A line longer than the target's line buffer, as the firmware counts.
        "E1002" TargetLineTooLong {
            target: &'static str,
            len: usize,
            limit: usize,
        },
        /// `--target nosuch`
        "E1003" UnknownTarget { name: String },
        /// `G0 Z1` then `G38.2 Z1` with `--target grblhal`: GRBL-class
        /// firmwares refuse a probe move to the point the tool is at
        /// (LinuxCNC accepts it and does nothing).
        "E1050" TargetProbeInPlace { target: &'static str },
    }
}

impl fmt::Display for TargetError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use TargetError::*;
        match self {
            TargetRefused { target, what, why } => {
                write!(f, "{what} cannot run on {target}: {why}")
            }
            TargetNeedsValue {
                target,
                what,
                value,
                option,
            } => write!(
                f,
                "{what} for {target} needs {value}, which is not known here; give it with {option}"
            ),
            TargetLineTooLong { target, len, limit } => write!(
                f,
                "this line is {len} bytes as {target} counts it, over its line buffer of {limit}; lines are never split"
            ),
            UnknownTarget { name } => {
                write!(f, "unknown target '{name}' (`ngcflat targets` lists them)")
            }
            TargetProbeInPlace { target } => write!(
                f,
                "probe move to the point the tool is already at: {target} refuses it (its error 33, invalid target)"
            ),
        }
    }
}
