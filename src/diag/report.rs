//! Writing diagnostics and the run's summary to stderr.

use std::io::IsTerminal;

use super::{Diagnostic, MessageFormat, render, render_summary, use_color};

/// Writes diagnostics to stderr in the chosen format.
pub fn report(diags: &[Diagnostic], format: MessageFormat) {
    let color = format == MessageFormat::Human
        && use_color(
            std::io::stderr().is_terminal(),
            std::env::var_os("NO_COLOR").as_deref(),
            std::env::var_os("TERM").as_deref(),
        );
    // Written as rendered (a million warnings are not held as one text);
    // failures ignored as in `write_stderr`.
    use std::io::Write;
    let mut err = std::io::BufWriter::with_capacity(1 << 16, std::io::stderr().lock());
    for d in diags {
        if err.write_all(render(d, format, color).as_bytes()).is_err() {
            return;
        }
    }
    let _ = err.flush();
}

/// Writes the summary that ends a run: the JSON summary object (both
/// commands), or for `check` the `N files, E errors, W warnings` line.
pub fn report_summary(
    files: usize,
    errors: usize,
    warnings: usize,
    exit_code: u8,
    format: MessageFormat,
    check: bool,
) {
    write_stderr(&render_summary(
        files, errors, warnings, exit_code, format, check,
    ));
}

/// Writes to stderr, ignoring failures: a closed or full stderr must not
/// stop the run (the exit status still tells the outcome).
pub fn write_stderr(s: &str) {
    use std::io::Write;
    let _ = std::io::stderr().lock().write_all(s.as_bytes());
}
