//! GRBL's settings and how its parser, motion control and planner turn a
//! move into planner blocks (gnea/grbl 1.1h, commit
//! `bfb67f0c7963fe3ce4aaf8a97f9009ea5a8db36e`: `planner.c`
//! `plan_buffer_line()`, `motion_control.c` `mc_arc()`, `defaults.h`
//! `DEFAULTS_GENERIC`, `config.h`).
//!
//! - A target is rounded to whole steps (`$100`–`$102`); a move of no step
//!   on any axis is dropped and leaves no junction behind.
//! - A block's acceleration and highest speed are the largest whose share
//!   on every axis stays within that axis's `$12x` and `$11x`: a diagonal
//!   may run faster than the slowest axis.
//! - The speed through a junction comes from the junction deviation `$11`:
//!   `v² = a·$11·s/(1−s)` with `s = sin(θ/2)` of the angle θ between the
//!   reversed previous direction and the new one and `a` the acceleration
//!   along the difference of the two directions; a reversal stops, a
//!   straight line does not limit.
//! - An arc is cut into `floor(|θ·r/2| / sqrt(tol·(2r − tol)))` chords
//!   (`$12`), each a block of its own.

use crate::diag::ErrorKind;

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
        for line in text.lines() {
            let Some((n, v)) = setting(line)? else {
                continue;
            };
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
        .ok_or_else(|| ErrorKind::BadMachineValue {
            source: format!("GRBL ${n}"),
            text: val.to_string(),
        })?;
    Ok(Some((n, v)))
}

/// The largest value along `unit` whose share on each axis stays within
/// that axis's `max` (GRBL's `limit_value_by_axis_maximum()`).
pub(crate) fn limit_by_axes(max: &[f64; 3], unit: &[f64; 3]) -> f64 {
    let mut v = f64::INFINITY;
    for i in 0..3 {
        if unit[i] != 0.0 {
            v = v.min(max[i] / unit[i].abs());
        }
    }
    v
}

/// The junction speed² limit between blocks of unit directions `prev` and
/// `unit` (GRBL's `plan_buffer_line()`), in (mm/s)².
pub(crate) fn junction_speed_sqr(s: &GrblSettings, prev: &[f64; 3], unit: &[f64; 3]) -> f64 {
    let cos_theta = -(prev[0] * unit[0] + prev[1] * unit[1] + prev[2] * unit[2]);
    if cos_theta > 0.999999 {
        // A reversal: a full stop (GRBL's minimum junction speed is 0).
        return 0.0;
    }
    if cos_theta < -0.999999 {
        return f64::INFINITY;
    }
    let mut j = [unit[0] - prev[0], unit[1] - prev[1], unit[2] - prev[2]];
    let n = (j[0] * j[0] + j[1] * j[1] + j[2] * j[2]).sqrt();
    if n > 0.0 {
        for c in &mut j {
            *c /= n;
        }
    }
    let a = limit_by_axes(&s.accel, &j);
    let sin_half = (0.5 * (1.0 - cos_theta)).sqrt();
    (a * s.junction_deviation * sin_half / (1.0 - sin_half)).max(0.0)
}

/// How many chords GRBL cuts an arc of `angle` radians (signed) and
/// radius `r` into (0: one straight move to the end).
pub(crate) fn arc_segments(s: &GrblSettings, angle: f64, r: f64) -> u64 {
    let tol = s.arc_tolerance;
    let d = (tol * (2.0 * r - tol)).sqrt();
    let n = (0.5 * angle * r).abs() / d;
    if n.is_finite() && n > 0.0 {
        n.floor().min(65535.0) as u64
    } else {
        0
    }
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

    #[test]
    fn corner_at_the_junction_deviation() {
        // A 90° corner from +X to +Y: cos θ = -(1·0) = 0, sin(θ/2) =
        // sqrt(0.5) = 0.70711; the direction of the junction (-1, 1)/√2
        // allows 10/0.70711 = 14.142 mm/s² on both axes; with $11 = 0.01:
        // v² = 14.142·0.01·0.70711/(1 − 0.70711) = 0.34142, v = 0.5843 mm/s.
        let s = GrblSettings::default();
        let v2 = junction_speed_sqr(&s, &[1.0, 0.0, 0.0], &[0.0, 1.0, 0.0]);
        assert!((v2.sqrt() - 0.584_31).abs() < 1e-5, "{}", v2.sqrt());
        // Straight on: no limit; back the same way: a stop.
        assert!(junction_speed_sqr(&s, &[1.0, 0.0, 0.0], &[1.0, 0.0, 0.0]).is_infinite());
        assert_eq!(
            junction_speed_sqr(&s, &[1.0, 0.0, 0.0], &[-1.0, 0.0, 0.0]),
            0.0
        );
    }

    #[test]
    fn arc_chords_from_the_tolerance() {
        // A half circle of radius 10 at $12 = 0.002: each chord may span
        // 2·sqrt(0.002·(20 − 0.002)) = 0.4 mm of sagitta-limited chord, half
        // of it 0.19999 mm; half the arc length is 0.5·π·10 = 15.708 mm:
        // floor(15.708 / 0.19999) = 78 chords.
        let s = GrblSettings::default();
        assert_eq!(arc_segments(&s, std::f64::consts::PI, 10.0), 78);
        assert_eq!(arc_segments(&s, 0.0, 10.0), 0);
    }
}
