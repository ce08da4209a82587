//! Progress on a terminal for long runs: lines written, the input line
//! reached and the time so far, on stderr, at most four times a second.
//! The evaluator calls [`Progress::tick`] only every few thousand output
//! lines (its output-limit check doubles as the trigger), so a run without
//! progress, and one with it, pay nothing per line.

use std::io::Write;
use std::time::{Duration, Instant};

/// How many output lines pass between two looks at the clock.
pub(crate) const EVERY: u64 = 4096;

pub(crate) struct Progress {
    start: Instant,
    /// Nothing is shown before this much time has passed (short runs stay
    /// quiet).
    delay: Duration,
    last: Option<Instant>,
}

impl Progress {
    pub(crate) fn new(delay: Duration) -> Progress {
        Progress {
            start: Instant::now(),
            delay,
            last: None,
        }
    }

    /// Shows the state if enough time has passed since the last update.
    pub(crate) fn tick(&mut self, lines: u64, input_line: u32, file: &str) {
        let now = Instant::now();
        let elapsed = now.duration_since(self.start);
        if elapsed < self.delay
            || self
                .last
                .is_some_and(|l| now.duration_since(l) < Duration::from_millis(250))
        {
            return;
        }
        self.last = Some(now);
        let text = format!(
            "\r\x1b[Kngcflat: {lines} lines written, at line {input_line} of {file}, {:.1} s",
            elapsed.as_secs_f64()
        );
        let _ = std::io::stderr().lock().write_all(text.as_bytes());
    }

    /// Clears the progress line, if one was shown.
    pub(crate) fn clear(&self) {
        if self.last.is_some() {
            let _ = std::io::stderr().lock().write_all(b"\r\x1b[K");
        }
    }
}
