//! Reading the source: lines, words and blocks, the plain-line fast paths.

pub(super) mod block;
pub(super) mod fast;
mod scan_ahead;
pub(super) mod straight;
pub(super) mod validate;
