//! A line's words applied to the machine model: the update itself is the
//! machine's ([`Machine::apply_codes`](crate::eval::state::Machine::apply_codes));
//! this step places its errors and warnings at the line and writes the
//! line the update asks for (RETAIN_G43's G43 or G49).

use std::rc::Rc;

use crate::diag::{Error, WarningKind};
use crate::parse::ast::Span;
use crate::program::FileIndex;

use crate::eval::Interp;
use crate::eval::state::Env;
use crate::eval::state::checked::Checked;

impl Interp<'_> {
    /// Applies the line's words to the model, with its G and M codes as
    /// the checks decoded them (`checked`). Returns true when the line ends
    /// the program.
    pub(in crate::eval) fn apply_words(
        &mut self,
        file: &Rc<FileIndex>,
        start: u32,
        words: &[(u8, f64)],
        checked: &Checked,
        m99: bool,
    ) -> Result<bool, Error> {
        if !m99 && self.mach.apply_simple(words) {
            return Ok(false);
        }
        let mut warnings = Vec::new();
        let mut env = Env {
            s: self.s,
            params: &mut self.params,
            line: self.reader.line_idx + 1,
        };
        let r = self
            .mach
            .apply_codes(&mut env, words, checked, m99, &mut warnings);
        for w in warnings {
            self.warn(w, file, start, start);
        }
        let end = r.map_err(|k| self.error(k, file, start, start))?;
        if let Some(on) = self.mach.retain_line.take() {
            self.emit_raw(if on { b"G43" } else { b"G49" })?;
        }
        self.mach
            .end_line(end)
            .map_err(|k| self.error(k, file, start, start))?;
        Ok(end.ends)
    }

    /// A read of the position after the standalone reference's position
    /// departed from the machine's: warning W0110 at the read.
    pub(in crate::eval) fn note_standalone_drift(&mut self, span: Span) {
        if let Some((why, line)) = self.mach.standalone_drift {
            self.warn_standalone(why, line, span);
        }
    }

    /// A read of the current tool (`data`: or of its data) after M61, which
    /// the standalone reference does not apply: warning W0110 at the read if
    /// the value differs there.
    pub(in crate::eval) fn note_m61(&mut self, span: Span, data: bool) {
        if let Some(line) = self.mach.m61_read_differs(data) {
            let why = "M61 (the standalone interpreter keeps its current tool)";
            self.warn_standalone(why, line, span);
        }
    }

    /// Warning W0110 at `span` of the current line.
    fn warn_standalone(&mut self, why: &'static str, line: u32, span: Span) {
        let file = self.flow.cur.file.clone();
        let at = self.reader.line_start;
        self.warn(
            WarningKind::QuirkStandalone { why, line },
            &file,
            at + span.start,
            at + span.end,
        );
    }
}

#[cfg(test)]
mod tests {
    use std::rc::Rc;
    use std::sync::Arc;

    use crate::codes::{
        ArcDistance, CutterComp, Distance, FeedMode, MotionMode, Plane, SpindleDir, Units,
    };
    use crate::emit::{Destination, MemoryOut, Sink};
    use crate::eval::Interp;
    use crate::eval::read::validate::check_block;
    use crate::program::{FileIndex, Loader, SearchPath, SourceFile};
    use crate::rules::Modes;
    use crate::settings::Settings;

    /// A line's words: `G80 G1 X1` → g 80, g 1, x 1.
    fn words(line: &str) -> Vec<(u8, f64)> {
        line.split_whitespace()
            .map(|w| {
                let v = w[1..].parse().expect("a number");
                (w.as_bytes()[0].to_ascii_lowercase(), v)
            })
            .collect()
    }

    /// Checks and applies each line in a fresh evaluator, as the reader
    /// does; returns the modes before and after, and whether the last line
    /// ended the program.
    fn run(s: &Settings, lines: &[&str], see: impl FnOnce(&Interp<'_>)) -> (Modes, Modes, bool) {
        let src = SourceFile::new("<t>".into(), "<t>".into(), Vec::new());
        let main = Rc::new(FileIndex::build(Arc::new(src), false));
        let sink = Sink::new(Destination::Memory(MemoryOut::default())).expect("sink");
        let loader = Loader::new(SearchPath::default(), None);
        let mut it = Interp::new(s, loader, main.clone(), sink);
        let before = it.mach.modal.clone();
        let mut ends = false;
        for line in lines {
            let w = words(line);
            let m = &it.mach;
            let checked = check_block(&w, &m.modal, &m.nurbs, &m.cycle, s.user_m)
                .unwrap_or_else(|e| panic!("{line}: {e:?}"));
            ends = it
                .apply_words(&main, 0, &w, &checked, false)
                .unwrap_or_else(|e| panic!("{line}: {e:?}"));
        }
        see(&it);
        (before, it.mach.modal.clone(), ends)
    }

    /// The state after lines whose G and M codes the checks decode (G80
    /// beside another motion code, several codes of a line, M codes in
    /// order, the fast acceptance's G0/G1 applied on the general path)
    /// is the one their codes give: the update acts on the checks' codes.
    #[test]
    fn the_update_acts_on_the_codes_the_checks_decoded() {
        type Want = fn(&mut Modes);
        let cases: &[(&[&str], bool, Want)] = &[
            (&["G80 G1 X1 F10"], false, |m| {
                m.motion = MotionMode::Linear;
                m.feed = 10.0;
            }),
            (&["G1 G80 X1 F10"], false, |m| {
                m.motion = MotionMode::Linear;
                m.feed = 10.0;
            }),
            (&["G80 G0 X2"], false, |m| m.motion = MotionMode::Rapid),
            (&["G1 F5", "G80"], false, |m| {
                m.motion = MotionMode::CancelCycle;
                m.feed = 5.0;
            }),
            (&["G0 G90.1 X1"], false, |m| {
                m.motion = MotionMode::Rapid;
                m.arc_distance = ArcDistance::Absolute;
            }),
            (&["G91 G0 Z1"], false, |m| {
                m.motion = MotionMode::Rapid;
                m.distance = Distance::Incremental;
            }),
            (&["G18 G20 G93 G1 X1 F2"], false, |m| {
                m.motion = MotionMode::Linear;
                m.plane = Plane::XZ;
                m.units = Units::Inch;
                m.feed_mode = FeedMode::InverseTime;
                m.feed = 2.0;
            }),
            (&["M3 M8"], false, |m| {
                m.spindle = SpindleDir::Cw;
                m.flood = true;
            }),
            (&["M4 M7", "M9 M5"], false, |_| {}),
            (&["M50 P0"], false, |m| m.feed_override = false),
            (&["G91 M4 M7 S100", "M2"], true, |m| {
                m.speed = 100.0;
                m.end_of_program();
            }),
            // G0 taken by the fast acceptance and applied by the general
            // update (compensation is on).
            (&["G41.1 D1 G1 X1 F10", "G0 X5"], false, |m| {
                m.motion = MotionMode::Rapid;
                m.cutter_comp = CutterComp::DynamicLeft;
                m.feed = 10.0;
            }),
        ];
        let s = Settings::default();
        for &(lines, want_end, want) in cases {
            let (before, after, ends) = run(&s, lines, |_| {});
            let mut expected = before;
            want(&mut expected);
            assert_eq!(after, expected, "{lines:?}");
            assert_eq!(ends, want_end, "{lines:?}");
        }
    }

    /// A T word selects the tool an M6 on its line loads, before or after
    /// it; M61 sets the tool of its Q.
    #[test]
    fn tool_codes_act_in_line_order() {
        let s = Settings::default();
        let tool = |lines: &[&str]| {
            let mut t = None;
            run(&s, lines, |it| t = it.mach.tools.current);
            t
        };
        assert_eq!(tool(&["T2 M6"]), Some(2.0));
        assert_eq!(tool(&["M6 T2"]), Some(2.0));
        assert_eq!(tool(&["T2", "M6"]), Some(2.0));
        assert_eq!(tool(&["Q3 M61"]), Some(3.0));
        assert_eq!(tool(&["M61 Q3"]), Some(3.0));
        assert_eq!(tool(&["T4 M8"]), None);
    }
}
