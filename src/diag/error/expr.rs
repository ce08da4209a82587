//! Evaluating expressions and reading parameters, including values only the machine knows.

use std::fmt;

super::phase! {
    /// Evaluating expressions and reading parameters, including values only the machine knows.
    pub enum ExprError {
        /// `[1/0]`
        "E0101" DivideByZero,
        /// `[-2**0.5]`
        "E0102" NegativePower,
        /// `ACOS[2]`
        "E0103" AcosRange,
        /// `ASIN[2]`
        "E0104" AsinRange,
        /// `LN[0]`
        "E0105" LnDomain,
        /// `SQRT[-1]`
        "E0106" SqrtNegative,
        /// `[1 MOD 0]`
        "E0107" NotANumber,
        /// `EXP[1000]`
        "E0108" Infinity,
        /// `#0=1`, `#5602`
        "E0201" ParamOutOfRange { index: i64 },
        /// `#5400=1`
        "E0202" ParamReadOnly { index: i64 },
        /// `G0 X#<nowhere>`
        "E0203" NamedUndefined { name: String },
        /// `#<_x>=1`
        "E0204" NamedReadOnly { name: String },
        /// `G0 X#5061`: a value that exists only on the running machine.
        "E0205" RuntimeParam {
            what: String,
            why: String,
            hint: String,
        },
        /// `(print, #<_x>)` with the X position unknown.
        "E0207" UnknownPosition { axis: char, why: String },
        /// `T50` with a `--tool-table` that has no tool 50.
        "E0208" ToolNotInTable { tool: i64 },
        /// `G38.2 Z-10` then `#5063`: the probe's result exists only on the
        /// machine (probing overwrites any -D value).
        "E0801" ProbeResultUnknown { index: usize, line: u32 },
    }
}

impl fmt::Display for ExprError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use ExprError::*;
        match self {
            DivideByZero => write!(f, "division by zero"),
            NegativePower => write!(f, "negative number raised to a non-integer power"),
            AcosRange => write!(f, "argument of ACOS is outside -1..1"),
            AsinRange => write!(f, "argument of ASIN is outside -1..1"),
            LnDomain => write!(f, "argument of LN is zero or negative"),
            SqrtNegative => write!(f, "argument of SQRT is negative"),
            NotANumber => write!(f, "calculation gives no number (NaN)"),
            Infinity => write!(f, "calculation gives infinity"),
            ParamOutOfRange { index } => write!(f, "parameter #{index} is out of range (1..5601)"),
            ParamReadOnly { index } => write!(f, "parameter #{index} is read-only"),
            NamedUndefined { name } => write!(f, "parameter #<{name}> is not defined"),
            NamedReadOnly { name } => write!(f, "parameter #<{name}> is read-only"),
            RuntimeParam { what, why, hint } => {
                write!(
                    f,
                    "{what} is only known on the running machine ({why}); supply it with {hint}"
                )
            }
            UnknownPosition { axis, why } => write!(
                f,
                "the {} position is not known here ({why}); fix it with an absolute move first, or give --start-position X0,Y0,Z0 (mm)",
                axis.to_ascii_uppercase()
            ),
            ToolNotInTable { tool } => write!(f, "tool {tool} is not in the tool table"),
            ProbeResultUnknown { index, line } => write!(
                f,
                "#{index} is the result of the probe at line {line}, known only on the machine; a program that uses it cannot be flattened ahead of time (--zero-start assumes the probe does not trip and reads its target, as LinuxCNC's standalone interpreter does)"
            ),
        }
    }
}
