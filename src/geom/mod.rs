//! Geometry computed ahead of time: cutter radius compensation.

pub mod comp;
