//! ngcflat: LinuxCNC-dialect G-code in, straight-line G-code out.
//!
//! Pipeline: `grammar/ngc.pest` → [`parse`] (typed line AST) → [`program`]
//! (file index, subroutine loader) → [`eval`] (parameters, expressions,
//! control flow) → [`emit`] (numbers, output sink) → [`diag`] (rendering).

pub mod check;
pub mod config;
pub mod diag;
pub mod emit;
pub mod eval;
mod fx_hasher;
pub mod geom;
mod library;
pub mod machine;
mod number;
pub mod parse;
pub mod program;
pub mod source;
pub mod target;
pub mod view;

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::rc::Rc;
use std::sync::Arc;

use diag::{Diagnostic, Error, ErrorKind, MessageFormat};
use emit::{Destination, Sink};
use eval::{Interp, Settings};
use program::{FileIndex, Loader, SearchPath, SourceFile};

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
            ErrorKind::Io {
                path,
                message: e.to_string(),
            },
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
    let loader = Loader::new(search.clone(), main_dir);
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
    let index = Rc::new(FileIndex::build(Arc::new(source)));
    let sink = Sink::new(dest.clone()).map_err(|e| {
        let path = match &dest {
            Destination::File(p) => p.clone(),
            _ => PathBuf::from("<output>"),
        };
        Diagnostic::error(
            ErrorKind::Io {
                path,
                message: e.to_string(),
            },
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
    let loader = Loader::new(SearchPath::default(), None).with_files(files);
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
    target: Option<target::TargetOptions>,
) -> Option<Box<dyn eval::LineConsumer + 's>> {
    target
        .filter(target::TargetOptions::active)
        .map(|t| Box::new(target::Lowering::new(settings, t)) as Box<dyn eval::LineConsumer>)
}

/// `ngcflat targets`: the profiles with their limits.
fn print_targets() -> ExitCode {
    let mut s = String::new();
    for p in target::PROFILES {
        s.push_str(&p.describe());
        s.push('\n');
    }
    print!("{s}");
    ExitCode::SUCCESS
}

/// Writes diagnostics to stderr in the chosen format.
pub fn report(diags: &[Diagnostic], format: MessageFormat) {
    let color = format == MessageFormat::Human
        && diag::use_color(
            std::io::stderr().is_terminal(),
            std::env::var_os("NO_COLOR").as_deref(),
            std::env::var_os("TERM").as_deref(),
        );
    // Written as rendered (a million warnings are not held as one text);
    // failures ignored as in `write_stderr`.
    use std::io::Write;
    let mut err = std::io::BufWriter::with_capacity(1 << 16, std::io::stderr().lock());
    for d in diags {
        if err
            .write_all(diag::render(d, format, color).as_bytes())
            .is_err()
        {
            return;
        }
    }
    let _ = err.flush();
}

/// Writes the summary that ends a run: the JSON summary object (both
/// commands), or for `check` the `N files, E errors, W warnings` line.
pub fn report_summary(
    files: usize,
    errors: usize,
    warnings: usize,
    exit_code: u8,
    format: MessageFormat,
    check: bool,
) {
    write_stderr(&diag::render_summary(
        files, errors, warnings, exit_code, format, check,
    ));
}

/// Progress is shown only when stderr is a terminal that is not `dumb`
/// (never in pipes, files or CI logs), after one second of work.
fn progress_delay() -> Option<std::time::Duration> {
    let term_ok = std::env::var_os("TERM").is_none_or(|t| t != "dumb");
    if !(std::io::stderr().is_terminal() && term_ok) {
        return None;
    }
    let ms = std::env::var("NGCFLAT_TEST_PROGRESS_MS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1000);
    Some(std::time::Duration::from_millis(ms))
}

/// Refuses a file that is not text (four or more NUL bytes in its first
/// 8 kB: an image, an archive, a compiled program), so that its bytes never
/// reach a terminal or log in diagnostics. A stray NUL in a comment of a
/// text program does not count; such bytes are shown escaped.
pub fn refuse_binary(source: &SourceFile) -> Result<(), Error> {
    if source.head(8192).iter().filter(|&&b| b == 0).count() >= 4 {
        return Err(Diagnostic::error(
            ErrorKind::NotText {
                path: source.path.clone(),
            },
            None,
        ));
    }
    Ok(())
}

/// Writes to stderr, ignoring failures: a closed or full stderr must not
/// stop the run (the exit status still tells the outcome).
pub fn write_stderr(s: &str) {
    use std::io::Write;
    let _ = std::io::stderr().lock().write_all(s.as_bytes());
}

fn exit_for(e: &Diagnostic) -> u8 {
    match e.error_kind() {
        Some(ErrorKind::Io { .. } | ErrorKind::NotText { .. }) => 2,
        _ => 1,
    }
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

/// The command-line program.
pub fn run(cli: config::Cli) -> ExitCode {
    emit::interrupt::install();
    match run_cli(cli) {
        Ok(code) => code,
        Err(e) => {
            // Usage and configuration problems: exit status 2.
            write_stderr(&format!("error: {e:#}\n"));
            ExitCode::from(2)
        }
    }
}

fn setup_error(k: ErrorKind, format: MessageFormat, check: bool) -> ExitCode {
    report(&[*Diagnostic::error(k, None)], format);
    report_summary(0, 1, 0, 2, format, check);
    ExitCode::from(2)
}

/// Reports the outcome of flattening one program and gives its exit code.
fn finish_flatten(diags: &[Diagnostic], code: u8, format: MessageFormat) -> ExitCode {
    report(diags, format);
    let errors = diags
        .iter()
        .filter(|d| d.level() == diag::Level::Error)
        .count();
    report_summary(1, errors, diags.len() - errors, code, format, false);
    ExitCode::from(code)
}

/// The CLI edge: configuration problems become `anyhow` errors with context;
/// program problems are diagnostics.
#[expect(
    clippy::too_many_lines,
    reason = "not split yet: its file is being changed"
)]
fn run_cli(cli: config::Cli) -> anyhow::Result<ExitCode> {
    let env_path = std::env::var("NGCFLAT_SUBROUTINE_PATH").ok();
    let common = match &cli.command {
        Some(config::Command::Check(args)) => &args.common,
        Some(config::Command::Stats(args)) => &args.common,
        Some(config::Command::Plot(args)) => &args.common,
        Some(config::Command::Targets) => return Ok(print_targets()),
        _ => &cli.flatten.common,
    };
    parse::named2007::enable(common.named_params_2007);
    let list = |name: Option<String>| name.is_some_and(|n| n.eq_ignore_ascii_case("list"));
    match &cli.command {
        Some(config::Command::Targets) => return Ok(print_targets()),
        Some(config::Command::Check(a)) if list(a.common.target_name()) => {
            return Ok(print_targets());
        }
        None if list(cli.flatten.common.target_name()) => return Ok(print_targets()),
        _ => {}
    }
    match cli.command {
        Some(config::Command::Targets) => Ok(print_targets()),
        Some(cmd @ (config::Command::Completions { .. } | config::Command::Man)) => {
            let mut out = std::io::stdout().lock();
            match config::write_generated(&cmd, &mut out) {
                Ok(_) => Ok(ExitCode::SUCCESS),
                Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(ExitCode::SUCCESS),
                Err(e) => {
                    write_stderr(&format!("ngcflat: writing to stdout: {e}\n"));
                    Ok(ExitCode::from(2))
                }
            }
        }
        Some(config::Command::Check(args)) => {
            let cfg = match args.common.to_config(env_path) {
                Ok(c) => c,
                Err(k) => return Ok(setup_error(k, args.common.format(), true)),
            };
            Ok(check::run(&args.paths, &args.ext, args.deny_warnings, &cfg))
        }
        Some(config::Command::Stats(args)) => {
            let cfg = match args.common.to_config(env_path) {
                Ok(c) => c,
                Err(k) => return Ok(setup_error(k, args.common.format(), false)),
            };
            Ok(view::run::stats_command(
                args.file.as_deref(),
                args.json,
                &cfg,
            ))
        }
        Some(config::Command::Plot(args)) => {
            let cfg = match args.common.to_config(env_path) {
                Ok(c) => c,
                Err(k) => return Ok(setup_error(k, args.common.format(), false)),
            };
            let view = match args.view {
                config::ViewArg::Xy => view::plot::View::Xy,
                config::ViewArg::Xz => view::plot::View::Xz,
                config::ViewArg::Yz => view::plot::View::Yz,
                config::ViewArg::Iso => view::plot::View::Iso,
            };
            Ok(view::run::plot_command(
                args.file.as_deref(),
                &args.output,
                view,
                &cfg,
            ))
        }
        None => {
            let args = cli.flatten;
            let mut cfg = match args.common.to_config(env_path) {
                Ok(c) => c,
                Err(k) => return Ok(setup_error(k, args.common.format(), false)),
            };
            // Configuration warnings come first, counted in the summary.
            let with_config = |mut d: Vec<Diagnostic>| {
                let mut all = cfg.warnings.clone();
                all.append(&mut d);
                all
            };
            let source = match read_source_limited(args.file.as_deref(), cfg.settings.input)
                .and_then(|s| refuse_binary(&s).map(|()| s))
            {
                Ok(s) => s,
                Err(e) => return Ok(finish_flatten(&with_config(vec![*e]), 2, cfg.format)),
            };
            cfg.settings.progress = progress_delay();
            let dest = match args.output {
                Some(p) => {
                    if same_file(&p, args.file.as_deref()) {
                        let k = ErrorKind::OutputIsInput { output: p };
                        return Ok(setup_error(k, cfg.format, false));
                    }
                    Destination::File(p)
                }
                None => Destination::Stdout,
            };
            let consumer = lowering(&cfg.settings, cfg.target.clone());
            if consumer.is_some() && (args.source_map.is_some() || args.annotate) {
                let k = ErrorKind::SourceMapNeedsLinuxcnc;
                return Ok(setup_error(k, cfg.format, false));
            }
            let extras = view::run::Extras {
                source_map: args.source_map,
                annotate: args.annotate,
            };
            let r = match view::run::flatten_chained(
                source,
                &cfg.settings,
                &cfg.search,
                dest,
                &cfg,
                &extras,
                consumer,
            ) {
                (w, None) => Ok(w),
                (_, Some(e)) => Err(e),
            };
            match r {
                Ok(warnings) => Ok(finish_flatten(&with_config(warnings), 0, cfg.format)),
                Err(e) => {
                    let code = exit_for(&e);
                    Ok(finish_flatten(&with_config(vec![*e]), code, cfg.format))
                }
            }
        }
    }
}
