//! `ngcflat check`: evaluate many programs in parallel and report.

use crate::diag::SetupError;
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
pub(crate) fn collect(paths: &[PathBuf], exts: &[String]) -> (Vec<PathBuf>, Vec<Diagnostic>) {
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
                            ErrorKind::Setup(SetupError::Io {
                                path,
                                message: err.to_string(),
                            }),
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
        let mut parser = index.parser();
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
    index
        .key(0)
        .filter(|k| AsRef::<str>::as_ref(&***k) == stem.as_str())
        .map(|k| k.to_string())
}

/// A plain run's result in the form of a consumer run's.
fn observed(
    r: Result<Vec<Diagnostic>, crate::diag::Error>,
) -> (Vec<Diagnostic>, Option<crate::diag::Error>) {
    match r {
        Ok(w) => (w, None),
        Err(e) => (Vec::new(), Some(e)),
    }
}

/// Checks one program; returns its diagnostics.
pub(crate) fn check_file(path: &Path, cfg: &Config) -> Vec<Diagnostic> {
    let opened = if path.as_os_str() == "-" {
        crate::flatten::read_source_limited(None, cfg.settings.input)
    } else {
        crate::program::SourceFile::open_regular(path, cfg.settings.input).map_err(|e| {
            Diagnostic::error(
                ErrorKind::Setup(SetupError::Io {
                    path: path.to_path_buf(),
                    message: e.to_string(),
                }),
                None,
            )
        })
    };
    let source = match opened.and_then(|s| crate::flatten::refuse_binary(&s).map(|()| s)) {
        Ok(s) => s,
        Err(e) => return vec![*e],
    };
    let source = std::sync::Arc::new(source);
    let probe = FileIndex::build(source.clone(), cfg.settings.named_params_2007);
    let mut settings = cfg.settings.clone();
    settings.warnings = true;
    if sub_file_name(&probe).is_some() {
        // A subroutine library: checked for what is known without a
        // caller; its callers report the rest.
        drop(probe);
        return crate::library::check_library(source, &settings, &cfg.search);
    }
    drop(probe);
    let target = cfg.target.clone().map(|mut t| {
        t.check = true;
        t
    });
    let result = match std::sync::Arc::try_unwrap(source) {
        Ok(source) => match crate::flatten::lowering(&settings, target) {
            Some(consumer) => crate::view::run::flatten_chained(
                source,
                &settings,
                &cfg.search,
                Destination::Discard,
                cfg,
                &Default::default(),
                Some(consumer),
            ),
            None => observed(crate::view::run::flatten_observed(
                source,
                &settings,
                &cfg.search,
                Destination::Discard,
                cfg,
                &Default::default(),
            )),
        },
        Err(_) => return Vec::new(),
    };
    match result {
        (w, None) => w,
        (mut w, Some(e)) => {
            // Target problems found before the error come first; the
            // lowering may have found the same error at the same place (it
            // checks arcs again with the positions it knows): it is
            // reported once.
            let site = |d: &Diagnostic| d.site.as_ref().map(|s| (s.file.path.clone(), s.start));
            w.retain(|d| {
                d.level() == Level::Error && !(d.code() == e.code() && site(d) == site(&e))
            });
            w.push(*e);
            w
        }
    }
}

/// [`check_file`], with a fault of ngcflat itself (a panic) reported as an
/// internal error of that file, so that one file cannot stop the run.
fn check_file_guarded(path: &Path, cfg: &Config) -> Vec<Diagnostic> {
    let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        if std::env::var_os("NGCFLAT_TEST_PANIC").is_some_and(|n| path.ends_with(n)) {
            panic!("test fault");
        }
        check_file(path, cfg)
    }));
    r.unwrap_or_else(|_| {
        let what = LAST_PANIC
            .with(|p| p.borrow_mut().take())
            .unwrap_or_else(|| "a panic".into());
        vec![*Diagnostic::error(
            ErrorKind::Setup(SetupError::Internal {
                what: format!("{what} while checking {}", path.display()),
            }),
            None,
        )]
    })
}

thread_local! {
    /// The message and place of the last panic on this thread.
    static LAST_PANIC: std::cell::RefCell<Option<String>> = const { std::cell::RefCell::new(None) };
}

/// Runs `f` with panics recorded for [`check_file_guarded`] instead of
/// printed.
fn with_quiet_panics<T>(f: impl FnOnce() -> T) -> T {
    let prev = std::panic::take_hook();
    std::panic::set_hook(Box::new(|info| {
        let msg = info
            .payload()
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| info.payload().downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "a panic".into());
        let at = info
            .location()
            .map(|l| format!(" at {}:{}", l.file(), l.line()))
            .unwrap_or_default();
        LAST_PANIC.with(|p| *p.borrow_mut() = Some(format!("'{msg}'{at}")));
    }));
    let r = f();
    std::panic::set_hook(prev);
    r
}

/// What `check` was asked for.
pub(super) struct Job {
    /// Programs or folders (walked recursively).
    paths: Vec<PathBuf>,
    /// File extensions checked in folders.
    exts: Vec<String>,
    /// Whether a warning fails the check too.
    deny_warnings: bool,
}

impl From<super::args::CheckArgs> for Job {
    fn from(a: super::args::CheckArgs) -> Job {
        Job {
            paths: a.paths,
            exts: a.ext,
            deny_warnings: a.deny_warnings,
        }
    }
}

pub(super) fn run(job: &Job, cfg: &Config) -> ExitCode {
    let (paths, exts, deny_warnings) = (&job.paths, &job.exts, job.deny_warnings);
    let (files, mut problems) = collect(paths, exts);
    let results: Mutex<Vec<(usize, Vec<Diagnostic>)>> = Mutex::new(Vec::new());
    let next = AtomicUsize::new(0);
    let workers = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(2)
        .min(files.len().max(1));
    with_quiet_panics(|| {
        std::thread::scope(|s| {
            for _ in 0..workers {
                s.spawn(|| {
                    loop {
                        let i = next.fetch_add(1, Ordering::Relaxed);
                        let Some(f) = files.get(i) else { break };
                        let d = check_file_guarded(f, cfg);
                        results
                            .lock()
                            .unwrap_or_else(|e| e.into_inner())
                            .push((i, d));
                    }
                });
            }
        })
    });
    let mut results = results.into_inner().unwrap_or_else(|e| e.into_inner());
    results.sort_by_key(|r| r.0);
    let mut all: Vec<Diagnostic> = cfg.warnings.clone();
    let problems_empty = problems.is_empty();
    all.append(&mut problems);
    for (_, mut d) in results {
        all.append(&mut d);
    }
    if files.is_empty() && problems_empty {
        all.push(*Diagnostic::error(
            ErrorKind::Setup(SetupError::NoPrograms {
                paths: paths.to_vec(),
                exts: exts.join(","),
            }),
            None,
        ));
    }
    // A file or folder that cannot be read (given directly or met in a
    // folder, a dangling symlink included) and finding no programs at all
    // are I/O errors: exit 2, as for flattening.
    let io_error = all.iter().any(|d| {
        matches!(
            d.error_kind(),
            Some(
                ErrorKind::Setup(SetupError::Io { .. })
                    | ErrorKind::Setup(SetupError::NoPrograms { .. })
                    | ErrorKind::Setup(SetupError::NotText { .. })
            )
        )
    });
    let errors = all.iter().filter(|d| d.level() == Level::Error).count();
    let warnings = all.iter().filter(|d| d.level() == Level::Warning).count();
    let code = if io_error {
        2
    } else if errors > 0 || (deny_warnings && warnings > 0) {
        1
    } else {
        0
    };
    crate::diag::report(&all, cfg.format);
    crate::diag::report_summary(files.len(), errors, warnings, code, cfg.format, true);
    ExitCode::from(code)
}
