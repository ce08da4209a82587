//! What each fuzz target does with one input, shared by the cargo-fuzz
//! targets (`fuzz/fuzz_targets/`) and the short bounded run of the test
//! suite (`tests/integration/fuzz.rs`, stable Rust, no libFuzzer). Each
//! function must return for any input; a panic is a finding.

use std::collections::HashMap;

use ngcflat::controller::{TargetOptions, ToolChange, profiles};
use ngcflat::diag::{MessageFormat, render};
use ngcflat::parse::LineParser;
use ngcflat::settings::Settings;

const FORMATS: [MessageFormat; 4] = [
    MessageFormat::Human,
    MessageFormat::Short,
    MessageFormat::Json,
    MessageFormat::Github,
];

/// Where a subroutine file starts in a `flatten` input.
pub const FILE_MARK: &[u8] = b"\0sub:";

/// The main program and the subroutine files of a `flatten` input.
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

/// `flatten`: two flag bytes (settings; a target controller, its tool
/// change and block delete, a small output bound), the main program, then
/// any number of subroutine files, each `\0sub:NAME\n` and its text.
/// Flattening ends with `Ok` or `Err` within the step and output limits,
/// and every diagnostic renders in every format.
pub fn flatten(data: &[u8]) {
    let (flags, more, text) = match data {
        [f, m, rest @ ..] => (*f, *m, rest),
        _ => return,
    };
    let mut settings = Settings {
        // Small run bounds: a program that loops stops within a
        // millisecond (both guards are still met often), so that a long
        // campaign makes millions of runs.
        max_steps: 2_000,
        max_output_lines: 2_000,
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
    let target = profiles()
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
    // Bit 6: the output, or the target with it, moves to its own thread
    // after a few lines.
    if more & 64 != 0 {
        settings.format_thread_after = 3;
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
}

/// `straight`: a flag byte and a program (UTF-8). The straight-line loop
/// (lines read in place or ahead on a second thread) and the line-by-line
/// path give the same output, or the same error; with the high bit, for
/// the grbl target too (lines read ahead then arrive decoded), diagnostics
/// included.
pub fn straight(data: &[u8]) {
    let Some((&flags, text)) = data.split_first() else {
        return;
    };
    let Ok(text) = std::str::from_utf8(text) else {
        return;
    };
    let fast = Settings {
        // Small run bounds: a program that loops stops within a
        // millisecond (both guards are still met often), so that a long
        // campaign makes millions of runs.
        max_steps: 2_000,
        max_output_lines: 2_000,
        zero_start: flags & 1 != 0,
        strip_comments: flags & 2 != 0,
        // Some runs read lines ahead on a second thread in tiny chunks.
        scan_ahead: if flags & 4 != 0 {
            1 + (flags >> 3) as usize
        } else {
            0
        },
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
    if flags & 0x80 != 0 {
        let grbl = |s: &Settings| {
            let consumer = ngcflat::lowering(s, Some(TargetOptions::new(&profiles()[1])));
            let (diags, r) =
                ngcflat::flatten_memory(text.as_bytes().to_vec(), HashMap::new(), s, consumer);
            let shown: Vec<String> = diags
                .iter()
                .map(|d| render(d, MessageFormat::Short, false))
                .collect();
            let out = match r {
                Ok(o) => String::from_utf8_lossy(&o).into_owned(),
                Err(e) => format!("error: {}", render(&e, MessageFormat::Short, false)),
            };
            (shown, out)
        };
        assert_eq!(grbl(&fast), grbl(&slow), "grbl, program:\n{text}");
    }
}

/// `parse_line`: one raw line, any bytes, with and without a terminating
/// newline: the line parser returns `Ok` or `Err`.
pub fn parse_line(data: &[u8]) {
    let mut parser = LineParser::default();
    let _ = parser.parse(data, false);
    // Reuse the same scratch space, as the file index does.
    let _ = parser.parse(data, true);
    // A line never contains its terminator; feed the part before the first
    // newline as well so long multi-line inputs still reach the grammar.
    if let Some(i) = data.iter().position(|&b| b == b'\n') {
        let _ = parser.parse(&data[..i], true);
    }
}
