//! Updates of the state model from the words of an executed line.

use std::rc::Rc;

use crate::diag::Error;
use crate::program::FileIndex;

use super::Interp;
use super::block::Words;
use super::state::Unknown;

const LINEAR: [bool; 9] = [true, true, true, false, false, false, true, true, true];

fn axis_index(letter: u8) -> Option<usize> {
    super::state::AXES.iter().position(|&c| c == letter)
}

impl Interp<'_> {
    fn line_no(&self) -> u32 {
        self.current_line_idx + 1
    }

    fn forget(&mut self, axes: &[usize], what: &'static str) {
        let line = self.line_no();
        for &a in axes {
            self.pos.axes[a] = Err(Unknown::After(what, line));
        }
    }

    /// G5x offset of coordinate system `cs` (1–9) on an axis, if known.
    fn g5x_offset(&self, cs: i32, axis: usize) -> Option<f64> {
        let i = 5221 + 20 * (cs as usize - 1) + axis;
        self.params.known[i].then(|| self.params.values[i])
    }

    fn g92_offset(&self, axis: usize) -> Option<f64> {
        let i = 5211 + axis;
        if self.params.known[5210] && self.params.values[5210] == 0.0 {
            return Some(0.0);
        }
        self.params.known[i].then(|| self.params.values[i])
    }

    /// Applies the line's words to the model. Returns true when the line ends
    /// the program.
    pub(super) fn apply_words(
        &mut self,
        _file: &Rc<FileIndex>,
        _start: u32,
        words: &Words,
        m99: bool,
    ) -> Result<bool, Error> {
        let mut gs: Vec<i32> = Vec::new();
        let mut ends = m99;
        let mut axis_words: Vec<(usize, f64)> = Vec::new();
        let mut p_word = None;
        let mut l_word = None;
        let mut r_word = None;
        for &(l, v) in words {
            match l {
                b'g' => gs.push((v * 10.0).round() as i32),
                b'f' => self.modal.feed = v,
                b's' => self.modal.speed = v,
                b't' => self.selected_tool = Some(v),
                b'p' => p_word = Some(v),
                b'l' => l_word = Some(v),
                b'r' => r_word = Some(v),
                b'm' => {
                    let m = (v * 10.0).round() as i32;
                    match m {
                        20 | 300 => ends = true,
                        30 => self.modal.spindle = 3,
                        40 => self.modal.spindle = 4,
                        50 => self.modal.spindle = 0,
                        60 => self.current_tool = self.selected_tool,
                        70 => self.modal.mist = true,
                        80 => self.modal.flood = true,
                        90 => {
                            self.modal.mist = false;
                            self.modal.flood = false;
                        }
                        480 => {
                            self.modal.speed_override = true;
                            self.modal.feed_override = true;
                        }
                        490 => {
                            self.modal.speed_override = false;
                            self.modal.feed_override = false;
                        }
                        500 => self.modal.feed_override = p_word.is_none_or(|p| p != 0.0),
                        510 => self.modal.speed_override = p_word.is_none_or(|p| p != 0.0),
                        520 => self.modal.adaptive_feed = p_word.is_none_or(|p| p != 0.0),
                        530 => self.modal.feed_hold = p_word.is_none_or(|p| p != 0.0),
                        _ => {}
                    }
                }
                _ => {
                    if let Some(a) = axis_index(l) {
                        axis_words.push((a, v));
                    }
                }
            }
        }
        // P words after M50.. on the same line: apply in a second pass.
        for &(l, v) in words {
            if l == b'm' {
                let m = (v * 10.0).round() as i32;
                let on = p_word.is_none_or(|p| p != 0.0);
                match m {
                    500 => self.modal.feed_override = on,
                    510 => self.modal.speed_override = on,
                    520 => self.modal.adaptive_feed = on,
                    530 => self.modal.feed_hold = on,
                    _ => {}
                }
            }
        }
        let mut special = None;
        for &g in &gs {
            match g {
                0
                | 10
                | 20
                | 30
                | 50
                | 51
                | 52
                | 330
                | 331
                | 382..=385
                | 730
                | 740
                | 760
                | 810..=890 => self.modal.motion = g,
                800 => self.modal.motion = 800,
                170 | 180 | 190 | 171 | 181 | 191 => self.modal.plane = g,
                200 => self.set_units(false),
                210 => self.set_units(true),
                900 => self.modal.absolute = true,
                910 => self.modal.absolute = false,
                901 => self.modal.ijk_absolute = true,
                911 => self.modal.ijk_absolute = false,
                930 | 940 | 950 => self.modal.feed_mode = g,
                400 => self.modal.ccomp = 400,
                410 | 411 => self.modal.ccomp = 410,
                420 | 421 => self.modal.ccomp = 420,
                430..=432 => {
                    self.modal.tool_offset = true;
                    self.forget(&[0, 1, 2, 3, 4, 5, 6, 7, 8], "a tool length offset (G43)");
                }
                490 => {
                    if self.modal.tool_offset {
                        self.forget(
                            &[0, 1, 2, 3, 4, 5, 6, 7, 8],
                            "cancelling the tool length offset (G49)",
                        );
                    }
                    self.modal.tool_offset = false;
                }
                610 | 611 | 640 => {
                    self.modal.path = g;
                }
                980 => self.modal.retract_r = false,
                990 => self.modal.retract_r = true,
                960 => self.modal.css = true,
                970 => self.modal.css = false,
                70 => self.modal.lathe_diameter = true,
                80 => self.modal.lathe_diameter = false,
                540 | 550 | 560 | 570 | 580 | 590 | 591 | 592 | 593 => {
                    let cs = match g {
                        591 => 7,
                        592 => 8,
                        593 => 9,
                        _ => (g - 530) / 10,
                    };
                    self.select_cs(cs);
                }
                100 | 280 | 281 | 300 | 301 | 530 | 920 | 921 | 922 | 923 | 520 => {
                    special = Some(g)
                }
                _ => {}
            }
        }
        let line = self.line_no();
        match special {
            Some(920) => {
                for &(a, v) in &axis_words {
                    // The position becomes the given value; the offset
                    // becomes known only if the position was.
                    let old = self.pos.axes[a].clone();
                    let old_off = self.g92_offset(a);
                    match (old, old_off) {
                        (Ok(p), Some(o)) => self.params.assign(5211 + a, p + o - v),
                        _ => self.params.known[5211 + a] = false,
                    }
                    self.pos.axes[a] = Ok(v);
                }
                self.params.assign(5210, 1.0);
            }
            Some(921) | Some(922) => {
                for a in 0..9 {
                    let off = self.g92_offset(a);
                    match (&self.pos.axes[a], off) {
                        (Ok(p), Some(o)) => self.pos.axes[a] = Ok(p + o),
                        _ => self.pos.axes[a] = Err(Unknown::After("G92.1/G92.2", line)),
                    }
                }
                if special == Some(921) {
                    for a in 0..9 {
                        self.params.assign(5211 + a, 0.0);
                    }
                }
                self.params.assign(5210, 0.0);
            }
            Some(923) => self.forget(&[0, 1, 2, 3, 4, 5, 6, 7, 8], "G92.3"),
            Some(100) => self.g10(l_word, p_word, r_word, &axis_words),
            Some(280) | Some(300) => {
                let axes: Vec<usize> = if axis_words.is_empty() {
                    (0..9).collect()
                } else {
                    axis_words.iter().map(|a| a.0).collect()
                };
                self.forget(&axes, "G28/G30 (moves to a home position)");
            }
            Some(530) => {
                let axes: Vec<usize> = axis_words.iter().map(|a| a.0).collect();
                self.forget(&axes, "a G53 machine-coordinate move");
            }
            Some(_) => {}
            None => {
                if !axis_words.is_empty() {
                    self.move_to(&axis_words);
                }
            }
        }
        if ends {
            self.modal.reset_at_end();
        }
        Ok(ends)
    }

    fn set_units(&mut self, metric: bool) {
        if self.modal.metric == metric {
            return;
        }
        let f = if metric { 25.4 } else { 1.0 / 25.4 };
        for (a, lin) in LINEAR.iter().enumerate() {
            if *lin && let Ok(p) = &mut self.pos.axes[a] {
                *p *= f;
            }
        }
        self.modal.metric = metric;
    }

    fn select_cs(&mut self, cs: i32) {
        let old = self.modal.coord_index;
        if old != cs {
            let line = self.line_no();
            for a in 0..9 {
                let (o, n) = (self.g5x_offset(old, a), self.g5x_offset(cs, a));
                match (&self.pos.axes[a], o, n) {
                    (Ok(p), Some(o), Some(n)) => self.pos.axes[a] = Ok(p + o - n),
                    _ => self.pos.axes[a] = Err(Unknown::After("a coordinate system change", line)),
                }
            }
        }
        self.modal.coord_index = cs;
        self.params.assign(5220, cs as f64);
    }

    fn g10(&mut self, l: Option<f64>, p: Option<f64>, r: Option<f64>, axis_words: &[(usize, f64)]) {
        let l = l.map(|v| v.round() as i32);
        let cs = match p.map(|v| v.round() as i32) {
            Some(0) | None => self.modal.coord_index,
            Some(n) => n.clamp(1, 9),
        };
        let base = 5221 + 20 * (cs as usize - 1);
        let line = self.line_no();
        match l {
            Some(2) => {
                for &(a, v) in axis_words {
                    let old = self.g5x_offset(cs, a);
                    if cs == self.modal.coord_index {
                        match (&self.pos.axes[a], old) {
                            (Ok(pos), Some(o)) => self.pos.axes[a] = Ok(pos + o - v),
                            _ => self.pos.axes[a] = Err(Unknown::After("G10 L2", line)),
                        }
                    }
                    self.params.assign(base + a, v);
                }
                if let Some(r) = r {
                    self.params.assign(base + 9, r);
                }
            }
            Some(20) => {
                for &(a, v) in axis_words {
                    let old = self.g5x_offset(cs, a);
                    if cs == self.modal.coord_index {
                        match (&self.pos.axes[a], old) {
                            (Ok(pos), Some(o)) => self.params.assign(base + a, pos + o - v),
                            _ => self.params.known[base + a] = false,
                        }
                        self.pos.axes[a] = Ok(v);
                    } else {
                        self.params.known[base + a] = false;
                    }
                }
            }
            _ => {
                // Tool table changes (L1, L10, L11) do not move anything.
            }
        }
    }

    fn move_to(&mut self, axis_words: &[(usize, f64)]) {
        let line = self.line_no();
        let motion = self.modal.motion;
        match motion {
            382..=385 => {
                self.forget(&[0, 1, 2, 3, 4, 5, 6, 7, 8], "a probing move");
                for i in 5061..=5070 {
                    self.params.known[i] = self.s.zero_start;
                }
            }
            730 | 740 | 760 | 810..=890 | 330 | 331 => {
                // Canned cycles and threading end at positions that depend on
                // retract rules and machine state.
                let axes: Vec<usize> = axis_words.iter().map(|a| a.0).collect();
                self.forget(&axes, "a canned cycle or threading move");
                if motion != 330 && motion != 331 {
                    self.forget(&[2], "a canned cycle");
                }
            }
            _ => {
                if self.modal.ccomp != 400 {
                    self.forget(&[0, 1, 2], "cutter radius compensation");
                    return;
                }
                for &(a, v) in axis_words {
                    if self.modal.absolute {
                        self.pos.axes[a] = Ok(v);
                    } else if let Ok(p) = &mut self.pos.axes[a] {
                        *p += v;
                    }
                }
                let _ = line;
            }
        }
    }
}
