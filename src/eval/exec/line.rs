//! One ordinary line: evaluate every value with pre-line parameters, apply
//! the assignments, act on the active comment, write the line with values in
//! place of expressions, and update the state model. The steps span the
//! parts: the reader's checks and buffers (`eval/read/block.rs`), the
//! expressions, the parameters, control flow (M99), the output and the
//! machine model.

use crate::diag::{ExprError, LimitError, OWordError};
use std::rc::Rc;

use crate::codes::MCode;
use crate::diag::{ErrorKind, WarningKind};
use crate::emit::{Edit, max_edited_len, write_edited};
use crate::parse::MAX_LINE;
use crate::parse::ast::{Assign, Comment, CommentKind, Item, ParamRef, Span, Word};
use crate::program::FileIndex;

use crate::eval::Interp;
use crate::eval::expr::message::{is_stable, stabilize};
use crate::eval::expr::params::is_read_only;
use crate::eval::flow::FrameKind;
use crate::eval::read::block::{
    Scratch, WordCounts, letter_refusal, letter_refused, m_word, m98_word, plain_word, plain_words,
    trimmed_len,
};
use crate::eval::read::validate::check_block;
use crate::eval::state::checked::Checked;

impl Interp<'_> {
    /// The block checks of a line's evaluated `words` in the machine's
    /// present state (its modes, the NURBS points gathered, the canned
    /// cycle series): the codes decoded, or the error and the index of the
    /// word it is about.
    #[inline]
    pub(super) fn check_words(
        &self,
        words: &[(u8, f64)],
    ) -> Result<Checked, (ErrorKind, Option<usize>)> {
        let m = &self.mach;
        check_block(words, &m.modal, &m.nurbs, &m.cycle, self.s.user_m)
    }

    pub(in crate::eval) fn exec_items(
        &mut self,
        file: &Rc<FileIndex>,
        start: u32,
        raw: &[u8],
        items: &[Item],
    ) -> Result<(), crate::diag::Error> {
        // Scratch buffers are reused from line to line.
        // Boxed: taking it out and putting it back moves a pointer.
        let mut scratch = self.reader.scratch.take().unwrap_or_default();
        let r = self.exec_items_with(file, start, raw, items, &mut scratch);
        self.reader.scratch = Some(scratch);
        r
    }

    fn exec_items_with(
        &mut self,
        file: &Rc<FileIndex>,
        start: u32,
        raw: &[u8],
        items: &[Item],
        scratch: &mut Scratch,
    ) -> Result<(), crate::diag::Error> {
        scratch.clear();
        if items.iter().all(plain_word) {
            return self.exec_words(file, start, raw, items, scratch);
        }
        if items.iter().all(|i| matches!(i, Item::Assign(_))) {
            return self.exec_assigns(file, start, items, scratch);
        }
        let Scratch {
            words,
            repl,
            num_set,
            named_set,
            context_ops,
            word_spans,
            ..
        } = scratch;
        let mut active = None;
        let mut counts = WordCounts::default();
        // 1. Read the line: every value sees the parameters as they were.
        for item in items {
            match item {
                Item::Word(w) => {
                    let v = self.read_word(file, start, w, &mut counts)?;
                    words.push((w.letter, v));
                    word_spans.push(w.span);
                    if !w.literal {
                        repl.push((w.value.span, Edit::Number(v)));
                    }
                }
                Item::Assign(a) => {
                    self.read_assign(file, start, a, num_set, named_set)?;
                    repl.push((a.span, Edit::Remove));
                }
                Item::Comment(c) => {
                    if c.kind != CommentKind::Semicolon {
                        active = Some(c);
                    }
                    if self.s.strip_comments {
                        repl.push((c.span, Edit::Remove));
                    }
                }
            }
        }
        // The reference checks the block before acting on it (a line
        // without words has no codes).
        let result = if words.is_empty() {
            Ok(Checked::Simple)
        } else {
            self.check_words(words)
        };
        // An M98 here is not a call (that is an O-line): refused.
        if let Ok(c) = &result
            && let Some(span) = m98_word(c, items, raw.len() as u32)
        {
            return Err(self.error_in_line(
                ErrorKind::OWord(OWordError::M98AmongWords),
                file,
                start,
                span,
            ));
        }
        // Borrowed where it is: the codes are not copied.
        let checked = match result {
            Ok(Checked::Simple) => &Checked::Simple,
            Err((k, at)) => {
                let span = at
                    .and_then(|i| word_spans.get(i).copied())
                    .unwrap_or(Span::new(0, raw.len() as u32));
                return Err(self.error_in_line(k, file, start, span));
            }
            Ok(Checked::Lathe(ref codes, at)) => {
                self.apply_assigns(num_set, named_set);
                return self.lathe_block(file, start, raw.len() as u32, words, codes, at);
            }
            Ok(ref c) => c,
        };
        // Context save/restore (M70-M73), from the checked codes: each
        // word is replaced by explicit words.
        let ms = checked.ms();
        if ms.iter().any(|m| matches!(m, MCode::State(_))) {
            for (k, &m) in ms.iter().enumerate() {
                if let (MCode::State(op), Some(w)) = (m, m_word(items, k)) {
                    repl.retain(|(s, _)| *s != w.value.span);
                    repl.push((w.span, Edit::Remove));
                    context_ops.push((op, w.span));
                }
            }
        }
        // 2. Assignments: numbered in order, then named in order.
        self.apply_assigns(num_set, named_set);
        // 3. The active comment, after the assignments.
        if let Some(c) = active {
            self.active_comment(file, start, raw, c, repl)?;
        }
        // 4. Program flow words: M99, from the checked codes.
        let m99_at = ms.iter().position(|&m| m == MCode::Other(99));
        if let Some(k) = m99_at.filter(|_| self.flow.level() > 0) {
            return self.m99_line(file, start, raw.len() as u32, items, k);
        }
        if let Some(w) = m99_at.and_then(|k| m_word(items, k)) {
            // M99 in the main program ends it like M2 in the reference.
            repl.retain(|(s, _)| *s != w.value.span);
            repl.push((w.span, Edit::Text("M2".into())));
        }
        let m99 = m99_at.is_some();
        // 5. Write the line.
        repl.sort_by_key(|(s, _)| s.start);
        let kept = items
            .iter()
            .filter(|i| match i {
                Item::Word(w) => !context_ops.iter().any(|(_, s)| *s == w.span),
                Item::Assign(_) => false,
                Item::Comment(c) => {
                    !self.s.strip_comments
                        && !repl
                            .iter()
                            .any(|(s, r)| matches!(r, Edit::Remove) && *s == c.span)
                }
            })
            .count();
        if kept > 0 {
            self.write_line(file, start, raw, repl, &[])?;
        }
        // 6. State.
        let ends = self.apply_words(file, start, words, checked, m99)?;
        for &(op, span) in context_ops.iter() {
            self.context_op(op, file, start, span)?;
        }
        if ends {
            self.end_program()?;
        }
        Ok(())
    }

    /// A line whose `k`-th M code is an M99 in a subprogram: the return,
    /// which is the whole line (the reference refuses a word or assignment
    /// beside it, after acting on them).
    fn m99_line(
        &mut self,
        file: &Rc<FileIndex>,
        start: u32,
        len: u32,
        items: &[Item],
        k: usize,
    ) -> Result<(), crate::diag::Error> {
        let own = m_word(items, k).map(|w| w.span);
        let other = items.iter().find_map(|i| match i {
            Item::Word(w) if Some(w.span) != own => Some(w.span),
            Item::Assign(a) => Some(a.span),
            _ => None,
        });
        // (In an O-word subroutine the M99 is refused on its own.)
        if let Some(span) = other
            && self.flow.frame().kind == FrameKind::M98
        {
            return Err(self.error_in_line(
                ErrorKind::OWord(OWordError::M99AmongWords),
                file,
                start,
                span,
            ));
        }
        self.return_m99(file, start, len)
    }

    /// A `(debug,…)`, `(print,…)`, `(log,…)` or `(abort,…)` comment, after
    /// the line's assignments: its text with the parameters substituted.
    fn active_comment(
        &mut self,
        file: &Rc<FileIndex>,
        start: u32,
        raw: &[u8],
        c: &Comment,
        repl: &mut Vec<(Span, Edit)>,
    ) -> Result<(), crate::diag::Error> {
        match c.kind {
            CommentKind::Debug | CommentKind::Print | CommentKind::Log | CommentKind::Abort => {
                let body =
                    String::from_utf8_lossy(&raw[c.body.start as usize..c.body.end as usize])
                        .into_owned();
                let text = self
                    .substitute(&body, c.body.start)
                    .map_err(|f| self.fault_in_line(*f, file, start))?;
                if c.kind == CommentKind::Abort {
                    return Err(self.error_in_line(
                        ErrorKind::OWord(OWordError::Abort { message: text }),
                        file,
                        start,
                        c.span,
                    ));
                }
                if !self.s.strip_comments {
                    if c.kind == CommentKind::Debug && self.params.values[5599] <= 0.0 {
                        repl.push((c.span, Edit::Remove));
                    } else if c.kind == CommentKind::Debug {
                        // As (msg,...) the text is shown exactly as
                        // substituted and never read for parameters again.
                        repl.push((c.span, Edit::Text(format!("(MSG,{text})"))));
                    } else {
                        let text = stabilize(&text);
                        if !is_stable(&text) {
                            self.warn(
                                WarningKind::MessageNotStable,
                                file,
                                start + c.span.start,
                                start + c.span.end,
                            );
                        }
                        repl.push((c.body, Edit::Text(text)));
                    }
                }
            }
            _ => {}
        }
        Ok(())
    }

    /// The value of a word, after the checks on its letter that the
    /// reference makes while reading the line (U/V/W without those axes, a
    /// fifth M word, a letter given twice).
    #[inline(always)]
    fn read_word(
        &mut self,
        file: &Rc<FileIndex>,
        start: u32,
        w: &Word,
        counts: &mut WordCounts,
    ) -> Result<f64, crate::diag::Error> {
        if letter_refused(w, self.s.uvw_axes) {
            let (k, at) = letter_refusal(w);
            return Err(self.error_in_line(k, file, start, at));
        }
        let v = self
            .eval_value(&w.value)
            .map_err(|f| self.fault_in_line(*f, file, start))?;
        if !counts.count(w) {
            let k = WordCounts::refusal(w);
            return Err(self.error_in_line(k, file, start, w.span));
        }
        Ok(v)
    }

    /// Reads an assignment (target checks, then the value) into the sets
    /// applied after the line is read.
    #[inline(always)]
    pub(in crate::eval) fn read_assign(
        &mut self,
        file: &Rc<FileIndex>,
        start: u32,
        a: &Assign,
        num_set: &mut Vec<(usize, f64)>,
        named_set: &mut Vec<(crate::parse::Name, f64)>,
    ) -> Result<(), crate::diag::Error> {
        match &a.target {
            ParamRef::Numbered(index) => {
                let i = self
                    .param_index(index)
                    .map_err(|f| self.fault_in_line(*f, file, start))?;
                if is_read_only(i) {
                    let k = ErrorKind::Expr(ExprError::ParamReadOnly { index: i as i64 });
                    return Err(self.error_in_line(k, file, start, a.target_span));
                }
                let v = self
                    .eval_value(&a.value)
                    .map_err(|f| self.fault_in_line(*f, file, start))?;
                num_set.push((i, v));
            }
            ParamRef::Named(name) => {
                self.create_named(name, a.target_span)
                    .map_err(|f| self.fault_in_line(*f, file, start))?;
                let v = self
                    .eval_value(&a.value)
                    .map_err(|f| self.fault_in_line(*f, file, start))?;
                named_set.push((name.clone(), v));
            }
        }
        Ok(())
    }

    /// The line's assignments, numbered in order, then named in order.
    pub(in crate::eval) fn apply_assigns(
        &mut self,
        num_set: &[(usize, f64)],
        named_set: &[(crate::parse::Name, f64)],
    ) {
        for &(i, v) in num_set {
            self.params.assign(i, v);
        }
        for (n, v) in named_set {
            self.set_named(n, *v);
        }
    }

    /// A block ended the program (M2, M30, M99 at the top): the closing `%`
    /// of a `%` program, then nothing more runs.
    pub(in crate::eval) fn end_program(&mut self) -> Result<(), crate::diag::Error> {
        if self.main.percent_start {
            self.emit_raw(b"%")?;
        }
        self.out.ended = true;
        Ok(())
    }

    /// A line of words only, none of them a program-flow or context M-code
    /// (the common line of a loop body): `exec_items_with` without the
    /// steps that have nothing to do.
    fn exec_words(
        &mut self,
        file: &Rc<FileIndex>,
        start: u32,
        raw: &[u8],
        items: &[Item],
        scratch: &mut Scratch,
    ) -> Result<(), crate::diag::Error> {
        let Scratch {
            words, repl, known, ..
        } = scratch;
        let mut counts = WordCounts::default();
        for item in items {
            let Item::Word(w) = item else {
                unreachable!("checked by plain_word")
            };
            let v = self.read_word(file, start, w, &mut counts)?;
            words.push((w.letter, v));
            if !w.literal {
                repl.push((w.value.span, Edit::Number(v)));
            }
        }
        // For a consumer, the values of the words as written (the shortest
        // text of each computed one reads back as exactly its value; a
        // literal keeps its text, read again).
        if self.out.consuming() && self.s.precision.is_none() {
            known.extend(items.iter().zip(words.iter()).map(|(i, &(l, v))| {
                let literal = matches!(i, Item::Word(w) if w.literal);
                (l.to_ascii_uppercase(), if literal { f64::NAN } else { v })
            }));
        }
        if self.fast_words(words) {
            // Checked and applied: a plain move.
            return self.write_line(file, start, raw, repl, known);
        }
        let checked = match self.check_words(words) {
            Err((k, at)) => {
                let span = match at.and_then(|i| items.get(i)) {
                    Some(Item::Word(w)) => w.span,
                    _ => Span::new(0, raw.len() as u32),
                };
                return Err(self.error_in_line(k, file, start, span));
            }
            Ok(Checked::Lathe(codes, at)) => {
                return self.lathe_block(file, start, raw.len() as u32, words, &codes, at);
            }
            Ok(c) => c,
        };
        self.write_line(file, start, raw, repl, known)?;
        if self.apply_words(file, start, words, &checked, false)? {
            self.end_program()?;
        }
        Ok(())
    }

    /// A line of assignments only: `exec_items_with` without the steps that
    /// have nothing to do (nothing is written).
    fn exec_assigns(
        &mut self,
        file: &Rc<FileIndex>,
        start: u32,
        items: &[Item],
        scratch: &mut Scratch,
    ) -> Result<(), crate::diag::Error> {
        let Scratch {
            num_set, named_set, ..
        } = scratch;
        for item in items {
            let Item::Assign(a) = item else {
                unreachable!("only assignments")
            };
            self.read_assign(file, start, a, num_set, named_set)?;
        }
        // No words: an empty block changes nothing in the state model.
        self.apply_assigns(num_set, named_set);
        Ok(())
    }

    /// Writes the line with its replacements. A line that cannot be too
    /// long whatever its numbers read goes to the output with them (to be
    /// written maybe on the output thread); any other is written here to
    /// check its length. A consumer gets the values of its words with it
    /// where `known` has them.
    fn write_line(
        &mut self,
        file: &Rc<FileIndex>,
        start: u32,
        raw: &[u8],
        repl: &[(Span, Edit)],
        known: &[(u8, f64)],
    ) -> Result<(), crate::diag::Error> {
        if !self.out.consuming()
            && max_edited_len(raw.len(), repl, self.s.precision).is_some_and(|n| n <= MAX_LINE)
        {
            self.count_line()?;
            return self
                .out
                .output
                .edited_line(raw, repl)
                .map_err(|e| self.output_error_at(e, &file.file, start));
        }
        // The consumer on its own thread puts a line of numbers in their
        // shortest form together itself, where it cannot fail.
        if self.out.consumer_apart()
            && self.s.precision.is_none()
            && !repl.is_empty()
            && repl.len() <= usize::from(u8::MAX)
            && repl.iter().all(|(_, e)| matches!(e, Edit::Number(_)))
            && max_edited_len(raw.len(), repl, None).is_some_and(|n| n <= MAX_LINE)
        {
            self.count_line()?;
            let f = file.file.clone();
            return self.consume_edited(&f, start, raw, repl, known);
        }
        let mut out = std::mem::take(&mut self.out.buf);
        out.clear();
        if let Err((value, span)) = write_edited(&mut out, raw, repl, self.s.precision) {
            self.out.buf = out;
            let k = ErrorKind::Limit(LimitError::Unprintable { value });
            return Err(self.error_in_line(k, file, start, span));
        }
        if out.len() > MAX_LINE {
            let len = out.len();
            self.out.buf = out;
            let end = start + trimmed_len(raw) as u32;
            return Err(self.error(
                ErrorKind::Limit(LimitError::OutputLineTooLong { len }),
                file,
                start,
                end,
            ));
        }
        let r = if self.out.consuming() {
            let f = file.file.clone();
            let verbatim = repl.is_empty();
            self.count_line().and_then(|_| {
                if known.is_empty() {
                    self.consume(&f, start, &out, verbatim)
                } else {
                    self.consume_known(&f, start, &out, verbatim, known)
                }
            })
        } else {
            self.emit_raw(&out)
        };
        self.out.buf = out;
        r
    }
}

impl Interp<'_> {
    /// Runs a plain line (literal words only, see
    /// [`crate::eval::read::plain`]) of the words `read` (their spans in the
    /// line). `None` sends the line to the grammar instead.
    pub(in crate::eval) fn exec_plain(
        &mut self,
        file: &Rc<FileIndex>,
        start: u32,
        raw: &[u8],
        read: &[crate::block::RawWord],
    ) -> Option<Result<(), crate::diag::Error>> {
        let mut words = std::mem::take(&mut self.reader.words_buf);
        words.clear();
        if !plain_words(read, self.s.uvw_axes, &mut words) {
            self.reader.words_buf = words;
            return None;
        }
        let r = (|| {
            let checked = match self.check_words(&words) {
                Err((k, at)) => {
                    let span = at
                        .and_then(|i| read.get(i))
                        .map(|w| Span::new(w.span.start.into(), w.span.end.into()))
                        .unwrap_or(Span::new(0, raw.len() as u32));
                    return Err(self.error_in_line(k, file, start, span));
                }
                Ok(Checked::Lathe(codes, at)) => {
                    let len = raw.len() as u32;
                    return self.lathe_block(file, start, len, &words, &codes, at);
                }
                Ok(c) => c,
            };
            self.emit_source(file, start, &raw[..trimmed_len(raw)])?;
            if self.apply_words(file, start, &words, &checked, false)? {
                self.end_program()?;
            }
            Ok(())
        })();
        self.reader.words_buf = words;
        Some(r)
    }
}
