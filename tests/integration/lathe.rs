//! Lathe cycles G70–G72 against rs274: random contours (lines and arcs,
//! with and without pockets, fillets and chamfers, in all four quadrants),
//! each cut by a random cycle with random D, I, R, E and P. The original
//! and its flattened output must give rs274 the same canon (numbers within
//! 2e-4: rs274 prints 4 decimals), and a program rs274 refuses must be
//! refused by ngcflat at the line rs274 names.
//!
//! `NGCFLAT_LATHE_CASES=N` sets the number of programs (default 200),
//! `NGCFLAT_LATHE_SEED=S` the first seed.

use std::io::Read;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use crate::oracle;
use crate::rng::Rng;

/// Rounded to 3 decimals, as a program would write it.
fn r3(v: f64) -> f64 {
    (v * 1000.0).round() / 1000.0
}

fn num(v: f64) -> String {
    let s = format!("{:.3}", r3(v));
    let s = s.trim_end_matches('0').trim_end_matches('.').to_string();
    if s == "-0" { "0".into() } else { s }
}

/// One generated program: its text and what it is (for messages).
pub struct Case {
    pub text: String,
    pub what: String,
}

pub fn case(seed: u64) -> Case {
    let mut g = Rng(seed.wrapping_mul(0x2545_F491_4F6C_DD1D) ^ 0x1234_5678);
    // The contour in the first quadrant, cut along -Z with X growing:
    // (z, x) points; pockets when X may go down.
    let pockets = g.chance(0.4);
    let n = 2 + g.below(5);
    let mut pts = vec![(r3(g.float(-0.5, 1.0)), r3(g.float(1.0, 6.0)))];
    for _ in 0..n {
        let (z, x) = *pts.last().unwrap_or(&(0.0, 0.0));
        let dz = g.float(0.5, 4.0);
        let dx = if pockets {
            g.float(-2.5, 3.0)
        } else if g.chance(0.3) {
            0.0
        } else {
            g.float(0.0, 3.0)
        };
        pts.push((r3(z - dz), r3((x + dx).max(0.5))));
    }
    let top = pts.iter().map(|p| p.1).fold(0.0, f64::max) + r3(g.float(1.0, 4.0));
    let zs = pts[0].0 + r3(g.float(0.5, 3.0));
    let code = ["G70", "G71", "G71.1", "G71.2", "G72", "G72.1", "G72.2"][g.below(7)];
    // G72 faces: the same contour turned a quarter (Z from X, X from Z),
    // and sometimes G70/G71 are given such a contour too.
    let face = code.starts_with("G72") != g.chance(0.15);
    // A quadrant: mirror X (boring) and/or Z.
    let (mx, mz) = (g.chance(0.3), g.chance(0.3));
    let m = |(z, x): (f64, f64)| -> (f64, f64) {
        let (z, x) = if face { (x, -z) } else { (z, x) };
        (if mz { -z } else { z }, if mx { -x } else { x })
    };
    let mut body = Vec::new();
    let mut finishes = false;
    for k in 1..pts.len() {
        let (p, q) = (m(pts[k - 1]), m(pts[k]));
        let corner = if k + 1 < pts.len() && g.chance(0.15) {
            finishes = true;
            if g.chance(0.5) {
                format!(" A{}", num(g.float(0.1, 0.8)))
            } else {
                format!(" C{}", num(g.float(0.1, 0.8)))
            }
        } else {
            String::new()
        };
        if g.chance(0.35) {
            // An arc through both points: radius from half the chord up.
            let (cz, cx) = (q.0 - p.0, q.1 - p.1);
            let chord = (cz * cz + cx * cx).sqrt();
            let r = chord / 2.0 * g.float(1.2, 4.0);
            let h = (r * r - chord * chord / 4.0).max(0.0).sqrt();
            let side = if g.chance(0.5) { 1.0 } else { -1.0 };
            let (midz, midx) = ((p.0 + q.0) / 2.0, (p.1 + q.1) / 2.0);
            let (nz, nx) = (-cx / chord * side, cz / chord * side);
            let (kz, kx) = (midz + nz * h, midx + nx * h);
            // The minor arc: G3 with the centre on the left of the travel
            // (sometimes the major one).
            let ccw = (side > 0.0) != g.chance(0.1);
            let g23 = if ccw { "G3" } else { "G2" };
            if g.chance(0.2) {
                body.push(format!(
                    "  {g23} X{} Z{} R{}{corner}",
                    num(q.1),
                    num(q.0),
                    num(r)
                ));
            } else {
                body.push(format!(
                    "  {g23} X{} Z{} I{} K{}{corner}",
                    num(q.1),
                    num(q.0),
                    num(kx - p.1),
                    num(kz - p.0)
                ));
            }
        } else {
            body.push(format!("  G1 X{} Z{}{corner}", num(q.1), num(q.0)));
        }
    }
    let first = m(pts[0]);
    let (sz, sx) = m((zs, top));
    let lead = if g.chance(0.5) { "G0" } else { "G1" };
    let mut text = String::from("G18 G21 G90 F100\n");
    text.push_str(&format!("G0 X{} Z{}\n", num(sx), num(sz)));
    text.push_str("o100 sub\n");
    text.push_str(&format!("  {lead} X{} Z{}\n", num(first.1), num(first.0)));
    for l in &body {
        text.push_str(l);
        text.push('\n');
    }
    if g.chance(0.6) {
        // Up to the top, away from the stock.
        let lastc = *pts.last().unwrap_or(&(0.0, 0.0));
        let (rz, rx) = m((lastc.0, top));
        text.push_str(&format!("  G1 X{} Z{}\n", num(rx), num(rz)));
    }
    text.push_str("o100 endsub\n");
    let d = if g.chance(0.2) {
        0.0
    } else {
        r3(g.float(0.05, 1.0))
    };
    let words = if code == "G70" {
        let e = r3(g.float(0.0, d));
        let p = 1 + g.below(3);
        format!("D{} E{} P{p}", num(d), num(e))
    } else {
        let i = r3(g.float(0.2, 2.0));
        let r = r3(g.float(0.0, 0.8));
        format!("D{} I{} R{}", num(d), num(i), num(r))
    };
    text.push_str(&format!("{code} Q100 X{} Z{} {words}\n", num(sx), num(sz)));
    if g.chance(0.3) {
        text.push_str(&format!("G70 Q100 X{} Z{} D0.2 P1\n", num(sx), num(sz)));
    }
    text.push_str("G1 X[#<_x> + 1] Z[#<_z> + 1]\nM2\n");
    let what = format!(
        "{code}, {} elements{}{}{}{}{}",
        n,
        if face { ", turned" } else { "" },
        if pockets { ", pockets" } else { "" },
        if finishes { ", corner finishes" } else { "" },
        if mx { ", X mirrored" } else { "" },
        if mz { ", Z mirrored" } else { "" }
    );
    Case { text, what }
}

/// rs274 on a program, given up after `limit` (it loops forever on some
/// contours): whether it succeeded, its canon lines and its stderr. None
/// when it did not finish.
fn rs274_within(program: &str, limit: Duration) -> Option<(bool, Vec<String>, String)> {
    let dir = tempfile::tempdir().expect("tempdir");
    let prog = dir.path().join("prog.ngc");
    std::fs::write(&prog, program).expect("write program");
    let mut child = Command::new(oracle::RS274)
        .current_dir(dir.path())
        .env("HOME", dir.path())
        .arg("-g")
        .arg(&prog)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run rs274");
    let mut out = child.stdout.take().expect("stdout");
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = out.read_to_string(&mut s);
        s
    });
    let mut err = child.stderr.take().expect("stderr");
    let err_reader = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = err.read_to_string(&mut s);
        s
    });
    let t0 = Instant::now();
    let status = loop {
        if let Some(st) = child.try_wait().expect("wait rs274") {
            break Some(st);
        }
        if t0.elapsed() > limit {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let text = reader.join().unwrap_or_default();
    let err_text = err_reader.join().unwrap_or_default();
    let status = status?;
    let lines = text
        .lines()
        .filter(|l| !l.starts_with("Oops"))
        .map(|l| {
            let t = l.trim_start();
            let digits = t.bytes().take_while(u8::is_ascii_digit).count();
            if digits > 0 && t[digits..].starts_with(" N") {
                let rest =
                    t[digits + 2..].trim_start_matches(|c: char| c == '.' || c.is_ascii_digit());
                rest.trim().to_string()
            } else {
                l.to_string()
            }
        })
        .filter(|l| !l.starts_with("COMMENT("))
        .collect();
    Some((status.success(), lines, err_text))
}

/// Whether ngcflat's error (its first ` --> file:line:col`) is at a line
/// rs274's refusal names: rs274 prints the line's text last; a subroutine
/// call it built for the cycle it prints as `O<q> CALL`, which stands for
/// the cycle line (docs/deviations.md).
fn same_error_line(program: &str, rs: &str, ours: &str) -> Result<(), String> {
    if !rs
        .lines()
        .map(str::trim)
        .any(|l| !l.is_empty() && l != "executing")
    {
        // rs274 crashed (a segmentation fault on some contours with
        // pockets): it names no line.
        return Ok(());
    }
    let lines: Vec<&str> = program.lines().map(str::trim).collect();
    let theirs: Vec<usize> = match rs.lines().rev().map(str::trim).find(|l| lines.contains(l)) {
        Some(t) => (0..lines.len())
            .filter(|&i| lines[i] == t)
            .map(|i| i + 1)
            .collect(),
        None if rs.lines().any(|l| l.trim().ends_with(" CALL")) => (0..lines.len())
            .filter(|&i| ["G70", "G71", "G72"].iter().any(|g| lines[i].contains(g)))
            .map(|i| i + 1)
            .collect(),
        None => Vec::new(),
    };
    let mine = ours
        .lines()
        .find_map(|l| l.trim_start().strip_prefix("--> "))
        .and_then(|site| site.rsplit(':').nth(1)?.parse::<usize>().ok());
    match mine {
        Some(l) if theirs.contains(&l) => Ok(()),
        _ => Err(format!(
            "rs274 refuses line(s) {theirs:?} ({}), ngcflat line {mine:?}: {}",
            rs.trim(),
            ours.lines().next().unwrap_or("")
        )),
    }
}

pub enum Verdict {
    Same,
    /// Refused by both; ngcflat's message.
    BothRefuse(String),
    Endless,
}

/// Runs one case; Err describes a difference.
pub fn check(c: &Case) -> Result<Verdict, String> {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("prog.ngc");
    std::fs::write(&path, &c.text).expect("write");
    let out = Command::new(crate::bin())
        .arg("--zero-start")
        .arg(&path)
        .stdin(Stdio::null())
        .output()
        .expect("run ngcflat");
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    if stderr.contains("E1319") || stderr.contains("E1320") {
        // ngcflat says the reference never ends (or makes millions of
        // moves): it must not end in time.
        return match rs274_within(&c.text, Duration::from_secs(5)) {
            None => Ok(Verdict::Endless),
            Some(_) => Err(format!("ngcflat calls it endless, rs274 ends: {stderr}")),
        };
    }
    let Some((ok, a, rs_err)) = rs274_within(&c.text, Duration::from_secs(20)) else {
        return Err(format!(
            "rs274 did not finish; ngcflat: exit {:?} {stderr}",
            out.status.code()
        ));
    };
    if !ok {
        return if out.status.success() {
            Err(format!(
                "rs274 refuses it, ngcflat flattens it; rs274 said: {:?}",
                a.iter().rev().take(3).collect::<Vec<_>>()
            ))
        } else {
            same_error_line(&c.text, &rs_err, &stderr)?;
            Ok(Verdict::BothRefuse(
                stderr.lines().next().unwrap_or("").to_string(),
            ))
        };
    }
    if !out.status.success() {
        return Err(format!("rs274 accepts it, ngcflat refuses: {stderr}"));
    }
    let flat = String::from_utf8_lossy(&out.stdout).into_owned();
    let Some((ok_b, b, _)) = rs274_within(&flat, Duration::from_secs(20)) else {
        return Err("rs274 did not finish the flattened program".into());
    };
    if !ok_b {
        return Err(format!(
            "rs274 refuses the flattened program: {:?}",
            b.last()
        ));
    }
    oracle::compare(&a, &b, 2e-4).map(|_| Verdict::Same)
}

#[test]
fn lathe_cycles_match_rs274() {
    if !oracle::available("lathe_cycles_match_rs274") {
        return;
    }
    let cases: u64 = std::env::var("NGCFLAT_LATHE_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(200);
    let seed: u64 = std::env::var("NGCFLAT_LATHE_SEED")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1);
    let (mut same, mut refused, mut endless) = (0, 0, 0);
    let mut failures = Vec::new();
    for s in seed..seed + cases {
        let c = case(s);
        match check(&c) {
            Ok(Verdict::Same) => same += 1,
            Ok(Verdict::BothRefuse(why)) => {
                refused += 1;
                if std::env::var_os("NGCFLAT_LATHE_VERBOSE").is_some() {
                    eprintln!("seed {s} ({}): refused: {why}\n{}", c.what, c.text);
                }
            }
            Ok(Verdict::Endless) => endless += 1,
            Err(e) => failures.push(format!("seed {s} ({}): {e}\n{}", c.what, c.text)),
        }
    }
    eprintln!(
        "lathe cycles: {cases} programs from seed {seed}: {same} same motion, {refused} refused by both, {endless} endless in rs274, {} differ",
        failures.len()
    );
    for f in &failures {
        eprintln!("{}", f.lines().next().unwrap_or(""));
    }
    assert!(
        failures.is_empty(),
        "{} of {cases} differ; first:\n{}",
        failures.len(),
        failures[0]
    );
    // The generator must mostly make programs that are cut, not refused.
    assert!(
        same * 2 > cases as usize,
        "only {same} of {cases} programs were cut"
    );
}

/// A G70 run with cutter compensation on: a random contour (lines and
/// arcs, sometimes pockets and mirrored), G41.1/G42.1 with a random
/// diameter (sometimes zero) and lathe tool orientation, entered by a move
/// of its own or by the cycle's rapid, the cycle's X or Z sometimes left
/// out (it starts from the compensated position), moves after the cycle,
/// and G40 or M2.
pub fn comp_case(seed: u64) -> Case {
    let mut g = Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0x0707_7070);
    let pockets = g.chance(0.3);
    let n = 2 + g.below(4);
    let mut pts = vec![(r3(g.float(-0.5, 1.0)), r3(g.float(1.0, 5.0)))];
    for _ in 0..n {
        let (z, x) = *pts.last().unwrap_or(&(0.0, 0.0));
        let dx = if pockets {
            g.float(-2.0, 3.0)
        } else {
            g.float(0.0, 3.0)
        };
        pts.push((r3(z - g.float(0.8, 4.0)), r3((x + dx).max(0.5))));
    }
    let top = pts.iter().map(|p| p.1).fold(0.0, f64::max) + r3(g.float(1.0, 4.0));
    let zs = pts[0].0 + r3(g.float(0.5, 3.0));
    let (mx, mz) = (g.chance(0.25), g.chance(0.25));
    let m = |(z, x): (f64, f64)| (if mz { -z } else { z }, if mx { -x } else { x });
    let mut text = String::from("G18 G21 G90 F100\n");
    let (sz, sx) = m((zs, top));
    let (fz, fx) = m((zs + 4.0, top + 4.0));
    text.push_str(&format!("G0 X{} Z{}\n", num(fx), num(fz)));
    text.push_str("o100 sub\n");
    let first = m(pts[0]);
    let lead = if g.chance(0.5) { "G0" } else { "G1" };
    text.push_str(&format!("  {lead} X{} Z{}\n", num(first.1), num(first.0)));
    for k in 1..pts.len() {
        let (p, q) = (m(pts[k - 1]), m(pts[k]));
        if g.chance(0.35) {
            let (cz, cx) = (q.0 - p.0, q.1 - p.1);
            let chord = (cz * cz + cx * cx).sqrt();
            let r = chord / 2.0 * g.float(1.2, 4.0);
            let h = (r * r - chord * chord / 4.0).max(0.0).sqrt();
            let side = if g.chance(0.5) { 1.0 } else { -1.0 };
            let (nz, nx) = (-cx / chord * side, cz / chord * side);
            let (kz, kx) = ((p.0 + q.0) / 2.0 + nz * h, (p.1 + q.1) / 2.0 + nx * h);
            let g23 = if side > 0.0 { "G3" } else { "G2" };
            text.push_str(&format!(
                "  {g23} X{} Z{} I{} K{}\n",
                num(q.1),
                num(q.0),
                num(kx - p.1),
                num(kz - p.0)
            ));
        } else {
            text.push_str(&format!("  G1 X{} Z{}\n", num(q.1), num(q.0)));
        }
    }
    if g.chance(0.6) {
        let last = *pts.last().unwrap_or(&(0.0, 0.0));
        let (rz, rx) = m((last.0, top));
        text.push_str(&format!("  G1 X{} Z{}\n", num(rx), num(rz)));
    }
    text.push_str("o100 endsub\n");
    let dia = if g.chance(0.1) {
        0.0
    } else {
        r3(g.float(0.05, 0.8))
    };
    let side = if g.chance(0.5) { "G41.1" } else { "G42.1" };
    let orient = if g.chance(0.5) {
        String::new()
    } else {
        format!(" L{}", g.below(10))
    };
    text.push_str(&format!("{side} D{}{orient}\n", num(dia)));
    let entry = g.chance(0.7);
    if entry {
        let mv = if g.chance(0.5) { "G0" } else { "G1" };
        let (ez, ex) = m((zs + g.float(1.0, 3.0), top + g.float(0.5, 3.0)));
        text.push_str(&format!("{mv} X{} Z{}\n", num(ex), num(ez)));
    }
    let d = r3(g.float(0.0, 1.0));
    let e = r3(g.float(0.0, d));
    let passes = 1 + g.below(3);
    let mut words = format!("D{} E{} P{passes}", num(d), num(e));
    let omit = if entry { g.below(6) } else { 5 };
    if omit != 0 {
        words = format!("Z{} {words}", num(sz));
    }
    if omit != 1 {
        words = format!("X{} {words}", num(sx));
    }
    text.push_str(&format!("G70 Q100 {words}\n"));
    if g.chance(0.5) {
        let last = m(*pts.last().unwrap_or(&(0.0, 0.0)));
        let (az, ax) = (last.0, last.1 + if mx { -2.0 } else { 2.0 });
        text.push_str(&format!("G1 X{} Z{}\n", num(ax), num(az)));
    }
    if g.chance(0.7) {
        text.push_str(&format!("G40\nG0 X{} Z{}\n", num(fx), num(fz)));
    }
    text.push_str("M2\n");
    let what = format!(
        "G70 with {side} D{}{orient}, {n} elements{}{}{}{}",
        num(dia),
        if entry { "" } else { ", G70 enters" },
        if pockets { ", pockets" } else { "" },
        if mx { ", X mirrored" } else { "" },
        if mz { ", Z mirrored" } else { "" }
    );
    Case { text, what }
}

/// The text of the line rs274 names in its refusal (the line after the
/// message), trimmed.
fn rs274_error_text(stderr: &str) -> Option<String> {
    let mut lines = stderr.lines().filter(|l| *l != "executing");
    lines.next()?;
    lines.next().map(|l| l.trim().to_string())
}

/// The text of the line ngcflat's first error (short format) names.
fn ngcflat_error_text(program: &str, stderr: &str) -> Option<String> {
    let n: usize = stderr
        .lines()
        .find_map(|l| l.strip_prefix("prog.ngc:")?.split(':').next()?.parse().ok())?;
    program.lines().nth(n - 1).map(|l| l.trim().to_string())
}

/// One G70-with-compensation case: for a target that computes the
/// compensation (GRBL, grblHAL) ngcflat must write the path rs274 moves
/// along, or refuse at the line rs274 refuses. Where the output keeps
/// G41/G42 (LinuxCNC) it must write the same canon at diameter zero, the
/// same motion where it writes the path itself (the G70 enters the
/// compensation), or refuse (E1321, or rs274's refusal). Returns rs274's
/// message when it refuses, and whether the LinuxCNC output got a written
/// path.
pub fn comp_check(c: &Case, seed: u64) -> Result<(Option<String>, bool), String> {
    let run = oracle::run_with(c.text.as_bytes(), "", None, None);
    let dir = crate::tmp();
    crate::put(dir.path(), "prog.ngc", &c.text);
    let target = if seed.is_multiple_of(2) {
        "grbl"
    } else {
        "grblhal"
    };
    let common = ["--zero-start", "--message-format", "short", "prog.ngc"];
    let mut args = vec!["--target", target];
    args.extend(common);
    let (code, flat, stderr) = crate::run(dir.path(), &args);
    if !run.ok {
        let theirs = rs274_error_text(&run.stderr);
        let mine = ngcflat_error_text(&c.text, &stderr);
        if code != 1 || theirs != mine {
            return Err(format!(
                "rs274 refuses {theirs:?} ({}), ngcflat for {target} exits {code} at {mine:?}: {stderr}",
                run.stderr.trim()
            ));
        }
    } else {
        if code != 0 {
            return Err(format!(
                "rs274 runs it, ngcflat for {target} refuses: {stderr}"
            ));
        }
        crate::motion::same_motion(c.text.as_bytes(), flat.as_bytes())
            .map_err(|e| format!("{target}: {e}\n---- flattened\n{flat}"))?;
    }
    let (code, flat, stderr) = crate::run(dir.path(), &common);
    let zero = c.what.contains(" D0,") || c.what.contains(" D0 L");
    if code == 0 {
        if !run.ok {
            return Err(format!(
                "for LinuxCNC, ngcflat flattens what rs274 refuses:\n{flat}"
            ));
        }
        if zero {
            // Nothing offset: the same canon.
            let b = oracle::run_with(flat.as_bytes(), "", None, None);
            oracle::compare(&run.lines, &b.lines, 2e-4)?;
        } else {
            crate::motion::same_motion(c.text.as_bytes(), flat.as_bytes())
                .map_err(|e| format!("linuxcnc: {e}\n---- flattened\n{flat}"))?;
        }
    } else if code != 1
        || zero && run.ok
        || !(stderr.contains("E1321")
            || ngcflat_error_text(&c.text, &stderr) == rs274_error_text(&run.stderr))
    {
        return Err(format!(
            "for LinuxCNC, ngcflat exits {code} without E1321 or rs274's refusal: {stderr}"
        ));
    }
    let refused = (!run.ok).then(|| {
        let m = run.stderr.lines().find(|l| *l != "executing").unwrap_or("");
        m.split(':').next().unwrap_or("").to_string()
    });
    Ok((refused, code == 0 && !zero))
}

#[test]
fn g70_with_compensation_matches_rs274() {
    if !oracle::available("g70_with_compensation_matches_rs274") {
        return;
    }
    let seeds = oracle::suite_seeds("NGCFLAT_LATHE_COMP", 120);
    let (cases, start) = (seeds.end - seeds.start, seeds.start);
    let results = oracle::on_threads(seeds, 1, |seed| {
        let c = comp_case(seed);
        comp_check(&c, seed).map_err(|e| format!("seed {seed} ({}): {e}\n{}", c.what, c.text))
    });
    let (mut same, mut refused, mut written) = (0, 0, 0);
    let mut failures = Vec::new();
    let mut messages = std::collections::BTreeMap::<String, usize>::new();
    for (_, r) in results {
        match r {
            Ok((Some(m), _)) => {
                refused += 1;
                *messages.entry(m).or_default() += 1;
            }
            Ok((None, w)) => {
                same += 1;
                written += w as usize;
            }
            Err(e) => failures.push(e),
        }
    }
    eprintln!(
        "G70 with compensation: {cases} programs from seed {start}: {same} move the same ({written} of them also for LinuxCNC with the path written), {refused} refused by both at the same line, {} differ",
        failures.len()
    );
    for (m, n) in messages {
        eprintln!("  {n:6}  refused: {m}");
    }
    assert!(
        failures.is_empty(),
        "{} of {cases} differ; first:\n{}",
        failures.len(),
        failures[0]
    );
    // LinuxCNC's rapid toward the contour's end makes many of them gouge:
    // a third at least must run.
    assert!(
        same * 3 > cases as usize,
        "only {same} of {cases} programs ran"
    );
}
