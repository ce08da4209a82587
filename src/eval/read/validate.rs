//! The G-code checks the reference makes on every block before running it:
//! known codes, modal-group conflicts, words without a code that uses them,
//! feed rates, arcs. A program LinuxCNC would reject is rejected here too,
//! with the word that is wrong.

use crate::diag::ErrorKind;

use crate::codes::SpindleDir;
use crate::codes::{CutterComp, FeedMode, MotionMode};
use crate::diag::BlockError;
use crate::eval::state::Modal;
use crate::eval::state::cycle::{Cycle, depth_axis};
use crate::eval::state::nurbs::{NURBS, Nurbs};

/// The motion mode as a code ×10 (-1: none, after G5.3).
fn motion10(m: MotionMode) -> i32 {
    match m {
        MotionMode::NurbsEnd => NO_MOTION,
        m => m.code10() as i32,
    }
}

const NO_MOTION: i32 = -1;

/// Whether a motion mode (G-code ×10) is a canned cycle.
fn is_cycle(motion: i32) -> bool {
    matches!(motion, 730 | 740 | 810..=890)
}

/// Modal group of a G-code (×10), or None for an unknown code.
fn g_group(g: i32) -> Option<u8> {
    Some(match g {
        0
        | 10
        | 20
        | 30
        | 50
        | 51
        | 52
        | 53
        | 330
        | 331
        | 382..=385
        | 730
        | 740
        | 760
        | 800..=890 => 1,
        40 | 100 | 280 | 281 | 300 | 301 | 520 | 530 | 920..=923 => 0,
        170 | 180 | 190 | 171 | 181 | 191 => 2,
        900 | 910 => 3,
        901 | 911 => 4,
        930 | 940 | 950 => 5,
        200 | 210 => 6,
        400 | 410 | 411 | 420 | 421 => 7,
        430 | 431 | 432 | 490 => 8,
        980 | 990 => 10,
        540 | 550 | 560 | 570 | 580 | 590 | 591 | 592 | 593 => 12,
        610 | 611 | 640 => 13,
        960 | 970 => 14,
        70 | 80 => 15,
        700 | 710 | 711 | 712 | 720 | 721 | 722 => 1,
        _ => return None,
    })
}

/// Modal group of an M-code, or None for an unknown code.
fn m_group(m: i64) -> Option<u8> {
    Some(match m {
        0 | 1 | 2 | 30 | 60 => 4,
        6 | 61 => 6,
        3..=5 => 7,
        7..=9 => 8,
        48..=53 => 9,
        19 => 7,
        62..=68 => 5,
        70..=73 => 10,
        98 | 99 => 4,
        _ => return None,
    })
}

/// Groups of G-codes that take axis words.
fn g_uses_axes(g: i32) -> bool {
    matches!(g, 100 | 280 | 300 | 520 | 920)
}

/// Checks a block. `words` are (letter, value) in line order; returns the
/// error and the index of the word it concerns, or whether the block runs
/// a lathe cycle (G70–G72).
pub(crate) fn check_block(
    words: &[(u8, f64)],
    modal: &Modal,
    points: &Nurbs,
    cycle: &Cycle,
    user_m: u128,
) -> Result<bool, (ErrorKind, Option<usize>)> {
    if simple_block_ok(words, modal) {
        return Ok(false);
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
fn simple_block_ok(words: &[(u8, f64)], modal: &Modal) -> bool {
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
            _ => {}
        }
    }
    let motion = match g {
        None => motion10(modal.motion),
        Some(0.0) => 0,
        Some(1.0) => 10,
        Some(_) => return false,
    };
    let moves = mask & AXES != 0 || g.is_some();
    match motion {
        0 => true,
        10 => {
            !moves
                || (modal.feed_mode != FeedMode::InverseTime && feed.unwrap_or(modal.feed) != 0.0)
        }
        _ => false,
    }
}

/// A check's result: the error and the index of the word it concerns.
type Check = Result<(), (ErrorKind, Option<usize>)>;

fn bad<T>(e: BlockError, at: Option<usize>) -> Result<T, (ErrorKind, Option<usize>)> {
    Err((ErrorKind::Block(e), at))
}

/// A block's words decoded once for the checks: its G- and M-codes (×10 for
/// G) with the index of their word, where each other letter is, and what
/// follows from them in the modal state the block meets.
struct Decoded<'a> {
    words: &'a [(u8, f64)],
    modal: &'a Modal,
    gs: &'a [(i32, usize)],
    ms: &'a [(i64, usize)],
    has: &'a [Option<u8>; 128],
    /// The first axis word.
    axis_word: Option<usize>,
    /// The motion code on the line.
    motion_here: Option<i32>,
    /// The motion mode the block runs in.
    motion: i32,
    /// The feed mode the block moves in (G93/G94/G95 on the line first).
    feed_mode: i32,
    /// A NURBS block (G5.2 ... G5.3).
    nurbs: bool,
    /// The G5.3 word.
    g53: Option<usize>,
    /// The non-motion code that takes the axis words (G43.1 without a
    /// motion code on the line takes them as offsets).
    axis_g0: Option<i32>,
}

impl<'a> Decoded<'a> {
    fn new(
        words: &'a [(u8, f64)],
        modal: &'a Modal,
        gs: &'a [(i32, usize)],
        ms: &'a [(i64, usize)],
        has: &'a [Option<u8>; 128],
    ) -> Decoded<'a> {
        let at = |c: u8| has[c as usize].map(usize::from);
        let axis_word = b"xyzabcuvw".iter().find_map(|&c| at(c));
        let motion_here = gs.iter().find(|(g, _)| g_group(*g) == Some(1)).map(|x| x.0);
        let feed_mode = gs
            .iter()
            .find(|g| matches!(g.0, 930 | 940 | 950))
            .map_or(modal.feed_mode.code10() as i32, |g| g.0);
        let axis_g0 = gs
            .iter()
            .find(|(g, _)| g_uses_axes(*g))
            .map(|x| x.0)
            .or_else(|| (gs.iter().any(|g| g.0 == 431) && motion_here.is_none()).then_some(431));
        Decoded {
            words,
            modal,
            gs,
            ms,
            has,
            axis_word,
            motion_here,
            motion: motion_here.unwrap_or(motion10(modal.motion)),
            feed_mode,
            nurbs: motion_here.unwrap_or(motion10(modal.motion)) == motion10(NURBS),
            g53: gs.iter().find(|g| g.0 == 53).map(|g| g.1),
            axis_g0,
        }
    }

    /// Index of the word with this letter.
    fn has_at(&self, c: u8) -> Option<usize> {
        self.has[c as usize].map(usize::from)
    }

    fn g_on(&self, codes: &[i32]) -> bool {
        self.gs.iter().any(|(g, _)| codes.contains(g))
    }

    fn m_on(&self, codes: &[i64]) -> bool {
        self.ms.iter().any(|(m, _)| codes.contains(m))
    }

    /// A user M-code (M100-M199) is on the line: it takes P and Q.
    fn user_m(&self) -> bool {
        self.ms.iter().any(|(m, _)| (100..=199).contains(m))
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

fn full_check(
    words: &[(u8, f64)],
    modal: &Modal,
    points: &Nurbs,
    cycle: &Cycle,
    user_m: u128,
) -> Result<bool, (ErrorKind, Option<usize>)> {
    let mut gseen: [Option<usize>; 16] = [None; 16];
    let mut mseen: [Option<usize>; 16] = [None; 16];
    // Fixed-size scratch: this runs for every line.
    let mut gbuf = [(0i32, 0usize); 16];
    let mut gn = 0;
    let mut mbuf = [(0i64, 0usize); 16];
    let mut mn = 0;
    let mut has = [None::<u8>; 128];
    let mut lathe = false;
    for (i, &(l, v)) in words.iter().enumerate() {
        match l {
            b'g' => {
                let g10 = (v * 10.0).round();
                if !(0.0..100.0).contains(&v) {
                    return bad(BlockError::GCodeOutOfRange, Some(i));
                }
                if (v * 10.0 - g10).abs() > 0.0001 {
                    return bad(BlockError::UnknownGCodeFraction, Some(i));
                }
                let g = g10 as i32;
                let Some(grp) = g_group(g) else {
                    return bad(
                        BlockError::UnknownGCode {
                            code: crate::emit::number_string(v, None),
                        },
                        Some(i),
                    );
                };
                // G80 may share a line with another motion code (which wins).
                let g80_pair = grp == 1 && gseen[1].is_some_and(|j| g == 800 || words[j].1 == 80.0);
                if gseen[grp as usize].is_some() && !g80_pair {
                    return bad(BlockError::SameGroupG, Some(i));
                }
                if g80_pair && g == 800 {
                    continue;
                }
                if g80_pair {
                    // Replace the G80 recorded before.
                    if let Some(k) = gbuf[..gn].iter().position(|x| x.0 == 800) {
                        gbuf[k] = (g, i);
                        gseen[1] = Some(i);
                        continue;
                    }
                }
                if matches!(g, 700 | 710 | 711 | 712 | 720 | 721 | 722) {
                    // The lathe cycles run a contour subroutine named by Q.
                    lathe = true;
                }
                gseen[grp as usize] = Some(i);
                gbuf[gn] = (g, i);
                gn += 1;
            }
            b'm' => {
                if v.fract() != 0.0 || v < 0.0 {
                    return bad(BlockError::UnknownMCodeFraction, Some(i));
                }
                let m = v as i64;
                if m > 199 {
                    return bad(BlockError::MCodeOver199 { m }, Some(i));
                }
                let grp = match m_group(m) {
                    Some(g) => g,
                    None if m >= 100 && user_m & (1u128 << (m - 100)) != 0 => USER_M_GROUP,
                    None if m >= 100 => {
                        return Err((ErrorKind::UndeclaredUserM { m }, Some(i)));
                    }
                    None => return bad(BlockError::UnknownMCode { m }, Some(i)),
                };
                if mseen[grp as usize].is_some() {
                    return bad(BlockError::SameGroupM, Some(i));
                }
                mseen[grp as usize] = Some(i);
                if mn == mbuf.len() {
                    // (More than four M words are refused before this.)
                    return Err((ErrorKind::TooManyMWords, Some(i)));
                }
                mbuf[mn] = (m, i);
                mn += 1;
            }
            _ => {
                if (l as usize) < 128 {
                    has[l as usize] = Some(i.min(255) as u8);
                }
            }
        }
    }
    let d = Decoded::new(words, modal, &gbuf[..gn], &mbuf[..mn], &has);
    check_nurbs(&d, points)?;
    check_motion_words(&d)?;
    check_axis_codes(&d)?;
    check_cycle(&d, cycle)?;
    check_axis_values(&d)?;
    check_word_values(&d)?;
    check_unused_words(&d)?;
    check_whole_numbers(&d)?;
    check_g10(&d)?;
    check_required_words(&d)?;
    check_feed(&d)?;
    if modal.ccomp != CutterComp::Off || d.g_on(&[410, 411, 420, 421]) {
        check_comp(&d)?;
    }
    Ok(lathe)
}

/// What the reference refuses while cutter compensation is on, and the
/// words G41/G42 and G41.1/G42.1 need. M-codes and the plane are checked
/// with the state before the block, the other G-codes after the block's
/// G40/G41/G42 (the reference's order of execution).
fn check_comp(d: &Decoded<'_>) -> Check {
    let g_at = |codes: &[i32]| d.gs.iter().find(|(g, _)| codes.contains(g)).map(|x| x.1);
    let m_at = |codes: &[i64]| d.ms.iter().find(|(m, _)| codes.contains(m)).map(|x| x.1);
    let forbid =
        |action: &'static str, at: Option<usize>| Err((ErrorKind::CompForbids { action }, at));
    let planes = |g: &i32| matches!(g, 170 | 180 | 190 | 171 | 181 | 191);
    let before = d.modal.ccomp != CutterComp::Off;
    let turning_on =
        d.gs.iter()
            .find(|(g, _)| matches!(g, 410 | 411 | 420 | 421));
    let after = turning_on.is_some() || (before && g_at(&[400]).is_none());
    if before {
        if let Some(i) = m_at(&[6]) {
            return forbid("change tools", Some(i));
        }
        if let Some(i) = m_at(&[62, 63, 64, 65]) {
            return forbid("set a digital output", Some(i));
        }
        if let Some(i) = m_at(&[66]) {
            return forbid("wait for an input", Some(i));
        }
        if let Some(i) = m_at(&[67, 68]) {
            return forbid("set an analog output", Some(i));
        }
        if let Some(i) = m_at(&[48, 49, 50, 51, 52, 53]) {
            return forbid("enable or disable overrides", Some(i));
        }
        if let Some(&(p, i)) = d.gs.iter().find(|(g, _)| planes(g))
            && p != d.modal.plane.code10() as i32
        {
            return Err((ErrorKind::CompPlaneChange, Some(i)));
        }
    }
    let plane =
        d.gs.iter()
            .find(|(g, _)| planes(g))
            .map_or(d.modal.plane.code10() as i32, |g| g.0);
    if let Some(&(g, i)) = turning_on {
        if plane != 170 && plane != 180 {
            return Err((ErrorKind::CompPlane, Some(i)));
        }
        if before {
            return Err((ErrorKind::CompAlreadyOn, Some(i)));
        }
        if matches!(g, 411 | 421) {
            let name = if g == 411 { "G41.1" } else { "G42.1" };
            if d.has_at(b'd').is_none() {
                return Err((ErrorKind::CompNoDiameter { g: name }, Some(i)));
            }
            if let Some(l) = d.has_at(b'l')
                && plane != 180
            {
                let what = if g == 411 {
                    "G41.1 with an L word (lathe tool orientation)"
                } else {
                    "G42.1 with an L word (lathe tool orientation)"
                };
                return Err((ErrorKind::CompLatheTool { what }, Some(l)));
            }
        }
    }
    if !after {
        return Ok(());
    }
    if let Some(i) = g_at(&[430, 431, 432, 490]) {
        return forbid("change the tool length offset", Some(i));
    }
    if let Some(i) = g_at(&[540, 550, 560, 570, 580, 590, 591, 592, 593]) {
        return forbid("change the coordinate system", Some(i));
    }
    if let Some(i) = g_at(&[610, 611, 640]) {
        return forbid("change the path control mode", Some(i));
    }
    if let Some(i) = g_at(&[980, 990]) {
        return forbid("change the canned cycle return mode", Some(i));
    }
    if let Some(i) = g_at(&[100]) {
        let l = d.value(b'l').map(|v| v.round() as i32);
        let p = d.value(b'p').map_or(0, |v| (v + 0.0001) as i32);
        let p = if p == 0 { d.modal.coord_index } else { p };
        if matches!(l, Some(2 | 20)) && p == d.modal.coord_index {
            return forbid("change the active coordinate system's offsets", Some(i));
        }
    }
    if let Some(i) = g_at(&[280, 300]) {
        return forbid("use G28 or G30", Some(i));
    }
    if let Some(i) = g_at(&[281, 301]) {
        return forbid("set a home position (G28.1, G30.1)", Some(i));
    }
    if let Some(i) = g_at(&[520, 920, 921, 922, 923]) {
        return forbid("change axis offsets (G52, G92)", Some(i));
    }
    let motion_at =
        d.gs.iter()
            .find(|(g, _)| g_group(*g) == Some(1))
            .map(|x| x.1);
    let moves = d.motion_here.is_some() || (d.axis_word.is_some() && d.axis_g0.is_none());
    if moves {
        match d.motion {
            382..=385 => return forbid("probe", motion_at),
            50 | 51 => return forbid("make a spline", motion_at),
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
        if d.feed_mode == 940 && feed == 0.0 {
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
        let needs_axes = matches!(m, 382..=385 | 730 | 760 | 810..=890);
        if needs_axes && d.axis_word.is_none() && !matches!(m, 760) {
            return bad(BlockError::AxesMissing, None);
        }
        if matches!(m, 820 | 860 | 880 | 890) && !d.given(b'p') {
            return bad(BlockError::CycleDwellMissing, None);
        }
        if matches!(m, 730 | 830) && !d.given(b'q') {
            return bad(BlockError::PeckQMissing, None);
        }
        if m == 760 && d.has_at(b'p').is_none() {
            return bad(BlockError::G76PMissing, None);
        }
        if matches!(m, 20 | 30)
            && ![b'i', b'j', b'k', b'r']
                .iter()
                .any(|&c| d.has_at(c).is_some())
        {
            return bad(BlockError::ArcWordsMissing, None);
        }
        if matches!(m, 330 | 331)
            && d.modal.spindle == SpindleDir::Off
            && !d.ms.iter().any(|x| matches!(x.0, 3 | 4))
        {
            return bad(BlockError::SpindleStoppedG33, None);
        }
    }
    Ok(())
}

/// Two codes that both take the axis words.
fn check_axis_codes(d: &Decoded<'_>) -> Check {
    if let (Some(_), Some(_), Some(i)) = (d.motion_here, d.axis_g0, d.axis_word)
        && d.motion_here != Some(800)
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
    let cycle_runs = is_cycle(d.motion)
        && (d.motion_here.is_some() || (d.axis_word.is_some() && d.axis_g0.is_none()));
    if cycle_runs {
        // Entering the cycle (not repeating it) needs the depth and R.
        let first = motion10(d.modal.motion) != d.motion;
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
        if d.feed_mode == 930 {
            return bad(BlockError::CycleInverseTime, None);
        }
        if d.modal.ccomp != CutterComp::Off && !d.g_on(&[400]) || d.g_on(&[410, 411, 420, 421]) {
            return bad(BlockError::CycleWithComp, None);
        }
        // The R plane must not be below the bottom of the hole (in G91 the
        // depth is relative to R, so it must not be positive).
        let cc = d.value(depth).unwrap_or(cycle.depth);
        let absolute = d.g_on(&[900]) || (d.modal.absolute && !d.g_on(&[910]));
        let below = if absolute { r < cc } else { cc > 0.0 };
        if below {
            return bad(BlockError::CycleRBelowDepth { axis: name }, d.has_at(b'r'));
        }
        let spindle = d.ms.iter().rev().find(|m| matches!(m.0, 3..=5)).map_or(
            match d.modal.spindle {
                SpindleDir::Off => 0,
                SpindleDir::Cw => 3,
                SpindleDir::Ccw => 4,
            },
            |m| if m.0 == 5 { 0 } else { m.0 as i32 },
        );
        let spindle_msg = match (d.motion, spindle) {
            (840, 0) | (740, 0) | (860, 0) | (870, 0) | (880, 0) => {
                Some(BlockError::CycleSpindleStopped)
            }
            (840, 4) => Some(BlockError::G84SpindleCcw),
            (740, 3) => Some(BlockError::G74SpindleCw),
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
        && matches!(d.motion, 800 | NO_MOTION)
    {
        return bad(
            if d.motion_here == Some(800) {
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
    let arcish = d.g_on(&[20, 30, 50, 51, 100, 331, 760, 870])
        || (d.motion_here.is_none()
            && matches!(
                motion10(d.modal.motion),
                20 | 30 | 50 | 51 | 331 | 760 | 870
            )
            && d.axis_word.is_some());
    let uses = |letter: u8, ok: bool, msg: BlockError| -> Result<(), (ErrorKind, Option<usize>)> {
        match d.has_at(letter) {
            Some(i) if !ok => bad(msg, Some(i)),
            _ => Ok(()),
        }
    };
    let rough = matches!(d.motion, 710 | 711 | 712 | 720 | 721 | 722);
    let lathe = rough || d.motion == 700;
    uses(
        b'i',
        arcish || (d.motion == 20 || d.motion == 30) || rough,
        BlockError::WordUnused { letter: 'i' },
    )?;
    uses(
        b'j',
        arcish || (d.motion == 20 || d.motion == 30),
        BlockError::WordUnused { letter: 'j' },
    )?;
    uses(
        b'k',
        arcish || matches!(d.motion, 20 | 30 | 330 | 331 | 760 | 870),
        BlockError::WordUnused { letter: 'k' },
    )?;
    let canned = matches!(d.motion, 730 | 740 | 760 | 810..=890);
    uses(
        b'r',
        matches!(d.motion, 20 | 30)
            || canned
            || d.g_on(&[100])
            || d.axis_g0 == Some(100)
            || d.m_on(&[19])
            || rough,
        BlockError::WordUnused { letter: 'r' },
    )?;
    uses(
        b'p',
        d.g_on(&[20, 30, 40, 100, 640, 50, 52, 760, 820, 860, 880, 890])
            || matches!(d.motion, 20 | 30 | 52 | 820 | 860 | 880 | 890 | 700)
            || d.m_on(&[19, 50, 51, 52, 53, 62, 63, 64, 65, 66, 98])
            || d.user_m(),
        BlockError::WordUnused { letter: 'p' },
    )?;
    uses(
        b'q',
        d.g_on(&[50, 100, 640, 730, 760, 830])
            || matches!(d.motion, 730 | 830)
            || lathe
            || d.m_on(&[19, 66, 67, 68, 61])
            || d.user_m(),
        BlockError::WordUnused { letter: 'q' },
    )?;
    uses(
        b'h',
        d.g_on(&[430, 432, 760]),
        BlockError::WordUnused { letter: 'h' },
    )?;
    uses(
        b'd',
        d.g_on(&[410, 411, 420, 421, 960]) || lathe,
        BlockError::WordUnused { letter: 'd' },
    )?;
    uses(
        b'e',
        d.g_on(&[760]) || d.m_on(&[66, 67, 68]) || d.motion == 700,
        BlockError::WordUnused { letter: 'e' },
    )?;
    uses(
        b'l',
        // (G74 takes no L in the reference.)
        d.g_on(&[100, 410, 411, 420, 421, 760])
            || (canned && d.motion != 740)
            || d.m_on(&[66, 98])
            || d.g_on(&[52, 53]),
        BlockError::WordUnused { letter: 'l' },
    )?;
    uses(
        b'$',
        d.m_on(&[3, 4, 5, 19, 51]) || d.g_on(&[330, 331, 760, 950, 960, 970]),
        BlockError::WordUnused { letter: '$' },
    )?;
    Ok(())
}

/// Whole numbers, peck depths, H, and G53's conditions.
fn check_whole_numbers(d: &Decoded<'_>) -> Check {
    // Whole numbers.
    for (i, &(l, v)) in d.words.iter().enumerate() {
        if matches!(l, b't' | b'h') && crate::parse::integer_value(v).is_err() {
            return Err((ErrorKind::NonInteger { value: v }, Some(i)));
        }
        // The reference's test: the D value within 0.0001 of the integer
        // (int)(D + 0.5), which also refuses every negative D.
        if l == b'd' && d.g_on(&[410, 420]) && (((v + 0.5) as i64) as f64 - v).abs() >= 0.0001 {
            return bad(BlockError::CompDNotWhole, Some(i));
        }
    }
    // Peck depths of a running G73/G83.
    if matches!(d.motion, 730 | 830)
        && (d.motion_here.is_some() || d.axis_word.is_some())
        && d.value(b'q').is_some_and(|q| q != -1.0 && q <= 0.0)
    {
        return bad(BlockError::PeckQNotPositive, d.has_at(b'q'));
    }
    if d.value(b'h').is_some_and(|h| h < -1.0) {
        return bad(BlockError::NegativeH, d.has_at(b'h'));
    }
    // G53 moves in machine coordinates: with G0 or G1, never incremental.
    if let Some(at) = d.gs.iter().find(|g| g.0 == 530).map(|g| g.1) {
        let motion_to_be = d
            .motion_here
            .or(d.axis_word.map(|_| motion10(d.modal.motion)));
        if !matches!(motion_to_be, Some(0 | 10)) {
            return bad(BlockError::G53NeedsG0G1, Some(at));
        }
        let incremental = d.g_on(&[910]) || (!d.modal.absolute && !d.g_on(&[900]));
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
    if d.g_on(&[100]) {
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
fn check_required_words(d: &Decoded<'_>) -> Check {
    if d.g_on(&[40]) && !d.given(b'p') {
        return bad(
            BlockError::G4PMissing,
            d.gs.iter().find(|g| g.0 == 40).map(|g| g.1),
        );
    }
    if d.g_on(&[960]) && d.has_at(b's').is_none() {
        return bad(BlockError::G96SMissing, None);
    }
    if d.m_on(&[62, 63, 64, 65]) && d.has_at(b'p').is_none() {
        return bad(BlockError::M62PMissing, None);
    }
    if d.m_on(&[66]) && !d.given(b'p') && d.has_at(b'e').is_none() {
        return bad(BlockError::M66PEMissing, None);
    }
    if d.m_on(&[61]) && d.has_at(b'q').is_none() {
        return bad(BlockError::M61QMissing, None);
    }
    Ok(())
}

/// Motion needing a feed rate; arcs needing their words; G33's K.
fn check_feed(d: &Decoded<'_>) -> Check {
    let moves = d.motion_here.is_some() || d.axis_word.is_some();
    if moves && d.axis_g0.is_none() && matches!(d.motion, 10 | 20 | 30 | 50 | 51 | 730 | 810..=890)
    {
        let feed = d.words.iter().rev().find(|w| w.0 == b'f').map(|w| w.1);
        let inverse = d.gs.iter().any(|g| g.0 == 930)
            || (d.modal.feed_mode == FeedMode::InverseTime && !d.g_on(&[940, 950]));
        if inverse {
            if feed.is_none() && d.axis_word.is_some() {
                return bad(BlockError::InverseTimeFMissing, None);
            }
        } else if feed.unwrap_or(d.modal.feed) == 0.0 {
            return bad(BlockError::ZeroFeed, None);
        }
        if matches!(d.motion, 20 | 30) && d.axis_word.is_some() {
            let arc = ["i", "j", "k", "r"]
                .iter()
                .any(|c| d.has[c.as_bytes()[0] as usize].is_some());
            if !arc {
                return bad(BlockError::ArcWordsMissing, None);
            }
        }
    }
    if d.motion_here.is_some_and(|m| matches!(m, 330 | 331)) && d.has_at(b'k').is_none() {
        return bad(BlockError::G33KMissing, None);
    }
    Ok(())
}
