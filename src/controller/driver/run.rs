//! Running a decoded block the general way: its words decided
//! ([`super::fates`]), the block run on the machine model, the rewrites
//! that need the state after it, its motion replaced by compensated or
//! lowered moves where needed, and the target's lines put together (lines
//! before it, its own line with the values written for its words and
//! rewritten feeds, the lowered lines, lines after it).

use crate::block::{
    Block, Distance, FeedMode, GCode, LatheMode, MCode, MotionMode, NonModal, ToolLength, Word,
    WordKind,
};
use crate::controller::format::AxisWords;
use crate::controller::lower::{self, PlainLine};
use crate::diag::{Diagnostic, Error, ErrorKind};
use crate::emit::Output;
use crate::eval::Origin;
use crate::machine::FlatMachine;

use super::fates::{Decided, Fate, code10, g_span};
use super::offsets::{shift_line, xyz_index};
use super::report::{LINE_START, site_of};
use super::{Lowering, Problem, io_error};

impl Lowering {
    /// Runs and writes the decoded line `b` (the short way when it is
    /// plain); the problems found.
    pub(super) fn run_block(
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
        let mut problems = Vec::new();
        let mut d = Decided {
            fates: vec![Fate::Keep; b.words.len()],
            extra: Vec::new(),
            extra_lines: Vec::new(),
            pre_lines: Vec::new(),
        };
        for (i, w) in b.words.iter().enumerate() {
            let fate = match w.kind {
                WordKind::G(g) => self.g_fate(b, w, g, &mut problems),
                WordKind::M(m) => {
                    self.m_fate(b, w, m, &mut problems, &mut d.pre_lines, &mut d.extra_lines)
                }
                WordKind::Value => self.value_fate(w, &mut problems),
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
        before: &FlatMachine,
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
        self.feed_words(b, &mut d.fates, &mut d.extra);
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
    fn state_lines(
        &mut self,
        b: &Block,
        before: &FlatMachine,
        d: &mut Decided,
    ) -> Result<(), Problem> {
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
            // LinuxCNC's own refusal at the line, as the evaluator reports
            // it; the target's at the probe code.
            let span = if matches!(k, ErrorKind::Block(_)) {
                Some(LINE_START)
            } else {
                b.g_codes()
                    .find(|(g, _)| matches!(g, GCode::Motion(MotionMode::Probe(_))))
                    .map(|(_, w)| w.span)
            };
            return Err(Problem { span, kind: k });
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
                Ok(ws) if ws.is_empty() => {}
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
        before: &FlatMachine,
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

    /// Writes a lowered block; a code the target lacks is refused.
    fn plain_line(&mut self, l: &PlainLine, buf: &mut Vec<u8>) -> Option<ErrorKind> {
        for w in &l.words {
            let ok = match w.letter {
                b'G' => self.p.has_g((w.value * 10.0).round() as u16),
                b'M' => {
                    let m = w.value.round() as u16;
                    // The firmware's own pause code (M600, M226) is no
                    // LinuxCNC code; M0 must be among the codes.
                    self.p.has_m(m) || m == self.p.pause && m >= 200
                }
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

    /// The value written for a kept word: X halved in G7 (in the mode
    /// after the block: a G7 or G8 on the line applies to its X words, as
    /// rs274 has it), an arc's absolute centre as an offset (G90.1
    /// lowered), otherwise as is.
    pub(super) fn out_value(&self, w: &Word) -> f64 {
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
    fn feed_words(&mut self, b: &Block, fates: &mut [Fate], extra: &mut Vec<(u8, f64)>) {
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
}

pub(super) fn words_line(l: &[(u8, f64)]) -> PlainLine {
    PlainLine {
        words: l
            .iter()
            .map(|&(letter, value)| lower::Word { letter, value })
            .collect(),
    }
}
