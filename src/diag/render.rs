//! Rendering of diagnostics: the one place where byte offsets become lines
//! and columns.

use std::fmt::Write as _;

use super::{Diagnostic, Level, Located};

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
    let here = d.site.as_ref().map(|s| s.located());
    let stack: Vec<&Located> = d.stack.iter().map(|s| s.located()).collect();
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
