//! grblHAL, the core's default build (three axes, 9 work coordinate
//! systems, no tool table, no spindle synchronisation, no path blending).
//!
//! Facts from grblHAL/core at commit f80fc34d503bd62391a23b197b3e0ee66ce00cb7:
//! `gcode.c` (`gc_execute_block`: the G and M switches with their build
//! options — G5 cubic splines, canned cycles G73/G81–G83/G85/G86/G89 with
//! G98/G99, G59.1–G59.3, G92.2/G92.3, M6, M7, M48–M51/M53, M60, M61,
//! M70–M73; G43/G43.2 only with a tool table, G33/G76 only with spindle
//! sync, G95/G96/G97 only with a spindle encoder; arcs take P turns,
//! G43.1 any axis), `protocol.h` (`LINE_BUFFER_SIZE` 257: 256 characters),
//! `config.h` (`N_AXIS` 3), the real-time command bytes of `grbl.h`.

use crate::target::profile::{Comments, LineCount, Profile, ToolChange};

pub const PROFILE: Profile = Profile {
    name: "grblhal",
    summary: "grblHAL, default core build (3 axes, G54-G59.3, no tool table)",
    source: "grblHAL/core f80fc34d gcode.c, protocol.h, config.h",
    passthrough: false,
    g_codes: &[
        0, 10, 20, 30, 40, 50, 100, 170, 180, 190, 200, 210, 280, 281, 300, 301, 382, 383, 384,
        385, 400, 431, 490, 530, 540, 550, 560, 570, 580, 590, 591, 592, 593, 610, 730, 800, 810,
        820, 830, 850, 860, 890, 900, 910, 911, 920, 921, 922, 923, 930, 940, 980, 990,
    ],
    m_codes: &[
        0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 30, 48, 49, 50, 51, 53, 60, 61, 70, 71, 72, 73,
    ],
    words: b"FIJKLNPQRSTXYZ",
    axes: b"XYZ",
    g10_l: &[2, 20],
    coord_systems: 9,
    line_limit: Some((257, LineCount::Significant)),
    max_digits: 8,
    decimals_mm: 4,
    decimals_inch: 5,
    realtime: b"?!~\x18",
    high_bytes: true,
    comments: Comments::Strip,
    messages: true,
    block_delete: true,
    max_line_number: 10_000_000.0,
    max_tool: 2_147_483_646.0,
    percent: true,
    spindle_sync: false,
    tool_change: ToolChange::Keep,
    arc_turns: true,
    g43_1_z_only: false,
};
