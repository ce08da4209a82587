//! Named parameters: locals per call level, `_` globals, the predefined
//! read-only names answered from the state model, INI values.

use crate::diag::ErrorKind;
use crate::diag::ExprError;
use crate::parse::Name;
use crate::parse::ast::Span;
use crate::rules::Modes;

use crate::codes as code;
use crate::codes::SpindleDir;
use crate::fx_hasher::FxMap;

use crate::eval::expr::params::AXES;
use crate::eval::expr::{EvalResult, Fault, Scope, fault};
use crate::settings::Settings;

fn flag(x: bool) -> f64 {
    if x { 1.0 } else { 0.0 }
}

/// Splits `_ini[section]name`.
fn ini_key(name: &str) -> Option<(&str, &str)> {
    let rest = name.strip_prefix("_ini[")?;
    let close = rest.find(']')?;
    Some((&rest[..close], &rest[close + 1..]))
}

/// The predefined names with a fixed meaning (besides `_x`, `_abs_x`,
/// `_ini[...]` and `_hal[...]`), listed once: [`predef`] names them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Predef {
    Value,
    ValueReturned,
    Line,
    CallLevel,
    RemapLevel,
    Task,
    Vmajor,
    Vminor,
    MetricMachine,
    Metric,
    Imperial,
    Absolute,
    Incremental,
    InverseTime,
    UnitsPerMinute,
    UnitsPerRev,
    CoordSystem,
    MotionMode,
    Plane,
    Ccomp,
    ToolOffset,
    RetractRPlane,
    RetractOldZ,
    SpindleRpmMode,
    SpindleCssMode,
    IjkAbsoluteMode,
    LatheDiameterMode,
    LatheRadiusMode,
    SpindleOn,
    SpindleCw,
    Mist,
    Flood,
    SpeedOverride,
    FeedOverride,
    AdaptiveFeed,
    FeedHold,
    Feed,
    Rpm,
    CurrentTool,
    SelectedTool,
    CurrentPocket,
    SelectedPocket,
}

/// The predefined name `name` is, if it is one with a fixed meaning.
fn predef(name: &str) -> Option<Predef> {
    use Predef::*;
    Some(match name {
        "_value" => Value,
        "_value_returned" => ValueReturned,
        "_line" => Line,
        "_call_level" => CallLevel,
        "_remap_level" => RemapLevel,
        "_task" => Task,
        "_vmajor" => Vmajor,
        "_vminor" => Vminor,
        "_metric_machine" => MetricMachine,
        "_metric" => Metric,
        "_imperial" => Imperial,
        "_absolute" => Absolute,
        "_incremental" => Incremental,
        "_inverse_time" => InverseTime,
        "_units_per_minute" => UnitsPerMinute,
        "_units_per_rev" => UnitsPerRev,
        "_coord_system" => CoordSystem,
        "_motion_mode" => MotionMode,
        "_plane" => Plane,
        "_ccomp" => Ccomp,
        "_tool_offset" => ToolOffset,
        "_retract_r_plane" => RetractRPlane,
        "_retract_old_z" => RetractOldZ,
        "_spindle_rpm_mode" => SpindleRpmMode,
        "_spindle_css_mode" => SpindleCssMode,
        "_ijk_absolute_mode" => IjkAbsoluteMode,
        "_lathe_diameter_mode" => LatheDiameterMode,
        "_lathe_radius_mode" => LatheRadiusMode,
        "_spindle_on" => SpindleOn,
        "_spindle_cw" => SpindleCw,
        "_mist" => Mist,
        "_flood" => Flood,
        "_speed_override" => SpeedOverride,
        "_feed_override" => FeedOverride,
        "_adaptive_feed" => AdaptiveFeed,
        "_feed_hold" => FeedHold,
        "_feed" => Feed,
        "_rpm" => Rpm,
        "_current_tool" => CurrentTool,
        "_selected_tool" => SelectedTool,
        "_current_pocket" => CurrentPocket,
        "_selected_pocket" => SelectedPocket,
        _ => return None,
    })
}

/// Value of a predefined name, `None` if the name is not predefined.
fn predefined(scope: &mut impl Scope, name: &str, span: Span) -> Option<EvalResult> {
    let Some(p) = predef(name) else {
        return predefined_pattern(scope, name, span);
    };
    let v = match p {
        Predef::Value => scope.returned().0,
        Predef::ValueReturned => flag(scope.returned().1),
        Predef::Line => (scope.line_idx() + 1) as f64,
        Predef::CallLevel => scope.call_level() as f64,
        Predef::RemapLevel => 0.0,
        Predef::Task => 0.0,
        Predef::Vmajor => 2.9,
        Predef::Vminor => 0.0,
        Predef::MetricMachine => match scope
            .settings()
            .ini
            .as_ref()
            .and_then(|i| i.get("TRAJ", "LINEAR_UNITS"))
        {
            None => -1.0,
            Some(u) => flag(!u.to_ascii_lowercase().starts_with("inch")),
        },
        Predef::CurrentTool
        | Predef::SelectedTool
        | Predef::CurrentPocket
        | Predef::SelectedPocket => return Some(tool_number(scope, p, name, span)),
        _ => modal_value(scope.modes(), p),
    };
    Some(Ok(v))
}

/// Value of a predefined name of the modal state.
fn modal_value(m: &Modes, p: Predef) -> f64 {
    match p {
        Predef::Metric => flag(m.units == code::Units::Mm),
        Predef::Imperial => flag(m.units == code::Units::Inch),
        Predef::Absolute => flag(m.distance == code::Distance::Absolute),
        Predef::Incremental => flag(m.distance == code::Distance::Incremental),
        Predef::InverseTime => flag(m.feed_mode == code::FeedMode::InverseTime),
        Predef::UnitsPerMinute => flag(m.feed_mode == code::FeedMode::PerMinute),
        Predef::UnitsPerRev => flag(m.feed_mode == code::FeedMode::PerRev),
        // The G code ×10 (G59.1 is 591).
        Predef::CoordSystem => m.coord.code10() as f64,
        // The G code ×10, as LinuxCNC reports them; -1 after G5.3.
        Predef::MotionMode => match m.motion {
            code::MotionMode::NurbsEnd => -1.0,
            motion => motion.code10() as f64,
        },
        Predef::Plane => m.plane.code10() as f64,
        Predef::Ccomp => m.cutter_comp.side().code10() as f64,
        Predef::ToolOffset => flag(m.tool_length.in_effect()),
        Predef::RetractRPlane => flag(m.retract == code::Retract::R),
        Predef::RetractOldZ => flag(m.retract == code::Retract::Initial),
        Predef::SpindleRpmMode => flag(m.spindle_mode == code::SpindleMode::Rpm),
        Predef::SpindleCssMode => flag(m.spindle_mode == code::SpindleMode::ConstantSurface),
        Predef::IjkAbsoluteMode => flag(m.arc_distance == code::ArcDistance::Absolute),
        Predef::LatheDiameterMode => flag(m.lathe == code::LatheMode::Diameter),
        Predef::LatheRadiusMode => flag(m.lathe == code::LatheMode::Radius),
        Predef::SpindleOn => flag(m.spindle != SpindleDir::Off),
        Predef::SpindleCw => flag(m.spindle == SpindleDir::Cw),
        Predef::Mist => flag(m.mist),
        Predef::Flood => flag(m.flood),
        Predef::SpeedOverride => flag(m.speed_override),
        Predef::FeedOverride => flag(m.feed_override),
        Predef::AdaptiveFeed => flag(m.adaptive_feed),
        Predef::FeedHold => flag(m.feed_hold),
        Predef::Feed => m.feed,
        Predef::Rpm => m.speed.abs(),
        // The others are not of the modal state (see `predefined`).
        _ => 0.0,
    }
}

/// The current or selected tool or pocket (`p`, named `name`), or why it
/// is unknown.
fn tool_number(scope: &mut impl Scope, p: Predef, name: &str, span: Span) -> EvalResult {
    if p == Predef::CurrentTool {
        scope.note_tool_read(span, false);
    }
    let (current, selected) = scope.tools();
    let v = match p {
        Predef::CurrentTool => current,
        Predef::SelectedTool => selected,
        Predef::CurrentPocket => scope.pockets().map(|p| p.0),
        _ => scope.pockets().map(|p| p.1),
    };
    v.ok_or_else(|| {
        fault(
            ErrorKind::Expr(ExprError::RuntimeParam {
                what: format!("#<{name}>"),
                why: "the tool in the spindle is known only on the machine".into(),
                hint: "a T word and M6 in the program first, or --zero-start".into(),
            }),
            span,
        )
    })
}

/// Value of a predefined name of a pattern (`_x`, `_abs_x`, `_hal[...]`,
/// `_ini[...]`), `None` if the name is none of them.
fn predefined_pattern(scope: &mut impl Scope, name: &str, span: Span) -> Option<EvalResult> {
    if let Some(axis) = name.strip_prefix('_').filter(|a| a.len() == 1)
        && let Some(i) = AXES.iter().position(|&c| c == axis.as_bytes()[0])
    {
        scope.note_position_read(span);
        return Some(scope.position(i, span));
    }
    if let Some(axis) = name.strip_prefix("_abs_").filter(|a| a.len() == 1)
        && let Some(i) = AXES.iter().position(|&c| c == axis.as_bytes()[0])
        && let Some(v) = scope.abs_position(i)
    {
        scope.note_position_read(span);
        return Some(Ok(v));
    }
    if let Some(axis) = name.strip_prefix("_abs_").filter(|a| a.len() == 1)
        && AXES.contains(&axis.as_bytes()[0])
    {
        return Some(Err(fault(
            ErrorKind::Expr(ExprError::RuntimeParam {
                what: format!("#<{name}> (machine position)"),
                why: "machine coordinates depend on homing and offsets".into(),
                hint: "--zero-start, or offsets and a position set by the program".into(),
            }),
            span,
        )));
    }
    let s = scope.settings();
    if name.starts_with("_hal[") && s.hal_pin_vars {
        return Some(Err(fault(
            ErrorKind::Expr(ExprError::RuntimeParam {
                what: format!("#<{name}>"),
                why: "HAL values exist only on the running machine".into(),
                hint: format!("-D {name}=VALUE"),
            }),
            span,
        )));
    }
    if let Some((sec, key)) = ini_key(name).filter(|_| s.ini_vars) {
        let found = s.ini.as_ref().and_then(|i| i.get_upper(sec, key));
        return Some(match found.and_then(|v| v.trim().parse::<f64>().ok()) {
            Some(v) => Ok(v),
            None => Err(fault(
                ErrorKind::Expr(ExprError::NamedUndefined {
                    name: name.to_string(),
                }),
                span,
            )),
        });
    }
    None
}

/// Whether `name` is a predefined (read-only) name under the settings `s`.
pub(in crate::eval) fn is_predefined(s: &Settings, name: &str) -> bool {
    name.starts_with('_')
        && (predef(name).is_some()
            || (name.len() == 2 && AXES.contains(&name.as_bytes()[1]))
            || (name.len() == 6 && name.starts_with("_abs_") && AXES.contains(&name.as_bytes()[5]))
            || (name.starts_with("_ini[") && s.ini_vars)
            || (name.starts_with("_hal[") && s.hal_pin_vars))
}

/// The table holding `name`: the globals for a `_` name or in the main
/// program, else the call's locals (`locals`, `None` in the main program).
#[inline(always)]
pub(in crate::eval) fn table_of<'a>(
    globals: &'a FxMap<Name, f64>,
    locals: Option<&'a FxMap<Name, f64>>,
    name: &str,
) -> &'a FxMap<Name, f64> {
    if name.starts_with('_') {
        globals
    } else {
        locals.unwrap_or(globals)
    }
}

pub(in crate::eval) fn read_named(scope: &mut impl Scope, name: &Name, span: Span) -> EvalResult {
    if name.starts_with('_') {
        // A -D value overrides a predefined one (e.g. _hal values).
        if let Some(v) = scope.params().globals.get(name) {
            return Ok(*v);
        }
        if let Some(r) = predefined(scope, name, span) {
            return r;
        }
    }
    let defining = scope.defining();
    match table_of(&scope.params().globals, scope.locals(), name).get(name) {
        Some(v) => Ok(*v),
        None if defining => Ok(0.0),
        None => Err(fault(
            ErrorKind::Expr(ExprError::NamedUndefined {
                name: name.to_string(),
            }),
            span,
        )),
    }
}

pub(in crate::eval) fn named_exists(
    scope: &mut impl Scope,
    name: &Name,
    span: Span,
) -> Result<bool, Fault> {
    let s = scope.settings();
    if (name.starts_with("_ini[") && s.ini_vars) || (name.starts_with("_hal[") && s.hal_pin_vars) {
        if scope.params().globals.contains_key(name) {
            return Ok(true);
        }
        return Ok(predefined(scope, name, span).is_some_and(|r| r.is_ok()));
    }
    if is_predefined(scope.settings(), name) {
        return Ok(true);
    }
    Ok(table_of(&scope.params().globals, scope.locals(), name).contains_key(name))
}

/// Whether the program may create (and set) the named parameter `name`;
/// the fault if it is read-only.
pub(in crate::eval) fn check_settable(
    scope: &mut impl Scope,
    name: &Name,
    span: Span,
) -> Result<(), Fault> {
    // An `_ini[...]` name the INI does not have is an ordinary global.
    let ini_missing =
        name.starts_with("_ini[") && predefined(scope, name, span).is_none_or(|r| r.is_err());
    let s = scope.settings();
    if (is_predefined(s, name) && !ini_missing)
        || (name.as_str() == "n_args" && s.oword_nargs && scope.call_level() > 0)
    {
        return Err(fault(
            ErrorKind::Expr(ExprError::NamedReadOnly {
                name: name.to_string(),
            }),
            span,
        ));
    }
    Ok(())
}
