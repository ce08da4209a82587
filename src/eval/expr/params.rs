//! Numbered parameters #1–#5601 and which of them hold values only the
//! running machine knows.

use crate::fx_hasher::FxMap;
use crate::parse::Name;

/// Axis letters in parameter order (X Y Z A B C U V W): the parameters of
/// an axis are at its index from the first of their group (#5221, #5420…).
pub(crate) const AXES: [u8; 9] = *b"xyzabcuvw";

pub(crate) use crate::settings::MAX_PARAM;

/// What a numbered parameter means to a flattener.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum ParamClass {
    Plain,
    /// Written by the machine at run time; readable once given or assigned.
    Runtime(&'static str, &'static str),
    /// Current position, answered from the position model.
    Position(usize),
    /// Overwritten by the machine before every line: assignments do not stick.
    Refreshed(&'static str, &'static str),
    /// Tool table and toolchanger data: read-only in LinuxCNC.
    ReadOnlyRuntime(&'static str, &'static str),
}

pub(crate) fn classify(i: usize) -> ParamClass {
    match i {
        5061..=5069 => ParamClass::Runtime("probe result", "it is written by G38 probing"),
        5070 => ParamClass::Runtime("probe success flag", "it is written by G38 probing"),
        5161..=5169 => ParamClass::Runtime(
            "G28 home position",
            "it comes from the machine's parameter file",
        ),
        5181..=5189 => ParamClass::Runtime(
            "G30 home position",
            "it comes from the machine's parameter file",
        ),
        5210..=5219 => {
            ParamClass::Runtime("G92 offset", "it comes from the machine's parameter file")
        }
        5220 => ParamClass::Runtime(
            "active coordinate system",
            "it comes from the machine's parameter file",
        ),
        5221..=5390 => ParamClass::Runtime(
            "coordinate system offset",
            "it comes from the machine's parameter file",
        ),
        5399 => ParamClass::Runtime("M66 input value", "it is read from a machine input"),
        5400..=5413 => ParamClass::ReadOnlyRuntime("tool data", "it comes from the tool table"),
        5420..=5428 => ParamClass::Position(i - 5420),
        5600 | 5601 => ParamClass::Refreshed(
            "toolchanger status",
            "it is refreshed from the toolchanger before every line",
        ),
        _ => ParamClass::Plain,
    }
}

pub(crate) fn is_read_only(i: usize) -> bool {
    matches!(i, 5400..=5413 | 5420..=5428)
}

#[derive(Debug, Clone)]
pub(crate) struct Params {
    pub values: Vec<f64>,
    /// The value is known (always true for plain parameters).
    pub known: Vec<bool>,
    /// Assigned by the program, a -D or a var file (for read-before-set).
    pub set: Vec<bool>,
    /// Global named parameters (`#<_name>`, and the main program's locals).
    pub globals: FxMap<Name, f64>,
}

impl Params {
    pub(crate) fn new(zero_start: bool) -> Params {
        let mut known = vec![true; MAX_PARAM];
        if !zero_start {
            // Only 5061..=5601 are anything but plain (see `classify`).
            for (i, k) in known.iter_mut().enumerate().take(5602).skip(5061) {
                if !matches!(classify(i), ParamClass::Plain | ParamClass::Position(_)) {
                    *k = false;
                }
            }
        }
        let mut values = vec![0.0; MAX_PARAM];
        values[5220] = 1.0;
        values[5599] = 1.0;
        let mut set = vec![false; MAX_PARAM];
        set[5599] = true;
        Params {
            values,
            known,
            set,
            globals: FxMap::default(),
        }
    }

    /// Whether the G92 offsets are applied (#5210 not known to be 0).
    pub(crate) fn g92_applied(&self) -> bool {
        !(self.known[5210] && self.values[5210] == 0.0)
    }

    /// A plain parameter (below 5000) the program or a -D set, if its
    /// value is finite.
    #[inline]
    pub(crate) fn stored(&self, i: usize) -> Option<f64> {
        if i < 5000 && self.set[i] {
            let v = self.values[i];
            if v.is_finite() {
                return Some(v);
            }
        }
        None
    }

    pub(crate) fn assign(&mut self, i: usize, v: f64) {
        self.values[i] = v;
        self.known[i] = true;
        self.set[i] = true;
    }
}
