//! One profile per controller.

pub mod fluidnc;
pub mod grbl;
pub mod grblhal;
pub mod linuxcnc;
