//! Refusals of the lathe cycles G70–G72 (codes E1300–E1349): the checks
//! LinuxCNC makes on the cycle block and its contour subroutine, and the
//! contours it cannot cut.

use std::fmt;

use crate::geom::lathe::LatheError as Geom;

#[derive(Debug, Clone, PartialEq)]
pub enum LatheError {
    /// A G70–G72 block without Q (the contour subroutine's number).
    NoQ { code: String },
    /// G71/G72 with cutter compensation on.
    WithComp { code: String },
    /// A lathe cycle outside the XZ plane.
    NotXz { code: String },
    /// Q is not a whole, positive subroutine number.
    BadQ { q: f64 },
    /// U (incremental X) in a contour line in G91.
    UIncremental,
    /// U and X in the same contour line.
    UAndX,
    /// W (incremental Z) in a contour line in G91.
    WIncremental,
    /// W and Z in the same contour line.
    WAndZ,
    /// An arc of the contour with R and I or K.
    ArcRAndIk,
    /// An arc of the contour with neither I nor K nor R.
    ArcNoIk,
    /// A corner of the contour with both A (fillet) and C (chamfer).
    AAndC,
    /// I (depth of cut) not above zero.
    INotPositive,
    /// An R arc of the contour whose radius is less than half its chord.
    ArcRadiusTooSmall,
    /// The contour cannot be cut.
    Geometry(Geom),
    /// G70 with cutter compensation offsetting the path where the output
    /// keeps G41/G42 (or the compensation's geometry is not known): LinuxCNC
    /// compensates the cycle's moves from the contour's end, which written
    /// G0/G1/G2/G3 lines under G41/G42 do not reproduce.
    G70Comp { why: &'static str },
    /// A contour of more elements than a cycle may make moves (`limit`).
    ContourTooLong { limit: usize },
}

impl LatheError {
    pub fn code(&self) -> &'static str {
        use LatheError::*;
        match self {
            NoQ { .. } => "E1300",
            WithComp { .. } => "E1301",
            NotXz { .. } => "E1302",
            BadQ { .. } => "E1303",
            UIncremental => "E1304",
            UAndX => "E1305",
            WIncremental => "E1306",
            WAndZ => "E1307",
            ArcRAndIk => "E1308",
            ArcNoIk => "E1309",
            AAndC => "E1310",
            INotPositive => "E1311",
            ArcRadiusTooSmall => "E1312",
            Geometry(g) => match g {
                Geom::CornerFinish { .. } => "E1313",
                Geom::NotMonotonic => "E1314",
                Geom::ParallelLines => "E1315",
                Geom::LostContour => "E1316",
                Geom::StraightDive => "E1317",
                Geom::Degenerate => "E1318",
                Geom::Endless => "E1319",
                Geom::TooManyMoves => "E1320",
            },
            G70Comp { .. } => "E1321",
            ContourTooLong { .. } => "E1322",
        }
    }
}

impl fmt::Display for LatheError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use LatheError::*;
        match self {
            NoQ { code } => write!(f, "{code} requires a Q word (the contour subroutine)"),
            WithComp { code } => {
                write!(f, "{code} cannot be used with cutter compensation enabled")
            }
            NotXz { code } => write!(f, "{code} can only be used in the XZ plane (G18)"),
            BadQ { q } => write!(
                f,
                "Q{q} does not name a contour subroutine (a whole number is needed)"
            ),
            UIncremental => {
                f.write_str("lathe cycle contour: U cannot be used in incremental mode (G91)")
            }
            UAndX => f.write_str("lathe cycle contour: U and X in the same block"),
            WIncremental => {
                f.write_str("lathe cycle contour: W cannot be used in incremental mode (G91)")
            }
            WAndZ => f.write_str("lathe cycle contour: W and Z in the same block"),
            ArcRAndIk => f.write_str("lathe cycle contour: both R and I or K used for an arc"),
            ArcNoIk => f.write_str("lathe cycle contour: either I or K must be present for an arc"),
            AAndC => f.write_str("lathe cycle contour: both A and C on a corner"),
            INotPositive => f.write_str("lathe cycle: I must be greater than zero"),
            ArcRadiusTooSmall => {
                f.write_str("lathe cycle contour: arc radius too small to reach the end point")
            }
            Geometry(g) => write!(f, "lathe cycle: {g}"),
            ContourTooLong { limit } => {
                write!(f, "lathe cycle contour: more than {limit} elements")
            }
            G70Comp { why } => write!(
                f,
                "G70 with cutter compensation on is not flattened here: {why}"
            ),
        }
    }
}
