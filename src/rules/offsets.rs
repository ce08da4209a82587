//! The offset rules both machine models follow: what G92, G52 and G10
//! (L2, L20, L1, L10, L11) write, and how a work position relates to the
//! machine's. Each model keeps its offsets its own way (the evaluator in
//! the numbered parameters, in program units, as LinuxCNC does; the model
//! after evaluation in millimetres, `None` where unknown) and hands the
//! numbers of one axis here, all in one unit; what it keeps, and whether a
//! number is known, stays its own.
//!
//! The tool-tip machine position ([`machine_tip`]) is the work position
//! with the coordinate system's offset and the G92/G52 offset added (that
//! offset 0 while G92.2 suspends it); the controlled point adds the tool
//! length offset to it.

use crate::codes::CoordSystem;

/// Which axes are lengths, X Y Z A B C U V W: A, B and C are rotary, their
/// words and offsets degrees whatever the units.
pub(crate) const LINEAR: [bool; 9] = [true, true, true, false, false, false, true, true, true];

/// Whether axis `a` (X Y Z A B C U V W) is a length (see [`LINEAR`]).
#[inline]
pub(crate) fn is_linear(a: usize) -> bool {
    LINEAR.get(a).copied().unwrap_or(true)
}

/// The coordinate system G10 L2 or L20 with the P word `p` writes: the
/// active one for P0 or no P, else G54–G59.3 for P1–P9 (P rounded, and
/// held in that range: the checks refuse any other before this).
#[inline]
pub(crate) fn g10_system(p: Option<f64>, active: CoordSystem) -> CoordSystem {
    match p.map(|v| v.round() as i64) {
        Some(0) | None => active,
        Some(n) => CoordSystem(n.clamp(1, 9) as u8),
    }
}

/// The tool tip's machine position of an axis at `work` in the active
/// coordinate system, whose offset is `g5x`, with the G92/G52 offset
/// `g92` in effect (0 when not applied).
#[inline]
pub(crate) fn machine_tip(work: f64, g5x: f64, g92: f64) -> f64 {
    work + g5x + g92
}

/// G92: the G92 offset that makes an axis at the tool-tip machine position
/// `machine` read `v` in the coordinate system whose offset is `g5x`.
#[inline]
pub(crate) fn g92_making(machine: f64, g5x: f64, v: f64) -> f64 {
    machine - g5x - v
}

/// G10 L20: the coordinate system's offset that makes an axis at the
/// tool-tip machine position `machine` read `v`, with the G92/G52 offset
/// `g92` in effect (0 when not applied).
#[inline]
pub(crate) fn g5x_making(machine: f64, g92: f64, v: f64) -> f64 {
    machine - g92 - v
}

/// G10 L10: the tool length offset that makes an axis at `work` (with the
/// tool length offset `tlo` in effect) read `v`.
#[inline]
pub(crate) fn tool_offset_l10(work: f64, tlo: f64, v: f64) -> f64 {
    work + tlo - v
}

/// G10 L11: as [`tool_offset_l10`], but for `v` in G59.3 (offset `g59_3`)
/// without G92: the offsets in effect, `g5x` and `g92`, counted in.
#[inline]
pub(crate) fn tool_offset_l11(work: f64, tlo: f64, g5x: f64, g92: f64, g59_3: f64, v: f64) -> f64 {
    work + tlo + g5x + g92 - g59_3 - v
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rules as LinuxCNC states them: after each, the position the
    /// program reads is the value the line gave.
    #[test]
    fn each_offset_makes_the_position_read_the_word() {
        let (work, g5x, g92, tlo) = (12.5, -3.25, 1.5, 7.0);
        let m = machine_tip(work, g5x, g92);
        assert_eq!(m, 10.75);
        // G92 X4: the new G92 offset makes the same machine point read 4.
        let new92 = g92_making(m, g5x, 4.0);
        assert_eq!(m - g5x - new92, 4.0);
        // G10 L20 X4: the new system offset does.
        let new5x = g5x_making(m, g92, 4.0);
        assert_eq!(m - new5x - g92, 4.0);
        // G10 L10 Z4: the new tool length offset does.
        let t = tool_offset_l10(work, tlo, 4.0);
        assert_eq!(work + tlo - t, 4.0);
        // G10 L11 Z4: in G59.3 (offset 2) without G92.
        let t = tool_offset_l11(work, tlo, g5x, g92, 2.0, 4.0);
        assert_eq!(m + tlo - 2.0 - t, 4.0);
    }

    #[test]
    fn g10_writes_the_system_p_names() {
        let active = CoordSystem(3);
        assert_eq!(g10_system(None, active), active);
        assert_eq!(g10_system(Some(0.0), active), active);
        assert_eq!(g10_system(Some(1.2), active), CoordSystem(1));
        assert_eq!(g10_system(Some(9.0), active), CoordSystem(9));
        assert_eq!(g10_system(Some(12.0), active), CoordSystem(9));
        assert!(is_linear(0) && !is_linear(3) && !is_linear(5) && is_linear(6));
    }
}
