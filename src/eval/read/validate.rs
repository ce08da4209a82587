//! The G-code checks the reference makes on every block before running it:
//! known codes, modal-group conflicts, words without a code that uses them,
//! feed rates, arcs. A program LinuxCNC would reject is rejected here too,
//! with the word that is wrong.

use crate::diag::ErrorKind;
use crate::diag::{MachineError, SyntaxError};

use crate::codes::g_tenths;
use crate::codes::{
    CutterComp, Distance, FeedMode, GCode, MCode, MotionMode, NonModal, PathMode, Plane,
    SpindleDir, SpindleMode, ToolLength,
};
use crate::diag::BlockError;
use crate::eval::state::checked::{Checked, G80, LineCodes};
use crate::eval::state::cycle::{Cycle, depth_axis};
use crate::eval::state::nurbs::{NO_MOTION, NURBS, Nurbs};
use crate::rules::Modes;

use MotionMode as M;

/// Modal group of an M-code, or None for an unknown code (M100–M199 are
/// the user's, checked on their own).
fn m_group(m: MCode) -> Option<u8> {
    Some(match m {
        MCode::Pause { .. } | MCode::End { .. } | MCode::PalletPause | MCode::Other(98 | 99) => 4,
        MCode::ToolChange | MCode::SetTool => 6,
        MCode::Spindle(_) | MCode::Orient => 7,
        MCode::Mist | MCode::Flood | MCode::CoolantOff => 8,
        MCode::Override(_) => 9,
        MCode::Io(_) => 5,
        MCode::State(_) => 10,
        MCode::User(_) | MCode::Other(_) => return None,
    })
}

/// Codes that take the axis words (besides motion codes, and G53, which
/// moves in G0 or G1): [`NonModal::takes_axis_words`].
fn g_uses_axes(g: GCode) -> bool {
    matches!(g, GCode::NonModal(n) if n.takes_axis_words() && n != NonModal::MachineCoords)
}

/// G41/G42 or G41.1/G42.1.
fn comp_on(g: GCode) -> bool {
    matches!(g, GCode::CutterComp(c) if c != CutterComp::Off)
}

const G40: GCode = GCode::CutterComp(CutterComp::Off);

/// An arc (G2 or G3).
fn arc(m: MotionMode) -> bool {
    matches!(m, M::ArcCw | M::ArcCcw)
}

/// G71, G72 and their .1 and .2 (rough turning and facing).
fn rough(m: MotionMode) -> bool {
    matches!(
        m,
        M::LatheCycle {
            number: 71 | 72,
            ..
        }
    )
}

/// Checks a block. `words` are (letter, value) in line order; returns the
/// error and the index of the word it concerns, or the block's codes as
/// the checks decoded them (and whether it runs a lathe cycle, G70–G72).
pub(in crate::eval) fn check_block(
    words: &[(u8, f64)],
    modal: &Modes,
    points: &Nurbs,
    cycle: &Cycle,
    user_m: u128,
) -> Result<Checked, (ErrorKind, Option<usize>)> {
    if simple_block_ok(words, modal) {
        return Ok(Checked::Simple);
    }
    full_check(words, modal, points, cycle, user_m)
}

/// Modal group of the user M-codes M100-M199 (one group: two on a line are
/// refused, as by the reference).
const USER_M_GROUP: u8 = 11;

const fn bit(c: u8) -> u32 {
    1 << (c - b'a')
}

/// Fast acceptance of the most common blocks (G0/G1 moves with axis, F and
/// S words). Anything it does not clearly accept goes to the full check.
#[inline]
fn simple_block_ok(words: &[(u8, f64)], modal: &Modes) -> bool {
    const SIMPLE: u32 = bit(b'g')
        | bit(b'x')
        | bit(b'y')
        | bit(b'z')
        | bit(b'a')
        | bit(b'b')
        | bit(b'c')
        | bit(b'f')
        | bit(b's');
    const AXES: u32 = bit(b'x') | bit(b'y') | bit(b'z') | bit(b'a') | bit(b'b') | bit(b'c');
    let mut mask = 0u32;
    let mut g = None;
    let mut feed = None;
    let mut speed = None;
    for &(l, v) in words {
        if !l.is_ascii_lowercase() {
            return false;
        }
        let b = bit(l);
        if b & SIMPLE == 0 || (mask & b != 0) {
            return false;
        }
        mask |= b;
        match l {
            b'g' => g = Some(v),
            b'f' | b's' if v < 0.0 => return false,
            b'f' => feed = Some(v),
            b's' => speed = Some(v),
            _ => {}
        }
    }
    let motion = match g {
        None => modal.motion,
        Some(0.0) => M::Rapid,
        Some(1.0) => M::Linear,
        Some(_) => return false,
    };
    let moves = mask & AXES != 0 || g.is_some();
    match motion {
        M::Rapid => true,
        M::Linear => {
            !moves
                || (modal.feed_mode != FeedMode::InverseTime
                    && feed.unwrap_or(modal.feed) != 0.0
                    && (modal.feed_mode != FeedMode::PerRev || speed.unwrap_or(modal.speed) != 0.0))
        }
        _ => false,
    }
}

/// A check's result: the error and the index of the word it concerns.
type Check = Result<(), (ErrorKind, Option<usize>)>;

/// The code a G word of value `v` stands for, as the reference reads it
/// (see [`g_tenths`]), or why it stands for none.
fn g_word(v: f64) -> Result<GCode, BlockError> {
    if !(0.0..100.0).contains(&v) {
        return Err(BlockError::GCodeOutOfRange);
    }
    let g10 = g_tenths(v).ok_or(BlockError::UnknownGCodeFraction)?;
    GCode::from_code10(g10 as u16).ok_or_else(|| BlockError::UnknownGCode {
        code: crate::emit::number_string(v, None),
    })
}

fn bad<T>(e: BlockError, at: Option<usize>) -> Result<T, (ErrorKind, Option<usize>)> {
    Err((ErrorKind::Block(e), at))
}

/// A block's words decoded once for the checks: its G and M codes with
/// the index of their word, where each other letter is, and what follows
/// from them in the modal state the block meets.
struct Decoded<'a> {
    words: &'a [(u8, f64)],
    modal: &'a Modes,
    gs: &'a [(GCode, usize)],
    ms: &'a [(MCode, usize)],
    has: &'a [Option<u8>; 128],
    /// The first axis word.
    axis_word: Option<usize>,
    /// The motion code on the line.
    motion_here: Option<MotionMode>,
    /// The motion mode the block runs in.
    motion: MotionMode,
    /// The feed mode the block moves in (G93/G94/G95 on the line first).
    feed_mode: FeedMode,
    /// A NURBS block (G5.2 ... G5.3).
    nurbs: bool,
    /// The G5.3 word.
    g53: Option<usize>,
    /// The non-motion code that takes the axis words (G43.1 without a
    /// motion code on the line takes them as offsets).
    axis_g0: Option<GCode>,
}

impl<'a> Decoded<'a> {
    fn new(
        words: &'a [(u8, f64)],
        modal: &'a Modes,
        gs: &'a [(GCode, usize)],
        ms: &'a [(MCode, usize)],
        has: &'a [Option<u8>; 128],
    ) -> Decoded<'a> {
        const G431: GCode = GCode::ToolLength(ToolLength::Dynamic);
        let at = |c: u8| has[c as usize].map(usize::from);
        let axis_word = b"xyzabcuvw".iter().find_map(|&c| at(c));
        let motion_here = gs.iter().find_map(|&(g, _)| match g {
            GCode::Motion(m) => Some(m),
            _ => None,
        });
        let feed_mode = gs
            .iter()
            .find_map(|&(g, _)| match g {
                GCode::FeedMode(f) => Some(f),
                _ => None,
            })
            .unwrap_or(modal.feed_mode);
        let axis_g0 = gs
            .iter()
            .find(|(g, _)| g_uses_axes(*g))
            .map(|x| x.0)
            .or_else(|| (gs.iter().any(|g| g.0 == G431) && motion_here.is_none()).then_some(G431));
        let motion = motion_here.unwrap_or(modal.motion);
        Decoded {
            words,
            modal,
            gs,
            ms,
            has,
            axis_word,
            motion_here,
            motion,
            feed_mode,
            nurbs: motion == NURBS,
            g53: gs
                .iter()
                .find(|g| g.0 == GCode::Motion(M::NurbsEnd))
                .map(|g| g.1),
            axis_g0,
        }
    }

    /// Index of the word with this letter.
    fn has_at(&self, c: u8) -> Option<usize> {
        self.has[c as usize].map(usize::from)
    }

    /// Whether a G code of the line is one `is` accepts.
    fn g_on(&self, is: impl Fn(GCode) -> bool) -> bool {
        self.gs.iter().any(|&(g, _)| is(g))
    }

    /// The index of the first G word `is` accepts.
    fn g_at(&self, is: impl Fn(GCode) -> bool) -> Option<usize> {
        self.gs.iter().find(|&&(g, _)| is(g)).map(|x| x.1)
    }

    /// This G code is on the line.
    fn has_g(&self, code: GCode) -> bool {
        self.gs.iter().any(|&(g, _)| g == code)
    }

    /// Whether an M code of the line is one `is` accepts.
    fn m_on(&self, is: impl Fn(MCode) -> bool) -> bool {
        self.ms.iter().any(|&(m, _)| is(m))
    }

    /// The index of the first M word `is` accepts.
    fn m_at(&self, is: impl Fn(MCode) -> bool) -> Option<usize> {
        self.ms.iter().find(|&&(m, _)| is(m)).map(|x| x.1)
    }

    /// A user M-code (M100-M199) is on the line: it takes P and Q.
    fn user_m(&self) -> bool {
        self.m_on(|m| matches!(m, MCode::User(_)))
    }

    fn value(&self, c: u8) -> Option<f64> {
        self.has_at(c).map(|i| self.words[i].1)
    }

    /// An absent P or Q reads as -1 in the reference, so a P-1 or Q-1 is
    /// no P or Q where one is required.
    fn given(&self, c: u8) -> bool {
        self.value(c).is_some_and(|v| v != -1.0)
    }
}

/// Which lines a check is for: lines that run, or a lathe cycle's contour
/// lines (see [`check_contour_line`]), which skip what only running needs.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Lines {
    Run,
    Contour,
}

/// A block's codes and where its other words are, as the reading of a
/// line finds them (see [`read_codes`]).
struct ReadCodes {
    gbuf: [(GCode, usize); 16],
    gn: usize,
    mbuf: [(MCode, usize); 16],
    mn: usize,
    has: [Option<u8>; 128],
    /// The lathe cycle's G word.
    lathe: Option<usize>,
    g80_gave_way: bool,
}

impl ReadCodes {
    fn decoded<'a>(&'a self, words: &'a [(u8, f64)], modal: &'a Modes) -> Decoded<'a> {
        Decoded::new(
            words,
            modal,
            &self.gbuf[..self.gn],
            &self.mbuf[..self.mn],
            &self.has,
        )
    }

    fn checked(&self, d: &Decoded<'_>) -> Checked {
        let codes = LineCodes::of(d.gs, d.ms, self.g80_gave_way);
        match self.lathe {
            Some(at) => Checked::Lathe(codes, at),
            None => Checked::Line(codes),
        }
    }
}

/// The G and M words of a block decoded, each group at most once (a G80
/// gives way to another motion code), and where each other letter is.
#[inline]
fn read_codes(words: &[(u8, f64)], user_m: u128) -> Result<ReadCodes, (ErrorKind, Option<usize>)> {
    let mut gseen: [Option<usize>; 16] = [None; 16];
    let mut mseen: [Option<usize>; 16] = [None; 16];
    // Fixed-size scratch: this runs for every line.
    let mut r = ReadCodes {
        gbuf: [(G80, 0usize); 16],
        gn: 0,
        mbuf: [(MCode::Other(0), 0usize); 16],
        mn: 0,
        has: [None::<u8>; 128],
        lathe: None,
        g80_gave_way: false,
    };
    // The code of the motion word recorded in gseen[1].
    let mut motion = None;
    for (i, &(l, v)) in words.iter().enumerate() {
        match l {
            b'g' => {
                let g = match g_word(v) {
                    Ok(g) => g,
                    Err(e) => return bad(e, Some(i)),
                };
                let grp = g.group() as usize;
                // The pairing looks at the codes, not at the words' values
                // (a G80 written G80.000001 is a G80).
                let g80_pair = grp == 1 && gseen[1].is_some() && (g == G80 || motion == Some(G80));
                if gseen[grp].is_some() && !g80_pair {
                    return bad(BlockError::SameGroupG, Some(i));
                }
                if g80_pair {
                    r.g80_gave_way = true;
                    if g == G80 {
                        continue;
                    }
                    // The other code takes the place of the G80 recorded
                    // before: the list stays in line order, without it.
                    if let Some(k) = r.gbuf[..r.gn].iter().position(|x| x.0 == G80) {
                        r.gbuf.copy_within(k + 1..r.gn, k);
                        r.gn -= 1;
                    }
                }
                if matches!(g, GCode::Motion(M::LatheCycle { .. })) {
                    // The lathe cycles run a contour subroutine named by Q
                    // (after a G80 on their line too).
                    r.lathe = Some(i);
                }
                gseen[grp] = Some(i);
                if grp == 1 {
                    motion = Some(g);
                }
                r.gbuf[r.gn] = (g, i);
                r.gn += 1;
            }
            b'm' => {
                if v.fract() != 0.0 || v < 0.0 {
                    return bad(BlockError::UnknownMCodeFraction, Some(i));
                }
                let m = v as i64;
                if m > 199 {
                    return bad(BlockError::MCodeOver199 { m }, Some(i));
                }
                let code = MCode::decode(v);
                let grp = match m_group(code) {
                    Some(g) => g,
                    None if m >= 100 && user_m & (1u128 << (m - 100)) != 0 => USER_M_GROUP,
                    None if m >= 100 => {
                        return Err((
                            ErrorKind::Machine(MachineError::UndeclaredUserM { m }),
                            Some(i),
                        ));
                    }
                    None => return bad(BlockError::UnknownMCode { m }, Some(i)),
                };
                if mseen[grp as usize].is_some() {
                    return bad(BlockError::SameGroupM, Some(i));
                }
                mseen[grp as usize] = Some(i);
                if r.mn == r.mbuf.len() {
                    // (More than four M words are refused before this.)
                    return Err((ErrorKind::Syntax(SyntaxError::TooManyMWords), Some(i)));
                }
                r.mbuf[r.mn] = (code, i);
                r.mn += 1;
            }
            _ => {
                if (l as usize) < 128 {
                    r.has[l as usize] = Some(i.min(255) as u8);
                }
            }
        }
    }
    Ok(r)
}

fn full_check(
    words: &[(u8, f64)],
    modal: &Modes,
    points: &Nurbs,
    cycle: &Cycle,
    user_m: u128,
) -> Result<Checked, (ErrorKind, Option<usize>)> {
    let r = read_codes(words, user_m)?;
    let d = r.decoded(words, modal);
    check_nurbs(&d, points)?;
    check_motion_words(&d)?;
    check_axis_codes(&d)?;
    check_cycle(&d, cycle)?;
    check_axis_values(&d)?;
    check_word_values(&d)?;
    check_unused_words(&d)?;
    check_whole_numbers(&d, Lines::Run)?;
    check_g10(&d)?;
    check_required_words(&d, Lines::Run)?;
    check_feed(&d)?;
    if modal.cutter_comp != CutterComp::Off || d.g_on(comp_on) {
        check_comp(&d)?;
    }
    Ok(r.checked(&d))
}

/// The checks of [`check_block`] the reference makes on a line of a lathe
/// cycle's contour (G70-G72 run their contour subroutine collecting its
/// moves): its codes and the words they take, not what its motion would
/// need to run (a feed rate, arc words, a canned cycle's state, cutter
/// compensation), which the cycle checks itself, nor what its M codes
/// need: they do not run there (a user M-code need not be declared).
/// `modal` has the motion the contour has reached. The line's codes, as
/// decoded.
pub(in crate::eval) fn check_contour_line(
    words: &[(u8, f64)],
    modal: &Modes,
) -> Result<LineCodes, (ErrorKind, Option<usize>)> {
    let r = read_codes(words, u128::MAX)?;
    let d = r.decoded(words, modal);
    check_axis_codes(&d)?;
    check_word_values(&d)?;
    check_unused_words(&d)?;
    check_whole_numbers(&d, Lines::Contour)?;
    check_g10(&d)?;
    check_required_words(&d, Lines::Contour)?;
    Ok(LineCodes::of(d.gs, d.ms, r.g80_gave_way))
}

/// What the reference refuses while cutter compensation is on, and the
/// words G41/G42 and G41.1/G42.1 need. M-codes and the plane are checked
/// with the state before the block, the other G-codes after the block's
/// G40/G41/G42 (the reference's order of execution).
fn check_comp(d: &Decoded<'_>) -> Check {
    let refuse = |e: MachineError, at: usize| Err((ErrorKind::Machine(e), Some(at)));
    let forbid = |action: &'static str, at: Option<usize>| {
        Err((ErrorKind::Machine(MachineError::CompForbids { action }), at))
    };
    let plane_here = d.gs.iter().find_map(|&(g, i)| match g {
        GCode::Plane(p) => Some((p, i)),
        _ => None,
    });
    let before = d.modal.cutter_comp != CutterComp::Off;
    let turning_on = d.gs.iter().find_map(|&(g, i)| match g {
        GCode::CutterComp(c) if c != CutterComp::Off => Some((c, i)),
        _ => None,
    });
    let after = turning_on.is_some() || (before && !d.has_g(G40));
    if before {
        if let Some(i) = d.m_at(|m| m == MCode::ToolChange) {
            return forbid("change tools", Some(i));
        }
        if let Some(i) = d.m_at(|m| matches!(m, MCode::Io(62..=65))) {
            return forbid("set a digital output", Some(i));
        }
        if let Some(i) = d.m_at(|m| m == MCode::Io(66)) {
            return forbid("wait for an input", Some(i));
        }
        if let Some(i) = d.m_at(|m| matches!(m, MCode::Io(67 | 68))) {
            return forbid("set an analog output", Some(i));
        }
        if let Some(i) = d.m_at(|m| matches!(m, MCode::Override(_))) {
            return forbid("enable or disable overrides", Some(i));
        }
        if let Some((p, i)) = plane_here
            && p != d.modal.plane
        {
            return refuse(MachineError::CompPlaneChange, i);
        }
    }
    let plane = plane_here.map_or(d.modal.plane, |p| p.0);
    if let Some((c, i)) = turning_on {
        if plane != Plane::XY && plane != Plane::XZ {
            return refuse(MachineError::CompPlane, i);
        }
        if before {
            return refuse(MachineError::CompAlreadyOn, i);
        }
        if matches!(c, CutterComp::DynamicLeft | CutterComp::DynamicRight) {
            let left = c == CutterComp::DynamicLeft;
            let name = if left { "G41.1" } else { "G42.1" };
            if d.has_at(b'd').is_none() {
                return refuse(MachineError::CompNoDiameter { g: name }, i);
            }
            if let Some(l) = d.has_at(b'l')
                && plane != Plane::XZ
            {
                let what = if left {
                    "G41.1 with an L word (lathe tool orientation)"
                } else {
                    "G42.1 with an L word (lathe tool orientation)"
                };
                return refuse(MachineError::CompLatheTool { what }, l);
            }
        }
    }
    if !after {
        return Ok(());
    }
    if let Some(i) = d.g_at(|g| matches!(g, GCode::ToolLength(_))) {
        return forbid("change the tool length offset", Some(i));
    }
    if let Some(i) = d.g_at(|g| matches!(g, GCode::Coord(_))) {
        return forbid("change the coordinate system", Some(i));
    }
    if let Some(i) = d.g_at(|g| matches!(g, GCode::Path(_))) {
        return forbid("change the path control mode", Some(i));
    }
    if let Some(i) = d.g_at(|g| matches!(g, GCode::Retract(_))) {
        return forbid("change the canned cycle return mode", Some(i));
    }
    if let Some(i) = d.g_at(|g| g == GCode::NonModal(NonModal::SetData)) {
        let l = d.value(b'l').map(|v| v.round() as i32);
        let p = d.value(b'p').map_or(0, |v| (v + 0.0001) as i32);
        let active = d.modal.coord.0 as i32;
        let p = if p == 0 { active } else { p };
        if matches!(l, Some(2 | 20)) && p == active {
            return forbid("change the active coordinate system's offsets", Some(i));
        }
    }
    if let Some(i) = d.g_at(|g| matches!(g, GCode::NonModal(NonModal::Home | NonModal::Home2))) {
        return forbid("use G28 or G30", Some(i));
    }
    if let Some(i) =
        d.g_at(|g| matches!(g, GCode::NonModal(NonModal::SetHome | NonModal::SetHome2)))
    {
        return forbid("set a home position (G28.1, G30.1)", Some(i));
    }
    if let Some(i) = d.g_at(|g| {
        matches!(
            g,
            GCode::NonModal(
                NonModal::LocalOffset
                    | NonModal::SetG92
                    | NonModal::ResetG92
                    | NonModal::SuspendG92
                    | NonModal::RestoreG92
            )
        )
    }) {
        return forbid("change axis offsets (G52, G92)", Some(i));
    }
    let motion_at = d.g_at(|g| matches!(g, GCode::Motion(_)));
    let moves = d.motion_here.is_some() || (d.axis_word.is_some() && d.axis_g0.is_none());
    if moves {
        match d.motion {
            M::Probe(_) => return forbid("probe", motion_at),
            M::CubicSpline | M::QuadSpline => return forbid("make a spline", motion_at),
            _ => {}
        }
    }
    Ok(())
}

/// NURBS blocks: G5.3 after G5.2 with enough points; control points.
fn check_nurbs(d: &Decoded<'_>, points: &Nurbs) -> Check {
    if let Some(at) = d.g53 {
        if d.modal.motion != NURBS {
            return bad(BlockError::NurbsEndWithoutStart, Some(at));
        }
        if let Some(order) = points.short_of_order() {
            return bad(BlockError::NurbsTooFewPoints { order }, Some(at));
        }
    }
    // A control point: on a G5.2 line, a line of axis words in G5.2 mode, or
    // axis words after G5.3 (which start a new block). The checks on P see
    // the points still pending, which G5.3 has just cleared.
    let point = (d.nurbs && (d.motion_here.is_some() || d.axis_word.is_some()))
        || (d.g53.is_some() && d.axis_word.is_some());
    if point {
        let pending = points.pending() && d.g53.is_none();
        let p = d.value(b'p').unwrap_or(-1.0);
        if d.has_at(b'x').is_some() != d.has_at(b'y').is_some() {
            return bad(BlockError::NurbsPointNeedsXY, d.axis_word);
        }
        if pending && d.axis_word.is_none() && p > 0.0 {
            return bad(BlockError::NurbsPWithoutXY, d.has_at(b'p'));
        }
        if pending && p <= 0.0 {
            return bad(
                BlockError::NurbsWeightNeeded,
                d.has_at(b'p').or(d.axis_word),
            );
        }
        let feed = d.value(b'f').unwrap_or(d.modal.feed);
        if d.feed_mode == FeedMode::PerMinute && feed == 0.0 {
            return bad(BlockError::NurbsZeroFeed, d.has_at(b'f'));
        }
    }
    if d.nurbs
        && d.motion_here.is_none()
        && d.axis_word.is_none()
        && let Some(i) = d.has_at(b'p')
    {
        return bad(BlockError::WordUnused { letter: 'p' }, Some(i));
    }
    Ok(())
}

/// Motion codes that need axis words, and their required words.
fn check_motion_words(d: &Decoded<'_>) -> Check {
    if let Some(m) = d.motion_here {
        let needs_axes = matches!(m, M::Probe(_) | M::Cycle(73 | 81..=89));
        if needs_axes && d.axis_word.is_none() {
            return bad(BlockError::AxesMissing, None);
        }
        // P and Q are sticky while the same cycle stays in effect, its
        // code written again or not.
        let again = d.modal.motion == m;
        if matches!(m, M::Cycle(82 | 86 | 88 | 89)) && !d.given(b'p') && !again {
            return bad(BlockError::CycleDwellMissing, None);
        }
        if matches!(m, M::Cycle(73 | 83)) && !d.given(b'q') && !again {
            return bad(BlockError::PeckQMissing, None);
        }
        if m == M::ThreadCycle && d.has_at(b'p').is_none() {
            return bad(BlockError::G76PMissing, None);
        }
        if m == M::ThreadCycle {
            // The reference's order; a missing word counts as 0.
            let v = |c: u8| d.value(c).unwrap_or(0.0);
            if v(b'i') == 0.0 {
                return bad(BlockError::G76IZero, None);
            }
            if v(b'j') <= 0.0 {
                return bad(BlockError::G76JNotPositive, None);
            }
            if v(b'k') <= v(b'j') {
                return bad(BlockError::G76KNotAboveJ, None);
            }
        }
        if arc(m)
            && ![b'i', b'j', b'k', b'r']
                .iter()
                .any(|&c| d.has_at(c).is_some())
        {
            return bad(BlockError::ArcWordsMissing, None);
        }
        if matches!(m, M::Thread | M::RigidTap)
            && d.modal.spindle == SpindleDir::Off
            && !d.m_on(|m| matches!(m, MCode::Spindle(SpindleDir::Cw | SpindleDir::Ccw)))
        {
            return bad(BlockError::SpindleStoppedG33, None);
        }
    }
    Ok(())
}

/// Two codes that both take the axis words.
fn check_axis_codes(d: &Decoded<'_>) -> Check {
    if let (Some(_), Some(_), Some(i)) = (d.motion_here, d.axis_g0, d.axis_word)
        && d.motion_here != Some(M::CancelCycle)
    {
        return bad(BlockError::TwoAxisGCodes, Some(i));
    }
    Ok(())
}

/// A canned cycle that runs: its code is on the line, or it is the motion
/// mode and the line has axis words no other code takes.
fn check_cycle(d: &Decoded<'_>, cycle: &Cycle) -> Check {
    // A canned cycle runs: its code is on the line, or it is the motion mode
    // and the line has axis words no other code takes.
    let cycle_runs = d.motion.is_canned_cycle()
        && (d.motion_here.is_some() || (d.axis_word.is_some() && d.axis_g0.is_none()));
    if cycle_runs {
        // Entering the cycle (not repeating it) needs the depth and R.
        let first = d.modal.motion != d.motion;
        let (depth, name) = depth_axis(d.modal.plane);
        if first && d.has_at(depth).is_none() {
            return bad(BlockError::CycleDepthMissing { axis: name }, None);
        }
        if let Some(i) = [b'a', b'b', b'c'].iter().find_map(|&c| d.has_at(c)) {
            return bad(BlockError::RotaryInCycle, Some(i));
        }
        let r = match d.value(b'r') {
            Some(r) => r,
            None if !first => cycle.r,
            None => return bad(BlockError::CycleRMissing, None),
        };
        if d.value(b'l') == Some(0.0) {
            return bad(BlockError::CycleL0, d.has_at(b'l'));
        }
        if d.feed_mode == FeedMode::InverseTime {
            return bad(BlockError::CycleInverseTime, None);
        }
        if d.modal.cutter_comp != CutterComp::Off && !d.has_g(G40) || d.g_on(comp_on) {
            return bad(BlockError::CycleWithComp, None);
        }
        // The R plane must not be below the bottom of the hole (in G91 the
        // depth is relative to R, so it must not be positive).
        let cc = d.value(depth).unwrap_or(cycle.depth);
        let absolute = d.has_g(GCode::Distance(Distance::Absolute))
            || (d.modal.distance == Distance::Absolute
                && !d.has_g(GCode::Distance(Distance::Incremental)));
        let below = if absolute { r < cc } else { cc > 0.0 };
        if below {
            return bad(BlockError::CycleRBelowDepth { axis: name }, d.has_at(b'r'));
        }
        let spindle =
            d.ms.iter()
                .rev()
                .find_map(|&(m, _)| match m {
                    MCode::Spindle(dir) => Some(dir),
                    _ => None,
                })
                .unwrap_or(d.modal.spindle);
        let spindle_msg = match (d.motion, spindle) {
            (M::Cycle(84 | 74 | 86 | 87 | 88), SpindleDir::Off) => {
                Some(BlockError::CycleSpindleStopped)
            }
            (M::Cycle(84), SpindleDir::Ccw) => Some(BlockError::G84SpindleCcw),
            (M::Cycle(74), SpindleDir::Cw) => Some(BlockError::G74SpindleCw),
            _ => None,
        };
        if let Some(msg) = spindle_msg {
            return bad(msg, None);
        }
    }
    Ok(())
}

/// Axis words with nothing to use them; polar and X/Y words together.
fn check_axis_values(d: &Decoded<'_>) -> Check {
    if let Some(i) = d.axis_word
        && d.axis_g0.is_none()
        && (d.motion == M::CancelCycle || (d.motion_here.is_none() && d.motion == NO_MOTION))
    {
        return bad(
            if d.motion_here == Some(M::CancelCycle) {
                BlockError::AxesWithG80
            } else {
                BlockError::AxesWithoutGCode
            },
            Some(i),
        );
    }
    if (d.has_at(b'@').is_some() || d.has_at(b'^').is_some())
        && (d.has_at(b'x').is_some() || d.has_at(b'y').is_some())
    {
        return bad(BlockError::PolarWithXY, d.has_at(b'@').or(d.has_at(b'^')));
    }
    // rs274 checks the plane in effect before the line.
    if d.modal.plane != Plane::XY
        && let Some(i) = d.has_at(b'@').or(d.has_at(b'^'))
    {
        return bad(BlockError::PolarOutsideXY, Some(i));
    }
    Ok(())
}

/// Values a word may not have.
fn check_word_values(d: &Decoded<'_>) -> Check {
    for (i, &(l, v)) in d.words.iter().enumerate() {
        // L is read as a whole number, and never negative.
        if l == b'l' {
            let n = crate::parse::integer_value(v).map_err(|k| (k, Some(i)))?;
            if n < 0 {
                return bad(BlockError::NegativeL, Some(i));
            }
        }
        if l == b'f' && v < 0.0 {
            return bad(BlockError::NegativeF, None);
        }
        if l == b's' && v < 0.0 {
            return bad(BlockError::NegativeS, None);
        }
        if l == b't' && v < 0.0 {
            return bad(BlockError::NegativeT, None);
        }
    }
    Ok(())
}

/// Words that need a code to use them.
fn check_unused_words(d: &Decoded<'_>) -> Check {
    // Motion that takes I, J and K: arcs, splines, G33.1, G76, G87.
    let arcish_motion = |m: MotionMode| {
        arc(m)
            || matches!(
                m,
                M::CubicSpline | M::QuadSpline | M::RigidTap | M::ThreadCycle | M::Cycle(87)
            )
    };
    let set_data = GCode::NonModal(NonModal::SetData);
    let arcish = d.g_on(|g| matches!(g, GCode::Motion(m) if arcish_motion(m)) || g == set_data)
        || (d.motion_here.is_none() && arcish_motion(d.modal.motion) && d.axis_word.is_some());
    let uses = |letter: u8, ok: bool, msg: BlockError| -> Result<(), (ErrorKind, Option<usize>)> {
        match d.has_at(letter) {
            Some(i) if !ok => bad(msg, Some(i)),
            _ => Ok(()),
        }
    };
    let rough = rough(d.motion);
    let lathe = rough || d.motion == G70;
    uses(
        b'i',
        arcish || arc(d.motion) || rough,
        BlockError::WordUnused { letter: 'i' },
    )?;
    uses(
        b'j',
        arcish || arc(d.motion),
        BlockError::WordUnused { letter: 'j' },
    )?;
    uses(
        b'k',
        arcish
            || arc(d.motion)
            || matches!(
                d.motion,
                M::Thread | M::RigidTap | M::ThreadCycle | M::Cycle(87)
            ),
        BlockError::WordUnused { letter: 'k' },
    )?;
    let canned = matches!(d.motion, M::Cycle(_) | M::ThreadCycle);
    uses(
        b'r',
        arc(d.motion)
            || canned
            || d.has_g(set_data)
            || d.axis_g0 == Some(set_data)
            || d.m_on(|m| m == MCode::Orient)
            || rough,
        BlockError::WordUnused { letter: 'r' },
    )?;
    uses(b'p', takes_p(d), BlockError::WordUnused { letter: 'p' })?;
    uses(
        b'q',
        takes_q(d) || lathe,
        BlockError::WordUnused { letter: 'q' },
    )?;
    uses(
        b'h',
        d.g_on(|g| {
            matches!(
                g,
                GCode::ToolLength(ToolLength::Apply | ToolLength::Add)
                    | GCode::Motion(M::ThreadCycle)
            )
        }),
        BlockError::WordUnused { letter: 'h' },
    )?;
    uses(
        b'd',
        d.g_on(|g| comp_on(g) || g == GCode::SpindleMode(SpindleMode::ConstantSurface)) || lathe,
        BlockError::WordUnused { letter: 'd' },
    )?;
    uses(
        b'e',
        d.has_g(GCode::Motion(M::ThreadCycle))
            || d.m_on(|m| matches!(m, MCode::Io(66..=68)))
            || d.motion == G70,
        BlockError::WordUnused { letter: 'e' },
    )?;
    uses(
        b'l',
        // (G74 takes no L in the reference.)
        d.g_on(|g| g == set_data || comp_on(g) || g == GCode::Motion(M::ThreadCycle))
            || (canned && d.motion != M::Cycle(74))
            || d.m_on(|m| matches!(m, MCode::Io(66) | MCode::Other(98)))
            // A NURBS block's motion, on its line or in effect (its
            // control points' lines).
            || d.motion == M::Nurbs,
        BlockError::WordUnused { letter: 'l' },
    )?;
    uses(
        b'$',
        d.m_on(|m| matches!(m, MCode::Spindle(_) | MCode::Orient | MCode::Override(51)))
            || d.g_on(|g| {
                matches!(
                    g,
                    GCode::Motion(M::Thread | M::RigidTap | M::ThreadCycle)
                        | GCode::FeedMode(FeedMode::PerRev)
                        | GCode::SpindleMode(_)
                )
            }),
        BlockError::WordUnused { letter: '$' },
    )?;
    Ok(())
}

/// The G70 lathe cycle (finishing).
const G70: MotionMode = M::LatheCycle { number: 70, sub: 0 };

/// Whether a code of the block takes a P word.
fn takes_p(d: &Decoded<'_>) -> bool {
    d.g_on(|g| {
        matches!(
            g,
            GCode::Motion(
                M::ArcCw
                    | M::ArcCcw
                    | M::CubicSpline
                    | M::Nurbs
                    | M::ThreadCycle
                    | M::Cycle(82 | 84 | 86 | 88 | 89)
            ) | GCode::NonModal(NonModal::Dwell | NonModal::SetData)
                | GCode::Path(PathMode::Blend)
        )
    }) || matches!(
        d.motion,
        M::ArcCw | M::ArcCcw | M::Nurbs | M::Cycle(82 | 84 | 86 | 88 | 89) | G70
    ) || d.m_on(|m| {
        matches!(
            m,
            MCode::Orient | MCode::Override(50..=53) | MCode::Io(62..=66) | MCode::Other(98)
        )
    }) || d.user_m()
}

/// Whether a code of the block takes a Q word (the lathe cycles aside).
fn takes_q(d: &Decoded<'_>) -> bool {
    d.g_on(|g| {
        matches!(
            g,
            GCode::Motion(M::CubicSpline | M::ThreadCycle | M::Cycle(73 | 83))
                | GCode::NonModal(NonModal::SetData)
                | GCode::Path(PathMode::Blend)
        )
    }) || matches!(d.motion, M::Cycle(73 | 83))
        || d.m_on(|m| matches!(m, MCode::Orient | MCode::Io(66..=68) | MCode::SetTool))
        || d.user_m()
}

/// Whole numbers, peck depths, H, and G53's conditions.
fn check_whole_numbers(d: &Decoded<'_>, lines: Lines) -> Check {
    let runs = lines == Lines::Run;
    // Whole numbers.
    let g41_g42 = d.g_on(|g| matches!(g, GCode::CutterComp(CutterComp::Left | CutterComp::Right)));
    for (i, &(l, v)) in d.words.iter().enumerate() {
        if matches!(l, b't' | b'h') && crate::parse::integer_value(v).is_err() {
            return Err((
                ErrorKind::Syntax(SyntaxError::NonInteger { value: v }),
                Some(i),
            ));
        }
        // The reference's test: the D value within 0.0001 of the integer
        // (int)(D + 0.5), which also refuses every negative D.
        if runs && l == b'd' && g41_g42 && (((v + 0.5) as i64) as f64 - v).abs() >= 0.0001 {
            return bad(BlockError::CompDNotWhole, Some(i));
        }
    }
    // Peck depths of a running G73/G83.
    if runs
        && matches!(d.motion, M::Cycle(73 | 83))
        && (d.motion_here.is_some() || d.axis_word.is_some())
        && d.value(b'q').is_some_and(|q| q != -1.0 && q <= 0.0)
    {
        return bad(BlockError::PeckQNotPositive, d.has_at(b'q'));
    }
    if d.value(b'h').is_some_and(|h| h < -1.0) {
        return bad(BlockError::NegativeH, d.has_at(b'h'));
    }
    // G53 moves in machine coordinates: with G0 or G1, never incremental.
    if let Some(at) = d.g_at(|g| g == GCode::NonModal(NonModal::MachineCoords)) {
        let motion_to_be = d.motion_here.or(d.axis_word.map(|_| d.modal.motion));
        if !matches!(motion_to_be, Some(M::Rapid | M::Linear)) {
            return bad(BlockError::G53NeedsG0G1, Some(at));
        }
        let incremental = d.has_g(GCode::Distance(Distance::Incremental))
            || (d.modal.distance == Distance::Incremental
                && !d.has_g(GCode::Distance(Distance::Absolute)));
        if incremental {
            return bad(BlockError::G53Incremental, Some(at));
        }
    }
    Ok(())
}

/// G10's L and P.
fn check_g10(d: &Decoded<'_>) -> Check {
    // G10's L and P: P is a tool number (L1, L10, L11) or a coordinate
    // system (L2, L20), rounded half away from zero; an absent P reads as
    // -1, and only a P above its rounding by more than 0.0001 is refused.
    if d.has_g(GCode::NonModal(NonModal::SetData)) {
        let p = d.value(b'p').unwrap_or(-1.0);
        let l = d.value(b'l').map_or(-1, |l| l.round() as i64);
        let p_int = if p >= 0.0 {
            (p + 0.5).trunc()
        } else {
            (p - 0.5).trunc()
        };
        if !matches!(l, 1 | 2 | 10 | 11 | 20) {
            return bad(BlockError::G10BadL, d.has_at(b'l'));
        }
        if p + 0.0001 - p_int > 0.0002 {
            return bad(BlockError::G10PNotWhole, d.has_at(b'p'));
        }
        if matches!(l, 2 | 20) && !(0.0..=9.0).contains(&p_int) {
            return bad(BlockError::G10CoordPRange, d.has_at(b'p'));
        }
        if matches!(l, 1 | 10 | 11) && p_int < 1.0 {
            return bad(BlockError::G10ToolPRange, d.has_at(b'p'));
        }
    }
    Ok(())
}

/// Codes that need words.
fn check_required_words(d: &Decoded<'_>, lines: Lines) -> Check {
    let g4 = d.g_at(|g| g == GCode::NonModal(NonModal::Dwell));
    if g4.is_some() && !d.given(b'p') {
        return bad(BlockError::G4PMissing, g4);
    }
    if d.has_g(GCode::SpindleMode(SpindleMode::ConstantSurface)) && d.has_at(b's').is_none() {
        return bad(BlockError::G96SMissing, None);
    }
    if lines == Lines::Contour {
        return Ok(());
    }
    if d.m_on(|m| matches!(m, MCode::Io(62..=65))) && d.has_at(b'p').is_none() {
        return bad(BlockError::M62PMissing, None);
    }
    if d.m_on(|m| m == MCode::Io(66)) && !d.given(b'p') && d.has_at(b'e').is_none() {
        return bad(BlockError::M66PEMissing, None);
    }
    if d.m_on(|m| m == MCode::SetTool) && d.has_at(b'q').is_none() {
        return bad(BlockError::M61QMissing, None);
    }
    Ok(())
}

/// Motion needing a feed rate; arcs needing their words; G33's K.
fn check_feed(d: &Decoded<'_>) -> Check {
    let moves = d.motion_here.is_some() || d.axis_word.is_some();
    let feeds = matches!(
        d.motion,
        M::Linear | M::ArcCw | M::ArcCcw | M::CubicSpline | M::QuadSpline | M::Cycle(73 | 81..=89)
    );
    if moves && d.axis_g0.is_none() && feeds {
        let feed = d.words.iter().rev().find(|w| w.0 == b'f').map(|w| w.1);
        let inverse = d.has_g(GCode::FeedMode(FeedMode::InverseTime))
            || (d.modal.feed_mode == FeedMode::InverseTime
                && !d.g_on(|g| {
                    matches!(g, GCode::FeedMode(FeedMode::PerMinute | FeedMode::PerRev))
                }));
        if inverse {
            if feed.is_none() && d.axis_word.is_some() {
                return bad(BlockError::InverseTimeFMissing, None);
            }
        } else if feed.unwrap_or(d.modal.feed) == 0.0 {
            return bad(BlockError::ZeroFeed, None);
        }
        // G1/G2/G3 per revolution need a spindle speed (the S value, not
        // whether the spindle turns; the cycles do not check it).
        let per_rev = d.has_g(GCode::FeedMode(FeedMode::PerRev))
            || (d.modal.feed_mode == FeedMode::PerRev
                && !d.g_on(|g| {
                    matches!(
                        g,
                        GCode::FeedMode(FeedMode::PerMinute | FeedMode::InverseTime)
                    )
                }));
        let speed = d.words.iter().rev().find(|w| w.0 == b's').map(|w| w.1);
        if per_rev
            && matches!(d.motion, M::Linear | M::ArcCw | M::ArcCcw)
            && speed.unwrap_or(d.modal.speed) == 0.0
        {
            return bad(BlockError::ZeroSpindlePerRev, None);
        }
        if arc(d.motion) && d.axis_word.is_some() {
            let arc = ["i", "j", "k", "r"]
                .iter()
                .any(|c| d.has[c.as_bytes()[0] as usize].is_some());
            if !arc {
                return bad(BlockError::ArcWordsMissing, None);
            }
        }
    }
    if d.motion_here
        .is_some_and(|m| matches!(m, M::Thread | M::RigidTap))
        && d.has_at(b'k').is_none()
    {
        return bad(BlockError::G33KMissing, None);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn checked(words: &[(u8, f64)]) -> Checked {
        let m = Modes::default();
        check_block(words, &m, &Nurbs::default(), &Cycle::default(), 0).expect("accepted")
    }

    fn gs(c: &LineCodes) -> Vec<GCode> {
        c.gs().to_vec()
    }

    /// A lathe cycle's other words keep the line's codes without the
    /// cycle's, and a G80 that gave way to it (before it or after it).
    #[test]
    fn lathe_cycle_codes_and_the_other_words_codes() {
        const G71: GCode = GCode::Motion(M::LatheCycle { number: 71, sub: 0 });
        const G18: GCode = GCode::Plane(Plane::XZ);
        let rest = [(b'q', 10.0), (b'x', 12.0), (b'z', 2.0), (b'd', 1.0)];
        // The G words, the cycle's index, the codes, the other words' codes.
        type Case = (&'static [f64], usize, &'static [GCode], &'static [GCode]);
        let cases: &[Case] = &[
            (&[71.0], 0, &[G71], &[]),
            (&[18.0, 71.0], 1, &[G18, G71], &[G18]),
            (&[71.0, 80.0], 0, &[G71], &[G80]),
            (&[80.0, 71.0, 18.0], 1, &[G71, G18], &[G80, G18]),
        ];
        for &(g, at, codes, others) in cases {
            let mut words: Vec<(u8, f64)> = g.iter().map(|&v| (b'g', v)).collect();
            words.extend(rest);
            let Checked::Lathe(c, i) = checked(&words) else {
                panic!("{g:?}: not a lathe cycle");
            };
            assert_eq!((i, gs(&c)), (at, codes.to_vec()), "{g:?}");
            assert_eq!(gs(&c.without_lathe_cycle()), others.to_vec(), "{g:?}");
        }
    }

    /// Codes come in line order, a G80 beside another motion code left
    /// out; the fast acceptance hands on its G0/G1 in the G word.
    #[test]
    fn codes_in_line_order() {
        let Checked::Line(c) = checked(&[(b'g', 80.0), (b'g', 17.0), (b'g', 0.0), (b'm', 8.0)])
        else {
            panic!("not a checked line");
        };
        let want = [GCode::Plane(Plane::XY), GCode::Motion(M::Rapid)];
        assert_eq!(gs(&c), want.to_vec());
        assert_eq!(c.ms().to_vec(), vec![MCode::Flood]);
        let simple = [(b'x', 1.0), (b'g', 1.0), (b'f', 5.0)];
        assert!(matches!(checked(&simple), Checked::Simple));
        assert_eq!(
            gs(&LineCodes::simple(&simple)),
            vec![GCode::Motion(M::Linear)]
        );
        assert!(LineCodes::simple(&[(b'x', 1.0)]).gs().is_empty());
    }
}
