//! Differential: the straight-line loop (lines read in place or ahead on a
//! second thread) against the line-by-line path. Any program must give the
//! same output, or the same error, both ways.
#![no_main]

use libfuzzer_sys::fuzz_target;
use ngcflat::diag::{MessageFormat, render};
use ngcflat::eval::Settings;

fuzz_target!(|data: &[u8]| {
    let Some((&flags, text)) = data.split_first() else {
        return;
    };
    let Ok(text) = std::str::from_utf8(text) else {
        return;
    };
    let fast = Settings {
        max_steps: 10_000,
        max_output_lines: 10_000,
        zero_start: flags & 1 != 0,
        strip_comments: flags & 2 != 0,
        // Some runs read lines ahead on a second thread in tiny chunks.
        scan_ahead: if flags & 4 != 0 { 1 + (flags >> 3) as usize } else { 0 },
        ..Settings::default()
    };
    let slow = Settings {
        plain_runs: false,
        ..fast.clone()
    };
    let show = |s: &Settings| match ngcflat::flatten_str(text, s) {
        Ok(out) => out,
        Err(e) => format!("error: {}", render(&e, MessageFormat::Short, false)),
    };
    assert_eq!(show(&fast), show(&slow), "program:\n{text}");
});
