//! Statistics of a program's motion: travel ranges, path lengths, counts
//! and an estimated run time.

use std::collections::BTreeSet;
use std::fmt::Write as _;

use serde::Serialize;

use super::geom::{ArcGeom, arc_length, extreme_points, line_length};
use crate::machine::axes::{LETTERS, MachineAxes, is_rotary};
use crate::machine::motion::{Axes, Motion, MoveKind};
use crate::runtime::{RunTime, TimeModel};

/// The range of one axis.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub(crate) struct Range {
    pub min: f64,
    pub max: f64,
}

impl Range {
    fn add(r: &mut Option<Range>, v: f64) {
        if !v.is_finite() {
            return;
        }
        match r {
            Some(r) => {
                r.min = r.min.min(v);
                r.max = r.max.max(v);
            }
            None => *r = Some(Range { min: v, max: v }),
        }
    }
}

/// Accumulates statistics over a motion stream.
#[derive(Debug, Clone)]
pub(crate) struct Stats {
    axes: MachineAxes,
    pub work: [Option<Range>; 9],
    pub machine: [Option<Range>; 9],
    /// Moves whose machine position was not known.
    pub machine_unknown: u64,
    pub rapid_moves: u64,
    pub feed_moves: u64,
    pub arcs: u64,
    pub probes: u64,
    pub rapid_length: f64,
    pub feed_length: f64,
    pub tool_changes: u64,
    pub tools: BTreeSet<i64>,
    /// The run time as the target's planner runs the program.
    pub run_time: RunTime,
    started: bool,
}

impl Stats {
    pub(crate) fn new(axes: MachineAxes, model: TimeModel) -> Stats {
        Stats {
            run_time: RunTime::new(model),
            axes,
            work: [None; 9],
            machine: [None; 9],
            machine_unknown: 0,
            rapid_moves: 0,
            feed_moves: 0,
            arcs: 0,
            probes: 0,
            rapid_length: 0.0,
            feed_length: 0.0,
            tool_changes: 0,
            tools: BTreeSet::new(),
            started: false,
        }
    }

    /// Adds one motion event.
    pub(crate) fn add(&mut self, m: &Motion) {
        self.run_time.motion(m);
        match m {
            Motion::Line { kind, from, to, .. } => {
                self.extent(m, from.offset.zip(to.offset).map(|(o, _)| o));
                let len = finite(line_length(&from.work, &to.work));
                if *kind == MoveKind::Rapid {
                    self.rapid_moves += 1;
                    self.rapid_length += len;
                } else {
                    if *kind == MoveKind::Probe {
                        self.probes += 1;
                    }
                    self.feed_moves += 1;
                    self.feed_length += len;
                }
            }
            Motion::Arc {
                from,
                to,
                center,
                plane,
                ccw,
                turns,
                ..
            } => {
                self.extent(m, from.offset);
                self.arcs += 1;
                self.feed_moves += 1;
                let g = ArcGeom::new(
                    &from.work,
                    &to.work,
                    *center,
                    *plane,
                    *ccw,
                    *turns,
                    crate::geom::arc::FullCircle::Exact,
                );
                self.feed_length += finite(arc_length(&g, &from.work, &to.work));
            }
            Motion::ToolChange { tool } => {
                self.tool_changes += 1;
                self.tools.insert(*tool);
            }
            _ => {}
        }
    }

    /// The run time planned so far (s): the blocks that have left the
    /// planner's look-ahead window, dwells and waits. It trails the events
    /// by up to the window; each line's own time, once final, comes from
    /// [`RunTime::line`] and [`RunTime::next_line`].
    pub(crate) fn total_time(&self) -> f64 {
        self.run_time.totals().total
    }

    /// Moves the run-time model could not time so far.
    pub(crate) fn untimed(&self) -> u64 {
        let t = self.run_time.totals();
        t.untimed_feeds + t.untimed_rapids
    }

    fn extent(&mut self, m: &Motion, offset: Option<Axes>) {
        let first = !self.started;
        self.started = true;
        let mut n = 0;
        extreme_points(m, |p| {
            n += 1;
            // The start point counts only for the first move: later ones
            // start where the previous move ended (in machine coordinates;
            // in work coordinates an offset change would add a point the
            // tool never went to in the coordinates it was in).
            if n == 1 && !first {
                return;
            }
            for (i, v) in p.iter().enumerate() {
                Range::add(&mut self.work[i], *v);
            }
            if let Some(o) = offset {
                for (i, v) in p.iter().enumerate() {
                    Range::add(&mut self.machine[i], v + o[i]);
                }
            }
        });
        if offset.is_none() {
            self.machine_unknown += 1;
        }
    }

    /// The axes worth reporting: X, Y and Z, and any other that moved or
    /// sits away from 0.
    fn shown_axes(&self) -> Vec<usize> {
        (0..9)
            .filter(|&i| match self.work[i] {
                Some(r) => i < 3 || r.min != 0.0 || r.max != 0.0,
                None => false,
            })
            .collect()
    }

    /// The run time, the program run to its end.
    fn time_report(&self) -> TimeReport {
        let mut rt = self.run_time.clone();
        rt.finish();
        let t = rt.totals();
        let info = rt.model();
        TimeReport {
            total_s: t.total,
            feed_s: t.feed,
            rapid_s: t.rapid,
            dwell_s: t.dwell,
            wait_s: t.waits,
            stops: t.stops,
            per_tool: t
                .per_tool
                .iter()
                .map(|(tool, s)| ToolTime {
                    tool: *tool,
                    seconds: *s,
                })
                .collect(),
            untimed_feed_moves: t.untimed_feeds,
            untimed_rapid_moves: t.untimed_rapids,
            machine_limits_used: self.axes.has_dynamics() || self.axes.grbl.is_some(),
            model_name: info.name,
            approximate: info.approximate,
            error: info.error,
            model: info.description,
        }
    }

    /// The statistics as a serialisable report.
    pub(crate) fn report(&self, program: &str) -> Report {
        let axes = self
            .shown_axes()
            .into_iter()
            .map(|i| AxisReport {
                axis: LETTERS[i].to_string(),
                unit: if is_rotary(i) { "deg" } else { "mm" },
                work: self.work[i],
                machine: if self.machine_unknown == 0 {
                    self.machine[i]
                } else {
                    None
                },
            })
            .collect();
        let limits = (0..9)
            .filter_map(|i| {
                let a = &self.axes.axes[i];
                if a.min.is_none() && a.max.is_none() {
                    return None;
                }
                let inside = if self.machine_unknown > 0 {
                    None
                } else {
                    self.machine[i].map(|r| {
                        a.min
                            .is_none_or(|lo| r.min >= lo - 1e-9 * lo.abs().max(1.0))
                            && a.max
                                .is_none_or(|hi| r.max <= hi + 1e-9 * hi.abs().max(1.0))
                    })
                };
                Some(LimitReport {
                    axis: LETTERS[i].to_string(),
                    min: a.min,
                    max: a.max,
                    source: a.limit_source.clone().unwrap_or_default(),
                    inside,
                })
            })
            .collect();
        Report {
            limits,
            program: program.to_string(),
            units: "mm",
            axes,
            machine_known: self.machine_unknown == 0,
            moves: self.rapid_moves + self.feed_moves,
            rapid_moves: self.rapid_moves,
            feed_moves: self.feed_moves,
            arcs: self.arcs,
            probe_moves: self.probes,
            rapid_length: self.rapid_length,
            feed_length: self.feed_length,
            tool_changes: self.tool_changes,
            tools: self.tools.iter().copied().collect(),
            time: self.time_report(),
        }
    }
}

/// A length of a move with an unknown end counts as 0.
fn finite(v: f64) -> f64 {
    if v.is_finite() { v } else { 0.0 }
}

#[derive(Debug, Clone, Serialize)]
pub(crate) struct AxisReport {
    pub axis: String,
    pub unit: &'static str,
    pub work: Option<Range>,
    pub machine: Option<Range>,
}

/// The run time of the program (s), from [`crate::runtime`].
#[derive(Debug, Clone, Serialize)]
pub(crate) struct TimeReport {
    pub total_s: f64,
    pub feed_s: f64,
    pub rapid_s: f64,
    pub dwell_s: f64,
    /// Waits after full stops (GRBL's step idle delay).
    pub wait_s: f64,
    /// Full stops where the planner ran empty.
    pub stops: u64,
    /// Time with each tool in the spindle (`tool` null: before any change).
    pub per_tool: Vec<ToolTime>,
    pub untimed_feed_moves: u64,
    pub untimed_rapid_moves: u64,
    pub machine_limits_used: bool,
    /// The planner model, e.g. "GRBL 1.1h planner".
    pub model_name: String,
    /// Whether the model is approximate for this target.
    pub approximate: bool,
    /// How far the figure is known to be off.
    pub error: String,
    /// How the figure is made and how far to trust it.
    pub model: String,
}

/// The time spent with one tool.
#[derive(Debug, Clone, Serialize)]
pub(crate) struct ToolTime {
    pub tool: Option<i64>,
    pub seconds: f64,
}

/// One axis's travel limits and whether the program stays inside them
/// (`None`: machine coordinates not known, or the axis never moved).
#[derive(Debug, Clone, Serialize)]
pub(crate) struct LimitReport {
    pub axis: String,
    pub min: Option<f64>,
    pub max: Option<f64>,
    pub source: String,
    pub inside: Option<bool>,
}

#[derive(Debug, Clone, Serialize)]
pub(crate) struct Report {
    pub program: String,
    /// Travel limits given for the machine (machine coordinates).
    pub limits: Vec<LimitReport>,
    pub units: &'static str,
    pub axes: Vec<AxisReport>,
    /// Whether machine coordinates are known for every move.
    pub machine_known: bool,
    pub moves: u64,
    pub rapid_moves: u64,
    pub feed_moves: u64,
    pub arcs: u64,
    pub probe_moves: u64,
    pub rapid_length: f64,
    pub feed_length: f64,
    pub tool_changes: u64,
    pub tools: Vec<i64>,
    pub time: TimeReport,
}

/// `h:mm:ss.s`
pub(crate) fn hms(s: f64) -> String {
    let s = s.max(0.0);
    let h = (s / 3600.0).floor();
    let m = ((s - h * 3600.0) / 60.0).floor();
    let sec = s - h * 3600.0 - m * 60.0;
    format!("{h}:{m:02}:{sec:04.1}")
}

fn num(v: f64) -> String {
    let r = (v * 1000.0).round() / 1000.0;
    if r == 0.0 {
        "0.000".into()
    } else {
        format!("{r:.3}")
    }
}

impl Report {
    pub(crate) fn json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_default() + "\n"
    }

    /// The human-readable statistics.
    pub(crate) fn text(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "program: {}", self.program);
        let _ = writeln!(
            s,
            "travel (mm, degrees for A-C; machine = work + offsets{})",
            if self.machine_known {
                ""
            } else {
                "; machine coordinates unknown: offsets not known (give --zero-start, --var-file or -D)"
            }
        );
        let _ = writeln!(
            s,
            "  axis {:>12} {:>12} {:>12} {:>12}",
            "work min", "work max", "machine min", "machine max"
        );
        for a in &self.axes {
            let (wmin, wmax) = a
                .work
                .map_or(("-".into(), "-".into()), |r| (num(r.min), num(r.max)));
            let (mmin, mmax) = a
                .machine
                .map_or(("-".into(), "-".into()), |r| (num(r.min), num(r.max)));
            let _ = writeln!(
                s,
                "  {:<4} {wmin:>12} {wmax:>12} {mmin:>12} {mmax:>12}",
                a.axis
            );
        }
        for l in &self.limits {
            let b = |v: Option<f64>| v.map_or("-".to_string(), num);
            let _ = writeln!(
                s,
                "  limit {} {}..{} from {}: {}",
                l.axis,
                b(l.min),
                b(l.max),
                l.source,
                match l.inside {
                    Some(true) => "inside",
                    Some(false) => "LEFT (flattening and check stop at the first move outside)",
                    None => "not known",
                }
            );
        }
        let _ = writeln!(
            s,
            "moves: {} ({} rapid, {} feed of which {} arcs{})",
            self.moves,
            self.rapid_moves,
            self.feed_moves,
            self.arcs,
            if self.probe_moves > 0 {
                format!(", {} probe", self.probe_moves)
            } else {
                String::new()
            }
        );
        let _ = writeln!(
            s,
            "path: feed {} mm, rapid {} mm",
            num(self.feed_length),
            num(self.rapid_length)
        );
        let tools: Vec<String> = self.tools.iter().map(|t| t.to_string()).collect();
        let _ = writeln!(
            s,
            "tool changes: {}{}",
            self.tool_changes,
            if tools.is_empty() {
                String::new()
            } else {
                format!(" (tools {})", tools.join(", "))
            }
        );
        self.time_text(&mut s);
        s
    }

    /// The run-time part of [`Report::text`].
    fn time_text(&self, s: &mut String) {
        let t = &self.time;
        if t.model_name == "none" {
            let _ = writeln!(s, "estimated time: not estimated (--no-time)");
            return;
        }
        let _ = writeln!(
            s,
            "estimated time: {}{} by the {} ({})",
            if t.approximate { "about " } else { "" },
            hms(t.total_s),
            t.model_name,
            t.error,
        );
        let _ = writeln!(
            s,
            "  feed {}, rapid {}, dwell {}{}; {} full stop{}",
            hms(t.feed_s),
            hms(t.rapid_s),
            hms(t.dwell_s),
            if t.wait_s > 0.0 {
                format!(", waits after stops {}", hms(t.wait_s))
            } else {
                String::new()
            },
            t.stops,
            if t.stops == 1 { "" } else { "s" },
        );
        if t.per_tool.len() > 1 || t.per_tool.iter().any(|p| p.tool.is_some()) {
            for p in &t.per_tool {
                let _ = writeln!(
                    s,
                    "  {}: {}",
                    p.tool
                        .map_or("before any tool change".to_string(), |n| format!(
                            "tool {n}"
                        )),
                    hms(p.seconds)
                );
            }
        }
        if t.untimed_feed_moves > 0 {
            let _ = writeln!(
                s,
                "  not timed: {} feed moves (no feed rate, or feed per revolution with the spindle stopped)",
                t.untimed_feed_moves
            );
        }
        if t.untimed_rapid_moves > 0 {
            let _ = writeln!(
                s,
                "  not timed: {} rapid moves (their start is not known: give --zero-start or \
                 a first move with every axis; or no maximum velocity for an axis they move)",
                t.untimed_rapid_moves
            );
        }
        let _ = writeln!(s, "how the estimate is made: {}", t.model);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::codes::{FeedMode, Plane};
    use crate::machine::motion::{Feed, Point};

    fn pt(x: f64, y: f64, z: f64, off: Option<f64>) -> Point {
        let mut w = [0.0; 9];
        w[0] = x;
        w[1] = y;
        w[2] = z;
        Point {
            work: w,
            offset: off.map(|o| [o; 9]),
        }
    }

    fn rest(axes: MachineAxes) -> TimeModel {
        TimeModel::RestToRest {
            axes: Box::new(axes),
        }
    }

    fn feed(r: f64) -> Feed {
        Feed {
            rate: r,
            mode: FeedMode::PerMinute,
        }
    }

    #[test]
    fn ranges_lengths_and_counts() {
        let mut s = Stats::new(MachineAxes::default(), rest(MachineAxes::default()));
        s.add(&Motion::Line {
            kind: MoveKind::Rapid,
            from: pt(0.0, 0.0, 0.0, Some(10.0)),
            to: pt(3.0, 4.0, 0.0, Some(10.0)),
            feed: feed(0.0),
        });
        // Half circle from (3,4) about (3,0) clockwise to (3,-4): crosses +X at (7,0).
        s.add(&Motion::Arc {
            from: pt(3.0, 4.0, 0.0, Some(10.0)),
            to: pt(3.0, -4.0, 0.0, Some(10.0)),
            center: [3.0, 0.0],
            plane: Plane::XY,
            ccw: false,
            turns: 1,
            feed: feed(600.0),
        });
        s.add(&Motion::ToolChange { tool: 4 });
        assert_eq!(s.work[0], Some(Range { min: 0.0, max: 7.0 }));
        assert_eq!(
            s.work[1],
            Some(Range {
                min: -4.0,
                max: 4.0
            })
        );
        assert_eq!(
            s.machine[0],
            Some(Range {
                min: 10.0,
                max: 17.0
            })
        );
        assert!((s.rapid_length - 5.0).abs() < 1e-12);
        assert!((s.feed_length - 4.0 * std::f64::consts::PI).abs() < 1e-12);
        let t = s.report("p").time;
        assert!((t.feed_s - 4.0 * std::f64::consts::PI / 10.0).abs() < 1e-12);
        assert_eq!(t.untimed_rapid_moves, 1);
        assert_eq!((s.arcs, s.tool_changes), (1, 1));
        let r = s.report("p");
        assert!(r.text().contains("tools 4"));
        assert!(r.json().contains("\"feed_length\""));
    }

    #[test]
    fn velocity_and_acceleration_caps() {
        let mut axes = MachineAxes::default();
        axes.axes[0].max_vel = Some(2.0);
        axes.axes[1].max_vel = Some(100.0);
        let mut s = Stats::new(axes.clone(), rest(axes));
        // 10 mm along X at F6000 (100 mm/s), capped by X at 2 mm/s.
        s.add(&Motion::Line {
            kind: MoveKind::Feed,
            from: pt(0.0, 0.0, 0.0, None),
            to: pt(10.0, 0.0, 0.0, None),
            feed: feed(6000.0),
        });
        assert!((s.report("p").time.feed_s - 5.0).abs() < 1e-12);
        // A rapid moving only Y at 100 mm/s.
        s.add(&Motion::Line {
            kind: MoveKind::Rapid,
            from: pt(10.0, 0.0, 0.0, None),
            to: pt(10.0, 50.0, 0.0, None),
            feed: feed(0.0),
        });
        assert!((s.report("p").time.rapid_s - 0.5).abs() < 1e-12);
        assert_eq!(s.machine_unknown, 2);
        assert!(s.report("p").axes.iter().all(|a| a.machine.is_none()));
    }
}
