//! Warn-only O-words (`--oword-warn-only`, `[RS274NGC]OWORD_WARNONLY`, bit
//! 0x20 of `FEATURES`): each of LinuxCNC's O-word errors becomes a warning
//! and its line is skipped. rs274 2.9 itself loops for ever or crashes on
//! several of these, so the output is checked against rs274 running the
//! program with the warned lines removed, without the switch.

use std::path::{Path, PathBuf};

use crate::fixtures::read_args;
use crate::{ngcflat, oracle, outcome, root, run};

fn warn_only_fixtures() -> Vec<PathBuf> {
    let dir = root().join("fixtures/deviation/oword-warn-only");
    let mut v: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("fixture folder")
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|e| e == "ngc"))
        .collect();
    v.sort();
    assert!(v.len() >= 9, "the nine O-word errors have fixtures");
    v
}

/// Runs a fixture with its arguments plus `extra`.
fn flatten(path: &Path, with_args: bool, extra: &[&str]) -> (i32, String, String) {
    let dir = path.parent().expect("dir");
    let mut args: Vec<String> = if with_args {
        read_args(path)
    } else {
        Vec::new()
    };
    args.extend(extra.iter().map(|s| s.to_string()));
    args.push(path.file_name().unwrap().to_string_lossy().into_owned());
    outcome(ngcflat(dir, &args, None))
}

/// Line numbers (1-based) of the W0900 warnings in `short` diagnostics.
fn skipped_lines(name: &str, stderr: &str) -> Vec<usize> {
    let mut v: Vec<usize> = stderr
        .lines()
        .filter(|l| l.starts_with(&format!("{name}:")) && l.contains("[W0900]"))
        .filter_map(|l| l.split(':').nth(1)?.parse().ok())
        .collect();
    v.sort();
    v.dedup();
    v
}

#[test]
fn each_case_is_an_error_without_the_switch() {
    for f in warn_only_fixtures() {
        let (code, stdout, stderr) = flatten(&f, false, &["--zero-start"]);
        assert_eq!(
            code,
            1,
            "{}: an error without the switch\n{stderr}",
            f.display()
        );
        assert!(stdout.is_empty());
        assert!(
            ["E0305", "E0306", "E0307", "E0308"]
                .iter()
                .any(|c| stderr.contains(&format!("[{c}]"))),
            "{}: {stderr}",
            f.display()
        );
    }
}

#[test]
fn skipping_matches_rs274_without_the_warned_lines() {
    if !oracle::available("skipping_matches_rs274_without_the_warned_lines") {
        return;
    }
    for f in warn_only_fixtures() {
        let name = f.file_name().unwrap().to_string_lossy().into_owned();
        let (code, stdout, stderr) =
            flatten(&f, true, &["--zero-start", "--message-format", "short"]);
        assert_eq!(code, 0, "{name}: flattens with the switch\n{stderr}");
        let skipped = skipped_lines(&name, &stderr);
        assert!(!skipped.is_empty(), "{name}: warns W0900\n{stderr}");
        let text = std::fs::read_to_string(&f).expect("read");
        let without: String = text
            .lines()
            .enumerate()
            .filter(|(i, _)| !skipped.contains(&(i + 1)))
            .map(|(_, l)| format!("{l}\n"))
            .collect();
        let a = oracle::run(without.as_bytes(), "", None);
        assert!(
            a.ok,
            "{name}: rs274 runs it without lines {skipped:?}: {}",
            a.stderr
        );
        let b = oracle::run(stdout.as_bytes(), "", None);
        assert!(b.ok, "{name}: rs274 runs the output: {}", b.stderr);
        if let Err(e) = oracle::compare(&a.lines, &b.lines, 1e-9) {
            panic!("{name}: {e}");
        }
    }
}

#[test]
fn check_reports_them_as_warnings() {
    let dir = root().join("fixtures/deviation/oword-warn-only");
    let args = ["check", "--oword-warn-only", "--message-format", "short"];
    let mut a: Vec<&str> = args.to_vec();
    a.push("else-undefined-label.ngc");
    let (code, _, stderr) = run(&dir, &a);
    assert_eq!(code, 0, "{stderr}");
    assert!(stderr.contains("[W0900]"), "{stderr}");
    assert!(
        stderr.ends_with("1 files, 0 errors, 2 warnings\n"),
        "{stderr}"
    );
    a.insert(1, "--deny-warnings");
    let (code, _, stderr) = run(&dir, &a);
    assert_eq!(code, 1, "{stderr}");
}

#[test]
fn features_mask_without_bit_0x20_keeps_the_errors() {
    let t = crate::tmp();
    crate::put(t.path(), "f.ini", "[RS274NGC]\nFEATURES = 0x1f\n");
    crate::put(
        t.path(),
        "o.ini",
        "[RS274NGC]\nFEATURES = 32\nOWORD_WARNONLY = no\n",
    );
    crate::put(t.path(), "p.ngc", "o1 endif\nM2\n");
    for ini in ["f.ini", "o.ini"] {
        let (code, _, stderr) = run(t.path(), &["--ini", ini, "p.ngc"]);
        assert_eq!(code, 1, "{ini}: {stderr}");
        assert!(stderr.contains("[E0307]"), "{ini}: {stderr}");
    }
}
