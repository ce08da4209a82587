//! LinuxCNC 2.9: the flattened program as it is (the default).

use crate::controller::profile::{Comments, Profile, ToolChange};

pub(crate) const PROFILE: Profile = Profile {
    name: "linuxcnc",
    summary: "LinuxCNC 2.9: the flattened program as it is (the default)",
    source: "LinuxCNC 2.9 rs274ngc (the reference itself)",
    passthrough: true,
    g_codes: &[],
    m_codes: &[],
    words: b"",
    axes: b"XYZABCUVW",
    g10_l: &[],
    coord_systems: 9,
    line_limit: None,
    max_digits: 17,
    decimals_mm: 17,
    decimals_inch: 17,
    realtime: b"",
    high_bytes: false,
    comments: Comments::Keep,
    messages: true,
    block_delete: true,
    max_line_number: 99_999.0,
    max_tool: f64::MAX,
    percent: true,
    spindle_sync: true,
    tool_change: ToolChange::Keep,
    arc_turns: true,
    g43_1_z_only: false,
    optional_stop: true,
};
