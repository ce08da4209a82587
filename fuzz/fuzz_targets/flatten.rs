//! A whole program, any bytes: flattening must end with `Ok` or `Err` within
//! the step and output limits, and rendering the result in every format must
//! not panic either.
#![no_main]

use std::path::PathBuf;

use libfuzzer_sys::fuzz_target;
use ngcflat::diag::{MessageFormat, render};
use ngcflat::emit::Destination;
use ngcflat::eval::Settings;
use ngcflat::program::{SearchPath, SourceFile};

const FORMATS: [MessageFormat; 4] = [
    MessageFormat::Human,
    MessageFormat::Short,
    MessageFormat::Json,
    MessageFormat::Github,
];

fuzz_target!(|data: &[u8]| {
    // The first byte picks a few settings so that they are fuzzed too.
    let (flags, text) = match data.split_first() {
        Some((f, rest)) => (*f, rest),
        None => (0, data),
    };
    let settings = Settings {
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
    // Named like stdin so that no folder is searched for subroutine files:
    // the target never touches the file system.
    let source = SourceFile::new(
        PathBuf::from("<stdin>"),
        "<stdin>".to_string(),
        text.to_vec(),
    );
    let diags = match ngcflat::flatten(
        source,
        &settings,
        &SearchPath::default(),
        Destination::Discard,
    ) {
        Ok(warnings) => warnings,
        Err(e) => vec![*e],
    };
    for d in &diags {
        for f in FORMATS {
            let _ = render(d, f, false);
            let _ = render(d, f, true);
        }
    }
});
