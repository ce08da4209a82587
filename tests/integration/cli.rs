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
