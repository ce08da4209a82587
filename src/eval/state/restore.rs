//! M70–M73: saving modal state and bringing it back with explicit words,
//! since the controllers ngcflat writes for do not know these codes.

use std::rc::Rc;

use crate::diag::{Error, ErrorKind};
use crate::parse::ast::Span;
use crate::program::FileIndex;

use super::Env;
use crate::codes::{CutterComp, GCode, SpindleDir, SpindleMode};
use crate::eval::Interp;
use crate::modes::Modes;

/// The state M70 or M73 saves: the modal state, and whether G92 offsets
/// were applied (M72 turns them on or off again).
#[derive(Clone)]
pub(crate) struct Saved {
    pub modal: Modes,
    pub g92_applied: bool,
}

impl Interp<'_> {
    /// M70 save, M71 invalidate, M72 restore, M73 save and restore on return.
    pub(in crate::eval) fn context_op(
        &mut self,
        op: u8,
        file: &Rc<FileIndex>,
        start: u32,
        span: Span,
    ) -> Result<(), Error> {
        match op {
            70 | 73 => {
                let m = Saved {
                    modal: self.mach.modal.clone(),
                    g92_applied: self.params.g92_applied(),
                };
                let nested = self.flow.frames.len() > 1;
                let f = self.flow.frames.last_mut().expect("frame");
                f.saved_modal = Some(Box::new(m));
                f.auto_restore = op == 73 && nested;
            }
            71 => {
                let f = self.flow.frames.last_mut().expect("frame");
                f.saved_modal = None;
                f.auto_restore = false;
            }
            _ => {
                let saved = self
                    .flow
                    .frames
                    .last()
                    .and_then(|f| f.saved_modal.as_deref().cloned());
                match saved {
                    Some(m) => self.restore_modal(&m)?,
                    None => {
                        return Err(self.error_in_line(
                            ErrorKind::NoSavedContext,
                            file,
                            start,
                            span,
                        ));
                    }
                }
            }
        }
        Ok(())
    }

    /// Writes the words that bring the machine from the current state to
    /// `saved`, and adopts it, moving the position model as those words do.
    /// Writes nothing if nothing changed.
    pub(in crate::eval) fn restore_modal(&mut self, saved: &Saved) -> Result<(), Error> {
        let Saved {
            modal: saved,
            g92_applied,
        } = saved;
        let cur = self.mach.modal.clone();
        // Units come first, on their own line, as in the reference.
        if cur.units != saved.units {
            self.emit_raw(GCode::Units(saved.units).name().as_bytes())?;
        }
        let mut words: Vec<String> = Vec::new();
        if cur.plane != saved.plane {
            words.push(GCode::Plane(saved.plane).name());
        }
        if cur.cutter_comp != saved.cutter_comp && saved.cutter_comp == CutterComp::Off {
            words.push("G40".into());
        }
        if cur.distance != saved.distance {
            words.push(GCode::Distance(saved.distance).name());
        }
        if cur.arc_distance != saved.arc_distance {
            words.push(GCode::ArcDistance(saved.arc_distance).name());
        }
        if cur.feed_mode != saved.feed_mode {
            words.push(GCode::FeedMode(saved.feed_mode).name());
        }
        if cur.coord != saved.coord {
            words.push(GCode::Coord(saved.coord).name());
        }
        let tool_offset = saved.tool_length.in_effect();
        if cur.tool_length.in_effect() != tool_offset {
            // G43 takes the current tool's offset, as the reference restores.
            words.push(if tool_offset { "G43" } else { "G49" }.into());
        }
        if cur.retract != saved.retract {
            words.push(GCode::Retract(saved.retract).name());
        }
        if cur.spindle_mode != saved.spindle_mode && saved.spindle_mode == SpindleMode::Rpm {
            words.push(GCode::SpindleMode(SpindleMode::Rpm).name());
        }
        if cur.path != saved.path {
            // The reference restores G64 without its P and Q.
            words.push(GCode::Path(saved.path).name());
        }
        let number = |v: f64, p| {
            let mut b = Vec::new();
            crate::emit::write_number(&mut b, v, p);
            String::from_utf8_lossy(&b).into_owned()
        };
        if cur.feed != saved.feed {
            words.push(format!("F{}", number(saved.feed, self.s.precision)));
        }
        if cur.speed != saved.speed {
            words.push(format!("S{}", number(saved.speed, self.s.precision)));
        }
        if cur.spindle != saved.spindle {
            words.push(
                match saved.spindle {
                    SpindleDir::Cw => "M3",
                    SpindleDir::Ccw => "M4",
                    SpindleDir::Off => "M5",
                }
                .into(),
            );
        }
        if !words.is_empty() {
            let line = words.join(" ");
            self.emit_raw(line.as_bytes())?;
        }
        let g92_now = self.params.g92_applied();
        if *g92_applied != g92_now {
            self.emit_raw(if *g92_applied { b"G92.3" } else { b"G92.2" })?;
        }
        // The position model follows what those words do.
        let line = self.reader.line_idx + 1;
        let mut env = Env {
            s: self.s,
            params: &mut self.params,
            line,
        };
        self.mach.set_units(line, saved.units);
        if cur.coord != saved.coord {
            self.mach.select_cs(&mut env, saved.coord);
        }
        if cur.tool_length.in_effect() != tool_offset {
            self.mach.tool_offset_words(&env, tool_offset);
        }
        if *g92_applied != g92_now {
            self.mach.g92_switch(&mut env, *g92_applied);
        }
        // Coolant: turn on what was on; M9 only when both were off.
        if saved.mist && !cur.mist {
            self.emit_raw(b"M7")?;
        }
        if saved.flood && !cur.flood {
            self.emit_raw(b"M8")?;
        }
        if !saved.mist && !saved.flood && (cur.mist || cur.flood) {
            self.emit_raw(b"M9")?;
        }
        let motion = self.mach.modal.motion;
        let (mist, flood) = (
            self.mach.modal.mist || saved.mist,
            self.mach.modal.flood || saved.flood,
        );
        let both_off = !saved.mist && !saved.flood;
        self.mach.modal = saved.clone();
        self.mach.modal.motion = motion;
        if !both_off {
            self.mach.modal.mist = mist;
            self.mach.modal.flood = flood;
        }
        Ok(())
    }
}
