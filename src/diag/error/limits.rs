//! Runaway guards, what the output can hold, and travel limits.

use std::fmt;

super::phase! {
    /// Runaway guards, what the output can hold, and travel limits.
    pub enum LimitError {
        /// An output line longer than 252 characters after substitution.
        "E0401" OutputLineTooLong { len: usize },
        /// `o1 while [1]` ... `o1 endwhile` with no exit.
        "E0402" StepLimit {
            limit: u64,
            label: Option<String>,
            line: Option<u32>,
        },
        /// A loop that writes more lines than `--max-output-lines`.
        "E0403" OutputLimit {
            limit: u64,
            label: Option<String>,
            line: Option<u32>,
        },
        /// A loop of long lines writing more than `--max-output-bytes`.
        "E0703" OutputBytesLimit { limit: u64 },
        /// A value that cannot be written as a G-code number.
        "E0404" Unprintable { value: f64 },
        /// An O-line read again when it runs is no longer the O-line the index
        /// found (the file changed during the run).
        "E0405" ProgramChanged { line: u32 },
        /// A move beyond a travel limit (machine coordinates).
        "E1203" TravelLimit {
            axis: char,
            value: f64,
            bound: f64,
            above: bool,
            source: String,
        },
        /// Travel limits are given but the offsets from work to machine
        /// coordinates (or the position) are not known at a move.
        "E1204" LimitNeedsOffsets,
    }
}

impl fmt::Display for LimitError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use LimitError::*;
        match self {
            OutputLineTooLong { len } => {
                write!(
                    f,
                    "output line would be {len} characters; the limit is 252 (try --precision)"
                )
            }
            StepLimit { limit, label, line } => runaway(
                f,
                format_args!("more than {limit} O-word lines executed; runaway loop or recursion?"),
                label,
                line,
                "--max-steps",
            ),
            OutputLimit { limit, label, line } => runaway(
                f,
                format_args!("more than {limit} output lines"),
                label,
                line,
                "--max-output-lines",
            ),
            OutputBytesLimit { limit } => write!(
                f,
                "the output grew past {limit} bytes (the program's size plus --max-output-bytes); runaway loop? (raise with --max-output-bytes)"
            ),
            Unprintable { value } => {
                write!(f, "value {value} cannot be written as a G-code number")
            }
            ProgramChanged { line } => write!(
                f,
                "the program changed while it was run: line {line} is no longer the O-word line it was when the file was read"
            ),
            TravelLimit {
                axis,
                value,
                bound,
                above,
                source,
            } => {
                let unit = if matches!(axis, 'A' | 'B' | 'C') {
                    "deg"
                } else {
                    "mm"
                };
                write!(
                    f,
                    "this move takes {axis} to {} {unit} (machine coordinates), {} the travel limit {} {unit} from {source}",
                    crate::number::number_string(*value, Some(4)),
                    if *above { "above" } else { "below" },
                    crate::number::number_string(*bound, Some(4)),
                )
            }
            LimitNeedsOffsets => write!(
                f,
                "travel limits are in machine coordinates, but where this move goes on the machine is not known (the offsets from work to machine coordinates, or the position); supply them with --zero-start, --var-file or -D (e.g. -D 5221=0 for the G54 X offset) and --start-position, or turn the check off with --no-limits"
            ),
        }
    }
}

/// A runaway guard's message: what passed the bound, the innermost loop,
/// and the option that raises it.
fn runaway(
    f: &mut fmt::Formatter<'_>,
    what: fmt::Arguments<'_>,
    label: &Option<String>,
    line: &Option<u32>,
    option: &str,
) -> fmt::Result {
    f.write_fmt(what)?;
    limit_site(f, label, line)?;
    write!(f, " (raise with {option})")
}

fn limit_site(
    f: &mut fmt::Formatter<'_>,
    label: &Option<String>,
    line: &Option<u32>,
) -> fmt::Result {
    match (label, line) {
        (Some(l), Some(n)) => write!(f, " (innermost loop: o{l} at line {n})"),
        (Some(l), None) => write!(f, " (innermost loop: o{l})"),
        _ => Ok(()),
    }
}
