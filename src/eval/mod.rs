//! The evaluator: runs a program the way LinuxCNC's interpreter would and
//! writes the lines it executes, with every parameter and expression replaced
//! by its value.

mod expr;
mod flow;
mod out;
mod read;
mod settings;
pub mod state;

pub use expr::params;
pub use state::tools;

use flow::control;
use out::progress;
use read::{block, fast};
use state::{ccomp, cycle, lathe, nurbs, restore};

use std::collections::HashSet;

use crate::fx_hasher::{FxMap, FxSet};
use std::rc::Rc;

use crate::diag::{Diagnostic, Error, ErrorKind, Site, WarningKind};
use crate::emit::{Output, Sink};
use crate::parse::ast::{Line, LineKind, OKind, Span};
use crate::parse::{LineParser, Name};
use crate::program::{FileIndex, Loader, Window, next_line};

pub use out::hook::{LineConsumer, Origin};
pub use settings::{Define, Settings};

use expr::params::Params;
use state::{Modal, Position};

/// Deepest nesting of active calls (the tenth nested call fails).
pub const MAX_CALL_LEVEL: usize = 9;

/// Where reading continues.
#[derive(Clone)]
pub struct Cursor {
    pub file: Rc<FileIndex>,
    /// Byte offset of the next line.
    pub pos: u32,
    /// 0-based index of the next line.
    pub line: u32,
    /// Index of the first O-line at or after `line`.
    pub next_o: usize,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrameKind {
    Main,
    Call,
    M98,
}

/// Record of a control label reached in this activation.
#[derive(Debug, Clone, Copy)]
pub struct LabelRec {
    pub kind: OKind,
    pub oidx: u32,
    pub line: u32,
    /// Remaining passes of a repeat loop (-1: not running).
    pub repeat: i64,
}

pub struct Frame {
    pub kind: FrameKind,
    pub name: Name,
    pub ret: Option<Cursor>,
    /// The O-line (of the file `ret` is in) that made the call; its site is
    /// worked out only for a message.
    pub call_oidx: Option<u32>,
    pub saved: Option<Box<[f64; 30]>>,
    pub locals: FxMap<Name, f64>,
    pub labels: FxMap<Name, LabelRec>,
    /// Pending passes of an `M98 ... L` on the given line of this frame.
    pub m98_loop: Option<(u32, i64)>,
    /// Modal state saved by M70/M73; `auto` restores it on return (M73).
    pub saved_modal: Option<Box<restore::Saved>>,
    pub auto_restore: bool,
}

impl Frame {
    /// Makes a pooled frame like a new one, keeping its tables' room.
    fn reset(&mut self, kind: FrameKind, name: Name) {
        let Frame {
            kind: k,
            name: n,
            ret,
            call_oidx,
            saved,
            locals,
            labels,
            m98_loop,
            saved_modal,
            auto_restore,
        } = self;
        *k = kind;
        *n = name;
        *ret = None;
        *call_oidx = None;
        *saved = None;
        locals.clear();
        labels.clear();
        *m98_loop = None;
        *saved_modal = None;
        *auto_restore = false;
    }

    fn new(kind: FrameKind, name: Name) -> Frame {
        Frame {
            kind,
            name,
            ret: None,
            call_oidx: None,
            saved: None,
            locals: FxMap::default(),
            labels: FxMap::default(),
            m98_loop: None,
            saved_modal: None,
            auto_restore: false,
        }
    }
}

/// A registered subroutine definition.
#[derive(Clone)]
pub struct SubRec {
    pub file: Rc<FileIndex>,
    pub oidx: u32,
}

pub struct Interp<'s> {
    s: &'s Settings,
    pub loader: Loader,
    main: Rc<FileIndex>,
    params: Params,
    globals: FxMap<Name, f64>,
    /// Boxed: a call moves a pointer, not the frame.
    #[allow(clippy::vec_box)]
    frames: Vec<Box<Frame>>,
    /// Frames of returned calls, reused by the next calls.
    #[allow(clippy::vec_box)]
    frame_pool: Vec<Box<Frame>>,
    /// Argument save areas of returned calls (boxed: they move between
    /// frames and the pool without copying).
    #[allow(clippy::vec_box)]
    saved_pool: Vec<Box<[f64; 30]>>,
    value: f64,
    value_returned: bool,
    /// Reading undefined named parameters gives 0 (sub definition skip).
    defining: bool,
    cur: Cursor,
    output: Output,
    out_lines: u64,
    /// Output lines allowed: `--max-output-lines` plus the main file's own
    /// line count, so that the guard counts generated lines, not lines
    /// copied from the input.
    line_budget: u64,
    /// Output line count at which `count_line` looks further: the output
    /// limit, or earlier, the next progress update.
    line_check: u64,
    progress: Option<progress::Progress>,
    steps: u64,
    pub warnings: Vec<Diagnostic>,
    subs: FxMap<Name, SubRec>,
    called: FxSet<Name>,
    /// The sub of the last call, already registered and marked called.
    last_called: Option<Name>,
    modal: Modal,
    pos: Position,
    current_tool: Option<f64>,
    /// RETAIN_G43 changed the tool length offset on this line: the output
    /// line to add after it (G43 or G49).
    retain_line: Option<bool>,
    selected_tool: Option<f64>,
    /// Pockets of the current and the selected tool, known as the standalone
    /// reference numbers them (by tool number) under `--zero-start`.
    pockets: Option<(f64, f64)>,
    executed_if: bool,
    /// The reference's never-cleared break/continue flags (for warnings).
    ref_stale_break: Option<u32>,
    ref_stale_continue: Option<u32>,
    /// Control key, line and file of the last loop passed (for limit
    /// messages).
    last_loop: Option<(Name, u32, Rc<FileIndex>)>,
    parser: LineParser,
    /// Parsed lines of loop and sub bodies, with their end and the start of
    /// the next line.
    cache: FxMap<(usize, u32), (Rc<Line>, u32, u32)>,
    out: Vec<u8>,
    ended: bool,
    current_line_start: u32,
    current_line_idx: u32,
    /// Warnings already given, to report each site once.
    warned: HashSet<(&'static str, usize, u32)>,
    window: Window,
    fast_words: Vec<fast::FastWord>,
    words_buf: Vec<(u8, f64)>,
    tools: FxMap<i64, tools::ToolData>,
    tools_known: bool,
    unknown_tools: HashSet<i64>,
    /// Applied tool length offset, machine units.
    tlo: Option<[f64; 9]>,
    /// An XY rotation was set (not modelled).
    rotated: bool,
    /// The repeat line (O-line index) an endrepeat just jumped back to.
    repeat_again: Option<u32>,
    scratch: Option<Box<block::Scratch>>,
    /// Control points of the NURBS block being read.
    nurbs: nurbs::Nurbs,
    /// R plane and depth of the last canned cycle.
    cycle: cycle::Cycle,
    /// The tool length offset changed since the last move.
    tlo_moved: bool,
    /// Line of the last G38 probe that left the results unknown.
    probed_at: Option<u32>,
    /// Why and since which line the standalone reference's position
    /// differs from the machine's (see W0110).
    standalone_drift: Option<(&'static str, u32)>,
    /// The line of an M61 not followed by a tool change, and the tool the
    /// standalone reference still has as current (see W0110).
    m61: Option<(u32, Option<f64>)>,
    /// Reads every output line instead of the output (see [`hook`]).
    consumer: Option<Box<dyn LineConsumer + 's>>,
    /// Cutter compensation, once a program turns it on.
    comp: Option<Box<ccomp::CompRun>>,
    /// G40 ended an offset path: the next move must be straight (the fast
    /// paths leave such lines to the general one).
    comp_pending: bool,
    /// A lathe cycle whose contour subroutine is running.
    lathe: Option<Box<lathe::LatheRun>>,
}

/// The call stack of `frames` as sites, innermost caller first.
#[allow(clippy::vec_box)]
fn stack_of(frames: &[Box<Frame>]) -> Vec<Site> {
    frames
        .iter()
        .rev()
        .filter_map(|f| {
            let (ret, oidx) = (f.ret.as_ref()?, f.call_oidx?);
            let (a, b) = control::osite_of(&ret.file, oidx);
            Some(Site::new(&ret.file.file, a, b))
        })
        .collect()
}

/// An error writing the output.
fn output_error(e: std::io::Error) -> Error {
    if let Some(t) = e
        .get_ref()
        .and_then(|i| i.downcast_ref::<crate::emit::OutputTooLarge>())
    {
        return Diagnostic::error(ErrorKind::OutputBytesLimit { limit: t.limit }, None);
    }
    Diagnostic::error(
        ErrorKind::Io {
            path: "<output>".into(),
            message: e.to_string(),
        },
        None,
    )
}

/// An error reading a streamed program file.
fn read_error(file: &FileIndex, e: std::io::Error) -> Error {
    Diagnostic::error(
        ErrorKind::Io {
            path: file.file.path.clone(),
            message: e.to_string(),
        },
        None,
    )
}

/// The label part of a control key (`scope#label`).
fn label_of_key(key: &str) -> String {
    key.rsplit('#').next().unwrap_or("").to_string()
}

fn file_key(f: &Rc<FileIndex>) -> usize {
    Rc::as_ptr(f) as usize
}

impl<'s> Interp<'s> {
    /// Evaluates an expression that reads no parameter (the library check
    /// of `check`): its value, or the error and its span in the line.
    pub fn eval_constant(
        &mut self,
        e: &crate::parse::ast::Expr,
    ) -> Result<f64, (ErrorKind, crate::parse::ast::Span)> {
        self.eval(e).map_err(|f| *f)
    }

    pub fn new(s: &'s Settings, loader: Loader, main: Rc<FileIndex>, sink: Sink) -> Interp<'s> {
        let mut params = Params::new(s.zero_start);
        let mut globals = FxMap::default();
        let mut main_frame = Frame::new(FrameKind::Main, Name::new(""));
        for d in &s.defines {
            match d {
                Define::Numbered(i, v) => params.assign(*i, *v),
                Define::Named(n, v) => {
                    if n.starts_with('_') {
                        globals.insert(Name::new(n), *v);
                    } else {
                        main_frame.locals.insert(Name::new(n), *v);
                    }
                }
            }
        }
        // Level-0 locals share the global table.
        for (k, v) in main_frame.locals.drain() {
            globals.insert(k, v);
        }
        let mut pos = if s.zero_start {
            Position::zero()
        } else {
            Position::unknown()
        };
        for &(axis, v) in &s.start_position {
            pos.axes[axis] = Ok(v);
        }
        let cur = Cursor {
            file: main.clone(),
            pos: 0,
            line: 0,
            next_o: 0,
        };
        let line_budget = s
            .max_output_lines
            .saturating_add(u64::from(main.line_count));
        Interp {
            s,
            loader,
            main,
            params,
            globals,
            frames: vec![Box::new(main_frame)],
            frame_pool: Vec::new(),
            saved_pool: Vec::new(),
            value: 0.0,
            value_returned: false,
            defining: false,
            cur,
            output: Output::new(sink, s.precision, s.format_thread_after),
            out_lines: 0,
            line_budget,
            line_check: if s.progress.is_some() {
                line_budget.min(progress::EVERY)
            } else {
                line_budget
            },
            progress: s.progress.map(progress::Progress::new),
            steps: 0,
            warnings: Vec::new(),
            subs: FxMap::default(),
            called: FxSet::default(),
            last_called: None,
            modal: Modal::default(),
            pos,
            retain_line: None,
            current_tool: if s.zero_start || !s.tool_table.is_empty() {
                Some(0.0)
            } else {
                None
            },
            selected_tool: if s.zero_start { Some(0.0) } else { None },
            pockets: s.zero_start.then_some((1.0, -1.0)),
            executed_if: true,
            ref_stale_break: None,
            ref_stale_continue: None,
            last_loop: None,
            parser: LineParser::default(),
            cache: FxMap::default(),
            out: Vec::with_capacity(256),
            ended: false,
            current_line_start: 0,
            current_line_idx: 0,
            warned: HashSet::new(),
            window: Window::default(),
            fast_words: Vec::with_capacity(16),
            words_buf: Vec::with_capacity(16),
            tools: s.tool_table.iter().copied().collect(),
            tools_known: s.zero_start,
            unknown_tools: HashSet::new(),
            tlo: Some([0.0; 9]),
            rotated: false,
            repeat_again: None,
            scratch: Some(Box::default()),
            nurbs: nurbs::Nurbs::default(),
            cycle: cycle::Cycle::default(),
            tlo_moved: false,
            probed_at: None,
            standalone_drift: None,
            comp: None,
            comp_pending: false,
            m61: None,
            consumer: None,
            lathe: None,
        }
    }

    /// Hands every output line to `consumer` instead of the output.
    pub fn with_consumer(mut self, consumer: Box<dyn LineConsumer + 's>) -> Interp<'s> {
        self.consumer = Some(consumer);
        self
    }

    pub fn level(&self) -> usize {
        self.frames.len() - 1
    }

    /// The call stack as sites, innermost caller first.
    fn stack(&self) -> Vec<Site> {
        stack_of(&self.frames)
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
        if !self.warned.insert((kind.code(), file_key(file), start)) {
            return;
        }
        let mut d = Diagnostic::warning(kind, Some(Site::new(&file.file, start, end)));
        d.stack = self.stack();
        self.warnings.push(d);
    }

    /// Runs the program to its end and releases the output.
    pub fn run(self) -> Result<Vec<Diagnostic>, Error> {
        match self.run_all() {
            (w, None) => Ok(w),
            (_, Some(e)) => Err(e),
        }
    }

    /// Runs the program; returns every diagnostic (with a consumer that
    /// keeps its errors, those too) and the error that stopped the run, if
    /// any. The output is released only without an error.
    pub fn run_all(mut self) -> (Vec<Diagnostic>, Option<Error>) {
        let r = self.run_steps();
        if let Some(p) = &self.progress {
            p.clear();
        }
        if r.is_ok() {
            self.finish_warnings();
        }
        let Interp {
            mut output,
            mut warnings,
            loader,
            consumer,
            ..
        } = self;
        warnings.extend(loader.warnings);
        let mut err = r.err();
        if let Some(mut c) = consumer {
            match c.finish(&mut output) {
                Ok(d) => warnings.extend(d),
                Err(e) => {
                    err.get_or_insert(e);
                }
            }
        }
        let failed = err.is_some()
            || warnings
                .iter()
                .any(|d| d.level() == crate::diag::Level::Error);
        if !failed && let Err(e) = output.finish() {
            err = Some(output_error(e));
        }
        (warnings, err)
    }

    fn run_steps(&mut self) -> Result<(), Error> {
        let main = self.main.clone();
        if let Some(e) = &main.read_error {
            let k = ErrorKind::Io {
                path: main.file.path.clone(),
                message: e.clone(),
            };
            return Err(Diagnostic::error(k, None));
        }
        match main.first_nonblank {
            None => return Err(self.error(ErrorKind::EmptyProgram, &main, 0, 0)),
            Some(first) => {
                if main.percent_start {
                    self.emit_raw(b"%")?;
                    // Continue after the opening % line.
                    self.cur.pos = main.first_nonblank_next;
                    self.cur.line = first + 1;
                    self.cur.next_o = main.oline_at_or_after(first + 1);
                }
            }
        }
        while !self.ended {
            self.step()?;
        }
        Ok(())
    }

    fn finish_warnings(&mut self) {
        let main = self.main.clone();
        self.warn_unreachable(&main);
        // Subs defined in the main file and never called.
        for (i, o) in main.olines.iter().enumerate() {
            if o.kind() == Some(OKind::Sub)
                && let Some(k) = &o.key
                && !self.called.contains(k)
                && main.defs.contains_key(&(i as u32))
            {
                let end = o.start + o.line_len();
                self.warn(
                    WarningKind::UnusedSub {
                        name: k.to_string(),
                    },
                    &main,
                    o.start,
                    end,
                );
            }
        }
    }

    /// Code after the program end that is not a subroutine definition
    /// never runs.
    fn warn_unreachable(&mut self, main: &Rc<FileIndex>) {
        if !self.s.warnings || !Rc::ptr_eq(&self.cur.file, main) || self.frames.len() > 1 {
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
        for (&s, d) in &main.defs {
            let a = main.olines[s as usize].line_idx;
            let b = d
                .end
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
        let mut pos = self.cur.pos as usize;
        let mut idx = self.cur.line;
        let mut parser = LineParser::default();
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
        self.steps += 1;
        if self.steps > self.s.max_steps {
            let (label, line, file) = match &self.last_loop {
                Some((k, n, f)) => (Some(label_of_key(k)), Some(*n), f.clone()),
                None => (None, None, self.cur.file.clone()),
            };
            let kind = ErrorKind::StepLimit {
                limit: self.s.max_steps,
                label,
                line: line.map(|n| n + 1),
            };
            let site = match (&self.last_loop, line) {
                (Some(_), Some(n)) => file
                    .olines
                    .iter()
                    .find(|o| o.line_idx == n)
                    .map(|o| (o.start, o.start + o.line_len())),
                _ => None,
            };
            let (a, b) = site.unwrap_or((self.current_line_start, self.current_line_start));
            return Err(self.error(kind, &file, a, b));
        }
        Ok(())
    }

    /// Reads and runs one line.
    /// When line `line_idx` of `file` (the cursor's) is an O-line: counts
    /// the step, moves the cursor past it and returns its index.
    #[inline(always)]
    fn take_oline(&mut self, file: &FileIndex, line_idx: u32) -> Result<Option<u32>, Error> {
        let Some(o) = file.olines.get(self.cur.next_o) else {
            return Ok(None);
        };
        if o.line_idx != line_idx {
            return Ok(None);
        }
        // Loops and calls all pass through O-lines: counting them bounds
        // any runaway, while straight code runs uncounted.
        self.count_step()?;
        let oidx = self.cur.next_o as u32;
        self.cur.next_o += 1;
        self.cur.pos = o.next;
        self.cur.line += 1;
        Ok(Some(oidx))
    }

    fn step(&mut self) -> Result<(), Error> {
        if self.lathe.is_some() {
            return self.step_contour();
        }
        let file = self.cur.file.clone();
        let start = self.cur.pos;
        if start as u64 >= file.file.len() {
            return self.end_of_file(&file);
        }
        let line_idx = self.cur.line;
        self.current_line_start = start;
        self.current_line_idx = line_idx;
        if let Some(oidx) = self.take_oline(&file, line_idx)? {
            return self.exec_oline(&file, oidx);
        }
        if let Some(data) = file.file.memory()
            && let Some((line, end, next)) = self.cache.get(&(file_key(&file), line_idx))
        {
            // A line of a loop or sub body run before.
            let (line, end, next) = (line.clone(), *end, *next);
            self.cur.pos = next;
            self.cur.line += 1;
            return self.exec_line(&file, start, &data[start as usize..end as usize], &line);
        }
        let mut window = std::mem::take(&mut self.window);
        if self.s.plain_runs {
            let stop = file
                .olines
                .get(self.cur.next_o)
                .map_or(u32::MAX, |o| o.line_idx);
            let run = match file.file.memory() {
                Some(data) => {
                    self.straight_run(&file, &data[start as usize..], start, line_idx, stop)
                }
                None => match window.from(&file.file, start) {
                    Ok(buf) => self.straight_run(&file, buf, start, line_idx, stop),
                    Err(e) => Err(read_error(&file, e)),
                },
            };
            match run {
                Ok(0) => {}
                other => {
                    self.window = window;
                    return other.map(|_| ());
                }
            }
        }
        let r = self.step_line(&file, start, line_idx, &mut window);
        self.window = window;
        r
    }

    fn step_line(
        &mut self,
        file: &Rc<FileIndex>,
        start: u32,
        line_idx: u32,
        window: &mut Window,
    ) -> Result<(), Error> {
        let (raw, next, terminated): (&[u8], u32, bool) = match file.file.memory() {
            Some(data) => {
                let (end, next, t) = next_line(data, start as usize);
                (&data[start as usize..end], next as u32, t)
            }
            None => {
                let l = window
                    .line(&file.file, start)
                    .map_err(|e| read_error(file, e))?;
                let next = l.next;
                let t = l.terminated;
                (window.bytes(&l), next, t)
            }
        };
        self.cur.pos = next;
        self.cur.line += 1;
        let mut fw = std::mem::take(&mut self.fast_words);
        if fast::scan(raw, &mut fw) && !fw.is_empty() {
            let r = self.exec_plain(file, start, raw, &fw);
            self.fast_words = fw;
            if let Some(r) = r {
                return r;
            }
        } else {
            self.fast_words = fw;
        }
        let line = if file.keeps(line_idx) {
            let key = (file_key(file), line_idx);
            match self.cache.get(&key) {
                Some(l) => l.0.clone(),
                None => {
                    let l = Rc::new(self.parse_line(file, start, raw, terminated)?);
                    let end = start + raw.len() as u32;
                    self.cache.insert(key, (l.clone(), end, next));
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
        self.parser
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
                    self.ended = true;
                    Ok(())
                } else {
                    Err(self.error(ErrorKind::StrayPercent, file, start, start + 1))
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
        if self.level() > 0 && !Rc::ptr_eq(file, &self.main) {
            let name = self
                .frames
                .last()
                .map(|f| f.name.to_string())
                .unwrap_or_default();
            return Err(self.error(ErrorKind::UnterminatedSub { name }, file, end, end));
        }
        Err(self.error(
            ErrorKind::MissingProgramEnd {
                percent: self.main.percent_start,
            },
            file,
            end,
            end,
        ))
    }

    /// Writes one finished output line.
    fn emit_raw(&mut self, bytes: &[u8]) -> Result<(), Error> {
        self.count_line()?;
        if self.consumer.is_some() {
            let file = self.cur.file.file.clone();
            return self.consume(&file, self.current_line_start, bytes, false);
        }
        self.output.line(bytes).map_err(output_error)
    }

    /// Writes a source line as it is (`bytes`: its text without trailing
    /// blanks, starting at `start` in `file`).
    fn emit_source(&mut self, file: &Rc<FileIndex>, start: u32, bytes: &[u8]) -> Result<(), Error> {
        self.count_line()?;
        if self.consumer.is_some() {
            let file = file.file.clone();
            return self.consume(&file, start, bytes, true);
        }
        self.output.line(bytes).map_err(output_error)
    }

    /// Counts an output line about to be written, against the limit.
    #[inline]
    fn count_line(&mut self) -> Result<(), Error> {
        self.out_lines += 1;
        if self.out_lines > self.line_check {
            return self.line_checkpoint();
        }
        Ok(())
    }

    /// The output limit, or a progress update, is due.
    #[cold]
    fn line_checkpoint(&mut self) -> Result<(), Error> {
        if self.out_lines > self.line_budget {
            return Err(self.output_limit());
        }
        if let Some(p) = &mut self.progress {
            let name = self.cur.file.file.display_name();
            p.tick(self.out_lines, self.current_line_idx + 1, &name);
            self.line_check = self.line_budget.min(self.out_lines + progress::EVERY);
        }
        Ok(())
    }

    /// The error of an output past the limit.
    #[cold]
    fn output_limit(&self) -> Error {
        let (label, line, file) = match &self.last_loop {
            Some((k, n, f)) => (Some(label_of_key(k)), Some(*n + 1), f.clone()),
            None => (None, None, self.cur.file.clone()),
        };
        let at = self.current_line_start;
        self.error(
            ErrorKind::OutputLimit {
                limit: self.s.max_output_lines,
                label,
                line,
            },
            &file,
            at,
            at,
        )
    }
}

impl crate::program::OInfo {
    /// Length of the line text without its terminator.
    pub fn line_len(&self) -> u32 {
        (self.next - self.start).saturating_sub(1)
    }
}
