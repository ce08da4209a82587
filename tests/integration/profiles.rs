//! Profiles as files: `targets --show NAME` prints a built-in profile, and
//! `--target FILE` reads one.
//!
//! * Round trip: for every built-in target, its printed file passed back
//!   with `--target FILE` writes byte for byte what `--target NAME` writes,
//!   on every fixture of that target and on the plain ok fixtures.
//! * `fixtures/profile/*.toml` are broken profiles: each is refused with
//!   its own code, snapshotted. Adding a case is adding a file.

use std::path::{Path, PathBuf};

use crate::{root, run};

/// The built-in targets, as `ngcflat targets` lists them.
fn targets() -> Vec<String> {
    let (code, out, _) = run(&root(), &["targets"]);
    assert_eq!(code, 0);
    out.lines()
        .filter(|l| !l.starts_with(' '))
        .filter_map(|l| l.split_whitespace().next())
        .map(str::to_string)
        .collect()
}

fn ngc_files(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = walkdir::WalkDir::new(dir)
        .into_iter()
        .filter_map(Result::ok)
        .map(|e| e.into_path())
        .filter(|p| p.extension().is_some_and(|e| e == "ngc"))
        .filter(|p| !p.components().any(|c| c.as_os_str() == "subs"))
        .collect();
    v.sort();
    v
}

#[test]
fn shown_profiles_read_back_write_the_same() {
    let names = targets();
    assert!(names.len() >= 4, "{names:?}");
    let tmp = crate::tmp();
    for name in names {
        let (code, file, err) = run(&root(), &["targets", "--show", &name]);
        assert_eq!(code, 0, "{name}: {err}");
        let path = tmp.path().join(format!("{name}.toml"));
        std::fs::write(&path, &file).unwrap();
        let path = path.to_string_lossy().into_owned();
        let mut programs = ngc_files(&root().join("fixtures/target").join(&name));
        programs.extend(ngc_files(&root().join("fixtures/ok/arcs")));
        programs.push(root().join("fixtures/ok/basics.ngc"));
        for p in programs {
            let dir = p.parent().unwrap();
            let mut args = crate::fixtures::read_args(&p);
            // The fixture's own target (if any) is replaced.
            if let Some(i) = args.iter().position(|a| a == "--target") {
                args.drain(i..i + 2);
            }
            let file_name = p.file_name().unwrap().to_string_lossy().into_owned();
            let with = |target: &str| {
                let mut a: Vec<&str> = vec!["--target", target];
                if !args.iter().any(|a| a == "--zero-start") {
                    a.push("--zero-start");
                }
                a.extend(args.iter().map(String::as_str));
                a.push(&file_name);
                run(dir, &a)
            };
            let by_name = with(&name);
            let by_file = with(&path);
            assert_eq!(by_name, by_file, "{name}: {}", p.display());
        }
    }
}

#[test]
fn broken_profiles_are_refused_with_their_code() {
    insta::glob!("../../fixtures/profile", "*.toml", |path| {
        let dir = path.parent().unwrap();
        let file = path.file_name().unwrap().to_string_lossy().into_owned();
        let tmp = crate::tmp();
        crate::put(tmp.path(), "p.ngc", "G0 X1\nM2\n");
        let ngc = tmp.path().join("p.ngc").to_string_lossy().into_owned();
        let target = format!("./{file}");
        let (code, out, err) = run(dir, &["--target", &target, &ngc]);
        assert_eq!(code, 2, "{file} should be refused: {out}{err}");
        assert!(out.is_empty());
        assert!(err.contains("[E100"), "{file}: {err}");
        let (check_code, _, check_err) = run(dir, &["check", "--target", &target, &ngc]);
        assert_eq!(check_code, 2, "{file}: check: {check_err}");
        insta::assert_snapshot!(err);
    });
}

#[test]
fn an_unknown_built_in_is_refused() {
    let (code, out, err) = run(&root(), &["targets", "--show", "nosuch"]);
    assert_eq!(code, 2);
    assert!(out.is_empty());
    assert!(err.contains("unknown target 'nosuch'"), "{err}");
}

#[test]
fn an_unreadable_profile_file_is_refused() {
    let tmp = crate::tmp();
    crate::put(tmp.path(), "p.ngc", "G0 X1\nM2\n");
    let (code, out, err) = run(tmp.path(), &["--target", "./nosuch.toml", "p.ngc"]);
    assert_eq!(code, 2);
    assert!(out.is_empty());
    assert!(
        err.contains("[E1009]") && err.contains("./nosuch.toml"),
        "{err}"
    );
}
