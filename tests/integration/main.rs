//! The one integration-test crate: fixture snapshots, the differential suite
//! against rs274, CLI behaviour, property tests and generated programs.

mod check;
mod cli;
mod config;
mod fixtures;
mod generated;
mod oracle;
mod props;

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
