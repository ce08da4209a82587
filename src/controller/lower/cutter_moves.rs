//! Cutter radius compensation for controllers that have none (GRBL,
//! grblHAL, FluidNC): the compensated path itself, as plain G0/G1/G2/G3
//! blocks, with G40/G41/G42 gone.
//!
//! The path is computed by [`crate::geom::cutter_comp::Comp`] exactly as LinuxCNC
//! computes it; this module writes the moves it releases. The caller feeds
//! the programmed moves of each block to the `Comp` and passes the released
//! moves here, with the tool position before the first of them. While the
//! `Comp` holds a move back ([`crate::geom::cutter_comp::Comp::holding`]), the
//! reference also holds back the feed, spindle, coolant and dwell commands
//! of the blocks that follow until the move is released: a caller writes
//! those blocks after the lines returned here, and writes each released
//! move's feed on its line (the tag carries what the caller needs for it).
//!
//! Arcs go through [`super::arc::lower_arc`] (parts of less than half a
//! turn, P turns unrolled). Lathe tools are already shifted to their tip by
//! the `Comp`. An arc whose start and end radius differ by more than a
//! controller reads as one circle (the reference releases one when a
//! program stop, M0/M1, falls inside a concave corner and the next move is
//! an arc) cannot be written and is refused ([`LowerError::BadArc`]); one
//! within [`arc_radius_tolerance`] is written as it is (the same centre and
//! end as LinuxCNC's canon). An arc of no radius (a helix milled with a
//! tool as wide as the hole) is the straight move it is.

use super::arc::{ArcInput, lower_arc};
use super::{LowerError, PlainLine, push};
use crate::codes::{Plane, Units};
use crate::geom::cutter_comp::Out;

/// XYZ indices of the compensation plane's coordinates (first, second,
/// third), as [`crate::geom::cutter_comp`] orders them: G17 X Y Z, G18 Z X Y.
/// LinuxCNC compensates in those two planes only.
fn axes(plane: Plane) -> Result<[usize; 3], LowerError> {
    match plane {
        Plane::XY | Plane::XZ => Ok(plane.axes()),
        Plane::YZ | Plane::UV | Plane::WU | Plane::VW => Err(LowerError::NotExpressible {
            construct: "cutter radius compensation",
            why: "it is only lowered in the XY and XZ planes (G17, G18)",
        }),
    }
}

/// The largest difference between the start and end radius of an arc
/// written as one (program units): 0.005 mm, which GRBL takes whatever the
/// radius, and below LinuxCNC's own arc tolerance.
pub fn arc_radius_tolerance(units: Units) -> f64 {
    match units {
        Units::Mm => 0.005,
        Units::Inch => 0.005 / 25.4,
    }
}

/// Blocks with the tag of the move each comes from, and the position after
/// the last move.
pub type Lowered<'a, T> = (Vec<(PlainLine, &'a T)>, [f64; 3]);

/// Plain blocks for the released moves `moves`, starting from `start` (X Y
/// Z, program units, absolute). Returns each block with the tag of the move
/// it comes from, and the position after the last move.
pub fn lower_comp_moves<T>(
    plane: Plane,
    start: [f64; 3],
    moves: &[Out<T>],
    radius_tolerance: f64,
) -> Result<Lowered<'_, T>, LowerError> {
    let [a, b, c] = axes(plane)?;
    let xyz = |p: [f64; 3]| {
        let mut v = [0.0; 3];
        v[a] = p[0];
        v[b] = p[1];
        v[c] = p[2];
        v
    };
    let mut out: Vec<(PlainLine, &T)> = Vec::new();
    let mut lines = Vec::new();
    let mut at = start;
    for m in moves {
        match m {
            Out::Line { rapid, end, tag } => {
                let p = xyz(*end);
                lines.clear();
                push(
                    &mut lines,
                    PlainLine::motion(if *rapid { 0.0 } else { 1.0 }, p),
                )?;
                out.extend(lines.drain(..).map(|l| (l, tag)));
                at = p;
            }
            Out::Arc {
                end,
                center,
                turn,
                end3,
                tag,
            } => {
                let p = xyz([end[0], end[1], *end3]);
                let centre = xyz([center[0], center[1], at[c]]);
                // After a program stop inside a concave corner the
                // reference can release an arc that does not start where the
                // tool is (its canon is not a circle): no G2/G3 expresses it.
                let r0 = (at[a] - center[0]).hypot(at[b] - center[1]);
                let r1 = (end[0] - center[0]).hypot(end[1] - center[1]);
                if (r0 - r1).abs() > radius_tolerance {
                    return Err(LowerError::BadArc);
                }
                if r0 <= radius_tolerance && r1 <= radius_tolerance {
                    // No radius: the tool moves straight.
                    lines.clear();
                    push(&mut lines, PlainLine::motion(1.0, p))?;
                    out.extend(lines.drain(..).map(|l| (l, tag)));
                    at = p;
                    continue;
                }
                let input = ArcInput {
                    plane,
                    clockwise: *turn < 0,
                    start: at,
                    end: p,
                    centre,
                    turns: turn.unsigned_abs().max(1),
                    radius_step: radius_tolerance,
                };
                for l in lower_arc(&input)? {
                    if out.len() >= super::MAX_LINES {
                        return Err(LowerError::TooManyLines);
                    }
                    out.push((l, tag));
                }
                at = p;
            }
        }
    }
    Ok((out, at))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn letters(l: &PlainLine) -> Vec<(char, f64)> {
        l.words
            .iter()
            .map(|w| (w.letter as char, w.value))
            .collect()
    }

    #[test]
    fn lines_and_arcs_in_g18_map_back_to_x_and_z() {
        // Plane coordinates of G18 are (Z, X, Y).
        let moves = vec![
            Out::Line {
                rapid: false,
                end: [-5.0, 10.0, 0.0],
                tag: 1,
            },
            Out::Arc {
                end: [-10.0, 15.0],
                center: [-10.0, 10.0],
                turn: 1,
                end3: 0.0,
                tag: 2,
            },
        ];
        let (lines, end) = lower_comp_moves(Plane::XZ, [0.0, 0.0, 0.0], &moves, 0.005).unwrap();
        assert_eq!(end, [15.0, 0.0, -10.0]);
        assert_eq!(
            letters(&lines[0].0),
            vec![('G', 1.0), ('X', 10.0), ('Y', 0.0), ('Z', -5.0)]
        );
        assert_eq!(*lines[0].1, 1);
        let arc = letters(&lines[1].0);
        // A quarter turn counterclockwise from Z towards X: one G3.
        assert_eq!(lines.len(), 2);
        assert_eq!(arc[0], ('G', 3.0));
        assert!(arc.contains(&('X', 15.0)) && arc.contains(&('Z', -10.0)));
        // Centre offsets from the arc's start (X10 Z-5): I0 K-5.
        assert!(
            arc.contains(&('I', 0.0)) && arc.contains(&('K', -5.0)),
            "{arc:?}"
        );
        assert_eq!(*lines[1].1, 2);
    }

    #[test]
    fn arcs_within_the_radius_tolerance_are_written_and_others_refused() {
        let arc = |end: [f64; 2]| Out::Arc {
            end,
            center: [0.0, 0.0],
            turn: 1,
            end3: 0.0,
            tag: (),
        };
        // Start radius 10, end radius 10.004: one arc about the same centre.
        let near = [arc([0.0, 10.004])];
        let (lines, _) = lower_comp_moves(Plane::XY, [10.0, 0.0, 0.0], &near, 0.005).unwrap();
        assert_eq!(letters(&lines[0].0)[0], ('G', 3.0));
        let far = [arc([0.0, 10.01])];
        assert!(matches!(
            lower_comp_moves(Plane::XY, [10.0, 0.0, 0.0], &far, 0.005),
            Err(LowerError::BadArc)
        ));
    }

    #[test]
    fn an_arc_of_no_radius_is_a_straight_move() {
        // A helix about the point the tool is at (hole as wide as the tool).
        let moves = [Out::Arc {
            end: [2.0, 3.0],
            center: [2.0, 3.0],
            turn: 1,
            end3: -1.5,
            tag: (),
        }];
        let (lines, end) = lower_comp_moves(Plane::XY, [2.0, 3.0, 0.0], &moves, 0.005).unwrap();
        assert_eq!(lines.len(), 1);
        assert_eq!(
            letters(&lines[0].0),
            vec![('G', 1.0), ('X', 2.0), ('Y', 3.0), ('Z', -1.5)]
        );
        assert_eq!(end, [2.0, 3.0, -1.5]);
    }

    #[test]
    fn full_turns_are_split() {
        let moves = vec![Out::Arc {
            end: [1.0, 0.0],
            center: [0.0, 0.0],
            turn: 2,
            end3: -1.0,
            tag: (),
        }];
        let (lines, end) = lower_comp_moves(Plane::XY, [1.0, 0.0, 0.0], &moves, 0.005).unwrap();
        // Two whole turns: more than four parts of under half a turn.
        assert!(lines.len() > 4, "{}", lines.len());
        assert_eq!(end, [1.0, 0.0, -1.0]);
    }

    #[test]
    fn planes_other_than_g17_and_g18_are_refused() {
        let moves = [Out::Line {
            rapid: false,
            end: [1.0, 2.0, 3.0],
            tag: (),
        }];
        for plane in [Plane::YZ, Plane::UV, Plane::WU, Plane::VW] {
            let e = lower_comp_moves(plane, [0.0; 3], &moves, 0.005).unwrap_err();
            assert_eq!(e.code(), "E1105", "{plane:?}");
        }
    }
}
