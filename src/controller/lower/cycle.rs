//! Canned cycles G73, G81–G89 as the G0/G1/G4 and spindle blocks LinuxCNC
//! 2.9 makes of them.
//!
//! The rules (LinuxCNC 2.9's interpreter; the plane's first two axes are
//! the cycle's "position" axes, the third its depth axis: G17 X Y / Z, G18
//! Z X / Y, G19 Y Z / X):
//!
//! * **Initial level.** The depth-axis position when the first cycle block
//!   since the last other motion started. Later cycle blocks keep it (even
//!   after a G99 block left the tool at R); G98 retracts to it.
//! * **Absolute (G90).** Position words are the hole position (missing ones
//!   keep the current position), R and the depth word are absolute. With
//!   polar words (G17 only) the hole is `@`·(cos, sin)(`^`), a missing word
//!   taken from the current position.
//! * **Incremental (G91).** R is relative to the initial level, the depth
//!   relative to R; position words are a step added before every repeat
//!   (polar `@`/`^` step the radius and angle of the position).
//! * **Start.** If the initial level is below R, a rapid along the depth
//!   axis only to R (at the current position), and R is the initial level
//!   from then on for this block. The clearance level is R (G99) or the
//!   initial level (G98).
//! * **Each of L repeats.** First repeat, when the tool is above R: rapid
//!   to the hole at the current depth-axis level, then down to R. Otherwise:
//!   rapid to the hole at the clearance level, then to R if the clearance
//!   is above it. Then the cycle's own moves:
//!   - G81: feed to the depth, rapid to clearance. G82: the same with a
//!     dwell P at the bottom.
//!   - G73: from R, feed down Q at a time, each peck followed by a rapid up
//!     0.254 mm (0.010 in); the last feed reaches the depth; rapid to
//!     clearance.
//!   - G83: as G73, but after each peck rapid up to R and rapid down to
//!     0.254 mm (0.010 in) above the peck's bottom.
//!   - G84 (G17 only): feed to the depth, M5, M4, dwell P (0 without),
//!     feed to clearance, M5, M3 (LinuxCNC also disables the overrides
//!     meanwhile; no block of the targets does that).
//!   - G85: feed to the depth, feed to R, rapid to clearance.
//!   - G86: feed to the depth, dwell, M5, rapid to clearance, spindle on
//!     again in its direction.
//!   - G87: rapid to the hole offset by I/J/K (in the plane's axes), M5,
//!     orient (M19 R0 P2), rapid to the depth, rapid to the hole, spindle
//!     on, feed to the back-bore level, feed to the depth, M5, orient,
//!     rapid to the offset point, up to clearance, back to the hole,
//!     spindle on.
//!   - G88: feed to the depth, dwell, M5, M0 (the operator retracts),
//!     spindle on again.
//!   - G89: feed to the depth, dwell, feed to clearance.
//! * **End.** The position is the last hole at the clearance level (also
//!   after G88, where LinuxCNC assumes the operator retracted).
//!
//! Stickiness between blocks (a block of the same cycle may leave out R,
//! the depth, Q, P, I/J/K) is kept by [`CycleState`]: call
//! [`CycleState::lower`] for every cycle block and [`CycleState::end`] when
//! any other motion (G0–G3, G80, a probe, …) runs.

use super::{LowerError, PlainLine, push};
use crate::codes::{Distance, Plane, Retract, SpindleDir, Units};

/// Which cycle.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CycleKind {
    G73,
    G81,
    G82,
    G83,
    G84,
    G85,
    G86,
    G87,
    G88,
    G89,
}

impl CycleKind {
    fn name(self) -> &'static str {
        match self {
            CycleKind::G73 => "G73",
            CycleKind::G81 => "G81",
            CycleKind::G82 => "G82",
            CycleKind::G83 => "G83",
            CycleKind::G84 => "G84",
            CycleKind::G85 => "G85",
            CycleKind::G86 => "G86",
            CycleKind::G87 => "G87",
            CycleKind::G88 => "G88",
            CycleKind::G89 => "G89",
        }
    }
}

/// The modal state a cycle block runs in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CycleModal {
    pub plane: Plane,
    pub distance: Distance,
    pub units: Units,
    pub retract: Retract,
    pub spindle: SpindleDir,
}

/// The words of one cycle block, in program units, as written (X a radius
/// in G7: convert diameters first). `None` is a word not on the line.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CycleBlock {
    /// X, Y, Z words.
    pub axes: [Option<f64>; 3],
    pub r: Option<f64>,
    /// L (repeats); `None` is 1.
    pub l: Option<u32>,
    /// P dwell in seconds (G82, G84, G86, G88, G89).
    pub p: Option<f64>,
    /// Q peck (G73, G83).
    pub q: Option<f64>,
    /// I, J, K (G87).
    pub ijk: [Option<f64>; 3],
    /// `@` polar radius, `^` polar angle in degrees (G17 only).
    pub radius: Option<f64>,
    pub angle: Option<f64>,
}

/// The blocks of one cycle block and where it leaves the tool.
#[derive(Debug, Clone, PartialEq)]
pub struct CycleOutput {
    pub lines: Vec<PlainLine>,
    /// X, Y, Z after the block, as LinuxCNC's interpreter has them.
    pub end: [f64; 3],
    /// X, Y, Z where the written blocks leave the tool, as the target (and
    /// rs274 running them) counts: `end`, except after G88, whose retract
    /// LinuxCNC leaves to the operator (it assumes the clearance level while
    /// the blocks stop at the bottom). An incremental move after a G88
    /// block must be written from `end` in absolute form.
    pub target_end: [f64; 3],
}

/// What LinuxCNC keeps between cycle blocks. Start with `default()`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CycleState {
    /// The cycle in effect (`None` after any other motion).
    active: Option<CycleKind>,
    /// Initial level of the current run of cycle blocks.
    initial_level: Option<f64>,
    r: f64,
    depth: f64,
    /// Shared by G82/G84/G86/G88/G89 and kept across other motion, as in
    /// LinuxCNC.
    p: f64,
    q: f64,
    ijk: [f64; 3],
}

/// The rapid up after each peck of G73 and the clearance above the last
/// peck of G83: 0.010 inch.
fn peck_clearance(units: Units) -> f64 {
    match units {
        Units::Inch => 0.010,
        Units::Mm => 0.010 * 25.4,
    }
}

/// G87: the offset point and the back-bore level, from I/J/K (X Y Z
/// order) taken in plane order (`map`, the plane's axes).
fn back_bore(modal: &CycleModal, map: [usize; 3], ijk: [f64; 3], bottom: f64) -> (f64, f64, f64) {
    let (off_a, off_b, middle) = (ijk[map[0]], ijk[map[1]], ijk[map[2]]);
    let middle = match modal.distance {
        Distance::Incremental => bottom + middle,
        Distance::Absolute => middle,
    };
    (off_a, off_b, middle)
}

/// One repeat's step in polar coordinates (G91 with `@`/`^`): the radius,
/// then the angle, changed about the origin.
fn polar_step(
    mut a: f64,
    mut b: f64,
    radius_step: f64,
    angle_step: f64,
) -> Result<(f64, f64), LowerError> {
    if radius_step != 0.0 {
        if a == 0.0 && b == 0.0 {
            return Err(LowerError::PolarAtOrigin);
        }
        let theta = b.atan2(a);
        let radius = b.hypot(a) + radius_step;
        a = radius * theta.cos();
        b = radius * theta.sin();
    }
    if angle_step != 0.0 {
        if a == 0.0 && b == 0.0 {
            return Err(LowerError::PolarAtOrigin);
        }
        let theta = b.atan2(a) + angle_step;
        let radius = b.hypot(a);
        a = radius * theta.cos();
        b = radius * theta.sin();
    }
    Ok((a, b))
}

/// The levels and values a cycle's moves use.
#[derive(Clone, Copy)]
struct Levels {
    /// The R level, the bottom, and the level to go back to.
    r: f64,
    bottom: f64,
    clear: f64,
    /// G87: the back-bore level and the offset point.
    middle: f64,
    offset: (f64, f64),
    /// G73/G83: the peck clearance and depth.
    delta: f64,
    q: f64,
    /// The dwell.
    p: f64,
    dir: SpindleDir,
}

/// Writes moves in plane coordinates (a, b, c) as XYZ lines.
struct Out {
    map: [usize; 3],
    lines: Vec<PlainLine>,
}

impl Out {
    fn point(&self, a: f64, b: f64, c: f64) -> [f64; 3] {
        let mut p = [0.0; 3];
        p[self.map[0]] = a;
        p[self.map[1]] = b;
        p[self.map[2]] = c;
        p
    }
    fn traverse(&mut self, a: f64, b: f64, c: f64) -> Result<(), LowerError> {
        let p = self.point(a, b, c);
        push(&mut self.lines, PlainLine::motion(0.0, p))
    }
    fn feed(&mut self, a: f64, b: f64, c: f64) -> Result<(), LowerError> {
        let p = self.point(a, b, c);
        push(&mut self.lines, PlainLine::motion(1.0, p))
    }
    fn dwell(&mut self, seconds: f64) -> Result<(), LowerError> {
        push(
            &mut self.lines,
            PlainLine::new(&[(b'G', 4.0), (b'P', seconds)]),
        )
    }
    fn m(&mut self, code: f64) -> Result<(), LowerError> {
        push(&mut self.lines, PlainLine::new(&[(b'M', code)]))
    }
    fn spindle_on(&mut self, dir: SpindleDir) -> Result<(), LowerError> {
        self.m(if dir == SpindleDir::Ccw { 4.0 } else { 3.0 })
    }
    fn orient(&mut self) -> Result<(), LowerError> {
        push(
            &mut self.lines,
            PlainLine::new(&[(b'M', 19.0), (b'R', 0.0), (b'P', 2.0)]),
        )
    }

    /// The moves of one cycle at the point (`a`, `b`) of the plane, from
    /// the R level down and back to the clearance level.
    fn drill(&mut self, kind: CycleKind, (a, b): (f64, f64), l: &Levels) -> Result<(), LowerError> {
        let Levels {
            r,
            bottom,
            clear,
            middle,
            delta,
            p,
            q,
            offset: (off_a, off_b),
            dir,
        } = *l;
        match kind {
            CycleKind::G81 => {
                self.feed(a, b, bottom)?;
                self.traverse(a, b, clear)?;
            }
            CycleKind::G82 => {
                self.feed(a, b, bottom)?;
                self.dwell(p)?;
                self.traverse(a, b, clear)?;
            }
            CycleKind::G73 | CycleKind::G83 => {
                let mut depth = r - q;
                while depth > bottom {
                    self.feed(a, b, depth)?;
                    if kind == CycleKind::G83 {
                        self.traverse(a, b, r)?;
                    }
                    self.traverse(a, b, depth + delta)?;
                    depth -= q;
                }
                self.feed(a, b, bottom)?;
                self.traverse(a, b, clear)?;
            }
            CycleKind::G84 => {
                self.feed(a, b, bottom)?;
                self.m(5.0)?;
                self.m(4.0)?;
                self.dwell(p)?;
                self.feed(a, b, clear)?;
                self.m(5.0)?;
                self.m(3.0)?;
            }
            CycleKind::G85 => {
                self.feed(a, b, bottom)?;
                self.feed(a, b, r)?;
                self.traverse(a, b, clear)?;
            }
            CycleKind::G86 => {
                self.feed(a, b, bottom)?;
                self.dwell(p)?;
                self.m(5.0)?;
                self.traverse(a, b, clear)?;
                self.spindle_on(dir)?;
            }
            CycleKind::G87 => {
                let (oa, ob) = (a + off_a, b + off_b);
                self.traverse(oa, ob, r)?;
                self.m(5.0)?;
                self.orient()?;
                self.traverse(oa, ob, bottom)?;
                self.traverse(a, b, bottom)?;
                self.spindle_on(dir)?;
                self.feed(a, b, middle)?;
                self.feed(a, b, bottom)?;
                self.m(5.0)?;
                self.orient()?;
                self.traverse(oa, ob, bottom)?;
                self.traverse(oa, ob, clear)?;
                self.traverse(a, b, clear)?;
                self.spindle_on(dir)?;
            }
            CycleKind::G88 => {
                self.feed(a, b, bottom)?;
                self.dwell(p)?;
                self.m(5.0)?;
                self.m(0.0)?;
                self.spindle_on(dir)?;
            }
            CycleKind::G89 => {
                self.feed(a, b, bottom)?;
                self.dwell(p)?;
                self.feed(a, b, clear)?;
            }
        }
        Ok(())
    }
}

impl CycleState {
    /// A motion other than a canned cycle ran (G0–G3, G80, G38, G5, …):
    /// the next cycle block starts afresh.
    pub fn end(&mut self) {
        self.active = None;
        self.initial_level = None;
    }

    /// Lowers one cycle block. `position` is the current X, Y, Z (`None`
    /// when not known: an error names the axis). On success the state is
    /// updated for the next block; on error it is unchanged.
    pub fn lower(
        &mut self,
        kind: CycleKind,
        block: &CycleBlock,
        modal: &CycleModal,
        position: [Option<f64>; 3],
    ) -> Result<CycleOutput, LowerError> {
        let mut next = *self;
        let out = next.run(kind, block, modal, position)?;
        *self = next;
        Ok(out)
    }

    fn run(
        &mut self,
        kind: CycleKind,
        block: &CycleBlock,
        modal: &CycleModal,
        position: [Option<f64>; 3],
    ) -> Result<CycleOutput, LowerError> {
        let name = kind.name();
        let same = self.active == Some(kind);
        // The plane's first, second and depth axes among X Y Z.
        let map = super::xyz_axes(modal.plane, name)?;
        let axis_letter = |i: usize| ['X', 'Y', 'Z'][i];
        let known = |i: usize| {
            position[i].ok_or(LowerError::PositionUnknown {
                axis: axis_letter(i),
            })
        };
        let cur_a = known(map[0])?;
        let cur_b = known(map[1])?;
        let current_c = known(map[2])?;

        let (r_word, repeats, depth_word) = self.cycle_start(kind, block, modal, same, map)?;
        let initial = self.initial_level.unwrap_or(current_c);
        let mut old_c = initial;
        let mut current_c = current_c;

        let (mut a, mut b) = (cur_a, cur_b);
        let (mut a_step, mut b_step, mut radius_step, mut angle_step) = (0.0, 0.0, 0.0, 0.0);
        let (r, bottom) = match modal.distance {
            Distance::Absolute => {
                if block.radius.is_some() || block.angle.is_some() {
                    let radius = block.radius.unwrap_or_else(|| cur_b.hypot(cur_a));
                    let theta = block
                        .angle
                        .map(f64::to_radians)
                        .unwrap_or_else(|| cur_b.atan2(cur_a));
                    a = radius * theta.cos();
                    b = radius * theta.sin();
                } else {
                    a = block.axes[map[0]].unwrap_or(cur_a);
                    b = block.axes[map[1]].unwrap_or(cur_b);
                }
                (r_word, depth_word)
            }
            Distance::Incremental => {
                a_step = block.axes[map[0]].unwrap_or(0.0);
                b_step = block.axes[map[1]].unwrap_or(0.0);
                radius_step = block.radius.unwrap_or(0.0);
                angle_step = block.angle.map(f64::to_radians).unwrap_or(0.0);
                let r = r_word + old_c;
                (r, r + depth_word)
            }
        };
        if r < bottom {
            return Err(LowerError::BadValue {
                construct: name,
                what: "R is below the depth",
            });
        }

        let mut out = Out {
            map,
            lines: Vec::new(),
        };
        if old_c < r {
            out.traverse(cur_a, cur_b, r)?;
            old_c = r;
            current_c = r;
        }
        let clear = match modal.retract {
            Retract::R => r,
            Retract::Initial => old_c,
        };

        // Per-cycle words, resolved before any motion so that an error
        // leaves no partial output.
        let (p, q, ijk) = self.cycle_words(kind, block, modal, same)?;
        // Refuse a runaway (a tiny Q, a huge L) before writing anything.
        let pecks = match kind {
            CycleKind::G73 | CycleKind::G83 => ((r - bottom) / q).ceil().max(0.0),
            _ => 0.0,
        };
        if (16.0 + 3.0 * pecks) * f64::from(repeats) + 1.0 > super::MAX_LINES as f64 {
            return Err(LowerError::TooManyLines);
        }
        let dir = modal.spindle;
        let (off_a, off_b, middle) = back_bore(modal, map, ijk, bottom);
        let delta = peck_clearance(modal.units);

        for repeat in 0..repeats {
            (a, b) = polar_step(a + a_step, b + b_step, radius_step, angle_step)?;
            if repeat == 0 && current_c > r {
                out.traverse(a, b, current_c)?;
                out.traverse(a, b, r)?;
            } else {
                out.traverse(a, b, clear)?;
                if clear > r {
                    out.traverse(a, b, r)?;
                }
            }
            out.drill(
                kind,
                (a, b),
                &Levels {
                    r,
                    bottom,
                    clear,
                    middle,
                    delta,
                    p,
                    q,
                    offset: (off_a, off_b),
                    dir,
                },
            )?;
        }

        self.active = Some(kind);
        self.initial_level = Some(initial);
        self.r = r_word;
        self.depth = depth_word;
        self.p = p;
        self.q = q;
        self.ijk = ijk;
        let end = out.point(a, b, clear);
        let target_end = if kind == CycleKind::G88 {
            out.point(a, b, bottom)
        } else {
            end
        };
        Ok(CycleOutput {
            lines: out.lines,
            end,
            target_end,
        })
    }

    /// What the block itself must give or the cycle keeps: the R level,
    /// the repeats and the depth; and where the cycle cannot be expressed.
    fn cycle_start(
        &self,
        kind: CycleKind,
        block: &CycleBlock,
        modal: &CycleModal,
        same: bool,
        map: [usize; 3],
    ) -> Result<(f64, u32, f64), LowerError> {
        let name = kind.name();
        let axis_letter = |i: usize| ['X', 'Y', 'Z'][i];
        if (block.radius.is_some() || block.angle.is_some()) && modal.plane != Plane::XY {
            return Err(LowerError::NotExpressible {
                construct: name,
                why: "polar coordinates are only allowed in the XY plane",
            });
        }
        if kind == CycleKind::G84 && modal.plane != Plane::XY {
            return Err(LowerError::NotExpressible {
                construct: name,
                why: "outside G17, LinuxCNC 2.9 moves to points with the axes swapped",
            });
        }
        let r_word = match (block.r, same) {
            (Some(r), _) => r,
            (None, true) => self.r,
            (None, false) => {
                return Err(LowerError::MissingWord {
                    construct: name,
                    letter: 'R',
                });
            }
        };
        let repeats = block.l.unwrap_or(1);
        if repeats == 0 {
            return Err(LowerError::BadValue {
                construct: name,
                what: "L 0 repeats",
            });
        }
        let depth_word = match (block.axes[map[2]], same) {
            (Some(z), _) => z,
            (None, true) => self.depth,
            (None, false) => {
                return Err(LowerError::MissingWord {
                    construct: name,
                    letter: axis_letter(map[2]),
                });
            }
        };
        Ok((r_word, repeats, depth_word))
    }

    /// The cycle's own words (P, Q, I/J/K), given or kept from the last
    /// block of the same cycle, and the spindle it needs.
    fn cycle_words(
        &self,
        kind: CycleKind,
        block: &CycleBlock,
        modal: &CycleModal,
        same: bool,
    ) -> Result<(f64, f64, [f64; 3]), LowerError> {
        let name = kind.name();
        let needs = |word: Option<f64>, last: f64, letter: char| match (word, same) {
            (Some(v), _) => Ok(v),
            (None, true) => Ok(last),
            (None, false) => Err(LowerError::MissingWord {
                construct: name,
                letter,
            }),
        };
        let mut p = self.p;
        let mut q = self.q;
        let mut ijk = self.ijk;
        match kind {
            CycleKind::G82 | CycleKind::G86 | CycleKind::G88 | CycleKind::G89 => {
                p = needs(block.p, self.p, 'P')?;
            }
            CycleKind::G84 => p = block.p.unwrap_or(self.p),
            CycleKind::G73 | CycleKind::G83 => {
                q = needs(block.q, self.q, 'Q')?;
                if q <= 0.0 {
                    return Err(LowerError::BadValue {
                        construct: name,
                        what: "Q is not above zero",
                    });
                }
            }
            CycleKind::G87 => {
                for (n, letter) in ['I', 'J', 'K'].into_iter().enumerate() {
                    ijk[n] = needs(block.ijk[n], self.ijk[n], letter)?;
                }
            }
            CycleKind::G81 | CycleKind::G85 => {}
        }
        match (kind, modal.spindle) {
            (CycleKind::G84, SpindleDir::Cw) => {}
            (CycleKind::G84, _) => return Err(LowerError::Spindle { construct: name }),
            (CycleKind::G86 | CycleKind::G87 | CycleKind::G88, SpindleDir::Off) => {
                return Err(LowerError::Spindle { construct: name });
            }
            (CycleKind::G87, SpindleDir::Ccw) => {
                return Err(LowerError::NotExpressible {
                    construct: name,
                    why: "LinuxCNC orients the spindle counter-clockwise (mode 3), which M19 cannot ask for",
                });
            }
            _ => {}
        }
        Ok((p, q, ijk))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn modal(plane: Plane, distance: Distance, retract: Retract) -> CycleModal {
        CycleModal {
            plane,
            distance,
            units: Units::Mm,
            retract,
            spindle: SpindleDir::Cw,
        }
    }

    fn text(lines: &[PlainLine]) -> Vec<String> {
        lines
            .iter()
            .map(|l| {
                l.words
                    .iter()
                    .map(|w| format!("{}{}", w.letter as char, w.value))
                    .collect::<Vec<_>>()
                    .join(" ")
            })
            .collect()
    }

    #[test]
    fn g81_from_above_g98() {
        let mut s = CycleState::default();
        let block = CycleBlock {
            axes: [Some(1.0), Some(2.0), Some(-5.0)],
            r: Some(2.0),
            ..Default::default()
        };
        let out = s
            .lower(
                CycleKind::G81,
                &block,
                &modal(Plane::XY, Distance::Absolute, Retract::Initial),
                [Some(0.0), Some(0.0), Some(10.0)],
            )
            .unwrap();
        assert_eq!(
            text(&out.lines),
            [
                "G0 X1 Y2 Z10",
                "G0 X1 Y2 Z2",
                "G1 X1 Y2 Z-5",
                "G0 X1 Y2 Z10"
            ]
        );
        assert_eq!(out.end, [1.0, 2.0, 10.0]);
    }

    #[test]
    fn g83_pecks_back_to_r() {
        let mut s = CycleState::default();
        let block = CycleBlock {
            axes: [Some(3.0), Some(2.0), Some(-3.0)],
            r: Some(2.0),
            q: Some(2.0),
            ..Default::default()
        };
        let out = s
            .lower(
                CycleKind::G83,
                &block,
                &modal(Plane::XY, Distance::Absolute, Retract::Initial),
                [Some(3.0), Some(2.0), Some(10.0)],
            )
            .unwrap();
        let t = text(&out.lines);
        assert_eq!(t[2], "G1 X3 Y2 Z0");
        assert_eq!(t[3], "G0 X3 Y2 Z2");
        assert_eq!(t[4], "G0 X3 Y2 Z0.254");
        assert_eq!(t.last().unwrap(), "G0 X3 Y2 Z10");
    }

    #[test]
    fn repeat_needs_r_on_entry_and_keeps_it() {
        let mut s = CycleState::default();
        let m = modal(Plane::XY, Distance::Absolute, Retract::R);
        let block = CycleBlock {
            axes: [Some(1.0), None, Some(-1.0)],
            ..Default::default()
        };
        let e = s
            .lower(CycleKind::G81, &block, &m, [Some(0.0); 3])
            .unwrap_err();
        assert_eq!(e.code(), "E1102");
        let first = CycleBlock {
            r: Some(1.0),
            ..block
        };
        s.lower(CycleKind::G81, &first, &m, [Some(0.0); 3]).unwrap();
        let again = s
            .lower(
                CycleKind::G81,
                &block,
                &m,
                [Some(1.0), Some(0.0), Some(1.0)],
            )
            .unwrap();
        assert_eq!(again.end, [1.0, 0.0, 1.0]);
    }

    #[test]
    fn spindle_and_inexpressible_refusals() {
        let block = CycleBlock {
            axes: [Some(1.0), None, Some(-1.0)],
            r: Some(1.0),
            p: Some(0.5),
            ijk: [Some(0.5), Some(0.0), Some(0.0)],
            ..Default::default()
        };
        let mut m = modal(Plane::XY, Distance::Absolute, Retract::Initial);
        m.spindle = SpindleDir::Ccw;
        let pos = [Some(0.0), Some(0.0), Some(5.0)];
        let mut s = CycleState::default();
        let e = s.lower(CycleKind::G84, &block, &m, pos).unwrap_err();
        assert_eq!(e.code(), "E1104");
        let e = s.lower(CycleKind::G87, &block, &m, pos).unwrap_err();
        assert_eq!(e.code(), "E1105");
        m.spindle = SpindleDir::Off;
        let e = s.lower(CycleKind::G86, &block, &m, pos).unwrap_err();
        assert_eq!(e.code(), "E1104");
        m.spindle = SpindleDir::Cw;
        m.plane = Plane::XZ;
        let e = s.lower(CycleKind::G84, &block, &m, pos).unwrap_err();
        assert_eq!(e.code(), "E1105");
        for plane in [Plane::UV, Plane::WU, Plane::VW] {
            m.plane = plane;
            let e = s.lower(CycleKind::G81, &block, &m, pos).unwrap_err();
            assert_eq!(e.code(), "E1105", "{plane:?}");
        }
        assert_eq!(s, CycleState::default());
    }

    #[test]
    fn g88_leaves_the_tool_at_the_bottom() {
        let block = CycleBlock {
            axes: [Some(1.0), Some(1.0), Some(-3.0)],
            r: Some(1.0),
            p: Some(0.5),
            ..Default::default()
        };
        let m = modal(Plane::XY, Distance::Absolute, Retract::Initial);
        let out = CycleState::default()
            .lower(
                CycleKind::G88,
                &block,
                &m,
                [Some(0.0), Some(0.0), Some(10.0)],
            )
            .unwrap();
        assert_eq!(out.end, [1.0, 1.0, 10.0]);
        assert_eq!(out.target_end, [1.0, 1.0, -3.0]);
        assert_eq!(text(&out.lines)[3..], ["G4 P0.5", "M5", "M0", "M3"]);
    }

    #[test]
    fn runaway_pecks_refused_before_writing() {
        let block = CycleBlock {
            axes: [None, None, Some(-100.0)],
            r: Some(1.0),
            q: Some(1e-6),
            ..Default::default()
        };
        let m = modal(Plane::XY, Distance::Absolute, Retract::Initial);
        let e = CycleState::default()
            .lower(CycleKind::G83, &block, &m, [Some(0.0); 3])
            .unwrap_err();
        assert_eq!(e, LowerError::TooManyLines);
        let e = CycleState::default()
            .lower(
                CycleKind::G81,
                &CycleBlock {
                    l: Some(u32::MAX),
                    q: None,
                    ..block
                },
                &m,
                [Some(0.0); 3],
            )
            .unwrap_err();
        assert_eq!(e, LowerError::TooManyLines);
    }

    #[test]
    fn g91_polar_step_at_origin_refused() {
        let block = CycleBlock {
            axes: [None, None, Some(-1.0)],
            r: Some(1.0),
            angle: Some(10.0),
            ..Default::default()
        };
        let m = modal(Plane::XY, Distance::Incremental, Retract::Initial);
        let e = CycleState::default()
            .lower(CycleKind::G81, &block, &m, [Some(0.0); 3])
            .unwrap_err();
        assert_eq!(e, LowerError::PolarAtOrigin);
    }

    #[test]
    fn unknown_depth_axis_position() {
        let mut s = CycleState::default();
        let block = CycleBlock {
            axes: [Some(1.0), None, Some(-1.0)],
            r: Some(1.0),
            ..Default::default()
        };
        let e = s
            .lower(
                CycleKind::G81,
                &block,
                &modal(Plane::XZ, Distance::Absolute, Retract::Initial),
                [Some(0.0), None, Some(0.0)],
            )
            .unwrap_err();
        assert_eq!(e, LowerError::PositionUnknown { axis: 'Y' });
        assert_eq!(s, CycleState::default());
    }
}
