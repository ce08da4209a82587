//! `ngcflat targets` (and `--target list`): the profiles with their limits.

use std::process::ExitCode;

pub(super) fn run() -> ExitCode {
    let mut s = String::new();
    for p in crate::controller::PROFILES {
        s.push_str(&p.describe());
        s.push('\n');
    }
    print!("{s}");
    ExitCode::SUCCESS
}
