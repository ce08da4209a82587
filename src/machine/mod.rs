//! The machine model for what follows evaluation: the state executed lines
//! (typed [`block`]s) put the machine in ([`model`]), the motion they make
//! ([`motion`]), and the machine's axes: travel limits, velocities and
//! accelerations ([`axes`]).

pub(crate) mod axes;
pub use crate::block;
pub(crate) mod model;
pub(crate) mod motion;

pub use block::Block;
pub use model::Machine;
pub(crate) use model::radius_center;
