//! Control flow: O-word blocks, loops, calls and their frames.

pub(super) mod control;
