//! The machine model for what follows evaluation: typed blocks of executed
//! lines, the state they put the machine in, and the motion they make.

pub mod motion;
