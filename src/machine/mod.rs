//! The machine model for what follows evaluation: the state executed lines
//! (typed [`crate::block`]s) put the machine in ([`model`]), the motion they make
//! ([`motion`]), and the machine's axes: travel limits, velocities and
//! accelerations ([`axes`]), and a GRBL `$$` listing's planner settings
//! ([`grbl_listing`]).

pub(crate) mod axes;
pub(crate) mod grbl_listing;
pub(crate) mod model;
pub(crate) mod motion;

pub(crate) use model::FlatMachine;
pub(crate) use model::radius_center;
