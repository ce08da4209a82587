//! The machine model for what follows evaluation: typed blocks of executed
//! lines ([`block`]), the state they put the machine in ([`model`]), the
//! motion they make ([`motion`]), and the machine's axes: travel limits,
//! velocities and accelerations ([`axes`]).

pub(crate) mod axes;
pub mod block;
pub(crate) mod model;
pub(crate) mod motion;

pub use block::Block;
pub use model::Machine;
