//! Everything the evaluator needs to know from the command line and the INI,
//! as plain data.

use crate::program::ini::Ini;

/// A parameter given before the run (`-D`, var file).
#[derive(Debug, Clone, PartialEq)]
pub enum Define {
    Numbered(usize, f64),
    /// Lower-cased name; `_` names are global.
    Named(String, f64),
}

#[derive(Debug, Clone)]
pub struct Settings {
    pub precision: Option<u8>,
    pub strip_comments: bool,
    pub max_steps: u64,
    pub max_output_lines: u64,
    /// Start like the reference's standalone interpreter: position, offsets,
    /// tool data and probe results all zero and known.
    pub zero_start: bool,
    /// Known start position, by axis index.
    pub start_position: Vec<(usize, f64)>,
    pub fanuc_disabled: bool,
    pub oword_nargs: bool,
    /// LinuxCNC's O-word errors (a stray `return`, `endif`, `break`...)
    /// are warnings and the line is skipped (`[RS274NGC]OWORD_WARNONLY`).
    pub oword_warn_only: bool,
    /// `[RS274NGC]RETAIN_G43`: a tool change while G43 is in effect applies
    /// the new tool's length offset; unloading the tool (T0) cancels G43.
    pub retain_g43: bool,
    /// `[RS274NGC]INI_VARS` (default on): `#<_ini[section]name>` reads the
    /// INI; off, it is an ordinary global parameter.
    pub ini_vars: bool,
    /// `[RS274NGC]HAL_PIN_VARS` (default on): `#<_hal[item]>` reads a HAL
    /// pin (a value only the machine knows); off, it is an ordinary global.
    pub hal_pin_vars: bool,
    /// `[RS274NGC]NO_DOWNCASE_OWORD`: names in comments keep their case so
    /// that mixed-case HAL items can be read. Read for completeness: HAL
    /// items are never read from a machine here, and a `-D` value for one
    /// matches whatever its case; other names are found as before (as in
    /// rs274 2.9).
    pub no_downcase_oword: bool,
    pub ini: Option<Ini>,
    /// Var-file parameters first, then `-D` values (later wins).
    pub defines: Vec<Define>,
    /// U, V and W are axes of this machine (from the INI's [TRAJ]COORDINATES);
    /// otherwise they are bad characters, as in LinuxCNC's XYZABC default.
    pub uvw_axes: bool,
    /// Machine units are millimetres (INI [TRAJ]LINEAR_UNITS); offset and
    /// home parameters are stored in machine units. Without an INI they are
    /// inches, as in LinuxCNC's standalone interpreter.
    pub machine_metric: bool,
    /// Tools from a LinuxCNC tool table file.
    pub tool_table: Vec<(i64, super::tools::ToolData)>,
    /// Collect warnings (check mode and stderr notes).
    pub warnings: bool,
    /// Runs of plain lines take the batched straight-line loop, and plain
    /// moves of evaluated lines its state update. Off only to check both
    /// against the line-by-line path and the general block checks.
    pub plain_runs: bool,
    /// Chunk size in bytes for reading plain lines on a second core during a
    /// long straight-line run (0: one core).
    pub scan_ahead: usize,
    /// Compiled expressions run on the stack machine. Off only to check it
    /// against the tree evaluation.
    pub compiled_exprs: bool,
    /// Lines with computed numbers written before number formatting and
    /// output writing move to a second thread (0: from the first line;
    /// `usize::MAX`: never). Output that is thrown away never moves.
    pub format_thread_after: usize,
    /// Bounds on reading the program (`--max-input-bytes`,
    /// `--max-line-bytes`).
    pub input: crate::program::InputLimits,
    /// Output bytes allowed beyond the program's own size
    /// (`--max-output-bytes`).
    pub max_output_bytes: u64,
    /// User M-codes M100-M199 the machine has (bit n: M(100+n)), declared
    /// with --user-m or found as executable files M1nn in the INI's
    /// PROGRAM_PREFIX and USER_M_PATH folders; they are written as they are.
    pub user_m: u128,
    /// Show progress on stderr (a terminal) after this delay.
    pub progress: Option<std::time::Duration>,
}

impl Default for Settings {
    fn default() -> Settings {
        Settings {
            precision: None,
            strip_comments: false,
            max_steps: 100_000_000,
            max_output_lines: 50_000_000,
            zero_start: false,
            start_position: Vec::new(),
            fanuc_disabled: false,
            oword_nargs: false,
            oword_warn_only: false,
            retain_g43: false,
            ini_vars: true,
            hal_pin_vars: true,
            no_downcase_oword: false,
            ini: None,
            defines: Vec::new(),
            warnings: true,
            plain_runs: true,
            scan_ahead: 32 << 10,
            compiled_exprs: true,
            format_thread_after: 4096,
            uvw_axes: false,
            machine_metric: false,
            tool_table: Vec::new(),
            input: crate::program::InputLimits::default(),
            max_output_bytes: 4 << 30,
            user_m: 0,
            progress: None,
        }
    }
}
