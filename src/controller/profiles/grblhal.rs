//! grblHAL, the core's default build (three axes, 9 work coordinate
//! systems, no tool table, no spindle synchronisation, no path blending).
//!
//! Facts from grblHAL/core at commit f80fc34d503bd62391a23b197b3e0ee66ce00cb7:
//! * `gcode.c` (`gc_execute_block`): the G and M switches with their build
//!   options — G5 cubic splines, G59.1–G59.3, G92.2/G92.3, M6 (ignored
//!   unless a tool change mode or an ATC is set up), M7 (when the driver
//!   has a mist output), M48–M51/M53, M60, M61, M70–M73; G43/G43.2 only
//!   with a tool table (`N_TOOLS` 0 in `config.h`), G33/G76 only with a
//!   spindle that reports its data, G84 only with an at-speed spindle,
//!   G7/G8/G96/G97 only in lathe mode, G64 and G61.1 only with path
//!   blending (off); arcs take P turns, G43.1 any axis.
//! * Canned cycles: `gcode.h` marks G85, G86 and G89 "not implemented"
//!   (accepted, never executed), and `mc_canned_drill` (`motion_control.c`)
//!   retracts G83 pecks to the clearance level without the rapid back
//!   down, dwells 0.25 s after each G73/G83 peck, backs G73 off by `$73`
//!   (0.1 mm by default) and takes a G98 level from each block: none of
//!   them moves as LinuxCNC does, so every cycle is lowered.
//! * G5 without I J takes minus the block's own P Q (LinuxCNC reflects the
//!   previous block's): the driver writes I J on every G5. G5.1 refuses
//!   I0 whatever J is: lowered.
//! * G38.x to the current position is refused (error 33).
//! * `protocol.c`: every byte after the leading blanks, comments and
//!   blanks included, goes into the 257-byte line buffer
//!   (`LINE_BUFFER_SIZE` in `protocol.h`: 256 characters); `config.h`
//!   (`N_AXIS` 3); the real-time command bytes of `grbl.h`.

use crate::controller::profile::{Comments, LineCount, Profile, ToolChange};

pub(crate) const PROFILE: Profile = Profile {
    name: "grblhal",
    summary: "grblHAL, default core build (3 axes, G54-G59.3, no tool table)",
    source: "grblHAL/core f80fc34d gcode.c, gcode.h, motion_control.c, protocol.c, config.h",
    passthrough: false,
    g_codes: &[
        0, 10, 20, 30, 40, 50, 100, 170, 180, 190, 200, 210, 280, 281, 300, 301, 382, 383, 384,
        385, 400, 431, 490, 530, 540, 550, 560, 570, 580, 590, 591, 592, 593, 610, 900, 910, 911,
        920, 921, 922, 923, 930, 940,
    ],
    m_codes: &[
        0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 30, 48, 49, 50, 51, 53, 60, 61, 70, 71, 72, 73,
    ],
    words: b"FIJKLNPQRSTXYZ",
    axes: b"XYZ",
    g10_l: &[2, 20],
    coord_systems: 9,
    line_limit: Some((257, LineCount::AllBytes)),
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
    optional_stop: true,
};
