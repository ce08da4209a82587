//! Target controllers: writing the flat program in a controller's own
//! language, with the same machine motion, or refusing with the reason.
//!
//! A [`Profile`] is data (one file per controller under `profiles/`); the
//! lowering driver ([`Lowering`]) reads each flattened line through the
//! evaluator's consumer hook, runs it on the machine model, and writes what
//! the profile accepts, lowering or refusing the rest.

mod driver;
mod format;
pub mod lower;
mod profile;
pub(crate) mod profiles;

pub use driver::Lowering;
pub use format::{format_number, significant_len};
pub use profile::{Comments, LineCount, Profile, ToolChange};

/// Every profile, the default first.
pub const PROFILES: &[&Profile] = &[
    &profiles::linuxcnc::PROFILE,
    &profiles::grbl::PROFILE,
    &profiles::grblhal::PROFILE,
    &profiles::fluidnc::PROFILE,
];

/// The profile called `name` (case-insensitive).
pub fn find(name: &str) -> Option<&'static Profile> {
    PROFILES
        .iter()
        .copied()
        .find(|p| p.name.eq_ignore_ascii_case(name))
}

/// Options of a target run.
#[derive(Debug, Clone)]
pub struct TargetOptions {
    pub profile: &'static Profile,
    /// `--tool-change`; the profile's default when not given.
    pub tool_change: Option<ToolChange>,
    /// `--block-delete on`: `/` lines are skipped (LinuxCNC's switch on).
    pub block_delete: bool,
    /// `--tolerance` in millimetres (spline segments).
    pub tolerance_mm: f64,
    /// Check mode: keep every problem instead of stopping at the first.
    pub check: bool,
}

impl TargetOptions {
    pub fn new(profile: &'static Profile) -> TargetOptions {
        TargetOptions {
            profile,
            tool_change: None,
            block_delete: false,
            tolerance_mm: 0.001,
            check: false,
        }
    }

    /// Whether lines go through the lowering at all.
    pub fn active(&self) -> bool {
        !self.profile.passthrough
    }
}
