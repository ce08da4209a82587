//! Target controllers: writing the flat program in a controller's own
//! language, with the same machine motion, or refusing with the reason.
//!
//! A [`Profile`] is data (one TOML file per controller under `profiles/`); the
//! lowering driver ([`Lowering`]) reads each flattened line through the
//! evaluator's consumer hook, runs it on the machine model, and writes what
//! the profile accepts, lowering or refusing the rest.

mod driver;
mod format;
pub mod lower;
mod profile;

pub use driver::Lowering;
pub use format::{format_number, significant_len};
pub use profile::{Comments, LineCount, Profile, ProfileError, ToolChange};

/// The built-in profiles' files, the default first: `targets --show NAME`
/// prints one, and each is read by [`Profile::from_toml`] like a user's.
pub const BUILT_IN: &[(&str, &str)] = &[
    ("linuxcnc", include_str!("profiles/linuxcnc.toml")),
    ("grbl", include_str!("profiles/grbl.toml")),
    ("grblhal", include_str!("profiles/grblhal.toml")),
    ("fluidnc", include_str!("profiles/fluidnc.toml")),
    ("g2core", include_str!("profiles/g2core.toml")),
    ("klipper", include_str!("profiles/klipper.toml")),
    ("marlin", include_str!("profiles/marlin.toml")),
    ("smoothieware", include_str!("profiles/smoothieware.toml")),
    (
        "reprapfirmware",
        include_str!("profiles/reprapfirmware.toml"),
    ),
];

static PROFILES: std::sync::LazyLock<Vec<Profile>> = std::sync::LazyLock::new(|| {
    BUILT_IN
        .iter()
        .map(|(name, text)| {
            Profile::from_toml(text)
                .unwrap_or_else(|e| panic!("built-in profile {name}: {} {e}", e.code()))
        })
        .collect()
});

/// Every built-in profile, the default first.
pub fn profiles() -> &'static [Profile] {
    &PROFILES
}

/// The built-in profile called `name` (case-insensitive).
pub fn find(name: &str) -> Option<&'static Profile> {
    profiles()
        .iter()
        .find(|p| p.name.eq_ignore_ascii_case(name))
}

/// The file of the built-in profile called `name` (case-insensitive).
pub fn built_in_file(name: &str) -> Option<&'static str> {
    BUILT_IN
        .iter()
        .find(|(n, _)| n.eq_ignore_ascii_case(name))
        .map(|(_, text)| *text)
}

/// Whether `--target VALUE` names a profile file rather than a built-in
/// profile: it ends in `.toml` or has a path separator.
pub fn is_profile_file(value: &str) -> bool {
    value.ends_with(".toml") || value.contains('/') || value.contains(std::path::MAIN_SEPARATOR)
}

/// The profile of file `path`. A run uses one profile for its whole life,
/// so it is kept for the rest of the process (leaked), as the built-in
/// ones are.
pub fn load(path: &str) -> Result<&'static Profile, crate::diag::ErrorKind> {
    use crate::diag::{ErrorKind, TargetError};
    let text = std::fs::read_to_string(path).map_err(|e| {
        ErrorKind::Target(TargetError::profile(
            path.to_string(),
            ProfileError::Unreadable {
                message: e.to_string(),
            },
        ))
    })?;
    let p = Profile::from_toml(&text)
        .map_err(|error| ErrorKind::Target(TargetError::profile(path.to_string(), error)))?;
    Ok(Box::leak(Box::new(p)))
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
