//! Target controllers: writing the flat program in a controller's own
//! language, with the same machine motion, or refusing with the reason.

pub mod lower;
