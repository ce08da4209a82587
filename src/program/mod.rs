//! Program structure: source files, their O-word index, and the loader that
//! finds subroutine files.

mod file_index;
pub mod ini;
mod loader;
mod source_file;

pub use file_index::{control_key, next_line, not_in_file, FileIndex, OInfo, SubDefInfo};
pub use loader::{check_name, Loader, SearchPath};
pub use source_file::SourceFile;
