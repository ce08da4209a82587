//! O-words: each O-line run (calls and subroutines are in `call.rs`),
//! conditionals and loops, and the forward searches they make. Jump
//! targets come from the file index (occurrences of each label in order),
//! so nothing is rescanned per iteration.

use crate::diag::{OWordError, SetupError};
use std::rc::Rc;

use crate::diag::{Diagnostic, Error, ErrorKind, WarningKind};
use crate::parse::ast::{Label, LineKind, OKind, OLine};
use crate::parse::{Name, integer_value};
use crate::program::{FileIndex, ParsedO, control_key};

use crate::eval::Interp;
use crate::eval::expr::round_half_even_int;
use crate::eval::flow::{LabelRec, label_of_key, osite_of};

/// What a forward search was looking for (for the error when nothing is found).
pub(super) enum Seek {
    Control,
    Sub { from_line: u32 },
}

impl Interp<'_> {
    /// O-line `oidx` of `file`, parsed (an error if the file changed so
    /// that it is no longer the O-line the index found).
    pub(super) fn oline(&self, file: &Rc<FileIndex>, oidx: u32) -> Result<ParsedO, Error> {
        file.oline(oidx).map_err(|k| self.oerr(k, file, oidx))
    }

    pub(in crate::eval) fn osite(&self, file: &Rc<FileIndex>, oidx: u32) -> (u32, u32) {
        osite_of(file, oidx)
    }
}

impl Interp<'_> {
    pub(super) fn oerr(&self, kind: ErrorKind, file: &Rc<FileIndex>, oidx: u32) -> Error {
        let (a, b) = self.osite(file, oidx);
        self.error(kind, file, a, b)
    }

    /// Evaluates an expression of an O-line.
    pub(super) fn o_eval(
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
    pub(super) fn seek(
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
            return Err(self.error(
                ErrorKind::OWord(OWordError::LabelBeforePercent { label }),
                file,
                a,
                b,
            ));
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
                    Seek::Control => ErrorKind::OWord(OWordError::MissingProgramEnd {
                        percent: self.main.percent_start,
                    }),
                    Seek::Sub { from_line } => ErrorKind::OWord(OWordError::EofSeeking {
                        label: key.to_string(),
                        from_line,
                    }),
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
                return Err(self.oerr(
                    ErrorKind::OWord(OWordError::DuplicateLabel { label, first_line }),
                    file,
                    oidx,
                ));
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
            None => Err(self.oerr(
                ErrorKind::OWord(OWordError::UndefinedLabel { label: label() }),
                file,
                oidx,
            )),
            Some(rec) if kinds.contains(&rec.kind) => Ok(rec),
            Some(rec) => Err(self.oerr(
                ErrorKind::OWord(OWordError::LabelMismatch {
                    label: label(),
                    here: file.kind_of(oidx).map_or("M98", OKind::name),
                    opened: rec.kind.name(),
                    line: rec.line + 1,
                }),
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
                ErrorKind::Setup(SetupError::Internal {
                    what: format!("an O-line without its {what}"),
                }),
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

    /// Under warn-only O-words (`OWORD_WARNONLY`), one of LinuxCNC's O-word
    /// errors raised by the line being run becomes a warning and the line
    /// is skipped (`Ok`); any other error stays an error.
    pub(super) fn soft(&mut self, e: Error, file: &Rc<FileIndex>) -> Result<(), Error> {
        let soft = self.s.oword_warn_only
            && matches!(
                e.error_kind(),
                Some(
                    ErrorKind::OWord(OWordError::NotInSub)
                        | ErrorKind::OWord(OWordError::DuplicateLabel { .. })
                        | ErrorKind::OWord(OWordError::UndefinedLabel { .. })
                        | ErrorKind::OWord(OWordError::LabelMismatch { .. })
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
            let e = self.oerr(
                ErrorKind::OWord(OWordError::DuplicateLabel { label, first_line }),
                file,
                t,
            );
            return self.soft(e, file);
        }
        let (opened, line) = rec.map(|r| (r.kind.name(), r.line + 1)).unwrap_or(("?", 0));
        let e = self.oerr(
            ErrorKind::OWord(OWordError::LabelMismatch {
                label,
                here: found,
                opened,
                line,
            }),
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
}
