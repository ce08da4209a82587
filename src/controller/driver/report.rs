//! Refusals, warnings and where problems are reported: the errors the
//! driver makes (a word the target refuses and why, a lowering that
//! failed), warnings given once each, the one whole-block check that
//! refuses (a probe to where the tool already is), and the site on the
//! source line each problem is reported at (stopping at the first, or all
//! of them kept in check mode).

use crate::diag::{SetupError, TargetError};
use std::sync::Arc;

use crate::block::{Block, DecodeError, MotionMode, NonModal, ToolLength};
use crate::controller::lower;
use crate::diag::{BlockError, Diagnostic, Error, ErrorKind, Site, WarningKind};
use crate::eval::Origin;
use crate::machine::FlatMachine;
use crate::program::SourceFile;

use super::{Lowering, Problem};

/// A problem's span that stands for the start of its line, where the
/// evaluator reports an error of the block (an arc rs274 refuses).
pub(super) const LINE_START: crate::block::BlockSpan = crate::block::BlockSpan {
    start: u16::MAX,
    end: u16::MAX,
};

impl Lowering {
    pub(super) fn refuse(&self, what: impl Into<String>, why: impl Into<String>) -> ErrorKind {
        ErrorKind::Target(TargetError::TargetRefused {
            target: self.name(),
            what: what.into(),
            why: why.into(),
        })
    }

    /// A warning about the current line; it gets the line's site when the
    /// line is done (worked out only then, and only for a warning not given
    /// before).
    pub(super) fn warn(&mut self, kind: WarningKind) {
        let key = (kind.code(), kind.to_string());
        if self.warned.insert(key) {
            self.pending.push(kind);
        }
    }

    pub(super) fn dropped(&mut self, what: &str, why: &str) {
        let k = WarningKind::TargetDropped {
            target: self.name(),
            what: what.into(),
            why: why.into(),
        };
        self.warn(k);
    }

    /// Stops the run at the first problem, or in check mode keeps them all.
    pub(super) fn report(
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

    /// GRBL and its descendants refuse a probe move whose target is the
    /// current position (error 33); LinuxCNC runs it as a move of length
    /// zero. Checked where both points are known: under `--zero-start` a
    /// probe is taken as not tripping, so a second probe to the same
    /// target is refused too.
    pub(super) fn probe_in_place(&self, b: &Block, before: &FlatMachine) -> Option<ErrorKind> {
        let motion = b.motion().unwrap_or(before.modes.motion);
        if !matches!(motion, MotionMode::Probe(_))
            || !b.has_axis()
            || b.non_modal().is_some_and(|n| !matches!(n, NonModal::Dwell))
            || b.tool_length() == Some(ToolLength::Dynamic)
        {
            return None;
        }
        // G38.2/G38.4 to the point the tool is at: LinuxCNC refuses it
        // itself, with its own error (a G38.3/G38.5 it runs).
        if matches!(motion, MotionMode::Probe(2 | 4)) {
            let to = before.target(b);
            let axes = b.axes();
            let here = (0..3).filter(|&a| axes[a].is_some()).all(
                |a| matches!((before.pos[a], to[a]), (Some(f), Some(t)) if (f - t).abs() < 1e-7),
            );
            if here && (0..3).any(|a| axes[a].is_some()) {
                return Some(ErrorKind::Block(BlockError::ProbeTooClose));
            }
        }
        // Where the probe ends if it does not trip (the model forgets the
        // position after a probe unless the probe is taken as not tripping).
        let mut m = before.clone();
        m.zero_start = true;
        m.apply(b);
        // The target's own axes must be known and unmoved; the others
        // cannot be written for it anyway.
        let mut sq = 0.0;
        for (_, (a, z)) in crate::block::AXIS_LETTERS
            .iter()
            .zip(before.pos.iter().zip(m.pos.iter()))
            .filter(|(l, _)| self.p.has_axis(**l))
        {
            match (a, z) {
                (Some(a), Some(z)) => sq += (a - z) * (a - z),
                _ => return None,
            }
        }
        let travel = f64::sqrt(sq);
        if travel < 1e-9 {
            return Some(ErrorKind::Target(TargetError::TargetProbeInPlace {
                target: self.name(),
                how: self.p.probe_in_place.as_str(),
            }));
        }
        (travel < self.p.min_probe_travel).then(|| {
            ErrorKind::Target(TargetError::TargetProbeTooShort {
                target: self.name(),
                travel: crate::emit::number_string(travel, Some(4)),
                min: crate::emit::number_string(self.p.min_probe_travel, None),
            })
        })
    }

    pub(super) fn lower_error(&self, e: lower::LowerError) -> ErrorKind {
        match e {
            lower::LowerError::PositionUnknown { axis } => {
                ErrorKind::Target(TargetError::TargetNeedsValue {
                    target: self.name(),
                    what: "this block's lowering".into(),
                    value: format!("the current {axis} position"),
                    option: format!(
                        "--start-position {axis}… (or --zero-start), or an absolute move first"
                    ),
                })
            }
            e => ErrorKind::TargetLowering {
                target: self.name(),
                code: e.code(),
                message: e.to_string(),
            },
        }
    }
}

/// The site of `span` of a flat line from `origin`: exact on a line written
/// as read; otherwise the same-lettered word of the source line (by its
/// rank), or the whole line; [`LINE_START`] where the line starts.
pub(super) fn site_of(
    origin: &Origin<'_>,
    text: &[u8],
    span: Option<crate::block::BlockSpan>,
) -> Site {
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

pub(super) fn decode_problem(e: DecodeError) -> Problem {
    Problem {
        span: Some(e.span),
        kind: ErrorKind::Setup(SetupError::Unsupported {
            what: format!("cannot read this flattened line: {}", e.what),
        }),
    }
}
