//! The validated configuration of a run, and reading what a LinuxCNC INI
//! says about programs, parameters and the machine. The command line's
//! `cli` part builds it.

use crate::diag::SetupError;
use std::path::{Path, PathBuf};

use crate::diag::{Diagnostic, ErrorKind, MessageFormat, WarningKind};
use crate::program::SearchPath;
use crate::program::ini::Ini;
use crate::settings::Settings;

/// Validated options shared by flattening and checking.
#[derive(Debug, Clone)]
pub(crate) struct Config {
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

pub(crate) fn expand_tilde(p: &str) -> PathBuf {
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

pub(crate) fn resolve_in(base: &Path, p: &str) -> PathBuf {
    let e = expand_tilde(p);
    if e.is_absolute() { e } else { base.join(e) }
}

/// Parses a `--user-m` value: `100`, `M100` or a range `101-105`, within
/// M100-M199. Returns the bits (bit n: M(100+n)).
pub(crate) fn parse_user_m(text: &str) -> Result<u128, ErrorKind> {
    let bad = || {
        ErrorKind::Setup(SetupError::BadUserM {
            text: text.to_string(),
        })
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
pub(crate) fn user_m_files(ini: &Ini, base: &Path) -> u128 {
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

/// Reads an INI file; returns it with the folder its relative paths are
/// resolved in.
pub(crate) fn read_ini(ini_path: &Path) -> Result<(Ini, PathBuf), ErrorKind> {
    let text = std::fs::read_to_string(ini_path).map_err(|e| {
        ErrorKind::Setup(SetupError::Io {
            path: ini_path.to_path_buf(),
            message: e.to_string(),
        })
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
pub(crate) struct IniPaths {
    pub(crate) program_prefix: Option<PathBuf>,
    pub(crate) subroutine_dirs: Vec<PathBuf>,
    pub(crate) wizard_root: Option<PathBuf>,
    pub(crate) parameter_file: Option<PathBuf>,
}

impl IniPaths {
    /// `want_parameters`: whether the parameter file is looked at (no
    /// --var-file was given).
    pub(crate) fn read(
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
pub(crate) fn ini_switches(ini: &Ini, settings: &mut Settings, warn: &mut impl FnMut(WarningKind)) {
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
