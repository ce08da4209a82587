//! Subroutines and calls: a `sub` definition reached and skipped, `call`
//! (the sub found: registered, in a file on the search path, or further
//! down), its arguments, `endsub`/`return`, and the Fanuc-style M98/M99
//! subprograms.

use crate::diag::OWordError;
use std::rc::Rc;

use crate::diag::{Error, ErrorKind, WarningKind};
use crate::parse::ast::{OKind, OLine};
use crate::parse::{Name, integer_value};
use crate::program::FileIndex;

use crate::eval::Interp;
use crate::eval::flow::{Cursor, FrameKind, MAX_CALL_LEVEL, SubRec, base_key};

use super::control::Seek;

impl Interp<'_> {
    /// `endsub`/`return`: leaves the subroutine with its value, if any.
    pub(super) fn exec_return(
        &mut self,
        file: &Rc<FileIndex>,
        oidx: u32,
        o: &OLine,
    ) -> Result<(), Error> {
        if self.flow.level() == 0 {
            let e = self.oerr(ErrorKind::OWord(OWordError::NotInSub), file, oidx);
            return self.soft(e, file);
        }
        if self.flow.frame().kind == FrameKind::M98 {
            return Err(self.oerr(ErrorKind::OWord(OWordError::EndsubInFanuc), file, oidx));
        }
        let v = match &o.expr {
            Some(e) => Some(self.o_eval(file, oidx, e)?),
            None => None,
        };
        self.return_from_call(file, oidx, v)
    }

    /// A bare O-word (M98 subprogram start) reached in normal flow.
    pub(super) fn exec_bare(
        &mut self,
        file: &Rc<FileIndex>,
        oidx: u32,
        key: &Name,
    ) -> Result<(), Error> {
        if self.s.fanuc_disabled {
            return Err(self.oerr(
                ErrorKind::OWord(OWordError::FanucDisabled {
                    what: "a bare O-word",
                }),
                file,
                oidx,
            ));
        }
        if self.flow.level() > 0 {
            return Err(self.oerr(
                ErrorKind::OWord(OWordError::FanucNeedsM98 {
                    name: key.to_string(),
                }),
                file,
                oidx,
            ));
        }
        Ok(())
    }

    /// A `sub` line reached by normal flow: a definition to register and
    /// skip.
    pub(super) fn reach_sub(
        &mut self,
        file: &Rc<FileIndex>,
        oidx: u32,
        key: &Name,
    ) -> Result<(), Error> {
        if self.flow.level() > 0 {
            let outer = self
                .flow
                .frames
                .last()
                .map(|f| f.name.to_string())
                .unwrap_or_default();
            return Err(self.oerr(
                ErrorKind::OWord(OWordError::NestedSubDefinition {
                    inner: key.to_string(),
                    outer,
                }),
                file,
                oidx,
            ));
        }
        if let Some(rec) = self.flow.subs.get(key) {
            if Rc::ptr_eq(&rec.file, file) && rec.oidx == oidx {
                return Err(self.oerr(
                    ErrorKind::OWord(OWordError::IllegalSubLocation {
                        name: key.to_string(),
                    }),
                    file,
                    oidx,
                ));
            }
            let first = rec.file.file.path.clone();
            let first_line = rec.file.olines[rec.oidx as usize].line_idx + 1;
            return Err(self.oerr(
                ErrorKind::OWord(OWordError::RedefiningSub {
                    name: key.to_string(),
                    first,
                    first_line,
                }),
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
            return Err(self.oerr(ErrorKind::OWord(OWordError::ComputedSubLabel), file, oidx));
        };
        if let Some((j, inner)) = &def.nested
            && def.end.is_none_or(|e| *j < e)
        {
            let k = ErrorKind::OWord(OWordError::NestedSubDefinition {
                inner: inner.to_string(),
                outer: key.to_string(),
            });
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
                ErrorKind::OWord(OWordError::UnterminatedSub {
                    name: key.to_string(),
                }),
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
            Err(e)
                if matches!(
                    e.error_kind(),
                    Some(ErrorKind::OWord(OWordError::EofSeeking { .. }))
                ) =>
            {
                let searched = self.loader.searched();
                Err(self.oerr(
                    ErrorKind::OWord(OWordError::SubNotFound {
                        name: name.to_string(),
                        searched,
                    }),
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
        Err(self.oerr(ErrorKind::OWord(OWordError::TooDeep { limit }), file, oidx))
    }

    pub(super) fn call(
        &mut self,
        file: &Rc<FileIndex>,
        oidx: u32,
        key: &Name,
    ) -> Result<(), Error> {
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
                ErrorKind::OWord(OWordError::FanucNeedsM98 {
                    name: base.to_string(),
                }),
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
        self.leave_call()
    }

    /// Leaves the innermost call: the caller's #1-#30 back, the modal state
    /// M73 saved restored, reading resumed after the call.
    fn leave_call(&mut self) -> Result<(), Error> {
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
            return Err(self.error(
                ErrorKind::OWord(OWordError::M99InSub),
                file,
                start,
                start + len,
            ));
        }
        self.flow.set_value(None);
        // An M98 frame saved no arguments: `params` stays as it is.
        self.leave_call()
    }

    pub(super) fn exec_m98(
        &mut self,
        file: &Rc<FileIndex>,
        oidx: u32,
        m: &crate::parse::ast::M98Line,
    ) -> Result<(), Error> {
        if self.s.fanuc_disabled {
            return Err(self.oerr(
                ErrorKind::OWord(OWordError::FanucDisabled { what: "M98" }),
                file,
                oidx,
            ));
        }
        let Some(p) = &m.p else {
            return Err(self.oerr(ErrorKind::OWord(OWordError::M98WithoutP), file, oidx));
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
                ErrorKind::OWord(OWordError::SubNeedsCall {
                    name: name.to_string(),
                }),
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
