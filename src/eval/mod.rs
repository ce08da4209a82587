//! The evaluator: runs a program the way LinuxCNC's interpreter would and
//! writes the lines it executes, with every parameter and expression replaced
//! by its value.

mod exec;
mod expr;
mod flow;
mod read;
pub(crate) mod state;
mod write;

pub(crate) use state::arc::arc_refusal;

use crate::diag::{LimitError, OWordError, SetupError, SyntaxError};
use flow::{Flow, Frame, FrameKind, label_of_key};
use read::Reader;
use read::plain;
use state::Machine;
pub(crate) use write::output_error;
use write::{Writer, place_limit, too_large};

use std::collections::HashSet;

use std::rc::Rc;
use std::sync::Arc;

use crate::diag::{Diagnostic, Error, ErrorKind, Site, WarningKind};
use crate::emit::Sink;
use crate::parse::ast::{Line, LineKind, OKind, Span};
use crate::parse::{LineParser, Name};
use crate::program::{FileIndex, Loader, SourceFile, Window, next_line};
use crate::settings::{Define, Settings};

pub(crate) use write::hook::{FormLine, FormLines, LineConsumer, Origin};

use expr::params::Params;

/// The evaluator. Its state is in owned parts, each changed through its own
/// fields and methods: the machine model (`mach`), control flow (`flow`),
/// parameters (`params`), the reader (`reader`), the output (`out`) and the
/// diagnostics (`diags`).
pub(crate) struct Interp<'s> {
    s: &'s Settings,
    pub loader: Loader,
    main: Rc<FileIndex>,
    mach: Machine,
    flow: Flow,
    params: Params,
    reader: Reader,
    out: Writer<'s>,
    diags: Diags,
}

/// Warnings given so far.
#[derive(Default)]
struct Diags {
    warnings: Vec<Diagnostic>,
    /// Warnings already given, to report each site once.
    warned: HashSet<(&'static str, usize, u32)>,
}

impl Diags {
    /// Notes a warning of `code` at `start` of the file `file_key`; false
    /// when one was given there already.
    fn first_at(&mut self, code: &'static str, file_key: usize, start: u32) -> bool {
        self.warned.insert((code, file_key, start))
    }
}

/// Subroutines defined in the main file and never called: (name, start,
/// end of the `sub` line), with the file and the call stack at the end.
#[derive(Default)]
struct Unused {
    file: Option<std::sync::Arc<crate::program::SourceFile>>,
    stack: Vec<Site>,
    subs: Vec<(Name, u32, u32)>,
}

impl Unused {
    /// Appends their warnings.
    fn give(self, warnings: &mut Vec<Diagnostic>) {
        let Some(file) = self.file else {
            return;
        };
        warnings.reserve_exact(self.subs.len());
        for (name, start, end) in self.subs {
            let kind = WarningKind::UnusedSub {
                name: name.to_string(),
            };
            let mut w = Diagnostic::warning(kind, Some(Site::new(&file, start, end)));
            w.stack.clone_from(&self.stack);
            warnings.push(w);
        }
    }
}

/// An error reading a streamed program file.
fn read_error(file: &FileIndex, e: std::io::Error) -> Error {
    Diagnostic::error(
        ErrorKind::Setup(SetupError::Io {
            path: file.file.path.clone(),
            message: e.to_string(),
        }),
        None,
    )
}

fn file_key(f: &Rc<FileIndex>) -> usize {
    Rc::as_ptr(f) as usize
}

impl<'s> Interp<'s> {
    /// Evaluates an expression that reads no parameter (the library check
    /// of `check`): its value, or the error and its span in the line.
    pub(crate) fn eval_constant(
        &mut self,
        e: &crate::parse::ast::Expr,
    ) -> Result<f64, (ErrorKind, crate::parse::ast::Span)> {
        self.eval(e).map_err(|f| *f)
    }

    pub(crate) fn new(
        s: &'s Settings,
        loader: Loader,
        main: Rc<FileIndex>,
        sink: Sink,
    ) -> Interp<'s> {
        let mut params = Params::new(s.zero_start);
        for d in &s.defines {
            match d {
                Define::Numbered(i, v) => params.assign(*i, *v),
                // Level-0 locals share the global table.
                Define::Named(n, v) => {
                    params.globals.insert(Name::new(n), *v);
                }
            }
        }
        let main_frame = Frame::new(FrameKind::Main, Name::new(""));
        Interp {
            s,
            loader: loader.named2007(s.named_params_2007),
            mach: Machine::new(s),
            flow: Flow::new(main.clone(), main_frame),
            params,
            reader: Reader::new(s.named_params_2007),
            out: Writer::new(sink, s, main.line_count),
            diags: Diags::default(),
            main,
        }
    }

    /// Hands every output line to `consumer` instead of the output.
    pub(crate) fn with_consumer(mut self, consumer: Box<dyn LineConsumer + 's>) -> Interp<'s> {
        self.out.consumer = Some(consumer);
        self.out.apart_after = self.s.format_thread_after;
        self
    }

    /// The call stack as sites, innermost caller first.
    fn stack(&self) -> Vec<Site> {
        self.flow.stack()
    }

    /// An error writing the output line that starts at `at` in `file`;
    /// the byte limit is placed at that line.
    #[cold]
    pub(crate) fn output_error_at(
        &self,
        e: std::io::Error,
        file: &Arc<SourceFile>,
        at: u32,
    ) -> Error {
        self.placed(output_error(e), file, at)
    }

    /// An error writing `bytes`, the bytes of `file` from `start` on
    /// (whole lines); the byte limit is placed at the line holding the
    /// first byte past it.
    #[cold]
    pub(crate) fn output_error_in(
        &self,
        e: std::io::Error,
        file: &Arc<SourceFile>,
        start: u64,
        bytes: &[u8],
    ) -> Error {
        let room = too_large(&e).map_or(0, |t| t.room);
        let past = usize::try_from(room)
            .unwrap_or(usize::MAX)
            .min(bytes.len().saturating_sub(1));
        let line =
            memchr::memrchr(b'\n', bytes.get(..past).unwrap_or_default()).map_or(0, |i| i + 1);
        let at = u32::try_from(start + line as u64).unwrap_or(u32::MAX);
        self.placed(output_error(e), file, at)
    }

    /// `e` placed at the line starting at `at` in `file` with the calls
    /// that led there, if it is the output byte limit without a place.
    #[cold]
    pub(crate) fn placed(&self, e: Error, file: &Arc<SourceFile>, at: u32) -> Error {
        place_limit(e, file, at, || self.stack())
    }

    pub(crate) fn error(
        &self,
        kind: ErrorKind,
        file: &Rc<FileIndex>,
        start: u32,
        end: u32,
    ) -> Error {
        let mut e = Diagnostic::error(kind, Some(Site::new(&file.file, start, end)));
        e.stack = self.stack();
        e
    }

    /// Error at a span of the line starting at `line_start`.
    pub(crate) fn error_in_line(
        &self,
        kind: ErrorKind,
        file: &Rc<FileIndex>,
        line_start: u32,
        span: Span,
    ) -> Error {
        self.error(kind, file, line_start + span.start, line_start + span.end)
    }

    /// Error for an evaluation fault in the line starting at `line_start`.
    pub(crate) fn fault_in_line(
        &self,
        (kind, span): (ErrorKind, Span),
        file: &Rc<FileIndex>,
        line_start: u32,
    ) -> Error {
        self.error_in_line(kind, file, line_start, span)
    }

    pub(crate) fn warn(&mut self, kind: WarningKind, file: &Rc<FileIndex>, start: u32, end: u32) {
        if !self.s.warnings {
            return;
        }
        if !self.diags.first_at(kind.code(), file_key(file), start) {
            return;
        }
        let mut d = Diagnostic::warning(kind, Some(Site::new(&file.file, start, end)));
        d.stack = self.stack();
        self.diags.warnings.push(d);
    }

    /// Runs the program; returns every diagnostic (with a consumer that
    /// keeps its errors, those too) and the error that stopped the run, if
    /// any. The output is released only without an error.
    pub(crate) fn run_all(mut self) -> (Vec<Diagnostic>, Option<Error>) {
        let r = self.run_steps();
        if let Some(p) = &self.out.progress {
            p.clear();
        }
        let unused = if r.is_ok() {
            self.finish_warnings()
        } else {
            Unused::default()
        };
        // Where an output error past the end of the run is placed: the last
        // line run.
        let (last, at) = (self.flow.cur.file.file.clone(), self.reader.line_start);
        let stack = self.stack();
        let place = |e: Error| place_limit(e, &last, at, || stack.clone());
        let Interp {
            out:
                Writer {
                    mut output,
                    consumer,
                    ..
                },
            diags: Diags { mut warnings, .. },
            mut loader,
            main,
            mach,
            flow,
            params,
            reader,
            ..
        } = self;
        // The run's state (the file index, the subroutine records, the
        // loaded files) goes before the never-called warnings are made: a
        // program of a million subroutines holds one or the other, not both.
        let loader_warnings = std::mem::take(&mut loader.warnings);
        drop((main, mach, flow, params, reader, loader));
        unused.give(&mut warnings);
        warnings.extend(loader_warnings);
        let mut err = r.err();
        if let Some(mut c) = consumer {
            match c.finish(&mut output) {
                Ok(d) => warnings.extend(d),
                Err(e) => {
                    err.get_or_insert(place(e));
                }
            }
        }
        let failed = err.is_some()
            || warnings
                .iter()
                .any(|d| d.level() == crate::diag::Level::Error);
        if !failed && let Err(e) = output.finish() {
            err = Some(place(output_error(e)));
        }
        (warnings, err)
    }

    fn run_steps(&mut self) -> Result<(), Error> {
        let main = self.main.clone();
        if let Some(e) = &main.read_error {
            let k = ErrorKind::Setup(SetupError::Io {
                path: main.file.path.clone(),
                message: e.clone(),
            });
            return Err(Diagnostic::error(k, None));
        }
        match main.first_nonblank {
            None => {
                return Err(self.error(ErrorKind::OWord(OWordError::EmptyProgram), &main, 0, 0));
            }
            Some(first) => {
                if main.percent_start {
                    self.emit_raw(b"%")?;
                    // Continue after the opening % line.
                    self.flow.cur.pos = main.first_nonblank_next;
                    self.flow.cur.line = first + 1;
                    self.flow.cur.next_o = main.oline_at_or_after(first + 1);
                }
            }
        }
        while !self.out.ended {
            self.step()?;
            if self.out.handed >= self.out.apart_after {
                return self.run_apart();
            }
        }
        Ok(())
    }

    /// Runs the rest of the program with the consumer (and the output) on
    /// a second thread (see [`write::apart`]); stays on this one if no thread
    /// can be had.
    fn run_apart(&mut self) -> Result<(), Error> {
        use std::sync::atomic::AtomicBool;
        use std::sync::mpsc;
        self.out.apart_after = usize::MAX;
        let rest = |i: &mut Interp<'s>| {
            while !i.out.ended {
                i.step()?;
            }
            Ok(())
        };
        let Some(placeholder) = crate::emit::Output::discarding() else {
            return rest(self);
        };
        let Some(consumer) = self.out.consumer.take() else {
            return rest(self);
        };
        let output = std::mem::replace(&mut self.out.output, placeholder);
        let computes_comp = consumer.computes_comp();
        // The consumer and the output reach the thread through a shared
        // slot, so that they stay here if no thread starts.
        let slot = std::sync::Mutex::new(Some((consumer, output)));
        let failed = Arc::new(AtomicBool::new(false));
        std::thread::scope(|sc| {
            let (to, from) = mpsc::sync_channel(write::apart::QUEUE);
            let (give_back, back) = mpsc::channel();
            let flag = failed.clone();
            let slot = &slot;
            let spawned = std::thread::Builder::new().spawn_scoped(sc, move || {
                let (c, o) = slot.lock().ok()?.take()?;
                Some(write::apart::serve(c, o, from, give_back, &flag))
            });
            let Ok(thread) = spawned else {
                if let Some((c, o)) = slot.lock().ok().and_then(|mut s| s.take()) {
                    self.out.consumer = Some(c);
                    self.out.output = o;
                }
                return rest(self);
            };
            self.out.apart = Some(write::apart::Apart::new(to, back, failed, computes_comp));
            let r = rest(self);
            if let Some(a) = self.out.apart.take() {
                a.close();
            }
            let served = match thread.join() {
                Ok(s) => s,
                Err(p) => std::panic::resume_unwind(p),
            };
            let Some((c, o, failure)) = served else {
                // The thread never had the consumer and the output (it
                // cannot happen: nothing else takes them from the slot).
                // Nothing is written rather than a partial program.
                return Err(write::apart::lost());
            };
            self.out.consumer = Some(c);
            self.out.output = o;
            match failure {
                Some(f) => {
                    self.diags.warnings.truncate(f.warnings);
                    Err(f.error)
                }
                None => r,
            }
        })
    }

    /// Warns of code after the end that never runs; returns the subs
    /// defined in the main file and never called, whose warnings come next.
    fn finish_warnings(&mut self) -> Unused {
        let main = self.main.clone();
        self.warn_unreachable(&main);
        if !self.s.warnings {
            return Unused::default();
        }
        // One warning per definition, given here only (no record of sites
        // warned needed).
        let mut subs = Vec::new();
        for d in main.defs() {
            let o = &main.olines[d.oidx as usize];
            if let Some(k) = main.key(d.oidx)
                && !self.flow.called.contains(k)
            {
                subs.push((k.clone(), o.start, o.start + o.line_len()));
            }
        }
        Unused {
            file: Some(main.file.clone()),
            stack: self.stack(),
            subs,
        }
    }

    /// Code after the program end that is not a subroutine definition
    /// never runs.
    fn warn_unreachable(&mut self, main: &Rc<FileIndex>) {
        if !self.s.warnings || !Rc::ptr_eq(&self.flow.cur.file, main) || self.flow.frames.len() > 1
        {
            return;
        }
        let Some(data) = main.file.memory() else {
            return;
        };
        // Definition line ranges by start, each with the furthest end of
        // it and those before: a line is inside one if the last range
        // starting at or before it reaches it (a search, not a scan: a
        // million definitions after the end stay linear).
        let mut inside: Vec<(u32, u32)> = Vec::new();
        for d in main.defs() {
            let a = main.olines[d.oidx as usize].line_idx;
            let b = d
                .end()
                .map(|e| main.olines[e as usize].line_idx)
                .unwrap_or(u32::MAX);
            inside.push((a, b));
        }
        inside.sort_unstable();
        let mut reach = 0;
        for r in &mut inside {
            reach = reach.max(r.1);
            r.1 = reach;
        }
        let mut pos = self.flow.cur.pos as usize;
        let mut idx = self.flow.cur.line;
        let mut parser = LineParser::new(self.s.named_params_2007);
        let mut in_fanuc = false;
        while pos < data.len() {
            let (end, next, term) = next_line(data, pos);
            let raw = &data[pos..end];
            // Fanuc-style O<n> ... M99 subprograms after the end are called
            // with M98, not unreachable.
            let o = main.oline_at_or_after(idx);
            if main
                .olines
                .get(o)
                .is_some_and(|l| l.line_idx == idx && l.kind() == Some(OKind::Bare))
            {
                in_fanuc = true;
            }
            let k = inside.partition_point(|&(a, _)| a <= idx);
            let in_def = in_fanuc || (k > 0 && inside[k - 1].1 >= idx);
            if in_fanuc && main.m99_lines.binary_search(&idx).is_ok() {
                in_fanuc = false;
            }
            if !in_def {
                let dead = match parser.parse(raw, term) {
                    Ok(l) => match &l.kind {
                        LineKind::Blank | LineKind::Percent => false,
                        LineKind::Items(items) => items
                            .iter()
                            .any(|i| !matches!(i, crate::parse::ast::Item::Comment(_))),
                        _ => true,
                    },
                    Err(_) => true,
                };
                if dead {
                    let (a, b) = (pos as u32, end as u32);
                    self.warn(
                        WarningKind::UnreachableAfterEnd { line: idx + 1 },
                        main,
                        a,
                        b,
                    );
                    return;
                }
            }
            pos = next;
            idx += 1;
        }
    }

    fn count_step(&mut self) -> Result<(), Error> {
        self.flow.steps += 1;
        if self.flow.steps > self.s.max_steps {
            let (label, line, file) = match &self.flow.last_loop {
                Some((k, n, f)) => (Some(label_of_key(k)), Some(*n), f.clone()),
                None => (None, None, self.flow.cur.file.clone()),
            };
            let kind = ErrorKind::Limit(LimitError::StepLimit {
                limit: self.s.max_steps,
                label,
                line: line.map(|n| n + 1),
            });
            let site = match (&self.flow.last_loop, line) {
                (Some(_), Some(n)) => file
                    .olines
                    .iter()
                    .find(|o| o.line_idx == n)
                    .map(|o| (o.start, o.start + o.line_len())),
                _ => None,
            };
            let (a, b) = site.unwrap_or((self.reader.line_start, self.reader.line_start));
            return Err(self.error(kind, &file, a, b));
        }
        Ok(())
    }

    /// Reads and runs one line.
    /// When line `line_idx` of `file` (the cursor's) is an O-line: counts
    /// the step, moves the cursor past it and returns its index.
    #[inline(always)]
    fn take_oline(&mut self, file: &FileIndex, line_idx: u32) -> Result<Option<u32>, Error> {
        let Some(o) = file.olines.get(self.flow.cur.next_o) else {
            return Ok(None);
        };
        if o.line_idx != line_idx {
            return Ok(None);
        }
        // Loops and calls all pass through O-lines: counting them bounds
        // any runaway, while straight code runs uncounted.
        self.count_step()?;
        let oidx = self.flow.cur.next_o as u32;
        self.flow.cur.next_o += 1;
        self.flow.cur.pos = o.next;
        self.flow.cur.line += 1;
        Ok(Some(oidx))
    }

    fn step(&mut self) -> Result<(), Error> {
        if self.mach.lathe.is_some() {
            return self.step_contour();
        }
        let file = self.flow.cur.file.clone();
        let start = self.flow.cur.pos;
        if start as u64 >= file.file.len() {
            return self.end_of_file(&file);
        }
        let line_idx = self.flow.cur.line;
        self.reader.at(start, line_idx);
        if let Some(oidx) = self.take_oline(&file, line_idx)? {
            return self.exec_oline(&file, oidx);
        }
        if let Some(data) = file.file.memory()
            && let Some((line, end, next)) = self.flow.cache.get(&(file_key(&file), line_idx))
        {
            // A line of a loop or sub body run before.
            let (line, end, next) = (line.clone(), *end, *next);
            self.flow.cur.pos = next;
            self.flow.cur.line += 1;
            return self.exec_line(&file, start, &data[start as usize..end as usize], &line);
        }
        let mut window = std::mem::take(&mut self.reader.window);
        if self.s.plain_runs {
            let stop = file
                .olines
                .get(self.flow.cur.next_o)
                .map_or(u32::MAX, |o| o.line_idx);
            // The lines of a straight run do not count toward moving the
            // consumer to a thread of its own: the run reads (and decodes
            // for the consumer) on the second core already, and on the
            // consumer's thread each line would be decoded again.
            let handed = self.out.handed;
            let run = match file.file.memory() {
                Some(data) => {
                    self.straight_run(&file, &data[start as usize..], start, line_idx, stop)
                }
                None => match window.from(&file.file, start) {
                    Ok(buf) => self.straight_run(&file, buf, start, line_idx, stop),
                    Err(e) => Err(read_error(&file, e)),
                },
            };
            self.out.handed = handed;
            match run {
                Ok(0) => {}
                other => {
                    self.reader.window = window;
                    return other.map(|_| ());
                }
            }
        }
        let r = self.step_line(&file, start, line_idx, &mut window);
        self.reader.window = window;
        r
    }

    fn step_line(
        &mut self,
        file: &Rc<FileIndex>,
        start: u32,
        line_idx: u32,
        window: &mut Window,
    ) -> Result<(), Error> {
        // The line and the bytes after it (the rest of the file, where it
        // is in memory), which let its numbers be read eight bytes at a time.
        let (raw, tail, next, terminated): (&[u8], &[u8], u32, bool) = match file.file.memory() {
            Some(data) => {
                let (end, next, t) = next_line(data, start as usize);
                let tail = &data[start as usize..];
                (&tail[..end - start as usize], tail, next as u32, t)
            }
            None => {
                let l = window
                    .line(&file.file, start)
                    .map_err(|e| read_error(file, e))?;
                let next = l.next;
                let t = l.terminated;
                let raw = window.bytes(&l);
                (raw, raw, next, t)
            }
        };
        self.flow.cur.pos = next;
        self.flow.cur.line += 1;
        let mut room = self.reader.plain.take().unwrap_or_default();
        let plain = if plain::read_plain_in(tail, raw.len(), &mut room.words) {
            self.exec_plain(file, start, raw, &room.words)
        } else {
            None
        };
        self.reader.plain = Some(room);
        if let Some(r) = plain {
            return r;
        }
        let line = if file.keeps(line_idx) {
            let key = (file_key(file), line_idx);
            match self.flow.cache.get(&key) {
                Some(l) => l.0.clone(),
                None => {
                    let l = Rc::new(self.parse_line(file, start, raw, terminated)?);
                    let end = start + raw.len() as u32;
                    if self.flow.cache.len() >= flow::LINES_KEPT {
                        // Bounded: a program of a million bodies run once
                        // each does not keep them all.
                        self.flow.cache.clear();
                    }
                    self.flow.cache.insert(key, (l.clone(), end, next));
                    l
                }
            }
        } else {
            Rc::new(self.parse_line(file, start, raw, terminated)?)
        };
        self.exec_line(file, start, raw, &line)
    }

    fn parse_line(
        &mut self,
        file: &Rc<FileIndex>,
        start: u32,
        raw: &[u8],
        terminated: bool,
    ) -> Result<Line, Error> {
        self.reader
            .parser
            .parse(raw, terminated)
            .map_err(|e| self.error_in_line(e.kind, file, start, e.span))
    }

    fn exec_line(
        &mut self,
        file: &Rc<FileIndex>,
        start: u32,
        raw: &[u8],
        line: &Line,
    ) -> Result<(), Error> {
        match &line.kind {
            LineKind::Blank => Ok(()),
            LineKind::Percent => {
                if self.main.percent_start {
                    self.emit_raw(b"%")?;
                    self.out.ended = true;
                    Ok(())
                } else {
                    Err(self.error(
                        ErrorKind::Syntax(SyntaxError::StrayPercent),
                        file,
                        start,
                        start + 1,
                    ))
                }
            }
            LineKind::Items(items) => self.exec_items(file, start, raw, items),
            // O-lines are executed from the file index; one that reaches
            // here failed to index, so re-raise its parse error.
            LineKind::O(_) | LineKind::M98(_) => Ok(()),
        }
    }

    fn end_of_file(&mut self, file: &Rc<FileIndex>) -> Result<(), Error> {
        let end = file.file.len() as u32;
        if self.flow.level() > 0 && !Rc::ptr_eq(file, &self.main) {
            let name = self
                .flow
                .frames
                .last()
                .map(|f| f.name.to_string())
                .unwrap_or_default();
            return Err(self.error(
                ErrorKind::OWord(OWordError::UnterminatedSub { name }),
                file,
                end,
                end,
            ));
        }
        Err(self.error(
            ErrorKind::OWord(OWordError::MissingProgramEnd {
                percent: self.main.percent_start,
            }),
            file,
            end,
            end,
        ))
    }

    /// Writes one finished output line.
    fn emit_raw(&mut self, bytes: &[u8]) -> Result<(), Error> {
        self.count_line()?;
        if self.out.consuming() {
            let file = self.flow.cur.file.file.clone();
            return self.consume(&file, self.reader.line_start, bytes, false);
        }
        self.out.output.line(bytes).map_err(|e| {
            let file = &self.flow.cur.file.file;
            self.output_error_at(e, file, self.reader.line_start)
        })
    }

    /// Writes a source line as it is (`bytes`: its text without trailing
    /// blanks, starting at `start` in `file`).
    fn emit_source(&mut self, file: &Rc<FileIndex>, start: u32, bytes: &[u8]) -> Result<(), Error> {
        self.count_line()?;
        if self.out.consuming() {
            let file = file.file.clone();
            return self.consume(&file, start, bytes, true);
        }
        self.out
            .output
            .line(bytes)
            .map_err(|e| self.output_error_at(e, &file.file, start))
    }

    /// Counts an output line about to be written, against the limit.
    #[inline]
    fn count_line(&mut self) -> Result<(), Error> {
        if self.out.count_line() {
            return self.line_checkpoint();
        }
        Ok(())
    }

    /// The output limit, or a progress update, is due.
    #[cold]
    fn line_checkpoint(&mut self) -> Result<(), Error> {
        let name = self.flow.cur.file.file.display_name();
        if self.out.checkpoint(self.reader.line_idx + 1, &name) {
            Ok(())
        } else {
            Err(self.output_limit())
        }
    }

    /// The error of an output past the limit.
    #[cold]
    fn output_limit(&self) -> Error {
        let (label, line, file) = match &self.flow.last_loop {
            Some((k, n, f)) => (Some(label_of_key(k)), Some(*n + 1), f.clone()),
            None => (None, None, self.flow.cur.file.clone()),
        };
        let at = self.reader.line_start;
        self.error(
            ErrorKind::Limit(LimitError::OutputLimit {
                limit: self.s.max_output_lines,
                label,
                line,
            }),
            &file,
            at,
            at,
        )
    }
}
