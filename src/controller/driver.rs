//! The lowering driver: reads each flat line (as the evaluator's consumer),
//! decodes it, runs it on the machine model, and writes what the target
//! profile accepts: each word kept, dropped (with a warning where the
//! motion may differ), rewritten, lowered into other blocks, or refused
//! with the position of the word and the reason.
//!
//! This file holds the driver's state ([`Lowering`]), its constructor and
//! its entry points (the [`LineConsumer`] methods). The work is in the
//! submodules:
//!
//! * `run`: a decoded block run the general way and its lines written;
//! * `plain`: the common line written the short way;
//! * `fates`: what happens to each word (kept, dropped, refused);
//! * `report`: refusals, warnings, and where problems are reported;
//! * `offsets`: coordinate systems, G92/G52 and tool length offsets;
//! * `motion`: the lowering chosen for a block's motion, and arcs, polar
//!   words and canned cycles lowered;
//! * `splines`: G5, G5.1 and NURBS;
//! * `comp`: cutter compensation computed into the path;
//! * `arcs`, `centres`, `inverse`: arcs the target would run otherwise,
//!   absolute arc centres, inverse-time feeds of lowered motion.

use std::collections::HashSet;

use crate::block::{Block, CoordSystem, DecodeError};
use crate::diag::{Diagnostic, Error, ErrorKind, WarningKind};
use crate::emit::Output;
use crate::eval::{LineConsumer, Origin};
use crate::machine::FlatMachine;
use crate::settings::Settings;

use super::TargetOptions;
use super::format::LineWriter;
use super::lower;
use super::profile::Profile;

use cutter_path::CompPath;
use report::decode_problem;
use splines::NurbsCurve;

mod arcs;
mod centres;
mod cutter_path;
mod fates;
mod inverse;
mod motion;
mod offsets;
mod plain;
mod report;
mod run;
mod splines;

/// A problem found on a line: the word it is about and what it is.
struct Problem {
    span: Option<crate::block::BlockSpan>,
    kind: ErrorKind,
}

/// The consumer that writes a program for a target.
pub struct Lowering {
    p: &'static Profile,
    opts: TargetOptions,
    /// The machine as LinuxCNC runs the program (its state alone: it
    /// records no motion events, nor do its snapshots).
    m: FlatMachine,
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
    /// number in its `MoveTag`, in comp.rs).
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

impl Lowering {
    pub fn new(settings: &Settings, opts: TargetOptions) -> Lowering {
        let p = opts.profile;
        let m = FlatMachine::new(settings);
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
        self.p.name.as_str()
    }

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

    fn known_line(
        &mut self,
        text: &[u8],
        known: &[(u8, f64)],
        origin: &Origin<'_>,
        out: &mut Output,
    ) -> Result<(), Error> {
        if self.p.passthrough {
            return out.line(text).map_err(io_error);
        }
        self.run_decoded(text, origin, out, |b| b.decode_known(text, known))
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
