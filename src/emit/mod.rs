//! Output: number formatting and the sink that holds flattened lines until
//! the program is known to be good.

mod number;
mod sink;

pub use number::{number_string, write_number};
pub use sink::{Destination, Sink};
