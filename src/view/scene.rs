//! The scene of the interactive page: every move of a program as a 3-D
//! polyline in work coordinates, with what the page shows about it (kind,
//! tool, feed, start time and duration, the output line and the source line
//! and call chain that made it).
//!
//! The scene has a budget of moves and vertices. A program that goes over
//! it is made coarser by levels, each applied to the whole program so the
//! density stays even: neighbouring moves of the same kind and tool merge
//! into one of up to `2^merge_level` program moves (all points kept);
//! inside a move only every `2^vertex_level`-th point the program made is
//! kept; and when
//! moves cannot merge, only every `2^drop_level`-th program move is kept.
//! Never left out: a vertex where the toolpath reaches its lowest or
//! highest X, Y or Z (so the drawn envelope is the program's), and a move
//! that leaves the machine's travel limits (the first [`MAX_VIOLATIONS`]).
//! The scene counts what it merged and left out; the page says so.

use std::collections::HashMap;
use std::f64::consts::TAU;

use serde::Serialize;

use super::geom::{ArcGeom, arc_point};
use super::source_map::{Locator, Place};
use crate::eval::Origin;
use crate::machine::motion::{Axes, Motion, MoveKind};

/// At most this many moves are kept.
pub(crate) const MAX_MOVES: usize = 80_000;
/// At most this many vertices are kept.
pub(crate) const MAX_VERTICES: usize = 200_000;
/// Moves outside the travel limits that are always kept and listed.
pub(crate) const MAX_VIOLATIONS: usize = 1000;
/// Distinct call chains kept (a chain past this is shown as unknown).
const MAX_CHAINS: usize = 50_000;
/// Longest output line text kept, in bytes.
const MAX_TEXT: usize = 160;
/// An arc is drawn with a segment per this angle (and at its extremes).
const ARC_STEP: f64 = TAU / 72.0;

/// Kind bits of a move.
pub(crate) const K_RAPID: u8 = 0;
pub(crate) const K_FEED: u8 = 1;
pub(crate) const K_PROBE: u8 = 2;
pub(crate) const K_SYNC: u8 = 3;
const K_MASK: u8 = 3;
/// Has an arc in it.
pub(crate) const F_ARC: u8 = 4;
/// Not timed by the run-time model.
pub(crate) const F_UNTIMED: u8 = 8;

#[derive(Debug, Clone)]
struct Mv {
    /// First and last vertex (the first is the start point).
    start: u32,
    end: u32,
    kind: u8,
    tool: u16,
    feed: f32,
    t0: f64,
    dur: f64,
    /// First output line (1-based) and how many lines after it are drawn
    /// as part of this move.
    line: u32,
    lines: u32,
    /// Program move number (0-based) of the first move, and how many
    /// program moves this one stands for.
    seq: u32,
    count: u32,
    file: u32,
    src_line: u32,
    chain: u32,
    /// Index + 1 of the travel-limit violation, 0 if none.
    viol: u32,
    /// The output line's text, on the first move of a line.
    text: Option<Box<str>>,
}

/// What the scene left out or merged to stay within its budget.
#[derive(Debug, Clone, Default, Serialize)]
pub(crate) struct Detail {
    /// Moves of the program (lines and arcs).
    pub program_moves: u64,
    /// Moves kept (after merging and leaving out).
    pub drawn_moves: u64,
    /// Program moves drawn merged into a neighbour.
    pub merged_moves: u64,
    /// Program moves left out.
    pub left_out_moves: u64,
    /// Moves from or to a position that is not known (not drawn).
    pub unknown_moves: u64,
    /// Points inside arcs and merged moves left out.
    pub left_out_points: u64,
    /// Travel-limit violations past the first [`MAX_VIOLATIONS`].
    pub violations_not_listed: u64,
    /// Moves not checked against the travel limits because the machine
    /// position was not known.
    pub limits_unchecked: u64,
    /// Coarsening passes made.
    pub passes: u32,
}

/// One travel-limit violation.
#[derive(Debug, Clone, Serialize)]
pub(crate) struct Violation {
    pub message: String,
    /// Program move number (0-based).
    pub seq: u64,
    pub line: u32,
}

/// An output line as the scene keeps it (see [`Scene::line_meta`]).
#[derive(Debug, Clone)]
pub(crate) struct LineMeta {
    text: Box<str>,
    file: u32,
    src_line: u32,
    chain: u32,
}

/// The scene being built from the motion stream.
pub(crate) struct Scene {
    verts: Vec<[f32; 3]>,
    /// How many envelope extremes a vertex holds.
    vprot: Vec<u8>,
    /// The number of each vertex in the order the program made them: the
    /// points inside moves kept at vertex level L are those whose number is
    /// a multiple of 2^L, whatever pass looks at them.
    vseq: Vec<u32>,
    vcount: u32,
    moves: Vec<Mv>,
    /// Per axis X, Y, Z: (lowest value, its vertex), (highest, its vertex).
    ext: [Option<(f64, u32)>; 6],
    tools: Vec<i64>,
    tool: u16,
    clock: f64,
    line_no: u32,
    line_text: Option<Box<str>>,
    line_file: u32,
    line_src: u32,
    line_chain: u32,
    locator: Locator,
    files: Vec<String>,
    file_ids: HashMap<String, u32>,
    chains: Vec<Vec<(u32, u32)>>,
    chain_ids: HashMap<Vec<(u32, u32)>, u32>,
    pub violations: Vec<Violation>,
    pub detail: Detail,
    /// The offset from work to machine coordinates of the first move that
    /// had one, and whether a later move had another.
    pub offset: Option<[f64; 3]>,
    pub offset_varies: bool,
    max_moves: usize,
    max_vertices: usize,
    merge_level: u8,
    drop_level: u8,
    vertex_level: u8,
}

impl std::fmt::Debug for Scene {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Scene")
            .field("moves", &self.moves.len())
            .field("vertices", &self.verts.len())
            .finish()
    }
}

impl Default for Scene {
    fn default() -> Scene {
        Scene::with_budget(MAX_MOVES, MAX_VERTICES)
    }
}

impl Scene {
    pub(crate) fn with_budget(max_moves: usize, max_vertices: usize) -> Scene {
        Scene {
            verts: Vec::new(),
            vprot: Vec::new(),
            vseq: Vec::new(),
            vcount: 0,
            moves: Vec::new(),
            ext: [None; 6],
            tools: vec![0],
            tool: 0,
            clock: 0.0,
            line_no: 0,
            line_text: None,
            line_file: 0,
            line_src: 0,
            line_chain: 0,
            locator: Locator::default(),
            files: Vec::new(),
            file_ids: HashMap::new(),
            chains: vec![Vec::new()],
            chain_ids: HashMap::new(),
            violations: Vec::new(),
            detail: Detail::default(),
            offset: None,
            offset_varies: false,
            max_moves: max_moves.max(16),
            max_vertices: max_vertices.max(64),
            merge_level: 0,
            drop_level: 0,
            vertex_level: 0,
        }
    }

    fn file_id(&mut self, name: String) -> u32 {
        if let Some(&i) = self.file_ids.get(&name) {
            return i;
        }
        let i = self.files.len() as u32;
        self.files.push(name.clone());
        self.file_ids.insert(name, i);
        i
    }

    /// The next output line's moves come from `meta`.
    pub(crate) fn set_line(&mut self, meta: LineMeta) {
        self.line_no += 1;
        self.line_text = Some(meta.text);
        self.line_file = meta.file;
        self.line_src = meta.src_line;
        self.line_chain = meta.chain;
    }

    /// The time the next move starts at (s): where the run-time model puts
    /// its line.
    pub(crate) fn set_clock(&mut self, start: f64) {
        if start.is_finite() {
            self.clock = start;
        }
    }

    /// What the scene keeps of an output line: its text, file, source line
    /// and call chain.
    pub(crate) fn line_meta(&mut self, text: &[u8], origin: &Origin<'_>) -> LineMeta {
        let cut = text.len().min(MAX_TEXT);
        let mut t = String::from_utf8_lossy(&text[..cut]).into_owned();
        if cut < text.len() {
            t.push('…');
        }
        let at = self.locator.locate(&Place {
            file: origin.file.clone(),
            offset: origin.line_start,
        });
        let file = self.file_id(at.file);
        let stack = (origin.stack)();
        let chain = if stack.is_empty() {
            0
        } else {
            let mut chain = Vec::with_capacity(stack.len());
            for s in stack {
                let l = self.locator.locate(&Place {
                    file: s.file,
                    offset: s.start,
                });
                let f = self.file_id(l.file);
                chain.push((f, l.line));
            }
            match self.chain_ids.get(&chain) {
                Some(&c) => c,
                None if self.chains.len() < MAX_CHAINS => {
                    let c = self.chains.len() as u32;
                    self.chains.push(chain.clone());
                    self.chain_ids.insert(chain, c);
                    c
                }
                None => u32::MAX,
            }
        };
        LineMeta {
            text: t.into_boxed_str(),
            file,
            src_line: at.line,
            chain,
        }
    }

    /// Time that passes without motion (a dwell).
    pub(crate) fn wait(&mut self, seconds: f64) {
        if seconds.is_finite() && seconds > 0.0 {
            self.clock += seconds;
        }
    }

    pub(crate) fn tool_change(&mut self, tool: i64) {
        self.tool = match self.tools.iter().position(|&t| t == tool) {
            Some(i) => i as u16,
            None if self.tools.len() < u16::MAX as usize => {
                self.tools.push(tool);
                (self.tools.len() - 1) as u16
            }
            None => self.tool,
        };
    }

    /// Adds one move taking `dur` seconds (`timed` false: the time model
    /// could not time it), with the travel-limit violation it makes.
    pub(crate) fn add(&mut self, m: &Motion, dur: f64, timed: bool, violation: Option<String>) {
        let (kind, from, to, feed, arc) = match m {
            Motion::Line {
                kind,
                from,
                to,
                feed,
            } => (*kind, from, to, feed.rate, None),
            Motion::Arc {
                from,
                to,
                center,
                plane,
                ccw,
                turns,
                feed,
            } => (
                MoveKind::Feed,
                from,
                to,
                feed.rate,
                Some(ArcGeom::new(
                    &from.work,
                    &to.work,
                    *center,
                    *plane,
                    *ccw,
                    *turns,
                    crate::geom::arc::FullCircle::Exact,
                )),
            ),
            Motion::Dwell { .. } => return self.wait(dur),
            Motion::ToolChange { tool } => {
                // What the planner ran to a stop here counts too.
                self.wait(dur);
                return self.tool_change(*tool);
            }
            _ => return self.wait(dur),
        };
        let seq = self.detail.program_moves;
        self.detail.program_moves += 1;
        let t0 = self.clock;
        let dur = if dur.is_finite() && dur > 0.0 {
            dur
        } else {
            0.0
        };
        self.clock += dur;
        if let Some(o) = to.offset {
            let o3 = [o[0], o[1], o[2]];
            match self.offset {
                None => self.offset = Some(o3),
                Some(p) if p != o3 && o3.iter().all(|v| v.is_finite()) => self.offset_varies = true,
                _ => {}
            }
        }
        let xyz = |p: &Axes| [p[0], p[1], p[2]];
        if !xyz(&from.work)
            .iter()
            .chain(xyz(&to.work).iter())
            .all(|v| v.is_finite())
        {
            self.detail.unknown_moves += 1;
            return;
        }
        let viol = self.violation(violation, seq);
        let a = xyz(&from.work);
        let connected = self
            .moves
            .last()
            .is_some_and(|l| self.verts[l.end as usize] == a.map(|v| v as f32));
        let start = if connected {
            self.moves.last().map_or(0, |l| l.end)
        } else {
            self.push_vertex(a)
        };
        let mut flags = 0;
        if let Some(g) = arc {
            flags |= F_ARC;
            self.push_arc(&g, &from.work, &to.work);
        }
        let end = self.push_vertex(xyz(&to.work));
        if !timed {
            flags |= F_UNTIMED;
        }
        let kind = match kind {
            MoveKind::Rapid => K_RAPID,
            MoveKind::Feed => K_FEED,
            MoveKind::Probe => K_PROBE,
            MoveKind::SpindleSync => K_SYNC,
        };
        let first_of_line = self.moves.last().is_none_or(|l| l.line != self.line_no);
        self.moves.push(Mv {
            start,
            end,
            kind: kind | flags,
            tool: self.tool,
            feed: if kind == K_RAPID {
                f32::NAN
            } else {
                feed as f32
            },
            t0,
            dur,
            line: self.line_no,
            lines: 0,
            seq: seq.min(u64::from(u32::MAX)) as u32,
            count: 1,
            file: self.line_file,
            src_line: self.line_src,
            chain: self.line_chain,
            viol,
            text: if first_of_line {
                self.line_text.clone()
            } else {
                None
            },
        });
        if self.moves.len() > self.max_moves || self.verts.len() > self.max_vertices {
            self.coarsen();
        }
    }

    /// The points inside an arc: one per [`ARC_STEP`] and its extremes.
    fn push_arc(&mut self, g: &ArcGeom, from: &Axes, to: &Axes) {
        let n = ((g.sweep.abs() / ARC_STEP).ceil() as usize).clamp(1, 4096);
        let mut ts: Vec<f64> = (1..n).map(|k| k as f64 / n as f64).collect();
        ts.extend(g.quadrant_crossings());
        ts.sort_by(f64::total_cmp);
        for t in ts {
            let p = arc_point(g, from, to, t);
            self.push_vertex([p[0], p[1], p[2]]);
        }
    }

    /// Records a travel-limit violation; its index + 1 (0: not listed).
    fn violation(&mut self, violation: Option<String>, seq: u64) -> u32 {
        match violation {
            Some(message) if self.violations.len() < MAX_VIOLATIONS => {
                self.violations.push(Violation {
                    message,
                    seq,
                    line: self.line_no,
                });
                self.violations.len() as u32
            }
            Some(_) => {
                self.detail.violations_not_listed += 1;
                0
            }
            None => 0,
        }
    }

    fn push_vertex(&mut self, p: [f64; 3]) -> u32 {
        let i = self.verts.len() as u32;
        self.verts.push(p.map(|v| v as f32));
        self.vprot.push(0);
        self.vseq.push(self.vcount);
        self.vcount = self.vcount.wrapping_add(1);
        for (axis, &v) in p.iter().enumerate() {
            for (slot, lower) in [(2 * axis, true), (2 * axis + 1, false)] {
                let better = match self.ext[slot] {
                    None => true,
                    Some((e, _)) => {
                        if lower {
                            v < e
                        } else {
                            v > e
                        }
                    }
                };
                if better {
                    if let Some((_, old)) = self.ext[slot] {
                        self.vprot[old as usize] -= 1;
                    }
                    self.vprot[i as usize] += 1;
                    self.ext[slot] = Some((v, i));
                }
            }
        }
        i
    }

    /// Coarsens until the scene is within three quarters of its budget.
    /// Each step raises a level only when the one before could do little,
    /// so the whole program ends up at the same density: moves merge up to
    /// `2^merge_level` program moves, every `2^drop_level`-th move is kept,
    /// and `vertex_level` halvings of the points inside moves are made.
    fn coarsen(&mut self) {
        let goal_m = self.max_moves * 3 / 4;
        let goal_v = self.max_vertices * 3 / 4;
        for _ in 0..200 {
            let (m0, v0) = (self.moves.len(), self.verts.len());
            if m0 <= goal_m && v0 <= goal_v {
                return;
            }
            // Enough progress: a tenth off whatever is over its goal.
            let reduced = |s: &Scene| {
                (m0 <= goal_m || s.moves.len() * 10 <= m0 * 9)
                    && (v0 <= goal_v || s.verts.len() * 10 <= v0 * 9)
            };
            self.pass();
            if !reduced(self) {
                if v0 > goal_v && self.vertex_level < 24 {
                    self.vertex_level += 1;
                }
                // Points at the ends of moves go only when moves merge.
                if (m0 > goal_m || self.vertex_level >= 6) && self.merge_level < 31 {
                    self.merge_level += 1;
                }
                self.pass();
                if !reduced(self) && self.drop_level < 31 {
                    self.drop_level += 1;
                    self.pass();
                }
            }
            self.detail.passes += 1;
        }
        // Nothing more could go (only moves that must stay are left): the
        // budget grows rather than coarsening again at every move.
        self.max_moves = self.max_moves.max(self.moves.len() * 2);
        self.max_vertices = self.max_vertices.max(self.verts.len() * 2);
    }

    /// Brings the moves added since the last coarsening to the level of the
    /// rest, so the density is even over the whole program.
    pub(crate) fn finish(&mut self) {
        if self.merge_level + self.drop_level + self.vertex_level == 0 {
            return;
        }
        for _ in 0..40 {
            let before = (self.moves.len(), self.verts.len());
            self.pass();
            if (self.moves.len(), self.verts.len()) == before {
                break;
            }
        }
    }

    /// Whether a move must stay: it leaves the limits or holds an extreme.
    fn keeps(&self, m: &Mv) -> bool {
        m.viol != 0 || (m.start..=m.end).any(|v| self.vprot[v as usize] > 0)
    }

    /// One pass at the current levels: merges neighbouring moves, leaves
    /// out moves off the sampling stride and thins points inside moves.
    fn pass(&mut self) {
        let old_moves = std::mem::take(&mut self.moves);
        let cap = 1u64 << self.merge_level;
        let stride = 1u64 << self.drop_level;
        // Moves as groups of one or two (merged), the sampled-out left out.
        let mut groups: Vec<(Mv, Option<Mv>)> = Vec::with_capacity(old_moves.len());
        let mut it = old_moves.into_iter().peekable();
        while let Some(a) = it.next() {
            let merge = it.peek().is_some_and(|b| {
                a.end == b.start
                    && a.kind & K_MASK == b.kind & K_MASK
                    && a.tool == b.tool
                    && a.viol == 0
                    && b.viol == 0
                    && self.vprot[a.end as usize] == 0
                    && u64::from(a.count) + u64::from(b.count) <= cap
            });
            let b = if merge { it.next() } else { None };
            if stride > 1
                && u64::from(a.seq) % stride != 0
                && !self.keeps(&a)
                && b.as_ref().is_none_or(|b| !self.keeps(b))
            {
                self.detail.left_out_moves +=
                    u64::from(a.count) + b.as_ref().map_or(0, |b| u64::from(b.count));
                continue;
            }
            groups.push((a, b));
        }
        let old_verts = std::mem::take(&mut self.verts);
        let old_prot = std::mem::take(&mut self.vprot);
        let old_seq = std::mem::take(&mut self.vseq);
        let mut remap: HashMap<u32, u32> = HashMap::new();
        let mut verts: Vec<[f32; 3]> = Vec::with_capacity(old_verts.len());
        let mut prot: Vec<u8> = Vec::with_capacity(old_verts.len());
        let mut seqs: Vec<u32> = Vec::with_capacity(old_verts.len());
        let mut put = |old: u32, verts: &mut Vec<[f32; 3]>, prot: &mut Vec<u8>| {
            let n = verts.len() as u32;
            verts.push(old_verts[old as usize]);
            prot.push(old_prot[old as usize]);
            seqs.push(old_seq[old as usize]);
            if old_prot[old as usize] > 0 {
                remap.insert(old, n);
            }
            n
        };
        // The old index of the last vertex written, and its new index.
        let mut last: Option<(u32, u32)> = None;
        let mut moves: Vec<Mv> = Vec::with_capacity(groups.len());
        for (mut a, b) in groups {
            let end = b.as_ref().map_or(a.end, |b| b.end);
            let step = 1u32 << self.vertex_level.min(31);
            let start = match last {
                Some((o, n)) if o == a.start => n,
                _ => put(a.start, &mut verts, &mut prot),
            };
            // The points inside: a's, the shared one, b's.
            let inner = a.start + 1..end;
            let keep_all = a.viol != 0 || b.as_ref().is_some_and(|b| b.viol != 0);
            for v in inner {
                if keep_all || old_seq[v as usize].is_multiple_of(step) || old_prot[v as usize] > 0
                {
                    put(v, &mut verts, &mut prot);
                } else {
                    self.detail.left_out_points += 1;
                }
            }
            let new_end = put(end, &mut verts, &mut prot);
            last = Some((end, new_end));
            if let Some(b) = b {
                a.kind |= b.kind & (F_ARC | F_UNTIMED);
                a.dur = b.t0 + b.dur - a.t0;
                a.lines = (b.line + b.lines).saturating_sub(a.line);
                a.count += b.count;
            }
            a.start = start;
            a.end = new_end;
            moves.push(a);
        }
        for (_, i) in self.ext.iter_mut().flatten() {
            if let Some(&n) = remap.get(i) {
                *i = n;
            }
        }
        self.moves = moves;
        self.verts = verts;
        self.vprot = prot;
        self.vseq = seqs;
    }

    /// The scene as the page's data.
    pub(crate) fn data(&self) -> SceneData {
        let mut d = self.detail.clone();
        d.drawn_moves = self.moves.len() as u64;
        d.merged_moves = self
            .moves
            .iter()
            .filter(|m| m.count > 1)
            .map(|m| u64::from(m.count))
            .sum();
        let b64 = |bytes: Vec<u8>| {
            use base64::Engine;
            base64::engine::general_purpose::STANDARD.encode(bytes)
        };
        fn bytes<T: Copy, const N: usize>(
            v: impl Iterator<Item = T>,
            f: fn(T) -> [u8; N],
        ) -> Vec<u8> {
            v.flat_map(f).collect()
        }
        let m = &self.moves;
        SceneData {
            vertices: b64(bytes(
                self.verts.iter().flatten().copied(),
                f32::to_le_bytes,
            )),
            start: b64(bytes(m.iter().map(|m| m.start), u32::to_le_bytes)),
            end: b64(bytes(m.iter().map(|m| m.end), u32::to_le_bytes)),
            kind: b64(m.iter().map(|m| m.kind).collect()),
            tool: b64(bytes(m.iter().map(|m| m.tool), u16::to_le_bytes)),
            feed: b64(bytes(m.iter().map(|m| m.feed), f32::to_le_bytes)),
            t0: b64(bytes(m.iter().map(|m| m.t0), f64::to_le_bytes)),
            dur: b64(bytes(m.iter().map(|m| m.dur as f32), f32::to_le_bytes)),
            line: b64(bytes(m.iter().map(|m| m.line), u32::to_le_bytes)),
            lines: b64(bytes(m.iter().map(|m| m.lines), u32::to_le_bytes)),
            seq: b64(bytes(m.iter().map(|m| m.seq), u32::to_le_bytes)),
            count: b64(bytes(m.iter().map(|m| m.count), u32::to_le_bytes)),
            file: b64(bytes(m.iter().map(|m| m.file), u32::to_le_bytes)),
            src_line: b64(bytes(m.iter().map(|m| m.src_line), u32::to_le_bytes)),
            chain: b64(bytes(m.iter().map(|m| m.chain), u32::to_le_bytes)),
            viol: b64(bytes(m.iter().map(|m| m.viol), u32::to_le_bytes)),
            texts: m
                .iter()
                .filter_map(|m| m.text.as_ref().map(|t| (m.line, t.to_string())))
                .collect(),
            files: self.files.clone(),
            chains: self.chains.clone(),
            tools: self.tools.clone(),
            total_time: self.clock,
            detail: d,
            violations: self.violations.clone(),
        }
    }
}

/// The scene as the page reads it: arrays as base64 of little-endian
/// values, one entry per move.
#[derive(Debug, Serialize)]
pub(crate) struct SceneData {
    /// X, Y, Z of every vertex (f32).
    pub vertices: String,
    pub start: String,
    pub end: String,
    pub kind: String,
    pub tool: String,
    pub feed: String,
    pub t0: String,
    pub dur: String,
    pub line: String,
    pub lines: String,
    pub seq: String,
    pub count: String,
    pub file: String,
    pub src_line: String,
    pub chain: String,
    pub viol: String,
    /// (output line, text) of the lines that start a kept move.
    pub texts: Vec<(u32, String)>,
    pub files: Vec<String>,
    /// Call chains, innermost caller first: (file, line).
    pub chains: Vec<Vec<(u32, u32)>>,
    pub tools: Vec<i64>,
    pub total_time: f64,
    pub detail: Detail,
    pub violations: Vec<Violation>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::codes::FeedMode;
    use crate::machine::motion::{Feed, Point};

    fn pt(x: f64, y: f64, z: f64) -> Point {
        let mut w = [0.0; 9];
        w[0] = x;
        w[1] = y;
        w[2] = z;
        Point {
            work: w,
            offset: Some([0.0; 9]),
        }
    }

    fn line(kind: MoveKind, a: [f64; 3], b: [f64; 3]) -> Motion {
        Motion::Line {
            kind,
            from: pt(a[0], a[1], a[2]),
            to: pt(b[0], b[1], b[2]),
            feed: Feed {
                rate: 100.0,
                mode: FeedMode::PerMinute,
            },
        }
    }

    fn decode<const N: usize, T>(b64: &str, f: fn([u8; N]) -> T) -> Vec<T> {
        use base64::Engine;
        let b = base64::engine::general_purpose::STANDARD
            .decode(b64)
            .expect("base64");
        b.chunks(N)
            .map(|c| f(c.try_into().expect("chunk")))
            .collect()
    }

    /// A zig-zag raster of `n` feed moves with rapids between rows every
    /// `row` moves; the deepest point in the middle, one move outside the
    /// limits near the end.
    fn raster(s: &mut Scene, n: usize, row: usize, kinds_alternate: bool) -> (usize, usize) {
        let mut p = [0.0, 0.0, 0.0];
        let (deep, bad) = (n / 2 + 3, n - 7);
        for i in 0..n {
            let mut q = p;
            q[0] = if (i / row).is_multiple_of(2) {
                p[0] + 1.0
            } else {
                p[0] - 1.0
            };
            q[2] = if i == deep {
                -9.5
            } else {
                -1.0 - (i % 3) as f64 * 0.1
            };
            let kind = if kinds_alternate && i % 2 == 1 || i % row == 0 {
                MoveKind::Rapid
            } else {
                MoveKind::Feed
            };
            if i % row == 0 {
                q[1] += 2.0;
            }
            let viol = (i == bad).then(|| "X leaves its limit".to_string());
            s.add(&line(kind, p, q), 0.5, true, viol);
            p = q;
        }
        (deep, bad)
    }

    fn check_budget(kinds_alternate: bool) {
        let mut s = Scene::with_budget(500, 1200);
        let n = 20_000;
        let (_, bad) = raster(&mut s, n, 40, kinds_alternate);
        s.finish();
        let d = s.data();
        let verts = decode(&d.vertices, f32::from_le_bytes);
        let count = decode(&d.count, u32::from_le_bytes);
        let viol = decode(&d.viol, u32::from_le_bytes);
        let seq = decode(&d.seq, u32::from_le_bytes);
        let t0 = decode(&d.t0, f64::from_le_bytes);
        let dur = decode(&d.dur, f32::from_le_bytes);
        assert!(
            count.len() <= 500 && verts.len() / 3 <= 1200,
            "{}",
            count.len()
        );
        assert!(
            count.len() > 100,
            "not coarser than needed: {}",
            count.len()
        );
        // Every program move is drawn, merged into another, or counted
        // as left out.
        let drawn: u64 = count.iter().map(|&c| u64::from(c)).sum();
        assert_eq!(drawn + d.detail.left_out_moves, n as u64);
        assert_eq!(d.detail.program_moves, n as u64);
        assert!(d.detail.merged_moves + d.detail.left_out_moves > 0);
        // The deepest point and the violation are kept.
        let zmin = verts.chunks(3).map(|v| v[2]).fold(f32::INFINITY, f32::min);
        assert_eq!(zmin, -9.5);
        let k = viol.iter().position(|&v| v == 1).expect("violation kept");
        assert_eq!(seq[k] as usize, bad);
        assert_eq!(d.violations.len(), 1);
        // Times stay in order and the last move ends at the total.
        assert!(t0.windows(2).all(|w| w[0] <= w[1]));
        let last = count.len() - 1;
        assert!(t0[last] + f64::from(dur[last]) <= d.total_time + 1e-6);
        assert_eq!(d.total_time, n as f64 * 0.5);
        // The density is even: the first and the last quarter of the
        // program keep about as many moves.
        let q = |lo: usize, hi: usize| {
            seq.iter()
                .filter(|&&s| (lo..hi).contains(&(s as usize)))
                .count() as f64
        };
        let (a, b) = (q(0, n / 4), q(3 * n / 4, n));
        assert!(a / b < 3.0 && b / a < 3.0, "{a} against {b}");
    }

    #[test]
    fn budget_merges_and_keeps_extremes_and_violations() {
        check_budget(false);
    }

    #[test]
    fn budget_samples_when_moves_cannot_merge() {
        check_budget(true);
    }

    #[test]
    fn small_program_is_drawn_whole() {
        let mut s = Scene::default();
        raster(&mut s, 300, 10, false);
        let d = s.data();
        assert_eq!(d.detail.drawn_moves, 300);
        assert_eq!(d.detail.merged_moves + d.detail.left_out_moves, 0);
    }
}
