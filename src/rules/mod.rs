//! The machine state both machine models keep, and the rules of its
//! change that both follow: the evaluator's (`eval/state`, program units,
//! offsets in the numbered parameters) and the one after evaluation
//! (`machine/model.rs`, mm, driven by the flat lines) keep a [`Modes`] and
//! change it through these functions alone, so that a rule lives once.
//! What each model keeps apart (positions, offsets, the order a line's
//! codes act in, events) is handed back to it ([`MachineCode`],
//! [`Switched`]).

pub(crate) mod offsets;
pub(crate) mod tools;

use crate::codes::{
    ArcDistance, CoordSystem, CutterComp, Distance, FeedMode, GCode, LatheMode, MCode, MotionMode,
    NonModal, PathMode, Plane, Retract, SpindleDir, SpindleMode, ToolLength, Units,
};

/// The modal state a program puts the machine in, as the evaluator and the
/// machine model both keep it: the code in effect in each modal group, the
/// feed and speed, the spindle, the coolant and the override switches.
/// `default()` is LinuxCNC's power-on state. A new modal code needs its
/// decoding in `codes`, its field here and its arm in
/// [`Modes::set_mode`], which both owners update the modes through.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Modes {
    /// Group 1. The evaluator keeps `NurbsEnd` after G5.3 (no motion mode).
    pub(crate) motion: MotionMode,
    pub(crate) plane: Plane,
    pub(crate) distance: Distance,
    pub(crate) arc_distance: ArcDistance,
    pub(crate) feed_mode: FeedMode,
    pub(crate) units: Units,
    /// As written: G41.1 and G42.1 stay dynamic (`#<_ccomp>` reads the
    /// side, [`CutterComp::side`]).
    pub(crate) cutter_comp: CutterComp,
    /// `Cancel` (G49), or the code that put an offset in effect.
    pub(crate) tool_length: ToolLength,
    /// G54 … G59.3
    pub(crate) coord: CoordSystem,
    pub(crate) path: PathMode,
    pub(crate) retract: Retract,
    pub(crate) spindle_mode: SpindleMode,
    pub(crate) lathe: LatheMode,
    /// In program units (per minute, per rev or inverse time).
    pub(crate) feed: f64,
    pub(crate) speed: f64,
    pub(crate) spindle: SpindleDir,
    pub(crate) mist: bool,
    pub(crate) flood: bool,
    /// M48–M53: speed and feed override, adaptive feed, feed hold.
    pub(crate) speed_override: bool,
    pub(crate) feed_override: bool,
    pub(crate) adaptive_feed: bool,
    pub(crate) feed_hold: bool,
}

impl Default for Modes {
    fn default() -> Modes {
        Modes {
            motion: MotionMode::CancelCycle,
            plane: Plane::XY,
            distance: Distance::Absolute,
            arc_distance: ArcDistance::Incremental,
            feed_mode: FeedMode::PerMinute,
            units: Units::Mm,
            cutter_comp: CutterComp::Off,
            tool_length: ToolLength::Cancel,
            coord: CoordSystem::G54,
            path: PathMode::Blend,
            // LinuxCNC starts in G99 (`#<_retract_r_plane>` reads 1).
            retract: Retract::R,
            spindle_mode: SpindleMode::Rpm,
            lathe: LatheMode::Radius,
            feed: 0.0,
            speed: 0.0,
            spindle: SpindleDir::Off,
            mist: false,
            flood: false,
            speed_override: true,
            feed_override: true,
            adaptive_feed: false,
            feed_hold: true,
        }
    }
}

/// A G code whose effect goes beyond the field of [`Modes`] its group is:
/// what [`Modes::set_mode`] leaves to the machine model that keeps the
/// modes, which knows the position, the offsets and the tools, and the
/// order the line's codes act in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum MachineCode {
    /// Group 1: the line's move runs in it, after its non-modal code.
    Motion(MotionMode),
    /// Group 6: positions and offsets are read in the new units.
    Units(Units),
    /// Group 8: a tool length offset from the tool data or the axis words.
    ToolLength(ToolLength),
    /// Group 12: the position is read in another system's offsets.
    Coord(CoordSystem),
    /// Group 0.
    NonModal(NonModal),
}

/// What an M code [`Modes::set_switch`] took set: the machine model may
/// tell the machine (a motion event).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Switched {
    /// M3, M4, M5
    Spindle,
    /// M7, M8, M9
    Coolant,
    /// M48–M53
    Overrides,
}

impl Modes {
    /// A G code's change of the modal state, where it is that group's
    /// field and nothing else (plane, distance, arc distance, feed mode,
    /// cutter compensation as written, path, retract, spindle mode, lathe
    /// mode); the codes that ask more of the machine are handed back,
    /// [`MachineCode`]. The one rule both machine models follow: a new
    /// modal code needs its decoding above, its field and an arm here.
    #[inline(always)]
    pub(crate) fn set_mode(&mut self, g: GCode) -> Option<MachineCode> {
        match g {
            GCode::Plane(p) => self.plane = p,
            GCode::Distance(d) => self.distance = d,
            GCode::ArcDistance(d) => self.arc_distance = d,
            GCode::FeedMode(f) => self.feed_mode = f,
            GCode::CutterComp(c) => self.cutter_comp = c,
            GCode::Path(p) => self.path = p,
            GCode::Retract(r) => self.retract = r,
            GCode::SpindleMode(s) => self.spindle_mode = s,
            GCode::Lathe(l) => self.lathe = l,
            GCode::Motion(m) => return Some(MachineCode::Motion(m)),
            GCode::Units(u) => return Some(MachineCode::Units(u)),
            GCode::ToolLength(t) => return Some(MachineCode::ToolLength(t)),
            GCode::Coord(c) => return Some(MachineCode::Coord(c)),
            GCode::NonModal(n) => return Some(MachineCode::NonModal(n)),
        }
        None
    }

    /// An axis word's value as the position it stands for, in both
    /// machine models: an X word is a diameter in lathe diameter mode
    /// (G7), and positions are radii.
    #[inline(always)]
    pub(crate) fn radius_word(&self, axis: usize, v: f64) -> f64 {
        if axis == 0 && self.lathe == LatheMode::Diameter {
            v / 2.0
        } else {
            v
        }
    }

    /// An M code's change of the switches (spindle direction, coolant,
    /// overrides with the line's P word, [`Modes::set_override`]): which
    /// it set, `None` for any other M code (left to the machine model).
    #[inline(always)]
    pub(crate) fn set_switch(&mut self, m: MCode, p: Option<f64>) -> Option<Switched> {
        match m {
            MCode::Spindle(d) => {
                self.spindle = d;
                Some(Switched::Spindle)
            }
            MCode::Mist => {
                self.mist = true;
                Some(Switched::Coolant)
            }
            MCode::Flood => {
                self.flood = true;
                Some(Switched::Coolant)
            }
            MCode::CoolantOff => {
                (self.mist, self.flood) = (false, false);
                Some(Switched::Coolant)
            }
            MCode::Override(n) => {
                self.set_override(n, p);
                Some(Switched::Overrides)
            }
            _ => None,
        }
    }

    /// M48–M53 (`n`) with the line's P word: M48 turns both overrides on,
    /// M49 off; M50–M53 turn their switch off with P0, on otherwise.
    pub(crate) fn set_override(&mut self, n: u8, p: Option<f64>) {
        let on = p.is_none_or(|p| p != 0.0);
        match n {
            48 | 49 => {
                self.speed_override = n == 48;
                self.feed_override = n == 48;
            }
            50 => self.feed_override = on,
            51 => self.speed_override = on,
            52 => self.adaptive_feed = on,
            53 => self.feed_hold = on,
            _ => {}
        }
    }

    /// What M2 and M30 reset, as LinuxCNC documents it: G54, G17, G90, G94,
    /// M48, G40, M5, G1, M9; and the feed rate, which rs274 sets to 0. The
    /// path mode (G61, G64) stays.
    pub(crate) fn end_of_program(&mut self) {
        self.feed = 0.0;
        self.coord = CoordSystem::G54;
        self.plane = Plane::XY;
        self.distance = Distance::Absolute;
        self.feed_mode = FeedMode::PerMinute;
        self.speed_override = true;
        self.feed_override = true;
        self.cutter_comp = CutterComp::Off;
        self.spindle = SpindleDir::Off;
        self.motion = MotionMode::Linear;
        self.mist = false;
        self.flood = false;
    }
}

/// A canned cycle line (G73, G74, G81–G89) as [`Modes::cycle_end`] reads
/// it, in the length unit of the machine model that asks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct CycleLine {
    /// The line's words on the plane's two axes ([`Plane::cycle_axes`]),
    /// X as a radius: where they send the axes in G90, the step of each
    /// repeat in G91 (`None`: no word).
    pub(crate) at: [Option<f64>; 2],
    /// The R plane, the line's R or the last cycle's, as written: from
    /// the series' level in G91.
    pub(crate) r: Option<f64>,
    /// The L word, 1 without one (the checks refuse 0).
    pub(crate) repeats: u32,
}

impl Modes {
    /// Where a canned cycle leaves the tool, the rule both machine models
    /// follow, from its start on the plane's axes and the depth axis
    /// ([`Plane::cycle_axes`]): the plane's axes end at the last repeat's
    /// position (the words in G90, the start plus every repeat's step in
    /// G91), the depth axis at the clear plane: R under G99, the higher of
    /// the series' level and R under G98 (R counted from the level in
    /// G91), as rs274 leaves it. Unknown where what it needs is.
    ///
    /// The level (`level`, kept by the model) is where the series of
    /// cycles started on the depth axis: rs274 keeps the first cycle's
    /// start until a line runs in another motion mode, G80 included, that
    /// is while the motion mode stays a cycle (`series`: it was one before
    /// the line), wherever the tool went since; it keeps its number when
    /// the units change.
    pub(crate) fn cycle_end(
        &self,
        start: [Option<f64>; 3],
        level: &mut Option<f64>,
        series: bool,
        line: CycleLine,
    ) -> [Option<f64>; 3] {
        if !series {
            *level = start[2];
        }
        let level = *level;
        let r = match self.distance {
            Distance::Absolute => line.r,
            Distance::Incremental => level.zip(line.r).map(|(z, r)| z + r),
        };
        let mut at = [start[0], start[1]];
        for _ in 0..line.repeats {
            for (k, w) in line.at.iter().enumerate() {
                at[k] = match self.distance {
                    Distance::Absolute => w.or(at[k]),
                    Distance::Incremental => at[k].map(|x| x + w.unwrap_or(0.0)),
                };
            }
        }
        let clear = match self.retract {
            Retract::R => r,
            Retract::Initial => level.zip(r).map(|(z, r)| z.max(r)),
        };
        [at[0], at[1], clear]
    }
}

impl Modes {
    /// How far the standalone reference backs a probe move off its
    /// target, in program units: 0.254 mm (0.01 inch).
    pub(crate) fn probe_backoff(&self) -> f64 {
        match self.units {
            Units::Mm => 0.254,
            Units::Inch => 0.01,
        }
    }
}

/// Where a probe move (G38.2–G38.5) from `start` to `target` leaves the
/// tool in the standalone reference, whose probe never trips: the rule
/// both machine models follow under `--zero-start`, each in its own unit.
/// At the target, backed off `backoff` ([`Modes::probe_backoff`]) toward
/// the start along the move's direction in X, Y and Z (an axis whose
/// start is unknown counts as not moving); the other axes at the target.
/// Unknown where the target is.
pub(crate) fn probe_end(
    start: [Option<f64>; 9],
    target: [Option<f64>; 9],
    backoff: f64,
) -> [Option<f64>; 9] {
    let dist: f64 = (0..3)
        .map(|a| match (start[a], target[a]) {
            (Some(s), Some(t)) => (t - s) * (t - s),
            _ => 0.0,
        })
        .sum::<f64>()
        .sqrt();
    std::array::from_fn(|a| {
        let t = target[a]?;
        let back = match start[a] {
            Some(s) if a < 3 && dist > 0.0 => (t - s) / dist * backoff,
            _ => 0.0,
        };
        Some(t - back)
    })
}

/// Where polar words (`@` radius, `^` angle in degrees, G17) send X
/// and Y from `current` (X, Y), rs274's rule, about the origin of the
/// work coordinates: in G90 the end is `@`·(cos `^`, sin `^`), a
/// missing `@` the current distance from the origin, a missing `^` the
/// current angle; in G91 `@` is added to the current distance (angle
/// kept), then `^` to the angle (distance kept). `None` where no angle
/// is defined (at the origin: an `@` alone in G90, a G91 step), which
/// rs274 refuses. The evaluator, the machine model and the targets'
/// lowering ask it.
pub(crate) fn polar_end(
    distance: Distance,
    current: [f64; 2],
    radius: Option<f64>,
    angle: Option<f64>,
) -> Option<[f64; 2]> {
    let [x, y] = current;
    match distance {
        Distance::Absolute => {
            if angle.is_none() && x == 0.0 && y == 0.0 {
                return None;
            }
            let radius = radius.unwrap_or_else(|| y.hypot(x));
            let theta = angle.map(f64::to_radians).unwrap_or_else(|| y.atan2(x));
            Some([radius * theta.cos(), radius * theta.sin()])
        }
        Distance::Incremental => {
            let (mut x, mut y) = (x, y);
            if let Some(step) = radius {
                if x == 0.0 && y == 0.0 {
                    return None;
                }
                let theta = y.atan2(x);
                let radius = y.hypot(x) + step;
                x = radius * theta.cos();
                y = radius * theta.sin();
            }
            if let Some(step) = angle {
                if x == 0.0 && y == 0.0 {
                    return None;
                }
                let theta = y.atan2(x) + step.to_radians();
                let radius = y.hypot(x);
                x = radius * theta.cos();
                y = radius * theta.sin();
            }
            Some([x, y])
        }
    }
}

impl Plane {
    /// The axes of a canned cycle in this plane: the plane's two (X and Y
    /// in G17, Z and X in G18, Y and Z in G19) and the depth axis. The
    /// UVW planes, whose cycles the checks refuse, read as G17.
    pub(crate) fn cycle_axes(self) -> [usize; 3] {
        self.xyz_axes().unwrap_or([0, 1, 2])
    }
}

impl ToolLength {
    /// The tool length offset per axis (X … W) this code puts in effect,
    /// the rule both machine models follow, each in its own unit: G43 the
    /// offsets of its tool (`tool`: H's, or the one in the spindle), on
    /// every axis the tool data gives (Z, and X on lathes; the others are
    /// 0 unless the table gives them); G43.2 the offset in effect (`old`)
    /// plus them; G43.1 the line's axis words (`words`), an axis without
    /// one keeping its offset (as rs274 does); G49 none. Unknown where
    /// what it needs is.
    #[inline]
    pub(crate) fn offset(
        self,
        old: [Option<f64>; 9],
        tool: Option<[f64; 9]>,
        words: [Option<f64>; 9],
    ) -> [Option<f64>; 9] {
        std::array::from_fn(|a| match self {
            ToolLength::Apply => Some(tool?[a]),
            ToolLength::Add => Some(old[a]? + tool?[a]),
            // The axes G43.1 names; the others keep their offsets.
            ToolLength::Dynamic => words[a].or(old[a]),
            ToolLength::Cancel => Some(0.0),
        })
    }
}

impl CoordSystem {
    /// The system a value of `#5220` (the active system, as a parameter
    /// file keeps it) starts a run in: its whole part (taken toward zero)
    /// when 1 to 9, else G54, as the reference reads it. Both machine
    /// models start from it.
    pub(crate) fn from_parameter(v: f64) -> CoordSystem {
        let n = v.trunc();
        if (1.0..=9.0).contains(&n) {
            CoordSystem(n as u8)
        } else {
            CoordSystem::G54
        }
    }
}

impl NonModal {
    /// The line's axis words are the code's (G10, G28, G30, G52, G53,
    /// G92), not a move in the motion mode. G4, G28.1, G30.1 and G92.1 to
    /// G92.3 leave them to the motion mode, as in the reference: the line
    /// moves, after the code acts.
    pub(crate) fn takes_axis_words(self) -> bool {
        use NonModal::*;
        match self {
            SetData | Home | Home2 | LocalOffset | MachineCoords | SetG92 => true,
            Dwell | SetHome | SetHome2 | ResetG92 | SuspendG92 | RestoreG92 => false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every G code either sets its group's field of the modes and
    /// nothing else, or is handed back untouched (groups 0, 1, 6, 8, 12).
    #[test]
    fn set_mode_sets_the_field_or_hands_the_code_back() {
        let mut handed = 0;
        for t in 0..=1000u16 {
            let Some(g) = GCode::from_code10(t) else {
                continue;
            };
            let mut m = Modes::default();
            match m.set_mode(g) {
                Some(c) => {
                    handed += 1;
                    assert!([0, 1, 6, 8, 12].contains(&g.group()), "{g:?}");
                    let back = match c {
                        MachineCode::Motion(x) => GCode::Motion(x),
                        MachineCode::Units(x) => GCode::Units(x),
                        MachineCode::ToolLength(x) => GCode::ToolLength(x),
                        MachineCode::Coord(x) => GCode::Coord(x),
                        MachineCode::NonModal(x) => GCode::NonModal(x),
                    };
                    assert_eq!(back, g);
                    assert_eq!(m, Modes::default(), "{g:?}");
                }
                None => {
                    let read = match g {
                        GCode::Plane(_) => GCode::Plane(m.plane),
                        GCode::Distance(_) => GCode::Distance(m.distance),
                        GCode::ArcDistance(_) => GCode::ArcDistance(m.arc_distance),
                        GCode::FeedMode(_) => GCode::FeedMode(m.feed_mode),
                        GCode::CutterComp(_) => GCode::CutterComp(m.cutter_comp),
                        GCode::Path(_) => GCode::Path(m.path),
                        GCode::Retract(_) => GCode::Retract(m.retract),
                        GCode::SpindleMode(_) => GCode::SpindleMode(m.spindle_mode),
                        GCode::Lathe(_) => GCode::Lathe(m.lathe),
                        _ => panic!("{g:?} is not set alone"),
                    };
                    assert_eq!(read, g);
                    // Only that field changed: setting it back restores
                    // the power-on state.
                    let mut again = Modes::default();
                    assert_eq!(again.set_mode(g), None);
                    assert_eq!(again, m);
                    let d = Modes::default();
                    let mut back = m.clone();
                    let _ = back.set_mode(match g {
                        GCode::Plane(_) => GCode::Plane(d.plane),
                        GCode::Distance(_) => GCode::Distance(d.distance),
                        GCode::ArcDistance(_) => GCode::ArcDistance(d.arc_distance),
                        GCode::FeedMode(_) => GCode::FeedMode(d.feed_mode),
                        GCode::CutterComp(_) => GCode::CutterComp(d.cutter_comp),
                        GCode::Path(_) => GCode::Path(d.path),
                        GCode::Retract(_) => GCode::Retract(d.retract),
                        GCode::SpindleMode(_) => GCode::SpindleMode(d.spindle_mode),
                        _ => GCode::Lathe(d.lathe),
                    });
                    assert_eq!(back, d, "{g:?}");
                }
            }
        }
        // 34 motion, 2 units, 4 tool length, 9 systems, 12 non-modal.
        assert_eq!(handed, 61);
    }

    #[test]
    fn tool_length_offsets() {
        let mut old = [Some(1.0); 9];
        old[4] = None;
        let mut tool = [0.0; 9];
        (tool[0], tool[2]) = (0.5, 2.0);
        let mut words = [None; 9];
        words[2] = Some(3.0);
        let apply = ToolLength::Apply.offset(old, Some(tool), words);
        assert_eq!(
            apply,
            tool.map(Some),
            "G43: the tool's, whatever was in effect"
        );
        let add = ToolLength::Add.offset(old, Some(tool), words);
        assert_eq!(
            (add[0], add[2], add[3], add[4]),
            (Some(1.5), Some(3.0), Some(1.0), None)
        );
        for code in [ToolLength::Apply, ToolLength::Add] {
            assert_eq!(
                code.offset(old, None, words),
                [None; 9],
                "{code:?}, no data"
            );
        }
        // G43.1: the axes named; the others keep what was in effect (as
        // rs274 does), unknown where that was.
        let dynamic = ToolLength::Dynamic.offset([None; 9], None, words);
        assert_eq!((dynamic[2], dynamic[0]), (Some(3.0), None));
        let dynamic = ToolLength::Dynamic.offset(old, None, words);
        assert_eq!((dynamic[2], dynamic[0]), (Some(3.0), old[0]));
        assert_eq!(
            ToolLength::Cancel.offset([None; 9], Some(tool), words),
            [Some(0.0); 9]
        );
    }

    /// The switches M codes set; and X words in G7 (not a switch, the
    /// other per-word rule of the modes).
    #[test]
    fn switches_of_m_codes() {
        let mut m = Modes::default();
        assert_eq!((m.radius_word(0, 3.0), m.radius_word(1, 3.0)), (3.0, 3.0));
        m.lathe = LatheMode::Diameter;
        assert_eq!((m.radius_word(0, 3.0), m.radius_word(2, 3.0)), (1.5, 3.0));
        let mut m = Modes::default();
        let on = |v: f64, m: &mut Modes, p| m.set_switch(MCode::decode(v), p);
        assert_eq!(on(4.0, &mut m, None), Some(Switched::Spindle));
        assert_eq!(m.spindle, SpindleDir::Ccw);
        assert_eq!(on(7.0, &mut m, None), Some(Switched::Coolant));
        assert_eq!(on(8.0, &mut m, None), Some(Switched::Coolant));
        assert!(m.mist && m.flood);
        assert_eq!(on(51.0, &mut m, Some(0.0)), Some(Switched::Overrides));
        assert!(!m.speed_override);
        let before = m.clone();
        for other in [0.0, 2.0, 6.0, 19.0, 61.0, 62.0, 70.0, 100.0, 6.5] {
            assert_eq!(on(other, &mut m, Some(0.0)), None, "M{other}");
        }
        assert_eq!(m, before);
        assert_eq!(on(9.0, &mut m, None), Some(Switched::Coolant));
        assert_eq!(on(5.0, &mut m, None), Some(Switched::Spindle));
        assert!(!m.mist && !m.flood && m.spindle == SpindleDir::Off);
    }

    #[test]
    fn override_switches_and_program_end() {
        let mut m = Modes::default();
        m.set_override(49, None);
        assert!(!m.speed_override && !m.feed_override);
        m.set_override(50, None);
        assert!(m.feed_override && !m.speed_override);
        m.set_override(53, Some(0.0));
        m.set_override(52, Some(2.0));
        assert!(!m.feed_hold && m.adaptive_feed);
        m.set_override(51, Some(0.0));
        m.set_override(48, Some(0.0));
        assert!(m.speed_override && m.feed_override);
        m.set_override(49, None);
        (m.plane, m.distance, m.motion) = (Plane::YZ, Distance::Incremental, MotionMode::Rapid);
        (m.cutter_comp, m.spindle, m.mist) = (CutterComp::Left, SpindleDir::Cw, true);
        (m.coord, m.feed, m.units) = (CoordSystem(3), 5.0, Units::Inch);
        m.path = PathMode::Exact;
        m.end_of_program();
        let mut want = Modes {
            motion: MotionMode::Linear,
            ..Modes::default()
        };
        (want.path, want.units) = (PathMode::Exact, Units::Inch);
        // M2 leaves adaptive feed and feed hold as they were.
        (want.adaptive_feed, want.feed_hold) = (true, false);
        assert_eq!(m, want);
    }

    /// The cycle end: known where rs274's rule needs nothing unknown;
    /// the level is taken when a series starts and kept while it runs.
    #[test]
    fn cycle_end_and_its_level() {
        let mut m = Modes::default();
        let line = CycleLine {
            at: [Some(1.0), None],
            r: Some(2.0),
            repeats: 2,
        };
        let mut level = Some(9.0);
        let unknown = [None, None, None];
        // G90 G99: the hole and R, whatever the start.
        assert_eq!(
            m.cycle_end(unknown, &mut level, false, line),
            [Some(1.0), None, Some(2.0)]
        );
        assert_eq!(level, None, "a new series takes the start");
        m.retract = Retract::Initial;
        assert_eq!(m.cycle_end(unknown, &mut level, true, line)[2], None);
        let start = [Some(0.0), Some(5.0), Some(1.0)];
        assert_eq!(
            m.cycle_end(start, &mut level, false, line),
            [Some(1.0), Some(5.0), Some(2.0)]
        );
        level = Some(7.0);
        assert_eq!(m.cycle_end(start, &mut level, true, line)[2], Some(7.0));
        // G91: L steps, R from the level.
        m.distance = Distance::Incremental;
        assert_eq!(
            m.cycle_end(start, &mut level, true, line),
            [Some(2.0), Some(5.0), Some(9.0)]
        );
        m.retract = Retract::R;
        assert_eq!(
            m.cycle_end(start, &mut level, false, line),
            [Some(2.0), Some(5.0), Some(3.0)]
        );
        assert_eq!(level, Some(1.0));
    }

    /// The standalone probe end: backed off along the XYZ move only.
    #[test]
    fn probe_end_backs_off_along_the_move() {
        let mut start = [Some(0.0); 9];
        let mut target = start;
        (target[0], target[1], target[3]) = (Some(3.0), Some(4.0), Some(90.0));
        let end = probe_end(start, target, 0.5);
        assert_eq!((end[0], end[1], end[2]), (Some(2.7), Some(3.6), Some(0.0)));
        assert_eq!(end[3], Some(90.0), "a rotary axis is not backed off");
        start[1] = None;
        target[8] = None;
        let end = probe_end(start, target, 0.5);
        assert_eq!((end[0], end[1], end[8]), (Some(2.5), Some(4.0), None));
        assert_eq!(probe_end(start, start, 0.5)[0], Some(0.0));
        let inch = Modes {
            units: Units::Inch,
            ..Modes::default()
        };
        assert_eq!(
            (Modes::default().probe_backoff(), inch.probe_backoff()),
            (0.254, 0.01)
        );
    }

    #[test]
    fn coordinate_system_from_the_parameter() {
        for (v, want) in [(2.0, 2), (2.6, 2), (9.9, 9), (0.0, 1), (0.5, 1), (10.0, 1)] {
            assert_eq!(CoordSystem::from_parameter(v), CoordSystem(want), "{v}");
        }
        assert_eq!(CoordSystem::from_parameter(f64::NAN), CoordSystem::G54);
        assert_eq!(CoordSystem::from_parameter(-1.0), CoordSystem::G54);
    }
}
