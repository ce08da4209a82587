//! Rendering of diagnostics: the one place where byte offsets become lines
//! and columns.

use super::SetupError;
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

/// How a character from a program or a user is shown in a diagnostic:
/// control characters (C0 but tab, DEL, C1) escaped as `\x1b` or `\u{85}`,
/// so that no byte of a program can act on the terminal or the CI log.
fn push_shown(out: &mut String, c: char) {
    if c.is_control() && c != '\t' {
        if (c as u32) < 0x80 {
            let _ = write!(out, "\\x{:02x}", c as u32);
        } else {
            let _ = write!(out, "\\u{{{:x}}}", c as u32);
        }
    } else {
        out.push(c);
    }
}

/// Text shown as [`push_shown`] shows it (messages, file names).
pub(crate) fn shown(s: &str) -> std::borrow::Cow<'_, str> {
    if !s.chars().any(|c| c.is_control() && c != '\t') {
        return std::borrow::Cow::Borrowed(s);
    }
    let mut out = String::with_capacity(s.len() + 8);
    for c in s.chars() {
        push_shown(&mut out, c);
    }
    std::borrow::Cow::Owned(out)
}

/// A source line as shown, and the blanks that lead to its 1-based column
/// `col` (columns count characters, an invalid UTF-8 sequence as one, as
/// the locating does). Bytes that are not UTF-8 are shown as `\xff`,
/// control characters as [`push_shown`] shows them.
pub(crate) fn shown_line(bytes: &[u8], col: u32) -> (String, String) {
    let mut text = String::with_capacity(bytes.len());
    let mut lead = String::new();
    let mut n = 1u32;
    let mut unit = |text: &mut String, lead: &mut String, before: usize, tab: bool| {
        if n < col {
            if tab {
                lead.push('\t');
            } else {
                let w = text[before..].chars().count();
                lead.extend(std::iter::repeat_n(' ', w));
            }
        }
        n += 1;
    };
    for chunk in bytes.utf8_chunks() {
        for c in chunk.valid().chars() {
            let before = text.len();
            push_shown(&mut text, c);
            unit(&mut text, &mut lead, before, c == '\t');
        }
        if !chunk.invalid().is_empty() {
            let before = text.len();
            for b in chunk.invalid() {
                let _ = write!(text, "\\x{b:02x}");
            }
            unit(&mut text, &mut lead, before, false);
        }
    }
    (text, lead)
}

/// Position of a diagnostic in the JSON format.
#[derive(serde::Serialize)]
struct JsonPos {
    line: u32,
    column: u32,
}

/// Byte offsets in the file of a diagnostic in the JSON format.
#[derive(serde::Serialize)]
struct JsonSpan {
    start: u32,
    end: u32,
}

/// A caller in the JSON format.
#[derive(serde::Serialize)]
struct JsonFrame {
    file: String,
    line: u32,
    column: u32,
}

/// One diagnostic in the JSON format (docs/usage.md: "Diagnostics").
#[derive(serde::Serialize)]
struct JsonDiagnostic {
    #[serde(rename = "type")]
    kind: &'static str,
    severity: &'static str,
    code: &'static str,
    message: String,
    file: Option<String>,
    line: Option<u32>,
    column: Option<u32>,
    end: Option<JsonPos>,
    span: Option<JsonSpan>,
    notes: Vec<String>,
    call_stack: Vec<JsonFrame>,
}

/// The summary object that ends the JSON output.
#[derive(serde::Serialize)]
struct JsonSummary {
    #[serde(rename = "type")]
    kind: &'static str,
    files: usize,
    errors: usize,
    warnings: usize,
    exit_code: u8,
}

fn json_line(d: &Diagnostic, here: Option<&Located>, stack: &[&Located]) -> String {
    let io_path = match d.error_kind() {
        Some(super::ErrorKind::Setup(SetupError::Io { path, .. })) => {
            Some(path.display().to_string())
        }
        _ => None,
    };
    let v = JsonDiagnostic {
        kind: "diagnostic",
        severity: match d.level() {
            Level::Error => "error",
            Level::Warning => "warning",
        },
        code: d.code(),
        // Control characters escaped as in the other formats, so that a
        // consumer printing the decoded text cannot act on a terminal.
        message: shown(&d.message()).into_owned(),
        file: here
            .map(|l| l.file.clone())
            .or(io_path)
            .map(|f| shown(&f).into_owned()),
        line: here.map(|l| l.line),
        column: here.map(|l| l.col),
        end: here.map(|l| JsonPos {
            line: l.end_line,
            column: l.end_col,
        }),
        span: d.site.as_ref().map(|s| JsonSpan {
            start: s.start,
            end: s.end,
        }),
        notes: stack
            .iter()
            .map(|c| format!("called from {}:{}:{}", shown(&c.file), c.line, c.col))
            .collect(),
        call_stack: stack
            .iter()
            .map(|c| JsonFrame {
                file: shown(&c.file).into_owned(),
                line: c.line,
                column: c.col,
            })
            .collect(),
    };
    let mut line = serde_json::to_string(&v).unwrap_or_default();
    line.push('\n');
    line
}

/// The summary line that ends a run in the given format: `N files, E
/// errors, W warnings` (check only), or a JSON object (both commands).
pub fn render_summary(
    files: usize,
    errors: usize,
    warnings: usize,
    exit_code: u8,
    format: MessageFormat,
    check: bool,
) -> String {
    match format {
        MessageFormat::Json => {
            let v = JsonSummary {
                kind: "summary",
                files,
                errors,
                warnings,
                exit_code,
            };
            let mut line = serde_json::to_string(&v).unwrap_or_default();
            line.push('\n');
            line
        }
        _ if check => format!("{files} files, {errors} errors, {warnings} warnings\n"),
        _ => String::new(),
    }
}

fn github_escape(s: &str) -> String {
    s.replace('%', "%25")
        .replace('\r', "%0D")
        .replace('\n', "%0A")
}

fn github_prop(s: &str) -> String {
    github_escape(s).replace(':', "%3A").replace(',', "%2C")
}

/// Whether human diagnostics get ANSI colours: only on a terminal, and not
/// when `NO_COLOR` is set to anything but the empty string
/// (<https://no-color.org>) or `TERM` is `dumb`.
pub fn use_color(
    is_terminal: bool,
    no_color: Option<&std::ffi::OsStr>,
    term: Option<&std::ffi::OsStr>,
) -> bool {
    is_terminal && no_color.is_none_or(|v| v.is_empty()) && term.is_none_or(|t| t != "dumb")
}

/// Renders one diagnostic in the given format. `color` adds ANSI colours to
/// the human format.
pub fn render(d: &Diagnostic, format: MessageFormat, color: bool) -> String {
    let level = d.level();
    let code = d.code();
    let message = shown(&d.message()).into_owned();
    let here = d.site.as_ref().map(|s| s.located());
    let stack: Vec<Located> = d.stack.iter().map(|s| s.located()).collect();
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
            let stack: Vec<&Located> = stack.iter().collect();
            out = json_line(d, here.as_ref(), &stack);
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
                let lead = &l.lead;
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

#[cfg(test)]
mod tests {
    use super::use_color;
    use std::ffi::OsStr;

    #[test]
    fn color_only_on_a_capable_terminal() {
        let s = |v: &'static str| Some(OsStr::new(v));
        assert!(use_color(true, None, s("xterm-256color")));
        assert!(use_color(true, None, None));
        assert!(use_color(true, s(""), s("xterm")));
        assert!(!use_color(false, None, s("xterm")));
        assert!(!use_color(true, s("1"), s("xterm")));
        assert!(!use_color(true, s("0"), s("xterm")));
        assert!(!use_color(true, None, s("dumb")));
    }
}
