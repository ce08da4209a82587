//! Looking at a program before the machine runs it: statistics, travel
//! limits, the toolpath picture and the source map. Everything here reads
//! the motion stream of [`crate::machine::motion`]; nothing runs unless asked
//! for.

pub mod consumer;
pub mod geom;
pub mod html;
pub mod limits;
pub mod plot;
pub mod run;
pub mod source_map;
pub mod stats;
