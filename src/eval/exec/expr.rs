//! Expressions in the evaluator: what an expression reads (the settings,
//! the parameters, the call, the line and the machine model) handed to
//! `eval/expr` as a [`Scope`] over the evaluator's parts, and the steps that
//! set named parameters, whose table is the call's.

use crate::diag::WarningKind;
use crate::fx_hasher::FxMap;
use crate::parse::Name;
use crate::parse::ast::{Expr, Span};
use crate::rules::Modes;

use crate::eval::Interp;
use crate::eval::expr::params::Params;
use crate::eval::expr::{self, EvalResult, Fault, Scope, message, named};
use crate::eval::flow::Flow;
use crate::settings::Settings;

/// The evaluator as an expression's surroundings: each reading is of one
/// part; a warning is the only change.
impl Scope for Interp<'_> {
    #[inline(always)]
    fn settings(&self) -> &Settings {
        self.s
    }

    #[inline(always)]
    fn params(&self) -> &Params {
        &self.params
    }

    #[inline(always)]
    fn locals(&self) -> Option<&FxMap<Name, f64>> {
        match self.flow.frames.as_slice() {
            [_main] => None,
            [.., f] => Some(&f.locals),
            [] => None,
        }
    }

    fn call_level(&self) -> usize {
        self.flow.level()
    }

    fn defining(&self) -> bool {
        self.flow.defining
    }

    fn returned(&self) -> (f64, bool) {
        (self.flow.value, self.flow.value_returned)
    }

    fn line_idx(&self) -> u32 {
        self.reader.line_idx
    }

    fn modes(&self) -> &Modes {
        &self.mach.modal
    }

    fn tools(&self) -> (Option<f64>, Option<f64>) {
        (self.mach.tools.current, self.mach.tools.selected)
    }

    fn pockets(&self) -> Option<(f64, f64)> {
        self.mach.pockets
    }

    fn position(&self, axis: usize, span: Span) -> EvalResult {
        self.mach.position(axis, span)
    }

    fn abs_position(&self, axis: usize) -> Option<f64> {
        self.mach.abs_position(self.s, &self.params, axis)
    }

    fn tool_param(&self, i: usize) -> Option<f64> {
        self.mach.tool_param(i)
    }

    fn probed_at(&self) -> Option<u32> {
        self.mach.probed_at
    }

    fn tool_data_hint(&self) -> String {
        self.mach.tool_data_hint()
    }

    fn note_position_read(&mut self, span: Span) {
        self.note_standalone_drift(span);
    }

    fn note_tool_read(&mut self, span: Span, data: bool) {
        self.note_m61(span, data);
    }

    fn warn_in_line(&mut self, kind: WarningKind, span: Span) {
        let file = self.flow.cur.file.clone();
        let at = self.reader.line_start;
        self.warn(kind, &file, at + span.start, at + span.end);
    }
}

/// The table a named parameter `name` is set in: the globals for a `_`
/// name or in the main program, else the call's locals.
fn named_table<'a>(
    params: &'a mut Params,
    flow: &'a mut Flow,
    name: &str,
) -> &'a mut FxMap<Name, f64> {
    if name.starts_with('_') || flow.frames.len() == 1 {
        &mut params.globals
    } else {
        &mut flow.frames.last_mut().expect("frame").locals
    }
}

impl Interp<'_> {
    /// Evaluates a value (see [`expr::eval`]).
    pub(in crate::eval) fn eval(&mut self, e: &Expr) -> EvalResult {
        expr::eval(self, e)
    }

    /// Evaluates a value, its commonest cases inline (see
    /// [`expr::eval_value`]).
    #[inline(always)]
    pub(in crate::eval) fn eval_value(&mut self, e: &Expr) -> EvalResult {
        expr::eval_value(self, e)
    }

    /// Index of a numbered parameter reference.
    pub(in crate::eval) fn param_index(&mut self, index: &Expr) -> Result<usize, Fault> {
        expr::param_index(self, index)
    }

    /// Substitutes parameters in a message body (see
    /// [`message::substitute`]).
    pub(in crate::eval) fn substitute(&mut self, text: &str, base: u32) -> Result<String, Fault> {
        message::substitute(self, text, base)
    }

    /// Creates a named parameter (value 0) when its setting is parsed.
    pub(in crate::eval) fn create_named(&mut self, name: &Name, span: Span) -> Result<(), Fault> {
        named::check_settable(self, name, span)?;
        let t = named_table(&mut self.params, &mut self.flow, name);
        if !t.contains_key(name) {
            t.insert(name.clone(), 0.0);
        }
        Ok(())
    }

    /// Sets a named parameter.
    pub(in crate::eval) fn set_named(&mut self, name: &Name, v: f64) {
        named_table(&mut self.params, &mut self.flow, name).insert(name.clone(), v);
    }
}
