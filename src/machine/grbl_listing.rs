//! A GRBL `$$` listing: the settings GRBL's planner runs a program with
//! (gnea/grbl 1.1h, commit `bfb67f0c7963fe3ce4aaf8a97f9009ea5a8db36e`,
//! `defaults.h` `DEFAULTS_GENERIC`, `settings.c`).

use crate::diag::{ErrorKind, SetupError};

/// The GRBL settings the run time depends on.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct GrblSettings {
    /// `$1` step idle delay (ms): GRBL waits this long each time the
    /// machine comes to a full stop (255: keep the motors on, no wait).
    pub(crate) idle_delay_ms: f64,
    /// `$11` junction deviation (mm).
    pub(crate) junction_deviation: f64,
    /// `$12` arc tolerance (mm).
    pub(crate) arc_tolerance: f64,
    /// `$100`–`$102` steps per mm.
    pub(crate) steps_per_mm: [f64; 3],
    /// `$110`–`$112` maximum rate (mm/min).
    pub(crate) max_rate: [f64; 3],
    /// `$120`–`$122` acceleration (mm/s²).
    pub(crate) accel: [f64; 3],
    /// Whether every value came from GRBL's defaults (no listing given).
    pub(crate) defaults: bool,
}

impl Default for GrblSettings {
    /// GRBL 1.1h's `DEFAULTS_GENERIC`, what a fresh board answers to `$$`.
    fn default() -> GrblSettings {
        GrblSettings {
            idle_delay_ms: 25.0,
            junction_deviation: 0.01,
            arc_tolerance: 0.002,
            steps_per_mm: [250.0; 3],
            max_rate: [500.0; 3],
            accel: [10.0; 3],
            defaults: true,
        }
    }
}

impl GrblSettings {
    /// Reads a saved `$$` listing over GRBL's defaults: `$1`, `$11`, `$12`,
    /// `$100`–`$102`, `$110`–`$112`, `$120`–`$122`; other lines are ignored.
    pub(crate) fn from_listing(text: &str) -> Result<GrblSettings, ErrorKind> {
        let mut s = GrblSettings {
            defaults: false,
            ..GrblSettings::default()
        };
        for (n, v) in listing(text)? {
            let axis = (n % 10) as usize;
            match n {
                1 => s.idle_delay_ms = v,
                11 => s.junction_deviation = v.abs(),
                12 => s.arc_tolerance = v.abs(),
                100..=102 => s.steps_per_mm[axis] = v.abs(),
                110..=112 => s.max_rate[axis] = v.abs(),
                120..=122 => s.accel[axis] = v.abs(),
                _ => {}
            }
        }
        Ok(s)
    }

    /// The idle wait after a full stop (s).
    pub(crate) fn idle_wait(&self) -> f64 {
        if self.idle_delay_ms >= 255.0 {
            0.0
        } else {
            self.idle_delay_ms.max(0.0) / 1000.0
        }
    }
}

/// The one reader of a `$$` listing: its `$n=v` lines in order (other
/// lines, comments and `ok` are ignored); a value that is not a finite
/// number is an error.
pub(crate) fn listing(text: &str) -> Result<Vec<(u32, f64)>, ErrorKind> {
    let mut out = Vec::new();
    for line in text.lines() {
        if let Some(s) = setting(line)? {
            out.push(s);
        }
    }
    Ok(out)
}

/// `$n=v` of a listing line, `None` for any other line.
fn setting(line: &str) -> Result<Option<(u32, f64)>, ErrorKind> {
    let Some(rest) = line.trim().strip_prefix('$') else {
        return Ok(None);
    };
    let Some((num, val)) = rest.split_once('=') else {
        return Ok(None);
    };
    let Ok(n) = num.trim().parse::<u32>() else {
        return Ok(None);
    };
    let val = val.split(['(', ';', ' ', '\t']).next().unwrap_or("").trim();
    let v: f64 = val
        .parse()
        .ok()
        .filter(|x: &f64| x.is_finite())
        .ok_or_else(|| {
            ErrorKind::Setup(SetupError::BadMachineValue {
                source: format!("GRBL ${n}"),
                text: val.to_string(),
            })
        })?;
    Ok(Some((n, v)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn listing_over_defaults() {
        let s =
            GrblSettings::from_listing("$1=255\n$11=0.02\n$110=1000 (x max rate)\nok\n").unwrap();
        assert_eq!(s.idle_wait(), 0.0);
        assert_eq!(s.junction_deviation, 0.02);
        assert_eq!(s.max_rate, [1000.0, 500.0, 500.0]);
        assert!(!s.defaults);
        assert!(GrblSettings::default().defaults);
        assert!(GrblSettings::from_listing("$120=fast").is_err());
    }
}
