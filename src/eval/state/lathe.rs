//! Lathe cycles G70–G72 in the machine model: the cycle whose contour
//! subroutine is running, the contour its lines add to, and the moves the
//! cycle makes (`crate::geom::lathe`) once it returns. Reading the contour's
//! lines, calling its subroutine and writing the moves are the evaluator's
//! steps (`eval/exec/lathe.rs`).

use std::rc::Rc;

use crate::diag::LatheError;
use crate::emit::number_string;
use crate::geom::lathe::{self, C, Contour, Cycle, MAX_MOVES, Move, cut_moves};
use crate::program::FileIndex;

use super::cutter_check::Written;
use super::{Machine, Unknown};
use crate::codes::{
    ArcDistance, CutterComp, Distance, FeedMode, LatheMode, MotionMode, Plane, Units,
};
use crate::rules::Modes;

/// A cycle whose contour subroutine is running.
pub(crate) struct LatheRun {
    /// Number of frames once the subroutine has returned.
    pub(in crate::eval) level: usize,
    /// The cycle line.
    file: Rc<FileIndex>,
    start: u32,
    line: u32,
    cycle: Cycle,
    begin: C,
    contour: Contour,
    /// The contour's current point (where the next element starts).
    point: C,
    /// Whether a contour line has moved the point (LinuxCNC then reads the
    /// position as the point).
    moved: bool,
    /// An arc's radius was too small for its chord: LinuxCNC reads on and
    /// refuses the contour at the `endsub` line.
    short_radius: bool,
    /// Motion mode the contour lines take.
    motion: MotionMode,
    distance: Distance,
    arc_distance: ArcDistance,
    /// Where the machine is while the contour is read (after the rapid).
    at: (Result<f64, Unknown>, Result<f64, Unknown>),
}

/// What a contour line adds.
enum Element {
    Line(C),
    Arc(bool, C, C),
}

/// The cycle's moves once its contour subroutine has returned
/// ([`Machine::finish_contour`]).
pub(in crate::eval) struct Finished {
    /// The moves, up to the first geometry error (`failed`).
    pub(in crate::eval) moves: Vec<Move>,
    pub(in crate::eval) failed: Option<lathe::LatheError>,
    /// The moves stopped at the cap on their number, before the geometry's
    /// own limit.
    pub(in crate::eval) capped: bool,
    /// Compensation offsets the path.
    pub(in crate::eval) offsets: bool,
    /// Where LinuxCNC's compensation now reads the tool's position (plane
    /// coordinates), when it changed.
    pub(in crate::eval) comp_point: Option<[f64; 2]>,
    /// The cycle line: its file, start and index.
    pub(in crate::eval) file: Rc<FileIndex>,
    pub(in crate::eval) start: u32,
    pub(in crate::eval) line: u32,
    /// The contour's last point.
    pub(in crate::eval) last: C,
}

impl Machine {
    /// The checks of a G70–G72 block (`code`: its name, `number` 70, 71
    /// or 72; `q`: its Q word) after its other words acted; `computes_comp`:
    /// the output computes the compensation into the path. Returns the Q
    /// word and whether the evaluator writes the compensated path itself
    /// (see [`Written`]).
    pub(in crate::eval) fn lathe_checks(
        &self,
        code: String,
        number: u8,
        q: Option<f64>,
        computes_comp: bool,
    ) -> Result<(f64, bool), LatheError> {
        let Some(q) = q else {
            return Err(LatheError::NoQ { code });
        };
        let comp = self.modal.cutter_comp != CutterComp::Off;
        if comp && number != 70 {
            return Err(LatheError::WithComp { code });
        }
        if self.modal.plane != Plane::XZ {
            return Err(LatheError::NotXz { code });
        }
        if q.fract() != 0.0 || !(0.0..1e9).contains(&q) {
            return Err(LatheError::BadQ { q });
        }
        let write = comp && self.written_g70(computes_comp);
        if comp && !write {
            self.g70_comp(computes_comp)?;
        }
        Ok((q, write))
    }

    /// Where the cycle of a block with `words` starts (Z, X) and where its
    /// rapid goes; `[cx, cz]`: the programmed position of X and Z, which
    /// the rapid reads a missing axis from (the start reads the tool's:
    /// with compensation, its offset position).
    pub(in crate::eval) fn lathe_begin(&self, [cx, cz]: [f64; 2], words: &[(u8, f64)]) -> (C, C) {
        let word = |l: u8| words.iter().rev().find(|w| w.0 == l).map(|w| w.1);
        let comp = self.modal.cutter_comp != CutterComp::Off;
        let (mut x, mut z) = match self.comp_current().filter(|_| comp) {
            Some([a, b, _]) => (b, a),
            None => (cx, cz),
        };
        if self.modal.distance == Distance::Absolute {
            x = word(b'x').unwrap_or(x);
            z = word(b'z').unwrap_or(z);
        } else {
            x += word(b'x').unwrap_or(0.0);
            z += word(b'z').unwrap_or(0.0);
        }
        // The rapid to the start is made with the words taken as absolute.
        let rapid = C::new(word(b'z').unwrap_or(cz), word(b'x').unwrap_or(cx));
        (C::new(z, x), rapid)
    }

    /// The output turns compensation off before a G70 whose path the
    /// evaluator writes (see [`Written`]), from where the tool is.
    pub(in crate::eval) fn start_written_path(&mut self) {
        let p = |i: usize| self.pos.axes[i].clone().unwrap_or(0.0);
        self.comp_written = Written::Cycle {
            at: [p(0), p(1), p(2)],
        };
    }

    /// The cycle of a G70–G72 block (`number`, `sub`; its `words`) starts
    /// reading its contour from `begin`, at frame `level`; the block is
    /// line `line` at `start` of `file`.
    pub(in crate::eval) fn begin_contour(
        &mut self,
        (number, sub): (u8, u8),
        words: &[(u8, f64)],
        (file, start, line): (&Rc<FileIndex>, u32, u32),
        level: usize,
        begin: C,
    ) {
        let word = |l: u8| words.iter().rev().find(|w| w.0 == l).map(|w| w.1);
        self.lathe = Some(Box::new(LatheRun {
            level,
            file: file.clone(),
            start,
            line,
            cycle: lathe_cycle(number, sub, word),
            begin,
            contour: Contour::new(begin),
            point: begin,
            moved: false,
            short_radius: false,
            motion: self.modal.motion,
            distance: self.modal.distance,
            arc_distance: self.modal.arc_distance,
            at: (self.pos.axes[0].clone(), self.pos.axes[2].clone()),
        }));
    }

    /// The modes a contour line is checked in: the motion the contour has
    /// reached.
    pub(in crate::eval) fn contour_modes(&self) -> Modes {
        let mut modal = self.modal.clone();
        if let Some(run) = self.lathe.as_deref() {
            modal.motion = run.motion;
        }
        modal
    }

    /// A line of the contour with `words` (evaluated, not empty) and its
    /// motion `code`, if it has one: its axis, I/K/R and A/C words and its
    /// motion add to the contour (of at most `max_contour` elements).
    pub(in crate::eval) fn add_to_contour(
        &mut self,
        words: &[(u8, f64)],
        code: Option<MotionMode>,
        max_contour: usize,
    ) -> Result<(), LatheError> {
        let word = |l: u8| words.iter().rev().find(|w| w.0 == l).map(|w| w.1);
        let lathe = self.modal.lathe;
        let Some(run) = self.lathe.as_deref() else {
            return Ok(());
        };
        let (distance, arc_distance) = (run.distance, run.arc_distance);
        let point = run.point;
        let mut end = contour_end(&word, point, distance, lathe)?;
        let (iw, kw) = (word(b'i'), word(b'k'));
        let mut center = C::new(kw.unwrap_or(0.0), iw.unwrap_or(0.0));
        if distance == Distance::Incremental {
            end = end + point;
        }
        let motion = code.unwrap_or(run.motion);
        let mut add: Option<Element> = None;
        let mut short_radius = false;
        if end != point {
            match motion {
                MotionMode::Rapid | MotionMode::Linear => add = Some(Element::Line(end)),
                MotionMode::ArcCw | MotionMode::ArcCcw => {
                    if let Some(r) = word(b'r') {
                        if iw.is_some() || kw.is_some() {
                            return Err(LatheError::ArcRAndIk);
                        }
                        match center_from_radius(point, end, r, motion == MotionMode::ArcCcw) {
                            Some(c) => center = c,
                            // Refused at the `endsub` (finish_lathe); the
                            // contour goes on from the arc's end.
                            None => short_radius = true,
                        }
                    } else {
                        if iw.is_none() && kw.is_none() {
                            return Err(LatheError::ArcNoIk);
                        }
                        if arc_distance == ArcDistance::Incremental {
                            center = center + point;
                        }
                    }
                    let ccw = motion == MotionMode::ArcCcw;
                    add = Some(if short_radius {
                        Element::Line(end)
                    } else {
                        Element::Arc(ccw, center, end)
                    });
                }
                _ => {}
            }
        }
        let corner = if end != point
            && matches!(
                motion,
                MotionMode::Rapid | MotionMode::Linear | MotionMode::ArcCw | MotionMode::ArcCcw
            ) {
            let (a, c) = (word(b'a'), word(b'c'));
            if a.is_some() && c.is_some() {
                return Err(LatheError::AAndC);
            }
            (a, c)
        } else {
            (None, None)
        };
        let Some(run) = self.lathe.as_deref_mut() else {
            return Ok(());
        };
        run.motion = motion;
        run.short_radius |= short_radius;
        if end != point {
            if run.contour.len() >= max_contour {
                // Every element is at least one move of the cycle: a
                // longer contour (a loop in its subroutine that never
                // ends) fails now, not after filling the memory.
                let limit = max_contour;
                return Err(LatheError::ContourTooLong { limit });
            }
            match add {
                Some(Element::Line(e)) => run.contour.line(e),
                Some(Element::Arc(ccw, c, e)) => run.contour.arc(ccw, c, e),
                None => {}
            }
            if let Some(a) = corner.0 {
                run.contour.fillet(a);
            }
            if let Some(c) = corner.1 {
                run.contour.chamfer(c);
            }
            run.point = end;
            run.moved = true;
            self.pos.axes[0] = Ok(end.im);
            self.pos.axes[2] = Ok(end.re);
        }
        Ok(())
    }

    /// The contour subroutine returned: the cycle's moves, made up to
    /// `cap` of them (the output's lines left allow no more), and the
    /// position put where the machine is. Refused where the contour is.
    pub(in crate::eval) fn finish_contour(
        &mut self,
        cap: usize,
    ) -> Option<Result<Finished, LatheError>> {
        let run = self.lathe.take()?;
        if run.short_radius {
            return Some(Err(LatheError::ArcRadiusTooSmall));
        }
        if let Cycle::Rough { i, .. } = run.cycle
            && i <= 0.0
            && run.contour.len() > 1
        {
            return Some(Err(LatheError::INotPositive));
        }
        // The moves made before a geometry error are checked first: the
        // reference makes them before it stops.
        let (moves, failed) = cut_moves(&run.contour, run.begin, &run.cycle, cap);
        let capped = cap < MAX_MOVES && failed == Some(lathe::LatheError::TooManyMoves);
        // With compensation offsetting the path, the position LinuxCNC's
        // compensation reads is the contour's end (set while reading it),
        // the programmed position the rapid's end.
        let offsets = self.comp_offsets() == Some(true);
        let mut comp_point = None;
        if self.modal.cutter_comp != CutterComp::Off && run.moved {
            let p = [run.point.re, run.point.im];
            self.comp_set_current(p);
            comp_point = Some(p);
        }
        // The moves start where the machine is (LinuxCNC's position is the
        // contour's end, which only its arcs' skip test reads).
        if !moves.is_empty() || offsets {
            (self.pos.axes[0], self.pos.axes[2]) = run.at.clone();
        }
        Some(Ok(Finished {
            moves,
            failed,
            capped,
            offsets,
            comp_point,
            last: run.contour.last(),
            file: run.file,
            start: run.start,
            line: run.line,
        }))
    }

    /// Whether the evaluator writes the compensated path of this G70 itself
    /// (see [`Written`]): the output keeps G41/G42 (`computes_comp`: it
    /// does not), the compensation offsets and the cycle's rapid is its
    /// entry move, in the modes the written moves are read in (G90,
    /// G91.1, G8, no G93).
    fn written_g70(&self, computes_comp: bool) -> bool {
        let m = &self.modal;
        !computes_comp
            && self.comp_entry_next()
            && self.comp_written == Written::No
            && m.distance == Distance::Absolute
            && m.arc_distance == ArcDistance::Incremental
            && m.lathe == LatheMode::Radius
            && m.feed_mode != FeedMode::InverseTime
    }

    /// Whether G70 can run with the cutter compensation that is on: it can
    /// where the compensation offsets nothing (radius zero), or where the
    /// output computes it into the path (`computes_comp`) and its geometry
    /// is known here.
    fn g70_comp(&self, computes_comp: bool) -> Result<(), LatheError> {
        match self.comp_offsets() {
            Some(false) => Ok(()),
            Some(true) if computes_comp => Ok(()),
            Some(true) | None if !computes_comp => Err(LatheError::G70Comp {
                why: "LinuxCNC moves the position its compensation reads to the contour's end while reading the contour, so the cycle's compensated moves start from there (it rapids toward the contour's end first); G0/G1/G2/G3 lines under G41/G42 cannot reproduce that. The path is written as plain moves only where the G70's rapid is the compensation's entry move (G41/G42 just before it), in G90, G91.1 and G8; else flatten for a target that computes the compensation into the path (--target grbl, grblhal or fluidnc), or turn it off (G40) before G70",
            }),
            Some(true) | None => Err(LatheError::G70Comp {
                why: "the compensation's path is not known here (the tool's diameter or the position is unknown: give --tool-table and --start-position, or --zero-start)",
            }),
        }
    }

    /// The compensated path of a G70 is written (see [`Written`]);
    /// compensation is still on in the program.
    pub(in crate::eval) fn end_written_path(&mut self) {
        self.comp_written = Written::After;
    }

    /// Whether the compensated path of a G70 is being written (see
    /// [`Written`]).
    pub(in crate::eval) fn writes_path(&self) -> bool {
        matches!(self.comp_written, Written::Cycle { .. })
    }

    /// The lines of the moves the compensation released while a G70's
    /// path is written (see [`Written`]): plain absolute G0/G1/G2/G3 (Z and
    /// X in the plane, Y the third axis; arc centres as offsets from the
    /// start), numbers with `precision`; then, if a move has no such line,
    /// why.
    pub(in crate::eval) fn comp_path_lines(
        &mut self,
        precision: Option<u8>,
    ) -> (Vec<String>, Result<(), &'static str>) {
        let Written::Cycle { mut at } = self.comp_written else {
            return (Vec::new(), Ok(()));
        };
        let mut lines = Vec::new();
        for m in self.comp_take_out() {
            let (words, end) = match comp_line(m, at, self.modal.units) {
                Ok(w) => w,
                Err(why) => return (lines, Err(why)),
            };
            let mut text = String::with_capacity(64);
            for &(l, v) in &words {
                if !text.is_empty() {
                    text.push(' ');
                }
                text.push(l as char);
                text.push_str(&number_string(v, precision));
            }
            lines.push(text);
            at = end;
        }
        self.comp_written = Written::Cycle { at };
        (lines, Ok(()))
    }

    /// The words of one move of a cycle, in the modes in effect, from
    /// where the tool is.
    pub(in crate::eval) fn lathe_move_words(&self, m: Move) -> Vec<(u8, f64)> {
        let cx = self.pos.axes[0].clone().unwrap_or(0.0);
        let cz = self.pos.axes[2].clone().unwrap_or(0.0);
        let (g, end, center) = match m {
            Move::Rapid(e) => (0.0, e, None),
            Move::Feed(e) => (1.0, e, None),
            Move::Arc { ccw, center, end } => (if ccw { 3.0 } else { 2.0 }, end, Some(center)),
        };
        let (xw, zw) = if self.modal.distance == Distance::Absolute {
            (end.im, end.re)
        } else if self.modal.lathe == LatheMode::Diameter {
            (end.im - 2.0 * cx, end.re - cz)
        } else {
            (end.im - cx, end.re - cz)
        };
        let mut words = vec![(b'g', g), (b'x', xw), (b'z', zw)];
        if let Some(c) = center {
            if self.modal.arc_distance == ArcDistance::Absolute {
                words.push((b'i', c.im));
                words.push((b'k', c.re));
            } else {
                words.push((b'i', c.im - cx));
                words.push((b'k', c.re - cz));
            }
        }
        words
    }
}

/// A written line of a compensated path (its words) and where it ends.
type PathLine = (Vec<(u8, f64)>, [f64; 3]);

/// The words of a move of the compensated path (plane coordinates Z, X,
/// third Y) from `at` (X Y Z), and where it ends. An arc whose start and
/// end lie at radii more than 0.005 mm apart (LinuxCNC releases such arcs
/// in some corners) has no G2/G3: `Err` says why.
fn comp_line(
    m: crate::geom::cutter_comp::Out<()>,
    at: [f64; 3],
    units: Units,
) -> Result<PathLine, &'static str> {
    use crate::geom::cutter_comp::Out;
    match m {
        Out::Line { rapid, end, .. } => {
            let e = [end[1], end[2], end[0]];
            let g = if rapid { 0.0 } else { 1.0 };
            Ok((vec![(b'G', g), (b'X', e[0]), (b'Y', e[1]), (b'Z', e[2])], e))
        }
        Out::Arc {
            end,
            center,
            turn,
            end3,
            ..
        } => {
            let e = [end[1], end3, end[0]];
            let r1 = (center[0] - at[2]).hypot(center[1] - at[0]);
            let r2 = (center[0] - end[0]).hypot(center[1] - end[1]);
            let tol = match units {
                Units::Mm => 0.005,
                Units::Inch => 0.005 / 25.4,
            };
            if (r1 - r2).abs() > tol {
                return Err(
                    "an arc of the compensated path starts and ends at different distances from its centre (a corner LinuxCNC cuts off its circle), which no G2/G3 writes",
                );
            }
            let g = if turn > 0 { 3.0 } else { 2.0 };
            let mut w = vec![
                (b'G', g),
                (b'X', e[0]),
                (b'Y', e[1]),
                (b'Z', e[2]),
                (b'I', center[1] - at[0]),
                (b'K', center[0] - at[2]),
            ];
            if turn.abs() > 1 {
                w.push((b'P', f64::from(turn.abs())));
            }
            Ok((w, e))
        }
    }
}

/// The cycle a G70 (`number` 70) or G71/G72 (71, 72 and `sub` 0, 1, 2)
/// block asks for, from its words.
fn lathe_cycle(number: u8, sub: u8, word: impl Fn(u8) -> Option<f64>) -> Cycle {
    if number == 70 {
        Cycle::Finish {
            d: word(b'd').unwrap_or(0.0),
            e: word(b'e').unwrap_or(0.0),
            passes: word(b'p').unwrap_or(1.0),
        }
    } else {
        Cycle::Rough {
            face: number == 72,
            mode: sub,
            u: word(b'u').unwrap_or(0.0),
            w: word(b'w').unwrap_or(0.0),
            d: word(b'd').unwrap_or(0.0),
            i: word(b'i').unwrap_or(1.0),
            r: word(b'r').unwrap_or(0.5),
        }
    }
}

/// The end of a contour move before the incremental offset is added: U/W
/// (absolute mode only) add to the current point, X/Z replace it (from
/// zero in incremental mode).
fn contour_end(
    word: &impl Fn(u8) -> Option<f64>,
    point: C,
    distance: Distance,
    lathe: LatheMode,
) -> Result<C, LatheError> {
    let absolute = distance == Distance::Absolute;
    let mut end = if absolute { point } else { C::new(0.0, 0.0) };
    if let Some(u) = word(b'u') {
        if !absolute {
            return Err(LatheError::UIncremental);
        }
        if word(b'x').is_some() {
            return Err(LatheError::UAndX);
        }
        end.im += match lathe {
            LatheMode::Diameter => u / 2.0,
            LatheMode::Radius => u,
        };
    } else if let Some(x) = word(b'x') {
        end.im = x;
    }
    if let Some(w) = word(b'w') {
        if !absolute {
            return Err(LatheError::WIncremental);
        }
        if word(b'z').is_some() {
            return Err(LatheError::WAndZ);
        }
        end.re += w;
    } else if let Some(z) = word(b'z') {
        end.re = z;
    }
    Ok(end)
}

/// The centre of the arc of radius `r` from `point` to `end` (counter-
/// clockwise: `ccw`); `None` when the radius is too small for the chord.
fn center_from_radius(point: C, end: C, r: f64, ccw: bool) -> Option<C> {
    let chord = end - point;
    let n = chord.re * chord.re + chord.im * chord.im;
    let f = ((r * r - n / 4.0) / n).sqrt();
    if !f.is_finite() {
        return None;
    }
    let mid = C::new((point.re + end.re) / 2.0, (point.im + end.im) / 2.0);
    // i * f * chord
    let d = C::new(-f * chord.im, f * chord.re);
    Some(if ccw {
        C::new(mid.re + d.re, mid.im + d.im)
    } else {
        C::new(mid.re - d.re, mid.im - d.im)
    })
}
