//! Running LinuxCNC's standalone interpreter `rs274` and comparing the
//! machine commands of two runs.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

pub const RS274: &str = "/usr/bin/rs274";

/// Whether rs274 is available; when it is not, tests that need it say they
/// were skipped, or fail when NGCFLAT_REQUIRE_RS274=1.
pub fn available(test: &str) -> bool {
    if Path::new(RS274).exists() {
        return true;
    }
    if std::env::var("NGCFLAT_REQUIRE_RS274").is_ok_and(|v| v == "1") {
        panic!("{test}: rs274 is required (NGCFLAT_REQUIRE_RS274=1) but {RS274} is missing");
    }
    eprintln!(
        "SKIPPED {test}: {RS274} not found (install linuxcnc-uspace); the differential tests did not run"
    );
    false
}

pub struct Run {
    pub ok: bool,
    /// Canon and print lines, counter and N field removed, COMMENT lines
    /// dropped.
    pub lines: Vec<String>,
    pub stderr: String,
}

/// Runs `rs274 -g` on a program text with an INI text, in a private folder
/// (rs274 writes files under HOME and the working folder).
pub fn run(program: &[u8], ini: &str, var: Option<&Path>) -> Run {
    run_with(program, ini, var, None)
}

/// As [`run`], with a tool table text (`-t`) when given.
pub fn run_with(program: &[u8], ini: &str, var: Option<&Path>, tools: Option<&str>) -> Run {
    let dir = tempfile::tempdir().expect("tempdir");
    let prog = dir.path().join("prog.ngc");
    std::fs::write(&prog, program).expect("write program");
    let ini_path = dir.path().join("oracle.ini");
    std::fs::write(&ini_path, ini).expect("write ini");
    let mut cmd = Command::new(RS274);
    cmd.current_dir(dir.path()).env("HOME", dir.path());
    cmd.arg("-g").arg("-i").arg(&ini_path);
    if let Some(v) = var {
        let copy = dir.path().join("params.var");
        std::fs::copy(v, &copy).expect("copy var file");
        cmd.arg("-v").arg(copy);
    }
    if let Some(t) = tools {
        let tbl = dir.path().join("tools.tbl");
        std::fs::write(&tbl, t).expect("write tool table");
        cmd.arg("-t").arg(tbl);
    }
    cmd.arg(&prog)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    let out = cmd.output().expect("run rs274");
    let text = String::from_utf8_lossy(&out.stdout);
    let lines = text.lines().filter_map(normalize).collect();
    Run {
        ok: out.status.success(),
        lines,
        stderr: String::from_utf8_lossy(&out.stderr).into_owned(),
    }
}

/// `   12 N..... STRAIGHT_FEED(...)` → `STRAIGHT_FEED(...)`; print output is
/// kept as it is; COMMENT lines are dropped.
fn normalize(line: &str) -> Option<String> {
    let t = line.trim_start();
    let digits = t.bytes().take_while(u8::is_ascii_digit).count();
    let cmd = if digits > 0 && t[digits..].starts_with(" N") {
        let rest = &t[digits + 2..];
        let rest = rest.trim_start_matches(['.', '0', '1', '2', '3', '4', '5', '6', '7', '8', '9']);
        rest.trim().to_string()
    } else {
        line.to_string()
    };
    if cmd.starts_with("COMMENT(") {
        return None;
    }
    Some(cmd)
}

pub fn split_numbers(s: &str) -> (Vec<String>, Vec<f64>) {
    let mut text = Vec::new();
    let mut nums = Vec::new();
    let mut cur = String::new();
    let b = s.as_bytes();
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        let starts_num = c.is_ascii_digit()
            || ((c == b'-' || c == b'.')
                && b.get(i + 1)
                    .is_some_and(|d| d.is_ascii_digit() || *d == b'.'));
        if starts_num && !cur.ends_with(|ch: char| ch.is_ascii_alphabetic() || ch == '_') {
            let j = i
                + 1
                + b[i + 1..]
                    .iter()
                    .take_while(|d| d.is_ascii_digit() || **d == b'.')
                    .count();
            if let Ok(v) = s[i..j].parse::<f64>() {
                text.push(std::mem::take(&mut cur));
                nums.push(v);
                i = j;
                continue;
            }
        }
        cur.push(c as char);
        i += 1;
    }
    text.push(cur);
    (text, nums)
}

/// Compares two runs line by line, numbers within `tol`. Returns a
/// description of the first difference.
pub fn compare(a: &[String], b: &[String], tol: f64) -> Result<(), String> {
    for (i, (x, y)) in a.iter().zip(b.iter()).enumerate() {
        let (tx, nx) = split_numbers(x);
        let (ty, ny) = split_numbers(y);
        let same = tx == ty
            && nx.len() == ny.len()
            && nx.iter().zip(&ny).all(|(p, q)| (p - q).abs() <= tol);
        if !same {
            return Err(format!("line {}: original `{x}` vs flattened `{y}`", i + 1));
        }
    }
    if a.len() != b.len() {
        return Err(format!(
            "original has {} lines, flattened {}; first extra: {:?}",
            a.len(),
            b.len(),
            a.get(b.len()).or(b.get(a.len()))
        ));
    }
    Ok(())
}

/// An INI for rs274 with the given subroutine folders (absolute).
pub fn ini_with(dirs: &[PathBuf], extra: &str) -> String {
    let mut s = String::new();
    if !dirs.is_empty() {
        let list: Vec<String> = dirs.iter().map(|d| d.display().to_string()).collect();
        s.push_str(&format!(
            "[RS274NGC]\nSUBROUTINE_PATH = {}\n",
            list.join(":")
        ));
    }
    s.push_str(extra);
    s
}

/// The seeds of a generated suite: `{var}_CASES` programs (default `cases`)
/// from seed `{var}_SEED` (default 1).
pub fn suite_seeds(var: &str, cases: u64) -> std::ops::Range<u64> {
    let env = |name: &str| -> Option<u64> {
        std::env::var(format!("{var}_{name}"))
            .ok()
            .and_then(|v| v.trim().parse().ok())
    };
    let start = env("SEED").unwrap_or(1);
    start..start.saturating_add(env("CASES").unwrap_or(cases))
}

/// Runs `f` on every seed, on `per_core` threads a core (two at least),
/// each thread taking the next seed; the results in seed order.
pub fn on_threads<T: Send>(
    seeds: std::ops::Range<u64>,
    per_core: usize,
    f: impl Fn(u64) -> T + Sync,
) -> Vec<(u64, T)> {
    use std::sync::Mutex;
    use std::sync::atomic::{AtomicU64, Ordering};
    let next = AtomicU64::new(seeds.start);
    let results = Mutex::new(Vec::new());
    let threads = std::thread::available_parallelism()
        .map_or(2, |n| n.get())
        .max(2)
        * per_core.max(1);
    std::thread::scope(|s| {
        for _ in 0..threads {
            s.spawn(|| {
                loop {
                    let seed = next.fetch_add(1, Ordering::Relaxed);
                    if seed >= seeds.end {
                        break;
                    }
                    let r = f(seed);
                    results.lock().expect("results").push((seed, r));
                }
            });
        }
    });
    let mut results = results.into_inner().expect("results");
    results.sort_by_key(|r| r.0);
    results
}
