//! Named parameters: locals per call level, `_` globals, the predefined
//! read-only names answered from the state model, INI values.

use crate::diag::ErrorKind;
use crate::parse::Name;
use crate::parse::ast::Span;

use super::Interp;
use super::expr::{EvalResult, Fault, fault};
use super::state::{AXES, Unknown};

fn flag(x: bool) -> f64 {
    if x { 1.0 } else { 0.0 }
}

/// Splits `_ini[section]name`.
fn ini_key(name: &str) -> Option<(&str, &str)> {
    let rest = name.strip_prefix("_ini[")?;
    let close = rest.find(']')?;
    Some((&rest[..close], &rest[close + 1..]))
}

impl Interp<'_> {
    /// Value of a predefined name, `None` if the name is not predefined.
    fn predefined(&mut self, name: &str, span: Span) -> Option<EvalResult> {
        let m = &self.modal;
        let v = match name {
            "_value" => self.value,
            "_value_returned" => flag(self.value_returned),
            "_line" => (self.current_line_idx + 1) as f64,
            "_call_level" => self.level() as f64,
            "_remap_level" => 0.0,
            "_task" => 0.0,
            "_vmajor" => 2.9,
            "_vminor" => 0.0,
            "_metric_machine" => match self
                .s
                .ini
                .as_ref()
                .and_then(|i| i.get("TRAJ", "LINEAR_UNITS"))
            {
                None => -1.0,
                Some(u) => flag(!u.to_ascii_lowercase().starts_with("inch")),
            },
            "_metric" => flag(m.metric),
            "_imperial" => flag(!m.metric),
            "_absolute" => flag(m.absolute),
            "_incremental" => flag(!m.absolute),
            "_inverse_time" => flag(m.feed_mode == 930),
            "_units_per_minute" => flag(m.feed_mode == 940),
            "_units_per_rev" => flag(m.feed_mode == 950),
            "_coord_system" => {
                let i = m.coord_index;
                if i < 7 {
                    (530 + 10 * i) as f64
                } else {
                    (584 + i) as f64
                }
            }
            "_motion_mode" => m.motion as f64,
            "_plane" => m.plane as f64,
            "_ccomp" => m.ccomp as f64,
            "_tool_offset" => flag(m.tool_offset),
            "_retract_r_plane" => flag(m.retract_r),
            "_retract_old_z" => flag(!m.retract_r),
            "_spindle_rpm_mode" => flag(!m.css),
            "_spindle_css_mode" => flag(m.css),
            "_ijk_absolute_mode" => flag(m.ijk_absolute),
            "_lathe_diameter_mode" => flag(m.lathe_diameter),
            "_lathe_radius_mode" => flag(!m.lathe_diameter),
            "_spindle_on" => flag(m.spindle != 0),
            "_spindle_cw" => flag(m.spindle == 3),
            "_mist" => flag(m.mist),
            "_flood" => flag(m.flood),
            "_speed_override" => flag(m.speed_override),
            "_feed_override" => flag(m.feed_override),
            "_adaptive_feed" => flag(m.adaptive_feed),
            "_feed_hold" => flag(m.feed_hold),
            "_feed" => m.feed,
            "_rpm" => m.speed.abs(),
            "_current_tool" | "_selected_tool" | "_current_pocket" | "_selected_pocket" => {
                if name == "_current_tool" {
                    self.note_m61(span, false);
                }
                let v = match name {
                    "_current_tool" => self.current_tool,
                    "_selected_tool" => self.selected_tool,
                    "_current_pocket" => self.pockets.map(|p| p.0),
                    _ => self.pockets.map(|p| p.1),
                };
                return Some(v.ok_or_else(|| {
                    fault(
                        ErrorKind::RuntimeParam {
                            what: format!("#<{name}>"),
                            why: "the tool in the spindle is known only on the machine".into(),
                            hint: "a T word and M6 in the program first, or --zero-start".into(),
                        },
                        span,
                    )
                }));
            }
            _ => {
                if let Some(axis) = name.strip_prefix('_').filter(|a| a.len() == 1)
                    && let Some(i) = AXES.iter().position(|&c| c == axis.as_bytes()[0])
                {
                    self.note_standalone_drift(span);
                    return Some(self.position(i, span));
                }
                if let Some(axis) = name.strip_prefix("_abs_").filter(|a| a.len() == 1)
                    && let Some(i) = AXES.iter().position(|&c| c == axis.as_bytes()[0])
                    && let Some(v) = self.abs_position(i)
                {
                    self.note_standalone_drift(span);
                    return Some(Ok(v));
                }
                if let Some(axis) = name.strip_prefix("_abs_").filter(|a| a.len() == 1)
                    && AXES.contains(&axis.as_bytes()[0])
                {
                    return Some(Err(fault(
                        ErrorKind::RuntimeParam {
                            what: format!("#<{name}> (machine position)"),
                            why: "machine coordinates depend on homing and offsets".into(),
                            hint: "--zero-start, or offsets and a position set by the program"
                                .into(),
                        },
                        span,
                    )));
                }
                if name.starts_with("_hal[") && self.s.hal_pin_vars {
                    return Some(Err(fault(
                        ErrorKind::RuntimeParam {
                            what: format!("#<{name}>"),
                            why: "HAL values exist only on the running machine".into(),
                            hint: format!("-D {name}=VALUE"),
                        },
                        span,
                    )));
                }
                if let Some((sec, key)) = ini_key(name).filter(|_| self.s.ini_vars) {
                    let found = self.s.ini.as_ref().and_then(|i| i.get_upper(sec, key));
                    return Some(match found.and_then(|v| v.trim().parse::<f64>().ok()) {
                        Some(v) => Ok(v),
                        None => Err(fault(
                            ErrorKind::NamedUndefined {
                                name: name.to_string(),
                            },
                            span,
                        )),
                    });
                }
                return None;
            }
        };
        Some(Ok(v))
    }

    pub(crate) fn is_predefined(&self, name: &str) -> bool {
        name.starts_with('_')
            && (matches!(
                name,
                "_value"
                    | "_value_returned"
                    | "_line"
                    | "_call_level"
                    | "_remap_level"
                    | "_task"
                    | "_vmajor"
                    | "_vminor"
                    | "_metric_machine"
                    | "_metric"
                    | "_imperial"
                    | "_absolute"
                    | "_incremental"
                    | "_inverse_time"
                    | "_units_per_minute"
                    | "_units_per_rev"
                    | "_coord_system"
                    | "_motion_mode"
                    | "_plane"
                    | "_ccomp"
                    | "_tool_offset"
                    | "_retract_r_plane"
                    | "_retract_old_z"
                    | "_spindle_rpm_mode"
                    | "_spindle_css_mode"
                    | "_ijk_absolute_mode"
                    | "_lathe_diameter_mode"
                    | "_lathe_radius_mode"
                    | "_spindle_on"
                    | "_spindle_cw"
                    | "_mist"
                    | "_flood"
                    | "_speed_override"
                    | "_feed_override"
                    | "_adaptive_feed"
                    | "_feed_hold"
                    | "_feed"
                    | "_rpm"
                    | "_current_tool"
                    | "_selected_tool"
                    | "_current_pocket"
                    | "_selected_pocket"
            ) || (name.len() == 2 && AXES.contains(&name.as_bytes()[1]))
                || (name.len() == 6
                    && name.starts_with("_abs_")
                    && AXES.contains(&name.as_bytes()[5]))
                || (name.starts_with("_ini[") && self.s.ini_vars)
                || (name.starts_with("_hal[") && self.s.hal_pin_vars))
    }

    /// Current position on an axis, or why it is unknown.
    pub(crate) fn position(&self, axis: usize, span: Span) -> EvalResult {
        if self.modal.ccomp != 400 {
            let why = "cutter radius compensation is on".to_string();
            return Err(fault(
                ErrorKind::UnknownPosition {
                    axis: AXES[axis] as char,
                    why,
                },
                span,
            ));
        }
        match &self.pos.axes[axis] {
            Ok(v) => Ok(*v),
            Err(why) => {
                let why = match why {
                    Unknown::Start => {
                        "the program has not moved it to an absolute position yet".to_string()
                    }
                    Unknown::After(what, line) => format!("{what} at line {line} made it unknown"),
                };
                Err(fault(
                    ErrorKind::UnknownPosition {
                        axis: AXES[axis] as char,
                        why,
                    },
                    span,
                ))
            }
        }
    }

    fn named_table(&mut self, name: &str) -> &mut crate::fx_hasher::FxMap<Name, f64> {
        if name.starts_with('_') || self.frames.len() == 1 {
            &mut self.globals
        } else {
            &mut self.frames.last_mut().expect("frame").locals
        }
    }

    pub(crate) fn read_named(&mut self, name: &Name, span: Span) -> EvalResult {
        if name.starts_with('_') {
            // A -D value overrides a predefined one (e.g. _hal values).
            if let Some(v) = self.globals.get(name) {
                return Ok(*v);
            }
            if let Some(r) = self.predefined(name, span) {
                return r;
            }
        }
        let defining = self.defining;
        match self.named_table(name).get(name) {
            Some(v) => Ok(*v),
            None if defining => Ok(0.0),
            None => Err(fault(
                ErrorKind::NamedUndefined {
                    name: name.to_string(),
                },
                span,
            )),
        }
    }

    pub(crate) fn named_exists(&mut self, name: &Name, span: Span) -> Result<bool, Fault> {
        if (name.starts_with("_ini[") && self.s.ini_vars)
            || (name.starts_with("_hal[") && self.s.hal_pin_vars)
        {
            if self.globals.contains_key(name) {
                return Ok(true);
            }
            return Ok(self.predefined(name, span).is_some_and(|r| r.is_ok()));
        }
        if self.is_predefined(name) {
            return Ok(true);
        }
        Ok(self.named_table(name).contains_key(name))
    }

    /// Creates a named parameter (value 0) when its setting is parsed.
    pub(crate) fn create_named(&mut self, name: &Name, span: Span) -> Result<(), Fault> {
        // An `_ini[...]` name the INI does not have is an ordinary global.
        let ini_missing =
            name.starts_with("_ini[") && self.predefined(name, span).is_none_or(|r| r.is_err());
        if (self.is_predefined(name) && !ini_missing)
            || (name.as_str() == "n_args" && self.s.oword_nargs && self.level() > 0)
        {
            return Err(fault(
                ErrorKind::NamedReadOnly {
                    name: name.to_string(),
                },
                span,
            ));
        }
        let t = self.named_table(name);
        if !t.contains_key(name) {
            t.insert(name.clone(), 0.0);
        }
        Ok(())
    }

    pub(crate) fn set_named(&mut self, name: &Name, v: f64) {
        self.named_table(name).insert(name.clone(), v);
    }
}
