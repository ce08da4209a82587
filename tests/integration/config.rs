//! Configuration: INI files as ngcflat reads them, the subroutine search
//! path (order, shadowing, refused names), parameter files and `-D`.

use std::path::Path;
use std::process::{Command, Stdio};

use crate::{bin, ngcflat, outcome, put, run, tmp};

/// A subroutine file `folder/name.ngc` that prints where it was found.
fn sub(dir: &Path, folder: &str, name: &str) {
    put(
        dir,
        &format!("{folder}/{name}.ngc"),
        &format!("o<{name}> sub\n  (print, {name} from {folder})\no<{name}> endsub\n"),
    );
}

/// Like `run`, with extra environment variables.
fn run_env(dir: &Path, args: &[&str], env: &[(&str, &str)]) -> (i32, String, String) {
    let out = Command::new(bin())
        .current_dir(dir)
        .args(args)
        .env_remove("NGCFLAT_SUBROUTINE_PATH")
        .envs(env.iter().copied())
        .stdin(Stdio::null())
        .output()
        .expect("run ngcflat");
    outcome(out)
}

const MISSING: &str = "subroutine o<nosuch> is not defined and no file nosuch.ngc was found";

// ---------------------------------------------------------------- INI

#[test]
fn ini_continuation_relative_folders_and_missing_ones_dropped() {
    let d = tmp();
    let p = d.path();
    sub(p, "conf/a", "s1");
    sub(p, "conf/b", "s2");
    sub(p, "conf/c", "s3");
    put(
        p,
        "conf/m.ini",
        "# comment\n[RS274NGC]\nSUBROUTINE_PATH = a:\\\n    nothere:b:\\\n/no/such/folder:c\n; another\n",
    );
    put(p, "prog/p.ngc", "o<s1> call\no<s2> call\no<s3> call\nM2\n");
    put(p, "prog/missing.ngc", "o<nosuch> call\nM2\n");
    // Relative to the INI's folder, not the working folder.
    let (exit, stdout, stderr) = run(p, &["--ini", "conf/m.ini", "prog/p.ngc"]);
    assert_eq!(exit, 0, "{stderr}");
    assert_eq!(
        stdout,
        "  (print, s1 from conf/a)\n  (print, s2 from conf/b)\n  (print, s3 from conf/c)\nM2\n"
    );
    let (exit, _, stderr) = run(
        p.join("prog").as_path(),
        &["--ini", "../conf/m.ini", "p.ngc"],
    );
    assert_eq!(exit, 0, "{stderr}");
    // Missing folders are not listed as searched.
    let (exit, _, stderr) = run(
        p,
        &[
            "--ini",
            "conf/m.ini",
            "--no-program-dir",
            "prog/missing.ngc",
        ],
    );
    assert_eq!(exit, 1);
    assert!(
        stderr.contains(&format!("{MISSING} in: conf/a, conf/b, conf/c\n")),
        "{stderr}"
    );
}

#[test]
fn ini_tilde_expansion() {
    let d = tmp();
    let p = d.path();
    sub(p, "home/nc", "s1");
    sub(p, "home/pre", "s2");
    put(
        p,
        "conf/m.ini",
        "[DISPLAY]\nPROGRAM_PREFIX = ~/pre\n[RS274NGC]\nSUBROUTINE_PATH = ~/nc\n",
    );
    put(p, "p.ngc", "o<s1> call\no<s2> call\nM2\n");
    let home = p.join("home");
    let (exit, stdout, stderr) = run_env(
        p,
        &["--ini", "conf/m.ini", "p.ngc"],
        &[("HOME", home.to_str().unwrap())],
    );
    assert_eq!(exit, 0, "{stderr}");
    assert!(stdout.contains("s1 from home/nc"), "{stdout}");
    assert!(stdout.contains("s2 from home/pre"), "{stdout}");
}

#[test]
fn subroutine_path_keeps_the_first_ten_existing_folders_as_rs274() {
    // rs274 runs in the folder, so the relative entries stay short.
    let d = tmp();
    let p = d.path();
    for i in 1..=11 {
        std::fs::create_dir_all(p.join(format!("d{i}"))).unwrap();
        put(
            p,
            &format!("d{i}/s{i}.ngc"),
            &format!("o<s{i}> sub\nG1 X{i}\no<s{i}> endsub\nM2\n"),
        );
    }
    let list: Vec<String> = (1..=11).map(|i| format!("d{i}")).collect();
    // A missing entry first: it does not count, so d10 is the tenth folder.
    let ini = format!("[RS274NGC]\nSUBROUTINE_PATH = gone:{}\n", list.join(":"));
    put(p, "eleven.ini", &ini);
    put(p, "p10.ngc", "G1 F100\no<s10> call\nM2\n");
    put(p, "p11.ngc", "G1 F100\no<s11> call\nM2\n");
    let args = |f: &str| {
        vec![
            "--no-program-dir",
            "--message-format",
            "short",
            "--ini",
            "eleven.ini",
            f,
        ]
        .into_iter()
        .map(String::from)
        .collect::<Vec<_>>()
    };
    let (exit, stdout, stderr) = outcome(ngcflat(p, &args("p10.ngc"), None));
    assert_eq!(exit, 0, "{stderr}");
    assert!(stdout.contains("G1 X10"), "{stdout}");
    assert!(
        stderr.contains("entry ./gone does not exist") && stderr.contains("[W0903]"),
        "{stderr}"
    );
    assert!(stderr.contains("ignored: ./d11 [W0902]"), "{stderr}");
    let (exit, _, stderr) = outcome(ngcflat(p, &args("p11.ngc"), None));
    assert_eq!(exit, 1, "{stderr}");
    assert!(stderr.contains("[E0314]"), "{stderr}");
    // check: the same warnings, once.
    let (exit, _, stderr) = run(
        p,
        &[
            "check",
            "--ini",
            "eleven.ini",
            "--message-format",
            "short",
            "p10.ngc",
        ],
    );
    assert_eq!(exit, 0, "{stderr}");
    assert_eq!(stderr.matches("[W0902]").count(), 1, "{stderr}");
    if !crate::oracle::available("subroutine_path_keeps_the_first_ten_existing_folders_as_rs274") {
        return;
    }
    for (prog, ok) in [("p10.ngc", true), ("p11.ngc", false)] {
        let out = Command::new(crate::oracle::RS274)
            .current_dir(p)
            .env("HOME", p)
            .args(["-g", "-i", "eleven.ini", prog])
            .stdin(Stdio::null())
            .output()
            .expect("rs274");
        let text = String::from_utf8_lossy(&out.stdout);
        assert_eq!(
            text.contains("STRAIGHT_FEED(10.0000") || text.contains("STRAIGHT_FEED(11.0000"),
            ok,
            "{prog}: {text}"
        );
    }
}

#[test]
fn ini_program_prefix_first_wizard_root_recursive() {
    let d = tmp();
    let p = d.path();
    sub(p, "conf/pre", "s1");
    sub(p, "conf/a", "s1");
    sub(p, "conf/a", "s2");
    sub(p, "conf/wiz/x/y", "deep");
    sub(p, "other", "s1");
    put(
        p,
        "conf/m.ini",
        "[DISPLAY]\nPROGRAM_PREFIX = pre\n[RS274NGC]\nSUBROUTINE_PATH = a\n[WIZARD]\nWIZARD_ROOT = wiz\n",
    );
    put(p, "p.ngc", "o<s1> call\no<s2> call\no<deep> call\nM2\n");
    put(p, "missing.ngc", "o<nosuch> call\nM2\n");
    let (exit, stdout, stderr) = run(p, &["--ini", "conf/m.ini", "p.ngc"]);
    assert_eq!(exit, 0, "{stderr}");
    assert_eq!(
        stdout,
        "  (print, s1 from conf/pre)\n  (print, s2 from conf/a)\n  (print, deep from conf/wiz/x/y)\nM2\n"
    );
    // The prefix shadows s1.ngc in SUBROUTINE_PATH: W0005 names both.
    assert!(stderr.contains("[W0005]"), "{stderr}");
    assert!(
        stderr.contains("s1.ngc in conf/pre hides the one in conf/a"),
        "{stderr}"
    );
    // --program-prefix replaces the INI's PROGRAM_PREFIX.
    let (exit, stdout, stderr) = run(
        p,
        &["--ini", "conf/m.ini", "--program-prefix", "other", "p.ngc"],
    );
    assert_eq!(exit, 0, "{stderr}");
    assert!(stdout.starts_with("  (print, s1 from other)\n"), "{stdout}");
    let (_, _, stderr) = run(
        p,
        &[
            "--ini",
            "conf/m.ini",
            "--program-prefix",
            "other",
            "--no-program-dir",
            "missing.ngc",
        ],
    );
    assert!(
        stderr.contains(&format!("{MISSING} in: other, conf/a, conf/wiz\n")),
        "{stderr}"
    );
}

#[test]
fn ini_parameter_file() {
    let d = tmp();
    let p = d.path();
    put(p, "conf/m.var", "3000 7\n3001 8\n");
    put(p, "other.var", "3000 1\n");
    put(p, "conf/m.ini", "[RS274NGC]\nPARAMETER_FILE = m.var\n");
    put(
        p,
        "conf/gone.ini",
        "[RS274NGC]\nPARAMETER_FILE = gone.var\n",
    );
    put(p, "p.ngc", "G0 X#3000 Y#3001\nM2\n");
    // (args, stdout)
    let cases: &[(&[&str], &str)] = &[
        (&["--ini", "conf/m.ini", "p.ngc"], "G0 X7 Y8\nM2\n"),
        // --var-file replaces PARAMETER_FILE.
        (
            &["--ini", "conf/m.ini", "--var-file", "other.var", "p.ngc"],
            "G0 X1 Y0\nM2\n",
        ),
        // -D overrides the parameter file.
        (
            &["--ini", "conf/m.ini", "-D", "3001=2", "p.ngc"],
            "G0 X7 Y2\nM2\n",
        ),
        // A PARAMETER_FILE that does not exist is not an error.
        (&["--ini", "conf/gone.ini", "p.ngc"], "G0 X0 Y0\nM2\n"),
    ];
    for (args, want) in cases {
        let (exit, stdout, stderr) = run(p, args);
        assert_eq!(exit, 0, "{args:?}\n{stderr}");
        assert_eq!(stdout, *want, "{args:?}");
    }
}

#[test]
fn ini_rs274ngc_flags() {
    let d = tmp();
    let p = d.path();
    let fanuc = "M98 P100\nM2\nO100\n  G0 X1\nM99\n";
    let nargs = "o<c> sub\n  G0 X#<n_args>\no<c> endsub\no<c> call [1] [2]\nM2\n";
    // (INI text, program, exit code, stdout or error code)
    let cases: &[(&str, &str, i32, &str)] = &[
        ("", fanuc, 0, "  G0 X1\nM2\n"),
        (
            "[RS274NGC]\nDISABLE_FANUC_STYLE_SUB = 0\n",
            fanuc,
            0,
            "  G0 X1\nM2\n",
        ),
        (
            "[RS274NGC]\nDISABLE_FANUC_STYLE_SUB = 1\n",
            fanuc,
            1,
            "[E0325]",
        ),
        (
            "[OTHER]\nDISABLE_FANUC_STYLE_SUB = 1\n",
            fanuc,
            0,
            "  G0 X1\nM2\n",
        ),
        ("[RS274NGC]\nOWORD_NARGS = 1\n", nargs, 0, "  G0 X2\nM2\n"),
        ("[RS274NGC]\nOWORD_NARGS = 0\n", nargs, 1, "[E0203]"),
        ("", nargs, 1, "[E0203]"),
    ];
    for (ini, program, want_exit, want) in cases {
        put(p, "m.ini", ini);
        put(p, "p.ngc", program);
        let (exit, stdout, stderr) =
            run(p, &["--ini", "m.ini", "--message-format", "short", "p.ngc"]);
        assert_eq!(exit, *want_exit, "{ini:?}\n{stderr}");
        if *want_exit == 0 {
            assert_eq!(stdout, *want, "{ini:?}");
        } else {
            assert!(stdout.is_empty());
            assert!(stderr.contains(want), "{ini:?}: want {want}\n{stderr}");
        }
    }
}

#[test]
fn ini_values() {
    let d = tmp();
    let p = d.path();
    put(
        p,
        "m.ini",
        "[MYSEC]\nDEPTH = 2.5\nCOUNT = 3\nMixed = 4\nWORD = abc\nLONG = 1\\\n5\n",
    );
    // (expression, stdout or error code)
    let cases: &[(&str, &str)] = &[
        ("#<_ini[mysec]depth>", "G0 X2.5\nM2\n"),
        ("#<_ini[MYSEC]COUNT>", "G0 X3\nM2\n"),
        ("#<_ini[MySec]Count>", "G0 X3\nM2\n"),
        ("#<_ini[mysec]long>", "G0 X15\nM2\n"),
        ("[EXISTS[#<_ini[mysec]nothere>]]", "G0 X0\nM2\n"),
        ("[EXISTS[#<_ini[mysec]depth>]]", "G0 X1\nM2\n"),
        // Keys are upper-cased before lookup, as in LinuxCNC.
        ("#<_ini[mysec]mixed>", "[E0203]"),
        ("#<_ini[mysec]nothere>", "[E0203]"),
        ("#<_ini[mysec]word>", "[E0203]"),
    ];
    for (expr, want) in cases {
        put(p, "p.ngc", &format!("G0 X{expr}\nM2\n"));
        let (exit, stdout, stderr) =
            run(p, &["--ini", "m.ini", "--message-format", "short", "p.ngc"]);
        if want.starts_with('[') {
            assert_eq!(exit, 1, "{expr}: {stdout}");
            assert!(stderr.contains(want), "{expr}: {stderr}");
        } else {
            assert_eq!(exit, 0, "{expr}: {stderr}");
            assert_eq!(stdout, *want, "{expr}");
        }
    }
    // Without --ini an _ini value is undefined.
    put(p, "p.ngc", "G0 X#<_ini[mysec]depth>\nM2\n");
    let (exit, _, stderr) = run(p, &["p.ngc"]);
    assert_eq!(exit, 1, "{stderr}");
}

#[test]
fn ini_that_cannot_be_read_is_exit_2() {
    let d = tmp();
    put(d.path(), "p.ngc", "M2\n");
    let (exit, stdout, stderr) = run(d.path(), &["--ini", "nope.ini", "p.ngc"]);
    assert_eq!(exit, 2, "{stderr}");
    assert!(stdout.is_empty());
    assert!(stderr.contains("nope.ini"), "{stderr}");
}

// ---------------------------------------------------------------- search path

/// Every source of folders, in the documented order.
fn search_tree() -> tempfile::TempDir {
    let d = tmp();
    let p = d.path();
    for f in [
        "pre",
        "i1",
        "i2",
        "e1",
        "e2",
        "conf/a",
        "conf/wiz/deep",
        "prog",
    ] {
        std::fs::create_dir_all(p.join(f)).unwrap();
    }
    put(
        p,
        "conf/m.ini",
        "[RS274NGC]\nSUBROUTINE_PATH = a\n[WIZARD]\nWIZARD_ROOT = wiz\n",
    );
    put(p, "prog/p.ngc", "o<s> call\nM2\n");
    put(p, "prog/missing.ngc", "o<nosuch> call\nM2\n");
    d
}

const SEARCH_ARGS: &[&str] = &[
    "--program-prefix",
    "pre",
    "-I",
    "i1",
    "--subroutine-path",
    "i2",
    "--ini",
    "conf/m.ini",
];
const SEARCH_ENV: &[(&str, &str)] = &[("NGCFLAT_SUBROUTINE_PATH", "e1::e2:")];

#[test]
fn missing_sub_names_every_folder_in_search_order() {
    let d = search_tree();
    let mut args = SEARCH_ARGS.to_vec();
    args.extend(["--message-format", "short", "prog/missing.ngc"]);
    let (exit, stdout, stderr) = run_env(d.path(), &args, SEARCH_ENV);
    assert_eq!(exit, 1);
    assert!(stdout.is_empty());
    assert_eq!(
        stderr,
        format!(
            "prog/missing.ngc:1:1: error: {MISSING} in: pre, i1, i2, e1, e2, conf/a, conf/wiz, prog [E0314]\n"
        )
    );
    // --no-program-dir drops the last one.
    args.insert(0, "--no-program-dir");
    let (_, _, stderr) = run_env(d.path(), &args, SEARCH_ENV);
    assert!(
        stderr.contains(&format!(
            "{MISSING} in: pre, i1, i2, e1, e2, conf/a, conf/wiz [E0314]"
        )),
        "{stderr}"
    );
}

#[test]
fn first_folder_wins_and_shadowing_warns() {
    // Folders in search order; s.ngc is put in folders[k..].
    let folders = [
        "pre",
        "i1",
        "i2",
        "e1",
        "e2",
        "conf/a",
        "conf/wiz/deep",
        "prog",
    ];
    for k in 0..folders.len() {
        let d = search_tree();
        for f in &folders[k..] {
            put(
                d.path(),
                &format!("{f}/s.ngc"),
                &format!("o<s> sub\n  (print, s from {f})\no<s> endsub\n"),
            );
        }
        let mut args = SEARCH_ARGS.to_vec();
        args.extend(["--message-format", "short", "prog/p.ngc"]);
        let (exit, stdout, stderr) = run_env(d.path(), &args, SEARCH_ENV);
        assert_eq!(exit, 0, "{k}: {stderr}");
        assert_eq!(
            stdout,
            format!("  (print, s from {})\nM2\n", folders[k]),
            "{k}"
        );
        if k + 1 < folders.len() {
            let next = folders[k + 1];
            assert_eq!(
                stderr,
                format!(
                    "ngcflat: warning: s.ngc in {} hides the one in {} [W0005]\n",
                    folders[k], next
                ),
                "{k}"
            );
        } else {
            assert!(stderr.is_empty(), "{k}: {stderr}");
        }
    }
}

#[test]
fn environment_path() {
    let d = tmp();
    let p = d.path();
    sub(p, "e1", "s1");
    sub(p, "home/e2", "s2");
    put(p, "p.ngc", "o<s1> call\no<s2> call\nM2\n");
    let home = p.join("home");
    let (exit, stdout, stderr) = run_env(
        p,
        &["p.ngc"],
        &[
            ("NGCFLAT_SUBROUTINE_PATH", ":e1::~/e2"),
            ("HOME", home.to_str().unwrap()),
        ],
    );
    assert_eq!(exit, 0, "{stderr}");
    assert_eq!(
        stdout,
        "  (print, s1 from e1)\n  (print, s2 from home/e2)\nM2\n"
    );
    // Without the variable neither is found.
    let (exit, _, _) = run(p, &["p.ngc"]);
    assert_eq!(exit, 1);
}

#[test]
fn dash_i_is_repeatable() {
    let d = tmp();
    let p = d.path();
    sub(p, "x", "s1");
    sub(p, "y", "s2");
    put(p, "prog/p.ngc", "o<s1> call\no<s2> call\nM2\n");
    // (args, exit code)
    let cases: &[(&[&str], i32)] = &[
        (&["-I", "x", "-I", "y", "prog/p.ngc"], 0),
        (&["-I", "y", "--subroutine-path", "x", "prog/p.ngc"], 0),
        (&["-I", "x", "prog/p.ngc"], 1),
        (&["-I", "y", "prog/p.ngc"], 1),
    ];
    for (args, want) in cases {
        let (exit, stdout, stderr) = run(p, args);
        assert_eq!(exit, *want, "{args:?}\n{stderr}");
        if *want == 0 {
            assert_eq!(stdout, "  (print, s1 from x)\n  (print, s2 from y)\nM2\n");
        }
    }
}

#[test]
fn program_folder_searched_last() {
    let d = tmp();
    let p = d.path();
    sub(p, "prog", "s1");
    sub(p, "lib", "s2");
    sub(p, "prog", "s2");
    put(p, "prog/p.ngc", "o<s1> call\nM2\n");
    put(p, "prog/q.ngc", "o<s2> call\nM2\n");
    // (args, exit code, stdout, stderr fragment)
    let cases: &[(&[&str], i32, &str, &str)] = &[
        (&["prog/p.ngc"], 0, "  (print, s1 from prog)\nM2\n", ""),
        (&["--no-program-dir", "prog/p.ngc"], 1, "", "[E0314]"),
        (
            &["-I", "lib", "prog/q.ngc"],
            0,
            "  (print, s2 from lib)\nM2\n",
            "s2.ngc in lib hides the one in prog [W0005]",
        ),
        (
            &["-I", "lib", "--no-program-dir", "prog/q.ngc"],
            0,
            "  (print, s2 from lib)\nM2\n",
            "",
        ),
        (
            &["check", "prog/p.ngc"],
            0,
            "",
            "1 files, 0 errors, 0 warnings",
        ),
        (
            &["check", "--no-program-dir", "prog/p.ngc"],
            1,
            "",
            "[E0314]",
        ),
    ];
    for (args, want_exit, want_out, want_err) in cases {
        let mut a = vec!["--message-format", "short"];
        if args[0] == "check" {
            a.insert(0, "check");
            a.extend_from_slice(&args[1..]);
        } else {
            a.extend_from_slice(args);
        }
        let (exit, stdout, stderr) = run(p, &a);
        assert_eq!(exit, *want_exit, "{args:?}\n{stderr}");
        assert_eq!(stdout, *want_out, "{args:?}");
        assert!(
            stderr.contains(want_err),
            "{args:?}: want {want_err}\n{stderr}"
        );
        if want_err.is_empty() {
            assert!(stderr.is_empty(), "{args:?}: {stderr}");
        }
    }
    // A program on stdin has no folder of its own.
    let out = ngcflat(
        p.join("prog").as_path(),
        &["--message-format".into(), "short".into()],
        Some(b"o<s1> call\nM2\n"),
    );
    assert_eq!(out.status.code(), Some(1));
}

// ---------------------------------------------------------------- names

#[test]
fn refused_subroutine_names() {
    let d = tmp();
    let p = d.path();
    // Files a refused name would reach if it were used as a path.
    put(p, "x.ngc", "o<x> sub\n  (print, OUTSIDE)\no<x> endsub\n");
    put(
        p,
        "lib/a/x.ngc",
        "o<x> sub\n  (print, OUTSIDE)\no<x> endsub\n",
    );
    let abs = p.join("x").display().to_string();
    let names: Vec<&str> = vec![
        "../x",
        "a/../../x",
        "./x",
        "a/./x",
        "a//x",
        &abs,
        "~/x",
        "a$b",
        "a\\x",
        "a*",
        "x?",
        "a:b",
        ".",
        "..",
        // Only letters, digits, '-' and '_' (LinuxCNC's rule): no folder
        // part, even one that exists inside a search folder.
        "a/x",
        "x.v2",
    ];
    for name in names {
        put(p, "lib/p.ngc", &format!("o<{name}> call\nM2\n"));
        for mode in [&["-I", "lib"][..], &["check", "-I", "lib"][..]] {
            let mut args = mode.to_vec();
            args.extend(["--message-format", "short", "lib/p.ngc"]);
            let (exit, stdout, stderr) = run(p, &args);
            assert_eq!(exit, 1, "{name}: {stderr}");
            assert!(stdout.is_empty(), "{name}: {stdout}");
            // Names are case-insensitive: the message shows them lower-cased.
            let want = format!(
                "subroutine name '{}' could leave the search path",
                name.to_lowercase()
            );
            assert!(
                stderr.contains(&want) && stderr.contains("[E0502]"),
                "{name}: {stderr}"
            );
            assert!(!stderr.contains("OUTSIDE"), "{name}: {stderr}");
        }
    }
    // Plain names with '_' and '-' are allowed.
    put(
        p,
        "lib/ok_name-1-v2.ngc",
        "o<ok_name-1-v2> sub\n  G0 X1\no<ok_name-1-v2> endsub\n",
    );
    put(p, "lib/p.ngc", "o<OK_Name-1-v2> call\nM2\n");
    let (exit, stdout, stderr) = run(p, &["-I", "lib", "lib/p.ngc"]);
    assert_eq!(exit, 0, "{stderr}");
    assert_eq!(stdout, "  G0 X1\nM2\n");
}

// ---------------------------------------------------------------- var file, -D

#[test]
fn var_file() {
    let d = tmp();
    let p = d.path();
    put(p, "p.ngc", "G0 X#5063 Y#5220\nM2\n");
    // (var file text, extra args, exit code, stdout or stderr fragment)
    let cases: &[(&str, &[&str], i32, &str)] = &[
        ("5063 1.5\n5220 2\n", &[], 0, "G0 X1.5 Y2\nM2\n"),
        (
            "\n5063 1.5 trailing\n\n5220 2\n",
            &[],
            0,
            "G0 X1.5 Y2\nM2\n",
        ),
        ("5063 1.5\n5220 2\n", &["-D", "5063=9"], 0, "G0 X9 Y2\nM2\n"),
        (
            "5063 1.5\n5220 2\n",
            &["-D", "5220=-3", "-D", "5063=4"],
            0,
            "G0 X4 Y-3\nM2\n",
        ),
        (
            "5220 2\n5063 1.5\n",
            &[],
            2,
            "parameter file is not in ascending order at #5063",
        ),
        (
            "5063 1\n5063 2\n",
            &[],
            2,
            "parameter file is not in ascending order at #5063",
        ),
        (
            "5063\n",
            &[],
            2,
            "parameter file line '5063' is not 'number value'",
        ),
        (
            "5063 abc\n",
            &[],
            2,
            "parameter file line '5063 abc' is not 'number value'",
        ),
        (
            "5063 1.5\n5220 2\n",
            &["-D", "bad"],
            2,
            "-D 'bad' is not PARAM=VALUE",
        ),
    ];
    for (var, extra, want_exit, want) in cases {
        put(p, "m.var", var);
        let mut args = vec!["--var-file", "m.var"];
        args.extend_from_slice(extra);
        args.push("p.ngc");
        let (exit, stdout, stderr) = run(p, &args);
        assert_eq!(exit, *want_exit, "{var:?} {extra:?}\n{stderr}");
        if *want_exit == 0 {
            assert_eq!(stdout, *want, "{var:?} {extra:?}");
        } else {
            assert!(stdout.is_empty());
            assert!(stderr.contains(want), "{var:?}: want {want}\n{stderr}");
        }
    }
    let (exit, _, stderr) = run(p, &["--var-file", "nope.var", "p.ngc"]);
    assert_eq!(exit, 2);
    assert!(stderr.contains("nope.var"), "{stderr}");
}

#[test]
fn define_forms() {
    let d = tmp();
    let p = d.path();
    // (program, -D arguments, stdout)
    let cases: &[(&str, &[&str], &str)] = &[
        ("G0 X#5063\nM2\n", &["5063=-1.25"], "G0 X-1.25\nM2\n"),
        ("G0 X#5063\nM2\n", &["#5063=-1.25"], "G0 X-1.25\nM2\n"),
        ("G0 X#5063\nM2\n", &["5063=1", "5063=2"], "G0 X2\nM2\n"),
        ("G0 X#100\nM2\n", &[" 100 = 3 "], "G0 X3\nM2\n"),
        ("G0 X#<depth>\nM2\n", &["depth=3"], "G0 X3\nM2\n"),
        ("G0 X#<depth>\nM2\n", &["Depth=3"], "G0 X3\nM2\n"),
        ("G0 X#<depth>\nM2\n", &["#<depth>=3"], "G0 X3\nM2\n"),
        ("G0 X#<depth>\nM2\n", &["<DEPTH>=3"], "G0 X3\nM2\n"),
        ("G0 X#<_depth>\nM2\n", &["_depth=4"], "G0 X4\nM2\n"),
        // A global is visible inside a subroutine.
        (
            "o<s> sub\n  G0 X#<_g>\no<s> endsub\no<s> call\nM2\n",
            &["_g=5"],
            "  G0 X5\nM2\n",
        ),
        // The program's own assignment wins over -D.
        (
            "#<depth>=1\nG0 X#<depth>\nM2\n",
            &["depth=3"],
            "G0 X1\nM2\n",
        ),
        ("G0 X#1\nM2\n", &["1=1e3"], "G0 X1000\nM2\n"),
    ];
    for (program, defs, want) in cases {
        put(p, "p.ngc", program);
        let mut args = Vec::new();
        for def in *defs {
            args.extend(["-D", def]);
        }
        args.push("p.ngc");
        let (exit, stdout, stderr) = run(p, &args);
        assert_eq!(exit, 0, "{defs:?}\n{stderr}");
        assert_eq!(stdout, *want, "{defs:?}");
    }
}

#[test]
fn define_bad_forms_are_usage_errors() {
    let d = tmp();
    let p = d.path();
    put(p, "p.ngc", "G0 X1\nM2\n");
    // (-D argument, message)
    let not_param = "is not PARAM=VALUE";
    let range = "is out of range";
    let cases: &[(&str, &str)] = &[
        ("nothing", not_param),
        ("=3", not_param),
        ("a=", not_param),
        ("a=b", not_param),
        ("a=inf", not_param),
        ("a=NaN", not_param),
        ("5063=1e999", not_param),
        (" = 1", not_param),
        ("<>=1", not_param),
        ("0=1", range),
        ("5602=1", range),
        ("99999999999999999999=1", not_param),
    ];
    for (def, message) in cases {
        for mode in [&[][..], &["check"][..]] {
            let mut args = mode.to_vec();
            args.extend(["-D", def, "p.ngc"]);
            let (exit, stdout, stderr) = run(p, &args);
            assert_eq!(exit, 2, "{def:?} {mode:?}\n{stderr}");
            assert!(stdout.is_empty());
            assert!(stderr.contains(message), "{def:?}: {stderr}");
            if *message == not_param {
                assert!(stderr.contains(&format!("-D '{def}'")), "{def:?}: {stderr}");
            }
        }
    }
}

/// A var file entry for #0 is out of range; the error says it is "not in
/// ascending order at #0".
// BUG: see report
#[test]
fn var_file_parameter_zero_is_out_of_range() {
    let d = tmp();
    put(d.path(), "p.ngc", "G0 X1\nM2\n");
    put(d.path(), "m.var", "0 1\n");
    let (exit, _, stderr) = run(d.path(), &["--var-file", "m.var", "p.ngc"]);
    assert_eq!(exit, 2);
    assert!(stderr.contains("parameter #0 is out of range"), "{stderr}");
}

/// `-D 1.5=2` is taken as the named parameter `#<1.5>`; a number that is
/// not an integer should be refused like `-D nothing`, as `#1.5=2` is in
/// a program (E0008).
// BUG: see report
#[test]
fn define_non_integer_number_is_refused() {
    let d = tmp();
    put(d.path(), "p.ngc", "G0 X1\nM2\n");
    let (exit, _, stderr) = run(d.path(), &["-D", "1.5=2", "p.ngc"]);
    assert_eq!(exit, 2, "{stderr}");
}

/// Setup errors (bad -D, bad INI, bad var file) are diagnostics too: they
/// carry their code ("Stable code shown with every diagnostic", ErrorKind)
/// and with `--message-format json` a CI parser must be able to read them.
// BUG: see report
#[test]
fn setup_errors_follow_message_format() {
    let d = tmp();
    put(d.path(), "p.ngc", "G0 X1\nM2\n");
    // (format, expected start of stderr)
    let cases: &[(&str, &str)] = &[
        ("human", "error[E0505]: -D 'bad' is not PARAM=VALUE"),
        (
            "json",
            "{\"type\":\"diagnostic\",\"severity\":\"error\",\"code\":\"E0505\"",
        ),
        ("short", "ngcflat: error: -D 'bad' is not PARAM=VALUE"),
        ("github", "::error title=E0505::"),
    ];
    for (format, want) in cases {
        for mode in [&[][..], &["check"][..]] {
            let mut args = mode.to_vec();
            args.extend(["--message-format", format, "-D", "bad", "p.ngc"]);
            let (exit, _, stderr) = run(d.path(), &args);
            assert_eq!(exit, 2);
            assert!(stderr.starts_with(want), "{format} {mode:?}: {stderr}");
        }
    }
}
