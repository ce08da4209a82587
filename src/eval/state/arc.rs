//! The reference's checks of an arc's geometry, which the machine model
//! (where it knows the start), the block checks and a target's lowering
//! ask.

use crate::codes::{ArcDistance, Units};
use crate::diag::BlockError;

/// The reference's refusal of an arc (its `arc_data_r` and `arc_data_ijk`
/// checks, with its tolerances for `units`), if it refuses it: from
/// `start` to `end` (the plane's first two axes, program units), with
/// radius `r`, or else the centre words `ij` of those axes (an absent one
/// is 0) read by `distance`. The evaluator's checks of a line and a
/// target's lowering (where it knows the positions the evaluator does
/// not) both ask it.
pub(crate) fn arc_refusal(
    ccw: bool,
    r: Option<f64>,
    ij: [Option<f64>; 2],
    distance: ArcDistance,
    units: Units,
    start: [f64; 2],
    end: [f64; 2],
) -> Option<BlockError> {
    use crate::geom::cutter_comp::{Arc, ArcCenter, CompError, Tolerances, arc_center};
    let (i, j) = (ij[0].unwrap_or(0.0), ij[1].unwrap_or(0.0));
    let center = match r {
        Some(r) => ArcCenter::Radius(r),
        None => ArcCenter::Offsets { i, j, distance },
    };
    let arc = Arc {
        ccw,
        center,
        turns: 1,
    };
    Some(
        match arc_center(&Tolerances::default_for(units), arc, start, end).err()? {
            CompError::ArcSamePoint => BlockError::ArcSamePoint,
            CompError::RadiusTooSmall => BlockError::ArcRadiusTooSmall,
            CompError::ZeroRadiusArc => BlockError::ZeroRadiusArc,
            // (An R arc fails only as above.)
            _ => {
                let c = match distance {
                    ArcDistance::Absolute => [i, j],
                    ArcDistance::Incremental => [start[0] + i, start[1] + j],
                };
                let r = |p: [f64; 2]| (p[0] - c[0]).hypot(p[1] - c[1]);
                BlockError::ArcRadiiDiffer {
                    r1: r(start),
                    r2: r(end),
                }
            }
        },
    )
}
