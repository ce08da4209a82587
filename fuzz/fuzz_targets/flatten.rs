//! A whole program, any bytes, with subroutine files: flattening must end
//! with `Ok` or `Err` within the step and output limits, and rendering the
//! result in every format must not panic either. The run is the command's
//! (`ngcflat::flatten_memory`: same evaluation, output released into
//! memory), so nothing touches the file system.
//!
//! Input: two flag bytes, the main program, then any number of subroutine
//! files, each `\0sub:NAME\n` followed by its text (found by
//! `o<NAME> call`).
#![no_main]

use std::collections::HashMap;

use libfuzzer_sys::fuzz_target;
use ngcflat::diag::{MessageFormat, render};
use ngcflat::eval::Settings;
use ngcflat::target::{PROFILES, TargetOptions, ToolChange};

const FORMATS: [MessageFormat; 4] = [
    MessageFormat::Human,
    MessageFormat::Short,
    MessageFormat::Json,
    MessageFormat::Github,
];

const FILE_MARK: &[u8] = b"\0sub:";

/// The main program and the subroutine files.
fn split(text: &[u8]) -> (Vec<u8>, HashMap<String, Vec<u8>>) {
    let mut parts = Vec::new();
    let mut rest = text;
    while let Some(i) = rest.windows(FILE_MARK.len()).position(|w| w == FILE_MARK) {
        parts.push(&rest[..i]);
        rest = &rest[i + FILE_MARK.len()..];
    }
    parts.push(rest);
    let main = parts[0].to_vec();
    let mut files = HashMap::new();
    for p in &parts[1..] {
        let (name, body) = match p.iter().position(|&b| b == b'\n') {
            Some(i) => (&p[..i], &p[i + 1..]),
            None => (*p, &[][..]),
        };
        files.insert(String::from_utf8_lossy(name).into_owned(), body.to_vec());
    }
    (main, files)
}

fuzz_target!(|data: &[u8]| {
    // The flag bytes pick settings and a target so that they are fuzzed too.
    let (flags, more, text) = match data {
        [f, m, rest @ ..] => (*f, *m, rest),
        _ => return,
    };
    let mut settings = Settings {
        max_steps: 10_000,
        max_output_lines: 10_000,
        zero_start: flags & 1 != 0,
        strip_comments: flags & 2 != 0,
        precision: if flags & 4 != 0 {
            Some(flags >> 5)
        } else {
            None
        },
        fanuc_disabled: flags & 8 != 0,
        oword_nargs: flags & 16 != 0,
        oword_warn_only: flags & 32 != 0,
        retain_g43: flags & 64 != 0,
        ini_vars: flags & 128 == 0,
        ..Settings::default()
    };
    // Low two bits: no target, or one of the others than linuxcnc.
    let target = PROFILES
        .get((more & 3) as usize)
        .filter(|_| more & 3 != 0)
        .map(|p| {
            let mut t = TargetOptions::new(p);
            t.tool_change = match (more >> 2) & 3 {
                1 => Some(ToolChange::Pause),
                2 => Some(ToolChange::Keep),
                3 => Some(ToolChange::Drop),
                _ => None,
            };
            t.block_delete = more & 16 != 0;
            t
        });
    // Bit 5: a small output byte bound, so that it is met often.
    if more & 32 != 0 {
        settings.max_output_bytes = 500 + u64::from(more >> 6) * 4000;
    }
    if target.is_some() {
        // As the command line sets it for a target.
        settings.user_m = (1u128 << 100) - 1;
    }
    let (main, files) = split(text);
    let consumer = ngcflat::lowering(&settings, target);
    let (mut diags, out) = ngcflat::flatten_memory(main, files, &settings, consumer);
    if let Err(e) = out {
        diags.push(*e);
    }
    for d in &diags {
        for f in FORMATS {
            let _ = render(d, f, false);
            let _ = render(d, f, true);
        }
    }
});
