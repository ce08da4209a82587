//! One profile per controller.

pub mod grbl;
pub mod linuxcnc;
