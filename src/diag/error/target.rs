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
        /// `--target ./board.toml` not TOML (`name = grbl`).
        "E1004" ProfileSyntax { path: String, error: super::ProfileError },
        /// A profile file with a key the format does not have.
        "E1005" ProfileUnknownKey { path: String, error: super::ProfileError },
        /// A profile file without a key the format requires.
        "E1006" ProfileMissingKey { path: String, error: super::ProfileError },
        /// A profile file key of the wrong type or range (`g_codes = ["G38.7"]`).
        "E1007" ProfileBadValue { path: String, error: super::ProfileError },
        /// Profile keys that contradict each other (`line_limit = 0`).
        "E1008" ProfileContradiction { path: String, error: super::ProfileError },
        /// `--target ./nosuch.toml`: the file cannot be read.
        "E1009" ProfileUnreadable { path: String, error: super::ProfileError },
        /// `G0 Z1` then `G38.2 Z1` with `--target grblhal`: GRBL-class
        /// firmwares refuse a probe move to the point the tool is at
        /// (LinuxCNC accepts it and does nothing); `how` is the firmware's
        /// own behaviour, from its profile (`probe_in_place`).
        "E1050" TargetProbeInPlace {
            target: &'static str,
            how: &'static str,
        },
        /// `G0 Z1` then `G38.2 Z0.9` with `--target g2core`: g2core refuses a
        /// probe move shorter than 0.254 mm (its profile's `min_probe_travel`).
        "E1051" TargetProbeTooShort {
            target: &'static str,
            travel: String,
            min: String,
        },
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
            ProfileSyntax { path, error }
            | ProfileUnknownKey { path, error }
            | ProfileMissingKey { path, error }
            | ProfileBadValue { path, error }
            | ProfileContradiction { path, error }
            | ProfileUnreadable { path, error } => {
                write!(f, "target profile {path}: {error}")
            }
            UnknownTarget { name } => {
                write!(f, "unknown target '{name}' (`ngcflat targets` lists them)")
            }
            TargetProbeInPlace { target, how } => write!(
                f,
                "probe move to the point the tool is already at: {target} refuses it ({how})"
            ),
            TargetProbeTooShort {
                target,
                travel,
                min,
            } => write!(
                f,
                "probe move of {travel} mm: {target} refuses a probe move shorter than {min} mm"
            ),
        }
    }
}

impl TargetError {
    /// The error of profile file `path`, by its kind.
    pub fn profile(path: String, error: super::ProfileError) -> TargetError {
        use super::ProfileError as P;
        match error {
            P::Unreadable { .. } => TargetError::ProfileUnreadable { path, error },
            P::Syntax { .. } => TargetError::ProfileSyntax { path, error },
            P::UnknownKey { .. } => TargetError::ProfileUnknownKey { path, error },
            P::MissingKey { .. } => TargetError::ProfileMissingKey { path, error },
            P::BadValue { .. } => TargetError::ProfileBadValue { path, error },
            P::Contradiction { .. } => TargetError::ProfileContradiction { path, error },
        }
    }
}
