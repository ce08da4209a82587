//! Writing lines for a target: numbers at the target's precision and never
//! with an exponent (`number`), comments stripped or cleaned, every line
//! measured as the firmware measures it and checked for bytes it acts on
//! in real time.
//!
//! In G91 the target adds up what is written: an increment rounded to the
//! target's decimals is off by up to half a unit of the last decimal, and a
//! thousand of them by five hundred. So the writer keeps, per axis, what
//! the rounding has left out so far ([`LineWriter::carry`]) and adds it to
//! the next increment it rounds: the target's position stays within half a
//! unit of the last decimal (of the last one rounded) of LinuxCNC's.

use crate::block::{
    AXIS_LETTERS, Block, CommentKind, Spacing, Units, Word, WordKind, without_trailing_zeros,
    written_as_is,
};
use crate::diag::ErrorKind;
use crate::diag::TargetError;

use super::lower::PlainLine;
use super::profile::{
    CommandsPerLine, CommentSyntax, Comments, DwellUnits, Inches, LineCount, Profile,
};

pub use number::format_number;
use number::{pow10, read_back, round_u64, write_fixed, write_number};

mod commands;
mod number;

/// Millimetres in an inch.
const MM_PER_INCH: f64 = 25.4;

/// What the axis words of the line being written are to the target.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum AxisWords {
    /// Positions (G90 motion, lowered lines): nothing is carried on.
    Positions,
    /// Increments the target adds to its position (G91 motion): what
    /// their rounding leaves out is carried on to the next.
    Increments,
    /// Neither (G92, G10, G43.1, G28's point, a canned cycle's words in
    /// G91): written as they are, the carry untouched.
    Other,
}

/// Puts one target line together.
pub(super) struct LineWriter {
    p: &'static Profile,
    buf: Vec<u8>,
    units: Units,
    axes: AxisWords,
    /// Per axis (X Y Z A B C U V W), in `carry_units`: the increments
    /// asked for less those written, since the last position written.
    carry: [f64; 9],
    carry_units: Units,
    num: String,
    /// Where the profile rewrites lines (`Profile::rewrites_lines`): the
    /// line's words, kept until it is finished.
    structured: bool,
    items: Vec<commands::Item>,
    /// The program's units of the line (`units` is what is written).
    in_units: Units,
    /// The line's comments, written after its words.
    tail: Vec<u8>,
    /// What one-command lines carry over to the next (`commands.rs`).
    carried: commands::Carried,
    /// The program's units after the last line rendered (None before the
    /// first): an F on a line that changes them is in the units before.
    prog_inch: Option<bool>,
    /// The target is in G93 as written: F is no length then.
    inverse: bool,
}

impl LineWriter {
    pub(super) fn new(p: &'static Profile) -> LineWriter {
        LineWriter {
            p,
            buf: Vec::with_capacity(128),
            units: Units::Mm,
            axes: AxisWords::Positions,
            carry: [0.0; 9],
            carry_units: Units::Mm,
            num: String::with_capacity(32),
            structured: p.rewrites_lines(),
            items: Vec::new(),
            in_units: Units::Mm,
            tail: Vec::new(),
            carried: commands::Carried::new(!p.feed_on_rapid),
            prog_inch: None,
            inverse: false,
        }
    }

    /// Starts a line for block `b` (its units decide the decimals), whose
    /// axis words are `axes`.
    pub(super) fn begin(&mut self, b: &Block, units: Units, axes: AxisWords) {
        self.begin_words(units, axes);
        if let Some((n, _)) = b.line_number
            && n <= self.p.max_line_number
        {
            self.push_word(b'N', n, true);
        }
    }

    /// [`LineWriter::begin`] for a line of words alone (no line number).
    pub(super) fn begin_words(&mut self, units: Units, axes: AxisWords) {
        self.buf.clear();
        self.items.clear();
        self.tail.clear();
        self.in_units = units;
        // Inches are written as millimetres where the target has no G20.
        let units = match self.p.inches {
            Inches::ToMm => Units::Mm,
            Inches::Native => units,
        };
        self.units = units;
        self.axes = axes;
        if units != self.carry_units {
            // Less than a unit of the last decimal either way: dropped.
            self.carry = [0.0; 9];
            self.carry_units = units;
        }
    }

    /// The axis index of a value word `letter`, if it is an axis word.
    #[inline]
    fn axis(letter: u8) -> Option<usize> {
        AXIS_LETTERS.iter().position(|&l| l == letter)
    }

    /// Writes axis word value `v` of axis `a` (its letter written), with
    /// `d` decimals, carrying its rounding on in G91 (see the module doc):
    /// an increment the decimals write exactly is written so (as the
    /// short ways copy it), one they round gets what earlier roundings
    /// left out added first.
    fn push_axis(&mut self, a: usize, v: f64, d: u8) {
        match self.axes {
            AxisWords::Increments => {
                let start = self.buf.len();
                write_number(&mut self.buf, v, d, self.p.max_digits);
                if read_back(&self.buf[start..]) == Some(v) {
                    return;
                }
                let want = v + self.carry[a];
                self.buf.truncate(start);
                write_number(&mut self.buf, want, d, self.p.max_digits);
                self.carry[a] = want - read_back(&self.buf[start..]).unwrap_or(want);
            }
            AxisWords::Positions => {
                self.carry[a] = 0.0;
                write_number(&mut self.buf, v, d, self.p.max_digits);
            }
            AxisWords::Other => write_number(&mut self.buf, v, d, self.p.max_digits),
        }
    }

    fn push_word(&mut self, letter: u8, v: f64, code: bool) {
        if self.structured {
            self.items.push((letter, v, code));
        } else {
            self.emit_word(letter, v, code);
        }
    }

    /// Writes a word into the line's bytes.
    fn emit_word(&mut self, letter: u8, v: f64, code: bool) {
        if self.buf.last().is_some_and(|&b| b != b'\n') {
            self.buf.push(b' ');
        }
        self.buf.push(letter);
        if code {
            let t = v * 10.0;
            if (0.0..9.0e15).contains(&t) {
                // Whole, or with its tenth (G38.2).
                let t = round_u64(t);
                let d = usize::from(!t.is_multiple_of(10));
                write_fixed(&mut self.buf, false, if d == 0 { t / 10 } else { t }, d);
            } else {
                use std::fmt::Write;
                let t = t.round();
                self.num.clear();
                let _ = if t % 10.0 == 0.0 {
                    write!(self.num, "{}", (t / 10.0) as i64)
                } else {
                    write!(self.num, "{:.1}", t / 10.0)
                };
                self.buf.extend_from_slice(self.num.as_bytes());
            }
        } else {
            let mut d = self.decimals();
            if letter == b'F' && v > 0.0 && v * pow10(usize::from(d)) < 0.5 {
                // A feed the decimals would write as 0: GRBL refuses F0
                // with a feed move (error 22), LinuxCNC moves at the feed.
                // As many decimals as the significant digits allow.
                d = self.p.max_digits;
            }
            match Self::axis(letter) {
                Some(a) => self.push_axis(a, v, d),
                None => write_number(&mut self.buf, v, d, self.p.max_digits),
            }
        }
    }

    fn decimals(&self) -> u8 {
        match self.units {
            Units::Mm => self.p.decimals_mm,
            Units::Inch => self.p.decimals_inch,
        }
    }

    /// Appends a word.
    pub(super) fn word(&mut self, letter: u8, value: f64, kind: WordKind) {
        let code = matches!(kind, WordKind::G(_) | WordKind::M(_)) || matches!(letter, b'G' | b'M');
        self.push_word(letter, value, code);
    }

    /// Appends word `w` of the line `text`: its number as written when
    /// that is already how the target's rules write its value (see
    /// [`written_as_is`]), otherwise as [`LineWriter::word`] does.
    pub(super) fn word_of(&mut self, w: &Word, text: &[u8]) {
        if self.structured {
            // Numbers are rewritten or words moved: nothing is copied.
            self.word(w.letter, w.value, w.kind);
            return;
        }
        let code = matches!(w.kind, WordKind::G(_) | WordKind::M(_));
        let number = text
            .get(w.span.start as usize + 1..w.span.end as usize)
            .unwrap_or_default();
        if !code
            && self.axes == AxisWords::Positions
            && let Some(a) = Self::axis(w.letter)
        {
            self.carry[a] = 0.0;
        }
        let kept = if written_as_is(w.shape, code, self.decimals(), self.p.max_digits) {
            number
        } else if let Some(n) = (!code)
            .then(|| without_trailing_zeros(w.shape, number, self.decimals(), self.p.max_digits))
            .flatten()
        {
            n
        } else {
            self.word(w.letter, w.value, w.kind);
            return;
        };
        if !self.buf.is_empty() {
            self.buf.push(b' ');
        }
        self.buf.push(w.letter);
        self.buf.extend_from_slice(kept);
    }

    /// Whether the line `text`, whose decoded block is `b`, is already what
    /// [`LineWriter::begin`], [`LineWriter::word_of`] for each word,
    /// [`LineWriter::comments`] and [`LineWriter::finished_line`] would put
    /// together under `units`: its words alone, each written as is, in
    /// upper case, one blank apart, and short enough for any count of the
    /// line limit. Such a line is written by copying it.
    pub(super) fn is_written_as_is(&self, b: &Block, text: &[u8], units: Units) -> bool {
        if b.line_number.is_some() || !b.comments.is_empty() || b.block_delete || b.percent {
            return false;
        }
        if self
            .p
            .line_limit
            .is_some_and(|(limit, _)| text.len() >= limit)
        {
            return false;
        }
        let decimals = match units {
            Units::Mm => self.p.decimals_mm,
            Units::Inch => self.p.decimals_inch,
        };
        let mut spacing = Spacing::new(0);
        for w in &b.words {
            let (start, end) = (w.span.start as usize, w.span.end as usize);
            // Upper case: the letter as the block has it.
            if !spacing.word(text, start, end) || text.get(start) != Some(&w.letter) {
                return false;
            }
            let code = matches!(w.kind, WordKind::G(_) | WordKind::M(_));
            if !written_as_is(w.shape, code, decimals, self.p.max_digits) {
                return false;
            }
        }
        spacing.ends_at(text.len())
    }

    /// Appends the comments of `b` (read from `text`) the target keeps.
    pub(super) fn comments(&mut self, b: &Block, text: &[u8]) {
        let p = self.p;
        // Where the line's words are kept apart, comments wait for them.
        let out = if self.structured {
            &mut self.tail
        } else {
            &mut self.buf
        };
        let mut semicolon = false;
        for c in &b.comments {
            let keep = match p.comments {
                Comments::Keep => p.comment_syntax != CommentSyntax::None,
                Comments::Strip => c.kind == CommentKind::Message && p.messages,
            };
            if !keep {
                continue;
            }
            let whole = &text[c.span.start as usize..c.span.end as usize];
            let inner = &text[c.text.start as usize..c.text.end as usize];
            if p.comments == Comments::Keep && p.comment_syntax == CommentSyntax::Semicolon {
                // One `;` comment to the line's end holds them all: the
                // firmware would read a `(…)` as words.
                if !semicolon {
                    if !out.is_empty() {
                        out.push(b' ');
                    }
                    out.push(b';');
                    semicolon = true;
                }
                out.push(b' ');
                out.extend(
                    inner
                        .iter()
                        .filter(|&&ch| (b' '..=b'~').contains(&ch) && !p.is_realtime(ch)),
                );
                continue;
            }
            if !out.is_empty() {
                out.push(b' ');
            }
            if p.comments == Comments::Keep {
                out.extend_from_slice(whole);
                continue;
            }
            out.extend_from_slice(b"(MSG,");
            for &ch in inner {
                if (b' '..=b'~').contains(&ch) && ch != b'(' && ch != b')' && !p.is_realtime(ch) {
                    out.push(ch);
                }
            }
            out.push(b')');
        }
    }

    /// Puts the kept words of a line rewritten by the profile into its
    /// bytes: lengths in millimetres where the target has no G20, G4's P
    /// in milliseconds where it reads them so, one command per line where
    /// it takes one (lines apart by a newline), the comments last.
    fn render(&mut self) {
        if !self.structured {
            return;
        }
        let mut items = std::mem::take(&mut self.items);
        let to_mm = self.p.inches == Inches::ToMm && self.in_units == Units::Inch;
        // LinuxCNC sets a line's feed before its units: the F of a line
        // with G20/G21 is in the units before it (the program's start
        // units, taken as millimetres, on a first line with G20/G21).
        let now_inch = self.in_units == Units::Inch;
        let sets_units = items
            .iter()
            .any(|&(l, v, code)| code && l == b'G' && (v == 20.0 || v == 21.0));
        let before_inch = match self.prog_inch {
            Some(b) => b,
            None => {
                let b = !sets_units && now_inch;
                self.carried.start_in_inches(b);
                b
            }
        };
        let f_inch = if sets_units { before_inch } else { now_inch };
        self.prog_inch = Some(now_inch);
        let mut dwell = false;
        for &(l, v, code) in &items {
            if code && l == b'G' {
                match (v * 10.0).round() as i64 {
                    930 => self.inverse = true,
                    940 | 950 => self.inverse = false,
                    40 => dwell = true,
                    _ => {}
                }
            }
        }
        let dwell_ms = dwell && self.p.dwell_units.in_ms();
        let whole_ms = self.p.dwell_units == DwellUnits::WholeMilliseconds;
        for (l, v, code) in &mut items {
            if *code {
                if *l == b'G' && self.p.inches == Inches::ToMm && *v == 20.0 {
                    *v = 21.0;
                }
                continue;
            }
            if *l == b'F' {
                if self.p.inches == Inches::ToMm && f_inch && !self.inverse {
                    *v *= MM_PER_INCH;
                }
            } else if to_mm && b"XYZUVWIJKRQ".contains(l) {
                *v *= MM_PER_INCH;
            }
            if dwell_ms && *l == b'P' {
                *v *= 1000.0;
                if whole_ms {
                    // Up to the next whole millisecond, a product's last
                    // bit of noise (0.003 s → 3.0000000000000004) aside.
                    *v = (*v - 1e-9).ceil().max(0.0);
                }
            }
        }
        self.buf.clear();
        match self.p.commands_per_line {
            CommandsPerLine::Many => {
                for &(l, v, code) in &items {
                    self.emit_word(l, v, code);
                }
            }
            CommandsPerLine::One => {
                for (i, line) in commands::split(&items, &mut self.carried)
                    .iter()
                    .enumerate()
                {
                    if i > 0 {
                        self.buf.push(b'\n');
                    }
                    for &(l, v, code) in line {
                        self.emit_word(l, v, code);
                    }
                }
            }
        }
        if !self.tail.is_empty() {
            if self.buf.last().is_some_and(|&b| b != b'\n') {
                self.buf.push(b' ');
            }
            self.buf.extend_from_slice(&self.tail);
            self.tail.clear();
        }
        items.clear();
        self.items = items;
    }

    /// Finishes the line into `out` (nothing for an empty line); an error
    /// if it does not fit the target's line buffer.
    pub(super) fn finish_line(&mut self, out: &mut Vec<u8>) -> Option<ErrorKind> {
        self.render();
        if self.buf.is_empty() {
            return None;
        }
        if let Some(k) = self.check() {
            return Some(k);
        }
        out.clear();
        out.extend_from_slice(&self.buf);
        None
    }

    /// The finished line with its newline (`None` for an empty line), or
    /// the error if it does not fit the target's line buffer:
    /// [`LineWriter::finish_line`] without the copy.
    pub(super) fn finished_line(&mut self) -> Result<Option<&[u8]>, ErrorKind> {
        self.render();
        if self.buf.is_empty() {
            return Ok(None);
        }
        if let Some(k) = self.check() {
            return Err(k);
        }
        self.buf.push(b'\n');
        Ok(Some(&self.buf))
    }

    fn check(&self) -> Option<ErrorKind> {
        debug_assert!(!self.buf.iter().any(|&b| self.p.is_realtime(b)));
        let (limit, how) = self.p.line_limit?;
        if self.buf.len() < limit {
            // Fits however it is counted.
            return None;
        }
        // Each line of a rewritten line on its own.
        self.buf.split(|&b| b == b'\n').find_map(|line| {
            let len = match how {
                LineCount::AllBytes => line.len() + 1,
                LineCount::Significant => significant_len(line) + 1,
            };
            (len > limit).then(|| {
                ErrorKind::Target(TargetError::TargetLineTooLong {
                    target: self.p.name.as_str(),
                    len: len - 1,
                    limit: limit - 1,
                })
            })
        })
    }

    /// Writes a lowered block into `out`.
    pub(super) fn plain(
        &mut self,
        l: &PlainLine,
        units: Units,
        out: &mut Vec<u8>,
    ) -> Option<ErrorKind> {
        self.begin_words(units, AxisWords::Positions);
        for w in &l.words {
            let code = matches!(w.letter, b'G' | b'M');
            self.push_word(w.letter, w.value, code);
        }
        self.finish_line(out)
    }
}

/// Bytes of a line without blanks and comments.
pub fn significant_len(line: &[u8]) -> usize {
    let mut n = 0;
    let mut in_comment = false;
    for &c in line {
        match c {
            b'(' => in_comment = true,
            b')' if in_comment => in_comment = false,
            b';' if !in_comment => break,
            b' ' | b'\t' | b'\r' => {}
            _ if !in_comment => n += 1,
            _ => {}
        }
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;

    fn f(v: f64, d: u8, m: u8) -> String {
        let mut s = String::new();
        format_number(&mut s, v, d, m);
        s
    }

    #[test]
    fn codes_are_written_whole_or_with_their_tenth() {
        let p = &crate::controller::find("grbl").unwrap();
        for (v, want) in [
            (1.0, "G1"),
            (38.2, "G38.2"),
            (0.0, "G0"),
            (92.1, "G92.1"),
            (5.0000001, "G5"),
            (-1.0, "G-1"),
            (-0.5, "G-0.5"),
        ] {
            let mut w = LineWriter::new(p);
            w.push_word(b'G', v, true);
            assert_eq!(String::from_utf8_lossy(&w.buf), want, "{v}");
        }
    }

    /// Writes `steps` lines of increments `inc` (X and Y) the way the
    /// driver does, with `axes`; what the target adds up (in its units)
    /// against the exact sums.
    fn summed(axes: AxisWords, units: Units, inc: [f64; 2], steps: u32) -> ([f64; 2], [f64; 2]) {
        let mut w = LineWriter::new(crate::controller::find("grbl").unwrap());
        let mut sum = [0.0; 2];
        for _ in 0..steps {
            w.begin_words(units, axes);
            w.word(b'X', inc[0], WordKind::Value);
            w.word(b'Y', inc[1], WordKind::Value);
            let line = String::from_utf8(w.buf.clone()).unwrap();
            for (i, word) in line.split(' ').enumerate() {
                sum[i] += word[1..].parse::<f64>().unwrap();
            }
        }
        let exact = inc.map(|v| v * f64::from(steps));
        (sum, exact)
    }

    #[test]
    fn rounded_increments_do_not_add_up() {
        // 0.000125 in is written 0.00013 or 0.00012 (5 decimals): over a
        // thousand lines the target stays within half of 0.00001 in.
        for (units, inc, half) in [
            (Units::Inch, [0.0005, 0.000125], 0.000005),
            (Units::Mm, [0.01234567, -1.0 / 3.0], 0.00005),
            (Units::Mm, [2.0 / 3.0, 0.00004], 0.00005),
        ] {
            let (sum, exact) = summed(AxisWords::Increments, units, inc, 1000);
            for i in 0..2 {
                assert!(
                    (sum[i] - exact[i]).abs() <= half * 1.0001,
                    "{inc:?}: {sum:?} {exact:?}"
                );
            }
            // Positions are written each on its own: nothing carried.
            let (once, _) = summed(AxisWords::Positions, units, inc, 1);
            let (again, _) = summed(AxisWords::Positions, units, inc, 2);
            assert_eq!(again, once.map(|v| 2.0 * v));
        }
        // A change of units drops the carry (under a unit of the last
        // decimal); the next increment starts afresh.
        let mut w = LineWriter::new(crate::controller::find("grbl").unwrap());
        w.begin_words(Units::Inch, AxisWords::Increments);
        w.word(b'X', 0.000004, WordKind::Value);
        assert_eq!(w.buf, b"X0");
        w.begin_words(Units::Mm, AxisWords::Increments);
        w.word(b'X', 0.00004, WordKind::Value);
        assert_eq!(w.buf, b"X0");
        w.begin_words(Units::Mm, AxisWords::Increments);
        w.word(b'X', 0.00004, WordKind::Value);
        assert_eq!(w.buf, b"X0.0001");
    }

    /// The shape the decoder gives the number `t` (written after an X).
    fn shape(t: &str) -> Option<crate::block::Shape> {
        let b = Block::decode(format!("X{t}").as_bytes()).ok()?;
        let w = b.words.first()?;
        (w.span.end as usize == t.len() + 1).then_some(w.shape)
    }

    proptest::proptest! {
        /// A number written as is is what the rules write for its value.
        #[test]
        fn numbers_written_as_is_are_formatted_so(
            t in "[-+]?[0-9]{0,9}(\\.[0-9]{0,9})?",
            code in proptest::bool::ANY,
            decimals in 0u8..7,
            max_digits in 1u8..12,
        ) {
            if let Some(s) = shape(&t)
                && written_as_is(s, code, decimals, max_digits)
            {
                let v: f64 = t.parse().unwrap();
                let mut w = LineWriter::new(crate::controller::find("grbl").unwrap());
                w.push_word(b'X', v, code);
                let want = if code {
                    String::from_utf8_lossy(&w.buf[1..]).into_owned()
                } else {
                    f(v, decimals, max_digits)
                };
                proptest::prop_assert_eq!(t, want);
            }
        }
    }

    proptest::proptest! {
        /// A number whose decimals end in zeros, written without them, is
        /// what the rules write for its value; blanks anywhere in it, or a
        /// sign or zero the rules do not write, leave it to them.
        #[test]
        fn numbers_without_trailing_zeros_are_formatted_so(
            t in "[-+]?[0-9 ]{0,7}(\\.[0-9 ]{0,7}0{1,3})?",
            decimals in 0u8..7,
            max_digits in 1u8..12,
        ) {
            if let Some(s) = shape(&t)
                && let Some(n) = without_trailing_zeros(s, t.as_bytes(), decimals, max_digits)
            {
                let v: f64 = t.replace(' ', "").parse().unwrap();
                proptest::prop_assert_eq!(String::from_utf8_lossy(n), f(v, decimals, max_digits));
            }
        }
    }

    #[test]
    fn numbers_without_their_trailing_zeros() {
        for (t, want) in [
            ("1.50", Some("1.5")),
            ("-2.000", Some("-2")),
            ("0.000", Some("0")),
            ("10.0", Some("10")),
            ("-0.0", None),
            ("1.5", None),
            ("1.23450", Some("1.2345")),
            ("1.234560", None),
            ("+1.50", None),
            ("01.50", None),
            ("1234567.50", Some("1234567.5")),
            ("12345678.50", None),
            ("1.5 0", None),
            ("1 .50", None),
            ("1. 50", None),
            ("1.50 ", None),
        ] {
            // A number with blanks in it may not be read whole (no shape).
            let got = shape(t).and_then(|s| without_trailing_zeros(s, t.as_bytes(), 4, 8));
            assert_eq!(got, want.map(str::as_bytes), "{t}");
        }
    }

    #[test]
    fn numbers_as_written() {
        for (t, want) in [
            ("1.5", true),
            ("-0.25", true),
            ("0", true),
            ("12", true),
            ("1.2345", true),
            ("1.23456", false),
            ("1.50", false),
            ("01.5", false),
            ("+1.5", false),
            ("-0", false),
            (".5", false),
            ("5.", false),
            ("1234567.5", true),
            ("12345678.5", false),
            ("0.0001", true),
            ("0.00001", false),
        ] {
            let s = shape(t).unwrap();
            assert_eq!(written_as_is(s, false, 4, 8), want, "{t}");
        }
        assert_eq!(shape("1 .5").map(|s| s.plain), Some(false));
        assert!(written_as_is(shape("38.2").unwrap(), true, 4, 8));
        assert!(!written_as_is(shape("38.25").unwrap(), true, 4, 8));
        assert!(!written_as_is(shape("-1").unwrap(), true, 4, 8));
    }

    #[test]
    fn significant_length() {
        assert_eq!(significant_len(b"G1 X1 (a comment) Y2"), 6);
        assert_eq!(significant_len(b"G1 X1 ; rest"), 4);
    }
}
