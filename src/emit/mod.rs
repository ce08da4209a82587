//! Output: number formatting, the sink that holds flattened lines until the
//! program is known to be good, and the output that writes into the sink,
//! on a second thread for long evaluated programs.

mod edit;
pub(crate) mod interrupt;
mod output;
mod sink;

pub use crate::number::{max_len, number_string, write_number};
pub use edit::{Edit, max_edited_len, write_edited};
pub use output::Output;
pub use sink::{Destination, MemoryOut, OutputTooLarge, Sink};
