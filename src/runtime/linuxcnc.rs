//! LinuxCNC 2.9's trajectory planner as a model: how it turns moves into
//! segments, blends their corners and limits their speed (LinuxCNC
//! `src/emc/tp/` at commit `5a7a31a26c30baae5de88a2305c404b5e6d7896e`,
//! branch 2.9: `tp.c` `tpAddLine()`, `tpAddCircle()`, `tpSetupTangent()`,
//! `tpRunOptimization()`; `blendmath.c` `blendParamKinematics()`,
//! `blendComputeParameters()`, `pmCircleActualMaxVel()`,
//! `calculateInscribedDiameter()`; `tc.c` `tcFindBlendTolerance()`,
//! `tcGetTangentialMaxAccel()`; `emccfg.h` for the defaults of what the
//! INI does not say).
//!
//! - **Limits.** A straight segment's speed and acceleration are the
//!   largest whose share on every axis stays within that axis's
//!   `MAX_VELOCITY` and `MAX_ACCELERATION` (`[AXIS_<L>]`, else
//!   `[JOINT_<n>]`; LinuxCNC's default 1 machine unit/s and /s² where the
//!   INI says nothing), and the speed within `[TRAJ]MAX_LINEAR_VELOCITY`.
//!   A segment no longer than one servo cycle at its speed is slowed to
//!   its length per cycle.
//! - **Arcs.** An arc runs at most at the slowest of its plane's axes, and
//!   at most `sqrt(0.866·a·r)`: the normal acceleration stays within
//!   `sqrt(1 − 0.5²)` of the axis limit. Its tangential acceleration is
//!   what is left, at most half the limit.
//! - **Corners (G64).** A corner between two segments is rounded by a
//!   blend arc within the `G64 P` tolerance (none given: a quarter of the
//!   shorter segment), using at most half of each segment; the machine
//!   runs the blend arc at `sqrt(0.866·a·R)`, `a` the acceleration the
//!   axes allow in the corner's plane. A corner within a small kink of a
//!   straight line (the change of direction at full speed asks less than
//!   a tenth of an axis's acceleration within one servo cycle) is run
//!   through at speed. A reversal (within 2°) stops.
//! - **Exact stop (G61, G61.1).** Every segment ends at rest.
//! - **Look-ahead.** The planner plans back over the last
//!   `ARC_BLEND_OPTIMIZATION_DEPTH` (50) segments, blend arcs included,
//!   the last ending at rest.
//! - **Stops.** Spindle, coolant, dwell, tool change, pause, probe and the
//!   program's end wait for the motion to finish. A dwell is waited
//!   exactly.

use super::Charge;
use super::planner::Block;

/// A corner between segments whose directions differ by less than this
/// (radians) is a reversal: `tpSetupTangent()`'s `SHARP_CORNER_DEG`.
const SHARP_CORNER: f64 = 2.0 * std::f64::consts::PI / 180.0;
/// `BLEND_ACC_RATIO_TANGENTIAL` and `BLEND_ACC_RATIO_NORMAL`.
const ACC_TANGENTIAL: f64 = 0.5;
const ACC_NORMAL: f64 = 0.866_025_403_784_438_6;
/// `BLEND_DIST_FRACTION`: a blend may use this much of a segment.
const BLEND_FRACTION: f64 = 0.5;
/// `tcFindBlendTolerance()`: with no tolerance, this much of a segment.
const TOLERANCE_RATIO: f64 = 0.25;
/// `ARC_BLEND_KINK_RATIO` (`[TRAJ]`, default 0.1).
const KINK_RATIO: f64 = 0.1;
/// `ARC_BLEND_GAP_CYCLES` (`[TRAJ]`, default 4).
const GAP_CYCLES: f64 = 4.0;
/// LinuxCNC's defaults (`emccfg.h`): an axis's `MAX_VELOCITY` and
/// `MAX_ACCELERATION` when the INI gives none, in machine units.
pub(crate) const DEFAULT_AXIS_LIMIT: f64 = 1.0;
/// `ARC_BLEND_OPTIMIZATION_DEPTH`'s default.
pub(crate) const DEFAULT_DEPTH: usize = 50;
/// The servo period of LinuxCNC's configurations (1 ms).
pub(crate) const DEFAULT_CYCLE: f64 = 0.001;

/// The machine's limits as LinuxCNC's planner reads them (mm, degrees, s).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Limits {
    pub(crate) vel: [f64; 9],
    pub(crate) acc: [f64; 9],
    /// `[TRAJ]MAX_LINEAR_VELOCITY` (infinite when not given).
    pub(crate) traj_vel: f64,
    /// `[TRAJ]MAX_LINEAR_ACCELERATION` (infinite when not given).
    pub(crate) traj_acc: f64,
    /// The planner's cycle (s).
    pub(crate) cycle: f64,
    /// Segments planned back over.
    pub(crate) depth: usize,
    /// Where the limits came from.
    pub(crate) source: LimitSource,
}

/// Where a LinuxCNC model's limits came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum LimitSource {
    /// No INI: LinuxCNC's defaults for every axis.
    Defaults,
    /// The INI, LinuxCNC's defaults for the axes' values it does not give.
    IniWithDefaults,
    /// The INI gives every moving axis's limits.
    Ini,
}

impl Limits {
    /// From the machine's axes (an INI's values in mm) and its `[TRAJ]`.
    pub(crate) fn from_axes(axes: &crate::machine::axes::MachineAxes) -> Limits {
        let unit = axes.traj.as_ref().map_or(1.0, |t| t.unit_mm);
        let mut defaulted = false;
        let mut pick = |v: Option<f64>, i: usize| {
            v.unwrap_or_else(|| {
                if i < 3 {
                    defaulted = true;
                }
                DEFAULT_AXIS_LIMIT * if (3..6).contains(&i) { 1.0 } else { unit }
            })
        };
        let vel = std::array::from_fn(|i| pick(axes.axes[i].max_vel, i));
        let acc = std::array::from_fn(|i| pick(axes.axes[i].max_acc, i));
        let t = axes.traj.as_ref();
        Limits {
            vel,
            acc,
            traj_vel: t.and_then(|t| t.max_vel).unwrap_or(f64::INFINITY),
            traj_acc: t.and_then(|t| t.max_acc).unwrap_or(f64::INFINITY),
            cycle: t.and_then(|t| t.cycle).unwrap_or(DEFAULT_CYCLE),
            depth: t.and_then(|t| t.depth).unwrap_or(DEFAULT_DEPTH).max(2),
            source: match (t.is_some(), defaulted) {
                (false, _) => LimitSource::Defaults,
                (true, true) => LimitSource::IniWithDefaults,
                (true, false) => LimitSource::Ini,
            },
        }
    }
}

/// One segment as the planner holds it before its corners are known.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Seg {
    /// Length left to run (mm; degrees for a move of rotary axes alone).
    pub(crate) len: f64,
    /// Length as programmed.
    pub(crate) nominal_len: f64,
    /// Unit tangents at the start and the end (XYZ).
    pub(crate) u0: [f64; 3],
    pub(crate) u1: [f64; 3],
    /// Requested speed (mm/s): the feed, or for a rapid the segment's
    /// highest.
    pub(crate) req: f64,
    /// Highest speed the axes allow (mm/s).
    pub(crate) maxvel: f64,
    /// Acceleration along the path the axes allow (mm/s²), before an
    /// arc's share for the normal acceleration.
    pub(crate) acc: f64,
    /// Share of `acc` left for speeding up and slowing down (arcs).
    pub(crate) acc_ratio: f64,
    pub(crate) arc: bool,
    /// Rotary or UVW axes move: LinuxCNC makes no blend arc.
    pub(crate) rotary: bool,
    /// The path mode it was planned in: exact stop, or the G64 tolerance.
    pub(crate) exact: bool,
    pub(crate) tolerance: f64,
    pub(crate) charge: Charge,
    /// Square of the highest speed it may be entered at.
    pub(crate) entry_sqr: f64,
}

impl Seg {
    /// The speed it cruises at (mm/s).
    fn cruise(&self) -> f64 {
        self.req.min(self.maxvel)
    }

    /// The block the window plans and runs.
    pub(crate) fn block(&self) -> Block {
        let v = self.cruise();
        Block {
            mm: self.len.max(0.0),
            accel: self.acc * self.acc_ratio,
            nominal: v,
            max_entry_sqr: self.entry_sqr.min(v * v),
            entry_sqr: 0.0,
            rev_sqr: f64::NAN,
            charge: self.charge,
        }
    }
}

/// The largest value along `dir` (any length) whose share on each axis
/// stays within `max` (LinuxCNC's canon `getStraightVelocity()` and
/// `getStraightAcceleration()`).
pub(crate) fn along(max: &[f64; 9], dir: &[f64; 9]) -> f64 {
    let len = path_len(dir);
    let mut v = f64::INFINITY;
    for i in 0..9 {
        if dir[i] != 0.0 {
            v = v.min(max[i] * len / dir[i].abs());
        }
    }
    v
}

/// The path length of a move: XYZ, else UVW, else ABC.
pub(crate) fn path_len(d: &[f64; 9]) -> f64 {
    let lin = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    if lin > 0.0 {
        return lin;
    }
    let uvw = (d[6] * d[6] + d[7] * d[7] + d[8] * d[8]).sqrt();
    if uvw > 0.0 {
        return uvw;
    }
    (d[3] * d[3] + d[4] * d[4] + d[5] * d[5]).sqrt()
}

/// An arc's highest speed and the share of its acceleration left along
/// the path, for radius `r`, highest speed `vmax` and acceleration `a`
/// (`pmCircleActualMaxVel()`): the normal acceleration `v²/r` stays within
/// 0.866·a; what it leaves, `sqrt(1 − (v²/r/a)²)`, but at least half.
pub(crate) fn arc_limits(r: f64, vmax: f64, a: f64) -> (f64, f64) {
    let a_n_cut = ACC_NORMAL * a;
    let a_n = vmax * vmax / r.max(1e-300);
    if a_n > a_n_cut {
        ((a_n_cut * r).sqrt(), ACC_TANGENTIAL)
    } else {
        (vmax, (1.0 - (a_n / a).powi(2)).sqrt())
    }
}

/// What happens at the corner between two segments.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Corner {
    /// The machine stops.
    Stop,
    /// Run through at up to this speed (mm/s), the acceleration of both
    /// segments reduced by the kink's share.
    Tangent { speed: f64, reduce: f64 },
    /// A blend arc: each segment gives up `trim` mm to the arc of `len`
    /// mm, which runs at up to `speed` (its highest `maxvel`) with
    /// acceleration `acc` along the path.
    Blend {
        trim: f64,
        len: f64,
        speed: f64,
        maxvel: f64,
        acc: f64,
    },
}

/// The corner between `prev` and `next` (`tpHandleBlendArc()`), with the
/// machine's acceleration limits per axis (XYZ).
pub(crate) fn corner(prev: &Seg, next: &Seg, acc: &[f64; 3], cycle: f64) -> Corner {
    if prev.exact || prev.rotary || next.rotary {
        return Corner::Stop;
    }
    let (u1, u2) = (prev.u1, next.u0);
    let dot = u1[0] * u2[0] + u1[1] * u2[1] + u1[2] * u2[2];
    // Anti-parallel within SHARP_CORNER: a reversal.
    if dot < -SHARP_CORNER.cos() {
        return Corner::Stop;
    }
    // tpSetupTangent(): the acceleration a change of direction at full
    // speed asks of each axis within one cycle, against its limit.
    let v_max = prev.cruise().min(next.cruise());
    let a_inst = v_max / cycle + next.acc;
    let mut scale: f64 = 0.0;
    for i in 0..3 {
        let d = (a_inst * (u2[i] - u1[i])).abs();
        if d > 0.0 {
            scale = scale.max(d / acc[i]);
        }
    }
    if prev.arc || next.arc {
        scale /= ACC_TANGENTIAL;
    }
    if scale < KINK_RATIO {
        return Corner::Tangent {
            speed: v_max,
            reduce: scale,
        };
    }
    match blend(prev, next, acc) {
        Some(c) => c,
        // tpChooseBestBlend(): the kink's speed, the next best.
        None => Corner::Tangent {
            speed: v_max * KINK_RATIO / scale,
            reduce: KINK_RATIO,
        },
    }
}

/// A blend arc between two segments, as for two lines
/// (`blendInit3FromLineLine()`, `blendParamKinematics()`,
/// `blendComputeParameters()`); `None` when none fits.
fn blend(prev: &Seg, next: &Seg, acc: &[f64; 3]) -> Option<Corner> {
    let (u1, u2) = (prev.u1, next.u0);
    let dot = (u1[0] * u2[0] + u1[1] * u2[1] + u1[2] * u2[2]).clamp(-1.0, 1.0);
    // θ: half the angle between the reversed first direction and the
    // second; φ: the change of direction.
    let theta = (-dot).acos() / 2.0;
    if std::f64::consts::FRAC_PI_2 - theta < 1e-6 || theta < 1e-6 {
        return None;
    }
    let phi = std::f64::consts::PI - 2.0 * theta;
    // The plane of the corner: a_max is the largest acceleration every
    // direction in it allows (calculateInscribedDiameter()).
    let mut n = [
        u1[1] * u2[2] - u1[2] * u2[1],
        u1[2] * u2[0] - u1[0] * u2[2],
        u1[0] * u2[1] - u1[1] * u2[0],
    ];
    let nn = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    if nn <= 0.0 {
        return None;
    }
    for c in &mut n {
        *c /= nn;
    }
    let mut a_max = f64::INFINITY;
    for i in 0..3 {
        let mut p = [-n[0] * n[i], -n[1] * n[i], -n[2] * n[i]];
        p[i] += 1.0;
        p[i] = p[i].abs().max(1e-12);
        let m = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
        a_max = a_max.min(acc[i] / m);
    }
    let a_n = a_max * ACC_NORMAL;
    // tcFindBlendTolerance(): no tolerance is a quarter of a segment.
    let t1 = if prev.tolerance > 0.0 {
        prev.tolerance
    } else {
        prev.nominal_len * TOLERANCE_RATIO
    };
    let t2 = if next.tolerance > 0.0 {
        next.tolerance
    } else {
        next.nominal_len * TOLERANCE_RATIO
    };
    let tolerance = t1
        .min(t2)
        .min(prev.nominal_len * TOLERANCE_RATIO)
        .min(next.nominal_len * TOLERANCE_RATIO);
    let l1 = prev.len.min(prev.nominal_len * BLEND_FRACTION);
    let l2 = next.len * BLEND_FRACTION;
    let v_req = prev.cruise().max(next.cruise());
    let h_tol = tolerance / (1.0 - theta.sin());
    let d_tol = theta.cos() * h_tol;
    let d_geom = l1.min(l2).min(d_tol);
    let r_geom = theta.tan() * d_geom;
    let v_plan = (a_n * r_geom).sqrt().min(v_req);
    let a_par = a_max * 0.5;
    let v_tri = (2.0 * a_par * d_geom).sqrt();
    let s_blend = v_tri.min(v_plan) / a_par * v_plan;
    let r_blend = (s_blend / phi).min(r_geom);
    let r_plan = (v_plan * v_plan / a_n).max(r_blend);
    let d_plan = r_plan / theta.tan();
    let s_arc = r_plan * phi;
    if !(r_plan >= 1e-12 && s_arc >= 1e-6) {
        return None;
    }
    Some(Corner::Blend {
        trim: d_plan,
        len: s_arc,
        speed: v_plan,
        maxvel: v_plan,
        acc: a_max * ACC_TANGENTIAL,
    })
}

/// Whether the rest of a segment after a blend is so short the planner
/// drops it (`blendCheckConsume()`: under `ARC_BLEND_GAP_CYCLES` cycles at
/// the blend's speed).
pub(crate) fn consumed(rest: f64, speed: f64, cycle: f64) -> bool {
    rest / speed < GAP_CYCLES * cycle
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(len: f64, u: [f64; 3], req: f64, acc: f64, tolerance: f64) -> Seg {
        Seg {
            len,
            nominal_len: len,
            u0: u,
            u1: u,
            req,
            maxvel: f64::INFINITY,
            acc,
            acc_ratio: 1.0,
            arc: false,
            rotary: false,
            exact: false,
            tolerance,
            charge: Charge::default(),
            entry_sqr: 0.0,
        }
    }

    #[test]
    fn a_blend_within_the_tolerance() {
        // A 90° corner from +X to +Y, both 100 mm at 10 mm/s, axes at
        // 100 mm/s², G64 P0.1. θ = 45°, φ = 90°. The plane is XY: a_max =
        // 100, a_n = 86.603. h_tol = 0.1/(1 − sin 45°) = 0.34142, d_tol =
        // cos 45°·h_tol = 0.24142 (the arc's middle 0.1 mm inside the
        // corner); d_geom = min(50, 50, 0.24142); R_geom = tan 45°·d_geom =
        // 0.24142; v_plan = min(sqrt(86.603·0.24142), 10) = 4.5725 mm/s.
        // a_par = 50, v_tri = sqrt(2·50·0.24142) = 4.9135; s_blend =
        // 4.5725/50·4.5725 = 0.41816; R_blend = min(0.41816/(π/2),
        // 0.24142) = 0.24142; R_plan = max(4.5725²/86.603, 0.24142) =
        // 0.24142; the arc is R·φ = 0.37922 mm long, 0.24142 mm taken
        // from each line.
        let a = line(100.0, [1.0, 0.0, 0.0], 10.0, 100.0, 0.1);
        let b = line(100.0, [0.0, 1.0, 0.0], 10.0, 100.0, 0.1);
        let Corner::Blend {
            trim, len, speed, ..
        } = corner(&a, &b, &[100.0; 3], 0.001)
        else {
            panic!("a blend arc");
        };
        assert!((speed - 4.5725).abs() < 1e-4, "{speed}");
        assert!((trim - 0.24142).abs() < 1e-5, "{trim}");
        assert!((len - 0.37922).abs() < 1e-5, "{len}");
        // G64 P0: a quarter of the shorter segment, 25 mm: d_tol =
        // 0.70711·25/(1 − 0.70711) = 60.355, d_geom = 50 (half a
        // segment), R = 50, v_plan = min(sqrt(86.603·50), 10) = 10: the
        // corner is run at the feed.
        let a = line(100.0, [1.0, 0.0, 0.0], 10.0, 100.0, 0.0);
        let b = line(100.0, [0.0, 1.0, 0.0], 10.0, 100.0, 0.0);
        let Corner::Blend { speed, .. } = corner(&a, &b, &[100.0; 3], 0.001) else {
            panic!("a blend arc");
        };
        assert_eq!(speed, 10.0);
    }

    #[test]
    fn exact_stop_reversal_and_kink() {
        let mut a = line(10.0, [1.0, 0.0, 0.0], 10.0, 100.0, 0.0);
        let b = line(10.0, [0.0, 1.0, 0.0], 10.0, 100.0, 0.0);
        a.exact = true;
        assert_eq!(corner(&a, &b, &[100.0; 3], 0.001), Corner::Stop);
        a.exact = false;
        let back = line(10.0, [-1.0, 0.0, 0.0], 10.0, 100.0, 0.0);
        assert_eq!(corner(&a, &back, &[100.0; 3], 0.001), Corner::Stop);
        // A kink of 0.0001 rad at 10 mm/s: a_inst = 10/0.001 + 100 =
        // 10100 mm/s², times |Δu| = 0.0001 on Y: 1.01 mm/s², 0.0101 of
        // the 100 mm/s² limit, under 0.1: run through at 10 mm/s.
        let k = 0.0001f64;
        let c = line(10.0, [k.cos(), k.sin(), 0.0], 10.0, 100.0, 0.0);
        match corner(&a, &c, &[100.0; 3], 0.001) {
            Corner::Tangent { speed, reduce } => {
                assert_eq!(speed, 10.0);
                assert!((reduce - 0.0101).abs() < 1e-6, "{reduce}");
            }
            c => panic!("{c:?}"),
        }
    }

    #[test]
    fn the_arc_speed_limit() {
        // r = 1 mm, axes 100 mm/s and 1000 mm/s²: v²/r = 10⁴ > 866.03, so
        // v = sqrt(866.03·1) = 29.428 mm/s and half the acceleration is
        // left along the path.
        let (v, k) = arc_limits(1.0, 100.0, 1000.0);
        assert!((v - 29.428).abs() < 1e-3, "{v}");
        assert_eq!(k, 0.5);
        // r = 100: 100²/100 = 100 mm/s² of normal acceleration, a tenth:
        // the full speed, sqrt(1 − 0.1²) = 0.99499 of it left.
        let (v, k) = arc_limits(100.0, 100.0, 1000.0);
        assert_eq!(v, 100.0);
        assert!((k - 0.994_987).abs() < 1e-6, "{k}");
    }
}
