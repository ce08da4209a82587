//! The one integration-test crate: fixture snapshots, the differential suite
//! against rs274, CLI behaviour, property tests and generated programs.

mod check;
mod cli;
mod comp;
mod config;
mod corpus;
mod cycles;
mod fixtures;
mod fuzz;
mod generated;
mod hostile;
mod lathe;
mod layers;
mod lowering;
mod motion;
mod named2007;
mod oracle;
mod profiles;
mod props;
mod report_page;
mod rng;
mod view;
mod warn_only;
mod webdriver;

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

/// Path of the built binary.
pub fn bin() -> PathBuf {
    PathBuf::from(env!("CARGO_BIN_EXE_ngcflat"))
}

pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Runs ngcflat in `dir` with `args`, feeding `stdin`.
pub fn ngcflat(dir: &Path, args: &[String], stdin: Option<&[u8]>) -> Output {
    use std::io::Write;
    let mut cmd = Command::new(bin());
    cmd.current_dir(dir)
        .args(args)
        .env_remove("NGCFLAT_SUBROUTINE_PATH");
    cmd.stdin(if stdin.is_some() {
        Stdio::piped()
    } else {
        Stdio::null()
    });
    cmd.stdout(Stdio::piped()).stderr(Stdio::piped());
    let mut child = cmd.spawn().expect("run ngcflat");
    if let Some(data) = stdin {
        let mut si = child.stdin.take().expect("stdin");
        let _ = si.write_all(data);
    }
    child.wait_with_output().expect("wait ngcflat")
}

/// A fresh temporary folder.
/// Output written for built-in target `target` as rs274 reads it: G4's P
/// in seconds where the target reads milliseconds, and an M2 at the end
/// where the target has no program end (the end of the file ends its
/// program). Everything else a target writes is LinuxCNC's G-code too.
pub fn as_rs274_reads(target: &str, out: &str) -> String {
    let profile = std::fs::read_to_string(
        root()
            .join("src/controller/profiles")
            .join(format!("{target}.toml")),
    )
    .unwrap_or_default();
    let ms = profile
        .lines()
        .any(|l| l.trim().starts_with("dwell_units") && l.contains("milliseconds"));
    let ends = profile
        .lines()
        .find(|l| l.starts_with("m_codes"))
        .is_none_or(|l| l.contains("\"M2\""));
    // The firmware's own pause code (Smoothieware's M600,
    // RepRapFirmware's M226) is LinuxCNC's M0.
    let pause = profile
        .lines()
        .find_map(|l| l.strip_prefix("pause = \""))
        .and_then(|r| r.strip_suffix('"'))
        .filter(|&code| code != "M0");
    let mut text = String::with_capacity(out.len() + 4);
    for line in out.lines() {
        if pause.is_some_and(|code| line == code) {
            text.push_str("M0\n");
            continue;
        }
        let words: Vec<&str> = line.split(' ').collect();
        if ms && words.first() == Some(&"G4") {
            let rest: Vec<String> = words
                .iter()
                .map(
                    |w| match w.strip_prefix('P').and_then(|v| v.parse::<f64>().ok()) {
                        Some(v) => format!("P{}", v / 1000.0),
                        None => w.to_string(),
                    },
                )
                .collect();
            text.push_str(&rest.join(" "));
        } else {
            text.push_str(line);
        }
        text.push('\n');
    }
    if !ends {
        text.push_str("M2\n");
    }
    text
}

pub fn tmp() -> tempfile::TempDir {
    tempfile::tempdir().expect("tempdir")
}

/// Writes `text` to `dir/rel`, creating folders.
pub fn put(dir: &Path, rel: &str, text: &str) {
    let p = dir.join(rel);
    std::fs::create_dir_all(p.parent().expect("parent")).expect("mkdir");
    std::fs::write(p, text).expect("write");
}

/// (exit code, stdout, stderr) of a finished run.
pub fn outcome(out: Output) -> (i32, String, String) {
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Runs ngcflat in `dir`; returns (exit code, stdout, stderr).
pub fn run(dir: &Path, args: &[&str]) -> (i32, String, String) {
    let args: Vec<String> = args.iter().map(|s| s.to_string()).collect();
    outcome(ngcflat(dir, &args, None))
}
