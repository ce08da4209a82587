//! The O-word structure of one file, resolved once: every O-line's kind,
//! label key and scope (the subroutine definition it lies in), the
//! occurrences of each label in order, sub definitions and their ends, and
//! the errors the reference reports even on lines it skips.
//!
//! Kept compact, since a program may hold a million labels: an O-line is a
//! record of a few integers; its label key is an index into the file's
//! table of distinct keys; the occurrences of all keys are one array cut
//! into runs; the parsed line itself is not kept but parsed again when it
//! is run (a bounded number of parsed O-lines are kept for loops, and of
//! a file in memory the first O-lines with values or arguments are kept
//! from the scan, so that a short program parses each line once).

use crate::diag::{LimitError, OWordError, SyntaxError};
use std::cell::{Cell, RefCell};
use std::rc::Rc;
use std::sync::Arc;

use crate::diag::ErrorKind;
use crate::fx_hasher::FxMap;
use crate::parse::ast::{Label, Line, LineKind, OKind, OLine, Span};
use crate::parse::{LineError, LineParser, Name};

use super::SourceFile;
use crate::source::{Marked, is_mark};

/// No key (a computed label, an M98 line) or no scope (outside any sub
/// definition).
const NONE: u32 = u32::MAX;

/// Parsed O-lines kept per file: slots indexed by the O-line index
/// modulo their number (a power of two, at most this many), so that a
/// lookup is one index and the memory is bounded (loops run from what is
/// kept; a line whose slot another took is parsed again).
const PARSED_KEPT: usize = 1 << 14;

/// O-lines of a file in memory whose parse at index time is kept for
/// their run (those made from the index without parsing are not counted).
const PARSED_AT_SCAN: usize = 1 << 12;

/// Bytes of a streamed file read at a time for parsing O-lines again.
const AHEAD: usize = 1 << 13;

/// A slot of the parsed O-lines kept: the O-line index and its line.
type KeptLine = Option<(u32, Rc<Line>)>;

/// One O-line (or M98 line) of a file.
#[derive(Debug, Clone, Copy)]
pub struct OInfo {
    /// 0-based line index.
    pub line_idx: u32,
    /// Byte offset of the line start and of the next line's start.
    pub start: u32,
    pub next: u32,
    /// Index of the label key in the file's key table (`NONE`: computed
    /// label or M98 line).
    key: u32,
    /// Key index of the sub definition the line lies in (`NONE`: outside).
    scope: u32,
    /// `None` for an M98 line.
    kind: Option<OKind>,
    /// The line ends with a newline.
    terminated: bool,
    /// An O-line with a fixed label and nothing else to run (no value,
    /// arguments, error, active comment, block delete or line number): it
    /// is made from the index when run, not parsed again.
    plain: bool,
}

impl OInfo {
    pub fn kind(&self) -> Option<OKind> {
        self.kind
    }

    /// Length of the line text without its terminator.
    pub fn line_len(&self) -> u32 {
        (self.next - self.start).saturating_sub(1)
    }
}

/// A parsed O-line (a line whose kind the index checked is `O`).
#[derive(Clone)]
pub struct ParsedO(Rc<Line>);

impl ParsedO {
    pub fn line(&self) -> &Rc<Line> {
        &self.0
    }
}

impl std::ops::Deref for ParsedO {
    type Target = OLine;
    fn deref(&self) -> &OLine {
        match &self.0.kind {
            LineKind::O(o) => o,
            // `FileIndex::oline` makes a `ParsedO` only of an O-line.
            _ => unreachable!("a ParsedO holds an O-line"),
        }
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

/// A sub definition as stored: O-line indices (`NONE`: absent) and a run
/// of `FileIndex::valued`.
#[derive(Debug, Clone, Copy)]
pub struct SubDef {
    /// O-line index of the `sub` line.
    pub oidx: u32,
    end: u32,
    nested: u32,
    valued_at: u32,
    valued_len: u32,
}

impl SubDef {
    /// O-line index of the matching `endsub`, if any.
    pub fn end(&self) -> Option<u32> {
        (self.end != NONE).then_some(self.end)
    }
}

pub struct FileIndex {
    pub file: Arc<SourceFile>,
    /// The file could not be read to its end.
    pub read_error: Option<String>,
    /// Offset of the line after the first non-blank one.
    pub first_nonblank_next: u32,
    pub olines: Vec<OInfo>,
    /// The distinct static label keys (`scope#label` for control labels,
    /// `label` for sub/endsub/return/call/bare).
    keys: Vec<Name>,
    /// Key indices sorted by the key's interned address (a search finds a
    /// key's index without a map).
    keys_by_addr: Vec<u32>,
    /// `occ[occ_at[k]..occ_at[k + 1]]`: the O-lines with key `k`, in file
    /// order.
    occ_at: Vec<u32>,
    occ: Vec<u32>,
    /// O-lines whose label is computed when read.
    pub dynamic: Vec<u32>,
    /// Errors raised even on skipped lines: (line index, line start, error).
    pub skip_errors: Vec<(u32, u32, LineError)>,
    /// Line indices of `%` lines.
    pub percent_lines: Vec<u32>,
    /// Line indices of lines starting with `M99` (the reference reads them
    /// while seeking a subroutine, which clears `#<_value>`).
    pub m99_lines: Vec<u32>,
    /// Sub definitions by O-line index of their `sub` line (ascending).
    defs: Vec<SubDef>,
    /// Runs of valued `return`/`endsub` O-lines of the definitions.
    valued: Vec<u32>,
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
    /// The empty scope.
    no_scope: Name,
    /// Parsed O-lines kept (at most [`PARSED_KEPT`]), each in the slot of
    /// its O-line index (see [`FileIndex::slot`]), with that index.
    parsed: RefCell<Vec<KeptLine>>,
    /// The number of those slots (a power of two) less one.
    parsed_mask: usize,
    parser: RefCell<LineParser>,
    /// Bytes of a streamed file read ahead for parsing O-lines again:
    /// (offset, bytes).
    ahead: RefCell<(u32, Vec<u8>)>,
}

impl std::fmt::Debug for FileIndex {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FileIndex")
            .field("file", &self.file.name)
            .field("olines", &self.olines.len())
            .field("keys", &self.keys.len())
            .finish_non_exhaustive()
    }
}

pub fn control_key(scope: &str, label: &str) -> Name {
    let mut s = String::with_capacity(scope.len() + label.len() + 1);
    s.push_str(scope);
    s.push('#');
    s.push_str(label);
    Name::new(&s)
}

pub use crate::source::next_line;

/// What one pass over the file's marked lines finds.
#[derive(Default)]
struct Scan {
    olines: Vec<OInfo>,
    keys: Vec<Name>,
    key_ids: FxMap<Name, u32>,
    dynamic: Vec<u32>,
    /// Key index of the sub definition being read.
    current_def: Option<u32>,
    skip_errors: Vec<(u32, u32, LineError)>,
    percent_lines: Vec<u32>,
    m99_lines: Vec<u32>,
    first_nonblank: Option<u32>,
    first_nonblank_next: u32,
    percent_start: bool,
    /// Keep the lines parsed (the file is in memory, so they are the
    /// lines a later read gives).
    keep_parsed: bool,
    /// Parsed O-lines kept for their run: (O-line index, line).
    parsed: Vec<(u32, Rc<Line>)>,
}

impl Scan {
    /// Records one marked line (`raw`, without its terminator).
    fn line(&mut self, parser: &mut LineParser, m: Marked, raw: &[u8]) {
        let (idx, pos, terminated) = (m.idx, m.start as u32, m.terminated);
        let next = (m.end + terminated as u64) as u32;
        if starts_with_m99(raw) {
            self.m99_lines.push(idx);
        }
        if let Some((kind, label)) = plain_oline(raw, parser.named2007()) {
            let label = Name::new(label);
            self.oline(idx, pos, (next, terminated, true), kind, Some(&label));
        } else if quick_is_candidate(raw) {
            match parse_marked(parser, m, raw) {
                Ok(line) => {
                    let at = self.olines.len();
                    self.parsed_line(&line, idx, pos, next, terminated);
                    // The line a later read gives (the whole line, from
                    // memory): kept for its run.
                    if self.keep_parsed
                        && self.parsed.len() < PARSED_AT_SCAN
                        && raw.len() as u64 == m.end - m.start
                        && self
                            .olines
                            .get(at)
                            .is_some_and(|o| !o.plain && o.kind.is_some())
                    {
                        self.parsed.push((at as u32, Rc::new(line)));
                    }
                }
                Err(e) => {
                    if e.when_skipped {
                        self.skip_errors.push((idx, pos, e));
                    }
                }
            }
        } else if overlong(raw, terminated)
            && let Err(e) = parse_marked(parser, m, raw)
        {
            self.skip_errors.push((idx, pos, e));
        }
        if self.first_nonblank.is_none() && m.first_nonblank {
            self.first_nonblank = Some(idx);
            self.first_nonblank_next = next;
        }
    }

    /// Records a line the scan parsed (`idx`, `pos`, `next`, `terminated`
    /// as in [`Scan::line`]).
    fn parsed_line(&mut self, line: &Line, idx: u32, pos: u32, next: u32, terminated: bool) {
        match &line.kind {
            LineKind::Blank | LineKind::Items(_) => {}
            LineKind::Percent => {
                if self.first_nonblank.is_none() {
                    self.percent_start = true;
                }
                self.percent_lines.push(idx);
            }
            LineKind::O(o) => {
                let label = match &o.label {
                    Label::Static(s) => Some(s),
                    Label::Dynamic(_) => None,
                };
                let plain = label.is_some()
                    && o.expr.is_none()
                    && o.args.is_empty()
                    && !o.active_comment
                    && o.exec_error.is_none()
                    && !line.block_delete
                    && line.line_number.is_none();
                self.oline(idx, pos, (next, terminated, plain), o.kind, label);
            }
            LineKind::M98(_) => self.olines.push(OInfo {
                line_idx: idx,
                start: pos,
                next,
                key: NONE,
                scope: NONE,
                kind: None,
                terminated,
                plain: false,
            }),
        }
    }

    /// The index of a key (made if new).
    fn key_id(&mut self, key: Name) -> u32 {
        let n = self.keys.len() as u32;
        let id = *self.key_ids.entry(key.clone()).or_insert(n);
        if id == n {
            self.keys.push(key);
        }
        id
    }

    /// Records an O-line with its scope and key: lines are handed on in
    /// file order, so the definition being read is known.
    fn oline(
        &mut self,
        idx: u32,
        pos: u32,
        (next, terminated, plain): (u32, bool, bool),
        kind: OKind,
        label: Option<&Name>,
    ) {
        let i = self.olines.len() as u32;
        let label_id = label.map(|l| self.key_id(l.clone()));
        let mut scope = NONE;
        if kind == OKind::Sub {
            if self.current_def.is_none() {
                self.current_def = label_id;
            }
        } else if kind == OKind::EndSub
            && self.current_def.is_some()
            && self.current_def == label_id
        {
            scope = self.current_def.take().unwrap_or(NONE);
        }
        if let Some(d) = self.current_def
            && (kind != OKind::Sub || label_id != Some(d))
        {
            scope = d;
        }
        let key = match label {
            Some(l) if kind.is_control() => {
                let scope_text = if scope == NONE {
                    ""
                } else {
                    self.keys[scope as usize].as_str()
                };
                let k = control_key(scope_text, l);
                self.key_id(k)
            }
            Some(_) => label_id.unwrap_or(NONE),
            None => {
                self.dynamic.push(i);
                NONE
            }
        };
        self.olines.push(OInfo {
            line_idx: idx,
            start: pos,
            next,
            key,
            scope,
            kind: Some(kind),
            terminated,
            plain,
        });
    }
}

/// The occurrences of each key in file order, as runs of one array:
/// `(occ_at, occ)`.
fn occurrences(olines: &[OInfo], keys: usize) -> (Vec<u32>, Vec<u32>) {
    let mut occ_at = vec![0u32; keys + 1];
    for o in olines.iter().filter(|o| o.key != NONE) {
        occ_at[o.key as usize + 1] += 1;
    }
    for k in 0..keys {
        occ_at[k + 1] += occ_at[k];
    }
    let mut fill = occ_at.clone();
    let mut occ = vec![0u32; occ_at[keys] as usize];
    for (i, o) in olines.iter().enumerate().filter(|(_, o)| o.key != NONE) {
        let at = &mut fill[o.key as usize];
        occ[*at as usize] = i as u32;
        *at += 1;
    }
    (occ_at, occ)
}

/// Sub definitions: each is matched through its own label's occurrences,
/// so the work is linear in the number of O-lines. Each definition's line
/// range is pushed onto `keep`.
fn sub_defs(index: &FileIndex, keep: &mut Vec<(u32, u32)>) -> (Vec<SubDef>, Vec<u32>) {
    let olines = &index.olines;
    let mut defs = Vec::new();
    let mut valued = Vec::new();
    let sub_lines: Vec<u32> = olines
        .iter()
        .enumerate()
        .filter(|(_, o)| matches!(o.kind, Some(OKind::Sub | OKind::Bare)))
        .map(|(j, _)| j as u32)
        .collect();
    for (i, info) in olines.iter().enumerate() {
        if info.kind != Some(OKind::Sub) || info.key == NONE {
            continue;
        }
        let mut def = SubDef {
            oidx: i as u32,
            end: NONE,
            nested: NONE,
            valued_at: valued.len() as u32,
            valued_len: 0,
        };
        let list = index.occ_of(info.key);
        let p = list.partition_point(|&j| j as usize <= i);
        for &j in &list[p..] {
            match olines[j as usize].kind {
                Some(OKind::EndSub) => {
                    valued.push(j);
                    def.end = j;
                    break;
                }
                Some(OKind::Return) => valued.push(j),
                Some(OKind::Sub | OKind::Bare) => break,
                _ => {}
            }
        }
        def.valued_len = valued.len() as u32 - def.valued_at;
        let q = sub_lines.partition_point(|&j| j as usize <= i);
        if let Some(&j) = sub_lines.get(q)
            && def.end().is_none_or(|e| j < e)
        {
            def.nested = j;
        }
        match def.end() {
            Some(e) => keep.push((info.line_idx, olines[e as usize].line_idx)),
            None => keep.push((info.line_idx, index.line_count)),
        }
        defs.push(def);
    }
    (defs, valued)
}

/// Loop bodies: one backward pass per label finds each opener's closer;
/// each body's line range is pushed onto `keep`.
fn loop_bodies(index: &FileIndex, keep: &mut Vec<(u32, u32)>) {
    let olines = &index.olines;
    for k in 0..index.keys.len() as u32 {
        let (mut next_endwhile, mut next_while, mut next_endrepeat) = (None, None, None);
        for &j in index.occ_of(k).iter().rev() {
            let info = &olines[j as usize];
            let closer = match info.kind {
                Some(OKind::While) => next_endwhile,
                Some(OKind::Do) => next_while,
                Some(OKind::Repeat) => next_endrepeat,
                _ => None,
            };
            if let Some(c) = closer {
                let c: u32 = c;
                keep.push((info.line_idx, olines[c as usize].line_idx));
            }
            match info.kind {
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
    merged.shrink_to_fit();
    merged
}

/// Address of a name's interned text (what `Name` equality compares).
fn addr(n: &Name) -> usize {
    n.as_str().as_ptr() as usize
}

impl FileIndex {
    /// Indexes `file`; `named2007`: its lines are in the 2007
    /// named-parameter syntax too.
    pub fn build(file: Arc<SourceFile>, named2007: bool) -> FileIndex {
        let mut parser = LineParser::new(named2007);
        let mut scan = Scan {
            keep_parsed: file.memory().is_some(),
            ..Scan::default()
        };
        let scanned = file.scan_marked_lines(crate::parse::MAX_LINE + 1, &matters, |m, raw| {
            scan.line(&mut parser, m, raw)
        });
        let (line_count, read_error) = match scanned {
            Ok(n) => (n, None),
            Err(e) => (0, Some(e.to_string())),
        };
        let Scan {
            mut olines,
            mut keys,
            key_ids,
            mut dynamic,
            mut skip_errors,
            mut percent_lines,
            mut m99_lines,
            first_nonblank,
            first_nonblank_next,
            percent_start,
            parsed,
            ..
        } = scan;
        drop(key_ids);
        olines.shrink_to_fit();
        keys.shrink_to_fit();
        dynamic.shrink_to_fit();
        skip_errors.shrink_to_fit();
        percent_lines.shrink_to_fit();
        m99_lines.shrink_to_fit();
        let (occ_at, occ) = occurrences(&olines, keys.len());
        let mut keys_by_addr: Vec<u32> = (0..keys.len() as u32).collect();
        keys_by_addr.sort_unstable_by_key(|&k| addr(&keys[k as usize]));
        let mut index = FileIndex {
            file,
            read_error,
            first_nonblank_next,
            seek_memo: vec![Cell::new(u32::MAX); olines.len()],
            parsed_mask: olines.len().next_power_of_two().min(PARSED_KEPT) - 1,
            olines,
            keys,
            keys_by_addr,
            occ_at,
            occ,
            dynamic,
            skip_errors,
            percent_lines,
            m99_lines,
            defs: Vec::new(),
            valued: Vec::new(),
            keep: Vec::new(),
            percent_start,
            first_nonblank,
            line_count,
            no_scope: Name::new(""),
            parsed: RefCell::new(Vec::new()),
            parser: RefCell::new(parser),
            ahead: RefCell::default(),
        };
        let mut keep = Vec::new();
        let (mut defs, mut valued) = sub_defs(&index, &mut keep);
        defs.shrink_to_fit();
        valued.shrink_to_fit();
        (index.defs, index.valued) = (defs, valued);
        loop_bodies(&index, &mut keep);
        index.keep = merge_ranges(keep);
        for (oidx, line) in parsed {
            index.keep_parsed(oidx, line);
        }
        // The labels of the lines parsed (a control label's key is kept,
        // its bare label not).
        Name::forget_unused();
        index
    }

    /// The O-lines with key index `k`, in file order.
    fn occ_of(&self, k: u32) -> &[u32] {
        let k = k as usize;
        match (self.occ_at.get(k), self.occ_at.get(k + 1)) {
            (Some(&a), Some(&b)) => &self.occ[a as usize..b as usize],
            _ => &[],
        }
    }

    /// Index of a static key in this file, if it occurs.
    fn key_index(&self, key: &Name) -> Option<u32> {
        let a = addr(key);
        let p = self
            .keys_by_addr
            .partition_point(|&k| addr(&self.keys[k as usize]) < a);
        self.keys_by_addr
            .get(p)
            .copied()
            .filter(|&k| self.keys[k as usize] == *key)
    }

    /// The O-lines with this static key, in file order.
    pub fn occ(&self, key: &Name) -> &[u32] {
        self.key_index(key).map_or(&[], |k| self.occ_of(k))
    }

    /// The O-lines with the same static key as O-line `oidx`, if `key` is
    /// that key (no search), else those with `key`.
    pub fn occ_like(&self, oidx: u32, key: &Name) -> &[u32] {
        match self.olines.get(oidx as usize) {
            Some(o) if o.key != NONE && self.keys[o.key as usize] == *key => self.occ_of(o.key),
            _ => self.occ(key),
        }
    }

    /// The static label key of O-line `oidx` (`None`: computed label or
    /// M98 line).
    pub fn key(&self, oidx: u32) -> Option<&Name> {
        let k = self.olines.get(oidx as usize)?.key;
        self.keys.get(k as usize)
    }

    /// Name of the sub definition O-line `oidx` lies in ("" outside).
    pub fn scope(&self, oidx: u32) -> &Name {
        self.olines
            .get(oidx as usize)
            .and_then(|o| self.keys.get(o.scope as usize))
            .unwrap_or(&self.no_scope)
    }

    /// Whether two O-lines lie in the same sub definition (or both outside).
    pub fn same_scope(&self, a: u32, b: u32) -> bool {
        let scope = |i: u32| self.olines.get(i as usize).map(|o| o.scope);
        scope(a) == scope(b)
    }

    /// The sub definition whose `sub` line is O-line `oidx`.
    pub fn def(&self, oidx: u32) -> Option<SubDefInfo> {
        let d = self.def_at(oidx)?;
        let nested = (d.nested != NONE).then(|| {
            let name = self
                .key(d.nested)
                .cloned()
                .unwrap_or_else(|| Name::new("?"));
            (d.nested, name)
        });
        let (a, n) = (d.valued_at as usize, d.valued_len as usize);
        Some(SubDefInfo {
            end: d.end(),
            nested,
            valued: self.valued.get(a..a + n).unwrap_or(&[]).to_vec(),
        })
    }

    fn def_at(&self, oidx: u32) -> Option<&SubDef> {
        let p = self.defs.partition_point(|d| d.oidx < oidx);
        self.defs.get(p).filter(|d| d.oidx == oidx)
    }

    /// Whether O-line `oidx` opens a sub definition (one indexed by its
    /// fixed label).
    pub fn is_def(&self, oidx: u32) -> bool {
        self.def_at(oidx).is_some()
    }

    /// The sub definitions, by their `sub` line.
    pub fn defs(&self) -> &[SubDef] {
        &self.defs
    }

    /// O-line `oidx` parsed (again: the index keeps its kind and key, not
    /// the line; up to `PARSED_KEPT` parsed lines are kept). An error
    /// when the line cannot be read again or is no longer the O-line the
    /// index found (the file changed during the run).
    pub fn oline(&self, oidx: u32) -> Result<ParsedO, ErrorKind> {
        if let Some(Some((i, l))) = self.parsed.borrow().get(self.slot(oidx))
            && *i == oidx
        {
            return Ok(ParsedO(l.clone()));
        }
        let info = self
            .olines
            .get(oidx as usize)
            .copied()
            .ok_or_else(|| changed(0))?;
        let line = Rc::new(if info.plain {
            self.made_again(&info)?
        } else {
            self.parse_again(&info)?
        });
        self.keep_parsed(oidx, line.clone());
        Ok(ParsedO(line))
    }

    /// The slot of O-line `oidx` among the parsed lines kept.
    #[inline]
    fn slot(&self, oidx: u32) -> usize {
        oidx as usize & self.parsed_mask
    }

    /// Keeps O-line `oidx` parsed, in its slot (made when first used).
    fn keep_parsed(&self, oidx: u32, line: Rc<Line>) {
        let mut kept = self.parsed.borrow_mut();
        if kept.is_empty() {
            kept.resize(self.parsed_mask + 1, None);
        }
        let at = self.slot(oidx);
        if let Some(s) = kept.get_mut(at) {
            *s = Some((oidx, line));
        }
    }

    /// O-line `oidx` as a whole line (O or M98), parsed again.
    pub fn line(&self, oidx: u32) -> Result<Rc<Line>, ErrorKind> {
        match self.olines.get(oidx as usize) {
            Some(o) if o.kind.is_some() => self.oline(oidx).map(|p| p.0),
            Some(o) => self.parse_again(o).map(Rc::new),
            None => Err(changed(0)),
        }
    }

    /// A plain O-line as parsing it gives it.
    fn made_again(&self, info: &OInfo) -> Result<Line, ErrorKind> {
        let (Some(kind), Some(key)) = (info.kind, self.keys.get(info.key as usize)) else {
            return Err(changed(info.line_idx));
        };
        let label = if kind.is_control() {
            let scope = self.keys.get(info.scope as usize).map_or(0, |n| n.len());
            Name::new(key.get(scope + 1..).unwrap_or(""))
        } else {
            key.clone()
        };
        Ok(Line {
            kind: LineKind::O(OLine {
                label: Label::Static(label),
                label_span: Span::default(),
                kind,
                expr: None,
                args: Vec::new(),
                active_comment: false,
                exec_error: None,
            }),
            block_delete: false,
            line_number: None,
        })
    }

    fn parse_again(&self, info: &OInfo) -> Result<Line, ErrorKind> {
        let len = (info.next - info.start).saturating_sub(info.terminated as u32) as usize;
        if len > crate::parse::MAX_LINE + 1 {
            // Longer than a line that parses.
            return Err(changed(info.line_idx));
        }
        let ahead;
        let raw: &[u8] = match self.file.memory() {
            Some(d) => d
                .get(info.start as usize..info.start as usize + len)
                .ok_or_else(|| changed(info.line_idx))?,
            None => {
                ahead = self
                    .read_ahead(info.start, len)
                    .ok_or_else(|| changed(info.line_idx))?;
                let from = (info.start - ahead.0) as usize;
                ahead
                    .1
                    .get(from..from + len)
                    .ok_or_else(|| changed(info.line_idx))?
            }
        };
        let line = self
            .parser
            .borrow_mut()
            .parse(raw, info.terminated)
            .map_err(|_| changed(info.line_idx))?;
        let same = match (&line.kind, info.kind) {
            (LineKind::O(o), Some(kind)) => {
                o.kind == kind
                    && match &o.label {
                        Label::Static(s) => self.key_label_is(info, s),
                        Label::Dynamic(_) => info.key == NONE,
                    }
            }
            (LineKind::M98(_), None) => true,
            _ => false,
        };
        if same {
            Ok(line)
        } else {
            Err(changed(info.line_idx))
        }
    }

    /// The read-ahead block of a streamed file holding `len` bytes from
    /// `start` (read from `start` on if it does not).
    fn read_ahead(&self, start: u32, len: usize) -> Option<std::cell::Ref<'_, (u32, Vec<u8>)>> {
        let holds = |b: &(u32, Vec<u8>)| start >= b.0 && (start - b.0) as usize + len <= b.1.len();
        if !holds(&self.ahead.borrow()) {
            let mut b = self.ahead.borrow_mut();
            b.1.resize(AHEAD.max(len), 0);
            let got = self.file.read_at(&mut b.1, start as u64).unwrap_or(0);
            b.1.truncate(got);
            b.0 = start;
        }
        let b = self.ahead.borrow();
        holds(&b).then_some(b)
    }

    /// Whether the static label `s` read again gives the line's key.
    fn key_label_is(&self, info: &OInfo, s: &Name) -> bool {
        let Some(key) = self.keys.get(info.key as usize) else {
            return false;
        };
        match info.kind {
            Some(k) if k.is_control() => {
                let scope = self
                    .keys
                    .get(info.scope as usize)
                    .map_or("", |n| n.as_str());
                key.len() == scope.len() + 1 + s.len()
                    && key.starts_with(scope)
                    && key.ends_with(s.as_str())
            }
            _ => key == s,
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

    /// A parser of the syntax the file was indexed in.
    pub fn parser(&self) -> LineParser {
        LineParser::new(self.parser.borrow().named2007())
    }

    pub fn kind_of(&self, oidx: u32) -> Option<OKind> {
        self.olines[oidx as usize].kind
    }
}

/// The error for an O-line that is not what the index found.
fn changed(line_idx: u32) -> ErrorKind {
    ErrorKind::Limit(LimitError::ProgramChanged { line: line_idx + 1 })
}

/// The kind and label of a plain O-line in its simplest spelling, read
/// without the parser (most O-lines of a large program): `o<name> sub`,
/// `o100 endif`, ... with a lowercase keyword, a label of lowercase letters,
/// digits and `_` or a number without leading zero, blanks only around
/// them, nothing else on the line. `None` for anything else (the parser
/// reads it).
fn plain_oline(raw: &[u8], named2007: bool) -> Option<(OKind, &str)> {
    if raw.len() > crate::parse::MAX_LINE || named2007 {
        return None;
    }
    let blank = |b: &u8| matches!(b, b' ' | b'\t');
    let mut i = raw.iter().take_while(|b| blank(b)).count();
    if !matches!(raw.get(i), Some(b'o' | b'O')) {
        return None;
    }
    i += 1;
    let label = match raw.get(i) {
        Some(b'<') => {
            let n = raw[i + 1..]
                .iter()
                .take_while(|b| b.is_ascii_lowercase() || b.is_ascii_digit() || **b == b'_')
                .count();
            if n == 0 || raw.get(i + 1 + n) != Some(&b'>') {
                return None;
            }
            let l = &raw[i + 1..i + 1 + n];
            i += n + 2;
            l
        }
        Some(b'1'..=b'9') => {
            let n = raw[i..].iter().take_while(|b| b.is_ascii_digit()).count();
            if n > 9 {
                return None;
            }
            let l = &raw[i..i + n];
            i += n;
            l
        }
        _ => return None,
    };
    i += raw[i..].iter().take_while(|b| blank(b)).count();
    let n = raw[i..]
        .iter()
        .take_while(|b| b.is_ascii_lowercase())
        .count();
    let kind = match &raw[i..i + n] {
        b"sub" => OKind::Sub,
        b"endsub" => OKind::EndSub,
        b"do" => OKind::Do,
        b"else" => OKind::Else,
        b"endif" => OKind::EndIf,
        b"break" => OKind::Break,
        b"continue" => OKind::Continue,
        b"endwhile" => OKind::EndWhile,
        b"endrepeat" => OKind::EndRepeat,
        b"return" => OKind::Return,
        _ => return None,
    };
    let rest = &raw[i + n..];
    if !rest.iter().all(|b| matches!(b, b' ' | b'\t' | b'\r')) {
        return None;
    }
    Some((kind, std::str::from_utf8(label).ok()?))
}

/// Whether the index looks at a line handed on after the leading blank lines
/// (the closure in `FileIndex::build` does nothing with the others).
fn matters(raw: &[u8], terminated: bool) -> bool {
    starts_with_m99(raw) || quick_is_candidate(raw) || overlong(raw, terminated)
}

/// Parses a line the scan handed on. Its raw bytes are cut at 4 kB; a line
/// longer than that is too long whatever it holds, and its error spans it
/// to its true end, as when the whole line is parsed.
fn parse_marked(parser: &mut LineParser, m: Marked, raw: &[u8]) -> Result<Line, LineError> {
    let len = m.end - m.start;
    parser.parse(raw, m.terminated).map_err(|mut e| {
        if (raw.len() as u64) < len
            && matches!(e.kind, ErrorKind::Syntax(SyntaxError::CommandTooLong))
        {
            e.span.end = len as u32;
        }
        e
    })
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
    ErrorKind::OWord(OWordError::SubNotInFile {
        name: name.to_string(),
        file: file.path.clone(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn index_of(text: &str) -> FileIndex {
        let file = SourceFile::new(PathBuf::from("t.ngc"), "t.ngc".into(), text.into());
        FileIndex::build(Arc::new(file), false)
    }

    /// What a program of a million labels keeps per O-line and per sub
    /// definition stays a few integers.
    #[test]
    fn records_stay_small() {
        assert!(std::mem::size_of::<OInfo>() <= 24);
        assert!(std::mem::size_of::<SubDef>() <= 20);
        assert!(std::mem::size_of::<crate::diag::Site>() <= 16);
        assert!(std::mem::size_of::<crate::diag::Diagnostic>() <= 128);
    }

    /// Every O-line run again (parsed, or made from the index when it holds
    /// nothing but its label) is the line parsing it gives.
    #[test]
    fn lines_read_again_are_the_lines_parsed() {
        let text = "o<a> sub\n  O100 IF [#1 GT 2]\n  o100 endif (done)\n  o101 do\n  \
                    o101 break\n  o101 while [#2]\n/o102 repeat [3]\n  o102 endrepeat\n\
                    o<a> return [4]\no<a> endsub\nN10 o<a> call [1] [2]\no103 if [1]\n\
                    o103 elseif [2]\no103 else\no103 endif;x\no[1+2] if [0]\no3 endif\n\
                    M98 P5 L2\no<b> sub\no<b> endsub [7]\nM2";
        let index = index_of(text);
        let lines: Vec<&str> = text.lines().collect();
        let mut parser = LineParser::default();
        assert_eq!(index.olines.len(), 20);
        for (i, o) in index.olines.iter().enumerate() {
            let raw = lines[o.line_idx as usize];
            let mut want = parser.parse(raw.as_bytes(), o.terminated).expect("parses");
            let got = index.line(i as u32).expect("read again");
            if o.plain
                && let LineKind::O(o) = &mut want.kind
            {
                // Only a computed label's span is ever used.
                o.label_span = Span::default();
            }
            assert_eq!(*got, want, "line {raw:?}");
        }
        // Plain lines (no value, arguments, block delete or line number)
        // are made from the index.
        let plain: Vec<bool> = index.olines.iter().map(|o| o.plain).collect();
        assert!(plain[0] && plain[2] && plain[3] && plain[4] && plain[9]);
        assert!(!plain[1] && !plain[5] && !plain[6] && !plain[10] && !plain[19]);
    }

    /// Of a file in memory, the O-lines with values or arguments are kept
    /// as the scan parsed them (a short program parses each once); of a
    /// streamed file none are (it is read again, to see it unchanged).
    #[test]
    fn the_scan_keeps_the_olines_it_parsed_of_a_file_in_memory() {
        let text = "o<a> sub\n  G1 X#1\no<a> endsub\no1 while [#2 LT 3]\r\n\
                    o<a> call [#2]\n  #2 = [#2 + 1]\no1 endwhile\nM98 P5\nM2\n";
        let index = index_of(text);
        let kept: Vec<u32> = index
            .parsed
            .borrow()
            .iter()
            .flatten()
            .map(|(i, _)| *i)
            .collect();
        // `while` and `call` (not the plain lines, not M98).
        assert_eq!(kept, vec![2, 3]);
        let d = tempfile::tempdir().expect("tmp");
        let p = d.path().join("p.ngc");
        std::fs::write(&p, text).expect("write");
        let file = SourceFile::open_streamed(&p).expect("open");
        let streamed = FileIndex::build(Arc::new(file), false);
        assert!(streamed.parsed.borrow().iter().all(Option::is_none));
        assert_eq!(
            *streamed.oline(3).expect("read").line(),
            *index.oline(3).expect("kept").line()
        );
    }

    /// Lines of O-words and others, for programs made at random.
    const PIECES: &[&str] = &[
        "o1 while [#1 LT 3]",
        "O1 ENDWHILE",
        "o<s> call [#2 + 1] [2]",
        "o<s> sub",
        "o<s> endsub [#3]",
        "o<s> return",
        "/o2 if [#1 EQ 2]",
        "N5 o2 elseif [1]",
        "o2 else (x)",
        "o2 endif",
        "o3 repeat [2.5]",
        "o3 endrepeat",
        "o[1 + 2] if [0]",
        "o<bad> call [",
        "o4 do",
        "o4 while [#5 GT 0] (debug, #5)",
        "M98 P7 L2",
        "  G1 X[#1 * 2] ; c",
        "#1 = [#1 + 1]",
        "%",
        "",
    ];

    proptest::proptest! {
        /// An O-line kept from the scan of a file in memory is the line
        /// the run parses again from the same text read from disk.
        #[test]
        fn olines_kept_from_the_scan_are_the_lines_read_again(
            picks in proptest::collection::vec((0..PIECES.len(), 0..3u8), 1..40),
        ) {
            let mut text = String::new();
            for (k, end) in picks {
                text.push_str(PIECES[k]);
                text.push_str(["\n", "\r\n", "\t\n"][end as usize]);
            }
            let kept = index_of(&text);
            let d = tempfile::tempdir().expect("tmp");
            let p = d.path().join("p.ngc");
            std::fs::write(&p, &text).expect("write");
            let read = FileIndex::build(Arc::new(SourceFile::open_streamed(&p).expect("open")), false);
            proptest::prop_assert_eq!(kept.olines.len(), read.olines.len());
            for i in 0..kept.olines.len() as u32 {
                let a = kept.line(i).map(|l| (*l).clone());
                let b = read.line(i).map(|l| (*l).clone());
                proptest::prop_assert_eq!(a, b, "O-line {} of {:?}", i, text);
            }
        }
    }

    /// The lines read without the parser are read as the parser reads them;
    /// others are left to it.
    #[test]
    fn plain_olines_read_as_parsed() {
        let mut parser = LineParser::default();
        let mut plain = 0;
        for line in [
            "o<a> sub",
            "O<a_1> endsub",
            "  o100 endif",
            "\to7 else\r",
            "o100endif",
            "o<s12> return ",
            "o1 do",
            "o1 break",
            "o1 continue",
            "o1 endwhile",
            "o123456789 endrepeat",
            "o0100 endif",
            "o<A> sub",
            "o< a> sub",
            "o<a> SUB",
            "o100 endif (c)",
            "o100 endif;",
            "/o100 endif",
            "n1 o100 endif",
            "o100 if [1]",
            "o100 endif x",
            "o<a> endsub [1]",
            "o1234567890 endif",
            "o<> sub",
            "o100 end if",
            "o<a>sub",
            "o<a-b> sub",
            "o#1 endif",
            "o100 elseif [1]",
            "o100 while [1]",
        ] {
            let parsed = parser.parse(line.as_bytes(), true);
            match plain_oline(line.as_bytes(), false) {
                Some((kind, label)) => {
                    plain += 1;
                    let Ok(Line {
                        kind: LineKind::O(o),
                        block_delete: false,
                        line_number: None,
                    }) = &parsed
                    else {
                        panic!("{line:?}: {parsed:?}");
                    };
                    assert_eq!(o.kind, kind, "{line:?}");
                    assert_eq!(o.label, Label::Static(Name::new(label)), "{line:?}");
                    assert!(o.expr.is_none() && o.args.is_empty() && !o.active_comment);
                    assert!(o.exec_error.is_none(), "{line:?}");
                }
                None => assert!(
                    !matches!(line, "o<a> sub" | "o100endif" | "o1 do" | "o<a>sub"),
                    "{line:?} not read"
                ),
            }
        }
        assert_eq!(plain, 12);
    }

    /// Keys, scopes, occurrences and definitions as the file has them.
    #[test]
    fn keys_scopes_and_definitions() {
        let index = index_of(
            "o<a> sub\no1 if [1]\no1 endif\no<a> endsub\no1 if [1]\no1 endif\n\
             o<a> call\no<b> sub\no<b> endsub\nM2\n",
        );
        let key = |i: u32| index.key(i).map(|k| k.to_string());
        assert_eq!(key(0).as_deref(), Some("a"));
        assert_eq!(key(1).as_deref(), Some("a#1"));
        assert_eq!(key(4).as_deref(), Some("#1"));
        assert_eq!(index.scope(1).as_str(), "a");
        assert_eq!(index.scope(3).as_str(), "a");
        assert_eq!(index.scope(4).as_str(), "");
        assert!(index.same_scope(1, 2) && !index.same_scope(2, 4));
        assert_eq!(index.occ(&Name::new("a")), &[0, 3, 6]);
        assert_eq!(index.occ(&Name::new("a#1")), &[1, 2]);
        assert_eq!(index.occ(&Name::new("#1")), &[4, 5]);
        assert!(index.occ(&Name::new("zz")).is_empty());
        let defs: Vec<(u32, Option<u32>)> =
            index.defs().iter().map(|d| (d.oidx, d.end())).collect();
        assert_eq!(defs, [(0, Some(3)), (7, Some(8))]);
        let a = index.def(0).expect("def");
        assert_eq!(
            (a.end, a.nested.is_none(), a.valued),
            (Some(3), true, vec![3])
        );
        assert!(index.is_def(7) && !index.is_def(1));
    }

    /// Lines over 4 kB, which the scan hands on cut: a streamed file and the
    /// same bytes in memory give the same first non-blank line (its
    /// non-blank bytes past the cut) and the same too-long errors, spanning
    /// each line to its true end.
    #[test]
    fn lines_over_the_cut_index_alike_streamed_and_in_memory() {
        let text = [
            b"\n".repeat(3),
            b" ".repeat(5000),
            b"G0 X1\n%\no100 if [0]\n(".to_vec(),
            b"x".repeat(6000),
            b")\no100 endif\n".to_vec(),
            b" ".repeat(4500),
            b"M2".to_vec(),
        ]
        .concat();
        let d = tempfile::tempdir().expect("tmp");
        let p = d.path().join("p.ngc");
        std::fs::write(&p, &text).expect("write");
        let memory = FileIndex::build(
            Arc::new(SourceFile::new(p.clone(), "p.ngc".into(), text.clone())),
            false,
        );
        let streamed = FileIndex::build(
            Arc::new(SourceFile::open_streamed(&p).expect("open")),
            false,
        );
        for index in [&memory, &streamed] {
            assert_eq!(index.first_nonblank, Some(3));
            assert!(!index.percent_start);
            let errors: Vec<(u32, Span)> = index
                .skip_errors
                .iter()
                .map(|(l, _, e)| (*l, e.span))
                .collect();
            assert_eq!(
                errors,
                [
                    (3, Span::new(252, 5005)),
                    (6, Span::new(252, 6002)),
                    (8, Span::new(252, 4502)),
                ]
            );
        }
        assert_eq!(memory.skip_errors, streamed.skip_errors);
        assert_eq!(memory.line_count, streamed.line_count);
    }

    /// A streamed file changed during the run: an O-line read again that is
    /// no longer the line indexed is an error, not run.
    #[test]
    fn an_oline_changed_during_the_run_is_an_error() {
        let d = tempfile::tempdir().expect("tmp");
        let p = d.path().join("p.ngc");
        std::fs::write(&p, "G0 X1\no100 if [1]\n  G1 X2\no100 endif\nM2\n").expect("write");
        let file = SourceFile::open_streamed(&p).expect("open");
        let index = FileIndex::build(Arc::new(file), false);
        assert_eq!(index.oline(0).expect("unchanged").kind, OKind::If);
        let forget = || {
            index.parsed.borrow_mut().fill(None);
            index.ahead.borrow_mut().1.clear();
        };
        // The same length, another label: a plain line is made from the
        // index, not read again.
        std::fs::write(&p, "G0 X1\no100 if [1]\n  G1 X2\no200 endif\nM2\n").expect("write");
        forget();
        assert!(index.oline(1).is_ok(), "plain lines come from the index");
        std::fs::write(&p, "G0 X1\no200 if [1]\n  G1 X2\no100 endif\nM2\n").expect("write");
        forget();
        assert!(matches!(
            index.oline(0),
            Err(ErrorKind::Limit(LimitError::ProgramChanged { line: 2 }))
        ));
        std::fs::write(&p, "G0 X1\n").expect("truncate");
        forget();
        assert!(matches!(
            index.oline(0),
            Err(ErrorKind::Limit(LimitError::ProgramChanged { line: 2 }))
        ));
    }
}
