//! Reader for LinuxCNC INI files: `[SECTION]` headers, `NAME = value`
//! entries (first occurrence wins), `#` and `;` comment lines, and a trailing
//! backslash joining the next line.

#[derive(Debug, Default, Clone)]
pub struct Ini {
    entries: Vec<(String, String, String)>,
}

impl Ini {
    pub fn parse(text: &str) -> Ini {
        let mut entries = Vec::new();
        let mut section = String::new();
        let mut lines = text.lines();
        while let Some(line) = lines.next() {
            let mut line = line.trim().to_string();
            if line.starts_with('#') || line.starts_with(';') || line.is_empty() {
                continue;
            }
            while line.ends_with('\\') {
                line.pop();
                match lines.next() {
                    Some(more) => line.push_str(more.trim()),
                    None => break,
                }
            }
            if let Some(rest) = line.strip_prefix('[') {
                if let Some(end) = rest.find(']') {
                    section = rest[..end].trim().to_string();
                }
                continue;
            }
            if let Some(eq) = line.find('=') {
                let key = line[..eq].trim().to_string();
                let value = line[eq + 1..].trim().to_string();
                entries.push((section.clone(), key, value));
            }
        }
        Ini { entries }
    }

    /// First value of `name` in `section`.
    pub fn get(&self, section: &str, name: &str) -> Option<&str> {
        self.entries
            .iter()
            .find(|(s, k, _)| s == section && k == name)
            .map(|(_, _, v)| v.as_str())
    }

    /// Lookup for `#<_ini[section]name>`: both upper-cased, then matched
    /// exactly (so a key written `Count` in the file is not found, as in
    /// LinuxCNC).
    pub fn get_upper(&self, section: &str, name: &str) -> Option<&str> {
        self.get(&section.to_ascii_uppercase(), &name.to_ascii_uppercase())
    }

    /// A LinuxCNC boolean (`1`/`TRUE`/`YES`/`ON` or `0`/`FALSE`/`NO`/`OFF`,
    /// any case; a number is true when not 0); `None` when the entry is
    /// absent or holds something else.
    pub fn boolean(&self, section: &str, name: &str) -> Option<bool> {
        let w = self.get(section, name)?.split_whitespace().next()?;
        match w.to_ascii_uppercase().as_str() {
            "TRUE" | "YES" | "ON" => Some(true),
            "FALSE" | "NO" | "OFF" => Some(false),
            _ => w.parse::<f64>().ok().map(|x| x != 0.0),
        }
    }

    /// An integer entry, decimal or `0x` hexadecimal (`FEATURES = 0x20`).
    pub fn integer(&self, section: &str, name: &str) -> Option<i64> {
        let w = self.get(section, name)?.split_whitespace().next()?;
        match w.strip_prefix("0x").or_else(|| w.strip_prefix("0X")) {
            Some(hex) => i64::from_str_radix(hex, 16).ok(),
            None => w.parse().ok(),
        }
    }

    pub fn flag(&self, section: &str, name: &str) -> bool {
        self.get(section, name)
            .and_then(|v| {
                v.split_whitespace()
                    .next()
                    .map(|w| w.parse::<f64>().map(|x| x != 0.0).unwrap_or(false))
            })
            .unwrap_or(false)
    }
}

#[cfg(test)]
mod tests {
    use super::Ini;

    #[test]
    fn sections_continuations_comments() {
        let ini = Ini::parse(
            "# top\n[RS274NGC]\nSUBROUTINE_PATH = a:\\\nb:c\n; x\nSUBROUTINE_PATH = ignored\n[DISPLAY]\nPROGRAM_PREFIX=~/nc\n",
        );
        assert_eq!(ini.get("RS274NGC", "SUBROUTINE_PATH"), Some("a:b:c"));
        assert_eq!(ini.get("DISPLAY", "PROGRAM_PREFIX"), Some("~/nc"));
        assert_eq!(ini.get_upper("display", "program_prefix"), Some("~/nc"));
        let mixed = Ini::parse("[SEC]\nCount = 3\n");
        assert_eq!(mixed.get_upper("sec", "count"), None);
        assert_eq!(ini.get("DISPLAY", "NOPE"), None);
        let b = Ini::parse("[R]\nA = yes\nB = False\nC = 2\nD = maybe\nF = 0x24\nG = 12\n");
        assert_eq!(b.boolean("R", "A"), Some(true));
        assert_eq!(b.boolean("R", "B"), Some(false));
        assert_eq!(b.boolean("R", "C"), Some(true));
        assert_eq!(b.boolean("R", "D"), None);
        assert_eq!(b.boolean("R", "E"), None);
        assert_eq!(b.integer("R", "F"), Some(0x24));
        assert_eq!(b.integer("R", "G"), Some(12));
        assert_eq!(b.integer("R", "D"), None);
    }
}
