//! Lowered motion in inverse time (G93). LinuxCNC moves a block at F times
//! the block's length as it works it out (an arc's: its start radius
//! times the angle, with the helix); a lowering writes the block as
//! several lines, and GRBL takes an inverse-time F for each G1/G2/G3 line
//! alone (and refuses one without F there, error 22). Each lowered line
//! gets the block's F scaled by the block's length over the line's, so
//! that every line moves at the block's speed.

use crate::block::{Block, FeedMode, Units};
use crate::controller::format::format_number;
use crate::machine::FlatMachine;

use super::Lowering;
use super::lower::{PlainLine, Word};

impl Lowering {
    /// Adds the inverse-time F of each G1/G2/G3 line of `lowered`, the
    /// lines a block `b` run from `before` is written as, when the program
    /// is in G93 (see the module doc).
    pub(super) fn inverse_time_feeds(
        &self,
        b: &Block,
        before: &FlatMachine,
        lowered: &mut [PlainLine],
    ) {
        if self.m.modes.feed_mode != FeedMode::InverseTime {
            return;
        }
        let Some(f) = b.value(b'F') else {
            return;
        };
        let s = before.scale();
        let [Some(x), Some(y), Some(z)] = [0, 1, 2].map(|a| before.pos[a].map(|v| v / s)) else {
            return;
        };
        let plane = self.m.modes.plane.xyz_axes().unwrap_or([0, 1, 2]);
        // The lines' lengths as the target works them out: from the
        // numbers as written.
        let decimals = match self.m.modes.units {
            Units::Mm => self.p.decimals_mm,
            Units::Inch => self.p.decimals_inch,
        };
        let digits = self.p.max_digits;
        let written = |v: f64| {
            let mut t = String::new();
            format_number(&mut t, v, decimals, digits);
            t.parse::<f64>().unwrap_or(v)
        };
        let mut at = [x, y, z].map(written);
        let mut lengths = Vec::with_capacity(lowered.len());
        // The parts of one arc: its start radius, the angle and the helix.
        let mut arc: Option<ArcPart> = None;
        let mut all_arcs = true;
        for l in lowered.iter() {
            let (len, end, part) = line_length(l, at, plane, &written);
            match part {
                Some((r, sweep, dn)) => {
                    let (r0, a, n) = arc.unwrap_or((r, 0.0, 0.0));
                    arc = Some((r0, a + sweep, n + dn));
                }
                None => all_arcs &= len.is_none(),
            }
            lengths.push(len);
            at = end;
        }
        let total = match arc {
            Some((r, sweep, dn)) if all_arcs => (r * sweep).hypot(dn),
            _ => lengths.iter().flatten().sum(),
        };
        for (l, len) in lowered.iter_mut().zip(lengths) {
            if let Some(len) = len {
                let value = if len > 0.0 && total > 0.0 {
                    f * total / len
                } else {
                    f
                };
                l.words.push(Word {
                    letter: b'F',
                    value,
                });
            }
        }
    }
}

/// An arc's start radius, the angle it turns and its helix rise.
type ArcPart = (f64, f64, f64);

/// The length of a G1/G2/G3 line from `at` as LinuxCNC works it out
/// (program units, from its numbers as `written`; `None` for any other
/// line), where it ends, and for an arc its start radius, angle and helix
/// rise.
fn line_length(
    l: &PlainLine,
    at: [f64; 3],
    plane: [usize; 3],
    written: &dyn Fn(f64) -> f64,
) -> (Option<f64>, [f64; 3], Option<ArcPart>) {
    let word = |letter: u8| {
        l.words
            .iter()
            .find(|w| w.letter == letter)
            .map(|w| written(w.value))
    };
    let mut end = at;
    for (a, letter) in [b'X', b'Y', b'Z'].into_iter().enumerate() {
        if let Some(v) = word(letter) {
            end[a] = v;
        }
    }
    let g = word(b'G').unwrap_or(-1.0);
    if g == 1.0 {
        let d: f64 = (0..3).map(|a| (end[a] - at[a]).powi(2)).sum();
        (Some(d.sqrt()), end, None)
    } else if g == 2.0 || g == 3.0 {
        let [p, q, n] = plane;
        let offset = [b'I', b'J', b'K'].map(|letter| word(letter).unwrap_or(0.0));
        let c = [at[p] + offset[p], at[q] + offset[q]];
        let angle = |v: [f64; 3]| (v[q] - c[1]).atan2(v[p] - c[0]);
        let r = |v: [f64; 3]| (v[p] - c[0]).hypot(v[q] - c[1]);
        let mut sweep = if g == 2.0 {
            angle(at) - angle(end)
        } else {
            angle(end) - angle(at)
        };
        if sweep <= 0.0 {
            sweep += std::f64::consts::TAU;
        }
        let (r0, dn) = (r(at), end[n] - at[n]);
        (Some((r0 * sweep).hypot(dn)), end, Some((r0, sweep, dn)))
    } else {
        (None, end, None)
    }
}
