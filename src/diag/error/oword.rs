//! O-words, subroutines, M98/M99 and the structure of a program.

use std::fmt;
use std::path::PathBuf;

super::phase! {
    /// O-words, subroutines, M98/M99 and the structure of a program.
    pub enum OWordError {
        /// `o1 frobnicate`
        "E0301" UnknownOCommand { word: String },
        /// `o1 if [1] G0 X1`
        "E0302" UnexpectedAfterOWord,
        /// `o1 if 1`
        "E0303" MissingBracket { keyword: &'static str },
        /// `o1 while [1 LT]`: the bracket holds no complete expression.
        "E0329" BadCondition { keyword: &'static str },
        /// `o1 call 5` (arguments must be bracketed)
        "E0304" CallArgNotBracketed,
        /// `o1 return` in the main program.
        "E0305" NotInSub,
        /// `o1 while [1]` twice at different lines in the same scope.
        "E0306" DuplicateLabel { label: String, first_line: u32 },
        /// `o9 endif` with no `o9 if`.
        "E0307" UndefinedLabel { label: String },
        /// `o1 while [0]` ... `o1 endif`
        "E0308" LabelMismatch {
            label: String,
            /// Keyword of the offending line.
            here: &'static str,
            /// Keyword the label was opened with.
            opened: &'static str,
            line: u32,
        },
        /// `o1 sub` inside another sub definition.
        "E0309" NestedSubDefinition { inner: String, outer: String },
        /// A `sub` line reached by normal flow after the sub was called.
        "E0310" IllegalSubLocation { name: String },
        /// Two `o<x> sub` definitions.
        "E0311" RedefiningSub {
            name: String,
            first: PathBuf,
            first_line: u32,
        },
        /// `o1 call [1] ... [31]`
        "E0312" TooManyArgs,
        /// Recursion ten calls deep.
        "E0313" TooDeep { limit: usize },
        /// `o<nothere> call` with no definition and no file.
        "E0314" SubNotFound {
            name: String,
            searched: Vec<PathBuf>,
        },
        /// A sub file that does not define the sub it is named after.
        "E0315" SubNotInFile { name: String, file: PathBuf },
        /// A closing `%` reached while looking for a label.
        "E0316" LabelBeforePercent { label: String },
        /// End of file while looking for `o<label> ...`.
        "E0317" EofSeeking { label: String, from_line: u32 },
        /// A program with no `M2`/`M30`/closing `%`.
        "E0318" MissingProgramEnd { percent: bool },
        /// An empty input.
        "E0319" EmptyProgram,
        /// `M98 L2`
        "E0320" M98WithoutP,
        /// An M98 among a line's words: after another word (`G0 X1 M98 P100`)
        /// or not written `M98` (`M098 P100`), both refused by the reference
        /// too, or with its code computed (`M#1 P100` with #1 = 98, a call the
        /// reference makes but ngcflat does not). An M98 call is written at
        /// the start of its line: `M98 P100`.
        "E0330" M98AmongWords,
        /// An M99 ending an M98 subprogram beside another word or an
        /// assignment (`G0 X5 M99`, `#1=1 M99`): the reference acts on them
        /// and then refuses the line. The return is a line of its own: `M99`.
        "E0331" M99AmongWords,
        /// `o100 call` where `O100` is a bare (M98-style) block.
        "E0321" FanucNeedsM98 { name: String },
        /// `M98 P100` where `o100 sub` is an O-call sub.
        "E0322" SubNeedsCall { name: String },
        /// `M99` ending an `o... sub`.
        "E0323" M99InSub,
        /// `o100 endsub` ending an M98 subprogram.
        "E0324" EndsubInFanuc,
        /// Fanuc-style M98/M99/bare O with `DISABLE_FANUC_STYLE_SUB`.
        "E0325" FanucDisabled { what: &'static str },
        /// `o<x> sub` with no `o<x> endsub` before the end of file.
        "E0326" UnterminatedSub { name: String },
        /// `(abort, tool broke)`
        "E0327" Abort { message: String },
        /// `o<../etc/passwd> call`
        "E0502" UnsafeSubName { name: String },
        /// `o[1] sub`: a definition whose label is computed.
        "E0701" ComputedSubLabel,
        /// A block of a library definition that is not closed before its
        /// `endsub`: `o1 if [#1 GT 0]` ... `o<s> endsub`.
        "E0804" UnclosedBlock {
            label: String,
            opened: &'static str,
            line: u32,
            closer: &'static str,
        },
    }
}

impl fmt::Display for OWordError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use OWordError::*;
        match self {
            UnknownOCommand { word } => write!(f, "unknown O-word command '{word}'"),
            UnexpectedAfterOWord => write!(f, "only a comment may follow an O-word command"),
            MissingBracket { keyword } => write!(f, "'[' expected after '{keyword}'"),
            BadCondition { keyword } => write!(
                f,
                "the bracketed expression after '{keyword}' is incomplete or not valid"
            ),
            CallArgNotBracketed => write!(f, "subroutine arguments must be bracketed: [value]"),
            NotInSub => write!(f, "return or endsub outside a subroutine"),
            DuplicateLabel { label, first_line } => {
                write!(f, "label o{label} is already used at line {first_line}")
            }
            UndefinedLabel { label } => write!(f, "label o{label} has not been opened"),
            LabelMismatch {
                label,
                here,
                opened,
                line,
            } => write!(
                f,
                "'o{label} {here}' does not match 'o{label} {opened}' at line {line}"
            ),
            NestedSubDefinition { inner, outer } => {
                write!(
                    f,
                    "subroutine o<{inner}> is defined inside subroutine o<{outer}>"
                )
            }
            IllegalSubLocation { name } => write!(
                f,
                "definition of o<{name}> reached by normal flow after it was called (put subroutines after the program end)"
            ),
            RedefiningSub {
                name,
                first,
                first_line,
            } => {
                write!(
                    f,
                    "subroutine o<{name}> is already defined at {}:{first_line}",
                    first.display()
                )
            }
            TooManyArgs => write!(f, "more than 30 subroutine arguments"),
            TooDeep { limit } => write!(f, "subroutine calls nested more than {limit} deep"),
            SubNotFound { name, searched } => sub_not_found(f, name, searched),
            SubNotInFile { name, file } => {
                write!(f, "file {} does not define o<{name}> sub", file.display())
            }
            LabelBeforePercent { label } => {
                write!(f, "closing '%' reached while looking for o{label}")
            }
            EofSeeking { label, from_line } => {
                write!(
                    f,
                    "end of file reached while looking for o{label} (from line {from_line})"
                )
            }
            MissingProgramEnd { percent: true } => write!(f, "file ends without the closing '%'"),
            MissingProgramEnd { percent: false } => {
                write!(f, "file ends without a program end (M2, M30 or '%')")
            }
            EmptyProgram => write!(f, "the program is empty"),
            M98WithoutP => write!(f, "M98 without a P word"),
            M98AmongWords => write!(
                f,
                "M98 not written 'M98 P...' at the start of its line (after other words, or computed) is not run"
            ),
            M99AmongWords => write!(
                f,
                "M99 returning from a subprogram shares its line with other words; write it alone: 'M99'"
            ),
            FanucNeedsM98 { name } => {
                write!(f, "O{name} is an M98 subprogram; call it with M98 P{name}")
            }
            SubNeedsCall { name } => write!(
                f,
                "o{name} is an O-word subroutine; call it with 'o{name} call'"
            ),
            M99InSub => write!(f, "M99 ends an 'o... sub' subroutine; use 'o... endsub'"),
            EndsubInFanuc => write!(f, "endsub/return inside an M98 subprogram; end it with M99"),
            FanucDisabled { what } => write!(f, "{what} used but DISABLE_FANUC_STYLE_SUB is set"),
            UnterminatedSub { name } => write!(f, "subroutine o<{name}> has no endsub"),
            Abort { message } => write!(f, "program aborted: {message}"),
            UnsafeSubName { name } => write!(
                f,
                "subroutine name '{name}' could leave the search path; use plain names (letters, digits, '_', '-')"
            ),
            ComputedSubLabel => write!(
                f,
                "a subroutine definition needs a fixed label (o<name> sub or o100 sub), not a computed one"
            ),
            UnclosedBlock {
                label,
                opened,
                line,
                closer,
            } => write!(
                f,
                "'o{label} {opened}' at line {line} has no 'o{label} {closer}' before the end of its subroutine"
            ),
        }
    }
}

fn sub_not_found(f: &mut fmt::Formatter<'_>, name: &str, searched: &[PathBuf]) -> fmt::Result {
    write!(
        f,
        "subroutine o<{name}> is not defined and no file {name}.ngc was found"
    )?;
    if searched.is_empty() {
        write!(f, " (no search folders configured)")
    } else {
        write!(f, " in: ")?;
        for (i, d) in searched.iter().enumerate() {
            if i > 0 {
                write!(f, ", ")?;
            }
            write!(f, "{}", d.display())?;
        }
        Ok(())
    }
}
