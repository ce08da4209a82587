//! Expression evaluation with the reference's rules: degrees, EQ/NE
//! tolerance, MOD sign, ROUND half away from zero, domain errors, and the
//! NaN/infinity check on every value (not on intermediate results).

pub(super) mod code;
pub(super) mod degrees;
pub(super) mod message;
pub(super) mod named;
pub(crate) mod params;

use crate::diag::ExprError;
use crate::diag::{ErrorKind, WarningKind};
use crate::fx_hasher::FxMap;
use crate::parse::Name;
use crate::parse::ast::{BinOp, Expr, ExprKind, Func, ParamRef, Span};
use crate::parse::integer_value;
use crate::rules::Modes;

use crate::eval::expr::params::{MAX_PARAM, ParamClass, Params, classify};
use crate::settings::Settings;

/// EQ/NE tolerance of LinuxCNC 2.9.
pub(super) const TOLERANCE_EQUAL: f64 = 0.0001;

/// An evaluation error: its kind and the span it is reported at. Boxed, so
/// that a result is two words wide and comes back in registers.
pub(super) type Fault = Box<(ErrorKind, Span)>;

pub(super) type EvalResult = Result<f64, Fault>;

/// A fault of `kind` at `span`.
#[cold]
pub(super) fn fault(kind: ErrorKind, span: Span) -> Fault {
    Box::new((kind, span))
}

fn check(v: f64, span: Span) -> EvalResult {
    if v.is_nan() {
        Err(fault(ErrorKind::Expr(ExprError::NotANumber), span))
    } else if v.is_infinite() {
        Err(fault(ErrorKind::Expr(ExprError::Infinity), span))
    } else {
        Ok(v)
    }
}

fn b(x: bool) -> f64 {
    if x { 1.0 } else { 0.0 }
}

/// `binary` with the plain arithmetic and comparisons inline; the rest
/// (which may fail or call libm) out of line.
#[inline(always)]
fn binary_fast(op: BinOp, a: f64, c: f64, span: Span) -> EvalResult {
    match op {
        BinOp::Mul => Ok(a * c),
        BinOp::Add => Ok(a + c),
        BinOp::Sub => Ok(a - c),
        BinOp::Lt => Ok(b(a < c)),
        BinOp::Gt => Ok(b(a > c)),
        BinOp::Eq => Ok(b((a - c).abs() < TOLERANCE_EQUAL)),
        _ => binary(op, a, c, span),
    }
}

/// Binary operation; `span` is where a domain error is reported.
#[inline(never)]
pub(super) fn binary(op: BinOp, a: f64, c: f64, span: Span) -> EvalResult {
    Ok(match op {
        BinOp::Pow => {
            if a < 0.0 && c.floor() != c {
                return Err(fault(ErrorKind::Expr(ExprError::NegativePower), span));
            }
            a.powf(c)
        }
        BinOp::Mul => a * c,
        BinOp::Div => {
            if c == 0.0 {
                return Err(fault(ErrorKind::Expr(ExprError::DivideByZero), span));
            }
            a / c
        }
        BinOp::Mod => modulo(a, c),
        BinOp::Add => a + c,
        BinOp::Sub => a - c,
        BinOp::Eq => b((a - c).abs() < TOLERANCE_EQUAL),
        BinOp::Ne => b((a - c).abs() >= TOLERANCE_EQUAL),
        BinOp::Gt => b(a > c),
        BinOp::Ge => b(a >= c),
        BinOp::Lt => b(a < c),
        BinOp::Le => b(a <= c),
        BinOp::And => b(a != 0.0 && c != 0.0),
        BinOp::Or => b(a != 0.0 || c != 0.0),
        BinOp::Xor => b((a != 0.0) != (c != 0.0)),
    })
}

/// `a MOD c`: the remainder made non-negative by adding `|c|`.
#[inline]
pub(super) fn modulo(a: f64, c: f64) -> f64 {
    let (ai, ci) = (a as i64, c as i64);
    let mut r =
        if ai as f64 == a && ci as f64 == c && ci != 0 && a.abs() < 9.0e15 && c.abs() < 9.0e15 {
            // Whole numbers: the remainder in integers is exact, as the
            // floating-point one is; only its zero keeps the sign of a.
            let r = (ai % ci) as f64;
            if r == 0.0 && a.is_sign_negative() {
                -0.0
            } else {
                r
            }
        } else {
            a % c
        };
    if r < 0.0 {
        r += c.abs();
    }
    r
}

/// One-argument function.
pub(super) fn unary(f: Func, x: f64, span: Span) -> EvalResult {
    Ok(match f {
        // As the reference computes it: -0 stays -0 (ATAN cares).
        Func::Abs => {
            if x < 0.0 {
                -x
            } else {
                x
            }
        }
        Func::Acos => {
            if !(-1.0..=1.0).contains(&x) {
                return Err(fault(ErrorKind::Expr(ExprError::AcosRange), span));
            }
            crate::eval::expr::degrees::to_degrees(x.acos())
        }
        Func::Asin => {
            if !(-1.0..=1.0).contains(&x) {
                return Err(fault(ErrorKind::Expr(ExprError::AsinRange), span));
            }
            crate::eval::expr::degrees::to_degrees(x.asin())
        }
        Func::Cos => crate::eval::expr::degrees::cos_deg(x),
        Func::Sin => crate::eval::expr::degrees::sin_deg(x),
        Func::Tan => crate::eval::expr::degrees::tan_deg(x),
        Func::Exp => x.exp(),
        Func::Fix => x.floor(),
        Func::Fup => x.ceil(),
        Func::Ln => {
            if x <= 0.0 {
                return Err(fault(ErrorKind::Expr(ExprError::LnDomain), span));
            }
            x.ln()
        }
        Func::Round => round_half_away(x),
        Func::Sqrt => {
            if x < 0.0 {
                return Err(fault(ErrorKind::Expr(ExprError::SqrtNegative), span));
            }
            x.sqrt()
        }
    })
}

/// `(int)(x + (x < 0 ? -0.5 : 0.5))` as x86 computes it.
pub(super) fn round_half_away(x: f64) -> f64 {
    let t = (x + if x < 0.0 { -0.5 } else { 0.5 }).trunc();
    if !(-2147483648.0..2147483648.0).contains(&t) || t.is_nan() {
        -2147483648.0
    } else {
        // Through an integer there: a zero has no sign.
        t + 0.0
    }
}

/// `(int)nearbyint(x)`: half to even, overflow to INT_MIN.
pub(super) fn round_half_even_int(x: f64) -> i64 {
    let r = x.round_ties_even();
    if !(-2147483648.0..2147483648.0).contains(&r) {
        i32::MIN as i64
    } else {
        r as i64
    }
}

/// What evaluating an expression reads besides the expression itself, and
/// the one thing it may change: the warnings. The evaluator implements it
/// over its parts (`eval/exec/expr.rs`); the evaluation here sees nothing
/// else.
pub(in crate::eval) trait Scope {
    /// The settings (compiled expressions, `--zero-start`, the INI).
    fn settings(&self) -> &Settings;
    /// The numbered parameters and the global named ones.
    fn params(&self) -> &Params;
    /// The named parameters local to the call being run; `None` in the
    /// main program, whose locals are the globals.
    fn locals(&self) -> Option<&FxMap<Name, f64>>;
    /// The call level (0 in the main program).
    fn call_level(&self) -> usize;
    /// Whether a subroutine definition is being read (an unset named
    /// parameter then reads 0).
    fn defining(&self) -> bool;
    /// The value the last call returned (`#<_value>`), and whether it
    /// returned one (`#<_value_returned>`).
    fn returned(&self) -> (f64, bool);
    /// The 0-based index of the line being run.
    fn line_idx(&self) -> u32;
    /// The machine model's modal state.
    fn modes(&self) -> &Modes;
    /// The tool in the spindle and the selected one, if known.
    fn tools(&self) -> (Option<f64>, Option<f64>);
    /// The pockets of those tools, if known.
    fn pockets(&self) -> Option<(f64, f64)>;
    /// The current position on an axis, or why it is unknown.
    fn position(&self, axis: usize, span: Span) -> EvalResult;
    /// The absolute machine position on an axis with the tool length
    /// offset, if known.
    fn abs_position(&self, axis: usize) -> Option<f64>;
    /// A tool-data parameter #5400..#5413, if known.
    fn tool_param(&self, i: usize) -> Option<f64>;
    /// The line of the last G38 probe that left its results unknown.
    fn probed_at(&self) -> Option<u32>;
    /// How to make the tool data of the tool in the spindle known.
    fn tool_data_hint(&self) -> String;
    /// A read of the position at `span` of the line (a warning if the
    /// standalone reference's position departed from the machine's).
    fn note_position_read(&mut self, span: Span);
    /// A read of the current tool (`data`: of its data) at `span` of the
    /// line (a warning after an M61 the standalone reference ignores).
    fn note_tool_read(&mut self, span: Span, data: bool);
    /// Warning `kind` at `span` of the line being run.
    fn warn_in_line(&mut self, kind: WarningKind, span: Span);
}

/// Evaluates a value (checked for NaN and infinity).
pub(in crate::eval) fn eval(scope: &mut impl Scope, e: &Expr) -> EvalResult {
    match &e.kind {
        ExprKind::Num(v) => check(*v, e.span),
        ExprKind::Slot(i) => {
            let i = *i as usize;
            let params = scope.params();
            if params.set[i] {
                return check(params.values[i], e.span);
            }
            eval_rare(scope, e)
        }
        ExprKind::Param(p) if let ParamRef::Named(name) = &**p => {
            let v = named::read_named(scope, name, e.span)?;
            check(v, e.span)
        }
        ExprKind::Code(c) => eval_code(scope, c),
        ExprKind::Neg(inner) => Ok(-eval(scope, inner)?),
        ExprKind::Bin(op, operands, checked) => {
            let a = eval_operand(scope, &operands.0)?;
            let c = eval_operand(scope, &operands.1)?;
            let v = binary_fast(*op, a, c, e.span)?;
            if *checked { check(v, e.span) } else { Ok(v) }
        }
        _ => eval_rare(scope, e),
    }
}

/// `eval` with its most common cases, a literal, a set parameter and a
/// compiled expression, done in the caller.
#[inline(always)]
pub(in crate::eval) fn eval_value(scope: &mut impl Scope, e: &Expr) -> EvalResult {
    match &e.kind {
        ExprKind::Num(v) => check(*v, e.span),
        ExprKind::Slot(i) if scope.params().set[*i as usize] => {
            check(scope.params().values[*i as usize], e.span)
        }
        ExprKind::Code(c) => eval_code(scope, c),
        _ => eval(scope, e),
    }
}

/// A compiled expression: the stack machine, or the tree where it gives
/// up (or is switched off).
#[inline(always)]
fn eval_code(scope: &mut impl Scope, c: &crate::parse::code::Code) -> EvalResult {
    match scope.settings().compiled_exprs {
        true => match code::run_code(scope, &c.ops) {
            Some(v) => Ok(v),
            None => eval(scope, &c.tree),
        },
        false => eval(scope, &c.tree),
    }
}

/// The less common expression kinds, kept out of `eval` so that its
/// frame stays small (`eval` does the others itself).
#[inline(never)]
fn eval_rare(scope: &mut impl Scope, e: &Expr) -> EvalResult {
    match &e.kind {
        ExprKind::Num(_) | ExprKind::Neg(_) | ExprKind::Bin(..) | ExprKind::Code(_) => {
            eval(scope, e)
        }
        ExprKind::Slot(i) => {
            let v = read_numbered(scope, *i as usize, e.span)?;
            check(v, e.span)
        }
        ExprKind::Param(p) => {
            let v = read_param(scope, p, e.span)?;
            check(v, e.span)
        }
        ExprKind::Func(f, arg) => {
            let x = eval(scope, arg)?;
            check(unary(*f, x, e.span)?, e.span)
        }
        ExprKind::Atan(args) => {
            let y = eval(scope, &args.0)?;
            let x = eval(scope, &args.1)?;
            check(crate::eval::expr::degrees::to_degrees(y.atan2(x)), e.span)
        }
        ExprKind::Exists(p) => Ok(b(param_exists(scope, p, e.span)?)),
    }
}

/// Operand of a binary operation: intermediate results pass unchecked.
fn eval_operand(scope: &mut impl Scope, e: &Expr) -> EvalResult {
    match &e.kind {
        ExprKind::Bin(op, operands, false) => {
            let a = eval_operand(scope, &operands.0)?;
            let c = eval_operand(scope, &operands.1)?;
            binary_fast(*op, a, c, e.span)
        }
        _ => eval(scope, e),
    }
}

/// Index of a numbered parameter reference.
pub(in crate::eval) fn param_index(scope: &mut impl Scope, index: &Expr) -> Result<usize, Fault> {
    // A literal in range (`#2 = ...`), the common case.
    if let ExprKind::Num(v) = index.kind {
        let i = v as usize;
        if i as f64 == v && (1..MAX_PARAM).contains(&i) {
            return Ok(i);
        }
    }
    let v = eval(scope, index)?;
    let i = integer_value(v).map_err(|k| fault(k, index.span))?;
    if i < 1 || i >= MAX_PARAM as i64 {
        return Err(fault(
            ErrorKind::Expr(ExprError::ParamOutOfRange { index: i }),
            index.span,
        ));
    }
    Ok(i as usize)
}

fn read_param(scope: &mut impl Scope, p: &ParamRef, span: Span) -> EvalResult {
    match p {
        ParamRef::Numbered(index) => {
            let i = param_index(scope, index)?;
            read_numbered(scope, i, span)
        }
        ParamRef::Named(name) => named::read_named(scope, name, span),
    }
}

pub(in crate::eval) fn read_numbered(scope: &mut impl Scope, i: usize, span: Span) -> EvalResult {
    // Plain parameters the program has assigned: the common case.
    if i < 5000 && scope.params().set[i] {
        return Ok(scope.params().values[i]);
    }
    if let ParamClass::Position(axis) = classify(i)
        && !scope.params().set[i]
    {
        scope.note_position_read(span);
        return scope.position(axis, span);
    }
    if let ParamClass::Refreshed(what, why) = classify(i) {
        if scope.settings().zero_start {
            return Ok(0.0);
        }
        return Err(fault(
            ErrorKind::Expr(ExprError::RuntimeParam {
                what: format!("#{i} ({what})"),
                why: why.to_string(),
                hint: "--zero-start (reads 0)".to_string(),
            }),
            span,
        ));
    }
    if (5400..=5413).contains(&i) {
        scope.note_tool_read(span, i != 5400);
    }
    if (5400..=5413).contains(&i)
        && let Some(v) = scope.tool_param(i)
    {
        return Ok(v);
    }
    if !scope.params().known[i] {
        return Err(unknown_param(scope, i, span));
    }
    if !scope.params().set[i]
        && scope.settings().warnings
        && scope.call_level() == 0
        && (1..5000).contains(&i)
    {
        scope.warn_in_line(WarningKind::ReadBeforeSet { index: i as i64 }, span);
    }
    Ok(scope.params().values[i])
}

/// The fault of reading parameter `i`, whose value is not known.
fn unknown_param(scope: &impl Scope, i: usize, span: Span) -> Fault {
    if let (Some(line), 5061..=5070) = (scope.probed_at(), i) {
        return fault(
            ErrorKind::Expr(ExprError::ProbeResultUnknown { index: i, line }),
            span,
        );
    }
    if (5400..=5413).contains(&i) {
        return fault(
            ErrorKind::Expr(ExprError::RuntimeParam {
                what: format!("#{i} (tool data)"),
                why: "it comes from the tool table".to_string(),
                hint: scope.tool_data_hint(),
            }),
            span,
        );
    }
    let (what, why) = match classify(i) {
        ParamClass::Runtime(w, y) | ParamClass::ReadOnlyRuntime(w, y) => (w, y),
        _ => ("value", "it depends on the machine"),
    };
    fault(
        ErrorKind::Expr(ExprError::RuntimeParam {
            what: format!("#{i} ({what})"),
            why: why.to_string(),
            hint: format!("-D {i}=VALUE, a --var-file, or --zero-start"),
        }),
        span,
    )
}

fn param_exists(scope: &mut impl Scope, p: &ParamRef, span: Span) -> Result<bool, Fault> {
    match p {
        ParamRef::Numbered(index) => {
            let v = eval(scope, index)?;
            let i = integer_value(v).map_err(|k| fault(k, index.span))?;
            Ok((1..MAX_PARAM as i64).contains(&i))
        }
        ParamRef::Named(name) => named::named_exists(scope, name, span),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const S: Span = Span { start: 0, end: 0 };

    use proptest::prelude::*;

    fn mod_reference(a: f64, c: f64) -> f64 {
        let mut r = a % c;
        if r < 0.0 {
            r += c.abs();
        }
        r
    }

    proptest! {
        /// MOD on whole numbers through integers gives what the
        /// floating-point remainder gives, bit for bit (zero's sign too).
        #[test]
        fn mod_matches_the_float_remainder(
            a in -1_000_000i64..1_000_000,
            c in -1000i64..1000,
            x in -1.0e6f64..1.0e6,
            big in prop_oneof![Just(9.0e15), Just(1.0e300), Just(-4.5e15), Just(f64::INFINITY)],
        ) {
            for (a, c) in [(a as f64, c as f64), (x, c as f64), (a as f64, x), (big, c as f64), (a as f64, big), (-(a as f64), c as f64)] {
                let got = binary(BinOp::Mod, a, c, S).map(f64::to_bits);
                prop_assert_eq!(got, Ok(mod_reference(a, c).to_bits()), "{} MOD {}", a, c);
            }
        }

        #[test]
        fn integer_values_as_before(v in prop_oneof![
            (-1_000_000i64..1_000_000).prop_map(|i| i as f64),
            -1.0e6f64..1.0e6,
            Just(-0.0), Just(f64::NAN), Just(1.0e300), Just(9.0e15), Just(-9.5e15),
        ]) {
            let f = v.floor();
            let frac = v - f;
            let want = if frac > 0.9999 {
                Ok(f as i64 + 1)
            } else if frac > 0.0001 || !v.is_finite() {
                Err(())
            } else {
                Ok(f as i64)
            };
            prop_assert_eq!(integer_value(v).map_err(|_| ()), want, "{}", v);
        }
    }

    #[test]
    fn operators_table() {
        let cases: &[(BinOp, f64, f64, f64)] = &[
            (BinOp::Mod, -7.0, 3.0, 2.0),
            (BinOp::Mod, 7.0, -3.0, 1.0),
            (BinOp::Mod, -7.0, -3.0, 2.0),
            (BinOp::Mod, 7.5, 2.0, 1.5),
            (BinOp::Eq, 1.0, 1.00005, 1.0),
            (BinOp::Eq, 1.0, 1.0002, 0.0),
            (BinOp::Ne, 1.0, 1.00005, 0.0),
            (BinOp::Ge, 1.0, 1.00005, 0.0),
            (BinOp::Le, 1.0000005, 1.0, 0.0),
            (BinOp::Pow, 2.0, 3.0, 8.0),
            (BinOp::Pow, -2.0, 2.0, 4.0),
            (BinOp::Xor, 1.0, 1.0, 0.0),
            (BinOp::And, 2.0, 0.5, 1.0),
            (BinOp::Or, 0.0, 0.0, 0.0),
        ];
        for &(op, a, c, want) in cases {
            assert_eq!(binary(op, a, c, S).unwrap(), want, "{a} {op:?} {c}");
        }
    }

    #[test]
    fn domain_errors() {
        assert_eq!(
            binary(BinOp::Div, 1.0, 0.0, S).unwrap_err().0,
            ErrorKind::Expr(ExprError::DivideByZero)
        );
        assert_eq!(
            binary(BinOp::Pow, -2.0, 0.5, S).unwrap_err().0,
            ErrorKind::Expr(ExprError::NegativePower)
        );
        assert!(binary(BinOp::Mod, 1.0, 0.0, S).unwrap().is_nan());
        assert_eq!(
            unary(Func::Acos, 1.5, S).unwrap_err().0,
            ErrorKind::Expr(ExprError::AcosRange)
        );
        assert_eq!(
            unary(Func::Asin, -1.5, S).unwrap_err().0,
            ErrorKind::Expr(ExprError::AsinRange)
        );
        assert_eq!(
            unary(Func::Ln, 0.0, S).unwrap_err().0,
            ErrorKind::Expr(ExprError::LnDomain)
        );
        assert_eq!(
            unary(Func::Sqrt, -1.0, S).unwrap_err().0,
            ErrorKind::Expr(ExprError::SqrtNegative)
        );
    }

    #[test]
    fn rounding() {
        assert_eq!(round_half_away(2.5), 3.0);
        assert_eq!(round_half_away(-2.5), -3.0);
        assert_eq!(round_half_away(3e9), -2147483648.0);
        assert_eq!(round_half_even_int(0.5), 0);
        assert_eq!(round_half_even_int(1.5), 2);
        assert_eq!(round_half_even_int(2.5), 2);
        assert_eq!(round_half_even_int(3e9), i32::MIN as i64);
        assert_eq!(unary(Func::Fix, -2.8, S).unwrap(), -3.0);
        assert_eq!(unary(Func::Fup, -2.8, S).unwrap(), -2.0);
    }
}
