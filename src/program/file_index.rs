//! The O-word structure of one file, resolved once: every O-line parsed, its
//! scope (the subroutine definition it lies in), the occurrences of each label
//! in order, sub definitions and their ends, and the errors the reference
//! reports even on lines it skips.

use std::cell::Cell;
use std::rc::Rc;
use std::sync::Arc;

use crate::diag::ErrorKind;
use crate::fx_hasher::FxMap;
use crate::parse::ast::{Label, Line, LineKind, OKind, OLine};
use crate::parse::{LineError, LineParser, Name};

use super::SourceFile;
use super::marked_lines::{Marked, is_mark};

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
    pub scope: Name,
    /// Internal key of a static label: `scope#label` for control labels,
    /// `label` for sub/endsub/return/call/bare.
    pub key: Option<Name>,
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
    pub nested: Option<(u32, Name)>,
    /// `return`/`endsub` lines with the same label, in order (the reference
    /// reads them while skipping the definition: a value sets `#<_value>`,
    /// none clears it).
    pub valued: Vec<u32>,
}

#[derive(Debug)]
pub struct FileIndex {
    pub file: Arc<SourceFile>,
    /// The file could not be read to its end.
    pub read_error: Option<String>,
    /// Offset of the line after the first non-blank one.
    pub first_nonblank_next: u32,
    pub olines: Vec<OInfo>,
    /// Static label key → O-line indices in file order.
    pub occ: FxMap<Name, Vec<u32>>,
    /// O-lines whose label is computed when read.
    pub dynamic: Vec<u32>,
    /// Errors raised even on skipped lines: (line index, line start, error).
    pub skip_errors: Vec<(u32, u32, LineError)>,
    /// Line indices of `%` lines.
    pub percent_lines: Vec<u32>,
    /// Line indices of lines starting with `M99` (the reference reads them
    /// while seeking a subroutine, which clears `#<_value>`).
    pub m99_lines: Vec<u32>,
    /// Sub definition details, by O-line index of the `sub` line.
    pub defs: FxMap<u32, SubDefInfo>,
    /// Found targets of control-label searches, by the O-line searched
    /// from (`u32::MAX`: not searched yet); see `Interp::seek`.
    pub seek_memo: Vec<Cell<u32>>,
    /// Line ranges (first, last) of loop bodies and sub definitions: lines in
    /// them are parsed once and kept.
    pub keep: Vec<(u32, u32)>,
    /// The first non-blank line is `%`.
    pub percent_start: bool,
    /// Index of the first non-blank line, if any.
    pub first_nonblank: Option<u32>,
    pub line_count: u32,
}

pub fn control_key(scope: &str, label: &str) -> Name {
    let mut s = String::with_capacity(scope.len() + label.len() + 1);
    s.push_str(scope);
    s.push('#');
    s.push_str(label);
    Name::new(&s)
}

pub use super::source_file::next_line;

/// What one pass over the file's marked lines finds.
#[derive(Default)]
struct Scan {
    olines: Vec<OInfo>,
    skip_errors: Vec<(u32, u32, LineError)>,
    percent_lines: Vec<u32>,
    m99_lines: Vec<u32>,
    first_nonblank: Option<u32>,
    first_nonblank_next: u32,
    percent_start: bool,
}

impl Scan {
    /// Records one marked line (`raw`, without its terminator).
    fn line(&mut self, parser: &mut LineParser, m: Marked, raw: &[u8]) {
        let (idx, pos, terminated) = (m.idx, m.start as u32, m.terminated);
        let next = (m.end + terminated as u64) as u32;
        if starts_with_m99(raw) {
            self.m99_lines.push(idx);
        }
        if quick_is_candidate(raw) {
            match parser.parse(raw, terminated) {
                Ok(line) => match &line.kind {
                    LineKind::Blank | LineKind::Items(_) => {}
                    LineKind::Percent => {
                        if self.first_nonblank.is_none() {
                            self.percent_start = true;
                        }
                        self.percent_lines.push(idx);
                    }
                    LineKind::O(_) | LineKind::M98(_) => {
                        self.olines.push(OInfo {
                            line_idx: idx,
                            start: pos,
                            next,
                            line: Rc::new(line),
                            scope: Name::new(""),
                            key: None,
                        });
                    }
                },
                Err(e) => {
                    if e.when_skipped {
                        self.skip_errors.push((idx, pos, e));
                    }
                }
            }
        } else if overlong(raw, terminated)
            && let Err(e) = parser.parse(raw, terminated)
        {
            self.skip_errors.push((idx, pos, e));
        }
        if self.first_nonblank.is_none() && raw.iter().any(|b| !b.is_ascii_whitespace()) {
            self.first_nonblank = Some(idx);
            self.first_nonblank_next = next;
        }
    }
}

/// Gives each O-line its scope and key; returns the occurrences of each
/// static key and the O-lines with computed labels.
fn assign_scopes(olines: &mut [OInfo]) -> (FxMap<Name, Vec<u32>>, Vec<u32>) {
    let mut current_def: Option<Name> = None;
    let mut occ: FxMap<Name, Vec<u32>> = FxMap::default();
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
            info.scope = current_def.clone().unwrap_or_else(|| Name::new(""));
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
    (occ, dynamic)
}

/// Sub definitions: each is matched through its own label's occurrences,
/// so the work is linear in the number of O-lines. Each definition's line
/// range is pushed onto `keep`.
fn sub_defs(
    olines: &[OInfo],
    occ: &FxMap<Name, Vec<u32>>,
    line_count: u32,
    keep: &mut Vec<(u32, u32)>,
) -> FxMap<u32, SubDefInfo> {
    let mut defs = FxMap::default();
    let sub_lines: Vec<u32> = olines
        .iter()
        .enumerate()
        .filter(|(_, o)| matches!(o.kind(), Some(OKind::Sub | OKind::Bare)))
        .map(|(j, _)| j as u32)
        .collect();
    for (i, info) in olines.iter().enumerate() {
        let (Some(OKind::Sub), Some(key)) = (info.kind(), &info.key) else {
            continue;
        };
        let mut def = SubDefInfo {
            end: None,
            nested: None,
            valued: Vec::new(),
        };
        if let Some(list) = occ.get(key) {
            let p = list.partition_point(|&j| j as usize <= i);
            for &j in &list[p..] {
                match olines[j as usize].kind() {
                    Some(OKind::EndSub) => {
                        def.valued.push(j);
                        def.end = Some(j);
                        break;
                    }
                    Some(OKind::Return) => def.valued.push(j),
                    Some(OKind::Sub | OKind::Bare) => break,
                    _ => {}
                }
            }
        }
        let q = sub_lines.partition_point(|&j| j as usize <= i);
        if let Some(&j) = sub_lines.get(q)
            && def.end.is_none_or(|e| j < e)
        {
            let name = olines[j as usize]
                .key
                .clone()
                .unwrap_or_else(|| Name::new("?"));
            def.nested = Some((j, name));
        }
        if let Some(e) = def.end {
            keep.push((info.line_idx, olines[e as usize].line_idx));
        } else {
            keep.push((info.line_idx, line_count));
        }
        defs.insert(i as u32, def);
    }
    defs
}

/// Loop bodies: one backward pass per label finds each opener's closer;
/// each body's line range is pushed onto `keep`.
fn loop_bodies(olines: &[OInfo], occ: &FxMap<Name, Vec<u32>>, keep: &mut Vec<(u32, u32)>) {
    for list in occ.values() {
        let (mut next_endwhile, mut next_while, mut next_endrepeat) = (None, None, None);
        for &j in list.iter().rev() {
            let info = &olines[j as usize];
            let closer = match info.kind() {
                Some(OKind::While) => next_endwhile,
                Some(OKind::Do) => next_while,
                Some(OKind::Repeat) => next_endrepeat,
                _ => None,
            };
            if let Some(c) = closer {
                let c: u32 = c;
                keep.push((info.line_idx, olines[c as usize].line_idx));
            }
            match info.kind() {
                Some(OKind::EndWhile) => next_endwhile = Some(j),
                Some(OKind::While) => next_while = Some(j),
                Some(OKind::EndRepeat) => next_endrepeat = Some(j),
                _ => {}
            }
        }
    }
}

/// Sorts line ranges and merges overlapping or adjacent ones.
fn merge_ranges(mut keep: Vec<(u32, u32)>) -> Vec<(u32, u32)> {
    keep.sort_unstable();
    let mut merged: Vec<(u32, u32)> = Vec::new();
    for (a, b) in keep {
        match merged.last_mut() {
            Some(last) if a <= last.1 + 1 => last.1 = last.1.max(b),
            _ => merged.push((a, b)),
        }
    }
    merged
}

impl FileIndex {
    pub fn build(file: Arc<SourceFile>) -> FileIndex {
        let mut parser = LineParser::default();
        let mut scan = Scan::default();
        let scanned = file.scan_marked_lines(crate::parse::MAX_LINE + 1, &matters, |m, raw| {
            scan.line(&mut parser, m, raw)
        });
        let (line_count, read_error) = match scanned {
            Ok(n) => (n, None),
            Err(e) => (0, Some(e.to_string())),
        };
        let Scan {
            mut olines,
            skip_errors,
            percent_lines,
            m99_lines,
            first_nonblank,
            first_nonblank_next,
            percent_start,
        } = scan;
        let (occ, dynamic) = assign_scopes(&mut olines);
        let mut keep = Vec::new();
        let defs = sub_defs(&olines, &occ, line_count, &mut keep);
        loop_bodies(&olines, &occ, &mut keep);
        FileIndex {
            file,
            read_error,
            first_nonblank_next,
            seek_memo: vec![Cell::new(u32::MAX); olines.len()],
            olines,
            occ,
            dynamic,
            skip_errors,
            percent_lines,
            m99_lines,
            defs,
            keep: merge_ranges(keep),
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

/// Whether the index looks at a line handed on after the leading blank lines
/// (the closure in `FileIndex::build` does nothing with the others).
fn matters(raw: &[u8], terminated: bool) -> bool {
    starts_with_m99(raw) || quick_is_candidate(raw) || overlong(raw, terminated)
}

/// Longer than the reference reads (an error even on a skipped line).
fn overlong(raw: &[u8], terminated: bool) -> bool {
    raw.len() + terminated as usize > crate::parse::MAX_LINE + 1
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
        let mut compact = [0u8; 3];
        let mut n = 0;
        for &b in rest.iter().filter(|b| !matches!(b, b' ' | b'\t')).take(3) {
            compact[n] = b;
            n += 1;
        }
        if compact[..n].eq_ignore_ascii_case(b"m98") {
            return true;
        }
    }
    memchr::memchr(b'(', raw).is_some() && !comments_inert(raw)
}

/// The line's comments are closed and not nested, and the bytes outside them
/// are ASCII without a mark (`o`, `m`, `%`) or `;`: it is no O-line, `%` or
/// M98 line, and parsing it raises no error the reference reports on
/// skipped lines (a mark inside a comment, `(segment 3)`, is common in CAM
/// output and needs no parse).
fn comments_inert(raw: &[u8]) -> bool {
    let mut inside = false;
    for &b in raw {
        if inside {
            match b {
                b'(' => return false,
                b')' => inside = false,
                _ => {}
            }
        } else if b == b'(' {
            inside = true;
        } else if !b.is_ascii() || is_mark(b) || b == b';' {
            return false;
        }
    }
    !inside
}

fn starts_with_m99(raw: &[u8]) -> bool {
    // Cheap reject: the first non-blank byte must be '/', 'n' or 'm'.
    match raw.iter().find(|b| !matches!(b, b' ' | b'\t')) {
        Some(b'/' | b'n' | b'N' | b'm' | b'M') => {}
        _ => return false,
    }
    let mut buf = [0u8; 12];
    let mut n = 0;
    for &b in raw.iter().filter(|b| !matches!(b, b' ' | b'\t')).take(12) {
        buf[n] = b.to_ascii_lowercase();
        n += 1;
    }
    let mut t: &[u8] = &buf[..n];
    if let [b'/', rest @ ..] = t {
        t = rest;
    }
    if let [b'n', rest @ ..] = t {
        let d = rest
            .iter()
            .take_while(|b| b.is_ascii_digit() || **b == b'.')
            .count();
        t = &rest[d..];
    }
    t.starts_with(b"m99") && !t.get(3).is_some_and(|b| b.is_ascii_digit() || *b == b'.')
}

impl FileIndex {
    /// Whether an `M99` line lies strictly between two line indices.
    pub fn m99_between(&self, after: u32, before: u32) -> bool {
        let p = self.m99_lines.partition_point(|&l| l <= after);
        self.m99_lines.get(p).is_some_and(|&l| l < before)
    }
}

/// Error for a sub file that lacks its sub.
pub fn not_in_file(name: &str, file: &SourceFile) -> ErrorKind {
    ErrorKind::SubNotInFile {
        name: name.to_string(),
        file: file.path.clone(),
    }
}
