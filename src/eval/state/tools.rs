//! The evaluator's steps with the tools: T, M6, M61 and tool data as the
//! evaluator's machine model takes them; the tools themselves and their
//! steps are [`crate::rules::tools`]'s, which the model after evaluation
//! keeps too.

use super::{Env, Machine, Unknown};
use crate::codes::CoordSystem;
use crate::rules::offsets;
use crate::rules::tools::ToolData;
use crate::settings::Settings;

impl Machine {
    /// Data of a tool, if the program can know it.
    pub(in crate::eval) fn tool(&self, t: f64) -> Option<ToolData> {
        let t = t.round() as i64;
        if self.unknown_tools.contains(&t) {
            return None;
        }
        self.tools.data(t)
    }

    /// A tool-data parameter #5400..#5413.
    pub(in crate::eval) fn tool_param(&self, i: usize) -> Option<f64> {
        let current = self.tools.current?;
        if i == 5400 {
            return Some(current);
        }
        let d = self.tool(current)?;
        Some(match i {
            5401..=5409 => d.offsets[i - 5401],
            5410 => d.diameter,
            5411 => d.front,
            5412 => d.back,
            _ => d.orientation,
        })
    }

    /// Applies a new tool length offset (machine units), moving the
    /// program position the other way (`what` on `line`: why it becomes
    /// unknown where it does).
    pub(in crate::eval) fn set_tlo(
        &mut self,
        s: &Settings,
        line: u32,
        new: Option<[f64; 9]>,
        what: &'static str,
    ) {
        for a in 0..9 {
            let f = self.to_prog(s, a);
            let ok = match (&self.pos.axes[a], self.tlo, new) {
                (Ok(p), Some(old), Some(n)) => Some(p + (old[a] - n[a]) * f),
                _ => None,
            };
            self.pos.axes[a] = ok.ok_or(Unknown::After(what, line));
        }
        for a in 0..9 {
            if new.map(|n| n[a]) != self.tlo.map(|t| t[a]) {
                self.tlo_moved |= 1 << a;
            }
        }
        self.tlo = new;
    }

    /// G10 L1/L10/L11: the program writes the tool table.
    pub(in crate::eval) fn g10_tool(
        &mut self,
        env: &Env<'_>,
        l: i32,
        p: Option<f64>,
        r: Option<f64>,
        words: &[(u8, f64)],
        axis_words: &[(usize, f64)],
    ) {
        let Some(t) = p.map(|v| v.round() as i64) else {
            return;
        };
        let mut d = self.tool(t as f64);
        for &(a, v) in axis_words {
            let f = self.to_prog(env.s, a);
            let value = match l {
                1 => Some(v),
                10 => self.pos.axes[a]
                    .as_ref()
                    .ok()
                    .zip(self.tlo)
                    .map(|(pos, tlo)| offsets::tool_offset_l10(*pos, tlo[a] * f, v)),
                _ => {
                    // L11: relative to G59.3 instead of the current system.
                    let cur = self.modal.coord;
                    let params = &*env.params;
                    let g5x = |cs: CoordSystem| {
                        params.known[cs.parameters() + a]
                            .then(|| params.values[cs.parameters() + a] * f)
                    };
                    let g92 = if params.values[5210] == 0.0 {
                        Some(0.0)
                    } else {
                        params.known[5211 + a].then(|| params.values[5211 + a] * f)
                    };
                    match (
                        self.pos.axes[a].as_ref().ok(),
                        self.tlo,
                        g5x(cur),
                        g5x(CoordSystem(9)),
                        g92,
                    ) {
                        (Some(pos), Some(tlo), Some(oc), Some(o9), Some(g)) => {
                            Some(offsets::tool_offset_l11(*pos, tlo[a] * f, oc, g, o9, v))
                        }
                        _ => None,
                    }
                }
            };
            match (value, d.as_mut()) {
                (Some(v), Some(data)) => data.offsets[a] = v / f,
                _ => d = None,
            }
        }
        for &(l, v) in words {
            if let Some(data) = d.as_mut() {
                match l {
                    b'i' => data.front = v,
                    b'j' => data.back = v,
                    b'q' => data.orientation = v,
                    _ => {}
                }
            }
        }
        if let (Some(r), Some(data)) = (r, d.as_mut()) {
            data.diameter = 2.0 * r / self.to_prog(env.s, 0);
        }
        match d {
            Some(data) => {
                self.tools.table.insert(t, data);
            }
            None => {
                self.tools.table.remove(&t);
                self.unknown_tools.insert(t);
            }
        }
    }
}

impl Machine {
    /// How to make the tool data of the tool in the spindle known.
    pub(in crate::eval) fn tool_data_hint(&self) -> String {
        if self.tools.current.is_none() {
            "--tool-table FILE (LinuxCNC's tool table; the spindle then starts with tool 0 until an M6 or M61), or --zero-start".into()
        } else {
            "--tool-table FILE (LinuxCNC's tool table), or --zero-start".into()
        }
    }
}
