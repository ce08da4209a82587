//! Flattening one program: reading its source, running the evaluator over
//! it into a destination, optionally through a target's lowering. The
//! library's entry points; the commands (flatten, check, stats, plot) are
//! built on them.

use crate::diag::SetupError;
use std::path::{Path, PathBuf};
use std::rc::Rc;
use std::sync::Arc;

use crate::controller;
use crate::diag::{Diagnostic, Error, ErrorKind};
use crate::emit::{self, Destination, Sink};
use crate::eval::{self, Interp};
use crate::program::{self, FileIndex, Loader, SearchPath, SourceFile};
use crate::settings::Settings;

/// Reads a program from a path (`-` is stdin).
pub fn read_source(path: Option<&Path>) -> Result<SourceFile, Error> {
    read_source_limited(path, program::InputLimits::default())
}

/// [`read_source`] within bounds on size and line length.
pub fn read_source_limited(
    path: Option<&Path>,
    lim: program::InputLimits,
) -> Result<SourceFile, Error> {
    let io_err = |path: PathBuf, e: std::io::Error| {
        Diagnostic::error(
            ErrorKind::Setup(SetupError::Io {
                path,
                message: e.to_string(),
            }),
            None,
        )
    };
    match path {
        Some(p) if p.as_os_str() != "-" => {
            SourceFile::open_limited(p, lim).map_err(|e| io_err(p.to_path_buf(), e))
        }
        _ => SourceFile::read_stream_limited(std::io::stdin().lock(), "<stdin>", lim)
            .map_err(|e| io_err(PathBuf::from("<stdin>"), e)),
    }
}

/// Flattens one program. On success returns the warnings; the output has
/// been released to `dest`. On error nothing was released.
pub fn flatten(
    source: SourceFile,
    settings: &Settings,
    search: &SearchPath,
    dest: Destination,
) -> Result<Vec<Diagnostic>, Error> {
    match flatten_with(source, settings, search, dest, None) {
        (w, None) => Ok(w),
        (_, Some(e)) => Err(e),
    }
}

/// Flattens one program, every output line going through `consumer` when
/// one is given. Returns every diagnostic (a consumer in check mode keeps
/// all its errors) and the error that stopped the run. The output is
/// released only when there is no error.
pub fn flatten_with<'s>(
    source: SourceFile,
    settings: &'s Settings,
    search: &SearchPath,
    dest: Destination,
    consumer: Option<Box<dyn eval::LineConsumer + 's>>,
) -> (Vec<Diagnostic>, Option<Error>) {
    let main_dir = if source.path.as_os_str() == "<stdin>" {
        None
    } else {
        Some(
            source
                .dir()
                .map(Path::to_path_buf)
                .filter(|d| !d.as_os_str().is_empty())
                .unwrap_or_else(|| PathBuf::from(".")),
        )
    };
    let loader = Loader::new(search.clone(), main_dir).named2007(settings.named_params_2007);
    run_with(source, settings, loader, dest, consumer)
}

/// The run behind every flattening entry: `loader` finds the subroutine
/// files, `dest` takes the output.
fn run_with<'s>(
    source: SourceFile,
    settings: &'s Settings,
    loader: Loader,
    dest: Destination,
    consumer: Option<Box<dyn eval::LineConsumer + 's>>,
) -> (Vec<Diagnostic>, Option<Error>) {
    let index = Rc::new(FileIndex::build(
        Arc::new(source),
        settings.named_params_2007,
    ));
    let sink = Sink::new(dest.clone()).map_err(|e| {
        let path = match &dest {
            Destination::File(p) => p.clone(),
            _ => PathBuf::from("<output>"),
        };
        Diagnostic::error(
            ErrorKind::Setup(SetupError::Io {
                path,
                message: e.to_string(),
            }),
            None,
        )
    });
    let mut sink = match sink {
        Ok(s) => s,
        Err(e) => return (Vec::new(), Some(e)),
    };
    sink.limit_bytes(settings.max_output_bytes, index.file.len());
    sink.refer_to(index.file.clone());
    let interp = Interp::new(settings, loader, index, sink);
    match consumer {
        Some(c) => interp.with_consumer(c).run_all(),
        None => interp.run_all(),
    }
}

/// Flattens a program held in memory, named `<string>` in diagnostics:
/// no file is read or written. `files` are its subroutine files (`name` →
/// text, found by `o<name> call`); no folder is searched. The evaluation is
/// the command's, with the output released into memory instead of a file.
/// Returns every diagnostic, and the output or the error that stopped the
/// run.
pub fn flatten_memory<'s>(
    text: Vec<u8>,
    files: std::collections::HashMap<String, Vec<u8>>,
    settings: &'s Settings,
    consumer: Option<Box<dyn eval::LineConsumer + 's>>,
) -> (Vec<Diagnostic>, Result<Vec<u8>, Error>) {
    let src = SourceFile::new(PathBuf::from("<string>"), "<string>".into(), text);
    let loader = Loader::new(SearchPath::default(), None)
        .with_files(files)
        .named2007(settings.named_params_2007);
    let out = emit::MemoryOut::default();
    let (diags, err) = run_with(
        src,
        settings,
        loader,
        Destination::Memory(out.clone()),
        consumer,
    );
    match err {
        Some(e) => (diags, Err(e)),
        None => (diags, Ok(out.take())),
    }
}

/// Flattens a string (for tests and tools); returns the output text.
pub fn flatten_str(text: &str, settings: &Settings) -> Result<String, Error> {
    let (_, r) = flatten_memory(text.as_bytes().to_vec(), Default::default(), settings, None);
    // Comments may carry bytes that are not UTF-8: keep them visible.
    r.map(|out| String::from_utf8_lossy(&out).into_owned())
}

/// The consumer that writes for a target, if one is chosen.
pub fn lowering<'s>(
    settings: &'s Settings,
    target: Option<controller::TargetOptions>,
) -> Option<Box<dyn eval::LineConsumer + 's>> {
    target
        .filter(controller::TargetOptions::active)
        .map(|t| Box::new(controller::Lowering::new(settings, t)) as Box<dyn eval::LineConsumer>)
}

/// Refuses a file that is not text (four or more NUL bytes in its first
/// 8 kB: an image, an archive, a compiled program), so that its bytes never
/// reach a terminal or log in diagnostics. A stray NUL in a comment of a
/// text program does not count; such bytes are shown escaped.
pub fn refuse_binary(source: &SourceFile) -> Result<(), Error> {
    if source.head(8192).iter().filter(|&&b| b == 0).count() >= 4 {
        return Err(Diagnostic::error(
            ErrorKind::Setup(SetupError::NotText {
                path: source.path.clone(),
            }),
            None,
        ));
    }
    Ok(())
}

/// Whether `-o output` names the input program (the same file by device
/// and inode, through any links; `None` or `-` is standard input).
pub(crate) fn same_file(output: &Path, input: Option<&Path>) -> bool {
    use std::os::unix::fs::MetadataExt;
    let input = match input {
        Some(p) if p.as_os_str() != "-" => p,
        _ => Path::new("/dev/stdin"),
    };
    match (std::fs::metadata(output), std::fs::metadata(input)) {
        (Ok(o), Ok(i)) => o.is_file() && o.dev() == i.dev() && o.ino() == i.ino(),
        _ => false,
    }
}
