//! The arguments shared by every command, resolved into a
//! [`Config`]: files read, values parsed and checked.

use crate::diag::{SetupError, TargetError};
use std::path::{Path, PathBuf};

use super::args::{CommonArgs, FormatArg, GrblEnvelopeArg, OnOff, ToolChangeArg};
use crate::config::{
    Config, IniPaths, expand_tilde, ini_switches, parse_user_m, read_ini, user_m_files,
};
use crate::diag::{Diagnostic, ErrorKind, MessageFormat};
use crate::program::SearchPath;
use crate::settings::{Settings, parse_axis_word, parse_define, read_tool_table, read_var_file};

impl CommonArgs {
    /// The requested diagnostic format.
    pub(super) fn format(&self) -> MessageFormat {
        match self.message_format {
            FormatArg::Human => MessageFormat::Human,
            FormatArg::Short => MessageFormat::Short,
            FormatArg::Json => MessageFormat::Json,
            FormatArg::Github => MessageFormat::Github,
        }
    }

    /// The target's name: --target, else $NGCFLAT_TARGET.
    pub(super) fn target_name(&self) -> Option<String> {
        self.target
            .clone()
            .or_else(|| std::env::var("NGCFLAT_TARGET").ok())
            .filter(|t| !t.is_empty())
    }

    fn target_options(&self) -> Result<Option<crate::controller::TargetOptions>, ErrorKind> {
        use crate::controller::{TargetOptions, ToolChange};
        let Some(name) = self.target_name() else {
            return Ok(None);
        };
        let profile = if crate::controller::is_profile_file(&name) {
            crate::controller::load(&name)?
        } else {
            crate::controller::find(&name)
                .ok_or(ErrorKind::Target(TargetError::UnknownTarget { name }))?
        };
        if !(self.tolerance > 0.0 && self.tolerance.is_finite()) {
            return Err(ErrorKind::Setup(SetupError::BadDefine {
                text: format!("--tolerance {}", self.tolerance),
            }));
        }
        let mut t = TargetOptions::new(profile);
        t.tool_change = self.tool_change.map(|c| match c {
            ToolChangeArg::Pause => ToolChange::Pause,
            ToolChangeArg::Keep => ToolChange::Keep,
            ToolChangeArg::Drop => ToolChange::Drop,
        });
        t.block_delete = self.block_delete == Some(OnOff::On);
        t.tolerance_mm = self.tolerance;
        Ok(t.active().then_some(t))
    }

    /// Builds the configuration; `env_path` is $NGCFLAT_SUBROUTINE_PATH.
    pub(super) fn to_config(&self, env_path: Option<String>) -> Result<Config, ErrorKind> {
        let mut settings = Settings {
            precision: self.precision,
            strip_comments: self.strip_comments,
            max_steps: self.max_steps,
            max_output_lines: self.max_output_lines,
            input: crate::program::InputLimits {
                max_bytes: self.max_input_bytes,
                max_line: self.max_line_bytes,
            },
            max_output_bytes: self.max_output_bytes,
            zero_start: self.zero_start,
            named_params_2007: self.named_params_2007,
            ..Settings::default()
        };
        let mut warnings = Vec::new();
        let mut search = SearchPath {
            program_dir: !self.no_program_dir,
            ..SearchPath::default()
        };
        let mut prefixes = Vec::new();
        if let Some(p) = &self.program_prefix {
            prefixes.push(p.clone());
        }
        let mut dirs: Vec<PathBuf> = self.subroutine_path.clone();
        if let Some(env) = env_path {
            dirs.extend(env.split(':').filter(|s| !s.is_empty()).map(expand_tilde));
        }
        let mut var_file = self.var_file.clone();
        let mut machine = crate::machine::axes::MachineAxes::default();
        if let Some(ini_path) = &self.ini {
            let (ini, base) = read_ini(ini_path)?;
            let mut warn = |kind| warnings.push(Diagnostic::warning(kind, None));
            let paths = IniPaths::read(&ini, &base, var_file.is_none(), &mut warn);
            if self.program_prefix.is_none() {
                prefixes.extend(paths.program_prefix);
            }
            dirs.extend(paths.subroutine_dirs);
            search.recursive.extend(paths.wizard_root);
            var_file = var_file.or(paths.parameter_file);
            ini_switches(&ini, &mut settings, &mut warn);
            machine.add_ini(&ini, settings.machine_metric)?;
            settings.user_m |= user_m_files(&ini, &base);
            settings.ini = Some(ini);
        }
        settings.oword_warn_only |= self.oword_warn_only;
        search.dirs = prefixes.into_iter().chain(dirs).collect();
        self.add_values(&mut settings, var_file.as_deref())?;
        let check_limits = self.add_machine_axes(&mut machine)?;
        let target = self.target_options()?;
        if target.is_some() {
            // A target other than linuxcnc has no user M-codes: they pass the
            // block checks so that the target refuses them with its reason
            // (rather than E0805 suggesting --user-m, which cannot help).
            settings.user_m = (1u128 << 100) - 1;
        }
        Ok(Config {
            settings,
            search,
            format: self.format(),
            warnings,
            machine,
            check_limits,
            target,
        })
    }

    /// The values given on the command line (and the var file): parameters,
    /// tool table, user M-codes, start position.
    fn add_values(
        &self,
        settings: &mut Settings,
        var_file: Option<&Path>,
    ) -> Result<(), ErrorKind> {
        if let Some(v) = var_file {
            settings.defines.extend(read_var_file(v)?);
        }
        if let Some(t) = &self.tool_table {
            settings.tool_table = read_tool_table(t)?;
        }
        for d in &self.define {
            settings.defines.push(parse_define(d)?);
        }
        for m in &self.user_m {
            settings.user_m |= parse_user_m(m)?;
        }
        for word in self
            .start_position
            .iter()
            .flat_map(|s| s.split_whitespace())
        {
            let axis = parse_axis_word(word).ok_or_else(|| {
                ErrorKind::Setup(SetupError::BadStartPosition {
                    text: word.to_string(),
                })
            })?;
            settings.start_position.push(axis);
        }
        Ok(())
    }

    /// Adds the GRBL listing and `--limits` to the axes (which hold the
    /// INI's); returns whether travel limits are checked.
    fn add_machine_axes(
        &self,
        machine: &mut crate::machine::axes::MachineAxes,
    ) -> Result<bool, ErrorKind> {
        if let Some(g) = &self.machine.grbl_settings {
            let text = std::fs::read_to_string(g).map_err(|e| {
                ErrorKind::Setup(SetupError::Io {
                    path: g.clone(),
                    message: e.to_string(),
                })
            })?;
            let env = match self.machine.grbl_envelope {
                GrblEnvelopeArg::Negative => crate::machine::axes::GrblEnvelope::Negative,
                GrblEnvelopeArg::Positive => crate::machine::axes::GrblEnvelope::Positive,
            };
            machine.add_grbl(&text, env)?;
        }
        if let Some(l) = &self.machine.limits {
            machine.add_limits(l)?;
        }
        // --limits and a GRBL listing ask for the check; an INI's limits
        // only with --ini-limits.
        let asked = self.machine.limits.is_some()
            || self.machine.grbl_settings.is_some()
            || self.machine.ini_limits;
        Ok(!self.machine.no_limits && asked && machine.has_limits())
    }
}
