//! Diagnostics: errors and warnings as data, and their rendering.

mod block_error;
mod error;
mod lathe_error;
mod render;
mod report;
mod warning_kind;

pub use block_error::BlockError;
pub use error::{
    ErrorKind, ExprError, LimitError, MachineError, OWordError, ProfileError, SetupError,
    SyntaxError, TargetError,
};
pub use lathe_error::LatheError;
pub use render::{MessageFormat, render, render_summary, use_color};
pub use report::{report, report_summary, write_stderr};
pub use warning_kind::WarningKind;

use std::fmt;
use std::sync::Arc;

use crate::source::SourceFile;

/// A place in a source file: byte offsets from the start of the file. The
/// line and column they are at are worked out when the diagnostic is
/// rendered (a site is small: a program with a million warnings holds a
/// million of them, not a copy of each line).
#[derive(Debug, Clone)]
pub struct Site {
    pub file: Arc<SourceFile>,
    pub start: u32,
    pub end: u32,
}

/// A site's line and column (1-based, columns in characters), its end, and
/// the text of its line.
#[derive(Debug, Clone)]
pub(crate) struct Located {
    pub(crate) file: String,
    pub(crate) line: u32,
    pub(crate) col: u32,
    pub(crate) end_line: u32,
    pub(crate) end_col: u32,
    /// The line as shown: control characters and bytes that are not
    /// UTF-8 escaped (see [`render::shown_line`]).
    pub(crate) text: String,
    /// Blanks as wide as the shown text before the column, for the caret.
    pub(crate) lead: String,
}

impl Site {
    pub fn new(file: &Arc<SourceFile>, start: u32, end: u32) -> Site {
        Site {
            file: Arc::clone(file),
            start,
            end: end.max(start),
        }
    }

    /// 1-based line and column of the start.
    pub fn line_col(&self) -> (u32, u32) {
        let here = self.file.locate(self.start);
        (here.line, here.col)
    }

    /// Line, column, end and line text of the site, read from its file.
    pub(crate) fn located(&self) -> Located {
        let (file, start, end) = (&self.file, self.start, self.end);
        let here = file.locate(start);
        let (end_line, end_col) = if end == start {
            (here.line, here.col)
        } else {
            let there = file.locate(end);
            (there.line, there.col)
        };
        let (text, lead) = render::shown_line(&here.text, here.col);
        Located {
            file: render::shown(&file.display_name()).into_owned(),
            line: here.line,
            col: here.col,
            end_line,
            end_col,
            text,
            lead,
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Level {
    Error,
    Warning,
}

impl fmt::Display for Level {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Level::Error => "error",
            Level::Warning => "warning",
        })
    }
}

#[derive(Debug, Clone)]
pub enum Kind {
    Error(ErrorKind),
    Warning(WarningKind),
}

/// One error or warning with its position and the chain of calls that led
/// there (innermost caller first).
#[derive(Debug, Clone)]
pub struct Diagnostic {
    pub kind: Kind,
    pub site: Option<Site>,
    pub stack: Vec<Site>,
}

/// The error type of the library.
pub type Error = Box<Diagnostic>;

impl Diagnostic {
    pub fn error(kind: ErrorKind, site: Option<Site>) -> Error {
        Box::new(Diagnostic {
            kind: Kind::Error(kind),
            site,
            stack: Vec::new(),
        })
    }

    pub fn warning(kind: WarningKind, site: Option<Site>) -> Diagnostic {
        Diagnostic {
            kind: Kind::Warning(kind),
            site,
            stack: Vec::new(),
        }
    }

    pub fn level(&self) -> Level {
        match self.kind {
            Kind::Error(_) => Level::Error,
            Kind::Warning(_) => Level::Warning,
        }
    }

    pub fn code(&self) -> &'static str {
        match &self.kind {
            Kind::Error(k) => k.code(),
            Kind::Warning(k) => k.code(),
        }
    }

    pub fn message(&self) -> String {
        match &self.kind {
            Kind::Error(k) => k.to_string(),
            Kind::Warning(k) => k.to_string(),
        }
    }

    pub fn error_kind(&self) -> Option<&ErrorKind> {
        match &self.kind {
            Kind::Error(k) => Some(k),
            Kind::Warning(_) => None,
        }
    }
}
