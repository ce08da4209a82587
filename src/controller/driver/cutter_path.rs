//! Cutter radius compensation computed into the path on a target without
//! it: G41/G42 (and their dynamic forms) start it, each move goes through
//! the compensation and the moves it releases are written with their
//! feeds, G40 ends it (and the first move after goes to the programmed
//! point); the words of a block run while a move is held back wait for
//! that move, and what cannot wait is refused.

use crate::block::{
    Block, CutterComp, FeedMode, GCode, MCode, MotionMode, NonModal, Plane, ToolLength, Units,
    Word, WordKind,
};
use crate::controller::lower::{self, PlainLine};
use crate::diag::ErrorKind;
use crate::diag::{SetupError, TargetError};
use crate::geom::cutter_comp::{Arc as CompArc, ArcCenter, Comp, Out, Side, Tolerances};
use crate::machine::FlatMachine;

use super::fates::Fate;
use super::run::words_line;
use super::{Lowering, Problem};

/// What a compensated move carries through the compensation: the feed of
/// its block and its number in the program's order of moves.
type MoveTag = (Option<f64>, u64);

/// Cutter compensation on, on a target without it.
pub(super) struct CompPath {
    pub(super) comp: Comp<MoveTag>,
    plane: Plane,
    /// Where the tool is (X Y Z, program units): the end of the last
    /// compensated move written.
    at: [f64; 3],
}

impl Lowering {
    /// The action words of a block run while compensated moves are held
    /// back (and a dwell's P), taken out of its own line: they wait for the
    /// held moves, while its modal words (G90/G91, ...) are written at once,
    /// as the moves written after them are read in those modes.
    pub(super) fn waiting_words(&self, b: &Block, fates: &mut [Fate]) -> Vec<(u8, f64)> {
        if self.defer_block.is_none() {
            return Vec::new();
        }
        let dwell = b.non_modal() == Some(NonModal::Dwell);
        let mut words = Vec::new();
        for (i, w) in b.words.iter().enumerate() {
            let dwell_p = dwell && w.letter == b'P' && matches!(w.kind, WordKind::Value);
            if fates[i] == Fate::Keep && (Self::is_action(w) || dwell_p) {
                words.push((w.letter, self.out_value(w)));
                fates[i] = Fate::Drop;
            }
        }
        words
    }

    /// Moves the waiting lines whose held moves are all written (number
    /// below `before`; all of them for `None`) into `lines`.
    pub(super) fn flush_deferred(&mut self, before: Option<u64>, lines: &mut Vec<Vec<u8>>) {
        let n = self
            .deferred
            .iter()
            .take_while(|(after, _)| before.is_none_or(|b| *after < b))
            .count();
        lines.extend(self.deferred.drain(..n).map(|(_, l)| l));
    }

    fn comp_refusal(
        &self,
        span: Option<crate::block::BlockSpan>,
        code: &'static str,
        message: &str,
    ) -> Problem {
        Problem {
            span,
            kind: ErrorKind::TargetLowering {
                target: self.name(),
                code,
                message: message.into(),
            },
        }
    }

    /// Whether a word of `b` would act while compensation holds a move
    /// back (spindle, coolant, dwell, tools, units, offsets, ...): the
    /// reference runs it only after the held move.
    fn holds_action(b: &Block) -> bool {
        b.words.iter().any(Self::is_action)
    }

    /// Whether `w` acts (or changes how later moves are read) rather than
    /// being part of a compensated move.
    fn is_action(w: &Word) -> bool {
        match w.kind {
            WordKind::G(g) => !matches!(
                g,
                GCode::Motion(
                    MotionMode::Rapid | MotionMode::Linear | MotionMode::ArcCw | MotionMode::ArcCcw
                ) | GCode::Plane(_)
                    | GCode::Distance(_)
                    | GCode::ArcDistance(_)
                    | GCode::CutterComp(_)
                    | GCode::Path(_)
                    | GCode::FeedMode(FeedMode::PerMinute)
            ),
            WordKind::M(m) => !matches!(m, MCode::Pause { .. } | MCode::End { .. }),
            WordKind::Value => !b"XYZIJKRPFN".contains(&w.letter),
        }
    }

    /// Actions written after the held moves, in the program's order, with
    /// the same effect: spindle, coolant, dwell and tool selection (none of
    /// them changes how a later move's words are read).
    fn deferrable(w: &Word) -> bool {
        match w.kind {
            WordKind::G(g) => matches!(g, GCode::NonModal(NonModal::Dwell)),
            WordKind::M(m) => matches!(
                m,
                MCode::Spindle(_) | MCode::Mist | MCode::Flood | MCode::CoolantOff
            ),
            WordKind::Value => matches!(w.letter, b'S' | b'T'),
        }
    }

    /// Cutter compensation on a target without it: the programmed moves
    /// of the blocks run while it is on go to a [`Comp`], and the moves it
    /// releases are written (absolute, each with its block's feed) in place
    /// of the line's motion. `None` when compensation plays no part in `b`.
    pub(super) fn comp_block(
        &mut self,
        b: &Block,
        before: &FlatMachine,
        fates: &mut [Fate],
    ) -> Result<Option<Vec<PlainLine>>, Problem> {
        if self.p.has_g(410)
            || self.comp.is_none() && b.cutter_comp().is_none() && self.after_off.is_none()
        {
            return Ok(None);
        }
        let cc_span = b
            .g_codes()
            .find(|(g, _)| matches!(g, GCode::CutterComp(_)))
            .map(|(_, w)| w.span);
        let motion_span = b
            .g_codes()
            .find(|(g, _)| matches!(g, GCode::Motion(_)))
            .map(|(_, w)| w.span);
        let moves = b.has_axis();
        let other_axis_use = b.non_modal().is_some_and(|n| !matches!(n, NonModal::Dwell))
            || b.tool_length() == Some(ToolLength::Dynamic);
        let motion = self.m.modes.motion;
        if !moves && self.tool_change_after_off(b) {
            return Ok(None);
        }
        if self.comp.as_ref().is_some_and(|c| c.comp.holding()) && Self::holds_action(b) {
            // LinuxCNC runs the block's actions after the held moves: the
            // line waits for them. What would change how later moves are
            // read (units, offsets, tools) is not lowered.
            if let Some(w) = b
                .words
                .iter()
                .find(|w| Self::is_action(w) && !Self::deferrable(w))
            {
                return Err(self.comp_refusal(
                    Some(w.span),
                    "E1180",
                    "while cutter compensation holds a move back (until the next move is known), LinuxCNC runs this only after that move; only spindle, coolant, dwell and tool selection are lowered there: put it before G41/G42 or after G40",
                ));
            }
            self.defer_block = Some(self.comp_seq);
        }
        for (i, w) in b.words.iter().enumerate() {
            if matches!(w.kind, WordKind::G(GCode::CutterComp(_))) {
                fates[i] = Fate::Drop;
            }
        }
        let mut released: Vec<Out<MoveTag>> = Vec::new();
        let mut lines: Vec<PlainLine> = Vec::new();
        let mut handled = false;
        // G40 comes before the block's motion.
        if b.cutter_comp() == Some(CutterComp::Off)
            && let Some(mut c) = self.comp.take()
        {
            c.comp
                .off(&mut released)
                .map_err(|e| self.comp_problem(cc_span, e))?;
            let at = self.write_released(&mut c, &released, &mut lines, motion_span)?;
            released.clear();
            self.after_off = Some(at);
            handled = true;
        }
        if let Some(cc) = b.cutter_comp().filter(|c| *c != CutterComp::Off) {
            for (i, w) in b.words.iter().enumerate() {
                if matches!(w.kind, WordKind::Value) && matches!(w.letter, b'D' | b'L') {
                    fates[i] = Fate::Drop;
                }
            }
            self.comp_on(b, before, cc, cc_span)?;
            handled = true;
        }
        if let Some(mut c) = self.comp.take() {
            let r = self.comp_move(
                &mut c,
                b,
                motion,
                moves,
                other_axis_use,
                motion_span,
                &mut lines,
            );
            self.comp = Some(c);
            if r? {
                handled = true;
            }
        } else if self.after_off.is_some() && (moves || other_axis_use) {
            let other_axis_use = other_axis_use && !self.g53_after_off(b, fates);
            lines.push(self.after_off_move(motion, other_axis_use, motion_span)?);
            self.released_seqs.push(u64::MAX);
            handled = true;
        }
        // Program stops release the held moves (an end also turns
        // compensation off).
        let stop = b.m_codes().find_map(|(m, _)| match m {
            MCode::Pause { .. } => Some(false),
            MCode::End { .. } => Some(true),
            _ => None,
        });
        if let Some(end) = stop
            && let Some(mut c) = self.comp.take()
        {
            c.comp
                .stop(end, &mut released)
                .map_err(|e| self.comp_problem(None, e))?;
            self.write_released(&mut c, &released, &mut lines, None)?;
            if !end {
                self.comp = Some(c);
            }
            handled = true;
        }
        if stop == Some(true) {
            self.after_off = None;
        }
        if self.comp.is_some() || handled {
            // Each compensated feed move carries its own F.
            for (i, w) in b.words.iter().enumerate() {
                if w.letter == b'F' && matches!(w.kind, WordKind::Value) {
                    fates[i] = Fate::Drop;
                }
            }
        }
        Ok(handled.then_some(lines))
    }

    /// A tool change after G40: the reference reads the position back
    /// from the machine, so the tool is where the compensated path left it
    /// and later moves start from there. Whether `b` was one.
    fn tool_change_after_off(&mut self, b: &Block) -> bool {
        if !b.m_codes().any(|(m, _)| matches!(m, MCode::ToolChange)) {
            return false;
        }
        let Some(at) = self.after_off.take() else {
            return false;
        };
        let s = self.m.scale();
        for (p, v) in self.m.pos.iter_mut().zip(at) {
            *p = Some(v * s);
        }
        true
    }

    /// A G53 move as the first move after G40 goes to a machine point: it
    /// is written in work coordinates with every axis, when they are all
    /// known (its G53 dropped). Whether it is.
    fn g53_after_off(&self, b: &Block, fates: &mut [Fate]) -> bool {
        let g53 = b.non_modal() == Some(NonModal::MachineCoords)
            && self.prog_pos(&self.m).iter().all(Option::is_some);
        if g53 {
            for (i, w) in b.words.iter().enumerate() {
                if matches!(
                    w.kind,
                    WordKind::G(GCode::NonModal(NonModal::MachineCoords))
                ) {
                    fates[i] = Fate::Drop;
                }
            }
        }
        g53
    }

    /// The first move after G40: from where the compensated path ended to
    /// the programmed point, with every axis (and the program's feed).
    fn after_off_move(
        &mut self,
        motion: MotionMode,
        other_axis_use: bool,
        motion_span: Option<crate::block::BlockSpan>,
    ) -> Result<PlainLine, Problem> {
        if other_axis_use || !matches!(motion, MotionMode::Rapid | MotionMode::Linear) {
            return Err(self.comp_refusal(
                motion_span,
                "E1181",
                "the first move after G40 starts where the compensated path ended and must be G0 or G1 to be lowered",
            ));
        }
        let end = self.prog_pos(&self.m);
        let mut words = vec![(
            b'G',
            if motion == MotionMode::Rapid {
                0.0
            } else {
                1.0
            },
        )];
        for (i, l) in [b'X', b'Y', b'Z'].into_iter().enumerate() {
            if let Some(v) = end[i] {
                words.push((l, v));
            }
        }
        if self.last_f != self.comp_f
            && let Some(f) = self.last_f
        {
            // The feed as the program has it (compensated moves wrote
            // their own).
            words.push((b'F', f));
            self.comp_f = self.last_f;
        }
        self.after_off = None;
        self.cycles.end();
        Ok(words_line(&words))
    }

    fn comp_problem(
        &self,
        span: Option<crate::block::BlockSpan>,
        error: crate::geom::cutter_comp::CompError,
    ) -> Problem {
        Problem {
            span,
            kind: ErrorKind::CutterComp { error },
        }
    }

    /// Writes `released` (plain blocks, feeds on G1/G2/G3) into `lines`;
    /// returns where the tool is after them.
    fn write_released(
        &mut self,
        c: &mut CompPath,
        released: &[Out<MoveTag>],
        lines: &mut Vec<PlainLine>,
        span: Option<crate::block::BlockSpan>,
    ) -> Result<[f64; 3], Problem> {
        let (out, at) = lower::cutter_moves::lower_comp_moves(
            c.plane,
            c.at,
            released,
            lower::cutter_moves::arc_radius_tolerance(self.m.modes.units),
        )
        .map_err(|e| Problem {
            span,
            kind: self.lower_error(e),
        })?;
        for (mut l, (feed, seq)) in out {
            self.released_seqs.push(*seq);
            let feeds = l
                .words
                .first()
                .is_some_and(|w| w.letter == b'G' && w.value != 0.0);
            if feeds
                && *feed != self.comp_f
                && let Some(f) = *feed
            {
                l.words.push(lower::Word {
                    letter: b'F',
                    value: f,
                });
                self.comp_f = Some(f);
            }
            lines.push(l);
        }
        c.at = at;
        Ok(at)
    }

    /// G41/G42/G41.1/G42.1 on block `b`.
    fn comp_on(
        &mut self,
        b: &Block,
        before: &FlatMachine,
        cc: CutterComp,
        span: Option<crate::block::BlockSpan>,
    ) -> Result<(), Problem> {
        let need = |s: &Self, value: &str, option: &str| Problem {
            span,
            kind: ErrorKind::Target(TargetError::TargetNeedsValue {
                target: s.name(),
                what: "cutter radius compensation (computed into the path)".into(),
                value: value.into(),
                option: option.into(),
            }),
        };
        let xz = match self.m.modes.plane {
            Plane::XY => false,
            Plane::XZ => true,
            _ => {
                return Err(Problem {
                    span,
                    kind: ErrorKind::Setup(SetupError::Unsupported {
                        what: "cutter radius compensation outside G17 and G18 is not lowered"
                            .into(),
                    }),
                });
            }
        };
        if self.feed_rewrite || self.m.modes.feed_mode != FeedMode::PerMinute {
            return Err(self.comp_refusal(
                span,
                "E1182",
                "compensated moves are written with feeds per minute; G93/G95 with cutter radius compensation is not lowered",
            ));
        }
        let side = if matches!(cc, CutterComp::Left | CutterComp::DynamicLeft) {
            Side::Left
        } else {
            Side::Right
        };
        let metric = self.m.modes.units == Units::Mm;
        let (radius, orientation) =
            if matches!(cc, CutterComp::DynamicLeft | CutterComp::DynamicRight) {
                let Some(d) = b.value(b'D') else {
                    return Err(need(self, "the tool's diameter", "a D word on G41.1/G42.1"));
                };
                (d / 2.0, b.value(b'L').map_or(0, |l| l.round() as i32))
            } else {
                let t = b
                    .value(b'D')
                    .map(|d| (d + 0.5) as i64)
                    .or(self.m.current_tool());
                let data = t.and_then(|t| match self.m.tools.table.get(&t) {
                    Some(d) => Some((d.diameter, d.orientation.round() as i32)),
                    None if self.standalone_tools => {
                        Some((crate::rules::tools::standalone_diameter(t), 0))
                    }
                    None if self.m.tools.known || t == 0 => Some((0.0, 0)),
                    None => None,
                });
                let Some((diameter, o)) = data else {
                    return Err(need(
                        self,
                        "the tool's diameter",
                        "--tool-table (the tool table of the machine), or --zero-start",
                    ));
                };
                // Machine units to program units as the reference computes it
                // (through millimetres).
                let mm = if self.m.machine_metric {
                    diameter
                } else {
                    diameter / 0.03937007874016
                };
                let v = if metric { mm } else { mm / 25.4 };
                (v / 2.0, o)
            };
        let plane = if xz { Plane::XZ } else { Plane::XY };
        let s = self.m.scale();
        let p = before.pos;
        let (Some(x), Some(y), Some(z)) = (p[0], p[1], p[2]) else {
            return Err(need(
                self,
                "the current position",
                "--start-position (or --zero-start), or an absolute move first",
            ));
        };
        let xyz = [x / s, y / s, z / s];
        let pos = if xz { [xyz[2], xyz[0], xyz[1]] } else { xyz };
        let mut comp = Comp::new(Tolerances::default_for(self.m.modes.units));
        comp.start(side, radius, orientation, xz, pos);
        if self.after_off.is_none() {
            self.comp_f = self.f_before;
        }
        let at = self.after_off.take().unwrap_or(xyz);
        self.comp = Some(Box::new(CompPath { comp, plane, at }));
        Ok(())
    }

    /// The move of block `b` while compensation is on. Returns whether the
    /// block's motion was taken.
    #[allow(clippy::too_many_arguments)]
    fn comp_move(
        &mut self,
        c: &mut CompPath,
        b: &Block,
        motion: MotionMode,
        moves: bool,
        other_axis_use: bool,
        span: Option<crate::block::BlockSpan>,
        lines: &mut Vec<PlainLine>,
    ) -> Result<bool, Problem> {
        let arc = matches!(motion, MotionMode::ArcCw | MotionMode::ArcCcw);
        let ijk_only = !moves
            && (b.value(b'I').is_some() || b.value(b'J').is_some() || b.value(b'K').is_some());
        if other_axis_use
            || (moves || ijk_only)
                && !matches!(motion, MotionMode::Rapid | MotionMode::Linear)
                && !arc
            || b.words
                .iter()
                .any(|w| matches!(w.kind, WordKind::Value) && b"ABCUVW".contains(&w.letter))
        {
            return Err(self.comp_refusal(
                span,
                "E1181",
                "with cutter radius compensation on, only G0, G1, G2 and G3 moves in X Y Z (with an end point) are lowered",
            ));
        }
        // An arc with I J K alone is a full circle back to where it starts.
        if !(moves || arc && ijk_only) {
            return Ok(false);
        }
        if b.units().is_some() && c.comp.holding() {
            return Err(self.comp_refusal(
                span,
                "E1180",
                "G20/G21 while a compensated move is held is not lowered",
            ));
        }
        let e = self.prog_pos(&self.m);
        let (Some(x), Some(y), Some(z)) = (e[0], e[1], e[2]) else {
            return Err(self.comp_refusal(
                span,
                "E1181",
                "the end of a compensated move is not known",
            ));
        };
        let xz = c.plane == Plane::XZ;
        let end = if xz { [z, x, y] } else { [x, y, z] };
        self.comp_seq += 1;
        let feed = (self.last_f, self.comp_seq);
        let mut released = Vec::new();
        let r = if arc {
            let center = match b.value(b'R') {
                Some(r) => ArcCenter::Radius(r),
                None => {
                    let (i, j) = if xz {
                        (b.value(b'K'), b.value(b'I'))
                    } else {
                        (b.value(b'I'), b.value(b'J'))
                    };
                    ArcCenter::Offsets {
                        i: i.unwrap_or(0.0),
                        j: j.unwrap_or(0.0),
                        distance: self.m.modes.arc_distance,
                    }
                }
            };
            let turns = b.value(b'P').map_or(1, |p| p.round() as i32);
            let a = CompArc {
                ccw: motion == MotionMode::ArcCcw,
                center,
                turns,
            };
            c.comp.arc(a, end, feed, &mut released)
        } else {
            c.comp
                .straight(motion == MotionMode::Rapid, end, feed, &mut released)
        };
        r.map_err(|e| self.comp_problem(span, e))?;
        self.cycles.end();
        self.write_released(c, &released, lines, span)?;
        Ok(true)
    }
}
