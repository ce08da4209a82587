//! A source file: its path and its bytes.

use std::borrow::Cow;
use std::path::{Path, PathBuf};

#[derive(Debug)]
pub struct SourceFile {
    /// Path as given or found (used to read it again for diagnostics).
    pub path: PathBuf,
    /// Name shown in diagnostics.
    pub name: String,
    pub data: Vec<u8>,
}

impl SourceFile {
    pub fn new(path: PathBuf, name: String, data: Vec<u8>) -> SourceFile {
        SourceFile { path, name, data }
    }

    pub fn display_name(&self) -> String {
        self.name.clone()
    }

    pub fn bytes(&self) -> Cow<'_, [u8]> {
        Cow::Borrowed(&self.data)
    }

    /// Folder of the file (for the last step of the subroutine search).
    pub fn dir(&self) -> Option<&Path> {
        self.path.parent()
    }
}
