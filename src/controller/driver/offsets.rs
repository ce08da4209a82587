//! Keeping the target's offsets in step with LinuxCNC's: positions
//! written in the coordinate system the target is in when it lacks the
//! program's, G52 and G92.1–G92.3 written as the target's G92, and tool
//! length offsets (G43, G43.2, G43.1 with other axes) written as the
//! target's `G43.1 Z`.

use crate::block::{Block, CoordSystem, Distance, NonModal, ToolLength, WordKind};
use crate::controller::lower::PlainLine;
use crate::diag::ErrorKind;
use crate::diag::TargetError;
use crate::machine::FlatMachine;

use super::fates::{Fate, g_span};
use super::{Lowering, Problem};

impl Lowering {
    /// Positions in a coordinate system the target lacks are written in
    /// the one it is in: the shift to add, when the block writes any.
    pub(super) fn target_shift(
        &self,
        b: &Block,
        fates: &[Fate],
        lowered: Option<&[PlainLine]>,
    ) -> Result<Option<[f64; 3]>, Problem> {
        if self.m.modes.coord == self.target_coord && !self.offsets_applied() {
            return Ok(None);
        }
        let needed = Self::positions_in_work(b, &self.m)
            && b.words.iter().zip(fates).any(|(w, f)| {
                *f == Fate::Keep
                    && matches!(w.kind, WordKind::Value)
                    && matches!(w.letter, b'X' | b'Y' | b'Z')
            })
            || lowered.is_some_and(|l| !l.is_empty());
        if !needed {
            return Ok(None);
        }
        self.machine_shift(&self.m).map(Some).map_err(|k| Problem {
            span: b.coord().and(g_span(b, 591, 593)),
            kind: k,
        })
    }

    /// Whether the target lacks offsets ngcflat applies to every position
    /// written (its work offsets, or its tool length offsets).
    fn offsets_applied(&self) -> bool {
        !self.p.work_offsets || self.p.tool_length_into_z
    }

    /// What to add (mm, X Y Z) to a position in `m`'s work coordinates to
    /// get the same machine position in the target's coordinates: the
    /// difference of the coordinate systems where the target lacks the
    /// program's, all of LinuxCNC's offsets where it has none, and the
    /// tool length offset where it has none.
    pub(super) fn machine_shift(&self, m: &FlatMachine) -> Result<[f64; 3], ErrorKind> {
        let mut out = if !self.p.work_offsets {
            let total = m.offset();
            let mut o = [0.0; 3];
            for i in 0..3 {
                let tool = if self.p.tool_length_into_z {
                    0.0
                } else {
                    m.tlo[i].unwrap_or(0.0)
                };
                o[i] = total[i].ok_or_else(|| self.offsets_unknown(m, i))? - tool;
            }
            return Ok(o);
        } else if m.modes.coord == self.target_coord {
            [0.0; 3]
        } else {
            self.coord_shift(m, self.target_coord)?
        };
        if self.p.tool_length_into_z {
            for (i, o) in out.iter_mut().enumerate() {
                *o += m.tlo[i].ok_or_else(|| self.offsets_unknown(m, i))?;
            }
        }
        Ok(out)
    }

    /// The error for offsets of axis `i` the model does not know.
    fn offsets_unknown(&self, m: &FlatMachine, i: usize) -> ErrorKind {
        let c = m.modes.coord;
        ErrorKind::Target(TargetError::TargetNeedsValue {
            target: self.name(),
            what: "positions written in machine coordinates (the target has no work or tool length offsets)".into(),
            value: format!(
                "the {} offsets of {} (parameter {}), of G92 (parameter {}) and the tool length",
                ['X', 'Y', 'Z'][i],
                c.name(),
                c.parameters() + i,
                5211 + i
            ),
            option: "--var-file (the machine's parameter file), -D, --tool-table, or --zero-start"
                .into(),
        })
    }

    /// Whether the axis words of `b` are positions in the active work
    /// coordinates: G92 values, and in absolute distance mode motion and
    /// G28/G30 intermediate points. Those are rewritten when the
    /// program's coordinate system is not the target's.
    pub(super) fn positions_in_work(b: &Block, m: &FlatMachine) -> bool {
        b.non_modal() == Some(NonModal::SetG92)
            || m.modes.distance == Distance::Absolute
                && b.tool_length() != Some(ToolLength::Dynamic)
                && matches!(
                    b.non_modal(),
                    None | Some(NonModal::Dwell | NonModal::Home | NonModal::Home2)
                )
    }

    /// What to add (mm, X Y Z) to a position in `m`'s work coordinates to
    /// get the same machine position in the target's system `target`.
    fn coord_shift(&self, m: &FlatMachine, target: CoordSystem) -> Result<[f64; 3], ErrorKind> {
        let (from, to) = (m.modes.coord, target);
        let (a, t) = (&m.g5x[from.index()], &m.g5x[to.index()]);
        let mut out = [0.0; 3];
        for i in 0..3 {
            match (a[i], t[i]) {
                (Some(a), Some(t)) => out[i] = a - t,
                _ => {
                    let param = |c: CoordSystem| c.parameters() + i;
                    return Err(ErrorKind::Target(TargetError::TargetNeedsValue {
                        target: self.name(),
                        what: format!(
                            "{} (a coordinate system the target lacks, written as coordinates in {})",
                            from.name(),
                            to.name()
                        ),
                        value: format!(
                            "the {} offsets of both (parameters {} and {})",
                            ['X', 'Y', 'Z'][i],
                            param(from),
                            param(to)
                        ),
                        option: "--var-file (the machine's parameter file), -D, or --zero-start"
                            .into(),
                    }));
                }
            }
        }
        Ok(out)
    }

    /// G52, G92.1, G92.2, G92.3 where the target lacks them: a `G92` (or
    /// `G92.1`) line that gives the target the effective G92/G52 offset
    /// LinuxCNC has after the block, computed in the target's state
    /// before it. `None` when the block has none of them or the target
    /// has the code; an empty line when nothing changes.
    pub(super) fn offset_sync(
        &self,
        b: &Block,
        before: &FlatMachine,
    ) -> Result<Option<Vec<(u8, f64)>>, ErrorKind> {
        let (code, what) = match b.non_modal() {
            Some(NonModal::LocalOffset) => (520, "G52 (local offset)"),
            Some(NonModal::ResetG92) => (921, "G92.1"),
            Some(NonModal::SuspendG92) => (922, "G92.2 (G92 offsets off)"),
            Some(NonModal::RestoreG92) => (923, "G92.3 (G92 offsets back on)"),
            _ => return Ok(None),
        };
        if self.p.has_g(code) || !self.p.work_offsets {
            // Had, or applied to every position (machine_shift).
            return Ok(None);
        }
        let effective = |m: &FlatMachine, a: usize| match m.g92_applied {
            Some(true) => m.g92[a],
            Some(false) => Some(0.0),
            None => None,
        };
        let need = |value: String, option: &str| {
            ErrorKind::Target(TargetError::TargetNeedsValue {
                target: self.name(),
                what: format!("{what}, written as the target's G92"),
                value,
                option: option.into(),
            })
        };
        let offsets_option =
            "--var-file (parameters 5210-5213 of the machine), -D, or --zero-start";
        let mut changed = Vec::new();
        let mut all_zero = true;
        for (a, &letter) in b"XYZ".iter().enumerate() {
            if !self.p.has_axis(letter) {
                continue;
            }
            let want = effective(&self.m, a)
                .ok_or_else(|| need("the G92 offsets".into(), offsets_option))?;
            let had = effective(before, a)
                .ok_or_else(|| need("the G92 offsets".into(), offsets_option))?;
            all_zero &= want == 0.0;
            if want != had {
                changed.push((a, letter, had, want));
            }
        }
        if changed.is_empty() {
            return Ok(Some(Vec::new()));
        }
        if all_zero && self.p.has_g(921) {
            return Ok(Some(vec![(b'G', 92.1)]));
        }
        // The target's G92 makes the current position read the value:
        // its offset = machine - G5x - tool length - value, and the
        // machine position is the work position plus G5x, the G92 offset
        // and the tool length: value = position + offset before - offset
        // wanted (+ the shift to the target's coordinate system).
        let shift = self.machine_shift(before)?;
        let s = before.scale();
        let mut words = vec![(b'G', 92.0)];
        for (a, letter, had, want) in changed {
            let p = before.pos[a].ok_or_else(|| {
                need(
                    format!("the current {} position", letter as char),
                    "--start-position (or --zero-start), or an absolute move first",
                )
            })?;
            words.push((letter, (p + had - want + shift[a]) / s));
        }
        Ok(Some(words))
    }

    /// G43/G43.2 as the target's G43.1 Z (the offset in program units).
    pub(super) fn tool_length_words(
        &self,
        b: &Block,
        before: &FlatMachine,
    ) -> Result<Vec<(u8, f64)>, ErrorKind> {
        // The G43.1 line goes before the block's own line, so its value is
        // in the units in effect before the block (a G20/G21 on the line
        // comes after it).
        let s = before.scale();
        let tlo = self.m.tlo;
        let need = |axis: &str| {
            ErrorKind::Target(TargetError::TargetNeedsValue {
                target: self.name(),
                what: "G43 (tool length offset)".into(),
                value: format!("the tool's {axis} length"),
                option: "--tool-table (the tool table of the machine)".into(),
            })
        };
        // The tool's data must really be known: from --tool-table or a G10
        // L1/L10/L11 of the program (--zero-start's zeros are not the
        // machine's tools).
        let h = b
            .value(b'H')
            .map(|h| h.round() as i64)
            .or(before.current_tool());
        if !h.is_some_and(|h| h == 0 || self.m.tools.table.contains_key(&h)) {
            return Err(need("Z"));
        }
        let z = tlo[2].ok_or_else(|| need("Z"))?;
        if self.p.tool_length_into_z {
            // Applied to the positions written (machine_shift).
            return Ok(Vec::new());
        }
        for (a, v) in tlo.iter().enumerate() {
            if a != 2 && v.is_some_and(|v| v != 0.0) && self.p.g43_1_z_only {
                return Err(self.refuse(
                    "G43 with an X or other non-Z tool offset",
                    "the target's G43.1 takes only Z",
                ));
            }
        }
        if !self.p.has_g(431) {
            return Err(self.refuse("G43", "the target has no tool length offset"));
        }
        Ok(vec![(b'G', 43.1), (b'Z', z / s)])
    }

    /// A G43.1 of the program on a target whose G43.1 takes a Z word alone
    /// (GRBL refuses any other, error 37): `None` when it has that form,
    /// else the target's `G43.1 Z` line for the offset it leaves (LinuxCNC
    /// sets the axes it names and keeps the others' offsets); an offset
    /// on another axis is refused.
    pub(super) fn dynamic_tool_length(
        &self,
        b: &Block,
        before: &FlatMachine,
    ) -> Result<Option<Vec<(u8, f64)>>, ErrorKind> {
        if b.tool_length() != Some(ToolLength::Dynamic) || !self.p.g43_1_z_only {
            return Ok(None);
        }
        let axes = b.axes();
        let z_alone =
            axes[2].is_some() && axes.iter().enumerate().all(|(a, v)| a == 2 || v.is_none());
        if z_alone {
            return Ok(None);
        }
        let tlo = self.m.tlo;
        if tlo
            .iter()
            .enumerate()
            .any(|(a, v)| a != 2 && v.is_some_and(|v| v != 0.0))
        {
            return Err(self.refuse(
                "G43.1 with an X or other non-Z tool offset",
                "the target's G43.1 takes only Z",
            ));
        }
        // In the units before the block, like the G43 line (see
        // `tool_length_words`).
        let z = tlo[2].ok_or_else(|| {
            ErrorKind::Target(TargetError::TargetNeedsValue {
                target: self.name(),
                what: "G43.1 without a Z word".into(),
                value: "the tool length offset in effect".into(),
                option: "--tool-table (the tool table of the machine)".into(),
            })
        })?;
        Ok(Some(vec![(b'G', 43.1), (b'Z', z / before.scale())]))
    }
}

/// 0, 1, 2 for X, Y, Z.
pub(super) fn xyz_index(letter: u8) -> Option<usize> {
    match letter {
        b'X' => Some(0),
        b'Y' => Some(1),
        b'Z' => Some(2),
        _ => None,
    }
}

/// A lowered (absolute) line with `shift` (mm) added to its X Y Z.
pub(super) fn shift_line(l: &PlainLine, shift: [f64; 3], scale: f64) -> PlainLine {
    let mut l = l.clone();
    for w in &mut l.words {
        if let Some(a) = xyz_index(w.letter) {
            w.value += shift[a] / scale;
        }
    }
    l
}
