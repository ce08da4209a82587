//! The command line's arguments as clap reads them. These types stay in
//! `cli`: [`super::resolve`] turns them into what to do.

use std::ffi::OsString;
use std::path::PathBuf;

use clap::{Args, Parser, Subcommand, ValueEnum};

use crate::settings::parse_axis_word;

/// Flatten LinuxCNC-dialect G-code (O-word subroutines, loops, conditionals,
/// parameters and expressions) into plain straight-line G-code: for
/// LinuxCNC, or with --target for GRBL, grblHAL, FluidNC, g2core, Klipper,
/// Marlin, Smoothieware or RepRapFirmware (`ngcflat targets` lists them).
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
    pub(super) command: Option<Command>,
    #[command(flatten)]
    pub(super) flatten: FlattenArgs,
}

// Parsed once per run: the size of the largest variant does not matter.
#[allow(clippy::large_enum_variant)]
#[derive(Subcommand, Debug)]
pub(crate) enum Command {
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
    /// List the target controllers with their limits, or print one's
    /// profile (--show NAME) as a file to edit and pass as --target FILE.
    Targets(TargetsArgs),
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

/// `ngcflat targets`.
#[derive(Args, Debug)]
pub(crate) struct TargetsArgs {
    /// Print the profile of target NAME (a TOML file: edit it and pass it
    /// back with --target ./FILE.toml).
    #[arg(long, value_name = "NAME")]
    pub(super) show: Option<String>,
}

#[derive(Args, Debug)]
pub(crate) struct StatsArgs {
    /// Program; stdin when absent or `-`.
    pub(super) file: Option<PathBuf>,
    /// Write JSON instead of text.
    #[arg(long)]
    pub(super) json: bool,
    /// Leave out the run-time estimate (the rest of the statistics only).
    #[arg(long)]
    pub(super) no_time: bool,
    #[command(flatten)]
    pub(super) common: CommonArgs,
}

#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) enum ViewArg {
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
pub(crate) struct PlotArgs {
    /// Program; stdin when absent or `-`.
    pub(super) file: Option<PathBuf>,
    /// The picture: FILE.svg, or FILE.html for a page with the statistics.
    #[arg(short, long, value_name = "FILE", required = true)]
    pub(super) output: PathBuf,
    /// Which way to look at the toolpath.
    #[arg(long, value_enum, default_value = "xy")]
    pub(super) view: ViewArg,
    /// Open the written page or picture in the desktop's browser (or
    /// viewer) for it.
    #[arg(long)]
    pub(super) open: bool,
    #[command(flatten)]
    pub(super) common: CommonArgs,
}

#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) enum GrblEnvelopeArg {
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
pub(crate) struct MachineArgs {
    /// Travel limits in machine coordinates, mm (degrees for A-C), e.g.
    /// `X0:300,Y0:200,Z-60:0`; overrides the INI's and GRBL's per axis.
    #[arg(long, value_name = "RANGES")]
    pub(super) limits: Option<String>,
    /// A saved GRBL `$$` listing: $110-$112 max rate (mm/min), $120-$122
    /// acceleration (mm/s²), $130-$132 max travel (mm).
    #[arg(long, value_name = "FILE")]
    pub(super) grbl_settings: Option<PathBuf>,
    /// Where GRBL's travel ($130-$132) lies in machine coordinates.
    #[arg(long, value_enum, default_value = "negative")]
    pub(super) grbl_envelope: GrblEnvelopeArg,
    /// Do not check travel limits (the INI's, GRBL's or --limits).
    #[arg(long)]
    pub(super) no_limits: bool,
    /// Also stop at moves outside the INI's `[AXIS_*]` MIN_LIMIT/MAX_LIMIT
    /// when flattening and checking (with --ini; off by default, so that
    /// giving a machine's INI for its subroutine path and switches does not
    /// also need its offsets; `stats` always reports them).
    #[arg(long)]
    pub(super) ini_limits: bool,
}

#[derive(Args, Debug)]
pub(crate) struct FlattenArgs {
    /// Program to flatten; stdin when absent or `-`.
    pub(super) file: Option<PathBuf>,
    /// Write the result to FILE (atomically: on error FILE is left as it was).
    #[arg(short, long, value_name = "FILE")]
    pub(super) output: Option<PathBuf>,
    /// Write a source map to FILE: one JSON line per output line with the
    /// file, line, column and call chain that produced it.
    #[arg(long, value_name = "FILE")]
    pub(super) source_map: Option<PathBuf>,
    /// Append to each output line a `;` comment naming where it came from
    /// (`;from part.ngc:12:1 < part.ngc:40:1`, innermost call first); left
    /// off `%` lines and lines it would make longer than 252 characters.
    #[arg(long)]
    pub(super) annotate: bool,
    #[command(flatten)]
    pub(super) common: CommonArgs,
}

#[derive(Args, Debug)]
pub(crate) struct CheckArgs {
    /// Programs or folders (walked recursively).
    #[arg(required = true)]
    pub(super) paths: Vec<PathBuf>,
    /// File extensions checked in folders (comma-separated).
    #[arg(long, value_delimiter = ',', default_value = "ngc,nc,tap")]
    pub(super) ext: Vec<String>,
    /// Exit 1 on warnings too.
    #[arg(long)]
    pub(super) deny_warnings: bool,
    #[command(flatten)]
    pub(super) common: CommonArgs,
}

#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum ToolChangeArg {
    /// A pause for a manual change (M0, or the target's own pause code such
    /// as M600; the default where the target has no M6).
    Pause,
    /// M6 as written.
    Keep,
    /// No M6 at all.
    Drop,
}

#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum OnOff {
    On,
    Off,
}

#[derive(ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum FormatArg {
    Human,
    Short,
    Json,
    Github,
}

#[derive(Args, Debug)]
pub(crate) struct CommonArgs {
    /// Folder searched for subroutine files (repeatable).
    #[arg(short = 'I', long = "subroutine-path", value_name = "DIR")]
    pub(super) subroutine_path: Vec<PathBuf>,
    /// Folder searched first for subroutine files (like PROGRAM_PREFIX).
    #[arg(long, value_name = "DIR")]
    pub(super) program_prefix: Option<PathBuf>,
    /// LinuxCNC INI file: PROGRAM_PREFIX, SUBROUTINE_PATH, WIZARD_ROOT,
    /// PARAMETER_FILE, DISABLE_FANUC_STYLE_SUB, OWORD_NARGS and #<_ini[..]>
    /// values.
    #[arg(long, value_name = "FILE")]
    pub(super) ini: Option<PathBuf>,
    /// LinuxCNC parameter (.var) file with numbered parameters.
    #[arg(long, value_name = "FILE")]
    pub(super) var_file: Option<PathBuf>,
    /// LinuxCNC tool table (`T1 P1 Z0.5 D0.125` lines, machine units): tool
    /// data for #5400-#5413 and for the position after G43.
    #[arg(long, value_name = "FILE")]
    pub(super) tool_table: Option<PathBuf>,
    /// Set a parameter before the run: `-D 5063=-1.25` (numbered),
    /// `-D depth=3` (named), `-D _depth=3` (global). Overrides the var file.
    #[arg(short = 'D', long = "define", value_name = "PARAM=VALUE")]
    pub(super) define: Vec<String>,
    /// Round computed numbers to N decimals (default: full precision).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u8).range(0..=12))]
    pub(super) precision: Option<u8>,
    /// Remove all comments from the output.
    #[arg(long)]
    pub(super) strip_comments: bool,
    /// Stop after this many executed O-word lines (runaway loops and
    /// recursion; straight code is not counted).
    #[arg(long, value_name = "N", default_value_t = 100_000_000)]
    pub(super) max_steps: u64,
    /// Stop when the output grows beyond this many lines.
    #[arg(long, value_name = "N", default_value_t = 50_000_000)]
    pub(super) max_output_lines: u64,
    /// Refuse programs larger than this many bytes (files, pipes, devices;
    /// at most 4 GiB - 1).
    #[arg(long, value_name = "BYTES", default_value_t = 2 << 30)]
    pub(super) max_input_bytes: u64,
    /// Refuse a line longer than this read from a pipe or device (lines of
    /// regular files are never read whole).
    #[arg(long, value_name = "BYTES", default_value_t = 1 << 20)]
    pub(super) max_line_bytes: u64,
    /// Stop when the output grows beyond the program's own size plus this
    /// many bytes.
    #[arg(long, value_name = "BYTES", default_value_t = 4 << 30)]
    pub(super) max_output_bytes: u64,
    /// Assume the state LinuxCNC's standalone interpreter starts in: position
    /// 0, all offsets, tool data and probe results 0 (as in conformance
    /// runs). Without it, reading such values is an error until the program
    /// or -D fixes them.
    #[arg(long)]
    pub(super) zero_start: bool,
    /// Known start position in mm, in the program's coordinates (LinuxCNC
    /// starts in G21): `--start-position X0,Y0,Z10`. A value ending in `in`
    /// is in inches (`Z0.5in`); A, B, C are degrees. `--start-position X0 Y0
    /// Z10` also works: the words that follow it are taken while they look
    /// like axis words.
    #[arg(long, value_name = "X0,Y0,Z10", value_delimiter = ',')]
    pub(super) start_position: Vec<String>,
    /// User M-codes the machine has (M100-M199, external programs on
    /// LinuxCNC), written to the output as they are: `--user-m 100,101-105`.
    /// With --ini, the executable files M100..M199 in the INI's
    /// `[DISPLAY]PROGRAM_PREFIX` and `[RS274NGC]USER_M_PATH` folders count too.
    #[arg(long, value_name = "M", value_delimiter = ',')]
    pub(super) user_m: Vec<String>,
    /// Do not search the program's own folder for subroutine files.
    #[arg(long)]
    pub(super) no_program_dir: bool,
    /// LinuxCNC's O-word errors (a `return` outside a subroutine, an
    /// `endif` without its `if`, a `break` outside a loop...) become
    /// warnings and the line is skipped, like the INI's
    /// `[RS274NGC]OWORD_WARNONLY` = 1.
    #[arg(long)]
    pub(super) oword_warn_only: bool,
    /// Read the named-parameter syntax of the 2007 proposal on the LinuxCNC
    /// wiki (not LinuxCNC syntax): `#[name]` and `#$name$` for `#<name>`,
    /// `#name$` for `#<_name>`, O-word names `oname$` and `o$name$` for
    /// `o<name>`.
    #[arg(long)]
    pub(super) named_params_2007: bool,
    /// How diagnostics are written to stderr.
    #[arg(long, value_enum, default_value = "human")]
    pub(super) message_format: FormatArg,
    #[command(flatten)]
    pub(super) machine: MachineArgs,
    /// Write for this controller: linuxcnc (the default: the flattened
    /// program as it is), grbl, ...; `list` prints them; a path (with a `/`
    /// or ending in .toml) reads a profile file (`ngcflat targets --show
    /// NAME` prints one to start from). Also $NGCFLAT_TARGET.
    #[arg(long, value_name = "NAME")]
    pub(super) target: Option<String>,
    /// What M6 becomes for a target: pause (M0 or the target's own pause
    /// code; the default where the target has no M6), keep, drop.
    #[arg(long, value_enum, value_name = "POLICY")]
    pub(super) tool_change: Option<ToolChangeArg>,
    /// LinuxCNC's block-delete switch for a target: on skips `/` lines, off
    /// (the default, as rs274) runs them; the `/` itself is never written
    /// for a controller that ignores it.
    #[arg(long, value_enum, value_name = "on|off")]
    pub(super) block_delete: Option<OnOff>,
    /// Largest deviation of lowered curves (splines) from the original, in
    /// millimetres (scaled for inch programs).
    #[arg(long, value_name = "MM", default_value_t = 0.001)]
    pub(super) tolerance: f64,
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
pub(crate) fn normalize_args<I: IntoIterator<Item = OsString>>(args: I) -> Vec<OsString> {
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

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    #[test]
    fn cli_is_consistent() {
        Cli::command().debug_assert();
    }
}
