//! Program structure: source files, their O-word index, and the loader that
//! finds subroutine files.

mod file_index;
pub mod ini;
mod loader;
mod locate;
mod marked_lines;
mod source_file;

pub use file_index::{
    FileIndex, OInfo, ParsedO, SubDef, SubDefInfo, control_key, next_line, not_in_file,
};
pub use loader::{Loader, SearchPath, check_name};
pub use source_file::{IN_MEMORY_LIMIT, InputLimits, SourceFile, Window, WindowLine};
