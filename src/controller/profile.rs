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
    /// M6 refused: the firmware can neither change tools nor pause.
    Refuse,
}

/// How many commands the firmware takes from one line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum CommandsPerLine {
    /// Several G and M codes on a line, run in LinuxCNC's order.
    Many,
    /// The first command of a line alone (Klipper, Marlin: `G21 G1 X20`
    /// runs G21 and drops the move). Each command is written on a line of
    /// its own, in the order LinuxCNC runs them, with its own words; every
    /// move names its motion code, F rides on the next move and S on the
    /// spindle command; line numbers are not written.
    One,
}

/// The comments the firmware strips.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum CommentSyntax {
    /// `(…)` (and `;` to the line's end).
    Parentheses,
    /// `;` to the line's end only: a `(…)` would be read as words.
    Semicolon,
    /// None: no comment is ever written.
    None,
}

/// The unit of G4's P word.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum DwellUnits {
    Seconds,
    /// Milliseconds read as a decimal number.
    Milliseconds,
    /// Milliseconds read as a whole number, the digits after a `.`
    /// dropped: the written P is rounded up, so no dwell is shorter than
    /// the program asks.
    WholeMilliseconds,
}

impl DwellUnits {
    /// Whether G4's P is written in milliseconds.
    pub fn in_ms(self) -> bool {
        self != DwellUnits::Seconds
    }
}

/// What the firmware does with inches.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Inches {
    /// G20 and G21 as LinuxCNC has them.
    Native,
    /// No G20: every length (feeds included) is written in millimetres,
    /// G20 as G21.
    ToMm,
}

/// Which arcs the firmware runs as LinuxCNC does.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Arcs {
    /// Centre (I J K) and radius (R) forms, in G90 and G91.
    All,
    /// Centre form only: R arcs are written with I J K.
    Ijk,
    /// Centre form only, and only in G90: R arcs and arcs in G91 are
    /// written as absolute centre-form arcs (between G90 and G91).
    IjkAbsolute,
    /// No arcs: every arc is written as G1 chords within `--tolerance`.
    None,
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
    /// A G0 reads F as LinuxCNC does (the feed of later moves). Where it
    /// does not (RepRapFirmware's G0 ignores F, Smoothieware's takes it as
    /// its rapid rate), F is written on feed moves only (with
    /// `commands_per_line = "one"`, which names the motion of every move).
    pub feed_on_rapid: bool,
    /// The M code the firmware pauses on until the operator resumes (0
    /// for M0; Smoothieware's M600, RepRapFirmware's M226): written for
    /// M0, M60 and a tool change by pause where the firmware's M0 is no
    /// such pause.
    pub pause: u16,
    /// How many commands it takes from a line.
    pub commands_per_line: CommandsPerLine,
    /// The comment form it strips.
    pub comment_syntax: CommentSyntax,
    /// The unit of G4 P.
    pub dwell_units: DwellUnits,
    /// G20, or inches written as millimetres.
    pub inches: Inches,
    /// The arcs it runs.
    pub arcs: Arcs,
    /// It has work offsets (G54…, G92 as the codes say); without, every
    /// position is written in machine coordinates and G5x, G92, G52 and
    /// G10 L2/L20 are applied by ngcflat.
    pub work_offsets: bool,
    /// Tool length offsets (G43, G43.1, G43.2, G49) are applied to the Z
    /// positions written (the firmware has none).
    pub tool_length_into_z: bool,
    /// What the firmware does with a probe move to the point the tool is
    /// at, in its own words (the reason of E1050).
    pub probe_in_place: String,
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

    /// Whether lines are rewritten beyond their words' values (one
    /// command per line, dwell units, inches, offsets or tool length
    /// applied to positions): no line is copied as it is then.
    pub fn rewrites_lines(&self) -> bool {
        self.commands_per_line == CommandsPerLine::One
            || self.dwell_units.in_ms()
            || self.inches == Inches::ToMm
            || !self.work_offsets
            || self.tool_length_into_z
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
                ToolChange::Pause => format!("pause (M{})", self.pause),
                ToolChange::Keep => "kept".into(),
                ToolChange::Drop => "dropped".into(),
                ToolChange::Refuse => "refused".into(),
            },
            if self.spindle_sync {
                "spindle-synchronised motion"
            } else {
                "no spindle sync (G33, G76, G96 refused)"
            },
            self.source
        ) + &self.describe_rewrites()
    }

    /// What the writer does beyond the GRBL family's rules, for
    /// `ngcflat targets` (empty when nothing).
    fn describe_rewrites(&self) -> String {
        let mut parts: Vec<&str> = Vec::new();
        if self.commands_per_line == CommandsPerLine::One {
            parts.push("one command per line");
        }
        if !self.feed_on_rapid {
            parts.push("F on feed moves only");
        }
        match self.comment_syntax {
            CommentSyntax::Parentheses => {}
            CommentSyntax::Semicolon => parts.push("`;` comments only"),
            CommentSyntax::None => parts.push("no comments"),
        }
        match self.dwell_units {
            DwellUnits::Seconds => {}
            DwellUnits::Milliseconds => parts.push("G4 P in milliseconds"),
            DwellUnits::WholeMilliseconds => {
                parts.push("G4 P in whole milliseconds (rounded up)");
            }
        }
        if self.inches == Inches::ToMm {
            parts.push("no G20 (inches written as mm)");
        }
        match self.arcs {
            Arcs::All => {}
            Arcs::Ijk => parts.push("arcs by I J K only"),
            Arcs::IjkAbsolute => parts.push("arcs by I J K in G90 only"),
            Arcs::None => parts.push("no arcs (G1 chords)"),
        }
        if !self.work_offsets {
            parts.push("no work offsets (machine coordinates)");
        }
        if self.tool_length_into_z {
            parts.push("tool length applied to Z");
        }
        if parts.is_empty() {
            String::new()
        } else {
            format!("\n          {}", parts.join("; "))
        }
    }
}
