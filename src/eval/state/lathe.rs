//! Lathe cycles G70–G72 in the evaluator: the cycle block rapids to its
//! start, the contour subroutine (Q) runs with its motion collected instead
//! of written (its parameters and control flow as usual), and on its return
//! the moves the cycle makes (`crate::geom::lathe`) are written as plain
//! G0/G1/G2/G3 lines and applied to the state model.

use std::rc::Rc;

use crate::diag::{Error, ErrorKind, LatheError, Site};
use crate::emit::number_string;
use crate::geom::lathe::{self, C, Contour, Cycle, MAX_MOVES, Move, arc_in_place, cut_moves};
use crate::parse::Name;
use crate::parse::ast::{Item, Line, LineKind};
use crate::program::{FileIndex, Window, next_line};

use super::ccomp::Written;
use crate::codes::{
    ArcDistance, CutterComp, Distance, FeedMode, GCode, LatheMode, MotionMode, Plane, Units,
};
use crate::eval::flow::{FrameKind, SubRec};
use crate::eval::read::validate::{Checked, LineCodes, check_block, check_contour_line};
use crate::eval::{Interp, file_key, read_error};

/// A cycle whose contour subroutine is running.
pub(crate) struct LatheRun {
    /// Number of frames once the subroutine has returned.
    level: usize,
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
    at: (
        Result<f64, crate::eval::state::Unknown>,
        Result<f64, crate::eval::state::Unknown>,
    ),
}

/// What a contour line adds.
enum Element {
    Line(C),
    Arc(bool, C, C),
}

fn lathe(k: LatheError) -> ErrorKind {
    ErrorKind::Lathe(k)
}

/// A contour line's evaluated words, and its motion code if it has one.
type ContourWords = (Vec<(u8, f64)>, Option<MotionMode>);

impl Interp<'_> {
    fn lathe_err(&self, k: LatheError, file: &Rc<FileIndex>, start: u32, len: u32) -> Error {
        self.error(lathe(k), file, start, start + len)
    }

    /// A block with G70–G72 (checked: its `codes`, and `at` the index of
    /// the cycle's G word): its other words act first, then the rapid to
    /// the cycle's start and the contour subroutine's call.
    pub(in crate::eval) fn lathe_block(
        &mut self,
        file: &Rc<FileIndex>,
        start: u32,
        len: u32,
        words: &[(u8, f64)],
        codes: &LineCodes,
        at: usize,
    ) -> Result<(), Error> {
        // G70 (70, 0) or G71/G72 and their .1 and .2 (71, 1).
        let (number, sub) = codes
            .gs()
            .iter()
            .find_map(|&g| match g {
                GCode::Motion(MotionMode::LatheCycle { number, sub }) => Some((number, sub)),
                _ => None,
            })
            .unwrap_or((0, 0));
        let mut others: Vec<(u8, f64)> = Vec::new();
        let word = |l: u8| words.iter().rev().find(|w| w.0 == l).map(|w| w.1);
        for (i, &(l, v)) in words.iter().enumerate() {
            match l {
                _ if i == at => {}
                b'q' | b'd' | b'e' | b'i' | b'p' | b'r' | b'u' | b'w' | b'x' | b'z' => {}
                _ => others.push((l, v)),
            }
        }
        let name = GCode::Motion(MotionMode::LatheCycle { number, sub }).name();
        // The block's other words act before its motion.
        let mut ends = false;
        if others.iter().any(|w| w.0 != b'n') {
            let mut text = String::new();
            for &(l, v) in &others {
                if !text.is_empty() {
                    text.push(' ');
                }
                text.push(l.to_ascii_uppercase() as char);
                text.push_str(&number_string(v, self.s.precision));
            }
            self.emit_raw(text.as_bytes())?;
            let checked = Checked::Line(codes.without_lathe_cycle());
            ends = self.apply_words(file, start, &others, &checked, false)?;
        }
        let Some(q) = word(b'q') else {
            return Err(self.lathe_err(LatheError::NoQ { code: name }, file, start, len));
        };
        let comp = self.mach.modal.cutter_comp != CutterComp::Off;
        if comp && number != 70 {
            return Err(self.lathe_err(LatheError::WithComp { code: name }, file, start, len));
        }
        if self.mach.modal.plane != Plane::XZ {
            return Err(self.lathe_err(LatheError::NotXz { code: name }, file, start, len));
        }
        if q.fract() != 0.0 || !(0.0..1e9).contains(&q) {
            return Err(self.lathe_err(LatheError::BadQ { q }, file, start, len));
        }
        let write = comp && self.written_g70();
        if comp
            && !write
            && let Err(k) = self.g70_comp()
        {
            return Err(self.lathe_err(k, file, start, len));
        }
        let span = crate::parse::ast::Span::new(0, len);
        // The rapid reads a missing axis from the programmed position, the
        // cycle's start from the tool's (with compensation: its offset
        // position).
        let cx = self
            .mach
            .programmed_position(0, span)
            .map_err(|f| self.fault_in_line(*f, file, start))?;
        let cz = self
            .mach
            .programmed_position(2, span)
            .map_err(|f| self.fault_in_line(*f, file, start))?;
        let (mut x, mut z) = match self.mach.comp_current().filter(|_| comp) {
            Some([a, b, _]) => (b, a),
            None => (cx, cz),
        };
        if self.mach.modal.distance == Distance::Absolute {
            x = word(b'x').unwrap_or(x);
            z = word(b'z').unwrap_or(z);
        } else {
            x += word(b'x').unwrap_or(0.0);
            z += word(b'z').unwrap_or(0.0);
        }
        let cycle = lathe_cycle(number, sub, word);
        // The rapid to the start is made with the words taken as absolute.
        let rapid = C::new(word(b'z').unwrap_or(cz), word(b'x').unwrap_or(cx));
        if write {
            // The output turns compensation off and gets the path itself.
            self.emit_raw(b"G40")?;
            let p = |i: usize| self.mach.pos.axes[i].clone().unwrap_or(0.0);
            self.mach.comp_written = Written::Cycle {
                at: [p(0), p(1), p(2)],
            };
        }
        self.lathe_move(file, start, len, Move::Rapid(rapid))?;
        if ends {
            // An M2 on the cycle line: LinuxCNC ends before the contour.
            return self.end_program();
        }
        let label = Name::new(&(q as i64).to_string());
        let target = self.contour_sub(file, start, len, &label)?;
        let level = self.enter_contour(file, start, len, label, &target)?;
        let begin = C::new(z, x);
        self.mach.lathe = Some(Box::new(LatheRun {
            level,
            file: file.clone(),
            start,
            line: self.reader.line_idx,
            cycle,
            begin,
            contour: Contour::new(begin),
            point: begin,
            moved: false,
            short_radius: false,
            motion: self.mach.modal.motion,
            distance: self.mach.modal.distance,
            arc_distance: self.mach.modal.arc_distance,
            at: (self.mach.pos.axes[0].clone(), self.mach.pos.axes[2].clone()),
        }));
        Ok(())
    }

    /// Enters the contour subroutine as a call without arguments; returns
    /// the frame level the cycle runs at.
    fn enter_contour(
        &mut self,
        file: &Rc<FileIndex>,
        start: u32,
        len: u32,
        label: Name,
        target: &SubRec,
    ) -> Result<usize, Error> {
        let ret = self.flow.cur.clone();
        let level = self.flow.frames.len();
        let mut f = self.flow.new_frame(FrameKind::Call, label.clone());
        if self.flow.level() + 1 > crate::eval::flow::MAX_CALL_LEVEL {
            return Err(self.error(
                ErrorKind::TooDeep {
                    limit: crate::eval::flow::MAX_CALL_LEVEL,
                },
                file,
                start,
                start + len,
            ));
        }
        f.ret = Some(ret);
        self.flow.frames.push(f);
        // A call without arguments.
        self.bind_args(&[0.0; 30], 0.0);
        self.flow
            .subs
            .entry(label.clone())
            .or_insert_with(|| target.clone());
        self.flow.called.insert(label.clone());
        self.flow.last_called = Some(label);
        self.flow.goto(&target.file, target.oidx, true);
        Ok(level)
    }

    /// The contour subroutine: one already defined, one in a file of the
    /// search path, or one defined further on in this file.
    fn contour_sub(
        &mut self,
        file: &Rc<FileIndex>,
        start: u32,
        len: u32,
        label: &Name,
    ) -> Result<SubRec, Error> {
        if let Some(rec) = self.flow.subs.get(label) {
            return Ok(rec.clone());
        }
        let err = |s: &Self, k: ErrorKind| s.error(k, file, start, start + len);
        let found = self.loader.find(label).map_err(|k| err(self, k))?;
        let (sub_file, from) = match found.clone() {
            Some(f) => (f, 0),
            None => (file.clone(), self.reader.line_idx),
        };
        let target = sub_file.occ(label).iter().copied().find(|&j| {
            sub_file.kind_of(j) == Some(crate::parse::ast::OKind::Sub)
                && sub_file.olines[j as usize].line_idx >= from
        });
        match target {
            Some(t) => Ok(SubRec {
                file: sub_file,
                oidx: t,
            }),
            None => {
                let kind = ErrorKind::SubNotFound {
                    name: label.to_string(),
                    searched: self.loader.searched(),
                };
                if found.is_some() {
                    return Err(err(self, kind));
                }
                // LinuxCNC looks for the definition further on in this
                // file and names the line where its search stops.
                let (a, b) = self.search_end(file, start)?;
                Err(self.error(kind, file, a, b))
            }
        }
    }

    /// The line a forward search from the line at `start` ends at: the
    /// closing `%` of a program that opens with one, or the file's last
    /// line (the line at `start` if none follows); its start and end.
    fn search_end(&self, file: &Rc<FileIndex>, start: u32) -> Result<(u32, u32), Error> {
        let from = self.reader.line_idx;
        let stop = file
            .percent_after(from)
            .filter(|_| Rc::ptr_eq(file, &self.main) && self.main.percent_start);
        let len = file.file.len();
        let mut window = Window::default();
        let (mut pos, mut idx) = (start, from);
        loop {
            let (end, next) = match file.file.memory() {
                Some(data) => {
                    let (end, next, _) = next_line(data, pos as usize);
                    (end as u32, next as u32)
                }
                None => {
                    let l = window
                        .line(&file.file, pos)
                        .map_err(|e| read_error(file, e))?;
                    (pos + (l.b - l.a) as u32, l.next)
                }
            };
            if stop == Some(idx) || next as u64 >= len {
                return Ok((pos, end));
            }
            (pos, idx) = (next, idx + 1);
        }
    }

    /// One line while the contour subroutine runs.
    pub(in crate::eval) fn step_contour(&mut self) -> Result<(), Error> {
        let file = self.flow.cur.file.clone();
        let start = self.flow.cur.pos;
        if start as u64 >= file.file.len() {
            return self.end_of_file(&file);
        }
        let line_idx = self.flow.cur.line;
        self.reader.at(start, line_idx);
        if let Some(oidx) = self.take_oline(&file, line_idx)? {
            self.exec_oline(&file, oidx)?;
            if self
                .mach
                .lathe
                .as_ref()
                .is_some_and(|l| l.level == self.flow.frames.len())
            {
                let end = file.olines[oidx as usize].line_len();
                return self.finish_lathe(&file, start, end);
            }
            return Ok(());
        }
        let mut window = std::mem::take(&mut self.reader.window);
        let r = self.contour_read(&file, start, line_idx, &mut window);
        self.reader.window = window;
        r
    }

    fn contour_read(
        &mut self,
        file: &Rc<FileIndex>,
        start: u32,
        line_idx: u32,
        window: &mut Window,
    ) -> Result<(), Error> {
        if let Some(data) = file.file.memory()
            && let Some((line, _, next)) = self.flow.cache.get(&(file_key(file), line_idx))
        {
            let (line, next) = (line.clone(), *next);
            let _ = data;
            self.flow.cur.pos = next;
            self.flow.cur.line += 1;
            return self.contour_line(file, start, &line);
        }
        let (raw, next, terminated): (Vec<u8>, u32, bool) = match file.file.memory() {
            Some(data) => {
                let (end, next, t) = next_line(data, start as usize);
                (data[start as usize..end].to_vec(), next as u32, t)
            }
            None => {
                let l = window
                    .line(&file.file, start)
                    .map_err(|e| read_error(file, e))?;
                (window.bytes(&l).to_vec(), l.next, l.terminated)
            }
        };
        self.flow.cur.pos = next;
        self.flow.cur.line += 1;
        let line = self.parse_line(file, start, &raw, terminated)?;
        self.contour_line(file, start, &line)
    }

    /// The words of a contour line, evaluated, and its motion code if it
    /// has one; its assignments done. The line's codes and words are
    /// checked as the reference checks every line the contour runs
    /// ([`check_contour_line`], in the motion the contour has reached): a G
    /// word it does not read as a code, two codes of one group, a word no
    /// code on the line uses are refused there.
    fn contour_words(
        &mut self,
        file: &Rc<FileIndex>,
        start: u32,
        items: &[Item],
    ) -> Result<ContourWords, Error> {
        let mut words: Vec<(u8, f64)> = Vec::new();
        let mut spans = Vec::new();
        let mut num_set = Vec::new();
        let mut named_set = Vec::new();
        for item in items {
            match item {
                Item::Word(w) => {
                    let v = self
                        .eval_value(&w.value)
                        .map_err(|f| self.fault_in_line(*f, file, start))?;
                    words.push((w.letter, v));
                    spans.push(w.span);
                }
                Item::Assign(a) => {
                    self.read_assign(file, start, a, &mut num_set, &mut named_set)?
                }
                Item::Comment(_) => {}
            }
        }
        let mut code = None;
        if !words.is_empty() {
            let mut modal = self.mach.modal.clone();
            if let Some(run) = self.mach.lathe.as_deref() {
                modal.motion = run.motion;
            }
            match check_contour_line(&words, &modal) {
                Ok(c) => {
                    code = c.gs().iter().find_map(|g| match g {
                        GCode::Motion(m) => Some(*m),
                        _ => None,
                    })
                }
                Err((kind, at)) => {
                    let whole = crate::parse::ast::Span::new(0, line_len(file, start));
                    let span = at.and_then(|i| spans.get(i).copied()).unwrap_or(whole);
                    return Err(self.error_in_line(kind, file, start, span));
                }
            }
        }
        self.apply_assigns(&num_set, &named_set);
        Ok((words, code))
    }

    /// A line of the contour: its assignments act; its axis, I/K/R and
    /// A/C words and its motion code add to the contour.
    fn contour_line(&mut self, file: &Rc<FileIndex>, start: u32, line: &Line) -> Result<(), Error> {
        let LineKind::Items(items) = &line.kind else {
            return Ok(());
        };
        let (words, code) = self.contour_words(file, start, items)?;
        if words.is_empty() {
            return Ok(());
        }
        let len = line_len(file, start);
        let bad = |s: &Self, k: LatheError| s.lathe_err(k, file, start, len);
        let word = |l: u8| words.iter().rev().find(|w| w.0 == l).map(|w| w.1);
        let lathe = self.mach.modal.lathe;
        let Some(run) = self.mach.lathe.as_deref() else {
            return Ok(());
        };
        let (distance, arc_distance) = (run.distance, run.arc_distance);
        let point = run.point;
        let mut end = contour_end(&word, point, distance, lathe).map_err(|k| bad(self, k))?;
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
                            return Err(bad(self, LatheError::ArcRAndIk));
                        }
                        match center_from_radius(point, end, r, motion == MotionMode::ArcCcw) {
                            Some(c) => center = c,
                            // Refused at the `endsub` (finish_lathe); the
                            // contour goes on from the arc's end.
                            None => short_radius = true,
                        }
                    } else {
                        if iw.is_none() && kw.is_none() {
                            return Err(bad(self, LatheError::ArcNoIk));
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
                return Err(bad(self, LatheError::AAndC));
            }
            (a, c)
        } else {
            (None, None)
        };
        let Some(run) = self.mach.lathe.as_deref_mut() else {
            return Ok(());
        };
        run.motion = motion;
        run.short_radius |= short_radius;
        if end != point {
            if run.contour.len() >= self.s.max_contour {
                // Every element is at least one move of the cycle: a
                // longer contour (a loop in its subroutine that never
                // ends) fails now, not after filling the memory.
                let limit = self.s.max_contour;
                return Err(bad(self, LatheError::ContourTooLong { limit }));
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
            self.mach.pos.axes[0] = Ok(end.im);
            self.mach.pos.axes[2] = Ok(end.re);
        }
        Ok(())
    }

    /// The contour subroutine returned (at the line `start` of `file`):
    /// the cycle's moves.
    fn finish_lathe(&mut self, file: &Rc<FileIndex>, start: u32, len: u32) -> Result<(), Error> {
        let Some(run) = self.mach.lathe.take() else {
            return Ok(());
        };
        if run.short_radius {
            return Err(self.lathe_err(LatheError::ArcRadiusTooSmall, file, start, len));
        }
        if let Cycle::Rough { i, .. } = run.cycle
            && i <= 0.0
            && run.contour.len() > 1
        {
            return Err(self.lathe_err(LatheError::INotPositive, file, start, len));
        }
        // The moves made before a geometry error are checked first: the
        // reference makes them before it stops.
        // A cycle making many more moves than the output has lines left
        // stops early: the output's limit is met within its first `cap`
        // moves unless most of them write nothing (then see below).
        let cap = self.out.lines_left().saturating_mul(2).saturating_add(64);
        let cap = usize::try_from(cap).unwrap_or(usize::MAX).min(MAX_MOVES);
        let (moves, failed) = cut_moves(&run.contour, run.begin, &run.cycle, cap);
        let capped = cap < MAX_MOVES && failed == Some(lathe::LatheError::TooManyMoves);
        // With compensation offsetting the path, the position LinuxCNC's
        // compensation reads is the contour's end (set while reading it),
        // the programmed position the rapid's end.
        let offsets = self.mach.comp_offsets() == Some(true);
        if self.mach.modal.cutter_comp != CutterComp::Off && run.moved {
            let p = [run.point.re, run.point.im];
            self.mach.comp_set_current(p);
            self.consumer_comp_position(p);
        }
        // The moves start where the machine is (LinuxCNC's position is the
        // contour's end, which only its arcs' skip test reads).
        if !moves.is_empty() || offsets {
            (self.mach.pos.axes[0], self.mach.pos.axes[2]) = run.at.clone();
        }
        // The moves belong to the cycle line.
        let (cf, cs) = (run.file.clone(), run.start);
        let saved = (self.reader.line_start, self.reader.line_idx);
        self.reader.at(cs, run.line);
        let clen = line_len(&cf, cs);
        let mut cur = run.contour.last();
        for m in moves {
            if arc_in_place(&m, cur) {
                continue;
            }
            if let Err(e) = self.lathe_move(&cf, cs, clen, m) {
                return Err(self.at_endsub(e, saved, file, start, len));
            }
            cur = match self.mach.comp_current().filter(|_| offsets) {
                Some([a, b, _]) => C::new(a, b),
                None => m.end(),
            };
        }
        if capped {
            // Stopped early and the output's limit was not met: more than
            // half of the moves made wrote no line (arcs in place). The
            // rest of the cycle is not made; it fails at the limit.
            let e = self.output_limit();
            return Err(self.at_endsub(e, saved, file, start, len));
        }
        if matches!(self.mach.comp_written, Written::Cycle { .. }) {
            // The cycle's last moves, held by the compensation until G40
            // or the program's end (the only ways on from here), end where
            // they are.
            let r = self
                .mach
                .comp_flush()
                .map_err(|k| self.error(k, file, start, start + len))
                .and_then(|()| self.write_comp_out(file, start, len));
            self.mach.comp_written = Written::After;
            r?;
        }
        (self.reader.line_start, self.reader.line_idx) = saved;
        match failed {
            Some(g) => Err(self.lathe_err(LatheError::Geometry(g), file, start, len)),
            None => Ok(()),
        }
    }

    /// An error of the cycle's moves, reported where the reference makes
    /// them: after reading the `endsub` line (`saved`: the reader there).
    fn at_endsub(
        &mut self,
        mut e: Error,
        saved: (u32, u32),
        file: &Rc<FileIndex>,
        start: u32,
        len: u32,
    ) -> Error {
        (self.reader.line_start, self.reader.line_idx) = saved;
        e.site = Some(Site::new(&file.file, start, start + len));
        e.stack = self.stack();
        e
    }

    /// Whether the evaluator writes the compensated path of this G70 itself
    /// (see [`Written`]): the output keeps G41/G42, the compensation
    /// offsets and the cycle's rapid is its entry move, in the modes the
    /// written moves are read in (G90, G91.1, G8, no G93).
    fn written_g70(&self) -> bool {
        let m = &self.mach.modal;
        !self.consumer_computes_comp()
            && self.mach.comp_entry_next()
            && self.mach.comp_written == Written::No
            && m.distance == Distance::Absolute
            && m.arc_distance == ArcDistance::Incremental
            && m.lathe == LatheMode::Radius
            && m.feed_mode != FeedMode::InverseTime
    }

    /// Writes the moves the compensation released while a G70's path is
    /// written: plain absolute G0/G1/G2/G3 (Z and X in the plane, Y the
    /// third axis; arc centres as offsets from the start).
    fn write_comp_out(&mut self, file: &Rc<FileIndex>, start: u32, len: u32) -> Result<(), Error> {
        let Written::Cycle { mut at } = self.mach.comp_written else {
            return Ok(());
        };
        for m in self.mach.comp_take_out() {
            let (words, end) = match comp_line(m, at, self.mach.modal.units) {
                Ok(w) => w,
                Err(why) => {
                    let k = LatheError::G70Comp { why };
                    return Err(self.lathe_err(k, file, start, len));
                }
            };
            let mut text = String::with_capacity(64);
            for &(l, v) in &words {
                if !text.is_empty() {
                    text.push(' ');
                }
                text.push(l as char);
                text.push_str(&number_string(v, self.s.precision));
            }
            self.emit_raw(text.as_bytes())?;
            at = end;
        }
        self.mach.comp_written = Written::Cycle { at };
        Ok(())
    }

    /// Whether G70 can run with the cutter compensation that is on: it can
    /// where the compensation offsets nothing (radius zero), or where the
    /// output computes it into the path and its geometry is known here.
    fn g70_comp(&self) -> Result<(), LatheError> {
        match self.mach.comp_offsets() {
            Some(false) => Ok(()),
            Some(true) if self.consumer_computes_comp() => Ok(()),
            Some(true) | None if !self.consumer_computes_comp() => Err(LatheError::G70Comp {
                why: "LinuxCNC moves the position its compensation reads to the contour's end while reading the contour, so the cycle's compensated moves start from there (it rapids toward the contour's end first); G0/G1/G2/G3 lines under G41/G42 cannot reproduce that. The path is written as plain moves only where the G70's rapid is the compensation's entry move (G41/G42 just before it), in G90, G91.1 and G8; else flatten for a target that computes the compensation into the path (--target grbl, grblhal or fluidnc), or turn it off (G40) before G70",
            }),
            Some(true) | None => Err(LatheError::G70Comp {
                why: "the compensation's path is not known here (the tool's diameter or the position is unknown: give --tool-table and --start-position, or --zero-start)",
            }),
        }
    }

    /// Writes one move of a cycle and applies it.
    fn lathe_move(
        &mut self,
        file: &Rc<FileIndex>,
        start: u32,
        len: u32,
        m: Move,
    ) -> Result<(), Error> {
        let cx = self.mach.pos.axes[0].clone().unwrap_or(0.0);
        let cz = self.mach.pos.axes[2].clone().unwrap_or(0.0);
        let (g, end, center) = match m {
            Move::Rapid(e) => (0.0, e, None),
            Move::Feed(e) => (1.0, e, None),
            Move::Arc { ccw, center, end } => (if ccw { 3.0 } else { 2.0 }, end, Some(center)),
        };
        let (xw, zw) = if self.mach.modal.distance == Distance::Absolute {
            (end.im, end.re)
        } else if self.mach.modal.lathe == LatheMode::Diameter {
            (end.im - 2.0 * cx, end.re - cz)
        } else {
            (end.im - cx, end.re - cz)
        };
        let mut words = vec![(b'g', g), (b'x', xw), (b'z', zw)];
        if let Some(c) = center {
            if self.mach.modal.arc_distance == ArcDistance::Absolute {
                words.push((b'i', c.im));
                words.push((b'k', c.re));
            } else {
                words.push((b'i', c.im - cx));
                words.push((b'k', c.re - cz));
            }
        }
        let checked = match check_block(
            &words,
            &self.mach.modal,
            &self.mach.nurbs,
            &self.mach.cycle,
            self.s.user_m,
        ) {
            Ok(c) => c,
            Err((k, _)) => return Err(self.error(k, file, start, start + len)),
        };
        let mut text = String::with_capacity(64);
        for &(l, v) in &words {
            if !text.is_empty() {
                text.push(' ');
            }
            text.push(l.to_ascii_uppercase() as char);
            text.push_str(&number_string(v, self.s.precision));
        }
        if matches!(self.mach.comp_written, Written::Cycle { .. }) {
            self.apply_words(file, start, &words, &checked, false)?;
            return self.write_comp_out(file, start, len);
        }
        self.emit_raw(text.as_bytes())?;
        self.apply_words(file, start, &words, &checked, false)?;
        Ok(())
    }
}

/// A written line of a compensated path (its words) and where it ends.
type PathLine = (Vec<(u8, f64)>, [f64; 3]);

/// The words of a move of the compensated path (plane coordinates Z, X,
/// third Y) from `at` (X Y Z), and where it ends. An arc whose start and
/// end lie at radii more than 0.005 mm apart (LinuxCNC releases such arcs
/// in some corners) has no G2/G3: `Err` says why.
fn comp_line(
    m: crate::geom::comp::Out<()>,
    at: [f64; 3],
    units: Units,
) -> Result<PathLine, &'static str> {
    use crate::geom::comp::Out;
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

/// Length of the line at `start` (for a site), without its terminator.
fn line_len(file: &Rc<FileIndex>, start: u32) -> u32 {
    match file.file.memory() {
        Some(data) => {
            let (end, _, _) = next_line(data, start as usize);
            (end as u32).saturating_sub(start)
        }
        None => 0,
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
