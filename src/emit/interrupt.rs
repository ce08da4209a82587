//! Temporary output files are removed when the run is interrupted (SIGINT,
//! SIGTERM, SIGHUP). The spool of `-o` is the only named temporary file
//! (standard input and the stdout spool are unnamed files, gone with the
//! process however it ends); it is registered here while it exists.
//!
//! [`install`] starts a thread (signal-hook's iterator: the signal handler
//! itself only writes to a pipe) that, on a signal, removes the registered
//! files and ends the process as the signal would have. The evaluator's loops
//! are not touched, so an interrupted run stops at once wherever it is
//! (evaluating, writing the spool, or blocked on a full pipe).

use std::path::{Path, PathBuf};
use std::sync::Mutex;

static FILES: Mutex<Vec<PathBuf>> = Mutex::new(Vec::new());

fn files() -> std::sync::MutexGuard<'static, Vec<PathBuf>> {
    FILES.lock().unwrap_or_else(|e| e.into_inner())
}

/// Removes `path` if the run is interrupted.
pub(crate) fn register(path: &Path) {
    files().push(path.to_path_buf());
}

/// `path` is no longer to be removed.
pub(crate) fn unregister(path: &Path) {
    files().retain(|p| p != path);
}

/// Renames the registered `path` onto `target`; an interruption waits until
/// the rename is done (the output is then complete) or happens before it
/// (the temporary file is removed).
pub(crate) fn persist(path: tempfile::TempPath, target: &Path) -> std::io::Result<()> {
    let mut list = files();
    let from = path.to_path_buf();
    let r = path.persist(target).map_err(|e| e.error);
    list.retain(|p| *p != from);
    r
}

/// Installs the signal thread (command-line use; once).
pub(crate) fn install() {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) else {
            return;
        };
        let _ = std::thread::Builder::new()
            .name("signals".into())
            .spawn(move || {
                if let Some(sig) = signals.forever().next() {
                    for p in files().drain(..) {
                        let _ = std::fs::remove_file(p);
                    }
                    // End as the signal would have (status 128 + signal).
                    let _ = signal_hook::low_level::emulate_default_handler(sig);
                    std::process::exit(128 + sig);
                }
            });
    });
}
