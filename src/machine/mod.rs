//! The machine model for what follows evaluation: typed blocks of executed
//! lines ([`block`]), the state they put the machine in ([`model`]), and the
//! motion they make ([`motion`]).

pub mod block;
pub mod model;
pub mod motion;

pub use block::Block;
pub use model::Machine;
