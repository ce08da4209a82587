//! Command line → validated configuration. Clap types stop here.

use std::ffi::OsString;
use std::path::{Path, PathBuf};

use clap::{Args, Parser, Subcommand, ValueEnum};

use crate::diag::{Diagnostic, ErrorKind, MessageFormat, WarningKind};
use crate::eval::{Settings, parse_axis_word, parse_define, read_tool_table, read_var_file};
use crate::program::SearchPath;
use crate::program::ini::Ini;

/// Flatten LinuxCNC-dialect G-code (O-word subroutines, loops, conditionals,
/// parameters and expressions) into plain straight-line G-code for
/// controllers such as GRBL, grblHAL, FluidNC, Marlin and Smoothieware.
///
/// Every expression and parameter is evaluated and every O-word expanded
/// exactly as LinuxCNC 2.9's interpreter would run the program; the result
/// goes to stdout (or --output) only if the whole program flattened without
/// error.
///
/// Subroutine files (`o<name> call` → name.ngc, lower-cased) are searched in:
/// --program-prefix (or the INI's `[DISPLAY]PROGRAM_PREFIX`), each -I folder,
/// each folder of $NGCFLAT_SUBROUTINE_PATH (colon-separated), the INI's
/// `[RS274NGC]SUBROUTINE_PATH`, the INI's `[WIZARD]WIZARD_ROOT` (recursively),
/// and last the folder of the program being flattened (unlike LinuxCNC;
/// --no-program-dir turns that off).
///
/// Exit status: 0 success, 1 the program is wrong, 2 usage or I/O error.
#[derive(Parser, Debug)]
#[command(name = "ngcflat", version, args_conflicts_with_subcommands = true)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
    #[command(flatten)]
    pub flatten: FlattenArgs,
}

// Parsed once per run: the size of the largest variant does not matter.
#[allow(clippy::large_enum_variant)]
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Check programs without writing output: every file is fully evaluated
    /// with the same rules as flattening; exit 1 if any has an error.
    Check(Box<CheckArgs>),
    /// Statistics of a program's motion: travel per axis (work and machine
    /// coordinates), feed and rapid path lengths, moves, arcs, tool changes
    /// and an estimated run time.
    Stats(StatsArgs),
    /// Draw the toolpath as SVG (or a self-contained HTML page with the
    /// statistics, when the output ends in .html).
    Plot(PlotArgs),
    /// List the target controllers with their limits.
    Targets,
    /// Print a shell completion script to stdout, e.g.
    /// `ngcflat completions bash > ~/.local/share/bash-completion/completions/ngcflat`.
    Completions {
        #[arg(value_enum)]
        shell: clap_complete::Shell,
    },
    /// Print the manual page (roff) to stdout, e.g.
    /// `ngcflat man > ~/.local/share/man/man1/ngcflat.1`.
    Man,
}

/// Writes the completion script or manual page a command asks for; false
/// for the commands that do the real work.
pub fn write_generated(cmd: &Command, out: &mut dyn std::io::Write) -> std::io::Result<bool> {
    use clap::CommandFactory;
    match cmd {
        Command::Completions { shell } => {
            clap_complete::generate(*shell, &mut Cli::command(), "ngcflat", out);
            Ok(true)
        }
        Command::Man => {
            clap_mangen::Man::new(Cli::command()).render(out)?;
            Ok(true)
        }
        Command::Check(_) | Command::Stats(_) | Command::Plot(_) | Command::Targets => Ok(false),
    }
}

#[derive(Args, Debug)]
pub struct StatsArgs {
    /// Program; stdin when absent or `-`.
    pub file: Option<PathBuf>,
    /// Write JSON instead of text.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub common: CommonArgs,
}

#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ViewArg {
    /// From above: X right, Y up.
    #[default]
    Xy,
    /// From the front: X right, Z up.
    Xz,
    /// From the side: Y right, Z up.
    Yz,
    /// Isometric.
    Iso,
}

#[derive(Args, Debug)]
pub struct PlotArgs {
    /// Program; stdin when absent or `-`.
    pub file: Option<PathBuf>,
    /// The picture: FILE.svg, or FILE.html for a page with the statistics.
    #[arg(short, long, value_name = "FILE", required = true)]
    pub output: PathBuf,
    /// Which way to look at the toolpath.
    #[arg(long, value_enum, default_value = "xy")]
    pub view: ViewArg,
    #[command(flatten)]
    pub common: CommonArgs,
}

#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum GrblEnvelopeArg {
    /// GRBL 1.1's default build: machine zero at the home switches, travel
    /// from -$130 to 0.
    #[default]
    Negative,
    /// Builds with HOMING_FORCE_SET_ORIGIN: travel from 0 to $130.
    Positive,
}

/// What ngcflat may know about the machine: travel limits (checked on every
/// move when flattening and checking) and axis velocities and accelerations
/// (used by the run-time estimate).
#[derive(Args, Debug, Default)]
pub struct MachineArgs {
    /// Travel limits in machine coordinates, mm (degrees for A-C), e.g.
    /// `X0:300,Y0:200,Z-60:0`; overrides the INI's and GRBL's per axis.
    #[arg(long, value_name = "RANGES")]
    pub limits: Option<String>,
    /// A saved GRBL `$$` listing: $110-$112 max rate (mm/min), $120-$122
    /// acceleration (mm/s²), $130-$132 max travel (mm).
    #[arg(long, value_name = "FILE")]
    pub grbl_settings: Option<PathBuf>,
    /// Where GRBL's travel ($130-$132) lies in machine coordinates.
    #[arg(long, value_enum, default_value = "negative")]
    pub grbl_envelope: GrblEnvelopeArg,
    /// Do not check travel limits (the INI's, GRBL's or --limits).
    #[arg(long)]
    pub no_limits: bool,
    /// Also stop at moves outside the INI's `[AXIS_*]` MIN_LIMIT/MAX_LIMIT
    /// when flattening and checking (with --ini; off by default, so that
    /// giving a machine's INI for its subroutine path and switches does not
    /// also need its offsets; `stats` always reports them).
    #[arg(long)]
    pub ini_limits: bool,
}

#[derive(Args, Debug)]
pub struct FlattenArgs {
    /// Program to flatten; stdin when absent or `-`.
    pub file: Option<PathBuf>,
    /// Write the result to FILE (atomically: on error FILE is left as it was).
    #[arg(short, long, value_name = "FILE")]
    pub output: Option<PathBuf>,
    /// Write a source map to FILE: one JSON line per output line with the
    /// file, line, column and call chain that produced it.
    #[arg(long, value_name = "FILE")]
    pub source_map: Option<PathBuf>,
    /// Append to each output line a `;` comment naming where it came from
    /// (`;from part.ngc:12:1 < part.ngc:40:1`, innermost call first); left
    /// off `%` lines and lines it would make longer than 252 characters.
    #[arg(long)]
    pub annotate: bool,
    #[command(flatten)]
    pub common: CommonArgs,
}

#[derive(Args, Debug)]
pub struct CheckArgs {
    /// Programs or folders (walked recursively).
    #[arg(required = true)]
    pub paths: Vec<PathBuf>,
    /// File extensions checked in folders (comma-separated).
    #[arg(long, value_delimiter = ',', default_value = "ngc,nc,tap")]
    pub ext: Vec<String>,
    /// Exit 1 on warnings too.
    #[arg(long)]
    pub deny_warnings: bool,
    #[command(flatten)]
    pub common: CommonArgs,
}

#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum ToolChangeArg {
    /// M0 (a pause for a manual change; the default where the target has no M6).
    Pause,
    /// M6 as written.
    Keep,
    /// No M6 at all.
    Drop,
}

#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum OnOff {
    On,
    Off,
}

#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum FormatArg {
    Human,
    Short,
    Json,
    Github,
}

#[derive(Args, Debug)]
pub struct CommonArgs {
    /// Folder searched for subroutine files (repeatable).
    #[arg(short = 'I', long = "subroutine-path", value_name = "DIR")]
    pub subroutine_path: Vec<PathBuf>,
    /// Folder searched first for subroutine files (like PROGRAM_PREFIX).
    #[arg(long, value_name = "DIR")]
    pub program_prefix: Option<PathBuf>,
    /// LinuxCNC INI file: PROGRAM_PREFIX, SUBROUTINE_PATH, WIZARD_ROOT,
    /// PARAMETER_FILE, DISABLE_FANUC_STYLE_SUB, OWORD_NARGS and #<_ini[..]>
    /// values.
    #[arg(long, value_name = "FILE")]
    pub ini: Option<PathBuf>,
    /// LinuxCNC parameter (.var) file with numbered parameters.
    #[arg(long, value_name = "FILE")]
    pub var_file: Option<PathBuf>,
    /// LinuxCNC tool table (`T1 P1 Z0.5 D0.125` lines, machine units): tool
    /// data for #5400-#5413 and for the position after G43.
    #[arg(long, value_name = "FILE")]
    pub tool_table: Option<PathBuf>,
    /// Set a parameter before the run: `-D 5063=-1.25` (numbered),
    /// `-D depth=3` (named), `-D _depth=3` (global). Overrides the var file.
    #[arg(short = 'D', long = "define", value_name = "PARAM=VALUE")]
    pub define: Vec<String>,
    /// Round computed numbers to N decimals (default: full precision).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u8).range(0..=12))]
    pub precision: Option<u8>,
    /// Remove all comments from the output.
    #[arg(long)]
    pub strip_comments: bool,
    /// Stop after this many executed O-word lines (runaway loops and
    /// recursion; straight code is not counted).
    #[arg(long, value_name = "N", default_value_t = 100_000_000)]
    pub max_steps: u64,
    /// Stop when the output grows beyond this many lines.
    #[arg(long, value_name = "N", default_value_t = 50_000_000)]
    pub max_output_lines: u64,
    /// Refuse programs larger than this many bytes (files, pipes, devices;
    /// at most 4 GiB - 1).
    #[arg(long, value_name = "BYTES", default_value_t = 2 << 30)]
    pub max_input_bytes: u64,
    /// Refuse a line longer than this read from a pipe or device (lines of
    /// regular files are never read whole).
    #[arg(long, value_name = "BYTES", default_value_t = 1 << 20)]
    pub max_line_bytes: u64,
    /// Stop when the output grows beyond the program's own size plus this
    /// many bytes.
    #[arg(long, value_name = "BYTES", default_value_t = 4 << 30)]
    pub max_output_bytes: u64,
    /// Assume the state LinuxCNC's standalone interpreter starts in: position
    /// 0, all offsets, tool data and probe results 0 (as in conformance
    /// runs). Without it, reading such values is an error until the program
    /// or -D fixes them.
    #[arg(long)]
    pub zero_start: bool,
    /// Known start position in mm, in the program's coordinates (LinuxCNC
    /// starts in G21): `--start-position X0,Y0,Z10`. A value ending in `in`
    /// is in inches (`Z0.5in`); A, B, C are degrees. `--start-position X0 Y0
    /// Z10` also works: the words that follow it are taken while they look
    /// like axis words.
    #[arg(long, value_name = "X0,Y0,Z10", value_delimiter = ',')]
    pub start_position: Vec<String>,
    /// User M-codes the machine has (M100-M199, external programs on
    /// LinuxCNC), written to the output as they are: `--user-m 100,101-105`.
    /// With --ini, the executable files M100..M199 in the INI's
    /// `[DISPLAY]PROGRAM_PREFIX` and `[RS274NGC]USER_M_PATH` folders count too.
    #[arg(long, value_name = "M", value_delimiter = ',')]
    pub user_m: Vec<String>,
    /// Do not search the program's own folder for subroutine files.
    #[arg(long)]
    pub no_program_dir: bool,
    /// LinuxCNC's O-word errors (a `return` outside a subroutine, an
    /// `endif` without its `if`, a `break` outside a loop...) become
    /// warnings and the line is skipped, like the INI's
    /// `[RS274NGC]OWORD_WARNONLY` = 1.
    #[arg(long)]
    pub oword_warn_only: bool,
    /// Read the named-parameter syntax of the 2007 proposal on the LinuxCNC
    /// wiki (not LinuxCNC syntax): `#[name]` and `#$name$` for `#<name>`,
    /// `#name$` for `#<_name>`, O-word names `oname$` and `o$name$` for
    /// `o<name>`.
    #[arg(long)]
    pub named_params_2007: bool,
    /// How diagnostics are written to stderr.
    #[arg(long, value_enum, default_value = "human")]
    pub message_format: FormatArg,
    #[command(flatten)]
    pub machine: MachineArgs,
    /// Write for this controller: linuxcnc (the default: the flattened
    /// program as it is), grbl, ...; `list` prints them. Also
    /// $NGCFLAT_TARGET.
    #[arg(long, value_name = "NAME")]
    pub target: Option<String>,
    /// What M6 becomes for a target: pause (M0; the default where the
    /// target has no M6), keep, drop.
    #[arg(long, value_enum, value_name = "POLICY")]
    pub tool_change: Option<ToolChangeArg>,
    /// LinuxCNC's block-delete switch for a target: on skips `/` lines, off
    /// (the default, as rs274) runs them; the `/` itself is never written
    /// for a controller that ignores it.
    #[arg(long, value_enum, value_name = "on|off")]
    pub block_delete: Option<OnOff>,
    /// Largest deviation of lowered curves (splines) from the original, in
    /// millimetres (scaled for inch programs).
    #[arg(long, value_name = "MM", default_value_t = 0.001)]
    pub tolerance: f64,
}

/// Validated options shared by flattening and checking.
#[derive(Debug, Clone)]
pub struct Config {
    pub settings: Settings,
    pub search: SearchPath,
    pub format: MessageFormat,
    /// Problems of the configuration that do not stop the run (INI entries
    /// naming missing folders, a SUBROUTINE_PATH cut to 10 folders).
    pub warnings: Vec<Diagnostic>,
    /// Travel limits, velocities and accelerations of the machine's axes.
    pub machine: crate::machine::axes::MachineAxes,
    /// Whether travel limits are checked (limits given and not --no-limits).
    pub check_limits: bool,
    /// A target other than linuxcnc (none: the flattened program as it is).
    pub target: Option<crate::controller::TargetOptions>,
}

/// Folders of `[RS274NGC]SUBROUTINE_PATH` LinuxCNC uses.
const MAX_SUB_DIRS: usize = 10;

fn expand_tilde(p: &str) -> PathBuf {
    if let Some(rest) = p.strip_prefix("~/") {
        if let Some(home) = std::env::var_os("HOME") {
            return Path::new(&home).join(rest);
        }
    } else if p == "~"
        && let Some(home) = std::env::var_os("HOME")
    {
        return PathBuf::from(home);
    }
    PathBuf::from(p)
}

fn resolve_in(base: &Path, p: &str) -> PathBuf {
    let e = expand_tilde(p);
    if e.is_absolute() { e } else { base.join(e) }
}

/// Whether a command-line word is a `--start-position` value (axis words
/// separated by commas or spaces).
fn is_axis_list(arg: &str) -> bool {
    let mut words = arg
        .split(|c: char| c == ',' || c.is_whitespace())
        .filter(|w| !w.is_empty())
        .peekable();
    words.peek().is_some() && words.all(|w| parse_axis_word(w).is_some())
}

/// Rewrites `--start-position X0 Y0 Z10` (the words after the option, as
/// long as they are axis words) into `--start-position=X0,Y0,Z10`, so that
/// a file name after them is not taken as a value.
pub fn normalize_args<I: IntoIterator<Item = OsString>>(args: I) -> Vec<OsString> {
    let mut out: Vec<OsString> = Vec::new();
    let mut it = args.into_iter().peekable();
    while let Some(a) = it.next() {
        if a == "--" {
            out.push(a);
            out.extend(it);
            break;
        }
        if a != "--start-position" {
            out.push(a);
            continue;
        }
        let mut words: Vec<String> = Vec::new();
        while let Some(next) = it.peek() {
            match next.to_str() {
                Some(w) if is_axis_list(w) => {
                    words.push(w.to_string());
                    it.next();
                }
                _ => break,
            }
        }
        if words.is_empty() {
            // Not axis words: let clap take the next word and the check
            // in to_config name it.
            out.push(a);
        } else {
            let joined: Vec<&str> = words
                .iter()
                .flat_map(|w| w.split(|c: char| c == ',' || c.is_whitespace()))
                .filter(|w| !w.is_empty())
                .collect();
            out.push(OsString::from(format!(
                "--start-position={}",
                joined.join(",")
            )));
        }
    }
    out
}

impl Cli {
    /// Parses the process's command line.
    pub fn from_env() -> Cli {
        Cli::parse_from(normalize_args(std::env::args_os()))
    }
}

/// Parses a `--user-m` value: `100`, `M100` or a range `101-105`, within
/// M100-M199. Returns the bits (bit n: M(100+n)).
pub fn parse_user_m(text: &str) -> Result<u128, ErrorKind> {
    let bad = || ErrorKind::BadUserM {
        text: text.to_string(),
    };
    let num = |s: &str| -> Result<u32, ErrorKind> {
        let s = s.trim();
        let s = s.strip_prefix(['M', 'm']).unwrap_or(s);
        s.parse::<u32>()
            .ok()
            .filter(|n| (100..=199).contains(n))
            .ok_or_else(bad)
    };
    let (a, b) = match text.split_once('-') {
        Some((a, b)) => (num(a)?, num(b)?),
        None => {
            let n = num(text)?;
            (n, n)
        }
    };
    if a > b {
        return Err(bad());
    }
    Ok((a..=b).fold(0u128, |bits, n| bits | 1u128 << (n - 100)))
}

/// The user M-codes LinuxCNC finds: an executable file `M1nn` (capital M)
/// in the first folder that has one, of PROGRAM_PREFIX (default `nc_files`)
/// then the USER_M_PATH folders (at most ten folders in all).
fn user_m_files(ini: &Ini, base: &Path) -> u128 {
    use std::os::unix::fs::PermissionsExt;
    let mut dirs = vec![resolve_in(
        base,
        ini.get("DISPLAY", "PROGRAM_PREFIX").unwrap_or("nc_files"),
    )];
    if let Some(p) = ini.get("RS274NGC", "USER_M_PATH") {
        dirs.extend(
            p.split(':')
                .map(str::trim)
                .filter(|s| !s.is_empty())
                .map(|s| resolve_in(base, s)),
        );
    }
    dirs.truncate(10);
    let mut bits = 0u128;
    for n in 0..100u32 {
        let name = format!("M{}", 100 + n);
        if dirs.iter().any(|d| {
            std::fs::metadata(d.join(&name))
                .is_ok_and(|m| m.is_file() && m.permissions().mode() & 0o100 != 0)
        }) {
            bits |= 1u128 << n;
        }
    }
    bits
}

impl CommonArgs {
    /// The requested diagnostic format.
    pub fn format(&self) -> MessageFormat {
        match self.message_format {
            FormatArg::Human => MessageFormat::Human,
            FormatArg::Short => MessageFormat::Short,
            FormatArg::Json => MessageFormat::Json,
            FormatArg::Github => MessageFormat::Github,
        }
    }

    /// The target's name: --target, else $NGCFLAT_TARGET.
    pub fn target_name(&self) -> Option<String> {
        self.target
            .clone()
            .or_else(|| std::env::var("NGCFLAT_TARGET").ok())
            .filter(|t| !t.is_empty())
    }

    fn target_options(&self) -> Result<Option<crate::controller::TargetOptions>, ErrorKind> {
        use crate::controller::{TargetOptions, ToolChange};
        let Some(name) = self.target_name() else {
            return Ok(None);
        };
        let profile = crate::controller::find(&name).ok_or(ErrorKind::UnknownTarget { name })?;
        if !(self.tolerance > 0.0 && self.tolerance.is_finite()) {
            return Err(ErrorKind::BadDefine {
                text: format!("--tolerance {}", self.tolerance),
            });
        }
        let mut t = TargetOptions::new(profile);
        t.tool_change = self.tool_change.map(|c| match c {
            ToolChangeArg::Pause => ToolChange::Pause,
            ToolChangeArg::Keep => ToolChange::Keep,
            ToolChangeArg::Drop => ToolChange::Drop,
        });
        t.block_delete = self.block_delete == Some(OnOff::On);
        t.tolerance_mm = self.tolerance;
        Ok(t.active().then_some(t))
    }

    /// Builds the configuration; `env_path` is $NGCFLAT_SUBROUTINE_PATH.
    pub fn to_config(&self, env_path: Option<String>) -> Result<Config, ErrorKind> {
        let mut settings = Settings {
            precision: self.precision,
            strip_comments: self.strip_comments,
            max_steps: self.max_steps,
            max_output_lines: self.max_output_lines,
            input: crate::program::InputLimits {
                max_bytes: self.max_input_bytes,
                max_line: self.max_line_bytes,
            },
            max_output_bytes: self.max_output_bytes,
            zero_start: self.zero_start,
            ..Settings::default()
        };
        let mut warnings = Vec::new();
        let mut search = SearchPath {
            program_dir: !self.no_program_dir,
            ..SearchPath::default()
        };
        let mut prefixes = Vec::new();
        if let Some(p) = &self.program_prefix {
            prefixes.push(p.clone());
        }
        let mut dirs: Vec<PathBuf> = self.subroutine_path.clone();
        if let Some(env) = env_path {
            dirs.extend(env.split(':').filter(|s| !s.is_empty()).map(expand_tilde));
        }
        let mut var_file = self.var_file.clone();
        let mut machine = crate::machine::axes::MachineAxes::default();
        if let Some(ini_path) = &self.ini {
            let (ini, base) = read_ini(ini_path)?;
            let mut warn = |kind| warnings.push(Diagnostic::warning(kind, None));
            let paths = IniPaths::read(&ini, &base, var_file.is_none(), &mut warn);
            if self.program_prefix.is_none() {
                prefixes.extend(paths.program_prefix);
            }
            dirs.extend(paths.subroutine_dirs);
            search.recursive.extend(paths.wizard_root);
            var_file = var_file.or(paths.parameter_file);
            ini_switches(&ini, &mut settings, &mut warn);
            machine.add_ini(&ini, settings.machine_metric)?;
            settings.user_m |= user_m_files(&ini, &base);
            settings.ini = Some(ini);
        }
        settings.oword_warn_only |= self.oword_warn_only;
        search.dirs = prefixes.into_iter().chain(dirs).collect();
        self.add_values(&mut settings, var_file.as_deref())?;
        let check_limits = self.add_machine_axes(&mut machine)?;
        let target = self.target_options()?;
        if target.is_some() {
            // A target other than linuxcnc has no user M-codes: they pass the
            // block checks so that the target refuses them with its reason
            // (rather than E0805 suggesting --user-m, which cannot help).
            settings.user_m = (1u128 << 100) - 1;
        }
        Ok(Config {
            settings,
            search,
            format: self.format(),
            warnings,
            machine,
            check_limits,
            target,
        })
    }

    /// The values given on the command line (and the var file): parameters,
    /// tool table, user M-codes, start position.
    fn add_values(
        &self,
        settings: &mut Settings,
        var_file: Option<&Path>,
    ) -> Result<(), ErrorKind> {
        if let Some(v) = var_file {
            settings.defines.extend(read_var_file(v)?);
        }
        if let Some(t) = &self.tool_table {
            settings.tool_table = read_tool_table(t)?;
        }
        for d in &self.define {
            settings.defines.push(parse_define(d)?);
        }
        for m in &self.user_m {
            settings.user_m |= parse_user_m(m)?;
        }
        for word in self
            .start_position
            .iter()
            .flat_map(|s| s.split_whitespace())
        {
            let axis = parse_axis_word(word).ok_or_else(|| ErrorKind::BadStartPosition {
                text: word.to_string(),
            })?;
            settings.start_position.push(axis);
        }
        Ok(())
    }

    /// Adds the GRBL listing and `--limits` to the axes (which hold the
    /// INI's); returns whether travel limits are checked.
    fn add_machine_axes(
        &self,
        machine: &mut crate::machine::axes::MachineAxes,
    ) -> Result<bool, ErrorKind> {
        if let Some(g) = &self.machine.grbl_settings {
            let text = std::fs::read_to_string(g).map_err(|e| ErrorKind::Io {
                path: g.clone(),
                message: e.to_string(),
            })?;
            let env = match self.machine.grbl_envelope {
                GrblEnvelopeArg::Negative => crate::machine::axes::GrblEnvelope::Negative,
                GrblEnvelopeArg::Positive => crate::machine::axes::GrblEnvelope::Positive,
            };
            machine.add_grbl(&text, env)?;
        }
        if let Some(l) = &self.machine.limits {
            machine.add_limits(l)?;
        }
        // --limits and a GRBL listing ask for the check; an INI's limits
        // only with --ini-limits.
        let asked = self.machine.limits.is_some()
            || self.machine.grbl_settings.is_some()
            || self.machine.ini_limits;
        Ok(!self.machine.no_limits && asked && machine.has_limits())
    }
}

/// Reads an INI file; returns it with the folder its relative paths are
/// resolved in.
fn read_ini(ini_path: &Path) -> Result<(Ini, PathBuf), ErrorKind> {
    let text = std::fs::read_to_string(ini_path).map_err(|e| ErrorKind::Io {
        path: ini_path.to_path_buf(),
        message: e.to_string(),
    })?;
    let base = ini_path.parent().map(Path::to_path_buf).unwrap_or_default();
    let base = if base.as_os_str().is_empty() {
        PathBuf::from(".")
    } else {
        base
    };
    Ok((Ini::parse(&text), base))
}

/// The folders and files an INI names for finding programs and parameters.
struct IniPaths {
    program_prefix: Option<PathBuf>,
    subroutine_dirs: Vec<PathBuf>,
    wizard_root: Option<PathBuf>,
    parameter_file: Option<PathBuf>,
}

impl IniPaths {
    /// `want_parameters`: whether the parameter file is looked at (no
    /// --var-file was given).
    fn read(
        ini: &Ini,
        base: &Path,
        want_parameters: bool,
        warn: &mut impl FnMut(WarningKind),
    ) -> IniPaths {
        let mut subroutine_dirs = Vec::new();
        if let Some(sp) = ini.get("RS274NGC", "SUBROUTINE_PATH") {
            // LinuxCNC keeps the first 10 entries that exist and stops
            // reading there; entries that do not exist do not count.
            let mut ignored: Vec<PathBuf> = Vec::new();
            for p in sp
                .split(':')
                .map(str::trim)
                .filter(|s| !s.is_empty())
                .map(|s| resolve_in(base, s))
            {
                if !p.is_dir() {
                    warn(WarningKind::ConfigPathMissing {
                        key: "[RS274NGC]SUBROUTINE_PATH",
                        path: p,
                    });
                } else if subroutine_dirs.len() < MAX_SUB_DIRS {
                    subroutine_dirs.push(p);
                } else {
                    ignored.push(p);
                }
            }
            if !ignored.is_empty() {
                warn(WarningKind::SubroutinePathTruncated { ignored });
            }
        }
        let mut parameter_file = None;
        if want_parameters && let Some(v) = ini.get("RS274NGC", "PARAMETER_FILE") {
            let p = resolve_in(base, v);
            if p.is_file() {
                parameter_file = Some(p);
            } else {
                warn(WarningKind::ConfigPathMissing {
                    key: "[RS274NGC]PARAMETER_FILE",
                    path: p,
                });
            }
        }
        IniPaths {
            program_prefix: ini
                .get("DISPLAY", "PROGRAM_PREFIX")
                .map(|p| resolve_in(base, p)),
            subroutine_dirs,
            wizard_root: ini
                .get("WIZARD", "WIZARD_ROOT")
                .map(|w| resolve_in(base, w)),
            parameter_file,
        }
    }
}

/// The interpreter's switches and the machine's units and axes from an
/// INI. One written for LinuxCNC before 2.8 has the switches as bits of one
/// FEATURES mask, honoured when the separate switch is absent.
fn ini_switches(ini: &Ini, settings: &mut Settings, warn: &mut impl FnMut(WarningKind)) {
    settings.fanuc_disabled = ini.flag("RS274NGC", "DISABLE_FANUC_STYLE_SUB");
    let features = ini.integer("RS274NGC", "FEATURES");
    let switch = |name: &str, bit: i64, default: bool| {
        ini.boolean("RS274NGC", name)
            .or(features.map(|m| m & bit != 0))
            .unwrap_or(default)
    };
    settings.retain_g43 = switch("RETAIN_G43", 0x1, false);
    settings.oword_nargs = switch("OWORD_NARGS", 0x2, false);
    settings.ini_vars = switch("INI_VARS", 0x4, true);
    settings.hal_pin_vars = switch("HAL_PIN_VARS", 0x8, true);
    settings.no_downcase_oword = switch("NO_DOWNCASE_OWORD", 0x10, false);
    settings.oword_warn_only = switch("OWORD_WARNONLY", 0x20, false);
    if let Some(mask) = features {
        let names = [
            (0x1, "RETAIN_G43"),
            (0x2, "OWORD_NARGS"),
            (0x4, "INI_VARS"),
            (0x8, "HAL_PIN_VARS"),
            (0x10, "NO_DOWNCASE_OWORD"),
            (0x20, "OWORD_WARNONLY"),
        ];
        let on: Vec<&str> = names
            .iter()
            .filter(|(bit, _)| mask & bit != 0)
            .map(|(_, n)| *n)
            .collect();
        let switches = if on.is_empty() {
            "all switches off".to_string()
        } else {
            format!("on: {}", on.join(", "))
        };
        warn(WarningKind::FeaturesMask { mask, switches });
    }
    settings.machine_metric = ini.get("TRAJ", "LINEAR_UNITS").is_some_and(|u| {
        matches!(
            u.to_ascii_lowercase().as_str(),
            "mm" | "metric" | "millimeter" | "millimetre"
        )
    });
    settings.uvw_axes = ini.get("TRAJ", "COORDINATES").is_some_and(|c| {
        c.chars()
            .any(|ch| matches!(ch.to_ascii_uppercase(), 'U' | 'V' | 'W'))
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    #[test]
    fn cli_is_consistent() {
        Cli::command().debug_assert();
    }
}
