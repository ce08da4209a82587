//! Lathe cycles G70 (finishing), G71/G72 (roughing along Z or X, with .1
//! no pockets and .2 pockets only): the moves LinuxCNC 2.9 makes from a
//! contour in the XZ plane.
//!
//! Points are complex numbers with Z as the real and X as the imaginary
//! part. The cycle turns the contour (flips and a quarter turn) so that it
//! runs with Z and X decreasing, cuts it there and turns each move back on
//! output. Every tolerance and every order of decision follows the
//! reference, so that the moves are the ones it makes; where the reference
//! would read outside its lists or never end, a typed error stops instead.

use std::ops::{Add, Div, Mul, Neg, Sub};

/// A point (or vector) of the XZ plane: `re` is Z, `im` is X.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub(crate) struct C {
    pub re: f64,
    pub im: f64,
}

impl C {
    pub(crate) const fn new(re: f64, im: f64) -> C {
        C { re, im }
    }
    fn conj(self) -> C {
        C::new(self.re, -self.im)
    }
    fn abs(self) -> f64 {
        self.re.hypot(self.im)
    }
    fn norm(self) -> f64 {
        self.re * self.re + self.im * self.im
    }
    /// Multiplied by the imaginary unit.
    fn rot90(self) -> C {
        C::new(-self.im, self.re)
    }
    fn scale(self, f: f64) -> C {
        C::new(self.re * f, self.im * f)
    }
    fn div_by(self, f: f64) -> C {
        C::new(self.re / f, self.im / f)
    }
}

impl Add for C {
    type Output = C;
    fn add(self, o: C) -> C {
        C::new(self.re + o.re, self.im + o.im)
    }
}
impl Sub for C {
    type Output = C;
    fn sub(self, o: C) -> C {
        C::new(self.re - o.re, self.im - o.im)
    }
}
impl Neg for C {
    type Output = C;
    fn neg(self) -> C {
        C::new(-self.re, -self.im)
    }
}
impl Mul for C {
    type Output = C;
    fn mul(self, o: C) -> C {
        C::new(
            self.re * o.re - self.im * o.im,
            self.re * o.im + self.im * o.re,
        )
    }
}
impl Div for C {
    type Output = C;
    /// Smith's division, the way the C runtime divides complex numbers.
    fn div(self, o: C) -> C {
        let (a, b, c, d) = (self.re, self.im, o.re, o.im);
        if c.abs() < d.abs() {
            let ratio = c / d;
            let denom = c * ratio + d;
            C::new((a * ratio + b) / denom, (b * ratio - a) / denom)
        } else {
            let ratio = d / c;
            let denom = d * ratio + c;
            C::new((b * ratio + a) / denom, (b - a * ratio) / denom)
        }
    }
}

const TOL: f64 = 1e-6;

/// Most moves one cycle may make (a runaway bound: tiny depths of cut).
pub(crate) const MAX_MOVES: usize = 2_000_000;

/// A move of the cycle, in program coordinates (Z real, X imaginary).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Move {
    Rapid(C),
    Feed(C),
    Arc { ccw: bool, center: C, end: C },
}

impl Move {
    pub(crate) fn end(&self) -> C {
        match *self {
            Move::Rapid(e) | Move::Feed(e) | Move::Arc { end: e, .. } => e,
        }
    }
}

/// Why a contour cannot be cut.
#[derive(Debug, Clone, PartialEq)]
pub enum LatheError {
    /// A fillet or chamfer (A/C word) that does not fit its corner; at the
    /// corner, in the cycle's turned coordinates.
    CornerFinish { z: f64, x: f64 },
    /// The contour goes back in Z or X (G71/G72) where the cycle cannot
    /// cut it.
    NotMonotonic,
    /// Two parallel lines had to be joined after offsetting.
    ParallelLines,
    /// The cut left the contour at a line it did not start on.
    LostContour,
    /// A diving line does not reach the depth of the pass.
    StraightDive,
    /// The contour collapses (nothing left to offset, or a segment with
    /// no neighbour to join).
    Degenerate,
    /// The reference never finishes this cycle (it loops forever).
    Endless,
    /// More moves than [`MAX_MOVES`].
    TooManyMoves,
}

impl std::fmt::Display for LatheError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LatheError::CornerFinish { z, x } => {
                write!(f, "corner finish failed at ({z},{x})")
            }
            LatheError::NotMonotonic => f.write_str("not monotonic"),
            LatheError::ParallelLines => f.write_str("cannot intersect parallel lines"),
            LatheError::LostContour => {
                f.write_str("the cut left the contour (\"how did we get here?\")")
            }
            LatheError::StraightDive => f.write_str("x too large in straight dive"),
            LatheError::Degenerate => f.write_str("the offset contour collapses"),
            LatheError::Endless => f.write_str("the cycle never ends (LinuxCNC loops forever)"),
            LatheError::TooManyMoves => write!(f, "more than {MAX_MOVES} moves"),
        }
    }
}

type R<T> = Result<T, LatheError>;

#[derive(Debug, Clone, Copy, PartialEq)]
enum Corner {
    No,
    Fillet,
    Chamfer,
}

/// One element of the contour: a line, or an arc with its centre.
#[derive(Debug, Clone, Copy)]
struct Seg {
    s: C,
    e: C,
    /// Direction and centre of an arc.
    arc: Option<(bool, C)>,
    finish: f64,
    corner: Corner,
}

/// Output turned back from the cycle's coordinates.
struct Out {
    flip: u8,
    moves: Vec<Move>,
    /// Most moves to make: [`MAX_MOVES`], or fewer for the output's limit.
    cap: usize,
}

impl Out {
    fn map(&self, p: C) -> C {
        match self.flip {
            1 => -p.conj(),
            2 => p.conj(),
            3 => -p,
            4 => p.rot90(),
            5 => p.rot90().conj(),
            6 => -p.rot90().conj(),
            7 => -p.rot90(),
            _ => p,
        }
    }
    fn push(&mut self, m: Move) -> R<()> {
        if self.moves.len() >= self.cap {
            return Err(LatheError::TooManyMoves);
        }
        self.moves.push(m);
        Ok(())
    }
    fn feed(&mut self, p: C) -> R<()> {
        let p = self.map(p);
        self.push(Move::Feed(p))
    }
    fn rapid(&mut self, p: C) -> R<()> {
        let p = self.map(p);
        self.push(Move::Rapid(p))
    }
    fn arc(&mut self, ccw: bool, center: C, end: C) -> R<()> {
        let ccw = if matches!(self.flip, 1 | 2 | 5 | 6) {
            !ccw
        } else {
            ccw
        };
        let (center, end) = (self.map(center), self.map(end));
        self.push(Move::Arc { ccw, center, end })
    }
}

impl Seg {
    fn line(s: C, e: C) -> Seg {
        Seg {
            s,
            e,
            arc: None,
            finish: 0.0,
            corner: Corner::No,
        }
    }
    fn round(ccw: bool, s: C, c: C, e: C) -> Seg {
        Seg {
            s,
            e,
            arc: Some((ccw, c)),
            finish: 0.0,
            corner: Corner::No,
        }
    }
    /// A copy that is a plain line or arc (corner finishes copy as such).
    fn dup(&self) -> Seg {
        Seg {
            corner: Corner::No,
            ..*self
        }
    }

    fn radius(&self) -> f64 {
        match self.arc {
            None => (self.s - self.e).abs(),
            Some((_, c)) => (self.s - self.e).abs().min((self.s - c).abs()),
        }
    }

    fn monotonic(&self) -> bool {
        match self.arc {
            None => (self.e - self.s).re <= 1e-3,
            Some((ccw, c)) => {
                if self.finish != 0.0 {
                    return true;
                }
                let entry = (self.s - c).im;
                let exit = (self.e - c).im;
                let dz = (self.e - self.s).re;
                if ccw {
                    entry >= -1e-3 && exit >= -1e-3 && dz <= -1e-3
                } else {
                    entry <= 1e-3 && exit <= 1e-3 && dz <= -1e-3
                }
            }
        }
    }

    fn flip_imag(&mut self) {
        self.s = self.s.conj();
        self.e = self.e.conj();
        if let Some((ccw, c)) = self.arc {
            self.arc = Some((!ccw, c.conj()));
        }
    }
    fn flip_real(&mut self) {
        self.s = -self.s.conj();
        self.e = -self.e.conj();
        if let Some((ccw, c)) = self.arc {
            self.arc = Some((!ccw, -c.conj()));
        }
    }
    fn rotate(&mut self) {
        self.s = -self.s.rot90();
        self.e = -self.e.rot90();
        if let Some((ccw, c)) = self.arc {
            self.arc = Some((ccw, -c.rot90()));
        }
    }
    fn shift(&mut self, d: C) {
        self.s = self.s + d;
        self.e = self.e + d;
        if let Some((ccw, c)) = self.arc {
            self.arc = Some((ccw, c + d));
        }
    }

    fn offset(&mut self, distance: f64) {
        match self.arc {
            None => {
                let d = offset_vec(self.s - self.e, distance);
                self.s = self.s + d;
                self.e = self.e + d;
            }
            Some((ccw, c)) => {
                let r = (self.s - c).abs();
                let factor = (r + if ccw { distance } else { -distance }) / r;
                self.s = (self.s - c).scale(factor) + c;
                self.e = (self.e - c).scale(factor) + c;
            }
        }
    }

    fn on_arc(&self, ccw: bool, c: C, p: C) -> bool {
        let a = ((self.s - c).conj() * (p - c)).im;
        let b = ((self.e - c).conj() * (p - c)).im;
        if ccw {
            a >= -TOL && b <= TOL
        } else {
            a <= TOL && b >= -TOL
        }
    }

    /// Z of the points of the segment at `x`.
    fn intersection_z(&self, x: f64, is: &mut Vec<f64>) {
        match self.arc {
            None => {
                let (s, e) = (self.s, self.e);
                if s.im.min(e.im) > x + TOL || s.im.max(e.im) < x - TOL {
                    return;
                }
                if (s - e).im.abs() < TOL {
                    is.push(s.re);
                    is.push(e.re);
                } else {
                    is.push((x - s.im) / (e.im - s.im) * (e.re - s.re) + s.re);
                }
            }
            Some((ccw, c)) => {
                let r = (self.s - c).abs();
                let mut s = -(x - r - c.im) * (x + r - c.im);
                if s < -TOL {
                    return;
                }
                if s < 0.0 {
                    s = 0.0;
                }
                let s = s.sqrt();
                let p1 = C::new(c.re + s, x);
                if self.on_arc(ccw, c, p1) {
                    is.push(p1.re);
                }
                let p2 = C::new(c.re - s, x);
                if self.on_arc(ccw, c, p2) {
                    is.push(p2.re);
                }
            }
        }
    }

    /// Follows the contour up from `loc`; true when it does not climb.
    fn climb(&self, loc: &mut C, out: &mut Out) -> R<bool> {
        match self.arc {
            None => {
                if self.e.im + TOL < self.s.im {
                    return Ok(true);
                }
                if (*loc - self.s).abs() > TOL {
                    return Err(LatheError::LostContour);
                }
                out.feed(self.e)?;
                *loc = self.e;
                Ok(false)
            }
            Some((false, c)) => {
                if loc.re > c.re {
                    return Ok(true);
                }
                if (*loc - self.e).abs() > 1e-3 {
                    out.arc(false, c, self.e)?;
                }
                *loc = self.e;
                Ok(false)
            }
            Some((true, c)) => {
                if loc.re < c.re {
                    return Ok(true);
                }
                let ep = self.ccw_top(c);
                if (*loc - ep).abs() > 1e-3 {
                    out.arc(true, c, ep)?;
                }
                *loc = ep;
                Ok(true)
            }
        }
    }

    /// End of a counter-clockwise arc's climb: its end, or its top.
    fn ccw_top(&self, c: C) -> C {
        if self.e.re < c.re {
            C::new(c.re, c.im + (self.s - c).abs())
        } else {
            self.e
        }
    }

    /// After the roughing pass of G71.1: along the climbing parts only.
    fn climb_only(&self, loc: &mut C, out: &mut Out) -> R<()> {
        let mut is = Vec::new();
        match self.arc {
            None => {
                if self.e.im < self.s.im {
                    return Ok(());
                }
                self.intersection_z(loc.im, &mut is);
                let Some(&z) = is.first() else {
                    return Ok(());
                };
                loc.re = z;
                out.feed(*loc)?;
                out.feed(self.e)?;
                *loc = self.e;
            }
            Some((ccw, c)) => {
                self.intersection_z(loc.im, &mut is);
                let (Some(&first), Some(&last)) = (is.first(), is.last()) else {
                    return Ok(());
                };
                if !ccw {
                    if last > c.re {
                        return Ok(());
                    }
                    loc.re = last;
                    out.feed(*loc)?;
                    if (*loc - self.e).abs() > 1e-3 {
                        out.arc(false, c, self.e)?;
                    }
                    *loc = self.e;
                } else {
                    if first < c.re {
                        return Ok(());
                    }
                    loc.re = first;
                    out.feed(*loc)?;
                    let ep = self.ccw_top(c);
                    if (*loc - ep).abs() > 1e-3 {
                        out.arc(true, c, ep)?;
                    }
                    *loc = ep;
                }
            }
        }
        Ok(())
    }

    /// Follows the contour down to depth `x`; true when it does not dive.
    fn dive(&self, loc: &mut C, x: f64, out: &mut Out, fast: bool) -> R<bool> {
        match self.arc {
            None => {
                if self.s.im <= self.e.im + TOL {
                    return Ok(true);
                }
                let target = if x < self.e.im {
                    self.e
                } else {
                    let mut is = Vec::new();
                    self.intersection_z(x, &mut is);
                    let Some(&z) = is.first() else {
                        return Err(LatheError::StraightDive);
                    };
                    C::new(z, x)
                };
                if fast {
                    out.rapid(target)?;
                } else {
                    out.feed(target)?;
                }
                *loc = target;
                Ok(false)
            }
            Some((ccw, c)) => {
                if (*loc - self.e).abs() < TOL || (*loc - self.e).re <= TOL {
                    *loc = self.e;
                    return Ok(false);
                }
                let mut is = Vec::new();
                self.intersection_z(x, &mut is);
                if is.is_empty() {
                    self.intersection_z(x - TOL, &mut is);
                }
                if ccw {
                    if loc.re - TOL > c.re {
                        return Ok(true);
                    }
                    match is.last() {
                        Some(&z) if z <= c.re => {
                            let ep = C::new(z, x);
                            out.arc(true, c, ep)?;
                            *loc = ep;
                        }
                        _ => {
                            out.arc(true, c, self.e)?;
                            *loc = self.e;
                        }
                    }
                    Ok(false)
                } else {
                    if loc.re <= c.re {
                        return Ok(true);
                    }
                    match is.first() {
                        None => {
                            out.arc(false, c, self.e)?;
                            *loc = self.e;
                        }
                        // Cut only on the far side: the pass goes deeper.
                        Some(&z) if z < c.re => {}
                        Some(&z) => {
                            let ep = C::new(z, x);
                            out.arc(false, c, ep)?;
                            *loc = ep;
                        }
                    }
                    Ok(false)
                }
            }
        }
    }

    fn draw(&self, out: &mut Out) -> R<()> {
        match self.arc {
            None => out.feed(self.e),
            Some((ccw, c)) => out.arc(ccw, c, self.e),
        }
    }
}

/// The offset of a line by `distance` to its left, as the reference
/// computes it.
fn offset_vec(v: C, distance: f64) -> C {
    // i * distance * v / |v|
    let a = C::new(0.0, distance) * v;
    let l = v.abs();
    C::new(a.re / l, a.im / l)
}

/// Joins `p`'s end and `n`'s start where the two meet.
fn intersect(p: &mut Seg, n: &mut Seg) -> R<()> {
    match (p.arc, n.arc) {
        (None, None) => {
            let rot = (n.s - n.e).conj().div_by((n.s - n.e).abs());
            let ps = (p.s - n.e) * rot;
            let pe = (p.e - n.e) * rot;
            if (ps - pe).im == 0.0 {
                return Err(LatheError::ParallelLines);
            }
            let f = ps.im / (ps - pe).im;
            let is = (ps + (pe - ps).scale(f)) / rot + n.e;
            n.s = is;
            p.e = is;
        }
        (Some((_, pc)), None) => {
            if (n.s - p.e).abs() < TOL {
                return Ok(());
            }
            let rot = (n.s - n.e).conj().div_by((n.s - n.e).abs());
            let pe = (p.e - n.e) * rot;
            let pc = (pc - n.e) * rot;
            let s = pick(n.s, pc, pe, rot, n.e);
            n.s = s;
            p.e = s;
        }
        (None, Some((_, nc))) => {
            if (n.s - p.e).abs() < TOL {
                return Ok(());
            }
            let rot = (p.s - p.e).conj().div_by((p.s - p.e).abs());
            let pe = (n.e - p.e) * rot;
            let pc = (nc - p.e) * rot;
            let s = pick(n.s, pc, pe, rot, p.e);
            n.s = s;
            p.e = s;
        }
        (Some((_, pc)), Some((_, nc))) => {
            let a = (n.s - nc).abs();
            let b = (p.s - pc).abs();
            let c = (nc - pc).abs();
            let cos_b = (c * c + a * a - b * b) / 2.0 / a / c;
            let cos_b2 = (cos_b * cos_b).min(1.0);
            let rot = C::new(cos_b, (1.0 - cos_b2).sqrt());
            let is = (rot * (pc - nc)).div_by(c).scale(a) + nc;
            p.e = is;
            n.s = is;
        }
    }
    Ok(())
}

/// Of the two points where a circle (centre `pc`, through `pe`, both in a
/// frame turned by `rot` about `origin`) crosses the frame's real axis,
/// the one nearer to `near`.
fn pick(near: C, pc: C, pe: C, rot: C, origin: C) -> C {
    let b = (pc - pe).norm() - pc.im * pc.im;
    let b = if b < 0.0 { 0.0 } else { b.sqrt() };
    let s1 = C::new(pc.re + b, 0.0) / rot + origin;
    let s2 = C::new(pc.re - b, 0.0) / rot + origin;
    if (near - s1).abs() < (near - s2).abs() {
        s1
    } else {
        s2
    }
}

/// A contour as the subroutine draws it, from the cycle's start point.
#[derive(Debug, Clone)]
pub(crate) struct Contour {
    segs: Vec<Seg>,
    last: C,
}

impl Contour {
    /// An empty contour starting at the cycle's start point.
    pub(crate) fn new(start: C) -> Contour {
        Contour {
            segs: Vec::new(),
            last: start,
        }
    }
    /// Number of elements (lines, arcs, corner finishes).
    pub(crate) fn len(&self) -> usize {
        self.segs.len()
    }
    /// Where the contour ends.
    pub(crate) fn last(&self) -> C {
        self.last
    }
    /// A straight line (G0 or G1) to `end`.
    pub(crate) fn line(&mut self, end: C) {
        self.segs.push(Seg::line(self.last, end));
        self.last = end;
    }
    /// An arc to `end` about `center`.
    pub(crate) fn arc(&mut self, ccw: bool, center: C, end: C) {
        self.segs.push(Seg::round(ccw, self.last, center, end));
        self.last = end;
    }
    /// A fillet of radius `r` (A word) at the contour's end.
    pub(crate) fn fillet(&mut self, r: f64) {
        let l = self.last;
        self.segs.push(Seg {
            s: l,
            e: l,
            arc: Some((false, l)),
            finish: r,
            corner: Corner::Fillet,
        });
    }
    /// A chamfer of size `c` (C word) at the contour's end.
    pub(crate) fn chamfer(&mut self, c: f64) {
        let l = self.last;
        self.segs.push(Seg {
            s: l,
            e: l,
            arc: None,
            finish: c,
            corner: Corner::Chamfer,
        });
    }
}

/// The cycle and its words.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Cycle {
    /// G70: `passes` (P) finishing passes from distance `d` (D) to `e` (E).
    Finish { d: f64, e: f64, passes: f64 },
    /// G71 (`face` false) or G72 (`face` true); `mode` 0 full, 1 (.1) no
    /// pockets, 2 (.2) pockets only; `u`/`w` displacement, `d` finishing
    /// distance, `i` depth of cut, `r` retract.
    Rough {
        face: bool,
        mode: u8,
        u: f64,
        w: f64,
        d: f64,
        i: f64,
        r: f64,
    },
}

/// Most passes G70 makes (P is a count).
pub(crate) const MAX_PASSES: f64 = 10_000.0;

struct Path {
    segs: Vec<Seg>,
    flip: u8,
    delta: f64,
    escape: C,
    pocket_starts: Vec<C>,
}

impl Path {
    fn new(segs: Vec<Seg>) -> Path {
        Path {
            segs,
            flip: 0,
            delta: 0.5,
            escape: C::new(0.3, 0.3),
            pocket_starts: Vec::new(),
        }
    }
    fn copy(&self) -> Path {
        Path {
            segs: self.segs.iter().map(Seg::dup).collect(),
            flip: self.flip,
            delta: self.delta,
            escape: self.escape,
            pocket_starts: Vec::new(),
        }
    }
    fn front(&self) -> R<&Seg> {
        self.segs.first().ok_or(LatheError::Degenerate)
    }
    fn back(&self) -> R<&Seg> {
        self.segs.last().ok_or(LatheError::Degenerate)
    }

    fn rotate(&mut self) {
        for s in &mut self.segs {
            s.rotate();
        }
        self.flip ^= 4;
    }

    /// Flips the contour so that it runs with Z and X decreasing.
    fn swap(&mut self) -> R<()> {
        let d = self.front()?.e - self.back()?.e;
        if d.im > 0.0 {
            for s in &mut self.segs {
                s.flip_imag();
            }
            self.flip ^= 2;
        }
        if d.re < 0.0 {
            for s in &mut self.segs {
                s.flip_real();
            }
            self.flip ^= 1;
        }
        Ok(())
    }

    fn monotonic(&mut self) -> R<()> {
        let f = self.segs.first_mut().ok_or(LatheError::Degenerate)?;
        if (f.e - f.s).re > 0.0 {
            f.s.re = f.e.re;
        }
        if self.segs.iter().all(Seg::monotonic) {
            Ok(())
        } else {
            Err(LatheError::NotMonotonic)
        }
    }

    /// Works out the fillets and chamfers between their neighbours.
    fn do_finish(&mut self) -> R<()> {
        let n = self.segs.len();
        if n >= 3 {
            for h in 1..n - 1 {
                if self.segs[h].corner != Corner::No {
                    self.corner_finish(h)?;
                }
            }
        }
        self.segs.retain(|s| s.radius() >= 1e-3);
        Ok(())
    }

    fn corner_finish(&mut self, h: usize) -> R<()> {
        let (prev, next) = (self.segs[h - 1], self.segs[h + 1]);
        let mut finish = self.segs[h].finish;
        let offset_pair = |f: f64| {
            let (mut p, mut n) = (prev.dup(), next.dup());
            p.offset(f);
            n.offset(f);
            (p, n)
        };
        let (mut p, mut n) = offset_pair(finish);
        if (p.e - n.s).re > 1e-2 {
            finish = -finish;
            (p, n) = offset_pair(finish);
        }
        if (p.e - n.s).re > 1e-2 {
            return Err(LatheError::CornerFinish {
                z: prev.e.re,
                x: prev.e.im,
            });
        }
        intersect(&mut p, &mut n)?;
        let center = (p.e + n.s).scale(0.5);
        p.offset(-finish);
        n.offset(-finish);
        self.segs[h - 1].e = p.e;
        self.segs[h + 1].s = n.s;
        let seg = &mut self.segs[h];
        seg.s = p.e;
        seg.e = n.s;
        seg.finish = finish;
        if seg.corner == Corner::Fillet {
            let ccw = (seg.s - center).im > 0.0 || (seg.e - center).im > 0.0;
            seg.arc = Some((ccw, center));
            seg.finish = 0.0;
        }
        Ok(())
    }

    /// Offsets the contour (all but its lead-in) by `distance` towards the
    /// cycle's start, in steps no larger than half the shortest segment.
    fn add_distance(&mut self, distance: f64) -> R<()> {
        let (f, b) = (*self.front()?, *self.back()?);
        let angle = (f.e - f.s) / (b.s - f.s);
        let distance = if angle.im < 0.0 { -distance } else { distance };
        let lead = self.segs.remove(0);
        let segs = &mut self.segs;
        let mut current = 0.0;
        let mut rounds = 0u32;
        while current != distance {
            rounds += 1;
            if segs.is_empty() {
                return Err(LatheError::Degenerate);
            }
            if rounds > 1_000_000 {
                return Err(LatheError::Endless);
            }
            let mut step = segs
                .iter()
                .map(|s| s.radius() / 2.0)
                .fold(1e9, f64::min)
                .min((distance - current).abs());
            if distance < 0.0 {
                step = -step;
            }
            if step == 0.0 || step.is_nan() {
                // The reference adds nothing and tries again, for ever.
                return Err(LatheError::Endless);
            }
            for s in segs.iter_mut() {
                s.offset(step);
            }
            segs.retain(|s| s.radius() >= 1e-3);
            // Arcs round the corners that opened up.
            let mut i = 0;
            while i + 1 < segs.len() {
                let n = i + 1;
                if (segs[i].e - segs[n].s).re > 1e-2 {
                    let (mut s, mut e) = (segs[i].dup(), segs[n].dup());
                    s.offset(-step);
                    e.offset(-step);
                    let center = (s.e + e.s).scale(0.5);
                    let arc = Seg::round(distance > 0.0, segs[i].e, center, segs[n].s);
                    segs.insert(n, arc);
                    i += 1;
                }
                i += 1;
            }
            // Join neighbours again, dropping what no longer fits.
            let mut i = 0;
            while i + 1 < segs.len() {
                if !segs[i].monotonic() {
                    if i == 0 {
                        return Err(LatheError::NotMonotonic);
                    }
                    if segs[i].radius() < segs[i - 1].radius() {
                        segs.remove(i);
                    } else {
                        segs.remove(i - 1);
                    }
                    i = 0;
                    if segs.len() < 2 {
                        return Err(LatheError::Degenerate);
                    }
                }
                if segs[i].radius() < 1e-3 {
                    segs.remove(i);
                    i = 0;
                } else {
                    let (a, b) = segs.split_at_mut(i + 1);
                    intersect(&mut a[i], &mut b[0])?;
                }
                i += 1;
            }
            current += step;
        }
        for i in 0..segs.len().saturating_sub(1) {
            let mid = (segs[i].e + segs[i + 1].s).scale(0.5);
            segs[i].e = mid;
            segs[i + 1].s = mid;
        }
        let mut lead = lead;
        lead.e = self.front()?.s;
        self.segs.insert(0, lead);
        Ok(())
    }

    fn g70(mut self, out: &mut Out, start: C, d: f64, e: f64, p: f64) -> R<()> {
        self.segs[0].s = start;
        let mut path = self.copy();
        path.segs.remove(0);
        path.swap()?;
        if !path.segs.iter().all(Seg::monotonic) {
            path.rotate();
            path.swap()?;
        }
        path.monotonic()?;
        if path.flip & 4 != 0 {
            self.rotate();
        }
        self.swap()?;
        self.do_finish()?;
        self.monotonic()?;
        out.flip = self.flip;
        let passes = p.clamp(-1.0, MAX_PASSES) as i64;
        for pass in (1..=passes).rev() {
            let distance = (pass - 1) as f64 * (d - e) / p + e;
            let mut path = self.copy();
            path.add_distance(distance)?;
            let f = *path.front()?;
            out.rapid(f.s)?;
            out.rapid(f.e)?;
            let n = path.segs.len();
            for s in path.segs.iter().take(n.saturating_sub(1)).skip(1) {
                s.draw(out)?;
            }
            path.back()?.draw(out)?;
        }
        Ok(())
    }

    #[allow(clippy::too_many_arguments)]
    fn rough(
        mut self,
        out: &mut Out,
        mode: u8,
        start: C,
        face: bool,
        disp: C,
        d: f64,
        i: f64,
        r: f64,
    ) -> R<()> {
        self.segs[0].s = start;
        if face {
            self.rotate();
        }
        self.swap()?;
        self.do_finish()?;
        self.monotonic()?;
        self.add_distance(d)?;
        for s in &mut self.segs {
            s.shift(disp);
        }
        out.flip = self.flip;
        self.delta = i.max(2.0 * TOL);
        self.escape = C::new(r, r);
        let fs = self.front()?.s;
        out.rapid(fs)?;
        let be = self.back()?.e;
        if be.im < fs.im {
            self.segs.push(Seg::line(be, C::new(be.re, fs.im)));
        }
        self.pocket_starts.push(fs);
        self.pocket(mode, fs, 0, out)
    }

    fn pocket(&mut self, mut cycle: u8, mut loc: C, mut p: usize, out: &mut Out) -> R<()> {
        let n = self.segs.len();
        let mut is = Vec::new();
        let mut last_entry = None;
        'pocket: loop {
            let entry = (
                p,
                loc,
                out.moves.len(),
                self.pocket_starts.len(),
                self.pocket_starts.last().copied(),
            );
            if last_entry == Some(entry) {
                return Err(LatheError::Endless);
            }
            last_entry = Some(entry);
            let mut x = self.pocket_starts.last().map_or(0.0, |s| s.im);
            if cycle == 2 {
                while p < n {
                    if self.segs[p].dive(&mut loc, -1e9, out, p == 0)? {
                        break;
                    }
                    p += 1;
                }
                cycle = 3;
            }
            while p < n {
                let before = (p, x, loc, out.moves.len());
                let mut lowered = 0u64;
                while x - TOL > loc.im {
                    x -= self.delta;
                    lowered += 1;
                    if lowered > MAX_MOVES as u64 {
                        return Err(LatheError::TooManyMoves);
                    }
                }
                if self.segs[p].dive(&mut loc, x, out, p == 0)? {
                    if cycle == 1 {
                        while p < n {
                            self.segs[p].climb_only(&mut loc, out)?;
                            p += 1;
                        }
                    } else {
                        while p < n {
                            if self.segs[p].climb(&mut loc, out)? {
                                if cycle == 3 {
                                    let top = self.pocket_starts.last().map_or(0.0, |s| s.im);
                                    if loc.im > top && self.pocket_starts.len() > 1 {
                                        self.pocket_starts.pop();
                                    }
                                    if self.pocket_starts.len() == 1 {
                                        self.pocket_starts.push(loc);
                                    }
                                }
                                continue 'pocket;
                            }
                            p += 1;
                        }
                    }
                    return Ok(());
                }
                if (loc.im - x).abs() > TOL {
                    // Beyond this segment: on to the next.
                    p += 1;
                    continue;
                }
                for ip in p..n {
                    is.clear();
                    self.segs[ip].intersection_z(loc.im, &mut is);
                    let (Some(&first), Some(&last)) = (is.first(), is.last()) else {
                        continue;
                    };
                    let dest_z = if ip != p { first } else { last };
                    let distance = (dest_z - loc.re).abs();
                    if dest_z - TOL > loc.re {
                        continue;
                    }
                    if distance < TOL {
                        if p == ip {
                            continue;
                        } else if (loc - self.segs[ip].s).abs() < TOL {
                            p = ip;
                            break;
                        } else {
                            x -= self.delta;
                            break;
                        }
                    }
                    let mut dest = C::new(dest_z, loc.im);
                    out.feed(dest)?;
                    let scale = (distance / 2.0 / self.escape.re).min(1.0);
                    let esc = self.escape.scale(scale);
                    dest = dest + esc;
                    out.rapid(dest)?;
                    out.rapid(loc - esc.conj())?;
                    if p == 0 {
                        out.rapid(loc)?;
                    } else {
                        out.feed(loc)?;
                    }
                    x -= self.delta;
                    break;
                }
                if before == (p, x, loc, out.moves.len()) {
                    return Err(LatheError::Endless);
                }
            }
            return Ok(());
        }
    }
}

#[cfg(test)]
/// The moves of a lathe cycle over `contour`, from the start point
/// `start` (the cycle's X and Z), in program coordinates.
pub(crate) fn cut(contour: &Contour, start: C, cycle: &Cycle) -> Result<Vec<Move>, LatheError> {
    match cut_partial(contour, start, cycle) {
        (moves, None) => Ok(moves),
        (_, Some(e)) => Err(e),
    }
}

/// As [`cut`], with the moves made before an error (the reference makes
/// them, one by one, before it stops; a move it refuses comes first).
#[cfg(test)]
pub(crate) fn cut_partial(
    contour: &Contour,
    start: C,
    cycle: &Cycle,
) -> (Vec<Move>, Option<LatheError>) {
    let (mut moves, err) = cut_moves(contour, start, cycle, MAX_MOVES);
    let mut cur = contour.last;
    moves.retain(|m| {
        if arc_in_place(m, cur) {
            return false;
        }
        cur = m.end();
        true
    });
    (moves, err)
}

/// Whether `m` is an arc to where the machine already is (`cur`, within
/// 0.0001 on both axes): the reference does not make it. Where the machine
/// is, for the reference, is the contour's end before the first move.
pub(crate) fn arc_in_place(m: &Move, cur: C) -> bool {
    let e = m.end();
    let same = (e.re - cur.re).abs() < 1e-4 && (e.im - cur.im).abs() < 1e-4;
    matches!(m, Move::Arc { .. }) && same
}

/// The moves of a cycle, with the error that stopped it; arcs in place
/// ([`arc_in_place`]) are still among them.
///
/// `cap` below [`MAX_MOVES`] stops the cycle after its first `cap` moves
/// with [`LatheError::TooManyMoves`]: the moves made are then the first
/// `cap` moves of the whole cycle, as moves are made in order.
pub(crate) fn cut_moves(
    contour: &Contour,
    start: C,
    cycle: &Cycle,
    cap: usize,
) -> (Vec<Move>, Option<LatheError>) {
    let mut out = Out {
        flip: 0,
        moves: Vec::new(),
        cap: cap.min(MAX_MOVES),
    };
    if contour.segs.len() <= 1 {
        return (Vec::new(), None);
    }
    let path = Path::new(contour.segs.clone());
    let r = match *cycle {
        Cycle::Finish { d, e, passes } => path.g70(&mut out, start, d, e, passes),
        Cycle::Rough {
            face,
            mode,
            u,
            w,
            d,
            i,
            r,
        } => path.rough(&mut out, mode, start, face, C::new(w, u), d, i, r),
    };
    (out.moves, r.err())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn step_contour() -> Contour {
        let mut c = Contour::new(C::new(2.0, 12.0));
        c.line(C::new(0.0, 4.0));
        c.line(C::new(-5.0, 4.0));
        c.line(C::new(-5.0, 10.0));
        c
    }

    fn rough(face: bool, mode: u8, d: f64, i: f64, r: f64) -> Cycle {
        Cycle::Rough {
            face,
            mode,
            u: 0.0,
            w: 0.0,
            d,
            i,
            r,
        }
    }

    /// The first pass and the final climb of G71 over a step, as rs274
    /// makes them (its canon, rounded to 4 places).
    #[test]
    fn g71_step_matches_reference() {
        let m = cut(
            &step_contour(),
            C::new(2.0, 12.0),
            &rough(false, 0, 1.0, 1.0, 0.5),
        )
        .unwrap();
        assert_eq!(m.len(), 40);
        let want = [
            (0, 'r', 2.0, 12.0),
            (2, 'f', -4.0, 12.0),
            (3, 'r', -3.5, 12.5),
            (6, 'r', 1.7143, 11.0),
            (36, 'r', 0.0, 5.0),
            (37, 'f', -4.0, 5.0),
            (38, 'f', -4.0, 10.0),
            (39, 'f', -4.0, 12.0),
        ];
        for (i, kind, z, x) in want {
            let (k, e) = match m[i] {
                Move::Rapid(e) => ('r', e),
                Move::Feed(e) => ('f', e),
                Move::Arc { end, .. } => ('a', end),
            };
            assert_eq!(k, kind, "move {i}");
            assert!(
                (e.re - z).abs() < 1e-4 && (e.im - x).abs() < 1e-4,
                "move {i}: {e:?}"
            );
        }
    }

    #[test]
    fn g70_follows_the_contour_offset() {
        let c = Cycle::Finish {
            d: 1.0,
            e: 0.0,
            passes: 1.0,
        };
        let m = cut(&step_contour(), C::new(2.0, 12.0), &c).unwrap();
        let ends: Vec<(f64, f64)> = m.iter().map(|m| (m.end().re, m.end().im)).collect();
        assert_eq!(
            ends,
            vec![(2.0, 12.0), (0.0, 4.0), (-5.0, 4.0), (-5.0, 10.0)],
            "{m:?}"
        );
    }

    #[test]
    fn backwards_z_is_not_monotonic() {
        let mut c = step_contour();
        c.line(C::new(-3.0, 11.0));
        let r = cut(&c, C::new(2.0, 12.0), &rough(false, 0, 1.0, 1.0, 0.5));
        assert_eq!(r, Err(LatheError::NotMonotonic));
    }

    #[test]
    fn fillet_becomes_an_arc() {
        let mut c = Contour::new(C::new(2.0, 12.0));
        c.line(C::new(0.0, 4.0));
        c.line(C::new(-5.0, 4.0));
        c.fillet(1.0);
        c.line(C::new(-5.0, 10.0));
        let f = Cycle::Finish {
            d: 0.0,
            e: 0.0,
            passes: 1.0,
        };
        let m = cut(&c, C::new(2.0, 12.0), &f).unwrap();
        assert!(m.iter().any(|m| matches!(m, Move::Arc { .. })), "{m:?}");
    }

    #[test]
    fn zero_retract_and_tiny_depth_terminate() {
        let m = cut(
            &step_contour(),
            C::new(2.0, 12.0),
            &rough(false, 0, 0.0, 0.01, 0.0),
        );
        assert!(m.is_ok_and(|m| m.len() > 100));
    }

    /// A cycle stopped by a cap has made the first moves of the whole
    /// cycle, as many as the cap, and says it made too many; a cap above
    /// its count changes nothing.
    #[test]
    fn a_capped_cycle_makes_the_first_moves() {
        let contours = [step_contour(), {
            let mut c = Contour::new(C::new(2.0, 12.0));
            c.line(C::new(0.0, 6.0));
            c.arc(false, C::new(-3.0, 6.0), C::new(-6.0, 6.0));
            c.line(C::new(-9.0, 11.0));
            c
        }];
        let cycles: Vec<Cycle> = (0..6)
            .map(|k| rough(k >= 3, k % 3, 0.0, 0.05, 0.1))
            .collect();
        let mut checked = 0;
        for c in &contours {
            for cy in &cycles {
                let (all, e) = cut_moves(c, C::new(2.0, 12.0), cy, MAX_MOVES);
                if all.len() < 20 {
                    continue;
                }
                checked += 1;
                for cap in [0, 1, 7, all.len() / 2, all.len() - 1] {
                    let (some, e) = cut_moves(c, C::new(2.0, 12.0), cy, cap);
                    assert_eq!(e, Some(LatheError::TooManyMoves));
                    assert_eq!(some[..], all[..cap]);
                }
                let again = cut_moves(c, C::new(2.0, 12.0), cy, all.len());
                assert_eq!((again.0, again.1), (all.clone(), e.clone()));
            }
        }
        assert!(checked >= 4, "{checked}");
    }
}
