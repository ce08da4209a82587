//! A target controller's profile: plain data read by the lowering driver.
//! A profile is a TOML file (`file.rs` reads and checks one); the built-in
//! ones are such files under `profiles/`, embedded in the program. Adding a
//! controller is adding one file there and listing it in
//! [`super::BUILT_IN`].

mod file;

pub use file::ProfileError;

/// How the firmware counts a line against its buffer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum LineCount {
    /// Every byte of the line (the terminator included).
    AllBytes,
    /// Only the bytes kept after blanks and comments are dropped, plus the
    /// terminating byte (GRBL's line buffer).
    Significant,
}

/// What happens to comments.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Comments {
    /// Written as they are.
    Keep,
    /// Removed; messages `(MSG, …)` kept (cleaned) if the firmware shows them.
    Strip,
}

/// What M6 becomes by default.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ToolChange {
    /// M0 and a message naming the tool.
    Pause,
    /// M6 written as it is.
    Keep,
    /// M6 removed.
    Drop,
}

/// A controller's G-code dialect, as its parser source has it.
#[derive(Debug, Clone, PartialEq)]
pub struct Profile {
    pub name: String,
    pub summary: String,
    /// The firmware source this profile was built from (file and commit).
    pub source: String,
    /// Everything is written as flattened (no lowering, no checks).
    pub passthrough: bool,
    /// G codes accepted, ×10 (G38.2 → 382).
    pub g_codes: Vec<u16>,
    /// M codes accepted.
    pub m_codes: Vec<u16>,
    /// Letters of value words accepted (axis letters included).
    pub words: Vec<u8>,
    /// Axis letters the machine has.
    pub axes: Vec<u8>,
    /// G10 L numbers accepted.
    pub g10_l: Vec<u8>,
    /// Coordinate systems accepted (1 = G54 … 9 = G59.3).
    pub coord_systems: u8,
    /// Line buffer in bytes (terminator included) and how it is counted.
    pub line_limit: Option<(usize, LineCount)>,
    /// Significant digits the firmware reads in a number.
    pub max_digits: u8,
    /// Decimals written in millimetres and in inches.
    pub decimals_mm: u8,
    pub decimals_inch: u8,
    /// Bytes the firmware acts on wherever they appear (real-time
    /// commands), besides every byte above 0x7F when `high_bytes` is set.
    pub realtime: Vec<u8>,
    pub high_bytes: bool,
    pub comments: Comments,
    /// `(MSG, …)` is shown to the operator.
    pub messages: bool,
    /// The firmware skips `/` lines when its switch is on (otherwise it
    /// ignores the `/` and runs them, as GRBL does).
    pub block_delete: bool,
    /// Line numbers above this are refused.
    pub max_line_number: f64,
    /// Tool numbers above this are refused.
    pub max_tool: f64,
    /// `%` lines are understood.
    pub percent: bool,
    /// Spindle-synchronised motion (G33, G76).
    pub spindle_sync: bool,
    pub tool_change: ToolChange,
    /// G43.1 takes only a Z word.
    pub g43_1_z_only: bool,
    /// M1 stops the program when the controller's optional-stop switch is
    /// on, as on LinuxCNC (GRBL and FluidNC accept M1 and ignore it).
    pub optional_stop: bool,
    /// Arcs take P (turns).
    pub arc_turns: bool,
    /// A probe move shorter than this (mm) is refused by the firmware; 0:
    /// only one to the point the tool is at.
    pub min_probe_travel: f64,
}

impl Profile {
    pub fn has_g(&self, code10: u16) -> bool {
        self.g_codes.contains(&code10)
    }

    pub fn has_m(&self, m: u16) -> bool {
        self.m_codes.contains(&m)
    }

    pub fn has_word(&self, letter: u8) -> bool {
        self.words.contains(&letter)
    }

    pub fn has_axis(&self, letter: u8) -> bool {
        self.axes.contains(&letter)
    }

    /// Whether the firmware acts on byte `b` in real time.
    pub fn is_realtime(&self, b: u8) -> bool {
        (self.high_bytes && b > 0x7f) || self.realtime.contains(&b)
    }

    /// One line for `ngcflat targets`.
    pub fn describe(&self) -> String {
        let limit = match self.line_limit {
            Some((n, LineCount::Significant)) => {
                format!("{} bytes per line (blanks and comments not counted)", n - 1)
            }
            Some((n, LineCount::AllBytes)) => format!("{} bytes per line", n - 1),
            None => "no line limit".into(),
        };
        if self.passthrough {
            return format!("{:<9} {}", self.name, self.summary);
        }
        let axes: String = self.axes.iter().map(|&b| b as char).collect();
        format!(
            "{:<9} {}\n          axes {axes}; {limit}; numbers {} significant digits, {} decimals (mm) / {} (inch); M6: {}; {}\n          built from {}",
            self.name,
            self.summary,
            self.max_digits,
            self.decimals_mm,
            self.decimals_inch,
            match self.tool_change {
                ToolChange::Pause => "pause (M0)",
                ToolChange::Keep => "kept",
                ToolChange::Drop => "dropped",
            },
            if self.spindle_sync {
                "spindle-synchronised motion"
            } else {
                "no spindle sync (G33, G76, G96 refused)"
            },
            self.source
        )
    }
}
