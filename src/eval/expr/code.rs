//! The fast path of expression evaluation: runs a compiled expression on a
//! small stack. It only reads, and gives up (`None`) on anything but plain
//! finite values, so that the tree evaluation, run instead, reports every
//! error and warning exactly as it would have.

use crate::parse::code::{Op, STACK};
use crate::parse::integer_value;

use crate::eval::expr::params::MAX_PARAM;
use crate::eval::expr::{Scope, TOLERANCE_EQUAL, binary, modulo, unary};
use crate::parse::ast::{BinOp, Span};

/// A binary operation, `None` where it fails (division by zero, a negative
/// base to a fractional power).
#[inline(always)]
fn apply(op: BinOp, a: f64, c: f64) -> Option<f64> {
    Some(match op {
        BinOp::Mul => a * c,
        BinOp::Add => a + c,
        BinOp::Sub => a - c,
        BinOp::Lt => f64::from(a < c),
        BinOp::Gt => f64::from(a > c),
        BinOp::Eq => f64::from((a - c).abs() < TOLERANCE_EQUAL),
        BinOp::Mod => modulo(a, c),
        _ => binary(op, a, c, Span::default()).ok()?,
    })
}

/// The value of a compiled expression, or `None` to evaluate the tree.
#[inline]
pub(in crate::eval) fn run_code(scope: &impl Scope, ops: &[Op]) -> Option<f64> {
    // The most common shape, `[a op b]` of two readings, without the
    // stack.
    if let [a, b @ (Op::BinK(..) | Op::BinS(..) | Op::BinN(..))] = ops
        && let Some(a) = leaf(scope, a)
    {
        return binary_op(scope, a?, b);
    }
    run_stack(scope, ops)
}

/// The value pushed by a reading (`None` if `op` is not one; `Some(None)`
/// if the reading gives up).
#[inline(always)]
fn leaf(scope: &impl Scope, op: &Op) -> Option<Option<f64>> {
    match op {
        Op::Num(v) => Some(Some(*v)),
        Op::Slot(i) => Some(scope.params().stored(*i as usize)),
        Op::Named(name) => Some(named(scope, name)),
        _ => None,
    }
}

/// A binary operation with its right operand read in place applied to
/// `a`; `None` for any other operation or when it gives up.
#[inline(always)]
fn binary_op(scope: &impl Scope, a: f64, op: &Op) -> Option<f64> {
    let (op, checked, c) = match op {
        Op::BinK(op, checked, k) => (*op, *checked, *k),
        Op::BinS(op, checked, i) => (*op, *checked, scope.params().stored(*i as usize)?),
        Op::BinN(op, checked, name) => (*op, *checked, named(scope, name)?),
        _ => return None,
    };
    let v = apply(op, a, c)?;
    (!checked || v.is_finite()).then_some(v)
}

/// A named parameter's stored value, if set and finite (the reading
/// `read_named` does first).
#[inline(always)]
fn named(scope: &impl Scope, name: &crate::parse::Name) -> Option<f64> {
    let globals = &scope.params().globals;
    let table = if name.starts_with('_') {
        globals
    } else {
        scope.locals().unwrap_or(globals)
    };
    let v = *table.get(name)?;
    v.is_finite().then_some(v)
}

/// The general case: every operation on a small stack.
fn run_stack(scope: &impl Scope, ops: &[Op]) -> Option<f64> {
    // Compiling checked that the stack never goes deeper than `STACK`
    // nor below empty; the masks only spare the bounds checks (a wrong
    // list would give `None` or a wrong value, never a panic).
    const MASK: usize = STACK - 1;
    const _: () = assert!(STACK.is_power_of_two());
    let mut stack = [0f64; STACK];
    let mut n = 0usize;
    for op in ops {
        match op {
            Op::Num(v) => {
                stack[n & MASK] = *v;
                n += 1;
            }
            Op::Slot(i) => {
                stack[n & MASK] = scope.params().stored(*i as usize)?;
                n += 1;
            }
            Op::Named(name) => {
                stack[n & MASK] = named(scope, name)?;
                n += 1;
            }
            Op::Index => {
                let top = &mut stack[n.wrapping_sub(1) & MASK];
                let i = integer_value(*top).ok()?;
                if i < 1 || i >= MAX_PARAM as i64 {
                    return None;
                }
                *top = scope.params().stored(i as usize)?;
            }
            Op::Neg => {
                let top = &mut stack[n.wrapping_sub(1) & MASK];
                *top = -*top;
            }
            Op::Bin(op, checked) => {
                n = n.wrapping_sub(1);
                let c = stack[n & MASK];
                let top = &mut stack[n.wrapping_sub(1) & MASK];
                *top = apply(*op, *top, c)?;
                if *checked && !top.is_finite() {
                    return None;
                }
            }
            Op::BinK(..) | Op::BinS(..) | Op::BinN(..) => {
                let top = &mut stack[n.wrapping_sub(1) & MASK];
                *top = binary_op(scope, *top, op)?;
            }
            Op::Func(f) => {
                let top = &mut stack[n.wrapping_sub(1) & MASK];
                let v = unary(*f, *top, Span::default()).ok()?;
                if !v.is_finite() {
                    return None;
                }
                *top = v;
            }
            Op::Atan => {
                n = n.wrapping_sub(1);
                let x = stack[n & MASK];
                let top = &mut stack[n.wrapping_sub(1) & MASK];
                let v = crate::eval::expr::degrees::to_degrees(top.atan2(x));
                if !v.is_finite() {
                    return None;
                }
                *top = v;
            }
        }
    }
    if n == 1 { Some(stack[0]) } else { None }
}
