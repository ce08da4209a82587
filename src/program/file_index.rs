//! The O-word structure of one file, resolved once: every O-line parsed, its
//! scope (the subroutine definition it lies in), the occurrences of each label
//! in order, sub definitions and their ends, and the errors the reference
//! reports even on lines it skips.

use std::collections::HashMap;
use std::rc::Rc;
use std::sync::Arc;

use crate::diag::ErrorKind;
use crate::parse::ast::{Label, Line, LineKind, OKind, OLine};
use crate::parse::{LineError, LineParser};

use super::SourceFile;

/// One O-line (or M98 line) of a file.
#[derive(Debug)]
pub struct OInfo {
    /// 0-based line index.
    pub line_idx: u32,
    /// Byte offset of the line start and of the next line's start.
    pub start: u32,
    pub next: u32,
    pub line: Rc<Line>,
    /// Name of the sub definition the line lies in ("" outside).
    pub scope: Rc<str>,
    /// Internal key of a static label: `scope#label` for control labels,
    /// `label` for sub/endsub/return/call/bare.
    pub key: Option<Rc<str>>,
}

impl OInfo {
    pub fn o(&self) -> Option<&OLine> {
        match &self.line.kind {
            LineKind::O(o) => Some(o),
            _ => None,
        }
    }

    pub fn kind(&self) -> Option<OKind> {
        self.o().map(|o| o.kind)
    }
}

/// Where a sub definition ends, found at index time.
#[derive(Debug, Clone)]
pub struct SubDefInfo {
    /// O-line index of the matching `endsub`, if any.
    pub end: Option<u32>,
    /// A `sub` or bare O line inside the definition: (O-line index, name).
    pub nested: Option<(u32, Rc<str>)>,
    /// `return`/`endsub` lines with the same label and a value, in order.
    pub valued: Vec<u32>,
}

#[derive(Debug)]
pub struct FileIndex {
    pub file: Arc<SourceFile>,
    pub olines: Vec<OInfo>,
    /// Static label key → O-line indices in file order.
    pub occ: HashMap<Rc<str>, Vec<u32>>,
    /// O-lines whose label is computed when read.
    pub dynamic: Vec<u32>,
    /// Errors raised even on skipped lines: (line index, line start, error).
    pub skip_errors: Vec<(u32, u32, LineError)>,
    /// Line indices of `%` lines.
    pub percent_lines: Vec<u32>,
    /// Sub definition details, by O-line index of the `sub` line.
    pub defs: HashMap<u32, SubDefInfo>,
    /// Line ranges (first, last) of loop bodies and sub definitions: lines in
    /// them are parsed once and kept.
    pub keep: Vec<(u32, u32)>,
    /// The first non-blank line is `%`.
    pub percent_start: bool,
    /// Index of the first non-blank line, if any.
    pub first_nonblank: Option<u32>,
    pub line_count: u32,
}

pub fn control_key(scope: &str, label: &str) -> Rc<str> {
    let mut s = String::with_capacity(scope.len() + label.len() + 1);
    s.push_str(scope);
    s.push('#');
    s.push_str(label);
    Rc::from(s)
}

/// Splits `data` into lines: (start, end without terminator, next start, terminated).
pub fn next_line(data: &[u8], start: usize) -> (usize, usize, bool) {
    match memchr::memchr(b'\n', &data[start..]) {
        Some(i) => (start + i, start + i + 1, true),
        None => (data.len(), data.len(), false),
    }
}

impl FileIndex {
    pub fn build(file: Arc<SourceFile>) -> FileIndex {
        let mut parser = LineParser::default();
        let mut olines = Vec::new();
        let mut skip_errors = Vec::new();
        let mut percent_lines = Vec::new();
        let mut first_nonblank = None;
        let mut percent_start = false;
        let data: &[u8] = &file.data;
        let mut pos = 0usize;
        let mut idx = 0u32;
        let mut current_def: Option<Rc<str>> = None;
        while pos < data.len() {
            let (end, next, terminated) = next_line(data, pos);
            let raw = &data[pos..end];
            if quick_is_candidate(raw) {
                match parser.parse(raw, terminated) {
                    Ok(line) => match &line.kind {
                        LineKind::Blank => {}
                        LineKind::Percent => {
                            if first_nonblank.is_none() {
                                percent_start = true;
                            }
                            percent_lines.push(idx);
                        }
                        LineKind::O(_) | LineKind::M98(_) => {
                            let scope: Rc<str> = Rc::from("");
                            olines.push(OInfo {
                                line_idx: idx,
                                start: pos as u32,
                                next: next as u32,
                                line: Rc::new(line),
                                scope,
                                key: None,
                            });
                        }
                        LineKind::Items(_) => {}
                    },
                    Err(e) => {
                        if e.when_skipped {
                            skip_errors.push((idx, pos as u32, e));
                        }
                    }
                }
            } else if raw.len() + terminated as usize > crate::parse::MAX_LINE + 1
                && let Err(e) = parser.parse(raw, terminated)
            {
                skip_errors.push((idx, pos as u32, e));
            }
            if first_nonblank.is_none() && raw.iter().any(|b| !b.is_ascii_whitespace()) {
                first_nonblank = Some(idx);
            }
            pos = next;
            idx += 1;
        }
        let line_count = idx;
        // Scopes and keys.
        let mut occ: HashMap<Rc<str>, Vec<u32>> = HashMap::new();
        let mut dynamic = Vec::new();
        for (i, info) in olines.iter_mut().enumerate() {
            let Some(o) = (match &info.line.kind {
                LineKind::O(o) => Some(o),
                _ => None,
            }) else {
                continue;
            };
            let label = match &o.label {
                Label::Static(s) => Some(s.clone()),
                Label::Dynamic(_) => None,
            };
            if o.kind == OKind::Sub {
                if current_def.is_none() {
                    current_def = label.clone();
                }
            } else if o.kind == OKind::EndSub && current_def.is_some() && current_def == label {
                info.scope = current_def.clone().unwrap_or_else(|| Rc::from(""));
                current_def = None;
            }
            if let Some(d) = &current_def
                && (o.kind != OKind::Sub || label.as_ref() != Some(d))
            {
                info.scope = d.clone();
            }
            match label {
                Some(l) => {
                    let key = if o.kind.is_control() {
                        control_key(&info.scope, &l)
                    } else {
                        l
                    };
                    occ.entry(key.clone()).or_default().push(i as u32);
                    info.key = Some(key);
                }
                None => dynamic.push(i as u32),
            }
        }
        // Sub definitions.
        let mut defs = HashMap::new();
        let mut keep = Vec::new();
        for (i, info) in olines.iter().enumerate() {
            let (Some(OKind::Sub), Some(key)) = (info.kind(), &info.key) else {
                continue;
            };
            let mut def = SubDefInfo {
                end: None,
                nested: None,
                valued: Vec::new(),
            };
            for (j, other) in olines.iter().enumerate().skip(i + 1) {
                let Some(k) = other.kind() else { continue };
                if matches!(k, OKind::Sub | OKind::Bare) {
                    if def.nested.is_none() {
                        let name = other.key.clone().unwrap_or_else(|| Rc::from("?"));
                        def.nested = Some((j as u32, name));
                    }
                    if other.key.as_ref() == Some(key) {
                        break;
                    }
                    continue;
                }
                if other.key.as_ref() != Some(key) {
                    continue;
                }
                if k == OKind::EndSub {
                    if other.o().is_some_and(|o| o.expr.is_some()) {
                        def.valued.push(j as u32);
                    }
                    def.end = Some(j as u32);
                    break;
                }
                if k == OKind::Return && other.o().is_some_and(|o| o.expr.is_some()) {
                    def.valued.push(j as u32);
                }
            }
            if let Some(e) = def.end {
                keep.push((info.line_idx, olines[e as usize].line_idx));
            } else {
                keep.push((info.line_idx, line_count));
            }
            defs.insert(i as u32, def);
        }
        // Loop bodies.
        for (i, info) in olines.iter().enumerate() {
            let (Some(kind), Some(key)) = (info.kind(), &info.key) else {
                continue;
            };
            let end_kind = match kind {
                OKind::While => OKind::EndWhile,
                OKind::Do => OKind::While,
                OKind::Repeat => OKind::EndRepeat,
                _ => continue,
            };
            if let Some(list) = occ.get(key) {
                let p = list.partition_point(|&j| j as usize <= i);
                if let Some(&j) = list[p..]
                    .iter()
                    .find(|&&j| olines[j as usize].kind() == Some(end_kind))
                {
                    keep.push((info.line_idx, olines[j as usize].line_idx));
                }
            }
        }
        keep.sort_unstable();
        let mut merged: Vec<(u32, u32)> = Vec::new();
        for (a, b) in keep {
            match merged.last_mut() {
                Some(last) if a <= last.1 + 1 => last.1 = last.1.max(b),
                _ => merged.push((a, b)),
            }
        }
        FileIndex {
            file,
            olines,
            occ,
            dynamic,
            skip_errors,
            percent_lines,
            defs,
            keep: merged,
            percent_start,
            first_nonblank,
            line_count,
        }
    }

    /// Whether lines at this index are worth keeping parsed.
    pub fn keeps(&self, line_idx: u32) -> bool {
        let p = self.keep.partition_point(|&(a, _)| a <= line_idx);
        p > 0 && self.keep[p - 1].1 >= line_idx
    }

    /// First O-line index with `line_idx >= line`.
    pub fn oline_at_or_after(&self, line: u32) -> usize {
        self.olines.partition_point(|o| o.line_idx < line)
    }

    /// The first error the reference reports on lines strictly between two
    /// line indices (exclusive), when it skips over them.
    pub fn skipped_error(&self, after: u32, before: u32) -> Option<&(u32, u32, LineError)> {
        let p = self.skip_errors.partition_point(|e| e.0 <= after);
        self.skip_errors.get(p).filter(|e| e.0 < before)
    }

    /// First `%` line strictly after `after`.
    pub fn percent_after(&self, after: u32) -> Option<u32> {
        let p = self.percent_lines.partition_point(|&l| l <= after);
        self.percent_lines.get(p).copied()
    }

    pub fn error_site(&self, line_start: u32, e: &LineError) -> (u32, u32) {
        (line_start + e.span.start, line_start + e.span.end)
    }

    pub fn kind_of(&self, oidx: u32) -> Option<OKind> {
        self.olines[oidx as usize].kind()
    }
}

/// Cheap test: could this raw line be an O-line, `%`, or carry a comment
/// error? Lines that cannot are not parsed at index time.
fn quick_is_candidate(raw: &[u8]) -> bool {
    let mut i = 0;
    while i < raw.len() && matches!(raw[i], b' ' | b'\t' | b'\r') {
        i += 1;
    }
    if i < raw.len() && raw[i] == b'/' {
        i += 1;
    }
    while i < raw.len() && matches!(raw[i], b' ' | b'\t' | b'\r') {
        i += 1;
    }
    if i < raw.len() && matches!(raw[i], b'n' | b'N') {
        i += 1;
        while i < raw.len() && (raw[i].is_ascii_digit() || matches!(raw[i], b'.' | b' ' | b'\t')) {
            i += 1;
        }
    }
    let rest = &raw[i..];
    if rest.is_empty() {
        return false;
    }
    if matches!(rest[0], b'o' | b'O' | b'%') {
        return true;
    }
    if rest.len() >= 3 && rest[0].eq_ignore_ascii_case(&b'm') {
        // m98 / m 9 8 with blanks.
        let compact: Vec<u8> = rest
            .iter()
            .filter(|b| !matches!(b, b' ' | b'\t'))
            .take(3)
            .copied()
            .collect();
        if compact.eq_ignore_ascii_case(b"m98") {
            return true;
        }
    }
    memchr::memchr(b'(', raw).is_some()
}

/// Error for a sub file that lacks its sub.
pub fn not_in_file(name: &str, file: &SourceFile) -> ErrorKind {
    ErrorKind::SubNotInFile {
        name: name.to_string(),
        file: file.path.clone(),
    }
}
