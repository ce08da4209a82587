//! What is wrong with a target profile file (`--target ./board.toml`): its
//! codes E1004–E1009 and messages. The reader lives with the profiles.

/// What is wrong with a profile file.
#[derive(Debug, Clone, PartialEq)]
pub enum ProfileError {
    /// The file cannot be read (`--target ./nosuch.toml`).
    Unreadable { message: String },
    /// The file is not TOML (`name = grbl`, a string without quotes).
    Syntax { line: usize, message: String },
    /// A key the format does not have (`line_limt = 80`).
    UnknownKey { key: String, line: usize },
    /// A key the format requires is not there.
    MissingKey { key: String },
    /// A key's value is of the wrong type or out of its range
    /// (`line_limit = "80"`, `g_codes = ["G38.7"]`).
    BadValue {
        key: String,
        line: usize,
        message: String,
    },
    /// Keys that do not agree (`arc_turns = true` without G2 and G3; a line
    /// limit of 0; an axis that is not among the words).
    Contradiction { what: String },
}

impl ProfileError {
    pub fn code(&self) -> &'static str {
        match self {
            ProfileError::Unreadable { .. } => "E1009",
            ProfileError::Syntax { .. } => "E1004",
            ProfileError::UnknownKey { .. } => "E1005",
            ProfileError::MissingKey { .. } => "E1006",
            ProfileError::BadValue { .. } => "E1007",
            ProfileError::Contradiction { .. } => "E1008",
        }
    }
}

impl std::fmt::Display for ProfileError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ProfileError::Unreadable { message } => write!(f, "cannot read it: {message}"),
            ProfileError::Syntax { line, message } => {
                write!(f, "line {line}: not a TOML file: {message}")
            }
            ProfileError::UnknownKey { key, line } => write!(
                f,
                "line {line}: unknown key `{key}` (`ngcflat targets --show grbl` prints every key)"
            ),
            ProfileError::MissingKey { key } => write!(
                f,
                "key `{key}` is missing (every key is required; `ngcflat targets --show grbl` prints them)"
            ),
            ProfileError::BadValue { key, line, message } => {
                write!(f, "line {line}: `{key}`: {message}")
            }
            ProfileError::Contradiction { what } => write!(f, "contradiction: {what}"),
        }
    }
}
