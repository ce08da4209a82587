//! One profile per controller.

pub(crate) mod fluidnc;
pub(crate) mod grbl;
pub(crate) mod grblhal;
pub(crate) mod linuxcnc;
