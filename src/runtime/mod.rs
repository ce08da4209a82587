//! Run time: how long the controller takes to run a program, as its own
//! motion planner runs it, in total and for every output line.
//!
//! # Use
//!
//! ```text
//! let mut rt = RunTime::new(TimeModel::for_target(Some("grbl"), &axes));
//! for each output line n (1, 2, …):
//!     rt.line(n);                     // the events that follow are line n's
//!     for each motion event m of the line: rt.motion(&m);
//!     while let Some(t) = rt.next_line() { … t.line, t.start, t.seconds … }
//! rt.finish();                        // end of program: the machine stops
//! while let Some(t) = rt.next_line() { … }
//! rt.totals()                         // total, feed, rapid, dwell, waits, per tool
//! rt.model()                          // what the figure is and how far to trust it
//! ```
//!
//! A line's time is final only once the planner has run every block the
//! line made: up to a look-ahead window (GRBL 1.1: 15 blocks) later. So
//! [`RunTime::next_line`] hands out the lines in order as their times
//! become final; [`LineTime::start`] is when the line starts on the
//! machine (seconds from the program's start), [`LineTime::seconds`] how
//! long it takes. The times of all lines add up to [`Totals::total`].
//!
//! Work per event is O(1) amortised (a replan walks the window once) and
//! memory is flat (the window, and the lines whose blocks are still in it).
//!
//! # Models
//!
//! - **GRBL family** (`grbl`, `grblhal`, `fluidnc`): GRBL 1.1h's planner and
//!   step-segment generator ([`grbl`], [`planner`]), from a saved `$$`
//!   listing or GRBL's defaults. Checked against GRBL 1.1h's own
//!   `planner.c`/`stepper.c` run on the same output: within 0.1% on
//!   LinuxCNC's example programs and dense CAM programs (docs/run-time.md
//!   has the table). grblHAL and FluidNC plan the same way with a larger
//!   window; their figures are GRBL's model with their window and are not
//!   measured.
//! - **LinuxCNC** (`linuxcnc`, and no target): LinuxCNC 2.9's trajectory
//!   planner ([`linuxcnc`]): blend arcs within the G64 P tolerance, exact
//!   stop in G61, arcs within the centripetal limit, the INI's limits (or
//!   LinuxCNC's defaults); not measured against LinuxCNC's own planner.
//! - **Every other target** ([`TimeModel::RestToRest`]): each move from
//!   rest to rest at its feed and the axes' limits: too long for programs
//!   of many short moves (up to 10× on dense CAM programs), said so next
//!   to the figure.

pub(crate) mod grbl;
pub(crate) mod linuxcnc;
pub(crate) mod planner;

use std::collections::{BTreeMap, VecDeque};

use serde::Serialize;

use crate::codes::FeedMode;
use crate::geom::arc::{ArcGeom, FullCircle};
use crate::machine::axes::MachineAxes;
pub(crate) use crate::machine::grbl_listing::GrblSettings;
use crate::machine::motion::{Axes, Motion, MoveKind, Point};
use planner::{Block, Window};

/// Which planner the run time follows.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum TimeModel {
    /// GRBL 1.1h's planner and stepper: the settings, the planner's window
    /// (blocks it holds: GRBL 1.1h keeps one of its 16 slots empty) and the
    /// firmware's name.
    Grbl {
        settings: GrblSettings,
        window: usize,
        firmware: &'static str,
    },
    /// LinuxCNC 2.9's trajectory planner ([`linuxcnc`]).
    LinuxCnc { limits: Box<linuxcnc::Limits> },
    /// Each move timed alone from rest to rest at the axes' limits.
    RestToRest { axes: Box<MachineAxes> },
    /// No estimate (`stats --no-time`).
    Off,
}

/// Blocks GRBL 1.1h's planner holds: `BLOCK_BUFFER_SIZE` 16 (`planner.h`),
/// one slot always empty.
pub(crate) const GRBL_WINDOW: usize = 15;

impl TimeModel {
    /// The model for a target (`None`: LinuxCNC, the flattened program as
    /// it is). The GRBL family uses `axes.grbl` (a `$$` listing) or GRBL's
    /// defaults; with no target, a `$$` listing says the machine runs GRBL.
    pub(crate) fn for_target(target: Option<&str>, axes: &MachineAxes) -> TimeModel {
        let firmware = match target {
            Some("grbl") => "GRBL 1.1h",
            None if axes.grbl.is_some() => "GRBL 1.1h",
            Some("grblhal") => "grblHAL",
            Some("fluidnc") => "FluidNC",
            None | Some("linuxcnc") => {
                return TimeModel::LinuxCnc {
                    limits: Box::new(linuxcnc::Limits::from_axes(axes)),
                };
            }
            _ => {
                return TimeModel::RestToRest {
                    axes: Box::new(axes.clone()),
                };
            }
        };
        TimeModel::Grbl {
            settings: axes.grbl.clone().unwrap_or_default(),
            window: GRBL_WINDOW,
            firmware,
        }
    }
}

/// What a figure means: the model, in words, and whether it is
/// approximate, for printing next to the figure.
#[derive(Debug, Clone, Serialize)]
pub(crate) struct ModelInfo {
    pub(crate) name: String,
    pub(crate) approximate: bool,
    /// How far the figure is known to be off, in a few words, for printing
    /// next to it.
    pub(crate) error: String,
    pub(crate) description: String,
}

/// The planned time of one output line.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct LineTime {
    /// The line number given to [`RunTime::line`].
    pub(crate) line: u64,
    /// When the line starts (s from the program's start).
    pub(crate) start: f64,
    /// How long it takes (s): its moves, dwells and waits.
    pub(crate) seconds: f64,
}

/// Sums over the whole program (s).
#[derive(Debug, Clone, Default, Serialize)]
pub(crate) struct Totals {
    pub(crate) total: f64,
    pub(crate) feed: f64,
    pub(crate) rapid: f64,
    pub(crate) dwell: f64,
    /// Waits after full stops (GRBL's `$1` step idle delay).
    pub(crate) waits: f64,
    /// Full stops: where the planner ran empty (program end, spindle,
    /// coolant, dwell, pause, offset changes).
    pub(crate) stops: u64,
    /// Time with each tool in the spindle (`None`: before any tool change).
    pub(crate) per_tool: BTreeMap<Option<i64>, f64>,
    /// Feed moves that could not be timed (no feed rate, or feed per
    /// revolution with the spindle stopped).
    pub(crate) untimed_feeds: u64,
    /// Rapids that could not be timed (no maximum velocity for an axis, or
    /// a start that is not known).
    pub(crate) untimed_rapids: u64,
}

/// What a block's time is charged to.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct Charge {
    pub(crate) line: u64,
    pub(crate) tool: Option<i64>,
    pub(crate) rapid: bool,
}

/// A line whose time is not final yet.
#[derive(Debug, Clone, Copy)]
struct Open {
    line: u64,
    seconds: f64,
    /// Blocks of the line still in the window.
    blocks: u64,
}

/// The run-time model fed with a program's motion, line by line.
#[derive(Debug, Clone)]
pub(crate) struct RunTime {
    model: TimeModel,
    window: Window,
    /// GRBL's planner position in steps (`None`: not known yet).
    steps: [Option<i64>; 3],
    prev_unit: [f64; 3],
    prev_nominal: f64,
    /// Offset of the last move (work → machine).
    offset: Option<Axes>,
    /// Spindle state the firmware last synchronised to (direction, speed).
    spindle: Option<(crate::codes::SpindleDir, f64)>,
    coolant: (bool, bool),
    /// Spindle speed for feed per revolution (rev/min).
    rpm: f64,
    /// The machine moved since the last full stop.
    moving: bool,
    /// LinuxCNC: the last segment, whose end waits for the next one's
    /// corner.
    pending: Option<linuxcnc::Seg>,
    /// LinuxCNC: the path mode in effect (exact stop, G64 tolerance).
    path: (bool, f64),
    charge: Charge,
    totals: Totals,
    open: VecDeque<Open>,
    /// Time handed out so far (start of the next final line).
    clock: f64,
}

impl RunTime {
    pub(crate) fn new(model: TimeModel) -> RunTime {
        let window = match &model {
            TimeModel::Grbl { window, .. } => Window::new(*window),
            TimeModel::LinuxCnc { limits } => Window::new(limits.depth),
            TimeModel::RestToRest { .. } | TimeModel::Off => Window::new(1),
        };
        RunTime {
            model,
            window,
            steps: [None; 3],
            prev_unit: [0.0; 3],
            prev_nominal: 0.0,
            offset: None,
            spindle: None,
            coolant: (false, false),
            rpm: 0.0,
            moving: false,
            pending: None,
            path: (false, 0.0),
            charge: Charge::default(),
            totals: Totals::default(),
            open: VecDeque::new(),
            clock: 0.0,
        }
    }

    /// The events that follow belong to output line `line` (numbers must
    /// increase).
    pub(crate) fn line(&mut self, line: u64) {
        self.charge.line = line;
        self.open.push_back(Open {
            line,
            seconds: 0.0,
            blocks: 0,
        });
    }

    /// What the figures mean.
    pub(crate) fn model(&self) -> ModelInfo {
        match &self.model {
            TimeModel::Grbl {
                settings,
                window,
                firmware,
            } => ModelInfo {
                name: format!("{firmware} planner"),
                approximate: *firmware != "GRBL 1.1h",
                error: if *firmware == "GRBL 1.1h" {
                    format!(
                        "within 0.1% of GRBL 1.1h's own planner on the 26 programs checked{}",
                        if settings.defaults {
                            "; GRBL's default settings: no --grbl-settings given"
                        } else {
                            ""
                        }
                    )
                } else {
                    format!("not measured on {firmware}; GRBL 1.1h's model")
                },
                description: format!(
                    "{firmware}'s look-ahead planner as GRBL 1.1h runs it ({window} blocks, \
                     junction deviation {} mm, arcs in chords within {} mm, per-axis rates and \
                     accelerations{}), full stops at spindle, coolant, dwell, pause and offset \
                     changes with a {} ms wait each, dwells in 50 ms steps; within 0.1% of \
                     GRBL 1.1h's own planner and stepper code on the programs checked{}",
                    settings.junction_deviation,
                    settings.arc_tolerance,
                    if settings.defaults {
                        " from GRBL's default settings: no --grbl-settings given"
                    } else {
                        " from the --grbl-settings listing"
                    },
                    settings.idle_wait() * 1000.0,
                    if *firmware == "GRBL 1.1h" {
                        ""
                    } else {
                        "; not measured on this firmware, whose window is larger"
                    }
                ),
            },
            TimeModel::LinuxCnc { limits } => ModelInfo {
                name: "LinuxCNC 2.9 trajectory planner".into(),
                approximate: true,
                error: match limits.source {
                    linuxcnc::LimitSource::Defaults => {
                        "a model: against LinuxCNC's simulator 0.1% to 7% short (arcs the most); canned cycles and splines not timed; no --ini: LinuxCNC's \
                         default limits of 1 mm/s and 1 mm/s², far slower than a real machine"
                    }
                    linuxcnc::LimitSource::IniWithDefaults => {
                        "a model: against LinuxCNC's simulator 0.1% to 7% short (arcs the most); canned cycles and splines not timed; LinuxCNC's default \
                         limits for what the INI does not give"
                    }
                    linuxcnc::LimitSource::Ini => {
                        "a model: against LinuxCNC's simulator 0.1% to 7% short (arcs the most); canned cycles and splines not timed"
                    }
                }
                .into(),
                description: format!(
                    "a model of LinuxCNC 2.9's trajectory planner: corners blended by arcs within \
                     the G64 P tolerance (without P: a quarter of the shorter move), a stop at every \
                     corner in G61/G61.1, look-ahead over {} segments, arcs within the centripetal \
                     limit, per-axis velocity and acceleration limits {}; full stops at spindle, \
                     coolant, dwell, tool change, pause and probe. Measured against LinuxCNC \
                     2.9's simulator (docs/run-time.md): within 1.1% on corners in G61 and G64 \
                     and on a dense circle of chords, 6-7% short on programs of arcs; canned cycles (G73, G81-G89) and splines (G5, G5.1, G5.2) \
                     are neither drawn nor timed without --target; parabolic blends, spindle \
                     at-speed waits and feed overrides are not modelled",
                    limits.depth,
                    match limits.source {
                        linuxcnc::LimitSource::Ini => "from the INI",
                        linuxcnc::LimitSource::IniWithDefaults =>
                            "from the INI, and LinuxCNC's defaults (1 machine unit/s, 1 machine \
                             unit/s²) for the X, Y or Z values it does not give",
                        linuxcnc::LimitSource::Defaults =>
                            "at LinuxCNC's defaults for an INI that gives none (1 mm/s, \
                             1 mm/s² on every axis): no --ini given, and a real machine is faster, \
                             so the figure is too long for it",
                    }
                ),
            },
            TimeModel::Off => ModelInfo {
                name: "none".into(),
                approximate: false,
                error: "not estimated (--no-time)".into(),
                description: "the run time was not estimated (--no-time)".into(),
            },
            TimeModel::RestToRest { axes } => ModelInfo {
                name: "rest to rest".into(),
                approximate: true,
                error: if axes.has_dynamics() {
                    "each move from rest to rest: too long, up to 10× on programs of many short \
                     moves"
                } else {
                    "no machine limits given: programmed feeds only, no acceleration, rapids not \
                     timed"
                }
                .into(),
                description: format!(
                    "{REST_TO_REST}{}",
                    if axes.has_dynamics() {
                        ""
                    } else {
                        ". No machine velocity or acceleration limits are given (--ini, \
                         --grbl-settings): feeds are timed at the programmed rate with no \
                         acceleration, rapids not at all"
                    }
                ),
            },
        }
    }

    /// Feeds one motion event of the current line.
    pub(crate) fn motion(&mut self, m: &Motion) {
        if self.model == TimeModel::Off {
            return;
        }
        match m {
            Motion::Line {
                kind,
                from,
                to,
                feed,
            } => {
                if *kind == MoveKind::Probe {
                    self.sync();
                }
                self.offset_change(from);
                let rate = self.feed_rate(*kind, feed.rate, feed.mode);
                let rapid = *kind == MoveKind::Rapid;
                self.straight(&machine(from), &machine(to), rate, rapid);
                if *kind == MoveKind::Probe {
                    self.sync();
                }
            }
            Motion::Arc {
                from,
                to,
                center,
                plane,
                ccw,
                turns,
                feed,
            } => {
                self.offset_change(from);
                // GRBL cuts a sweep within its epsilon of 0 as a full circle.
                let rule = match self.model {
                    TimeModel::Grbl { .. } => FullCircle::Grbl,
                    _ => FullCircle::Exact,
                };
                let g = ArcGeom::new(&from.work, &to.work, *center, *plane, *ccw, *turns, rule);
                let rate = self.feed_rate(MoveKind::Feed, feed.rate, feed.mode);
                self.arc(&g, from, to, rate);
            }
            Motion::Dwell { seconds } => {
                self.sync();
                // GRBL waits in 50 ms steps, rounding up (delay_sec()).
                let t = if matches!(self.model, TimeModel::Grbl { .. }) {
                    (seconds.max(0.0) * 20.0).ceil() * 0.05
                } else {
                    seconds.max(0.0)
                };
                self.totals.dwell += t;
                self.add_wait(t);
            }
            Motion::Spindle { dir, speed, .. } => {
                self.rpm = if *dir == crate::codes::SpindleDir::Off {
                    0.0
                } else {
                    *speed
                };
                let state = Some((*dir, *speed));
                if self.spindle != state {
                    self.sync();
                    self.spindle = state;
                }
            }
            Motion::Coolant { mist, flood } => {
                if self.coolant != (*mist, *flood) {
                    self.sync();
                    self.coolant = (*mist, *flood);
                }
            }
            Motion::ToolChange { tool } => {
                // A tool change is a pause for the GRBL family (M6 → M0).
                self.sync();
                self.charge.tool = Some(*tool);
            }
            Motion::Pause { optional } => {
                // GRBL ignores M1; LinuxCNC waits for the motion first.
                if !optional || matches!(self.model, TimeModel::LinuxCnc { .. }) {
                    self.sync();
                }
            }
            Motion::PathMode { exact, tolerance } => self.path = (*exact, *tolerance),
            // GRBL empties its buffer when it sets offsets or stored
            // positions (FORCE_BUFFER_SYNC_DURING_WCO_CHANGE and
            // FORCE_BUFFER_SYNC_DURING_EEPROM_WRITE, both on by default),
            // whatever the values.
            Motion::Offsets => {
                if matches!(self.model, TimeModel::Grbl { .. }) {
                    self.sync();
                }
            }
            Motion::End => self.sync(),
        }
    }

    /// The end of the program: whatever is planned runs to a stop.
    pub(crate) fn finish(&mut self) {
        self.sync();
    }

    /// The next line whose time is final, in line order. Call it between
    /// lines (after all the events of a line): a line is final once every
    /// block it made has run.
    pub(crate) fn next_line(&mut self) -> Option<LineTime> {
        if self.open.front()?.blocks > 0 {
            return None;
        }
        let o = self.open.pop_front()?;
        let t = LineTime {
            line: o.line,
            start: self.clock,
            seconds: o.seconds,
        };
        self.clock += o.seconds;
        Some(t)
    }

    pub(crate) fn totals(&self) -> &Totals {
        &self.totals
    }

    fn feed_rate(&self, kind: MoveKind, rate: f64, mode: FeedMode) -> Feed {
        if kind == MoveKind::Rapid {
            return Feed::Rapid;
        }
        match mode {
            FeedMode::PerMinute if rate > 0.0 => Feed::PerMinute(rate),
            FeedMode::InverseTime if rate > 0.0 => Feed::Inverse(rate),
            FeedMode::PerRev if rate > 0.0 && self.rpm > 0.0 => Feed::PerMinute(rate * self.rpm),
            _ => Feed::None,
        }
    }

    /// A move whose offset differs from the last one's: GRBL empties its
    /// buffer at every change of the work offset (G10, G92, G43.1, G54…;
    /// `FORCE_BUFFER_SYNC_DURING_WCO_CHANGE`).
    fn offset_change(&mut self, from: &Point) {
        if let (Some(o), Some(n)) = (self.offset, from.offset)
            && o != n
            && matches!(self.model, TimeModel::Grbl { .. })
        {
            self.sync();
        }
        if from.offset.is_some() {
            self.offset = from.offset;
        }
    }

    /// A straight move from `from` to `target` (machine coordinates, NaN:
    /// not known).
    fn straight(&mut self, from: &Axes, target: &Axes, feed: Feed, rapid: bool) {
        let settings = match &self.model {
            TimeModel::Grbl { settings, .. } => settings,
            TimeModel::LinuxCnc { .. } => return self.lc_line(from, target, feed, rapid),
            TimeModel::Off => return,
            TimeModel::RestToRest { axes } => {
                let b = rest_to_rest(axes, from, target, feed, rapid, self.charge);
                match b {
                    Some(b) => self.push(b),
                    None => self.untimed(rapid),
                }
                return;
            }
        };
        let mut delta = [0i64; 3];
        let mut known = true;
        for i in 0..3 {
            let spm = settings.steps_per_mm[i];
            if self.steps[i].is_none() && from[i].is_finite() {
                self.steps[i] = Some((from[i] * spm).round() as i64);
            }
            let x = target[i];
            if !x.is_finite() {
                continue;
            }
            let t = (x * spm).round() as i64;
            match self.steps[i] {
                Some(p) => delta[i] = t - p,
                None => known = false,
            }
            self.steps[i] = Some(t);
        }
        if !known {
            self.untimed(rapid);
            return;
        }
        if delta == [0; 3] {
            return; // GRBL drops a block of no step.
        }
        let mut unit: [f64; 3] =
            std::array::from_fn(|i| delta[i] as f64 / settings.steps_per_mm[i]);
        let mm = (unit[0] * unit[0] + unit[1] * unit[1] + unit[2] * unit[2]).sqrt();
        for u in &mut unit {
            *u /= mm;
        }
        let max_rate: [f64; 3] = settings.max_rate.map(|r| r / 60.0);
        let rapid_rate = grbl::limit_by_axes(&max_rate, &unit);
        let programmed = match feed {
            Feed::Rapid => rapid_rate,
            Feed::PerMinute(f) => f / 60.0,
            Feed::Inverse(f) => f * mm / 60.0,
            Feed::None => {
                self.untimed(rapid);
                return;
            }
        };
        // GRBL's MINIMUM_FEED_RATE: 1 mm/min.
        let nominal = programmed.min(rapid_rate).max(1.0 / 60.0);
        let junction = grbl::junction_speed_sqr(settings, &self.prev_unit, &unit);
        let b = Block {
            mm,
            accel: grbl::limit_by_axes(&settings.accel, &unit),
            nominal,
            max_entry_sqr: (nominal * nominal)
                .min(self.prev_nominal * self.prev_nominal)
                .min(junction),
            entry_sqr: 0.0,
            rev_sqr: f64::NAN,
            charge: Charge {
                rapid,
                ..self.charge
            },
        };
        self.prev_unit = unit;
        self.prev_nominal = nominal;
        self.push(b);
    }

    /// An arc: GRBL's chords, each a straight move.
    fn arc(&mut self, g: &ArcGeom, from: &Point, to: &Point, feed: Feed) {
        let target = machine(to);
        let off = from.offset.unwrap_or([0.0; 9]);
        let segments = match &self.model {
            TimeModel::Grbl { settings, .. } => grbl::arc_segments(settings, g.sweep, g.r0),
            TimeModel::LinuxCnc { .. } => return self.lc_arc(g, from, to, feed),
            TimeModel::Off => return,
            TimeModel::RestToRest { axes } => {
                match rest_to_rest_arc(axes, g, from, to, feed, self.charge) {
                    Some(b) => self.push(b),
                    None => self.untimed(false),
                }
                return;
            }
        };
        if segments == 0 {
            return self.straight(&machine(from), &target, feed, false);
        }
        // Inverse time: GRBL gives every chord the arc's inverse-time value
        // times the number of chords, read as mm/min (mc_arc()).
        let feed = match feed {
            Feed::Inverse(f) => Feed::PerMinute(f * segments as f64),
            f => f,
        };
        let h0 = from.work[g.h];
        let dh = to.work[g.h] - h0;
        let mut last = machine(from);
        for i in 1..segments {
            let t = i as f64 / segments as f64;
            let ang = g.start + g.sweep * t;
            let mut p = target;
            p[g.a] = g.ca + g.r0 * ang.cos() + off[g.a];
            p[g.b] = g.cb + g.r0 * ang.sin() + off[g.b];
            p[g.h] = h0 + dh * t + off[g.h];
            self.straight(&last, &p, feed, false);
            last = p;
        }
        self.straight(&last, &target, feed, false);
    }

    fn untimed(&mut self, rapid: bool) {
        if rapid {
            self.totals.untimed_rapids += 1;
        } else {
            self.totals.untimed_feeds += 1;
        }
    }

    fn push(&mut self, b: Block) {
        self.moving = true;
        self.reserve(b.charge.line, 1);
        if let Some(ran) = self.window.push(b) {
            self.account(ran);
        }
    }

    /// Counts a block of `line` still to run (`delta` 1), or one less.
    fn reserve(&mut self, line: u64, delta: i64) {
        if let Some(o) = self.open.iter_mut().rev().find(|o| o.line == line) {
            o.blocks = o.blocks.saturating_add_signed(delta);
        }
    }

    /// LinuxCNC: a straight move from `from` to `to` (machine
    /// coordinates, NaN: not known).
    fn lc_line(&mut self, from: &Axes, to: &Axes, feed: Feed, rapid: bool) {
        let TimeModel::LinuxCnc { limits } = &self.model else {
            return;
        };
        let mut d = [0.0; 9];
        for i in 0..9 {
            match (from[i].is_finite(), to[i].is_finite()) {
                (true, true) => d[i] = to[i] - from[i],
                (false, false) => {}
                _ => return self.untimed(rapid),
            }
        }
        let len = linuxcnc::path_len(&d);
        if len < 1e-12 {
            return; // LinuxCNC drops a segment of no length.
        }
        let maxvel = linuxcnc::along(&limits.vel, &d)
            .min(limits.traj_vel)
            .min(len / limits.cycle);
        let acc = linuxcnc::along(&limits.acc, &d).min(limits.traj_acc);
        let req = match feed {
            Feed::Rapid => maxvel,
            Feed::PerMinute(f) => f / 60.0,
            Feed::Inverse(f) => f * len / 60.0,
            Feed::None => return self.untimed(rapid),
        };
        let xyz = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        let u = if xyz > 0.0 {
            [d[0] / xyz, d[1] / xyz, d[2] / xyz]
        } else {
            [0.0; 3]
        };
        let seg = linuxcnc::Seg {
            len,
            nominal_len: len,
            u0: u,
            u1: u,
            req,
            maxvel,
            acc,
            acc_ratio: 1.0,
            arc: false,
            rotary: d[3..].iter().any(|v| *v != 0.0),
            exact: self.path.0,
            tolerance: self.path.1,
            charge: Charge {
                rapid,
                ..self.charge
            },
            entry_sqr: 0.0,
        };
        self.lc_add(seg);
    }

    /// LinuxCNC: an arc or helix.
    fn lc_arc(&mut self, g: &ArcGeom, from: &Point, to: &Point, feed: Feed) {
        let TimeModel::LinuxCnc { limits } = &self.model else {
            return;
        };
        let len = g.length(&from.work, &to.work);
        if !len.is_finite() {
            return self.untimed(false);
        }
        if len < 1e-12 {
            return;
        }
        let dh = to.work[g.h] - from.work[g.h];
        let cap = |m: &[f64; 9]| {
            let mut v = m[g.a].min(m[g.b]);
            if dh != 0.0 {
                v = v.min(m[g.h] * len / dh.abs());
            }
            v
        };
        let (maxvel, ratio) = linuxcnc::arc_limits(
            g.r0.min(g.r1),
            cap(&limits.vel).min(limits.traj_vel),
            cap(&limits.acc).min(limits.traj_acc),
        );
        let req = match feed {
            Feed::PerMinute(f) => f / 60.0,
            Feed::Inverse(f) => f * len / 60.0,
            Feed::Rapid | Feed::None => return self.untimed(false),
        };
        let planar = g.sweep.abs() * 0.5 * (g.r0 + g.r1);
        let tangent = |ang: f64| {
            let s = g.sweep.signum() * planar / len;
            let mut u = [0.0; 3];
            u[g.a] = -ang.sin() * s;
            u[g.b] = ang.cos() * s;
            u[g.h] = dh / len;
            u
        };
        let seg = linuxcnc::Seg {
            len,
            nominal_len: len,
            u0: tangent(g.start),
            u1: tangent(g.start + g.sweep),
            req,
            maxvel: maxvel.min(len / limits.cycle),
            acc: cap(&limits.acc).min(limits.traj_acc),
            acc_ratio: ratio,
            arc: true,
            rotary: false,
            exact: self.path.0,
            tolerance: self.path.1,
            charge: Charge {
                rapid: false,
                ..self.charge
            },
            entry_sqr: 0.0,
        };
        self.lc_add(seg);
    }

    /// LinuxCNC: a new segment; the corner with the one before decides
    /// how that one ends.
    fn lc_add(&mut self, mut next: linuxcnc::Seg) {
        let TimeModel::LinuxCnc { limits } = &self.model else {
            return;
        };
        let acc3 = [limits.acc[0], limits.acc[1], limits.acc[2]];
        let cycle = limits.cycle;
        self.moving = true;
        self.reserve(next.charge.line, 1);
        let Some(mut prev) = self.pending.take() else {
            next.entry_sqr = 0.0;
            self.pending = Some(next);
            return;
        };
        let mut arc = None;
        match linuxcnc::corner(&prev, &next, &acc3, cycle) {
            linuxcnc::Corner::Stop => next.entry_sqr = 0.0,
            linuxcnc::Corner::Tangent { speed, reduce } => {
                prev.acc *= 1.0 - reduce;
                next.acc *= 1.0 - reduce;
                next.entry_sqr = speed * speed;
            }
            linuxcnc::Corner::Blend {
                trim,
                len,
                speed,
                maxvel,
                acc,
            } => {
                prev.len -= trim;
                next.len -= trim;
                let mut a = linuxcnc::Seg {
                    len,
                    nominal_len: len,
                    u0: prev.u1,
                    u1: next.u0,
                    req: speed,
                    maxvel,
                    acc,
                    acc_ratio: 1.0,
                    arc: true,
                    rotary: false,
                    exact: false,
                    tolerance: prev.tolerance,
                    charge: prev.charge,
                    entry_sqr: 0.0,
                };
                next.entry_sqr = speed * speed;
                a.entry_sqr = speed * speed;
                if linuxcnc::consumed(prev.len, speed, cycle) {
                    // The blend takes the rest of the segment as its
                    // lead-in, and its place.
                    a.len += prev.len.max(0.0);
                    a.entry_sqr = prev.entry_sqr;
                    self.reserve(prev.charge.line, -1);
                    self.push(a.block());
                    self.pending = Some(next);
                    return;
                }
                arc = Some(a);
            }
        }
        let pc = prev.req.min(prev.maxvel);
        next.entry_sqr = next.entry_sqr.min(pc * pc);
        self.reserve(prev.charge.line, -1);
        self.push(prev.block());
        if let Some(mut a) = arc {
            a.entry_sqr = a.entry_sqr.min(pc * pc);
            self.push(a.block());
        }
        self.pending = Some(next);
    }

    /// Charges a block that ran to its line, its tool and its kind.
    fn account(&mut self, (b, t): planner::Ran) {
        let c = b.charge;
        if c.rapid {
            self.totals.rapid += t;
        } else {
            self.totals.feed += t;
        }
        self.totals.total += t;
        *self.totals.per_tool.entry(c.tool).or_default() += t;
        if let Some(o) = self.open.iter_mut().find(|o| o.line == c.line) {
            o.seconds += t;
            o.blocks = o.blocks.saturating_sub(1);
        }
    }

    /// A wait (dwell, idle delay) of the current line.
    fn add_wait(&mut self, t: f64) {
        self.totals.total += t;
        *self.totals.per_tool.entry(self.charge.tool).or_default() += t;
        if let Some(o) = self.open.back_mut() {
            o.seconds += t;
        }
    }

    /// The firmware empties its buffer: everything planned runs to a stop,
    /// then the idle delay.
    fn sync(&mut self) {
        if let Some(p) = self.pending.take() {
            self.reserve(p.charge.line, -1);
            self.push(p.block());
        }
        while let Some(ran) = self.window.run_first() {
            self.account(ran);
        }
        if self.moving {
            self.moving = false;
            self.totals.stops += 1;
            if let TimeModel::Grbl { settings, .. } = &self.model {
                let w = settings.idle_wait();
                self.totals.waits += w;
                self.add_wait(w);
            }
        }
    }
}

/// A straight move timed alone, from rest to rest (`None`: not timed).
fn rest_to_rest(
    axes: &MachineAxes,
    from: &Axes,
    to: &Axes,
    feed: Feed,
    rapid: bool,
    charge: Charge,
) -> Option<Block> {
    let mut d = [0.0; 9];
    for i in 0..9 {
        match (from[i].is_finite(), to[i].is_finite()) {
            (true, true) => d[i] = to[i] - from[i],
            // An axis never given: it does not move.
            (false, false) => {}
            _ => return None,
        }
    }
    let path = path_len(&d);
    if path <= 0.0 {
        return Some(still(charge));
    }
    let mut vmax = f64::INFINITY;
    let mut amax = f64::INFINITY;
    for (i, di) in d.iter().enumerate() {
        if *di == 0.0 {
            continue;
        }
        let k = path / di.abs();
        match axes.axes[i].max_vel {
            Some(m) => vmax = vmax.min(m * k),
            None if rapid => return None,
            None => {}
        }
        if let Some(m) = axes.axes[i].max_acc {
            amax = amax.min(m * k);
        }
    }
    let v = match feed {
        Feed::Rapid => vmax,
        Feed::PerMinute(f) => (f / 60.0).min(vmax),
        Feed::Inverse(f) => (f * path / 60.0).min(vmax),
        Feed::None => return None,
    };
    Some(Block {
        mm: path,
        accel: amax,
        nominal: v,
        max_entry_sqr: 0.0,
        entry_sqr: 0.0,
        rev_sqr: f64::NAN,
        charge: Charge { rapid, ..charge },
    })
}

/// An arc timed alone, from rest to rest: at most as fast as the slowest
/// axis of its plane allows, and below sqrt(acceleration · radius).
fn rest_to_rest_arc(
    axes: &MachineAxes,
    g: &ArcGeom,
    from: &Point,
    to: &Point,
    feed: Feed,
    charge: Charge,
) -> Option<Block> {
    let len = g.length(&from.work, &to.work);
    if !len.is_finite() {
        return None;
    }
    if len <= 0.0 {
        return Some(still(charge));
    }
    let cap = |f: fn(&crate::machine::axes::AxisData) -> Option<f64>| {
        [g.a, g.b]
            .iter()
            .filter_map(|&i| f(&axes.axes[i]))
            .fold(f64::INFINITY, f64::min)
    };
    let amax = cap(|a| a.max_acc);
    let vmax = cap(|a| a.max_vel).min((amax * 0.5 * (g.r0 + g.r1)).sqrt());
    let v = match feed {
        Feed::PerMinute(f) => (f / 60.0).min(vmax),
        Feed::Inverse(f) => (f * len / 60.0).min(vmax),
        Feed::Rapid | Feed::None => return None,
    };
    Some(Block {
        mm: len,
        accel: amax,
        nominal: v,
        max_entry_sqr: 0.0,
        entry_sqr: 0.0,
        rev_sqr: f64::NAN,
        charge,
    })
}

/// A block of no length (it takes no time).
fn still(charge: Charge) -> Block {
    Block {
        mm: 0.0,
        accel: f64::INFINITY,
        nominal: 1.0,
        max_entry_sqr: 0.0,
        entry_sqr: 0.0,
        rev_sqr: f64::NAN,
        charge,
    }
}

/// The path length of a move: XYZ, else UVW, else ABC (degrees).
fn path_len(d: &Axes) -> f64 {
    let lin = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    if lin > 0.0 {
        return lin;
    }
    let uvw = (d[6] * d[6] + d[7] * d[7] + d[8] * d[8]).sqrt();
    if uvw > 0.0 {
        return uvw;
    }
    (d[3] * d[3] + d[4] * d[4] + d[5] * d[5]).sqrt()
}

/// How a move's speed is given.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Feed {
    Rapid,
    /// mm/min
    PerMinute(f64),
    /// 1/min (G93)
    Inverse(f64),
    /// Not known (no feed, or per revolution with the spindle stopped).
    None,
}

/// Machine coordinates of a point (work coordinates when the offset is not
/// known: the run time does not depend on where the program sits).
fn machine(p: &Point) -> Axes {
    match p.offset {
        Some(o) => std::array::from_fn(|i| p.work[i] + o[i]),
        None => p.work,
    }
}

const REST_TO_REST: &str = "each move is timed on its own as a trapezoid that starts and ends at rest: \
it speeds up at the acceleration limit, runs at the programmed feed (rapids: the \
maximum velocity), and slows down again; the feed and acceleration of a move are \
capped so that no axis exceeds its own maximum velocity or acceleration. This target's \
planner is not modelled: it blends moves, so programs of many short moves run faster \
than this figure (up to 10 times on dense CAM programs)";

#[cfg(test)]
mod tests;
