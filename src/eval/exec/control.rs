//! O-words: subroutines, conditionals, loops, M98/M99. Jump targets come from
//! the file index (occurrences of each label in order), so nothing is
//! rescanned per iteration.

use std::rc::Rc;

use crate::diag::{Diagnostic, Error, ErrorKind, WarningKind};
use crate::parse::ast::{Label, LineKind, OKind, OLine};
use crate::parse::{Name, integer_value};
use crate::program::{FileIndex, ParsedO, control_key};

use crate::eval::Interp;
use crate::eval::expr::round_half_even_int;
use crate::eval::flow::{
    Cursor, FrameKind, LabelRec, MAX_CALL_LEVEL, SubRec, base_key, label_of_key, osite_of,
};

/// What a forward search was looking for (for the error when nothing is found).
enum Seek {
    Control,
    Sub { from_line: u32 },
}

impl Interp<'_> {
    /// O-line `oidx` of `file`, parsed (an error if the file changed so
    /// that it is no longer the O-line the index found).
    fn oline(&self, file: &Rc<FileIndex>, oidx: u32) -> Result<ParsedO, Error> {
        file.oline(oidx).map_err(|k| self.oerr(k, file, oidx))
    }

    pub(in crate::eval) fn osite(&self, file: &Rc<FileIndex>, oidx: u32) -> (u32, u32) {
        osite_of(file, oidx)
    }
}

impl Interp<'_> {
    fn oerr(&self, kind: ErrorKind, file: &Rc<FileIndex>, oidx: u32) -> Error {
        let (a, b) = self.osite(file, oidx);
        self.error(kind, file, a, b)
    }

    /// Evaluates an expression of an O-line.
    fn o_eval(
        &mut self,
        file: &Rc<FileIndex>,
        oidx: u32,
        e: &crate::parse::ast::Expr,
    ) -> Result<f64, Error> {
        self.eval_value(e).map_err(|f| {
            let start = file.olines[oidx as usize].start;
            self.fault_in_line(*f, file, start)
        })
    }

    /// The label text of an O-line (computed labels are evaluated).
    fn label_text(&mut self, file: &Rc<FileIndex>, oidx: u32) -> Result<Name, Error> {
        let o = self.oline(file, oidx)?;
        match &o.label {
            Label::Static(s) => Ok(s.clone()),
            Label::Dynamic(e) => {
                let e = e.clone();
                let v = self.o_eval(file, oidx, &e)?;
                let n = integer_value(v).map_err(|k| {
                    let start = file.olines[oidx as usize].start;
                    self.error_in_line(k, file, start, o.label_span)
                })?;
                Ok(Name::new(&n.to_string()))
            }
        }
    }

    /// Internal key of the O-line's label.
    fn key_of(&mut self, file: &Rc<FileIndex>, oidx: u32) -> Result<Name, Error> {
        if let Some(k) = file.key(oidx) {
            return Ok(k.clone());
        }
        let label = self.label_text(file, oidx)?;
        let kind = file.kind_of(oidx).unwrap_or(OKind::Bare);
        Ok(if kind.is_control() {
            control_key(file.scope(oidx), &label)
        } else {
            label
        })
    }

    /// Finds the next O-line after `from` whose label key is `key`, raising
    /// the errors of the lines skipped on the way.
    fn seek(
        &mut self,
        file: &Rc<FileIndex>,
        from: u32,
        key: &Name,
        what: Seek,
        only: &[OKind],
    ) -> Result<u32, Error> {
        // A control search from a static label finds the same line every
        // time (the label occurrences, skipped-line errors and `%` lines are
        // fixed per file): found targets are kept.
        let memo = matches!(what, Seek::Control)
            && only.is_empty()
            && file.dynamic.is_empty()
            && file.key(from) == Some(key);
        if memo {
            let t = file.seek_memo[from as usize].get();
            if t != u32::MAX {
                return Ok(t);
            }
        }
        let from_line = file.olines[from as usize].line_idx;
        let list = file.occ_like(from, key);
        let p = list.partition_point(|&j| j <= from);
        let mut best = list[p..]
            .iter()
            .copied()
            .find(|&j| only.is_empty() || file.kind_of(j).is_some_and(|k| only.contains(&k)));
        if !file.dynamic.is_empty() {
            let p = file.dynamic.partition_point(|&j| j <= from);
            for &j in &file.dynamic[p..] {
                if best.is_some_and(|b| j > b) {
                    break;
                }
                if !only.is_empty() && !file.kind_of(j).is_some_and(|k| only.contains(&k)) {
                    continue;
                }
                if !file.same_scope(j, from) && matches!(what, Seek::Control) {
                    continue;
                }
                if self.key_of(file, j)? == *key {
                    best = Some(j);
                    break;
                }
            }
        }
        let until = best
            .map(|b| file.olines[b as usize].line_idx)
            .unwrap_or(u32::MAX);
        if let Some((_, start, e)) = file.skipped_error(from_line, until) {
            return Err(self.error_in_line(e.kind.clone(), file, *start, e.span));
        }
        if Rc::ptr_eq(file, &self.main)
            && self.main.percent_start
            && let Some(pl) = file.percent_after(from_line)
            && pl < until
        {
            let label = key.to_string();
            let (a, b) = self.osite(file, from);
            return Err(self.error(ErrorKind::LabelBeforePercent { label }, file, a, b));
        }
        match best {
            Some(b) => {
                if memo {
                    file.seek_memo[from as usize].set(b);
                }
                Ok(b)
            }
            None => {
                let (a, b) = self.osite(file, from);
                let kind = match what {
                    Seek::Control => ErrorKind::MissingProgramEnd {
                        percent: self.main.percent_start,
                    },
                    Seek::Sub { from_line } => ErrorKind::EofSeeking {
                        label: key.to_string(),
                        from_line,
                    },
                };
                Err(self.error(kind, file, a, b))
            }
        }
    }

    /// Like `seek`, but passes over `break`/`continue` lines of the same
    /// loop, which do nothing while the loop is being left.
    fn seek_loop_end(&mut self, file: &Rc<FileIndex>, from: u32, key: &Name) -> Result<u32, Error> {
        let mut at = from;
        let from_continue = file.kind_of(from) == Some(OKind::Continue);
        loop {
            let t = self.seek(file, at, key, Seek::Control, &[])?;
            if from_continue && file.kind_of(t) == Some(OKind::Break) {
                let (a, b) = self.osite(file, t);
                self.warn(WarningKind::QuirkSkippedBreak, file, a, b);
            }
            if matches!(file.kind_of(t), Some(OKind::Break | OKind::Continue)) {
                at = t;
                continue;
            }
            return Ok(t);
        }
    }

    fn record(
        &mut self,
        file: &Rc<FileIndex>,
        oidx: u32,
        key: &Name,
        kind: OKind,
    ) -> Result<(), Error> {
        let line = file.olines[oidx as usize].line_idx;
        if let Some(rec) = self.flow.label(key) {
            if rec.line != line && matches!(kind, OKind::If | OKind::While | OKind::Repeat) {
                let first_line = rec.line + 1;
                let label = self.label_text(file, oidx)?.to_string();
                return Err(self.oerr(ErrorKind::DuplicateLabel { label, first_line }, file, oidx));
            }
            if rec.line == line && rec.kind == kind {
                return Ok(());
            }
            if rec.line != line {
                let (a, b) = self.osite(file, oidx);
                let first_line = rec.line + 1;
                self.warn(WarningKind::LabelReused { first_line }, file, a, b);
            }
        }
        self.flow.set_label(key, kind, oidx, line);
        Ok(())
    }

    /// The record of a label that must exist and be one of `kinds`.
    fn expect(
        &mut self,
        file: &Rc<FileIndex>,
        oidx: u32,
        key: &Name,
        kinds: &[OKind],
        _expected: &'static str,
    ) -> Result<LabelRec, Error> {
        let label = || label_of_key(key);
        match self.flow.label(key) {
            None => Err(self.oerr(ErrorKind::UndefinedLabel { label: label() }, file, oidx)),
            Some(rec) if kinds.contains(&rec.kind) => Ok(rec),
            Some(rec) => Err(self.oerr(
                ErrorKind::LabelMismatch {
                    label: label(),
                    here: file.kind_of(oidx).map_or("M98", OKind::name),
                    opened: rec.kind.name(),
                    line: rec.line + 1,
                },
                file,
                oidx,
            )),
        }
    }

    /// Evaluates a condition the reference evaluates but ngcflat skips; warns
    /// if it would fail there.
    /// The expression an O-line must carry (its condition or count).
    fn expr_of<'a>(o: &'a OLine, what: &str) -> Result<&'a crate::parse::ast::Expr, Error> {
        o.expr.as_ref().ok_or_else(|| {
            Diagnostic::error(
                ErrorKind::Internal {
                    what: format!("an O-line without its {what}"),
                },
                None,
            )
        })
    }

    /// The condition of O-line `t`, reached from another line (a
    /// `continue` to a do loop's `while`, an `elseif` after a false
    /// branch): the line's own error if it has one.
    fn condition_of(
        &mut self,
        file: &Rc<FileIndex>,
        t: u32,
    ) -> Result<crate::parse::ast::Expr, Error> {
        let o = self.oline(file, t)?;
        if let Some(b) = &o.exec_error {
            let (k, span) = &**b;
            let start = file.olines[t as usize].start;
            return Err(self.error_in_line(k.clone(), file, start, *span));
        }
        match Self::expr_of(&o, "condition") {
            Ok(e) => Ok(e.clone()),
            Err(e) => {
                let (a, b) = self.osite(file, t);
                Err(Box::new(Diagnostic {
                    site: Some(crate::diag::Site::new(&file.file, a, b)),
                    ..*e
                }))
            }
        }
    }

    fn probe_condition(&mut self, file: &Rc<FileIndex>, oidx: u32) {
        if let Ok(o) = self.oline(file, oidx)
            && let Some(e) = o.expr.clone()
            && let Err(f) = self.eval(&e)
        {
            let (a, b) = self.osite(file, oidx);
            self.warn(
                WarningKind::QuirkSkippedCondition {
                    message: f.0.to_string(),
                },
                file,
                a,
                b,
            );
        }
    }

    /// Runs the O-line `oidx` of `file` (reached in normal flow).
    pub(in crate::eval) fn exec_oline(
        &mut self,
        file: &Rc<FileIndex>,
        oidx: u32,
    ) -> Result<(), Error> {
        self.reader.at(
            file.olines[oidx as usize].start,
            file.olines[oidx as usize].line_idx,
        );
        let line = file.line(oidx).map_err(|k| self.oerr(k, file, oidx))?;
        let o = match &line.kind {
            LineKind::O(o) => o,
            LineKind::M98(m) => return self.exec_m98(file, oidx, m),
            _ => return Ok(()),
        };
        if let Some(b) = &o.exec_error {
            let (k, span) = &**b;
            let start = file.olines[oidx as usize].start;
            return Err(self.error_in_line(k.clone(), file, start, *span));
        }
        if o.active_comment {
            let (a, b) = self.osite(file, oidx);
            self.warn(WarningKind::CommentOnOLine, file, a, b);
        }
        let computed;
        let key = match file.key(oidx) {
            Some(k) => k,
            None => {
                computed = self.key_of(file, oidx)?;
                &computed
            }
        };
        match o.kind {
            OKind::If => self.exec_if(file, oidx, o, key),
            OKind::ElseIf | OKind::Else => self.exec_else(file, oidx, o, key),
            OKind::EndIf => {
                if let Err(e) = self.expect(file, oidx, key, &[OKind::If], "if") {
                    return self.soft(e, file);
                }
                self.flow.executed_if = true;
                Ok(())
            }
            OKind::Do => self.exec_do(file, oidx, key),
            OKind::While => self.exec_while(file, oidx, o, key),
            OKind::EndWhile => self.exec_loop_back(file, oidx, key, OKind::While),
            OKind::Repeat => self.exec_repeat(file, oidx, o, key),
            OKind::EndRepeat => self.exec_loop_back(file, oidx, key, OKind::Repeat),
            OKind::Break | OKind::Continue => self.exec_break_continue(file, oidx, o, key),
            OKind::Sub => self.reach_sub(file, oidx, key),
            OKind::EndSub | OKind::Return => self.exec_return(file, oidx, o),
            OKind::Call => self.call(file, oidx, key),
            OKind::Bare => self.exec_bare(file, oidx, key),
        }
    }

    /// `if`: evaluates the condition; when false, goes to the branch taken.
    // One call site, on the hot path: kept inline as before the split.
    #[inline(always)]
    fn exec_if(
        &mut self,
        file: &Rc<FileIndex>,
        oidx: u32,
        o: &OLine,
        key: &Name,
    ) -> Result<(), Error> {
        let c = self.o_eval(file, oidx, Self::expr_of(o, "condition")?)?;
        // Each pass after the first finds its own record.
        let line = file.olines[oidx as usize].line_idx;
        let recorded = matches!(self.flow.frame().labels.get(key),
            Some(r) if r.kind == OKind::If && r.line == line);
        if !recorded && let Err(e) = self.record(file, oidx, key, OKind::If) {
            return self.soft(e, file);
        }
        if c != 0.0 {
            self.flow.executed_if = true;
            Ok(())
        } else {
            self.flow.executed_if = false;
            self.skip_if(file, oidx, key)
        }
    }

    /// `elseif`/`else` reached in normal flow: a branch was taken, so goes to the `endif`.
    fn exec_else(
        &mut self,
        file: &Rc<FileIndex>,
        oidx: u32,
        o: &OLine,
        key: &Name,
    ) -> Result<(), Error> {
        if let Err(e) = self.expect(file, oidx, key, &[OKind::If], "if") {
            return self.soft(e, file);
        }
        if o.kind == OKind::ElseIf {
            self.probe_condition(file, oidx);
        }
        // A branch was taken: go to the endif.
        let mut at = oidx;
        loop {
            let t = self.seek(file, at, key, Seek::Control, &[])?;
            match file.kind_of(t) {
                Some(OKind::EndIf) => {
                    self.flow.executed_if = true;
                    self.flow.goto(file, t, true);
                    return Ok(());
                }
                Some(OKind::ElseIf) => {
                    self.probe_condition(file, t);
                    at = t;
                }
                Some(OKind::Else) => at = t,
                _ => {
                    self.stray(file, t, key)?;
                    at = t;
                }
            }
        }
    }

    /// `do`: records the loop start.
    fn exec_do(&mut self, file: &Rc<FileIndex>, oidx: u32, key: &Name) -> Result<(), Error> {
        // The reference records a do label only on first sight.
        match self.flow.label(key) {
            Some(rec) if rec.oidx != oidx => {
                let (a, b) = self.osite(file, oidx);
                let first_line = rec.line + 1;
                self.warn(WarningKind::LabelReused { first_line }, file, a, b);
            }
            _ => self.record(file, oidx, key, OKind::Do)?,
        }
        Ok(())
    }

    /// `while`: the end of a `do` loop, or the start of a `while` loop.
    // One call site, on the hot path: kept inline as before the split.
    #[inline(always)]
    fn exec_while(
        &mut self,
        file: &Rc<FileIndex>,
        oidx: u32,
        o: &OLine,
        key: &Name,
    ) -> Result<(), Error> {
        let line = file.olines[oidx as usize].line_idx;
        // One look at the label: the end of a do loop, this loop
        // already recorded (each pass after the first), or new.
        let (do_rec, recorded) = match self.flow.frame().labels.get(key) {
            Some(r) if r.kind == OKind::Do => (Some(*r), false),
            Some(r) => (None, r.kind == OKind::While && r.line == line),
            None => (None, false),
        };
        let c = self.o_eval(file, oidx, Self::expr_of(o, "condition")?)?;
        if let Some(rec) = do_rec {
            if c != 0.0 {
                if let Some(first_line) = self.flow.ref_stale_break.take() {
                    let (a, b) = self.osite(file, oidx);
                    self.warn(WarningKind::QuirkStaleBreak { first_line }, file, a, b);
                }
                self.flow.note_loop(file, rec.oidx, key);
                self.flow.goto(file, rec.oidx, true);
            } else {
                self.flow.ref_stale_break = None;
            }
            return Ok(());
        }
        if !recorded && let Err(e) = self.record(file, oidx, key, OKind::While) {
            return self.soft(e, file);
        }
        if c != 0.0 {
            return Ok(());
        }
        self.loop_exit(file, oidx, key, OKind::EndWhile)
    }

    /// `endwhile` and `endrepeat`: back to the loop's opening line
    /// (`opener`, While or Repeat).
    // Two call sites, on the hot path: kept inline as before the split.
    #[inline(always)]
    fn exec_loop_back(
        &mut self,
        file: &Rc<FileIndex>,
        oidx: u32,
        key: &Name,
        opener: OKind,
    ) -> Result<(), Error> {
        let repeat = matches!(opener, OKind::Repeat);
        let name = if repeat { "repeat" } else { "while" };
        let rec = match self.expect(file, oidx, key, &[opener], name) {
            Ok(r) => r,
            Err(e) => return self.soft(e, file),
        };
        self.flow.note_loop(file, rec.oidx, key);
        if repeat {
            self.flow.repeat_again = Some(rec.oidx);
        }
        self.flow.goto(file, rec.oidx, false);
        Ok(())
    }

    /// `repeat`: starts or continues the count.
    // One call site, on the hot path: kept inline as before the split.
    #[inline(always)]
    fn exec_repeat(
        &mut self,
        file: &Rc<FileIndex>,
        oidx: u32,
        o: &OLine,
        key: &Name,
    ) -> Result<(), Error> {
        if let Err(e) = self.record(file, oidx, key, OKind::Repeat) {
            return self.soft(e, file);
        }
        let count = self
            .flow
            .frame()
            .labels
            .get(key)
            .map(|r| r.repeat)
            .unwrap_or(-1);
        let mut count = count;
        // Reached from its endrepeat, the loop goes on; reached any
        // other way it starts afresh (the reference would continue a
        // count left over by a jump out of the loop).
        let again = self.flow.repeat_again.take() == Some(oidx);
        if !again && count != -1 {
            let (a, b) = self.osite(file, oidx);
            self.warn(WarningKind::QuirkRepeatCount, file, a, b);
            count = -1;
        }
        if count == -1 {
            let n = self.o_eval(file, oidx, Self::expr_of(o, "count")?)?;
            count = round_half_even_int(n);
        }
        if count > 0 {
            if let Some(r) = self.flow.frame().labels.get_mut(key) {
                r.repeat = count - 1;
            }
            Ok(())
        } else {
            if let Some(r) = self.flow.frame().labels.get_mut(key) {
                r.repeat = -1;
            }
            self.loop_exit(file, oidx, key, OKind::EndRepeat)
        }
    }

    /// `break`/`continue`: finds the end of the loop and leaves or repeats it.
    fn exec_break_continue(
        &mut self,
        file: &Rc<FileIndex>,
        oidx: u32,
        o: &OLine,
        key: &Name,
    ) -> Result<(), Error> {
        let expected = "while/do";
        let rec = match self.expect(file, oidx, key, &[OKind::While, OKind::Do], expected) {
            Ok(r) => r,
            Err(e) => return self.soft(e, file),
        };
        // The end of the loop (a line of another kind with the same
        // label is skipped under warn-only O-words).
        let mut at = oidx;
        let (t, tkind) = loop {
            let t = self.seek_loop_end(file, at, key)?;
            let tkind = file.kind_of(t);
            match (rec.kind, tkind) {
                (OKind::While, Some(OKind::EndWhile)) | (OKind::Do, Some(OKind::While)) => {
                    break (t, tkind);
                }
                _ => {
                    self.stray(file, t, key)?;
                    at = t;
                }
            }
        };
        match (rec.kind, tkind, o.kind) {
            (OKind::While, Some(OKind::EndWhile), OKind::Break) => {
                if let Some(first_line) = self.flow.ref_stale_continue.take() {
                    let (a, b) = self.osite(file, t);
                    self.warn(WarningKind::QuirkStaleContinue { first_line }, file, a, b);
                }
                self.flow.ref_stale_break = Some(file.olines[oidx as usize].line_idx + 1);
                self.flow.goto(file, t, true);
                Ok(())
            }
            (OKind::While, Some(OKind::EndWhile), _) => {
                self.flow.note_loop(file, rec.oidx, key);
                self.flow.goto(file, rec.oidx, false);
                Ok(())
            }
            (OKind::Do, Some(OKind::While), OKind::Break) => {
                self.probe_condition(file, t);
                self.flow.goto(file, t, true);
                Ok(())
            }
            (OKind::Do, Some(OKind::While), _) => {
                self.flow.ref_stale_continue = Some(file.olines[oidx as usize].line_idx + 1);
                let e = self.condition_of(file, t)?;
                let c = self.o_eval(file, t, &e)?;
                if c != 0.0 {
                    self.flow.note_loop(file, rec.oidx, key);
                    self.flow.goto(file, rec.oidx, true);
                } else {
                    self.flow.goto(file, t, true);
                }
                Ok(())
            }
            _ => unreachable!("loop end checked above"),
        }
    }

    /// `endsub`/`return`: leaves the subroutine with its value, if any.
    fn exec_return(&mut self, file: &Rc<FileIndex>, oidx: u32, o: &OLine) -> Result<(), Error> {
        if self.flow.level() == 0 {
            let e = self.oerr(ErrorKind::NotInSub, file, oidx);
            return self.soft(e, file);
        }
        if self.flow.frame().kind == FrameKind::M98 {
            return Err(self.oerr(ErrorKind::EndsubInFanuc, file, oidx));
        }
        let v = match &o.expr {
            Some(e) => Some(self.o_eval(file, oidx, e)?),
            None => None,
        };
        self.return_from_call(file, oidx, v)
    }

    /// A bare O-word (M98 subprogram start) reached in normal flow.
    fn exec_bare(&mut self, file: &Rc<FileIndex>, oidx: u32, key: &Name) -> Result<(), Error> {
        if self.s.fanuc_disabled {
            return Err(self.oerr(
                ErrorKind::FanucDisabled {
                    what: "a bare O-word",
                },
                file,
                oidx,
            ));
        }
        if self.flow.level() > 0 {
            return Err(self.oerr(
                ErrorKind::FanucNeedsM98 {
                    name: key.to_string(),
                },
                file,
                oidx,
            ));
        }
        Ok(())
    }

    /// Under warn-only O-words (`OWORD_WARNONLY`), one of LinuxCNC's O-word
    /// errors raised by the line being run becomes a warning and the line
    /// is skipped (`Ok`); any other error stays an error.
    fn soft(&mut self, e: Error, file: &Rc<FileIndex>) -> Result<(), Error> {
        let soft = self.s.oword_warn_only
            && matches!(
                e.error_kind(),
                Some(
                    ErrorKind::NotInSub
                        | ErrorKind::DuplicateLabel { .. }
                        | ErrorKind::UndefinedLabel { .. }
                        | ErrorKind::LabelMismatch { .. }
                )
            );
        if !soft {
            return Err(e);
        }
        let (a, b) = e.site.as_ref().map_or((0, 0), |s| (s.start, s.end));
        let code = e.code();
        let message = e.message();
        self.warn(WarningKind::OWordSkipped { code, message }, file, a, b);
        Ok(())
    }

    /// A line with the label being looked for, but of a kind that does not
    /// belong there: an error, or under warn-only O-words a warning (`Ok`:
    /// the line is passed over and the search goes on).
    fn stray(&mut self, file: &Rc<FileIndex>, t: u32, key: &Name) -> Result<(), Error> {
        let label = label_of_key(key);
        let found = file.kind_of(t).map(|k| k.name()).unwrap_or("?");
        let rec = self.flow.label(key);
        if let Some(r) = &rec
            && file.kind_of(t) == Some(r.kind)
            && matches!(r.kind, OKind::If | OKind::While | OKind::Repeat)
        {
            let first_line = r.line + 1;
            let e = self.oerr(ErrorKind::DuplicateLabel { label, first_line }, file, t);
            return self.soft(e, file);
        }
        let (opened, line) = rec.map(|r| (r.kind.name(), r.line + 1)).unwrap_or(("?", 0));
        let e = self.oerr(
            ErrorKind::LabelMismatch {
                label,
                here: found,
                opened,
                line,
            },
            file,
            t,
        );
        self.soft(e, file)
    }

    fn skip_if(&mut self, file: &Rc<FileIndex>, oidx: u32, key: &Name) -> Result<(), Error> {
        let mut at = oidx;
        loop {
            let t = self.seek(file, at, key, Seek::Control, &[])?;
            self.reader.at(
                file.olines[t as usize].start,
                file.olines[t as usize].line_idx,
            );
            match file.kind_of(t) {
                Some(OKind::ElseIf) => {
                    let e = self.condition_of(file, t)?;
                    let c = self.o_eval(file, t, &e)?;
                    if c != 0.0 {
                        self.flow.executed_if = true;
                        self.flow.goto(file, t, true);
                        return Ok(());
                    }
                    at = t;
                }
                Some(OKind::Else) | Some(OKind::EndIf) => {
                    self.flow.executed_if = true;
                    self.flow.goto(file, t, true);
                    return Ok(());
                }
                _ => {
                    self.stray(file, t, key)?;
                    at = t;
                }
            }
        }
    }

    /// Leaves the loop of line `from` at its end line (of kind `end`, found
    /// by skipping).
    fn loop_exit(
        &mut self,
        file: &Rc<FileIndex>,
        from: u32,
        key: &Name,
        end: OKind,
    ) -> Result<(), Error> {
        let mut at = from;
        let t = loop {
            let t = self.seek_loop_end(file, at, key)?;
            if file.kind_of(t) == Some(end) {
                break t;
            }
            self.stray(file, t, key)?;
            at = t;
        };
        if let Some(first_line) = self.flow.ref_stale_continue.take() {
            let (a, b) = self.osite(file, t);
            self.warn(WarningKind::QuirkStaleContinue { first_line }, file, a, b);
        }
        self.flow.goto(file, t, true);
        Ok(())
    }

    /// A `sub` line reached by normal flow: a definition to register and
    /// skip.
    fn reach_sub(&mut self, file: &Rc<FileIndex>, oidx: u32, key: &Name) -> Result<(), Error> {
        if self.flow.level() > 0 {
            let outer = self
                .flow
                .frames
                .last()
                .map(|f| f.name.to_string())
                .unwrap_or_default();
            return Err(self.oerr(
                ErrorKind::NestedSubDefinition {
                    inner: key.to_string(),
                    outer,
                },
                file,
                oidx,
            ));
        }
        if let Some(rec) = self.flow.subs.get(key) {
            if Rc::ptr_eq(&rec.file, file) && rec.oidx == oidx {
                return Err(self.oerr(
                    ErrorKind::IllegalSubLocation {
                        name: key.to_string(),
                    },
                    file,
                    oidx,
                ));
            }
            let first = rec.file.file.path.clone();
            let first_line = rec.file.olines[rec.oidx as usize].line_idx + 1;
            return Err(self.oerr(
                ErrorKind::RedefiningSub {
                    name: key.to_string(),
                    first,
                    first_line,
                },
                file,
                oidx,
            ));
        }
        self.flow.subs.insert(
            key.clone(),
            SubRec {
                file: file.clone(),
                oidx,
            },
        );
        let Some(def) = file.def(oidx) else {
            // Definitions are indexed by their fixed label only.
            return Err(self.oerr(ErrorKind::ComputedSubLabel, file, oidx));
        };
        if let Some((j, inner)) = &def.nested
            && def.end.is_none_or(|e| *j < e)
        {
            let k = ErrorKind::NestedSubDefinition {
                inner: inner.to_string(),
                outer: key.to_string(),
            };
            return Err(self.oerr(k, file, *j));
        }
        let end_line = def
            .end
            .map(|e| file.olines[e as usize].line_idx)
            .unwrap_or(u32::MAX);
        if let Some((_, start, e)) =
            file.skipped_error(file.olines[oidx as usize].line_idx, end_line)
        {
            return Err(self.error_in_line(e.kind.clone(), file, *start, e.span));
        }
        // The reference evaluates valued endsub/return lines of the
        // definition while skipping it, setting #<_value>.
        self.flow.defining = true;
        for &j in &def.valued {
            self.reader.at(
                file.olines[j as usize].start,
                file.olines[j as usize].line_idx,
            );
            let expr = match self.oline(file, j) {
                Ok(o) => o.expr.clone(),
                Err(e) => {
                    self.flow.defining = false;
                    return Err(e);
                }
            };
            match expr {
                Some(e) => match self.o_eval(file, j, &e) {
                    Ok(v) => {
                        self.flow.set_value(Some(v));
                    }
                    Err(e) => {
                        self.flow.defining = false;
                        return Err(e);
                    }
                },
                None => {
                    self.flow.set_value(None);
                }
            }
        }
        self.flow.defining = false;
        match def.end {
            Some(e) => {
                self.flow.goto(file, e, true);
                Ok(())
            }
            None => Err(self.oerr(
                ErrorKind::UnterminatedSub {
                    name: key.to_string(),
                },
                file,
                oidx,
            )),
        }
    }

    /// Finds a subroutine: registered, then a file on the search path, then
    /// further down the current file.
    fn resolve(
        &mut self,
        file: &Rc<FileIndex>,
        oidx: u32,
        name: &Name,
        base: &Name,
    ) -> Result<SubRec, Error> {
        if let Some(rec) = self.flow.subs.get(base) {
            return Ok(rec.clone());
        }
        let found = self
            .loader
            .find(name)
            .map_err(|k| self.oerr(k, file, oidx))?;
        if let Some(sub_file) = found {
            let target = sub_file
                .occ(base)
                .iter()
                .copied()
                .find(|&j| matches!(sub_file.kind_of(j), Some(OKind::Sub | OKind::Bare)));
            let Some(t) = target else {
                let k = crate::program::not_in_file(base, &sub_file.file);
                return Err(self.oerr(k, file, oidx));
            };
            let until = sub_file.olines[t as usize].line_idx;
            if let Some((_, start, e)) = sub_file.skipped_error(0, until).or_else(|| {
                sub_file
                    .skip_errors
                    .first()
                    .filter(|e| e.0 == 0 && until > 0)
            }) {
                let mut err = self.error_in_line(e.kind.clone(), &sub_file, *start, e.span);
                let (a, b) = self.osite(file, oidx);
                err.stack
                    .insert(0, crate::diag::Site::new(&file.file, a, b));
                return Err(err);
            }
            if sub_file.m99_lines.first().is_some_and(|&l| l < until) {
                // The reference reads M99 lines while seeking, which clears
                // #<_value>.
                self.flow.set_value(None);
            }
            return Ok(SubRec {
                file: sub_file,
                oidx: t,
            });
        }
        // Forward search in the current file.
        let line = file.olines[oidx as usize].line_idx;
        let t = self.seek(
            file,
            oidx,
            base,
            Seek::Sub {
                from_line: line + 1,
            },
            &[OKind::Sub, OKind::Bare],
        );
        match t {
            Ok(t) => {
                if file.m99_between(line, file.olines[t as usize].line_idx) {
                    self.flow.set_value(None);
                }
                Ok(SubRec {
                    file: file.clone(),
                    oidx: t,
                })
            }
            Err(e) if matches!(e.error_kind(), Some(ErrorKind::EofSeeking { .. })) => {
                let searched = self.loader.searched();
                Err(self.oerr(
                    ErrorKind::SubNotFound {
                        name: name.to_string(),
                        searched,
                    },
                    file,
                    oidx,
                ))
            }
            Err(e) => Err(e),
        }
    }

    /// Enters a call made by O-line `oidx` of `file`: the error past
    /// [`MAX_CALL_LEVEL`] nested calls.
    fn push_frame(
        &mut self,
        file: &Rc<FileIndex>,
        oidx: u32,
        kind: FrameKind,
        name: Name,
        ret: Cursor,
    ) -> Result<(), Error> {
        debug_assert!(Rc::ptr_eq(&ret.file, file));
        if self.flow.enter(kind, name, ret, oidx) {
            return Ok(());
        }
        let limit = MAX_CALL_LEVEL;
        Err(self.oerr(ErrorKind::TooDeep { limit }, file, oidx))
    }

    fn call(&mut self, file: &Rc<FileIndex>, oidx: u32, key: &Name) -> Result<(), Error> {
        let o = self.oline(file, oidx)?;
        let mut argv = [0f64; 30];
        let nargs = o.args.len().min(30);
        for (slot, a) in argv.iter_mut().zip(&o.args) {
            *slot = self.o_eval(file, oidx, a)?;
        }
        let base = base_key(key);
        let target = self.resolve(file, oidx, key, &base)?;
        if target.file.kind_of(target.oidx) == Some(OKind::Bare) {
            return Err(self.oerr(
                ErrorKind::FanucNeedsM98 {
                    name: base.to_string(),
                },
                file,
                oidx,
            ));
        }
        // Recursion from inside a running repeat shares its counter in the
        // reference.
        if self.flow.frame().name == base && self.flow.repeat_running() {
            let (a, b) = self.osite(file, oidx);
            self.warn(WarningKind::QuirkRepeatRecursion, file, a, b);
        }
        if self.flow.last_called.as_ref() != Some(&base) {
            self.flow.note_called(&base, &target);
            self.flow.last_called = Some(base.clone());
        }
        let o_info = &file.olines[oidx as usize];
        let ret = Cursor {
            file: file.clone(),
            pos: o_info.next,
            line: o_info.line_idx + 1,
            next_o: oidx as usize + 1,
        };
        self.push_frame(file, oidx, FrameKind::Call, base, ret)?;
        self.bind_args(&argv, nargs as f64);
        self.flow.goto(&target.file, target.oidx, true);
        Ok(())
    }

    /// Gives the frame just entered its arguments (see `Flow::bind_args`).
    pub(in crate::eval) fn bind_args(&mut self, argv: &[f64; 30], nargs: f64) {
        let oword_nargs = self.s.oword_nargs;
        self.flow
            .bind_args(&mut self.params, argv, nargs, oword_nargs);
    }

    fn return_from_call(
        &mut self,
        file: &Rc<FileIndex>,
        oidx: u32,
        v: Option<f64>,
    ) -> Result<(), Error> {
        self.flow.set_value(v);
        if self.flow.repeat_running() {
            let (a, b) = self.osite(file, oidx);
            self.warn(WarningKind::QuirkRepeatCount, file, a, b);
        }
        let mut f = self.flow.pop_call(&mut self.params);
        if f.auto_restore
            && let Some(m) = f.saved_modal.take()
        {
            self.restore_modal(&m)?;
        }
        self.flow.resume(f);
        Ok(())
    }

    /// `M99` inside a subprogram called with M98.
    pub(in crate::eval) fn return_m99(
        &mut self,
        file: &Rc<FileIndex>,
        start: u32,
        len: u32,
    ) -> Result<(), Error> {
        if self.flow.frame().kind != FrameKind::M98 {
            return Err(self.error(ErrorKind::M99InSub, file, start, start + len));
        }
        self.flow.set_value(None);
        // An M98 frame saved no arguments: `params` stays as it is.
        let mut f = self.flow.pop_call(&mut self.params);
        if f.auto_restore
            && let Some(m) = f.saved_modal.take()
        {
            self.restore_modal(&m)?;
        }
        self.flow.resume(f);
        Ok(())
    }

    fn exec_m98(
        &mut self,
        file: &Rc<FileIndex>,
        oidx: u32,
        m: &crate::parse::ast::M98Line,
    ) -> Result<(), Error> {
        if self.s.fanuc_disabled {
            return Err(self.oerr(ErrorKind::FanucDisabled { what: "M98" }, file, oidx));
        }
        let Some(p) = &m.p else {
            return Err(self.oerr(ErrorKind::M98WithoutP, file, oidx));
        };
        let line = file.olines[oidx as usize].line_idx;
        let pv = self.o_eval(file, oidx, p)?;
        let start = file.olines[oidx as usize].start;
        let n = integer_value(pv).map_err(|k| self.error_in_line(k, file, start, p.span))?;
        let pending = match self.flow.frame().m98_loop {
            Some((l, rem)) if l == line => Some(rem),
            _ => None,
        };
        match pending {
            Some(0) => {
                self.flow.frame().m98_loop = None;
                return Ok(());
            }
            Some(rem) => self.flow.frame().m98_loop = Some((line, rem - 1)),
            None => {
                let count = match &m.l {
                    Some(l) => {
                        let lv = self.o_eval(file, oidx, l)?;
                        integer_value(lv).map_err(|k| self.error_in_line(k, file, start, l.span))?
                    }
                    None => 1,
                };
                if count <= 0 {
                    if count == 0 {
                        let (a, b) = self.osite(file, oidx);
                        self.warn(WarningKind::QuirkL0, file, a, b);
                    }
                    return Ok(());
                }
                self.flow.frame().m98_loop = Some((line, count - 1));
            }
        }
        let name = Name::new(&n.to_string());
        let target = self.resolve(file, oidx, &name, &base_key(&name))?;
        if target.file.kind_of(target.oidx) == Some(OKind::Sub) {
            return Err(self.oerr(
                ErrorKind::SubNeedsCall {
                    name: name.to_string(),
                },
                file,
                oidx,
            ));
        }
        self.flow.note_called(&name, &target);
        let info = &file.olines[oidx as usize];
        let ret = Cursor {
            file: file.clone(),
            pos: info.start,
            line: info.line_idx,
            next_o: oidx as usize,
        };
        self.push_frame(file, oidx, FrameKind::M98, name, ret)?;
        self.flow.goto(&target.file, target.oidx, true);
        Ok(())
    }
}
