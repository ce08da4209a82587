//! `ngcflat targets` (and `--target list`): the profiles with their limits;
//! `targets --show NAME`: one built-in profile's file.

use std::process::ExitCode;

use crate::diag::{ErrorKind, MessageFormat, TargetError};

pub(super) fn run() -> ExitCode {
    let mut s = String::new();
    for p in crate::controller::profiles() {
        s.push_str(&p.describe());
        s.push('\n');
    }
    print!("{s}");
    ExitCode::SUCCESS
}

pub(super) fn show(name: &str) -> ExitCode {
    match crate::controller::built_in_file(name) {
        Some(text) => {
            print!("{text}");
            ExitCode::SUCCESS
        }
        None => super::setup_error(
            ErrorKind::Target(TargetError::UnknownTarget { name: name.into() }),
            MessageFormat::Human,
            false,
        ),
    }
}
