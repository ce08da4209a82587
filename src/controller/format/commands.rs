//! One command per line, for a firmware that runs only the first command
//! of a line (Klipper, Marlin: `G21 G1 X20` runs G21 and drops the move).
//!
//! The words of a line as the writer has them are cut into commands, each
//! a G or M code with the value words it reads, written in the order
//! LinuxCNC runs a line (feed mode, F, S, T, M6, spindle, coolant,
//! overrides, dwell, plane, units, compensation, tool length, coordinate
//! system, path mode, distance mode, retract mode, G10/G28/G30/G92, motion,
//! stops). Such a firmware has no modal words of its own either: a move
//! names its motion code (the last one written), F is written on the next
//! move and S on the spindle command (M3/M4 again while the spindle
//! turns), and line numbers are not written (Marlin would want a checksum
//! with them).

/// A word as the writer keeps it: letter, value, whether it is a code
/// (G or M).
pub(super) type Item = (u8, f64, bool);

/// What the target has been given so far, which the next lines depend on.
#[derive(Debug, Default, Clone)]
pub(super) struct Carried {
    /// The last motion code written (G0–G3, G38.x, a cycle).
    motion: Option<f64>,
    /// An F not written yet (no move since).
    feed: Option<f64>,
    /// An S not written yet (the spindle off since).
    speed: Option<f64>,
    /// M3 or M4 while the spindle turns.
    spindle: Option<f64>,
    /// F is written on feed moves only, never on G0 (the profile's
    /// `feed_on_rapid = false`).
    feed_moves_only: bool,
    /// The target is in inches (the last G20/G21 written), and the carried
    /// F is in inches per minute.
    inch: bool,
    feed_inch: bool,
    /// The target is in G91 (the last G90/G91 written).
    incremental: bool,
}

impl Carried {
    /// Nothing carried yet; `feed_moves_only`: F never on a G0.
    pub(super) fn new(feed_moves_only: bool) -> Carried {
        Carried {
            feed_moves_only,
            ..Carried::default()
        }
    }

    /// The units the target is in before the first line (the program's
    /// at its start).
    pub(super) fn start_in_inches(&mut self, inch: bool) {
        self.inch = inch;
    }
}

/// Feed `f`, in inches per minute when `from_inch`, in those of `to_inch`.
fn feed_in(f: f64, from_inch: bool, to_inch: bool) -> f64 {
    match (from_inch, to_inch) {
        (true, false) => f * 25.4,
        (false, true) => f / 25.4,
        _ => f,
    }
}

/// Where LinuxCNC runs a code in a line (its order of execution).
fn rank(letter: u8, v: f64) -> u8 {
    let t = (v * 10.0).round() as i64;
    if letter == b'M' {
        return match t / 10 {
            6 | 61 => 6,
            3..=5 => 7,
            7..=9 => 8,
            48..=53 => 9,
            0 | 1 | 2 | 30 | 60 => 23,
            _ => 10,
        };
    }
    match t {
        930 | 940 | 950 => 1,
        40 => 11,
        170 | 180 | 190 => 12,
        200 | 210 => 13,
        400 | 410 | 411 | 420 | 421 => 14,
        430 | 431 | 432 | 490 => 15,
        540..=593 => 16,
        610 | 611 | 640 => 17,
        900 | 910 => 18,
        901 | 911 => 19,
        980 | 990 => 20,
        100 | 280 | 281 | 300 | 301 | 520 | 920..=923 => 21,
        // G53 goes in front of its move (Marlin's prefix).
        530 => 22,
        _ => 22,
    }
}

fn is_motion(letter: u8, v: f64) -> bool {
    let t = (v * 10.0).round() as i64;
    letter == b'G'
        && matches!(t, 0 | 10 | 20 | 30 | 50 | 51 | 52 | 53 | 330 | 331 | 382..=385 | 730 | 760 | 800..=890)
}

/// G10, G28, G30, G52, G92 and G43.1: codes that read axis words as
/// their own.
fn takes_axes(letter: u8, v: f64) -> bool {
    let t = (v * 10.0).round() as i64;
    letter == b'G' && matches!(t, 100 | 280 | 300 | 431 | 520 | 920)
}

/// The lines of one command each for the words `items` of a line.
pub(super) fn split(items: &[Item], c: &mut Carried) -> Vec<Vec<Item>> {
    let f_inch = c.inch;
    // The commands of the line: (rank, code) with their words.
    let mut cmds: Vec<(u8, Vec<Item>)> = Vec::new();
    let find = |cmds: &Vec<(u8, Vec<Item>)>, pred: &dyn Fn(u8, f64) -> bool| {
        cmds.iter().position(|(_, w)| pred(w[0].0, w[0].1))
    };
    for &(l, v, code) in items {
        if code {
            if l == b'G' && (v * 10.0).round() as i64 == 530 {
                // G53 written with the move it applies to.
                cmds.push((22, vec![(l, v, true)]));
                continue;
            }
            if is_motion(l, v)
                && let Some(i) = find(&cmds, &|l, v| l == b'G' && (v * 10.0).round() as i64 == 530)
            {
                cmds[i].1.push((l, v, true));
                continue;
            }
            cmds.push((rank(l, v), vec![(l, v, true)]));
        }
    }
    let motion_at = cmds
        .iter()
        .position(|(_, w)| w.iter().any(|&(l, v, code)| code && is_motion(l, v)));
    let owner = |letter: u8, cmds: &Vec<(u8, Vec<Item>)>| -> Option<usize> {
        let code = |want: &[i64], m: bool| {
            cmds.iter().position(|(_, w)| {
                let (l, v, _) = w[0];
                (if m { l == b'M' } else { l == b'G' })
                    && want.contains(&((v * 10.0).round() as i64))
            })
        };
        match letter {
            b'P' => code(&[40], false)
                .or(code(&[100], false))
                .or(code(&[640], false))
                .or(motion_at),
            b'L' | b'R' => code(&[100], false).or(motion_at),
            b'Q' => code(&[640], false).or(motion_at),
            b'H' => code(&[430, 432], false),
            b'D' => code(&[410, 420], false),
            b'S' => code(&[30, 40], true),
            b'F' => motion_at,
            b'X' | b'Y' | b'Z' | b'A' | b'B' | b'C' | b'U' | b'V' | b'W' => cmds
                .iter()
                .position(|(_, w)| takes_axes(w[0].0, w[0].1))
                .or(motion_at),
            _ => motion_at,
        }
    };
    let mut loose: Vec<Item> = Vec::new();
    let mut tool: Option<Item> = None;
    let mut speed = None;
    let mut feed = None;
    for &(l, v, code) in items {
        if code || l == b'N' {
            continue;
        }
        match l {
            b'T' => tool = Some((l, v, false)),
            b'S' if owner(l, &cmds).is_none() => speed = Some(v),
            b'F' if owner(l, &cmds).is_none() => feed = Some(v),
            _ => match owner(l, &cmds) {
                Some(i) => cmds[i].1.push((l, v, false)),
                None => loose.push((l, v, false)),
            },
        }
    }
    if let Some(t) = tool {
        cmds.push((5, vec![t]));
    }
    // M5 (or the end of the program) on the line stops the spindle after
    // LinuxCNC has set the speed: the speed waits for the next M3/M4.
    let stops = cmds.iter().any(|(_, w)| {
        let (l, v, _) = w[0];
        l == b'M' && matches!((v * 10.0).round() as i64, 20 | 50 | 300)
    });
    if let Some(s) = speed {
        match c.spindle {
            _ if stops => c.speed = Some(s),
            // A new speed while the spindle turns: its command again.
            Some(m) => cmds.push((7, vec![(b'M', m, true), (b'S', s, false)])),
            None => c.speed = Some(s),
        }
    }
    if let Some(f) = feed {
        c.feed = Some(f);
        c.feed_inch = f_inch;
    }
    if !loose.is_empty() {
        // Axis or arc words of the modal motion.
        let mut line = Vec::with_capacity(loose.len() + 1);
        if let Some(m) = c.motion {
            line.push((b'G', m, true));
        }
        line.extend(loose);
        cmds.push((22, line));
    }
    cmds.sort_by_key(|(r, _)| *r);
    carry_on(cmds, c, f_inch)
}

/// The commands of a line in their order, with the F and S they carry
/// over (see [`Carried`]).
///
/// An F of the line is in the units before the line: LinuxCNC sets the
/// feed before the units (`G20 F60` is 60 mm/min), so one written on a
/// move after the line's G20 is converted (`f_inch`: those units).
fn carry_on(cmds: Vec<(u8, Vec<Item>)>, c: &mut Carried, f_inch: bool) -> Vec<Vec<Item>> {
    let mut out = Vec::with_capacity(cmds.len());
    for (_, mut w) in cmds {
        let (l, v, code) = w[0];
        let t = (v * 10.0).round() as i64;
        if code && l == b'G' && (t == 200 || t == 210) {
            c.inch = t == 200;
        }
        if code && l == b'G' && (t == 900 || t == 910) {
            c.incremental = t == 910;
        }
        if code && l == b'G' && t == 100 && c.incremental && w.contains(&(b'L', 2.0, false)) {
            // G10 L2's values are the offsets in LinuxCNC whatever the
            // distance mode; Smoothieware adds them to the offset in G91.
            out.push(vec![(b'G', 90.0, true)]);
            out.push(w);
            out.push(vec![(b'G', 91.0, true)]);
            continue;
        }
        if code && l == b'M' {
            match t {
                30 | 40 => {
                    c.spindle = Some(v);
                    match w.iter().position(|x| x.0 == b'S') {
                        Some(_) => c.speed = None,
                        None => {
                            if let Some(s) = c.speed.take() {
                                w.push((b'S', s, false));
                            }
                        }
                    }
                }
                50 | 20 | 300 => c.spindle = None,
                _ => {}
            }
        }
        // The motion code of the command (after a G53 prefix).
        let motion = w
            .iter()
            .find(|&&(l, v, code)| code && is_motion(l, v))
            .map(|&(_, v, _)| v);
        if let Some(m) = motion {
            c.motion = (m != 80.0).then_some(m);
        }
        if c.feed_moves_only && motion == Some(0.0) {
            // A firmware whose G0 reads no F (or reads it as its own
            // rapid rate): the F waits for the next feed move.
            if let Some(i) = w.iter().position(|x| x.0 == b'F' && !x.2) {
                c.feed = Some(w.remove(i).1);
                c.feed_inch = f_inch;
            }
        } else if motion.is_some_and(|m| m != 80.0) {
            match w.iter().position(|x| x.0 == b'F' && !x.2) {
                Some(i) => {
                    w[i].1 = feed_in(w[i].1, f_inch, c.inch);
                    c.feed = None;
                }
                None => {
                    if let Some(f) = c.feed.take() {
                        w.push((b'F', feed_in(f, c.feed_inch, c.inch), false));
                    }
                }
            }
        }
        out.push(w);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(line: &str) -> Vec<Item> {
        line.split_whitespace()
            .map(|w| {
                let l = w.as_bytes()[0];
                (l, w[1..].parse().unwrap(), l == b'G' || l == b'M')
            })
            .collect()
    }

    fn show(lines: &[Vec<Item>]) -> Vec<String> {
        lines
            .iter()
            .map(|l| {
                l.iter()
                    .map(|&(c, v, _)| format!("{}{}", c as char, v))
                    .collect::<Vec<_>>()
                    .join(" ")
            })
            .collect()
    }

    fn run(lines: &[&str]) -> Vec<String> {
        let mut c = Carried::default();
        lines
            .iter()
            .flat_map(|l| show(&split(&parse(l), &mut c)))
            .collect()
    }

    #[test]
    fn commands_in_linuxcnc_order_with_their_words() {
        assert_eq!(run(&["G21 G1 X20 F100"]), ["G21", "G1 X20 F100"]);
        assert_eq!(run(&["G1 X1 G90 G17"]), ["G17", "G90", "G1 X1"]);
        assert_eq!(run(&["G4 P0.5 G91"]), ["G4 P0.5", "G91"]);
        assert_eq!(
            run(&["M0 G0 X1 M3 S1000 M8"]),
            ["M3 S1000", "M8", "G0 X1", "M0"]
        );
        assert_eq!(run(&["N10 G0 X1"]), ["G0 X1"]);
        assert_eq!(run(&["G53 G0 Z0 G90"]), ["G90", "G53 G0 Z0"]);
    }

    #[test]
    fn modal_words_are_carried_to_the_command_that_reads_them() {
        // A move names its motion code; F waits for the next move.
        assert_eq!(
            run(&["G1 X1 F100", "Y2", "F200", "G4 P1", "X3"]),
            ["G1 X1 F100", "G1 Y2", "G4 P1", "G1 X3 F200"]
        );
        // S waits for M3 while the spindle is off, and rides on M3 again
        // while it turns.
        assert_eq!(
            run(&["S500", "M3", "S800", "M5", "S900", "M4"]),
            ["M3 S500", "M3 S800", "M5", "M4 S900"]
        );
        // G80 ends the modal motion.
        assert_eq!(run(&["G80", "G0 X1", "Y1"]), ["G80", "G0 X1", "G0 Y1"]);
    }

    #[test]
    fn axis_words_of_a_setting_code_stay_with_it() {
        assert_eq!(run(&["G92 X0 Y0"]), ["G92 X0 Y0"]);
        assert_eq!(run(&["G10 L2 P1 X3"]), ["G10 L2 P1 X3"]);
        assert_eq!(run(&["G1 X1 F10", "G92 Z0 X2"]), ["G1 X1 F10", "G92 Z0 X2"]);
    }

    fn run_with(mut c: Carried, lines: &[&str]) -> Vec<String> {
        lines
            .iter()
            .flat_map(|l| show(&split(&parse(l), &mut c)))
            .collect()
    }

    #[test]
    fn feed_on_feed_moves_only_where_a_g0_reads_none() {
        let lines = ["G0 X1 F300", "G0 Y1", "G1 X2", "G0 X0 F50", "G2 X1 I1"];
        assert_eq!(
            run_with(Carried::new(true), &lines),
            ["G0 X1", "G0 Y1", "G1 X2 F300", "G0 X0", "G2 X1 I1 F50"]
        );
        // Otherwise it rides on the G0 as written.
        assert_eq!(
            run_with(Carried::new(false), &lines[..3]),
            ["G0 X1 F300", "G0 Y1", "G1 X2"]
        );
    }

    #[test]
    fn a_speed_beside_m5_waits_for_the_next_start() {
        assert_eq!(
            run(&["M3 S500", "M5 S800", "G0 X1", "M3"]),
            ["M3 S500", "M5", "G0 X1", "M3 S800"]
        );
    }

    #[test]
    fn a_feed_is_in_the_units_before_its_lines_g20() {
        // LinuxCNC sets F before G20/G21: `G20 F60` is 60 mm/min.
        let mut c = Carried::new(false);
        c.start_in_inches(false);
        assert_eq!(
            run_with(
                c,
                &["G20 F60", "G1 X1", "F10", "G21", "G1 X2", "G20 G1 X3 F254"]
            ),
            [
                "G20",
                &format!("G1 X1 F{}", 60.0 / 25.4),
                "G21",
                &format!("G1 X2 F{}", 10.0 * 25.4),
                "G20",
                "G1 X3 F10",
            ]
        );
    }

    #[test]
    fn g10_l2_in_g91_is_written_in_g90() {
        assert_eq!(
            run(&["G91 G10 L2 P1 X5", "G10 L20 P1 X1", "G90 G10 L2 P2 Y1"]),
            [
                "G91",
                "G90",
                "G10 L2 P1 X5",
                "G91",
                "G10 L20 P1 X1",
                "G90",
                "G10 L2 P2 Y1"
            ]
            .map(String::from)
        );
    }
}
