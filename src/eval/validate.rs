//! The G-code checks the reference makes on every block before running it:
//! known codes, modal-group conflicts, words without a code that uses them,
//! feed rates, arcs. A program LinuxCNC would reject is rejected here too,
//! with the word that is wrong.

use crate::diag::ErrorKind;

use super::cycle::{Cycle, depth_axis, is_cycle};
use super::nurbs::{NO_MOTION, NURBS, Nurbs};
use super::state::Modal;
use crate::diag::BlockError;

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

/// Whether a G-code (×10) is a motion code.
pub fn is_motion(g: i32) -> bool {
    g_group(g) == Some(1)
}

/// Groups of G-codes that take axis words.
fn g_uses_axes(g: i32) -> bool {
    matches!(g, 100 | 280 | 300 | 520 | 920)
}

/// Checks a block. `words` are (letter, value) in line order; returns the
/// error and the index of the word it concerns.
pub fn check_block(
    words: &[(u8, f64)],
    modal: &Modal,
    points: &Nurbs,
    cycle: &Cycle,
) -> Result<(), (ErrorKind, Option<usize>)> {
    if simple_block_ok(words, modal) {
        return Ok(());
    }
    full_check(words, modal, points, cycle)
}

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
        None => modal.motion,
        Some(0.0) => 0,
        Some(1.0) => 10,
        Some(_) => return false,
    };
    let moves = mask & AXES != 0 || g.is_some();
    match motion {
        0 => true,
        10 => !moves || (modal.feed_mode != 930 && feed.unwrap_or(modal.feed) != 0.0),
        _ => false,
    }
}

fn full_check(
    words: &[(u8, f64)],
    modal: &Modal,
    points: &Nurbs,
    cycle: &Cycle,
) -> Result<(), (ErrorKind, Option<usize>)> {
    let bad = |e: BlockError, at: Option<usize>| Err((ErrorKind::Block(e), at));
    let mut gseen: [Option<usize>; 16] = [None; 16];
    let mut mseen: [Option<usize>; 16] = [None; 16];
    // Fixed-size scratch: this runs for every line.
    let mut gbuf = [(0i32, 0usize); 16];
    let mut gn = 0;
    let mut mbuf = [(0i64, 0usize); 16];
    let mut mn = 0;
    let mut has = [None::<u8>; 128];
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
                    // The lathe cycles run a contour subroutine named by Q;
                    // a flattened program has no subroutines left.
                    let what = format!(
                        "G{} (lathe cycle with a contour subroutine) cannot be flattened: the controller would need the subroutine; rewrite the cycle as moves",
                        crate::emit::number_string(v, None)
                    );
                    return Err((ErrorKind::Unsupported { what }, Some(i)));
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
                let Some(grp) = m_group(m) else {
                    return bad(BlockError::UnknownMCode { m }, Some(i));
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
    let gs = &gbuf[..gn];
    let ms = &mbuf[..mn];
    let has_at = |c: u8| has[c as usize].map(usize::from);
    let g_on = |codes: &[i32]| gs.iter().any(|(g, _)| codes.contains(g));
    let m_on = |codes: &[i64]| ms.iter().any(|(m, _)| codes.contains(m));
    let axis_word = b"xyzabcuvw".iter().find_map(|&c| has_at(c));
    let motion_here = gs.iter().find(|(g, _)| g_group(*g) == Some(1)).map(|x| x.0);
    // An absent P or Q reads as -1 in the reference, so a P-1 or Q-1 is no P
    // or Q where one is required.
    let value = |c: u8| has_at(c).map(|i| words[i].1);
    let given = |c: u8| value(c).is_some_and(|v| v != -1.0);
    // The feed mode the block moves in (G93/G94/G95 on the line first).
    let feed_mode = gs
        .iter()
        .find(|g| matches!(g.0, 930 | 940 | 950))
        .map_or(modal.feed_mode, |g| g.0);
    // NURBS blocks (G5.2 ... G5.3).
    let nurbs = motion_here.unwrap_or(modal.motion) == NURBS;
    let g53 = gs.iter().find(|g| g.0 == 53).map(|g| g.1);
    if let Some(at) = g53 {
        if modal.motion != NURBS {
            return bad(BlockError::NurbsEndWithoutStart, Some(at));
        }
        if let Some(order) = points.short_of_order() {
            return bad(BlockError::NurbsTooFewPoints { order }, Some(at));
        }
    }
    // A control point: on a G5.2 line, a line of axis words in G5.2 mode, or
    // axis words after G5.3 (which start a new block). The checks on P see
    // the points still pending, which G5.3 has just cleared.
    let point = (nurbs && (motion_here.is_some() || axis_word.is_some()))
        || (g53.is_some() && axis_word.is_some());
    if point {
        let pending = points.pending() && g53.is_none();
        let p = value(b'p').unwrap_or(-1.0);
        if has_at(b'x').is_some() != has_at(b'y').is_some() {
            return bad(BlockError::NurbsPointNeedsXY, axis_word);
        }
        if pending && axis_word.is_none() && p > 0.0 {
            return bad(BlockError::NurbsPWithoutXY, has_at(b'p'));
        }
        if pending && p <= 0.0 {
            return bad(BlockError::NurbsWeightNeeded, has_at(b'p').or(axis_word));
        }
        let feed = value(b'f').unwrap_or(modal.feed);
        if feed_mode == 940 && feed == 0.0 {
            return bad(BlockError::NurbsZeroFeed, has_at(b'f'));
        }
    }
    if nurbs
        && motion_here.is_none()
        && axis_word.is_none()
        && let Some(i) = has_at(b'p')
    {
        return bad(BlockError::WordUnused { letter: 'p' }, Some(i));
    }
    // Motion codes that need axis words, and their required words.
    if let Some(m) = motion_here {
        let needs_axes = matches!(m, 382..=385 | 730 | 760 | 810..=890);
        if needs_axes && axis_word.is_none() && !matches!(m, 760) {
            return bad(BlockError::AxesMissing, None);
        }
        if matches!(m, 820 | 860 | 880 | 890) && !given(b'p') {
            return bad(BlockError::CycleDwellMissing, None);
        }
        if matches!(m, 730 | 830) && !given(b'q') {
            return bad(BlockError::PeckQMissing, None);
        }
        if m == 760 && has_at(b'p').is_none() {
            return bad(BlockError::G76PMissing, None);
        }
        if matches!(m, 20 | 30)
            && ![b'i', b'j', b'k', b'r']
                .iter()
                .any(|&c| has_at(c).is_some())
        {
            return bad(BlockError::ArcWordsMissing, None);
        }
        if matches!(m, 330 | 331) && modal.spindle == 0 && !ms.iter().any(|x| matches!(x.0, 3 | 4))
        {
            return bad(BlockError::SpindleStoppedG33, None);
        }
    }
    // G43.1 takes the axis words as offsets; with a motion code on the line
    // they are also the move's end point.
    let axis_g0 = gs
        .iter()
        .find(|(g, _)| g_uses_axes(*g))
        .map(|x| x.0)
        .or_else(|| (g_on(&[431]) && motion_here.is_none()).then_some(431));
    if let (Some(_), Some(_), Some(i)) = (motion_here, axis_g0, axis_word)
        && motion_here != Some(800)
    {
        return bad(BlockError::TwoAxisGCodes, Some(i));
    }
    let motion = motion_here.unwrap_or(modal.motion);
    // A canned cycle runs: its code is on the line, or it is the motion mode
    // and the line has axis words no other code takes.
    let cycle_runs =
        is_cycle(motion) && (motion_here.is_some() || (axis_word.is_some() && axis_g0.is_none()));
    if cycle_runs {
        // Entering the cycle (not repeating it) needs the depth and R.
        let first = modal.motion != motion;
        let (depth, name) = depth_axis(modal.plane);
        if first && has_at(depth).is_none() {
            return bad(BlockError::CycleDepthMissing { axis: name }, None);
        }
        if let Some(i) = [b'a', b'b', b'c'].iter().find_map(|&c| has_at(c)) {
            return bad(BlockError::RotaryInCycle, Some(i));
        }
        let r = match value(b'r') {
            Some(r) => r,
            None if !first => cycle.r,
            None => return bad(BlockError::CycleRMissing, None),
        };
        if value(b'l') == Some(0.0) {
            return bad(BlockError::CycleL0, has_at(b'l'));
        }
        if feed_mode == 930 {
            return bad(BlockError::CycleInverseTime, None);
        }
        if modal.ccomp != 400 && !g_on(&[400]) {
            return bad(BlockError::CycleWithComp, None);
        }
        // The R plane must not be below the bottom of the hole (in G91 the
        // depth is relative to R, so it must not be positive).
        let cc = value(depth).unwrap_or(cycle.depth);
        let absolute = g_on(&[900]) || (modal.absolute && !g_on(&[910]));
        let below = if absolute { r < cc } else { cc > 0.0 };
        if below {
            return bad(BlockError::CycleRBelowDepth { axis: name }, has_at(b'r'));
        }
        let spindle = ms
            .iter()
            .rev()
            .find(|m| matches!(m.0, 3..=5))
            .map_or(modal.spindle, |m| if m.0 == 5 { 0 } else { m.0 as i32 });
        let spindle_msg = match (motion, spindle) {
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
    if let Some(i) = axis_word
        && axis_g0.is_none()
        && matches!(motion, 800 | NO_MOTION)
    {
        return bad(
            if motion_here == Some(800) {
                BlockError::AxesWithG80
            } else {
                BlockError::AxesWithoutGCode
            },
            Some(i),
        );
    }
    if (has_at(b'@').is_some() || has_at(b'^').is_some())
        && (has_at(b'x').is_some() || has_at(b'y').is_some())
    {
        return bad(BlockError::PolarWithXY, has_at(b'@').or(has_at(b'^')));
    }
    for (i, &(l, v)) in words.iter().enumerate() {
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
    // Words that need a code to use them.
    let arcish = g_on(&[20, 30, 50, 51, 100, 331, 760, 870])
        || (motion_here.is_none()
            && matches!(modal.motion, 20 | 30 | 50 | 51 | 331 | 760 | 870)
            && axis_word.is_some());
    let uses = |letter: u8, ok: bool, msg: BlockError| -> Result<(), (ErrorKind, Option<usize>)> {
        match has_at(letter) {
            Some(i) if !ok => bad(msg, Some(i)),
            _ => Ok(()),
        }
    };
    uses(
        b'i',
        arcish || (motion == 20 || motion == 30),
        BlockError::WordUnused { letter: 'i' },
    )?;
    uses(
        b'j',
        arcish || (motion == 20 || motion == 30),
        BlockError::WordUnused { letter: 'j' },
    )?;
    uses(
        b'k',
        arcish || matches!(motion, 20 | 30 | 330 | 331 | 760 | 870),
        BlockError::WordUnused { letter: 'k' },
    )?;
    let canned = matches!(motion, 730 | 740 | 760 | 810..=890);
    uses(
        b'r',
        matches!(motion, 20 | 30) || canned || g_on(&[100]) || axis_g0 == Some(100) || m_on(&[19]),
        BlockError::WordUnused { letter: 'r' },
    )?;
    uses(
        b'p',
        g_on(&[20, 30, 40, 100, 640, 50, 52, 760, 820, 860, 880, 890])
            || matches!(motion, 20 | 30 | 52 | 820 | 860 | 880 | 890)
            || m_on(&[19, 50, 51, 52, 53, 62, 63, 64, 65, 66, 98]),
        BlockError::WordUnused { letter: 'p' },
    )?;
    uses(
        b'q',
        g_on(&[50, 100, 640, 730, 760, 830])
            || matches!(motion, 730 | 830)
            || m_on(&[19, 66, 67, 68, 61]),
        BlockError::WordUnused { letter: 'q' },
    )?;
    uses(
        b'h',
        g_on(&[430, 432, 760]),
        BlockError::WordUnused { letter: 'h' },
    )?;
    uses(
        b'd',
        g_on(&[410, 411, 420, 421, 960]),
        BlockError::WordUnused { letter: 'd' },
    )?;
    uses(
        b'e',
        g_on(&[760]) || m_on(&[66, 67, 68]),
        BlockError::WordUnused { letter: 'e' },
    )?;
    uses(
        b'l',
        // (G74 takes no L in the reference.)
        g_on(&[100, 410, 420, 760])
            || (canned && motion != 740)
            || m_on(&[66, 98])
            || g_on(&[52, 53]),
        BlockError::WordUnused { letter: 'l' },
    )?;
    uses(
        b'$',
        m_on(&[3, 4, 5, 19, 51]) || g_on(&[330, 331, 760, 950, 960, 970]),
        BlockError::WordUnused { letter: '$' },
    )?;
    // Whole numbers.
    for (i, &(l, v)) in words.iter().enumerate() {
        if matches!(l, b't' | b'h') && crate::parse::integer_value(v).is_err() {
            return Err((ErrorKind::NonInteger { value: v }, Some(i)));
        }
        if l == b'd' && g_on(&[410, 420]) && v.fract() != 0.0 {
            return bad(BlockError::CompDNotWhole, Some(i));
        }
    }
    // Peck depths of a running G73/G83.
    if matches!(motion, 730 | 830)
        && (motion_here.is_some() || axis_word.is_some())
        && value(b'q').is_some_and(|q| q != -1.0 && q <= 0.0)
    {
        return bad(BlockError::PeckQNotPositive, has_at(b'q'));
    }
    if value(b'h').is_some_and(|h| h < -1.0) {
        return bad(BlockError::NegativeH, has_at(b'h'));
    }
    // G53 moves in machine coordinates: with G0 or G1, never incremental.
    if let Some(at) = gs.iter().find(|g| g.0 == 530).map(|g| g.1) {
        let motion_to_be = motion_here.or(axis_word.map(|_| modal.motion));
        if !matches!(motion_to_be, Some(0 | 10)) {
            return bad(BlockError::G53NeedsG0G1, Some(at));
        }
        let incremental = g_on(&[910]) || (!modal.absolute && !g_on(&[900]));
        if incremental {
            return bad(BlockError::G53Incremental, Some(at));
        }
    }
    // G10's L and P: P is a tool number (L1, L10, L11) or a coordinate
    // system (L2, L20), rounded half away from zero; an absent P reads as
    // -1, and only a P above its rounding by more than 0.0001 is refused.
    if g_on(&[100]) {
        let p = value(b'p').unwrap_or(-1.0);
        let l = value(b'l').map_or(-1, |l| l.round() as i64);
        let p_int = if p >= 0.0 {
            (p + 0.5).trunc()
        } else {
            (p - 0.5).trunc()
        };
        if !matches!(l, 1 | 2 | 10 | 11 | 20) {
            return bad(BlockError::G10BadL, has_at(b'l'));
        }
        if p + 0.0001 - p_int > 0.0002 {
            return bad(BlockError::G10PNotWhole, has_at(b'p'));
        }
        if matches!(l, 2 | 20) && !(0.0..=9.0).contains(&p_int) {
            return bad(BlockError::G10CoordPRange, has_at(b'p'));
        }
        if matches!(l, 1 | 10 | 11) && p_int < 1.0 {
            return bad(BlockError::G10ToolPRange, has_at(b'p'));
        }
    }
    // Codes that need words.
    if g_on(&[40]) && !given(b'p') {
        return bad(
            BlockError::G4PMissing,
            gs.iter().find(|g| g.0 == 40).map(|g| g.1),
        );
    }
    if g_on(&[960]) && has_at(b's').is_none() {
        return bad(BlockError::G96SMissing, None);
    }
    if m_on(&[62, 63, 64, 65]) && has_at(b'p').is_none() {
        return bad(BlockError::M62PMissing, None);
    }
    if m_on(&[66]) && !given(b'p') && has_at(b'e').is_none() {
        return bad(BlockError::M66PEMissing, None);
    }
    if m_on(&[61]) && has_at(b'q').is_none() {
        return bad(BlockError::M61QMissing, None);
    }
    // Motion needing a feed rate.
    let moves = motion_here.is_some() || axis_word.is_some();
    if moves && axis_g0.is_none() && matches!(motion, 10 | 20 | 30 | 50 | 51 | 730 | 810..=890) {
        let feed = words.iter().rev().find(|w| w.0 == b'f').map(|w| w.1);
        let inverse =
            gs.iter().any(|g| g.0 == 930) || (modal.feed_mode == 930 && !g_on(&[940, 950]));
        if inverse {
            if feed.is_none() && axis_word.is_some() {
                return bad(BlockError::InverseTimeFMissing, None);
            }
        } else if feed.unwrap_or(modal.feed) == 0.0 {
            return bad(BlockError::ZeroFeed, None);
        }
        if matches!(motion, 20 | 30) && axis_word.is_some() {
            let arc = ["i", "j", "k", "r"]
                .iter()
                .any(|c| has[c.as_bytes()[0] as usize].is_some());
            if !arc {
                return bad(BlockError::ArcWordsMissing, None);
            }
        }
    }
    if motion_here.is_some_and(|m| matches!(m, 330 | 331)) && has_at(b'k').is_none() {
        return bad(BlockError::G33KMissing, None);
    }
    Ok(())
}
