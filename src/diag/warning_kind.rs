//! Legal but suspicious constructs, and places where a program depends on a
//! behaviour of the reference interpreter that ngcflat deliberately does not
//! copy. Each variant names an input that triggers it.

use std::fmt;
use std::path::PathBuf;

#[derive(Debug, Clone, PartialEq)]
pub enum WarningKind {
    /// `o1 if [1] (debug, x)`: an active comment (debug, msg, print, log,
    /// abort, …) on an O-line is never executed. Plain comments are fine.
    CommentOnOLine,
    /// `o<unused> sub` never called.
    UnusedSub { name: String },
    /// `#7` read in the main program before anything assigned it.
    ReadBeforeSet { index: i64 },
    /// `o1 if [1] ... o1 endif` then `o1 do`: one label for two blocks.
    LabelReused { first_line: u32 },
    /// Lines after `M2` that can never run.
    UnreachableAfterEnd { line: u32 },
    /// A sub file found in two folders of the search path.
    ShadowedSubFile {
        name: String,
        used: PathBuf,
        shadowed: PathBuf,
    },
    /// A `(debug/print/log, ...)` text that changes meaning if read again.
    MessageNotStable,
    /// The reference evaluates a condition ngcflat skips, and it would fail.
    QuirkSkippedCondition { message: String },
    /// A `break` out of a while loop leaves the reference's break flag set.
    QuirkStaleBreak { first_line: u32 },
    /// A `continue` in a do loop leaves the reference's continue flag set.
    QuirkStaleContinue { first_line: u32 },
    /// `return` inside a `repeat`: the reference keeps the remaining count.
    QuirkRepeatCount,
    /// Recursion from inside a `repeat`: the reference shares the counter.
    QuirkRepeatRecursion,
    /// `o1 continue` then `o1 break` in the same loop body: the reference
    /// acts on the skipped break.
    QuirkSkippedBreak,
    /// `G41` without `--tool-table` or `--zero-start`: the compensated path
    /// cannot be computed, so its errors are not looked for.
    CompNotChecked { why: &'static str },
    /// `M98 P.. L0`: the reference leaks a call frame.
    QuirkL0,
    /// `G43 H1`, `G20`, then `#<_abs_z>`; `G43 H1`, `M6`, then `#<_z>`; or
    /// `M61 Q2` then `#<_current_tool>`: the standalone reference keeps the
    /// tool length offset in the old units, takes the position after a tool
    /// change from the last move without the offset changed since, and does
    /// not change its current tool on M61.
    QuirkStandalone { why: &'static str, line: u32 },
    /// `o1 endif` with no `o1 if`, under warn-only O-words
    /// (`OWORD_WARNONLY`): one of LinuxCNC's O-word errors, the line skipped.
    OWordSkipped { code: &'static str, message: String },
    /// `[RS274NGC]FEATURES = 32` in the INI: the mask LinuxCNC read before
    /// 2.8 (2.8 and later ignore it).
    FeaturesMask { mask: i64, switches: String },
    /// `[RS274NGC]SUBROUTINE_PATH` with eleven existing folders.
    SubroutinePathTruncated { ignored: Vec<PathBuf> },
    /// `[RS274NGC]SUBROUTINE_PATH = nothere` or `PARAMETER_FILE = gone.var`.
    ConfigPathMissing { key: &'static str, path: PathBuf },
    /// `G64 P0.01` with `--target grbl`: dropped, with what it changes.
    TargetDropped {
        target: &'static str,
        what: String,
        why: String,
    },
    /// `G95` with `--target grbl`: written another way, with the condition
    /// under which that is exact.
    TargetRewritten {
        target: &'static str,
        what: String,
        how: String,
    },
    /// `M1` with `--target grbl`: written, and accepted, but the
    /// controller does nothing with it where LinuxCNC may.
    TargetIgnores {
        target: &'static str,
        what: String,
        why: String,
    },
}

impl WarningKind {
    pub fn code(&self) -> &'static str {
        use WarningKind::*;
        match self {
            CommentOnOLine => "W0001",
            UnusedSub { .. } => "W0002",
            ReadBeforeSet { .. } => "W0003",
            UnreachableAfterEnd { .. } => "W0004",
            LabelReused { .. } => "W0007",
            ShadowedSubFile { .. } => "W0005",
            MessageNotStable => "W0006",
            QuirkSkippedCondition { .. } => "W0101",
            QuirkStaleBreak { .. } => "W0102",
            QuirkStaleContinue { .. } => "W0103",
            QuirkRepeatCount => "W0104",
            QuirkRepeatRecursion => "W0105",
            QuirkL0 => "W0106",
            QuirkSkippedBreak => "W0109",
            CompNotChecked { .. } => "W1150",
            QuirkStandalone { .. } => "W0110",
            OWordSkipped { .. } => "W0900",
            FeaturesMask { .. } => "W0901",
            SubroutinePathTruncated { .. } => "W0902",
            ConfigPathMissing { .. } => "W0903",
            TargetDropped { .. } => "W1000",
            TargetRewritten { .. } => "W1001",
            TargetIgnores { .. } => "W1002",
        }
    }
}

impl fmt::Display for WarningKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use WarningKind::*;
        match self {
            CommentOnOLine => write!(
                f,
                "a (debug/msg/print/log/abort,…) comment on an O-word line is never executed; put it on a line of its own"
            ),
            UnusedSub { name } => write!(f, "subroutine o<{name}> is never called"),
            ReadBeforeSet { index } => write!(
                f,
                "parameter #{index} is read before anything sets it (reads 0)"
            ),
            LabelReused { first_line } => write!(
                f,
                "label already used for another block at line {first_line}; give each block its own label"
            ),
            UnreachableAfterEnd { line } => {
                write!(f, "code after the program end (line {line}) never runs")
            }
            ShadowedSubFile {
                name,
                used,
                shadowed,
            } => write!(
                f,
                "{name}.ngc in {} hides the one in {}",
                used.display(),
                shadowed.display()
            ),
            MessageNotStable => write!(
                f,
                "the substituted message still contains '#' or '%' directives and may read differently"
            ),
            QuirkSkippedCondition { message } => write!(
                f,
                "LinuxCNC evaluates this condition although its branch cannot run, and fails: {message}"
            ),
            QuirkStaleBreak { first_line } => write!(
                f,
                "LinuxCNC would end this do-loop after one pass (break flag left over from line {first_line}); ngcflat runs it normally"
            ),
            QuirkStaleContinue { first_line } => write!(
                f,
                "LinuxCNC would run this loop once more (continue flag left over from line {first_line}); ngcflat exits it normally"
            ),
            QuirkRepeatCount => write!(
                f,
                "a repeat left early (return, break, continue) keeps its remaining count in LinuxCNC; ngcflat starts it afresh"
            ),
            QuirkRepeatRecursion => write!(
                f,
                "recursive call inside a repeat: LinuxCNC shares one counter across the calls; ngcflat counts each call"
            ),
            QuirkStandalone { why, line } => write!(
                f,
                "since {why} at line {line}, LinuxCNC's standalone interpreter (rs274) reads a different value here; ngcflat gives the machine's"
            ),
            CompNotChecked { why } => {
                write!(f, "cutter radius compensation is not checked here: {why}")
            }
            QuirkSkippedBreak => write!(
                f,
                "LinuxCNC acts on this break although a continue skips over it, leaving the loop; ngcflat continues the loop"
            ),
            OWordSkipped { code, message } => write!(
                f,
                "{message} ({code}); O-word errors are warnings here, so this line is skipped"
            ),
            FeaturesMask { mask, switches } => write!(
                f,
                "[RS274NGC]FEATURES = {mask} is read as LinuxCNC before 2.8 read it ({switches}); LinuxCNC 2.8 and later ignore FEATURES and read separate switches (OWORD_WARNONLY = 1, ...)"
            ),
            SubroutinePathTruncated { ignored } => {
                let list: Vec<String> = ignored.iter().map(|p| p.display().to_string()).collect();
                write!(
                    f,
                    "[RS274NGC]SUBROUTINE_PATH has more than 10 existing folders; as in LinuxCNC only the first 10 are searched, these are ignored: {}",
                    list.join(", ")
                )
            }
            ConfigPathMissing { key, path } => write!(
                f,
                "{key} entry {} does not exist; it is ignored",
                path.display()
            ),
            QuirkL0 => write!(
                f,
                "M98 with L0: LinuxCNC leaves a call frame behind; ngcflat does not"
            ),
            TargetDropped { target, what, why } => {
                write!(f, "{what} is dropped for {target}: {why}")
            }
            TargetRewritten { target, what, how } => {
                write!(f, "{what} is written for {target} as {how}")
            }
            TargetIgnores { target, what, why } => {
                write!(f, "{what} is written for {target}, which ignores it: {why}")
            }
        }
    }
}
