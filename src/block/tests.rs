use super::read::{read_number, read_number_slow};
use super::*;
use crate::number::digits_at;
use proptest::strategy::Strategy as _;

/// The block sink reading every word itself, without [`read_words`].
struct Unusual(Block);

impl LineSink for Unusual {
    type Error = DecodeError;
    const SHAPES: bool = true;
    const USUAL: bool = false;

    fn on_percent(&mut self) -> Result<(), DecodeError> {
        self.0.on_percent()
    }

    fn on_block_delete(&mut self) {
        self.0.on_block_delete();
    }

    fn on_word(
        &mut self,
        letter: u8,
        value: f64,
        span: BlockSpan,
        shape: Shape,
        spaced: bool,
    ) -> Result<(), DecodeError> {
        self.0.on_word(letter, value, span, shape, spaced)
    }

    fn on_comment(&mut self, line: &[u8], start: usize, end: usize) -> Result<(), DecodeError> {
        self.0.on_comment(line, start, end)
    }
}

proptest::proptest! {
    /// The words written the usual way, read by `read_words`, make
    /// the block (or the error) the flat-line reader makes reading
    /// every word itself, with or without bytes after the line.
    #[test]
    fn usual_words_read_as_the_whole_reader_reads_them(
        parts in proptest::collection::vec(
            proptest::prop_oneof![
                "[gGxXyYzZmMnNfF@^][+-]?[0-9]{0,5}(\\.[0-9]{0,4})?",
                "[gGxXyYzZmMnNfF@^]",
                "[ \t\r]{0,2}[0-9.]{1,3}",
                "[+-]?[0-9]{14,20}",
                "[ \t\r]{0,2}",
                "[/%;()#\n.]",
                "\\([a-z ,]{0,5}\\)",
            ],
            0..12,
        ),
        tail in "[\n0-9. X]{0,20}",
    ) {
        let line = parts.concat();
        let buf = format!("{line}{tail}");
        for b in [line.as_bytes(), buf.as_bytes()] {
            let mut usual = Block::default();
            usual.clear();
            let got = read_flat_line_in(b, line.len(), &mut usual);
            let mut whole = Unusual(Block::default());
            whole.0.clear();
            let want = read_flat_line_in(b, line.len(), &mut whole);
            proptest::prop_assert_eq!(&got, &want, "{:?}", buf);
            if want.is_ok() {
                proptest::prop_assert_eq!(&usual, &whole.0, "{:?}", buf);
            }
        }
    }

    /// The one-step rule of the straight-line reader gives what the
    /// shape of the number and the writer's two tests give, for value
    /// words at any place in a line (the eight-byte read of their end
    /// and the byte-by-byte one).
    #[test]
    fn kept_digits_is_the_shape_rule(
        lead in 0usize..10,
        sign in "[-+]?",
        text in "[0-9]{0,8}(\\.[0-9]{0,8})?",
        decimals in 0u8..7,
        max_digits in 1u8..10,
    ) {
        let line = format!("{}X{sign}{text} Y1{}", " ".repeat(lead), " ".repeat(16));
        let b = line.as_bytes();
        let num = lead + 1 + sign.len();
        if let Some(d) = digits_at(b, num) {
            let (neg, plus) = (sign == "-", sign == "+");
            let shape = Shape::of(&d, b, num, neg, plus);
            let want = if written_as_is(shape, false, decimals, max_digits) {
                Some(0)
            } else {
                let number = &b[lead + 1..d.end];
                without_trailing_zeros(shape, number, decimals, max_digits)
                    .map(|kept| number.len() - kept.len())
            };
            let sign_byte = sign.bytes().next().unwrap_or(b'X');
            proptest::prop_assert_eq!(
                kept_digits(&d, b, num, sign_byte, decimals, max_digits),
                want,
                "{:?} decimals {} digits {}", line, decimals, max_digits
            );
        }
    }

    /// The one-pass number reader gives what the general one gives
    /// (value, end, or no number) on any text of number characters.
    #[test]
    fn number_reader_fast_path_is_exact(
        text in "[-+ .0-9]{0,24}[XY; (]?",
        at in 0usize..3,
    ) {
        let line = format!("X{text}");
        let start = at.min(line.len());
        let fast = read_number(line.as_bytes(), line.as_bytes(), start, true, None).map(|n| (n.value, n.end));
        let slow = read_number_slow(line.as_bytes(), start);
        proptest::prop_assert_eq!(
            fast.map(|(v, e)| (v.to_bits(), e)),
            slow.map(|(v, e)| (v.to_bits(), e)),
            "{:?}", line
        );
    }

    /// A line read with the bytes after it reads as the line alone:
    /// the same block, or the same error.
    #[test]
    fn line_reads_the_same_with_bytes_after_it(
        line in "[GXYM ]{0,3}[-+]?[0-9]{0,9}(\\.[0-9]{0,9})?( [XY][0-9.]{1,12})?",
        tail in "[\r\n0-9.X ]{0,20}",
    ) {
        let buf = format!("{line}{tail}");
        let mut alone = Block::default();
        let want = alone.decode_into(line.as_bytes());
        let mut within = Block::default();
        within.clear();
        let got = read_flat_line_in(buf.as_bytes(), line.len(), &mut within);
        proptest::prop_assert_eq!(&got, &want, "{:?}", buf);
        if want.is_ok() {
            proptest::prop_assert_eq!(&within, &alone, "{:?}", buf);
        }
    }

    /// Numbers of 16 to 20 digits, near and past 2^53 as an integer,
    /// read as `str::parse` reads them, wherever the point is.
    #[test]
    fn number_reader_reads_long_numbers_exactly(
        mant in proptest::prop_oneof![
            1_000_000_000_000_000u64..(1 << 53) + 2,
            (1u64 << 53) - 2..100_000_000_000_000_000,
            10_000_000_000_000_000_000u64..u64::MAX,
        ],
        lead in 0usize..3,
        point in 0usize..21,
        neg in proptest::bool::ANY,
    ) {
        let digits = format!("{}{mant}", "0".repeat(lead));
        let at = point.min(digits.len());
        let text = format!(
            "{}{}.{}",
            if neg { "-" } else { "" },
            &digits[..at],
            &digits[at..],
        );
        let line = format!("X{text} Y1");
        let got = read_number(line.as_bytes(), line.as_bytes(), 1, true, None)
            .map(|n| (n.value.to_bits(), n.end));
        let want: f64 = text.parse().unwrap();
        proptest::prop_assert_eq!(got, Some((want.to_bits(), 1 + text.len())), "{}", line);
    }

    #[test]
    fn number_reader_reads_decimals_exactly(
        int in 0u64..100_000_000,
        frac in 0u64..10_000_000,
        width in 0usize..12,
        neg in proptest::bool::ANY,
    ) {
        let line = format!(
            "X{}{int}.{frac:0width$} Y1",
            if neg { "-" } else { "" },
        );
        let got = read_number(line.as_bytes(), line.as_bytes(), 1, true, None).map(|n| (n.value, n.end));
        let want: f64 = line[1..line.len() - 3].parse().unwrap();
        proptest::prop_assert_eq!(got.map(|g| g.0.to_bits()), Some(want.to_bits()));
        proptest::prop_assert_eq!(got.map(|g| g.1), Some(line.len() - 3));
    }
}

proptest::proptest! {
    /// A line of words whose values are written as the evaluator writes
    /// them (shortest, [`crate::number::write_number`]) decodes with
    /// the values known into the block it decodes into from its text,
    /// bit for bit, whichever of its words are known, with a line
    /// number, blanks and a comment about.
    #[test]
    fn known_values_decode_as_the_text(
        words in proptest::collection::vec(
            (
                proptest::sample::select(b"GXYZFIJKRSPQABC".to_vec()),
                proptest::prop_oneof![
                    -1.0e6f64..1.0e6,
                    (-4000i64..4000, 0u32..6).prop_map(|(n, k)| n as f64 * 0.025 - f64::from(k) * 0.002),
                    (-100_000i64..100_000).prop_map(|n| n as f64 / 1000.0),
                    proptest::num::f64::NORMAL.prop_map(|v| v.clamp(-1e14, 1e14)),
                ],
                proptest::bool::ANY,
            ),
            1..8,
        ),
        indent in 0usize..3,
        number in proptest::option::of(1u32..99999),
        comment in proptest::bool::ANY,
        lower in proptest::bool::ANY,
    ) {
        let mut line = " ".repeat(indent).into_bytes();
        if let Some(n) = number {
            line.extend(format!("N{n} ").bytes());
        }
        let mut known = Vec::new();
        for (k, &(letter, v, is_known)) in words.iter().enumerate() {
            if k > 0 {
                line.push(b' ');
            }
            line.push(if lower { letter.to_ascii_lowercase() } else { letter });
            proptest::prop_assert!(crate::number::write_number(&mut line, v, None));
            known.push((letter, if is_known { v } else { f64::NAN }));
        }
        if comment {
            line.extend_from_slice(b" (c)");
        }
        let want = Block::decode(&line);
        let mut got = Block::default();
        let r = got.decode_known(&line, &known);
        match want {
            Ok(want) => {
                proptest::prop_assert!(r.is_ok(), "{:?}", String::from_utf8_lossy(&line));
                proptest::prop_assert_eq!(&got, &want, "{:?}", String::from_utf8_lossy(&line));
                let bits = |b: &Block| b.words.iter().map(|w| w.value.to_bits()).collect::<Vec<_>>();
                proptest::prop_assert_eq!(bits(&got), bits(&want));
            }
            Err(e) => proptest::prop_assert_eq!(r, Err(e)),
        }
    }
}

#[test]
fn g80_beside_another_motion_code() {
    for (line, want) in [
        ("G80 G0 X1", MotionMode::Rapid),
        ("G1 G80 X2", MotionMode::Linear),
        ("G80 G81 X3 R1 Z-1", MotionMode::Cycle(81)),
    ] {
        let b = Block::decode(line.as_bytes()).unwrap();
        assert_eq!(b.motion(), Some(want), "{line}");
    }
    assert!(Block::decode(b"G0 G1 X1").is_err());
}

#[test]
fn decodes_groups_words_and_comments() {
    let b = Block::decode(b"N10 g20 G64 P0.01 g1 x1.5 Y - 2 f300 (MSG, hi) ; rest").unwrap();
    assert_eq!(b.units(), Some(Units::Inch));
    assert_eq!(b.code(13), Some(GCode::Path(PathMode::Blend)));
    assert_eq!(b.code(99), None);
    assert_eq!(b.motion(), Some(MotionMode::Linear));
    assert_eq!(b.value(b'X'), Some(1.5));
    assert_eq!(b.value(b'Y'), Some(-2.0));
    assert_eq!(b.value(b'P'), Some(0.01));
    assert_eq!(b.line_number.map(|l| l.0), Some(10.0));
    assert_eq!(b.comments.len(), 2);
    assert_eq!(b.comments[0].kind, CommentKind::Message);
    assert_eq!(b.words.len(), 7);
    assert!(b.has_axis());
    assert_eq!(b.axes()[..3], [Some(1.5), Some(-2.0), None]);
    let f = Block::decode(b"G1 F300 I2 J1").unwrap();
    assert!(!f.has_axis());
    assert_eq!(f.axes(), [None; 9]);
    assert!(Block::decode(b"G1 W-1").unwrap().has_axis());
}

/// Any two G codes on a line: refused when of one group (but a G80
/// beside another motion code, which gives way), kept by group
/// otherwise; a line of one code and an axis word is a plain move for
/// G0-G3 alone.
#[test]
fn one_code_a_group() {
    let all: Vec<GCode> = (0..=1000u16).filter_map(GCode::from_code10).collect();
    let name = |g: GCode| g.name();
    let g80 = GCode::Motion(MotionMode::CancelCycle);
    for &a in &all {
        let one = Block::decode(format!("{} X1", name(a)).as_bytes()).unwrap();
        assert_eq!(one.code(a.group()), Some(a));
        let plain = matches!(
            a,
            GCode::Motion(
                MotionMode::Rapid | MotionMode::Linear | MotionMode::ArcCw | MotionMode::ArcCcw
            )
        );
        assert_eq!(one.is_plain_move(), plain, "{a:?}");
        for &b in &all {
            let line = format!("{} {}", name(a), name(b));
            let got = Block::decode(line.as_bytes());
            if a.group() != b.group() {
                let got = got.unwrap();
                assert_eq!(
                    (got.code(a.group()), got.code(b.group())),
                    (Some(a), Some(b))
                );
                let mut want = vec![a, b];
                want.sort_by_key(|g| g.group());
                assert_eq!(got.modal_codes().collect::<Vec<_>>(), want, "{line}");
            } else if a == g80 || b == g80 {
                let other = if a == g80 { b } else { a };
                let got = got.unwrap();
                assert_eq!(got.code(1), Some(other), "{line}");
                assert_eq!(got.modal_codes().count(), 1);
            } else {
                assert_eq!(
                    got.unwrap_err().what,
                    DecodeProblem::GroupConflict,
                    "{line}"
                );
            }
        }
    }
    // The room is cleared between lines.
    let mut b = Block::decode(b"G20 G91 G1 X1").unwrap();
    b.decode_into(b"X2").unwrap();
    assert_eq!(
        (b.units(), b.motion(), b.modal_codes().count()),
        (None, None, 0)
    );
    assert!(b.is_plain_move());
}

#[test]
fn decodes_codes() {
    let b = Block::decode(b"G59.1 G43.2 H2 G98 G83 M6 T3 M61 Q1").unwrap();
    assert_eq!(b.coord(), Some(CoordSystem(7)));
    assert_eq!(b.coord().map(|c| c.code10()), Some(591));
    assert_eq!(b.tool_length(), Some(ToolLength::Add));
    assert_eq!(b.retract(), Some(Retract::Initial));
    assert_eq!(b.motion(), Some(MotionMode::Cycle(83)));
    let ms: Vec<MCode> = b.m_codes().map(|m| m.0).collect();
    assert_eq!(ms, vec![MCode::ToolChange, MCode::SetTool]);
    assert!(Block::decode(b"%").unwrap().percent);
    assert!(Block::decode(b"/G0 X1").unwrap().block_delete);
    assert_eq!(
        Block::decode(b"G0 X1 X2").unwrap_err().what,
        DecodeProblem::GroupConflict
    );
    assert!(Block::decode(b"G0 X").is_err());
    assert!(Block::decode(b"G0 (x").is_err());
    assert!(Block::decode(b"G12.5").is_err());
    assert_eq!(Block::decode(b"G54").unwrap().coord(), Some(CoordSystem(1)));
    assert_eq!(Block::decode(b"G59").unwrap().coord(), Some(CoordSystem(6)));
}
