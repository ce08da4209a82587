//! The tool table as far as the program can know it: loaded from a
//! LinuxCNC tool table file, assumed all zero with --zero-start, and written
//! by the program itself (G10 L1/L10/L11). Tool data is kept in machine
//! units, as LinuxCNC stores it.

use super::Modes;
use crate::codes::SpindleDir;
use crate::fx_hasher::FxMap;
use crate::settings::Settings;

pub(crate) use crate::settings::ToolData;

/// The tools as a run of the program knows them: the table, whether it is
/// complete, the tool in the spindle and the one selected. The evaluator
/// and the machine model after it both keep one and change it through the
/// same steps: a T word selects ([`Tools::select`]), M6 loads the selected
/// tool ([`Tools::change`]), M61 sets the tool in the spindle
/// ([`Tools::set_current`]). Numbers are kept as the words give them (the
/// evaluator reads `#<_current_tool>` as written); the machine model reads
/// them as whole numbers.
#[derive(Debug, Clone, Default)]
pub(crate) struct Tools {
    /// Tool data as given (machine units), by tool number.
    pub(crate) table: FxMap<i64, ToolData>,
    /// The table is complete (`--zero-start`): a tool not in it has no
    /// offsets and no diameter.
    pub(crate) known: bool,
    /// The tool in the spindle, if known: tool 0 (none) with a tool table
    /// or `--zero-start`, else unknown until an M6 or M61.
    pub(crate) current: Option<f64>,
    /// The tool the last T word selected (0 under `--zero-start`).
    pub(crate) selected: Option<f64>,
    /// An M6 loaded a tool other than 0: the spindle's entry, which tool 0
    /// reads without a row of its own, is no longer empty
    /// ([`Tools::data`]).
    pub(crate) loaded: bool,
}

impl Tools {
    /// The tools at the start of a run with `s`.
    pub(crate) fn new(s: &Settings) -> Tools {
        Tools {
            table: s.tool_table.iter().copied().collect(),
            known: s.zero_start,
            current: (s.zero_start || !s.tool_table.is_empty()).then_some(0.0),
            selected: s.zero_start.then_some(0.0),
            loaded: false,
        }
    }

    /// A T word: selects tool `t` for the next M6.
    #[inline]
    pub(crate) fn select(&mut self, t: f64) {
        self.selected = Some(t);
    }

    /// M6: the spindle stops for the change and stays off (LinuxCNC's
    /// default, `[EMCIO]TOOL_CHANGE_WITH_SPINDLE_ON = 0`), and the selected
    /// tool goes in (an unknown one if none was selected). True when the
    /// spindle was turning.
    #[inline]
    pub(crate) fn change(&mut self, modes: &mut Modes) -> bool {
        self.current = self.selected;
        self.loaded |= self.selected.is_none_or(|t| t.round() != 0.0);
        let stops = modes.spindle != SpindleDir::Off;
        modes.spindle = SpindleDir::Off;
        stops
    }

    /// M61 with its Q word: the tool in the spindle is `q` (unknown
    /// without one).
    #[inline]
    pub(crate) fn set_current(&mut self, q: Option<f64>) {
        self.current = q;
    }

    /// The table's data of tool `t` (machine units): its row, or none
    /// (all zero) when the table is complete, and for tool 0 (no tool)
    /// until an M6 loads another; `None` when unknown (tool 0 after such
    /// an M6: rs274 then reads the spindle's entry, a copy of the last
    /// tool loaded).
    pub(crate) fn data(&self, t: i64) -> Option<ToolData> {
        match self.table.get(&t) {
            Some(d) => Some(*d),
            None if self.known || t == 0 && !self.loaded => Some(ToolData::default()),
            None => None,
        }
    }
}

/// The diameter (machine units) of tool `t` in the standalone
/// interpreter's built-in tool table, which `--zero-start` without a tool
/// table stands for: T1-T3 have diameters, every other tool none.
pub(crate) fn standalone_diameter(t: i64) -> f64 {
    match t {
        1 => 0.125,
        2 => 0.0625,
        3 => 0.201,
        _ => 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The start as the settings give it, and T, M6 and M61 in turn.
    #[test]
    fn tools_start_and_change() {
        let plain = Tools::new(&Settings::default());
        assert_eq!(
            (plain.current, plain.selected, plain.known),
            (None, None, false)
        );
        assert_eq!(plain.data(1), None);
        let row = ToolData {
            diameter: 0.5,
            ..ToolData::default()
        };
        let table = Settings {
            tool_table: vec![(2, row)],
            ..Settings::default()
        };
        let mut t = Tools::new(&table);
        assert_eq!((t.current, t.selected), (Some(0.0), None));
        assert_eq!((t.data(2), t.data(3)), (Some(row), None));
        assert_eq!(t.data(0), Some(ToolData::default()), "no tool yet");
        let mut modes = Modes::default();
        t.select(0.2);
        assert!(!t.change(&mut modes));
        assert_eq!(t.data(0), Some(ToolData::default()), "T0 M6 loads none");
        t.selected = None;
        assert!(!t.change(&mut modes));
        assert_eq!(t.current, None, "M6 with no tool selected");
        assert_eq!(t.data(0), None, "the spindle's entry is a tool's");
        t.select(2.4);
        assert_eq!((t.current, t.selected), (None, Some(2.4)));
        modes.spindle = SpindleDir::Ccw;
        assert!(t.change(&mut modes), "the spindle stops");
        assert_eq!((t.current, modes.spindle), (Some(2.4), SpindleDir::Off));
        t.set_current(Some(5.0));
        assert_eq!((t.current, t.selected), (Some(5.0), Some(2.4)));
        t.set_current(None);
        assert_eq!(t.current, None);
        let zero = Tools::new(&Settings {
            zero_start: true,
            ..Settings::default()
        });
        assert_eq!(
            (zero.current, zero.selected, zero.known),
            (Some(0.0), Some(0.0), true)
        );
        assert_eq!(zero.data(7), Some(ToolData::default()));
    }
}
