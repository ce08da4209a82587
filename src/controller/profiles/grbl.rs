//! GRBL 1.1 (the default build: three axes, no M7).
//!
//! Facts from gnea/grbl at commit bfb67f0c7963fe3ce4aaf8a97f9009ea5a8db36e:
//! `grbl/gcode.c` (`gc_execute_line`: the G, M and value-word switches, the
//! G10 L2/L20 and G43.1 Z-only checks, line number and tool number limits),
//! `grbl/protocol.c` (comments and blanks dropped before the line buffer,
//! `LINE_BUFFER_SIZE` 80 in `protocol.h`, a `/` ignored), `grbl/serial.c`
//! (`?`, `!`, `~`, ctrl-X and bytes above 0x7F acted on as they arrive) and
//! `grbl/nuts_bolts.c` (`read_float`: at most 8 significant digits, no
//! exponent).

use crate::controller::profile::{Comments, LineCount, Profile, ToolChange};

pub(crate) const PROFILE: Profile = Profile {
    name: "grbl",
    summary: "GRBL 1.1, default build (3 axes, no M7)",
    source: "gnea/grbl bfb67f0c grbl/gcode.c, grbl/protocol.c, grbl/serial.c",
    passthrough: false,
    g_codes: &[
        0, 10, 20, 30, 40, 100, 170, 180, 190, 200, 210, 280, 281, 300, 301, 382, 383, 384, 385,
        400, 431, 490, 530, 540, 550, 560, 570, 580, 590, 610, 800, 900, 910, 911, 920, 921, 930,
        940,
    ],
    m_codes: &[0, 1, 2, 3, 4, 5, 8, 9, 30],
    words: b"FIJKLNPRSTXYZ",
    axes: b"XYZ",
    g10_l: &[2, 20],
    coord_systems: 6,
    line_limit: Some((80, LineCount::Significant)),
    max_digits: 8,
    decimals_mm: 4,
    decimals_inch: 5,
    realtime: b"?!~\x18",
    high_bytes: true,
    comments: Comments::Strip,
    messages: false,
    block_delete: false,
    max_line_number: 10_000_000.0,
    max_tool: 255.0,
    percent: false,
    spindle_sync: false,
    tool_change: ToolChange::Pause,
    arc_turns: false,
    g43_1_z_only: true,
    optional_stop: false,
};
