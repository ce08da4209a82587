//! Everything that can go wrong with a program, as data, by the phase that
//! finds it: reading a line (`syntax`), evaluating it (`expr`), O-words and
//! program structure (`oword`), the machine model (`machine`, beside
//! [`BlockError`] and [`LatheError`]), runaway guards and travel limits
//! (`limits`), the command line and files (`setup`) and target controllers
//! (`target`). Each phase is an enum whose variants carry their stable code
//! beside them and name an input that triggers them; its message is an
//! exhaustive `match` in its `Display`. Positions and call stacks are added
//! by [`crate::diag::Diagnostic`].

use std::fmt;

use super::{BlockError, LatheError};
use crate::geom::cutter_comp::CompError;

/// Declares one phase's errors: each variant is written after its code,
/// and `code()` gives it back.
macro_rules! phase {
    (
        $(#[$meta:meta])*
        pub enum $name:ident {
            $(
                $(#[$vmeta:meta])*
                $code:literal $variant:ident $({
                    $( $(#[$fmeta:meta])* $field:ident : $fty:ty ),* $(,)?
                })?
            ),* $(,)?
        }
    ) => {
        $(#[$meta])*
        #[derive(Debug, Clone, PartialEq)]
        pub enum $name {
            $(
                $(#[$vmeta])*
                $variant $({ $( $(#[$fmeta])* $field: $fty ),* })?,
            )*
        }

        impl $name {
            /// Every code of the phase, in the order of its variants.
            pub const CODES: &[&str] = &[$($code),*];

            /// The stable code shown with every diagnostic.
            pub fn code(&self) -> &'static str {
                match self {
                    $( Self::$variant { .. } => $code, )*
                }
            }
        }
    };
}
use phase;

mod expr;
mod limits;
mod machine;
mod oword;
mod profile;
mod setup;
mod syntax;
mod target;

pub use expr::ExprError;
pub use limits::LimitError;
pub use machine::MachineError;
pub use oword::OWordError;
pub use profile::ProfileError;
pub use setup::SetupError;
pub use syntax::SyntaxError;
pub use target::TargetError;

/// An error of any phase.
#[derive(Debug, Clone, PartialEq)]
pub enum ErrorKind {
    /// Reading a line.
    Syntax(SyntaxError),
    /// Expressions and parameters.
    Expr(ExprError),
    /// O-words, subroutines and program structure.
    OWord(OWordError),
    /// The machine model.
    Machine(MachineError),
    /// `G0 G1 X1`, `G1 X1 F0`, `M3 M4`: a block the reference refuses
    /// (codes E0601 on).
    Block(BlockError),
    /// A lathe cycle (G70–G72) LinuxCNC refuses.
    Lathe(LatheError),
    /// `G41 G1 X0.1` with a 0.25 radius tool: the compensated path cannot
    /// be made (see [`crate::geom::cutter_comp::CompError`]).
    CutterComp { error: CompError },
    /// Runaway guards, output and travel limits.
    Limit(LimitError),
    /// The command line, files and what is outside the program.
    Setup(SetupError),
    /// What a target controller cannot run.
    Target(TargetError),
    /// A lowering for a target that failed (its own code, E1100–E1149).
    TargetLowering {
        target: &'static str,
        code: &'static str,
        message: String,
    },
}

impl ErrorKind {
    /// Stable code shown with every diagnostic.
    pub fn code(&self) -> &'static str {
        match self {
            ErrorKind::Syntax(e) => e.code(),
            ErrorKind::Expr(e) => e.code(),
            ErrorKind::OWord(e) => e.code(),
            ErrorKind::Machine(e) => e.code(),
            ErrorKind::Block(e) => e.code(),
            ErrorKind::Lathe(e) => e.code(),
            ErrorKind::CutterComp { error } => comp_code(*error),
            ErrorKind::Limit(e) => e.code(),
            ErrorKind::Setup(e) => e.code(),
            ErrorKind::Target(e) => e.code(),
            ErrorKind::TargetLowering { code, .. } => code,
        }
    }
}

impl fmt::Display for ErrorKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ErrorKind::Syntax(e) => write!(f, "{e}"),
            ErrorKind::Expr(e) => write!(f, "{e}"),
            ErrorKind::OWord(e) => write!(f, "{e}"),
            ErrorKind::Machine(e) => write!(f, "{e}"),
            ErrorKind::Block(e) => write!(f, "{e}"),
            ErrorKind::Lathe(e) => write!(f, "{e}"),
            ErrorKind::CutterComp { error } => write!(f, "{error}"),
            ErrorKind::Limit(e) => write!(f, "{e}"),
            ErrorKind::Setup(e) => write!(f, "{e}"),
            ErrorKind::Target(e) => write!(f, "{e}"),
            ErrorKind::TargetLowering {
                target, message, ..
            } => write!(f, "{message} (lowering for {target})"),
        }
    }
}

/// Codes of the compensation geometry errors: E1150 and up, in the order
/// of [`crate::geom::cutter_comp::CompError::ALL`].
fn comp_code(e: crate::geom::cutter_comp::CompError) -> &'static str {
    use crate::geom::cutter_comp::CompError::*;
    match e {
        EntryTooShort => "E1150",
        EntryArcTooShort => "E1151",
        ToolTooBigForArc => "E1152",
        StraightFeedGouge => "E1153",
        StraightTraverseGouge => "E1154",
        ArcGouge => "E1155",
        ArcArcSameCenter => "E1156",
        ArcArcGouge => "E1157",
        ArcLineGouge => "E1158",
        ZeroRadiusArc => "E1160",
        RadiusMismatch => "E1161",
        RadiusTooSmall => "E1162",
        ArcSamePoint => "E1163",
        Inconsistent => "E1164",
        ArcRadiusChanged => "E1165",
    }
}

/// Every code of the phases with fixed codes.
#[cfg(test)]
pub(crate) fn phase_codes() -> Vec<&'static str> {
    [
        SyntaxError::CODES,
        ExprError::CODES,
        OWordError::CODES,
        MachineError::CODES,
        LimitError::CODES,
        SetupError::CODES,
        TargetError::CODES,
    ]
    .concat()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Codes are `E` and four digits, and no two variants share one.
    #[test]
    fn codes_are_well_formed_and_unique() {
        let mut codes = phase_codes();
        codes.extend(
            crate::geom::cutter_comp::CompError::ALL
                .iter()
                .map(|e| comp_code(*e)),
        );
        assert!(codes.len() > 100, "codes: {}", codes.len());
        for c in &codes {
            assert!(
                c.len() == 5 && c.starts_with('E') && c[1..].bytes().all(|b| b.is_ascii_digit()),
                "{c}"
            );
        }
        let mut sorted = codes.clone();
        sorted.sort_unstable();
        sorted.dedup();
        assert_eq!(sorted.len(), codes.len(), "a code is used twice");
    }
}
