//! Looking at a program before the machine runs it: statistics, travel
//! limits, the toolpath picture and the source map. Everything here reads
//! the motion stream of [`crate::machine::motion`]; nothing runs unless asked
//! for.

pub(crate) mod consumer;
pub(crate) mod geom;
pub(crate) mod html;
pub(crate) mod limits;
pub(crate) mod plot;
pub(crate) mod run;
pub(crate) mod scene;
pub(crate) mod source_map;
pub(crate) mod stats;
