//! Blocks LinuxCNC refuses: a line's words that do not make a valid
//! block in the modal state they meet. Each refusal has its own code
//! (E0600–E0699) and keeps the reference's meaning.

use std::fmt;

#[derive(Debug, Clone, PartialEq)]
pub enum BlockError {
    /// G-code out of range
    GCodeOutOfRange,
    /// unknown G-code
    UnknownGCodeFraction,
    /// two G-codes from the same modal group
    SameGroupG,
    /// unknown M-code
    UnknownMCodeFraction,
    /// two M-codes from the same modal group
    SameGroupM,
    /// G5.3 without a G5.2 block before it
    NurbsEndWithoutStart,
    /// both X and Y are needed for a NURBS control point
    NurbsPointNeedsXY,
    /// a P word without X and Y is only allowed for the first NURBS control point
    NurbsPWithoutXY,
    /// a positive weight P is needed for every NURBS control point
    NurbsWeightNeeded,
    /// a NURBS block with a zero feed rate
    NurbsZeroFeed,
    /// all axes missing with motion code
    AxesMissing,
    /// dwell time P word missing with G82/G86/G88/G89
    CycleDwellMissing,
    /// Q word missing with G73/G83
    PeckQMissing,
    /// P word missing with G76
    G76PMissing,
    /// G76 with I 0
    G76IZero,
    /// G76 with J not above 0
    G76JNotPositive,
    /// G76 with K not above J
    G76KNotAboveJ,
    /// a G1/G2/G3 feed per revolution with spindle speed 0
    ZeroSpindlePerRev,
    /// R, I, J and K words all missing for arc
    ArcWordsMissing,
    /// spindle not turning in G33
    SpindleStoppedG33,
    /// two G-codes that both use axis values
    TwoAxisGCodes,
    /// cannot put a rotary axis word in a canned cycle
    RotaryInCycle,
    /// R clearance plane unspecified in canned cycle
    CycleRMissing,
    /// a canned cycle cannot be repeated zero times (L0)
    CycleL0,
    /// canned cycles cannot use inverse time feed (G93)
    CycleInverseTime,
    /// canned cycles cannot be used with cutter compensation on
    CycleWithComp,
    /// spindle not turning in a tapping or boring cycle
    CycleSpindleStopped,
    /// spindle turning counterclockwise in G84
    G84SpindleCcw,
    /// spindle turning clockwise in G74
    G74SpindleCw,
    /// axis values with G80
    AxesWithG80,
    /// axis values without a G-code that uses them
    AxesWithoutGCode,
    /// polar coordinates and X/Y words together
    PolarWithXY,
    /// polar coordinates while the plane is not G17 (the plane before the
    /// line: a G17 on it comes too late)
    PolarOutsideXY,
    /// negative L word
    NegativeL,
    /// negative F word
    NegativeF,
    /// negative spindle speed
    NegativeS,
    /// negative tool number
    NegativeT,
    /// G41/G42 need a whole-number D word
    CompDNotWhole,
    /// negative or zero Q value in G73/G83
    PeckQNotPositive,
    /// negative H word
    NegativeH,
    /// G53 needs G0 or G1
    G53NeedsG0G1,
    /// G53 cannot be used in incremental mode (G91)
    G53Incremental,
    /// G10 needs L1, L2, L10, L11 or L20
    G10BadL,
    /// G10 P value not a whole number
    G10PNotWhole,
    /// G10 L2/L20 P value out of range (0 to 9)
    G10CoordPRange,
    /// G10 L1/L10/L11 P value (a tool number) out of range
    G10ToolPRange,
    /// dwell time missing with G4
    G4PMissing,
    /// S word missing with G96
    G96SMissing,
    /// no valid P word with M62-M65
    M62PMissing,
    /// M66 needs a P or an E word
    M66PEMissing,
    /// M61 needs a Q word (tool number)
    M61QMissing,
    /// F word missing with an inverse time move
    InverseTimeFMissing,
    /// cannot move at zero feed rate
    ZeroFeed,
    /// K word missing with G33
    G33KMissing,
    /// current point same as end point of arc
    ArcSamePoint,
    /// arc radius too small to reach end point
    ArcRadiusTooSmall,
    /// zero-radius arc
    ZeroRadiusArc,
    /// start point too close to probe point
    ProbeTooClose,
    UnknownGCode {
        code: String,
    },
    MCodeOver199 {
        m: i64,
    },
    UnknownMCode {
        m: i64,
    },
    NurbsTooFewPoints {
        order: u32,
    },
    CycleDepthMissing {
        axis: &'static str,
    },
    CycleRBelowDepth {
        axis: &'static str,
    },
    ArcRadiiDiffer {
        r1: f64,
        r2: f64,
    },
    WordUnused {
        letter: char,
    },
    /// polar coordinates at the origin, where no angle is defined: an
    /// `@` alone in G90, any polar word in G91
    PolarAtOrigin {
        incremental: bool,
    },
}

impl BlockError {
    pub fn code(&self) -> &'static str {
        use BlockError::*;
        match self {
            GCodeOutOfRange => "E0601",
            UnknownGCodeFraction => "E0602",
            SameGroupG => "E0603",
            UnknownMCodeFraction => "E0604",
            SameGroupM => "E0605",
            NurbsEndWithoutStart => "E0607",
            NurbsPointNeedsXY => "E0608",
            NurbsPWithoutXY => "E0609",
            NurbsWeightNeeded => "E0610",
            NurbsZeroFeed => "E0611",
            AxesMissing => "E0612",
            CycleDwellMissing => "E0613",
            PeckQMissing => "E0614",
            G76PMissing => "E0615",
            G76IZero => "E0665",
            G76JNotPositive => "E0666",
            G76KNotAboveJ => "E0667",
            ZeroSpindlePerRev => "E0668",
            ArcWordsMissing => "E0616",
            SpindleStoppedG33 => "E0617",
            TwoAxisGCodes => "E0618",
            RotaryInCycle => "E0619",
            CycleRMissing => "E0620",
            CycleL0 => "E0621",
            CycleInverseTime => "E0622",
            CycleWithComp => "E0623",
            CycleSpindleStopped => "E0624",
            G84SpindleCcw => "E0625",
            G74SpindleCw => "E0626",
            AxesWithG80 => "E0627",
            AxesWithoutGCode => "E0628",
            PolarWithXY => "E0629",
            PolarOutsideXY => "E0664",
            NegativeL => "E0630",
            NegativeF => "E0631",
            NegativeS => "E0632",
            NegativeT => "E0633",
            CompDNotWhole => "E0634",
            PeckQNotPositive => "E0635",
            NegativeH => "E0636",
            G53NeedsG0G1 => "E0637",
            G53Incremental => "E0638",
            G10BadL => "E0639",
            G10PNotWhole => "E0640",
            G10CoordPRange => "E0641",
            G10ToolPRange => "E0642",
            G4PMissing => "E0643",
            G96SMissing => "E0644",
            M62PMissing => "E0645",
            M66PEMissing => "E0646",
            M61QMissing => "E0647",
            InverseTimeFMissing => "E0648",
            ZeroFeed => "E0649",
            G33KMissing => "E0650",
            ArcSamePoint => "E0651",
            ArcRadiusTooSmall => "E0652",
            ZeroRadiusArc => "E0653",
            ProbeTooClose => "E0654",
            UnknownGCode { .. } => "E0655",
            MCodeOver199 { .. } => "E0656",
            UnknownMCode { .. } => "E0657",
            NurbsTooFewPoints { .. } => "E0658",
            CycleDepthMissing { .. } => "E0659",
            CycleRBelowDepth { .. } => "E0660",
            ArcRadiiDiffer { .. } => "E0661",
            WordUnused { .. } => "E0662",
            PolarAtOrigin { .. } => "E0663",
        }
    }
}

impl fmt::Display for BlockError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use BlockError::*;
        let text = match self {
            GCodeOutOfRange => "G-code out of range",
            UnknownGCodeFraction => "unknown G-code",
            SameGroupG => "two G-codes from the same modal group",
            UnknownMCodeFraction => "unknown M-code",
            SameGroupM => "two M-codes from the same modal group",
            NurbsEndWithoutStart => "G5.3 without a G5.2 block before it",
            NurbsPointNeedsXY => "both X and Y are needed for a NURBS control point",
            NurbsPWithoutXY => {
                "a P word without X and Y is only allowed for the first NURBS control point"
            }
            NurbsWeightNeeded => "a positive weight P is needed for every NURBS control point",
            NurbsZeroFeed => "a NURBS block with a zero feed rate",
            AxesMissing => "all axes missing with motion code",
            CycleDwellMissing => "dwell time P word missing with G82/G86/G88/G89",
            PeckQMissing => "Q word missing with G73/G83",
            G76PMissing => "P word missing with G76",
            G76IZero => "in G76, I must not be 0",
            G76JNotPositive => "in G76, J must be greater than 0",
            G76KNotAboveJ => "in G76, K must be greater than J",
            ZeroSpindlePerRev => "cannot feed with zero spindle speed in feed per rev mode",
            ArcWordsMissing => "R, I, J and K words all missing for arc",
            SpindleStoppedG33 => "spindle not turning in G33",
            TwoAxisGCodes => "two G-codes that both use axis values",
            RotaryInCycle => "cannot put a rotary axis word in a canned cycle",
            CycleRMissing => "R clearance plane unspecified in canned cycle",
            CycleL0 => "a canned cycle cannot be repeated zero times (L0)",
            CycleInverseTime => "canned cycles cannot use inverse time feed (G93)",
            CycleWithComp => "canned cycles cannot be used with cutter compensation on",
            CycleSpindleStopped => "spindle not turning in a tapping or boring cycle",
            G84SpindleCcw => "spindle turning counterclockwise in G84",
            G74SpindleCw => "spindle turning clockwise in G74",
            AxesWithG80 => "axis values with G80",
            AxesWithoutGCode => "axis values without a G-code that uses them",
            PolarWithXY => "polar coordinates and X/Y words together",
            PolarOutsideXY => "polar coordinates outside the G17 plane",
            NegativeL => "negative L word",
            NegativeF => "negative F word",
            NegativeS => "negative spindle speed",
            NegativeT => "negative tool number",
            CompDNotWhole => "G41/G42 need a whole-number D word",
            PeckQNotPositive => "negative or zero Q value in G73/G83",
            NegativeH => "negative H word",
            G53NeedsG0G1 => "G53 needs G0 or G1",
            G53Incremental => "G53 cannot be used in incremental mode (G91)",
            G10BadL => "G10 needs L1, L2, L10, L11 or L20",
            G10PNotWhole => "G10 P value not a whole number",
            G10CoordPRange => "G10 L2/L20 P value out of range (0 to 9)",
            G10ToolPRange => "G10 L1/L10/L11 P value (a tool number) out of range",
            G4PMissing => "dwell time missing with G4",
            G96SMissing => "S word missing with G96",
            M62PMissing => "no valid P word with M62-M65",
            M66PEMissing => "M66 needs a P or an E word",
            M61QMissing => "M61 needs a Q word (tool number)",
            InverseTimeFMissing => "F word missing with an inverse time move",
            ZeroFeed => "cannot move at zero feed rate",
            G33KMissing => "K word missing with G33",
            ArcSamePoint => "current point same as end point of arc",
            ArcRadiusTooSmall => "arc radius too small to reach end point",
            ZeroRadiusArc => "zero-radius arc",
            ProbeTooClose => "start point too close to probe point",
            UnknownGCode { code } => return write!(f, "unknown G-code G{code}"),
            MCodeOver199 { m } => return write!(f, "M-code greater than 199: M{m}"),
            UnknownMCode { m } => return write!(f, "unknown M-code M{m}"),
            NurbsTooFewPoints { order } => {
                return write!(
                    f,
                    "a NURBS block needs at least as many control points as its order L = {order}"
                );
            }
            CycleDepthMissing { axis } => {
                return write!(f, "{axis} value unspecified in canned cycle");
            }
            CycleRBelowDepth { axis } => return write!(f, "R less than {axis} in canned cycle"),
            ArcRadiiDiffer { r1, r2 } => {
                return write!(
                    f,
                    "radius to end of arc differs from radius to start (r1={r1:.4} r2={r2:.4})"
                );
            }
            PolarAtOrigin { incremental: true } => {
                "incremental motion with polar coordinates is indeterminate at the origin"
            }
            PolarAtOrigin { incremental: false } => {
                "polar coordinates at the origin need an angle (^)"
            }
            WordUnused { letter } => match letter {
                'i' => "I word with no G2, G3, G5, G5.1, G10, G33.1, G76 or G87 to use it",
                'j' => "J word with no G2, G3, G5, G5.1, G10, G76 or G87 to use it",
                'k' => "K word with no G2, G3, G33, G33.1, G76 or G87 to use it",
                'r' => "R word with no G-code that uses it",
                'p' => "P word with no G-code or M-code to use it",
                'q' => "Q word with no G-code or M-code to use it",
                'h' => "H word with no G43 or G76 to use it",
                'd' => "D word with no G41, G42 or G96 to use it",
                'e' => "E word with no G76, M66, M67 or M68 to use it",
                'l' => "L word with no G10, canned cycle or M66 to use it",
                '$' => "$ word with no spindle code to use it",
                _ => {
                    return write!(
                        f,
                        "{} word with no code to use it",
                        letter.to_ascii_uppercase()
                    );
                }
            },
        };
        f.write_str(text)
    }
}
