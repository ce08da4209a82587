//! Typed syntax tree of one line. Spans are byte offsets relative to the start
//! of the raw line; the line knows its own offset in the file.

use super::Name;

pub(crate) use crate::source::Span;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BinOp {
    Pow,
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

impl BinOp {
    /// Binding strength; every level is left-associative.
    pub fn precedence(self) -> u8 {
        use BinOp::*;
        match self {
            Pow => 6,
            Mul | Div | Mod => 5,
            Add | Sub => 4,
            Eq | Ne | Gt | Ge | Lt | Le => 3,
            And | Or | Xor => 2,
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Func {
    Abs,
    Acos,
    Asin,
    Cos,
    Exp,
    Fix,
    Fup,
    Ln,
    Round,
    Sin,
    Sqrt,
    Tan,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Expr {
    pub kind: ExprKind,
    pub span: Span,
}

#[derive(Debug, Clone, PartialEq)]
pub enum ExprKind {
    Num(f64),
    /// `#7`: a numbered parameter whose index is a whole literal from 1 to
    /// 4999 (the plain parameters), resolved when the line is parsed.
    Slot(u16),
    Param(Box<ParamRef>),
    Neg(Box<Expr>),
    /// The flag marks a bracketed (value-level) result, which is checked for
    /// NaN and infinity; intermediate results are not.
    Bin(BinOp, Box<(Expr, Expr)>, bool),
    Func(Func, Box<Expr>),
    Atan(Box<(Expr, Expr)>),
    Exists(Box<ParamRef>),
    /// A value expression with its compiled form (only at the top of a
    /// word, assignment or O-line value).
    Code(Box<super::code::Code>),
}

/// A parameter reference: `#<integer value>` or `#<name>`.
#[derive(Debug, Clone, PartialEq)]
pub enum ParamRef {
    Numbered(Expr),
    /// Lower-cased name without blanks; globals start with `_`.
    Named(Name),
}

#[derive(Debug, Clone, PartialEq)]
pub struct Word {
    pub letter: u8,
    /// The whole word, letter included.
    pub span: Span,
    pub value: Expr,
    /// The value is a plain number as written: output keeps its text.
    pub literal: bool,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Assign {
    pub target: ParamRef,
    pub target_span: Span,
    pub value: Expr,
    pub span: Span,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CommentKind {
    Plain,
    Msg,
    Debug,
    Print,
    Log,
    LogOpen,
    LogAppend,
    LogClose,
    Abort,
    /// `py,`, `pyrun,`, `pyreload`: Python plug-in comments.
    Python,
    /// `;` comment: never active.
    Semicolon,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Comment {
    pub kind: CommentKind,
    /// The whole comment including `(` `)` or `;`.
    pub span: Span,
    /// For active comments: the text after the keyword's comma.
    pub body: Span,
}

#[derive(Debug, Clone, PartialEq)]
pub enum Item {
    Word(Word),
    Assign(Assign),
    Comment(Comment),
}

#[derive(Debug, Clone, PartialEq)]
pub enum Label {
    /// `o100` (as "100"), `o<name>`.
    Static(Name),
    /// `o[#1+2]`, `o#1`: evaluated when the line is read.
    Dynamic(Expr),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum OKind {
    Sub,
    EndSub,
    Call,
    Do,
    While,
    Repeat,
    If,
    ElseIf,
    Else,
    EndIf,
    Break,
    Continue,
    EndWhile,
    EndRepeat,
    Return,
    Bare,
}

impl OKind {
    pub fn name(self) -> &'static str {
        use OKind::*;
        match self {
            Sub => "sub",
            EndSub => "endsub",
            Call => "call",
            Do => "do",
            While => "while",
            Repeat => "repeat",
            If => "if",
            ElseIf => "elseif",
            Else => "else",
            EndIf => "endif",
            Break => "break",
            Continue => "continue",
            EndWhile => "endwhile",
            EndRepeat => "endrepeat",
            Return => "return",
            Bare => "O",
        }
    }

    /// Control labels are scoped per subroutine; sub/call/return are global.
    pub fn is_control(self) -> bool {
        !matches!(
            self,
            OKind::Sub | OKind::EndSub | OKind::Call | OKind::Return | OKind::Bare
        )
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct OLine {
    pub label: Label,
    pub label_span: Span,
    pub kind: OKind,
    /// Condition, count or return value.
    pub expr: Option<Expr>,
    /// Call arguments.
    pub args: Vec<Expr>,
    /// Carries a comment that acts on other lines (`(debug,…)`, `(msg,…)`,
    /// …); LinuxCNC ignores it on an O-line. Plain comments do not count.
    pub active_comment: bool,
    /// An error that only counts when the line is executed (trailing text,
    /// missing bracket).
    /// Boxed: rare, and an O-line stays small (a file of a million labels
    /// keeps a million of them).
    pub exec_error: Option<Box<(crate::diag::ErrorKind, Span)>>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct M98Line {
    pub p: Option<Expr>,
    pub l: Option<Expr>,
    /// Every item on the line (read, but only P and L are used).
    pub items: Vec<Item>,
}

#[derive(Debug, Clone, PartialEq)]
pub enum LineKind {
    /// Nothing but blanks (or only a line number / block delete).
    Blank,
    /// A `%` delimiter line.
    Percent,
    Items(Vec<Item>),
    O(OLine),
    M98(M98Line),
}

#[derive(Debug, Clone, PartialEq)]
pub struct Line {
    pub kind: LineKind,
    pub block_delete: bool,
    pub line_number: Option<Span>,
}
