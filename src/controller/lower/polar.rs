//! Polar coordinates: the `@` (radius) and `^` (angle, degrees) words of
//! a G17 motion block, as the X Y end point LinuxCNC 2.9 moves to.
//!
//! The rule, about the origin of the active coordinate system:
//!
//! * **G90**: the end point is `@`·(cos `^`, sin `^`); a missing `@` is the
//!   current distance from the origin, a missing `^` the current angle
//!   (an error at the origin, where there is none).
//! * **G91**: starting from the current point, `@` is added to its
//!   distance from the origin (angle kept), then `^` to its angle
//!   (distance kept). Either fails at the origin, where the angle is
//!   undefined.
//!
//! X and Y words are not allowed with polar words, and polar words only in
//! G17; the caller's block checks refuse those. The block is then written
//! with X and Y instead of `@` and `^`: absolute values in G90, and in G91
//! the differences from the current point (or absolute values under a G90
//! the caller adds).

use super::LowerError;
use crate::codes::Distance;
use crate::rules::polar_end;

/// The polar words of a block and where the tool is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PolarInput {
    pub distance: Distance,
    /// Current X and Y (program coordinates).
    pub current: [f64; 2],
    /// `@` word.
    pub radius: Option<f64>,
    /// `^` word, degrees.
    pub angle: Option<f64>,
}

/// The X Y end point of a block with polar words (absolute), by the
/// rule the evaluator and the machine model follow too (`polar_end`).
pub fn polar_target(p: &PolarInput) -> Result<[f64; 2], LowerError> {
    polar_end(p.distance, p.current, p.radius, p.angle).ok_or(LowerError::PolarAtOrigin)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn absolute_and_missing_words() {
        let t = polar_target(&PolarInput {
            distance: Distance::Absolute,
            current: [3.0, 4.0],
            radius: None,
            angle: Some(90.0),
        })
        .unwrap();
        assert!(t[0].abs() < 1e-12 && (t[1] - 5.0).abs() < 1e-12);
        let t = polar_target(&PolarInput {
            distance: Distance::Absolute,
            current: [3.0, 4.0],
            radius: Some(10.0),
            angle: None,
        })
        .unwrap();
        assert!((t[0] - 6.0).abs() < 1e-12 && (t[1] - 8.0).abs() < 1e-12);
    }

    #[test]
    fn incremental_steps_and_origin() {
        let t = polar_target(&PolarInput {
            distance: Distance::Incremental,
            current: [1.0, 0.0],
            radius: Some(1.0),
            angle: Some(90.0),
        })
        .unwrap();
        assert!(t[0].abs() < 1e-12 && (t[1] - 2.0).abs() < 1e-12);
        assert_eq!(
            polar_target(&PolarInput {
                distance: Distance::Incremental,
                current: [0.0, 0.0],
                radius: None,
                angle: Some(10.0),
            }),
            Err(LowerError::PolarAtOrigin)
        );
    }
}
