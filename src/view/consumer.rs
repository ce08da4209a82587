//! The line consumer that connects the evaluator's output to the machine
//! model and to what looks at the motion: the travel-limit check, the
//! statistics and picture, the source map and `--annotate`.

use crate::diag::SetupError;
use std::io::Write;

use std::collections::VecDeque;

use super::run::Observer;
use super::source_map::{Locator, NoteRules, Place, SourceMap, annotation, time_note};
use crate::block::Block;
use crate::diag::{Diagnostic, Error, ErrorKind, Site};
use crate::emit::Output;
use crate::eval::{LineConsumer, Origin};
use crate::machine::model::FlatMachine;
use crate::settings::Settings;

/// Where the source map goes.
pub(crate) type MapSink = SourceMap<std::io::BufWriter<std::fs::File>>;

pub(crate) struct ViewConsumer<'a> {
    machine: Option<FlatMachine>,
    block: Block,
    pub observer: &'a mut Observer,
    /// Write each line to the output (flattening; not for stats and plot).
    pass_through: bool,
    pub source_map: Option<MapSink>,
    annotate: Option<Locator>,
    /// What an annotation may hold, for the controller reading the output.
    notes: NoteRules,
    /// Where the last line came from: the lines a target's lowering writes
    /// at the program's end are mapped there.
    last: Option<(Place, Vec<Place>)>,
    buf: Vec<u8>,
    /// The consumer that writes the output for a target controller: it gets
    /// every line after this one has looked at it.
    next: Option<Box<dyn LineConsumer + 'a>>,
    /// The planned time of every line, for the source map and annotations:
    /// lines wait here until the planner has fixed their time.
    timing: Option<Timing>,
}

/// Lines held until their planned time is final (at most the planner's
/// look-ahead behind).
struct Timing {
    run_time: crate::runtime::RunTime,
    lines: u64,
    held: VecDeque<Held>,
}

/// An output line waiting for its time.
struct Held {
    text: Vec<u8>,
    at: Place,
    calls: Vec<Place>,
}

impl<'a> ViewConsumer<'a> {
    /// `observer` sees the motion of every line; `pass_through` writes the
    /// lines to the output; `annotate` appends their origin (and, with a
    /// `timing` model, their planned time) as a comment; the source map
    /// gets each line's time from `timing` too.
    pub(crate) fn new(
        settings: &Settings,
        observer: &'a mut Observer,
        pass_through: bool,
        source_map: Option<MapSink>,
        annotate: bool,
        timing: Option<crate::runtime::TimeModel>,
    ) -> ViewConsumer<'a> {
        let timing = timing
            .filter(|_| source_map.is_some() || annotate)
            .map(|m| Timing {
                run_time: crate::runtime::RunTime::new(m),
                lines: 0,
                held: VecDeque::new(),
            });
        ViewConsumer {
            machine: (observer.is_active() || timing.is_some()).then(|| FlatMachine::new(settings)),
            timing,
            block: Block::default(),
            observer,
            pass_through,
            source_map,
            annotate: annotate.then(Locator::default),
            notes: NoteRules::linuxcnc(),
            last: None,
            buf: Vec::new(),
            next: None,
        }
    }

    /// Annotations follow `rules` (a target controller's).
    pub(crate) fn with_notes(mut self, rules: NoteRules) -> ViewConsumer<'a> {
        self.notes = rules;
        self
    }

    /// Whether this consumer writes the lines it is given.
    pub(crate) fn writes(&self) -> bool {
        self.pass_through
    }

    /// A line that has no place in the program (written by a target's
    /// lowering when the program ended), written out: mapped to where the
    /// last line came from.
    pub(crate) fn end_line(&mut self, text: &[u8], out: &mut Output) -> Result<(), Error> {
        if let Some(t) = &mut self.timing {
            t.lines += 1;
            t.run_time.line(t.lines);
        }
        self.block_line(text)?;
        let Some((at, calls)) = self.last.clone() else {
            return out.line(text).map_err(crate::eval::output_error);
        };
        if let Some(t) = &mut self.timing {
            t.held.push_back(Held {
                text: text.to_vec(),
                at,
                calls,
            });
            return Ok(());
        }
        self.write_now(text, &at, &calls, out)
    }

    /// Writes a line with its source-map entry and annotation, no time.
    fn write_now(
        &mut self,
        text: &[u8],
        at: &Place,
        calls: &[Place],
        out: &mut Output,
    ) -> Result<(), Error> {
        if let Some(sm) = &mut self.source_map {
            sm.line(at, calls, None)
                .map_err(|e| io_error("<source map>", e))?;
        }
        if let Some(loc) = &mut self.annotate {
            let a = loc.locate(at);
            let c: Vec<_> = calls.iter().map(|p| loc.locate(p)).collect();
            let note = annotation(&a, &c, &self.notes);
            // Never past the line limit: the comment is left off a line it
            // would make too long.
            if self.notes.fits(text.len(), note.len()) && text.first() != Some(&b'%') {
                self.buf.clear();
                self.buf.extend_from_slice(text);
                self.buf.extend_from_slice(note.as_bytes());
                if self.pass_through {
                    return out.line(&self.buf).map_err(crate::eval::output_error);
                }
                return Ok(());
            }
        }
        if self.pass_through {
            out.line(text).map_err(crate::eval::output_error)?;
        }
        Ok(())
    }

    /// Hands every line on to `next` (which writes the output) after
    /// looking at it.
    pub(crate) fn then(mut self, next: Option<Box<dyn LineConsumer + 'a>>) -> ViewConsumer<'a> {
        self.next = next;
        self
    }

    /// The motion of a line that has no place in the program (written by
    /// a target's lowering when the program ended).
    pub(crate) fn block_line(&mut self, text: &[u8]) -> Result<(), Error> {
        let Some(m) = &mut self.machine else {
            return Ok(());
        };
        if let Err(e) = self.block.decode_into(text) {
            let what = format!(
                "the machine model cannot read the output line '{}' ({})",
                String::from_utf8_lossy(text),
                e.what
            );
            return Err(Diagnostic::error(
                ErrorKind::Setup(SetupError::Internal { what }),
                None,
            ));
        }
        m.apply(&self.block);
        for ev in m.take_events() {
            self.observer
                .motion(&ev)
                .map_err(|kind| Diagnostic::error(kind, None))?;
        }
        Ok(())
    }

    fn places(origin: &Origin<'_>) -> (Place, Vec<Place>) {
        let at = Place {
            file: origin.file.clone(),
            offset: origin.line_start,
        };
        let calls = (origin.stack)()
            .into_iter()
            .map(|s| Place {
                file: s.file,
                offset: s.start,
            })
            .collect();
        (at, calls)
    }
}

impl LineConsumer for ViewConsumer<'_> {
    fn line(&mut self, text: &[u8], origin: &Origin<'_>, out: &mut Output) -> Result<(), Error> {
        if let Some(t) = &mut self.timing {
            t.lines += 1;
            t.run_time.line(t.lines);
        }
        if let Some(m) = &mut self.machine {
            // Every line the evaluator writes is one it has checked and the
            // block decoder reads; one it cannot read is a fault of ngcflat,
            // not of the program, and the motion must not be skipped.
            if let Err(e) = self.block.decode_into(text) {
                let mut d = Diagnostic::error(
                    ErrorKind::Setup(SetupError::Internal {
                        what: format!(
                            "the machine model cannot read the output line '{}' ({})",
                            String::from_utf8_lossy(text),
                            e.what
                        ),
                    }),
                    Some(line_site(origin)),
                );
                d.stack = (origin.stack)();
                return Err(d);
            } else {
                self.observer.line(text, origin);
                m.apply(&self.block);
                for ev in m.take_events() {
                    if let Some(t) = &mut self.timing {
                        t.run_time.motion(&ev);
                    }
                    if let Err(kind) = self.observer.motion(&ev) {
                        let mut d = Diagnostic::error(kind, Some(line_site(origin)));
                        d.stack = (origin.stack)();
                        return Err(d);
                    }
                }
            }
        }
        if let Some(n) = &mut self.next {
            return n.line(text, origin, out);
        }
        if let Some(t) = &mut self.timing {
            let (at, calls) = Self::places(origin);
            self.last = Some((at.clone(), calls.clone()));
            t.held.push_back(Held {
                text: text.to_vec(),
                at,
                calls,
            });
            return self.release(out, false);
        }
        if self.source_map.is_some() || self.annotate.is_some() {
            let (at, calls) = Self::places(origin);
            self.write_now(text, &at, &calls, out)?;
            self.last = Some((at, calls));
            return Ok(());
        }
        if self.pass_through {
            out.line(text).map_err(crate::eval::output_error)?;
        }
        Ok(())
    }

    fn computes_comp(&self) -> bool {
        self.next.as_ref().is_some_and(|n| n.computes_comp())
    }

    fn comp_position(&mut self, p: [f64; 2]) {
        if let Some(n) = &mut self.next {
            n.comp_position(p);
        }
    }

    fn finish(&mut self, out: &mut Output) -> Result<Vec<Diagnostic>, Error> {
        if let Some(t) = &mut self.timing {
            t.run_time.finish();
            self.release(out, true)?;
        }
        if let Some(sm) = self.source_map.as_mut() {
            sm.flush().map_err(|e| io_error("<source map>", e))?;
        }
        match &mut self.next {
            Some(n) => n.finish(out),
            None => Ok(Vec::new()),
        }
    }
}

impl ViewConsumer<'_> {
    /// Writes the held lines whose planned time is final (all of them at
    /// the end), with their source-map entries and annotations.
    fn release(&mut self, out: &mut Output, all: bool) -> Result<(), Error> {
        let Some(t) = &mut self.timing else {
            return Ok(());
        };
        loop {
            let time = t.run_time.next_line();
            if time.is_none() && (!all || t.held.is_empty()) {
                return Ok(());
            }
            let Some(h) = t.held.pop_front() else {
                return Ok(());
            };
            if let Some(sm) = &mut self.source_map {
                sm.line(&h.at, &h.calls, time)
                    .map_err(|e| io_error("<source map>", e))?;
            }
            let mut line: &[u8] = &h.text;
            if let Some(loc) = &mut self.annotate {
                let a = loc.locate(&h.at);
                let c: Vec<_> = h.calls.iter().map(|p| loc.locate(p)).collect();
                let mut note = annotation(&a, &c, &self.notes);
                if let Some(lt) = &time {
                    note.push_str(&time_note(lt));
                }
                // Never past the line limit: the comment is left off a line
                // it would make too long.
                if self.notes.fits(h.text.len(), note.len()) && h.text.first() != Some(&b'%') {
                    self.buf.clear();
                    self.buf.extend_from_slice(&h.text);
                    self.buf.extend_from_slice(note.as_bytes());
                    line = &self.buf;
                }
            }
            if self.pass_through {
                out.line(line).map_err(crate::eval::output_error)?;
            }
        }
    }
}

/// The source line that made an output line, from its first non-blank
/// character to its end.
fn line_site(origin: &Origin<'_>) -> Site {
    let lc = origin.file.locate(origin.line_start);
    let line = &lc.text[..lc
        .text
        .iter()
        .position(|&b| b == b'\n')
        .unwrap_or(lc.text.len())];
    let lead = line.iter().take_while(|b| b.is_ascii_whitespace()).count();
    let body = line
        .iter()
        .rposition(|b| !b.is_ascii_whitespace())
        .map_or(lead, |p| p + 1);
    Site::new(
        origin.file,
        origin.line_start + lead as u32,
        origin.line_start + body as u32,
    )
}

fn io_error(what: &str, e: std::io::Error) -> Error {
    Diagnostic::error(
        ErrorKind::Setup(SetupError::Io {
            path: what.into(),
            message: e.to_string(),
        }),
        None,
    )
}

impl<W: Write> SourceMap<W> {
    /// Flushes what was written so far.
    pub(crate) fn flush(&mut self) -> std::io::Result<()> {
        self.out_mut().flush()
    }
}

/// Looks at a program as the target controller receives it: each line goes
/// through the target's lowering first, and the lines the lowering writes
/// are what `view` sees (for `stats` and `plot` with a target: the run time
/// of what the controller runs, canned cycles and all, as lowered).
pub(crate) struct Lowered<'a> {
    lower: Box<dyn LineConsumer + 'a>,
    scratch: Output,
    view: ViewConsumer<'a>,
}

impl<'a> Lowered<'a> {
    pub(crate) fn new(lower: Box<dyn LineConsumer + 'a>, view: ViewConsumer<'a>) -> Lowered<'a> {
        let scratch = crate::emit::Sink::new(crate::emit::Destination::Memory(Default::default()))
            .map(|s| Output::new(s, None, usize::MAX))
            .ok()
            .or_else(Output::discarding)
            .expect("an output in memory");
        Lowered {
            lower,
            scratch,
            view,
        }
    }

    /// Hands the lines the lowering wrote so far to the view.
    fn pass(&mut self, origin: &Origin<'_>, out: &mut Output) -> Result<(), Error> {
        let lines = self.scratch.drain_memory();
        for l in lines.split(|&b| b == b'\n').filter(|l| !l.is_empty()) {
            self.view.line(l, origin, out)?;
        }
        Ok(())
    }
}

impl LineConsumer for Lowered<'_> {
    fn line(&mut self, text: &[u8], origin: &Origin<'_>, out: &mut Output) -> Result<(), Error> {
        self.lower.line(text, origin, &mut self.scratch)?;
        self.pass(origin, out)
    }

    fn computes_comp(&self) -> bool {
        self.lower.computes_comp()
    }

    fn comp_position(&mut self, p: [f64; 2]) {
        self.lower.comp_position(p);
    }

    fn finish(&mut self, out: &mut Output) -> Result<Vec<Diagnostic>, Error> {
        let warnings = self.lower.finish(&mut self.scratch)?;
        let lines = self.scratch.drain_memory();
        for l in lines.split(|&b| b == b'\n').filter(|l| !l.is_empty()) {
            if self.view.writes() {
                self.view.end_line(l, out)?;
            } else {
                self.view.block_line(l)?;
            }
        }
        self.view.finish(out)?;
        Ok(warnings)
    }
}
