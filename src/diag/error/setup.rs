//! The command line, files and what is outside the program.

use std::fmt;
use std::path::PathBuf;

super::phase! {
    /// The command line, files and what is outside the program.
    pub enum SetupError {
        /// A file that cannot be read.
        "E0501" Io { path: PathBuf, message: String },
        /// A var file whose parameter numbers are not ascending.
        "E0503" VarFileOrder { index: i64 },
        /// A var file line that is not `number value`.
        "E0504" VarFileSyntax { text: String },
        /// A `-D` definition that is not `PARAM=VALUE`.
        "E0505" BadDefine { text: String },
        /// Lathe cycle needing a contour sub (`G71 Q...`).
        "E0507" Unsupported { what: String },
        /// A fault of ngcflat itself (a panic caught while checking a file).
        "E0700" Internal { what: String },
        /// `ngcflat -o part.ngc part.ngc` (also through links).
        "E0702" OutputIsInput { output: PathBuf },
        /// `--start-position part.ngc`: not a list of axis words.
        "E0800" BadStartPosition { text: String },
        /// `ngcflat check emptydir`, or an `--ext` that matches nothing.
        "E0802" NoPrograms { paths: Vec<PathBuf>, exts: String },
        /// A file with NUL bytes (an image, an archive, a compiled program).
        "E0803" NotText { path: PathBuf },
        /// A `--user-m` value that is not M100-M199 or a range of them.
        "E0806" BadUserM { text: String },
        /// `--limits X300` (not `LETTER[MIN]:[MAX],...`).
        "E1201" BadLimits { text: String },
        /// `MAX_VELOCITY = fast` in an INI axis section, `$110=x` in GRBL settings.
        "E1202" BadMachineValue { source: String, text: String },
    }
}

impl fmt::Display for SetupError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use SetupError::*;
        match self {
            Io { path, message } => write!(f, "{}: {message}", path.display()),
            VarFileOrder { index } => {
                write!(f, "parameter file is not in ascending order at #{index}")
            }
            VarFileSyntax { text } => {
                write!(f, "parameter file line '{text}' is not 'number value'")
            }
            BadDefine { text } => write!(
                f,
                "-D '{text}' is not PARAM=VALUE (e.g. 5063=-1.25, depth=3, _depth=3)"
            ),
            Unsupported { what } => write!(f, "{what}"),
            Internal { what } => write!(
                f,
                "internal error: {what}; please report it with the program"
            ),
            OutputIsInput { output } => write!(
                f,
                "the output {} is the program being flattened; choose another output file",
                output.display()
            ),
            BadStartPosition { text } => write!(
                f,
                "--start-position '{text}' is not a list of axis words such as X0,Y0,Z10 (mm; X0.5in for inches)"
            ),
            NoPrograms { paths, exts } => no_programs(f, paths, exts),
            NotText { path } => write!(
                f,
                "{}: not a text G-code program (it contains NUL bytes: a binary file?)",
                path.display()
            ),
            BadUserM { text } => write!(
                f,
                "--user-m '{text}' is not a user M-code M100-M199 or a range of them (e.g. 100,101-105)"
            ),
            BadLimits { text } => write!(
                f,
                "--limits '{text}' is not a list of AXIS[MIN]:[MAX] ranges in mm (e.g. X0:300,Y0:200,Z-60:0)"
            ),
            BadMachineValue { source, text } => {
                write!(f, "{source} value '{text}' is not a number")
            }
        }
    }
}

fn no_programs(f: &mut fmt::Formatter<'_>, paths: &[PathBuf], exts: &str) -> fmt::Result {
    write!(f, "no programs found in")?;
    for p in paths {
        write!(f, " {}", p.display())?;
    }
    write!(f, " (extensions {exts}; --ext chooses others)")
}
