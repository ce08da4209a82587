//! `ngcflat check`: evaluate many programs in parallel and report.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use crate::config::Config;
use crate::diag::{Diagnostic, ErrorKind, Level};
use crate::emit::Destination;
use crate::parse::ast::{LineKind, OKind};
use crate::program::FileIndex;

/// Programs to check: files given directly, and files with a matching
/// extension under given folders (hidden folders skipped, symlink loops
/// reported by walkdir and skipped).
pub fn collect(paths: &[PathBuf], exts: &[String]) -> (Vec<PathBuf>, Vec<Diagnostic>) {
    let mut files = Vec::new();
    let mut problems = Vec::new();
    for p in paths {
        if p.is_dir() {
            let walker = walkdir::WalkDir::new(p)
                .follow_links(true)
                .sort_by_file_name()
                .into_iter()
                .filter_entry(|e| {
                    e.depth() == 0 || !e.file_name().to_str().is_some_and(|n| n.starts_with('.'))
                });
            for entry in walker {
                match entry {
                    Ok(e) => {
                        let ext = e
                            .path()
                            .extension()
                            .and_then(|x| x.to_str())
                            .map(str::to_ascii_lowercase);
                        if e.file_type().is_file()
                            && ext.is_some_and(|x| {
                                exts.iter()
                                    .any(|w| w.trim_start_matches('.').eq_ignore_ascii_case(&x))
                            })
                        {
                            files.push(e.into_path());
                        }
                    }
                    Err(err) => {
                        let path = err
                            .path()
                            .map(Path::to_path_buf)
                            .unwrap_or_else(|| p.clone());
                        problems.push(*Diagnostic::error(
                            ErrorKind::Io {
                                path,
                                message: err.to_string(),
                            },
                            None,
                        ));
                    }
                }
            }
        } else {
            files.push(p.clone());
        }
    }
    (files, problems)
}

/// Whether a file is a subroutine file: its first O-line is `o<name> sub`
/// and nothing but comments and blanks comes before it.
fn sub_file_name(index: &FileIndex) -> Option<String> {
    let first = index.olines.first()?;
    if first.kind() != Some(OKind::Sub) {
        return None;
    }
    if index.first_nonblank.is_some_and(|n| n < first.line_idx) {
        // Only comment lines may come before it.
        let mut parser = crate::parse::LineParser::default();
        let mut only_comments = true;
        let _ = index.file.scan_lines(|idx, _, raw, term| {
            if idx >= first.line_idx || !only_comments {
                return;
            }
            match parser.parse(raw, term) {
                Ok(l) => {
                    if let LineKind::Items(items) = &l.kind
                        && items
                            .iter()
                            .any(|i| !matches!(i, crate::parse::ast::Item::Comment(_)))
                    {
                        only_comments = false;
                    }
                }
                Err(_) => only_comments = false,
            }
        });
        if !only_comments {
            return None;
        }
    }
    // LinuxCNC's rule: name.ngc holds o<name> sub. A program that merely
    // starts with a definition is a program.
    let stem = index
        .file
        .path
        .file_stem()?
        .to_string_lossy()
        .to_ascii_lowercase();
    first
        .key
        .as_ref()
        .filter(|k| k.as_ref() == stem)
        .map(|k| k.to_string())
}

/// Checks one program; returns its diagnostics.
pub fn check_file(path: &Path, cfg: &Config) -> Vec<Diagnostic> {
    let source = match crate::read_source(Some(path)) {
        Ok(s) => s,
        Err(e) => return vec![*e],
    };
    let source = std::sync::Arc::new(source);
    let probe = FileIndex::build(source.clone());
    let mut settings = cfg.settings.clone();
    settings.warnings = true;
    let result = if let Some(name) = sub_file_name(&probe) {
        // A subroutine file: check it by calling it from a tiny program in
        // its own folder.
        let dir = path
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_else(|| PathBuf::from("."));
        let mut search = cfg.search.clone();
        search.dirs.insert(0, dir.clone());
        let nargs = 30;
        let args: String = (0..nargs).map(|_| "[0]").collect::<Vec<_>>().join("");
        let _ = args;
        let text = format!("o<{name}> call\nM2\n");
        let src = crate::program::SourceFile::new(
            dir.join("<check>"),
            format!("<call of {}>", path.display()),
            text.into_bytes(),
        );
        crate::flatten(src, &settings, &search, Destination::Discard)
    } else {
        drop(probe);
        match std::sync::Arc::try_unwrap(source) {
            Ok(source) => crate::flatten(source, &settings, &cfg.search, Destination::Discard),
            Err(_) => return Vec::new(),
        }
    };
    match result {
        Ok(w) => w,
        Err(e) => vec![*e],
    }
}

pub fn run(paths: &[PathBuf], exts: &[String], deny_warnings: bool, cfg: &Config) -> ExitCode {
    let (files, mut problems) = collect(paths, exts);
    let results: Mutex<Vec<(usize, Vec<Diagnostic>)>> = Mutex::new(Vec::new());
    let next = AtomicUsize::new(0);
    let workers = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(2)
        .min(files.len().max(1));
    std::thread::scope(|s| {
        for _ in 0..workers {
            s.spawn(|| {
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(f) = files.get(i) else { break };
                    let d = check_file(f, cfg);
                    results.lock().expect("results").push((i, d));
                }
            });
        }
    });
    let mut results = results.into_inner().expect("results");
    results.sort_by_key(|r| r.0);
    let mut all: Vec<Diagnostic> = Vec::new();
    all.append(&mut problems);
    for (_, mut d) in results {
        all.append(&mut d);
    }
    // A path given on the command line that cannot be read is a usage
    // error (exit 2); problems met while walking folders are errors (1).
    let io_error = paths.iter().any(|p| !p.exists());
    let errors = all.iter().filter(|d| d.level() == Level::Error).count();
    let warnings = all.iter().filter(|d| d.level() == Level::Warning).count();
    crate::report(&all, cfg.format);
    eprintln!(
        "{} files, {} errors, {} warnings",
        files.len(),
        errors,
        warnings
    );
    if io_error {
        ExitCode::from(2)
    } else if errors > 0 || (deny_warnings && warnings > 0) {
        ExitCode::from(1)
    } else {
        ExitCode::SUCCESS
    }
}
