//! Command-line behaviour: exit codes, stdin, atomic -o, closed pipes.

use std::process::{Command, Stdio};

use crate::{bin, ngcflat, tmp};

#[test]
fn exit_codes() {
    let d = tmp();
    std::fs::write(d.path().join("good.ngc"), "G0 X1\nM2\n").unwrap();
    std::fs::write(d.path().join("bad.ngc"), "G0 X[1/0]\nM2\n").unwrap();
    // (args, expected exit code)
    let cases: &[(&[&str], i32)] = &[
        (&["good.ngc"], 0),
        (&["bad.ngc"], 1),
        (&["missing.ngc"], 2),
        (&["--no-such-option", "good.ngc"], 2),
        (&["--version"], 0),
        (&["--help"], 0),
        (&["check", "good.ngc"], 0),
        (&["check", "good.ngc", "bad.ngc"], 1),
    ];
    for (args, want) in cases {
        let args: Vec<String> = args.iter().map(|s| s.to_string()).collect();
        let out = ngcflat(d.path(), &args, None);
        assert_eq!(
            out.status.code(),
            Some(*want),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

#[test]
fn reads_stdin() {
    let d = tmp();
    for args in [vec![], vec!["-".to_string()]] {
        let out = ngcflat(d.path(), &args, Some(b"#1=2\nG1 X[#1*3] F100\nM2\n"));
        assert_eq!(String::from_utf8_lossy(&out.stdout), "G1 X6 F100\nM2\n");
    }
}

#[test]
fn error_writes_nothing_to_stdout() {
    let d = tmp();
    let prog = "o1 repeat [1000]\nG1 X1 F1\no1 endrepeat\nG0 X[1/0]\nM2\n";
    let out = ngcflat(d.path(), &[], Some(prog.as_bytes()));
    assert_eq!(out.status.code(), Some(1));
    assert!(out.stdout.is_empty());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("<stdin>:4:"), "{err}");
}

#[test]
fn output_file_is_atomic() {
    let d = tmp();
    let target = d.path().join("out.ngc");
    std::fs::write(&target, "OLD\n").unwrap();
    std::fs::write(d.path().join("bad.ngc"), "G0 X1\nG0 X[SQRT[-1]]\nM2\n").unwrap();
    std::fs::write(d.path().join("good.ngc"), "G0 X[1+1]\nM2\n").unwrap();
    let out = ngcflat(
        d.path(),
        &["-o".into(), "out.ngc".into(), "bad.ngc".into()],
        None,
    );
    assert_eq!(out.status.code(), Some(1));
    assert_eq!(std::fs::read_to_string(&target).unwrap(), "OLD\n");
    let out = ngcflat(
        d.path(),
        &["-o".into(), "out.ngc".into(), "good.ngc".into()],
        None,
    );
    assert_eq!(out.status.code(), Some(0));
    assert_eq!(std::fs::read_to_string(&target).unwrap(), "G0 X2\nM2\n");
    let leftovers: Vec<_> = std::fs::read_dir(d.path())
        .unwrap()
        .filter_map(Result::ok)
        .filter(|e| e.file_name().to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "temporary files left behind");
}

#[test]
fn closed_pipe_is_success() {
    let prog = "o1 repeat [200000]\nG1 X1 Y2 Z3 F100\no1 endrepeat\nM2\n";
    let d = tmp();
    std::fs::write(d.path().join("big.ngc"), prog).unwrap();
    let mut child = Command::new(bin())
        .current_dir(d.path())
        .arg("big.ngc")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdout = child.stdout.take().unwrap();
    let mut buf = [0u8; 64];
    use std::io::Read;
    let n = stdout.read(&mut buf).unwrap();
    assert!(n > 0);
    drop(stdout);
    let out = child.wait_with_output().unwrap();
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        out.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// A program over the in-memory limit, mixing lines copied as they are,
/// trimmed lines, evaluated lines, loops and subroutine calls.
fn big_mixed_program() -> String {
    let mut s = String::from("G21 G90 G17 F600\n#<_step> = 0.25\n");
    s.push_str("o<pass> sub\n  G1 X[#1 * #<_step>] Y#2\no<pass> endsub\n");
    let mut i = 0u64;
    while s.len() < 8_600_000 {
        match i % 97 {
            0 => s.push_str(&format!("o<pass> call [{}] [{}]\n", i % 13, i % 7)),
            1 => s.push_str(&format!("G1 X[{i} * 0.001] Y{}.5  \n", i % 50)),
            2 => s.push_str(&format!("o{i} repeat [3]\nG0 Z1\no{i} endrepeat\n")),
            3 => s.push_str("G1 X1 Y2 (comment)\n"),
            4 => s.push_str("G0 X0 Y0\nG2 X10 Y0 I5 J0\n\n"),
            5 => s.push_str("N10 G1 X3.25 Y1\r\n"),
            _ => s.push_str(&format!(
                "G1 X{}.{:04} Y-{}.5 Z0.1\n",
                i % 100,
                i % 10_000,
                i % 30
            )),
        }
        i += 1;
    }
    s.push_str("G0 X0 Y0\nM2\n");
    s
}

#[test]
fn stdout_of_a_streamed_file_equals_the_spooled_output() {
    // To stdout, unchanged input is copied from the input file on release;
    // to a file, everything is spooled. Both must be the same bytes.
    let d = tmp();
    std::fs::write(d.path().join("big.ngc"), big_mixed_program()).unwrap();
    let direct = ngcflat(d.path(), &["big.ngc".into()], None);
    assert_eq!(
        direct.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&direct.stderr)
    );
    let (code, _, err) = crate::run(d.path(), &["big.ngc", "-o", "out.ngc"]);
    assert_eq!(code, 0, "{err}");
    let spooled = std::fs::read(d.path().join("out.ngc")).unwrap();
    assert!(spooled.len() > 8_400_000);
    assert!(direct.stdout == spooled, "stdout and -o differ");
    // Through stdin (spilled to a temporary file) as well.
    let input = std::fs::read(d.path().join("big.ngc")).unwrap();
    let piped = ngcflat(d.path(), &["-".into()], Some(&input));
    assert_eq!(piped.status.code(), Some(0));
    assert!(piped.stdout == spooled, "stdin and -o differ");
}

#[test]
fn start_position_forms() {
    let d = tmp();
    std::fs::write(
        d.path().join("part.ngc"),
        "G91 G1 X1 F100\nG90\n(debug, #<_x> #<_z>)\nM2\n",
    )
    .unwrap();
    // Every form gives X 1 and Z 10 (mm) and keeps the file name.
    let forms: &[&[&str]] = &[
        &["--start-position", "X0", "Y0", "Z10", "part.ngc"],
        &["--start-position", "X0,Y0,Z10", "part.ngc"],
        &["--start-position", "X0 Y0 Z10", "part.ngc"],
        &["--start-position=X0,Y0,Z10", "part.ngc"],
        &["part.ngc", "--start-position", "X0", "Y0", "Z10"],
        &[
            "--start-position",
            "x0",
            "z0.3937007874015748in",
            "part.ngc",
        ],
    ];
    for args in forms {
        let (code, out, err) = crate::run(d.path(), args);
        assert_eq!(code, 0, "{args:?}: {err}");
        assert!(out.contains("X1 F100"), "{args:?}: {out}");
        assert!(out.contains("(MSG, 1.000000 10.000000)"), "{args:?}: {out}");
    }
    // A word that is not an axis word is named, with the form that works.
    let (code, _, err) = crate::run(d.path(), &["--start-position", "Q1", "part.ngc"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("E0800") && err.contains("X0,Y0,Z10"), "{err}");
    assert!(!err.contains("-D '"), "{err}");
    // The help shows the form and the unit.
    let (_, help, _) = crate::run(d.path(), &["--help"]);
    assert!(help.contains("--start-position <X0,Y0,Z10>"), "{help}");
    assert!(help.contains("in mm"), "{help}");
}

#[test]
fn unknown_position_error_suggests_a_working_form() {
    let d = tmp();
    std::fs::write(
        d.path().join("p.ngc"),
        "G91 G1 X1 F100\n(debug, #<_x>)\nM2\n",
    )
    .unwrap();
    let (code, _, err) = crate::run(d.path(), &["p.ngc"]);
    assert_eq!(code, 1);
    assert!(err.contains("--start-position X0,Y0,Z0 (mm)"), "{err}");
}

/// A program with three constructs GRBL cannot run, each on its own line.
const THREE_PROBLEMS: &str = "G21 G90\nG0 X1 A5\nM7\nM3 S100\nG33 Z-1 K1\nM2\n";

#[test]
fn check_with_a_target_reports_every_problem_at_its_place() {
    let d = tmp();
    std::fs::write(d.path().join("p.ngc"), THREE_PROBLEMS).unwrap();
    let (code, out, err) = crate::run(
        d.path(),
        &[
            "check",
            "--target",
            "grbl",
            "--message-format",
            "short",
            "p.ngc",
        ],
    );
    assert_eq!(code, 1, "{err}");
    assert!(out.is_empty());
    for at in [
        "p.ngc:2:7: error:",
        "p.ngc:3:1: error:",
        "p.ngc:5:1: error:",
    ] {
        assert!(err.contains(at), "{at} missing:\n{err}");
    }
    assert_eq!(err.matches("[E1000]").count(), 3, "{err}");
    assert!(err.contains("1 files, 3 errors"), "{err}");
    // Flattening stops at the first, and writes nothing.
    let (code, out, err) = crate::run(d.path(), &["--target", "grbl", "p.ngc"]);
    assert_eq!((code, out.as_str()), (1, ""), "{err}");
    assert_eq!(err.matches("error[E1000]").count(), 1, "{err}");
    // Without a target the program is fine.
    let (code, _, err) = crate::run(d.path(), &["check", "p.ngc"]);
    assert_eq!(code, 0, "{err}");
}

#[test]
fn targets_are_listed_and_chosen() {
    let d = tmp();
    for args in [
        &["targets"][..],
        &["--target", "list"][..],
        &["check", "--target", "list", "x"][..],
    ] {
        let (code, out, err) = crate::run(d.path(), args);
        assert_eq!(code, 0, "{args:?}: {err}");
        assert!(
            out.contains("grbl ") && out.contains("79 bytes per line"),
            "{out}"
        );
        assert!(out.contains("linuxcnc "), "{out}");
    }
    std::fs::write(d.path().join("p.ngc"), "G21 G64 P0.01\nG0 X1\nM2\n").unwrap();
    let (code, _, err) = crate::run(d.path(), &["--target", "nosuch", "p.ngc"]);
    assert_eq!(code, 2);
    assert!(err.contains("E1003") && err.contains("nosuch"), "{err}");
    // NGCFLAT_TARGET chooses the target; --target wins over it.
    let env = |args: &[&str]| {
        let out = Command::new(bin())
            .current_dir(d.path())
            .args(args)
            .env("NGCFLAT_TARGET", "grbl")
            .stdin(Stdio::null())
            .output()
            .expect("run");
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    assert_eq!(env(&["p.ngc"]), "G21\nG0 X1\nM2\n");
    assert_eq!(
        env(&["--target", "linuxcnc", "p.ngc"]),
        "G21 G64 P0.01\nG0 X1\nM2\n"
    );
}

#[test]
fn the_linuxcnc_target_is_the_flattened_program_byte_for_byte() {
    let d = tmp();
    let program =
        "%\n(a comment! ~)\nG21 G64 P0.01\n#1=2\nG0 X[#1] A3 (ü)\n/G1 X2 F100\nT1 M6\nG43 H1\n%\n";
    std::fs::write(d.path().join("p.ngc"), program).unwrap();
    let plain = crate::run(d.path(), &["--zero-start", "p.ngc"]);
    let target = crate::run(d.path(), &["--zero-start", "--target", "linuxcnc", "p.ngc"]);
    assert_eq!(plain.0, 0, "{}", plain.2);
    assert_eq!(plain, target);
}

#[test]
fn grbl_output_holds_no_real_time_byte() {
    let d = tmp();
    let program = "G21 (stop! why? ~ \u{e4})\n(MSG, hold! ~)\nG0 X1 ; what?\nM2\n";
    std::fs::write(d.path().join("p.ngc"), program).unwrap();
    let out = ngcflat(
        d.path(),
        &["--target".into(), "grbl".into(), "p.ngc".into()],
        None,
    );
    assert_eq!(out.status.code(), Some(0));
    assert_eq!(String::from_utf8_lossy(&out.stdout), "G21\nG0 X1\nM2\n");
}

/// A binary file is refused as not text, and none of its bytes reach the
/// terminal or log.
#[test]
fn binary_file_is_not_a_program() {
    let d = tmp();
    let mut data = b"\x7fELF\x02\x01\x01\x00\x00\x00\x1b[31m".to_vec();
    data.extend(std::iter::repeat_n(0u8, 64));
    data.extend(b"G0 X1\nM2\n");
    std::fs::write(d.path().join("a.out"), &data).unwrap();
    std::fs::write(d.path().join("b.ngc"), &data).unwrap();
    for args in [&["a.out"][..], &["check", "b.ngc"][..]] {
        let args: Vec<String> = args.iter().map(|s| s.to_string()).collect();
        let out = ngcflat(d.path(), &args, None);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        assert!(out.stdout.is_empty());
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains("E0803") && err.contains("not a text"), "{err}");
        assert!(
            !out.stderr.iter().any(|&b| b == 0 || b == 0x1b || b == 0x7f),
            "{err:?}"
        );
    }
    // Through stdin too.
    let out = ngcflat(d.path(), &[], Some(&data));
    assert_eq!(out.status.code(), Some(2));
}

/// Colours only on a terminal, and not with NO_COLOR or TERM=dumb (run
/// through a pseudo-terminal with `script`).
#[test]
fn no_color_and_dumb_terminal() {
    let d = tmp();
    std::fs::write(d.path().join("bad.ngc"), "G0 X[1/0]\nM2\n").unwrap();
    let probe = Command::new("script").arg("--version").output();
    if !probe.is_ok_and(|o| o.status.success()) {
        eprintln!("SKIPPED: no `script` command for a pseudo-terminal");
        return;
    }
    let on_tty = |env: &[(&str, &str)]| {
        let mut cmd = Command::new("script");
        cmd.current_dir(d.path())
            .args(["-qec"])
            .arg(format!("{} bad.ngc", bin().display()))
            .arg("/dev/null")
            .env_remove("NO_COLOR")
            .env("TERM", "xterm")
            .stdin(Stdio::null());
        for (k, v) in env {
            cmd.env(k, v);
        }
        let out = cmd.output().expect("script");
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    let plain = on_tty(&[]);
    assert!(plain.contains("E0101"), "{plain}");
    assert!(plain.contains('\x1b'), "colours on a terminal: {plain:?}");
    for env in [&[("NO_COLOR", "1")][..], &[("TERM", "dumb")][..]] {
        let out = on_tty(env);
        assert!(out.contains("E0101"), "{env:?}: {out}");
        assert!(!out.contains('\x1b'), "{env:?}: {out:?}");
    }
}

/// Shell completions and the manual page come from the option definitions.
#[test]
fn completions_and_man_page() {
    let d = tmp();
    let cases: &[(&[&str], &str)] = &[
        (&["completions", "bash"], "_ngcflat()"),
        (&["completions", "zsh"], "#compdef ngcflat"),
        (&["completions", "fish"], "complete -c ngcflat"),
        (&["man"], ".TH ngcflat"),
    ];
    for (args, marker) in cases {
        let (code, out, err) = crate::run(d.path(), args);
        assert_eq!(code, 0, "{args:?}: {err}");
        assert!(out.contains(marker), "{args:?}: {out}");
        // Every option is there (roff escapes the hyphens).
        let out = out.replace("\\-", "-");
        assert!(out.contains("start-position"), "{args:?}");
        assert!(out.contains("message-format"), "{args:?}");
    }
    // The bash script is valid shell.
    let (_, script, _) = crate::run(d.path(), &["completions", "bash"]);
    std::fs::write(d.path().join("c.bash"), &script).unwrap();
    let ok = Command::new("bash")
        .args(["-n", "c.bash"])
        .current_dir(d.path())
        .status()
        .expect("bash");
    assert!(ok.success());
    let (code, _, err) = crate::run(d.path(), &["completions", "cmd.exe"]);
    assert_eq!(code, 2, "{err}");
}

/// User M-codes M100-M199: refused with the way to declare them; declared
/// with --user-m or found as LinuxCNC finds them (an executable file M1nn
/// in the INI's PROGRAM_PREFIX or USER_M_PATH folders), written as they are
/// with P and Q evaluated.
#[test]
fn user_m_codes() {
    use std::os::unix::fs::PermissionsExt;
    let d = tmp();
    let p = d.path();
    std::fs::write(p.join("p.ngc"), "#1=0.5\nM101 P[#1*2] Q#1\nG0 X1\nM2\n").unwrap();
    let exe = |rel: &str, mode: u32| {
        let f = p.join(rel);
        std::fs::create_dir_all(f.parent().unwrap()).unwrap();
        std::fs::write(&f, "#!/bin/sh\n").unwrap();
        std::fs::set_permissions(&f, std::fs::Permissions::from_mode(mode)).unwrap();
    };
    // Undeclared: the error names both ways to declare it.
    let (code, out, err) = crate::run(p, &["p.ngc"]);
    assert_eq!(code, 1, "{err}");
    assert!(out.is_empty());
    assert!(
        err.contains("E0805") && err.contains("--user-m 101") && err.contains("USER_M_PATH"),
        "{err}"
    );
    for args in [
        &["--user-m", "101", "p.ngc"][..],
        &["--user-m", "M100-M105,150", "p.ngc"][..],
    ] {
        let (code, out, err) = crate::run(p, args);
        assert_eq!(code, 0, "{args:?}: {err}");
        assert_eq!(out, "M101 P1 Q0.5\nG0 X1\nM2\n", "{args:?}");
    }
    let (code, _, err) = crate::run(p, &["--user-m", "99", "p.ngc"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("E0806"), "{err}");
    // Found through the INI: USER_M_PATH relative to the INI's folder.
    std::fs::create_dir_all(p.join("cfg")).unwrap();
    std::fs::write(
        p.join("cfg/m.ini"),
        "[RS274NGC]\nUSER_M_PATH = mcodes:other\n",
    )
    .unwrap();
    let ini_run = || crate::run(p, &["--ini", "cfg/m.ini", "p.ngc"]);
    // Not executable, or not a capital M: not a user M-code.
    exe("cfg/mcodes/M101", 0o644);
    exe("cfg/mcodes/m101", 0o755);
    assert_eq!(ini_run().0, 1);
    exe("cfg/other/M101", 0o755);
    let (code, out, err) = ini_run();
    assert_eq!(code, 0, "{err}");
    assert!(out.starts_with("M101 P1 Q0.5\n"), "{out}");
    // Two user M-codes on a line are one modal group, as in LinuxCNC.
    std::fs::write(p.join("two.ngc"), "M101 M102\nM2\n").unwrap();
    let (code, _, err) = crate::run(p, &["--user-m", "101,102", "two.ngc"]);
    assert_eq!(code, 1, "{err}");
}

/// Progress on a terminal for long runs, cleared at the end; never when
/// stderr is not a terminal or is a dumb one.
#[test]
fn progress_only_on_a_terminal() {
    let d = tmp();
    let prog = "#1=0\no1 while [#1 LT 20000]\nG1 X#1 F100\n#1=[#1+1]\no1 endwhile\nM2\n";
    std::fs::write(d.path().join("long.ngc"), prog).unwrap();
    // Piped stderr: nothing but the output, even with no delay.
    let mut cmd = Command::new(bin());
    cmd.current_dir(d.path())
        .arg("long.ngc")
        .env("NGCFLAT_TEST_PROGRESS_MS", "0")
        .env("TERM", "xterm");
    let out = cmd.output().expect("run");
    assert_eq!(out.status.code(), Some(0));
    assert!(
        out.stderr.is_empty(),
        "{:?}",
        String::from_utf8_lossy(&out.stderr)
    );
    if !Command::new("script")
        .arg("--version")
        .output()
        .is_ok_and(|o| o.status.success())
    {
        eprintln!("SKIPPED: no `script` command for a pseudo-terminal");
        return;
    }
    let on_tty = |term: &str| {
        let out = Command::new("script")
            .current_dir(d.path())
            .args(["-qec"])
            .arg(format!("{} long.ngc > out.nc", bin().display()))
            .arg("/dev/null")
            .env("NGCFLAT_TEST_PROGRESS_MS", "0")
            .env("TERM", term)
            .stdin(Stdio::null())
            .output()
            .expect("script");
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    let shown = on_tty("xterm");
    assert!(shown.contains("lines written, at line"), "{shown:?}");
    assert!(shown.ends_with("\r\x1b[K"), "cleared at the end: {shown:?}");
    let out = std::fs::read_to_string(d.path().join("out.nc")).unwrap();
    assert_eq!(out.lines().count(), 20001, "the output is unchanged");
    let dumb = on_tty("dumb");
    assert!(!dumb.contains("lines written"), "{dumb:?}");
}

/// On a target other than linuxcnc, user M-codes are refused with the
/// reason, declared or not (no advice to declare them).
#[test]
fn user_m_codes_on_other_targets() {
    let d = tmp();
    std::fs::write(d.path().join("p.ngc"), "M101 P1\nG0 X1\nM2\n").unwrap();
    for args in [
        &["--target", "grbl", "p.ngc"][..],
        &["--target", "grbl", "--user-m", "101", "p.ngc"][..],
    ] {
        let (code, out, err) = crate::run(d.path(), args);
        assert_eq!(code, 1, "{args:?}: {err}");
        assert!(out.is_empty());
        assert!(
            err.contains("M101 cannot run on grbl") && err.contains("user M-codes"),
            "{args:?}: {err}"
        );
        assert!(!err.contains("--user-m"), "{args:?}: {err}");
    }
    let (code, out, err) = crate::run(
        d.path(),
        &["--target", "linuxcnc", "--user-m", "101", "p.ngc"],
    );
    assert_eq!(code, 0, "{err}");
    assert_eq!(out, "M101 P1\nG0 X1\nM2\n");
    let (code, _, err) = crate::run(d.path(), &["--target", "linuxcnc", "p.ngc"]);
    assert_eq!(code, 1);
    assert!(err.contains("E0805"), "{err}");
}

/// The in-memory entry (`flatten_memory`, used by the fuzz targets) gives
/// the command's output and diagnostics: every fixture with a `subs`
/// folder, its subroutine files handed over as a map, and a long output
/// (more than the 1 MB a file output holds before spilling, through the
/// output thread).
#[test]
fn memory_entry_matches_the_command() {
    use std::collections::HashMap;
    let dir = crate::root().join("fixtures/ok/filesubs");
    let subs: HashMap<String, Vec<u8>> = std::fs::read_dir(dir.join("subs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "ngc"))
        .map(|p| {
            let name = p.file_stem().unwrap().to_string_lossy().into_owned();
            (name, std::fs::read(&p).unwrap())
        })
        .collect();
    let settings = ngcflat::settings::Settings::default();
    let mut seen = 0;
    for e in std::fs::read_dir(&dir).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_none_or(|x| x != "ngc") {
            continue;
        }
        let text = std::fs::read(&p).unwrap();
        let name = p.file_name().unwrap().to_string_lossy().into_owned();
        let (code, want, err) = crate::run(&dir, &["-I", "subs", &name]);
        assert_eq!(code, 0, "{name}: {err}");
        let (_, got) = ngcflat::flatten_memory(text.clone(), subs.clone(), &settings, None);
        assert_eq!(String::from_utf8_lossy(&got.unwrap()), want, "{name}");
        // Without the files, a call of one is the command's error (the
        // message differs only in the folders searched).
        let (_, got) = ngcflat::flatten_memory(text, HashMap::new(), &settings, None);
        let (code, _, err) = crate::run(&dir, &["--message-format", "short", &name]);
        assert_eq!(code, 1, "{name}");
        let msg = ngcflat::diag::render(
            &got.unwrap_err(),
            ngcflat::diag::MessageFormat::Short,
            false,
        );
        let code_of = |m: &str| m.find(" [E").map(|i| m[i..i + 8].to_string());
        let line_of = |m: &str| m.split(':').nth(1).map(str::to_string);
        assert_eq!(
            code_of(&msg),
            code_of(err.lines().next().unwrap_or("")),
            "{name}: {msg} vs {err}"
        );
        assert_eq!(line_of(&msg), line_of(&err), "{name}: {msg} vs {err}");
        seen += 1;
    }
    assert!(seen >= 10, "{seen} fixtures");
    let d = tmp();
    let prog = "G0 X0\no1 repeat [60000]\nG1 X[#5420+0.123456] Y1.5 F100 (a comment to make it long)\no1 endrepeat\nM2\n";
    std::fs::write(d.path().join("long.ngc"), prog).unwrap();
    let (code, want, err) = crate::run(d.path(), &["long.ngc"]);
    assert_eq!(code, 0, "{err}");
    assert!(want.len() > 2 << 20, "{}", want.len());
    let (_, got) = ngcflat::flatten_memory(prog.into(), HashMap::new(), &settings, None);
    assert!(got.unwrap() == want.as_bytes());
}

/// The firmwares a user might look for, as `--help` and the README spell
/// them, by the name of their target (`None`: no target).
const FIRMWARES: [(&str, &str); 9] = [
    ("GRBL", "grbl"),
    ("grblHAL", "grblhal"),
    ("FluidNC", "fluidnc"),
    ("Marlin", "marlin"),
    ("Smoothieware", "smoothieware"),
    ("Klipper", "klipper"),
    ("RepRapFirmware", "reprapfirmware"),
    ("g2core", "g2core"),
    ("TinyG", "tinyg"),
];

fn listed_targets() -> Vec<String> {
    let (code, out, _) = crate::run(&crate::root(), &["targets"]);
    assert_eq!(code, 0);
    out.lines()
        .filter(|l| l.starts_with(|c: char| c.is_ascii_alphanumeric()))
        .filter_map(|l| l.split_whitespace().next().map(str::to_string))
        .collect()
}

/// `--help` and the README's target table name every target `ngcflat
/// targets` lists, and no firmware that has none.
#[test]
fn help_and_readme_name_the_targets_that_exist() {
    let targets = listed_targets();
    let (code, help, _) = crate::run(&crate::root(), &["--help"]);
    assert_eq!(code, 0);
    // The description above the options (clap prints it first).
    let about = help.split("Usage:").next().unwrap_or_default();
    let readme = std::fs::read_to_string(crate::root().join("README.md")).unwrap();
    let table: Vec<&str> = readme
        .lines()
        .skip_while(|l| !l.starts_with("| `--target`"))
        .skip(2)
        .take_while(|l| l.starts_with('|'))
        .collect();
    let rows: Vec<String> = table
        .iter()
        .filter_map(|r| r.split('`').nth(1).map(str::to_string))
        .collect();
    assert_eq!(rows, targets, "README's target table");
    let word = |text: &str, w: &str| {
        text.split(|c: char| !c.is_ascii_alphanumeric())
            .any(|t| t == w)
    };
    for (name, target) in FIRMWARES {
        let exists = targets.iter().any(|t| t == target);
        assert_eq!(word(about, name), exists, "--help on {name}:\n{about}");
        let said = readme
            .lines()
            .any(|l| word(l, name) && !l.contains("no profile"));
        assert!(said || !exists, "README never names {name}");
    }
}
