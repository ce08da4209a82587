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

use crate::machine::grbl_listing::GrblSettings;

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
