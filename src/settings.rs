//! Everything the evaluator needs to know from the command line and the INI,
//! as plain data.

use crate::diag::{ExprError, SetupError};
use std::path::Path;

use crate::diag::ErrorKind;
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
    /// Most elements a lathe cycle's contour may have (E1322): the
    /// cycle's move bound, so that a contour subroutine that never ends
    /// fails before it fills the memory. Smaller in tests.
    pub max_contour: usize,
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
    /// U, V and W are axes of this machine (from the INI's `[TRAJ]COORDINATES`);
    /// otherwise they are bad characters, as in LinuxCNC's XYZABC default.
    pub uvw_axes: bool,
    /// Machine units are millimetres (INI `[TRAJ]LINEAR_UNITS`); offset and
    /// home parameters are stored in machine units. Without an INI they are
    /// inches, as in LinuxCNC's standalone interpreter.
    pub machine_metric: bool,
    /// Tools from a LinuxCNC tool table file.
    pub tool_table: Vec<(i64, ToolData)>,
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
    /// Read the named-parameter syntax of the 2007 proposal
    /// (`--named-params-2007`), for this run's programs.
    pub named_params_2007: bool,
}

impl Default for Settings {
    fn default() -> Settings {
        Settings {
            precision: None,
            strip_comments: false,
            max_steps: 100_000_000,
            max_output_lines: 50_000_000,
            max_contour: crate::geom::lathe::MAX_MOVES,
            zero_start: false,
            named_params_2007: false,
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

/// Parses a `-D` argument.
pub fn parse_define(text: &str) -> Result<Define, ErrorKind> {
    let bad = || {
        ErrorKind::Setup(SetupError::BadDefine {
            text: text.to_string(),
        })
    };
    let (k, v) = text.split_once('=').ok_or_else(bad)?;
    let k = k.trim().trim_start_matches('#');
    let k = k.trim_start_matches('<').trim_end_matches('>');
    let v: f64 = v.trim().parse().map_err(|_| bad())?;
    if !v.is_finite() {
        return Err(bad());
    }
    if !k.is_empty() && k.bytes().all(|b| b.is_ascii_digit()) {
        let i: usize = k.parse().map_err(|_| bad())?;
        if !(1..MAX_PARAM).contains(&i) {
            return Err(ErrorKind::Expr(ExprError::ParamOutOfRange {
                index: i as i64,
            }));
        }
        return Ok(Define::Numbered(i, v));
    }
    if k.starts_with(|c: char| c.is_ascii_digit() || c == '.') {
        return Err(bad());
    }
    let name: String = k
        .chars()
        .filter(|c| !c.is_whitespace())
        .flat_map(|c| c.to_lowercase())
        .collect();
    if name.is_empty() || name.contains('>') {
        return Err(bad());
    }
    Ok(Define::Named(name, v))
}

/// Parses one `--start-position` word: an axis letter and a number in mm
/// (degrees for A, B, C), or in inches with an `in` suffix (`mm` is
/// accepted too). Returns the axis index and the value in mm.
pub fn parse_axis_word(word: &str) -> Option<(usize, f64)> {
    let mut chars = word.chars();
    let letter = chars.next()?.to_ascii_lowercase();
    let axis = crate::block::AXIS_LETTERS
        .iter()
        .position(|&c| c.to_ascii_lowercase() as char == letter)?;
    let rest = chars.as_str();
    let lower = rest.to_ascii_lowercase();
    let linear = !matches!(letter, 'a' | 'b' | 'c');
    let (num, scale) = if let Some(n) = lower.strip_suffix("in").filter(|_| linear) {
        (n, 25.4)
    } else if let Some(n) = lower.strip_suffix("mm").filter(|_| linear) {
        (n, 1.0)
    } else {
        (lower.as_str(), 1.0)
    };
    let v: f64 = num.trim().parse().ok()?;
    let v = v * scale;
    v.is_finite().then_some((axis, v))
}

/// Reads a LinuxCNC .var file: `number value` lines in ascending order.
pub fn read_var_file(path: &Path) -> Result<Vec<Define>, ErrorKind> {
    let text = std::fs::read_to_string(path).map_err(|e| {
        ErrorKind::Setup(SetupError::Io {
            path: path.to_path_buf(),
            message: e.to_string(),
        })
    })?;
    let mut out = Vec::new();
    let mut last = 0i64;
    for line in text.lines() {
        let t = line.trim();
        if t.is_empty() || t.starts_with('#') || t.starts_with(';') {
            continue;
        }
        let mut it = t.split_whitespace();
        let (Some(a), Some(b)) = (it.next(), it.next()) else {
            return Err(ErrorKind::Setup(SetupError::VarFileSyntax {
                text: t.to_string(),
            }));
        };
        let (Ok(i), Ok(v)) = (a.parse::<i64>(), b.parse::<f64>()) else {
            return Err(ErrorKind::Setup(SetupError::VarFileSyntax {
                text: t.to_string(),
            }));
        };
        if !(1..MAX_PARAM as i64).contains(&i) {
            return Err(ErrorKind::Expr(ExprError::ParamOutOfRange { index: i }));
        }
        if i <= last {
            return Err(ErrorKind::Setup(SetupError::VarFileOrder { index: i }));
        }
        last = i;
        out.push(Define::Numbered(i as usize, v));
    }
    Ok(out)
}

/// Reads a LinuxCNC tool table file.
pub fn read_tool_table(path: &Path) -> Result<Vec<(i64, ToolData)>, ErrorKind> {
    let io = |message: String| {
        ErrorKind::Setup(SetupError::Io {
            path: path.to_path_buf(),
            message,
        })
    };
    let text = std::fs::read_to_string(path).map_err(|e| io(e.to_string()))?;
    parse_tool_table(&text).map_err(io)
}

/// One past the highest numbered parameter.
pub const MAX_PARAM: usize = 5602;

/// One tool: offsets X..W, diameter, front and back angle, orientation.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ToolData {
    pub offsets: [f64; 9],
    pub diameter: f64,
    pub front: f64,
    pub back: f64,
    pub orientation: f64,
}

/// Reads a LinuxCNC tool table (`T1 P1 Z0.5 D0.125 ;comment` per line).
fn parse_tool_table(text: &str) -> Result<Vec<(i64, ToolData)>, String> {
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let line = line.split(';').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        let mut tool = None;
        let mut data = ToolData::default();
        for word in line.split_whitespace() {
            let (letter, value) = word.split_at(1);
            let letter = letter.to_ascii_lowercase();
            let v: f64 = value.parse().map_err(|_| {
                format!(
                    "tool table line {}: '{word}' is not a letter and a number",
                    n + 1
                )
            })?;
            match letter.as_str() {
                "t" => tool = Some(v as i64),
                "p" => {}
                "d" => data.diameter = v,
                "i" => data.front = v,
                "j" => data.back = v,
                "q" => data.orientation = v,
                l => match crate::block::AXIS_LETTERS.iter().position(|&c| {
                    c.to_ascii_lowercase() as char == l.chars().next().unwrap_or(' ')
                }) {
                    Some(a) => data.offsets[a] = v,
                    None => {
                        return Err(format!("tool table line {}: unknown word '{word}'", n + 1));
                    }
                },
            }
        }
        let t = tool.ok_or_else(|| format!("tool table line {}: no T word", n + 1))?;
        out.push((t, data));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defines() {
        assert_eq!(
            parse_define("5063=-1.25").unwrap(),
            Define::Numbered(5063, -1.25)
        );
        assert_eq!(
            parse_define("Depth=3").unwrap(),
            Define::Named("depth".into(), 3.0)
        );
        assert_eq!(
            parse_define("_g=1").unwrap(),
            Define::Named("_g".into(), 1.0)
        );
        assert!(parse_define("nothing").is_err());
        assert!(parse_define("0=1").is_err());
        assert!(parse_define("x=inf").is_err());
    }
}
