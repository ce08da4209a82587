//! Geometry computed ahead of time: cutter radius compensation and the
//! moves of lathe cycles.

pub mod comp;
pub(crate) mod lathe;
