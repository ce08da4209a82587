//! The G-code checks the reference makes on every block before running it:
//! known codes, modal-group conflicts, words without a code that uses them,
//! feed rates, arcs. A program LinuxCNC would reject is rejected here too,
//! with the word that is wrong.

use crate::diag::ErrorKind;

use super::cycle::{Cycle, depth_axis, is_cycle};
use super::nurbs::{NO_MOTION, NURBS, Nurbs};
use super::state::Modal;

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
    let bad = |msg: &str, at: Option<usize>| {
        Err((
            ErrorKind::Semantic {
                message: msg.to_string(),
            },
            at,
        ))
    };
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
                    return bad("G-code out of range", Some(i));
                }
                if (v * 10.0 - g10).abs() > 0.0001 {
                    return bad("unknown G-code", Some(i));
                }
                let g = g10 as i32;
                let Some(grp) = g_group(g) else {
                    return bad(
                        &format!("unknown G-code G{}", crate::emit::number_string(v, None)),
                        Some(i),
                    );
                };
                // G80 may share a line with another motion code (which wins).
                let g80_pair = grp == 1 && gseen[1].is_some_and(|j| g == 800 || words[j].1 == 80.0);
                if gseen[grp as usize].is_some() && !g80_pair {
                    return bad("two G-codes from the same modal group", Some(i));
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
                    return bad("unknown M-code", Some(i));
                }
                let m = v as i64;
                if m > 199 {
                    return bad(&format!("M-code greater than 199: M{m}"), Some(i));
                }
                let Some(grp) = m_group(m) else {
                    return bad(&format!("unknown M-code M{m}"), Some(i));
                };
                if mseen[grp as usize].is_some() {
                    return bad("two M-codes from the same modal group", Some(i));
                }
                mseen[grp as usize] = Some(i);
                if mn == mbuf.len() {
                    return bad("too many M-codes", Some(i));
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
            return bad("G5.3 without a G5.2 block before it", Some(at));
        }
        if let Some(order) = points.short_of_order() {
            let msg = format!(
                "a NURBS block needs at least as many control points as its order L = {order}"
            );
            return bad(&msg, Some(at));
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
            return bad(
                "both X and Y are needed for a NURBS control point",
                axis_word,
            );
        }
        if pending && axis_word.is_none() && p > 0.0 {
            return bad(
                "a P word without X and Y is only allowed for the first NURBS control point",
                has_at(b'p'),
            );
        }
        if pending && p <= 0.0 {
            return bad(
                "a positive weight P is needed for every NURBS control point",
                has_at(b'p').or(axis_word),
            );
        }
        let feed = value(b'f').unwrap_or(modal.feed);
        if feed_mode == 940 && feed == 0.0 {
            return bad("a NURBS block with a zero feed rate", has_at(b'f'));
        }
    }
    if nurbs
        && motion_here.is_none()
        && axis_word.is_none()
        && let Some(i) = has_at(b'p')
    {
        return bad("P word with no G-code or M-code to use it", Some(i));
    }
    // Motion codes that need axis words, and their required words.
    if let Some(m) = motion_here {
        let needs_axes = matches!(m, 382..=385 | 730 | 760 | 810..=890);
        if needs_axes && axis_word.is_none() && !matches!(m, 760) {
            return bad("all axes missing with motion code", None);
        }
        if matches!(m, 820 | 860 | 880 | 890) && !given(b'p') {
            return bad("dwell time P word missing with G82/G86/G88/G89", None);
        }
        if matches!(m, 730 | 830) && !given(b'q') {
            return bad("Q word missing with G73/G83", None);
        }
        if m == 760 && has_at(b'p').is_none() {
            return bad("P word missing with G76", None);
        }
        if matches!(m, 20 | 30)
            && ![b'i', b'j', b'k', b'r']
                .iter()
                .any(|&c| has_at(c).is_some())
        {
            return bad("R, I, J and K words all missing for arc", None);
        }
        if matches!(m, 330 | 331) && modal.spindle == 0 && !ms.iter().any(|x| matches!(x.0, 3 | 4))
        {
            return bad("spindle not turning in G33", None);
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
        return bad("two G-codes that both use axis values", Some(i));
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
            return bad(&format!("{name} value unspecified in canned cycle"), None);
        }
        if let Some(i) = [b'a', b'b', b'c'].iter().find_map(|&c| has_at(c)) {
            return bad("cannot put a rotary axis word in a canned cycle", Some(i));
        }
        let r = match value(b'r') {
            Some(r) => r,
            None if !first => cycle.r,
            None => return bad("R clearance plane unspecified in canned cycle", None),
        };
        if value(b'l') == Some(0.0) {
            return bad(
                "a canned cycle cannot be repeated zero times (L0)",
                has_at(b'l'),
            );
        }
        if feed_mode == 930 {
            return bad("canned cycles cannot use inverse time feed (G93)", None);
        }
        if modal.ccomp != 400 && !g_on(&[400]) {
            return bad(
                "canned cycles cannot be used with cutter compensation on",
                None,
            );
        }
        // The R plane must not be below the bottom of the hole (in G91 the
        // depth is relative to R, so it must not be positive).
        let cc = value(depth).unwrap_or(cycle.depth);
        let absolute = g_on(&[900]) || (modal.absolute && !g_on(&[910]));
        let below = if absolute { r < cc } else { cc > 0.0 };
        if below {
            return bad(&format!("R less than {name} in canned cycle"), has_at(b'r'));
        }
        let spindle = ms
            .iter()
            .rev()
            .find(|m| matches!(m.0, 3..=5))
            .map_or(modal.spindle, |m| if m.0 == 5 { 0 } else { m.0 as i32 });
        let spindle_msg = match (motion, spindle) {
            (840, 0) | (740, 0) | (860, 0) | (870, 0) | (880, 0) => {
                Some("spindle not turning in a tapping or boring cycle")
            }
            (840, 4) => Some("spindle turning counterclockwise in G84"),
            (740, 3) => Some("spindle turning clockwise in G74"),
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
                "axis values with G80"
            } else {
                "axis values without a G-code that uses them"
            },
            Some(i),
        );
    }
    if (has_at(b'@').is_some() || has_at(b'^').is_some())
        && (has_at(b'x').is_some() || has_at(b'y').is_some())
    {
        return bad(
            "polar coordinates and X/Y words together",
            has_at(b'@').or(has_at(b'^')),
        );
    }
    for (i, &(l, v)) in words.iter().enumerate() {
        // L is read as a whole number, and never negative.
        if l == b'l' {
            let n = crate::parse::integer_value(v).map_err(|k| (k, Some(i)))?;
            if n < 0 {
                return bad("negative L word", Some(i));
            }
        }
        if l == b'f' && v < 0.0 {
            return bad("negative F word", None);
        }
        if l == b's' && v < 0.0 {
            return bad("negative spindle speed", None);
        }
        if l == b't' && v < 0.0 {
            return bad("negative tool number", None);
        }
    }
    // Words that need a code to use them.
    let arcish = g_on(&[20, 30, 50, 51, 100, 331, 760, 870])
        || (motion_here.is_none()
            && matches!(modal.motion, 20 | 30 | 50 | 51 | 331 | 760 | 870)
            && axis_word.is_some());
    let uses = |letter: u8, ok: bool, msg: &str| -> Result<(), (ErrorKind, Option<usize>)> {
        match has_at(letter) {
            Some(i) if !ok => bad(msg, Some(i)),
            _ => Ok(()),
        }
    };
    uses(
        b'i',
        arcish || (motion == 20 || motion == 30),
        "I word with no G2, G3, G5, G5.1, G10, G33.1, G76 or G87 to use it",
    )?;
    uses(
        b'j',
        arcish || (motion == 20 || motion == 30),
        "J word with no G2, G3, G5, G5.1, G10, G76 or G87 to use it",
    )?;
    uses(
        b'k',
        arcish || matches!(motion, 20 | 30 | 330 | 331 | 760 | 870),
        "K word with no G2, G3, G33, G33.1, G76 or G87 to use it",
    )?;
    let canned = matches!(motion, 730 | 740 | 760 | 810..=890);
    uses(
        b'r',
        matches!(motion, 20 | 30) || canned || g_on(&[100]) || axis_g0 == Some(100) || m_on(&[19]),
        "R word with no G-code that uses it",
    )?;
    uses(
        b'p',
        g_on(&[20, 30, 40, 100, 640, 50, 52, 760, 820, 860, 880, 890])
            || matches!(motion, 20 | 30 | 52 | 820 | 860 | 880 | 890)
            || m_on(&[19, 50, 51, 52, 53, 62, 63, 64, 65, 66, 98]),
        "P word with no G-code or M-code to use it",
    )?;
    uses(
        b'q',
        g_on(&[50, 100, 640, 730, 760, 830])
            || matches!(motion, 730 | 830)
            || m_on(&[19, 66, 67, 68, 61]),
        "Q word with no G-code or M-code to use it",
    )?;
    uses(
        b'h',
        g_on(&[430, 432, 760]),
        "H word with no G43 or G76 to use it",
    )?;
    uses(
        b'd',
        g_on(&[410, 411, 420, 421, 960]),
        "D word with no G41, G42 or G96 to use it",
    )?;
    uses(
        b'e',
        g_on(&[760]) || m_on(&[66, 67, 68]),
        "E word with no G76, M66, M67 or M68 to use it",
    )?;
    uses(
        b'l',
        // (G74 takes no L in the reference.)
        g_on(&[100, 410, 420, 760])
            || (canned && motion != 740)
            || m_on(&[66, 98])
            || g_on(&[52, 53]),
        "L word with no G10, canned cycle or M66 to use it",
    )?;
    uses(
        b'$',
        m_on(&[3, 4, 5, 19, 51]) || g_on(&[330, 331, 760, 950, 960, 970]),
        "$ word with no spindle code to use it",
    )?;
    // Whole numbers.
    for (i, &(l, v)) in words.iter().enumerate() {
        if matches!(l, b't' | b'h') && crate::parse::integer_value(v).is_err() {
            return Err((ErrorKind::NonInteger { value: v }, Some(i)));
        }
        if l == b'd' && g_on(&[410, 420]) && v.fract() != 0.0 {
            return bad("G41/G42 need a whole-number D word", Some(i));
        }
    }
    // Peck depths of a running G73/G83.
    if matches!(motion, 730 | 830)
        && (motion_here.is_some() || axis_word.is_some())
        && value(b'q').is_some_and(|q| q != -1.0 && q <= 0.0)
    {
        return bad("negative or zero Q value in G73/G83", has_at(b'q'));
    }
    if value(b'h').is_some_and(|h| h < -1.0) {
        return bad("negative H word", has_at(b'h'));
    }
    // G53 moves in machine coordinates: with G0 or G1, never incremental.
    if let Some(at) = gs.iter().find(|g| g.0 == 530).map(|g| g.1) {
        let motion_to_be = motion_here.or(axis_word.map(|_| modal.motion));
        if !matches!(motion_to_be, Some(0 | 10)) {
            return bad("G53 needs G0 or G1", Some(at));
        }
        let incremental = g_on(&[910]) || (!modal.absolute && !g_on(&[900]));
        if incremental {
            return bad("G53 cannot be used in incremental mode (G91)", Some(at));
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
            return bad("G10 needs L1, L2, L10, L11 or L20", has_at(b'l'));
        }
        if p + 0.0001 - p_int > 0.0002 {
            return bad("G10 P value not a whole number", has_at(b'p'));
        }
        if matches!(l, 2 | 20) && !(0.0..=9.0).contains(&p_int) {
            return bad("G10 L2/L20 P value out of range (0 to 9)", has_at(b'p'));
        }
        if matches!(l, 1 | 10 | 11) && p_int < 1.0 {
            return bad(
                "G10 L1/L10/L11 P value (a tool number) out of range",
                has_at(b'p'),
            );
        }
    }
    // Codes that need words.
    if g_on(&[40]) && !given(b'p') {
        return bad(
            "dwell time missing with G4",
            gs.iter().find(|g| g.0 == 40).map(|g| g.1),
        );
    }
    if g_on(&[960]) && has_at(b's').is_none() {
        return bad("S word missing with G96", None);
    }
    if m_on(&[62, 63, 64, 65]) && has_at(b'p').is_none() {
        return bad("no valid P word with M62-M65", None);
    }
    if m_on(&[66]) && !given(b'p') && has_at(b'e').is_none() {
        return bad("M66 needs a P or an E word", None);
    }
    if m_on(&[61]) && has_at(b'q').is_none() {
        return bad("M61 needs a Q word (tool number)", None);
    }
    // Motion needing a feed rate.
    let moves = motion_here.is_some() || axis_word.is_some();
    if moves && axis_g0.is_none() && matches!(motion, 10 | 20 | 30 | 50 | 51 | 730 | 810..=890) {
        let feed = words.iter().rev().find(|w| w.0 == b'f').map(|w| w.1);
        let inverse =
            gs.iter().any(|g| g.0 == 930) || (modal.feed_mode == 930 && !g_on(&[940, 950]));
        if inverse {
            if feed.is_none() && axis_word.is_some() {
                return bad("F word missing with an inverse time move", None);
            }
        } else if feed.unwrap_or(modal.feed) == 0.0 {
            return bad("cannot move at zero feed rate", None);
        }
        if matches!(motion, 20 | 30) && axis_word.is_some() {
            let arc = ["i", "j", "k", "r"]
                .iter()
                .any(|c| has[c.as_bytes()[0] as usize].is_some());
            if !arc {
                return bad("R, I, J and K words all missing for arc", None);
            }
        }
    }
    if motion_here.is_some_and(|m| matches!(m, 330 | 331)) && has_at(b'k').is_none() {
        return bad("K word missing with G33", None);
    }
    Ok(())
}
