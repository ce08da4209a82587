//! `check` of a subroutine library: a file whose first O-line is
//! `o<name> sub` (with only comments before it). Such a file is not run:
//! its arguments and globals come from its callers, and flattening or
//! checking a caller reports what depends on them. What can be known
//! without a caller is checked here: every line parses, the O-word blocks
//! of each definition open and close in order with matching labels, O-lines
//! carry nothing after their command, and expressions that read no
//! parameter evaluate without error.

use crate::diag::{OWordError, SetupError};
use std::rc::Rc;
use std::sync::Arc;

use crate::diag::{Diagnostic, ErrorKind, Site};
use crate::emit::{Destination, Sink};
use crate::eval::Interp;
use crate::parse::ast::{Expr, ExprKind, Item, Label, LineKind, OKind, ParamRef};
use crate::program::{FileIndex, Loader, SearchPath, SourceFile};
use crate::settings::Settings;

/// An open O-word block of a definition.
struct Open {
    kind: OKind,
    label: String,
    line: u32,
    /// Byte offsets of the line.
    at: (u32, u32),
}

/// How a label is written in messages: `100` or `<name>`.
fn label_text(l: &Label) -> Option<String> {
    match l {
        Label::Static(n) => {
            let s: &str = n.as_ref();
            Some(if s.bytes().all(|b| b.is_ascii_digit()) {
                s.to_string()
            } else {
                format!("<{s}>")
            })
        }
        Label::Dynamic(_) => None,
    }
}

/// Whether an expression reads a parameter (its value then depends on the
/// caller).
fn reads_params(e: &Expr) -> bool {
    match &e.kind {
        ExprKind::Num(_) => false,
        ExprKind::Slot(_) | ExprKind::Param(_) | ExprKind::Exists(_) => true,
        ExprKind::Neg(a) | ExprKind::Func(_, a) => reads_params(a),
        ExprKind::Bin(_, ab, _) | ExprKind::Atan(ab) => reads_params(&ab.0) || reads_params(&ab.1),
        ExprKind::Code(c) => reads_params(&c.tree),
    }
}

/// The state of the structure check of one file.
struct Structure {
    stack: Vec<Open>,
    /// The current definition has a structure error already, or a computed
    /// label: its blocks are not checked further.
    skip: bool,
    /// Where the last error is reported when not on the current line (the
    /// opener of an unclosed block).
    err_at: Option<(u32, u32)>,
}

impl Structure {
    /// Checks one O-line; returns the error it makes, if any.
    fn line(
        &mut self,
        kind: OKind,
        label: Option<String>,
        line: u32,
        at: (u32, u32),
    ) -> Option<ErrorKind> {
        let in_sub = self.stack.iter().any(|o| o.kind == OKind::Sub);
        if kind == OKind::Sub {
            if let Some(outer) = self.stack.iter().find(|o| o.kind == OKind::Sub) {
                let e = ErrorKind::OWord(OWordError::NestedSubDefinition {
                    inner: label.unwrap_or_default(),
                    outer: outer.label.clone(),
                });
                self.skip = true;
                return Some(e);
            }
            self.stack.clear();
            self.skip = label.is_none();
            self.stack.push(Open {
                kind,
                label: label.unwrap_or_default(),
                line,
                at,
            });
            return None;
        }
        if !in_sub {
            // Outside a definition nothing runs when the file is called.
            return None;
        }
        if kind == OKind::EndSub {
            let skip = std::mem::replace(&mut self.skip, false);
            let top = self.stack.pop();
            self.stack.clear();
            if skip {
                return None;
            }
            let label = label?;
            let top = top?;
            if top.kind != OKind::Sub {
                self.err_at = Some(top.at);
                return Some(ErrorKind::OWord(OWordError::UnclosedBlock {
                    label: top.label.clone(),
                    opened: top.kind.name(),
                    line: top.line,
                    closer: closer_of(top.kind),
                }));
            }
            if top.label != label {
                return Some(ErrorKind::OWord(OWordError::LabelMismatch {
                    label,
                    here: "endsub",
                    opened: "sub",
                    line: top.line,
                }));
            }
            return None;
        }
        if self.skip {
            return None;
        }
        let Some(label) = label else {
            self.skip = true;
            return None;
        };
        let err = self.control(kind, &label, line, at);
        if err.is_some() {
            self.skip = true;
        }
        err
    }

    fn control(
        &mut self,
        kind: OKind,
        label: &str,
        line: u32,
        at: (u32, u32),
    ) -> Option<ErrorKind> {
        use OKind::*;
        let top_is = |s: &Structure, k: &[OKind]| {
            s.stack
                .last()
                .is_some_and(|o| o.label == label && k.contains(&o.kind))
        };
        let mismatch =
            |s: &Structure, here: OKind| match s.stack.iter().rev().find(|o| o.label == label) {
                Some(o) => ErrorKind::OWord(OWordError::LabelMismatch {
                    label: label.to_string(),
                    here: here.name(),
                    opened: o.kind.name(),
                    line: o.line,
                }),
                None => ErrorKind::OWord(OWordError::UndefinedLabel {
                    label: label.to_string(),
                }),
            };
        match kind {
            // The `while` of a do-while closes its `do`.
            While if top_is(self, &[Do]) => {
                self.stack.pop();
                None
            }
            If | Do | Repeat | While => {
                self.stack.push(Open {
                    kind,
                    label: label.to_string(),
                    line,
                    at,
                });
                None
            }
            ElseIf | Else => (!top_is(self, &[If])).then(|| mismatch(self, kind)),
            EndIf | EndWhile | EndRepeat => {
                let opener = match kind {
                    EndIf => If,
                    EndWhile => While,
                    _ => Repeat,
                };
                if top_is(self, &[opener]) {
                    self.stack.pop();
                    None
                } else {
                    Some(mismatch(self, kind))
                }
            }
            Break | Continue => {
                let in_loop = self
                    .stack
                    .iter()
                    .any(|o| o.label == label && matches!(o.kind, While | Do | Repeat));
                (!in_loop).then(|| mismatch(self, kind))
            }
            Return => {
                let sub = self.stack.first().map(|o| o.label.as_str());
                (sub != Some(label)).then(|| mismatch(self, kind))
            }
            Sub | EndSub | Call | Bare => None,
        }
    }
}

fn closer_of(kind: OKind) -> &'static str {
    match kind {
        OKind::If => "endif",
        OKind::While => "endwhile",
        OKind::Do => "while",
        OKind::Repeat => "endrepeat",
        _ => "endsub",
    }
}

/// Checks a subroutine library file; returns its diagnostics.
pub(crate) fn check_library(
    source: Arc<SourceFile>,
    settings: &Settings,
    search: &SearchPath,
) -> Vec<Diagnostic> {
    let mut out = Vec::new();
    let file = source.clone();
    let index = Rc::new(FileIndex::build(source, settings.named_params_2007));
    // An evaluator for the expressions that read no parameter.
    let mut interp = Sink::new(Destination::Discard).ok().map(|sink| {
        let loader = Loader::new(search.clone(), None).named2007(settings.named_params_2007);
        Interp::new(settings, loader, index.clone(), sink)
    });
    let mut parser = index.parser();
    let mut st = Structure {
        stack: Vec::new(),
        skip: false,
        err_at: None,
    };
    let site = |a: u32, b: u32| Some(Site::new(&file, a, b));
    let scanned = file.scan_lines(|idx, start, raw, terminated| {
        let line_end = start + raw.len() as u32;
        let line = match parser.parse(raw, terminated) {
            Ok(l) => l,
            Err(e) => {
                out.push(*Diagnostic::error(
                    e.kind,
                    site(start + e.span.start, start + e.span.end),
                ));
                return;
            }
        };
        let mut exprs: Vec<&Expr> = Vec::new();
        match &line.kind {
            LineKind::O(o) => {
                if let Some(e) = st.line(o.kind, label_text(&o.label), idx + 1, (start, line_end)) {
                    let (a, b) = st.err_at.take().unwrap_or((start, line_end));
                    out.push(*Diagnostic::error(e, site(a, b)));
                }
                if let Some(err) = &o.exec_error {
                    let (k, span) = &**err;
                    out.push(*Diagnostic::error(
                        k.clone(),
                        site(start + span.start, start + span.end),
                    ));
                }
                exprs.extend(o.expr.iter());
                exprs.extend(o.args.iter());
            }
            LineKind::Items(items) => {
                for it in items {
                    match it {
                        Item::Word(w) => exprs.push(&w.value),
                        Item::Assign(a) => {
                            if let ParamRef::Numbered(i) = &a.target {
                                exprs.push(i);
                            }
                            exprs.push(&a.value);
                        }
                        Item::Comment(_) => {}
                    }
                }
            }
            _ => {}
        }
        if let Some(interp) = interp.as_mut() {
            for e in exprs {
                if reads_params(e) {
                    continue;
                }
                if let Err((k, span)) = interp.eval_constant(e) {
                    out.push(*Diagnostic::error(
                        k,
                        site(start + span.start, start + span.end),
                    ));
                }
            }
        }
    });
    if let Err(e) = scanned {
        out.push(*Diagnostic::error(
            ErrorKind::Setup(SetupError::Io {
                path: file.path.clone(),
                message: e.to_string(),
            }),
            None,
        ));
    }
    if let Some(sub) = st.stack.first().filter(|o| o.kind == OKind::Sub) {
        out.push(*Diagnostic::error(
            ErrorKind::OWord(OWordError::UnterminatedSub {
                name: sub.label.trim_matches(['<', '>']).to_string(),
            }),
            site(sub.at.0, sub.at.1),
        ));
    }
    out
}
