//! A profile as a TOML file: read, every key checked, then the whole
//! checked for contradictions, each problem a typed [`ProfileError`].
//!
//! The file is read with the `toml` crate into serde types: TOML's strings,
//! escapes, integers, `inf` and comments are the crate's to get right, and
//! its errors carry the line and column. What a key means and which keys
//! must agree is checked here.
//!
//! Every key is required (a file says everything about its controller), and
//! a key the format does not have is an error, not ignored: a misspelt
//! `line_limt = 80` must not leave the limit out.

use serde::Deserialize;

use super::{
    Arcs, CommandsPerLine, CommentSyntax, Comments, DwellUnits, Inches, LineCount, Profile,
    ToolChange,
};
use crate::codes::GCode;

pub use crate::diag::ProfileError;

/// The file's keys, in the order `targets --show` writes them.
pub(super) const KEYS: &[&str] = &[
    "name",
    "summary",
    "source",
    "passthrough",
    "g_codes",
    "m_codes",
    "words",
    "axes",
    "g10_l",
    "coord_systems",
    "line_limit",
    "line_count",
    "max_digits",
    "decimals_mm",
    "decimals_inch",
    "realtime",
    "high_bytes",
    "comments",
    "messages",
    "block_delete",
    "max_line_number",
    "max_tool",
    "percent",
    "spindle_sync",
    "tool_change",
    "pause",
    "feed_on_rapid",
    "g43_1_z_only",
    "optional_stop",
    "arc_turns",
    "min_probe_travel",
    "probe_in_place",
    "commands_per_line",
    "comment_syntax",
    "dwell_units",
    "inches",
    "arcs",
    "work_offsets",
    "tool_length_into_z",
];

/// `line_limit`: bytes, or `"none"`.
#[derive(Deserialize)]
#[serde(untagged)]
enum Limit {
    Bytes(i64),
    Text(String),
}

/// The file as serde reads it (every key required, none other allowed).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ProfileFile {
    name: String,
    summary: String,
    source: String,
    passthrough: bool,
    g_codes: Vec<String>,
    m_codes: Vec<String>,
    words: String,
    axes: String,
    g10_l: Vec<u8>,
    coord_systems: u8,
    line_limit: Limit,
    line_count: LineCount,
    max_digits: u8,
    decimals_mm: u8,
    decimals_inch: u8,
    realtime: String,
    high_bytes: bool,
    comments: Comments,
    messages: bool,
    block_delete: bool,
    max_line_number: f64,
    max_tool: f64,
    percent: bool,
    spindle_sync: bool,
    tool_change: ToolChange,
    pause: String,
    feed_on_rapid: bool,
    g43_1_z_only: bool,
    optional_stop: bool,
    arc_turns: bool,
    min_probe_travel: f64,
    probe_in_place: String,
    commands_per_line: CommandsPerLine,
    comment_syntax: CommentSyntax,
    dwell_units: DwellUnits,
    inches: Inches,
    arcs: Arcs,
    work_offsets: bool,
    tool_length_into_z: bool,
}

/// The 1-based line of byte `at` in `text`.
fn line_of(text: &str, at: usize) -> usize {
    text.as_bytes()[..at.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

/// The line where `key` is set (`key =` at the start of a line), or 0.
fn key_line(text: &str, key: &str) -> usize {
    text.lines()
        .position(|l| {
            l.trim_start()
                .strip_prefix(key)
                .is_some_and(|r| r.trim_start().starts_with('='))
        })
        .map_or(0, |i| i + 1)
}

impl Profile {
    /// The profile a TOML file describes.
    pub fn from_toml(text: &str) -> Result<Profile, ProfileError> {
        let table: toml::Table = toml::from_str(text).map_err(|e| ProfileError::Syntax {
            line: e.span().map_or(0, |s| line_of(text, s.start)),
            message: e.message().trim().to_string(),
        })?;
        if let Some(key) = table.keys().find(|k| !KEYS.contains(&k.as_str())) {
            return Err(ProfileError::UnknownKey {
                line: key_line(text, key),
                key: key.clone(),
            });
        }
        if let Some(key) = KEYS.iter().find(|k| !table.contains_key(**k)) {
            return Err(ProfileError::MissingKey {
                key: (*key).to_string(),
            });
        }
        let f: ProfileFile = toml::from_str(text).map_err(|e| {
            let line = e.span().map_or(0, |s| line_of(text, s.start));
            // The key set on that line.
            let key = text
                .lines()
                .nth(line.saturating_sub(1))
                .and_then(|l| l.split('=').next())
                .map(|k| k.trim().to_string())
                .filter(|k| KEYS.contains(&k.as_str()))
                .unwrap_or_default();
            ProfileError::BadValue {
                key,
                line,
                message: e.message().trim().to_string(),
            }
        })?;
        f.into_profile(text)
    }
}

impl ProfileFile {
    fn into_profile(self, text: &str) -> Result<Profile, ProfileError> {
        let bad = |key: &str, message: String| ProfileError::BadValue {
            key: key.to_string(),
            line: key_line(text, key),
            message,
        };
        let g_codes = self
            .g_codes
            .iter()
            .map(|c| {
                g_code(c).ok_or_else(|| {
                    bad(
                        "g_codes",
                        format!("`{c}` is not a G code LinuxCNC has (write it as G38.2)"),
                    )
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        let m_codes = self
            .m_codes
            .iter()
            .map(|c| {
                m_code(c)
                    .ok_or_else(|| bad("m_codes", format!("`{c}` is not an M code (M0 to M199)")))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let letters = |key: &str, s: &str| -> Result<Vec<u8>, ProfileError> {
            match s.bytes().find(|b| !b.is_ascii_uppercase()) {
                Some(b) => Err(bad(
                    key,
                    format!("`{}` is not an upper-case word letter", b as char),
                )),
                None => Ok(s.bytes().collect()),
            }
        };
        let words = letters("words", &self.words)?;
        let axes = letters("axes", &self.axes)?;
        if let Some(b) = axes.iter().find(|b| !b"XYZABCUVW".contains(b)) {
            return Err(bad(
                "axes",
                format!("`{}` is not an axis (X Y Z A B C U V W)", *b as char),
            ));
        }
        let line_limit = match self.line_limit {
            Limit::Text(t) if t == "none" => None,
            Limit::Text(t) => {
                return Err(bad(
                    "line_limit",
                    format!("`{t}`: a number of bytes or \"none\""),
                ));
            }
            Limit::Bytes(n) => Some((
                usize::try_from(n).map_err(|_| bad("line_limit", format!("{n} bytes")))?,
                self.line_count,
            )),
        };
        let pause = self
            .pause
            .strip_prefix('M')
            .filter(|n| (1..=4).contains(&n.len()) && n.bytes().all(|b| b.is_ascii_digit()))
            .and_then(|n| n.parse::<u16>().ok())
            .ok_or_else(|| {
                bad(
                    "pause",
                    format!(
                        "`{}`: the M code the firmware pauses on (M0, M600 …)",
                        self.pause
                    ),
                )
            })?;
        if !self.realtime.is_ascii() {
            return Err(bad(
                "realtime",
                "bytes above 0x7F are set with high_bytes".into(),
            ));
        }
        let p = Profile {
            name: self.name,
            summary: self.summary,
            source: self.source,
            passthrough: self.passthrough,
            g_codes,
            m_codes,
            words,
            axes,
            g10_l: self.g10_l,
            coord_systems: self.coord_systems,
            line_limit,
            max_digits: self.max_digits,
            decimals_mm: self.decimals_mm,
            decimals_inch: self.decimals_inch,
            realtime: self.realtime.into_bytes(),
            high_bytes: self.high_bytes,
            comments: self.comments,
            messages: self.messages,
            block_delete: self.block_delete,
            max_line_number: self.max_line_number,
            max_tool: self.max_tool,
            percent: self.percent,
            spindle_sync: self.spindle_sync,
            tool_change: self.tool_change,
            pause,
            feed_on_rapid: self.feed_on_rapid,
            g43_1_z_only: self.g43_1_z_only,
            optional_stop: self.optional_stop,
            arc_turns: self.arc_turns,
            min_probe_travel: self.min_probe_travel,
            probe_in_place: self.probe_in_place,
            commands_per_line: self.commands_per_line,
            comment_syntax: self.comment_syntax,
            dwell_units: self.dwell_units,
            inches: self.inches,
            arcs: self.arcs,
            work_offsets: self.work_offsets,
            tool_length_into_z: self.tool_length_into_z,
        };
        match p.contradiction() {
            Some(what) => Err(ProfileError::Contradiction { what }),
            None => Ok(p),
        }
    }
}

/// `G38.2` → 382, for a G code LinuxCNC has.
fn g_code(s: &str) -> Option<u16> {
    let n = s.strip_prefix(['G', 'g'])?;
    let (whole, tenth) = n.split_once('.').unwrap_or((n, "0"));
    if whole.is_empty() || tenth.len() != 1 || whole.len() > 3 {
        return None;
    }
    let t = whole.parse::<u16>().ok()? * 10 + tenth.parse::<u16>().ok()?;
    GCode::from_code10(t).map(|_| t)
}

/// `M6` → 6.
fn m_code(s: &str) -> Option<u16> {
    let n = s.strip_prefix(['M', 'm'])?;
    if n.is_empty() || n.len() > 3 || !n.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    n.parse::<u16>().ok().filter(|&m| m < 200)
}

impl Profile {
    /// The first pair of keys that do not agree, said in words.
    fn contradiction(&self) -> Option<String> {
        let checks: [(bool, String); 7] = [
            (
                self.line_limit.is_some_and(|(n, _)| n < 2),
                "line_limit must leave room for a byte and the line's end (2 or more), or be \"none\"".into(),
            ),
            (
                !(1..=17).contains(&self.max_digits),
                "max_digits must be 1 to 17".into(),
            ),
            (
                self.decimals_mm > self.max_digits || self.decimals_inch > self.max_digits,
                "decimals_mm and decimals_inch cannot exceed max_digits".into(),
            ),
            (
                !(1..=9).contains(&self.coord_systems),
                "coord_systems must be 1 (G54 only) to 9 (G54 to G59.3)".into(),
            ),
            (
                !(self.max_line_number >= 0.0
                    && self.max_tool >= 0.0
                    && (0.0..1000.0).contains(&self.min_probe_travel)),
                "max_line_number, max_tool and min_probe_travel cannot be negative".into(),
            ),
            (
                self.realtime
                    .iter()
                    .any(|b| b.is_ascii_alphanumeric() || b" .-+\n\r".contains(b)),
                "realtime holds a byte every written line may need (a letter, digit, blank, sign, point or line end)".into(),
            ),
            (
                self.passthrough && !self.g_codes.is_empty(),
                "a passthrough profile writes the program as it is: g_codes must be empty".into(),
            ),
        ];
        if let Some((_, what)) = checks.into_iter().find(|(bad, _)| *bad) {
            return Some(what);
        }
        if self.passthrough {
            return None;
        }
        if let Some(&a) = self.axes.iter().find(|a| !self.words.contains(a)) {
            return Some(format!("axis {} is not among the words", a as char));
        }
        let needs: [(bool, &str, &str); 6] = [
            (self.arc_turns, "arc_turns = true", "G2 and G3"),
            (!self.g10_l.is_empty(), "g10_l is not empty", "G10"),
            (self.g43_1_z_only, "g43_1_z_only = true", "G43.1"),
            (self.optional_stop, "optional_stop = true", "M1"),
            (
                self.tool_change == ToolChange::Keep,
                "tool_change = \"keep\"",
                "M6",
            ),
            (
                self.tool_change == ToolChange::Pause && self.pause == 0,
                "tool_change = \"pause\" with pause = \"M0\"",
                "M0",
            ),
        ];
        for (on, what, codes) in needs {
            let has = codes.split(" and ").all(|c| match c.as_bytes()[0] {
                b'G' => g_code(c).is_some_and(|n| self.has_g(n)),
                _ => m_code(c).is_some_and(|n| self.has_m(n)),
            });
            if on && !has {
                return Some(format!("{what} needs {codes} among the codes"));
            }
        }
        // A pause code LinuxCNC also has is one the firmware must have
        // (M600 and the like are the firmware's own).
        if self.pause != 0 && self.pause < 200 && !self.has_m(self.pause) {
            return Some(format!(
                "pause = \"M{0}\" needs M{0} among the codes",
                self.pause
            ));
        }
        // Only the writer of one command per line moves an F off its G0.
        if !self.feed_on_rapid && self.commands_per_line != CommandsPerLine::One {
            return Some("feed_on_rapid = false needs commands_per_line = \"one\"".into());
        }
        // G54 up to the last system the profile has, and none beyond.
        const SYSTEMS: [u16; 9] = [540, 550, 560, 570, 580, 590, 591, 592, 593];
        for (i, &g) in SYSTEMS.iter().enumerate() {
            let within = i < usize::from(self.coord_systems);
            if within && self.coord_systems > 1 && !self.has_g(g) {
                return Some(format!(
                    "coord_systems = {} but G{} is not among the G codes",
                    self.coord_systems,
                    format_code(g)
                ));
            }
            if !within && self.has_g(g) {
                return Some(format!(
                    "G{} is among the G codes but coord_systems = {}",
                    format_code(g),
                    self.coord_systems
                ));
            }
        }
        let feeds = [10, 20, 30].iter().any(|&g| self.has_g(g));
        if feeds && !self.words.contains(&b'F') {
            return Some("feed moves (G1, G2, G3) need F among the words".into());
        }
        self.writer_contradiction()
    }
}

impl Profile {
    /// The writer's capabilities that do not agree with the codes or with
    /// each other.
    fn writer_contradiction(&self) -> Option<String> {
        let any = |codes: &[u16]| codes.iter().find(|&&c| self.has_g(c)).copied();
        if self.comments == Comments::Keep && self.comment_syntax == CommentSyntax::None {
            return Some("comments = \"keep\" needs a comment_syntax other than \"none\"".into());
        }
        if self.messages && self.comment_syntax != CommentSyntax::Parentheses {
            return Some(
                "messages = true writes (MSG,…), which needs comment_syntax = \"parentheses\""
                    .into(),
            );
        }
        if self.dwell_units.in_ms() && !self.has_g(40) {
            return Some("dwell_units in milliseconds needs G4 among the codes".into());
        }
        match self.inches {
            Inches::Native if !(self.has_g(200) && self.has_g(210)) => {
                return Some("inches = \"native\" needs G20 and G21 among the codes".into());
            }
            Inches::ToMm if self.has_g(200) || !self.has_g(210) => {
                return Some(
                    "inches = \"to-mm\" writes G20 as G21: G21 must be among the codes, G20 not"
                        .into(),
                );
            }
            _ => {}
        }
        let arcs = self.has_g(20) || self.has_g(30);
        match self.arcs {
            Arcs::None if arcs => {
                return Some("arcs = \"none\" but G2 or G3 is among the codes".into());
            }
            Arcs::All | Arcs::Ijk | Arcs::IjkAbsolute if !(self.has_g(20) && self.has_g(30)) => {
                return Some("arcs other than \"none\" need G2 and G3 among the codes".into());
            }
            _ => {}
        }
        // The centre words of every plane the profile has arcs in (an arc
        // in a plane without its code is written as chords).
        let planes = [170, 180, 190].iter().any(|&c| self.has_g(c));
        for (code, letters) in [(170, "IJ"), (180, "IK"), (190, "JK")] {
            let has_plane = self.has_g(code) || code == 170 && !planes;
            if arcs && has_plane && !letters.bytes().all(|l| self.has_word(l)) {
                return Some(format!(
                    "arcs in the plane of G{} need {} among the words",
                    format_code(code),
                    letters
                ));
            }
        }
        if self.arc_turns && self.arcs != Arcs::All {
            return Some("arc_turns = true needs arcs = \"all\"".into());
        }
        if self.tool_length_into_z
            && let Some(c) = any(&[430, 431, 432])
        {
            return Some(format!(
                "tool_length_into_z = true but G{} is among the codes",
                format_code(c)
            ));
        }
        if !self.work_offsets {
            if let Some(c) = any(&[
                520, 530, 540, 550, 560, 570, 580, 590, 591, 592, 593, 920, 921, 922, 923,
            ]) {
                return Some(format!(
                    "work_offsets = false but G{} is among the codes",
                    format_code(c)
                ));
            }
            if self.coord_systems != 1 || self.g10_l.iter().any(|&l| l == 2 || l == 20) {
                return Some(
                    "work_offsets = false needs coord_systems = 1 and no G10 L2 or L20".into(),
                );
            }
        }
        let probes = [382, 383, 384, 385].iter().any(|&c| self.has_g(c));
        if probes && self.probe_in_place.trim().is_empty() {
            return Some(
                "probe_in_place must say what the firmware does with a probe move to the point the tool is at".into(),
            );
        }
        None
    }
}

/// 382 → `38.2`.
fn format_code(t: u16) -> String {
    if t.is_multiple_of(10) {
        format!("{}", t / 10)
    } else {
        format!("{}.{}", t / 10, t % 10)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_built_in_file_has_every_key_and_reads() {
        for (name, text) in crate::controller::BUILT_IN {
            let p = Profile::from_toml(text).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(p.name, *name);
            for key in KEYS {
                assert_ne!(key_line(text, key), 0, "{name}: {key}");
            }
        }
    }

    #[test]
    fn codes_are_read_as_linuxcnc_writes_them() {
        assert_eq!(g_code("G38.2"), Some(382));
        assert_eq!(g_code("G0"), Some(0));
        assert_eq!(g_code("G59.3"), Some(593));
        assert_eq!(g_code("G38.7"), None);
        assert_eq!(g_code("G1.25"), None);
        assert_eq!(g_code("X1"), None);
        assert_eq!(g_code("G"), None);
        assert_eq!(m_code("M6"), Some(6));
        assert_eq!(m_code("M200"), None);
        assert_eq!(m_code("M1.5"), None);
    }

    /// grbl's file with `from` replaced by `to`.
    fn grbl_with(from: &str, to: &str) -> Result<Profile, ProfileError> {
        let text = crate::controller::built_in_file("grbl").unwrap();
        assert!(text.contains(from), "{from}");
        Profile::from_toml(&text.replacen(from, to, 1))
    }

    fn contradiction(from: &str, to: &str) -> String {
        match grbl_with(from, to) {
            Err(ProfileError::Contradiction { what }) => what,
            other => panic!("{to}: {other:?}"),
        }
    }

    #[test]
    fn contradictions_are_named() {
        for (from, to, want) in [
            ("line_limit = 80", "line_limit = 1", "line_limit"),
            ("max_digits = 8", "max_digits = 3", "decimals"),
            ("max_digits = 8", "max_digits = 18", "max_digits"),
            ("coord_systems = 6", "coord_systems = 0", "coord_systems"),
            ("coord_systems = 6", "coord_systems = 5", "G59 is among"),
            (
                "words = \"FIJKLNPRSTXYZ\"",
                "words = \"FIJKLNPRSTXY\"",
                "axis Z",
            ),
            (
                "words = \"FIJKLNPRSTXYZ\"",
                "words = \"IJKLNPRSTXYZ\"",
                "F among",
            ),
            ("\"G43.1\", ", "", "G43.1"),
            ("\"M0\", ", "", "M0"),
            ("passthrough = false", "passthrough = true", "passthrough"),
            ("max_tool = 255", "max_tool = -1", "negative"),
        ] {
            let what = contradiction(from, to);
            assert!(what.contains(want), "{to}: {what}");
        }
    }

    #[test]
    fn key_problems_are_typed() {
        assert!(matches!(
            grbl_with("max_tool", "max_tol"),
            Err(ProfileError::UnknownKey { key, line }) if key == "max_tol" && line > 1
        ));
        assert!(matches!(
            grbl_with("max_tool = 255\n", ""),
            Err(ProfileError::MissingKey { key }) if key == "max_tool"
        ));
        assert!(matches!(
            grbl_with("max_digits = 8", "max_digits = \"8\""),
            Err(ProfileError::BadValue { key, .. }) if key == "max_digits"
        ));
        assert!(matches!(
            grbl_with("comments = \"strip\"", "comments = \"hide\""),
            Err(ProfileError::BadValue { key, .. }) if key == "comments"
        ));
        assert!(matches!(
            grbl_with("axes = \"XYZ\"", "axes = \"XYQ\""),
            Err(ProfileError::BadValue { key, .. }) if key == "axes"
        ));
        assert!(matches!(
            grbl_with("name = \"grbl\"", "name = grbl"),
            Err(ProfileError::Syntax { line, .. }) if line > 1
        ));
    }
}
