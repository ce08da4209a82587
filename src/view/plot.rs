//! The toolpath picture: an SVG of the moves in one view, feeds solid and
//! rapids dashed, a colour per tool, arcs as SVG arcs where the view shows
//! them as circles, the work origin, the bounding box with its numbers, a
//! scale bar and the units.
//!
//! Large programs stay small: while the motion streams in, points closer
//! together than a fraction of a pixel (at the drawing's size so far) and
//! runs of points on one straight line within that tolerance are merged;
//! when the picture is written, segments that land on the same pixels as
//! one already drawn in the same style are left out.

use std::collections::{BTreeSet, HashSet};
use std::f64::consts::{FRAC_PI_6, TAU};
use std::fmt::Write as _;

use super::geom::ArcGeom;
use crate::codes::Plane;
use crate::machine::motion::{Axes, Motion, MoveKind};

/// Which way the toolpath is looked at.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(crate) enum View {
    /// From above: X to the right, Y up.
    #[default]
    Xy,
    /// From the front: X to the right, Z up.
    Xz,
    /// From the side: Y to the right, Z up.
    Yz,
    /// Isometric: X to the lower right... X and Y at 30 degrees, Z up.
    Iso,
}

impl View {
    pub(crate) fn name(self) -> &'static str {
        match self {
            View::Xy => "XY (from above)",
            View::Xz => "XZ (from the front)",
            View::Yz => "YZ (from the side)",
            View::Iso => "isometric",
        }
    }

    fn project(self, p: &Axes) -> [f64; 2] {
        match self {
            View::Xy => [p[0], p[1]],
            View::Xz => [p[0], p[2]],
            View::Yz => [p[1], p[2]],
            View::Iso => {
                let (c, s) = (FRAC_PI_6.cos(), FRAC_PI_6.sin());
                [(p[0] - p[1]) * c, (p[0] + p[1]) * s + p[2]]
            }
        }
    }

    /// The axis labels of the horizontal and vertical directions.
    fn axis_names(self) -> Option<(char, char)> {
        match self {
            View::Xy => Some(('X', 'Y')),
            View::Xz => Some(('X', 'Z')),
            View::Yz => Some(('Y', 'Z')),
            View::Iso => None,
        }
    }

    /// For an arc plane seen face-on: whether the view's (horizontal,
    /// vertical) axes are the plane's (first, second) axes in the same
    /// order (true) or swapped (false).
    fn face_on(self, plane: Plane) -> Option<bool> {
        match (self, plane) {
            (View::Xy, Plane::XY) => Some(true),
            (View::Xz, Plane::XZ) => Some(false),
            (View::Yz, Plane::YZ) => Some(true),
            _ => None,
        }
    }
}

/// Drawing style: rapid or not, and the tool's colour index.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
struct Style {
    rapid: bool,
    tool: i64,
}

#[derive(Debug, Clone, Copy)]
enum Seg {
    Line([f64; 2]),
    /// An SVG arc: radius, large-arc flag, sweep flag (in SVG's y-down
    /// frame), end point.
    Arc {
        r: f64,
        large: bool,
        ccw_math: bool,
        to: [f64; 2],
    },
}

#[derive(Debug, Clone)]
struct Path {
    style: Style,
    start: [f64; 2],
    segs: Vec<Seg>,
    /// Points merged away since the last kept point (for the collinearity
    /// test), at most [`MERGE_WINDOW`].
    dropped: Vec<[f64; 2]>,
}

const MERGE_WINDOW: usize = 48;
/// Drawing size in pixels (the longer side of the drawing area).
const AREA: f64 = 900.0;
/// Merge tolerance as a fraction of a pixel.
const TOL_PX: f64 = 0.25;

/// Collects the motion of a program for the picture.
#[derive(Debug, Clone)]
pub(crate) struct Plot {
    view: View,
    paths: Vec<Path>,
    min: [f64; 2],
    max: [f64; 2],
    tool: i64,
    tools: BTreeSet<i64>,
    cursor: Option<[f64; 2]>,
    /// X, Y and Z ranges of the toolpath (work coordinates).
    range: [Option<(f64, f64)>; 3],
    pub moves: u64,
}

impl Plot {
    pub(crate) fn new(view: View) -> Plot {
        Plot {
            view,
            paths: Vec::new(),
            // The work origin is always in the picture.
            min: [0.0; 2],
            max: [0.0; 2],
            tool: 0,
            tools: BTreeSet::new(),
            cursor: None,
            range: [None; 3],
            moves: 0,
        }
    }

    /// World distance below which detail is merged (a quarter pixel at the
    /// extent seen so far).
    fn tol(&self) -> f64 {
        let ext = (self.max[0] - self.min[0]).max(self.max[1] - self.min[1]);
        ext / AREA * TOL_PX
    }

    fn grow3(&mut self, p: &Axes) {
        for (i, r) in self.range.iter_mut().enumerate() {
            let v = p[i];
            if v.is_finite() {
                *r = Some(r.map_or((v, v), |(a, b)| (a.min(v), b.max(v))));
            }
        }
    }

    fn grow(&mut self, p: [f64; 2]) {
        for (i, v) in p.iter().enumerate() {
            self.min[i] = self.min[i].min(*v);
            self.max[i] = self.max[i].max(*v);
        }
    }

    /// Adds one motion event.
    pub(crate) fn add(&mut self, m: &Motion) {
        match m {
            Motion::ToolChange { tool } => self.tool = *tool,
            Motion::Line { kind, from, to, .. } => {
                self.moves += 1;
                let a = self.view.project(&from.work);
                let b = self.view.project(&to.work);
                let style = Style {
                    rapid: *kind == MoveKind::Rapid,
                    tool: self.tool,
                };
                if !finite(a) || !finite(b) {
                    // A move from or to an unknown position is not drawn.
                    self.cursor = None;
                    return;
                }
                self.grow3(&from.work);
                self.grow3(&to.work);
                self.grow(a);
                self.grow(b);
                self.begin(style, a);
                self.line_to(b);
            }
            Motion::Arc {
                from,
                to,
                center,
                plane,
                ccw,
                turns,
                ..
            } => {
                self.moves += 1;
                let style = Style {
                    rapid: false,
                    tool: self.tool,
                };
                let g = ArcGeom::new(
                    &from.work,
                    &to.work,
                    *center,
                    *plane,
                    *ccw,
                    *turns,
                    crate::geom::arc::FullCircle::Exact,
                );
                let a = self.view.project(&from.work);
                let b = self.view.project(&to.work);
                if !finite(a) || !finite(b) {
                    self.cursor = None;
                    return;
                }
                self.grow3(&from.work);
                self.grow3(&to.work);
                self.grow(a);
                self.grow(b);
                // The extreme points: for a face-on view they are exact, for
                // the others the sampled points below grow the box.
                for t in g.quadrant_crossings() {
                    let p = super::geom::arc_point(&g, &from.work, &to.work, t);
                    let q = self.view.project(&p);
                    self.grow3(&p);
                    self.grow(q);
                }
                self.begin(style, a);
                let circle = (g.r0 - g.r1).abs() <= 1e-9 * g.r0.max(1.0);
                match self.view.face_on(*plane) {
                    Some(same_order) if circle && g.r0 > 0.0 => {
                        let tol = self.tol();
                        if g.r0 < tol {
                            self.line_to(b);
                            return;
                        }
                        let ccw_view = (g.sweep > 0.0) == same_order;
                        let sweep = g.sweep.abs().min(TAU);
                        if sweep >= TAU - 1e-9 {
                            // A full circle (or more): two halves, then the
                            // part of a turn that is left.
                            let t = std::f64::consts::PI / g.sweep.abs();
                            let h = super::geom::arc_point(&g, &from.work, &to.work, t);
                            let mid = self.view.project(&h);
                            self.arc_to(g.r0, false, ccw_view, mid);
                            self.arc_to(g.r0, false, ccw_view, a);
                            let rem = g.sweep.abs() % TAU;
                            if rem > 1e-9 && dist(a, b) > 0.0 {
                                self.arc_to(g.r0, rem > std::f64::consts::PI, ccw_view, b);
                            }
                        } else {
                            self.arc_to(g.r0, sweep > std::f64::consts::PI, ccw_view, b);
                        }
                    }
                    _ => {
                        // Sampled: chord error within the tolerance.
                        let r = g.r0.max(g.r1);
                        let tol = self.tol().max(r * 1e-6);
                        let step = if r > tol {
                            2.0 * (1.0 - tol / r).clamp(-1.0, 1.0).acos()
                        } else {
                            TAU
                        };
                        let n = ((g.sweep.abs() / step.max(1e-3)).ceil() as usize).clamp(1, 20_000);
                        for k in 1..=n {
                            let t = k as f64 / n as f64;
                            let p = super::geom::arc_point(&g, &from.work, &to.work, t);
                            let q = self.view.project(&p);
                            self.grow(q);
                            self.line_to(q);
                        }
                    }
                }
                self.cursor = Some(b);
            }
            _ => {}
        }
    }

    /// Starts a new path unless the current one has this style and ends at `a`.
    fn begin(&mut self, style: Style, a: [f64; 2]) {
        self.tools.insert(style.tool);
        let continues =
            self.cursor == Some(a) && self.paths.last().is_some_and(|p| p.style == style);
        if !continues {
            self.paths.push(Path {
                style,
                start: a,
                segs: Vec::new(),
                dropped: Vec::new(),
            });
        }
        self.cursor = Some(a);
    }

    fn arc_to(&mut self, r: f64, large: bool, ccw_math: bool, to: [f64; 2]) {
        if let Some(p) = self.paths.last_mut() {
            p.segs.push(Seg::Arc {
                r,
                large,
                ccw_math,
                to,
            });
            p.dropped.clear();
        }
        self.cursor = Some(to);
    }

    fn line_to(&mut self, q: [f64; 2]) {
        let tol = self.tol();
        self.cursor = Some(q);
        let Some(p) = self.paths.last_mut() else {
            return;
        };
        let last = match p.segs.last() {
            Some(Seg::Line(l)) => Some(*l),
            Some(Seg::Arc { .. }) => None,
            None => None,
        };
        let prev_end = match p.segs.len() {
            0 => p.start,
            n => match p.segs[n - 1] {
                Seg::Line(l) | Seg::Arc { to: l, .. } => l,
            },
        };
        if let Some(l) = last {
            // A sub-pixel step may turn back; a longer one must go on forward.
            let sub_pixel = dist(prev_end, q) <= tol;
            let anchor = anchor_of(p);
            if p.dropped.len() < MERGE_WINDOW
                && (sub_pixel || forward(anchor, l, q))
                && p.dropped
                    .iter()
                    .chain([&l])
                    .all(|d| seg_dist(*d, anchor, q) <= tol)
            {
                // Replace the end point only if that keeps the shape.
                p.dropped.push(l);
                if let Some(Seg::Line(e)) = p.segs.last_mut() {
                    *e = q;
                }
                Self::compress_window(p);
                return;
            }
        }
        p.dropped.clear();
        p.segs.push(Seg::Line(q));
    }

    /// Keeps the merge window bounded: when full, only the points farthest
    /// to either side of the current direction stay (the ones that decide
    /// whether the next merge keeps the shape).
    fn compress_window(p: &mut Path) {
        if p.dropped.len() < MERGE_WINDOW {
            return;
        }
        let anchor = anchor_of(p);
        let Some(Seg::Line(last)) = p.segs.last().copied() else {
            p.dropped.clear();
            return;
        };
        let (dx, dy) = (last[0] - anchor[0], last[1] - anchor[1]);
        let side = |q: &[f64; 2]| (q[0] - anchor[0]) * dy - (q[1] - anchor[1]) * dx;
        let mut lo = p.dropped[0];
        let mut hi = p.dropped[0];
        for q in &p.dropped {
            if side(q) < side(&lo) {
                lo = *q;
            }
            if side(q) > side(&hi) {
                hi = *q;
            }
        }
        p.dropped.clear();
        p.dropped.push(lo);
        p.dropped.push(hi);
    }

    /// The SVG document. `caption` is printed under the drawing (program
    /// name), `note` lines after it.
    /// The SVG path data of the toolpath, one string per style; a segment
    /// drawn already (either way for a line) is left out.
    fn path_data(&self, tx: &impl Fn([f64; 2]) -> (f64, f64), scale: f64) -> Vec<(Style, String)> {
        let mut seen: HashSet<(Style, [i64; 4])> = HashSet::new();
        let mut by_style: Vec<(Style, String)> = Vec::new();
        for p in &self.paths {
            let d = match by_style.iter_mut().find(|(st, _)| *st == p.style) {
                Some((_, d)) => d,
                None => {
                    by_style.push((p.style, String::new()));
                    &mut by_style.last_mut().expect("just pushed").1
                }
            };
            let mut pen = tx(p.start);
            let mut pen_down_at: Option<(f64, f64)> = None;
            for seg in &p.segs {
                let end = match seg {
                    Seg::Line(q) | Seg::Arc { to: q, .. } => tx(*q),
                };
                let key = {
                    let (a, b) = (key(pen), key(end));
                    // A line is the same either way; an arc is not.
                    let (a, b) = if a <= b || !matches!(seg, Seg::Line(_)) {
                        (a, b)
                    } else {
                        (b, a)
                    };
                    let tag = match seg {
                        Seg::Line(_) => 0,
                        Seg::Arc {
                            r, large, ccw_math, ..
                        } => {
                            1 + ((r * scale * 10.0).round() as i64) * 4
                                + i64::from(*large) * 2
                                + i64::from(*ccw_math)
                        }
                    };
                    (p.style, [a.0 ^ (tag << 32), a.1, b.0, b.1])
                };
                if pen == end && matches!(seg, Seg::Line(_)) {
                    continue;
                }
                if !seen.insert(key) {
                    pen = end;
                    pen_down_at = None;
                    continue;
                }
                if pen_down_at != Some(pen) {
                    let _ = write!(d, "M{} {}", pen.0, pen.1);
                }
                match seg {
                    Seg::Line(_) => {
                        let _ = write!(d, "L{} {}", end.0, end.1);
                    }
                    Seg::Arc {
                        r, large, ccw_math, ..
                    } => {
                        // Math counter-clockwise is SVG's negative sweep
                        // (y points down).
                        let _ = write!(
                            d,
                            "A{r} {r} 0 {} {} {} {}",
                            u8::from(*large),
                            u8::from(!*ccw_math),
                            end.0,
                            end.1,
                            r = q10(r * scale).max(0.1),
                        );
                    }
                }
                pen = end;
                pen_down_at = Some(end);
            }
        }
        by_style
    }

    pub(crate) fn svg(&self, caption: &str) -> String {
        let view = self.view;
        let (w0, h0) = (self.max[0] - self.min[0], self.max[1] - self.min[1]);
        let ext = w0.max(h0);
        let scale = if ext > 0.0 { AREA / ext } else { 1.0 };
        let margin_l = 70.0;
        let margin_t = 40.0;
        let legend_h = 70.0;
        let dw = (w0 * scale).max(1.0);
        let dh = (h0 * scale).max(1.0);
        let width = (dw + margin_l + 70.0).max(420.0).ceil();
        let height = (dh + margin_t + 40.0 + legend_h).ceil();
        let tx = |p: [f64; 2]| -> (f64, f64) {
            (
                q10(margin_l + (p[0] - self.min[0]) * scale),
                q10(margin_t + (self.max[1] - p[1]) * scale),
            )
        };
        let mut s = String::with_capacity(1 << 16);
        let _ = write!(
            s,
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{width}\" height=\"{height}\" viewBox=\"0 0 {width} {height}\" font-family=\"sans-serif\" font-size=\"12\">\n\
             <rect width=\"100%\" height=\"100%\" fill=\"#ffffff\"/>\n"
        );
        // Bounding box.
        let (bx0, by0) = tx([self.min[0], self.max[1]]);
        let (bx1, by1) = tx([self.max[0], self.min[1]]);
        let _ = writeln!(
            s,
            "<rect x=\"{bx0}\" y=\"{by0}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"#b0b0b0\" stroke-width=\"0.8\" stroke-dasharray=\"2 3\"/>",
            q10(bx1 - bx0),
            q10(by1 - by0)
        );
        if let Some((hn, vn)) = view.axis_names() {
            let _ = writeln!(
                s,
                "<text x=\"{bx0}\" y=\"{}\" fill=\"#555\">{hn} {}</text>\n<text x=\"{bx1}\" y=\"{}\" fill=\"#555\" text-anchor=\"end\">{hn} {}</text>\n\
                 <text x=\"{}\" y=\"{by1}\" fill=\"#555\" text-anchor=\"end\">{vn} {}</text>\n<text x=\"{}\" y=\"{}\" fill=\"#555\" text-anchor=\"end\">{vn} {}</text>",
                q10(by1 + 16.0),
                fmt_mm(self.min[0]),
                q10(by1 + 16.0),
                fmt_mm(self.max[0]),
                q10(bx0 - 6.0),
                fmt_mm(self.min[1]),
                q10(bx0 - 6.0),
                q10(by0 + 10.0),
                fmt_mm(self.max[1]),
            );
        }
        // Toolpath.
        let _ = writeln!(
            s,
            "<g fill=\"none\" stroke-width=\"1\" stroke-linecap=\"round\" stroke-linejoin=\"round\">"
        );
        let mut by_style = self.path_data(&tx, scale);
        by_style.sort_by_key(|(st, _)| (st.rapid, st.tool));
        let tools: Vec<i64> = self.tools.iter().copied().collect();
        let colour =
            |tool: i64| PALETTE[tools.iter().position(|&t| t == tool).unwrap_or(0) % PALETTE.len()];
        for (st, d) in by_style.iter().rev() {
            if d.is_empty() {
                continue;
            }
            if st.rapid {
                let _ = writeln!(
                    s,
                    "<path stroke=\"{}\" stroke-opacity=\"0.7\" stroke-dasharray=\"4 3\" d=\"{d}\"/>",
                    colour(st.tool)
                );
            } else {
                let _ = writeln!(s, "<path stroke=\"{}\" d=\"{d}\"/>", colour(st.tool));
            }
        }
        let _ = writeln!(s, "</g>");
        // Work origin.
        work_origin(&mut s, tx([0.0, 0.0]));
        // Scale bar and units.
        let bar = nice_length(ext.max(1e-9) / 5.0);
        let bar_px = q10(bar * scale);
        let ly = q10(margin_t + dh + 40.0);
        let _ = writeln!(
            s,
            "<g stroke=\"#000\" stroke-width=\"1.5\"><line x1=\"{margin_l}\" y1=\"{ly}\" x2=\"{}\" y2=\"{ly}\"/><line x1=\"{margin_l}\" y1=\"{}\" x2=\"{margin_l}\" y2=\"{}\"/><line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\"/></g>\n<text x=\"{}\" y=\"{}\">{} mm</text>",
            q10(margin_l + bar_px),
            q10(ly - 4.0),
            q10(ly + 4.0),
            q10(margin_l + bar_px),
            q10(ly - 4.0),
            q10(margin_l + bar_px),
            q10(ly + 4.0),
            q10(margin_l + bar_px + 8.0),
            q10(ly + 4.0),
            fmt_mm(bar),
        );
        // Legend.
        let ly2 = q10(ly + 24.0);
        legend(&mut s, &tools, &colour, margin_l, ly2);
        let ranges: Vec<String> = ["X", "Y", "Z"]
            .iter()
            .zip(self.range)
            .filter_map(|(n, r)| r.map(|(a, b)| format!("{n} {} to {}", fmt_mm(a), fmt_mm(b))))
            .collect();
        let _ = writeln!(
            s,
            "<text x=\"{}\" y=\"{}\" fill=\"#555\">bounding box (work coordinates, mm): {}</text>",
            margin_l,
            q10(ly2 + 26.0),
            ranges.join(", ")
        );
        let _ = writeln!(
            s,
            "<text x=\"10\" y=\"20\">{} — view {}, mm, {} moves</text>",
            xml_escape(caption),
            view.name(),
            self.moves
        );
        s.push_str("</svg>\n");
        s
    }
}

const PALETTE: [&str; 8] = [
    "#1f5fbf", "#d9480f", "#2b8a3e", "#862e9c", "#c92a2a", "#0b7285", "#e67700", "#495057",
];

fn finite(p: [f64; 2]) -> bool {
    p[0].is_finite() && p[1].is_finite()
}

fn q10(v: f64) -> f64 {
    let r = (v * 10.0).round() / 10.0;
    if r == 0.0 { 0.0 } else { r }
}

fn key(p: (f64, f64)) -> (i64, i64) {
    ((p.0 * 10.0).round() as i64, (p.1 * 10.0).round() as i64)
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// Distance from `p` to the segment `a`–`b`.
fn seg_dist(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let l2 = dx * dx + dy * dy;
    if l2 == 0.0 {
        return dist(p, a);
    }
    let t = (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2).clamp(0.0, 1.0);
    dist(p, [a[0] + t * dx, a[1] + t * dy])
}

/// Whether `q` continues in the direction from `a` to `b` (no reversal).
fn forward(a: [f64; 2], b: [f64; 2], q: [f64; 2]) -> bool {
    (b[0] - a[0]) * (q[0] - b[0]) + (b[1] - a[1]) * (q[1] - b[1]) >= 0.0
}

/// The kept point before the path's last one.
fn anchor_of(p: &Path) -> [f64; 2] {
    match p.segs.len() {
        0 | 1 => p.start,
        n => match p.segs[n - 2] {
            Seg::Line(l) | Seg::Arc { to: l, .. } => l,
        },
    }
}

/// 1, 2 or 5 times a power of ten, at most `v`.
fn nice_length(v: f64) -> f64 {
    let e = 10f64.powf(v.log10().floor());
    let m = v / e;
    let k = if m >= 5.0 {
        5.0
    } else if m >= 2.0 {
        2.0
    } else {
        1.0
    };
    k * e
}

fn fmt_mm(v: f64) -> String {
    crate::emit::number_string(v, Some(3))
}

pub(crate) fn xml_escape(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '&' => o.push_str("&amp;"),
            '"' => o.push_str("&quot;"),
            c if (c as u32) < 0x20 => o.push(' '),
            c => o.push(c),
        }
    }
    o
}

/// The work origin: a red cross in a circle, named.
fn work_origin(s: &mut String, (ox, oy): (f64, f64)) {
    let _ = writeln!(
        s,
        "<g stroke=\"#d00000\" stroke-width=\"1.2\"><line x1=\"{}\" y1=\"{oy}\" x2=\"{}\" y2=\"{oy}\"/><line x1=\"{ox}\" y1=\"{}\" x2=\"{ox}\" y2=\"{}\"/><circle cx=\"{ox}\" cy=\"{oy}\" r=\"4\" fill=\"none\"/></g>\n<text x=\"{}\" y=\"{}\" fill=\"#d00000\">work 0</text>",
        q10(ox - 9.0),
        q10(ox + 9.0),
        q10(oy - 9.0),
        q10(oy + 9.0),
        q10(ox + 6.0),
        q10(oy - 6.0),
    );
}
/// The legend: a line per tool in its colour, then feed and rapid.
fn legend(s: &mut String, tools: &[i64], colour: &impl Fn(i64) -> &'static str, x: f64, ly2: f64) {
    let mut lx = x;
    for t in tools {
        let c = colour(*t);
        let name = if *t == 0 {
            "no tool".to_string()
        } else {
            format!("T{t}")
        };
        let _ = writeln!(
            s,
            "<line x1=\"{lx}\" y1=\"{ly2}\" x2=\"{}\" y2=\"{ly2}\" stroke=\"{c}\" stroke-width=\"2\"/><text x=\"{}\" y=\"{}\">{name}</text>",
            q10(lx + 20.0),
            q10(lx + 24.0),
            q10(ly2 + 4.0)
        );
        lx += 80.0;
    }
    let _ = writeln!(
        s,
        "<line x1=\"{lx}\" y1=\"{ly2}\" x2=\"{}\" y2=\"{ly2}\" stroke=\"#444\"/><text x=\"{}\" y=\"{}\">feed</text><line x1=\"{}\" y1=\"{ly2}\" x2=\"{}\" y2=\"{ly2}\" stroke=\"#444\" stroke-dasharray=\"4 3\"/><text x=\"{}\" y=\"{}\">rapid</text>",
        q10(lx + 20.0),
        q10(lx + 24.0),
        q10(ly2 + 4.0),
        q10(lx + 70.0),
        q10(lx + 90.0),
        q10(lx + 94.0),
        q10(ly2 + 4.0),
    );
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
    const F: Feed = Feed {
        rate: 300.0,
        mode: FeedMode::PerMinute,
    };

    fn line(kind: MoveKind, a: (f64, f64, f64), b: (f64, f64, f64)) -> Motion {
        Motion::Line {
            kind,
            from: pt(a.0, a.1, a.2),
            to: pt(b.0, b.1, b.2),
            feed: F,
        }
    }

    /// A small part: a rapid in, a square with rounded corners (tool 1),
    /// a tool change and a helix (tool 2).
    pub(crate) fn sample() -> Vec<Motion> {
        let mut v = vec![
            Motion::ToolChange { tool: 1 },
            line(MoveKind::Rapid, (0.0, 0.0, 0.0), (10.0, 0.0, 5.0)),
            line(MoveKind::Feed, (10.0, 0.0, 5.0), (10.0, 0.0, -1.0)),
            line(MoveKind::Feed, (10.0, 0.0, -1.0), (40.0, 0.0, -1.0)),
        ];
        v.push(Motion::Arc {
            from: pt(40.0, 0.0, -1.0),
            to: pt(50.0, 10.0, -1.0),
            center: [40.0, 10.0],
            plane: Plane::XY,
            ccw: true,
            turns: 1,
            feed: F,
        });
        v.push(line(MoveKind::Feed, (50.0, 10.0, -1.0), (50.0, 30.0, -1.0)));
        v.push(Motion::ToolChange { tool: 2 });
        v.push(line(MoveKind::Rapid, (50.0, 30.0, -1.0), (25.0, 15.0, 5.0)));
        v.push(Motion::Arc {
            from: pt(25.0, 15.0, 5.0),
            to: pt(25.0, 15.0, -3.0),
            center: [25.0, 20.0],
            plane: Plane::XY,
            ccw: false,
            turns: 2,
            feed: F,
        });
        v
    }

    fn svg_of(ms: &[Motion], view: View) -> String {
        let mut p = Plot::new(view);
        for m in ms {
            p.add(m);
        }
        p.svg("sample")
    }

    #[test]
    fn styles_arcs_and_marks() {
        let s = svg_of(&sample(), View::Xy);
        // Two tools, two colours; rapids dashed.
        assert!(s.contains(PALETTE[0]) && s.contains(PALETTE[1]), "{s}");
        assert!(s.contains("stroke-dasharray=\"4 3\" d=\"M"));
        // The corner is an SVG arc; the two-turn helix is a full circle in
        // two halves.
        assert!(s.matches('A').count() >= 3, "{s}");
        assert!(s.contains("work 0"));
        assert!(s.contains("X 50") && s.contains("Y 30"), "{s}");
        assert!(s.contains(" mm</text>"));
        // Seen from the front the arcs are polylines, no SVG arcs.
        let f = svg_of(&sample(), View::Xz);
        let paths: String = f.lines().filter(|l| l.starts_with("<path")).collect();
        assert!(!paths.contains('A'), "{paths}");
        let _ = std::fs::write(std::env::temp_dir().join("ngcflat-plot-sample.svg"), &s);
    }

    #[test]
    fn dense_collinear_and_repeated_moves_merge() {
        // 100 passes of 1000 tiny collinear steps on the same line: one
        // segment survives per direction.
        let mut ms = Vec::new();
        for pass in 0..100 {
            for i in 0..1000 {
                let (a, b) = if pass % 2 == 0 {
                    (i as f64 * 0.01, (i + 1) as f64 * 0.01)
                } else {
                    (10.0 - i as f64 * 0.01, 10.0 - (i + 1) as f64 * 0.01)
                };
                ms.push(line(MoveKind::Feed, (a, 0.0, 0.0), (b, 0.0, 0.0)));
            }
        }
        let s = svg_of(&ms, View::Xy);
        let path = s.lines().find(|l| l.starts_with("<path")).expect("a path");
        assert!(path.len() < 200, "{path}");
    }
}
