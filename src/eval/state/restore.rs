//! M70–M73: saving modal state and bringing it back with explicit words,
//! since the controllers ngcflat writes for do not know these codes.

use super::{Env, Machine};
use crate::codes::{CutterComp, GCode, SpindleDir, SpindleMode};
use crate::eval::expr::params::Params;
use crate::rules::Modes;

/// The state M70 or M73 saves: the modal state, and whether G92 offsets
/// were applied (M72 turns them on or off again).
#[derive(Clone)]
pub(crate) struct Saved {
    pub modal: Modes,
    pub g92_applied: bool,
}

/// The lines that bring the machine back to a saved state: those written
/// before the position model follows them, then the coolant's.
pub(in crate::eval) struct RestoreLines {
    pub(in crate::eval) before: Vec<String>,
    pub(in crate::eval) coolant: Vec<&'static [u8]>,
}

impl Machine {
    /// What M70 or M73 saves (`params`: whether the G92 offsets apply).
    pub(in crate::eval) fn save(&self, params: &Params) -> Saved {
        Saved {
            modal: self.modal.clone(),
            g92_applied: params.g92_applied(),
        }
    }

    /// The lines that bring the machine from the current state to `saved`
    /// (`g92_now`: whether the G92 offsets apply now; `precision`: of the
    /// numbers written); none where nothing changed.
    pub(in crate::eval) fn restore_lines(
        &self,
        saved: &Saved,
        g92_now: bool,
        precision: Option<u8>,
    ) -> RestoreLines {
        let Saved {
            modal: saved,
            g92_applied,
        } = saved;
        let cur = &self.modal;
        let mut before = Vec::new();
        // Units come first, on their own line, as in the reference.
        if cur.units != saved.units {
            before.push(GCode::Units(saved.units).name());
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
            words.push(format!("F{}", number(saved.feed, precision)));
        }
        if cur.speed != saved.speed {
            words.push(format!("S{}", number(saved.speed, precision)));
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
            before.push(words.join(" "));
        }
        if *g92_applied != g92_now {
            before.push(if *g92_applied { "G92.3" } else { "G92.2" }.into());
        }
        // Coolant: turn on what was on; M9 only when both were off.
        let mut coolant: Vec<&'static [u8]> = Vec::new();
        if saved.mist && !cur.mist {
            coolant.push(b"M7");
        }
        if saved.flood && !cur.flood {
            coolant.push(b"M8");
        }
        if !saved.mist && !saved.flood && (cur.mist || cur.flood) {
            coolant.push(b"M9");
        }
        RestoreLines { before, coolant }
    }

    /// The position model follows what the lines of
    /// [`Machine::restore_lines`] do to the units, the coordinate system,
    /// the tool length offset and the G92 offsets (`g92_now`: whether
    /// those apply now).
    pub(in crate::eval) fn restore_offsets(
        &mut self,
        env: &mut Env<'_>,
        saved: &Saved,
        g92_now: bool,
    ) {
        let Saved {
            modal: saved,
            g92_applied,
        } = saved;
        let (coord, tool_offset) = (self.modal.coord, self.modal.tool_length.in_effect());
        self.set_units(env.line, saved.units);
        if coord != saved.coord {
            self.select_cs(env, saved.coord);
        }
        if tool_offset != saved.tool_length.in_effect() {
            self.tool_offset_words(env, saved.tool_length.in_effect());
        }
        if *g92_applied != g92_now {
            self.g92_switch(env, *g92_applied);
        }
    }

    /// Adopts the saved modes (but the motion mode; a coolant the saved
    /// state had off stays on, unless both were off).
    pub(in crate::eval) fn restore_modes(&mut self, saved: &Saved) {
        let saved = &saved.modal;
        let motion = self.modal.motion;
        let (mist, flood) = (
            self.modal.mist || saved.mist,
            self.modal.flood || saved.flood,
        );
        let both_off = !saved.mist && !saved.flood;
        self.modal = saved.clone();
        self.modal.motion = motion;
        if !both_off {
            self.modal.mist = mist;
            self.modal.flood = flood;
        }
    }
}
