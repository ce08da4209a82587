//! The output: lines written, their count against the limits, progress, and
//! the consumer that may take them instead.

pub mod hook;
pub(super) mod progress;
