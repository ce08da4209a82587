//! FluidNC with a three-axis configuration.
//!
//! Facts from bdring/FluidNC at commit e952f33f407cf3dff55166ec908ea93177ea78c9:
//! `FluidNC/src/GCode.cpp` (`gc_execute_line`: G0–G3, G4, G10 L2/L20,
//! G17–G19, G20/G21, G28/G30 and .1, G38.2–G38.5, G40, G43.1/G49, G53,
//! G54–G59.3, G61, G80, G90/G91, G91.1, G92/G92.1, G93/G94; M0–M2, M30,
//! M3–M5, M6, M7/M8/M9 (M7 only when the machine has mist), M61,
//! M62–M68; `(MSG …)` comments shown; no canned cycles, splines, G43,
//! G90.1, G64 or G95; M7 without a mist output is accepted and does
//! nothing, so it is refused here; G38.x to the current position is
//! refused), `FluidNC/src/Channel.cpp` and `Channel.h` (`lineComplete`:
//! every byte up to the line end goes into a 255-byte buffer, `maxLine`,
//! and bytes past 254 are dropped without an error, so longer lines are
//! refused here) and the real-time characters of `FluidNC/src/RealtimeCmd.h`.

use crate::controller::profile::{Comments, LineCount, Profile, ToolChange};

pub(crate) const PROFILE: Profile = Profile {
    name: "fluidnc",
    summary: "FluidNC, 3-axis configuration (flood coolant, no mist)",
    source: "bdring/FluidNC e952f33f FluidNC/src/GCode.cpp, Channel.cpp",
    passthrough: false,
    g_codes: &[
        0, 10, 20, 30, 40, 100, 170, 180, 190, 200, 210, 280, 281, 300, 301, 382, 383, 384, 385,
        400, 431, 490, 530, 540, 550, 560, 570, 580, 590, 591, 592, 593, 610, 800, 900, 910, 911,
        920, 921, 930, 940,
    ],
    m_codes: &[0, 1, 2, 3, 4, 5, 6, 8, 9, 30, 61],
    words: b"FIJKLNPQRSTXYZ",
    axes: b"XYZ",
    g10_l: &[2, 20],
    coord_systems: 9,
    line_limit: Some((255, LineCount::AllBytes)),
    max_digits: 8,
    decimals_mm: 4,
    decimals_inch: 5,
    realtime: b"?!~\x18",
    high_bytes: true,
    comments: Comments::Strip,
    messages: true,
    block_delete: false,
    max_line_number: 10_000_000.0,
    max_tool: 2_147_483_646.0,
    percent: false,
    spindle_sync: false,
    tool_change: ToolChange::Keep,
    arc_turns: false,
    g43_1_z_only: true,
    optional_stop: false,
};
