//! The common line, written without the general machinery: a block whose
//! every word the target keeps as it is (G0–G3, plane, units, distance
//! mode, M codes the target has but M6, M2 and M30, axis words, F, S,
//! I J K) while nothing is being lowered (no cutter compensation computed
//! into the path, no G95 rewritten, no G7, the target in the program's
//! coordinate system). It is the same decoded block, run on the same
//! machine model and written by the same [`super::LineWriter`] calls; only
//! the per-word decisions and the lowering steps, which keep every word and
//! add nothing for such a block, are not gone through. The tests below run
//! random lines both ways and compare output, state and diagnostics.

use crate::block::written_as_is;
use crate::block::{
    Block, Distance, GCode, LatheMode, MCode, MotionMode, MoveValues, MovesRule, Plane, RawWord,
    Units, Word, WordKind,
};
use crate::diag::Error;
use crate::emit::Output;
use crate::eval::{FormLine, FormLines, Origin};

use super::{Lowering, Problem, Profile, io_error};
use crate::target::format::AxisWords;
use crate::target::profile::Comments;

/// The whole G and M codes below 128 the profile has, and its word and
/// axis letters, as bits (G17 is bit 17, X bit 88): looked up once per word
/// instead of searched in the profile's lists.
pub(super) struct Codes {
    g: u128,
    m: u128,
    /// Value word letters and axis letters, by their byte.
    words: u128,
    axes: u128,
    /// Which words of a line of moves alone the short way keeps: G0, G1,
    /// X, Y, Z, F (the same answers as the bits above).
    moves: [bool; 6],
}

impl Codes {
    pub(super) fn of(p: &Profile) -> Codes {
        let bits = |has: &dyn Fn(u16) -> bool| {
            (0..128u16)
                .filter(|&n| has(n))
                .fold(0u128, |b, n| b | 1 << n)
        };
        let g = bits(&|n| p.has_g(n * 10));
        let words = bits(&|n| p.has_word(n as u8));
        let axes = bits(&|n| p.has_axis(n as u8));
        let value = |l: u8| words & 1 << l != 0;
        let axis = |l: u8| value(l) && axes & 1 << l != 0;
        Codes {
            g,
            // M1 where the target ignores it takes the way that warns.
            m: bits(&|n| p.has_m(n) && (n != 1 || p.optional_stop)),
            words,
            axes,
            moves: [
                g & 1 != 0,
                g & 2 != 0,
                axis(b'X'),
                axis(b'Y'),
                axis(b'Z'),
                value(b'F'),
            ],
        }
    }
}

/// What became of a line of moves alone (see [`Lowering::write_moves`]).
pub(super) enum Moves {
    NotTaken,
    Done,
    /// Run, but the line as the target writes it is too long.
    Problem(crate::diag::ErrorKind),
}

impl Lowering {
    /// Whether `b` is such a line in the current state.
    pub(super) fn is_plain(&self, b: &Block) -> bool {
        if b.percent || b.block_delete || !self.plain_state() {
            return false;
        }
        let motion = b.motion().unwrap_or(self.m.modes.motion);
        let arc = match motion {
            MotionMode::Rapid | MotionMode::Linear => false,
            MotionMode::ArcCw | MotionMode::ArcCcw => true,
            _ => return false,
        };
        let mut ijk = false;
        for w in &b.words {
            let ok = match w.kind {
                WordKind::G(g) => {
                    let n = match g {
                        GCode::Motion(MotionMode::Rapid) => 0,
                        GCode::Motion(MotionMode::Linear) => 1,
                        GCode::Motion(MotionMode::ArcCw) => 2,
                        GCode::Motion(MotionMode::ArcCcw) => 3,
                        GCode::Plane(Plane::XY) => 17,
                        GCode::Plane(Plane::XZ) => 18,
                        GCode::Plane(Plane::YZ) => 19,
                        GCode::Units(Units::Inch) => 20,
                        GCode::Units(Units::Mm) => 21,
                        GCode::Distance(Distance::Absolute) => 90,
                        GCode::Distance(Distance::Incremental) => 91,
                        _ => return false,
                    };
                    self.codes.g & (1 << n) != 0
                }
                WordKind::M(m) => {
                    // M2/M30 also bring the target back to G54.
                    !matches!(m, MCode::ToolChange | MCode::End { .. })
                        && w.value.fract() == 0.0
                        && (0.0..128.0).contains(&w.value)
                        && self.codes.m & (1 << (w.value as u32)) != 0
                }
                WordKind::Value => {
                    let bit = 1u128 << (w.letter & 0x7f);
                    let word = self.codes.words & bit != 0;
                    match w.letter {
                        b'X' | b'Y' | b'Z' => word && self.codes.axes & bit != 0,
                        b'I' | b'J' | b'K' => {
                            ijk = true;
                            word
                        }
                        b'F' | b'S' => word,
                        _ => false,
                    }
                }
            };
            if !ok {
                return false;
            }
        }
        // An arc without an axis word of its plane, given by its centre,
        // is a full circle or a helix (lowered).
        let plane = match b.code(2) {
            Some(GCode::Plane(p)) => p,
            _ => self.m.modes.plane,
        };
        let xyz = [b'X', b'Y', b'Z'].map(|l| b.value(l));
        !(arc && ijk && !names_plane_axis(xyz, plane))
    }

    /// Whether a block [`Lowering::is_plain`] accepted is an arc to be
    /// lowered (see `arcs.rs`): it then goes the general way.
    pub(super) fn plain_arc_off(&self, b: &Block) -> bool {
        let motion = b.motion().unwrap_or(self.m.modes.motion);
        if !matches!(motion, MotionMode::ArcCw | MotionMode::ArcCcw) {
            return false;
        }
        let mut after = self.m.snapshot();
        after.apply(b);
        self.arc_off_target(b, &self.m, &after, motion)
            || self.arc_refused(b, &self.m, &after, motion).is_some()
    }

    /// What the axis words of a line of moves (G0–G3) are to the target.
    pub(super) fn moves_axis_words(&self) -> AxisWords {
        match self.m.modes.distance {
            Distance::Incremental => AxisWords::Increments,
            Distance::Absolute => AxisWords::Positions,
        }
    }

    /// Whether the state lets a line through the short way: nothing is
    /// being lowered (compensation, G95, G7 on a target without it, G90.1
    /// arc centres on a target without it) and the target is in the
    /// program's coordinate system.
    fn plain_state(&self) -> bool {
        !(self.comp.is_some()
            || self.after_off.is_some()
            || self.feed_rewrite
            // Positions in a coordinate system the target lacks are moved.
            || self.m.modes.coord != self.target_coord
            // Arc centres rewritten as offsets (centres.rs).
            || self.centres_rewritten()
            || self.m.modes.lathe == LatheMode::Diameter && !self.p.has_g(70))
    }

    /// A line that is a move alone (G0 or G1, X Y Z F, see
    /// [`crate::block::RawLine::moves_only`]) run and written without its
    /// block where [`Lowering::is_plain`] and [`Lowering::write_plain`]
    /// would take its block (they decide and do the same, which a test
    /// compares); [`Moves::NotTaken`] leaves it to the block's way.
    pub(super) fn write_moves(
        &mut self,
        text: &[u8],
        words: &[RawWord],
        out: &mut Output,
    ) -> Result<Moves, Error> {
        if !self.plain || !self.plain_state() {
            return Ok(Moves::NotTaken);
        }
        let decimals = match self.m.modes.units {
            Units::Mm => self.p.decimals_mm,
            Units::Inch => self.p.decimals_inch,
        };
        let mut motion = None;
        let mut f = None;
        let mut xyz = [None; 3];
        let mut as_is = self
            .p
            .line_limit
            .is_none_or(|(limit, _)| text.len() < limit);
        for w in words {
            let code = w.letter == b'G';
            let k = match w.letter {
                b'G' => {
                    let linear = w.value == 1.0;
                    motion = Some(if linear {
                        MotionMode::Linear
                    } else {
                        MotionMode::Rapid
                    });
                    usize::from(linear)
                }
                b'F' => {
                    f = Some(w.value);
                    5
                }
                l => {
                    let a = usize::from(l - b'X');
                    xyz[a] = Some(w.value);
                    2 + a
                }
            };
            if !self.codes.moves[k] {
                return Ok(Moves::NotTaken);
            }
            as_is &= written_as_is(w.shape, code, decimals, self.p.max_digits);
        }
        let values = MoveValues::new(motion, xyz, f, false);
        if !self.run_form(&values) {
            return Ok(Moves::NotTaken);
        }
        if as_is {
            out.line(text).map_err(io_error)?;
            return Ok(Moves::Done);
        }
        // Numbers to write the target's way, as write_plain does.
        self.w
            .begin_words(self.m.modes.units, self.moves_axis_words());
        for w in words {
            let kind = match (w.letter, motion) {
                (b'G', Some(m)) => WordKind::G(GCode::Motion(m)),
                _ => WordKind::Value,
            };
            let word = Word {
                letter: w.letter,
                value: w.value,
                kind,
                span: w.span,
                shape: w.shape,
            };
            self.w.word_of(&word, text);
        }
        match self.w.finished_line() {
            Ok(Some(line)) => out.write(line).map_err(io_error)?,
            Ok(None) => {}
            Err(kind) => return Ok(Moves::Problem(kind)),
        }
        Ok(Moves::Done)
    }

    /// The rule by which [`Lowering::write_moves`] writes a line of moves
    /// alone in the present state, when it takes such lines (see
    /// [`MovesRule`]).
    pub(super) fn moves_rule(&self) -> Option<MovesRule> {
        if self.p.passthrough
            || !self.plain
            || !self.plain_state()
            || !self.codes.moves.iter().all(|&m| m)
        {
            return None;
        }
        let decimals = match self.m.modes.units {
            Units::Mm => self.p.decimals_mm,
            Units::Inch => self.p.decimals_inch,
        };
        let word = |l: u8| self.codes.words & 1 << l != 0;
        Some(MovesRule {
            decimals,
            max_digits: self.p.max_digits,
            max_len: self.p.line_limit.map_or(usize::MAX, |(limit, _)| limit),
            arcs: self.codes.g & 0b1100 == 0b1100 && word(b'I') && word(b'J') && word(b'K'),
            // Inert comments are kept only where the target keeps them all.
            drops_comments: self.p.comments == Comments::Strip,
        })
    }

    /// Runs a line of moves alone as [`Lowering::write_plain`] does with
    /// its block, if [`plain_form`] takes it; false leaves it untouched.
    #[inline]
    fn run_form(&mut self, v: &MoveValues) -> bool {
        let motion = v.motion.unwrap_or(self.m.modes.motion);
        let Some((arc, axis)) = plain_form(v, motion, self.m.modes.plane) else {
            return false;
        };
        if arc
            && self.form_arc_off(
                self.m_xyz(),
                v.xyz(),
                v.centre,
                motion == MotionMode::ArcCcw,
            )
        {
            return false;
        }
        if !self.m.apply_plain_motion(v.motion, v.f(), v.xyz()) {
            return false;
        }
        let _ = self.m.take_events();
        if arc || axis {
            self.cycles.end();
        }
        self.f_before = self.last_f;
        if v.f().is_some() {
            self.last_f = v.f();
        }
        true
    }

    /// Lines of moves alone handed over at once: while the batch's rule is
    /// the present one, each is run as [`Lowering::write_plain`] runs its
    /// block, and their written bytes, which are what it writes for them,
    /// are written together; a line not so taken goes the way of its
    /// block, after the lines before it.
    pub(super) fn write_forms(
        &mut self,
        batch: &FormLines<'_>,
        origin: &Origin<'_>,
        out: &mut Output,
    ) -> Result<(), (usize, Error)> {
        let lines = batch.lines;
        let mut taken = self.moves_rule() == Some(batch.rule);
        // Written bytes before `from` are written.
        let mut from = 0;
        let mut k = 0;
        while k < lines.len() {
            if taken {
                k += self.run_forms(&lines[k..]);
                if k == lines.len() {
                    break;
                }
            }
            // Line `k` goes the way of its block, after the lines before it.
            let start = k
                .checked_sub(1)
                .map_or(0, |j| lines[j].written_end as usize);
            out.write(&batch.written[from..start])
                .map_err(|e| (k, io_error(e)))?;
            let l = &lines[k];
            from = l.written_end as usize;
            let text = batch.text(l);
            let o = Origin {
                line_start: l.line_start,
                ..*origin
            };
            self.run_decoded(text, &o, out, |b| b.decode_into(text))
                .map_err(|e| (k, e))?;
            taken = self.moves_rule() == Some(batch.rule);
            k += 1;
        }
        let last = lines.len().saturating_sub(1);
        out.write(&batch.written[from..])
            .map_err(|e| (last, io_error(e)))
    }

    /// Runs the longest run of `lines` from the first that
    /// [`Lowering::run_form`] would take one by one, as it would, and
    /// returns how many. Where positions are absolute the state after them
    /// depends only on the last of each word (the model keeps no motion:
    /// each move sets the axes it names from their values alone), so they
    /// are applied at once.
    fn run_forms(&mut self, lines: &[FormLine]) -> usize {
        if self.m.modes.distance != Distance::Absolute {
            let mut n = 0;
            while n < lines.len() && self.run_form(&lines[n].values) {
                n += 1;
            }
            return n;
        }
        // How many lines from the first are taken, in the motion each runs
        // in, and whether one ends a canned cycle's run.
        let mut motion = self.m.modes.motion;
        let mut ends_cycle = false;
        let mut n = 0;
        for l in lines {
            let v = &l.values;
            let m = v.motion.unwrap_or(motion);
            let Some((arc, axis)) = plain_form(v, m, self.m.modes.plane) else {
                break;
            };
            if arc
                && self.form_arc_off(
                    self.start_of(&lines[..n]),
                    v.xyz(),
                    v.centre,
                    m == MotionMode::ArcCcw,
                )
            {
                break;
            }
            motion = m;
            ends_cycle |= arc || axis;
            n += 1;
        }
        let taken = &lines[..n];
        // The last of each word among them: found from the end. (The last
        // motion is the one the loop ended in.)
        let last_of = |of: fn(&MoveValues) -> Option<f64>, lines: &[FormLine]| {
            lines.iter().rev().find_map(|l| of(&l.values))
        };
        let xyz = [
            last_of(|v| v.axis(0), taken),
            last_of(|v| v.axis(1), taken),
            last_of(|v| v.axis(2), taken),
        ];
        let f = last_of(MoveValues::f, taken);
        // The feed before the last line, as a line-by-line run leaves it.
        let f_before = last_of(MoveValues::f, &taken[..n.saturating_sub(1)]).or(self.last_f);
        let last_f = f.or(self.last_f);
        if n == 0 || !self.m.apply_plain_motion(Some(motion), f, xyz) {
            return 0;
        }
        let _ = self.m.take_events();
        if ends_cycle {
            self.cycles.end();
        }
        self.f_before = f_before;
        self.last_f = last_f;
        n
    }

    /// Runs and writes a line [`Lowering::is_plain`] accepted, as the
    /// general path does for it.
    pub(super) fn write_plain(
        &mut self,
        b: &Block,
        text: &[u8],
        out: &mut Output,
    ) -> Result<Vec<Problem>, Error> {
        let motion = b.motion().unwrap_or(self.m.modes.motion);
        // G7 is not in effect (or the target has it): values as written.
        self.m.apply(b);
        let _ = self.m.take_events();
        // The canned cycle's run ends with other motion.
        if matches!(motion, MotionMode::ArcCw | MotionMode::ArcCcw) || b.has_axis() {
            self.cycles.end();
        }
        self.f_before = self.last_f;
        if let Some(f) = b.value(b'F') {
            self.last_f = Some(f);
        }
        if self.w.is_written_as_is(b, text, self.m.modes.units) {
            out.line(text).map_err(io_error)?;
            return Ok(Vec::new());
        }
        self.w.begin(b, self.m.modes.units, self.moves_axis_words());
        for w in &b.words {
            self.w.word_of(w, text);
        }
        self.w.comments(b, text);
        match self.w.finished_line() {
            Ok(Some(line)) => out.write(line).map_err(io_error)?,
            Ok(None) => {}
            Err(kind) => return Ok(vec![Problem { span: None, kind }]),
        }
        Ok(Vec::new())
    }
}

impl Lowering {
    /// The model's X Y Z (mm).
    #[inline(always)]
    fn m_xyz(&self) -> [Option<f64>; 3] {
        [self.m.pos[0], self.m.pos[1], self.m.pos[2]]
    }

    /// Where the line after `before` starts (X Y Z, mm) when they are run
    /// from the model's state with absolute positions: each axis of the
    /// plane at the last value of its word among them (the others are not
    /// needed by the arc check).
    fn start_of(&self, before: &[FormLine]) -> [Option<f64>; 3] {
        let s = self.m.scale();
        let mut at = self.m_xyz();
        if let Some(axes) = self.m.modes.plane.xyz_axes() {
            for a in [axes[0], axes[1]] {
                if let Some(x) = before.iter().rev().find_map(|l| l.values.axis(a)) {
                    at[a] = self.m.axis_target(a, x, s);
                }
            }
        }
        at
    }
}

/// Whether a line of moves alone with values `v`, run in `motion` (its
/// own or the modal one), is one [`Lowering::is_plain`] accepts with its
/// block: G0 or G1 without I, J, K, G2/G3 with them and an axis word of
/// `plane`, or no word at all (a comment alone) in any of them. If so,
/// whether it is run as an arc and whether it names an axis.
fn plain_form(v: &MoveValues, motion: MotionMode, plane: Plane) -> Option<(bool, bool)> {
    let arc = matches!(motion, MotionMode::ArcCw | MotionMode::ArcCcw);
    let axis = v.has_axis();
    let plain = arc || matches!(motion, MotionMode::Rapid | MotionMode::Linear);
    (plain && (v.ijk == arc && (!arc || names_plane_axis(v.xyz(), plane)) || v.is_blank()))
        .then_some((arc, axis))
}

/// Whether an arc's X Y Z words `xyz` name an axis of its `plane`: GRBL-class
/// firmwares refuse an arc without one (GRBL's error 32), which LinuxCNC
/// runs as a full circle, or a helix when the third axis moves.
pub(super) fn names_plane_axis(xyz: [Option<f64>; 3], plane: Plane) -> bool {
    plane
        .xyz_axes()
        .is_some_and(|[p, q, _]| xyz[p].is_some() || xyz[q].is_some())
}

#[cfg(test)]
mod tests {
    use std::path::PathBuf;
    use std::sync::Arc;

    use proptest::prelude::*;

    use crate::emit::{Destination, Output, Sink};
    use crate::eval::{LineConsumer, Origin, Settings};
    use crate::program::SourceFile;
    use crate::target::{PROFILES, TargetOptions};

    use super::Lowering;

    /// Output, state after each line and diagnostics of `lines` run
    /// through a lowering for profile `p`, the short way on or off.
    fn run(lines: &[String], p: usize, zero_start: bool, plain: bool) -> (String, Vec<String>) {
        run_with(lines, p, zero_start, plain, false)
    }

    /// The words of `line` as the straight-line reader keeps them, if it
    /// is a move alone (see `RawLine::moves_only`).
    fn moves_of(line: &str) -> Option<Vec<crate::block::RawWord>> {
        let b = crate::block::Block::decode(line.as_bytes()).ok()?;
        let mut raw = crate::block::RawLine::default();
        if let Some((v, s)) = b.line_number {
            raw.set_line_number(v, s);
        }
        if let Some(c) = b.comments.first() {
            raw.set_comment(c.span);
        }
        for w in &b.words {
            raw.push(crate::block::RawWord {
                letter: line.as_bytes()[w.span.start as usize],
                value: w.value,
                span: w.span,
                shape: w.shape,
            });
        }
        let text = line.trim_end_matches([' ', '\t', '\r']);
        raw.moves_only(text.as_bytes()).map(<[_]>::to_vec)
    }

    /// [`run`]; with `moves`, each line that is a move alone goes the
    /// way of lines read ahead (`moves_line`, its words without a block).
    fn run_with(
        lines: &[String],
        p: usize,
        zero_start: bool,
        plain: bool,
        moves: bool,
    ) -> (String, Vec<String>) {
        let settings = Settings {
            zero_start,
            ..Settings::default()
        };
        let mut opts = TargetOptions::new(PROFILES[p]);
        opts.check = true;
        let mut l = Lowering::new(&settings, opts);
        l.plain = plain;
        let dir = tempfile::tempdir().expect("dir");
        let path = dir.path().join("out");
        let sink = Sink::new(Destination::File(path.clone())).expect("sink");
        let mut out = Output::new(sink, None, usize::MAX);
        let text = lines.join("\n");
        let file = Arc::new(SourceFile::new(
            PathBuf::from("<t>"),
            "<t>".into(),
            text.clone().into_bytes(),
        ));
        let stack = Vec::new;
        let mut states = Vec::new();
        let mut at = 0;
        for line in lines {
            let origin = Origin {
                file: &file,
                line_start: at,
                verbatim: true,
                stack: &stack,
            };
            at += line.len() as u32 + 1;
            let r = match moves.then(|| moves_of(line)).flatten() {
                Some(words) => {
                    let text = line.trim_end_matches([' ', '\t', '\r']);
                    l.moves_line(text.as_bytes(), &words, &origin, &mut out)
                }
                None => l.line(line.as_bytes(), &origin, &mut out),
            };
            states.push(format!(
                "{r:?} {:?} {:?} {:?} {} {:?} {:?} {:?}",
                l.m, l.last_f, l.f_before, l.percent_open, l.cycles, l.written_feed, l.last_pq
            ));
        }
        let diags = l.finish(&mut out).expect("finish");
        states.push(format!("{diags:?}"));
        out.finish().expect("written");
        (std::fs::read_to_string(path).expect("read"), states)
    }

    /// The G2/G3 lines of `out` (absolute, G17) as (start, end, centre),
    /// each as the target reads it from the numbers written.
    fn written_arcs(out: &str) -> Vec<([f64; 2], [f64; 2], [f64; 2])> {
        let (mut at, mut arcs, mut motion) = ([0.0f64; 2], Vec::new(), 0.0);
        for line in out.lines() {
            let (mut end, mut ij) = (at, [0.0; 2]);
            for w in line.split(' ') {
                let v: f64 = w[1..].parse().unwrap_or(f64::NAN);
                match w.as_bytes()[0] {
                    b'G' if matches!(v as u32, 0..=3) => motion = v,
                    b'X' => end[0] = v,
                    b'Y' => end[1] = v,
                    b'I' => ij[0] = v,
                    b'J' => ij[1] = v,
                    _ => {}
                }
            }
            if motion >= 2.0 && line.contains(['X', 'Y']) {
                arcs.push((at, end, [at[0] + ij[0], at[1] + ij[1]]));
            }
            at = end;
        }
        arcs
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        /// An arc that turns very little (a corner of a compensated path,
        /// CAM output in fine steps) is never written so that the target
        /// takes it for a full circle: its end written on its start, or an
        /// angle under GRBL's 5e-7 rad. Each way (the block's, the short
        /// way, the line of moves alone).
        #[test]
        fn arcs_that_barely_turn_are_not_written_as_full_circles(
            radius in 0.05f64..2000.0,
            from in -3.2f64..3.2,
            sweep_exp in -12.0f64..-3.0,
            ccw in proptest::bool::ANY,
            ways in 0usize..3,
        ) {
            let sweep = 10f64.powf(sweep_exp);
            let to = if ccw { from + sweep } else { from - sweep };
            let (cx, cy) = (3.0, -7.0);
            let point = |a: f64| [cx + radius * a.cos(), cy + radius * a.sin()];
            let (s, e) = (point(from), point(to));
            let lines = vec![
                "G21 G90 G17 F100".to_string(),
                format!("G0 X{} Y{}", s[0], s[1]),
                format!("G{} X{} Y{} I{} J{}", if ccw { 3 } else { 2 }, e[0], e[1], cx - s[0], cy - s[1]),
                "G1 X0 Y0".to_string(),
            ];
            let (out, _) = run_with(&lines, 1, true, ways > 0, ways == 2);
            for (start, end, centre) in written_arcs(&out) {
                prop_assert!(start != end, "{out}");
                let angle = |p: [f64; 2]| (p[1] - centre[1]).atan2(p[0] - centre[0]);
                let turned = (angle(end) - angle(start)).abs();
                prop_assert!(turned > 5e-7 && turned < std::f64::consts::TAU - 5e-7, "{out}");
            }
        }
    }

    /// A number as a program or the evaluator may write it.
    fn number() -> impl Strategy<Value = String> {
        prop_oneof![
            (-300i32..300).prop_map(|v| v.to_string()),
            (-3000.0f64..3000.0, 0usize..7).prop_map(|(v, d)| format!("{v:.d$}")),
            (-2.0f64..2.0).prop_map(|v| v.to_string()),
            Just("+1.5".to_string()),
            Just("-0".to_string()),
            Just("0.00001".to_string()),
            Just("12345678.9".to_string()),
            Just("007.50".to_string()),
            Just(".5".to_string()),
        ]
    }

    /// A word: mostly what the short way takes, and its near misses.
    fn word() -> impl Strategy<Value = String> {
        let codes = prop_oneof![
            Just("G0"),
            Just("G1"),
            Just("G2"),
            Just("G3"),
            Just("G17"),
            Just("G18"),
            Just("G19"),
            Just("G20"),
            Just("G21"),
            Just("G90"),
            Just("G91"),
            Just("G7"),
            Just("G8"),
            Just("G80"),
            Just("G81"),
            Just("G94"),
            Just("G95"),
            Just("G64"),
            Just("G41"),
            Just("G40"),
            Just("G43"),
            Just("G5"),
            Just("G38.2"),
            Just("M3"),
            Just("M5"),
            Just("M8"),
            Just("M9"),
            Just("M7"),
            Just("M0"),
            Just("M2"),
            Just("M6"),
            Just("g1"),
        ]
        .prop_map(str::to_string);
        let values = (
            prop_oneof![
                8 => proptest::sample::select(b"XYZF".to_vec()),
                3 => proptest::sample::select(b"IJKS".to_vec()),
                1 => proptest::sample::select(b"ARPTDHLQxz".to_vec()),
            ],
            number(),
        )
            .prop_map(|(l, v)| format!("{}{v}", l as char));
        // Whole blocks of what is lowered, to have its state around.
        let blocks = proptest::sample::select(vec![
            "G81 X1 Y1 Z-1 R2",
            "G83 Z-3 R1 Q1",
            "G99 G82 X2 Z-1 R1 P0.5",
            "G95 S1000",
            "G41.1 D2",
            "G43.1 Z2",
            "G2 X2 Y1 R0.4",
            "G38.2 Z-5",
            "G5 X3 Y3 I1 J0 P1 Q1",
            "G59.1",
            "G55",
            "G54",
            "G10 L2 P7 X5 Y-1",
            "G10 L20 P2 X1",
            "G52 X2 Y1",
            "G92 X0 Y0",
            "G92.2",
            "G92.3",
            "G92.1",
            "G5.2 X1 Y1 P1 L3",
            "G5.3",
        ])
        .prop_map(str::to_string);
        prop_oneof![4 => codes, 10 => values, 1 => blocks]
    }

    fn line() -> impl Strategy<Value = String> {
        (
            proptest::option::weighted(0.1, (1u32..200).prop_map(|n| format!("N{n} "))),
            proptest::collection::vec(word(), 0..6),
            proptest::sample::select(vec!["", " ", "  "]),
            proptest::option::weighted(
                0.15,
                proptest::sample::select(vec![
                    "(plain)",
                    "(MSG, tool ? now!)",
                    "; rest",
                    "(debug, x)",
                ]),
            ),
        )
            .prop_map(|(n, words, sep, comment)| {
                let mut l = n.unwrap_or_default();
                l.push_str(&words.join(sep));
                if let Some(c) = comment {
                    l.push(' ');
                    l.push_str(c);
                }
                l
            })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(300))]

        /// Lines taken the short way give the same output, state and
        /// diagnostics as through the general lowering.
        #[test]
        fn short_way_matches_the_general_lowering(
            lines in proptest::collection::vec(line(), 1..30),
            p in 1usize..4,
            zero_start in any::<bool>(),
        ) {
            let mut lines = lines;
            // Start where most lines are plain: feed moves in millimetres.
            lines.insert(0, "G21 G1 F100".into());
            let fast = run(&lines, p, zero_start, true);
            let slow = run(&lines, p, zero_start, false);
            prop_assert_eq!(&fast.0, &slow.0, "output of {:?}", lines);
            for (i, (a, b)) in fast.1.iter().zip(slow.1.iter()).enumerate() {
                prop_assert_eq!(a, b, "state after line {} of {:?}", i, lines);
            }
            // Moves alone taken without their block: the same again.
            let moves = run_with(&lines, p, zero_start, true, true);
            prop_assert_eq!(&moves.0, &slow.0, "output of {:?} (moves)", lines);
            for (i, (a, b)) in moves.1.iter().zip(slow.1.iter()).enumerate() {
                prop_assert_eq!(a, b, "state after line {} of {:?} (moves)", i, lines);
            }
        }
    }

    /// The random lines do take the short way (the test above compares
    /// something).
    #[test]
    fn common_lines_are_plain() {
        let settings = Settings::default();
        let mut l = Lowering::new(&settings, TargetOptions::new(PROFILES[1]));
        let mut b = crate::block::Block::default();
        for (text, want) in [
            ("G1 X1.5000 Y-2 F300", true),
            ("G2 X1 Y2 I1 J0", true),
            ("G21 G90 G17 M3 S1000", true),
            ("(a comment)", true),
            ("G2 I1 J0", false),
            ("G1 X1 A2", false),
            ("G64 P0.01", false),
            ("G2 X1 Y2 R5", false),
            ("M6 T1", false),
            ("M2", false),
        ] {
            b.decode_into(text.as_bytes()).expect("decodes");
            l.m.modes.motion = crate::block::MotionMode::Linear;
            assert_eq!(l.is_plain(&b), want, "{text}");
        }
    }
}
