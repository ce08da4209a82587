//! The machine a flat program drives: modal state as enums, the position
//! per axis (known or not), the offsets (G5x table, G92/G52, tool length),
//! the tools, and the [`Motion`] each block makes. It starts from the same
//! [`Settings`] as the evaluator and is driven by the decoded flat lines
//! alone: the flat program and those settings determine the motion.
//!
//! Lengths are kept in millimetres whatever the program's units; offsets
//! and tool data given in machine units (inches without an INI, as in the
//! standalone interpreter) are converted when read.

// Axis-indexed loops over several per-axis arrays read best by index.
#![allow(clippy::needless_range_loop)]

use crate::fx_hasher::FxMap;
use crate::rules::offsets;
use crate::rules::tools::{ToolData, Tools};
use crate::settings::Settings;

use super::motion::{Feed, Motion, MoveKind, Point};
use crate::block::{
    AXIS_LETTERS, ArcDistance, Block, CoordSystem, Distance, FeedMode, MCode, MotionMode, NonModal,
    Plane, SpindleDir, ToolLength, Units,
};
use crate::rules::{CycleLine, MachineCode, Modes, Switched, polar_end, probe_end};

const MM_PER_INCH: f64 = 25.4;

/// Per-axis values that may be unknown.
pub(crate) type MaybeAxes = [Option<f64>; 9];

const UNKNOWN: MaybeAxes = [None; 9];
const ZERO: MaybeAxes = [Some(0.0); 9];

/// The machine state a flat program runs on.
#[derive(Debug, Clone)]
pub(crate) struct FlatMachine {
    pub modes: Modes,
    /// Tool-tip position in the active work coordinates, mm.
    pub pos: MaybeAxes,
    /// G54–G59.3 offsets, mm.
    pub g5x: [MaybeAxes; 9],
    /// G92/G52 offsets, mm, and whether they are applied.
    pub g92: MaybeAxes,
    pub g92_applied: Option<bool>,
    /// Applied tool length offset, mm.
    pub tlo: MaybeAxes,
    /// G28 and G30 home positions, machine coordinates, mm.
    pub home28: MaybeAxes,
    pub home30: MaybeAxes,
    /// The tool table (machine units), the tool in the spindle and the
    /// selected one, kept as the evaluator keeps them
    /// ([`FlatMachine::current_tool`] reads the tool as a whole number).
    pub tools: Tools,
    /// Machine units are millimetres.
    pub machine_metric: bool,
    pub zero_start: bool,
    /// An XY rotation is in effect (G10 L2 R): positions are not modelled.
    pub rotated: bool,
    /// The R plane of the last canned cycle (program units as written).
    pub cycle_r: Option<f64>,
    /// The level the last series of canned cycles started from, mm
    /// ([`Modes::cycle_end`]).
    pub cycle_level: Option<f64>,
    /// The program ended (M2/M30).
    pub ended: bool,
    events: Vec<Motion>,
    /// Motion events are recorded (a reader that only follows the state
    /// turns this off: no event is put together).
    record: bool,
}

fn numbered(settings: &Settings) -> FxMap<usize, f64> {
    let mut m = FxMap::default();
    for d in &settings.defines {
        if let crate::settings::Define::Numbered(i, v) = d {
            m.insert(*i, *v);
        }
    }
    m
}

impl FlatMachine {
    /// The machine at the start of a program run with `settings`.
    pub(crate) fn new(settings: &Settings) -> FlatMachine {
        let zs = settings.zero_start;
        let base = if zs { ZERO } else { UNKNOWN };
        let mu = if settings.machine_metric {
            1.0
        } else {
            MM_PER_INCH
        };
        let p = numbered(settings);
        let from = |first: usize, base: MaybeAxes| -> MaybeAxes {
            std::array::from_fn(|a| p.get(&(first + a)).map(|v| v * mu).or(base[a]))
        };
        let g5x = std::array::from_fn(|k| from(5221 + 20 * k, base));
        let mut pos = base;
        for &(a, v) in &settings.start_position {
            if let Some(slot) = pos.get_mut(a) {
                // The start position is given in the program's start units
                // (millimetres).
                *slot = Some(v);
            }
        }
        let coord = p
            .get(&5220)
            .map_or(CoordSystem::G54, |&v| CoordSystem::from_parameter(v));
        let g92_applied = match p.get(&5210) {
            Some(v) => Some(*v != 0.0),
            None => zs.then_some(false),
        };
        FlatMachine {
            modes: Modes {
                coord,
                ..Modes::default()
            },
            pos,
            g5x,
            g92: from(5211, base),
            g92_applied,
            tlo: ZERO,
            home28: from(5161, base),
            home30: from(5181, base),
            tools: Tools::new(settings),
            machine_metric: settings.machine_metric,
            zero_start: zs,
            rotated: false,
            cycle_r: None,
            cycle_level: None,
            ended: false,
            events: Vec::new(),
            record: true,
        }
    }

    /// A copy of the state without the tool table and the pending events
    /// (cheap: no allocation), for comparing before and after a block.
    pub(crate) fn snapshot(&self) -> FlatMachine {
        FlatMachine {
            modes: self.modes.clone(),
            pos: self.pos,
            g5x: self.g5x,
            g92: self.g92,
            g92_applied: self.g92_applied,
            tlo: self.tlo,
            home28: self.home28,
            home30: self.home30,
            tools: Tools {
                table: FxMap::default(),
                ..self.tools
            },
            machine_metric: self.machine_metric,
            zero_start: self.zero_start,
            rotated: self.rotated,
            cycle_r: self.cycle_r,
            cycle_level: self.cycle_level,
            ended: self.ended,
            events: Vec::new(),
            record: self.record,
        }
    }

    /// Millimetres per program unit.
    pub(crate) fn scale(&self) -> f64 {
        match self.modes.units {
            Units::Mm => 1.0,
            Units::Inch => MM_PER_INCH,
        }
    }

    /// Millimetres per machine unit (offsets and tool data).
    pub(crate) fn machine_scale(&self) -> f64 {
        if self.machine_metric {
            1.0
        } else {
            MM_PER_INCH
        }
    }

    /// The offset from work to machine coordinates (G5x, G92/G52 if applied,
    /// tool length), per axis.
    pub(crate) fn offset(&self) -> MaybeAxes {
        let cs = &self.g5x[self.modes.coord.index()];
        std::array::from_fn(|a| {
            let g92 = match self.g92_applied {
                Some(true) => self.g92[a]?,
                Some(false) => 0.0,
                None => return None,
            };
            Some(cs[a]? + g92 + self.tlo[a]?)
        })
    }

    /// The G92/G52 offset in effect on axis `a`: 0 while suspended.
    fn g92_in_effect(&self, a: usize) -> Option<f64> {
        match self.g92_applied {
            Some(true) => self.g92[a],
            Some(false) => Some(0.0),
            None => None,
        }
    }

    /// The tool tip's machine position on axis `a`
    /// ([`offsets::machine_tip`]).
    fn tip_machine(&self, a: usize) -> Option<f64> {
        let cs = self.g5x[self.modes.coord.index()][a]?;
        Some(offsets::machine_tip(
            self.pos[a]?,
            cs,
            self.g92_in_effect(a)?,
        ))
    }

    /// The position in machine coordinates (controlled point), per axis.
    pub(crate) fn machine_pos(&self) -> MaybeAxes {
        let off = self.offset();
        std::array::from_fn(|a| Some(self.pos[a]? + off[a]?))
    }

    /// The tool in the spindle, if known, as a whole number.
    pub(crate) fn current_tool(&self) -> Option<i64> {
        self.tools.current.map(|t| t.round() as i64)
    }

    /// The tool the last T word selected, as a whole number.
    pub(crate) fn selected_tool(&self) -> Option<i64> {
        self.tools.selected.map(|t| t.round() as i64)
    }

    /// Tool data of tool `t` in mm, if known.
    pub(crate) fn tool(&self, t: i64) -> Option<ToolData> {
        let s = self.machine_scale();
        let d = match self.tools.data(t) {
            Some(d) => d,
            // No tool: a machine has no offsets for it (the evaluator,
            // after rs274, leaves it unknown once an M6 loaded a tool).
            None if t == 0 => ToolData::default(),
            None => return None,
        };
        Some(ToolData {
            offsets: d.offsets.map(|v| v * s),
            diameter: d.diameter * s,
            ..d
        })
    }

    /// Stops recording motion events ([`FlatMachine::take_events`] then gives
    /// none); the state is followed as before.
    pub(crate) fn without_events(mut self) -> FlatMachine {
        self.record = false;
        self
    }

    fn push(&mut self, ev: Motion) {
        if self.record {
            self.events.push(ev);
        }
    }

    /// Takes the motion events made since the last call.
    pub(crate) fn take_events(&mut self) -> std::vec::Drain<'_, Motion> {
        self.events.drain(..)
    }

    fn point(&self, work: MaybeAxes) -> Point {
        let off = self.offset();
        let known = off.iter().all(Option::is_some);
        Point {
            work: work.map(|v| v.unwrap_or(f64::NAN)),
            offset: known.then(|| off.map(|v| v.unwrap_or(0.0))),
        }
    }

    fn feed(&self) -> Feed {
        let mode = self.modes.feed_mode;
        let rate = match mode {
            FeedMode::PerMinute | FeedMode::PerRev => self.modes.feed * self.scale(),
            FeedMode::InverseTime => self.modes.feed,
        };
        Feed { rate, mode }
    }

    /// Moves to `to` (work coordinates, mm), emitting a line.
    fn line_to(&mut self, kind: MoveKind, to: MaybeAxes) {
        if !self.record {
            self.pos = to;
            return;
        }
        let from = self.point(self.pos);
        let to_p = self.point(to);
        self.push(Motion::Line {
            kind,
            from,
            to: to_p,
            feed: self.feed(),
        });
        self.pos = to;
    }

    /// Applies one decoded block in LinuxCNC's order of execution.
    pub(crate) fn apply(&mut self, b: &Block) {
        // A G2 or G3 without axis words (a full circle) goes the general
        // way.
        if !self.record
            && b.is_plain_move()
            && self.plain_motion(b.motion())
            && (b.has_axis() || b.motion().is_none())
        {
            self.apply_plain_move(b);
            return;
        }
        self.apply_any(b);
    }

    /// Whether the motion of a block whose motion code is `m` is G0–G3.
    fn plain_motion(&self, m: Option<MotionMode>) -> bool {
        matches!(
            m.unwrap_or(self.modes.motion),
            MotionMode::Rapid | MotionMode::Linear | MotionMode::ArcCw | MotionMode::ArcCcw
        )
    }

    /// [`FlatMachine::apply`] for a block of G0–G3 (written or modal), axis
    /// words, F, S and arc words alone, without motion events: only the
    /// steps of [`FlatMachine::apply_any`] such a block reaches (a test runs
    /// both on random blocks).
    fn apply_plain_move(&mut self, b: &Block) {
        let axes = AXIS_LETTERS.map(|l| b.value(l));
        self.apply_plain_values(b.motion(), b.value(b'F'), b.value(b'S'), &axes);
    }

    /// [`FlatMachine::apply`] for a block of G0–G3 (or none, in G0–G3) with X,
    /// Y, Z, F and arc centre words alone, given as values (the centre
    /// changes nothing the model keeps when it records no motion): false
    /// (nothing done) when the model records motion or the motion is
    /// another.
    pub(crate) fn apply_plain_motion(
        &mut self,
        motion: Option<MotionMode>,
        f: Option<f64>,
        xyz: [Option<f64>; 3],
    ) -> bool {
        if self.record || !self.plain_motion(motion) {
            return false;
        }
        self.apply_plain_values(motion, f, None, &xyz);
        true
    }

    /// The steps of [`FlatMachine::apply_plain_move`], from the block's values.
    #[inline]
    fn apply_plain_values(
        &mut self,
        motion: Option<MotionMode>,
        f: Option<f64>,
        s: Option<f64>,
        axes: &[Option<f64>],
    ) {
        if let Some(f) = f {
            self.modes.feed = f;
        }
        if let Some(s) = s {
            // The spindle event is a motion event: none are recorded.
            self.modes.speed = s;
        }
        if let Some(m) = motion {
            self.modes.motion = m;
        }
        if axes.iter().all(Option::is_none) {
            return;
        }
        if self.rotated {
            self.pos = UNKNOWN;
            return;
        }
        let s = self.scale();
        for (a, v) in axes.iter().enumerate() {
            if let Some(v) = *v {
                self.pos[a] = self.axis_target(a, v, s);
            }
        }
    }

    /// Applies any decoded block in LinuxCNC's order of execution.
    fn apply_any(&mut self, b: &Block) {
        if b.percent || self.ended && b.words.is_empty() {
            return;
        }
        if let Some(f) = b.value(b'F') {
            self.modes.feed = f;
        }
        if let Some(s) = b.value(b'S') {
            self.modes.speed = s;
            if self.modes.spindle != SpindleDir::Off {
                self.spindle_event();
            }
        }
        if let Some(t) = b.value(b'T') {
            self.tools.select(t);
        }
        for (m, _) in b.m_codes() {
            match self.modes.set_switch(m, b.value(b'P')) {
                Some(Switched::Spindle) => self.spindle_event(),
                Some(Switched::Coolant) => self.push(Motion::Coolant {
                    mist: self.modes.mist,
                    flood: self.modes.flood,
                }),
                Some(Switched::Overrides) | None => {}
            }
            match m {
                MCode::ToolChange => {
                    if self.tools.change(&mut self.modes) {
                        self.spindle_event();
                    }
                    if let Some(t) = self.selected_tool() {
                        self.push(Motion::ToolChange { tool: t });
                    }
                }
                MCode::SetTool => {
                    self.tools.set_current(b.value(b'Q'));
                }
                _ => {}
            }
        }
        if b.non_modal() == Some(NonModal::Dwell) {
            let seconds = b.value(b'P').unwrap_or(0.0);
            self.push(Motion::Dwell { seconds });
        }
        // The modes: those that are a field alone, and the units. The
        // codes that act on the position act below, from the block's
        // fields, in the reference's order (tool length, coordinate
        // system, non-modal code, motion).
        for g in b.modal_codes() {
            if let crate::codes::GCode::Path(p) = g {
                // G64's P is in the units in effect after the line's own
                // G20/G21 (LinuxCNC sets the units first; the groups come
                // in that order here).
                let exact = p != crate::codes::PathMode::Blend;
                let tolerance = if exact {
                    0.0
                } else {
                    b.value(b'P').unwrap_or(0.0).abs() * self.scale()
                };
                self.push(Motion::PathMode { exact, tolerance });
            }
            if let Some(MachineCode::Units(u)) = self.modes.set_mode(g) {
                // The cycles' level keeps its number in program units.
                let from = self.scale();
                self.modes.units = u;
                let to = self.scale();
                if let Some(z) = &mut self.cycle_level {
                    *z = *z / from * to;
                }
            }
        }
        if let Some(t) = b.tool_length() {
            self.tool_length(b, t);
        }
        if let Some(c) = b.coord() {
            if c != self.modes.coord {
                self.push(Motion::Offsets);
            }
            let before = self.offset();
            self.modes.coord = c;
            self.shift(before);
        }
        let motion_used = match b.non_modal() {
            Some(n) => {
                if matches!(
                    n,
                    NonModal::SetData
                        | NonModal::SetHome
                        | NonModal::SetHome2
                        | NonModal::LocalOffset
                        | NonModal::SetG92
                        | NonModal::ResetG92
                        | NonModal::SuspendG92
                        | NonModal::RestoreG92
                ) {
                    self.push(Motion::Offsets);
                }
                self.non_modal(b, n);
                n.takes_axis_words()
            }
            None => false,
        } || b.tool_length() == Some(ToolLength::Dynamic) && b.motion().is_none();
        let series = self.modes.motion.is_canned_cycle();
        if let Some(m) = b.motion() {
            self.modes.motion = m;
        }
        let polar = b.value(b'@').is_some() || b.value(b'^').is_some();
        if !motion_used && (b.has_axis() || polar || b.motion().is_some_and(moves_without_axes)) {
            self.motion(b, series);
        }
        for (m, _) in b.m_codes() {
            match m {
                MCode::Pause { optional } => self.push(Motion::Pause { optional }),
                MCode::PalletPause => self.push(Motion::Pause { optional: false }),
                MCode::End { .. } => self.end(),
                _ => {}
            }
        }
    }

    fn spindle_event(&mut self) {
        self.push(Motion::Spindle {
            dir: self.modes.spindle,
            speed: self.modes.speed,
            mode: self.modes.spindle_mode,
        });
    }

    /// Keeps the machine where it is when the offset changes from `before`.
    fn shift(&mut self, before: MaybeAxes) {
        let after = self.offset();
        for a in 0..9 {
            self.pos[a] = match (self.pos[a], before[a], after[a]) {
                (Some(p), Some(b), Some(n)) => Some(p + b - n),
                _ => None,
            };
        }
    }

    /// G43, G43.2 (with H's tool or the current one), G43.1, G49: the
    /// offset by [`ToolLength::offset`], in mm; the machine stays where
    /// it is.
    fn tool_length(&mut self, b: &Block, t: ToolLength) {
        let before = self.offset();
        let tool = match t {
            ToolLength::Apply | ToolLength::Add => b
                .value(b'H')
                .map(|h| h.round() as i64)
                .or(self.current_tool())
                .and_then(|h| self.tool(h))
                .map(|d| d.offsets),
            ToolLength::Dynamic | ToolLength::Cancel => None,
        };
        let words = if t == ToolLength::Dynamic {
            let s = self.scale();
            b.axes().map(|v| v.map(|v| v * s))
        } else {
            UNKNOWN
        };
        self.tlo = t.offset(self.tlo, tool, words);
        self.modes.tool_length = t;
        self.shift(before);
    }

    /// Target of axis words in work coordinates (mm), by the distance mode.
    pub(crate) fn target(&self, b: &Block) -> MaybeAxes {
        let s = self.scale();
        let axes = b.axes();
        let mut t = self.pos;
        for a in 0..9 {
            if let Some(v) = axes[a] {
                t[a] = self.axis_target(a, v, s);
            }
        }
        // Polar words: @ radius, ^ angle (XY plane), by the rule the
        // targets lower them with; unknown at the origin, where rs274
        // refuses them.
        let (radius, angle) = (b.value(b'@'), b.value(b'^'));
        if radius.is_some() || angle.is_some() {
            let end = self.pos[0]
                .zip(self.pos[1])
                .and_then(|(x, y)| polar_end(self.modes.distance, [x / s, y / s], radius, angle));
            t[0] = end.map(|e| e[0] * s);
            t[1] = end.map(|e| e[1] * s);
        }
        t
    }

    /// Where axis `a` goes for its word `v` (program units; `s` mm per
    /// program unit), by the distance and diameter modes.
    #[inline]
    pub(crate) fn axis_target(&self, a: usize, v: f64, s: f64) -> Option<f64> {
        let v = self.modes.radius_word(a, v);
        let rot = if (3..=5).contains(&a) { 1.0 } else { s };
        match self.modes.distance {
            Distance::Absolute => Some(v * rot),
            Distance::Incremental => self.pos[a].map(|p| p + v * rot),
        }
    }

    fn non_modal(&mut self, b: &Block, n: NonModal) {
        let s = self.scale();
        let ms = self.machine_scale();
        let axes = b.axes();
        match n {
            NonModal::Dwell => {}
            NonModal::SetData => {
                self.set_data(b);
            }
            NonModal::Home | NonModal::Home2 => {
                if b.has_axis() {
                    let mid = self.target(b);
                    self.line_to(MoveKind::Rapid, mid);
                }
                let home = if n == NonModal::Home {
                    self.home28
                } else {
                    self.home30
                };
                let off = self.offset();
                let mut to = self.pos;
                for a in 0..9 {
                    if !b.has_axis() || axes[a].is_some() {
                        to[a] = match (home[a], off[a], self.tlo[a]) {
                            // Homes are tool-tip machine positions.
                            (Some(h), Some(o), Some(t)) => Some(h - o + t),
                            _ => None,
                        };
                    }
                }
                self.line_to(MoveKind::Rapid, to);
            }
            NonModal::SetHome | NonModal::SetHome2 => {
                let m = self.machine_pos();
                let tl = self.tlo;
                let h: MaybeAxes = std::array::from_fn(|a| Some(m[a]? - tl[a]?));
                if n == NonModal::SetHome {
                    self.home28 = h;
                } else {
                    self.home30 = h;
                }
            }
            NonModal::MachineCoords => {
                let off = self.offset();
                let mut to = self.pos;
                for a in 0..9 {
                    if let Some(v) = axes[a] {
                        let rot = if offsets::is_linear(a) { s } else { 1.0 };
                        to[a] = off[a].map(|o| v * rot - o);
                    }
                }
                // The line's own G0 or G1 (it becomes the mode after the
                // non-modal code), else the mode in effect.
                let kind = if b.motion().unwrap_or(self.modes.motion) == MotionMode::Rapid {
                    MoveKind::Rapid
                } else {
                    MoveKind::Feed
                };
                if b.has_axis() {
                    self.line_to(kind, to);
                }
            }
            NonModal::SetG92 | NonModal::LocalOffset => {
                let before = self.offset();
                let cs = self.g5x[self.modes.coord.index()];
                for a in 0..9 {
                    if let Some(v) = axes[a] {
                        let rot = if offsets::is_linear(a) { s } else { 1.0 };
                        self.g92[a] = if n == NonModal::LocalOffset {
                            Some(v * rot)
                        } else {
                            // The position becomes v.
                            self.tip_machine(a)
                                .zip(cs[a])
                                .map(|(m, c)| offsets::g92_making(m, c, v * rot))
                        };
                    } else if self.g92_applied != Some(true) {
                        self.g92[a] = Some(0.0);
                    }
                }
                self.g92_applied = Some(true);
                self.shift(before);
                let _ = ms;
            }
            NonModal::ResetG92 | NonModal::SuspendG92 => {
                let before = self.offset();
                if n == NonModal::ResetG92 {
                    self.g92 = ZERO;
                }
                self.g92_applied = Some(false);
                self.shift(before);
            }
            NonModal::RestoreG92 => {
                let before = self.offset();
                self.g92_applied = Some(true);
                self.shift(before);
            }
        }
    }

    fn set_data(&mut self, b: &Block) {
        let l = b.value(b'L').map(|v| v.round() as i64);
        let p = b.value(b'P').map(|v| v.round() as i64);
        let s = self.scale();
        let axes = b.axes();
        let scaled = |a: usize, v: f64| if offsets::is_linear(a) { v * s } else { v };
        match l {
            Some(2) | Some(20) => {
                if b.value(b'R').is_some_and(|r| r != 0.0) {
                    self.rotated = true;
                }
                let k = offsets::g10_system(b.value(b'P'), self.modes.coord).index();
                let before = self.offset();
                let active = k == self.modes.coord.index();
                for a in 0..9 {
                    if let Some(v) = axes[a] {
                        self.g5x[k][a] = if l == Some(2) {
                            Some(scaled(a, v))
                        } else {
                            // The current position becomes v in system k.
                            self.tip_machine(a)
                                .zip(self.g92_in_effect(a))
                                .map(|(m, g)| offsets::g5x_making(m, g, scaled(a, v)))
                        };
                    }
                }
                if active {
                    self.shift(before);
                }
            }
            Some(1) | Some(10) | Some(11) => {
                let Some(t) = p else { return };
                let mut d = self.tools.table.get(&t).copied().unwrap_or_default();
                let ms = self.machine_scale();
                for a in 0..9 {
                    if let Some(v) = axes[a] {
                        let mm = if l == Some(1) {
                            Some(scaled(a, v))
                        } else {
                            // L10/L11: the offset that makes the current
                            // position read v with it: L10 in the current
                            // system and G92 (the offset in effect counted),
                            // L11 in G59.3 without G92 (as rs274 writes
                            // them: after G92 Z1 at Z5 with 7.5 in effect,
                            // L10 Z2 gives 6.5, L11 Z2 then 13.5).
                            let v = scaled(a, v);
                            let cs = self.g5x[self.modes.coord.index()][a];
                            if l == Some(11) {
                                match (self.pos[a], self.tlo[a], cs, self.g92_in_effect(a)) {
                                    (Some(p), Some(tl), Some(c), Some(g)) => self.g5x[8][a]
                                        .map(|c9| offsets::tool_offset_l11(p, tl, c, g, c9, v)),
                                    _ => None,
                                }
                            } else {
                                match (self.pos[a], self.tlo[a]) {
                                    (Some(p), Some(tl)) => Some(offsets::tool_offset_l10(p, tl, v)),
                                    _ => None,
                                }
                            }
                        };
                        match mm {
                            Some(mm) => d.offsets[a] = mm / ms,
                            None => {
                                self.tools.table.remove(&t);
                                return;
                            }
                        }
                    }
                }
                if let Some(r) = b.value(b'R') {
                    d.diameter = 2.0 * r * s / ms;
                }
                self.tools.table.insert(t, d);
            }
            _ => {}
        }
    }

    /// The line's move in the motion mode (`series`: the mode was a canned
    /// cycle before the line).
    fn motion(&mut self, b: &Block, series: bool) {
        if self.rotated {
            self.pos = UNKNOWN;
            return;
        }
        let to = self.target(b);
        match self.modes.motion {
            MotionMode::Rapid => self.line_to(MoveKind::Rapid, to),
            MotionMode::Linear => self.line_to(MoveKind::Feed, to),
            MotionMode::ArcCw | MotionMode::ArcCcw => self.arc(b, to),
            MotionMode::Probe(_) => {
                let from = self.pos;
                self.line_to(MoveKind::Probe, to);
                // Where it trips only the machine knows; the standalone
                // reference backs off the target.
                self.pos = if self.zero_start {
                    probe_end(from, to, self.modes.probe_backoff() * self.scale())
                } else {
                    UNKNOWN
                };
            }
            MotionMode::Thread | MotionMode::RigidTap => {
                let from = self.pos;
                self.line_to(MoveKind::SpindleSync, to);
                if self.modes.motion == MotionMode::RigidTap {
                    self.pos = from;
                    self.pos[2] = from[2];
                }
            }
            MotionMode::Cycle(_) => self.cycle(b, to, series),
            // Splines and threading cycles end at their end point; their
            // path is left to the lowerings.
            _ => self.pos = to,
        }
    }

    /// Where a canned cycle leaves the tool: [`Modes::cycle_end`], in mm.
    /// (Polar words in G90 are read as where they send X and Y.)
    fn cycle(&mut self, b: &Block, to: MaybeAxes, series: bool) {
        let s = self.scale();
        if let Some(r) = b.value(b'R') {
            self.cycle_r = Some(r);
        }
        let axes = self.modes.plane.cycle_axes();
        let words = b.axes();
        let at = [0, 1].map(|k| {
            let a = axes[k];
            match self.modes.distance {
                Distance::Absolute => to[a],
                Distance::Incremental => words[a].map(|d| self.modes.radius_word(a, d) * s),
            }
        });
        let line = CycleLine {
            at,
            r: self.cycle_r.map(|r| r * s),
            repeats: b.value(b'L').map_or(1, |l| l.round().max(1.0) as u32),
        };
        let start = axes.map(|a| self.pos[a]);
        let end = self
            .modes
            .cycle_end(start, &mut self.cycle_level, series, line);
        for (k, a) in axes.into_iter().enumerate() {
            self.pos[a] = end[k];
        }
    }

    fn arc(&mut self, b: &Block, to: MaybeAxes) {
        if !self.record {
            self.pos = to;
            return;
        }
        let s = self.scale();
        // The one place that builds a Motion::Arc: none in the UVW planes.
        let plane = self.modes.plane;
        let (i0, i1, o0, o1) = match plane {
            Plane::XY => (0, 1, b'I', b'J'),
            Plane::XZ => (0, 2, b'I', b'K'),
            Plane::YZ => (1, 2, b'J', b'K'),
            Plane::UV | Plane::WU | Plane::VW => {
                self.pos = to;
                return;
            }
        };
        let ccw = self.modes.motion == MotionMode::ArcCcw;
        let (Some(f0), Some(f1), Some(t0), Some(t1)) = (self.pos[i0], self.pos[i1], to[i0], to[i1])
        else {
            self.pos = to;
            return;
        };
        let center = if let Some(r) = b.value(b'R') {
            // The centre is worked out in ascending axis order; in the XZ
            // plane that is (X, Z), where G2/G3 turn the other way round
            // (LinuxCNC's XZ frame is Z-X).
            radius_center([f0, f1], [t0, t1], r * s, ccw != (plane == Plane::XZ))
        } else {
            let (a, c) = (
                b.value(o0).unwrap_or(0.0) * s,
                b.value(o1).unwrap_or(0.0) * s,
            );
            match self.modes.arc_distance {
                ArcDistance::Incremental => [f0 + a, f1 + c],
                ArcDistance::Absolute => [a, c],
            }
        };
        let turns = b.value(b'P').map_or(1, |p| p.round().max(1.0) as u32);
        let (from, to_p) = (self.point(self.pos), self.point(to));
        self.push(Motion::Arc {
            from,
            to: to_p,
            center,
            plane,
            ccw,
            turns,
            feed: self.feed(),
        });
        self.pos = to;
    }

    fn end(&mut self) {
        let before = self.offset();
        self.modes.end_of_program();
        if self.g92_applied == Some(true) {
            // M2 keeps G92 offsets in LinuxCNC 2.9 (DISABLE_G92_PERSISTENCE
            // aside); nothing to change.
        }
        self.shift(before);
        self.push(Motion::End);
        self.ended = true;
    }
}

/// Motion modes that act on a line without axis words.
/// Motion a line makes without axis words: the end of a NURBS, and a G2 or
/// G3 written on the line (a full circle back to where it starts, as
/// LinuxCNC runs `G2 I5 J5`).
fn moves_without_axes(m: MotionMode) -> bool {
    matches!(
        m,
        MotionMode::NurbsEnd | MotionMode::ArcCw | MotionMode::ArcCcw
    )
}

/// Centre of an R-format arc from `a` to `b` (positive R: the shorter arc).
pub(crate) fn radius_center(a: [f64; 2], b: [f64; 2], r: f64, ccw: bool) -> [f64; 2] {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let d = (dx * dx + dy * dy).sqrt();
    let mid = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
    if d == 0.0 {
        return mid;
    }
    let h = (r * r - d * d / 4.0).max(0.0).sqrt();
    // (nx, ny) is the left of the chord; a clockwise arc with positive R
    // (the shorter way) has its centre on the right.
    let (nx, ny) = (-dy / d, dx / d);
    let side = if (r > 0.0) != ccw { -1.0 } else { 1.0 };
    [mid[0] + side * h * nx, mid[1] + side * h * ny]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(lines: &[&str]) -> (FlatMachine, Vec<Motion>) {
        let s = Settings {
            zero_start: true,
            ..Settings::default()
        };
        let mut m = FlatMachine::new(&s);
        let mut ev = Vec::new();
        for l in lines {
            m.apply(&Block::decode(l.as_bytes()).unwrap());
            ev.extend(m.take_events());
        }
        (m, ev)
    }

    proptest::proptest! {
        /// The short way for plain moves leaves the machine as the whole
        /// of `apply` does, line after line, from random lines of moves,
        /// modes, offsets and their near misses.
        #[test]
        fn plain_moves_apply_as_any_block(
            lines in proptest::collection::vec(
                proptest::collection::vec(
                    proptest::sample::select(vec![
                        "G0", "G1", "G2", "G3", "G7", "G8", "G17", "G18", "G20", "G21",
                        "G90", "G91", "G91.1", "G80", "G81", "G92", "G54", "G55", "G43",
                        "G10 L2 P2", "M3", "M5", "T2", "S100", "F50", "R2",
                    ]),
                    0..3,
                ),
                1..12,
            ),
            values in proptest::collection::vec((0usize..10, -50.0f64..50.0), 12),
            zero in proptest::bool::ANY,
            rotated in proptest::bool::ANY,
        ) {
            let s = Settings {
                zero_start: zero,
                ..Settings::default()
            };
            let mut fast = FlatMachine::new(&s).without_events();
            fast.rotated = rotated;
            let mut slow = fast.clone();
            for (k, codes) in lines.iter().enumerate() {
                let (axis, v) = values[k % values.len()];
                let mut line = codes.join(" ");
                // Zero, one or two axis words, and arc words.
                for l in ["X", "Y", "Z", "A", "I", "J", "R", "X Y", "Z I J", ""][..=axis]
                    .iter()
                    .rev()
                    .take(2)
                {
                    for w in l.split_whitespace() {
                        line.push_str(&format!(" {w}{v:.3}"));
                    }
                }
                let Ok(b) = Block::decode(line.as_bytes()) else {
                    continue;
                };
                fast.apply(&b);
                slow.apply_any(&b);
                proptest::prop_assert_eq!(format!("{fast:?}"), format!("{slow:?}"), "{}", line);
            }
        }
    }

    /// `G2 I.5 J.5` with no axis word is a full circle (3dtest.ngc draws
    /// three such): an arc back to its start.
    #[test]
    fn an_arc_without_axis_words_is_a_full_circle() {
        let (_, ev) = run(&["G21 G0 X1 Y1", "G17 G2 I.5 J.5 F100"]);
        let Some(Motion::Arc { from, to, .. }) = ev.last() else {
            panic!("an arc: {ev:?}")
        };
        assert_eq!(from.work, to.work);
        // I and J alone, without G2 on the line, move nothing.
        let (_, ev) = run(&["G21 G2 X1 Y1 I.5 J.5 F100", "I.5 J.5"]);
        assert_eq!(
            ev.iter()
                .filter(|e| matches!(e, Motion::Arc { .. }))
                .count(),
            1
        );
    }

    #[test]
    fn units_offsets_and_moves() {
        let (m, ev) = run(&["G20 G0 X1", "G10 L2 P1 X1", "G92 X0", "G91 G1 X1 F10"]);
        assert_eq!(m.pos[0], Some(25.4));
        assert_eq!(m.machine_pos()[0], Some(50.8));
        // The G10 and the G92 each set offsets: an event each.
        assert_eq!(ev.len(), 4);
        assert!(
            matches!(ev[1..3], [Motion::Offsets, Motion::Offsets]),
            "{ev:?}"
        );
        let Motion::Line { kind, to, feed, .. } = &ev[3] else {
            panic!("a line")
        };
        assert_eq!(*kind, MoveKind::Feed);
        assert_eq!(to.machine().map(|a| a[0]), Some(50.8));
        assert_eq!(feed.rate, 254.0);
    }

    #[test]
    fn arcs_and_cycles() {
        let (m, ev) = run(&[
            "G0 X10 Y0 Z5",
            "G3 X-10 Y0 R10 F100",
            "G99 G81 X5 Y5 Z-1 R2",
        ]);
        let Motion::Arc { center, ccw, .. } = &ev[1] else {
            panic!("an arc")
        };
        assert!(*ccw);
        assert!(center[0].abs() < 1e-9 && center[1].abs() < 1e-9);
        assert_eq!(
            (m.pos[0], m.pos[1], m.pos[2]),
            (Some(5.0), Some(5.0), Some(2.0))
        );
    }

    /// A canned cycle ends on its plane's axes at the target and on the
    /// third at the clear plane, in each plane (the positions rs274 reads
    /// after these lines from X0 Y5 Z0).
    #[test]
    fn cycles_end_on_their_plane() {
        for (line, want) in [
            ("G17 G99 G81 X1 Y2 Z-1 R2 F100", [1.0, 2.0, 2.0]),
            ("G18 G99 G81 X1 Z3 Y-1 R2 F100", [1.0, 2.0, 3.0]),
            ("G18 G98 G81 X1 Z3 Y-1 R2 F100", [1.0, 5.0, 3.0]),
            ("G19 G99 G81 Y1 Z3 X-1 R2 F100", [2.0, 1.0, 3.0]),
            ("G19 G98 G83 Y1 Z3 X-1 R7 Q1 F100", [7.0, 1.0, 3.0]),
            ("G18 G91 G99 G81 X1 Z1 Y-1 R-2 L2 F100", [2.0, 3.0, 2.0]),
        ] {
            let (m, _) = run(&["G0 X0 Y5 Z0", line]);
            assert_eq!(m.pos[..3], want.map(Some), "{line}");
        }
    }

    /// A series of cycles keeps the level its first cycle started from
    /// until a line moves in another mode (G80 included); in G7 an X step
    /// is a diameter; the level keeps its number in new units (the
    /// positions rs274 reads after these lines, here in mm).
    #[test]
    fn cycle_series_keep_their_level() {
        let start = "G0 X0 Y0 Z10";
        for (lines, want) in [
            (&["G98 G82 X2 Z-1 R2 P0.5"][..], [2.0, 0.0, 10.0]),
            (
                &["G99 G81 X1 Z-1 R2", "G98 G82 X2 Z-1 R2 P0.5"],
                [2.0, 0.0, 10.0],
            ),
            (
                &["G99 G81 X1 Z-1 R2", "G91 G99 G85 X1 Z-1 R-7"],
                [2.0, 0.0, 3.0],
            ),
            (
                &["G99 G81 X1 Z-1 R2", "G80", "G91 G98 G81 X1 Z-1 R1"],
                [2.0, 0.0, 3.0],
            ),
            (
                &["G99 G81 X1 Z-1 R2", "G0 Z1", "G91 G98 G81 X1 Z-1 R1"],
                [2.0, 0.0, 2.0],
            ),
            (
                &["G18 G7 G0 X2 Y2 Z2", "G91 G99 G81 X4 Z2 Y-1 R2"],
                [3.0, 4.0, 4.0],
            ),
            (
                &["Z25.4", "G98 G81 X1 Z-1 R2", "G20", "X0.5"],
                [12.7, 0.0, 645.16],
            ),
        ] {
            let (m, _) = run(&[&[start][..], lines].concat());
            for a in 0..3 {
                let got = m.pos[a].expect("known");
                assert!((got - want[a]).abs() < 1e-9, "{lines:?}: {:?}", m.pos);
            }
        }
    }

    /// M2 resets the modes both machine models reset (the feed rate to 0,
    /// as rs274 sets it) and keeps the path mode (rs274 leaves G61 on).
    #[test]
    fn program_end_keeps_the_path_mode() {
        let (m, _) = run(&["G61 G1 X1 F50", "M2"]);
        assert_eq!(
            (m.modes.path, m.modes.feed),
            (crate::codes::PathMode::Exact, 0.0)
        );
    }

    /// G53 moves in the line's own G0 or G1, else in the motion mode.
    #[test]
    fn machine_coordinate_moves_take_the_line_s_motion() {
        let kind = |lines: &[&str]| {
            let (_, ev) = run(lines);
            match ev.last() {
                Some(Motion::Line { kind, .. }) => *kind,
                e => panic!("a line: {e:?}"),
            }
        };
        assert_eq!(kind(&["G1 X5 F100", "G53 G0 X0"]), MoveKind::Rapid);
        assert_eq!(kind(&["G0 X5", "G53 G1 X0 F100"]), MoveKind::Feed);
        assert_eq!(kind(&["G0 X5", "G53 X0"]), MoveKind::Rapid);
        assert_eq!(kind(&["G1 X5 F100", "G53 X0"]), MoveKind::Feed);
    }

    #[test]
    fn radius_arcs_take_the_shorter_way_round() {
        // G2 from (0,0) to (2,2) with R2 turns about (2,0); G3 about (0,2);
        // a negative R takes the other centre; in G18 the frame is Z-X.
        for (lines, want) in [
            (["G17 G0 X0 Y0 Z0", "G2 X2 Y2 R2 F100"], [2.0, 0.0]),
            (["G17 G0 X0 Y0 Z0", "G3 X2 Y2 R2 F100"], [0.0, 2.0]),
            (["G17 G0 X0 Y0 Z0", "G2 X2 Y2 R-2 F100"], [0.0, 2.0]),
            (["G18 G0 X0 Y0 Z0", "G2 X2 Z2 R2 F100"], [0.0, 2.0]),
            (["G18 G0 X0 Y0 Z0", "G3 X2 Z2 R2 F100"], [2.0, 0.0]),
        ] {
            let (_, ev) = run(&lines);
            let Motion::Arc { center, .. } = &ev[1] else {
                panic!("an arc")
            };
            assert!(
                (center[0] - want[0]).abs() < 1e-9 && (center[1] - want[1]).abs() < 1e-9,
                "{lines:?}: {center:?}"
            );
        }
    }

    #[test]
    fn tool_length_from_the_table() {
        let s = Settings {
            zero_start: true,
            machine_metric: true,
            tool_table: vec![(
                2,
                ToolData {
                    offsets: [0.0, 0.0, 5.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                    ..ToolData::default()
                },
            )],
            ..Settings::default()
        };
        let mut m = FlatMachine::new(&s);
        for l in ["T2 M6", "G43", "G0 Z1"] {
            m.apply(&Block::decode(l.as_bytes()).unwrap());
        }
        assert_eq!(m.machine_pos()[2], Some(6.0));
        assert_eq!(m.current_tool(), Some(2));
    }

    /// The model reads the tools the shared state keeps as written as
    /// whole numbers: T2.6 M6 loads tool 3; M61 without Q leaves the tool
    /// unknown.
    #[test]
    fn tools_read_as_whole_numbers() {
        let (m, ev) = run(&["T2.6 M6", "T4"]);
        assert!(matches!(ev[..], [Motion::ToolChange { tool: 3 }]), "{ev:?}");
        assert_eq!((m.current_tool(), m.selected_tool()), (Some(3), Some(4)));
        let (m, _) = run(&["M61 Q1.6"]);
        assert_eq!(m.current_tool(), Some(2));
        let (m, _) = run(&["M61"]);
        assert_eq!(m.current_tool(), None);
    }
}
