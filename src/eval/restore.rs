//! M70–M73: saving modal state and bringing it back with explicit words,
//! since the controllers ngcflat writes for do not know these codes.

use crate::diag::Error;

use super::Interp;
use super::state::Modal;

impl Interp<'_> {
    /// Writes the words that bring the machine from the current state to
    /// `saved`, and adopts it. Writes nothing if nothing changed.
    pub(super) fn restore_modal(&mut self, saved: &Modal) -> Result<(), Error> {
        let cur = self.modal.clone();
        let mut words: Vec<String> = Vec::new();
        if cur.metric != saved.metric {
            words.push(if saved.metric {
                "G21".into()
            } else {
                "G20".into()
            });
        }
        if cur.plane != saved.plane {
            words.push(gcode(saved.plane));
        }
        if cur.ccomp != saved.ccomp && saved.ccomp == 400 {
            words.push("G40".into());
        }
        if cur.absolute != saved.absolute {
            words.push(if saved.absolute {
                "G90".into()
            } else {
                "G91".into()
            });
        }
        if cur.ijk_absolute != saved.ijk_absolute {
            words.push(if saved.ijk_absolute {
                "G90.1".into()
            } else {
                "G91.1".into()
            });
        }
        if cur.feed_mode != saved.feed_mode {
            words.push(gcode(saved.feed_mode));
        }
        if cur.coord_index != saved.coord_index {
            words.push(match saved.coord_index {
                7 => "G59.1".into(),
                8 => "G59.2".into(),
                9 => "G59.3".into(),
                n => format!("G{}", 53 + n),
            });
        }
        if cur.retract_r != saved.retract_r {
            words.push(if saved.retract_r {
                "G99".into()
            } else {
                "G98".into()
            });
        }
        if cur.css != saved.css {
            words.push(if saved.css {
                "G96".into()
            } else {
                "G97".into()
            });
        }
        if cur.path != saved.path {
            words.push(gcode(saved.path));
        }
        if cur.feed != saved.feed {
            let mut b = Vec::new();
            crate::emit::write_number(&mut b, saved.feed, self.s.precision);
            words.push(format!("F{}", String::from_utf8_lossy(&b)));
        }
        if cur.speed != saved.speed {
            let mut b = Vec::new();
            crate::emit::write_number(&mut b, saved.speed, self.s.precision);
            words.push(format!("S{}", String::from_utf8_lossy(&b)));
        }
        if cur.spindle != saved.spindle {
            words.push(format!(
                "M{}",
                if saved.spindle == 0 { 5 } else { saved.spindle }
            ));
        }
        if cur.mist != saved.mist || cur.flood != saved.flood {
            if !saved.mist && !saved.flood {
                words.push("M9".into());
            } else {
                if cur.mist || cur.flood {
                    words.push("M9".into());
                }
                if saved.mist {
                    words.push("M7".into());
                }
                if saved.flood {
                    words.push("M8".into());
                }
            }
        }
        if !words.is_empty() {
            let line = words.join(" ");
            self.emit_raw(line.as_bytes())?;
        }
        let motion = self.modal.motion;
        self.modal = saved.clone();
        self.modal.motion = motion;
        Ok(())
    }
}

fn gcode(g10: i32) -> String {
    if g10 % 10 == 0 {
        format!("G{}", g10 / 10)
    } else {
        format!("G{}.{}", g10 / 10, g10 % 10)
    }
}
