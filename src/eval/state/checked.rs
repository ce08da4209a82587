//! A line's G and M codes as the block checks (`eval/read/validate.rs`)
//! decoded and accepted them, which the update of the machine model acts
//! on ([`Machine::apply_codes`](super::Machine::apply_codes)): the checks
//! hand them down, so that the codes are decoded once a line.

use crate::codes::{GCode, MCode, MotionMode as M};

/// G80: it may share a line with another motion code (which wins).
pub(in crate::eval) const G80: GCode = GCode::Motion(M::CancelCycle);

/// What the checks hand on with a block they accept: its G and M codes,
/// decoded once, for the state update to act on.
#[derive(Clone, Copy)]
pub(in crate::eval) enum Checked {
    /// The fast acceptance took it: G0/G1 moves with axis, F and S words,
    /// whose one code is in its G word (read only when the state update
    /// needs it, off the common path).
    Simple,
    /// The block's codes.
    Line(LineCodes),
    /// A lathe cycle block: its codes, and the index of the cycle's G word.
    Lathe(LineCodes, usize),
}

impl Checked {
    /// The block's M codes, in line order: one for each of its M words
    /// (the k-th code is the k-th M word's), none for a simple block.
    #[inline]
    pub(in crate::eval) fn ms(&self) -> &[MCode] {
        match self {
            Checked::Simple => &[],
            Checked::Line(c) | Checked::Lathe(c, _) => c.ms(),
        }
    }
}

/// A block's G and M codes in line order, as the checks decoded and
/// accepted them. A G80 that gave way to another motion code on its line
/// is left out: it changes nothing there.
#[derive(Clone, Copy)]
pub(in crate::eval) struct LineCodes {
    g: [GCode; 16],
    gn: u8,
    m: [MCode; 16],
    mn: u8,
    /// A G80 of the line was left out beside another motion code (the
    /// one that wins, or another G80).
    g80_gave_way: bool,
}

impl LineCodes {
    fn empty() -> LineCodes {
        LineCodes {
            g: [G80; 16],
            gn: 0,
            m: [MCode::Other(0); 16],
            mn: 0,
            g80_gave_way: false,
        }
    }

    /// The codes the full check accepted (at most 16 of each, as its
    /// lists), without their word indices.
    pub(in crate::eval) fn of(
        gs: &[(GCode, usize)],
        ms: &[(MCode, usize)],
        g80_gave_way: bool,
    ) -> LineCodes {
        let mut c = LineCodes::empty();
        for (k, &(g, _)) in gs.iter().enumerate() {
            c.g[k] = g;
        }
        for (k, &(m, _)) in ms.iter().enumerate() {
            c.m[k] = m;
        }
        c.gn = gs.len() as u8;
        c.mn = ms.len() as u8;
        c.g80_gave_way = g80_gave_way;
        c
    }

    /// The codes of a block the fast acceptance took: G0 or G1 from its G
    /// word (the only values it takes), no M code.
    pub(in crate::eval) fn simple(words: &[(u8, f64)]) -> LineCodes {
        let mut c = LineCodes::empty();
        for &(l, v) in words {
            if l == b'g' {
                let m = if v == 0.0 { M::Rapid } else { M::Linear };
                c.g[0] = GCode::Motion(m);
                c.gn = 1;
            }
        }
        c
    }

    /// The G codes, in line order.
    #[inline]
    pub(in crate::eval) fn gs(&self) -> &[GCode] {
        &self.g[..self.gn as usize]
    }

    /// The M codes, in line order (one for each M word).
    #[inline]
    pub(in crate::eval) fn ms(&self) -> &[MCode] {
        &self.m[..self.mn as usize]
    }

    /// The codes of a lathe cycle block's other words, which act before
    /// the cycle: without the cycle's code, with a G80 that gave way to it
    /// in its place.
    pub(in crate::eval) fn without_lathe_cycle(&self) -> LineCodes {
        let mut c = *self;
        let cycle = |g: &GCode| matches!(g, GCode::Motion(M::LatheCycle { .. }));
        if let Some(k) = c.gs().iter().position(cycle) {
            if c.g80_gave_way {
                c.g[k] = G80;
                c.g80_gave_way = false;
            } else {
                c.g.copy_within(k + 1..c.gn as usize, k);
                c.gn -= 1;
            }
        }
        c
    }
}
