//! The scene of the interactive page: every move of a program as a 3-D
//! polyline in work coordinates, with what the page shows about it (kind,
//! tool, feed, start time and duration, the output line and the source line
//! and call chain that made it).
//!
//! The scene has a budget of moves and vertices. A program that goes over
//! it is made coarser in passes, each roughly halving what is kept:
//! neighbouring moves of the same kind and tool are drawn as one (their
//! shared point and every other point inside an arc left out), and if that
//! is not enough, every other move is left out. Never left out: a vertex
//! where the toolpath reaches its lowest or highest X, Y or Z (so the
//! drawn envelope is the program's), and a move that leaves the machine's
//! travel limits (the first [`MAX_VIOLATIONS`]). The scene counts what it
//! merged and left out; the page says so.

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

/// The scene being built from the motion stream.
pub(crate) struct Scene {
    verts: Vec<[f32; 3]>,
    /// How many envelope extremes a vertex holds.
    vprot: Vec<u8>,
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

    /// The next output line: its text and where it came from.
    pub(crate) fn line(&mut self, text: &[u8], origin: &Origin<'_>) {
        self.line_no += 1;
        let cut = text.len().min(MAX_TEXT);
        let mut t = String::from_utf8_lossy(&text[..cut]).into_owned();
        if cut < text.len() {
            t.push('…');
        }
        self.line_text = Some(t.into_boxed_str());
        let at = self.locator.locate(&Place {
            file: origin.file.clone(),
            offset: origin.line_start,
        });
        self.line_file = self.file_id(at.file);
        self.line_src = at.line;
        let stack = (origin.stack)();
        self.line_chain = if stack.is_empty() {
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
                    &from.work, &to.work, *center, *plane, *ccw, *turns,
                )),
            ),
            Motion::Dwell { .. } => return self.wait(dur),
            Motion::ToolChange { tool } => return self.tool_change(*tool),
            _ => return,
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

    /// Coarsens until the scene is within three quarters of its budget
    /// (or nothing more can go).
    fn coarsen(&mut self) {
        let goal_m = self.max_moves * 3 / 4;
        let goal_v = self.max_vertices * 3 / 4;
        let mut drop = false;
        loop {
            let before = (self.moves.len(), self.verts.len());
            self.pass(drop);
            self.detail.passes += 1;
            if self.moves.len() <= goal_m && self.verts.len() <= goal_v {
                return;
            }
            let after = (self.moves.len(), self.verts.len());
            // Merging alone did not get there: leave moves out too.
            if after.0 * 10 > before.0 * 8 || after.1 * 10 > before.1 * 8 {
                if drop && after == before {
                    return;
                }
                drop = true;
            }
        }
    }

    /// One pass: merges pairs of neighbouring moves, thins the points inside
    /// moves and, with `drop`, leaves out every other move that holds no
    /// extreme or violation.
    fn pass(&mut self, drop: bool) {
        let old_moves = std::mem::take(&mut self.moves);
        let old_verts = std::mem::take(&mut self.verts);
        let old_prot = std::mem::take(&mut self.vprot);
        let mut remap: HashMap<u32, u32> = HashMap::new();
        let mut moves: Vec<Mv> = Vec::with_capacity(old_moves.len() / 2 + 1);
        let mut verts: Vec<[f32; 3]> = Vec::with_capacity(old_verts.len() / 2 + 1);
        let mut prot: Vec<u8> = Vec::with_capacity(old_verts.len() / 2 + 1);
        // The old index of the last vertex written, and its new index.
        let mut last: Option<(u32, u32)> = None;
        let mut it = old_moves.into_iter().peekable();
        let mut toggle = false;
        let keeps =
            |m: &Mv, prot: &[u8]| m.viol != 0 || (m.start..=m.end).any(|v| prot[v as usize] > 0);
        while let Some(mut a) = it.next() {
            let merge = it.peek().is_some_and(|b| {
                a.end == b.start
                    && a.kind & K_MASK == b.kind & K_MASK
                    && a.tool == b.tool
                    && a.viol == 0
                    && b.viol == 0
                    && old_prot[a.end as usize] == 0
            });
            if merge && let Some(b) = it.next() {
                a.end = b.end;
                a.kind |= b.kind & (F_ARC | F_UNTIMED);
                a.dur = b.t0 + b.dur - a.t0;
                a.lines = (b.line + b.lines).saturating_sub(a.line);
                a.count += b.count;
            }
            if drop {
                toggle = !toggle;
                if toggle && !keeps(&a, &old_prot) {
                    self.detail.left_out_moves += u64::from(a.count);
                    continue;
                }
            }
            let mut put = |old: u32, verts: &mut Vec<[f32; 3]>, prot: &mut Vec<u8>| {
                let n = verts.len() as u32;
                verts.push(old_verts[old as usize]);
                prot.push(old_prot[old as usize]);
                if old_prot[old as usize] > 0 {
                    remap.insert(old, n);
                }
                n
            };
            let start = match last {
                Some((o, n)) if o == a.start => n,
                _ => put(a.start, &mut verts, &mut prot),
            };
            let keep_all = a.viol != 0;
            for (k, v) in (a.start + 1..a.end).enumerate() {
                if keep_all || k % 2 == 1 || old_prot[v as usize] > 0 {
                    put(v, &mut verts, &mut prot);
                } else {
                    self.detail.left_out_points += 1;
                }
            }
            let end = put(a.end, &mut verts, &mut prot);
            last = Some((a.end, end));
            a.start = start;
            a.end = end;
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
