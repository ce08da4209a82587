//! The common line, written without the general machinery: a block whose
//! every word the target keeps as it is (G0–G3, plane, units, distance
//! mode, M codes the target has but M6, M2 and M30, axis words, F, S,
//! I J K) while nothing is being lowered (no cutter compensation computed
//! into the path, no G95 rewritten, no G7, the target in the program's
//! coordinate system). It is the same decoded block, run on the same
//! machine model and written by the same [`super::LineWriter`] calls; only
//! the per-word decisions and the lowering steps, which keep every word and
//! add nothing for such a block, are not gone through. The tests
//! (`plain/tests.rs`) run random lines both ways and compare output, state
//! and diagnostics.

use crate::block::written_as_is;
use crate::block::{
    Block, Distance, GCode, LatheMode, MCode, MotionMode, MoveValues, MovesRule, Plane, RawWord,
    Units, Word, WordKind,
};
use crate::diag::Error;
use crate::emit::Output;
use crate::eval::{FormLine, FormLines, Origin};

use super::{Lowering, Problem, Profile, io_error};
use crate::controller::format::AxisWords;
use crate::controller::profile::Comments;

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
            // Lines rewritten beyond their values (the writer's own rules).
            || self.p.rewrites_lines()
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
mod tests;
