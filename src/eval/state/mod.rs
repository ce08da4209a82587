//! The modal state the flattened program puts the machine in, line by line,
//! starting from LinuxCNC's power-on state; it answers the predefined named
//! parameters and the position parameters.

pub(super) mod ccomp;
pub(super) mod cycle;
pub(super) mod lathe;
pub(super) mod modal;
pub(super) mod nurbs;
pub(super) mod restore;
pub mod tools;

/// Axis letters in parameter order (X Y Z A B C U V W).
pub const AXES: [u8; 9] = *b"xyzabcuvw";

#[derive(Debug, Clone, PartialEq)]
pub struct Modal {
    pub metric: bool,
    pub absolute: bool,
    pub ijk_absolute: bool,
    /// 170, 180, 190, 171, 181, 191
    pub plane: i32,
    /// 930, 940, 950
    pub feed_mode: i32,
    pub feed: f64,
    pub speed: f64,
    /// G-code ×10 (G0 → 0, G1 → 10, G80 → 800, G38.2 → 382)
    pub motion: i32,
    /// 1 (G54) … 9 (G59.3)
    pub coord_index: i32,
    pub tool_offset: bool,
    /// G98 (true) / G99
    pub retract_r: bool,
    /// G96 (css) / G97 (rpm)
    pub css: bool,
    /// 0 off, 3 cw, 4 ccw
    pub spindle: i32,
    pub mist: bool,
    pub flood: bool,
    /// 610, 611, 640
    pub path: i32,
    pub path_p: Option<f64>,
    pub path_q: Option<f64>,
    /// 400, 410, 420
    pub ccomp: i32,
    pub lathe_diameter: bool,
    pub speed_override: bool,
    pub feed_override: bool,
    pub adaptive_feed: bool,
    pub feed_hold: bool,
}

impl Default for Modal {
    fn default() -> Modal {
        Modal {
            metric: true,
            absolute: true,
            ijk_absolute: false,
            plane: 170,
            feed_mode: 940,
            feed: 0.0,
            speed: 0.0,
            motion: 800,
            coord_index: 1,
            tool_offset: false,
            retract_r: true,
            css: false,
            spindle: 0,
            mist: false,
            flood: false,
            path: 640,
            path_p: None,
            path_q: None,
            ccomp: 400,
            lathe_diameter: false,
            speed_override: true,
            feed_override: true,
            adaptive_feed: false,
            feed_hold: true,
        }
    }
}

impl Modal {
    /// The state after M2/M30.
    pub fn reset_at_end(&mut self) {
        self.coord_index = 1;
        self.plane = 170;
        self.absolute = true;
        self.feed_mode = 940;
        self.feed = 0.0;
        self.spindle = 0;
        self.mist = false;
        self.flood = false;
        self.ccomp = 400;
        self.motion = 10;
        self.speed_override = true;
        self.feed_override = true;
    }
}

/// Why a position became unknown.
#[derive(Debug, Clone, PartialEq)]
pub enum Unknown {
    Start,
    After(&'static str, u32),
}

#[derive(Debug, Clone)]
pub struct Position {
    /// Current position in program coordinates and program units.
    pub axes: [Result<f64, Unknown>; 9],
}

impl Position {
    pub fn unknown() -> Position {
        Position {
            axes: std::array::from_fn(|_| Err(Unknown::Start)),
        }
    }

    pub fn zero() -> Position {
        Position {
            axes: std::array::from_fn(|_| Ok(0.0)),
        }
    }
}
