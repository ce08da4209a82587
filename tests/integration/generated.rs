//! Generated-program differential testing against rs274.
//!
//! A seeded generator writes valid, terminating LinuxCNC programs that mix
//! every expression operator and function, numbered / indirect / named
//! parameters, parallel assignments, nested control flow, subroutines (in
//! the main file before the main program and after `M2`, in files on a
//! search path, Fanuc-style `M98`/`M99`), recursion, return values,
//! `(debug,…)` messages and motion. Each program is run through rs274, then
//! flattened by ngcflat, and the flattened output is run through rs274 with
//! an INI that has no subroutine path; the two canons must agree. Programs
//! rs274 rejects must be rejected by ngcflat too. A mismatch is shrunk
//! (statements, branches, words dropped while the same kind of mismatch
//! persists) and reported with its seed.
//!
//! `NGCFLAT_DIFF_CASES=N` sets the number of programs (default 300),
//! `NGCFLAT_DIFF_SEED=S` the first seed. The generator avoids the rs274
//! quirks ngcflat deliberately does not reproduce (docs/deviations.md):
//! stale break/continue flags are cleared by empty loops that behave the
//! same under both semantics, `return` and recursion never happen inside a
//! `repeat` body, `elseif`/do-loop conditions never fail, `M98 … L0` is
//! never written.

use std::path::Path;

use crate::oracle;
use crate::rng::Rng;

/// Bound on the magnitude of every value stored in a parameter.
const B: f64 = 1000.0;
/// Values above this are wrapped back into [-B, B] before further use.
const CAP: f64 = 1e12;

// ---------------------------------------------------------------- PRNG

// ---------------------------------------------------------------- program model

#[derive(Clone, Debug)]
enum Stmt {
    /// One non-O line made of items (words, assignments, a comment).
    Line(Vec<String>),
    /// Physical lines that only make sense together.
    Raw(Vec<String>),
    /// One O-line (call, return, break, continue, M98, M99).
    OLine(String),
    If {
        label: String,
        arms: Vec<(String, Vec<Stmt>)>,
        els: Option<Vec<Stmt>>,
    },
    Loop {
        kind: LoopKind,
        label: String,
        /// Lines before the loop (counter initialisation).
        pre: Vec<String>,
        /// First lines of the body (flag clearing, counter increment).
        head: Vec<String>,
        /// while/do condition or repeat count (without brackets).
        cond: String,
        body: Vec<Stmt>,
        /// Lines after the loop (flag clearing).
        post: Vec<String>,
    },
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum LoopKind {
    While,
    Do,
    Repeat,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum SubKind {
    /// Defined in the main file before the main program.
    Pre,
    /// Bare `O<n>` … `M99` after the program end, called with M98.
    Fanuc,
    /// Defined in the main file after the program end.
    Post,
    /// In its own file on the subroutine path.
    File,
}

#[derive(Clone, Debug)]
struct SubDef {
    kind: SubKind,
    /// Label text: `<name>` or a number.
    name: String,
    /// Name as written at call sites (case may differ).
    call_name: String,
    body: Vec<Stmt>,
    end_value: Option<String>,
    /// File text before the `sub` line and after `endsub` (File only).
    file_pre: Vec<String>,
    file_post: Vec<String>,
}

#[derive(Clone, Debug)]
struct Program {
    /// Main-program lines that run before the subs defined first in the file.
    init: Vec<Stmt>,
    percent: bool,
    title: bool,
    main: Vec<Stmt>,
    end: String,
    subs: Vec<SubDef>,
}

impl SubDef {
    fn file_name(&self) -> String {
        format!("{}.ngc", self.name.trim_matches(['<', '>']).to_lowercase())
    }
}

fn render_body(body: &[Stmt], out: &mut Vec<String>) {
    for s in body {
        match s {
            Stmt::Line(items) => {
                if !items.is_empty() {
                    out.push(items.join(" "))
                }
            }
            Stmt::Raw(lines) => out.extend(lines.iter().cloned()),
            Stmt::OLine(l) => out.push(l.clone()),
            Stmt::If { label, arms, els } => {
                for (i, (cond, b)) in arms.iter().enumerate() {
                    let kw = if i == 0 { "if" } else { "elseif" };
                    out.push(format!("o{label} {kw} [{cond}]"));
                    render_body(b, out);
                }
                if let Some(b) = els {
                    out.push(format!("o{label} else"));
                    render_body(b, out);
                }
                out.push(format!("o{label} endif"));
            }
            Stmt::Loop {
                kind,
                label,
                pre,
                head,
                cond,
                body,
                post,
            } => {
                out.extend(pre.iter().cloned());
                match kind {
                    LoopKind::While => out.push(format!("o{label} while [{cond}]")),
                    LoopKind::Do => out.push(format!("o{label} do")),
                    LoopKind::Repeat => out.push(format!("o{label} repeat [{cond}]")),
                }
                out.extend(head.iter().cloned());
                render_body(body, out);
                match kind {
                    LoopKind::While => out.push(format!("o{label} endwhile")),
                    LoopKind::Do => out.push(format!("o{label} while [{cond}]")),
                    LoopKind::Repeat => out.push(format!("o{label} endrepeat")),
                }
                out.extend(post.iter().cloned());
            }
        }
    }
}

/// Whether every rendered line stays below rs274's 252-character limit.
fn fits(body: &[Stmt]) -> bool {
    let mut out = Vec::new();
    render_body(body, &mut out);
    out.iter().all(|l| l.len() <= 240)
}

fn render_sub(s: &SubDef, out: &mut Vec<String>) {
    if s.kind == SubKind::Fanuc {
        out.push(format!("O{}", s.name));
        render_body(&s.body, out);
        out.push("M99".into());
        return;
    }
    out.push(format!("o{} sub", s.name));
    render_body(&s.body, out);
    match &s.end_value {
        Some(v) => out.push(format!("o{} endsub [{v}]", s.name)),
        None => out.push(format!("o{} endsub", s.name)),
    }
}

impl Program {
    fn main_text(&self) -> String {
        let mut out = Vec::new();
        if self.percent {
            out.push("%".to_string());
        }
        if self.title {
            out.push("O9000 (generated program)".to_string());
        }
        render_body(&self.init, &mut out);
        for s in self.subs.iter().filter(|s| s.kind == SubKind::Pre) {
            render_sub(s, &mut out);
        }
        render_body(&self.main, &mut out);
        out.push(self.end.clone());
        for k in [SubKind::Fanuc, SubKind::Post] {
            for s in self.subs.iter().filter(|s| s.kind == k) {
                render_sub(s, &mut out);
            }
        }
        if self.percent && self.end != "%" {
            out.push("%".to_string());
        }
        let mut t = out.join("\n");
        t.push('\n');
        t
    }

    fn files(&self) -> Vec<(String, String)> {
        self.subs
            .iter()
            .filter(|s| s.kind == SubKind::File)
            .map(|s| {
                let mut out = s.file_pre.clone();
                render_sub(s, &mut out);
                out.extend(s.file_post.iter().cloned());
                let mut t = out.join("\n");
                t.push('\n');
                (s.file_name(), t)
            })
            .collect()
    }

    fn full_text(&self) -> String {
        let mut t = format!("---- main program\n{}", self.main_text());
        for (name, text) in self.files() {
            t.push_str(&format!(
                "---- file {name} (on the subroutine path)\n{text}"
            ));
        }
        t
    }
}

// ---------------------------------------------------------------- expressions

#[derive(Clone, Debug)]
struct Ex {
    s: String,
    lo: f64,
    hi: f64,
}

fn ex(s: impl Into<String>, lo: f64, hi: f64) -> Ex {
    Ex {
        s: s.into(),
        lo,
        hi,
    }
}

impl Ex {
    fn mag(&self) -> f64 {
        self.lo.abs().max(self.hi.abs())
    }
    fn has_zero(&self) -> bool {
        self.lo <= 0.0 && self.hi >= 0.0
    }
    fn min_abs(&self) -> f64 {
        if self.has_zero() {
            0.0
        } else {
            self.lo.abs().min(self.hi.abs())
        }
    }
}

/// Wraps a value into [-B, B] (identity for values already there).
fn tame(e: Ex) -> Ex {
    if e.mag() <= B && e.lo.is_finite() && e.hi.is_finite() {
        e
    } else {
        ex(format!("[[{} + 1000] MOD 2000 - 1000]", e.s), -B, B)
    }
}

fn cap(e: Ex) -> Ex {
    if e.mag() <= CAP && e.lo.is_finite() && e.hi.is_finite() {
        e
    } else {
        tame(e)
    }
}

#[derive(Clone, Copy, PartialEq)]
enum Op {
    Mul,
    Div,
    Mod,
    Add,
    Sub,
    Eq,
    Ne,
    Gt,
    Ge,
    Lt,
    Le,
    And,
    Or,
    Xor,
}

const OPS: [Op; 14] = [
    Op::Mul,
    Op::Div,
    Op::Mod,
    Op::Add,
    Op::Sub,
    Op::Eq,
    Op::Ne,
    Op::Gt,
    Op::Ge,
    Op::Lt,
    Op::Le,
    Op::And,
    Op::Or,
    Op::Xor,
];

impl Op {
    fn text(self) -> &'static str {
        match self {
            Op::Mul => "*",
            Op::Div => "/",
            Op::Mod => "MOD",
            Op::Add => "+",
            Op::Sub => "-",
            Op::Eq => "EQ",
            Op::Ne => "NE",
            Op::Gt => "GT",
            Op::Ge => "GE",
            Op::Lt => "LT",
            Op::Le => "LE",
            Op::And => "AND",
            Op::Or => "OR",
            Op::Xor => "XOR",
        }
    }
    fn prec(self) -> u8 {
        match self {
            Op::Mul | Op::Div | Op::Mod => 5,
            Op::Add | Op::Sub => 4,
            Op::Eq | Op::Ne | Op::Gt | Op::Ge | Op::Lt | Op::Le => 3,
            Op::And | Op::Or | Op::Xor => 2,
        }
    }
    fn apply(self, a: (f64, f64), b: (f64, f64)) -> (f64, f64) {
        let mm = |xs: [f64; 4]| {
            (
                xs.iter().cloned().fold(f64::INFINITY, f64::min),
                xs.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
            )
        };
        match self {
            Op::Add => (a.0 + b.0, a.1 + b.1),
            Op::Sub => (a.0 - b.1, a.1 - b.0),
            Op::Mul => mm([a.0 * b.0, a.0 * b.1, a.1 * b.0, a.1 * b.1]),
            Op::Div => {
                let (r0, r1) = (1.0 / b.0, 1.0 / b.1);
                mm([a.0 * r0, a.0 * r1, a.1 * r0, a.1 * r1])
            }
            Op::Mod => (0.0, b.0.abs().max(b.1.abs())),
            _ => (0.0, 1.0),
        }
    }
}

/// Interval of a flat operator chain evaluated with rs274's precedence
/// (all binary operators left-associative).
fn chain_interval(vals: &[Ex], ops: &[Op]) -> (f64, f64) {
    let mut vs: Vec<(f64, f64)> = vec![(vals[0].lo, vals[0].hi)];
    let mut os: Vec<Op> = Vec::new();
    for (op, v) in ops.iter().zip(&vals[1..]) {
        while let Some(&top) = os.last() {
            if top.prec() >= op.prec() {
                let b = vs.pop().unwrap();
                let a = vs.pop().unwrap();
                vs.push(top.apply(a, b));
                os.pop();
            } else {
                break;
            }
        }
        os.push(*op);
        vs.push((v.lo, v.hi));
    }
    while let Some(top) = os.pop() {
        let b = vs.pop().unwrap();
        let a = vs.pop().unwrap();
        vs.push(top.apply(a, b));
    }
    vs[0]
}

const LITERALS: &[f64] = &[
    0.0, 1.0, -1.0, 2.0, -2.0, 3.0, 0.5, -0.5, 1.5, -1.5, 2.5, -2.5, 3.5, 0.4999, 1.00005, 1.0002,
    0.99995, 1.0001, 0.0001, 0.00005, 90.0, 45.0, 30.0, 180.0, -90.0, 360.0, 7.0, -7.0, 0.1, 0.3,
    10.0, 100.0, 12.75, -3.25, 1000.0, 0.000001, 0.0000004, 4.5, -4.5, 60.0,
];

/// Generation context of one body (main program or one subroutine).
#[derive(Clone)]
struct Ctx {
    /// Readable numbered parameters (always hold values in [-B, B]).
    numbered: Vec<u32>,
    /// Writable numbered parameters.
    writable: Vec<u32>,
    /// Readable named parameters (initialised at the top of the scope).
    named: Vec<String>,
    loops: Vec<LoopFrame>,
    in_repeat: bool,
    depth: usize,
    next_label: u32,
    /// Subs callable with `o… call` (indices into Gen::subs).
    callees: Vec<usize>,
    /// Fanuc subs callable with M98 (indices).
    fanuc: Vec<usize>,
    /// This sub's index, name and kind when generating a sub body.
    me: Option<(usize, SubKind)>,
    /// Loops have no more than this many iterations.
    counter: u32,
}

#[derive(Clone)]
struct LoopFrame {
    label: String,
    kind: LoopKind,
    has_break: bool,
    has_cont: bool,
}

struct Gen {
    rng: Rng,
    subs: Vec<Option<SubDef>>,
    kinds: Vec<SubKind>,
    levels: Vec<usize>,
    cost: Vec<f64>,
    rec: Vec<usize>,
    nargs: Vec<usize>,
    msg: u32,
}

impl Gen {
    fn kw(&mut self, s: &str) -> String {
        match self.rng.below(10) {
            0 => s.to_uppercase(),
            1 => {
                let mut c = s.chars();
                match c.next() {
                    Some(f) => f.to_uppercase().collect::<String>() + c.as_str(),
                    None => String::new(),
                }
            }
            _ => s.to_lowercase(),
        }
    }

    fn op_text(&mut self, op: Op) -> String {
        let t = op.text();
        if t.chars().all(|c| c.is_ascii_alphabetic()) {
            format!(" {} ", self.kw(t))
        } else if self.rng.chance(0.5) {
            format!(" {t} ")
        } else {
            t.to_string()
        }
    }

    fn literal_text(&mut self, v: f64) -> String {
        let base = format!("{v}");
        let frac = v.fract() != 0.0;
        match self.rng.below(8) {
            0 if !frac => format!("{base}."),
            1 if !frac => format!("{base}.000"),
            2 if frac && v.abs() < 1.0 => base.replacen("0.", ".", 1),
            3 if v > 0.0 => format!("+{base}"),
            4 if v == 0.0 => "0.0".into(),
            _ => base,
        }
    }

    fn literal(&mut self) -> Ex {
        let v = *self.rng.pick(LITERALS);
        let s = self.literal_text(v);
        ex(s, v, v)
    }

    fn named_text(&mut self, name: &str) -> String {
        if self.rng.chance(0.15) {
            format!("#<{}>", name.to_uppercase())
        } else {
            format!("#<{name}>")
        }
    }

    fn param(&mut self, c: &Ctx) -> Ex {
        let r = self.rng.below(100);
        if r < 45 && !c.numbered.is_empty() {
            let n = *self.rng.pick(&c.numbered);
            let s = match self.rng.below(20) {
                0 => format!("#{n}.00003"),
                1 => format!("#[{}]", n as f64 - 0.00004),
                _ => format!("#{n}"),
            };
            ex(s, -B, B)
        } else if r < 90 && !c.named.is_empty() {
            let n = self.rng.pick(&c.named).clone();
            ex(self.named_text(&n), -B, B)
        } else {
            ex("#<_value>", -B, B)
        }
    }

    fn nonzero(&mut self, c: &Ctx, d: usize) -> Ex {
        if self.rng.chance(0.3) {
            let v = *self.rng.pick(&[2.0, -3.0, 0.5, 7.0, -0.25, 1.5, 360.0]);
            let s = self.literal_text(v);
            return ex(s, v, v);
        }
        let v = self.value(c, d);
        if v.has_zero() {
            let k = *self.rng.pick(&[1.0, 0.5, 2.0]);
            ex(format!("[ABS[{}] + {k}]", v.s), k, v.mag() + k)
        } else {
            v
        }
    }

    /// A value (literal, parameter, function, bracketed expression).
    fn value(&mut self, c: &Ctx, d: usize) -> Ex {
        let r = self.rng.below(100);
        let e = if d == 0 || r < 30 {
            if self.rng.chance(0.4) {
                self.literal()
            } else {
                self.param(c)
            }
        } else if r < 52 {
            self.func(c, d)
        } else if r < 75 {
            self.chain(c, d)
        } else if r < 82 {
            self.power(c, d)
        } else if r < 87 {
            let v = self.value(c, d - 1);
            let s = if v.s.starts_with(['-', '+'])
                || v.s.starts_with(|ch: char| ch.is_ascii_digit() || ch == '.')
            {
                if self.rng.chance(0.5) {
                    format!("-{}", v.s)
                } else {
                    format!("-[{}]", v.s)
                }
            } else {
                format!("-{}", v.s)
            };
            ex(s, -v.hi, -v.lo)
        } else if r < 91 {
            self.edge_compare(c, d)
        } else {
            self.special(c, d)
        };
        cap(e)
    }

    fn edge_compare(&mut self, c: &Ctx, d: usize) -> Ex {
        let a = self.value(c, d - 1);
        let delta = *self.rng.pick(&[
            "0.00005",
            "0.0001",
            "0.00009999",
            "0.0002",
            "-0.00005",
            "-0.0001",
            "0",
            "0.0000001",
        ]);
        let op = *self
            .rng
            .pick(&[Op::Eq, Op::Ne, Op::Ge, Op::Le, Op::Lt, Op::Gt]);
        let ot = self.op_text(op);
        ex(format!("[{}{ot}[{} + {delta}]]", a.s, a.s), 0.0, 1.0)
    }

    fn special(&mut self, c: &Ctx, d: usize) -> Ex {
        match self.rng.below(10) {
            0 | 1 => {
                let kw = self.kw("EXISTS");
                let target = match self.rng.below(9) {
                    0 => "#<a>".to_string(),
                    1 => "#<opt>".into(),
                    2 => "#<_gopt>".into(),
                    3 => "#<zz>".into(),
                    4 => "#31".into(),
                    5 => "##50".into(),
                    6 => "#<_g1>".into(),
                    7 => "#<OPT>".into(),
                    _ => "#<depth>".into(),
                };
                ex(format!("{kw}[{target}]"), 0.0, 1.0)
            }
            2 | 3 => {
                let a = self.value(c, d - 1);
                let b = self.value(c, d - 1);
                let kw = self.kw("ATAN");
                ex(format!("{kw}[{}]/[{}]", a.s, b.s), -180.0, 180.0)
            }
            4 | 5 => {
                let s = match self.rng.below(4) {
                    0 => "##50".to_string(),
                    1 => "##51".to_string(),
                    _ => {
                        let v = self.value(c, d - 1);
                        let fix = self.kw("FIX");
                        let abs = self.kw("ABS");
                        let m = self.kw("MOD");
                        format!("#[31 + [{fix}[{abs}[{}]] {m} 8]]", v.s)
                    }
                };
                ex(s, -B, B)
            }
            6 => {
                let s = *self
                    .rng
                    .pick(&["#5420", "#5421", "#5422", "#<_x>", "#<_y>", "#<_z>"]);
                ex(s, -1e9, 1e9)
            }
            7 => {
                let s = *self.rng.pick(&[
                    "#<_call_level>",
                    "#<_value_returned>",
                    "#<_metric>",
                    "#<_imperial>",
                    "#<_absolute>",
                    "#<_incremental>",
                ]);
                ex(s, 0.0, 9.0)
            }
            8 => ex("#<_line>", 0.0, 10000.0),
            _ => self.literal(),
        }
    }

    fn func(&mut self, c: &Ctx, d: usize) -> Ex {
        let v = self.value(c, d - 1);
        let f = *self.rng.pick(&[
            "ABS", "ACOS", "ASIN", "COS", "EXP", "FIX", "FUP", "LN", "ROUND", "SIN", "SQRT", "TAN",
        ]);
        let name = self.kw(f);
        let unit = |g: &mut Gen, v: Ex| -> String {
            if v.lo >= -1.0 && v.hi <= 1.0 {
                v.s
            } else {
                match g.rng.below(3) {
                    0 => format!("{}[{}]", g.kw("SIN"), v.s),
                    1 => format!("{}[{}]", g.kw("COS"), v.s),
                    _ => format!("[{} {} 2 - 1]", v.s, g.kw("MOD")),
                }
            }
        };
        match f {
            "ABS" => ex(format!("{name}[{}]", v.s), v.min_abs(), v.mag()),
            "ACOS" => ex(format!("{name}[{}]", unit(self, v)), 0.0, 180.0),
            "ASIN" => ex(format!("{name}[{}]", unit(self, v)), -90.0, 90.0),
            "COS" | "SIN" => ex(format!("{name}[{}]", v.s), -1.0, 1.0),
            "TAN" => {
                let arg = match self.rng.below(4) {
                    0 => format!("{}[{}] * 60", self.kw("SIN"), v.s),
                    1 => format!("{} {} 80", v.s, self.kw("MOD")),
                    2 => self
                        .rng
                        .pick(&["45", "-30", "0", "89", "135", "-60"])
                        .to_string(),
                    _ => format!("{}[{}] * 45", self.kw("COS"), v.s),
                };
                ex(format!("{name}[{arg}]"), -60.0, 60.0)
            }
            "EXP" => {
                if v.lo >= -30.0 && v.hi <= 12.0 {
                    ex(format!("{name}[{}]", v.s), v.lo.exp(), v.hi.exp())
                } else {
                    ex(
                        format!("{name}[{} {} 7]", v.s, self.kw("MOD")),
                        1.0,
                        7f64.exp(),
                    )
                }
            }
            "FIX" => ex(format!("{name}[{}]", v.s), v.lo.floor(), v.hi.floor()),
            "FUP" => ex(format!("{name}[{}]", v.s), v.lo.ceil(), v.hi.ceil()),
            "ROUND" => {
                let v = if v.mag() > 1e9 { tame(v) } else { v };
                ex(
                    format!("{name}[{}]", v.s),
                    v.lo.round() - 1.0,
                    v.hi.round() + 1.0,
                )
            }
            "LN" => {
                if v.lo > 0.0 {
                    ex(format!("{name}[{}]", v.s), v.lo.ln(), v.hi.ln())
                } else {
                    let k: f64 = *self.rng.pick(&[1.0, 0.5, 0.001]);
                    ex(
                        format!("{name}[{}[{}] + {k}]", self.kw("ABS"), v.s),
                        k.ln(),
                        (v.mag() + k).ln(),
                    )
                }
            }
            _ => {
                // SQRT
                if v.lo >= 0.0 {
                    ex(format!("{name}[{}]", v.s), v.lo.sqrt(), v.hi.sqrt())
                } else {
                    ex(
                        format!("{name}[{}[{}]]", self.kw("ABS"), v.s),
                        0.0,
                        v.mag().sqrt(),
                    )
                }
            }
        }
    }

    fn power(&mut self, c: &Ctx, d: usize) -> Ex {
        let mut b = self.value(c, d - 1);
        if b.mag() > B {
            b = tame(b);
        }
        let (k_text, kmax, kneg, kint) = match self.rng.below(10) {
            0..=4 => {
                let k = *self.rng.pick(&[0i32, 1, 2, 3, -1, -2, 2, 3]);
                let t = if self.rng.chance(0.2) {
                    format!("{k}.0")
                } else {
                    format!("{k}")
                };
                (t, k.abs() as f64, k < 0, true)
            }
            5..=7 => {
                let k = *self.rng.pick(&[0.5, 1.5, 2.5]);
                (self.literal_text(k), k, false, false)
            }
            _ => {
                let v = self.value(c, d - 1);
                (
                    format!(
                        "[{}[{}[{}]] {} 3]",
                        self.kw("FIX"),
                        self.kw("ABS"),
                        v.s,
                        self.kw("MOD")
                    ),
                    3.0,
                    false,
                    true,
                )
            }
        };
        if !kint && b.lo < 0.0 {
            b = ex(format!("{}[{}]", self.kw("ABS"), b.s), b.min_abs(), b.mag());
        }
        if kneg && b.has_zero() {
            b = ex(
                format!("[{}[{}] + 1]", self.kw("ABS"), b.s),
                1.0,
                b.mag() + 1.0,
            );
        }
        let m = if kneg {
            (1.0 / b.min_abs()).powf(kmax)
        } else {
            b.mag().powf(kmax).max(1.0)
        };
        let mut s = format!("[{} ** {k_text}", b.s);
        let mut m = m;
        if kint && !kneg && m <= 1000.0 && self.rng.chance(0.3) {
            let k2 = self.rng.int(0, 2);
            s.push_str(&format!(" ** {k2}"));
            m = m.powi(k2 as i32).max(1.0);
        }
        s.push(']');
        if b.lo >= 0.0 {
            ex(s, 0.0, m)
        } else {
            ex(s, -m, m)
        }
    }

    fn chain(&mut self, c: &Ctx, d: usize) -> Ex {
        let n = self.rng.int(2, 4);
        let mut vals = vec![self.value(c, d - 1)];
        let mut ops = Vec::new();
        let mut s = format!("[{}", vals[0].s);
        for _ in 1..n {
            let op = *self.rng.pick(&OPS);
            let v = if matches!(op, Op::Div | Op::Mod) {
                self.nonzero(c, d - 1)
            } else {
                self.value(c, d - 1)
            };
            let ot = self.op_text(op);
            // `1-` followed by a number would read as one number
            // (`1--2` is fine, `1 - 2`); keep a space before signed values.
            s.push_str(&ot);
            if !ot.ends_with(' ') && v.s.starts_with(['-', '+']) {
                s.push(' ');
            }
            s.push_str(&v.s);
            ops.push(op);
            vals.push(v);
        }
        s.push(']');
        let (lo, hi) = chain_interval(&vals, &ops);
        ex(s, lo, hi)
    }

    /// An expression for a stored value: bracketed or plain, within [-B, B].
    fn stored(&mut self, c: &Ctx) -> Ex {
        let d = *self.rng.pick(&[0, 0, 1, 1, 1, 1, 2, 2, 2, 3]);
        tame(self.value(c, d))
    }

    fn cond(&mut self, c: &Ctx) -> String {
        let d = *self.rng.pick(&[1, 1, 2, 2, 3]);
        let v = self.value(c, d);
        v.s
    }

    // ------------------------------------------------------------ statements

    fn label(&mut self, c: &mut Ctx) -> String {
        c.next_label += 1;
        if self.rng.chance(0.15) {
            format!("<L{}>", c.next_label)
        } else if self.rng.chance(0.1) {
            format!("0{}", c.next_label)
        } else {
            format!("{}", c.next_label)
        }
    }

    fn assign_target(&mut self, c: &Ctx) -> String {
        match self.rng.below(12) {
            0..=4 => format!("#{}", self.rng.pick(&c.writable)),
            5..=7 => {
                let n = self.rng.pick(&c.named).clone();
                self.named_text(&n)
            }
            8 => "##50".into(),
            9 => {
                let v = self.value(c, 1);
                format!(
                    "#[31 + [{}[{}[{}]] MOD 8]]",
                    self.kw("FIX"),
                    self.kw("ABS"),
                    v.s
                )
            }
            10 => self.rng.pick(&["#<opt>", "#<_gopt>", "#<Opt>"]).to_string(),
            _ => format!("#{}", self.rng.pick(&c.writable)),
        }
    }

    fn assignments(&mut self, c: &Ctx) -> Vec<String> {
        let mut items = Vec::new();
        match self.rng.below(10) {
            0 => {
                // swap
                let a = self.assign_target(c);
                let b = self.assign_target(c);
                let opt = |t: &str| t.to_lowercase().contains("opt");
                if !opt(&a) && !opt(&b) {
                    items.push(format!("{a}={b}"));
                    items.push(format!("{b}={a}"));
                } else {
                    items.push(format!("{a}={}", self.stored(c).s));
                }
            }
            1 => {
                // indices
                let v = self.value(c, 1);
                let n = *self.rng.pick(&[50, 51]);
                items.push(format!(
                    "#{n}=[31 + [{}[{}[{}]] {} 8]]",
                    self.kw("FIX"),
                    self.kw("ABS"),
                    v.s,
                    self.kw("MOD")
                ));
            }
            _ => {
                for _ in 0..self.rng.int(1, 3) {
                    let t = self.assign_target(c);
                    let v = self.stored(c);
                    let sp = if self.rng.chance(0.3) { " = " } else { "=" };
                    items.push(format!("{t}{sp}{}", v.s));
                }
            }
        }
        items
    }

    fn debug(&mut self, c: &Ctx) -> String {
        self.msg += 1;
        let kw = *self
            .rng
            .pick(&["debug", "debug", "debug", "DEBUG", "print", "msg"]);
        let mut text = format!("m{}", self.msg);
        if kw == "msg" {
            return format!("({kw}, {text} plain #31 text)");
        }
        for _ in 0..self.rng.int(1, 4) {
            if self.rng.chance(0.3) {
                let f = *self
                    .rng
                    .pick(&["%d", "%f", "%.3f", "%.0f", "%.9f", "%.1f", "%x", "%.f"]);
                text.push(' ');
                text.push_str(f);
            }
            let p = match self.rng.below(12) {
                0..=3 => format!("#{}", self.rng.pick(&c.numbered)),
                4..=6 => {
                    let n = self.rng.pick(&c.named).clone();
                    self.named_text(&n)
                }
                7 => "#<_value>".into(),
                // undefined names print `######` (kept rare: see the report on
                // re-substitution of `#` in flattened debug text)
                8 if self.rng.chance(0.2) => self
                    .rng
                    .pick(&["#<undefined>", "#<opt>", "#<_gopt>", "#5602", "#<Opt >"])
                    .to_string(),
                8 | 10 => self
                    .rng
                    .pick(&["#abc", "#<_value_returned>", "#<_g1>"])
                    .to_string(),
                9 => self
                    .rng
                    .pick(&["#5420", "#5421", "#<_call_level>", "#<_line>"])
                    .to_string(),
                _ => "#50".into(),
            };
            text.push_str(&format!(" v={p}"));
        }
        format!("({kw}, {text})")
    }

    fn coord(&mut self, c: &Ctx) -> String {
        let v = self.stored(c);
        if v.s.starts_with('#')
            || v.s.starts_with('[')
            || v.s.starts_with(|ch: char| ch.is_ascii_alphabetic())
        {
            v.s
        } else {
            // plain literals and unary minus
            v.s
        }
    }

    fn motion(&mut self, c: &mut Ctx) -> Stmt {
        let g = match self.rng.below(10) {
            0 => self
                .rng
                .pick(&["G90", "G91", "G20", "G21", "G17", "G90 G21", "G91 G20"])
                .to_string(),
            _ => String::new(),
        };
        let mut items: Vec<String> = Vec::new();
        if !g.is_empty() {
            items.push(g);
        }
        match self.rng.below(10) {
            0..=2 => {
                items.push("G0".into());
                for ax in ["X", "Y", "Z"] {
                    if self.rng.chance(0.6) {
                        let v = self.coord(c);
                        items.push(format!("{ax}{v}"));
                    }
                }
                if items.len() == 1 {
                    let v = self.coord(c);
                    items.push(format!("X{v}"));
                }
            }
            3..=6 => {
                items.push(self.kw("G1"));
                for ax in ["X", "Y", "Z"] {
                    if self.rng.chance(0.6) {
                        let v = self.coord(c);
                        items.push(format!("{ax}{v}"));
                    }
                }
                if self.rng.chance(0.3) {
                    let v = self.value(c, 1);
                    items.push(format!("F[{}[{}] + 50]", self.kw("ABS"), tame(v).s));
                }
            }
            7 | 8 => {
                // IJ arc: end = start + (I, J) + r (cos t, sin t)
                let i = self.stored(c);
                let j = self.stored(c);
                let t = self.stored(c);
                let abs = self.rng.chance(0.3);
                let (px, py) = if abs {
                    ("#5420 + ", "#5421 + ")
                } else {
                    ("", "")
                };
                let mode = if abs { "G90" } else { "G91" };
                let dir = *self.rng.pick(&["G2", "G3"]);
                let lines = vec![
                    format!(
                        "#<ai>=[{} {} 5 + 0.5] #<aj>=[{} {} 4 - 2] #<at>={}",
                        i.s,
                        self.kw("MOD"),
                        j.s,
                        self.kw("MOD"),
                        t.s
                    ),
                    format!(
                        "{mode} {dir} X[{px}#<ai> + SQRT[#<ai>**2 + #<aj>**2] * COS[#<at>]] Y[{py}#<aj> + SQRT[#<ai>**2 + #<aj>**2] * SIN[#<at>]] I#<ai> J#<aj>"
                    ),
                ];
                return Stmt::Raw(lines);
            }
            _ => {
                // R arc with a radius above half the chord
                let x = self.stored(c);
                let y = self.stored(c);
                let e = self.stored(c);
                let neg = if self.rng.chance(0.3) { "-" } else { "" };
                let dir = *self.rng.pick(&["G2", "G3"]);
                let lines = vec![
                    format!(
                        "#<ax>=[{} {} 6 + 0.5] #<ay>=[{} {} 6 - 3]",
                        x.s,
                        self.kw("MOD"),
                        y.s,
                        self.kw("MOD")
                    ),
                    format!(
                        "G91 {dir} X#<ax> Y#<ay> R{neg}[SQRT[#<ax>**2 + #<ay>**2] / 2 + 0.1 + ABS[SIN[{}]]]",
                        e.s
                    ),
                ];
                return Stmt::Raw(lines);
            }
        }
        if self.rng.chance(0.2) {
            items.push(self.debug(c));
        }
        Stmt::Line(items)
    }

    fn line(&mut self, c: &mut Ctx) -> Stmt {
        let mut items = Vec::new();
        if self.rng.chance(0.08) {
            items.push(format!("N{}", self.rng.int(1, 9999)));
        }
        if self.rng.chance(0.04) {
            items.insert(0, "/".into());
        }
        match self.rng.below(10) {
            0..=4 => items.extend(self.assignments(c)),
            5 | 6 => items.push(self.debug(c)),
            7 => {
                items.extend(self.assignments(c));
                if let Stmt::Line(m) = self.motion(c) {
                    items.extend(m);
                }
                items.push(self.debug(c));
            }
            _ => return self.motion(c),
        }
        if self.rng.chance(0.05) {
            items.push("; trailing comment".into());
        }
        Stmt::Line(items)
    }

    fn call(&mut self, c: &mut Ctx, target: usize, depth_arg: Option<String>) -> Vec<Stmt> {
        let kind = self.kinds[target];
        let mut out = Vec::new();
        if kind == SubKind::Fanuc {
            // M98 to this target, or an expression choosing among callable ones.
            let p = if self.rng.chance(0.6) {
                let n = target + 100;
                if self.rng.chance(0.2) {
                    format!("P0{n}")
                } else {
                    format!("P{n}")
                }
            } else {
                let lo = *c.fanuc.iter().min().unwrap() + 100;
                let k = c.fanuc.len();
                // rs274 re-reads the M98 line in the called frame, where the
                // caller's named locals are not visible: numbered and
                // global parameters only.
                let mut c2 = c.clone();
                c2.named.retain(|n| n.starts_with('_'));
                let v = self.value(&c2, 1);
                format!(
                    "P[{lo} + [{}[{}[{}]] {} {k}]]",
                    self.kw("FIX"),
                    self.kw("ABS"),
                    v.s,
                    self.kw("MOD")
                )
            };
            let l = if self.rng.chance(0.4) {
                format!(" L{}", self.rng.int(1, 3))
            } else {
                String::new()
            };
            out.push(Stmt::OLine(format!("{} {p}{l}", self.kw("M98"))));
        } else {
            let name = self.subs_name(target);
            let mut args = Vec::new();
            let n = if self.rng.chance(0.1) {
                self.rng.int(0, 30)
            } else {
                let want = self.nargs[target];
                (want + self.rng.below(3)).saturating_sub(1).min(30)
            };
            if self.rec[target] > 0 {
                args.push(
                    depth_arg.unwrap_or_else(|| format!("{}", self.rng.int(0, self.rec[target]))),
                );
            }
            while args.len() < n {
                let a = if n > 8 {
                    if self.rng.chance(0.5) {
                        self.literal().s
                    } else {
                        self.param(c).s
                    }
                } else {
                    self.stored(c).s
                };
                args.push(a);
            }
            let mut line = format!("o{name} {}", self.kw("call"));
            for (i, a) in args.iter().enumerate() {
                if i == 1 && self.rng.chance(0.05) {
                    line.push_str(" (between args)");
                }
                line.push_str(&format!(" [{a}]"));
            }
            if line.len() > 250 {
                line = format!("o{name} call");
                if self.rec[target] > 0 {
                    line.push_str(" [0]");
                }
            }
            out.push(Stmt::OLine(line));
        }
        if self.rng.chance(0.6) {
            let t = self.assign_target(c);
            let items = match self.rng.below(3) {
                0 => vec![format!("{t}=#<_value>")],
                1 => vec![format!(
                    "(debug, m{} after call #<_value> #<_value_returned>)",
                    self.bump()
                )],
                _ => vec![format!("{t}=[#<_value> * 2 + #<_value_returned>]")],
            };
            out.push(Stmt::Line(items));
        }
        out
    }

    fn bump(&mut self) -> u32 {
        self.msg += 1;
        self.msg
    }

    fn subs_name(&mut self, i: usize) -> String {
        self.subs[i]
            .as_ref()
            .map(|s| s.call_name.clone())
            .unwrap_or_default()
    }

    fn block(&mut self, c: &mut Ctx, n: usize) -> Vec<Stmt> {
        let mut out = Vec::new();
        for _ in 0..n {
            for attempt in 0..20 {
                let st = self.stmt(c);
                if fits(&st) {
                    out.extend(st);
                    break;
                }
                if attempt == 19 {
                    out.push(Stmt::Line(vec![self.debug(c)]));
                }
            }
        }
        out
    }

    fn stmt(&mut self, c: &mut Ctx) -> Vec<Stmt> {
        let r = self.rng.below(100);
        let nest = c.depth < 3;
        if r < 40 || (!nest && r < 75) {
            return vec![self.line(c)];
        }
        if r < 52 && nest {
            return vec![self.if_stmt(c)];
        }
        if r < 64 && nest {
            return vec![self.loop_stmt(c)];
        }
        if r < 72 && !c.loops.is_empty() {
            return vec![self.jump(c)];
        }
        if r < 84 && (!c.callees.is_empty() || !c.fanuc.is_empty()) {
            let mut all: Vec<usize> = c.callees.clone();
            all.extend(c.fanuc.iter().cloned());
            let t = *self.rng.pick(&all);
            return self.call(c, t, None);
        }
        if r < 90
            && let Some((me, kind)) = c.me
            && !c.in_repeat
        {
            {
                {
                    let lbl = self.label(c);
                    let ret = if kind == SubKind::Fanuc {
                        "M99".to_string()
                    } else {
                        let name = self.subs_name(me);
                        let name = if self.rng.chance(0.1) {
                            "100".to_string()
                        } else {
                            name
                        };
                        if self.rng.chance(0.7) {
                            format!("o{name} {} [{}]", self.kw("return"), self.stored(c).s)
                        } else {
                            format!("o{name} {}", self.kw("return"))
                        }
                    };
                    let cond = self.cond(c);
                    return vec![Stmt::If {
                        label: lbl,
                        arms: vec![(cond, vec![Stmt::OLine(ret)])],
                        els: None,
                    }];
                }
            }
        }
        vec![self.line(c)]
    }

    fn if_stmt(&mut self, c: &mut Ctx) -> Stmt {
        let label = self.label(c);
        c.depth += 1;
        let mut arms = Vec::new();
        for _ in 0..self.rng.int(1, 3) {
            let cond = self.cond(c);
            let n = self.rng.int(1, 3);
            arms.push((cond, self.block(c, n)));
        }
        let els = if self.rng.chance(0.5) {
            let n = self.rng.int(1, 2);
            Some(self.block(c, n))
        } else {
            None
        };
        c.depth -= 1;
        Stmt::If { label, arms, els }
    }

    fn loop_stmt(&mut self, c: &mut Ctx) -> Stmt {
        let label = self.label(c);
        let kind = *self
            .rng
            .pick(&[LoopKind::While, LoopKind::Do, LoopKind::Repeat]);
        c.counter += 1;
        let ctr = format!("#<w{}>", c.counter);
        let mut pre = Vec::new();
        let mut head = Vec::new();
        let cond = match kind {
            LoopKind::Repeat => {
                if self.rng.chance(0.6) {
                    self.rng
                        .pick(&[
                            "0", "0.5", "1", "1.5", "2", "2.5", "3", "0.4999", "-1", "2.5001",
                        ])
                        .to_string()
                } else {
                    let v = self.value(c, 1);
                    format!("{}[{}] {} 3", self.kw("ABS"), v.s, self.kw("MOD"))
                }
            }
            _ => {
                pre.push(format!("{ctr}=0"));
                head.push(format!("{ctr}=[{ctr} + 1]"));
                let lim = self
                    .rng
                    .pick(&["0", "1", "2", "3", "1.5", "2.00005", "1.99995"])
                    .to_string();
                let cmp = self.rng.pick(&["LT", "LE", "NE", "LT"]).to_string();
                let lim = if cmp == "LE" || cmp == "NE" {
                    self.rng.pick(&["1", "2", "0.5", "1.99995"]).to_string()
                } else {
                    lim
                };
                let base = if cmp == "NE" {
                    // counts up to the first integer >= lim
                    format!("{ctr} NE {}", lim.parse::<f64>().unwrap().ceil().max(1.0))
                } else {
                    format!("{ctr} {} {lim}", self.kw(&cmp))
                };
                if self.rng.chance(0.3) {
                    let v = self.value(c, 1);
                    format!("[{base}] {} {}", self.kw("AND"), v.s)
                } else {
                    base
                }
            }
        };
        c.loops.push(LoopFrame {
            label: label.clone(),
            kind,
            has_break: false,
            has_cont: false,
        });
        let saved_rep = c.in_repeat;
        if kind == LoopKind::Repeat {
            c.in_repeat = true;
        }
        c.depth += 1;
        let n = self.rng.int(1, 3);
        let body = self.block(c, n);
        c.depth -= 1;
        c.in_repeat = saved_rep;
        let frame = c.loops.pop().unwrap();
        let mut post = Vec::new();
        // rs274 leaves `doing_break` set after a break out of a while loop and
        // `doing_continue` after a continue in a do loop; an empty loop that
        // behaves the same under both semantics clears them.
        if kind == LoopKind::While && frame.has_break {
            let l = self.label(c);
            post.push(format!("o{l} do"));
            post.push(format!("o{l} while [0]"));
        }
        if kind == LoopKind::Do && frame.has_cont {
            let l = self.label(c);
            head.insert(0, format!("o{l} endwhile"));
            head.insert(0, format!("o{l} while [0]"));
            let l2 = self.label(c);
            post.push(format!("o{l2} while [0]"));
            post.push(format!("o{l2} endwhile"));
        }
        Stmt::Loop {
            kind,
            label,
            pre,
            head,
            cond,
            body,
            post,
        }
    }

    fn jump(&mut self, c: &mut Ctx) -> Stmt {
        // A jump out of a repeat leaves rs274's per-label counter stale (a
        // documented deviation), so targets are loops inside the innermost
        // repeat only.
        let floor = c
            .loops
            .iter()
            .rposition(|l| l.kind == LoopKind::Repeat)
            .map_or(0, |r| r + 1);
        let targets: Vec<usize> = (floor..c.loops.len())
            .filter(|&i| c.loops[i].kind != LoopKind::Repeat)
            .collect();
        if targets.is_empty() {
            return self.line(c);
        }
        let t = *self.rng.pick(&targets);
        // rs274 acts on a break that a continue skips over (a documented
        // deviation), so no break follows a continue to the same loop.
        let brk = self.rng.chance(0.5) && !c.loops[t].has_cont;
        if brk {
            c.loops[t].has_break = true;
        } else {
            c.loops[t].has_cont = true;
        }
        let kw = self.kw(if brk { "break" } else { "continue" });
        let line = Stmt::OLine(format!("o{} {kw}", c.loops[t].label));
        if self.rng.chance(0.85) {
            let l = self.label(c);
            let cond = self.cond(c);
            Stmt::If {
                label: l,
                arms: vec![(cond, vec![line])],
                els: None,
            }
        } else {
            line
        }
    }

    fn init_line(&mut self, c: &Ctx, names: &[&str]) -> Stmt {
        let mut items = Vec::new();
        for n in names {
            let v = if c.numbered.contains(&1) && self.rng.chance(0.6) {
                let k = self.rng.int(1, 6);
                ex(format!("#{k}"), -B, B)
            } else {
                let mut c2 = c.clone();
                c2.named.clear();
                self.stored(&c2)
            };
            let vs = if v.s.len() > 50 {
                self.literal().s
            } else {
                v.s
            };
            items.push(format!("#<{n}>={vs}"));
        }
        Stmt::Line(items)
    }
}

// ---------------------------------------------------------------- program generation

fn cost(body: &[Stmt], g: &Gen) -> f64 {
    let mut t = 0.0;
    for s in body {
        t += match s {
            Stmt::Line(_) | Stmt::Raw(_) => 1.0,
            Stmt::OLine(l) => {
                let mut c: f64 = 1.0;
                for (i, sub) in g.subs.iter().enumerate() {
                    let Some(sub) = sub else { continue };
                    let lower = l.to_lowercase();
                    let hit = if sub.kind == SubKind::Fanuc {
                        lower.starts_with("m98")
                    } else {
                        lower.starts_with(&format!("o{} call", sub.call_name.to_lowercase()))
                    };
                    if hit {
                        let lmul = if lower.contains(" l") { 3.0 } else { 1.0 };
                        c = c.max(1.0 + g.cost[i] * lmul);
                    }
                }
                c
            }
            Stmt::If { arms, els, .. } => {
                let mut m: f64 = 0.0;
                for (_, b) in arms {
                    m = m.max(cost(b, g));
                }
                if let Some(b) = els {
                    m = m.max(cost(b, g));
                }
                1.0 + m
            }
            Stmt::Loop { kind, body, .. } => {
                let n = if *kind == LoopKind::Repeat { 4.0 } else { 3.0 };
                2.0 + n * (2.0 + cost(body, g))
            }
        };
    }
    t
}

fn generate(seed: u64) -> Program {
    let mut attempt = 0u64;
    loop {
        let (p, c) = generate_once(seed.wrapping_add(attempt.wrapping_mul(0x1000_0000_0000)));
        if c <= 20_000.0 {
            return p;
        }
        attempt += 1;
    }
}

/// Gives each subroutine its name and the name its calls use.
fn name_subs(g: &mut Gen, kinds: &[SubKind]) {
    let n = kinds.len();
    let mut file_num = 90;
    for (i, kind) in kinds.iter().enumerate().take(n) {
        let (name, call_name) = match kind {
            SubKind::Fanuc => (format!("{}", i + 100), format!("{}", i + 100)),
            SubKind::File if g.rng.chance(0.25) => {
                file_num += 1;
                (format!("{file_num}"), format!("{file_num}"))
            }
            SubKind::File => {
                let nm = format!("fs{i}");
                let cn = if g.rng.chance(0.3) {
                    format!("<Fs{i}>")
                } else {
                    format!("<{nm}>")
                };
                (format!("<{nm}>"), cn)
            }
            _ if g.rng.chance(0.2) => (format!("{}", i + 1), format!("{}", i + 1)),
            _ => {
                let nm = format!("s{i}");
                let cn = if g.rng.chance(0.2) {
                    format!("<S{i}>")
                } else {
                    format!("<{nm}>")
                };
                (format!("<{nm}>"), cn)
            }
        };
        g.subs[i] = Some(SubDef {
            kind: kinds[i],
            name,
            call_name,
            body: Vec::new(),
            end_value: None,
            file_pre: Vec::new(),
            file_post: Vec::new(),
        });
    }
}

/// Writes the body of subroutine `i` (its callees, the later ones, are
/// written already) and works out its cost.
fn sub_body(g: &mut Gen, kinds: &[SubKind], i: usize) {
    let n = kinds.len();
    let k = kinds[i];
    let allowed = |j: usize| -> bool {
        j > i
            && match k {
                SubKind::Pre => true,
                SubKind::Fanuc => kinds[j] != SubKind::Pre,
                SubKind::Post => matches!(kinds[j], SubKind::Post | SubKind::File),
                SubKind::File => kinds[j] == SubKind::File,
            }
    };
    let mut callees: Vec<usize> = (0..n)
        .filter(|&j| allowed(j) && kinds[j] != SubKind::Fanuc && g.levels[j] <= 6)
        .collect();
    let fanuc: Vec<usize> = (0..n)
        .filter(|&j| allowed(j) && kinds[j] == SubKind::Fanuc && g.levels[j] <= 6)
        .collect();
    // fanuc targets chosen by expression must be contiguous: they are.
    callees.retain(|_| g.rng.chance(0.8));
    let maxc = callees
        .iter()
        .chain(fanuc.iter())
        .map(|&j| g.levels[j])
        .max()
        .unwrap_or(0);
    let rec = if k != SubKind::Fanuc && g.rng.chance(0.35) {
        g.rng.int(1, (8 - maxc).min(5))
    } else {
        0
    };
    g.rec[i] = rec;
    g.levels[i] = 1 + rec + maxc;
    g.nargs[i] = if g.rng.chance(0.15) {
        g.rng.int(10, 30)
    } else {
        g.rng.int(0, 5)
    };
    let numbered: Vec<u32> = (1..=10).chain(31..=38).collect();
    let mut c = Ctx {
        numbered: numbered.clone(),
        writable: numbered,
        named: vec![
            "a".into(),
            "b".into(),
            "cc".into(),
            "_g1".into(),
            "_g2".into(),
        ],
        loops: Vec::new(),
        in_repeat: false,
        depth: 0,
        next_label: 0,
        callees: callees.clone(),
        fanuc,
        me: Some((i, k)),
        counter: 0,
    };
    let mut body = Vec::new();
    let mut init = vec!["a", "b", "cc"];
    if rec > 0 {
        init.push("depth");
    }
    let mut init_line = g.init_line(&c, &init);
    if rec > 0
        && let Stmt::Line(items) = &mut init_line
    {
        items.pop();
        items.push("#<depth>=#1".into());
    }
    body.push(init_line);
    let nstmt = g.rng.int(1, 5);
    body.extend(g.block(&mut c, nstmt));
    if rec > 0 {
        // self-recursion, never inside a repeat body
        let lbl = g.label(&mut c);
        let call = g.call(&mut c, i, Some("#<depth> - 1".into()));
        let pos = g.rng.int(1, body.len());
        body.insert(
            pos,
            Stmt::If {
                label: lbl,
                arms: vec![("#<depth> GT 0".into(), call)],
                els: None,
            },
        );
    }
    let end_value = if k != SubKind::Fanuc && g.rng.chance(0.4) {
        Some(g.stored(&c).s).filter(|v| v.len() < 200)
    } else {
        None
    };
    {
        let s = g.subs[i].as_mut().unwrap();
        s.body = body;
        s.end_value = end_value;
        if k == SubKind::File {
            s.file_pre = vec![
                "(file header, never executed)".into(),
                "(debug, must not print)".into(),
            ];
            if g.rng.chance(0.5) {
                s.file_post = vec!["M2".into()];
            }
        }
    }
    let body_cost = cost(&g.subs[i].as_ref().unwrap().body, g);
    g.cost[i] = body_cost * (rec as f64 + 1.0) + 1.0;
}

fn generate_once(seed: u64) -> (Program, f64) {
    let mut rng = Rng::new(seed);
    let mut kinds = Vec::new();
    for (k, max) in [
        (SubKind::Pre, 2),
        (SubKind::Fanuc, 2),
        (SubKind::Post, 2),
        (SubKind::File, 3),
    ] {
        for _ in 0..rng.int(0, max) {
            kinds.push(k);
        }
    }
    let n = kinds.len();
    let mut g = Gen {
        rng,
        subs: vec![None; n],
        kinds: kinds.clone(),
        levels: vec![0; n],
        cost: vec![0.0; n],
        rec: vec![0; n],
        nargs: vec![0; n],
        msg: 0,
    };
    // names first (calls need them)
    name_subs(&mut g, &kinds);
    // bodies, callees first
    for i in (0..n).rev() {
        sub_body(&mut g, &kinds, i);
    }
    // main
    let mut main = Vec::new();
    let numbered: Vec<u32> = (1..=5).chain(31..=38).collect();
    let mut c = Ctx {
        numbered: numbered.clone(),
        writable: numbered,
        named: vec![
            "a".into(),
            "b".into(),
            "cc".into(),
            "_g1".into(),
            "_g2".into(),
        ],
        loops: Vec::new(),
        in_repeat: false,
        depth: 0,
        next_label: 0,
        callees: (0..n).filter(|&j| kinds[j] != SubKind::Fanuc).collect(),
        fanuc: (0..n).filter(|&j| kinds[j] == SubKind::Fanuc).collect(),
        me: None,
        counter: 0,
    };
    let mut init = vec![Stmt::Line(vec!["G21 G90 G17 F100".into()])];
    init.push(Stmt::Line(vec![format!(
        "#50={} #51={}",
        g.rng.int(31, 38),
        g.rng.int(31, 38)
    )]));
    {
        let mut items = Vec::new();
        for n in [31, 32, 33, 34, 1, 2] {
            if g.rng.chance(0.7) {
                let mut c2 = c.clone();
                c2.named.clear();
                let mut v = g.stored(&c2).s;
                if v.len() > 60 {
                    v = g.literal().s;
                }
                items.push(format!("#{n}={v}"));
            }
        }
        if !items.is_empty() {
            init.push(Stmt::Line(items));
        }
    }
    let gl = g.init_line(&c, &["_g1", "_g2", "a", "b", "cc"]);
    init.push(gl);
    let nstmt = g.rng.int(4, 12);
    main.extend(g.block(&mut c, nstmt));
    // make sure every sub is called at least sometimes
    for j in 0..n {
        if g.rng.chance(0.7) {
            let stmts = g.call(&mut c, j, None);
            let pos = g.rng.int(0, main.len());
            for (k, s) in stmts.into_iter().enumerate() {
                main.insert(pos + k, s);
            }
        }
    }
    if g.rng.chance(0.02) {
        // M2 inside a sub: ends everything
        if let Some(i) = (0..n).find(|&i| kinds[i] != SubKind::Fanuc) {
            let s = g.subs[i].as_mut().unwrap();
            let pos = s.body.len().min(2);
            s.body.insert(pos, Stmt::Line(vec!["M2".into()]));
        }
    }
    let has_after = kinds
        .iter()
        .any(|k| matches!(k, SubKind::Fanuc | SubKind::Post));
    let percent = g.rng.chance(0.15);
    let end = if percent && !has_after && g.rng.chance(0.5) {
        "%".to_string()
    } else {
        g.rng
            .pick(&["M2", "M2", "M2", "M30", "m2", "M02", "M99"])
            .to_string()
    };
    let total = cost(&main, &g);
    let mut prog = Program {
        init,
        percent,
        title: g.rng.chance(0.1),
        main,
        end,
        subs: g.subs.into_iter().map(|s| s.unwrap()).collect(),
    };
    // a deliberately wrong line somewhere (rs274 and ngcflat must both
    // refuse it when it runs)
    if g.rng.chance(0.12) {
        insert_bad_line(&mut g.rng, &mut prog);
    }
    (prog, total)
}

/// Puts a line both rs274 and ngcflat refuse at a random place.
fn insert_bad_line(rng: &mut Rng, prog: &mut Program) {
    let bad = [
        "#31=[1/[#31-#31]]",
        "#31=SQRT[-1-ABS[#32]]",
        "#31=LN[0]",
        "#31=ACOS[1.0002]",
        "#31=ASIN[-1.5]",
        "#31=[-2 ** 0.5]",
        "#31=[5 MOD 0]",
        "#31=EXP[1000]",
        "#31=[0 ** -1]",
        "#31=#<nope>",
        "#0=1",
        "#31=#5602",
        "(abort, stopped #31)",
        "G1 X[1/0]",
        "#<_value>=1",
        "o<missing> call",
    ];
    let line = rng.pick(&bad).to_string();
    let st = if line.starts_with('o') {
        Stmt::OLine(line)
    } else {
        Stmt::Line(vec![line])
    };
    let total: usize = count_bodies(&prog.main)
        + prog
            .subs
            .iter()
            .map(|s| count_bodies(&s.body))
            .sum::<usize>();
    let mut k = rng.below(total);
    let frac = rng.below(1000) as f64 / 1000.0;
    let mut st = Some(st);
    insert_into(&mut prog.main, &mut k, frac, &mut st);
    for s in prog.subs.iter_mut() {
        insert_into(&mut s.body, &mut k, frac, &mut st);
    }
}

fn count_bodies(body: &[Stmt]) -> usize {
    1 + body
        .iter()
        .map(|s| match s {
            Stmt::If { arms, els, .. } => {
                arms.iter().map(|a| count_bodies(&a.1)).sum::<usize>()
                    + els.as_ref().map_or(0, |e| count_bodies(e))
            }
            Stmt::Loop { body, .. } => count_bodies(body),
            _ => 0,
        })
        .sum::<usize>()
}

/// Inserts `st` into the k-th body (pre-order), at relative position `frac`.
fn insert_into(body: &mut Vec<Stmt>, k: &mut usize, frac: f64, st: &mut Option<Stmt>) {
    if st.is_none() {
        return;
    }
    if *k == 0 {
        let pos = ((body.len() as f64) * frac) as usize;
        body.insert(pos.min(body.len()), st.take().unwrap());
        return;
    }
    *k -= 1;
    for s in body.iter_mut() {
        match s {
            Stmt::If { arms, els, .. } => {
                for a in arms.iter_mut() {
                    insert_into(&mut a.1, k, frac, st);
                }
                if let Some(e) = els {
                    insert_into(e, k, frac, st);
                }
            }
            Stmt::Loop { body, .. } => insert_into(body, k, frac, st),
            _ => {}
        }
    }
}

// ---------------------------------------------------------------- running

#[derive(Debug, Clone, PartialEq)]
enum Kind {
    Canon,
    NgcflatRefuses,
    NgcflatAccepts,
    FlatRejected,
    Crash,
}

enum Verdict {
    BothOk,
    BothRejected(String),
    Mismatch(Kind, String),
}

fn check(p: &Program) -> Verdict {
    let dir = tempfile::tempdir().expect("tempdir");
    let subs = dir.path().join("subs");
    let progdir = dir.path().join("prog");
    std::fs::create_dir_all(&subs).unwrap();
    std::fs::create_dir_all(&progdir).unwrap();
    for (name, text) in p.files() {
        std::fs::write(subs.join(name), text).unwrap();
    }
    let main = p.main_text();
    std::fs::write(progdir.join("main.ngc"), &main).unwrap();
    let a = oracle::run(
        main.as_bytes(),
        &oracle::ini_with(std::slice::from_ref(&subs), ""),
        None,
    );
    let args: Vec<String> = vec![
        "--zero-start".into(),
        "--no-program-dir".into(),
        "-I".into(),
        subs.display().to_string(),
        "main.ngc".into(),
    ];
    let out = crate::ngcflat(&progdir, &args, None);
    let code = out.status.code().unwrap_or(-1);
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    if code != 0 && code != 1 {
        return Verdict::Mismatch(Kind::Crash, format!("ngcflat exit {code}:\n{stderr}"));
    }
    if !a.ok {
        if code == 1 {
            return Verdict::BothRejected(a.stderr);
        }
        return Verdict::Mismatch(
            Kind::NgcflatAccepts,
            format!(
                "rs274 rejects the program:\n{}\nbut ngcflat flattens it:\n{stdout}",
                a.stderr.trim()
            ),
        );
    }
    if code != 0 {
        return Verdict::Mismatch(
            Kind::NgcflatRefuses,
            format!("rs274 accepts the program, ngcflat refuses it:\n{stderr}"),
        );
    }
    let b = oracle::run(stdout.as_bytes(), "", None);
    if !b.ok {
        return Verdict::Mismatch(
            Kind::FlatRejected,
            format!(
                "rs274 rejects ngcflat's output: {}\n--- output\n{stdout}",
                b.stderr.trim()
            ),
        );
    }
    match oracle::compare(&a.lines, &b.lines, 1e-4) {
        Ok(()) => Verdict::BothOk,
        Err(e) => Verdict::Mismatch(Kind::Canon, format!("{e}\n--- ngcflat output\n{stdout}")),
    }
}

// ---------------------------------------------------------------- shrinking

/// Applies the k-th simplification of `body`; false when k is past the end.
fn mutate_body(body: &mut Vec<Stmt>, k: &mut usize) -> bool {
    for i in 0..body.len() {
        if *k == 0 {
            body.remove(i);
            return true;
        }
        *k -= 1;
    }
    for i in 0..body.len() {
        let inner = match &body[i] {
            Stmt::If { arms, els, .. } => {
                let mut v: Vec<Stmt> = arms.iter().flat_map(|a| a.1.clone()).collect();
                if let Some(e) = els {
                    v.extend(e.clone());
                }
                Some(v)
            }
            Stmt::Loop { body: b, .. } => Some(b.clone()),
            _ => None,
        };
        if let Some(inner) = inner {
            if *k == 0 {
                body.splice(i..=i, inner);
                return true;
            }
            *k -= 1;
        }
    }
    for s in body.iter_mut() {
        match s {
            Stmt::Line(items) if items.len() > 1 => {
                for j in 0..items.len() {
                    if *k == 0 {
                        items.remove(j);
                        return true;
                    }
                    *k -= 1;
                }
            }
            Stmt::If { arms, els, .. } => {
                if arms.len() > 1 {
                    for j in 0..arms.len() {
                        if *k == 0 {
                            arms.remove(j);
                            return true;
                        }
                        *k -= 1;
                    }
                }
                if els.is_some() {
                    if *k == 0 {
                        *els = None;
                        return true;
                    }
                    *k -= 1;
                }
                for a in arms.iter_mut() {
                    if mutate_body(&mut a.1, k) {
                        return true;
                    }
                }
                if let Some(e) = els
                    && mutate_body(e, k)
                {
                    return true;
                }
            }
            Stmt::Loop { body: b, .. } => {
                let hit = mutate_body(b, k);
                if hit {
                    return true;
                }
            }
            _ => {}
        }
    }
    false
}

fn mutate(p: &Program, mut k: usize) -> Option<Program> {
    let mut q = p.clone();
    for i in 0..q.subs.len() {
        if k == 0 {
            q.subs.remove(i);
            return Some(q);
        }
        k -= 1;
    }
    for i in 0..q.subs.len() {
        if q.subs[i].end_value.is_some() {
            if k == 0 {
                q.subs[i].end_value = None;
                return Some(q);
            }
            k -= 1;
        }
    }
    if q.title {
        if k == 0 {
            q.title = false;
            return Some(q);
        }
        k -= 1;
    }
    if mutate_body(&mut q.init, &mut k) {
        return Some(q);
    }
    if mutate_body(&mut q.main, &mut k) {
        return Some(q);
    }
    for i in 0..q.subs.len() {
        if mutate_body(&mut q.subs[i].body, &mut k) {
            return Some(q);
        }
    }
    None
}

fn shrink(p: &Program, kind: &Kind, detail: &str) -> (Program, String) {
    let mut best = p.clone();
    let mut best_detail = detail.to_string();
    let mut checks = 0;
    loop {
        let mut changed = false;
        let mut k = 0;
        while let Some(q) = mutate(&best, k) {
            if checks >= 250 {
                return (best, best_detail);
            }
            checks += 1;
            match check(&q) {
                Verdict::Mismatch(kq, d) if kq == *kind => {
                    best = q;
                    best_detail = d;
                    changed = true;
                }
                _ => k += 1,
            }
        }
        if !changed {
            return (best, best_detail);
        }
    }
}

// ---------------------------------------------------------------- tests

#[test]
fn generator_is_deterministic_and_well_formed() {
    for seed in 0..200 {
        let a = generate(seed);
        let b = generate(seed);
        assert_eq!(a.full_text(), b.full_text(), "seed {seed}");
        for (_, t) in std::iter::once(("main".to_string(), a.main_text())).chain(a.files()) {
            for line in t.lines() {
                assert!(line.len() <= 252, "seed {seed}: line too long: {line}");
            }
        }
    }
}

#[test]
fn generated_programs_match_rs274() {
    if !oracle::available("generated_programs_match_rs274") {
        return;
    }
    let seeds = oracle::suite_seeds("NGCFLAT_DIFF", 300);
    let (cases, start) = (seeds.end - seeds.start, seeds.start);
    let t0 = std::time::Instant::now();
    let results = oracle::on_threads(seeds, 2, |seed| {
        let p = generate(seed);
        let v = check(&p);
        if let Ok(dir) = std::env::var("NGCFLAT_DIFF_DUMP") {
            let what = match &v {
                Verdict::BothOk => "both ok".to_string(),
                Verdict::BothRejected(e) => format!("both rejected; rs274: {e}"),
                Verdict::Mismatch(k, d) => format!("MISMATCH {k:?}: {d}"),
            };
            let _ = std::fs::write(
                Path::new(&dir).join(format!("{seed}.txt")),
                format!("{}==== {what}\n", p.full_text()),
            );
        }
        match v {
            Verdict::Mismatch(k, d) => Err(Box::new((p, k, d))),
            Verdict::BothOk => Ok(true),
            Verdict::BothRejected(_) => Ok(false),
        }
    });
    let (mut ok, mut rej) = (0, 0);
    let mut failures = Vec::new();
    for (seed, r) in results {
        match r {
            Ok(true) => ok += 1,
            Ok(false) => rej += 1,
            Err(m) => {
                let (p, k, d) = *m;
                failures.push((seed, p, k, d));
            }
        }
    }
    eprintln!(
        "generated programs: {cases} from seed {start}: {} agree ({ok} flattened identically, {rej} refused by both), {} differ; {:.1}s",
        ok + rej,
        failures.len(),
        t0.elapsed().as_secs_f64()
    );
    if failures.is_empty() {
        return;
    }
    let mut report = String::new();
    let shrink_max = std::env::var("NGCFLAT_DIFF_SHRINK")
        .ok()
        .and_then(|v| v.trim().parse().ok())
        .unwrap_or(2);
    let seeds: Vec<String> = failures
        .iter()
        .map(|f| format!("{} ({:?})", f.0, f.2))
        .collect();
    report.push_str(&format!(
        "{} of {cases} generated programs differ: seeds {}\n",
        failures.len(),
        seeds.join(", ")
    ));
    for (seed, p, kind, detail) in failures.iter().take(shrink_max) {
        let (small, d) = shrink(p, kind, detail);
        report.push_str(&format!(
            "\n==== seed {seed} ({kind:?}); reproduce with NGCFLAT_DIFF_SEED={seed} NGCFLAT_DIFF_CASES=1\n{}---- difference\n{d}\n",
            small.full_text()
        ));
    }
    panic!("{report}");
}
