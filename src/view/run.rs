//! Running a program for what the `stats` and `plot` commands show, and the
//! per-move consumer that flattening and `check` use for travel limits.

use super::limits::LimitCheck;
use super::plot::{Plot, View};
use super::scene::{LineMeta, Scene};
use super::source_map::NoteRules;
use super::stats::Stats;
use crate::diag::ErrorKind;
use crate::diag::{LimitError, SetupError};
use crate::machine::axes::MachineAxes;
use crate::machine::motion::Motion;

/// Everything that looks at the motion stream of one run. Only what was
/// asked for is present.
#[derive(Debug, Default)]
pub(crate) struct Observer {
    pub stats: Option<Stats>,
    pub plot: Option<Plot>,
    pub limits: Option<LimitCheck>,
    /// The interactive page's scene, timed by `stats`.
    pub scene: Option<Scene>,
    /// Travel limits the scene marks moves against (the run goes on).
    pub scene_limits: Option<LimitCheck>,
    /// Lines waiting for their planned time before the scene gets them.
    held: std::collections::VecDeque<HeldLine>,
    lines: u64,
}

/// An output line whose planned time is not final yet, with its motion.
#[derive(Debug)]
struct HeldLine {
    meta: LineMeta,
    /// Each event, whether it was timed, and the travel-limit violation it
    /// makes.
    events: Vec<(Motion, bool, Option<String>)>,
}

impl Observer {
    /// For flattening and `check`: the travel-limit check only.
    pub(crate) fn limits(axes: &MachineAxes) -> Observer {
        Observer {
            limits: LimitCheck::new(axes),
            ..Observer::default()
        }
    }

    /// For `stats` (and `plot` with `view`), timing the program with the
    /// planner of `target` (`None`: LinuxCNC).
    pub(crate) fn stats(axes: &MachineAxes, target: Option<&str>, view: Option<View>) -> Observer {
        Observer {
            stats: Some(Stats::new(
                axes.clone(),
                crate::runtime::TimeModel::for_target(target, axes),
            )),
            plot: view.map(Plot::new),
            ..Observer::default()
        }
    }

    /// For the interactive page: statistics and the scene, with moves
    /// outside the travel limits marked.
    pub(crate) fn scene(axes: &MachineAxes, target: Option<&str>) -> Observer {
        Observer {
            stats: Some(Stats::new(
                axes.clone(),
                crate::runtime::TimeModel::for_target(target, axes),
            )),
            scene: Some(Scene::default()),
            scene_limits: LimitCheck::new(axes),
            ..Observer::default()
        }
    }

    /// Whether anything needs the motion at all.
    pub(crate) fn is_active(&self) -> bool {
        self.stats.is_some() || self.plot.is_some() || self.limits.is_some() || self.scene.is_some()
    }

    /// The output line whose motion comes next (for the scene, which
    /// gets each line once the run-time model has fixed its time).
    pub(crate) fn line(&mut self, text: &[u8], origin: &crate::eval::Origin<'_>) {
        let Some(s) = &mut self.scene else {
            return;
        };
        let meta = s.line_meta(text, origin);
        self.release_lines();
        self.lines += 1;
        if let Some(st) = &mut self.stats {
            st.run_time.line(self.lines);
        }
        self.held.push_back(HeldLine {
            meta,
            events: Vec::new(),
        });
    }

    /// The end of the run: the scene gets the lines still held.
    pub(crate) fn finish(&mut self) {
        if self.scene.is_none() {
            return;
        }
        if let Some(st) = &mut self.stats {
            st.run_time.finish();
        }
        self.release_lines();
        // Lines the model gave no time (none timed the run).
        while let Some(h) = self.held.pop_front() {
            self.replay(h, None);
        }
        if let (Some(scene), Some(st)) = (&mut self.scene, &self.stats) {
            scene.set_clock(st.total_time());
        }
    }

    /// Hands the scene the held lines whose time is final.
    fn release_lines(&mut self) {
        loop {
            let Some(t) = self.stats.as_mut().and_then(|s| s.run_time.next_line()) else {
                return;
            };
            let Some(h) = self.held.pop_front() else {
                return;
            };
            self.replay(h, Some(t));
        }
    }

    /// One line for the scene: its moves share the line's time by their
    /// lengths (a line of one move, the common case, gets it all).
    fn replay(&mut self, h: HeldLine, time: Option<crate::runtime::LineTime>) {
        let Some(scene) = &mut self.scene else {
            return;
        };
        let length = |m: &Motion| match m {
            Motion::Line { from, to, .. } => super::geom::line_length(&from.work, &to.work),
            Motion::Arc {
                from,
                to,
                center,
                plane,
                ccw,
                turns,
                ..
            } => {
                let g = super::geom::ArcGeom::new(
                    &from.work,
                    &to.work,
                    *center,
                    *plane,
                    *ccw,
                    *turns,
                    crate::geom::arc::FullCircle::Exact,
                );
                super::geom::arc_length(&g, &from.work, &to.work)
            }
            _ => 0.0,
        };
        let moves = |m: &Motion| matches!(m, Motion::Line { .. } | Motion::Arc { .. });
        let lengths: Vec<f64> = h
            .events
            .iter()
            .map(|(m, ..)| {
                let l = length(m);
                if l.is_finite() { l } else { 0.0 }
            })
            .collect();
        let total: f64 = lengths.iter().sum();
        let count = h.events.iter().filter(|(m, ..)| moves(m)).count();
        let seconds = time.map_or(0.0, |t| t.seconds);
        if let Some(t) = time {
            scene.set_clock(t.start);
        }
        scene.set_line(h.meta);
        for ((m, timed, violation), len) in h.events.into_iter().zip(lengths) {
            let dur = if !moves(&m) {
                0.0
            } else if total > 0.0 {
                seconds * len / total
            } else {
                seconds / count as f64
            };
            scene.add(&m, dur, timed, violation);
        }
    }

    /// Feeds one motion event; an error stops the run at the line that
    /// made it.
    pub(crate) fn motion(&mut self, m: &Motion) -> Result<(), ErrorKind> {
        if let Some(l) = &self.limits {
            l.check(m)?;
        }
        let before = self.stats.as_ref().map(|s| s.untimed());
        if let Some(s) = &mut self.stats {
            s.add(m);
        }
        if let Some(scene) = &mut self.scene {
            let timed = match (before, &self.stats) {
                (Some(u), Some(s)) => s.untimed() == u,
                _ => false,
            };
            let violation = match self.scene_limits.as_ref().map(|l| l.check(m)) {
                Some(Err(ErrorKind::Limit(LimitError::LimitNeedsOffsets))) => {
                    scene.detail.limits_unchecked += 1;
                    None
                }
                Some(Err(e)) => Some(e.to_string()),
                _ => None,
            };
            match self.held.back_mut() {
                Some(h) => h.events.push((m.clone(), timed, violation)),
                // Motion before any line (none in practice): untimed.
                None => scene.add(m, 0.0, timed, violation),
            }
        }
        if let Some(p) = &mut self.plot {
            p.add(m);
        }
        Ok(())
    }
}

/// Writes `data` to `path` atomically (a temporary file beside it, then a
/// rename), so that a failed run leaves the old file.
pub(crate) fn write_atomic(path: &std::path::Path, data: &[u8]) -> std::io::Result<()> {
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(std::path::Path::new("."));
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = dir.join(format!(".{name}.{}.tmp", std::process::id()));
    std::fs::write(&tmp, data)?;
    std::fs::rename(&tmp, path).inspect_err(|_| {
        let _ = std::fs::remove_file(&tmp);
    })
}

/// Runs a program and feeds its motion to `observer` (nothing is written);
/// with a target, the motion of the program as lowered for it.
/// Returns the warnings.
pub(crate) fn observe(
    source: crate::program::SourceFile,
    cfg: &crate::config::Config,
    observer: &mut Observer,
) -> Result<Vec<crate::diag::Diagnostic>, crate::diag::Error> {
    let view =
        super::consumer::ViewConsumer::new(&cfg.settings, observer, false, None, false, None);
    // With a target, what its controller receives: the lowered lines.
    let consumer: Box<dyn crate::eval::LineConsumer + '_> =
        match crate::flatten::lowering(&cfg.settings, cfg.target.clone()) {
            Some(lower) => Box::new(super::consumer::Lowered::new(lower, view)),
            None => Box::new(view),
        };
    match crate::flatten::flatten_with(
        source,
        &cfg.settings,
        &cfg.search,
        crate::emit::Destination::Discard,
        Some(consumer),
    ) {
        (w, None) => Ok(w),
        (_, Some(e)) => Err(e),
    }
}

/// The name of the target a program is written for (`None`: LinuxCNC).
pub(crate) fn target_name(cfg: &crate::config::Config) -> Option<&str> {
    cfg.target.as_ref().map(|t| t.profile.name.as_str())
}

pub(crate) fn program_name(file: Option<&std::path::Path>) -> String {
    match file {
        Some(p) if p.as_os_str() != "-" => p.display().to_string(),
        _ => "<stdin>".into(),
    }
}

/// Runs a program for its statistics (and picture). Err is the exit code
/// after the diagnostics were reported.
pub(crate) fn run_for_view(
    file: Option<&std::path::Path>,
    cfg: &crate::config::Config,
    mut observer: Observer,
) -> Result<(Observer, Vec<crate::diag::Diagnostic>), std::process::ExitCode> {
    let source = match crate::flatten::read_source(file) {
        Ok(s) => s,
        Err(e) => {
            crate::diag::report(&[*e], cfg.format);
            return Err(std::process::ExitCode::from(2));
        }
    };
    match observe(source, cfg, &mut observer) {
        Ok(warnings) => {
            observer.finish();
            crate::diag::report(&warnings, cfg.format);
            Ok((observer, warnings))
        }
        Err(e) => {
            let code = match e.error_kind() {
                Some(ErrorKind::Setup(SetupError::Io { .. })) => 2,
                _ => 1,
            };
            crate::diag::report(&[*e], cfg.format);
            Err(std::process::ExitCode::from(code))
        }
    }
}

/// What flattening may be asked for besides the output.
#[derive(Debug, Clone, Default)]
pub(crate) struct Extras {
    /// Write a source map (JSON lines) to this file.
    pub source_map: Option<std::path::PathBuf>,
    /// Append each line's origin as a comment.
    pub annotate: bool,
}

/// Flattens like [`crate::flatten::flatten`], checking travel limits when the
/// configuration has them and writing the source map and annotations when
/// asked. Without any of these it is exactly [`crate::flatten::flatten`].
pub(crate) fn flatten_observed(
    source: crate::program::SourceFile,
    settings: &crate::settings::Settings,
    search: &crate::program::SearchPath,
    dest: crate::emit::Destination,
    cfg: &crate::config::Config,
    extras: &Extras,
) -> Result<Vec<crate::diag::Diagnostic>, crate::diag::Error> {
    match flatten_chained(source, settings, search, dest, cfg, extras, None) {
        (w, None) => Ok(w),
        (_, Some(e)) => Err(e),
    }
}

/// [`flatten_observed`] in front of `next`, the consumer that writes the
/// output for a target controller (it sees every line after the limit
/// check). Returns every diagnostic and the error that stopped the run, as
/// [`crate::flatten::flatten_with`]. With `next`, the source map and the
/// annotations are those of the lines `next` writes (each mapped to the
/// program line it was lowered from), timed by the target's planner, the
/// annotations within what the target's profile allows.
pub(crate) fn flatten_chained<'s>(
    source: crate::program::SourceFile,
    settings: &'s crate::settings::Settings,
    search: &crate::program::SearchPath,
    dest: crate::emit::Destination,
    cfg: &crate::config::Config,
    extras: &Extras,
    next: Option<Box<dyn crate::eval::LineConsumer + 's>>,
) -> (Vec<crate::diag::Diagnostic>, Option<crate::diag::Error>) {
    if !cfg.check_limits && extras.source_map.is_none() && !extras.annotate {
        return crate::flatten::flatten_with(source, settings, search, dest, next);
    }
    let mut lowered_observer = Observer::default();
    let mut observer = if cfg.check_limits {
        Observer::limits(&cfg.machine)
    } else {
        Observer::default()
    };
    let io_err = |path: &std::path::Path, e: std::io::Error| {
        crate::diag::Diagnostic::error(
            ErrorKind::Setup(SetupError::Io {
                path: path.to_path_buf(),
                message: e.to_string(),
            }),
            None,
        )
    };
    // The source map goes to a temporary file beside its target, renamed
    // into place only when the program flattened.
    let map_tmp = extras.source_map.as_ref().map(|p| {
        let dir = p
            .parent()
            .filter(|d| !d.as_os_str().is_empty())
            .unwrap_or(std::path::Path::new("."));
        let name = p
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        (
            p.clone(),
            dir.join(format!(".{name}.{}.tmp", std::process::id())),
        )
    });
    let map = match &map_tmp {
        Some((target, tmp)) => match std::fs::File::create(tmp) {
            Ok(f) => Some(super::source_map::SourceMap::new(std::io::BufWriter::new(
                f,
            ))),
            Err(e) => return (Vec::new(), Some(io_err(target, e))),
        },
        None => None,
    };
    // Each line's planned time by the target's planner (no target:
    // LinuxCNC's, or GRBL's when a `$$` listing says the machine runs it).
    let timing = crate::runtime::TimeModel::for_target(target_name(cfg), &cfg.machine);
    let consumer = match next {
        None => super::consumer::ViewConsumer::new(
            settings,
            &mut observer,
            true,
            map,
            extras.annotate,
            Some(timing),
        ),
        // The limits are checked on the program's lines; the map, the
        // annotations and the times follow the lines the target gets.
        Some(lower) => {
            let rules = cfg
                .target
                .as_ref()
                .map_or_else(NoteRules::linuxcnc, |t| NoteRules::for_profile(t.profile));
            let view = super::consumer::ViewConsumer::new(
                settings,
                &mut lowered_observer,
                true,
                map,
                extras.annotate,
                Some(timing),
            )
            .with_notes(rules);
            let lowered = super::consumer::Lowered::new(lower, view);
            super::consumer::ViewConsumer::new(settings, &mut observer, false, None, false, None)
                .then(Some(Box::new(lowered)))
        }
    };
    let (w, mut err) =
        crate::flatten::flatten_with(source, settings, search, dest, Some(Box::new(consumer)));
    if let Some((target, tmp)) = &map_tmp {
        if err.is_none() {
            if let Err(e) = std::fs::rename(tmp, target) {
                let _ = std::fs::remove_file(tmp);
                err = Some(io_err(target, e));
            }
        } else {
            let _ = std::fs::remove_file(tmp);
        }
    }
    (w, err)
}
