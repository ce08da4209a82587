//! Value expressions compiled to a flat list of stack operations. The
//! evaluator runs the list on its fast path and falls back to the tree, kept
//! beside it, whenever the list gives up (an error, a warning, a parameter
//! that is not a plain stored value): the tree stays the definition.

use super::Name;
use super::ast::{BinOp, Expr, ExprKind, Func, ParamRef};

/// Deepest stack a compiled expression may use.
pub(crate) const STACK: usize = 8;

/// One stack operation. Reads push a value and give up unless it is finite.
/// A binary operation whose right operand is a read takes it directly
/// (`BinK`, `BinS`, `BinN`), and `checked` says its result must be finite
/// (a bracketed result).
#[derive(Debug, Clone, PartialEq)]
pub enum Op {
    Num(f64),
    /// A plain numbered parameter, `#1` to `#4999`.
    Slot(u16),
    /// The value on top is a parameter number: it is replaced by the value
    /// of that parameter.
    Index,
    Named(Name),
    Neg,
    /// The two values on top.
    Bin(BinOp, bool),
    /// The value on top and a number.
    BinK(BinOp, bool, f64),
    /// The value on top and a numbered parameter.
    BinS(BinOp, bool, u16),
    /// The value on top and a named parameter.
    BinN(BinOp, bool, Name),
    /// A function of the value on top; its result must be finite.
    Func(Func),
    /// `ATAN[y]/[x]` of the two values on top; the result must be finite.
    Atan,
}

/// A compiled expression and the expression it was compiled from.
#[derive(Debug, Clone, PartialEq)]
pub struct Code {
    pub ops: Box<[Op]>,
    pub tree: Expr,
}

/// The value expression `e`, wrapped with its compiled form when it has
/// operations to gain from (plain numbers and single reads stay as they are,
/// and so does anything the stack machine does not cover).
pub(crate) fn compile(e: Expr) -> Expr {
    let worth = match &e.kind {
        ExprKind::Bin(..) | ExprKind::Neg(_) | ExprKind::Func(..) | ExprKind::Atan(_) => true,
        ExprKind::Param(p) => matches!(**p, ParamRef::Numbered(_)),
        _ => false,
    };
    if !worth {
        return e;
    }
    let mut ops = Vec::new();
    let mut depth = 0;
    let mut max = 0;
    if !emit(&e, &mut ops, &mut depth, &mut max) || max > STACK {
        return e;
    }
    Expr {
        span: e.span,
        kind: ExprKind::Code(Box::new(Code {
            ops: ops.into_boxed_slice(),
            tree: e,
        })),
    }
}

/// Appends the operations of `e`; false if some part is not covered.
fn emit(e: &Expr, ops: &mut Vec<Op>, depth: &mut usize, max: &mut usize) -> bool {
    let mut push = |ops: &mut Vec<Op>, op: Op, delta: isize| {
        ops.push(op);
        *depth = depth.wrapping_add_signed(delta);
        *max = (*max).max(*depth);
    };
    match &e.kind {
        ExprKind::Num(v) => {
            if !v.is_finite() {
                return false;
            }
            push(ops, Op::Num(*v), 1);
        }
        ExprKind::Slot(i) => push(ops, Op::Slot(*i), 1),
        ExprKind::Param(p) => match &**p {
            ParamRef::Named(n) => push(ops, Op::Named(n.clone()), 1),
            ParamRef::Numbered(index) => {
                if !emit(index, ops, depth, max) {
                    return false;
                }
                ops.push(Op::Index);
            }
        },
        ExprKind::Neg(inner) => {
            if !emit(inner, ops, depth, max) {
                return false;
            }
            ops.push(Op::Neg);
        }
        ExprKind::Bin(op, operands, checked) => {
            if !emit(&operands.0, ops, depth, max) {
                return false;
            }
            // A read on the right is taken by the operation itself.
            let fused = match &operands.1.kind {
                ExprKind::Num(v) if v.is_finite() => Some(Op::BinK(*op, *checked, *v)),
                ExprKind::Slot(i) => Some(Op::BinS(*op, *checked, *i)),
                ExprKind::Param(p) => match &**p {
                    ParamRef::Named(n) => Some(Op::BinN(*op, *checked, n.clone())),
                    ParamRef::Numbered(_) => None,
                },
                _ => None,
            };
            match fused {
                Some(f) => ops.push(f),
                None => {
                    if !emit(&operands.1, ops, depth, max) {
                        return false;
                    }
                    *depth -= 1;
                    ops.push(Op::Bin(*op, *checked));
                }
            }
        }
        ExprKind::Func(f, arg) => {
            if !emit(arg, ops, depth, max) {
                return false;
            }
            ops.push(Op::Func(*f));
        }
        ExprKind::Atan(args) => {
            if !emit(&args.0, ops, depth, max) || !emit(&args.1, ops, depth, max) {
                return false;
            }
            *depth -= 1;
            ops.push(Op::Atan);
        }
        ExprKind::Exists(_) | ExprKind::Code(_) => return false,
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parse::ast::{Item, LineKind};

    /// The compiled form of the first word's value on a line, if any.
    fn ops_of(line: &str) -> Option<Vec<Op>> {
        let l = crate::parse::LineParser::default()
            .parse(line.as_bytes(), true)
            .expect("parses");
        let LineKind::Items(items) = l.kind else {
            panic!("not a line of items")
        };
        let Item::Word(w) = &items[0] else {
            panic!("not a word")
        };
        match &w.value.kind {
            ExprKind::Code(c) => Some(c.ops.to_vec()),
            _ => None,
        }
    }

    #[test]
    fn compiled_forms() {
        use BinOp::*;
        let n = |s: &str| Op::Named(Name::new(s));
        let cases: &[(&str, Option<Vec<Op>>)] = &[
            ("X1.5", None),
            ("X#3", None),
            ("X#<a>", None),
            (
                "X[1 + #2]",
                Some(vec![Op::Num(1.0), Op::BinS(Add, true, 2)]),
            ),
            (
                "X[#<a> * [2 - #1]]",
                Some(vec![
                    n("a"),
                    Op::Num(2.0),
                    Op::BinS(Sub, true, 1),
                    Op::Bin(Mul, true),
                ]),
            ),
            ("X-#<a>", Some(vec![n("a"), Op::Neg])),
            ("X##2", Some(vec![Op::Slot(2), Op::Index])),
            (
                "X[1 + 2 * 3]",
                Some(vec![
                    Op::Num(1.0),
                    Op::Num(2.0),
                    Op::BinK(Mul, false, 3.0),
                    Op::Bin(Add, true),
                ]),
            ),
            (
                "X[#1 - #<b>]",
                Some(vec![Op::Slot(1), Op::BinN(Sub, true, Name::new("b"))]),
            ),
            (
                "X[#1 / ##2]",
                Some(vec![
                    Op::Slot(1),
                    Op::Slot(2),
                    Op::Index,
                    Op::Bin(Div, true),
                ]),
            ),
            ("XSQRT[#1]", Some(vec![Op::Slot(1), Op::Func(Func::Sqrt)])),
            (
                "XATAN[1]/[#2]",
                Some(vec![Op::Num(1.0), Op::Slot(2), Op::Atan]),
            ),
            ("X[EXISTS[#<a>] + 1]", None),
        ];
        for (line, want) in cases {
            assert_eq!(&ops_of(line), want, "{line}");
        }
    }

    #[test]
    fn deep_expressions_stay_trees() {
        let deep = format!("X{}1{}", "[1 + ".repeat(20), "]".repeat(20));
        assert!(ops_of(&deep).is_none());
        let shallow = format!("X{}1{}", "[1 + ".repeat(5), "]".repeat(5));
        assert!(ops_of(&shallow).is_some());
    }
}
