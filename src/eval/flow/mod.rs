//! Control flow: where reading continues, O-word blocks, loops, calls and
//! their frames, the subroutines known, and the parsed lines of bodies that
//! run again.

use std::cell::OnceCell;
use std::rc::Rc;
use std::sync::Arc;

use crate::diag::Site;
use crate::fx_hasher::{FxMap, FxSet};
use crate::parse::Name;
use crate::parse::ast::{Line, OKind};
use crate::program::FileIndex;

use super::expr::params::Params;

/// Deepest nesting of active calls (the tenth nested call fails).
pub(super) const MAX_CALL_LEVEL: usize = 9;

/// Parsed body lines kept (see `Flow::cache`); past this, the kept lines
/// are dropped and the cache fills again.
pub(super) const LINES_KEPT: usize = 1 << 14;

/// Where reading continues.
#[derive(Clone)]
pub(super) struct Cursor {
    pub file: Rc<FileIndex>,
    /// Byte offset of the next line.
    pub pos: u32,
    /// 0-based index of the next line.
    pub line: u32,
    /// Index of the first O-line at or after `line`.
    pub next_o: usize,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum FrameKind {
    Main,
    Call,
    M98,
}

/// Record of a control label reached in this activation.
#[derive(Debug, Clone, Copy)]
pub(super) struct LabelRec {
    pub kind: OKind,
    pub oidx: u32,
    pub line: u32,
    /// Remaining passes of a repeat loop (-1: not running).
    pub repeat: i64,
}

pub(super) struct Frame {
    pub kind: FrameKind,
    pub name: Name,
    pub ret: Option<Cursor>,
    /// The O-line (of the file `ret` is in) that made the call; its site is
    /// worked out only for a message.
    pub call_oidx: Option<u32>,
    pub saved: Option<Box<[f64; 30]>>,
    pub locals: FxMap<Name, f64>,
    pub labels: FxMap<Name, LabelRec>,
    /// Pending passes of an `M98 ... L` on the given line of this frame.
    pub m98_loop: Option<(u32, i64)>,
    /// Modal state saved by M70/M73; `auto` restores it on return (M73).
    pub saved_modal: Option<Box<crate::eval::state::restore::Saved>>,
    pub auto_restore: bool,
    /// The call stack of the lines run in this frame, once asked for (see
    /// [`calls_of`]).
    pub calls: OnceCell<Option<Arc<Calls>>>,
}

impl Frame {
    /// Makes a pooled frame like a new one, keeping its tables' room.
    pub(in crate::eval) fn reset(&mut self, kind: FrameKind, name: Name) {
        let Frame {
            kind: k,
            name: n,
            ret,
            call_oidx,
            saved,
            locals,
            labels,
            m98_loop,
            saved_modal,
            auto_restore,
            calls,
        } = self;
        *k = kind;
        *n = name;
        *ret = None;
        *call_oidx = None;
        *saved = None;
        locals.clear();
        labels.clear();
        *m98_loop = None;
        *saved_modal = None;
        *auto_restore = false;
        calls.take();
    }

    pub(in crate::eval) fn new(kind: FrameKind, name: Name) -> Frame {
        Frame {
            kind,
            name,
            ret: None,
            call_oidx: None,
            saved: None,
            locals: FxMap::default(),
            labels: FxMap::default(),
            m98_loop: None,
            saved_modal: None,
            auto_restore: false,
            calls: OnceCell::new(),
        }
    }
}

/// A registered subroutine definition.
#[derive(Clone)]
pub(super) struct SubRec {
    pub file: Rc<FileIndex>,
    pub oidx: u32,
}

/// The call stack of `frames` as sites, innermost caller first.
#[allow(clippy::vec_box)]
pub(super) fn stack_of(frames: &[Box<Frame>]) -> Vec<Site> {
    frames
        .iter()
        .rev()
        .filter_map(|f| {
            let (ret, oidx) = (f.ret.as_ref()?, f.call_oidx?);
            let (a, b) = osite_of(&ret.file, oidx);
            Some(Site::new(&ret.file.file, a, b))
        })
        .collect()
}

/// A call site and the calls around it, innermost first: the call stack
/// of the lines run in a call, made once for the call and shared by them
/// (the consumer on its own thread gets it with each line).
pub(crate) struct Calls {
    site: Site,
    up: Option<Arc<Calls>>,
}

impl Calls {
    /// The sites, innermost caller first: [`stack_of`] of the frames it
    /// was made of.
    pub(crate) fn sites(&self) -> Vec<Site> {
        let mut out = vec![self.site.clone()];
        let mut at = &self.up;
        while let Some(c) = at {
            out.push(c.site.clone());
            at = &c.up;
        }
        out
    }
}

/// [`stack_of`] `frames` as shared [`Calls`] (none outside calls): each
/// frame's worked out once, when first asked for.
#[allow(clippy::vec_box)]
pub(super) fn calls_of(frames: &[Box<Frame>]) -> Option<Arc<Calls>> {
    let (last, outer) = frames.split_last()?;
    last.calls
        .get_or_init(|| match (last.ret.as_ref(), last.call_oidx) {
            (Some(ret), Some(oidx)) => {
                let (a, b) = osite_of(&ret.file, oidx);
                let site = Site::new(&ret.file.file, a, b);
                let up = calls_of(outer);
                Some(Arc::new(Calls { site, up }))
            }
            _ => calls_of(outer),
        })
        .clone()
}

/// The label part of a control key (`scope#label`).
pub(super) fn label_of_key(key: &str) -> String {
    key.rsplit('#').next().unwrap_or("").to_string()
}

/// The control-flow state.
pub(super) struct Flow {
    /// Where reading continues.
    pub(super) cur: Cursor,
    /// Active calls, the main program first. Boxed: a call moves a pointer,
    /// not the frame.
    #[allow(clippy::vec_box)]
    pub(super) frames: Vec<Box<Frame>>,
    /// Frames of returned calls, reused by the next calls.
    #[allow(clippy::vec_box)]
    pub(super) frame_pool: Vec<Box<Frame>>,
    /// Argument save areas of returned calls (boxed: they move between
    /// frames and the pool without copying).
    #[allow(clippy::vec_box)]
    pub(super) saved_pool: Vec<Box<[f64; 30]>>,
    /// The value of the last `return`/`endsub` with a value (`#<_value>`).
    pub(super) value: f64,
    pub(super) value_returned: bool,
    /// Reading undefined named parameters gives 0 (sub definition skip).
    pub(super) defining: bool,
    /// O-lines executed (the `--max-steps` guard).
    pub(super) steps: u64,
    pub(super) subs: FxMap<Name, SubRec>,
    pub(super) called: FxSet<Name>,
    /// The sub of the last call, already registered and marked called.
    pub(super) last_called: Option<Name>,
    pub(super) executed_if: bool,
    /// The reference's never-cleared break/continue flags (for warnings).
    pub(super) ref_stale_break: Option<u32>,
    pub(super) ref_stale_continue: Option<u32>,
    /// Control key, line and file of the last loop passed (for limit
    /// messages).
    pub(super) last_loop: Option<(Name, u32, Rc<FileIndex>)>,
    /// Parsed lines of loop and sub bodies, with their end and the start of
    /// the next line.
    /// At most [`LINES_KEPT`] lines.
    pub(super) cache: FxMap<(usize, u32), (Rc<Line>, u32, u32)>,
    /// The repeat line (O-line index) an endrepeat just jumped back to.
    pub(super) repeat_again: Option<u32>,
}

impl Flow {
    /// At the start of `main`, with the main program's frame.
    pub(super) fn new(main: Rc<FileIndex>, main_frame: Frame) -> Flow {
        Flow {
            cur: Cursor {
                file: main,
                pos: 0,
                line: 0,
                next_o: 0,
            },
            frames: vec![Box::new(main_frame)],
            frame_pool: Vec::new(),
            saved_pool: Vec::new(),
            value: 0.0,
            value_returned: false,
            defining: false,
            steps: 0,
            subs: FxMap::default(),
            called: FxSet::default(),
            last_called: None,
            executed_if: true,
            ref_stale_break: None,
            ref_stale_continue: None,
            last_loop: None,
            cache: FxMap::default(),
            repeat_again: None,
        }
    }

    /// Call level: 0 in the main program.
    pub(super) fn level(&self) -> usize {
        self.frames.len() - 1
    }

    /// The innermost frame.
    pub(super) fn frame(&mut self) -> &mut Frame {
        self.frames
            .last_mut()
            .expect("the main frame is never popped")
    }

    /// The call stack as sites, innermost caller first.
    pub(super) fn stack(&self) -> Vec<Site> {
        stack_of(&self.frames)
    }

    /// A frame for a new call, reusing a returned one's tables.
    pub(super) fn new_frame(&mut self, kind: FrameKind, name: Name) -> Box<Frame> {
        match self.frame_pool.pop() {
            Some(mut f) => {
                f.reset(kind, name);
                f
            }
            None => Box::new(Frame::new(kind, name)),
        }
    }
}

/// Span of O-line `oidx` of `file`, from its O-word to its last non-blank.
pub(in crate::eval) fn osite_of(file: &Rc<FileIndex>, oidx: u32) -> (u32, u32) {
    let o = &file.olines[oidx as usize];
    let end = o.start + o.line_len();
    // Point at the O-word, not at the indentation before it.
    let lead = file.file.memory().map_or(0, |d| {
        d[o.start as usize..end as usize]
            .iter()
            .take_while(|b| matches!(b, b' ' | b'\t'))
            .count() as u32
    });
    let mut e = end;
    if let Some(d) = file.file.memory() {
        while e > o.start + lead && matches!(d[e as usize - 1], b' ' | b'\t' | b'\r') {
            e -= 1;
        }
    }
    (o.start + lead, e)
}

/// The sub name of a call label, as a key (the label itself when it is
/// already bare).
pub(in crate::eval) fn base_key(label: &Name) -> Name {
    let base = base_name(label);
    if base.len() == label.len() {
        label.clone()
    } else {
        Name::new(base)
    }
}

/// The sub name of a call label: its part after the last `/`.
fn base_name(label: &str) -> &str {
    // Labels are short: a plain search beats setting up a vector one.
    match label.bytes().rposition(|b| b == b'/') {
        Some(i) => &label[i + 1..],
        None => label,
    }
}

impl Flow {
    /// Moves reading to an O-line (`after`: to the line after it).
    pub(in crate::eval) fn goto(&mut self, file: &Rc<FileIndex>, oidx: u32, after: bool) {
        let o = &file.olines[oidx as usize];
        if Rc::ptr_eq(&self.cur.file, file) {
            // The same file (any jump within a body): no count to touch.
            let c = &mut self.cur;
            (c.pos, c.line, c.next_o) = if after {
                (o.next, o.line_idx + 1, oidx as usize + 1)
            } else {
                (o.start, o.line_idx, oidx as usize)
            };
            return;
        }
        self.cur = if after {
            Cursor {
                file: file.clone(),
                pos: o.next,
                line: o.line_idx + 1,
                next_o: oidx as usize + 1,
            }
        } else {
            Cursor {
                file: file.clone(),
                pos: o.start,
                line: o.line_idx,
                next_o: oidx as usize,
            }
        };
    }

    pub(in crate::eval) fn note_loop(&mut self, file: &Rc<FileIndex>, oidx: u32, key: &Name) {
        let line = file.olines[oidx as usize].line_idx;
        // The key is kept as it is (no allocation per pass); the label is
        // cut from it only for a message.
        let same = matches!(&self.last_loop, Some((k, l, f)) if *l == line && k == key && Rc::ptr_eq(f, file));
        if !same {
            self.last_loop = Some((key.clone(), line, file.clone()));
        }
    }
}

impl Flow {
    /// The record of `key` in the innermost frame.
    #[inline]
    pub(in crate::eval) fn label(&mut self, key: &Name) -> Option<LabelRec> {
        self.frame().labels.get(key).copied()
    }

    /// Records control label `key` of O-line `oidx` (on 0-based line
    /// `line`) as opening a block of `kind`, not yet counting.
    #[inline]
    pub(in crate::eval) fn set_label(&mut self, key: &Name, kind: OKind, oidx: u32, line: u32) {
        let rec = LabelRec {
            kind,
            oidx,
            line,
            repeat: -1,
        };
        self.frame().labels.insert(key.clone(), rec);
    }

    /// Whether a repeat loop of the innermost frame is counting.
    #[inline]
    pub(in crate::eval) fn repeat_running(&mut self) -> bool {
        self.frame()
            .labels
            .values()
            .any(|r| r.kind == OKind::Repeat && r.repeat >= 0)
    }

    /// Sets `#<_value>`: the value returned, or 0 and none.
    #[inline]
    pub(in crate::eval) fn set_value(&mut self, v: Option<f64>) {
        self.value = v.unwrap_or(0.0);
        self.value_returned = v.is_some();
    }

    /// Notes the sub `name`, found at `target`, as called (registering it
    /// if it was found in a file or further down).
    #[inline]
    pub(in crate::eval) fn note_called(&mut self, name: &Name, target: &SubRec) {
        self.subs
            .entry(name.clone())
            .or_insert_with(|| target.clone());
        self.called.insert(name.clone());
    }

    /// Enters a call of `kind` to `name` made by O-line `call_oidx`,
    /// returning to `ret`; false (nothing entered) past
    /// [`MAX_CALL_LEVEL`].
    #[inline]
    pub(in crate::eval) fn enter(
        &mut self,
        kind: FrameKind,
        name: Name,
        ret: Cursor,
        call_oidx: u32,
    ) -> bool {
        if self.level() + 1 > MAX_CALL_LEVEL {
            return false;
        }
        let mut f = self.new_frame(kind, name);
        f.ret = Some(ret);
        f.call_oidx = Some(call_oidx);
        self.frames.push(f);
        true
    }

    /// Enters a call to `name` that no O-line makes (a lathe cycle's call
    /// of its contour subroutine), returning to `ret`; false (nothing
    /// entered) past [`MAX_CALL_LEVEL`].
    pub(in crate::eval) fn enter_unsited(&mut self, name: Name, ret: Cursor) -> bool {
        let mut f = self.new_frame(FrameKind::Call, name);
        if self.level() + 1 > MAX_CALL_LEVEL {
            return false;
        }
        f.ret = Some(ret);
        self.frames.push(f);
        true
    }

    /// Gives the frame just entered its arguments: #1-#30 of `params`
    /// saved in it (the caller gets them back on return) and set to
    /// `argv`, and `n_args` when `oword_nargs`.
    #[inline]
    pub(in crate::eval) fn bind_args(
        &mut self,
        params: &mut Params,
        argv: &[f64; 30],
        nargs: f64,
        oword_nargs: bool,
    ) {
        let mut saved = self.saved_pool.pop().unwrap_or_else(|| Box::new([0.0; 30]));
        saved.copy_from_slice(&params.values[1..31]);
        params.values[1..31].copy_from_slice(argv);
        params.set[1..31].fill(true);
        let f = self.frame();
        f.saved = Some(saved);
        if oword_nargs {
            f.locals.insert(Name::new("n_args"), nargs);
        }
    }

    /// Leaves the innermost call: its frame, with the caller's #1-#30 put
    /// back into `params`. [`Flow::resume`] then goes back to the caller.
    #[inline]
    pub(in crate::eval) fn pop_call(&mut self, params: &mut Params) -> Box<Frame> {
        let mut f = self.frames.pop().expect("call frame");
        if let Some(saved) = f.saved.take() {
            params.values[1..31].copy_from_slice(&saved[..]);
            self.saved_pool.push(saved);
        }
        f
    }

    /// Reading goes on where the call of `f`, just left, was made; its
    /// frame is kept for the next call.
    // Hot on every return; left to itself the compiler calls it.
    #[inline(always)]
    pub(in crate::eval) fn resume(&mut self, mut f: Box<Frame>) {
        self.cur = f.ret.take().expect("return cursor");
        self.frame_pool.push(f);
    }
}
