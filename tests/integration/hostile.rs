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
