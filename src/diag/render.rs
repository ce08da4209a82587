//! Rendering of diagnostics: the one place where byte offsets become lines
//! and columns.

use std::borrow::Cow;
use std::fmt::Write as _;

use super::{Diagnostic, Level, Site};

#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum MessageFormat {
    /// rustc-style message with the source line and a caret.
    #[default]
    Human,
    /// `file:line:col: level: message [code]`
    Short,
    /// One JSON object per line.
    Json,
    /// GitHub Actions workflow commands (`::error file=...`).
    Github,
}

/// Line starts of a text, for turning byte offsets into line and column.
pub struct LineIndex<'a> {
    text: &'a [u8],
    starts: Vec<u32>,
}

impl<'a> LineIndex<'a> {
    pub fn new(text: &'a [u8]) -> LineIndex<'a> {
        let mut starts = vec![0u32];
        starts.extend(
            text.iter()
                .enumerate()
                .filter(|(_, b)| **b == b'\n')
                .map(|(i, _)| i as u32 + 1),
        );
        LineIndex { text, starts }
    }

    /// 1-based line and 1-based column (in characters) of a byte offset.
    pub fn line_col(&self, offset: u32) -> (u32, u32) {
        let offset = offset.min(self.text.len() as u32);
        let line = self.starts.partition_point(|&s| s <= offset).max(1) - 1;
        let start = self.starts[line] as usize;
        let col = String::from_utf8_lossy(&self.text[start..offset as usize])
            .chars()
            .count();
        (line as u32 + 1, col as u32 + 1)
    }

    /// Text of a 1-based line, without its terminator.
    pub fn line_text(&self, line: u32) -> Cow<'a, str> {
        let i = (line as usize).saturating_sub(1).min(self.starts.len() - 1);
        let start = self.starts[i] as usize;
        let end = self
            .starts
            .get(i + 1)
            .map(|&e| e as usize - 1)
            .unwrap_or(self.text.len());
        let mut s = &self.text[start..end.max(start)];
        while let [rest @ .., b'\r'] = s {
            s = rest;
        }
        String::from_utf8_lossy(s)
    }
}

struct Located {
    file: String,
    line: u32,
    col: u32,
    end_line: u32,
    end_col: u32,
    text: String,
}

fn locate(site: &Site) -> Located {
    let data = site.file.bytes();
    let index = LineIndex::new(&data);
    let (line, col) = index.line_col(site.start);
    let (end_line, end_col) = index.line_col(site.end);
    Located {
        file: site.file.display_name(),
        line,
        col,
        end_line,
        end_col,
        text: index.line_text(line).into_owned(),
    }
}

fn json_str(out: &mut String, s: &str) {
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\r' => out.push_str("\\r"),
            '\t' => out.push_str("\\t"),
            c if (c as u32) < 0x20 => {
                let _ = write!(out, "\\u{:04x}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
}

fn github_escape(s: &str) -> String {
    s.replace('%', "%25")
        .replace('\r', "%0D")
        .replace('\n', "%0A")
}

fn github_prop(s: &str) -> String {
    github_escape(s).replace(':', "%3A").replace(',', "%2C")
}

/// Renders one diagnostic in the given format. `color` adds ANSI colours to
/// the human format.
pub fn render(d: &Diagnostic, format: MessageFormat, color: bool) -> String {
    let level = d.level();
    let code = d.code();
    let message = d.message();
    let here = d.site.as_ref().map(locate);
    let stack: Vec<Located> = d.stack.iter().map(locate).collect();
    let mut out = String::new();
    match format {
        MessageFormat::Short => {
            match &here {
                Some(l) => {
                    let _ = write!(out, "{}:{}:{}: ", l.file, l.line, l.col);
                }
                None => out.push_str("ngcflat: "),
            }
            let _ = write!(out, "{level}: {message} [{code}]");
            for c in &stack {
                let _ = write!(out, " (called from {}:{}:{})", c.file, c.line, c.col);
            }
            out.push('\n');
        }
        MessageFormat::Github => {
            let cmd = match level {
                Level::Error => "error",
                Level::Warning => "warning",
            };
            let mut msg = message.clone();
            for c in &stack {
                let _ = write!(msg, "\ncalled from {}:{}:{}", c.file, c.line, c.col);
            }
            match &here {
                Some(l) => {
                    let _ = writeln!(
                        out,
                        "::{cmd} file={},line={},col={},endLine={},endColumn={},title={}::{}",
                        github_prop(&l.file),
                        l.line,
                        l.col,
                        l.end_line,
                        l.end_col,
                        code,
                        github_escape(&msg)
                    );
                }
                None => {
                    let _ = writeln!(out, "::{cmd} title={}::{}", code, github_escape(&msg));
                }
            }
        }
        MessageFormat::Json => {
            out.push('{');
            out.push_str("\"file\":");
            match &here {
                Some(l) => {
                    json_str(&mut out, &l.file);
                    let _ = write!(
                        out,
                        ",\"line\":{},\"column\":{},\"end\":{{\"line\":{},\"column\":{}}}",
                        l.line, l.col, l.end_line, l.end_col
                    );
                }
                None => out.push_str("null,\"line\":null,\"column\":null,\"end\":null"),
            }
            let _ = write!(
                out,
                ",\"level\":\"{level}\",\"code\":\"{code}\",\"message\":"
            );
            json_str(&mut out, &message);
            out.push_str(",\"call_stack\":[");
            for (i, c) in stack.iter().enumerate() {
                if i > 0 {
                    out.push(',');
                }
                out.push_str("{\"file\":");
                json_str(&mut out, &c.file);
                let _ = write!(out, ",\"line\":{},\"column\":{}}}", c.line, c.col);
            }
            out.push_str("]}\n");
        }
        MessageFormat::Human => {
            let (lvl, bold, blue, reset) = if color {
                let c = if level == Level::Error {
                    "\x1b[1;31m"
                } else {
                    "\x1b[1;33m"
                };
                (c, "\x1b[1m", "\x1b[1;34m", "\x1b[0m")
            } else {
                ("", "", "", "")
            };
            let _ = writeln!(out, "{lvl}{level}[{code}]{reset}{bold}: {message}{reset}");
            if let Some(l) = &here {
                let num = l.line.to_string();
                let pad = " ".repeat(num.len());
                let _ = writeln!(out, "{pad}{blue}-->{reset} {}:{}:{}", l.file, l.line, l.col);
                let _ = writeln!(out, "{pad} {blue}|{reset}");
                let _ = writeln!(out, "{blue}{num} |{reset} {}", l.text);
                let width = if l.end_line == l.line && l.end_col > l.col {
                    (l.end_col - l.col) as usize
                } else {
                    1
                };
                let lead: String = l
                    .text
                    .chars()
                    .take(l.col as usize - 1)
                    .map(|c| if c == '\t' { '\t' } else { ' ' })
                    .collect();
                let _ = writeln!(
                    out,
                    "{pad} {blue}|{reset} {lead}{lvl}{}{reset}",
                    "^".repeat(width)
                );
            }
            for c in &stack {
                let _ = writeln!(out, "  = note: called from {}:{}:{}", c.file, c.line, c.col);
            }
        }
    }
    out
}
