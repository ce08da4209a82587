//! Cutter radius compensation (G41/G42, G41.1/G42.1) as LinuxCNC 2.9's
//! interpreter computes it.
//!
//! Everything here works in the coordinates of the compensation plane: for
//! G17 `a` is X, `b` is Y and the third coordinate is Z; for G18 (lathes)
//! `a` is Z, `b` is X and the third coordinate is Y, the order in which
//! LinuxCNC's ARC_FEED names them.
//!
//! The rules, as the reference applies them:
//!
//! * The entry move (the first move after G41/G42) goes to a point one tool
//!   radius to the side of the programmed end point, perpendicular to the
//!   line from the tool's position to that end point (for an arc, on the
//!   arc's normal there). It must be longer than the radius.
//! * Each later move is offset by the radius. Where two moves meet at a
//!   convex corner a corner arc is inserted around the programmed corner
//!   (for rapids a straight rapid instead); at a concave corner the end of
//!   the previous move is cut back to the intersection of both offset
//!   paths, which fails when the tool cannot reach it without gouging.
//! * Because of the cut-back, the compensated move of a block is held back
//!   until the next move is known (or G40, or a program stop). Moves without
//!   motion in the plane are held with it and share its cut-back end point.
//! * G40 ends the last move where it is; the next move starts there.
//! * Lathe tools (orientation 1–8, G18) control their tip, not the centre of
//!   their nose radius: the output is shifted by one radius accordingly.
//!
//! [`Comp`] keeps that state; it returns moves ([`Out`]) as they are
//! released, in order, and errors ([`CompError`]) for the block being
//! processed.

use std::f64::consts::{FRAC_PI_2, PI};
use std::fmt;

use crate::codes::{ArcDistance, Units};

/// The side of the path the tool keeps to, seen in the direction of motion.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// G41
    Left,
    /// G42
    Right,
}

impl Side {
    fn other(self) -> Side {
        match self {
            Side::Left => Side::Right,
            Side::Right => Side::Left,
        }
    }
}

/// How an arc's centre is given.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ArcCenter {
    /// I/J (or K/I in G18) offsets, relative to the arc's start (G91.1)
    /// or absolute (G90.1).
    Offsets {
        i: f64,
        j: f64,
        distance: ArcDistance,
    },
    /// An R word (negative: more than half a circle).
    Radius(f64),
}

/// A programmed arc in the compensation plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Arc {
    /// G3 (true) or G2.
    pub ccw: bool,
    pub center: ArcCenter,
    /// The P word (number of turns), 1 without one.
    pub turns: i32,
}

/// A move released by compensation, in plane coordinates.
#[derive(Debug, Clone, PartialEq)]
pub enum Out<T> {
    /// A straight move to `end` (`a`, `b`, third coordinate).
    Line { rapid: bool, end: [f64; 3], tag: T },
    /// An arc to `end` around `center`; `turn` is positive counterclockwise
    /// (its size is the number of turns); `end3` is the third coordinate
    /// at the end.
    Arc {
        end: [f64; 2],
        center: [f64; 2],
        turn: i32,
        end3: f64,
        tag: T,
    },
}

impl<T> Out<T> {
    pub fn tag(&self) -> &T {
        match self {
            Out::Line { tag, .. } | Out::Arc { tag, .. } => tag,
        }
    }
}

/// Why the reference refuses a block under cutter compensation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CompError {
    /// The entry move ends within one tool radius of where it starts.
    EntryTooShort,
    /// An entry arc ends within one tool radius of where it starts.
    EntryArcTooShort,
    /// The tool does not fit inside an arc (radius not below the arc's).
    ToolTooBigForArc,
    /// A line before a concave corner is shorter than the cut-back.
    StraightFeedGouge,
    /// The same for a rapid.
    StraightTraverseGouge,
    /// An arc into a concave corner cannot be reached, or its cut-back
    /// would make it longer than programmed.
    ArcGouge,
    /// Arc then arc around the same centre at a concave corner.
    ArcArcSameCenter,
    /// Arc then arc at a concave corner the tool cannot fit in.
    ArcArcGouge,
    /// Arc then line at a concave corner the tool cannot fit in.
    ArcLineGouge,
    /// A full-circle arc or an arc whose centre is its start or end.
    ZeroRadiusArc,
    /// The centre is not the same distance from start and end.
    RadiusMismatch,
    /// An R arc too small for the distance between its ends.
    RadiusTooSmall,
    /// An R arc that ends where it starts.
    ArcSamePoint,
    /// The compensated entry arc does not close (the reference calls this
    /// a bug in its compensation; it happens for extreme geometry).
    Inconsistent,
    /// A cut-back end point no longer on a held arc (also reported by the
    /// reference as an internal error).
    ArcRadiusChanged,
}

impl CompError {
    /// Every variant, for tables and tests.
    pub const ALL: [CompError; 15] = [
        CompError::EntryTooShort,
        CompError::EntryArcTooShort,
        CompError::ToolTooBigForArc,
        CompError::StraightFeedGouge,
        CompError::StraightTraverseGouge,
        CompError::ArcGouge,
        CompError::ArcArcSameCenter,
        CompError::ArcArcGouge,
        CompError::ArcLineGouge,
        CompError::ZeroRadiusArc,
        CompError::RadiusMismatch,
        CompError::RadiusTooSmall,
        CompError::ArcSamePoint,
        CompError::Inconsistent,
        CompError::ArcRadiusChanged,
    ];
}

impl fmt::Display for CompError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use CompError::*;
        let s = match self {
            EntryTooShort => "cutter compensation entry move is not longer than the tool radius",
            EntryArcTooShort => {
                "cutter compensation entry arc ends within the tool radius of its start"
            }
            ToolTooBigForArc => "tool radius is not less than the arc radius with compensation",
            StraightFeedGouge => {
                "the tool cannot reach this concave corner after a straight feed without gouging"
            }
            StraightTraverseGouge => {
                "the tool cannot reach this concave corner after a straight rapid without gouging"
            }
            ArcGouge => "the tool cannot reach this concave corner with an arc without gouging",
            ArcArcSameCenter => {
                "arc after arc with the same centre is invalid with cutter compensation"
            }
            ArcArcGouge => {
                "the compensated tool cannot fit in the corner between these two arcs without gouging"
            }
            ArcLineGouge => {
                "the compensated tool cannot fit in the corner between the arc and this line without gouging"
            }
            ZeroRadiusArc => "zero-radius arc",
            RadiusMismatch => "radius to end of arc differs from radius to start",
            RadiusTooSmall => "arc radius too small to reach end point",
            ArcSamePoint => "current point same as end point of arc",
            Inconsistent => {
                "cutter compensation cannot compute this entry arc (the reference reports an internal error)"
            }
            ArcRadiusChanged => {
                "cutter compensation moved a held arc's end off its circle (the reference reports an internal error)"
            }
        };
        f.write_str(s)
    }
}

/// Tolerances of the reference, in the current program units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tolerances {
    /// Smallest arc radius (0.00005 in).
    pub radius: f64,
    /// Allowed difference between start and end radius of a centre-format
    /// arc (INI `[RS274NGC]CENTER_ARC_RADIUS_TOLERANCE_*`).
    pub spiral_abs: f64,
    /// How much longer than programmed a held arc may become by a cut-back
    /// (0.001 in or 0.0254 mm).
    pub arc_growth: f64,
}

impl Tolerances {
    /// The reference's defaults for the program's units.
    pub fn default_for(units: Units) -> Self {
        match units {
            Units::Mm => Tolerances {
                radius: 0.00005 * 25.4,
                spiral_abs: 2.0 * 0.01 * std::f64::consts::SQRT_2,
                arc_growth: 0.0254,
            },
            Units::Inch => Tolerances {
                radius: 0.00005,
                spiral_abs: 2.0 * 0.001 * std::f64::consts::SQRT_2,
                arc_growth: 0.001,
            },
        }
    }
}

/// Relative tolerance of a centre-format arc's radii.
const SPIRAL_RELATIVE: f64 = 0.001;
/// Angle within which a corner counts as straight (radians).
const CORNER: f64 = 0.05;
/// The reference's tolerance for "equal".
const EQUAL: f64 = 0.0001;
/// Tolerance of the half-circle test of R arcs.
const TINY: f64 = 1e-12;

#[derive(Debug, Clone)]
enum Held<T> {
    Line {
        rapid: bool,
        /// Direction of the programmed motion (for the entry move: the
        /// direction of its offset), used to see a cut-back reverse it.
        dir: [f64; 2],
        end: [f64; 3],
        tag: T,
    },
    Arc {
        /// Programmed sweep in radians (0 for corner arcs).
        sweep: f64,
        end: [f64; 2],
        center: [f64; 2],
        turn: i32,
        end3: f64,
        tag: T,
    },
}

/// The compensation state of one program run.
#[derive(Debug, Clone)]
pub struct Comp<T> {
    side: Option<Side>,
    radius: f64,
    orientation: i32,
    xz: bool,
    tol: Tolerances,
    first: bool,
    /// Where the tool (compensated) is, and the last programmed point.
    current: [f64; 3],
    programmed: [f64; 3],
    queue: Vec<Held<T>>,
    /// The first move of the last queue that had one: the reference reads
    /// it when a corner follows a program stop that emptied the queue.
    stale_front: Option<Held<T>>,
    endpoint: Option<[f64; 2]>,
}

fn hypot(a: f64, b: f64) -> f64 {
    a.hypot(b)
}

/// Signed sweep (radians, positive counterclockwise) from `p1` to `p2`
/// around `c` for `turn` turns.
pub fn sweep(p1: [f64; 2], c: [f64; 2], turn: i32, p2: [f64; 2]) -> f64 {
    if turn == 0 {
        return 0.0;
    }
    let mut alpha = (p1[1] - c[1]).atan2(p1[0] - c[0]);
    let mut beta = (p2[1] - c[1]).atan2(p2[0] - c[0]);
    if turn > 0 {
        if beta <= alpha {
            beta += 2.0 * PI;
        }
        beta - alpha + f64::from(turn - 1) * 2.0 * PI
    } else {
        if alpha <= beta {
            alpha += 2.0 * PI;
        }
        beta - alpha + f64::from(turn + 1) * 2.0 * PI
    }
}

fn tool_inside(side: Side, turn: i32) -> bool {
    (side == Side::Left && turn > 0) || (side == Side::Right && turn < 0)
}

/// Centre and signed turns of a centre-format arc (the reference's checks).
#[allow(clippy::too_many_arguments)]
fn arc_ijk(
    tol: &Tolerances,
    ccw: bool,
    start: [f64; 2],
    end: [f64; 2],
    i: f64,
    j: f64,
    distance: ArcDistance,
    turns: i32,
) -> Result<([f64; 2], f64, i32), CompError> {
    let c = match distance {
        ArcDistance::Absolute => [i, j],
        ArcDistance::Incremental => [start[0] + i, start[1] + j],
    };
    let r1 = hypot(c[0] - start[0], c[1] - start[1]);
    let r2 = hypot(c[0] - end[0], c[1] - end[1]);
    if r1 < tol.radius || r2 < tol.radius {
        return Err(CompError::ZeroRadiusArc);
    }
    let abs_err = (r1 - r2).abs();
    let rel_err = abs_err / r1.max(r2);
    if abs_err > tol.spiral_abs * 100.0 || (rel_err > SPIRAL_RELATIVE && abs_err > tol.spiral_abs) {
        return Err(CompError::RadiusMismatch);
    }
    Ok((c, r1, if ccw { turns } else { -turns }))
}

/// Centre and signed turns of a radius-format arc.
fn arc_r(
    tol: &Tolerances,
    ccw: bool,
    start: [f64; 2],
    end: [f64; 2],
    radius: f64,
    turns: i32,
) -> Result<([f64; 2], i32), CompError> {
    if end == start {
        return Err(CompError::ArcSamePoint);
    }
    let abs_r = radius.abs();
    let mid = [(end[0] + start[0]) / 2.0, (end[1] + start[1]) / 2.0];
    let mut half = hypot(mid[0] - end[0], mid[1] - end[1]);
    if half - abs_r > tol.radius {
        return Err(CompError::RadiusTooSmall);
    }
    if half / abs_r > 1.0 - TINY {
        half = abs_r;
    }
    let dir = (end[1] - start[1]).atan2(end[0] - start[0]);
    let theta = if (!ccw && radius > 0.0) || (ccw && radius < 0.0) {
        dir - FRAC_PI_2
    } else {
        dir + FRAC_PI_2
    };
    let offset = abs_r * (half / abs_r).asin().cos();
    let c = [mid[0] + offset * theta.cos(), mid[1] + offset * theta.sin()];
    Ok((c, if ccw { turns } else { -turns }))
}

/// The centre and signed turns of a programmed arc from `start` to `end`
/// (plane coordinates), with the reference's checks of its words: the
/// same ones it makes without compensation.
pub fn arc_center(
    tol: &Tolerances,
    arc: Arc,
    start: [f64; 2],
    end: [f64; 2],
) -> Result<([f64; 2], i32), CompError> {
    match arc.center {
        ArcCenter::Radius(rr) => arc_r(tol, arc.ccw, start, end, rr, arc.turns),
        ArcCenter::Offsets { i, j, distance } => {
            let (c, _, t) = arc_ijk(tol, arc.ccw, start, end, i, j, distance, arc.turns)?;
            Ok((c, t))
        }
    }
}

impl<T: Clone> Comp<T> {
    /// Compensation off, tool at `pos`.
    pub fn new(tol: Tolerances) -> Self {
        Comp {
            side: None,
            radius: 0.0,
            orientation: 0,
            xz: false,
            tol,
            first: true,
            current: [0.0; 3],
            programmed: [0.0; 3],
            queue: Vec::new(),
            stale_front: None,
            endpoint: None,
        }
    }

    /// Tolerances for new blocks (after G20/G21 or an INI setting).
    pub fn set_tolerances(&mut self, tol: Tolerances) {
        self.tol = tol;
    }

    /// Whether compensation is on (possibly with radius 0).
    pub fn is_on(&self) -> bool {
        self.side.is_some()
    }

    /// Whether moves are being offset (on, with a radius above 0).
    pub fn is_offsetting(&self) -> bool {
        self.side.is_some() && self.radius > 0.0
    }

    /// Whether the entry move is still to come.
    pub fn is_first(&self) -> bool {
        self.first
    }

    /// Whether released moves are still held back.
    pub fn holding(&self) -> bool {
        !self.queue.is_empty()
    }

    /// The tag of the first move held back (the oldest).
    pub fn first_held(&self) -> Option<&T> {
        self.queue.first().map(|h| match h {
            Held::Line { tag, .. } | Held::Arc { tag, .. } => tag,
        })
    }

    /// The side and radius in effect (radius made positive).
    pub fn side(&self) -> Option<(Side, f64)> {
        self.side.map(|s| (s, self.radius))
    }

    /// G41/G42 (or the .1 forms): `radius` may be negative (a tool table
    /// diameter below nominal), which swaps the side. `orientation` is the
    /// lathe tool orientation (0 for mills), `xz` whether the plane is G18,
    /// `pos` the tool's position in plane coordinates.
    pub fn start(&mut self, side: Side, radius: f64, orientation: i32, xz: bool, pos: [f64; 3]) {
        let (side, radius) = if radius < 0.0 {
            (side.other(), -radius)
        } else {
            (side, radius)
        };
        self.side = Some(side);
        self.radius = radius;
        self.orientation = orientation;
        self.xz = xz;
        self.current = pos;
        if self.first {
            self.programmed = pos;
        }
    }

    /// The tool's position before a block while compensation is on and not
    /// offsetting: the programmed position.
    pub fn current(&self) -> [f64; 3] {
        self.current
    }

    /// The last programmed point.
    pub fn programmed(&self) -> [f64; 3] {
        self.programmed
    }

    /// Puts the tool's position (as the next move reads it) at `p` in the
    /// plane, leaving the programmed point and the held moves as they are.
    /// LinuxCNC's G70 does this while it reads its contour: each contour
    /// point becomes the position, so the compensated moves of the cycle
    /// start from the contour's end, offset or not.
    pub fn set_current(&mut self, p: [f64; 2]) {
        self.current[0] = p[0];
        self.current[1] = p[1];
    }

    fn lathe_shift(&self, p: [f64; 2]) -> [f64; 2] {
        if !self.xz {
            return p;
        }
        let o = self.orientation;
        let r = self.radius;
        let mut z = p[0];
        let mut x = p[1];
        if matches!(o, 2 | 6 | 1) {
            x -= r;
        }
        if matches!(o, 3 | 8 | 4) {
            x += r;
        }
        if matches!(o, 2 | 7 | 3) {
            z -= r;
        }
        if matches!(o, 1 | 5 | 4) {
            z += r;
        }
        [z, x]
    }

    fn release(&mut self, out: &mut Vec<Out<T>>) {
        self.endpoint = None;
        for h in std::mem::take(&mut self.queue) {
            out.push(match h {
                Held::Line {
                    rapid, end, tag, ..
                } => {
                    let [a, b] = self.lathe_shift([end[0], end[1]]);
                    Out::Line {
                        rapid,
                        end: [a, b, end[2]],
                        tag,
                    }
                }
                Held::Arc {
                    end,
                    center,
                    turn,
                    end3,
                    tag,
                    ..
                } => Out::Arc {
                    end: self.lathe_shift(end),
                    center: self.lathe_shift(center),
                    turn,
                    end3,
                    tag,
                },
            });
        }
    }

    fn hold(&mut self, h: Held<T>) {
        if self.queue.is_empty() {
            self.stale_front = Some(h.clone());
        }
        self.queue.push(h);
    }

    /// The first held move, or (after a stop emptied the queue) the one
    /// that was first before.
    fn front(&self) -> Option<&Held<T>> {
        self.queue.first().or(self.stale_front.as_ref())
    }

    /// Moves the end of every held move to `p`, checking that none is
    /// reversed or lengthened by it, and releases them.
    fn move_end_and_release(
        &mut self,
        p: [f64; 2],
        out: &mut Vec<Out<T>>,
    ) -> Result<(), CompError> {
        if self.queue.is_empty() {
            return Ok(());
        }
        let endpoint = self.endpoint;
        let growth = self.tol.arc_growth;
        for h in &mut self.queue {
            match h {
                Held::Arc {
                    sweep: l1,
                    end,
                    center,
                    turn,
                    ..
                } => {
                    let r1 = hypot(end[0] - center[0], end[1] - center[1]);
                    let r2 = hypot(p[0] - center[0], p[1] - center[1]);
                    if (r1 - r2).abs() > 0.01 {
                        return Err(CompError::ArcRadiusChanged);
                    }
                    if let Some(e) = endpoint {
                        let l2 = sweep(e, *center, *turn, p);
                        if *l1 != 0.0 && l2.abs() > l1.abs() + growth {
                            return Err(CompError::ArcGouge);
                        }
                    }
                    *end = p;
                }
                Held::Line {
                    rapid, dir, end, ..
                } => {
                    if let Some(e) = endpoint {
                        let dot = dir[0] * (p[0] - e[0]) + dir[1] * (p[1] - e[1]);
                        if dot < 0.0 {
                            return Err(if *rapid {
                                CompError::StraightTraverseGouge
                            } else {
                                CompError::StraightFeedGouge
                            });
                        }
                    }
                    end[0] = p[0];
                    end[1] = p[1];
                }
            }
        }
        self.release(out);
        self.endpoint = Some(p);
        Ok(())
    }

    /// A straight move (G0 when `rapid`, else G1) to the programmed `end`.
    pub fn straight(
        &mut self,
        rapid: bool,
        end: [f64; 3],
        tag: T,
        out: &mut Vec<Out<T>>,
    ) -> Result<(), CompError> {
        let Some(side) = self.side.filter(|_| self.radius > 0.0) else {
            out.push(Out::Line { rapid, end, tag });
            self.current = end;
            return Ok(());
        };
        if self.first {
            self.entry_line(side, rapid, end, tag)
        } else {
            self.next_line(side, rapid, end, tag, out)
        }
    }

    fn entry_line(
        &mut self,
        side: Side,
        rapid: bool,
        p: [f64; 3],
        tag: T,
    ) -> Result<(), CompError> {
        let c = self.current;
        let r = self.radius;
        if hypot(p[0] - c[0], p[1] - c[1]) <= r {
            return Err(CompError::EntryTooShort);
        }
        let alpha = (p[1] - c[1]).atan2(p[0] - c[0])
            + if side == Side::Left {
                FRAC_PI_2
            } else {
                -FRAC_PI_2
            };
        let end = [p[0] + r * alpha.cos(), p[1] + r * alpha.sin(), p[2]];
        self.endpoint = Some([c[0], c[1]]);
        self.hold(Held::Line {
            rapid,
            dir: [alpha.cos(), alpha.sin()],
            end,
            tag,
        });
        self.first = false;
        self.current = end;
        self.programmed = p;
        Ok(())
    }

    fn next_line(
        &mut self,
        side: Side,
        rapid: bool,
        p: [f64; 3],
        tag: T,
        out: &mut Vec<Out<T>>,
    ) -> Result<(), CompError> {
        let c = self.current;
        let op = self.programmed;
        let r = self.radius;
        if p[0] == op[0] && p[1] == op[1] {
            // No motion in the plane: held with the previous move.
            self.hold(Held::Line {
                rapid,
                dir: [0.0, 0.0],
                end: [c[0], c[1], p[2]],
                tag,
            });
            self.current = [c[0], c[1], p[2]];
            self.programmed = p;
            return Ok(());
        }
        let mut theta = (c[1] - op[1]).atan2(c[0] - op[0]);
        let mut alpha = (p[1] - op[1]).atan2(p[0] - op[0]);
        let (beta, gamma) = match side {
            Side::Left => {
                if theta < alpha {
                    theta += 2.0 * PI;
                }
                (theta - alpha - FRAC_PI_2, FRAC_PI_2)
            }
            Side::Right => {
                if alpha < theta {
                    alpha += 2.0 * PI;
                }
                (alpha - theta - FRAC_PI_2, -FRAC_PI_2)
            }
        };
        let end = [
            p[0] + r * (alpha + gamma).cos(),
            p[1] + r * (alpha + gamma).sin(),
        ];
        let mid = [
            op[0] + r * (alpha + gamma).cos(),
            op[1] + r * (alpha + gamma).sin(),
        ];
        let after_round = || match self.queue.first() {
            Some(Held::Arc { turn, .. }) => {
                (side == Side::Right && *turn > 0) || (side == Side::Left && *turn < 0)
            }
            _ => false,
        };
        let concave =
            !(-CORNER..=PI + CORNER).contains(&beta) || (beta > PI - CORNER && after_round());
        if !concave && beta > CORNER {
            // Convex corner: go around it.
            self.move_end_and_release([c[0], c[1]], out)?;
            if rapid {
                self.hold(Held::Line {
                    rapid: true,
                    dir: [0.0, 0.0],
                    end: [mid[0], mid[1], c[2]],
                    tag: tag.clone(),
                });
            } else {
                self.hold(Held::Arc {
                    sweep: 0.0,
                    end: mid,
                    center: [op[0], op[1]],
                    turn: if side == Side::Left { -1 } else { 1 },
                    end3: c[2],
                    tag: tag.clone(),
                });
            }
            self.release(out);
            self.endpoint = Some(mid);
        } else if concave {
            match self.front().cloned() {
                Some(Held::Arc {
                    end: pe,
                    center: pc,
                    turn: pturn,
                    ..
                }) => {
                    let oldrad = hypot(pc[1] - pe[1], pc[0] - pe[0]);
                    let base = (p[1] - op[1]).atan2(p[0] - op[0]);
                    let th = if pturn > 0 {
                        base + FRAC_PI_2
                    } else {
                        base - FRAC_PI_2
                    };
                    let phi = (pc[1] - op[1]).atan2(pc[0] - op[0]);
                    let inside = tool_inside(side, pturn);
                    let uncomp = if inside { oldrad + r } else { oldrad - r };
                    let d = uncomp * (th - phi).cos();
                    let l = if inside { d - r } else { d + r } / oldrad;
                    if !(-1.0..=1.0).contains(&l) {
                        return Err(CompError::ArcLineGouge);
                    }
                    let plus = (pturn > 0) != inside;
                    let ang = if plus { l.acos() } else { -l.acos() } + th + PI;
                    let m = [pc[0] + oldrad * ang.cos(), pc[1] + oldrad * ang.sin()];
                    self.move_end_and_release(m, out)?;
                }
                _ => {
                    // beta is at least -pi/2 here, so the half corner is at
                    // least pi/4 (the reference's test for a zero-degree
                    // corner cannot fire).
                    let half = (beta + PI) / 2.0;
                    let retreat = r / half.tan();
                    let m = [
                        c[0] + retreat * (theta + gamma).cos(),
                        c[1] + retreat * (theta + gamma).sin(),
                    ];
                    self.move_end_and_release(m, out)?;
                }
            }
        } else {
            // Straight on (or a tangent arc into a line).
            self.release(out);
            self.endpoint = Some([c[0], c[1]]);
        }
        self.hold(Held::Line {
            rapid,
            dir: [p[0] - op[0], p[1] - op[1]],
            end: [end[0], end[1], p[2]],
            tag,
        });
        self.current = [end[0], end[1], p[2]];
        self.programmed = p;
        Ok(())
    }

    /// An arc (G2/G3) to the programmed `end`.
    pub fn arc(
        &mut self,
        arc: Arc,
        end: [f64; 3],
        tag: T,
        out: &mut Vec<Out<T>>,
    ) -> Result<(), CompError> {
        let Some(side) = self.side.filter(|_| self.radius > 0.0) else {
            let c = self.current;
            let start = [c[0], c[1]];
            let e2 = [end[0], end[1]];
            let (center, turn) = self.arc_data(arc, start, e2)?;
            out.push(Out::Arc {
                end: e2,
                center,
                turn,
                end3: end[2],
                tag,
            });
            self.current = end;
            return Ok(());
        };
        if self.first {
            self.entry_arc(side, arc, end, tag)
        } else {
            self.next_arc(side, arc, end, tag, out)
        }
    }

    fn arc_data(
        &self,
        arc: Arc,
        start: [f64; 2],
        end: [f64; 2],
    ) -> Result<([f64; 2], i32), CompError> {
        arc_center(&self.tol, arc, start, end)
    }

    fn entry_arc(&mut self, side: Side, arc: Arc, p: [f64; 3], tag: T) -> Result<(), CompError> {
        let c = self.current;
        let r = self.radius;
        let start = [c[0], c[1]];
        let pe = [p[0], p[1]];
        if hypot(p[0] - c[0], p[1] - c[1]) <= r {
            return Err(CompError::EntryArcTooShort);
        }
        // Tool inside the arc when it turns towards the tool's side.
        let inside_by_move = (side == Side::Left && arc.ccw) || (side == Side::Right && !arc.ccw);
        let (center, turn) = match arc.center {
            ArcCenter::Radius(rr) => {
                if rr.abs() <= r && inside_by_move {
                    return Err(CompError::ToolTooBigForArc);
                }
                arc_r(&self.tol, arc.ccw, start, pe, rr, arc.turns)?
            }
            ArcCenter::Offsets { i, j, distance } => {
                let (cc, r1, t) =
                    arc_ijk(&self.tol, arc.ccw, start, pe, i, j, distance, arc.turns)?;
                if r1 <= r && inside_by_move {
                    return Err(CompError::ToolTooBigForArc);
                }
                (cc, t)
            }
        };
        let gamma = if tool_inside(side, turn) {
            (center[1] - p[1]).atan2(center[0] - p[0])
        } else {
            (p[1] - center[1]).atan2(p[0] - center[0])
        };
        self.first = false;
        self.programmed = p;
        let end = [p[0] + r * gamma.cos(), p[1] + r * gamma.sin()];
        // The compensated arc: through the tool's position and the offset
        // end, its centre on the line from that end to the programmed one.
        let b_len = hypot(c[1] - end[1], c[0] - end[0]) / 2.0;
        let ab = (center[1] - end[1]).atan2(center[0] - end[0]);
        let a_ang = (c[1] - end[1]).atan2(c[0] - end[0]) - ab;
        if a_ang.cos().abs() < EQUAL {
            return Err(CompError::ToolTooBigForArc);
        }
        let c_len = b_len / a_ang.cos();
        let nc = [end[0] + c_len * ab.cos(), end[1] + c_len * ab.sin()];
        if (hypot(nc[0] - end[0], nc[1] - end[1]) - hypot(nc[0] - c[0], nc[1] - c[1])).abs()
            > self.tol.spiral_abs
        {
            return Err(CompError::Inconsistent);
        }
        if self.orientation != 0 && self.orientation != 9 {
            self.hold(Held::Line {
                rapid: false,
                dir: [0.0, 0.0],
                end: c,
                tag: tag.clone(),
            });
            self.endpoint = Some(start);
        }
        let sw = sweep(start, nc, turn, end);
        self.hold(Held::Arc {
            sweep: sw,
            end,
            center: nc,
            turn,
            end3: p[2],
            tag,
        });
        self.current = [end[0], end[1], p[2]];
        Ok(())
    }

    fn next_arc(
        &mut self,
        side: Side,
        arc: Arc,
        p: [f64; 3],
        tag: T,
        out: &mut Vec<Out<T>>,
    ) -> Result<(), CompError> {
        let op = self.programmed;
        let c = self.current;
        let r = self.radius;
        let start = [op[0], op[1]];
        let pe = [p[0], p[1]];
        let (center, turn) = self.arc_data(arc, start, pe)?;
        let arc_radius = hypot(center[0] - p[0], center[1] - p[1]);
        let mut theta = (c[1] - op[1]).atan2(c[0] - op[0]);
        theta = if side == Side::Left {
            theta - FRAC_PI_2
        } else {
            theta + FRAC_PI_2
        };
        let mut delta = (center[1] - op[1]).atan2(center[0] - op[0]);
        let alpha = if arc.ccw {
            delta - FRAC_PI_2
        } else {
            delta + FRAC_PI_2
        };
        let mut beta = if side == Side::Left {
            theta - alpha
        } else {
            alpha - theta
        };
        if beta > 1.5 * PI {
            beta -= 2.0 * PI;
        } else if beta < -FRAC_PI_2 {
            beta += 2.0 * PI;
        }
        let inside_by_move = (side == Side::Left && arc.ccw) || (side == Side::Right && !arc.ccw);
        let gamma = if inside_by_move {
            if arc_radius <= r {
                return Err(CompError::ToolTooBigForArc);
            }
            (center[1] - p[1]).atan2(center[0] - p[0])
        } else {
            delta += PI;
            (p[1] - center[1]).atan2(p[0] - center[0])
        };
        let new_end = [p[0] + r * gamma.cos(), p[1] + r * gamma.sin()];
        let inside = tool_inside(side, turn);
        let sw = sweep(start, center, turn, pe);
        let concave =
            !(-CORNER..=PI + CORNER).contains(&beta) || ((beta - PI).abs() < CORNER && !inside);
        if concave {
            match self.front().cloned() {
                Some(Held::Arc {
                    end: qe,
                    center: qc,
                    turn: qturn,
                    ..
                }) => {
                    let newrad = if inside {
                        arc_radius - r
                    } else {
                        arc_radius + r
                    };
                    let m = arc_arc_meet(side, (qe, qc, qturn), center, turn, newrad)?;
                    self.move_end_and_release(m, out)?;
                }
                _ => {
                    let cy = arc_radius * (beta - FRAC_PI_2).sin();
                    let (dist, toward) = if inside {
                        (arc_radius - r, cy + r)
                    } else {
                        (arc_radius + r, cy - r)
                    };
                    let l = toward / dist;
                    if !(-1.0..=1.0).contains(&l) {
                        return Err(CompError::ArcGouge);
                    }
                    let ang = if inside {
                        if turn > 0 {
                            theta + l.asin()
                        } else {
                            theta - l.asin()
                        }
                    } else if turn > 0 {
                        theta + PI - l.asin()
                    } else {
                        theta + PI + l.asin()
                    };
                    let m = [center[0] + dist * ang.cos(), center[1] + dist * ang.sin()];
                    self.move_end_and_release(m, out)?;
                }
            }
        } else if beta > CORNER {
            // Convex: a corner arc first.
            let mid = [op[0] + r * delta.cos(), op[1] + r * delta.sin()];
            self.release(out);
            self.hold(Held::Arc {
                sweep: 0.0,
                end: mid,
                center: start,
                turn: if side == Side::Left { -1 } else { 1 },
                end3: c[2],
                tag: tag.clone(),
            });
            self.release(out);
            self.endpoint = Some(mid);
        } else {
            self.release(out);
            self.endpoint = Some([c[0], c[1]]);
        }
        self.hold(Held::Arc {
            sweep: sw,
            end: new_end,
            center,
            turn,
            end3: p[2],
            tag,
        });
        self.programmed = p;
        self.current = [new_end[0], new_end[1], p[2]];
        Ok(())
    }

    /// A program stop (M0, M1, M2, M30, M60): the held moves are released
    /// where they end. M2/M30 also turn compensation off (`end`).
    pub fn stop(&mut self, end: bool, out: &mut Vec<Out<T>>) -> Result<(), CompError> {
        let c = self.current;
        self.move_end_and_release([c[0], c[1]], out)?;
        self.release(out);
        if end {
            self.side = None;
            self.first = true;
        }
        Ok(())
    }

    /// G40: the held moves are released where they end, and the next move
    /// starts from the tool's position. Returns whether the next move must be
    /// straight (the reference refuses an arc right after G40).
    pub fn off(&mut self, out: &mut Vec<Out<T>>) -> Result<bool, CompError> {
        let mut straight_next = false;
        if self.side.is_some() && self.radius > 0.0 && !self.first {
            let c = self.current;
            self.move_end_and_release([c[0], c[1]], out)?;
            self.release(out);
            self.current = self.programmed;
            straight_next = true;
        }
        self.side = None;
        self.first = true;
        Ok(straight_next)
    }

    /// G20/G21: the positions, the radius and any held moves are converted
    /// (the reference scales the remembered corner point once per held
    /// move).
    pub fn scale(&mut self, f: f64) {
        for v in self.current.iter_mut().chain(self.programmed.iter_mut()) {
            *v *= f;
        }
        self.radius *= f;
        if self.queue.is_empty() {
            return;
        }
        if let Some(e) = &mut self.endpoint {
            let n = self.queue.len() as i32;
            e[0] *= f.powi(n);
            e[1] *= f.powi(n);
        }
        for h in &mut self.queue {
            match h {
                Held::Arc {
                    end, center, end3, ..
                } => {
                    end[0] *= f;
                    end[1] *= f;
                    *end3 *= f;
                    center[0] *= f;
                    center[1] *= f;
                }
                Held::Line { end, .. } => {
                    for v in end.iter_mut() {
                        *v *= f;
                    }
                }
            }
        }
    }
}

/// Where the offset path of a held arc (end `qe`, centre `qc`, turn
/// `qturn`) meets the offset circle of radius `newrad` around `center` of
/// the next arc (turn `turn`), at a concave corner between the two arcs.
fn arc_arc_meet(
    side: Side,
    (qe, qc, qturn): ([f64; 2], [f64; 2], i32),
    center: [f64; 2],
    turn: i32,
    newrad: f64,
) -> Result<[f64; 2], CompError> {
    let oldrad = hypot(qc[1] - qe[1], qc[0] - qe[0]);
    let arc_cc = hypot(qc[1] - center[1], qc[0] - center[0]);
    if oldrad == 0.0 || arc_cc == 0.0 {
        return Err(CompError::ArcArcSameCenter);
    }
    let a = (oldrad * oldrad + arc_cc * arc_cc - newrad * newrad) / (2.0 * oldrad * arc_cc);
    if !(-1.0..=1.0).contains(&a) {
        return Err(CompError::ArcArcGouge);
    }
    let pullback = a.acos();
    let cc_dir = (center[1] - qc[1]).atan2(center[0] - qc[0]);
    let plus = tool_inside(side, qturn) == (turn > 0);
    let dir = if plus {
        cc_dir + pullback
    } else {
        cc_dir - pullback
    };
    Ok([qc[0] + oldrad * dir.cos(), qc[1] + oldrad * dir.sin()])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn inch() -> Comp<u32> {
        Comp::new(Tolerances::default_for(Units::Inch))
    }

    fn line_end(o: &Out<u32>) -> [f64; 3] {
        match o {
            Out::Line { end, .. } => *end,
            Out::Arc { .. } => panic!("expected a line, got {o:?}"),
        }
    }

    #[test]
    fn entry_offsets_perpendicular_and_holds_the_move() {
        let mut c = inch();
        let mut out = Vec::new();
        c.start(Side::Left, 0.25, 0, false, [0.0, 0.0, 0.0]);
        c.straight(false, [1.0, 0.0, 0.0], 1, &mut out).unwrap();
        assert!(out.is_empty() && c.holding());
        c.straight(false, [2.0, 0.0, 0.0], 2, &mut out).unwrap();
        assert_eq!(out.len(), 1);
        let e = line_end(&out[0]);
        assert!((e[0] - 1.0).abs() < 1e-12 && (e[1] - 0.25).abs() < 1e-12);
        // A left turn on the left side is concave: the held line is cut back.
        c.straight(false, [2.0, 1.0, 0.0], 3, &mut out).unwrap();
        let e = line_end(&out[1]);
        assert!(
            (e[0] - 1.75).abs() < 1e-12 && (e[1] - 0.25).abs() < 1e-12,
            "{e:?}"
        );
        // A right turn is convex: a corner arc around the programmed corner.
        c.straight(false, [3.0, 1.0, 0.0], 4, &mut out).unwrap();
        match &out[3] {
            Out::Arc { center, turn, .. } => {
                assert_eq!(*center, [2.0, 1.0]);
                assert_eq!(*turn, -1);
            }
            o => panic!("expected the corner arc, got {o:?}"),
        }
        assert!(c.off(&mut out).unwrap());
        assert_eq!(c.programmed(), [3.0, 1.0, 0.0]);
        assert!(!c.holding());
    }

    #[test]
    fn set_current_moves_where_the_next_move_starts() {
        let mut c = inch();
        let mut out = Vec::new();
        c.start(Side::Left, 0.25, 0, false, [0.0, 0.0, 0.0]);
        c.straight(true, [1.0, 0.0, 0.0], 1, &mut out).unwrap();
        c.set_current([5.0, 2.0]);
        assert_eq!(c.current(), [5.0, 2.0, 0.0]);
        assert_eq!(c.programmed(), [1.0, 0.0, 0.0]);
        // A move to the programmed point again has no motion in the plane:
        // it goes to the position set, held with the move before.
        c.straight(true, [1.0, 0.0, 0.0], 2, &mut out).unwrap();
        assert!(out.is_empty());
        c.stop(false, &mut out).unwrap();
        assert_eq!(out.len(), 2);
        assert_eq!(line_end(&out[1]), [5.0, 2.0, 0.0]);
    }

    #[test]
    fn negative_radius_swaps_the_side() {
        let mut c = inch();
        c.start(Side::Left, -0.1, 0, false, [0.0; 3]);
        assert_eq!(c.side(), Some((Side::Right, 0.1)));
    }

    #[test]
    fn entry_too_short() {
        let mut c = inch();
        let mut out = Vec::new();
        c.start(Side::Right, 0.25, 0, false, [0.0; 3]);
        let r = c.straight(false, [0.25, 0.0, 0.0], 1, &mut out);
        assert_eq!(r, Err(CompError::EntryTooShort));
    }

    #[test]
    fn arc_data_errors_of_the_reference() {
        let mut c = inch();
        let mut out = Vec::new();
        c.start(Side::Left, 0.1, 0, false, [0.0; 3]);
        c.straight(false, [1.0, 0.0, 0.0], 1, &mut out).unwrap();
        let r_arc = |r: f64| Arc {
            ccw: false,
            center: ArcCenter::Radius(r),
            turns: 1,
        };
        // An R arc whose radius cannot span the chord.
        let r = c.arc(r_arc(0.4), [2.0, 0.0, 0.0], 2, &mut out);
        assert_eq!(r, Err(CompError::RadiusTooSmall));
        // An R arc ending where it starts.
        let r = c.arc(r_arc(0.4), [1.0, 0.0, 0.0], 2, &mut out);
        assert_eq!(r, Err(CompError::ArcSamePoint));
        // Centre offsets of different radii.
        let ijk = Arc {
            ccw: true,
            center: ArcCenter::Offsets {
                i: 0.5,
                j: 0.0,
                distance: ArcDistance::Incremental,
            },
            turns: 1,
        };
        let r = c.arc(ijk, [1.5, 0.6, 0.0], 2, &mut out);
        assert_eq!(r, Err(CompError::RadiusMismatch));
    }

    #[test]
    fn lathe_orientation_shifts_the_output() {
        let mut c = inch();
        let mut out = Vec::new();
        // G18: a = Z, b = X; orientation 2 moves both back by the radius.
        c.start(Side::Left, 0.1, 2, true, [0.0; 3]);
        c.straight(false, [1.0, 0.0, 0.0], 1, &mut out).unwrap();
        c.stop(true, &mut out).unwrap();
        let e = line_end(&out[0]);
        assert!(
            (e[0] - 0.9).abs() < 1e-12 && (e[1] - 0.0).abs() < 1e-12,
            "{e:?}"
        );
        assert!(!c.is_on());
    }

    #[test]
    fn units_scale_held_moves() {
        let mut c = inch();
        let mut out = Vec::new();
        c.start(Side::Left, 0.1, 0, false, [0.0; 3]);
        c.straight(false, [1.0, 0.0, 0.0], 1, &mut out).unwrap();
        c.scale(25.4);
        assert_eq!(c.programmed(), [25.4, 0.0, 0.0]);
        c.stop(false, &mut out).unwrap();
        let e = line_end(&out[0]);
        assert!(
            (e[0] - 25.4).abs() < 1e-9 && (e[1] - 2.54).abs() < 1e-9,
            "{e:?}"
        );
    }
}
