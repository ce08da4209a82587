//! Updates of the state model from the words of an executed line.

use crate::diag::{BlockError, ErrorKind, WarningKind};
use crate::diag::{ExprError, MachineError};

use super::arc::arc_refusal;
use super::checked::{Checked, LineCodes};
use super::nurbs::{NO_MOTION, NURBS};
use super::{AXES, Env, Machine, Unknown};
use crate::codes::{
    CoordSystem, CutterComp, Distance, GCode, MCode, MotionMode, NonModal, Plane, ToolLength, Units,
};
use crate::eval::expr::params::Params;
use crate::rules::offsets::{self, LINEAR};
use crate::rules::{MachineCode, polar_end, probe_end};
use crate::settings::Settings;

/// A motion code other than G80 (which gives way to one on its line).
#[inline]
fn is_moving_code(g: GCode) -> bool {
    matches!(g, GCode::Motion(m) if m != MotionMode::CancelCycle)
}

fn axis_index(letter: u8) -> Option<usize> {
    AXES.iter().position(|&c| c == letter)
}

/// How a line the general update ran ends (see [`Machine::end_line`]).
#[derive(Clone, Copy)]
pub(in crate::eval) struct LineEnd {
    /// The line ends the program.
    pub(in crate::eval) ends: bool,
    /// The line stops the program (M0, M1, M60) or ends it while
    /// compensation state exists.
    stops: bool,
}

impl Machine {
    /// The positions of `axes` become unknown after `what` on `line`.
    pub(in crate::eval) fn forget(&mut self, axes: &[usize], what: &'static str, line: u32) {
        for &a in axes {
            self.pos.axes[a] = Err(Unknown::After(what, line));
        }
    }

    /// Factor from machine units (parameter storage) to program units.
    pub(in crate::eval) fn to_prog(&self, s: &Settings, axis: usize) -> f64 {
        if !LINEAR[axis] || s.machine_metric == (self.modal.units == Units::Mm) {
            1.0
        } else if s.machine_metric {
            1.0 / 25.4
        } else {
            25.4
        }
    }

    /// A length parameter in program units, if known.
    fn param_prog(&self, s: &Settings, params: &Params, i: usize, axis: usize) -> Option<f64> {
        params.known[i].then(|| params.values[i] * self.to_prog(s, axis))
    }

    fn set_param_prog(&self, env: &mut Env<'_>, i: usize, axis: usize, v: Option<f64>) {
        match v {
            Some(v) => {
                let f = self.to_prog(env.s, axis);
                env.params.assign(i, v / f)
            }
            None => env.params.known[i] = false,
        }
    }

    /// G5x offset of coordinate system `cs` on an axis, program units.
    fn g5x_offset(
        &self,
        s: &Settings,
        params: &Params,
        cs: CoordSystem,
        axis: usize,
    ) -> Option<f64> {
        self.param_prog(s, params, cs.parameters() + axis, axis)
    }

    /// Applied G92 offset, program units.
    fn g92_offset(&self, s: &Settings, params: &Params, axis: usize) -> Option<f64> {
        if !params.g92_applied() {
            return Some(0.0);
        }
        self.param_prog(s, params, 5211 + axis, axis)
    }

    /// Machine position (without tool offsets), program units.
    fn machine_pos(&self, s: &Settings, params: &Params, axis: usize) -> Option<f64> {
        let p = self.pos.axes[axis].as_ref().ok()?;
        Some(offsets::machine_tip(
            *p,
            self.g5x_offset(s, params, self.modal.coord, axis)?,
            self.g92_offset(s, params, axis)?,
        ))
    }

    /// The machine positions of all axes (program units).
    fn machine_all(&self, env: &Env<'_>) -> Vec<Option<f64>> {
        (0..9)
            .map(|a| self.machine_pos(env.s, env.params, a))
            .collect()
    }

    /// Absolute machine position including the tool length offset, program
    /// units (for `#<_abs_x>`...).
    pub(in crate::eval) fn abs_position(
        &self,
        s: &Settings,
        params: &Params,
        axis: usize,
    ) -> Option<f64> {
        let tlo = self.tlo?[axis] * self.to_prog(s, axis);
        Some(self.machine_pos(s, params, axis)? + tlo)
    }

    /// Sets the position from a machine position (program units).
    fn set_from_machine(&mut self, env: &Env<'_>, axis: usize, m: Option<f64>, what: &'static str) {
        let (s, params) = (env.s, &*env.params);
        let v = m.and_then(|m| {
            Some(
                m - self.g5x_offset(s, params, self.modal.coord, axis)?
                    - self.g92_offset(s, params, axis)?,
            )
        });
        self.pos.axes[axis] = v.ok_or(Unknown::After(what, env.line));
    }

    /// A tool length code: G43 or G43.2 with the tool of `h` or the
    /// current one, G43.1 with the line's axis words, G49; the offset by
    /// [`ToolLength::offset`], in machine units, moving the program
    /// position the other way.
    fn tool_length(
        &mut self,
        env: &Env<'_>,
        code: ToolLength,
        h: Option<f64>,
        axis_words: &[(usize, f64)],
    ) {
        self.modal.tool_length = code;
        let tool = match code {
            ToolLength::Apply | ToolLength::Add => h
                .or(self.tools.current)
                .and_then(|t| self.tool(t))
                .map(|d| d.offsets),
            ToolLength::Dynamic | ToolLength::Cancel => None,
        };
        let mut words = [None; 9];
        if code == ToolLength::Dynamic {
            for &(a, v) in axis_words {
                words[a] = Some(v / self.to_prog(env.s, a));
            }
        }
        let old = self.tlo.map_or([None; 9], |t| t.map(Some));
        let new = code.offset(old, tool, words);
        let new = new
            .iter()
            .all(Option::is_some)
            .then(|| new.map(|v| v.unwrap_or(0.0)));
        let what = match code {
            ToolLength::Dynamic => "G43.1",
            ToolLength::Cancel => "G49",
            ToolLength::Apply | ToolLength::Add => {
                "a tool length offset (G43) of a tool whose data is unknown"
            }
        };
        self.set_tlo(env.s, env.line, new, what);
    }

    /// G43 without H (`on`: the current tool's offset) or G49, as M72
    /// restores them.
    pub(in crate::eval) fn tool_offset_words(&mut self, env: &Env<'_>, on: bool) {
        let code = if on {
            ToolLength::Apply
        } else {
            ToolLength::Cancel
        };
        self.tool_length(env, code, None, &[]);
    }

    /// G92.3 (`on`) applies the offsets kept in the parameters, G92.2 stops
    /// applying them and keeps the parameters; the machine does not move.
    pub(in crate::eval) fn g92_switch(&mut self, env: &mut Env<'_>, on: bool) {
        let machine = self.machine_all(env);
        env.params.assign(5210, if on { 1.0 } else { 0.0 });
        let what = if on { "G92.3" } else { "G92.1/G92.2" };
        for (a, m) in machine.into_iter().enumerate() {
            self.set_from_machine(env, a, m, what);
        }
    }

    /// Sets the position from a machine position of the tool tip (G53, G28,
    /// G30 targets), which includes the tool length offset.
    fn set_from_machine_tip(
        &mut self,
        env: &Env<'_>,
        axis: usize,
        m: Option<f64>,
        what: &'static str,
    ) {
        let tlo = self.tlo.map(|t| t[axis] * self.to_prog(env.s, axis));
        self.set_from_machine(env, axis, m.zip(tlo).map(|(m, t)| m - t), what);
    }

    /// Applies the line's words to the model, with its G and M codes as
    /// the checks decoded them (`checked`), up to what follows the line's
    /// output of [`Machine::retain_line`] ([`Machine::end_line`]). The
    /// warnings it gives go to `warnings`.
    pub(in crate::eval) fn apply_codes(
        &mut self,
        env: &mut Env<'_>,
        words: &[(u8, f64)],
        checked: &Checked,
        m99: bool,
        warnings: &mut Vec<WarningKind>,
    ) -> Result<LineEnd, ErrorKind> {
        let simple;
        let codes = match checked {
            Checked::Line(c) | Checked::Lathe(c, _) => c,
            Checked::Simple => {
                simple = LineCodes::simple(words);
                &simple
            }
        };
        let motion_before = self.modal.motion;
        // Filled in place: returning it would copy it.
        let mut w = LineWords::new(m99, codes);
        self.read_words(env.s, words, &mut w)?;
        // The M codes act after the F, S and T words, whatever their place
        // on the line (the reference's order: a T word selects the tool an
        // M6 on its line loads), with the line's P and Q.
        let codes = w.codes;
        for &m in codes.ms() {
            self.apply_m(m, &mut w, env.line);
        }
        // RETAIN_G43: a tool change while G43 is in effect applies the new
        // tool's offset, and unloading the tool (T0) cancels G43, before the
        // line's own G43/G49. The output says so in a line of its own.
        if w.tool_changed && env.s.retain_g43 && self.modal.tool_length.in_effect() {
            let on = self.tools.current != Some(0.0);
            self.tool_offset_words(env, on);
            if !w.gs().iter().any(|g| matches!(g, GCode::ToolLength(_))) {
                self.retain_line = Some(on);
            }
        }
        let (special, dynamic_tlo) = self.apply_g_modes(env, &w);
        if self.comp.is_some() || self.modal.cutter_comp != CutterComp::Off {
            for &g in w.gs() {
                match g {
                    GCode::CutterComp(CutterComp::Off) => self.comp_off()?,
                    GCode::CutterComp(c) => self.comp_on(env.s, c, words, warnings)?,
                    _ => {}
                }
            }
        }
        if let Some(g) = special {
            self.apply_non_modal(env, g, words, &w)?;
        }
        if !special.is_some_and(NonModal::takes_axis_words) {
            self.apply_motion(env, words, &w, motion_before, dynamic_tlo)?;
        }
        if w.tool_changed {
            // The reference takes the position after the whole line, so
            // a G43 beside the M6 counts and a move beside it does not.
            self.tool_change_sync(env.line);
        }
        let stops = self.comp.is_some()
            && (w.ends
                || w.codes
                    .ms()
                    .iter()
                    .any(|m| matches!(m, MCode::Pause { .. } | MCode::PalletPause)));
        Ok(LineEnd {
            ends: w.ends,
            stops,
        })
    }

    /// The end of a line [`Machine::apply_codes`] ran, after its output:
    /// a program stop or end releases the compensation's held moves; an
    /// end resets the modes.
    pub(in crate::eval) fn end_line(&mut self, end: LineEnd) -> Result<(), ErrorKind> {
        if end.stops {
            self.comp_stop(end.ends)?;
        }
        if end.ends {
            self.modal.end_of_program();
        }
        Ok(())
    }

    /// First pass over the line's words: F, S and T words act in order;
    /// axis words and the P, H, Q, L, R values are gathered.
    // One call site, on the hot path: kept inline as before the split.
    #[inline(always)]
    fn read_words(
        &mut self,
        s: &Settings,
        words: &[(u8, f64)],
        w: &mut LineWords<'_>,
    ) -> Result<(), ErrorKind> {
        for &(l, v) in words {
            match l {
                b'f' => self.modal.feed = v,
                b's' => self.modal.speed = v,
                b't' => {
                    // With a tool table, a tool must be in it (T0: none).
                    let t = v.round() as i64;
                    if !s.tool_table.is_empty() && t != 0 && !self.tools.table.contains_key(&t) {
                        return Err(ErrorKind::Expr(ExprError::ToolNotInTable { tool: t }));
                    }
                    self.tools.select(v);
                    if let Some(p) = &mut self.pockets {
                        p.1 = v;
                    }
                }
                b'p' => w.p = Some(v),
                b'h' => w.h = Some(v),
                b'q' => w.q = Some(v),
                b'l' => w.l = Some(v),
                b'r' => w.r = Some(v),
                _ => {
                    if let Some(a) = axis_index(l)
                        && w.an < w.axes.len()
                    {
                        w.axes[w.an] = (a, v);
                        w.an += 1;
                    }
                }
            }
        }
        Ok(())
    }

    /// One M code, after the line's other words: the switches (spindle,
    /// coolant, overrides with their P) as the modes set them
    /// ([`Modes::set_switch`](crate::rules::Modes::set_switch)), tool change
    /// (M6, M61 with its Q); M2/M30 end the program.
    // One call site, on the hot path: kept inline as before the split.
    #[inline(always)]
    fn apply_m(&mut self, m: MCode, w: &mut LineWords<'_>, line: u32) {
        if self.modal.set_switch(m, w.p).is_some() {
            return;
        }
        match m {
            MCode::End { .. } => w.ends = true,
            MCode::ToolChange => {
                // The spindle stops for the change, as in the model after
                // evaluation (no event here: the line is written as is).
                self.tools.change(&mut self.modal);
                if let Some(p) = &mut self.pockets {
                    p.0 = p.1;
                }
                self.m61 = None;
                w.tool_changed = true;
            }
            MCode::SetTool => {
                if self.m61.is_none() {
                    self.m61 = Some((line, self.tools.current));
                }
                self.tools.set_current(w.q);
                if let (Some(p), Some(q)) = (&mut self.pockets, w.q) {
                    p.0 = q;
                }
                w.tool_changed = true;
            }
            _ => {}
        }
    }

    /// The line's G codes in line order: each sets its field of the modes
    /// ([`Modes::set_mode`](crate::rules::Modes::set_mode)), and those it
    /// hands back act on the machine here. Returns the non-modal code
    /// (G10, G28, G30, G53, G92.x, G52) if any, and whether G43.1 set a
    /// tool length offset from axis words. (A G80 beside another motion
    /// code is not among the codes: the checks left it out.)
    // One call site, on the hot path: kept inline as before the split.
    #[inline(always)]
    fn apply_g_modes(&mut self, env: &mut Env<'_>, w: &LineWords<'_>) -> (Option<NonModal>, bool) {
        let mut special = None;
        let mut dynamic_tlo = false;
        for &g in w.gs() {
            let Some(code) = self.modal.set_mode(g) else {
                continue;
            };
            match code {
                // G5.3 ends a NURBS block without choosing a motion.
                MachineCode::Motion(MotionMode::NurbsEnd) => {}
                MachineCode::Motion(m) => self.modal.motion = m,
                MachineCode::Units(u) => self.set_units(env.line, u),
                MachineCode::ToolLength(t) => {
                    self.tool_length(env, t, w.h, w.axis_words());
                    dynamic_tlo |= t == ToolLength::Dynamic;
                }
                MachineCode::Coord(cs) => self.select_cs(env, cs),
                // G4 acts in the output alone.
                MachineCode::NonModal(NonModal::Dwell) => {}
                MachineCode::NonModal(n) => special = Some(n),
            }
        }
        (special, dynamic_tlo)
    }

    /// A non-modal code that sets offsets, tool data or the position: G92,
    /// G92.1-G92.3, G52, G10, G28/G30 and their .1, G53.
    fn apply_non_modal(
        &mut self,
        env: &mut Env<'_>,
        special: NonModal,
        words: &[(u8, f64)],
        w: &LineWords<'_>,
    ) -> Result<(), ErrorKind> {
        match special {
            NonModal::SetG92 => {
                keep_active_g92(env.params);
                for &(a, v) in w.axis_words() {
                    // The position becomes the given value; the offset is
                    // known only if the machine position was.
                    let m = self.machine_pos(env.s, env.params, a);
                    let g5x = self.g5x_offset(env.s, env.params, self.modal.coord, a);
                    let off = m.zip(g5x).map(|(m, o)| offsets::g92_making(m, o, v));
                    self.set_param_prog(env, 5211 + a, a, off);
                    self.pos.axes[a] = Ok(v);
                }
                env.params.assign(5210, 1.0);
            }
            NonModal::ResetG92 | NonModal::SuspendG92 => {
                self.g92_switch(env, false);
                // G92.1 also clears the parameters (no longer applied).
                if special == NonModal::ResetG92 {
                    for a in 0..9 {
                        env.params.assign(5211 + a, 0.0);
                    }
                }
            }
            NonModal::LocalOffset => {
                // G52: a local offset kept in the G92 parameters.
                let machine = self.machine_all(env);
                keep_active_g92(env.params);
                for &(a, v) in w.axis_words() {
                    self.set_param_prog(env, 5211 + a, a, Some(v));
                }
                env.params.assign(5210, 1.0);
                for (a, m) in machine.into_iter().enumerate() {
                    if self.pos.axes[a].is_ok() {
                        self.set_from_machine(env, a, m, "G52");
                    }
                }
            }
            NonModal::RestoreG92 => self.g92_switch(env, true),
            NonModal::SetData => match w.l.map(|v| v.round() as i32) {
                Some(l @ (1 | 10 | 11)) => self.g10_tool(env, l, w.p, w.r, words, w.axis_words()),
                _ => self.g10(env, w.l, w.p, w.r, w.axis_words()),
            },
            NonModal::Home | NonModal::Home2 => {
                let base = if special == NonModal::Home {
                    5161
                } else {
                    5181
                };
                let axes: Vec<usize> = if w.axis_words().is_empty() {
                    (0..9).collect()
                } else {
                    w.axis_words().iter().map(|a| a.0).collect()
                };
                for a in axes {
                    let home = self.param_prog(env.s, env.params, base + a, a);
                    let what = "G28/G30 (a move to a home position)";
                    self.set_from_machine_tip(env, a, home, what);
                }
            }
            NonModal::SetHome | NonModal::SetHome2 => {
                let base = if special == NonModal::SetHome {
                    5161
                } else {
                    5181
                };
                for a in 0..9 {
                    let m = self.machine_pos(env.s, env.params, a);
                    self.set_param_prog(env, base + a, a, m);
                }
            }
            NonModal::MachineCoords => {
                if self.comp_offsetting() {
                    return Err(ErrorKind::Machine(MachineError::CompForbids {
                        action: "use G53",
                    }));
                }
                if self.modal.cutter_comp != CutterComp::Off {
                    self.forget(&[0, 1, 2], "cutter radius compensation", env.line);
                }
                for &(a, v) in w.axis_words() {
                    self.set_from_machine_tip(env, a, Some(v), "a G53 machine-coordinate move");
                }
            }
            _ => {}
        }
        Ok(())
    }

    /// The line's motion (no non-modal code): NURBS points, or a move to
    /// the axis words.
    // One call site, on the hot path: kept inline as before the split.
    #[inline(always)]
    fn apply_motion(
        &mut self,
        env: &mut Env<'_>,
        words: &[(u8, f64)],
        w: &LineWords<'_>,
        motion_before: MotionMode,
        dynamic_tlo: bool,
    ) -> Result<(), ErrorKind> {
        let axis_words = w.axis_words();
        if w.gs().contains(&GCode::Motion(MotionMode::NurbsEnd)) {
            // G5.3 ends the block; axis words on its line start another
            // one (the reference runs them as G5.2).
            self.nurbs_end(env.line);
            if !axis_words.is_empty() {
                self.nurbs_point(NO_MOTION, axis_words, w.l);
            }
        } else if w.gs().contains(&GCode::Motion(NURBS))
            || (motion_before == NURBS && self.modal.motion == NURBS && !axis_words.is_empty())
        {
            // (Axis words in a G5.2 block are a control point; a line with
            // another motion code, G3 say, moves in that mode instead.)
            self.nurbs_point(motion_before, axis_words, w.l);
        } else {
            // G43.1's axis words are a move too when the line has a
            // motion code.
            let explicit_motion = w.gs().iter().any(|&g| is_moving_code(g));
            let polar = polar_words(words).map(|_| self.polar_xy(words));
            let moves = !axis_words.is_empty() || polar.is_some();
            let full_circle = !moves
                && w.gs()
                    .iter()
                    .any(|g| matches!(g, GCode::Motion(MotionMode::ArcCw | MotionMode::ArcCcw)));
            if full_circle {
                // A full circle without end point (`G2 I5`): the reference
                // checks its radius as for any arc.
                self.check_motion_polar(words, axis_words, polar)?;
            }
            if moves && (!dynamic_tlo || explicit_motion) {
                self.check_motion_polar(words, axis_words, polar)?;
                if self.modal.motion.is_canned_cycle() {
                    self.note_cycle(words);
                }
                self.move_to(env, words, axis_words, w.l, motion_before.is_canned_cycle());
                if self.comp.is_some() || self.modal.cutter_comp != CutterComp::Off {
                    self.comp_move(words, self.modal.motion)?;
                }
            }
        }
        Ok(())
    }

    /// M6 or M61 on `line`, after the line's other codes: the standalone
    /// reference then takes the position from its last move, which misses
    /// a tool length offset changed since (the machine does not move).
    fn tool_change_sync(&mut self, line: u32) {
        let lasting = self.standalone_drift.is_some() && self.drift_axes == 0;
        if self.tlo_moved != 0 && !lasting {
            self.standalone_drift = Some((
                "a tool change after the tool length offset changed without a move",
                line,
            ));
            self.drift_axes |= self.tlo_moved;
        }
    }

    /// An absolute move on `axis` after a tool change's drift: the
    /// standalone reference's position there is the machine's again.
    #[cold]
    fn end_drift(&mut self, axis: usize) {
        self.drift_axes &= !(1 << axis);
        if self.drift_axes == 0 {
            self.standalone_drift = None;
        }
    }

    /// A read of the current tool (`data`: or of its data) after M61,
    /// which the standalone reference does not apply, if the value differs
    /// there: the line of the M61.
    pub(in crate::eval) fn m61_read_differs(&self, data: bool) -> Option<u32> {
        let (line, old) = self.m61?;
        (old != self.tools.current
            && (!data
                || old.and_then(|t| self.tool(t)) != self.tools.current.and_then(|t| self.tool(t))))
        .then_some(line)
    }

    /// G20 or G21 (`units`) on `line`: the position is converted.
    pub(in crate::eval) fn set_units(&mut self, line: u32, units: Units) {
        if self.modal.units == units {
            return;
        }
        if self.tlo.is_some_and(|t| t.iter().any(|&v| v != 0.0)) {
            self.standalone_drift = Some((
                "a change of units with a tool length offset in effect",
                line,
            ));
            self.drift_axes = 0;
        }
        let f = match units {
            Units::Mm => 25.4,
            Units::Inch => 1.0 / 25.4,
        };
        for (a, lin) in LINEAR.iter().enumerate() {
            if *lin && let Ok(p) = &mut self.pos.axes[a] {
                *p *= f;
            }
        }
        self.modal.units = units;
        self.comp_units(units);
    }

    /// G54–G59.3 (`cs`): the position moves to the new system's
    /// coordinates; `#5220` says which system is active.
    pub(in crate::eval) fn select_cs(&mut self, env: &mut Env<'_>, cs: CoordSystem) {
        let machine = self.machine_all(env);
        self.modal.coord = cs;
        env.params.assign(5220, cs.0 as f64);
        for (a, m) in machine.into_iter().enumerate() {
            if self.pos.axes[a].is_ok() {
                self.set_from_machine(env, a, m, "a coordinate system change");
            }
        }
    }

    /// G10 L2 or L20 (and G10 L1, L10, L11, which change no position).
    fn g10(
        &mut self,
        env: &mut Env<'_>,
        l: Option<f64>,
        p: Option<f64>,
        r: Option<f64>,
        axis_words: &[(usize, f64)],
    ) {
        let l = l.map(|v| v.round() as i32);
        let cs = offsets::g10_system(p, self.modal.coord);
        let base = cs.parameters();
        let active = cs == self.modal.coord;
        match l {
            Some(2) | Some(20) => {
                if r.is_some_and(|r| r != 0.0) {
                    // XY rotation is not modelled: positions become unknown.
                    self.rotated = true;
                    let what = "an XY rotation (G10 R)";
                    self.forget(&[0, 1, 2, 3, 4, 5, 6, 7, 8], what, env.line);
                }
                for &(a, v) in axis_words {
                    let m = self.machine_pos(env.s, env.params, a);
                    let new_off = if l == Some(2) {
                        Some(v)
                    } else {
                        m.zip(self.g92_offset(env.s, env.params, a))
                            .map(|(m, g)| offsets::g5x_making(m, g, v))
                    };
                    self.set_param_prog(env, base + a, a, new_off);
                    if active {
                        if l == Some(20) {
                            self.pos.axes[a] = Ok(v);
                        } else {
                            let what = "G10 L2 on the active coordinate system";
                            self.set_from_machine(env, a, m, what);
                        }
                    }
                }
                if let Some(r) = r {
                    env.params.assign(base + 9, r);
                }
            }
            _ => {
                // Tool table changes (L1, L10, L11) do not move anything.
            }
        }
    }

    /// G38.x: results only the machine knows. With --zero-start, as the
    /// standalone interpreter: the probe does not trip, #5061.. hold the
    /// target, and the position is the target backed off 0.254 mm.
    fn probe(&mut self, env: &mut Env<'_>, axis_words: &[(usize, f64)]) {
        let line = env.line;
        if !env.s.zero_start {
            self.forget(&[0, 1, 2, 3, 4, 5, 6, 7, 8], "a probing move", line);
            for i in 5061..=5070 {
                env.params.known[i] = false;
            }
            self.probed_at = Some(line);
            return;
        }
        let start: [Option<f64>; 9] =
            std::array::from_fn(|a| self.pos.axes[a].as_ref().ok().copied());
        let mut target = start;
        for &(a, v) in axis_words {
            target[a] = self.axis_end(a, v).ok();
        }
        let end = probe_end(start, target, self.modal.probe_backoff());
        for a in 0..9 {
            match target[a] {
                Some(t) => env.params.assign(5061 + a, t),
                None => env.params.known[5061 + a] = false,
            }
            self.pos.axes[a] = end[a].ok_or(Unknown::After("a probing move", line));
        }
        env.params.assign(5070, 0.0);
    }

    /// The line's move to its axis words in the motion mode (`l`: its L
    /// word; `series`: the mode was a canned cycle before the line).
    fn move_to(
        &mut self,
        env: &mut Env<'_>,
        words: &[(u8, f64)],
        axis_words: &[(usize, f64)],
        l: Option<f64>,
        series: bool,
    ) {
        let line = env.line;
        self.tlo_moved = 0;
        if self.rotated {
            self.forget(&[0, 1, 2, 3, 4, 5, 6, 7, 8], "an XY rotation (G10 R)", line);
            return;
        }
        let motion = self.modal.motion;
        use MotionMode as M;
        match motion {
            M::Probe(_) => self.probe(env, axis_words),
            M::Cycle(_) => {
                self.cycle_end(axis_words, l, series);
                if polar_words(words).is_some() {
                    // Polar holes are not followed.
                    self.forget(&[0, 1], "a canned cycle with polar coordinates", line);
                }
            }
            M::ThreadCycle | M::Thread | M::RigidTap => {
                // Threading ends at positions that depend on retract rules
                // and machine state.
                let axes: Vec<usize> = axis_words.iter().map(|a| a.0).collect();
                self.forget(&axes, "a canned cycle or threading move", line);
                if motion == M::ThreadCycle {
                    self.forget(&[2], "a canned cycle", line);
                }
            }
            _ => {
                // With compensation on this is the programmed position,
                // which is what the reference reads missing words from.
                for &(a, v) in axis_words {
                    self.move_axis(a, v);
                }
                if polar_words(words).is_some() {
                    let why = Unknown::After("a move by polar coordinates", line);
                    let [x, y] = self.polar_xy(words).map_or([None, None], |p| p.map(Some));
                    self.pos.axes[0] = x.ok_or(why.clone());
                    self.pos.axes[1] = y.ok_or(why);
                }
            }
        }
    }
}

/// Before G92 or G52 writes the offset parameters: axes without a word
/// keep the offsets in effect, which are none after G92.2 (whose
/// parameters still hold the old values).
fn keep_active_g92(params: &mut Params) {
    if !params.g92_applied() {
        for a in 0..9 {
            params.assign(5211 + a, 0.0);
        }
    }
}

/// A line's words as `apply_codes` gathers them in its first pass, with
/// its codes as the checks decoded them.
struct LineWords<'c> {
    codes: &'c LineCodes,
    /// Axis words: (axis index, value).
    axes: [(usize, f64); 9],
    an: usize,
    p: Option<f64>,
    h: Option<f64>,
    q: Option<f64>,
    l: Option<f64>,
    r: Option<f64>,
    /// The line ends the program (M2, M30, or M99 ending the main program).
    ends: bool,
    tool_changed: bool,
}

impl LineWords<'_> {
    #[inline]
    fn new(ends: bool, codes: &LineCodes) -> LineWords<'_> {
        LineWords {
            codes,
            axes: [(0, 0.0); 9],
            an: 0,
            p: None,
            h: None,
            q: None,
            l: None,
            r: None,
            ends,
            tool_changed: false,
        }
    }

    /// The line's G codes, in line order.
    #[inline]
    fn gs(&self) -> &[GCode] {
        self.codes.gs()
    }

    #[inline]
    fn axis_words(&self) -> &[(usize, f64)] {
        &self.axes[..self.an]
    }
}

/// The line's polar words (`@` radius, `^` angle), if it has any.
#[inline]
fn polar_words(words: &[(u8, f64)]) -> Option<(Option<f64>, Option<f64>)> {
    // One pass for the common line without them (arcs on the fast path).
    if !words.iter().any(|w| matches!(w.0, b'@' | b'^')) {
        return None;
    }
    let word = |l: u8| words.iter().rev().find(|w| w.0 == l).map(|w| w.1);
    let (r, a) = (word(b'@'), word(b'^'));
    (r.is_some() || a.is_some()).then_some((r, a))
}

impl Machine {
    /// Where the line's polar words send X and Y (program units),
    /// [`polar_end`]: `None` where the position is unknown, or at the
    /// origin, where rs274 refuses them.
    fn polar_xy(&self, words: &[(u8, f64)]) -> Option<[f64; 2]> {
        let (radius, angle) = polar_words(words)?;
        let at = |a: usize| self.pos.axes[a].as_ref().ok().copied();
        polar_end(self.modal.distance, [at(0)?, at(1)?], radius, angle)
    }

    /// Whether the machine is in a plain state, where the fast paths may
    /// run a line: no XY rotation, and cutter compensation neither on nor
    /// just turned off (the next move is then checked).
    #[inline(always)]
    pub(in crate::eval) fn is_plain(&self) -> bool {
        !(self.rotated || self.modal.cutter_comp != CutterComp::Off || self.comp_pending)
    }

    /// A line the straight-line loop accepted (G0–G3 with axis, F and S
    /// words): its motion mode, feed and speed (`speed`: its S word, if it
    /// has one) are set; its moves follow ([`Machine::move_axis`]).
    #[inline(always)]
    pub(in crate::eval) fn set_plain_modes(
        &mut self,
        motion: MotionMode,
        feed: f64,
        speed: Option<f64>,
    ) {
        self.modal.motion = motion;
        self.modal.feed = feed;
        if let Some(v) = speed {
            self.modal.speed = v;
        }
    }

    /// [`Machine::check_motion`] with the motion mode `motion` (the one
    /// the line sets) in place of the current one.
    #[inline(always)]
    pub(in crate::eval) fn check_motion_as(
        &mut self,
        motion: MotionMode,
        words: &[(u8, f64)],
        axis_words: &[(usize, f64)],
    ) -> Result<(), ErrorKind> {
        let old = std::mem::replace(&mut self.modal.motion, motion);
        let r = self.check_motion(words, axis_words);
        self.modal.motion = old;
        r
    }

    /// The common line (G0/G1, axis, F and S words, each at most once) in
    /// a plain state: as the general update below, in a few steps. False
    /// leaves the state untouched.
    pub(in crate::eval) fn apply_simple(&mut self, words: &[(u8, f64)]) -> bool {
        if !self.is_plain() {
            return false;
        }
        let mut motion = self.modal.motion;
        let mut seen = 0u32;
        for &(l, v) in words {
            let bit = 1u32 << (l.wrapping_sub(b'a') & 31);
            if seen & bit != 0 {
                return false;
            }
            seen |= bit;
            match l {
                b'g' if v == 0.0 => motion = MotionMode::Rapid,
                b'g' if v == 1.0 => motion = MotionMode::Linear,
                b'x' | b'y' | b'z' | b'a' | b'b' | b'c' | b'f' | b's' => {}
                _ => return false,
            }
        }
        if !matches!(motion, MotionMode::Rapid | MotionMode::Linear) {
            return false;
        }
        self.modal.motion = motion;
        for &(l, v) in words {
            match l {
                b'f' => self.modal.feed = v,
                b's' => self.modal.speed = v,
                _ => {
                    if let Some(a) = axis_index(l) {
                        self.move_axis(a, v);
                    }
                }
            }
        }
        true
    }

    /// Where a word sends an axis: its value (G90) or the position plus it
    /// (G91).
    pub(in crate::eval) fn axis_end(&self, axis: usize, v: f64) -> Result<f64, Unknown> {
        let v = self.modal.radius_word(axis, v);
        if self.modal.distance == Distance::Absolute {
            Ok(v)
        } else {
            self.pos.axes[axis].clone().map(|p| p + v)
        }
    }

    /// The end of a move on one axis: the word's value (G90) or the
    /// position plus it (G91); an unknown position stays unknown.
    #[inline]
    pub(in crate::eval) fn move_axis(&mut self, axis: usize, v: f64) {
        self.tlo_moved = 0;
        let v = self.modal.radius_word(axis, v);
        if self.modal.distance == Distance::Absolute {
            self.pos.axes[axis] = Ok(v);
            if self.drift_axes != 0 {
                self.end_drift(axis);
            }
        } else if let Ok(p) = &mut self.pos.axes[axis] {
            *p += v;
        }
    }

    /// [`Machine::check_motion_polar`] for a line without polar words
    /// (the straight-line loop takes none).
    pub(in crate::eval) fn check_motion(
        &self,
        words: &[(u8, f64)],
        axis_words: &[(usize, f64)],
    ) -> Result<(), ErrorKind> {
        self.check_motion_polar(words, axis_words, None)
    }

    /// Checks the reference makes with the start position: arc geometry,
    /// probe distance, polar words at the origin; `polar`: where the
    /// line's polar words send X and Y, if it has any
    /// ([`Machine::polar_xy`]). Skipped where the position is not known.
    pub(in crate::eval) fn check_motion_polar(
        &self,
        words: &[(u8, f64)],
        axis_words: &[(usize, f64)],
        polar: Option<Option<[f64; 2]>>,
    ) -> Result<(), ErrorKind> {
        let motion = self.modal.motion;
        let start = |a: usize| self.pos.axes[a].as_ref().ok().copied();
        let end = |a: usize| -> Option<f64> {
            match (axis_words.iter().find(|w| w.0 == a), polar) {
                (_, Some(xy)) if a < 2 => Some(xy?[a]),
                (Some(&(_, v)), _) => self.axis_end(a, v).ok(),
                (None, _) => start(a),
            }
        };
        let word = |l: u8| words.iter().rev().find(|w| w.0 == l).map(|w| w.1);
        let bad = ErrorKind::Block;
        // Polar words from a known position with no end: at the origin
        // (not in a cycle, which reads an angle of 0 there in G90).
        if polar.is_some_and(|xy| xy.is_none())
            && !motion.is_canned_cycle()
            && start(0).is_some()
            && start(1).is_some()
        {
            let incremental = self.modal.distance == Distance::Incremental;
            return Err(bad(BlockError::PolarAtOrigin { incremental }));
        }
        match motion {
            MotionMode::ArcCw | MotionMode::ArcCcw => {
                let (a0, a1, c0, c1) = match self.modal.plane {
                    Plane::XZ | Plane::WU => (2, 0, b'k', b'i'),
                    Plane::YZ | Plane::VW => (1, 2, b'j', b'k'),
                    Plane::XY | Plane::UV => (0, 1, b'i', b'j'),
                };
                let (Some(sx), Some(sy), Some(ex), Some(ey)) =
                    (start(a0), start(a1), end(a0), end(a1))
                else {
                    return Ok(());
                };
                // The reference's checks (arc_data_r / arc_data_ijk).
                let refusal = arc_refusal(
                    motion == MotionMode::ArcCcw,
                    word(b'r'),
                    [word(c0), word(c1)],
                    self.modal.arc_distance,
                    self.modal.units,
                    [sx, sy],
                    [ex, ey],
                );
                if let Some(e) = refusal {
                    return Err(bad(e));
                }
            }
            MotionMode::Probe(2 | 4) => {
                // Axes without a word do not move, known or not.
                let d: f64 = axis_words
                    .iter()
                    .filter(|w| w.0 < 3)
                    .filter_map(|w| Some((end(w.0)? - start(w.0)?).powi(2)))
                    .sum::<f64>()
                    .sqrt();
                let known = axis_words.iter().all(|w| {
                    start(w.0).is_some() || (self.modal.distance == Distance::Absolute && w.0 >= 3)
                });
                if known && d < 1e-7 {
                    return Err(bad(BlockError::ProbeTooClose));
                }
            }
            _ => {}
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Applies one line of `words` with its G `codes` to the machine, as
    /// line `line`; the update needs nothing but its arguments.
    fn apply(m: &mut Machine, env: &mut Env<'_>, words: &[(u8, f64)], codes: &[GCode]) {
        let gs: Vec<(GCode, usize)> = codes.iter().map(|&g| (g, 0)).collect();
        let checked = Checked::Line(LineCodes::of(&gs, &[], false));
        let mut warnings = Vec::new();
        let end = m
            .apply_codes(env, words, &checked, false, &mut warnings)
            .expect("applied");
        m.end_line(end).expect("ended");
        assert!(warnings.is_empty());
    }

    /// A probe without `--zero-start` leaves the position and its results
    /// unknown, naming the line the update was given.
    #[test]
    fn a_probe_forgets_the_position_at_its_line() {
        let s = Settings::default();
        let mut params = Params::new(s.zero_start);
        let mut m = Machine::new(&s);
        let mut env = Env {
            s: &s,
            params: &mut params,
            line: 7,
        };
        let probe = GCode::Motion(MotionMode::Probe(2));
        apply(&mut m, &mut env, &[(b'g', 38.2), (b'z', -1.0)], &[probe]);
        assert_eq!(m.pos.axes[2], Err(Unknown::After("a probing move", 7)));
        assert_eq!(m.probed_at, Some(7));
        assert!(!params.known[5061]);
    }

    /// G92 writes its offset to the parameters it is handed: the position
    /// becomes the word's value, the offset the difference, kept in the
    /// machine's units the settings give (inches by default).
    #[test]
    fn g92_writes_the_offset_parameters() {
        let s = Settings {
            zero_start: true,
            ..Settings::default()
        };
        let mut params = Params::new(s.zero_start);
        let mut m = Machine::new(&s);
        let mut env = Env {
            s: &s,
            params: &mut params,
            line: 1,
        };
        let g92 = GCode::NonModal(NonModal::SetG92);
        apply(&mut m, &mut env, &[(b'g', 92.0), (b'x', 2.0)], &[g92]);
        assert_eq!(m.pos.axes[0], Ok(2.0));
        assert_eq!(params.values[5211], -2.0 / 25.4);
        assert!(params.g92_applied());
    }
}
