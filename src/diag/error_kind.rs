//! Everything that can go wrong with a program, as data. Each variant names
//! an input that triggers it. Messages are rendered by [`std::fmt::Display`];
//! positions and call stacks are added by [`crate::diag::Diagnostic`].

use std::fmt;
use std::path::PathBuf;

#[derive(Debug, Clone, PartialEq)]
pub enum ErrorKind {
    // ------------------------------------------------------------ lexical
    /// A line of 253 characters or more.
    CommandTooLong,
    /// `(a (b))`
    NestedComment,
    /// `G0 (open`
    UnclosedComment,
    /// `G0 X1 {` or a UTF-8 byte outside a comment.
    BadCharacter { ch: char, byte: u8 },
    /// `G1 X[1+2` and other shapes the grammar does not accept.
    Syntax { expected: String },
    /// `X.` or `[1+]`
    BadNumber { text: String },
    /// `X1.2.3`
    TrailingNumber { text: String },
    /// `#1.5=0` or `G1.5`-style integer contexts.
    NonInteger { value: f64 },
    /// `%` line in a program that did not start with `%`.
    StrayPercent,
    /// `G0 X1 X2`
    DuplicateWord { letter: char },
    /// `M3 M8 M7 M9 M5`: more than four M words.
    TooManyMWords,
    /// `N` number that is not at the start of the line: `G0 N10`.
    MisplacedLineNumber,
    // ------------------------------------------------------------ expressions
    /// `[1/0]`
    DivideByZero,
    /// `[-2**0.5]`
    NegativePower,
    /// `ACOS[2]`
    AcosRange,
    /// `ASIN[2]`
    AsinRange,
    /// `LN[0]`
    LnDomain,
    /// `SQRT[-1]`
    SqrtNegative,
    /// `[1 MOD 0]`
    NotANumber,
    /// `EXP[1000]`
    Infinity,
    // ------------------------------------------------------------ parameters
    /// `#0=1`, `#5602`
    ParamOutOfRange { index: i64 },
    /// `#5400=1`
    ParamReadOnly { index: i64 },
    /// `G0 X#<nowhere>`
    NamedUndefined { name: String },
    /// `#<_x>=1`
    NamedReadOnly { name: String },
    /// `G0 X#5061`: a value that exists only on the running machine.
    RuntimeParam {
        what: String,
        why: String,
        hint: String,
    },
    /// `(debug, #<open)`
    UnterminatedName,
    /// `(print, #<_x>)` with the X position unknown.
    UnknownPosition { axis: char, why: String },
    /// `T50` with a `--tool-table` that has no tool 50.
    ToolNotInTable { tool: i64 },
    // ------------------------------------------------------------ O-words
    /// `o1 frobnicate`
    UnknownOCommand { word: String },
    /// `o1 if [1] G0 X1`
    UnexpectedAfterOWord,
    /// `o1 if 1`
    MissingBracket { keyword: &'static str },
    /// `o1 while [1 LT]`: the bracket holds no complete expression.
    BadCondition { keyword: &'static str },
    /// `o1 call 5` (arguments must be bracketed)
    CallArgNotBracketed,
    /// `o1 return` in the main program.
    NotInSub,
    /// `o1 while [1]` twice at different lines in the same scope.
    DuplicateLabel { label: String, first_line: u32 },
    /// `o9 endif` with no `o9 if`.
    UndefinedLabel { label: String },
    /// `o1 while [0]` ... `o1 endif`
    LabelMismatch {
        label: String,
        /// Keyword of the offending line.
        here: &'static str,
        /// Keyword the label was opened with.
        opened: &'static str,
        line: u32,
    },
    /// `o1 sub` inside another sub definition.
    NestedSubDefinition { inner: String, outer: String },
    /// A `sub` line reached by normal flow after the sub was called.
    IllegalSubLocation { name: String },
    /// Two `o<x> sub` definitions.
    RedefiningSub {
        name: String,
        first: PathBuf,
        first_line: u32,
    },
    /// `o1 call [1] ... [31]`
    TooManyArgs,
    /// Recursion ten calls deep.
    TooDeep { limit: usize },
    /// `o<nothere> call` with no definition and no file.
    SubNotFound {
        name: String,
        searched: Vec<PathBuf>,
    },
    /// A sub file that does not define the sub it is named after.
    SubNotInFile { name: String, file: PathBuf },
    /// A closing `%` reached while looking for a label.
    LabelBeforePercent { label: String },
    /// End of file while looking for `o<label> ...`.
    EofSeeking { label: String, from_line: u32 },
    /// A program with no `M2`/`M30`/closing `%`.
    MissingProgramEnd { percent: bool },
    /// An empty input.
    EmptyProgram,
    /// `M98 L2`
    M98WithoutP,
    /// An M98 among a line's words: after another word (`G0 X1 M98 P100`)
    /// or not written `M98` (`M098 P100`), both refused by the reference
    /// too, or with its code computed (`M#1 P100` with #1 = 98, a call the
    /// reference makes but ngcflat does not). An M98 call is written at
    /// the start of its line: `M98 P100`.
    M98AmongWords,
    /// An M99 ending an M98 subprogram beside another word or an
    /// assignment (`G0 X5 M99`, `#1=1 M99`): the reference acts on them
    /// and then refuses the line. The return is a line of its own: `M99`.
    M99AmongWords,
    /// `o100 call` where `O100` is a bare (M98-style) block.
    FanucNeedsM98 { name: String },
    /// `M98 P100` where `o100 sub` is an O-call sub.
    SubNeedsCall { name: String },
    /// `M99` ending an `o... sub`.
    M99InSub,
    /// `o100 endsub` ending an M98 subprogram.
    EndsubInFanuc,
    /// Fanuc-style M98/M99/bare O with `DISABLE_FANUC_STYLE_SUB`.
    FanucDisabled { what: &'static str },
    /// `o<x> sub` with no `o<x> endsub` before the end of file.
    UnterminatedSub { name: String },
    /// `G0 G1 X1`, `G1 X1 F0`, `M3 M4`: a block the reference refuses.
    /// A block LinuxCNC refuses (codes E0601 on).
    Block(super::BlockError),
    /// A lathe cycle (G70–G72) LinuxCNC refuses.
    Lathe(super::LatheError),
    /// `M72` with no `M70`/`M73` before it in this call level.
    NoSavedContext,
    /// `(abort, tool broke)`
    Abort { message: String },
    // ------------------------------------------------------------ cutter compensation
    /// `G41 G1 X0.1` with a 0.25 radius tool: the compensated path cannot
    /// be made (see [`crate::geom::comp::CompError`]).
    CutterComp { error: crate::geom::comp::CompError },
    /// `G41` then `G54`: something the reference refuses while
    /// compensation is on (`action` says what).
    CompForbids { action: &'static str },
    /// `G41` then `G42` without `G40`.
    CompAlreadyOn,
    /// `G19 G41`: compensation in a plane other than XY or XZ.
    CompPlane,
    /// `G41` in G17, then `G18`.
    CompPlaneChange,
    /// `G40` then `G2 ...`: the move after compensation ends must be
    /// straight.
    CompArcAfterOff,
    /// `G41.1` without a D word.
    CompNoDiameter { g: &'static str },
    /// `G41` with a lathe tool (orientation 1-8), or `G41.1 L3`, outside
    /// G18.
    CompLatheTool { what: &'static str },
    // ------------------------------------------------------------ limits and output
    /// An output line longer than 252 characters after substitution.
    OutputLineTooLong { len: usize },
    /// `o1 while [1]` ... `o1 endwhile` with no exit.
    StepLimit {
        limit: u64,
        label: Option<String>,
        line: Option<u32>,
    },
    /// A loop that writes more lines than `--max-output-lines`.
    OutputLimit {
        limit: u64,
        label: Option<String>,
        line: Option<u32>,
    },
    /// A value that cannot be written as a G-code number.
    Unprintable { value: f64 },
    /// An O-line read again when it runs is no longer the O-line the index
    /// found (the file changed during the run).
    ProgramChanged { line: u32 },
    // ------------------------------------------------------------ files and setup
    /// A file that cannot be read.
    Io { path: PathBuf, message: String },
    /// `o<../etc/passwd> call`
    UnsafeSubName { name: String },
    /// A var file whose parameter numbers are not ascending.
    VarFileOrder { index: i64 },
    /// A var file line that is not `number value`.
    VarFileSyntax { text: String },
    /// A `-D` definition that is not `PARAM=VALUE`.
    BadDefine { text: String },
    /// Lathe cycle needing a contour sub (`G71 Q...`).
    Unsupported { what: String },
    // ------------------------------------------------------------ targets
    /// `G33 Z-1 K1` with `--target grbl`: a construct the target cannot run
    /// and no exact lowering exists.
    TargetRefused {
        target: &'static str,
        what: String,
        why: String,
    },
    /// `G43` with `--target grbl` and the tool's length unknown: the
    /// lowering needs a value only the machine knows.
    TargetNeedsValue {
        target: &'static str,
        what: String,
        value: String,
        option: String,
    },
    /// A line longer than the target's line buffer, as the firmware counts.
    TargetLineTooLong {
        target: &'static str,
        len: usize,
        limit: usize,
    },
    /// `--target nosuch`
    UnknownTarget { name: String },
    /// `G0 Z1` then `G38.2 Z1` with `--target grblhal`: GRBL-class
    /// firmwares refuse a probe move to the point the tool is at
    /// (LinuxCNC accepts it and does nothing).
    TargetProbeInPlace { target: &'static str },
    /// A lowering that failed (its own code, E1100–E1149).
    TargetLowering {
        target: &'static str,
        code: &'static str,
        message: String,
    },
    // ------------------------------------------------------------ robustness
    /// A fault of ngcflat itself (a panic caught while checking a file).
    Internal { what: String },
    /// `o[1] sub`: a definition whose label is computed.
    ComputedSubLabel,
    /// `ngcflat -o part.ngc part.ngc` (also through links).
    OutputIsInput { output: PathBuf },
    /// A loop of long lines writing more than `--max-output-bytes`.
    OutputBytesLimit { limit: u64 },
    /// `--start-position part.ngc`: not a list of axis words.
    BadStartPosition { text: String },
    /// `G38.2 Z-10` then `#5063`: the probe's result exists only on the
    /// machine (probing overwrites any -D value).
    ProbeResultUnknown { index: usize, line: u32 },
    // ------------------------------------------------------------ machine view
    /// `--limits X300` (not `LETTER[MIN]:[MAX],...`).
    BadLimits { text: String },
    /// `MAX_VELOCITY = fast` in an INI axis section, `$110=x` in GRBL settings.
    BadMachineValue { source: String, text: String },
    /// A move beyond a travel limit (machine coordinates).
    TravelLimit {
        axis: char,
        value: f64,
        bound: f64,
        above: bool,
        source: String,
    },
    /// Travel limits are given but the offsets from work to machine
    /// coordinates (or the position) are not known at a move.
    LimitNeedsOffsets,
    /// `--source-map` or `--annotate` with `--target grbl`.
    SourceMapNeedsLinuxcnc,
    /// `ngcflat check emptydir`, or an `--ext` that matches nothing.
    NoPrograms { paths: Vec<PathBuf>, exts: String },
    /// A file with NUL bytes (an image, an archive, a compiled program).
    NotText { path: PathBuf },
    /// A `--user-m` value that is not M100-M199 or a range of them.
    BadUserM { text: String },
    /// `M100`-`M199` that neither --user-m nor the INI's folders declare.
    UndeclaredUserM { m: i64 },
    /// A block of a library definition that is not closed before its
    /// `endsub`: `o1 if [#1 GT 0]` ... `o<s> endsub`.
    UnclosedBlock {
        label: String,
        opened: &'static str,
        line: u32,
        closer: &'static str,
    },
}

impl ErrorKind {
    /// Stable code shown with every diagnostic.
    pub fn code(&self) -> &'static str {
        use ErrorKind::*;
        match self {
            CommandTooLong => "E0001",
            NestedComment => "E0002",
            UnclosedComment => "E0003",
            BadCharacter { .. } => "E0004",
            Syntax { .. } => "E0005",
            BadNumber { .. } => "E0006",
            TrailingNumber { .. } => "E0007",
            NonInteger { .. } => "E0008",
            StrayPercent => "E0009",
            DuplicateWord { .. } => "E0010",
            TooManyMWords => "E0011",
            MisplacedLineNumber => "E0012",
            DivideByZero => "E0101",
            NegativePower => "E0102",
            AcosRange => "E0103",
            AsinRange => "E0104",
            LnDomain => "E0105",
            SqrtNegative => "E0106",
            NotANumber => "E0107",
            Infinity => "E0108",
            ParamOutOfRange { .. } => "E0201",
            ParamReadOnly { .. } => "E0202",
            NamedUndefined { .. } => "E0203",
            NamedReadOnly { .. } => "E0204",
            RuntimeParam { .. } => "E0205",
            UnterminatedName => "E0206",
            UnknownPosition { .. } => "E0207",
            ToolNotInTable { .. } => "E0208",
            UnknownOCommand { .. } => "E0301",
            UnexpectedAfterOWord => "E0302",
            MissingBracket { .. } => "E0303",
            CallArgNotBracketed => "E0304",
            NotInSub => "E0305",
            DuplicateLabel { .. } => "E0306",
            UndefinedLabel { .. } => "E0307",
            LabelMismatch { .. } => "E0308",
            NestedSubDefinition { .. } => "E0309",
            IllegalSubLocation { .. } => "E0310",
            RedefiningSub { .. } => "E0311",
            TooManyArgs => "E0312",
            TooDeep { .. } => "E0313",
            SubNotFound { .. } => "E0314",
            SubNotInFile { .. } => "E0315",
            LabelBeforePercent { .. } => "E0316",
            EofSeeking { .. } => "E0317",
            MissingProgramEnd { .. } => "E0318",
            EmptyProgram => "E0319",
            M98WithoutP => "E0320",
            M98AmongWords => "E0330",
            M99AmongWords => "E0331",
            FanucNeedsM98 { .. } => "E0321",
            SubNeedsCall { .. } => "E0322",
            M99InSub => "E0323",
            EndsubInFanuc => "E0324",
            FanucDisabled { .. } => "E0325",
            UnterminatedSub { .. } => "E0326",
            Abort { .. } => "E0327",
            NoSavedContext => "E0328",
            BadCondition { .. } => "E0329",
            Block(e) => e.code(),
            CutterComp { error } => comp_code(*error),
            CompForbids { .. } => "E1170",
            CompAlreadyOn => "E1171",
            CompPlane => "E1172",
            CompPlaneChange => "E1173",
            CompArcAfterOff => "E1174",
            CompNoDiameter { .. } => "E1175",
            CompLatheTool { .. } => "E1176",
            Lathe(e) => e.code(),
            OutputLineTooLong { .. } => "E0401",
            StepLimit { .. } => "E0402",
            OutputLimit { .. } => "E0403",
            Unprintable { .. } => "E0404",
            ProgramChanged { .. } => "E0405",
            Io { .. } => "E0501",
            UnsafeSubName { .. } => "E0502",
            VarFileOrder { .. } => "E0503",
            VarFileSyntax { .. } => "E0504",
            BadDefine { .. } => "E0505",
            Unsupported { .. } => "E0507",
            TargetRefused { .. } => "E1000",
            TargetNeedsValue { .. } => "E1001",
            TargetLineTooLong { .. } => "E1002",
            UnknownTarget { .. } => "E1003",
            TargetProbeInPlace { .. } => "E1050",
            TargetLowering { code, .. } => code,
            Internal { .. } => "E0700",
            ComputedSubLabel => "E0701",
            OutputIsInput { .. } => "E0702",
            OutputBytesLimit { .. } => "E0703",
            BadStartPosition { .. } => "E0800",
            ProbeResultUnknown { .. } => "E0801",
            BadLimits { .. } => "E1201",
            BadMachineValue { .. } => "E1202",
            TravelLimit { .. } => "E1203",
            LimitNeedsOffsets => "E1204",
            SourceMapNeedsLinuxcnc => "E1205",
            NoPrograms { .. } => "E0802",
            NotText { .. } => "E0803",
            UnclosedBlock { .. } => "E0804",
            UndeclaredUserM { .. } => "E0805",
            BadUserM { .. } => "E0806",
        }
    }
}

/// Codes of the compensation geometry errors: E1150 and up, in the order
/// of [`crate::geom::comp::CompError::ALL`].
fn comp_code(e: crate::geom::comp::CompError) -> &'static str {
    use crate::geom::comp::CompError::*;
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

/// A runaway guard's message: what passed the bound, the innermost loop,
/// and the option that raises it.
fn runaway(
    f: &mut fmt::Formatter<'_>,
    what: fmt::Arguments<'_>,
    label: &Option<String>,
    line: &Option<u32>,
    option: &str,
) -> fmt::Result {
    f.write_fmt(what)?;
    limit_site(f, label, line)?;
    write!(f, " (raise with {option})")
}

fn no_programs(f: &mut fmt::Formatter<'_>, paths: &[PathBuf], exts: &str) -> fmt::Result {
    write!(f, "no programs found in")?;
    for p in paths {
        write!(f, " {}", p.display())?;
    }
    write!(f, " (extensions {exts}; --ext chooses others)")
}

fn limit_site(
    f: &mut fmt::Formatter<'_>,
    label: &Option<String>,
    line: &Option<u32>,
) -> fmt::Result {
    match (label, line) {
        (Some(l), Some(n)) => write!(f, " (innermost loop: o{l} at line {n})"),
        (Some(l), None) => write!(f, " (innermost loop: o{l})"),
        _ => Ok(()),
    }
}

impl fmt::Display for ErrorKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // Each group of variants has its own function; every variant is in
        // exactly one of them.
        self.fmt_syntax(f)
            .or_else(|| self.fmt_value(f))
            .or_else(|| self.fmt_oword(f))
            .or_else(|| self.fmt_machine(f))
            .or_else(|| self.fmt_limits(f))
            .or_else(|| self.fmt_setup(f))
            .unwrap_or_else(|| write!(f, "{self:?}"))
    }
}

impl ErrorKind {
    /// Lexing and line syntax.
    fn fmt_syntax(&self, f: &mut fmt::Formatter<'_>) -> Option<fmt::Result> {
        use ErrorKind::*;
        Some(match self {
            CommandTooLong => write!(f, "line is longer than 252 characters"),
            NestedComment => write!(f, "comment opened inside a comment"),
            UnclosedComment => write!(f, "comment is not closed before the end of the line"),
            BadCharacter { ch, byte } => {
                if ch.is_ascii_graphic() {
                    write!(f, "character '{ch}' is not allowed here")
                } else {
                    write!(f, "byte 0x{byte:02x} is not allowed outside a comment")
                }
            }
            Syntax { expected } => write!(f, "expected {expected}"),
            BadNumber { text } => write!(f, "'{text}' is not a number"),
            TrailingNumber { text } => {
                write!(f, "'{text}' is not a number (more than one decimal point)")
            }
            NonInteger { value } => write!(f, "{value} is not an integer"),
            StrayPercent => write!(f, "'%' line in a program that does not start with '%'"),
            DuplicateWord { letter } => write!(
                f,
                "more than one {} word on the line",
                letter.to_ascii_uppercase()
            ),
            TooManyMWords => write!(f, "more than four M words on the line"),
            MisplacedLineNumber => write!(f, "an N line number may only start the line"),
            UnterminatedName => write!(f, "named parameter is not terminated by '>'"),
            NotText { path } => write!(
                f,
                "{}: not a text G-code program (it contains NUL bytes: a binary file?)",
                path.display()
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
            _ => return None,
        })
    }

    /// Expressions, parameters and values only the machine knows.
    fn fmt_value(&self, f: &mut fmt::Formatter<'_>) -> Option<fmt::Result> {
        use ErrorKind::*;
        Some(match self {
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
            Unprintable { value } => {
                write!(f, "value {value} cannot be written as a G-code number")
            }
            ProgramChanged { line } => write!(
                f,
                "the program changed while it was run: line {line} is no longer the O-word line it was when the file was read"
            ),
            ProbeResultUnknown { index, line } => write!(
                f,
                "#{index} is the result of the probe at line {line}, known only on the machine; a program that uses it cannot be flattened ahead of time (--zero-start assumes the probe does not trip and reads its target, as LinuxCNC's standalone interpreter does)"
            ),
            _ => return None,
        })
    }

    /// O-words, subroutines, program structure and state saved by M70/M73.
    fn fmt_oword(&self, f: &mut fmt::Formatter<'_>) -> Option<fmt::Result> {
        use ErrorKind::*;
        Some(match self {
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
            M99AmongWords => write!(
                f,
                "M99 returning from a subprogram shares its line with other words; write it alone: 'M99'"
            ),
            M98AmongWords => write!(
                f,
                "M98 not written 'M98 P...' at the start of its line (after other words, or computed) is not run"
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
            NoSavedContext => write!(
                f,
                "M72 without a state saved by M70 or M73 at this call level"
            ),
            UnsafeSubName { name } => write!(
                f,
                "subroutine name '{name}' could leave the search path; use plain names (letters, digits, '_', '-')"
            ),
            ComputedSubLabel => write!(
                f,
                "a subroutine definition needs a fixed label (o<name> sub or o100 sub), not a computed one"
            ),
            _ => return None,
        })
    }

    /// Blocks the machine model refuses: modal checks, cutter compensation, lathe cycles.
    fn fmt_machine(&self, f: &mut fmt::Formatter<'_>) -> Option<fmt::Result> {
        use ErrorKind::*;
        Some(match self {
            Block(e) => write!(f, "{e}"),
            CutterComp { error } => write!(f, "{error}"),
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
            Lathe(e) => write!(f, "{e}"),
            _ => return None,
        })
    }

    /// Runaway guards and travel limits.
    fn fmt_limits(&self, f: &mut fmt::Formatter<'_>) -> Option<fmt::Result> {
        use ErrorKind::*;
        Some(match self {
            OutputLineTooLong { len } => {
                write!(
                    f,
                    "output line would be {len} characters; the limit is 252 (try --precision)"
                )
            }
            StepLimit { limit, label, line } => runaway(
                f,
                format_args!("more than {limit} O-word lines executed; runaway loop or recursion?"),
                label,
                line,
                "--max-steps",
            ),
            OutputLimit { limit, label, line } => runaway(
                f,
                format_args!("more than {limit} output lines"),
                label,
                line,
                "--max-output-lines",
            ),
            OutputBytesLimit { limit } => write!(
                f,
                "the output grew past {limit} bytes (the program's size plus --max-output-bytes); runaway loop? (raise with --max-output-bytes)"
            ),
            TravelLimit {
                axis,
                value,
                bound,
                above,
                source,
            } => {
                let unit = if matches!(axis, 'A' | 'B' | 'C') {
                    "deg"
                } else {
                    "mm"
                };
                write!(
                    f,
                    "this move takes {axis} to {} {unit} (machine coordinates), {} the travel limit {} {unit} from {source}",
                    crate::number::number_string(*value, Some(4)),
                    if *above { "above" } else { "below" },
                    crate::number::number_string(*bound, Some(4)),
                )
            }
            LimitNeedsOffsets => write!(
                f,
                "travel limits are in machine coordinates, but where this move goes on the machine is not known (the offsets from work to machine coordinates, or the position); supply them with --zero-start, --var-file or -D (e.g. -D 5221=0 for the G54 X offset) and --start-position, or turn the check off with --no-limits"
            ),
            _ => return None,
        })
    }

    /// Settings, files, targets and what is outside the program.
    fn fmt_setup(&self, f: &mut fmt::Formatter<'_>) -> Option<fmt::Result> {
        use ErrorKind::*;
        Some(match self {
            Io { path, message } => write!(f, "{}: {message}", path.display()),
            VarFileOrder { index } => {
                write!(f, "parameter file is not in ascending order at #{index}")
            }
            VarFileSyntax { text } => {
                write!(f, "parameter file line '{text}' is not 'number value'")
            }
            BadDefine { text } => write!(
                f,
                "-D '{text}' is not PARAM=VALUE (e.g. 5063=-1.25, depth=3, _depth=3)"
            ),
            Unsupported { what } => write!(f, "{what}"),
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
            TargetLowering {
                target, message, ..
            } => write!(f, "{message} (lowering for {target})"),
            Internal { what } => write!(
                f,
                "internal error: {what}; please report it with the program"
            ),
            OutputIsInput { output } => write!(
                f,
                "the output {} is the program being flattened; choose another output file",
                output.display()
            ),
            NoPrograms { paths, exts } => no_programs(f, paths, exts),
            BadUserM { text } => write!(
                f,
                "--user-m '{text}' is not a user M-code M100-M199 or a range of them (e.g. 100,101-105)"
            ),
            UndeclaredUserM { m } => write!(
                f,
                "M{m} is a user M-code (an external program on the LinuxCNC machine) that is not declared: give --user-m {m}, or --ini with an [RS274NGC]USER_M_PATH or [DISPLAY]PROGRAM_PREFIX folder holding an executable file M{m}"
            ),
            BadStartPosition { text } => write!(
                f,
                "--start-position '{text}' is not a list of axis words such as X0,Y0,Z10 (mm; X0.5in for inches)"
            ),
            BadLimits { text } => write!(
                f,
                "--limits '{text}' is not a list of AXIS[MIN]:[MAX] ranges in mm (e.g. X0:300,Y0:200,Z-60:0)"
            ),
            BadMachineValue { source, text } => {
                write!(f, "{source} value '{text}' is not a number")
            }
            SourceMapNeedsLinuxcnc => write!(
                f,
                "--source-map and --annotate map output lines written as the program's own lines; they work with --target linuxcnc only"
            ),
            _ => return None,
        })
    }
}

#[cfg(test)]
mod tests {
    /// The variant names of `ErrorKind`, read from its definition.
    fn variants(src: &str) -> Vec<&str> {
        let body = src
            .split_once("pub enum ErrorKind {")
            .and_then(|(_, rest)| rest.split_once("\n}\n"))
            .map(|(body, _)| body)
            .expect("the ErrorKind definition");
        body.lines()
            .filter_map(|l| l.strip_prefix("    "))
            .filter(|l| l.starts_with(|c: char| c.is_ascii_uppercase()))
            .map(|l| {
                l.split(|c: char| !c.is_ascii_alphanumeric())
                    .next()
                    .unwrap_or("")
            })
            .collect()
    }

    /// The variants the match arms of one `fmt_*` group function name (an
    /// arm starts a line: `Name =>`, `Name {`, `Name(`, or `| Name`).
    fn arms(body: &str) -> Vec<&str> {
        body.lines()
            .map(|l| l.trim_start().trim_start_matches("| "))
            .filter(|l| l.starts_with(|c: char| c.is_ascii_uppercase()))
            .filter_map(|l| {
                let name = l.split(|c: char| !c.is_ascii_alphanumeric()).next()?;
                let rest = l[name.len()..].trim_start();
                (rest.starts_with("=>")
                    || rest.starts_with('{')
                    || rest.starts_with('(')
                    || rest.starts_with('|'))
                .then_some(name)
            })
            .collect()
    }

    /// Display falls back to Debug for a variant no group function names:
    /// every variant must be in exactly one group, so that each has a real
    /// message.
    #[test]
    fn every_variant_has_a_message() {
        let src = include_str!("error_kind.rs");
        let variants = variants(src);
        assert!(variants.len() > 100, "variants found: {}", variants.len());
        let groups: Vec<(&str, Vec<&str>)> = src
            .split("\n    fn fmt_")
            .skip(1)
            .map(|g| {
                let name = g.split('(').next().unwrap_or("");
                let body = g.split_once("\n    }\n").map_or(g, |(b, _)| b);
                (name, arms(body))
            })
            .collect();
        assert!(groups.len() >= 6, "groups found: {}", groups.len());
        let mut problems = Vec::new();
        for v in &variants {
            let in_groups: Vec<&str> = groups
                .iter()
                .filter(|(_, arms)| arms.contains(v))
                .map(|(g, _)| *g)
                .collect();
            if in_groups.len() != 1 {
                problems.push(format!("{v}: in {in_groups:?}"));
            }
        }
        assert!(
            problems.is_empty(),
            "ErrorKind variants not in exactly one fmt_* group (their message would be Debug output): {problems:#?}"
        );
    }
}
