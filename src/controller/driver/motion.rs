//! Motion the target lacks, lowered into plain lines: the choice of a
//! lowering for the block's motion (`lower_motion`), arcs (full circles,
//! P turns, arcs off the target's reading), polar words (`@`, `^`) and
//! canned cycles, with the positions each lowering needs.

use crate::block::{ArcDistance, Block, Distance, MotionMode, NonModal, Plane, ToolLength};
use crate::controller::lower::{self, PlainLine};
use crate::controller::profile::Arcs;
use crate::diag::ErrorKind;
use crate::diag::{SetupError, TargetError};
use crate::geom::cutter_comp::{Arc as CompArc, ArcCenter, Tolerances};
use crate::machine::FlatMachine;

use super::fates::g_span;
use super::run::words_line;
use super::{Lowering, Problem, plain};

impl Lowering {
    /// Arcs with P turns, full circles without end point and canned cycles
    /// as plain blocks; `None` when the line's motion is written as is.
    pub(super) fn lower_motion(
        &mut self,
        b: &Block,
        before: &FlatMachine,
    ) -> Result<Option<Vec<PlainLine>>, ErrorKind> {
        let motion = b.motion().unwrap_or(before.modes.motion);
        let moves = b.has_axis() || b.value(b'@').is_some() || b.value(b'^').is_some();
        let other_axis_use = b.non_modal().is_some_and(|n| !matches!(n, NonModal::Dwell))
            || b.tool_length() == Some(ToolLength::Dynamic);
        match motion {
            MotionMode::Cycle(n) if !self.p.has_g(n as u16 * 10) => {
                if !moves || other_axis_use {
                    return Ok(None);
                }
                self.lower_cycle(n, b, before).map(Some)
            }
            MotionMode::ArcCw | MotionMode::ArcCcw => {
                self.cycles.end();
                let turns = b.value(b'P').map_or(1.0, |p| p.round());
                // A full circle or a helix (no axis word of its plane).
                let xyz = [b'X', b'Y', b'Z'].map(|l| b.value(l));
                let ijk_only = !plain::names_plane_axis(xyz, self.m.modes.plane)
                    && (b.value(b'I').is_some()
                        || b.value(b'J').is_some()
                        || b.value(b'K').is_some());
                if !(moves || ijk_only) {
                    // No arc on this line (`G4 P2` under G2 is a dwell):
                    // its P is not turns.
                    return Ok(None);
                }
                if !other_axis_use && (moves || ijk_only) {
                    // Arcs the target has not in this form: chords where
                    // it has none (or none in the plane), centre-form arcs
                    // in G90 where it wants them.
                    let plane_code = match self.m.modes.plane {
                        Plane::XY => 170,
                        Plane::XZ => 180,
                        _ => 190,
                    };
                    let planes = [170, 180, 190].iter().any(|&c| self.p.has_g(c));
                    let in_plane = self.p.has_g(plane_code) || !planes && plane_code == 170;
                    if self.p.arcs == Arcs::None || !in_plane {
                        return self.lower_arc_chords(b, before, motion, turns).map(Some);
                    }
                    let incremental = self.m.modes.distance == Distance::Incremental;
                    let radius_form = b.value(b'R').is_some();
                    let rewrite = match self.p.arcs {
                        Arcs::Ijk => radius_form,
                        Arcs::IjkAbsolute => radius_form || incremental,
                        Arcs::All | Arcs::None => false,
                    };
                    if rewrite {
                        return self.lower_arc(b, before, motion, turns).map(Some);
                    }
                }
                let p_ok = self.p.arc_turns;
                // Polar words name the end point (the target has none).
                let polar = b.value(b'@').is_some() || b.value(b'^').is_some();
                if ijk_only || polar || (turns != 1.0 && !p_ok) {
                    if other_axis_use {
                        return Ok(None);
                    }
                    return self.lower_arc(b, before, motion, turns).map(Some);
                }
                if !other_axis_use
                    && b.has_axis()
                    && self.arc_off_target(b, before, &self.m, motion)
                {
                    return self.lower_arc(b, before, motion, turns).map(Some);
                }
                Ok(None)
            }
            MotionMode::Cycle(_) => Ok(None),
            MotionMode::CubicSpline | MotionMode::QuadSpline
                if !self.p.has_g(if motion == MotionMode::CubicSpline {
                    50
                } else {
                    51
                }) =>
            {
                self.cycles.end();
                if other_axis_use || !moves {
                    return Ok(None);
                }
                self.lower_spline(b, before, motion).map(Some)
            }
            MotionMode::Nurbs | MotionMode::NurbsEnd
                if !self
                    .p
                    .has_g(if motion == MotionMode::Nurbs { 52 } else { 53 }) =>
            {
                self.cycles.end();
                self.lower_nurbs_block(b, before, motion)
            }
            MotionMode::Rapid | MotionMode::Linear
                if b.value(b'@').is_some() || b.value(b'^').is_some() =>
            {
                self.cycles.end();
                self.lower_polar(b, before, motion).map(Some)
            }
            _ => {
                if moves && !other_axis_use {
                    self.cycles.end();
                }
                Ok(None)
            }
        }
    }

    pub(super) fn prog_pos(&self, m: &FlatMachine) -> [Option<f64>; 3] {
        let s = m.scale();
        [
            m.pos[0].map(|v| v / s),
            m.pos[1].map(|v| v / s),
            m.pos[2].map(|v| v / s),
        ]
    }

    pub(super) fn plane(m: &FlatMachine) -> Result<Plane, ErrorKind> {
        match m.modes.plane {
            p @ (Plane::XY | Plane::XZ | Plane::YZ) => Ok(p),
            Plane::UV | Plane::WU | Plane::VW => Err(ErrorKind::Setup(SetupError::Unsupported {
                what: "arcs and cycles in the UVW planes are not lowered".into(),
            })),
        }
    }

    /// The block's arc as G1 chords within `--tolerance`.
    fn lower_arc_chords(
        &mut self,
        b: &Block,
        before: &FlatMachine,
        motion: MotionMode,
        turns: f64,
    ) -> Result<Vec<PlainLine>, ErrorKind> {
        let input = self.arc_input(b, before, motion, turns)?;
        let tolerance = self.opts.tolerance_mm / self.m.scale();
        lower::arc::lower_arc_chords(&input, tolerance).map_err(|e| self.lower_error(e))
    }

    fn lower_arc(
        &mut self,
        b: &Block,
        before: &FlatMachine,
        motion: MotionMode,
        turns: f64,
    ) -> Result<Vec<PlainLine>, ErrorKind> {
        let input = self.arc_input(b, before, motion, turns)?;
        lower::arc::lower_arc(&input).map_err(|e| self.lower_error(e))
    }

    /// The block's arc as LinuxCNC moves it.
    fn arc_input(
        &self,
        b: &Block,
        before: &FlatMachine,
        motion: MotionMode,
        turns: f64,
    ) -> Result<lower::arc::ArcInput, ErrorKind> {
        let start = self.prog_pos(before);
        let end = self.prog_pos(&self.m);
        let known = |v: [Option<f64>; 3], what: &str| -> Result<[f64; 3], ErrorKind> {
            let mut o = [0.0; 3];
            for i in 0..3 {
                o[i] = v[i].ok_or_else(|| {
                    ErrorKind::Target(TargetError::TargetNeedsValue {
                        target: self.name(),
                        what: format!("this arc's lowering ({what})"),
                        value: format!("the current {} position", ['X', 'Y', 'Z'][i]),
                        option: "--start-position (or --zero-start), or an absolute move first"
                            .into(),
                    })
                })?;
            }
            Ok(o)
        };
        let start = known(start, "start")?;
        let end = known(end, "end")?;
        let plane = Self::plane(&self.m)?;
        let mut centre = start;
        if let Some(r) = b.value(b'R') {
            // LinuxCNC's centre for the radius (a checked arc), the same
            // whatever the turns: P turns go round it from there.
            let [p, q, _] = plane.axes();
            let arc = CompArc {
                ccw: motion == MotionMode::ArcCcw,
                center: ArcCenter::Radius(r),
                turns: 1,
            };
            let tol = Tolerances::default_for(self.m.modes.units);
            let (c, _) = crate::geom::cutter_comp::arc_center(
                &tol,
                arc,
                [start[p], start[q]],
                [end[p], end[q]],
            )
            .map_err(|_| self.lower_error(lower::LowerError::BadArc))?;
            (centre[p], centre[q]) = (c[0], c[1]);
        }
        let ijk = [b.value(b'I'), b.value(b'J'), b.value(b'K')];
        for i in 0..3 {
            if let Some(v) = ijk[i] {
                centre[i] = match self.m.modes.arc_distance {
                    ArcDistance::Incremental => start[i] + v,
                    ArcDistance::Absolute => v,
                };
            }
        }
        Ok(lower::arc::ArcInput {
            plane,
            clockwise: motion == MotionMode::ArcCw,
            start,
            end,
            centre,
            turns: turns.max(1.0) as u32,
            radius_step: self.radius_step(),
        })
    }

    /// The current X Y (program units), which a lowering needs.
    pub(super) fn xy_known(&self, m: &FlatMachine, what: &str) -> Result<[f64; 2], ErrorKind> {
        let p = self.prog_pos(m);
        let need = |axis: char| {
            ErrorKind::Target(TargetError::TargetNeedsValue {
                target: self.name(),
                what: what.into(),
                value: format!("the current {axis} position"),
                option: "--start-position (or --zero-start), or an absolute move first".into(),
            })
        };
        Ok([
            p[0].ok_or_else(|| need('X'))?,
            p[1].ok_or_else(|| need('Y'))?,
        ])
    }

    /// G0/G1 with polar words as G0/G1 X Y (and Z).
    /// The X Y end point of a block with polar words (program units),
    /// which the model then has.
    fn polar_end(&mut self, b: &Block, before: &FlatMachine) -> Result<[f64; 2], ErrorKind> {
        let current = self.xy_known(before, "polar coordinates (@ ^)")?;
        let input = lower::polar::PolarInput {
            distance: self.m.modes.distance,
            current,
            radius: b.value(b'@'),
            angle: b.value(b'^'),
        };
        let [x, y] = lower::polar::polar_target(&input).map_err(|e| self.lower_error(e))?;
        // The model follows the lowered target.
        let s = self.m.scale();
        self.m.pos[0] = Some(x * s);
        self.m.pos[1] = Some(y * s);
        Ok([x, y])
    }

    /// An arc with polar words: its end point is worked out before the
    /// arc is checked and lowered (the model's is not LinuxCNC's).
    pub(super) fn polar_arc_end(&mut self, b: &Block, before: &FlatMachine) -> Result<(), Problem> {
        let motion = b.motion().unwrap_or(before.modes.motion);
        let other_axis_use = b.non_modal().is_some_and(|n| !matches!(n, NonModal::Dwell))
            || b.tool_length() == Some(ToolLength::Dynamic);
        if !matches!(motion, MotionMode::ArcCw | MotionMode::ArcCcw)
            || other_axis_use
            || b.value(b'@').is_none() && b.value(b'^').is_none()
        {
            return Ok(());
        }
        self.polar_end(b, before)
            .map(|_| ())
            .map_err(|kind| Problem {
                span: g_span(b, 20, 30),
                kind,
            })
    }

    fn lower_polar(
        &mut self,
        b: &Block,
        before: &FlatMachine,
        motion: MotionMode,
    ) -> Result<Vec<PlainLine>, ErrorKind> {
        let [x, y] = self.polar_end(b, before)?;
        let g = if motion == MotionMode::Rapid {
            0.0
        } else {
            1.0
        };
        let mut words = vec![(b'G', g), (b'X', x), (b'Y', y)];
        if b.value(b'Z').is_some()
            && let Some(z) = self.prog_pos(&self.m)[2]
        {
            words.push((b'Z', z));
        }
        Ok(vec![words_line(&words)])
    }

    fn lower_cycle(
        &mut self,
        n: u8,
        b: &Block,
        before: &FlatMachine,
    ) -> Result<Vec<PlainLine>, ErrorKind> {
        use lower::CycleKind as K;
        let kind = match n {
            73 => K::G73,
            81 => K::G81,
            82 => K::G82,
            83 => K::G83,
            84 => K::G84,
            85 => K::G85,
            86 => K::G86,
            87 => K::G87,
            88 => K::G88,
            89 => K::G89,
            _ => return Err(self.refuse(format!("G{n}"), "the target has no such cycle")),
        };
        // In G7 an X word is a diameter; the lowering reads radii.
        let modes = &self.m.modes;
        let block = lower::CycleBlock {
            axes: [
                b.value(b'X').map(|x| modes.radius_word(0, x)),
                b.value(b'Y'),
                b.value(b'Z'),
            ],
            r: b.value(b'R'),
            l: b.value(b'L').map(|l| l.round().max(0.0) as u32),
            p: b.value(b'P'),
            q: b.value(b'Q'),
            ijk: [b.value(b'I'), b.value(b'J'), b.value(b'K')],
            radius: b.value(b'@'),
            angle: b.value(b'^'),
        };
        let m = &self.m.modes;
        let modal = lower::CycleModal {
            plane: Self::plane(&self.m)?,
            distance: m.distance,
            units: m.units,
            retract: m.retract,
            spindle: m.spindle,
        };
        // A series of cycles runs while the motion mode stays a cycle
        // (rs274 keeps its level until a line runs in another mode, G80
        // or a motion code without axis words included).
        if !before.modes.motion.is_canned_cycle() {
            self.cycles.end();
        }
        let pos = self.prog_pos(before);
        let out = self
            .cycles
            .lower(kind, &block, &modal, pos)
            .map_err(|e| self.lower_error(e))?;
        // The model follows LinuxCNC's end position.
        let s = self.m.scale();
        for i in 0..3 {
            self.m.pos[i] = Some(out.end[i] * s);
        }
        Ok(out.lines)
    }
}
