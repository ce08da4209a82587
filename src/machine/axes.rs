//! What the statistics and the travel-limit check know about the machine's
//! axes: travel limits, maximum velocity and acceleration, in millimetres
//! (degrees for rotary axes) and seconds, with where each came from.
//!
//! Sources: `--limits X0:300,...`, a LinuxCNC INI (`[AXIS_<L>]` or, for an
//! axis without that section, `[JOINT_<n>]` with `n` the axis's place in
//! `[TRAJ]COORDINATES`), or a saved GRBL `$$` listing.

use crate::diag::ErrorKind;
use crate::diag::SetupError;
use crate::program::ini::Ini;

/// Axis letters in parameter order.
pub(crate) const LETTERS: [char; 9] = ['X', 'Y', 'Z', 'A', 'B', 'C', 'U', 'V', 'W'];

/// Whether axis `i` is rotary (A, B, C).
pub(crate) fn is_rotary(i: usize) -> bool {
    (3..6).contains(&i)
}

#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct AxisData {
    /// Travel envelope in machine coordinates.
    pub min: Option<f64>,
    pub max: Option<f64>,
    /// Where the envelope came from (`--limits`, `INI [AXIS_X]`, `GRBL $130`).
    pub limit_source: Option<String>,
    /// mm/s (deg/s).
    pub max_vel: Option<f64>,
    /// mm/s² (deg/s²).
    pub max_acc: Option<f64>,
}

/// Where GRBL's machine envelope lies (`--grbl-envelope`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) enum GrblEnvelope {
    /// GRBL 1.1 as built by default: homing sets machine zero at the home
    /// switches and the work area is negative, `-$13x..0`, whatever the
    /// homing direction.
    #[default]
    Negative,
    /// Builds with `HOMING_FORCE_SET_ORIGIN` homing towards the negative end:
    /// `0..$13x`.
    Positive,
}

#[derive(Debug, Clone, Default, PartialEq)]
pub(crate) struct MachineAxes {
    pub axes: [AxisData; 9],
    /// The planner settings of a GRBL `$$` listing, when one was given.
    pub(crate) grbl: Option<super::grbl_listing::GrblSettings>,
    /// What a LinuxCNC INI says about its trajectory planner, when one was
    /// given.
    pub(crate) traj: Option<Traj>,
}

/// The trajectory planner's settings of a LinuxCNC INI, in mm and seconds.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Traj {
    /// `[TRAJ]MAX_LINEAR_VELOCITY` (mm/s).
    pub(crate) max_vel: Option<f64>,
    /// `[TRAJ]MAX_LINEAR_ACCELERATION` (mm/s²).
    pub(crate) max_acc: Option<f64>,
    /// One machine unit in mm (`[TRAJ]LINEAR_UNITS`): LinuxCNC's defaults
    /// for what the INI does not say are 1 machine unit per second.
    pub(crate) unit_mm: f64,
    /// `[EMCMOT]SERVO_PERIOD` (s): the planner's cycle.
    pub(crate) cycle: Option<f64>,
    /// `[TRAJ]ARC_BLEND_OPTIMIZATION_DEPTH`: segments the planner looks
    /// back over.
    pub(crate) depth: Option<usize>,
}

impl MachineAxes {
    /// Whether any axis has a travel limit.
    pub(crate) fn has_limits(&self) -> bool {
        self.axes.iter().any(|a| a.min.is_some() || a.max.is_some())
    }

    /// Whether any axis has a velocity or acceleration limit.
    pub(crate) fn has_dynamics(&self) -> bool {
        self.axes
            .iter()
            .any(|a| a.max_vel.is_some() || a.max_acc.is_some())
    }

    /// Reads `[AXIS_<L>]` (or `[JOINT_<n>]`) MIN_LIMIT, MAX_LIMIT,
    /// MAX_VELOCITY and MAX_ACCELERATION; linear values are converted from
    /// `[TRAJ]LINEAR_UNITS` (`metric` says whether the INI is in mm).
    pub(crate) fn add_ini(&mut self, ini: &Ini, metric: bool) -> Result<(), ErrorKind> {
        let scale = if metric { 1.0 } else { 25.4 };
        let coords: Vec<char> = ini
            .get("TRAJ", "COORDINATES")
            .unwrap_or("XYZ")
            .chars()
            .filter(|c| c.is_ascii_alphabetic())
            .map(|c| c.to_ascii_uppercase())
            .collect();
        for (i, letter) in LETTERS.iter().enumerate() {
            let axis_sec = format!("AXIS_{letter}");
            let joint_sec = coords
                .iter()
                .position(|c| c == letter)
                .map(|n| format!("JOINT_{n}"));
            let k = if is_rotary(i) { 1.0 } else { scale };
            let get = |key: &str| -> Result<Option<(f64, String)>, ErrorKind> {
                let mut found = ini.get(&axis_sec, key).map(|v| (v, axis_sec.clone()));
                if found.is_none()
                    && let Some(j) = &joint_sec
                {
                    found = ini.get(j, key).map(|v| (v, j.clone()));
                }
                match found {
                    None => Ok(None),
                    Some((v, sec)) => {
                        let x: f64 = v
                            .split_whitespace()
                            .next()
                            .and_then(|w| w.parse().ok())
                            .filter(|x: &f64| x.is_finite())
                            .ok_or_else(|| {
                                ErrorKind::Setup(SetupError::BadMachineValue {
                                    source: format!("INI [{sec}]{key}"),
                                    text: v.to_string(),
                                })
                            })?;
                        Ok(Some((x * k, sec)))
                    }
                }
            };
            let a = &mut self.axes[i];
            let lo = get("MIN_LIMIT")?;
            let hi = get("MAX_LIMIT")?;
            if let Some((v, sec)) = &lo {
                a.min = Some(*v);
                a.limit_source = Some(format!("INI [{sec}]"));
            }
            if let Some((v, sec)) = &hi {
                a.max = Some(*v);
                a.limit_source = Some(format!("INI [{sec}]"));
            }
            if let Some((v, _)) = get("MAX_VELOCITY")? {
                a.max_vel = Some(v.abs());
            }
            if let Some((v, _)) = get("MAX_ACCELERATION")? {
                a.max_acc = Some(v.abs());
            }
        }
        let num = |sec: &str, key: &str| -> Result<Option<f64>, ErrorKind> {
            match ini.get(sec, key) {
                None => Ok(None),
                Some(v) => v
                    .split_whitespace()
                    .next()
                    .and_then(|w| w.parse::<f64>().ok())
                    .filter(|x| x.is_finite())
                    .map(|x| Some(x.abs()))
                    .ok_or_else(|| {
                        ErrorKind::Setup(SetupError::BadMachineValue {
                            source: format!("INI [{sec}]{key}"),
                            text: v.to_string(),
                        })
                    }),
            }
        };
        self.traj = Some(Traj {
            max_vel: num("TRAJ", "MAX_LINEAR_VELOCITY")?.map(|v| v * scale),
            max_acc: num("TRAJ", "MAX_LINEAR_ACCELERATION")?.map(|v| v * scale),
            unit_mm: scale,
            cycle: num("EMCMOT", "SERVO_PERIOD")?
                .filter(|&ns| ns > 0.0)
                .map(|ns| ns * 1e-9),
            depth: num("TRAJ", "ARC_BLEND_OPTIMIZATION_DEPTH")?.map(|d| d as usize),
        });
        Ok(())
    }

    /// Reads a saved GRBL `$$` listing: `$110`–`$112` max rate (mm/min),
    /// `$120`–`$122` acceleration (mm/s²), `$130`–`$132` max travel (mm).
    /// Other settings, comments and `ok` lines are ignored.
    pub(crate) fn add_grbl(&mut self, text: &str, envelope: GrblEnvelope) -> Result<(), ErrorKind> {
        self.grbl = Some(super::grbl_listing::GrblSettings::from_listing(text)?);
        for (n, v) in super::grbl_listing::listing(text)? {
            let (group, axis) = (n / 10, (n % 10) as usize);
            if !matches!(group, 11..=13) || axis > 2 {
                continue;
            }
            let a = &mut self.axes[axis];
            match group {
                11 => a.max_vel = Some(v.abs() / 60.0),
                12 => a.max_acc = Some(v.abs()),
                _ => {
                    let t = v.abs();
                    (a.min, a.max) = match envelope {
                        GrblEnvelope::Negative => (Some(-t), Some(0.0)),
                        GrblEnvelope::Positive => (Some(0.0), Some(t)),
                    };
                    a.limit_source = Some(format!("GRBL ${n}"));
                }
            }
        }
        Ok(())
    }

    /// Reads `--limits X0:300,Y0:200,Z-60:0` (millimetres, degrees for A-C;
    /// either bound may be left empty: `Z:0`).
    pub(crate) fn add_limits(&mut self, text: &str) -> Result<(), ErrorKind> {
        let bad = || {
            ErrorKind::Setup(SetupError::BadLimits {
                text: text.to_string(),
            })
        };
        for part in text.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            let mut chars = part.chars();
            let letter = chars.next().ok_or_else(bad)?.to_ascii_uppercase();
            let i = LETTERS.iter().position(|&c| c == letter).ok_or_else(bad)?;
            let (lo, hi) = chars.as_str().split_once(':').ok_or_else(bad)?;
            let num = |s: &str| -> Result<Option<f64>, ErrorKind> {
                let s = s.trim();
                if s.is_empty() {
                    return Ok(None);
                }
                s.parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .map(Some)
                    .ok_or_else(bad)
            };
            let (lo, hi) = (num(lo)?, num(hi)?);
            if lo.is_none() && hi.is_none() {
                return Err(bad());
            }
            if let (Some(l), Some(h)) = (lo, hi)
                && l > h
            {
                return Err(bad());
            }
            let a = &mut self.axes[i];
            a.min = lo;
            a.max = hi;
            a.limit_source = Some("--limits".into());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limits_option() {
        let mut m = MachineAxes::default();
        m.add_limits("X0:300, y-10:200,Z:0").unwrap();
        assert_eq!(m.axes[0].min, Some(0.0));
        assert_eq!(m.axes[0].max, Some(300.0));
        assert_eq!(m.axes[1].min, Some(-10.0));
        assert_eq!(m.axes[2].min, None);
        assert_eq!(m.axes[2].max, Some(0.0));
        for bad in ["X", "Q0:1", "X1:0", "X:", "Xa:1", "X0:inf"] {
            assert!(MachineAxes::default().add_limits(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn grbl_listing() {
        let text = "$0=10\n$110=6000.000\n$111=3000 (y)\n$120=250.000\n$130=300.000\n$132=80\nok\n";
        let mut m = MachineAxes::default();
        m.add_grbl(text, GrblEnvelope::Negative).unwrap();
        assert_eq!(m.axes[0].max_vel, Some(100.0));
        assert_eq!(m.axes[1].max_vel, Some(50.0));
        assert_eq!(m.axes[0].max_acc, Some(250.0));
        assert_eq!((m.axes[0].min, m.axes[0].max), (Some(-300.0), Some(0.0)));
        assert_eq!((m.axes[2].min, m.axes[2].max), (Some(-80.0), Some(0.0)));
        assert_eq!(m.axes[1].min, None);
        let mut p = MachineAxes::default();
        p.add_grbl(text, GrblEnvelope::Positive).unwrap();
        assert_eq!((p.axes[0].min, p.axes[0].max), (Some(0.0), Some(300.0)));
        assert!(
            MachineAxes::default()
                .add_grbl("$110=fast", GrblEnvelope::Negative)
                .is_err()
        );
    }

    #[test]
    fn ini_axes_and_joints() {
        let ini = Ini::parse(
            "[TRAJ]\nCOORDINATES = X Y Z\n[AXIS_X]\nMIN_LIMIT = -1\nMAX_LIMIT = 10\nMAX_VELOCITY = 2\n[JOINT_2]\nMAX_ACCELERATION = 3\nMIN_LIMIT=-4\n",
        );
        let mut m = MachineAxes::default();
        m.add_ini(&ini, false).unwrap();
        assert_eq!(m.axes[0].min, Some(-25.4));
        assert_eq!(m.axes[0].max, Some(254.0));
        assert_eq!(m.axes[0].max_vel, Some(50.8));
        assert_eq!(m.axes[2].max_acc, Some(3.0 * 25.4));
        assert_eq!(m.axes[2].min, Some(-4.0 * 25.4));
        assert_eq!(m.axes[2].max, None);
        let mut mm = MachineAxes::default();
        mm.add_ini(&ini, true).unwrap();
        assert_eq!(mm.axes[0].max, Some(10.0));
    }
}
