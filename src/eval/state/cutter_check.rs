//! Cutter radius compensation in the evaluator: the programmed moves of
//! blocks run while G41/G42 is on are handed to [`crate::geom::cutter_comp`], so
//! that a program the reference would refuse (an entry move too short, a
//! concave corner the tool cannot reach, an arc too small for the tool, ...)
//! is refused here too, at the same line. Programs that never turn
//! compensation on do not reach this code.
//!
//! The geometry is followed only while it is known: the tool's radius (from
//! the tool table, `--zero-start`, or G41.1/G42.1's D) and the position in
//! the plane. The position model itself keeps the programmed position,
//! which is what the reference reads missing axis words from.

use crate::diag::{ErrorKind, WarningKind};
use crate::diag::{ExprError, MachineError};
use crate::geom::cutter_comp::{Arc, ArcCenter, Comp, CompError, Out, Side, Tolerances};

use super::Machine;
use crate::codes::{CutterComp, Distance, MotionMode, Plane, Units};
use crate::rules::tools::{ToolData, standalone_diameter};
use crate::settings::Settings;

/// A G70 entered with compensation when the output keeps G41/G42
/// (LinuxCNC): G-code with G41/G42 cannot put LinuxCNC's compensation in
/// the state its G70 leaves it in, so the compensation is turned off in the
/// output before the cycle and the compensated path written as plain moves.
/// That is exact only until the program turns compensation off: a move
/// while it is still on is refused, and the first move after G40 must name
/// X and Z (LinuxCNC reads a missing axis from the programmed point there,
/// the output from where the written path ended).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(in crate::eval) enum Written {
    No,
    /// The cycle's moves are being written; the tool is at `at` (X Y Z).
    Cycle {
        at: [f64; 3],
    },
    /// The cycle is written; compensation is still on in the program.
    After,
    /// G40 came after the cycle; the next move must name X and Z.
    AfterOff,
}

/// Why a move after a written G70 is refused.
const WRITTEN_AFTER: &str = "after a G70 entered with compensation, the output has compensation off (the path was written as plain moves); a move while it is still on in the program cannot be written so: turn it off (G40) right after the G70";
const WRITTEN_AFTER_OFF: &str = "after a G70 entered with compensation, the first move after G40 must be G0 or G1 with X and Z in G90 (LinuxCNC reads a missing axis from the programmed point, the output from where the compensated path ended)";

/// Compensation state of a run, made when a program first turns it on.
#[derive(Debug)]
pub(in crate::eval) struct CompRun {
    comp: Comp<()>,
    /// Whether the geometry is being followed (radius and position known
    /// when compensation was turned on).
    known: bool,
    out: Vec<Out<()>>,
}

fn geom(error: CompError) -> ErrorKind {
    ErrorKind::CutterComp { error }
}

impl Machine {
    /// G41/G42 or G41.1/G42.1 (`g`) on the block with `words`; the block
    /// checks have accepted them. A warning that the path is not checked
    /// goes to `warnings`.
    pub(in crate::eval) fn comp_on(
        &mut self,
        s: &Settings,
        g: CutterComp,
        words: &[(u8, f64)],
        warnings: &mut Vec<WarningKind>,
    ) -> Result<(), ErrorKind> {
        let word = |l: u8| words.iter().rev().find(|w| w.0 == l).map(|w| w.1);
        let side = if g.side() == CutterComp::Left {
            Side::Left
        } else {
            Side::Right
        };
        let xz = self.modal.plane == Plane::XZ;
        let tool = if matches!(g, CutterComp::DynamicLeft | CutterComp::DynamicRight) {
            word(b'd').map(|d| (d / 2.0, word(b'l').map_or(0, |l| l.round() as i32)))
        } else {
            let number = match word(b'd') {
                Some(d) => {
                    let t = ((d + 0.5) as i64) as f64;
                    if !s.tool_table.is_empty()
                        && t != 0.0
                        && !self.tools.table.contains_key(&(t as i64))
                    {
                        return Err(ErrorKind::Expr(ExprError::ToolNotInTable {
                            tool: t as i64,
                        }));
                    }
                    Some(t)
                }
                None => self.tools.current,
            };
            match number.and_then(|t| self.comp_tool(s, t)) {
                Some(data) => {
                    let o = data.orientation.round() as i32;
                    if !xz && o != 0 && o != 9 {
                        let what = if side == Side::Left {
                            "G41 with a lathe tool (orientation 1-8)"
                        } else {
                            "G42 with a lathe tool (orientation 1-8)"
                        };
                        return Err(ErrorKind::Machine(MachineError::CompLatheTool { what }));
                    }
                    Some((self.user_to_program(s, data.diameter) / 2.0, o))
                }
                None => None,
            }
        };
        let pos = self.comp_pos();
        let tol = Tolerances::default_for(self.modal.units);
        let run = self.comp.get_or_insert_with(|| {
            Box::new(CompRun {
                comp: Comp::new(tol),
                known: false,
                out: Vec::new(),
            })
        });
        run.comp.set_tolerances(tol);
        match (tool, pos) {
            (Some((radius, orientation)), Some(pos)) => {
                run.comp.start(side, radius, orientation, xz, pos);
                run.known = true;
            }
            (tool, _) => {
                run.known = false;
                let why = if tool.is_none() {
                    "the tool's diameter is not known (give --tool-table, or --zero-start)"
                } else {
                    "the position is not known (give --start-position, or --zero-start)"
                };
                warnings.push(WarningKind::CompNotChecked { why });
            }
        }
        Ok(())
    }

    /// A tool's data for G41/G42. Under `--zero-start` without a tool
    /// table, tools the program has not set itself have the data of the
    /// standalone interpreter's built-in table (T1-T3 have diameters).
    fn comp_tool(&self, s: &Settings, t: f64) -> Option<ToolData> {
        let n = t.round() as i64;
        if s.zero_start
            && s.tool_table.is_empty()
            && !self.tools.table.contains_key(&n)
            && !self.unknown_tools.contains(&n)
        {
            return Some(ToolData {
                diameter: standalone_diameter(n),
                ..Default::default()
            });
        }
        self.tool(t)
    }

    /// A length from the tool table (machine units) in program units,
    /// computed as the reference does: through millimetres, with the
    /// standalone interpreter's inch factor (the boundary cases of the
    /// entry-move check depend on the last bit).
    fn user_to_program(&self, s: &Settings, v: f64) -> f64 {
        let ext = if s.machine_metric {
            1.0
        } else {
            0.03937007874016
        };
        let mm = v / ext;
        match self.modal.units {
            Units::Mm => mm,
            Units::Inch => mm / 25.4,
        }
    }
}

impl Machine {
    /// Axis indices of the compensation plane's coordinates (a, b, third).
    fn comp_axes(&self) -> [usize; 3] {
        if self.modal.plane == Plane::XZ {
            [2, 0, 1]
        } else {
            [0, 1, 2]
        }
    }

    fn comp_pos(&self) -> Option<[f64; 3]> {
        let [a, b, c] = self.comp_axes();
        let p = |i: usize| self.pos.axes[i].as_ref().ok().copied();
        Some([p(a)?, p(b)?, p(c)?])
    }

    /// G40.
    pub(in crate::eval) fn comp_off(&mut self) -> Result<(), ErrorKind> {
        if self.comp_written == Written::After {
            self.comp_written = Written::AfterOff;
        }
        let Some(run) = self.comp.as_mut() else {
            return Ok(());
        };
        if run.known {
            self.comp_pending = run.comp.off(&mut run.out).map_err(geom)?;
            run.out.clear();
        } else {
            run.comp = Comp::new(Tolerances::default_for(self.modal.units));
        }
        run.known = false;
        Ok(())
    }

    /// The move of a block just applied to the position model (`motion`
    /// is the motion mode).
    pub(in crate::eval) fn comp_move(
        &mut self,
        words: &[(u8, f64)],
        motion: MotionMode,
    ) -> Result<(), ErrorKind> {
        if matches!(self.comp_written, Written::After | Written::AfterOff) {
            self.written_move(words, motion)?;
        }
        if self.modal.cutter_comp == CutterComp::Off {
            if self.comp_pending {
                use MotionMode as M;
                match motion {
                    M::ArcCw | M::ArcCcw => {
                        return Err(ErrorKind::Machine(MachineError::CompArcAfterOff));
                    }
                    M::Rapid | M::Linear | M::Thread | M::RigidTap => self.comp_pending = false,
                    _ => {}
                }
            }
            return Ok(());
        }
        let end = self.comp_pos();
        let xz = self.modal.plane == Plane::XZ;
        let arc_distance = self.modal.arc_distance;
        let Some(run) = self.comp.as_mut().filter(|r| r.known) else {
            return Ok(());
        };
        let Some(end) = end else {
            run.known = false;
            return Ok(());
        };
        let word = |l: u8| words.iter().rev().find(|w| w.0 == l).map(|w| w.1);
        use MotionMode as M;
        let r = match motion {
            // The reference runs a G76 line with compensation on as a
            // compensated straight feed (its threading check is never
            // reached).
            M::Rapid | M::Linear | M::ThreadCycle => {
                run.comp.straight(motion == M::Rapid, end, (), &mut run.out)
            }
            M::ArcCw | M::ArcCcw => {
                let center = match word(b'r') {
                    Some(r) => ArcCenter::Radius(r),
                    None => {
                        let (i, j) = if xz {
                            (word(b'k'), word(b'i'))
                        } else {
                            (word(b'i'), word(b'j'))
                        };
                        ArcCenter::Offsets {
                            i: i.unwrap_or(0.0),
                            j: j.unwrap_or(0.0),
                            distance: arc_distance,
                        }
                    }
                };
                let turns = word(b'p').map_or(1, |p| p.round() as i32);
                let arc = Arc {
                    ccw: motion == M::ArcCcw,
                    center,
                    turns,
                };
                run.comp.arc(arc, end, (), &mut run.out)
            }
            _ => {
                // Other motion is refused with compensation on, or not
                // modelled: stop following the geometry.
                run.known = false;
                Ok(())
            }
        };
        if !matches!(self.comp_written, Written::Cycle { .. }) {
            run.out.clear();
        }
        r.map_err(geom)
    }

    /// With compensation on and its geometry followed: whether it offsets
    /// the moves (a radius above zero). `None` when it is not followed.
    pub(in crate::eval) fn comp_offsets(&self) -> Option<bool> {
        self.comp
            .as_ref()
            .filter(|r| r.known && self.modal.cutter_comp != CutterComp::Off)
            .map(|r| r.comp.is_offsetting())
    }

    /// The tool's position as the compensation reads it (plane
    /// coordinates), when its geometry is followed.
    pub(in crate::eval) fn comp_current(&self) -> Option<[f64; 3]> {
        self.comp
            .as_ref()
            .filter(|r| r.known)
            .map(|r| r.comp.current())
    }

    /// LinuxCNC's G70 put the position the compensation reads at `p`
    /// (plane coordinates) while reading its contour.
    pub(in crate::eval) fn comp_set_current(&mut self, p: [f64; 2]) {
        if let Some(run) = self.comp.as_mut().filter(|r| r.known) {
            run.comp.set_current(p);
        }
    }

    /// Whether the compensation is on, offsetting, and its entry move still
    /// to come.
    pub(in crate::eval) fn comp_entry_next(&self) -> bool {
        self.comp_offsets() == Some(true) && self.comp.as_ref().is_some_and(|r| r.comp.is_first())
    }

    /// The moves the compensation released since the last call (kept only
    /// while a G70's path is written).
    pub(in crate::eval) fn comp_take_out(&mut self) -> Vec<Out<()>> {
        self.comp
            .as_mut()
            .map(|r| std::mem::take(&mut r.out))
            .unwrap_or_default()
    }

    /// Releases the held moves (as G40 or a program end will, the ends
    /// where they are) into the moves [`Machine::comp_take_out`] returns.
    pub(in crate::eval) fn comp_flush(&mut self) -> Result<(), ErrorKind> {
        if let Some(run) = self.comp.as_mut().filter(|r| r.known) {
            run.comp.stop(false, &mut run.out).map_err(geom)?;
        }
        Ok(())
    }

    /// A move after a written G70 (see [`Written`]): refused where the
    /// output would not move as LinuxCNC does.
    fn written_move(&mut self, words: &[(u8, f64)], motion: MotionMode) -> Result<(), ErrorKind> {
        let refuse = |why| Err(ErrorKind::Lathe(crate::diag::LatheError::G70Comp { why }));
        match self.comp_written {
            Written::After => refuse(WRITTEN_AFTER),
            Written::AfterOff => {
                let has = |l: u8| words.iter().any(|w| w.0 == l);
                if self.modal.cutter_comp != CutterComp::Off
                    || self.modal.distance != Distance::Absolute
                    || !has(b'x')
                    || !has(b'z')
                    || !matches!(motion, MotionMode::Rapid | MotionMode::Linear)
                {
                    return refuse(WRITTEN_AFTER_OFF);
                }
                self.comp_written = Written::No;
                Ok(())
            }
            _ => Ok(()),
        }
    }

    /// Whether G53 would move with an offset path (the reference refuses it).
    pub(in crate::eval) fn comp_offsetting(&self) -> bool {
        self.modal.cutter_comp != CutterComp::Off
            && self
                .comp
                .as_ref()
                .is_some_and(|r| r.known && r.comp.is_offsetting())
    }

    /// A program stop (M0, M1, M60) or end (M2, M30): held moves are
    /// released; an end also turns compensation off.
    pub(in crate::eval) fn comp_stop(&mut self, end: bool) -> Result<(), ErrorKind> {
        if end {
            self.comp_pending = false;
            self.comp_written = Written::No;
        }
        let Some(run) = self.comp.as_mut() else {
            return Ok(());
        };
        if run.known {
            run.comp.stop(end, &mut run.out).map_err(geom)?;
            run.out.clear();
        }
        if end {
            run.comp = Comp::new(Tolerances::default_for(self.modal.units));
            run.known = false;
        }
        Ok(())
    }

    /// G20/G21 while compensation state exists.
    pub(in crate::eval) fn comp_units(&mut self, units: Units) {
        if let Some(run) = self.comp.as_mut() {
            run.comp.scale(match units {
                Units::Mm => 25.4,
                Units::Inch => 1.0 / 25.4,
            });
            run.comp.set_tolerances(Tolerances::default_for(units));
        }
    }
}
