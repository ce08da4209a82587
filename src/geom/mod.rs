//! Geometry computed ahead of time: cutter radius compensation and the
//! moves of lathe cycles.

pub(crate) mod arc;
pub mod cutter_comp;
pub(crate) mod lathe;
