//! Lathe cycles G70–G72: the cycle block rapids to its start, the contour
//! subroutine (Q) runs with its motion collected instead of written (its
//! parameters and control flow as usual), and on its return the moves the
//! cycle makes are written as plain G0/G1/G2/G3 lines and applied to the
//! machine model. The cycle, its contour and its moves are the machine's
//! (`eval/state/lathe.rs`); reading the contour's lines, the call and the
//! output are the steps here.

use crate::diag::OWordError;
use std::rc::Rc;

use crate::diag::{Error, ErrorKind, LatheError, Site};
use crate::emit::number_string;
use crate::geom::lathe::{C, MAX_MOVES, Move, arc_in_place};
use crate::parse::Name;
use crate::parse::ast::{Item, Line, LineKind};
use crate::program::{FileIndex, Window, next_line};

use crate::codes::{GCode, MotionMode};
use crate::eval::flow::SubRec;
use crate::eval::read::validate::check_contour_line;
use crate::eval::state::checked::{Checked, LineCodes};
use crate::eval::{Interp, file_key, read_error};

/// A contour line's evaluated words, and its motion code if it has one.
type ContourWords = (Vec<(u8, f64)>, Option<MotionMode>);

impl Interp<'_> {
    fn lathe_err(&self, k: LatheError, file: &Rc<FileIndex>, start: u32, len: u32) -> Error {
        self.error(ErrorKind::Lathe(k), file, start, start + len)
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
        let q = words.iter().rev().find(|w| w.0 == b'q').map(|w| w.1);
        let computes_comp = self.out.consumer_computes_comp();
        let (q, write) = self
            .mach
            .lathe_checks(name, number, q, computes_comp)
            .map_err(|k| self.lathe_err(k, file, start, len))?;
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
        let (begin, rapid) = self.mach.lathe_begin([cx, cz], words);
        if write {
            // The output turns compensation off and gets the path itself.
            self.emit_raw(b"G40")?;
            self.mach.start_written_path();
        }
        self.lathe_move(file, start, len, Move::Rapid(rapid))?;
        if ends {
            // An M2 on the cycle line: LinuxCNC ends before the contour.
            return self.end_program();
        }
        let label = Name::new(&(q as i64).to_string());
        let target = self.contour_sub(file, start, len, &label)?;
        let level = self.enter_contour(file, start, len, label, &target)?;
        let line = self.reader.line_idx;
        self.mach
            .begin_contour((number, sub), words, (file, start, line), level, begin);
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
        let level = self.flow.frames.len();
        if !self
            .flow
            .enter_unsited(label.clone(), self.flow.cur.clone())
        {
            let limit = crate::eval::flow::MAX_CALL_LEVEL;
            return Err(self.error(
                ErrorKind::OWord(OWordError::TooDeep { limit }),
                file,
                start,
                start + len,
            ));
        }
        // A call without arguments.
        self.bind_args(&[0.0; 30], 0.0);
        self.flow.note_called(&label, target);
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
                let kind = ErrorKind::OWord(OWordError::SubNotFound {
                    name: label.to_string(),
                    searched: self.loader.searched(),
                });
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
        if file.file.memory().is_some()
            && let Some((line, _, next)) = self.flow.cache.get(&(file_key(file), line_idx))
        {
            let (line, next) = (line.clone(), *next);
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
            match check_contour_line(&words, &self.mach.contour_modes()) {
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
        self.mach
            .add_to_contour(&words, code, self.s.max_contour)
            .map_err(|k| self.lathe_err(k, file, start, line_len(file, start)))
    }

    /// The contour subroutine returned (at the line `start` of `file`):
    /// the cycle's moves.
    fn finish_lathe(&mut self, file: &Rc<FileIndex>, start: u32, len: u32) -> Result<(), Error> {
        // A cycle making many more moves than the output has lines left
        // stops early: the output's limit is met within its first `cap`
        // moves unless most of them write nothing (then see below).
        let cap = self.out.lines_left().saturating_mul(2).saturating_add(64);
        let cap = usize::try_from(cap).unwrap_or(usize::MAX).min(MAX_MOVES);
        let f = match self.mach.finish_contour(cap) {
            None => return Ok(()),
            Some(Ok(f)) => f,
            Some(Err(k)) => return Err(self.lathe_err(k, file, start, len)),
        };
        if let Some(p) = f.comp_point {
            self.out.consumer_comp_position(p);
        }
        // The moves belong to the cycle line.
        let (cf, cs) = (f.file.clone(), f.start);
        let saved = (self.reader.line_start, self.reader.line_idx);
        self.reader.at(cs, f.line);
        let clen = line_len(&cf, cs);
        let mut cur = f.last;
        for m in f.moves {
            if arc_in_place(&m, cur) {
                continue;
            }
            if let Err(e) = self.lathe_move(&cf, cs, clen, m) {
                return Err(self.at_endsub(e, saved, file, start, len));
            }
            cur = match self.mach.comp_current().filter(|_| f.offsets) {
                Some([a, b, _]) => C::new(a, b),
                None => m.end(),
            };
        }
        if f.capped {
            // Stopped early and the output's limit was not met: more than
            // half of the moves made wrote no line (arcs in place). The
            // rest of the cycle is not made; it fails at the limit.
            let e = self.output_limit();
            return Err(self.at_endsub(e, saved, file, start, len));
        }
        if self.mach.writes_path() {
            // The cycle's last moves, held by the compensation until G40
            // or the program's end (the only ways on from here), end where
            // they are.
            let r = self
                .mach
                .comp_flush()
                .map_err(|k| self.error(k, file, start, start + len))
                .and_then(|()| self.write_comp_out(file, start, len));
            self.mach.end_written_path();
            r?;
        }
        (self.reader.line_start, self.reader.line_idx) = saved;
        match f.failed {
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

    /// Writes the moves the compensation released while a G70's path is
    /// written ([`Machine::comp_path_lines`](crate::eval::state::Machine::comp_path_lines)).
    fn write_comp_out(&mut self, file: &Rc<FileIndex>, start: u32, len: u32) -> Result<(), Error> {
        let (lines, refused) = self.mach.comp_path_lines(self.s.precision);
        for line in lines {
            self.emit_raw(line.as_bytes())?;
        }
        refused.map_err(|why| self.lathe_err(LatheError::G70Comp { why }, file, start, len))
    }

    /// Writes one move of a cycle and applies it.
    fn lathe_move(
        &mut self,
        file: &Rc<FileIndex>,
        start: u32,
        len: u32,
        m: Move,
    ) -> Result<(), Error> {
        let words = self.mach.lathe_move_words(m);
        let checked = match self.check_words(&words) {
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
        if self.mach.writes_path() {
            self.apply_words(file, start, &words, &checked, false)?;
            return self.write_comp_out(file, start, len);
        }
        self.emit_raw(text.as_bytes())?;
        self.apply_words(file, start, &words, &checked, false)?;
        Ok(())
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
