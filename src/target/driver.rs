//! The lowering driver: reads each flat line (as the evaluator's consumer),
//! decodes it, runs it on the machine model, and writes what the target
//! profile accepts: each word kept, dropped (with a warning where the
//! motion may differ), rewritten, lowered into other blocks, or refused
//! with the position of the word and the reason.

use std::collections::HashSet;
use std::sync::Arc;

use crate::block::{
    ArcDistance, Block, CommentKind, CoordSystem, CutterComp, DecodeError, Distance, FeedMode,
    GCode, LatheMode, MCode, MotionMode, NonModal, PathMode, Plane, SpindleDir, SpindleMode,
    ToolLength, Units, Word, WordKind,
};
use crate::diag::{Diagnostic, Error, ErrorKind, Site, WarningKind};
use crate::emit::Output;
use crate::eval::{LineConsumer, Origin, Settings};
use crate::geom::comp::{Arc as CompArc, ArcCenter, Comp, Out, Side, Tolerances};
use crate::machine::Machine;
use crate::program::SourceFile;

use super::TargetOptions;
use super::format::{AxisWords, LineWriter};
use super::lower::{self, PlainLine};
use super::profile::{Profile, ToolChange};

mod arcs;
mod centres;
mod inverse;
mod plain;

/// A problem found on a line: the word it is about and what it is.
struct Problem {
    span: Option<crate::block::Span>,
    kind: ErrorKind,
}

/// What deciding a block's words leaves for writing it.
struct Decided {
    /// One per word of the block.
    fates: Vec<Fate>,
    /// Words written after the line's own (G43.1 Z for G43, M0 for M6).
    extra: Vec<(u8, f64)>,
    /// Lines written after the line.
    extra_lines: Vec<Vec<(u8, f64)>>,
    /// Lines written before the line (G43.1 Z: an axis command of its own).
    pre_lines: Vec<Vec<(u8, f64)>>,
}

/// What happens to one word of a block.
#[derive(Clone, Copy, PartialEq)]
enum Fate {
    Keep,
    Drop,
}

/// The consumer that writes a program for a target.
pub struct Lowering {
    p: &'static Profile,
    opts: TargetOptions,
    /// The machine as LinuxCNC runs the program.
    m: Machine,
    /// Scratch for decoding (boxed: taken out and put back each line).
    block: Option<Box<Block>>,
    w: LineWriter,
    /// Errors kept in check mode.
    errors: Vec<Diagnostic>,
    warnings: Vec<Diagnostic>,
    warned: HashSet<(&'static str, String)>,
    cycles: lower::CycleState,
    /// The feed last written, when feeds are rewritten (G95 lowered).
    feed_rewrite: bool,
    written_feed: Option<f64>,
    /// The target is in G93 (inverse time) as written.
    target_inverse: bool,
    /// The program's opening `%` was read: the next `%` ends the program.
    percent_open: bool,
    /// P and Q of the last G5 (a G5 without I J continues from them).
    last_pq: Option<[f64; 2]>,
    /// Warnings of the line being lowered, waiting for its site.
    pending: Vec<WarningKind>,
    /// Cutter compensation computed into the path (targets without it).
    comp: Option<Box<CompPath>>,
    /// After G40: the tool is where the last compensated move left it,
    /// and the next move goes to the programmed point with every axis.
    after_off: Option<[f64; 3]>,
    /// `--zero-start` without a tool table: tools the program has not set
    /// have the standalone interpreter's built-in data.
    standalone_tools: bool,
    /// The value of the last F word read, and the one before the block.
    last_f: Option<f64>,
    f_before: Option<f64>,
    /// The F value the target has after compensated moves were written.
    comp_f: Option<f64>,
    /// Compensated moves given to the compensation so far (each move's
    /// number in its [`MoveTag`]).
    comp_seq: u64,
    /// The number of each line of the block's released moves (parallel to
    /// them; `u64::MAX` for a line after G40).
    released_seqs: Vec<u64>,
    /// Lines of blocks run while moves were held back: LinuxCNC runs them
    /// after those moves, so each waits until the moves up to its number
    /// are written.
    deferred: Vec<(u64, Vec<u8>)>,
    /// The block being lowered is deferred: its line waits (the number of
    /// the last move before it).
    defer_block: Option<u64>,
    /// Lines every word of which is kept as it is take the short way
    /// (plain.rs); off only to compare both ways in tests.
    plain: bool,
    /// The coordinate system the target is in (1 = G54): the program's,
    /// or the last one the target has when the program's is lowered.
    target_coord: CoordSystem,
    /// G5.2 control points collected until G5.3.
    nurbs: Option<NurbsCurve>,
    codes: plain::Codes,
    /// The I J K written for the block's arc under G90.1 (offsets from
    /// its start, by letter) where the target lacks G90.1 (centres.rs).
    centres: Option<[Option<f64>; 3]>,
}

/// A NURBS being collected (G5.2 blocks), in program units.
struct NurbsCurve {
    points: Vec<lower::spline::NurbsPoint>,
    order: usize,
    /// The current point when the first G5.2 came (G91 points are
    /// relative to it: LinuxCNC moves nothing until G5.3).
    start: [f64; 2],
}

/// What a compensated move carries through the compensation: the feed of
/// its block and its number in the program's order of moves.
type MoveTag = (Option<f64>, u64);

/// Cutter compensation on, on a target without it.
struct CompPath {
    comp: Comp<MoveTag>,
    plane: Plane,
    /// Where the tool is (X Y Z, program units): the end of the last
    /// compensated move written.
    at: [f64; 3],
}

impl Lowering {
    pub fn new(settings: &Settings, opts: TargetOptions) -> Lowering {
        let p = opts.profile;
        let m = Machine::new(settings);
        // A program starting in a system the target lacks: the target is
        // in G54, as after its reset.
        let target_coord = if m.modes.coord.0 <= p.coord_systems {
            m.modes.coord
        } else {
            CoordSystem::G54
        };
        Lowering {
            target_coord,
            nurbs: None,
            p,
            opts,
            m: m.without_events(),
            block: None,
            w: LineWriter::new(p),
            errors: Vec::new(),
            warnings: Vec::new(),
            warned: HashSet::new(),
            cycles: lower::CycleState::default(),
            feed_rewrite: false,
            written_feed: None,
            target_inverse: false,
            percent_open: false,
            last_pq: None,
            pending: Vec::new(),
            comp: None,
            after_off: None,
            standalone_tools: settings.zero_start && settings.tool_table.is_empty(),
            last_f: None,
            f_before: None,
            comp_f: None,
            comp_seq: 0,
            released_seqs: Vec::new(),
            deferred: Vec::new(),
            defer_block: None,
            plain: true,
            codes: plain::Codes::of(p),
            centres: None,
        }
    }

    fn name(&self) -> &'static str {
        self.p.name
    }

    fn refuse(&self, what: impl Into<String>, why: impl Into<String>) -> ErrorKind {
        ErrorKind::TargetRefused {
            target: self.name(),
            what: what.into(),
            why: why.into(),
        }
    }

    /// A warning about the current line; it gets the line's site when the
    /// line is done (worked out only then, and only for a warning not given
    /// before).
    fn warn(&mut self, _site: Option<Site>, kind: WarningKind) {
        let key = (kind.code(), kind.to_string());
        if self.warned.insert(key) {
            self.pending.push(kind);
        }
    }

    fn dropped(&mut self, site: &Option<Site>, what: &str, why: &str) {
        let k = WarningKind::TargetDropped {
            target: self.name(),
            what: what.into(),
            why: why.into(),
        };
        self.warn(site.clone(), k);
    }
}

/// A problem's span that stands for the start of its line, where the
/// evaluator reports an error of the block (an arc rs274 refuses).
const LINE_START: crate::block::Span = crate::block::Span {
    start: u16::MAX,
    end: u16::MAX,
};

/// The site of `span` of a flat line from `origin`: exact on a line written
/// as read; otherwise the same-lettered word of the source line (by its
/// rank), or the whole line; [`LINE_START`] where the line starts.
fn site_of(origin: &Origin<'_>, text: &[u8], span: Option<crate::block::Span>) -> Site {
    let file: &Arc<SourceFile> = origin.file;
    let start = origin.line_start;
    let Some(span) = span else {
        return Site::new(file, start, start + line_len(file, start));
    };
    if span == LINE_START {
        return Site::new(file, start, start);
    }
    if origin.verbatim {
        return Site::new(file, start + span.start as u32, start + span.end as u32);
    }
    let letter = text.get(span.start as usize).map(u8::to_ascii_uppercase);
    if let (Some(letter), Some(data)) = (letter, file.memory()) {
        let rank = words_with(text, letter)
            .iter()
            .position(|&i| i == span.start as usize);
        let from = (start as usize).min(data.len());
        let end = memchr::memchr(b'\n', &data[from..]).map_or(data.len(), |p| from + p);
        if let Some(rank) = rank
            && let Some(&i) = words_with(&data[from..end], letter).get(rank)
        {
            return Site::new(file, (from + i) as u32, (from + i + 1) as u32);
        }
    }
    Site::new(file, start, start + line_len(file, start))
}

fn line_len(file: &SourceFile, start: u32) -> u32 {
    file.memory().map_or(0, |d| {
        let from = (start as usize).min(d.len());
        let end = memchr::memchr(b'\n', &d[from..]).map_or(d.len(), |p| from + p);
        let mut e = end;
        while e > from && d[e - 1].is_ascii_whitespace() {
            e -= 1;
        }
        (e - from) as u32
    })
}

/// Offsets of the letters `letter` outside comments.
fn words_with(text: &[u8], letter: u8) -> Vec<usize> {
    let mut out = Vec::new();
    let mut depth = false;
    for (i, &c) in text.iter().enumerate() {
        match c {
            b'(' => depth = true,
            b')' => depth = false,
            b';' if !depth => break,
            c if !depth && c.to_ascii_uppercase() == letter => out.push(i),
            _ => {}
        }
    }
    out
}

fn decode_problem(e: DecodeError) -> Problem {
    Problem {
        span: Some(e.span),
        kind: ErrorKind::Unsupported {
            what: format!("cannot read this flattened line: {}", e.what),
        },
    }
}

/// G number ×10 of a word.
fn code10(w: &Word) -> u16 {
    (w.value * 10.0).round().clamp(0.0, 60000.0) as u16
}

fn g_name(w: &Word) -> String {
    let c = code10(w);
    if c.is_multiple_of(10) {
        format!("G{}", c / 10)
    } else {
        format!("G{}.{}", c / 10, c % 10)
    }
}

impl Lowering {
    /// Runs the line `text` through the reused block that `decode` fills
    /// (from the text, or from words read ahead), reporting a line it
    /// cannot decode as a problem.
    fn run_decoded(
        &mut self,
        text: &[u8],
        origin: &Origin<'_>,
        out: &mut Output,
        decode: impl FnOnce(&mut Block) -> Result<(), DecodeError>,
    ) -> Result<(), Error> {
        let mut block = self.block.take().unwrap_or_default();
        let problems = match decode(&mut block) {
            Ok(()) => self.run_block(&block, text, origin, out),
            Err(e) => Ok(vec![decode_problem(e)]),
        };
        self.block = Some(block);
        self.report(problems?, text, origin)
    }
}

impl LineConsumer for Lowering {
    fn line(&mut self, text: &[u8], origin: &Origin<'_>, out: &mut Output) -> Result<(), Error> {
        if self.p.passthrough {
            return out.line(text).map_err(io_error);
        }
        self.run_decoded(text, origin, out, |b| b.decode_into(text))
    }

    fn reads_blocks(&self) -> bool {
        !self.p.passthrough
    }

    fn decoded_line(
        &mut self,
        text: &[u8],
        block: &Block,
        origin: &Origin<'_>,
        out: &mut Output,
    ) -> Result<(), Error> {
        if self.p.passthrough {
            return out.line(text).map_err(io_error);
        }
        let problems = self.run_block(block, text, origin, out)?;
        self.report(problems, text, origin)
    }

    fn moves_line(
        &mut self,
        text: &[u8],
        words: &[crate::block::RawWord],
        origin: &Origin<'_>,
        out: &mut Output,
    ) -> Result<(), Error> {
        if self.p.passthrough {
            return out.line(text).map_err(io_error);
        }
        match self.write_moves(text, words, out)? {
            plain::Moves::Done => return Ok(()),
            plain::Moves::Problem(kind) => {
                return self.report(vec![Problem { span: None, kind }], text, origin);
            }
            plain::Moves::NotTaken => {}
        }
        self.run_decoded(text, origin, out, |b| b.replay_words(words))
    }

    fn moves_rule(&self) -> Option<crate::block::MovesRule> {
        Lowering::moves_rule(self)
    }

    fn form_lines(
        &mut self,
        batch: &crate::eval::FormLines<'_>,
        origin: &Origin<'_>,
        out: &mut Output,
    ) -> Result<(), (usize, Error)> {
        self.write_forms(batch, origin, out)
    }

    fn computes_comp(&self) -> bool {
        !self.p.passthrough && !self.p.has_g(410)
    }

    fn comp_position(&mut self, p: [f64; 2]) {
        if let Some(c) = &mut self.comp {
            c.comp.set_current(p);
        }
    }

    fn finish(&mut self, _out: &mut Output) -> Result<Vec<Diagnostic>, Error> {
        let mut all = std::mem::take(&mut self.warnings);
        all.append(&mut self.errors);
        Ok(all)
    }
}

fn io_error(e: std::io::Error) -> Error {
    crate::eval::output_error(e)
}

impl Lowering {
    /// Runs and writes the decoded line `b` (the short way when it is
    /// plain); the problems found.
    fn run_block(
        &mut self,
        b: &Block,
        text: &[u8],
        origin: &Origin<'_>,
        out: &mut Output,
    ) -> Result<Vec<Problem>, Error> {
        if self.plain && self.is_plain(b) && !self.plain_arc_off(b) {
            self.write_plain(b, text, out)
        } else {
            self.lower_block(b, text, origin, out)
        }
    }

    /// Stops the run at the first problem, or in check mode keeps them all.
    fn report(
        &mut self,
        problems: Vec<Problem>,
        text: &[u8],
        origin: &Origin<'_>,
    ) -> Result<(), Error> {
        if problems.is_empty() {
            return Ok(());
        }
        for p in problems {
            let mut d = Diagnostic::error(p.kind, Some(site_of(origin, text, p.span)));
            d.stack = (origin.stack)();
            if !self.opts.check {
                return Err(d);
            }
            self.errors.push(*d);
        }
        Ok(())
    }

    /// Decides every word of `b`, runs it on the machine model and writes
    /// the target's lines. Returns the problems (the line is not written
    /// when there are any).
    fn lower_block(
        &mut self,
        b: &Block,
        text: &[u8],
        origin: &Origin<'_>,
        out: &mut Output,
    ) -> Result<Vec<Problem>, Error> {
        if b.percent {
            if self.p.percent {
                // The target reads `%` lines as LinuxCNC does.
                out.line(b"%").map_err(io_error)?;
            } else if !self.percent_open {
                // The opening `%` is simply dropped.
                self.percent_open = true;
            } else if !self.m.ended {
                // A program ended by `%` alone ends there: the target gets
                // M2, also when it has no words at all.
                self.m.ended = true;
                out.line(b"M2").map_err(io_error)?;
            }
            return Ok(Vec::new());
        }
        if b.block_delete && self.opts.block_delete {
            // The switch is on: LinuxCNC skips the line.
            return Ok(Vec::new());
        }
        self.released_seqs.clear();
        self.defer_block = None;
        let before = self.m.snapshot();
        let mut d = match self.decide_words(b, text, origin) {
            Ok(d) => d,
            Err(problems) => return Ok(problems),
        };
        match self.block_lines(b, text, &before, &mut d) {
            Ok(lines) => {
                for l in &lines {
                    out.line(l).map_err(io_error)?;
                }
                Ok(Vec::new())
            }
            Err(p) => Ok(vec![p]),
        }
    }

    /// Decides the fate of each word of `b` and runs the block on the
    /// machine model; the problems found, if any.
    fn decide_words(
        &mut self,
        b: &Block,
        text: &[u8],
        origin: &Origin<'_>,
    ) -> Result<Decided, Vec<Problem>> {
        // The line's site is worked out only for a warning (see `warn`).
        let site: Option<Site> = None;
        let mut problems = Vec::new();
        let mut d = Decided {
            fates: vec![Fate::Keep; b.words.len()],
            extra: Vec::new(),
            extra_lines: Vec::new(),
            pre_lines: Vec::new(),
        };
        for (i, w) in b.words.iter().enumerate() {
            let fate = match w.kind {
                WordKind::G(g) => self.g_fate(b, w, g, &site, &mut problems),
                WordKind::M(m) => self.m_fate(
                    b,
                    w,
                    m,
                    &site,
                    &mut problems,
                    &mut d.pre_lines,
                    &mut d.extra_lines,
                ),
                WordKind::Value => self.value_fate(b, w, &mut problems),
            };
            d.fates[i] = fate;
        }
        if !self.pending.is_empty() {
            let at = site_of(origin, text, None);
            for kind in std::mem::take(&mut self.pending) {
                self.warnings
                    .push(Diagnostic::warning(kind, Some(at.clone())));
            }
        }
        // Words that belong to a dropped code go with it.
        self.drop_owned(b, &mut d.fates);
        self.m.apply(b);
        let _ = self.m.take_events();
        if problems.is_empty() {
            Ok(d)
        } else {
            Err(problems)
        }
    }

    /// The target's lines for a block whose words are decided and which
    /// ran on the machine model (`before`: the model before it).
    fn block_lines(
        &mut self,
        b: &Block,
        text: &[u8],
        before: &Machine,
        d: &mut Decided,
    ) -> Result<Vec<Vec<u8>>, Problem> {
        self.polar_arc_end(b, before)?;
        self.state_lines(b, before, d)?;
        // Compensated moves, or lowered motion, replace the line's motion
        // words.
        let mut lowered = self.motion_lines(b, before, &mut d.fates)?;
        if let Some(l) = lowered.as_mut() {
            self.inverse_time_feeds(b, before, l);
        }
        self.centres = match lowered {
            Some(_) => None,
            None => self.centre_offsets(b, before).map_err(|kind| Problem {
                span: g_span(b, 20, 30),
                kind,
            })?,
        };
        self.feed_words(b, before, &mut d.fates, &mut d.extra);
        // The line itself.
        let incremental_lowered = self.incremental_lowered(lowered.as_deref());
        let shift = self.target_shift(b, &d.fates, lowered.as_deref())?;
        let waiting = self.waiting_words(b, &mut d.fates);
        let written = self.own_line(b, text, d, lowered.as_deref(), shift)?;
        let mut lines: Vec<Vec<u8>> = Vec::new();
        for l in &d.pre_lines {
            lines.push(self.plain_bytes(&words_line(l))?);
        }
        if !written.is_empty() {
            lines.push(written);
        }
        if let Some(after) = self.defer_block.take()
            && !waiting.is_empty()
        {
            // Runs after the held moves (see `comp_block`).
            let l = self.plain_bytes(&words_line(&waiting))?;
            self.deferred.push((after, l));
        }
        let seqs = std::mem::take(&mut self.released_seqs);
        if let Some(lowered) = lowered {
            if incremental_lowered {
                lines.push(b"G90".to_vec());
            }
            for (i, l) in lowered.iter().enumerate() {
                if let Some(&seq) = seqs.get(i) {
                    self.flush_deferred(Some(seq), &mut lines);
                }
                let shifted;
                let l = match shift {
                    Some(sh) => {
                        shifted = shift_line(l, sh, self.m.scale());
                        &shifted
                    }
                    None => l,
                };
                lines.push(self.plain_bytes(l)?);
            }
            if incremental_lowered {
                lines.push(b"G91".to_vec());
            }
        }
        if !self.deferred.is_empty() {
            let first_held = self
                .comp
                .as_ref()
                .and_then(|c| c.comp.first_held())
                .map(|t| t.1);
            self.flush_deferred(first_held, &mut lines);
        }
        for l in &d.extra_lines {
            lines.push(self.plain_bytes(&words_line(l))?);
        }
        Ok(lines)
    }

    /// A plain line written for the target.
    fn plain_bytes(&mut self, l: &PlainLine) -> Result<Vec<u8>, Problem> {
        let mut buf = Vec::new();
        match self.plain_line(l, &mut buf) {
            Some(kind) => Err(Problem { span: None, kind }),
            None => Ok(buf),
        }
    }

    /// Rewrites that need the state after the block: the target's G92
    /// offset and coordinate system, refused probes and arcs, G5 words,
    /// tool length offsets the target lacks.
    fn state_lines(&mut self, b: &Block, before: &Machine, d: &mut Decided) -> Result<(), Problem> {
        // The target's G92 offset follows LinuxCNC's effective G92/G52
        // offset (a line before the block's own, in the target's state
        // before it); then the target takes the block's coordinate system
        // if it has it.
        match self.offset_sync(b, before) {
            Ok(Some(ws)) if !ws.is_empty() => d.pre_lines.push(ws),
            Ok(_) => {}
            Err(k) => {
                return Err(Problem {
                    span: b
                        .g_codes()
                        .find(|(g, _)| matches!(g, GCode::NonModal(_)))
                        .map(|(_, w)| w.span),
                    kind: k,
                });
            }
        }
        if let Some(c) = b.coord()
            && c.0 <= self.p.coord_systems
        {
            self.target_coord = c;
        }
        if self.m.ended {
            // M2/M30 select G54 on LinuxCNC and on the GRBL family.
            self.target_coord = self.m.modes.coord;
        }
        if let Some(k) = self.probe_in_place(b, before) {
            return Err(Problem {
                span: b
                    .g_codes()
                    .find(|(g, _)| matches!(g, GCode::Motion(MotionMode::Probe(_))))
                    .map(|(_, w)| w.span),
                kind: k,
            });
        }
        if let Some(ws) = self.dynamic_tool_length(b, before).map_err(|k| Problem {
            span: g_span(b, 431, 431),
            kind: k,
        })? {
            // The block's G43.1 and its axis words give way to the line.
            for (i, w) in b.words.iter().enumerate() {
                let axis = matches!(w.kind, WordKind::Value) && xyz_index(w.letter).is_some();
                if axis || matches!(w.kind, WordKind::G(_)) && code10(w) == 431 {
                    d.fates[i] = Fate::Drop;
                }
            }
            d.pre_lines.push(ws);
        }
        if let Some(k) = self.linuxcnc_arc_refusal(b, before) {
            // At the line, as the evaluator reports it.
            return Err(Problem {
                span: Some(LINE_START),
                kind: k,
            });
        }
        self.native_g5_words(b, before, &mut d.extra);
        if b.tool_length()
            .is_some_and(|t| matches!(t, ToolLength::Apply | ToolLength::Add))
            && !self.p.has_g(if b.tool_length() == Some(ToolLength::Apply) {
                430
            } else {
                432
            })
        {
            match self.tool_length_words(b, before) {
                Ok(ws) => d.pre_lines.push(ws),
                Err(k) => {
                    return Err(Problem {
                        span: g_span(b, 430, 432),
                        kind: k,
                    });
                }
            }
        }
        Ok(())
    }

    /// The lines of compensated or lowered motion, if the block's motion
    /// is replaced (its motion words are then dropped).
    fn motion_lines(
        &mut self,
        b: &Block,
        before: &Machine,
        fates: &mut [Fate],
    ) -> Result<Option<Vec<PlainLine>>, Problem> {
        self.f_before = self.last_f;
        if let Some(f) = b.value(b'F') {
            self.last_f = Some(f);
        }
        let compensated = self.comp_block(b, before, fates)?;
        let lowered = compensated
            .map_or_else(|| self.lower_motion(b, before), |c| Ok(Some(c)))
            .map_err(|k| Problem {
                span: b.motion().and_then(|_| {
                    b.g_codes()
                        .find(|(g, _)| matches!(g, GCode::Motion(_)))
                        .map(|(_, w)| w.span)
                }),
                kind: k,
            })?;
        if lowered.is_some() {
            for (i, w) in b.words.iter().enumerate() {
                let motion_word = matches!(w.kind, WordKind::G(GCode::Motion(_)))
                    || matches!(w.kind, WordKind::Value) && b"XYZIJKRPLQ@^".contains(&w.letter);
                if motion_word {
                    fates[i] = Fate::Drop;
                }
            }
        }
        Ok(lowered)
    }

    /// Positions in a coordinate system the target lacks are written in
    /// the one it is in: the shift to add, when the block writes any.
    fn target_shift(
        &self,
        b: &Block,
        fates: &[Fate],
        lowered: Option<&[PlainLine]>,
    ) -> Result<Option<[f64; 3]>, Problem> {
        if self.m.modes.coord == self.target_coord {
            return Ok(None);
        }
        let needed = Self::positions_in_work(b, &self.m)
            && b.words.iter().zip(fates).any(|(w, f)| {
                *f == Fate::Keep
                    && matches!(w.kind, WordKind::Value)
                    && matches!(w.letter, b'X' | b'Y' | b'Z')
            })
            || lowered.is_some_and(|l| !l.is_empty());
        if !needed {
            return Ok(None);
        }
        self.coord_shift(&self.m, self.target_coord)
            .map(Some)
            .map_err(|k| Problem {
                span: b.coord().and(g_span(b, 591, 593)),
                kind: k,
            })
    }

    /// Lowered motion in G91: the lowered lines are absolute, with G90
    /// before them and G91 after.
    fn incremental_lowered(&self, lowered: Option<&[PlainLine]>) -> bool {
        lowered.is_some_and(|l| !l.is_empty()) && self.m.modes.distance == Distance::Incremental
    }

    /// The block's own line: its kept words, the extra words, its
    /// comments; empty when nothing is left. Pauses and program ends
    /// of a line with lowered motion go after the motion, as lines of
    /// their own.
    fn own_line(
        &mut self,
        b: &Block,
        text: &[u8],
        d: &mut Decided,
        lowered: Option<&[PlainLine]>,
        shift: Option<[f64; 3]>,
    ) -> Result<Vec<u8>, Problem> {
        let incremental_lowered = self.incremental_lowered(lowered);
        let lowered = lowered.is_some();
        let mut written = Vec::new();
        let word_shift = shift.filter(|_| Self::positions_in_work(b, &self.m));
        self.w.begin(b, self.m.modes.units, self.axis_words(b));
        for (i, w) in b.words.iter().enumerate() {
            if d.fates[i] != Fate::Keep {
                continue;
            }
            if incremental_lowered && matches!(w.kind, WordKind::G(GCode::Distance(_))) {
                // The lowered blocks are absolute; G91 comes after them.
                continue;
            }
            if lowered && matches!(w.kind, WordKind::M(MCode::Pause { .. } | MCode::End { .. })) {
                // Stops act after the motion.
                d.extra_lines.push(vec![(b'M', w.value)]);
                continue;
            }
            let mut v = self.out_value(w);
            if let (Some(sh), WordKind::Value) = (word_shift, w.kind)
                && let Some(a) = xyz_index(w.letter)
            {
                v += sh[a] / self.m.scale();
            }
            self.w.word(w.letter, v, w.kind);
        }
        for &(l, v) in &d.extra {
            self.w.word(l, v, WordKind::Value);
        }
        self.w.comments(b, text);
        if let Some(kind) = self.w.finish_line(&mut written) {
            return Err(Problem { span: None, kind });
        }
        Ok(written)
    }

    /// What the axis words of block `b`, which the model has run, are to
    /// the target: increments in G91 motion (G0–G3), positions in G90
    /// motion, neither for a code that takes them (G92, G10, G28, G53,
    /// G43.1) or a canned cycle.
    fn axis_words(&self, b: &Block) -> AxisWords {
        let other = b.non_modal().is_some_and(NonModal::takes_axis_words)
            || b.tool_length() == Some(ToolLength::Dynamic)
            || !matches!(
                self.m.modes.motion,
                MotionMode::Rapid | MotionMode::Linear | MotionMode::ArcCw | MotionMode::ArcCcw
            );
        if other {
            AxisWords::Other
        } else {
            self.moves_axis_words()
        }
    }

    /// The action words of a block run while compensated moves are held
    /// back (and a dwell's P), taken out of its own line: they wait for the
    /// held moves, while its modal words (G90/G91, ...) are written at once,
    /// as the moves written after them are read in those modes.
    fn waiting_words(&self, b: &Block, fates: &mut [Fate]) -> Vec<(u8, f64)> {
        if self.defer_block.is_none() {
            return Vec::new();
        }
        let dwell = b.non_modal() == Some(NonModal::Dwell);
        let mut words = Vec::new();
        for (i, w) in b.words.iter().enumerate() {
            let dwell_p = dwell && w.letter == b'P' && matches!(w.kind, WordKind::Value);
            if fates[i] == Fate::Keep && (Self::is_action(w) || dwell_p) {
                words.push((w.letter, self.out_value(w)));
                fates[i] = Fate::Drop;
            }
        }
        words
    }

    /// Moves the waiting lines whose held moves are all written (number
    /// below `before`; all of them for `None`) into `lines`.
    fn flush_deferred(&mut self, before: Option<u64>, lines: &mut Vec<Vec<u8>>) {
        let n = self
            .deferred
            .iter()
            .take_while(|(after, _)| before.is_none_or(|b| *after < b))
            .count();
        lines.extend(self.deferred.drain(..n).map(|(_, l)| l));
    }

    /// Whether the axis words of `b` are positions in the active work
    /// coordinates: G92 values, and in absolute distance mode motion and
    /// G28/G30 intermediate points. Those are rewritten when the
    /// program's coordinate system is not the target's.
    fn positions_in_work(b: &Block, m: &Machine) -> bool {
        b.non_modal() == Some(NonModal::SetG92)
            || m.modes.distance == Distance::Absolute
                && b.tool_length() != Some(ToolLength::Dynamic)
                && matches!(
                    b.non_modal(),
                    None | Some(NonModal::Dwell | NonModal::Home | NonModal::Home2)
                )
    }

    /// What to add (mm, X Y Z) to a position in `m`'s work coordinates to
    /// get the same machine position in the target's system `target`.
    fn coord_shift(&self, m: &Machine, target: CoordSystem) -> Result<[f64; 3], ErrorKind> {
        let (from, to) = (m.modes.coord, target);
        let (a, t) = (&m.g5x[from.index()], &m.g5x[to.index()]);
        let mut out = [0.0; 3];
        for i in 0..3 {
            match (a[i], t[i]) {
                (Some(a), Some(t)) => out[i] = a - t,
                _ => {
                    let param = |c: CoordSystem| c.parameters() + i;
                    return Err(ErrorKind::TargetNeedsValue {
                        target: self.name(),
                        what: format!(
                            "{} (a coordinate system the target lacks, written as coordinates in {})",
                            from.name(),
                            to.name()
                        ),
                        value: format!(
                            "the {} offsets of both (parameters {} and {})",
                            ['X', 'Y', 'Z'][i],
                            param(from),
                            param(to)
                        ),
                        option: "--var-file (the machine's parameter file), -D, or --zero-start"
                            .into(),
                    });
                }
            }
        }
        Ok(out)
    }

    /// G52, G92.1, G92.2, G92.3 where the target lacks them: a `G92` (or
    /// `G92.1`) line that gives the target the effective G92/G52 offset
    /// LinuxCNC has after the block, computed in the target's state
    /// before it. `None` when the block has none of them or the target
    /// has the code; an empty line when nothing changes.
    fn offset_sync(
        &self,
        b: &Block,
        before: &Machine,
    ) -> Result<Option<Vec<(u8, f64)>>, ErrorKind> {
        let (code, what) = match b.non_modal() {
            Some(NonModal::LocalOffset) => (520, "G52 (local offset)"),
            Some(NonModal::ResetG92) => (921, "G92.1"),
            Some(NonModal::SuspendG92) => (922, "G92.2 (G92 offsets off)"),
            Some(NonModal::RestoreG92) => (923, "G92.3 (G92 offsets back on)"),
            _ => return Ok(None),
        };
        if self.p.has_g(code) {
            return Ok(None);
        }
        let effective = |m: &Machine, a: usize| match m.g92_applied {
            Some(true) => m.g92[a],
            Some(false) => Some(0.0),
            None => None,
        };
        let need = |value: String, option: &str| ErrorKind::TargetNeedsValue {
            target: self.name(),
            what: format!("{what}, written as the target's G92"),
            value,
            option: option.into(),
        };
        let offsets_option =
            "--var-file (parameters 5210-5213 of the machine), -D, or --zero-start";
        let mut changed = Vec::new();
        let mut all_zero = true;
        for (a, &letter) in b"XYZ".iter().enumerate() {
            if !self.p.has_axis(letter) {
                continue;
            }
            let want = effective(&self.m, a)
                .ok_or_else(|| need("the G92 offsets".into(), offsets_option))?;
            let had = effective(before, a)
                .ok_or_else(|| need("the G92 offsets".into(), offsets_option))?;
            all_zero &= want == 0.0;
            if want != had {
                changed.push((a, letter, had, want));
            }
        }
        if changed.is_empty() {
            return Ok(Some(Vec::new()));
        }
        if all_zero && self.p.has_g(921) {
            return Ok(Some(vec![(b'G', 92.1)]));
        }
        // The target's G92 makes the current position read the value:
        // its offset = machine - G5x - tool length - value, and the
        // machine position is the work position plus G5x, the G92 offset
        // and the tool length: value = position + offset before - offset
        // wanted (+ the shift to the target's coordinate system).
        let shift = if before.modes.coord == self.target_coord {
            [0.0; 3]
        } else {
            self.coord_shift(before, self.target_coord)?
        };
        let s = before.scale();
        let mut words = vec![(b'G', 92.0)];
        for (a, letter, had, want) in changed {
            let p = before.pos[a].ok_or_else(|| {
                need(
                    format!("the current {} position", letter as char),
                    "--start-position (or --zero-start), or an absolute move first",
                )
            })?;
            words.push((letter, (p + had - want + shift[a]) / s));
        }
        Ok(Some(words))
    }

    /// GRBL and its descendants refuse a probe move whose target is the
    /// current position (error 33); LinuxCNC runs it as a move of length
    /// zero. Checked where both points are known: under `--zero-start` a
    /// probe is taken as not tripping, so a second probe to the same
    /// target is refused too.
    fn probe_in_place(&self, b: &Block, before: &Machine) -> Option<ErrorKind> {
        let motion = b.motion().unwrap_or(before.modes.motion);
        if !matches!(motion, MotionMode::Probe(_))
            || !b.has_axis()
            || b.non_modal().is_some_and(|n| !matches!(n, NonModal::Dwell))
            || b.tool_length() == Some(ToolLength::Dynamic)
        {
            return None;
        }
        // Where the probe ends if it does not trip (the model forgets the
        // position after a probe unless the probe is taken as not tripping).
        let mut m = before.clone();
        m.zero_start = true;
        m.apply(b);
        let _ = m.take_events();
        // The target's own axes must be known and unmoved; the others
        // cannot be written for it anyway.
        let same = crate::block::AXIS_LETTERS
            .iter()
            .zip(before.pos.iter().zip(m.pos.iter()))
            .filter(|(l, _)| self.p.has_axis(**l))
            .all(|(_, (a, z))| matches!((a, z), (Some(a), Some(z)) if (a - z).abs() < 1e-9));
        same.then_some(ErrorKind::TargetProbeInPlace {
            target: self.name(),
        })
    }

    /// A G5 the target runs itself: its I J are written on every block,
    /// since the target would take a missing pair as minus the block's own
    /// P Q, where LinuxCNC reflects the previous block's P Q.
    fn native_g5_words(&mut self, b: &Block, before: &Machine, extra: &mut Vec<(u8, f64)>) {
        let motion = b.motion().unwrap_or(before.modes.motion);
        if motion != MotionMode::CubicSpline || !self.p.has_g(50) || !b.has_axis() {
            return;
        }
        let (i, j) = (b.value(b'I'), b.value(b'J'));
        match (i, j) {
            (None, None) => {
                let [p, q] = self.last_pq.unwrap_or([0.0, 0.0]);
                extra.push((b'I', -p));
                extra.push((b'J', -q));
            }
            (Some(_), None) => extra.push((b'J', 0.0)),
            (None, Some(_)) => extra.push((b'I', 0.0)),
            (Some(_), Some(_)) => {}
        }
        self.last_pq = Some([b.value(b'P').unwrap_or(0.0), b.value(b'Q').unwrap_or(0.0)]);
    }

    /// Writes a lowered block; a code the target lacks is refused.
    fn plain_line(&mut self, l: &PlainLine, buf: &mut Vec<u8>) -> Option<ErrorKind> {
        for w in &l.words {
            let ok = match w.letter {
                b'G' => self.p.has_g((w.value * 10.0).round() as u16),
                b'M' => self.p.has_m(w.value.round() as u16),
                l => self.p.has_word(l),
            };
            if !ok {
                return Some(self.refuse(
                    format!("{}{}", w.letter as char, w.value),
                    "the lowering needs it and the target does not have it",
                ));
            }
        }
        self.w.plain(l, self.m.modes.units, buf)
    }

    fn g_fate(
        &mut self,
        b: &Block,
        w: &Word,
        g: GCode,
        site: &Option<Site>,
        problems: &mut Vec<Problem>,
    ) -> Fate {
        let c = code10(w);
        let p = self.p;
        let refuse = |s: &Self, why: &str| Problem {
            span: Some(w.span),
            kind: s.refuse(g_name(w), why),
        };
        match g {
            GCode::Motion(m) => match m {
                MotionMode::Thread | MotionMode::RigidTap | MotionMode::ThreadCycle
                    if !p.spindle_sync || !p.has_g(c) =>
                {
                    problems.push(refuse(
                        self,
                        "spindle-synchronised motion needs spindle synchronisation, which the target does not have",
                    ));
                    Fate::Drop
                }
                MotionMode::Cycle(_) if !p.has_g(c) => Fate::Drop,
                // Without canned cycles G80 only stops axis words from
                // being used by G10/G28/G92/G43.1 (GRBL's error 31): the
                // source has no cycle running on the target to cancel.
                MotionMode::CancelCycle if !p.has_g(810) => Fate::Drop,
                // Lowered into G1 segments (lower_motion).
                MotionMode::CubicSpline | MotionMode::QuadSpline if !p.has_g(c) => Fate::Drop,
                // Control points collected, the curve lowered at G5.3
                // (lower_nurbs_block).
                MotionMode::Nurbs | MotionMode::NurbsEnd if !p.has_g(c) => Fate::Drop,
                _ if p.has_g(c) => Fate::Keep,
                _ => {
                    problems.push(refuse(self, "the target does not have this motion"));
                    Fate::Drop
                }
            },
            GCode::NonModal(NonModal::SetData) => self.g10_fate(b, w, problems),
            _ if p.has_g(c) => Fate::Keep,
            // The target's G92 offset is set to the same effective offset
            // after the block (offset_sync); a coordinate system the target
            // lacks is written as coordinates in the one it is in
            // (coord_shift).
            GCode::NonModal(
                NonModal::LocalOffset
                | NonModal::ResetG92
                | NonModal::SuspendG92
                | NonModal::RestoreG92,
            )
            | GCode::Coord(_) => Fate::Drop,
            GCode::Path(PathMode::Blend) | GCode::Path(PathMode::ExactStop) => {
                self.dropped(
                    site,
                    &g_name(w),
                    "the target has no such path mode; the path may blend differently at corners",
                );
                Fate::Drop
            }
            GCode::Path(PathMode::Exact) => {
                self.dropped(
                    site,
                    "G61",
                    "the target has no exact-path mode; corners may blend",
                );
                Fate::Drop
            }
            GCode::Lathe(LatheMode::Radius) => Fate::Drop,
            GCode::Lathe(LatheMode::Diameter) => Fate::Drop,
            GCode::SpindleMode(SpindleMode::Rpm) => Fate::Drop,
            GCode::SpindleMode(SpindleMode::ConstantSurface) => {
                problems.push(refuse(
                    self,
                    "constant surface speed needs spindle speed control from the axis position, which the target does not have",
                ));
                Fate::Drop
            }
            GCode::FeedMode(FeedMode::PerMinute) => {
                // G94 after a lowered G95 changes nothing on the target.
                Fate::Drop
            }
            GCode::FeedMode(FeedMode::PerRev) => {
                let s = b.value(b'S').unwrap_or(self.m.modes.speed);
                if s > 0.0 && self.m.modes.spindle_mode == SpindleMode::Rpm {
                    self.feed_rewrite = true;
                    let k = WarningKind::TargetRewritten {
                        target: self.name(),
                        what: "G95 (feed per revolution)".into(),
                        how: "feed per minute at the programmed spindle speed; exact only if the spindle holds that speed".into(),
                    };
                    self.warn(site.clone(), k);
                } else {
                    problems.push(Problem {
                        span: Some(w.span),
                        kind: ErrorKind::TargetNeedsValue {
                            target: self.name(),
                            what: "G95 (feed per revolution)".into(),
                            value: "a constant spindle speed".into(),
                            option: "an S word before G95 (and G97)".into(),
                        },
                    });
                }
                Fate::Drop
            }
            // Arcs are written with offsets from their start (centres.rs).
            GCode::ArcDistance(_) | GCode::Retract(_) => Fate::Drop,
            GCode::ToolLength(ToolLength::Apply | ToolLength::Add) if p.has_g(431) => Fate::Drop,
            GCode::CutterComp(CutterComp::Off) => Fate::Drop,
            // Computed into the path (comp_block).
            GCode::CutterComp(_) => Fate::Drop,
            _ => {
                problems.push(refuse(self, "the target does not have this code"));
                Fate::Drop
            }
        }
    }

    /// G10: kept when the target has its L form and the coordinate system
    /// it writes; tool table writes (L1, L10, L11) and writes to a system
    /// the target lacks are dropped, the model keeps them (G43 and the
    /// coordinate rewriting read them).
    fn g10_fate(&mut self, b: &Block, w: &Word, problems: &mut Vec<Problem>) -> Fate {
        let l = b
            .value(b'L')
            .map_or(0, |l| l.round().clamp(0.0, 255.0) as u8);
        let p = self.p;
        let native = p.has_g(100) && p.g10_l.contains(&l);
        match l {
            1 | 10 | 11 if !native => Fate::Drop,
            2 | 20 => {
                if b.value(b'R').is_some_and(|r| r != 0.0) {
                    problems.push(Problem {
                        span: Some(w.span),
                        kind: self.refuse(
                            "G10 L2 R (coordinate system rotation)",
                            "the target has no rotation of the coordinate system",
                        ),
                    });
                    return Fate::Drop;
                }
                if !b.has_axis() {
                    // Nothing changes (GRBL refuses it without an axis
                    // word, error 26).
                    return Fate::Drop;
                }
                // P0 (or none) is the active system, as LinuxCNC has it.
                let k = match b.value(b'P').map(|v| v.round()) {
                    Some(v) if v >= 1.0 => v.min(255.0) as u8,
                    _ => self.m.modes.coord.0,
                };
                if k > p.coord_systems {
                    Fate::Drop
                } else if native {
                    Fate::Keep
                } else {
                    problems.push(Problem {
                        span: Some(w.span),
                        kind: self.refuse(
                            format!("G10 L{l}"),
                            "the target does not have this form of G10",
                        ),
                    });
                    Fate::Drop
                }
            }
            _ if native => Fate::Keep,
            _ => {
                problems.push(Problem {
                    span: Some(w.span),
                    kind: self.refuse(
                        format!("G10 L{l}"),
                        "the target does not have this form of G10",
                    ),
                });
                Fate::Drop
            }
        }
    }

    #[allow(clippy::too_many_arguments)]
    fn m_fate(
        &mut self,
        b: &Block,
        w: &Word,
        m: MCode,
        site: &Option<Site>,
        problems: &mut Vec<Problem>,
        pre_lines: &mut Vec<Vec<(u8, f64)>>,
        extra_lines: &mut Vec<Vec<(u8, f64)>>,
    ) -> Fate {
        let n = w.value.round() as u16;
        let p = self.p;
        if m == MCode::ToolChange {
            let policy = self.opts.tool_change.unwrap_or(p.tool_change);
            if self.m.modes.spindle != SpindleDir::Off {
                // LinuxCNC stops the spindle for the change (and leaves it
                // off), before the block's spindle words and motion. Also
                // where M6 is kept: grblHAL ignores M6 by default, and
                // what FluidNC's does depends on its spindle.
                pre_lines.push(vec![(b'M', 5.0)]);
            }
            return match policy {
                ToolChange::Keep => Fate::Keep,
                ToolChange::Drop => Fate::Drop,
                ToolChange::Pause => {
                    let tool = b
                        .value(b'T')
                        .map(|t| t.round() as i64)
                        .or(self.m.selected_tool());
                    let what = match tool {
                        Some(t) => format!("M6 (change to tool {t})"),
                        None => "M6 (tool change)".into(),
                    };
                    let k = WarningKind::TargetRewritten {
                        target: self.name(),
                        what,
                        how: "M0: the program pauses for a manual tool change (--tool-change keep|drop to change that)".into(),
                    };
                    self.warn(site.clone(), k);
                    // The change comes before the block's spindle words,
                    // tool length offset and motion.
                    pre_lines.push(vec![(b'M', 0.0)]);
                    Fate::Drop
                }
            };
        }
        if m == (MCode::Pause { optional: true }) && !p.optional_stop {
            let k = WarningKind::TargetIgnores {
                target: self.name(),
                what: "M1 (optional stop)".into(),
                why: "the program does not pause there, where LinuxCNC stops if its optional-stop switch is on".into(),
            };
            self.warn(site.clone(), k);
            return Fate::Keep;
        }
        if p.has_m(n) && w.value.fract() == 0.0 {
            return Fate::Keep;
        }
        match m {
            MCode::SetTool | MCode::State(_) => Fate::Drop,
            MCode::Override(_) => {
                self.dropped(
                    site,
                    &format!("M{n}"),
                    "the target has no such override switch; overrides stay as the operator sets them",
                );
                Fate::Drop
            }
            MCode::PalletPause => {
                extra_lines.push(vec![(b'M', 0.0)]);
                Fate::Drop
            }
            MCode::User(_) => {
                problems.push(Problem {
                    span: Some(w.span),
                    kind: self.refuse(
                        format!("M{n}"),
                        "user M-codes (M100-M199) run external programs on a LinuxCNC machine; this controller has none",
                    ),
                });
                Fate::Drop
            }
            MCode::Mist => {
                problems.push(Problem {
                    span: Some(w.span),
                    kind: self.refuse("M7 (mist coolant)", "the target has no mist coolant output"),
                });
                Fate::Drop
            }
            _ => {
                problems.push(Problem {
                    span: Some(w.span),
                    kind: self.refuse(
                        format!("M{}", crate::emit::number_string(w.value, None)),
                        "the target does not have this code",
                    ),
                });
                Fate::Drop
            }
        }
    }

    fn value_fate(&mut self, b: &Block, w: &Word, problems: &mut Vec<Problem>) -> Fate {
        let l = w.letter;
        let axis = crate::block::AXIS_LETTERS.contains(&l);
        if axis && !self.p.has_axis(l) {
            problems.push(Problem {
                span: Some(w.span),
                kind: self.refuse(
                    format!("axis word {}", l as char),
                    "the target has no such axis",
                ),
            });
            return Fate::Drop;
        }
        match l {
            b'T' if w.value > self.p.max_tool => return Fate::Drop,
            // Polar words are lowered with their motion (lower_motion).
            b'@' | b'^' => return Fate::Drop,
            _ => {}
        }
        if self.p.has_word(l) {
            return Fate::Keep;
        }
        // Words of codes that are dropped or lowered go with them (see
        // drop_owned); others are refused.
        let owned = matches!(l, b'Q' | b'H' | b'D' | b'E' | b'P' | b'L' | b'R');
        if !owned {
            problems.push(Problem {
                span: Some(w.span),
                kind: self.refuse(
                    format!("the {} word", l as char),
                    "the target does not read it",
                ),
            });
        }
        let _ = b;
        Fate::Drop
    }

    /// Drops the value words of dropped codes (G64's P and Q, M61's Q,
    /// G43's H, G10 L1's words, P on an arc of one turn).
    fn drop_owned(&self, b: &Block, fates: &mut [Fate]) {
        let snapshot = fates.to_vec();
        let dropped_g = |c: u16| {
            b.words.iter().zip(snapshot.iter()).any(|(w, f)| {
                *f == Fate::Drop && matches!(w.kind, WordKind::G(_)) && code10(w) == c
            })
        };
        let mut drop = |letter: u8| {
            for (i, w) in b.words.iter().enumerate() {
                if w.letter == letter && matches!(w.kind, WordKind::Value) {
                    fates[i] = Fate::Drop;
                }
            }
        };
        if dropped_g(640) {
            drop(b'P');
            drop(b'Q');
        }
        if b.m_codes().any(|(m, _)| m == MCode::SetTool) && !self.p.has_m(61) {
            drop(b'Q');
        }
        if dropped_g(430) || dropped_g(432) {
            drop(b'H');
        }
        if dropped_g(100) {
            for l in *b"LPRXYZABCUVWIJQ" {
                drop(l);
            }
        }
        if dropped_g(520) {
            for l in *b"XYZABCUVW" {
                drop(l);
            }
        }
        let arc = matches!(b.motion(), Some(MotionMode::ArcCw | MotionMode::ArcCcw))
            || b.motion().is_none()
                && matches!(self.m.modes.motion, MotionMode::ArcCw | MotionMode::ArcCcw)
                && b.has_axis();
        if arc && b.value(b'P') == Some(1.0) {
            drop(b'P');
        }
        if b.retract().is_some() && !self.p.has_g(980) {
            // Nothing else belongs to G98/G99.
        }
    }

    /// G43/G43.2 as the target's G43.1 Z (the offset in program units).
    fn tool_length_words(&self, b: &Block, before: &Machine) -> Result<Vec<(u8, f64)>, ErrorKind> {
        // The G43.1 line goes before the block's own line, so its value is
        // in the units in effect before the block (a G20/G21 on the line
        // comes after it).
        let s = before.scale();
        let tlo = self.m.tlo;
        let need = |axis: &str| ErrorKind::TargetNeedsValue {
            target: self.name(),
            what: "G43 (tool length offset)".into(),
            value: format!("the tool's {axis} length"),
            option: "--tool-table (the tool table of the machine)".into(),
        };
        // The tool's data must really be known: from --tool-table or a G10
        // L1/L10/L11 of the program (--zero-start's zeros are not the
        // machine's tools).
        let h = b
            .value(b'H')
            .map(|h| h.round() as i64)
            .or(before.current_tool());
        if !h.is_some_and(|h| h == 0 || self.m.tools.table.contains_key(&h)) {
            return Err(need("Z"));
        }
        let z = tlo[2].ok_or_else(|| need("Z"))?;
        for (a, v) in tlo.iter().enumerate() {
            if a != 2 && v.is_some_and(|v| v != 0.0) && self.p.g43_1_z_only {
                return Err(self.refuse(
                    "G43 with an X or other non-Z tool offset",
                    "the target's G43.1 takes only Z",
                ));
            }
        }
        if !self.p.has_g(431) {
            return Err(self.refuse("G43", "the target has no tool length offset"));
        }
        Ok(vec![(b'G', 43.1), (b'Z', z / s)])
    }

    /// A G43.1 of the program on a target whose G43.1 takes a Z word alone
    /// (GRBL refuses any other, error 37): `None` when it has that form,
    /// else the target's `G43.1 Z` line for the offset it leaves (LinuxCNC
    /// sets the axes it names and keeps the others' offsets); an offset
    /// on another axis is refused.
    fn dynamic_tool_length(
        &self,
        b: &Block,
        before: &Machine,
    ) -> Result<Option<Vec<(u8, f64)>>, ErrorKind> {
        if b.tool_length() != Some(ToolLength::Dynamic) || !self.p.g43_1_z_only {
            return Ok(None);
        }
        let axes = b.axes();
        let z_alone =
            axes[2].is_some() && axes.iter().enumerate().all(|(a, v)| a == 2 || v.is_none());
        if z_alone {
            return Ok(None);
        }
        let tlo = self.m.tlo;
        if tlo
            .iter()
            .enumerate()
            .any(|(a, v)| a != 2 && v.is_some_and(|v| v != 0.0))
        {
            return Err(self.refuse(
                "G43.1 with an X or other non-Z tool offset",
                "the target's G43.1 takes only Z",
            ));
        }
        // In the units before the block, like the G43 line (see
        // `tool_length_words`).
        let z = tlo[2].ok_or_else(|| ErrorKind::TargetNeedsValue {
            target: self.name(),
            what: "G43.1 without a Z word".into(),
            value: "the tool length offset in effect".into(),
            option: "--tool-table (the tool table of the machine)".into(),
        })?;
        Ok(Some(vec![(b'G', 43.1), (b'Z', z / before.scale())]))
    }

    /// The value written for a kept word: X halved in G7 (in the mode
    /// after the block: a G7 or G8 on the line applies to its X words, as
    /// rs274 has it), an arc's absolute centre as an offset (G90.1
    /// lowered), otherwise as is.
    fn out_value(&self, w: &Word) -> f64 {
        if let Some(c) = &self.centres
            && matches!(w.kind, WordKind::Value)
            && let Some(a) = w.letter.checked_sub(b'I').filter(|&a| a < 3)
            && let Some(v) = c[usize::from(a)]
        {
            return v;
        }
        if w.letter == b'X'
            && matches!(w.kind, WordKind::Value)
            && self.m.modes.lathe == LatheMode::Diameter
            && !self.p.has_g(70)
        {
            return w.value / 2.0;
        }
        w.value
    }

    /// With G95 lowered, feed words become per-minute feeds at the spindle
    /// speed, written whenever they change.
    fn feed_words(
        &mut self,
        b: &Block,
        _before: &Machine,
        fates: &mut [Fate],
        extra: &mut Vec<(u8, f64)>,
    ) {
        if let Some(m) = b.feed_mode() {
            self.target_inverse = m == FeedMode::InverseTime;
        }
        if !self.feed_rewrite {
            return;
        }
        for (i, w) in b.words.iter().enumerate() {
            if w.letter == b'F' && matches!(w.kind, WordKind::Value) {
                fates[i] = Fate::Drop;
            }
        }
        let modes = &self.m.modes;
        let want = match modes.feed_mode {
            FeedMode::PerRev => modes.feed * modes.speed,
            _ => modes.feed,
        };
        let feeds = matches!(
            modes.motion,
            MotionMode::Linear | MotionMode::ArcCw | MotionMode::ArcCcw | MotionMode::Cycle(_)
        ) && b.has_axis();
        if (feeds || b.value(b'F').is_some()) && self.written_feed != Some(want) {
            extra.push((b'F', want));
            self.written_feed = Some(want);
        }
    }

    /// Arcs with P turns, full circles without end point and canned cycles
    /// as plain blocks; `None` when the line's motion is written as is.
    fn lower_motion(
        &mut self,
        b: &Block,
        before: &Machine,
    ) -> Result<Option<Vec<PlainLine>>, ErrorKind> {
        let motion = b.motion().unwrap_or(before.modes.motion);
        let moves = b.has_axis() || b.value(b'@').is_some() || b.value(b'^').is_some();
        let other_axis_use = b.non_modal().is_some_and(|n| !matches!(n, NonModal::Dwell))
            || b.tool_length() == Some(ToolLength::Dynamic);
        match motion {
            MotionMode::Cycle(n) if !self.p.has_g(n as u16 * 10) => {
                if !moves || other_axis_use {
                    return Ok(None);
                }
                self.lower_cycle(n, b, before).map(Some)
            }
            MotionMode::ArcCw | MotionMode::ArcCcw => {
                self.cycles.end();
                let turns = b.value(b'P').map_or(1.0, |p| p.round());
                // A full circle or a helix (no axis word of its plane).
                let xyz = [b'X', b'Y', b'Z'].map(|l| b.value(l));
                let ijk_only = !plain::names_plane_axis(xyz, self.m.modes.plane)
                    && (b.value(b'I').is_some()
                        || b.value(b'J').is_some()
                        || b.value(b'K').is_some());
                if !(moves || ijk_only) {
                    // No arc on this line (`G4 P2` under G2 is a dwell):
                    // its P is not turns.
                    return Ok(None);
                }
                let p_ok = self.p.arc_turns;
                // Polar words name the end point (the target has none).
                let polar = b.value(b'@').is_some() || b.value(b'^').is_some();
                if ijk_only || polar || (turns != 1.0 && !p_ok) {
                    if other_axis_use {
                        return Ok(None);
                    }
                    return self.lower_arc(b, before, motion, turns).map(Some);
                }
                if !other_axis_use
                    && b.has_axis()
                    && self.arc_off_target(b, before, &self.m, motion)
                {
                    return self.lower_arc(b, before, motion, turns).map(Some);
                }
                Ok(None)
            }
            MotionMode::Cycle(_) => Ok(None),
            MotionMode::CubicSpline | MotionMode::QuadSpline
                if !self.p.has_g(if motion == MotionMode::CubicSpline {
                    50
                } else {
                    51
                }) =>
            {
                self.cycles.end();
                if other_axis_use || !moves {
                    return Ok(None);
                }
                self.lower_spline(b, before, motion).map(Some)
            }
            MotionMode::Nurbs | MotionMode::NurbsEnd
                if !self
                    .p
                    .has_g(if motion == MotionMode::Nurbs { 52 } else { 53 }) =>
            {
                self.cycles.end();
                self.lower_nurbs_block(b, before, motion)
            }
            MotionMode::Rapid | MotionMode::Linear
                if b.value(b'@').is_some() || b.value(b'^').is_some() =>
            {
                self.cycles.end();
                self.lower_polar(b, before, motion).map(Some)
            }
            _ => {
                if moves && !other_axis_use {
                    self.cycles.end();
                }
                Ok(None)
            }
        }
    }

    fn prog_pos(&self, m: &Machine) -> [Option<f64>; 3] {
        let s = m.scale();
        [
            m.pos[0].map(|v| v / s),
            m.pos[1].map(|v| v / s),
            m.pos[2].map(|v| v / s),
        ]
    }

    fn lower_error(&self, e: lower::LowerError) -> ErrorKind {
        match e {
            lower::LowerError::PositionUnknown { axis } => ErrorKind::TargetNeedsValue {
                target: self.name(),
                what: "this block's lowering".into(),
                value: format!("the current {axis} position"),
                option: format!(
                    "--start-position {axis}… (or --zero-start), or an absolute move first"
                ),
            },
            e => ErrorKind::TargetLowering {
                target: self.name(),
                code: e.code(),
                message: e.to_string(),
            },
        }
    }

    fn plane(m: &Machine) -> Result<Plane, ErrorKind> {
        match m.modes.plane {
            p @ (Plane::XY | Plane::XZ | Plane::YZ) => Ok(p),
            Plane::UV | Plane::WU | Plane::VW => Err(ErrorKind::Unsupported {
                what: "arcs and cycles in the UVW planes are not lowered".into(),
            }),
        }
    }

    fn lower_arc(
        &mut self,
        b: &Block,
        before: &Machine,
        motion: MotionMode,
        turns: f64,
    ) -> Result<Vec<PlainLine>, ErrorKind> {
        let start = self.prog_pos(before);
        let end = self.prog_pos(&self.m);
        let known = |v: [Option<f64>; 3], what: &str| -> Result<[f64; 3], ErrorKind> {
            let mut o = [0.0; 3];
            for i in 0..3 {
                o[i] = v[i].ok_or_else(|| ErrorKind::TargetNeedsValue {
                    target: self.name(),
                    what: format!("this arc's lowering ({what})"),
                    value: format!("the current {} position", ['X', 'Y', 'Z'][i]),
                    option: "--start-position (or --zero-start), or an absolute move first".into(),
                })?;
            }
            Ok(o)
        };
        let start = known(start, "start")?;
        let end = known(end, "end")?;
        let plane = Self::plane(&self.m)?;
        let mut centre = start;
        if let Some(r) = b.value(b'R') {
            // LinuxCNC's centre for the radius (a checked arc), the same
            // whatever the turns: P turns go round it from there.
            let [p, q, _] = plane.axes();
            let arc = CompArc {
                ccw: motion == MotionMode::ArcCcw,
                center: ArcCenter::Radius(r),
                turns: 1,
            };
            let tol = Tolerances::default_for(self.m.modes.units);
            let (c, _) =
                crate::geom::comp::arc_center(&tol, arc, [start[p], start[q]], [end[p], end[q]])
                    .map_err(|_| self.lower_error(lower::LowerError::BadArc))?;
            (centre[p], centre[q]) = (c[0], c[1]);
        }
        let ijk = [b.value(b'I'), b.value(b'J'), b.value(b'K')];
        for i in 0..3 {
            if let Some(v) = ijk[i] {
                centre[i] = match self.m.modes.arc_distance {
                    ArcDistance::Incremental => start[i] + v,
                    ArcDistance::Absolute => v,
                };
            }
        }
        let input = lower::arc::ArcInput {
            plane,
            clockwise: motion == MotionMode::ArcCw,
            start,
            end,
            centre,
            turns: turns.max(1.0) as u32,
            radius_step: self.radius_step(),
        };
        lower::arc::lower_arc(&input).map_err(|e| self.lower_error(e))
    }

    /// The current X Y (program units), which a lowering needs.
    fn xy_known(&self, m: &Machine, what: &str) -> Result<[f64; 2], ErrorKind> {
        let p = self.prog_pos(m);
        let need = |axis: char| ErrorKind::TargetNeedsValue {
            target: self.name(),
            what: what.into(),
            value: format!("the current {axis} position"),
            option: "--start-position (or --zero-start), or an absolute move first".into(),
        };
        Ok([
            p[0].ok_or_else(|| need('X'))?,
            p[1].ok_or_else(|| need('Y'))?,
        ])
    }

    /// G5/G5.1 as G1 segments within the tolerance.
    fn lower_spline(
        &mut self,
        b: &Block,
        before: &Machine,
        motion: MotionMode,
    ) -> Result<Vec<PlainLine>, ErrorKind> {
        if self.m.modes.plane != Plane::XY {
            return Err(self.refuse("a spline outside G17", "LinuxCNC draws them only in XY"));
        }
        let name = if motion == MotionMode::CubicSpline {
            "G5"
        } else {
            "G5.1"
        };
        if self.m.modes.feed_mode == FeedMode::InverseTime {
            return Err(ErrorKind::TargetLowering {
                target: self.name(),
                code: "E1004",
                message: format!(
                    "a spline ({name}) in G93 is not lowered; its segments would each need their own inverse-time feed"
                ),
            });
        }
        let start = self.xy_known(before, &format!("{name} (spline)"))?;
        let end = self.xy_known(&self.m, &format!("{name} (spline)"))?;
        let tol = self.opts.tolerance_mm / self.m.scale();
        let ij = match (b.value(b'I'), b.value(b'J')) {
            (None, None) if motion == MotionMode::CubicSpline => {
                // After a G5, the previous P Q reflected.
                self.last_pq.map(|[p, q]| [-p, -q]).unwrap_or([0.0, 0.0])
            }
            (i, j) => [i.unwrap_or(0.0), j.unwrap_or(0.0)],
        };
        let r = if motion == MotionMode::CubicSpline {
            let pq = [b.value(b'P').unwrap_or(0.0), b.value(b'Q').unwrap_or(0.0)];
            self.last_pq = Some(pq);
            lower::spline::lower_g5(start, ij, pq, end, tol)
        } else {
            lower::spline::lower_g5_1(start, ij, end, tol)
        };
        r.map_err(|e| self.lower_error(e))
    }

    /// G5.2 blocks collect control points (nothing is written for them:
    /// LinuxCNC moves only at G5.3); G5.3 writes the curve as G1 segments
    /// within the tolerance, with the feed in effect. The control points
    /// are the current point (weight P of a first block without X Y, or
    /// one) and each block's X Y (G91: from the point the curve starts at)
    /// with its weight P; the order is 3, or an L above 3.
    fn lower_nurbs_block(
        &mut self,
        b: &Block,
        before: &Machine,
        motion: MotionMode,
    ) -> Result<Option<Vec<PlainLine>>, ErrorKind> {
        let not_lowered = |s: &Self, message: &str| ErrorKind::TargetLowering {
            target: s.name(),
            code: "E1004",
            message: message.into(),
        };
        if motion == MotionMode::NurbsEnd {
            if b.motion() != Some(MotionMode::NurbsEnd) {
                return Ok(None);
            }
            let Some(curve) = self.nurbs.take() else {
                return Err(not_lowered(self, "G5.3 without control points (G5.2)"));
            };
            let tol = self.opts.tolerance_mm / self.m.scale();
            let mut lines = lower::spline::lower_nurbs(&curve.points, curve.order, tol)
                .map_err(|e| self.lower_error(e))?;
            if let Some(first) = lines.first_mut() {
                // The feed the curve runs at (a G5.2 block may have set it).
                first.words.push(lower::Word {
                    letter: b'F',
                    value: self.m.modes.feed,
                });
            }
            if let Some(last) = curve.points.last() {
                let s = self.m.scale();
                self.m.pos[0] = Some(last.x * s);
                self.m.pos[1] = Some(last.y * s);
            }
            return Ok(Some(lines));
        }
        let pending = before.modes.motion == MotionMode::Nurbs && self.nurbs.is_some();
        if pending && b.units().is_some_and(|u| u != before.modes.units) {
            return Err(not_lowered(
                self,
                "G20/G21 between G5.2 and G5.3 is not lowered (LinuxCNC keeps the points already given in the old units)",
            ));
        }
        if b.motion() != Some(MotionMode::Nurbs) && !b.has_axis() {
            return Ok(None);
        }
        // Nothing moves until G5.3.
        self.m.pos = before.pos;
        if self.m.modes.plane != Plane::XY {
            return Err(self.refuse("a NURBS outside G17", "LinuxCNC draws them only in XY"));
        }
        if self.feed_rewrite || self.m.modes.feed_mode != FeedMode::PerMinute {
            return Err(not_lowered(
                self,
                "a NURBS (G5.2) in G93 or G95 is not lowered; the segments are written with a feed per minute",
            ));
        }
        if self.m.modes.lathe == LatheMode::Diameter {
            return Err(not_lowered(
                self,
                "a NURBS (G5.2) in G7 (diameter mode) is not lowered",
            ));
        }
        let fresh = !pending;
        let (x, y) = (b.value(b'X'), b.value(b'Y'));
        if fresh {
            let start = self.xy_known(before, "G5.2 (NURBS)")?;
            let weight = match (x, y, b.value(b'P')) {
                (None, None, Some(p)) if p > 0.0 => p,
                _ => 1.0,
            };
            self.nurbs = Some(NurbsCurve {
                points: vec![lower::spline::NurbsPoint {
                    x: start[0],
                    y: start[1],
                    weight,
                }],
                order: 3,
                start,
            });
        }
        let incremental = self.m.modes.distance == Distance::Incremental;
        if let Some(c) = self.nurbs.as_mut() {
            if let Some(l) = b.value(b'L').map(f64::round)
                && l > 3.0
            {
                c.order = l.min(1000.0) as usize;
            }
            if let (Some(x), Some(y)) = (x, y) {
                let (x, y) = if incremental {
                    (c.start[0] + x, c.start[1] + y)
                } else {
                    (x, y)
                };
                c.points.push(lower::spline::NurbsPoint {
                    x,
                    y,
                    // LinuxCNC takes a missing P as -1 (refused when lowered).
                    weight: b.value(b'P').unwrap_or(-1.0),
                });
            }
        }
        Ok(Some(Vec::new()))
    }

    /// G0/G1 with polar words as G0/G1 X Y (and Z).
    /// The X Y end point of a block with polar words (program units),
    /// which the model then has.
    fn polar_end(&mut self, b: &Block, before: &Machine) -> Result<[f64; 2], ErrorKind> {
        let current = self.xy_known(before, "polar coordinates (@ ^)")?;
        let input = lower::polar::PolarInput {
            distance: self.m.modes.distance,
            current,
            radius: b.value(b'@'),
            angle: b.value(b'^'),
        };
        let [x, y] = lower::polar::polar_target(&input).map_err(|e| self.lower_error(e))?;
        // The model follows the lowered target.
        let s = self.m.scale();
        self.m.pos[0] = Some(x * s);
        self.m.pos[1] = Some(y * s);
        Ok([x, y])
    }

    /// An arc with polar words: its end point is worked out before the
    /// arc is checked and lowered (the model's is not LinuxCNC's).
    fn polar_arc_end(&mut self, b: &Block, before: &Machine) -> Result<(), Problem> {
        let motion = b.motion().unwrap_or(before.modes.motion);
        let other_axis_use = b.non_modal().is_some_and(|n| !matches!(n, NonModal::Dwell))
            || b.tool_length() == Some(ToolLength::Dynamic);
        if !matches!(motion, MotionMode::ArcCw | MotionMode::ArcCcw)
            || other_axis_use
            || b.value(b'@').is_none() && b.value(b'^').is_none()
        {
            return Ok(());
        }
        self.polar_end(b, before)
            .map(|_| ())
            .map_err(|kind| Problem {
                span: g_span(b, 20, 30),
                kind,
            })
    }

    fn lower_polar(
        &mut self,
        b: &Block,
        before: &Machine,
        motion: MotionMode,
    ) -> Result<Vec<PlainLine>, ErrorKind> {
        let [x, y] = self.polar_end(b, before)?;
        let g = if motion == MotionMode::Rapid {
            0.0
        } else {
            1.0
        };
        let mut words = vec![(b'G', g), (b'X', x), (b'Y', y)];
        if b.value(b'Z').is_some()
            && let Some(z) = self.prog_pos(&self.m)[2]
        {
            words.push((b'Z', z));
        }
        Ok(vec![words_line(&words)])
    }

    fn lower_cycle(
        &mut self,
        n: u8,
        b: &Block,
        before: &Machine,
    ) -> Result<Vec<PlainLine>, ErrorKind> {
        use lower::CycleKind as K;
        let kind = match n {
            73 => K::G73,
            81 => K::G81,
            82 => K::G82,
            83 => K::G83,
            84 => K::G84,
            85 => K::G85,
            86 => K::G86,
            87 => K::G87,
            88 => K::G88,
            89 => K::G89,
            _ => return Err(self.refuse(format!("G{n}"), "the target has no such cycle")),
        };
        let block = lower::CycleBlock {
            axes: [b.value(b'X'), b.value(b'Y'), b.value(b'Z')],
            r: b.value(b'R'),
            l: b.value(b'L').map(|l| l.round().max(0.0) as u32),
            p: b.value(b'P'),
            q: b.value(b'Q'),
            ijk: [b.value(b'I'), b.value(b'J'), b.value(b'K')],
            radius: b.value(b'@'),
            angle: b.value(b'^'),
        };
        let m = &self.m.modes;
        let modal = lower::CycleModal {
            plane: Self::plane(&self.m)?,
            distance: m.distance,
            units: m.units,
            retract: m.retract,
            spindle: m.spindle,
        };
        // A series of cycles runs while the motion mode stays a cycle
        // (rs274 keeps its level until a line runs in another mode, G80
        // or a motion code without axis words included).
        if !before.modes.motion.is_canned_cycle() {
            self.cycles.end();
        }
        let pos = self.prog_pos(before);
        let out = self
            .cycles
            .lower(kind, &block, &modal, pos)
            .map_err(|e| self.lower_error(e))?;
        // The model follows LinuxCNC's end position.
        let s = self.m.scale();
        for i in 0..3 {
            self.m.pos[i] = Some(out.end[i] * s);
        }
        Ok(out.lines)
    }
    fn comp_refusal(
        &self,
        span: Option<crate::block::Span>,
        code: &'static str,
        message: &str,
    ) -> Problem {
        Problem {
            span,
            kind: ErrorKind::TargetLowering {
                target: self.name(),
                code,
                message: message.into(),
            },
        }
    }

    /// The first word of `b` that would act while compensation holds a
    /// move back (spindle, coolant, dwell, tools, units, offsets, ...):
    /// the reference runs it only after the held move.
    fn held_action(b: &Block) -> Option<&Word> {
        b.words.iter().find(|w| Self::is_action(w))
    }

    /// Whether `w` acts (or changes how later moves are read) rather than
    /// being part of a compensated move.
    fn is_action(w: &Word) -> bool {
        match w.kind {
            WordKind::G(g) => !matches!(
                g,
                GCode::Motion(
                    MotionMode::Rapid | MotionMode::Linear | MotionMode::ArcCw | MotionMode::ArcCcw
                ) | GCode::Plane(_)
                    | GCode::Distance(_)
                    | GCode::ArcDistance(_)
                    | GCode::CutterComp(_)
                    | GCode::Path(_)
                    | GCode::FeedMode(FeedMode::PerMinute)
            ),
            WordKind::M(m) => !matches!(m, MCode::Pause { .. } | MCode::End { .. }),
            WordKind::Value => !b"XYZIJKRPFN".contains(&w.letter),
        }
    }

    /// Actions written after the held moves, in the program's order, with
    /// the same effect: spindle, coolant, dwell and tool selection (none of
    /// them changes how a later move's words are read).
    fn deferrable(w: &Word) -> bool {
        match w.kind {
            WordKind::G(g) => matches!(g, GCode::NonModal(NonModal::Dwell)),
            WordKind::M(m) => matches!(
                m,
                MCode::Spindle(_) | MCode::Mist | MCode::Flood | MCode::CoolantOff
            ),
            WordKind::Value => matches!(w.letter, b'S' | b'T'),
        }
    }

    /// Cutter compensation on a target without it: the programmed moves
    /// of the blocks run while it is on go to a [`Comp`], and the moves it
    /// releases are written (absolute, each with its block's feed) in place
    /// of the line's motion. `None` when compensation plays no part in `b`.
    fn comp_block(
        &mut self,
        b: &Block,
        before: &Machine,
        fates: &mut [Fate],
    ) -> Result<Option<Vec<PlainLine>>, Problem> {
        if self.p.has_g(410)
            || self.comp.is_none() && b.cutter_comp().is_none() && self.after_off.is_none()
        {
            return Ok(None);
        }
        let cc_span = b
            .g_codes()
            .find(|(g, _)| matches!(g, GCode::CutterComp(_)))
            .map(|(_, w)| w.span);
        let motion_span = b
            .g_codes()
            .find(|(g, _)| matches!(g, GCode::Motion(_)))
            .map(|(_, w)| w.span);
        let moves = b.has_axis();
        let other_axis_use = b.non_modal().is_some_and(|n| !matches!(n, NonModal::Dwell))
            || b.tool_length() == Some(ToolLength::Dynamic);
        let motion = self.m.modes.motion;
        if !moves && self.tool_change_after_off(b) {
            return Ok(None);
        }
        if self.comp.as_ref().is_some_and(|c| c.comp.holding())
            && let Some(w) = Self::held_action(b)
        {
            // LinuxCNC runs the block's actions after the held moves: the
            // line waits for them. What would change how later moves are
            // read (units, offsets, tools) is not lowered.
            if let Some(w) = b
                .words
                .iter()
                .find(|w| Self::is_action(w) && !Self::deferrable(w))
            {
                return Err(self.comp_refusal(
                    Some(w.span),
                    "E1180",
                    "while cutter compensation holds a move back (until the next move is known), LinuxCNC runs this only after that move; only spindle, coolant, dwell and tool selection are lowered there: put it before G41/G42 or after G40",
                ));
            }
            let _ = w;
            self.defer_block = Some(self.comp_seq);
        }
        for (i, w) in b.words.iter().enumerate() {
            if matches!(w.kind, WordKind::G(GCode::CutterComp(_))) {
                fates[i] = Fate::Drop;
            }
        }
        let mut released: Vec<Out<MoveTag>> = Vec::new();
        let mut lines: Vec<PlainLine> = Vec::new();
        let mut handled = false;
        // G40 comes before the block's motion.
        if b.cutter_comp() == Some(CutterComp::Off)
            && let Some(mut c) = self.comp.take()
        {
            c.comp
                .off(&mut released)
                .map_err(|e| self.comp_problem(cc_span, e))?;
            let at = self.write_released(&mut c, &released, &mut lines, motion_span)?;
            released.clear();
            self.after_off = Some(at);
            handled = true;
        }
        if let Some(cc) = b.cutter_comp().filter(|c| *c != CutterComp::Off) {
            for (i, w) in b.words.iter().enumerate() {
                if matches!(w.kind, WordKind::Value) && matches!(w.letter, b'D' | b'L') {
                    fates[i] = Fate::Drop;
                }
            }
            self.comp_on(b, before, cc, cc_span)?;
            handled = true;
        }
        if let Some(mut c) = self.comp.take() {
            let r = self.comp_move(
                &mut c,
                b,
                motion,
                moves,
                other_axis_use,
                motion_span,
                &mut lines,
            );
            self.comp = Some(c);
            if r? {
                handled = true;
            }
        } else if self.after_off.is_some() && (moves || other_axis_use) {
            let other_axis_use = other_axis_use && !self.g53_after_off(b, fates);
            lines.push(self.after_off_move(motion, other_axis_use, motion_span)?);
            self.released_seqs.push(u64::MAX);
            handled = true;
        }
        // Program stops release the held moves (an end also turns
        // compensation off).
        let stop = b.m_codes().find_map(|(m, _)| match m {
            MCode::Pause { .. } => Some(false),
            MCode::End { .. } => Some(true),
            _ => None,
        });
        if let Some(end) = stop
            && let Some(mut c) = self.comp.take()
        {
            c.comp
                .stop(end, &mut released)
                .map_err(|e| self.comp_problem(None, e))?;
            self.write_released(&mut c, &released, &mut lines, None)?;
            if !end {
                self.comp = Some(c);
            }
            handled = true;
        }
        if stop == Some(true) {
            self.after_off = None;
        }
        if self.comp.is_some() || handled {
            // Each compensated feed move carries its own F.
            for (i, w) in b.words.iter().enumerate() {
                if w.letter == b'F' && matches!(w.kind, WordKind::Value) {
                    fates[i] = Fate::Drop;
                }
            }
        }
        Ok(handled.then_some(lines))
    }

    /// A tool change after G40: the reference reads the position back
    /// from the machine, so the tool is where the compensated path left it
    /// and later moves start from there. Whether `b` was one.
    fn tool_change_after_off(&mut self, b: &Block) -> bool {
        if !b.m_codes().any(|(m, _)| matches!(m, MCode::ToolChange)) {
            return false;
        }
        let Some(at) = self.after_off.take() else {
            return false;
        };
        let s = self.m.scale();
        for (p, v) in self.m.pos.iter_mut().zip(at) {
            *p = Some(v * s);
        }
        true
    }

    /// A G53 move as the first move after G40 goes to a machine point: it
    /// is written in work coordinates with every axis, when they are all
    /// known (its G53 dropped). Whether it is.
    fn g53_after_off(&self, b: &Block, fates: &mut [Fate]) -> bool {
        let g53 = b.non_modal() == Some(NonModal::MachineCoords)
            && self.prog_pos(&self.m).iter().all(Option::is_some);
        if g53 {
            for (i, w) in b.words.iter().enumerate() {
                if matches!(
                    w.kind,
                    WordKind::G(GCode::NonModal(NonModal::MachineCoords))
                ) {
                    fates[i] = Fate::Drop;
                }
            }
        }
        g53
    }

    /// The first move after G40: from where the compensated path ended to
    /// the programmed point, with every axis (and the program's feed).
    fn after_off_move(
        &mut self,
        motion: MotionMode,
        other_axis_use: bool,
        motion_span: Option<crate::block::Span>,
    ) -> Result<PlainLine, Problem> {
        if other_axis_use || !matches!(motion, MotionMode::Rapid | MotionMode::Linear) {
            return Err(self.comp_refusal(
                motion_span,
                "E1181",
                "the first move after G40 starts where the compensated path ended and must be G0 or G1 to be lowered",
            ));
        }
        let end = self.prog_pos(&self.m);
        let mut words = vec![(
            b'G',
            if motion == MotionMode::Rapid {
                0.0
            } else {
                1.0
            },
        )];
        for (i, l) in [b'X', b'Y', b'Z'].into_iter().enumerate() {
            if let Some(v) = end[i] {
                words.push((l, v));
            }
        }
        if self.last_f != self.comp_f
            && let Some(f) = self.last_f
        {
            // The feed as the program has it (compensated moves wrote
            // their own).
            words.push((b'F', f));
            self.comp_f = self.last_f;
        }
        self.after_off = None;
        self.cycles.end();
        Ok(words_line(&words))
    }

    fn comp_problem(
        &self,
        span: Option<crate::block::Span>,
        error: crate::geom::comp::CompError,
    ) -> Problem {
        Problem {
            span,
            kind: ErrorKind::CutterComp { error },
        }
    }

    /// Writes `released` (plain blocks, feeds on G1/G2/G3) into `lines`;
    /// returns where the tool is after them.
    fn write_released(
        &mut self,
        c: &mut CompPath,
        released: &[Out<MoveTag>],
        lines: &mut Vec<PlainLine>,
        span: Option<crate::block::Span>,
    ) -> Result<[f64; 3], Problem> {
        let (out, at) = lower::comp::lower_comp_moves(
            c.plane,
            c.at,
            released,
            lower::comp::arc_radius_tolerance(self.m.modes.units),
        )
        .map_err(|e| Problem {
            span,
            kind: self.lower_error(e),
        })?;
        for (mut l, (feed, seq)) in out {
            self.released_seqs.push(*seq);
            let feeds = l
                .words
                .first()
                .is_some_and(|w| w.letter == b'G' && w.value != 0.0);
            if feeds
                && *feed != self.comp_f
                && let Some(f) = *feed
            {
                l.words.push(lower::Word {
                    letter: b'F',
                    value: f,
                });
                self.comp_f = Some(f);
            }
            lines.push(l);
        }
        c.at = at;
        Ok(at)
    }

    /// G41/G42/G41.1/G42.1 on block `b`.
    fn comp_on(
        &mut self,
        b: &Block,
        before: &Machine,
        cc: CutterComp,
        span: Option<crate::block::Span>,
    ) -> Result<(), Problem> {
        let need = |s: &Self, value: &str, option: &str| Problem {
            span,
            kind: ErrorKind::TargetNeedsValue {
                target: s.name(),
                what: "cutter radius compensation (computed into the path)".into(),
                value: value.into(),
                option: option.into(),
            },
        };
        let xz = match self.m.modes.plane {
            Plane::XY => false,
            Plane::XZ => true,
            _ => {
                return Err(Problem {
                    span,
                    kind: ErrorKind::Unsupported {
                        what: "cutter radius compensation outside G17 and G18 is not lowered"
                            .into(),
                    },
                });
            }
        };
        if self.feed_rewrite || self.m.modes.feed_mode != FeedMode::PerMinute {
            return Err(self.comp_refusal(
                span,
                "E1182",
                "compensated moves are written with feeds per minute; G93/G95 with cutter radius compensation is not lowered",
            ));
        }
        let side = if matches!(cc, CutterComp::Left | CutterComp::DynamicLeft) {
            Side::Left
        } else {
            Side::Right
        };
        let metric = self.m.modes.units == Units::Mm;
        let (radius, orientation) =
            if matches!(cc, CutterComp::DynamicLeft | CutterComp::DynamicRight) {
                let Some(d) = b.value(b'D') else {
                    return Err(need(self, "the tool's diameter", "a D word on G41.1/G42.1"));
                };
                (d / 2.0, b.value(b'L').map_or(0, |l| l.round() as i32))
            } else {
                let t = b
                    .value(b'D')
                    .map(|d| (d + 0.5) as i64)
                    .or(self.m.current_tool());
                let data = t.and_then(|t| match self.m.tools.table.get(&t) {
                    Some(d) => Some((d.diameter, d.orientation.round() as i32)),
                    None if self.standalone_tools => {
                        Some((crate::eval::tools::standalone_diameter(t), 0))
                    }
                    None if self.m.tools.known || t == 0 => Some((0.0, 0)),
                    None => None,
                });
                let Some((diameter, o)) = data else {
                    return Err(need(
                        self,
                        "the tool's diameter",
                        "--tool-table (the tool table of the machine), or --zero-start",
                    ));
                };
                // Machine units to program units as the reference computes it
                // (through millimetres).
                let mm = if self.m.machine_metric {
                    diameter
                } else {
                    diameter / 0.03937007874016
                };
                let v = if metric { mm } else { mm / 25.4 };
                (v / 2.0, o)
            };
        let plane = if xz { Plane::XZ } else { Plane::XY };
        let s = self.m.scale();
        let p = before.pos;
        let (Some(x), Some(y), Some(z)) = (p[0], p[1], p[2]) else {
            return Err(need(
                self,
                "the current position",
                "--start-position (or --zero-start), or an absolute move first",
            ));
        };
        let xyz = [x / s, y / s, z / s];
        let pos = if xz { [xyz[2], xyz[0], xyz[1]] } else { xyz };
        let mut comp = Comp::new(Tolerances::default_for(self.m.modes.units));
        comp.start(side, radius, orientation, xz, pos);
        if self.after_off.is_none() {
            self.comp_f = self.f_before;
        }
        let at = self.after_off.take().unwrap_or(xyz);
        self.comp = Some(Box::new(CompPath { comp, plane, at }));
        Ok(())
    }

    /// The move of block `b` while compensation is on. Returns whether the
    /// block's motion was taken.
    #[allow(clippy::too_many_arguments)]
    fn comp_move(
        &mut self,
        c: &mut CompPath,
        b: &Block,
        motion: MotionMode,
        moves: bool,
        other_axis_use: bool,
        span: Option<crate::block::Span>,
        lines: &mut Vec<PlainLine>,
    ) -> Result<bool, Problem> {
        let arc = matches!(motion, MotionMode::ArcCw | MotionMode::ArcCcw);
        let ijk_only = !moves
            && (b.value(b'I').is_some() || b.value(b'J').is_some() || b.value(b'K').is_some());
        if other_axis_use
            || (moves || ijk_only)
                && !matches!(motion, MotionMode::Rapid | MotionMode::Linear)
                && !arc
            || b.words
                .iter()
                .any(|w| matches!(w.kind, WordKind::Value) && b"ABCUVW".contains(&w.letter))
        {
            return Err(self.comp_refusal(
                span,
                "E1181",
                "with cutter radius compensation on, only G0, G1, G2 and G3 moves in X Y Z (with an end point) are lowered",
            ));
        }
        // An arc with I J K alone is a full circle back to where it starts.
        if !(moves || arc && ijk_only) {
            return Ok(false);
        }
        if b.units().is_some() && c.comp.holding() {
            return Err(self.comp_refusal(
                span,
                "E1180",
                "G20/G21 while a compensated move is held is not lowered",
            ));
        }
        let e = self.prog_pos(&self.m);
        let (Some(x), Some(y), Some(z)) = (e[0], e[1], e[2]) else {
            return Err(self.comp_refusal(
                span,
                "E1181",
                "the end of a compensated move is not known",
            ));
        };
        let xz = c.plane == Plane::XZ;
        let end = if xz { [z, x, y] } else { [x, y, z] };
        self.comp_seq += 1;
        let feed = (self.last_f, self.comp_seq);
        let mut released = Vec::new();
        let r = if arc {
            let center = match b.value(b'R') {
                Some(r) => ArcCenter::Radius(r),
                None => {
                    let (i, j) = if xz {
                        (b.value(b'K'), b.value(b'I'))
                    } else {
                        (b.value(b'I'), b.value(b'J'))
                    };
                    ArcCenter::Offsets {
                        i: i.unwrap_or(0.0),
                        j: j.unwrap_or(0.0),
                        distance: self.m.modes.arc_distance,
                    }
                }
            };
            let turns = b.value(b'P').map_or(1, |p| p.round() as i32);
            let a = CompArc {
                ccw: motion == MotionMode::ArcCcw,
                center,
                turns,
            };
            c.comp.arc(a, end, feed, &mut released)
        } else {
            c.comp
                .straight(motion == MotionMode::Rapid, end, feed, &mut released)
        };
        r.map_err(|e| self.comp_problem(span, e))?;
        self.cycles.end();
        self.write_released(c, &released, lines, span)?;
        Ok(true)
    }
}

/// 0, 1, 2 for X, Y, Z.
fn xyz_index(letter: u8) -> Option<usize> {
    match letter {
        b'X' => Some(0),
        b'Y' => Some(1),
        b'Z' => Some(2),
        _ => None,
    }
}

/// A lowered (absolute) line with `shift` (mm) added to its X Y Z.
fn shift_line(l: &PlainLine, shift: [f64; 3], scale: f64) -> PlainLine {
    let mut l = l.clone();
    for w in &mut l.words {
        if let Some(a) = xyz_index(w.letter) {
            w.value += shift[a] / scale;
        }
    }
    l
}

fn words_line(l: &[(u8, f64)]) -> PlainLine {
    PlainLine {
        words: l
            .iter()
            .map(|&(letter, value)| lower::Word { letter, value })
            .collect(),
    }
}

fn g_span(b: &Block, a: u16, c: u16) -> Option<crate::block::Span> {
    b.words
        .iter()
        .find(|w| matches!(w.kind, WordKind::G(_)) && (code10(w) == a || code10(w) == c))
        .map(|w| w.span)
}

#[allow(dead_code)]
fn comment_kind_is_message(k: CommentKind) -> bool {
    k == CommentKind::Message
}

#[allow(dead_code)]
fn spindle_mode(_: SpindleMode) {}
