//! Fixture programs under `fixtures/`:
//!
//! * `ok/**/*.ngc` flatten successfully; the output is snapshotted and must
//!   give rs274 the same machine commands as the original.
//! * `err/**/*.ngc` are refused by both ngcflat and rs274; the diagnostic is
//!   snapshotted in every message format.
//! * `refuse/**/*.ngc` are refused by ngcflat by design (runtime-only values,
//!   limits, unsafe names...); diagnostics snapshotted, no rs274 comparison.
//! * `setup/**/*.ngc` are not run: what the run is told (the arguments in
//!   `NAME.args`, the files they name) is refused first, exit status 2;
//!   diagnostics snapshotted.
//! * `deviation/**/*.ngc` depend on a documented rs274 bug ngcflat does not
//!   copy (docs/deviations.md): they flatten with a warning; no comparison.
//!
//! * `target/NAME/ok|refuse/**/*.ngc` run with `--target NAME`: lowered
//!   output snapshotted and compared with the original by machine motion
//!   (`motion.rs`), or refused.
//!
//! A fixture may have `NAME.args` beside it (extra arguments, relative to
//! the fixture's folder). Folders named `subs` hold subroutine files, not
//! fixtures. Adding a case is adding a file.

use std::path::{Path, PathBuf};

use crate::oracle;

pub fn read_args(ngc: &Path) -> Vec<String> {
    let args = ngc.with_extension("args");
    let mut v: Vec<String> = target_of(ngc)
        .map(|t| vec!["--target".to_string(), t])
        .unwrap_or_default();
    if let Ok(t) = std::fs::read_to_string(args) {
        v.extend(t.split_whitespace().map(str::to_string));
    }
    v
}

/// The target of a fixture under `fixtures/target/NAME/`.
pub fn target_of(ngc: &Path) -> Option<String> {
    let parts: Vec<String> = ngc
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    parts
        .windows(3)
        .rev()
        .find(|w| w[0] == "fixtures" && w[1] == "target")
        .map(|w| w[2].clone())
}

fn is_fixture(p: &Path) -> bool {
    p.extension().is_some_and(|e| e == "ngc") && !p.components().any(|c| c.as_os_str() == "subs")
}

fn category(p: &Path) -> &'static str {
    let s = p.to_string_lossy();
    if s.contains("/err/") {
        "err"
    } else if s.contains("/setup/") {
        "setup"
    } else if s.contains("/deviation/") {
        "deviation"
    } else if s.contains("/refuse/") {
        "refuse"
    } else {
        "ok"
    }
}

pub fn run_fixture(path: &Path, extra: &[&str]) -> (i32, String, String) {
    let dir = path.parent().expect("dir");
    let mut args = read_args(path);
    args.extend(extra.iter().map(|s| s.to_string()));
    args.push(
        path.file_name()
            .expect("name")
            .to_string_lossy()
            .into_owned(),
    );
    crate::outcome(crate::ngcflat(dir, &args, None))
}

#[test]
fn fixture_snapshots() {
    insta::glob!("../../fixtures", "**/*.ngc", |path| {
        if !is_fixture(path) {
            return;
        }
        let cat = category(path);
        let (code, stdout, stderr) = run_fixture(path, &[]);
        let mut snap = format!(
            "args: {:?}\nexit: {code}\n--- stdout\n{stdout}--- stderr\n{stderr}",
            read_args(path)
        );
        match cat {
            "ok" => assert_eq!(code, 0, "{} should flatten:\n{stderr}", path.display()),
            "deviation" => {
                assert_eq!(code, 0, "{} should flatten:\n{stderr}", path.display());
                assert!(
                    stderr.contains("warning"),
                    "{}: a deviation must warn",
                    path.display()
                );
            }
            _ => {
                assert_eq!(
                    code,
                    if cat == "setup" { 2 } else { 1 },
                    "{} should be refused:\n{stdout}{stderr}",
                    path.display()
                );
                assert!(stdout.is_empty(), "{}: output on error", path.display());
                for f in ["short", "json", "github"] {
                    let (_, _, e) = run_fixture(path, &["--message-format", f]);
                    snap.push_str(&format!("--- stderr ({f})\n{e}"));
                }
            }
        }
        insta::assert_snapshot!(snap);
    });
}

/// Turns relative folders of an INI into absolute ones (rs274 reads them
/// relative to its working folder) and drops them for `isolated`.
fn derive_ini(ini: &Path, isolated: bool) -> String {
    let text = std::fs::read_to_string(ini).expect("read ini");
    let base = ini.parent().expect("ini dir");
    let mut out = String::new();
    let mut lines = text.lines().peekable();
    while let Some(line) = lines.next() {
        let mut line = line.to_string();
        while line.trim_end().ends_with('\\') {
            let l = line.trim_end();
            line = l[..l.len() - 1].to_string();
            if let Some(n) = lines.next() {
                line.push_str(n.trim());
            }
        }
        let key = line.split('=').next().unwrap_or("").trim().to_string();
        if matches!(
            key.as_str(),
            "SUBROUTINE_PATH" | "PROGRAM_PREFIX" | "WIZARD_ROOT"
        ) {
            if isolated {
                continue;
            }
            let value = line.split_once('=').map(|x| x.1).unwrap_or("").trim();
            let abs: Vec<String> = value
                .split(':')
                .filter(|s| !s.is_empty())
                .map(|s| {
                    let p = Path::new(s.trim());
                    if p.is_absolute() {
                        p.to_path_buf()
                    } else {
                        base.join(p)
                    }
                    .display()
                    .to_string()
                })
                .collect();
            out.push_str(&format!("{key} = {}\n", abs.join(":")));
        } else {
            out.push_str(&line);
            out.push('\n');
        }
    }
    out
}

/// Differential check of one fixture; Err describes the mismatch, Ok(None)
/// passes, Ok(Some(reason)) was not comparable.
pub fn differential(path: &Path) -> Result<Option<String>, String> {
    let cat = category(path);
    if cat == "refuse" || cat == "deviation" || cat == "setup" {
        return Ok(Some("not comparable by design".into()));
    }
    if target_of(path).is_some() {
        return Ok(Some("compared by machine motion (motion.rs)".into()));
    }
    let dir = path.parent().expect("dir");
    let args = read_args(path);
    let mut sub_dirs: Vec<PathBuf> = Vec::new();
    let mut ini_a = String::new();
    let mut ini_b = String::new();
    let mut var = None;
    let mut tools = None;
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "-I" | "--subroutine-path" => {
                sub_dirs.push(dir.join(it.next().expect("-I value")));
            }
            "--ini" => {
                let ini = dir.join(it.next().expect("--ini value"));
                ini_a = derive_ini(&ini, false);
                ini_b = derive_ini(&ini, true);
            }
            "--var-file" => var = Some(dir.join(it.next().expect("--var-file value"))),
            "--tool-table" => {
                let t = dir.join(it.next().expect("--tool-table value"));
                tools = Some(std::fs::read_to_string(t).expect("read tool table"));
            }
            "-D" | "--define" | "--precision" | "--start-position" => {
                return Ok(Some(format!("{a} has no rs274 equivalent")));
            }
            _ => {}
        }
    }
    let ini_orig = format!("{}{}", oracle::ini_with(&sub_dirs, ""), ini_a);
    // rs274 reads INI lines of at most 255 characters; a long path list made
    // absolute no longer fits (the folder counting is compared in the
    // configuration tests, with short relative entries).
    if ini_orig.lines().any(|l| l.len() > 255) {
        return Ok(Some(
            "INI line too long for rs274 once made absolute".into(),
        ));
    }
    let program = std::fs::read(path).expect("read fixture");
    let a = oracle::run_with(&program, &ini_orig, var.as_deref(), tools.as_deref());
    let zero: &[&str] = if args.iter().any(|a| a == "--zero-start") {
        &[]
    } else {
        &["--zero-start"]
    };
    let (code, stdout, stderr) = run_fixture(path, zero);
    match cat {
        "err" => {
            if a.ok {
                return Err(format!(
                    "rs274 accepts the original, but it is filed under err/ (ngcflat exit {code})"
                ));
            }
            if code == 0 {
                return Err(format!(
                    "rs274 rejects the original ({}) but ngcflat flattens it",
                    a.stderr.trim()
                ));
            }
            same_error_line(path, &program, &a.stderr, &stderr)?;
            Ok(None)
        }
        _ => {
            if !a.ok {
                return Err(format!("rs274 rejects the original: {}", a.stderr.trim()));
            }
            if code != 0 {
                return Err(format!("ngcflat refuses it: {stderr}"));
            }
            // RETAIN_G43: the output carries the G43/G49 the switch implies,
            // so it runs without the switch; rs274 re-applies the same
            // offset at every block under it, so only offset changes count.
            let retain = ini_b.lines().any(|l| {
                let mut kv = l.splitn(2, '=');
                kv.next().is_some_and(|k| k.trim() == "RETAIN_G43")
                    && kv.next().is_some_and(|v| {
                        matches!(v.trim().to_ascii_uppercase().as_str(), "1" | "TRUE" | "YES")
                    })
            });
            let ini_b = if retain {
                ini_b
                    .lines()
                    .filter(|l| !l.trim_start().starts_with("RETAIN_G43"))
                    .map(|l| format!("{l}\n"))
                    .collect()
            } else {
                ini_b
            };
            let b = oracle::run_with(stdout.as_bytes(), &ini_b, var.as_deref(), tools.as_deref());
            if !b.ok {
                return Err(format!(
                    "rs274 rejects the flattened output: {}",
                    b.stderr.trim()
                ));
            }
            if retain {
                let changes = |lines: &[String]| -> Vec<String> {
                    let mut last: Option<&String> = None;
                    let mut v = Vec::new();
                    for l in lines {
                        if l.starts_with("USE_TOOL_LENGTH_OFFSET(") {
                            if last == Some(l) {
                                continue;
                            }
                            last = Some(l);
                        }
                        v.push(l.clone());
                    }
                    v
                };
                return oracle::compare(&changes(&a.lines), &changes(&b.lines), 1e-4).map(|_| None);
            }
            oracle::compare(&a.lines, &b.lines, 1e-4).map(|_| None)
        }
    }
}

/// For the cutter compensation and lathe cycle fixtures: ngcflat's error is
/// at the line rs274 names (rs274 prints the offending line's text last).
fn same_error_line(path: &Path, program: &[u8], rs: &str, ours: &str) -> Result<(), String> {
    let p = path.to_string_lossy();
    if !p.contains("/err/comp/") && !p.contains("/err/lathe-cycles/") {
        return Ok(());
    }
    let text = String::from_utf8_lossy(program);
    let lines: Vec<&str> = text.lines().map(str::trim).collect();
    let theirs: Vec<usize> = match rs.lines().rev().map(str::trim).find(|l| lines.contains(l)) {
        Some(t) => (0..lines.len())
            .filter(|&i| lines[i] == t)
            .map(|i| i + 1)
            .collect(),
        None => cycle_call_lines(&lines, rs),
    };
    let mine = ours
        .lines()
        .find_map(|l| l.trim_start().strip_prefix("--> "))
        .and_then(|site| site.rsplit(':').nth(1)?.parse::<usize>().ok());
    match mine {
        Some(l) if theirs.contains(&l) => Ok(()),
        _ => Err(format!(
            "rs274 refuses line(s) {theirs:?}, ngcflat line {mine:?}:\n{ours}"
        )),
    }
}

/// rs274 refusing the subroutine call it builds for a lathe cycle prints
/// that call as `O<q> CALL` (`%f`), a text in no file: the lines of the
/// cycles with that Q (docs/deviations.md: ngcflat names the cycle line).
fn cycle_call_lines(lines: &[&str], rs: &str) -> Vec<usize> {
    let Some(q) = rs.lines().find_map(|l| {
        let n = l.trim().strip_prefix('O')?.strip_suffix(" CALL")?;
        n.parse::<f64>().ok()
    }) else {
        return Vec::new();
    };
    let q_of = |l: &str| -> Option<f64> {
        let u = l.to_ascii_uppercase();
        if !["G70", "G71", "G72"].iter().any(|g| u.contains(g)) {
            return None;
        }
        let rest = &u[u.find('Q')? + 1..];
        let end = rest
            .find(|c: char| !(c.is_ascii_digit() || c == '.'))
            .unwrap_or(rest.len());
        rest[..end].parse().ok()
    };
    (0..lines.len())
        .filter(|&i| q_of(lines[i]).is_some_and(|v| (v - q).abs() < 1e-6))
        .map(|i| i + 1)
        .collect()
}

pub fn all_fixtures() -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = walkdir::WalkDir::new(crate::root().join("fixtures"))
        .sort_by_file_name()
        .into_iter()
        .filter_map(Result::ok)
        .map(|e| e.into_path())
        .filter(|p| is_fixture(p))
        .collect();
    v.sort();
    v
}

#[test]
fn fixtures_match_rs274() {
    if !oracle::available("fixtures_match_rs274") {
        return;
    }
    let files = all_fixtures();
    let failures = std::sync::Mutex::new(Vec::new());
    let next = std::sync::atomic::AtomicUsize::new(0);
    std::thread::scope(|s| {
        for _ in 0..4 {
            s.spawn(|| {
                loop {
                    let i = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                    let Some(f) = files.get(i) else { break };
                    if let Err(e) = differential(f) {
                        failures
                            .lock()
                            .unwrap()
                            .push(format!("{}: {e}", f.display()));
                    }
                }
            });
        }
    });
    let failures = failures.into_inner().unwrap();
    assert!(
        failures.is_empty(),
        "{} of {} fixtures differ from rs274:\n{}",
        failures.len(),
        files.len(),
        failures.join("\n")
    );
    eprintln!("{} fixtures agree with rs274", files.len());
}

/// Every refusal of a block (codes E0600–E0699 in `src/diag/block_error.rs`)
/// is documented by a fixture whose snapshot shows it.
#[test]
fn every_block_error_has_a_fixture() {
    let src = std::fs::read_to_string(crate::root().join("src/diag/block_error.rs"))
        .expect("block_error.rs");
    let codes: Vec<&str> = src
        .split('"')
        .filter(|t| t.len() == 5 && t.starts_with("E06"))
        .collect();
    assert!(codes.len() > 40, "codes found: {codes:?}");
    let mut shown = String::new();
    for e in walkdir::WalkDir::new(crate::root().join("tests/integration/snapshots"))
        .into_iter()
        .flatten()
    {
        if e.path().to_string_lossy().contains("@err__") {
            shown.push_str(&std::fs::read_to_string(e.path()).unwrap_or_default());
        }
    }
    let missing: Vec<&&str> = codes
        .iter()
        .filter(|c| !shown.contains(&format!("[{c}]")))
        .collect();
    assert!(
        missing.is_empty(),
        "block errors without an err/ fixture: {missing:?}"
    );
}

/// Codes no fixture shows, each with why: shown by a command-line test
/// instead (what a fixture cannot do: another command, a folder, a file
/// written), not reachable from any input, or not yet shown. A code leaves
/// this list when a fixture shows it; a new code may not join it.
const CODES_WITHOUT_A_FIXTURE: &[(&str, &str)] = &[
    (
        "E0317",
        "unreachable: the sub search's end of file, reported as E0314",
    ),
    ("E0404", "not yet shown: a value the writer cannot print"),
    (
        "E0405",
        "unreachable by a fixture: the file changed while read (file_index tests)",
    ),
    (
        "E0507",
        "not yet shown: a feature a target's lowering does not support",
    ),
    ("E0700", "command line: an internal failure (hostile.rs)"),
    (
        "E0702",
        "command line: -o names the input (hostile.rs, view.rs)",
    ),
    (
        "E0802",
        "command line: check of a folder without programs (check.rs)",
    ),
    ("E0803", "command line: a binary input (cli.rs)"),
    (
        "E0804",
        "command line: check --library of an unclosed block (check.rs)",
    ),
    (
        "E1160",
        "not yet shown: compensation geometry guard (zero-radius arc)",
    ),
    (
        "E1161",
        "not yet shown: compensation geometry guard (radius mismatch)",
    ),
    (
        "E1162",
        "not yet shown: compensation geometry guard (radius too small)",
    ),
    (
        "E1163",
        "not yet shown: compensation geometry guard (arc to its start)",
    ),
    (
        "E1164",
        "not yet shown: compensation geometry guard (inconsistent)",
    ),
    ("E1313", "not yet shown: lathe contour geometry guard"),
    ("E1316", "not yet shown: lathe contour geometry guard"),
    ("E1317", "not yet shown: lathe contour geometry guard"),
    ("E1318", "not yet shown: lathe contour geometry guard"),
    ("E1319", "command line: lathe cycle bounds (lathe.rs)"),
    ("E1320", "command line: lathe cycle bounds (lathe.rs)"),
    (
        "E1322",
        "command line: the contour bound set small (hostile.rs)",
    ),
];

/// Every error code defined (a `"Ennnn"` in `src/diag`) is shown by a
/// fixture's snapshot (`[Ennnn]` in its diagnostics: a program under
/// `fixtures/`, or a broken profile under `fixtures/profile/`), apart from the listed
/// ones; a listed one shown by a command-line test is named by it.
#[test]
fn every_error_code_has_a_fixture() {
    let mut codes = std::collections::BTreeSet::new();
    for e in walkdir::WalkDir::new(crate::root().join("src/diag"))
        .into_iter()
        .flatten()
    {
        let text = std::fs::read_to_string(e.path()).unwrap_or_default();
        for t in text.split('"') {
            if t.len() == 5 && t.starts_with('E') && t[1..].bytes().all(|b| b.is_ascii_digit()) {
                codes.insert(t.to_string());
            }
        }
    }
    assert!(codes.len() > 150, "codes found: {}", codes.len());
    let mut shown = String::new();
    for e in std::fs::read_dir(crate::root().join("tests/integration/snapshots"))
        .expect("snapshots")
        .flatten()
    {
        if e.file_name().to_string_lossy().ends_with(".snap") {
            shown.push_str(&std::fs::read_to_string(e.path()).unwrap_or_default());
        }
    }
    let mut tests = String::new();
    for e in std::fs::read_dir(crate::root().join("tests/integration"))
        .expect("tests")
        .flatten()
    {
        if e.file_name() != "fixtures.rs" {
            tests.push_str(&std::fs::read_to_string(e.path()).unwrap_or_default());
        }
    }
    let listed = |c: &str| CODES_WITHOUT_A_FIXTURE.iter().find(|(l, _)| *l == c);
    let mut missing = Vec::new();
    let mut listed_but_shown = Vec::new();
    let mut cli_not_named = Vec::new();
    for c in &codes {
        let by_fixture = shown.contains(&format!("[{c}]"));
        match (by_fixture, listed(c)) {
            (false, None) => missing.push(c.clone()),
            (true, Some(_)) => listed_but_shown.push(c.clone()),
            (false, Some((_, why)))
                if why.starts_with("command line") && !tests.contains(c.as_str()) =>
            {
                cli_not_named.push(c.clone())
            }
            _ => {}
        }
    }
    let stale: Vec<&str> = CODES_WITHOUT_A_FIXTURE
        .iter()
        .map(|(c, _)| *c)
        .filter(|c| !codes.contains(*c))
        .collect();
    assert!(missing.is_empty(), "codes without a fixture: {missing:?}");
    assert!(
        listed_but_shown.is_empty(),
        "codes a fixture shows now: take them off CODES_WITHOUT_A_FIXTURE: {listed_but_shown:?}"
    );
    assert!(
        cli_not_named.is_empty(),
        "codes listed as shown by a command-line test that no test names: {cli_not_named:?}"
    );
    assert!(
        stale.is_empty(),
        "listed codes that no longer exist: {stale:?}"
    );
}
