//! Hostile inputs and a hostile environment: closed streams, FIFOs, panics
//! in one file of a check run, files changed during a run, resource bounds.

use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use crate::{bin, put, run, tmp};

/// Waits for `child` at most `secs` seconds; kills it and fails past that.
fn wait_bounded(mut child: Child, secs: u64) -> std::process::Output {
    let deadline = Instant::now() + Duration::from_secs(secs);
    loop {
        if child.try_wait().expect("wait").is_some() {
            return child.wait_with_output().expect("output");
        }
        if Instant::now() > deadline {
            let _ = child.kill();
            let _ = child.wait();
            panic!("ngcflat did not finish within {secs} s");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

/// A program that flattens with a warning (a subroutine never called).
const WARNS: &str = "o<unused> sub\no<unused> endsub\nG0 X1\nM2\n";

#[test]
fn a_closed_stderr_does_not_stop_the_run() {
    let d = tmp();
    put(d.path(), "w.ngc", WARNS);
    let (reader, writer) = std::io::pipe().expect("pipe");
    drop(reader);
    let out = Command::new(bin())
        .current_dir(d.path())
        .arg("w.ngc")
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(writer)
        .output()
        .expect("run");
    assert_eq!(out.status.code(), Some(0));
    assert_eq!(String::from_utf8_lossy(&out.stdout), "G0 X1\nM2\n");
}

#[test]
fn a_full_stderr_does_not_stop_the_run() {
    let d = tmp();
    put(d.path(), "w.ngc", WARNS);
    put(d.path(), "bad.ngc", "G0 X[1/0]\nM2\n");
    for (args, want) in [(&["w.ngc"][..], 0), (&["check", "w.ngc", "bad.ngc"][..], 1)] {
        let full = std::fs::File::options()
            .write(true)
            .open("/dev/full")
            .expect("/dev/full");
        let out = Command::new(bin())
            .current_dir(d.path())
            .args(args)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(full)
            .output()
            .expect("run");
        assert_eq!(out.status.code(), Some(want), "{args:?}");
    }
}

#[test]
fn check_reports_every_file_whatever_one_does() {
    let d = tmp();
    put(d.path(), "t/a-sub.ngc", "o[1]sub\n");
    put(d.path(), "t/b-continue.ngc", "o1do\no1 continue\no1while\n");
    put(d.path(), "t/c-good.ngc", "G0 X1\nM2\n");
    put(d.path(), "t/d-bad.ngc", "G0 X[1/0]\nM2\n");
    let (code, _, err) = run(d.path(), &["check", "--message-format", "short", "t"]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("a-sub.ngc:1:1: error: ") && err.contains("[E0701]"),
        "{err}"
    );
    assert!(err.contains("b-continue.ngc:3:8: error: "), "{err}");
    assert!(err.contains("d-bad.ngc:1:"), "{err}");
    assert!(err.contains("4 files, 3 errors"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn a_panic_in_one_file_is_an_internal_error_of_that_file() {
    let d = tmp();
    put(d.path(), "t/a.ngc", "G0 X1\nM2\n");
    put(d.path(), "t/b.ngc", "G0 X1\nM2\n");
    put(d.path(), "t/c.ngc", "G0 X[1/0]\nM2\n");
    let out = Command::new(bin())
        .current_dir(d.path())
        .args(["check", "--message-format", "short", "t"])
        .env("NGCFLAT_TEST_PANIC", "b.ngc")
        .stdin(Stdio::null())
        .output()
        .expect("run");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("[E0700]") && err.contains("b.ngc"), "{err}");
    assert!(err.contains("c.ngc:1:"), "{err}");
    assert!(err.contains("3 files, 2 errors"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn check_does_not_wait_on_a_fifo() {
    let d = tmp();
    put(d.path(), "good.ngc", "G0 X1\nM2\n");
    let fifo = d.path().join("pipe.ngc");
    let st = Command::new("mkfifo").arg(&fifo).status().expect("mkfifo");
    assert!(st.success());
    let child = Command::new(bin())
        .current_dir(d.path())
        .args(["check", "pipe.ngc", "good.ngc"])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run");
    let out = wait_bounded(child, 10);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_ne!(out.status.code(), Some(0), "{err}");
    assert!(err.contains("pipe.ngc: not a regular file"), "{err}");
    assert!(err.contains("2 files"), "{err}");
}

/// A streamed input (over the 8 MB kept in memory) of plain moves.
fn big_input(dir: &std::path::Path) -> std::path::PathBuf {
    let mut text = String::with_capacity(12 << 20);
    text.push_str("F100\n");
    for i in 0..800_000 {
        text.push_str(&format!("G1 X{i} Y{}\n", i % 7));
    }
    text.push_str("M2\n");
    let p = dir.join("big.ngc");
    std::fs::write(&p, text).unwrap();
    p
}

/// Runs ngcflat on `args`, pausing at release `phase` (a test hook) to let
/// `change` act on the input; returns the finished run.
fn run_changing(
    dir: &std::path::Path,
    args: &[&str],
    phase: &str,
    change: impl FnOnce(),
) -> std::process::Output {
    let pause = dir.join("pause");
    std::fs::create_dir_all(&pause).unwrap();
    let wait = pause.join(format!("{phase}.wait"));
    std::fs::write(&wait, b"").unwrap();
    let mut child = Command::new(bin())
        .current_dir(dir)
        .args(args)
        .env("NGCFLAT_TEST_PAUSE_DIR", &pause)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Read stdout on a thread so that a large release cannot block.
    let mut stdout = child.stdout.take().unwrap();
    let reader = std::thread::spawn(move || {
        use std::io::Read;
        let mut v = Vec::new();
        stdout.read_to_end(&mut v).unwrap();
        v
    });
    let deadline = Instant::now() + Duration::from_secs(120);
    while !pause.join(format!("{phase}.paused")).exists() {
        assert!(Instant::now() < deadline, "the run never reached {phase}");
        std::thread::sleep(Duration::from_millis(10));
    }
    change();
    std::fs::remove_file(&wait).unwrap();
    let mut out = child.wait_with_output().unwrap();
    out.stdout = reader.join().unwrap();
    std::fs::remove_dir_all(&pause).unwrap();
    out
}

/// Rewrites `len` bytes at `at` in place and puts the modification time back.
fn rewrite_keeping_mtime(path: &std::path::Path, at: u64, bytes: &[u8]) {
    use std::io::{Seek, SeekFrom, Write};
    let mtime = std::fs::metadata(path).unwrap().modified().unwrap();
    let mut f = std::fs::OpenOptions::new().write(true).open(path).unwrap();
    f.seek(SeekFrom::Start(at)).unwrap();
    f.write_all(bytes).unwrap();
    f.set_modified(mtime).unwrap();
}

#[test]
fn released_bytes_are_the_bytes_evaluated() {
    let d = tmp();
    let big = big_input(d.path());
    let want = run(d.path(), &["big.ngc"]).1;
    assert!(want.len() > 8 << 20);
    let text = std::fs::read(&big).unwrap();
    let line_at = |k: usize| {
        text.split_inclusive(|&b| b == b'\n')
            .take(k)
            .map(|l| l.len() as u64)
            .sum::<u64>()
    };
    // "G1 X1000 Y6" rewritten to as many bytes that do not evaluate, the
    // modification time restored: not released.
    let at = line_at(1000);
    let out = run_changing(d.path(), &["big.ngc"], "verify", || {
        rewrite_keeping_mtime(&big, at, b"G1 X[1/0]Y")
    });
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(out.stdout.is_empty(), "{} bytes released", out.stdout.len());
    assert!(
        err.contains("changed while it was being flattened"),
        "{err}"
    );
    std::fs::write(&big, &text).unwrap();
    // Truncated before the release: nothing released.
    let out = run_changing(d.path(), &["big.ngc"], "verify", || {
        std::fs::OpenOptions::new()
            .write(true)
            .open(&big)
            .unwrap()
            .set_len(text.len() as u64 / 2)
            .unwrap()
    });
    assert_eq!(out.status.code(), Some(2));
    assert!(out.stdout.is_empty(), "{} bytes released", out.stdout.len());
    std::fs::write(&big, &text).unwrap();
    // Changed after the check, before the first byte is written or once
    // the first megabyte is out: the release never reads the input, the
    // output is whole and exactly the evaluated program.
    let at = line_at(700_000);
    for phase in ["copy", "copying"] {
        let out = run_changing(d.path(), &["big.ngc"], phase, || {
            rewrite_keeping_mtime(&big, at, b"G1 X[1/0]Y")
        });
        assert_eq!(out.status.code(), Some(0), "{phase}");
        assert!(out.stdout == want.as_bytes(), "{phase}");
        std::fs::write(&big, &text).unwrap();
        let out = run_changing(d.path(), &["big.ngc"], phase, || {
            std::fs::OpenOptions::new()
                .write(true)
                .open(&big)
                .unwrap()
                .set_len(100)
                .unwrap()
        });
        assert_eq!(out.status.code(), Some(0), "{phase}");
        assert!(out.stdout == want.as_bytes(), "{phase}");
        std::fs::write(&big, &text).unwrap();
    }
    // Unchanged: released whole.
    let out = run_changing(d.path(), &["big.ngc"], "verify", || {});
    assert_eq!(out.status.code(), Some(0));
    assert!(out.stdout == want.as_bytes());
}

#[test]
fn an_output_file_is_not_written_from_a_changed_input() {
    let d = tmp();
    let big = big_input(d.path());
    let text = std::fs::read(&big).unwrap();
    // Appended to, or a line rewritten with the modification time put
    // back: both seen before the output file is put in place.
    let append = || {
        use std::io::Write;
        let mut f = std::fs::OpenOptions::new().append(true).open(&big).unwrap();
        f.write_all(b"G1 X[1/0]\n").unwrap();
    };
    let rewrite = || rewrite_keeping_mtime(&big, 5_000_000, b"G1 X[1/0]Y");
    for change in [&append as &dyn Fn(), &rewrite] {
        let out = run_changing(d.path(), &["-o", "out.nc", "big.ngc"], "finish", change);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(
            err.contains("changed while it was being flattened"),
            "{err}"
        );
        assert_eq!(
            names(d.path()),
            ["big.ngc"],
            "no output and no temporary file"
        );
        std::fs::write(&big, &text).unwrap();
    }
}

/// Names in a folder, sorted.
fn names(dir: &std::path::Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn standard_input_is_spooled_to_no_named_file() {
    let d = tmp();
    let big = big_input(d.path());
    let text = std::fs::read(&big).unwrap();
    let tmpdir = d.path().join("tmp");
    std::fs::create_dir(&tmpdir).unwrap();
    // A program with an error at its end, and a good one: neither leaves a
    // file in the temporary folder, during the run or after it.
    let mut bad = text[..text.len() - 3].to_vec();
    bad.extend_from_slice(b"G1 X[1/0]\nM2\n");
    for (input, want) in [(bad, 1), (text, 0)] {
        let pause = d.path().join("pause");
        std::fs::create_dir_all(&pause).unwrap();
        std::fs::write(pause.join("verify.wait"), b"").unwrap();
        let mut child = Command::new(bin())
            .current_dir(d.path())
            .env("TMPDIR", &tmpdir)
            .env("NGCFLAT_TEST_PAUSE_DIR", &pause)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let mut stdin = child.stdin.take().unwrap();
        let feeder = std::thread::spawn(move || {
            use std::io::Write;
            let _ = stdin.write_all(&input);
        });
        feeder.join().unwrap();
        if want == 0 {
            let deadline = Instant::now() + Duration::from_secs(120);
            while !pause.join("verify.paused").exists() {
                assert!(Instant::now() < deadline, "never paused");
                std::thread::sleep(Duration::from_millis(10));
            }
            assert!(names(&tmpdir).is_empty(), "{:?}", names(&tmpdir));
            std::fs::remove_file(pause.join("verify.wait")).unwrap();
        }
        let out = child.wait_with_output().unwrap();
        assert_eq!(out.status.code(), Some(want));
        assert!(names(&tmpdir).is_empty(), "{:?}", names(&tmpdir));
        std::fs::remove_dir_all(&pause).unwrap();
    }
}

#[test]
fn an_interrupted_run_leaves_no_temporary_file() {
    let d = tmp();
    big_input(d.path());
    for sig in ["INT", "TERM"] {
        let pause = d.path().join("pause");
        std::fs::create_dir_all(&pause).unwrap();
        std::fs::write(pause.join("finish.wait"), b"").unwrap();
        let child = Command::new(bin())
            .current_dir(d.path())
            .args(["-o", "out.nc", "big.ngc"])
            .env("NGCFLAT_TEST_PAUSE_DIR", &pause)
            .stdin(Stdio::null())
            .spawn()
            .unwrap();
        let deadline = Instant::now() + Duration::from_secs(120);
        while !pause.join("finish.paused").exists() {
            assert!(Instant::now() < deadline, "never paused");
            std::thread::sleep(Duration::from_millis(10));
        }
        // The spool file is there, full, while the run waits.
        assert!(names(d.path()).iter().any(|n| n.ends_with(".tmp")));
        let st = Command::new("kill")
            .args([format!("-{sig}"), child.id().to_string()])
            .status()
            .unwrap();
        assert!(st.success());
        let out = wait_bounded(child, 30);
        assert!(!out.status.success());
        std::fs::remove_dir_all(&pause).unwrap();
        assert_eq!(names(d.path()), ["big.ngc"], "after SIG{sig}");
    }
}

#[test]
fn a_subroutine_name_cannot_walk_through_a_link() {
    let d = tmp();
    let p = d.path();
    put(
        p,
        "outside/x/y.ngc",
        "o<y> sub\n  (print, OUTSIDE)\no<y> endsub\n",
    );
    put(p, "lib/p.ngc", "o<root/x/y> call\nM2\n");
    std::os::unix::fs::symlink(p.join("outside"), p.join("lib/root")).unwrap();
    let (code, out, err) = run(p, &["-I", "lib", "lib/p.ngc"]);
    assert_eq!(code, 1, "{err}");
    assert!(out.is_empty() && err.contains("[E0502]"), "{err}");
    // A link inside a search folder, named as a plain name, may point
    // anywhere: the user made it.
    std::os::unix::fs::symlink(p.join("outside/x/y.ngc"), p.join("lib/y.ngc")).unwrap();
    put(p, "lib/q.ngc", "o<y> call\nM2\n");
    let (code, out, err) = run(p, &["-I", "lib", "lib/q.ngc"]);
    assert_eq!(code, 0, "{err}");
    assert!(out.contains("OUTSIDE"), "{out}");
}

#[test]
fn the_output_line_guard_counts_generated_lines_only() {
    let d = tmp();
    let mut straight = String::from("F100\n");
    for i in 0..1000 {
        straight.push_str(&format!("G1 X{i}\n"));
    }
    straight.push_str("M2\n");
    put(d.path(), "straight.ngc", &straight);
    let (code, out, err) = run(d.path(), &["--max-output-lines", "10", "straight.ngc"]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(out.lines().count(), 1002);
    // A loop writing more than the limit beyond the file's own lines stops.
    put(
        d.path(),
        "loop.ngc",
        "F100\no1 repeat [100]\nG1 X1\no1 endrepeat\nM2\n",
    );
    let (code, out, err) = run(d.path(), &["--max-output-lines", "10", "loop.ngc"]);
    assert_eq!(code, 1, "{err}");
    assert!(out.is_empty() && err.contains("[E0403]"), "{err}");
}

/// A lathe cycle with a tiny depth of cut under a small output bound: it
/// fails at that bound, at the contour's `endsub`, whether the bound falls
/// within the moves it makes or after them; under the bound it runs.
#[test]
fn a_lathe_cycle_stops_at_the_output_line_guard() {
    let d = tmp();
    let prog = "G18 G21 G90 F300\n\
                o500 sub\nG1 X4 Z0\nG1 X4 Z-5\nG1 X9 Z-10\no500 endsub\n\
                G0 X12 Z2\nG71 Q500 X12 Z2 D0.01 I0.01 R0.3\nM2\n";
    put(d.path(), "cut.ngc", prog);
    let (code, out, _) = run(d.path(), &["cut.ngc"]);
    assert_eq!(code, 0);
    let lines = out.lines().count();
    assert!(lines > 1000, "{lines}");
    for limit in [0, 10, lines / 2, lines - 12] {
        let l = limit.to_string();
        let (code, out, err) = run(d.path(), &["--max-output-lines", &l, "cut.ngc"]);
        assert_eq!(code, 1, "{limit} {err}");
        assert!(out.is_empty(), "{limit}");
        assert!(
            err.contains(&format!("more than {limit} output lines")) && err.contains("cut.ngc:6:1"),
            "{limit} {err}"
        );
    }
    let l = lines.to_string();
    let (code, again, err) = run(d.path(), &["--max-output-lines", &l, "cut.ngc"]);
    assert_eq!((code, again), (0, out), "{err}");
}

/// A contour subroutine that never ends fails at the element past the
/// contour bound (E1322, at the line adding it), not after filling the
/// memory; a contour within the bound is cut.
#[test]
fn a_contour_that_never_ends_stops_at_its_bound() {
    let s = ngcflat::settings::Settings {
        max_contour: 50,
        ..Default::default()
    };
    let prog = |cond: &str| {
        format!(
            "G18 G21 G90 F150\nG0 X30 Z5\no300 sub\nG1 X10 Z0\n#1=0\n\
             o301 while [{cond}]\nG1 Z[#<_z> - 1]\nG1 X[#<_x> + 0.1]\n#1=[#1+1]\n\
             o301 endwhile\n\
             o300 endsub\nG71 Q300 X30 Z5 D0.4 I2 R0.5\nM2\n"
        )
    };
    let e = ngcflat::flatten_str(&prog("1"), &s).expect_err("endless contour");
    let shown = ngcflat::diag::render(&e, ngcflat::diag::MessageFormat::Short, false);
    assert!(
        shown.contains(":8:1: error: lathe cycle contour: more than 50 elements [E1322]"),
        "{shown}"
    );
    // 1 + 2 * 24 elements: cut; 1 + 2 * 25: one too many.
    let ok = ngcflat::flatten_str(&prog("#1 LT 24"), &s);
    assert!(ok.is_ok_and(|o| o.lines().count() > 50));
    let e = ngcflat::flatten_str(&prog("#1 LT 25"), &s).expect_err("one too many");
    assert_eq!(e.code(), "E1322");
}

#[test]
fn the_output_cannot_be_the_program() {
    let d = tmp();
    let p = d.path();
    let prog = "G0 X[1+1]\nM2\n";
    put(p, "part.ngc", prog);
    std::os::unix::fs::symlink("part.ngc", p.join("link.ngc")).unwrap();
    std::fs::hard_link(p.join("part.ngc"), p.join("hard.ngc")).unwrap();
    for (out, input) in [
        ("part.ngc", "part.ngc"),
        ("./part.ngc", "part.ngc"),
        ("link.ngc", "part.ngc"),
        ("hard.ngc", "part.ngc"),
        ("part.ngc", "link.ngc"),
    ] {
        let (code, _, err) = run(p, &["-o", out, input]);
        assert_eq!(code, 2, "-o {out} {input}: {err}");
        assert!(err.contains("[E0702]"), "{err}");
        assert_eq!(std::fs::read_to_string(p.join("part.ngc")).unwrap(), prog);
    }
    // From standard input too.
    let out = Command::new(bin())
        .current_dir(p)
        .args(["-o", "part.ngc"])
        .stdin(std::fs::File::open(p.join("part.ngc")).unwrap())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert_eq!(std::fs::read_to_string(p.join("part.ngc")).unwrap(), prog);
}

#[test]
fn the_output_keeps_links_fifos_and_modes() {
    use std::os::unix::fs::PermissionsExt;
    let d = tmp();
    let p = d.path();
    put(p, "part.ngc", "G0 X[1+1]\nM2\n");
    let want = "G0 X2\nM2\n";
    // A symbolic link: its target is replaced, the link kept.
    put(p, "real/out.nc", "OLD\n");
    std::os::unix::fs::symlink("real/out.nc", p.join("out.nc")).unwrap();
    let (code, _, err) = run(p, &["-o", "out.nc", "part.ngc"]);
    assert_eq!(code, 0, "{err}");
    let m = std::fs::symlink_metadata(p.join("out.nc")).unwrap();
    assert!(m.file_type().is_symlink());
    assert_eq!(
        std::fs::read_to_string(p.join("real/out.nc")).unwrap(),
        want
    );
    assert_eq!(names(&p.join("real")), ["out.nc"]);
    // An existing file's mode is kept.
    for mode in [0o600, 0o755, 0o640] {
        put(p, "m.nc", "OLD\n");
        std::fs::set_permissions(p.join("m.nc"), std::fs::Permissions::from_mode(mode)).unwrap();
        let (code, _, err) = run(p, &["-o", "m.nc", "part.ngc"]);
        assert_eq!(code, 0, "{err}");
        let got = std::fs::metadata(p.join("m.nc"))
            .unwrap()
            .permissions()
            .mode()
            & 0o7777;
        assert_eq!(got, mode);
        assert_eq!(std::fs::read_to_string(p.join("m.nc")).unwrap(), want);
    }
    // A new file gets the usual mode (0666 less the umask), not 0600.
    let (code, _, _) = run(p, &["-o", "new.nc", "part.ngc"]);
    assert_eq!(code, 0);
    let got = std::fs::metadata(p.join("new.nc"))
        .unwrap()
        .permissions()
        .mode()
        & 0o777;
    assert_ne!(got & 0o044, 0, "mode {got:o}");
    // A FIFO is written into, not replaced.
    let fifo = p.join("fifo.nc");
    assert!(
        Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success()
    );
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || std::fs::read_to_string(fifo).unwrap())
    };
    let child = Command::new(bin())
        .current_dir(p)
        .args(["-o", "fifo.nc", "part.ngc"])
        .stdin(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let out = wait_bounded(child, 30);
    assert_eq!(out.status.code(), Some(0));
    assert_eq!(reader.join().unwrap(), want);
    use std::os::unix::fs::FileTypeExt;
    assert!(
        std::fs::symlink_metadata(&fifo)
            .unwrap()
            .file_type()
            .is_fifo()
    );
    let left: Vec<String> = names(p)
        .into_iter()
        .filter(|n| n.ends_with(".tmp"))
        .collect();
    assert!(left.is_empty(), "{left:?}");
}

#[test]
fn an_unwritable_folder_is_named() {
    use std::os::unix::fs::PermissionsExt;
    let d = tmp();
    let p = d.path();
    put(p, "part.ngc", "G0 X1\nM2\n");
    // A folder that is not there (testable as any user): named.
    let (code, _, err) = run(p, &["-o", "nodir/out.nc", "part.ngc"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("in the folder nodir"), "{err}");
    put(p, "ro/out.nc", "OLD\n");
    std::fs::set_permissions(p.join("ro"), std::fs::Permissions::from_mode(0o555)).unwrap();
    if std::fs::write(p.join("ro/probe"), b"").is_ok() {
        eprintln!("SKIPPED: permissions are not enforced for this user");
        return;
    }
    let (code, _, err) = run(p, &["-o", "ro/out.nc", "part.ngc"]);
    std::fs::set_permissions(p.join("ro"), std::fs::Permissions::from_mode(0o755)).unwrap();
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("in the folder ro"), "{err}");
}

#[test]
fn endless_input_stops_at_a_bound_and_leaves_nothing() {
    let d = tmp();
    let p = d.path();
    let tmpdir = p.join("tmp");
    std::fs::create_dir(&tmpdir).unwrap();
    let ngcflat = |args: &[&str], stdin: Stdio| {
        let child = Command::new(bin())
            .current_dir(p)
            .args(args)
            .env("TMPDIR", &tmpdir)
            .stdin(stdin)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        wait_bounded(child, 20)
    };
    // A device given by path, and as standard input: one endless line.
    let zero = || std::fs::File::open("/dev/zero").unwrap().into();
    for out in [ngcflat(&["/dev/zero"], Stdio::null()), ngcflat(&[], zero())] {
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(err.contains("line 1 is longer than 1048576 bytes"), "{err}");
        assert!(err.len() < 400, "the line is not echoed whole: {err}");
        assert!(out.stdout.is_empty());
    }
    // `yes`: endless short lines, stopped by the size bound.
    let mut yes = Command::new("yes").stdout(Stdio::piped()).spawn().unwrap();
    let out = ngcflat(
        &["--max-input-bytes", "20000000"],
        yes.stdout.take().unwrap().into(),
    );
    let _ = yes.kill();
    let _ = yes.wait();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("larger than 20000000 bytes"), "{err}");
    assert!(names(&tmpdir).is_empty(), "{:?}", names(&tmpdir));
    // A line bound below the read size, from a pipe.
    let long = format!("G0 X1\nG0 X2 ({})\nM2\n", "a".repeat(3000));
    let out = crate::ngcflat(
        p,
        &["--max-line-bytes".into(), "1000".into()],
        Some(long.as_bytes()),
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("line 2 is longer than 1000 bytes"), "{err}");
}

#[test]
fn programs_over_the_size_bound_are_refused_before_reading() {
    let d = tmp();
    let p = d.path();
    put(p, "small.ngc", "G0 X1\nM2\n");
    let (code, _, err) = run(p, &["--max-input-bytes", "5", "small.ngc"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("larger than 5 bytes"), "{err}");
    // Over 4 GiB (a sparse file): offsets are 32-bit, refused whatever the
    // bound.
    let f = std::fs::File::create(p.join("huge.ngc")).unwrap();
    f.set_len(5 << 30).unwrap();
    let (code, _, err) = run(p, &["--max-input-bytes", "6000000000", "huge.ngc"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("4 GiB or more are not supported"), "{err}");
}

#[test]
fn the_output_byte_bound_stops_a_runaway_loop() {
    let d = tmp();
    let p = d.path();
    put(
        p,
        "loop.ngc",
        &format!(
            "F100\no1 repeat [100000]\nG1 X1 ({})\no1 endrepeat\nM2\n",
            "c".repeat(200)
        ),
    );
    for args in [
        &["--max-output-bytes", "1000000", "loop.ngc"][..],
        &["--max-output-bytes", "1000000", "-o", "out.nc", "loop.ngc"][..],
    ] {
        let (code, out, err) = run(p, args);
        assert_eq!(code, 1, "{err}");
        assert!(out.is_empty() && err.contains("[E0703]"), "{err}");
        assert_eq!(names(p), ["loop.ngc"]);
    }
    let (code, out, _) = run(p, &["--max-output-bytes", "100000000", "loop.ngc"]);
    assert_eq!(code, 0);
    assert_eq!(out.lines().count(), 100_002);
}

/// A program of `n` subroutines (each with `pad` comment lines) and `n`
/// numbered blocks, every third subroutine called; returns the text and the
/// (line, name) of each never-called one, in file order.
fn many_subs(n: usize, pad: usize) -> (String, Vec<(usize, String)>) {
    let mut text = String::from("F100\n#1 = 0\n");
    let mut line = 2;
    let mut unused = Vec::new();
    let filler = format!("({})\n", "x".repeat(200));
    for k in 0..n {
        line += 1;
        text.push_str(&format!("o<s{k}> sub\n"));
        if k % 3 != 0 {
            unused.push((line, format!("s{k}")));
        }
        for _ in 0..pad {
            text.push_str(&filler);
        }
        text.push_str(&format!("  G1 X#1\no<s{k}> endsub\n"));
        line += pad + 2;
    }
    for k in 0..n {
        if k % 3 == 0 {
            text.push_str(&format!("o<s{k}> call [{}]\n", k % 10));
        }
        text.push_str(&format!(
            "o{} if [#1 GT {}]\nG1 Y1\no{0} endif\n",
            1000 + k,
            k % 7
        ));
    }
    text.push_str("M2\n");
    (text, unused)
}

/// The never-called warnings of `stderr` (short format): (line, name).
fn unused_warnings(stderr: &str) -> Vec<(usize, String)> {
    stderr
        .lines()
        .filter(|l| l.contains("[W0002]"))
        .map(|l| {
            let line = l
                .split(':')
                .nth(1)
                .and_then(|n| n.parse().ok())
                .unwrap_or(0);
            let name = l
                .split("o<")
                .nth(1)
                .and_then(|r| r.split('>').next())
                .unwrap_or("")
                .to_string();
            (line, name)
        })
        .collect()
}

#[test]
fn every_never_called_subroutine_is_warned_in_order() {
    let d = tmp();
    // Held in memory, and streamed from disk (over 8 MB).
    for (name, pad) in [("small.ngc", 0), ("big.ngc", 15)] {
        let (text, want) = many_subs(3000, pad);
        assert_eq!(text.len() > 8 << 20, pad > 0);
        put(d.path(), name, &text);
        for args in [
            vec!["--message-format", "short", name],
            vec!["--message-format", "short", "--oword-warn-only", name],
            vec!["check", "--message-format", "short", name],
        ] {
            let (code, _, err) = run(d.path(), &args);
            assert_eq!(code, 0, "{args:?}");
            let got = unused_warnings(&err);
            assert_eq!(got.len(), 2000, "{args:?}");
            assert!(got == want, "{args:?}: warnings not all given in order");
            let columns_ok = err
                .lines()
                .filter(|l| l.contains("[W0002]"))
                .all(|l| l.starts_with(&format!("{name}:")) && l.split(':').nth(2) == Some("1"));
            assert!(columns_ok, "{args:?}");
        }
    }
}
