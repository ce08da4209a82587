//! What happens to each word of a block on the target: kept, dropped
//! (with a warning where the motion may differ), or refused with the
//! reason, for G codes (G10 by its L form), M codes (M6 by the tool change
//! policy) and value words; and the value words that go with a dropped
//! code.

use crate::block::{
    Block, CutterComp, FeedMode, GCode, LatheMode, MCode, MotionMode, NonModal, PathMode,
    SpindleDir, SpindleMode, ToolLength, Units, Word, WordKind,
};
use crate::controller::profile::{Inches, ToolChange};
use crate::diag::TargetError;
use crate::diag::{ErrorKind, WarningKind};

use super::{Lowering, Problem};

/// What deciding a block's words leaves for writing it.
pub(super) struct Decided {
    /// One per word of the block.
    pub(super) fates: Vec<Fate>,
    /// Words written after the line's own (G43.1 Z for G43, M0 for M6).
    pub(super) extra: Vec<(u8, f64)>,
    /// Lines written after the line.
    pub(super) extra_lines: Vec<Vec<(u8, f64)>>,
    /// Lines written before the line (G43.1 Z: an axis command of its own).
    pub(super) pre_lines: Vec<Vec<(u8, f64)>>,
}

/// What happens to one word of a block.
#[derive(Clone, Copy, PartialEq)]
pub(super) enum Fate {
    Keep,
    Drop,
}

impl Lowering {
    pub(super) fn g_fate(
        &mut self,
        b: &Block,
        w: &Word,
        g: GCode,
        problems: &mut Vec<Problem>,
    ) -> Fate {
        let c = code10(w);
        let p = self.p;
        let refuse = |s: &Self, why: &str| Problem {
            span: Some(w.span),
            kind: s.refuse(g_name(w), why),
        };
        match g {
            GCode::Motion(m) => match m {
                MotionMode::Thread | MotionMode::RigidTap | MotionMode::ThreadCycle
                    if !p.spindle_sync || !p.has_g(c) =>
                {
                    problems.push(refuse(
                        self,
                        "spindle-synchronised motion needs spindle synchronisation, which the target does not have",
                    ));
                    Fate::Drop
                }
                MotionMode::Cycle(_) if !p.has_g(c) => Fate::Drop,
                // Without canned cycles G80 only stops axis words from
                // being used by G10/G28/G92/G43.1 (GRBL's error 31): the
                // source has no cycle running on the target to cancel.
                MotionMode::CancelCycle if !p.has_g(810) => Fate::Drop,
                // Lowered into G1 segments (lower_motion).
                MotionMode::CubicSpline | MotionMode::QuadSpline if !p.has_g(c) => Fate::Drop,
                // Control points collected, the curve lowered at G5.3
                // (lower_nurbs_block).
                MotionMode::Nurbs | MotionMode::NurbsEnd if !p.has_g(c) => Fate::Drop,
                _ if p.has_g(c) => Fate::Keep,
                _ => {
                    problems.push(refuse(self, "the target does not have this motion"));
                    Fate::Drop
                }
            },
            GCode::NonModal(NonModal::SetData) => self.g10_fate(b, w, problems),
            _ if p.has_g(c) => Fate::Keep,
            // Written as G21, every length in millimetres (format.rs).
            GCode::Units(Units::Inch) if p.inches == Inches::ToMm => Fate::Keep,
            // A plane the target has no code for: its arcs are lowered
            // (lower_motion), the code goes.
            GCode::Plane(_) => Fate::Drop,
            // Without work offsets every position is written in machine
            // coordinates (target_shift): the codes that set or pick an
            // offset go, and G53's positions are the target's own.
            GCode::NonModal(
                NonModal::SetG92
                | NonModal::LocalOffset
                | NonModal::ResetG92
                | NonModal::SuspendG92
                | NonModal::RestoreG92
                | NonModal::MachineCoords,
            )
            | GCode::Coord(_)
                if !p.work_offsets =>
            {
                Fate::Drop
            }
            // Applied to the Z positions written (target_shift).
            GCode::ToolLength(_) if p.tool_length_into_z => Fate::Drop,
            // The target's G92 offset is set to the same effective offset
            // after the block (offset_sync); a coordinate system the target
            // lacks is written as coordinates in the one it is in
            // (coord_shift).
            GCode::NonModal(
                NonModal::LocalOffset
                | NonModal::ResetG92
                | NonModal::SuspendG92
                | NonModal::RestoreG92,
            )
            | GCode::Coord(_) => Fate::Drop,
            GCode::Path(PathMode::Blend) | GCode::Path(PathMode::ExactStop) => {
                self.dropped(
                    &g_name(w),
                    "the target has no such path mode; the path may blend differently at corners",
                );
                Fate::Drop
            }
            GCode::Path(PathMode::Exact) => {
                self.dropped(
                    "G61",
                    "the target has no exact-path mode; corners may blend",
                );
                Fate::Drop
            }
            GCode::Lathe(LatheMode::Radius) => Fate::Drop,
            GCode::Lathe(LatheMode::Diameter) => Fate::Drop,
            GCode::SpindleMode(SpindleMode::Rpm) => Fate::Drop,
            GCode::SpindleMode(SpindleMode::ConstantSurface) => {
                problems.push(refuse(
                    self,
                    "constant surface speed needs spindle speed control from the axis position, which the target does not have",
                ));
                Fate::Drop
            }
            GCode::FeedMode(FeedMode::PerMinute) => {
                // G94 after a lowered G95 changes nothing on the target.
                Fate::Drop
            }
            GCode::FeedMode(FeedMode::PerRev) => {
                let s = b.value(b'S').unwrap_or(self.m.modes.speed);
                if s > 0.0 && self.m.modes.spindle_mode == SpindleMode::Rpm {
                    self.feed_rewrite = true;
                    let k = WarningKind::TargetRewritten {
                        target: self.name(),
                        what: "G95 (feed per revolution)".into(),
                        how: "feed per minute at the programmed spindle speed; exact only if the spindle holds that speed".into(),
                    };
                    self.warn(k);
                } else {
                    problems.push(Problem {
                        span: Some(w.span),
                        kind: ErrorKind::Target(TargetError::TargetNeedsValue {
                            target: self.name(),
                            what: "G95 (feed per revolution)".into(),
                            value: "a constant spindle speed".into(),
                            option: "an S word before G95 (and G97)".into(),
                        }),
                    });
                }
                Fate::Drop
            }
            // Arcs are written with offsets from their start (centres.rs).
            GCode::ArcDistance(_) | GCode::Retract(_) => Fate::Drop,
            GCode::ToolLength(ToolLength::Apply | ToolLength::Add) if p.has_g(431) => Fate::Drop,
            GCode::CutterComp(CutterComp::Off) => Fate::Drop,
            // Computed into the path (comp_block).
            GCode::CutterComp(_) => Fate::Drop,
            _ => {
                problems.push(refuse(self, "the target does not have this code"));
                Fate::Drop
            }
        }
    }

    /// G10: kept when the target has its L form and the coordinate system
    /// it writes; tool table writes (L1, L10, L11) and writes to a system
    /// the target lacks are dropped, the model keeps them (G43 and the
    /// coordinate rewriting read them).
    fn g10_fate(&mut self, b: &Block, w: &Word, problems: &mut Vec<Problem>) -> Fate {
        let l = b
            .value(b'L')
            .map_or(0, |l| l.round().clamp(0.0, 255.0) as u8);
        let p = self.p;
        let native = p.has_g(100) && p.g10_l.contains(&l);
        match l {
            1 | 10 | 11 if !native => return Fate::Drop,
            // Offsets the model keeps and target_shift applies.
            2 | 20 if !p.work_offsets && !b.value(b'R').is_some_and(|r| r != 0.0) => {
                return Fate::Drop;
            }
            2 | 20 => {
                if b.value(b'R').is_some_and(|r| r != 0.0) {
                    problems.push(Problem {
                        span: Some(w.span),
                        kind: self.refuse(
                            "G10 L2 R (coordinate system rotation)",
                            "the target has no rotation of the coordinate system",
                        ),
                    });
                    return Fate::Drop;
                }
                if !b.has_axis() {
                    // Nothing changes (GRBL refuses it without an axis
                    // word, error 26).
                    return Fate::Drop;
                }
                // P0 (or none) is the active system, as LinuxCNC has it.
                let k = match b.value(b'P').map(|v| v.round()) {
                    Some(v) if v >= 1.0 => v.min(255.0) as u8,
                    _ => self.m.modes.coord.0,
                };
                if k > p.coord_systems {
                    return Fate::Drop;
                }
            }
            _ => {}
        }
        if native {
            return Fate::Keep;
        }
        problems.push(Problem {
            span: Some(w.span),
            kind: self.refuse(
                format!("G10 L{l}"),
                "the target does not have this form of G10",
            ),
        });
        Fate::Drop
    }

    pub(super) fn m_fate(
        &mut self,
        b: &Block,
        w: &Word,
        m: MCode,
        problems: &mut Vec<Problem>,
        pre_lines: &mut Vec<Vec<(u8, f64)>>,
        extra_lines: &mut Vec<Vec<(u8, f64)>>,
    ) -> Fate {
        let n = w.value.round() as u16;
        let p = self.p;
        if m == MCode::ToolChange {
            let policy = self.opts.tool_change.unwrap_or(p.tool_change);
            if self.m.modes.spindle != SpindleDir::Off {
                // LinuxCNC stops the spindle for the change (and leaves it
                // off), before the block's spindle words and motion. Also
                // where M6 is kept: grblHAL ignores M6 by default, and
                // what FluidNC's does depends on its spindle.
                pre_lines.push(vec![(b'M', 5.0)]);
            }
            return match policy {
                ToolChange::Keep => Fate::Keep,
                ToolChange::Drop => Fate::Drop,
                ToolChange::Refuse => {
                    problems.push(Problem {
                        span: Some(w.span),
                        kind: self.refuse(
                            "M6 (tool change)",
                            "the target can neither change tools nor pause for a manual change (--tool-change drop to go on with the same tool)",
                        ),
                    });
                    Fate::Drop
                }
                ToolChange::Pause => {
                    let tool = b
                        .value(b'T')
                        .map(|t| t.round() as i64)
                        .or(self.m.selected_tool());
                    let what = match tool {
                        Some(t) => format!("M6 (change to tool {t})"),
                        None => "M6 (tool change)".into(),
                    };
                    let k = WarningKind::TargetRewritten {
                        target: self.name(),
                        what,
                        how: format!(
                            "M{}: the program pauses for a manual tool change (--tool-change keep|drop to change that)",
                            p.pause
                        ),
                    };
                    self.warn(k);
                    // The change comes before the block's spindle words,
                    // tool length offset and motion.
                    pre_lines.push(vec![(b'M', f64::from(p.pause))]);
                    Fate::Drop
                }
            };
        }
        if let Some(fate) = self.stop_fate(m, extra_lines) {
            return fate;
        }
        if p.has_m(n) && w.value.fract() == 0.0 {
            return Fate::Keep;
        }
        match m {
            MCode::SetTool | MCode::State(_) => Fate::Drop,
            MCode::End { .. } => {
                // The end of the file ends the program on a target without
                // M2/M30; what LinuxCNC's M2 switches off is switched off
                // on a line of its own.
                if self.m.modes.spindle != SpindleDir::Off && p.has_m(5) {
                    extra_lines.push(vec![(b'M', 5.0)]);
                }
                if (self.m.modes.mist || self.m.modes.flood) && p.has_m(9) {
                    extra_lines.push(vec![(b'M', 9.0)]);
                }
                Fate::Drop
            }
            MCode::Override(_) => {
                self.dropped(
                    &format!("M{n}"),
                    "the target has no such override switch; overrides stay as the operator sets them",
                );
                Fate::Drop
            }
            MCode::PalletPause => {
                extra_lines.push(vec![(b'M', f64::from(p.pause))]);
                Fate::Drop
            }
            MCode::User(_) => {
                problems.push(Problem {
                    span: Some(w.span),
                    kind: self.refuse(
                        format!("M{n}"),
                        "user M-codes (M100-M199) run external programs on a LinuxCNC machine; this controller has none",
                    ),
                });
                Fate::Drop
            }
            MCode::Mist => {
                problems.push(Problem {
                    span: Some(w.span),
                    kind: self.refuse("M7 (mist coolant)", "the target has no mist coolant output"),
                });
                Fate::Drop
            }
            _ => {
                problems.push(Problem {
                    span: Some(w.span),
                    kind: self.refuse(
                        format!("M{}", crate::emit::number_string(w.value, None)),
                        "the target does not have this code",
                    ),
                });
                Fate::Drop
            }
        }
    }

    /// M0, M1, M30 and M9 where the firmware has no such code or reads it
    /// otherwise: its pause code for M0, M1 dropped (or kept where the
    /// firmware reads it and does nothing), M30 as M2, M9 with the coolant
    /// off not written. `None`: the general rules decide.
    fn stop_fate(&mut self, m: MCode, extra_lines: &mut Vec<Vec<(u8, f64)>>) -> Option<Fate> {
        let p = self.p;
        if m == (MCode::Pause { optional: true }) && !p.optional_stop {
            let why = "the program does not pause there, where LinuxCNC stops if its optional-stop switch is on";
            if !p.has_m(1) {
                // Not written where the firmware lacks it (RepRapFirmware
                // ends the job on M1).
                self.dropped("M1 (optional stop)", why);
                return Some(Fate::Drop);
            }
            let k = WarningKind::TargetIgnores {
                target: self.name(),
                what: "M1 (optional stop)".into(),
                why: why.into(),
            };
            self.warn(k);
            return Some(Fate::Keep);
        }
        if m == (MCode::Pause { optional: false }) && p.pause != 0 {
            // The firmware's M0 is no pause (Smoothieware ignores it,
            // RepRapFirmware ends the job): its own pause code, after the
            // block's motion as LinuxCNC stops.
            extra_lines.push(vec![(b'M', f64::from(p.pause))]);
            return Some(Fate::Drop);
        }
        if m == (MCode::End { rewind: true }) && !p.has_m(30) && p.has_m(2) {
            // M30 and M2 end the program alike (the rewind and pallet
            // exchange move nothing); some firmwares read M30 as
            // "delete a file".
            extra_lines.push(vec![(b'M', 2.0)]);
            return Some(Fate::Drop);
        }
        if m == MCode::CoolantOff && !p.has_m(9) && !self.m.modes.mist && !self.m.modes.flood {
            // Coolant that is off staying off: nothing to write.
            return Some(Fate::Drop);
        }
        None
    }

    pub(super) fn value_fate(&mut self, w: &Word, problems: &mut Vec<Problem>) -> Fate {
        let l = w.letter;
        let axis = crate::block::AXIS_LETTERS.contains(&l);
        if axis && !self.p.has_axis(l) {
            problems.push(Problem {
                span: Some(w.span),
                kind: self.refuse(
                    format!("axis word {}", l as char),
                    "the target has no such axis",
                ),
            });
            return Fate::Drop;
        }
        match l {
            b'T' if w.value > self.p.max_tool => return Fate::Drop,
            // Polar words are lowered with their motion (lower_motion).
            b'@' | b'^' => return Fate::Drop,
            _ => {}
        }
        if self.p.has_word(l) {
            return Fate::Keep;
        }
        // Words of codes that are dropped or lowered go with them (see
        // drop_owned); others are refused.
        // T selects a tool, which only M6 acts on (by --tool-change).
        // S sets the speed of a spindle only M3/M4 start, which a target
        // without them refuses.
        let no_spindle = l == b'S' && !self.p.has_m(3) && !self.p.has_m(4);
        let owned = no_spindle
            || matches!(
                l,
                b'Q' | b'H' | b'D' | b'E' | b'P' | b'L' | b'R' | b'T' | b'I' | b'J' | b'K'
            );
        if !owned {
            problems.push(Problem {
                span: Some(w.span),
                kind: self.refuse(
                    format!("the {} word", l as char),
                    "the target does not read it",
                ),
            });
        }
        Fate::Drop
    }

    /// Drops the value words of dropped codes (G64's P and Q, M61's Q,
    /// G43's H, G10 L1's words, P on an arc of one turn).
    pub(super) fn drop_owned(&self, b: &Block, fates: &mut [Fate]) {
        let snapshot = fates.to_vec();
        let dropped_g = |c: u16| {
            b.words.iter().zip(snapshot.iter()).any(|(w, f)| {
                *f == Fate::Drop && matches!(w.kind, WordKind::G(_)) && code10(w) == c
            })
        };
        let mut drop = |letter: u8| {
            for (i, w) in b.words.iter().enumerate() {
                if w.letter == letter && matches!(w.kind, WordKind::Value) {
                    fates[i] = Fate::Drop;
                }
            }
        };
        if dropped_g(640) {
            drop(b'P');
            drop(b'Q');
        }
        if b.m_codes().any(|(m, _)| m == MCode::SetTool) && !self.p.has_m(61) {
            drop(b'Q');
        }
        if dropped_g(430) || dropped_g(432) {
            drop(b'H');
        }
        if dropped_g(100) {
            for l in *b"LPRXYZABCUVWIJQ" {
                drop(l);
            }
        }
        // G92's and G43.1's axis words go with them (the offsets are
        // applied to the positions written).
        if dropped_g(520) || dropped_g(920) || dropped_g(431) {
            for l in *b"XYZABCUVW" {
                drop(l);
            }
        }
        let arc = matches!(b.motion(), Some(MotionMode::ArcCw | MotionMode::ArcCcw))
            || b.motion().is_none()
                && matches!(self.m.modes.motion, MotionMode::ArcCw | MotionMode::ArcCcw)
                && b.has_axis();
        if arc && b.value(b'P') == Some(1.0) {
            drop(b'P');
        }
    }
}

/// G number ×10 of a word.
pub(super) fn code10(w: &Word) -> u16 {
    (w.value * 10.0).round().clamp(0.0, 60000.0) as u16
}

fn g_name(w: &Word) -> String {
    let c = code10(w);
    if c.is_multiple_of(10) {
        format!("G{}", c / 10)
    } else {
        format!("G{}.{}", c / 10, c % 10)
    }
}

pub(super) fn g_span(b: &Block, a: u16, c: u16) -> Option<crate::block::BlockSpan> {
    b.words
        .iter()
        .find(|w| matches!(w.kind, WordKind::G(_)) && (code10(w) == a || code10(w) == c))
        .map(|w| w.span)
}
