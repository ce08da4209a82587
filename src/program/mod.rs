//! Program structure: the O-word index of source files, and the loader that
//! finds subroutine files.

mod file_index;
pub(crate) mod ini;
mod loader;

pub use crate::source::{IN_MEMORY_LIMIT, InputLimits, SourceFile, Window, WindowLine};
pub use file_index::{
    FileIndex, OInfo, ParsedO, SubDef, SubDefInfo, control_key, next_line, not_in_file,
};
pub use loader::{Loader, SearchPath, check_name};
