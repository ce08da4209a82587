//! G and M codes by what they do: one enum per modal group, decoded from
//! the code's number. The evaluator (its modal state, the block checks and
//! the state update) and the machine model after it read codes through these
//! types alone; the numbers LinuxCNC reports (`#<_plane>` is 170 for G17)
//! come from [`GCode::code10`] and its kin at that edge.

/// Motion modes (group 1), including canned cycles and the codes that stop
/// them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MotionMode {
    Rapid,
    Linear,
    ArcCw,
    ArcCcw,
    /// G5 cubic spline.
    CubicSpline,
    /// G5.1 quadratic spline.
    QuadSpline,
    /// G5.2 NURBS control points.
    Nurbs,
    /// G5.3 end of NURBS block.
    NurbsEnd,
    /// G33 spindle-synchronised motion.
    Thread,
    /// G33.1 rigid tapping.
    RigidTap,
    /// G38.2–G38.5 (the sub-code 2–5).
    Probe(u8),
    /// G76 threading cycle.
    ThreadCycle,
    /// G70–G72 lathe cycles: the number and the sub-code (G71.2 is 71, 2).
    LatheCycle {
        number: u8,
        sub: u8,
    },
    /// G73, G74, G81–G89 (their number).
    Cycle(u8),
    /// G80
    CancelCycle,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Plane {
    XY,
    XZ,
    YZ,
    /// G17.1, G18.1, G19.1 (UV, WU, VW)
    UV,
    WU,
    VW,
}

/// Distance mode (group 3). Of two-way groups the variant the hot paths
/// test for is declared second (discriminant 1): `d == Distance::Absolute`
/// is then a plain load, as a bool was.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Distance {
    Incremental,
    Absolute,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FeedMode {
    InverseTime,
    PerMinute,
    PerRev,
}

/// Units (group 6); Mm second, as in [`Distance`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Units {
    Inch,
    Mm,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CutterComp {
    Off,
    Left,
    Right,
    /// G41.1 / G42.1 (diameter given by D)
    DynamicLeft,
    DynamicRight,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ToolLength {
    /// G43 (H or the current tool)
    Apply,
    /// G43.1 (axis words give the offset)
    Dynamic,
    /// G43.2 (adds H's offset)
    Add,
    /// G49
    Cancel,
}

impl ToolLength {
    /// A tool length offset is in effect (G43, G43.1, G43.2; not G49), as
    /// `#<_tool_offset>` reads it.
    pub fn in_effect(self) -> bool {
        self != ToolLength::Cancel
    }
}

/// G54–G59.3 as 1–9.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CoordSystem(pub u8);

impl CoordSystem {
    /// G54, LinuxCNC's first coordinate system.
    pub const G54: CoordSystem = CoordSystem(1);

    /// Its row in a table of the nine systems (G54 is 0, G59.3 is 8).
    pub fn index(self) -> usize {
        (self.0.clamp(1, 9) - 1) as usize
    }

    /// The first of its parameters (#5221 for G54, #5241 for G55, ...).
    pub fn parameters(self) -> usize {
        5221 + 20 * (self.0 as usize).saturating_sub(1)
    }

    /// Its G code as written (G54, G59.1).
    pub fn name(self) -> String {
        let c = CoordSystem(self.0.clamp(1, 9)).code10();
        if c.is_multiple_of(10) {
            format!("G{}", c / 10)
        } else {
            format!("G{}.{}", c / 10, c % 10)
        }
    }

    /// The G code ×10 (G54 → 540, G59.1 → 591).
    pub fn code10(self) -> u16 {
        match self.0 {
            1..=6 => 530 + 10 * self.0 as u16,
            n => 590 + (n as u16 - 6),
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PathMode {
    /// G61
    Exact,
    /// G61.1
    ExactStop,
    /// G64
    Blend,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Retract {
    /// G98
    Initial,
    /// G99
    R,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SpindleMode {
    /// G96
    ConstantSurface,
    /// G97
    Rpm,
}

/// Lathe diameter mode (group 15); Diameter second, as in [`Distance`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LatheMode {
    /// G8
    Radius,
    /// G7
    Diameter,
}

/// Non-modal G codes (group 0).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NonModal {
    Dwell,
    /// G10 (L and P say what)
    SetData,
    /// G28, G28.1
    Home,
    SetHome,
    /// G30, G30.1
    Home2,
    SetHome2,
    /// G52
    LocalOffset,
    /// G53
    MachineCoords,
    /// G92, G92.1, G92.2, G92.3
    SetG92,
    ResetG92,
    SuspendG92,
    RestoreG92,
}

/// Arc distance mode (group 4); Absolute second, as in [`Distance`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ArcDistance {
    /// G91.1
    Incremental,
    /// G90.1
    Absolute,
}

/// A G code by modal group.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GCode {
    Motion(MotionMode),
    Plane(Plane),
    Distance(Distance),
    ArcDistance(ArcDistance),
    FeedMode(FeedMode),
    Units(Units),
    CutterComp(CutterComp),
    ToolLength(ToolLength),
    Coord(CoordSystem),
    Path(PathMode),
    Retract(Retract),
    SpindleMode(SpindleMode),
    Lathe(LatheMode),
    NonModal(NonModal),
}

/// The G number ×10 a G word's value stands for, as the reference reads
/// it: ten times the value, taken down to a whole number, or up when it is
/// more than 0.999 above one; `None` when it is more than 0.001 above one
/// and not that far (`G1.00005` is G1, `G1.0005` is refused). The evaluator's
/// checks and the decoder of flat lines share it, so that a target reads
/// every G word the evaluator accepted.
pub(crate) fn g_tenths(value: f64) -> Option<f64> {
    let v10 = value * 10.0;
    let down = v10.floor();
    match v10 - down {
        f if f > 0.999 => Some(down + 1.0),
        f if f > 0.001 => None,
        _ => Some(down),
    }
}

impl GCode {
    /// Decodes a G number (`value` as written, e.g. 59.1).
    pub fn decode(value: f64) -> Option<GCode> {
        let t = g_tenths(value).filter(|t| (0.0..=1000.0).contains(t))?;
        GCode::from_code10(t as u16)
    }

    /// The G code of a number ×10 (G59.1 → 591), None for one LinuxCNC
    /// does not know. The evaluator, which rounds G words with its own
    /// tolerance, decodes through this too.
    #[inline]
    pub fn from_code10(t: u16) -> Option<GCode> {
        use GCode::*;
        use MotionMode as M;
        Some(match t {
            0 => Motion(M::Rapid),
            10 => Motion(M::Linear),
            20 => Motion(M::ArcCw),
            30 => Motion(M::ArcCcw),
            40 => NonModal(self::NonModal::Dwell),
            50 => Motion(M::CubicSpline),
            51 => Motion(M::QuadSpline),
            52 => Motion(M::Nurbs),
            53 => Motion(M::NurbsEnd),
            70 => Lathe(LatheMode::Diameter),
            80 => Lathe(LatheMode::Radius),
            100 => NonModal(self::NonModal::SetData),
            170 => Plane(self::Plane::XY),
            180 => Plane(self::Plane::XZ),
            190 => Plane(self::Plane::YZ),
            171 => Plane(self::Plane::UV),
            181 => Plane(self::Plane::WU),
            191 => Plane(self::Plane::VW),
            200 => Units(self::Units::Inch),
            210 => Units(self::Units::Mm),
            280 => NonModal(self::NonModal::Home),
            281 => NonModal(self::NonModal::SetHome),
            300 => NonModal(self::NonModal::Home2),
            301 => NonModal(self::NonModal::SetHome2),
            330 => Motion(M::Thread),
            331 => Motion(M::RigidTap),
            382..=385 => Motion(M::Probe((t - 380) as u8)),
            400 => CutterComp(self::CutterComp::Off),
            410 => CutterComp(self::CutterComp::Left),
            420 => CutterComp(self::CutterComp::Right),
            411 => CutterComp(self::CutterComp::DynamicLeft),
            421 => CutterComp(self::CutterComp::DynamicRight),
            430 => ToolLength(self::ToolLength::Apply),
            431 => ToolLength(self::ToolLength::Dynamic),
            432 => ToolLength(self::ToolLength::Add),
            490 => ToolLength(self::ToolLength::Cancel),
            520 => NonModal(self::NonModal::LocalOffset),
            530 => NonModal(self::NonModal::MachineCoords),
            540..=590 if t.is_multiple_of(10) => Coord(CoordSystem(((t - 530) / 10) as u8)),
            591..=593 => Coord(CoordSystem((t - 591 + 7) as u8)),
            610 => Path(PathMode::Exact),
            611 => Path(PathMode::ExactStop),
            640 => Path(PathMode::Blend),
            700 | 710..=712 | 720..=722 => Motion(M::LatheCycle {
                number: (t / 10) as u8,
                sub: (t % 10) as u8,
            }),
            730 => Motion(M::Cycle(73)),
            740 => Motion(M::Cycle(74)),
            760 => Motion(M::ThreadCycle),
            800 => Motion(M::CancelCycle),
            810..=890 if t.is_multiple_of(10) => Motion(M::Cycle((t / 10) as u8)),
            900 => Distance(self::Distance::Absolute),
            910 => Distance(self::Distance::Incremental),
            901 => ArcDistance(self::ArcDistance::Absolute),
            911 => ArcDistance(self::ArcDistance::Incremental),
            920 => NonModal(self::NonModal::SetG92),
            921 => NonModal(self::NonModal::ResetG92),
            922 => NonModal(self::NonModal::SuspendG92),
            923 => NonModal(self::NonModal::RestoreG92),
            930 => FeedMode(self::FeedMode::InverseTime),
            940 => FeedMode(self::FeedMode::PerMinute),
            950 => FeedMode(self::FeedMode::PerRev),
            960 => SpindleMode(self::SpindleMode::ConstantSurface),
            970 => SpindleMode(self::SpindleMode::Rpm),
            980 => Retract(self::Retract::Initial),
            990 => Retract(self::Retract::R),
            _ => return None,
        })
    }

    /// Whether the code sets modal state (everything but group 0).
    pub fn is_modal(self) -> bool {
        !matches!(self, GCode::NonModal(_))
    }

    /// The G code ×10 (the inverse of [`GCode::from_code10`]).
    pub fn code10(self) -> u16 {
        match self {
            GCode::Motion(m) => m.code10(),
            GCode::Plane(p) => p.code10(),
            GCode::Distance(Distance::Absolute) => 900,
            GCode::Distance(Distance::Incremental) => 910,
            GCode::ArcDistance(ArcDistance::Absolute) => 901,
            GCode::ArcDistance(ArcDistance::Incremental) => 911,
            GCode::FeedMode(f) => f.code10(),
            GCode::Units(Units::Inch) => 200,
            GCode::Units(Units::Mm) => 210,
            GCode::CutterComp(c) => c.code10(),
            GCode::ToolLength(ToolLength::Apply) => 430,
            GCode::ToolLength(ToolLength::Dynamic) => 431,
            GCode::ToolLength(ToolLength::Add) => 432,
            GCode::ToolLength(ToolLength::Cancel) => 490,
            GCode::Coord(c) => c.code10(),
            GCode::Path(p) => p.code10(),
            GCode::Retract(Retract::Initial) => 980,
            GCode::Retract(Retract::R) => 990,
            GCode::SpindleMode(SpindleMode::ConstantSurface) => 960,
            GCode::SpindleMode(SpindleMode::Rpm) => 970,
            GCode::Lathe(LatheMode::Diameter) => 70,
            GCode::Lathe(LatheMode::Radius) => 80,
            GCode::NonModal(n) => match n {
                NonModal::Dwell => 40,
                NonModal::SetData => 100,
                NonModal::Home => 280,
                NonModal::SetHome => 281,
                NonModal::Home2 => 300,
                NonModal::SetHome2 => 301,
                NonModal::LocalOffset => 520,
                NonModal::MachineCoords => 530,
                NonModal::SetG92 => 920,
                NonModal::ResetG92 => 921,
                NonModal::SuspendG92 => 922,
                NonModal::RestoreG92 => 923,
            },
        }
    }

    /// The code as written in a program: `G17`, `G59.1`.
    pub fn name(self) -> String {
        let t = self.code10();
        if t.is_multiple_of(10) {
            format!("G{}", t / 10)
        } else {
            format!("G{}.{}", t / 10, t % 10)
        }
    }

    /// LinuxCNC's modal group: 0 non-modal, 1 motion, 2 plane, 3 distance,
    /// 4 arc distance, 5 feed mode, 6 units, 7 cutter compensation, 8 tool
    /// length, 10 canned cycle return, 12 coordinate system, 13 path
    /// control, 14 spindle speed mode, 15 lathe diameter mode.
    pub fn group(self) -> u8 {
        match self {
            GCode::NonModal(_) => 0,
            GCode::Motion(_) => 1,
            GCode::Plane(_) => 2,
            GCode::Distance(_) => 3,
            GCode::ArcDistance(_) => 4,
            GCode::FeedMode(_) => 5,
            GCode::Units(_) => 6,
            GCode::CutterComp(_) => 7,
            GCode::ToolLength(_) => 8,
            GCode::Retract(_) => 10,
            GCode::Coord(_) => 12,
            GCode::Path(_) => 13,
            GCode::SpindleMode(_) => 14,
            GCode::Lathe(_) => 15,
        }
    }
}

impl MotionMode {
    /// The G code ×10 (G1 → 10, G38.2 → 382, G80 → 800).
    pub fn code10(self) -> u16 {
        use MotionMode::*;
        match self {
            Rapid => 0,
            Linear => 10,
            ArcCw => 20,
            ArcCcw => 30,
            CubicSpline => 50,
            QuadSpline => 51,
            Nurbs => 52,
            NurbsEnd => 53,
            Thread => 330,
            RigidTap => 331,
            Probe(s) => 380 + s as u16,
            ThreadCycle => 760,
            LatheCycle { number, sub } => 10 * number as u16 + sub as u16,
            Cycle(n) => 10 * n as u16,
            CancelCycle => 800,
        }
    }

    /// A canned cycle: G73, G74, G81–G89.
    pub fn is_canned_cycle(self) -> bool {
        matches!(self, MotionMode::Cycle(_))
    }
}

impl Plane {
    /// The G code ×10 (G17 → 170, G18.1 → 181), as `#<_plane>` reads.
    pub fn code10(self) -> u16 {
        match self {
            Plane::XY => 170,
            Plane::XZ => 180,
            Plane::YZ => 190,
            Plane::UV => 171,
            Plane::WU => 181,
            Plane::VW => 191,
        }
    }

    /// The plane's axes as indices into X Y Z A B C U V W: the first and
    /// second in-plane axes, in LinuxCNC's order for the plane (XY, ZX, YZ,
    /// UV, WU, VW), in which a counter-clockwise arc (G3) turns from the
    /// first toward the second, and the normal (helix) axis.
    pub fn axes(self) -> [usize; 3] {
        match self {
            Plane::XY => [0, 1, 2],
            Plane::XZ => [2, 0, 1],
            Plane::YZ => [1, 2, 0],
            Plane::UV => [6, 7, 8],
            Plane::WU => [8, 6, 7],
            Plane::VW => [7, 8, 6],
        }
    }

    /// [`Plane::axes`] of the XYZ planes (G17, G18, G19), indices into X Y
    /// Z; `None` for the UVW planes (G17.1, G18.1, G19.1).
    pub fn xyz_axes(self) -> Option<[usize; 3]> {
        match self {
            Plane::XY | Plane::XZ | Plane::YZ => Some(self.axes()),
            Plane::UV | Plane::WU | Plane::VW => None,
        }
    }
}

impl FeedMode {
    /// The G code ×10 (G93 → 930).
    pub fn code10(self) -> u16 {
        match self {
            FeedMode::InverseTime => 930,
            FeedMode::PerMinute => 940,
            FeedMode::PerRev => 950,
        }
    }
}

impl CutterComp {
    /// The G code ×10 (G41.1 → 411).
    pub fn code10(self) -> u16 {
        match self {
            CutterComp::Off => 400,
            CutterComp::Left => 410,
            CutterComp::Right => 420,
            CutterComp::DynamicLeft => 411,
            CutterComp::DynamicRight => 421,
        }
    }

    /// The side the tool is on (G41.1 is G41 with its own diameter): Off,
    /// Left or Right, as `#<_ccomp>` reads it.
    pub fn side(self) -> CutterComp {
        match self {
            CutterComp::DynamicLeft => CutterComp::Left,
            CutterComp::DynamicRight => CutterComp::Right,
            c => c,
        }
    }
}

impl PathMode {
    /// The G code ×10 (G61.1 → 611).
    pub fn code10(self) -> u16 {
        match self {
            PathMode::Exact => 610,
            PathMode::ExactStop => 611,
            PathMode::Blend => 640,
        }
    }
}

/// M codes by what they do.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MCode {
    /// M0, M1
    Pause {
        optional: bool,
    },
    /// M60 (pallet change pause)
    PalletPause,
    /// M2, M30
    End {
        rewind: bool,
    },
    /// M3, M4, M5
    Spindle(SpindleDir),
    /// M19
    Orient,
    /// M6
    ToolChange,
    /// M61 (Q gives the tool)
    SetTool,
    /// M7, M8, M9
    Mist,
    Flood,
    CoolantOff,
    /// M48–M53: overrides and feed hold (the number)
    Override(u8),
    /// M70 save, M71 invalidate, M72 restore, M73 save and auto-restore
    State(u8),
    /// M62–M68: digital and analog I/O (the number)
    Io(u8),
    /// M100–M199
    User(u8),
    /// Anything else (the number ×10 when not whole, else the number).
    Other(u16),
}

impl MCode {
    pub fn decode(value: f64) -> MCode {
        if value.fract() != 0.0 || !(0.0..=1000.0).contains(&value) {
            return MCode::Other((value * 10.0).clamp(0.0, 60000.0) as u16);
        }
        match value as u16 {
            0 => MCode::Pause { optional: false },
            1 => MCode::Pause { optional: true },
            2 => MCode::End { rewind: false },
            30 => MCode::End { rewind: true },
            60 => MCode::PalletPause,
            3 => MCode::Spindle(SpindleDir::Cw),
            4 => MCode::Spindle(SpindleDir::Ccw),
            5 => MCode::Spindle(SpindleDir::Off),
            19 => MCode::Orient,
            6 => MCode::ToolChange,
            61 => MCode::SetTool,
            7 => MCode::Mist,
            8 => MCode::Flood,
            9 => MCode::CoolantOff,
            n @ 48..=53 => MCode::Override(n as u8),
            n @ 70..=73 => MCode::State(n as u8),
            n @ 62..=68 => MCode::Io(n as u8),
            n @ 100..=199 => MCode::User((n - 100) as u8),
            n => MCode::Other(n),
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SpindleDir {
    Off,
    Cw,
    Ccw,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn g_codes_by_number_and_back() {
        let mut known = 0;
        for t in 0..=1000u16 {
            if let Some(g) = GCode::from_code10(t) {
                assert_eq!(g.code10(), t, "{g:?}");
                assert_eq!(GCode::decode(t as f64 / 10.0), Some(g));
                known += 1;
            }
        }
        assert_eq!(known, 88);
        let g711 = GCode::from_code10(711).unwrap();
        assert_eq!(g711.name(), "G71.1");
        assert_eq!(g711.group(), 1);
        assert_eq!(GCode::from_code10(593).unwrap().name(), "G59.3");
        assert_eq!(CutterComp::DynamicRight.side(), CutterComp::Right);
        assert_eq!(CoordSystem::G54.parameters(), 5221);
        assert_eq!(CoordSystem(9).parameters(), 5381);
        assert_eq!(CoordSystem(6).code10(), 590);
        assert_eq!(CoordSystem(7).code10(), 591);
    }

    #[test]
    fn plane_axes() {
        // G18 turns from Z toward X; G18.1 likewise from W toward U.
        assert_eq!(Plane::XZ.axes(), [2, 0, 1]);
        assert_eq!(Plane::WU.axes(), [8, 6, 7]);
        for (xyz, uvw) in [
            (Plane::XY, Plane::UV),
            (Plane::XZ, Plane::WU),
            (Plane::YZ, Plane::VW),
        ] {
            assert_eq!(xyz.xyz_axes(), Some(xyz.axes()));
            assert_eq!(uvw.xyz_axes(), None);
            // The UVW plane is its XYZ plane six axes on.
            assert_eq!(uvw.axes(), xyz.axes().map(|i| i + 6));
        }
    }
}
