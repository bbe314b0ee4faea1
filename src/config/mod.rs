//! The TOML configuration: parsed with serde (unknown keys rejected), then
//! validated into the core crate's types. Every error names the key path.
//! Room: the schema and its validation. May import: the core crate only.
//!
//! Physics (`[model.geometry]`, `[model.material]`, `[[model.springs]]`,
//! `[[model.constraints]]`) is kept apart from discretisation
//! (`[model.discretization]`); see the guide's configuration reference for every key.

mod built_model;
mod events;
mod frequency_domain;
mod frf;
mod ground;
mod kappa_order;
mod loss_factor;
mod loss_sites;
mod materials;
mod metrics;
mod model;
mod monitoring;
mod oma;
mod output;
mod patches;
mod schedule;
mod schema;
mod setup;
mod tie;
#[cfg(feature = "daemon")]
mod tls;
mod updating;
mod web;
mod zenoh;

pub use events::{EventAmplitude, EventForecast, EventsConfig, ResponseFunction};
pub use frequency_domain::{FrequencyDomainConfig, FrequencyDomainPlan, MAX_FITTED_MODES};
pub use frf::FrfConfig;
pub use ground::{ground_sensors, ground_signals, restrict_plan, GroundInputPlan};
pub use loss_factor::{ComponentLossFactor, LossFactorConfig, LossFactorTable};
pub use loss_sites::LossSite;
pub use metrics::MetricsConfig;
pub use model::{
    ConstraintConfig, DampingConfig, DirectionConfig, DiscretizationConfig, EdgeConfig, GeometryConfig, ModelConfig,
    ModesChoice, QuantityList, SensorConfig, SolverConfig, SpringConfig, StiffnessFieldConfig, SupportConfig,
    AUTO_TRUNCATED_CONTROL_POINTS, MAX_CONTROL_POINTS, MAX_DENSE_CONTROL_POINTS,
};
pub use monitoring::{MonitoringConfig, NotifyConfig};
pub use oma::{horizon_rows, OmaConfig};
pub use output::{OutputConfig, RawRecordingConfig};
pub use patches::FaceConfig;
pub use schedule::ScheduleConfig;
pub use schema::config_schema;
pub use setup::{frf_setup, frf_setup_of, frf_setup_with_points, solver_model, FrfSetup};
#[cfg(feature = "daemon")]
pub use tls::{CertificateSummary, TlsFile, TlsReport, EXPIRY_WARNING_DAYS};
pub use updating::{ParameterFamily, Residues, UpdatingConfig};
pub use web::{WebConfig, WebTlsConfig};
pub use zenoh::ZenohConfig;

use anyhow::Context;
use serde::{Deserialize, Serialize};
use std::fmt::Display;
use std::path::Path;
use thiserror::Error;

/// A configuration error: the key path and what is wrong with it.
#[derive(Debug, Error)]
#[error("config: {path}: {message}")]
pub struct ConfigError {
    pub path: String,
    pub message: String,
}

pub(crate) fn err(path: impl Into<String>, message: impl Display) -> ConfigError {
    ConfigError {
        path: path.into(),
        message: message.to_string(),
    }
}

#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Config {
    pub structure: StructureConfig,
    /// The deck; absent, only what needs no model works (`oma`, `import`,
    /// `frf`): the others say `model: no deck`.
    #[serde(default)]
    pub model: ModelConfig,
    #[serde(default)]
    pub sensors: Vec<SensorConfig>,
    #[serde(default)]
    pub updating: UpdatingConfig,
    #[serde(default)]
    pub frf: FrfConfig,
    #[serde(default)]
    pub schedule: ScheduleConfig,
    #[serde(default)]
    pub output: OutputConfig,
    #[serde(default)]
    pub zenoh: ZenohConfig,
    /// `[oma]`: absent, an output-only config identifies with the defaults
    /// and a config with a force sensor does not identify at all
    /// ([`Config::runs_oma`]); read through [`Config::oma`].
    #[serde(default, rename = "oma")]
    pub oma_section: Option<OmaConfig>,
    /// `[monitoring]`: compensation and alarms; absent: none.
    #[serde(default)]
    pub monitoring: Option<MonitoringConfig>,
    /// `[events]`: earthquake records one event at a time (`events`; the
    /// daemon on a triggered logger when present). Read through
    /// [`Config::events`].
    #[serde(default, rename = "events")]
    pub events_section: Option<EventsConfig>,
    /// `[metrics]`: Prometheus text at `/metrics` (daemon, `replay --metrics`); absent: none.
    #[serde(default)]
    pub metrics: Option<MetricsConfig>,
    /// `[web]`: the daemon's read-only status page; absent: none.
    #[serde(default)]
    pub web: Option<WebConfig>,
    /// The file the config was read from and its text ([`load_config`]),
    /// which the results files record; none for a config made in memory.
    #[serde(skip)]
    pub source: Option<ConfigSource>,
    /// The model `model` describes, once built ([`Config::build_model`]).
    #[serde(skip)]
    built_model: built_model::BuiltModel,
}

/// Where a config came from: its path and its text as read.
#[derive(Debug, Clone, Default)]
pub struct ConfigSource {
    pub path: std::path::PathBuf,
    pub text: String,
}

#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct StructureConfig {
    /// Identifier of the monitored structure; also the default zenoh/MCAP prefix
    /// `bridge/<name>`.
    pub name: String,
}

/// Reads and validates a configuration file.
pub fn load_config(path: &Path) -> anyhow::Result<Config> {
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read config file {}", path.display()))?;
    let mut config = Config::from_toml(&text).with_context(|| path.display().to_string())?;
    config.validate().with_context(|| path.display().to_string())?;
    config.source = Some(ConfigSource {
        path: path.to_path_buf(),
        text,
    });
    Ok(config)
}

impl Config {
    /// Parses TOML text. A syntax error names its line and column; a value
    /// of the wrong type or an unknown key names its key path
    /// (`model.material.density`, or the table holding an unknown key) and
    /// its line.
    pub fn from_toml(text: &str) -> Result<Self, ConfigError> {
        let at = |e: &toml::de::Error| e.span().map(|s| line_of(text, s.start));
        let document = toml::Deserializer::parse(text)
            .map_err(|e| err(at(&e).unwrap_or_else(|| "(document)".into()), e.message()))?;
        let config: Config = serde_path_to_error::deserialize(document).map_err(|e| {
            let path = e.path().to_string();
            let inner = e.into_inner();
            let message = match at(&inner) {
                Some(line) => format!("{} ({line})", inner.message()),
                None => inner.message().to_string(),
            };
            err(if path == "." { "(document)".into() } else { path }, message)
        })?;
        config.validate_names()?;
        let mut config = config;
        config.place_ground_sensors_last()?;
        Ok(config)
    }

    /// Whether the config describes a deck (`[model]` with a geometry or
    /// patches).
    pub fn has_model(&self) -> bool {
        let m = &self.model;
        m.geometry.is_some() || m.discretization.is_some() || m.material.is_some() || !m.patches.is_empty()
    }

    fn validate_names(&self) -> Result<(), ConfigError> {
        if self.structure.name.trim().is_empty() {
            return Err(err("structure.name", "must not be empty"));
        }
        let mut seen = std::collections::BTreeSet::new();
        for (i, s) in self.sensors.iter().enumerate() {
            if s.name.trim().is_empty() || s.name.contains('/') || s.name.contains(char::is_whitespace) {
                return Err(err(
                    format!("sensors[{i}].name"),
                    format!("{:?} must be non-empty without '/' or spaces", s.name),
                ));
            }
            if !seen.insert(s.name.as_str()) {
                return Err(err(format!("sensors[{i}].name"), format!("{:?} is used twice", s.name)));
            }
        }
        let mut seen = std::collections::BTreeSet::new();
        for (i, s) in self.model.springs.iter().enumerate() {
            let valid = !s.name.is_empty()
                && s.name
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
            if !valid {
                return Err(err(
                    format!("model.springs[{i}].name"),
                    format!("{:?} must be non-empty ASCII letters, digits, '_' or '-'", s.name),
                ));
            }
            if !seen.insert(s.name.as_str()) {
                return Err(err(
                    format!("model.springs[{i}].name"),
                    format!("{:?} is used twice", s.name),
                ));
            }
        }
        Ok(())
    }

    /// Results folder: `[output] dir`, default `out/<structure.name>`.
    pub fn output_dir(&self) -> std::path::PathBuf {
        self.output
            .dir
            .clone()
            .unwrap_or_else(|| std::path::Path::new("out").join(&self.structure.name))
    }

    /// `[events]`, or its defaults when the section is absent.
    pub fn events(&self) -> &EventsConfig {
        static DEFAULTS: std::sync::LazyLock<EventsConfig> = std::sync::LazyLock::new(EventsConfig::default);
        self.events_section.as_ref().unwrap_or(&DEFAULTS)
    }

    /// Where the daemon on a triggered logger (`[events]`) keeps its chain
    /// next to the state file `state_file`: `events.json` beside it.
    pub fn events_file(&self, state_file: &Path) -> Option<std::path::PathBuf> {
        self.events_section.as_ref()?;
        Some(state_file.with_file_name("events.json"))
    }

    /// Where the monitor (`[monitoring]`) persists next to the state file
    /// `state_file`: `[monitoring] state_file`, or `monitoring.json` beside it.
    pub fn monitor_file(&self, state_file: &Path) -> Option<std::path::PathBuf> {
        let m = self.monitoring.as_ref()?;
        Some(
            m.state_file
                .clone()
                .unwrap_or_else(|| state_file.with_file_name("monitoring.json")),
        )
    }

    /// Topic / key-expression prefix: `bridge/<structure.name>`.
    pub fn topic_prefix(&self) -> String {
        format!("bridge/{}", self.structure.name)
    }

    /// Builds every section, so all errors surface at load time.
    pub fn validate(&self) -> Result<(), ConfigError> {
        // Without a model only the sensors and the analysis settings are
        // checked (output-only identification needs no deck).
        if self.has_model() {
            let model = self.build_model()?;
            self.build_sensors(&model)?;
            let groups = self.support_groups(&model)?;
            self.ground_plan(&groups)?;
            self.modal_cutoff_hz()?;
            self.loss_sites()?;
            if self.model.damping.is_some() {
                self.build_damping()?;
            }
            self.build_parameters()?;
        } else if self.has_ground_sensors() {
            self.ground_plan_of_sensors()?;
        } else if self.sensors.is_empty() {
            return Err(err(
                "model",
                "no deck and no sensors: give [model] (or [[model.patches]]), or [[sensors]] for output-only identification",
            ));
        }
        self.update_settings()?;
        // The sampling rate is only known from the data; check with a nominal one.
        self.welch_settings(256.0)?;
        // A config without sensors serves the model's own commands (`modes`,
        // `check-config`, `matrices`); those that need sensors say so.
        if !self.sensors.is_empty() && self.runs_oma() {
            self.oma_settings()?;
        }
        if !self.sensors.is_empty() {
            self.frequency_domain()?;
            self.residues()?;
        }
        self.validate_monitoring()?;
        let deck: Vec<&str> = self.sensors[..self.deck_sensor_count()]
            .iter()
            .map(|s| s.name.as_str())
            .collect();
        self.events().check(&deck)?;
        if let Some(m) = &self.metrics {
            m.check()?;
        }
        if let Some(w) = &self.web {
            w.check(self.metrics.as_ref().map(|m| m.listen.as_str()))?;
        }
        for (key, hours) in [
            ("output.rerun_rotate_hours", self.output.rerun_rotate_hours),
            ("output.results_rotate_hours", self.output.results_rotate_hours),
        ] {
            if !(hours.is_finite() && hours >= 1.0 / 3600.0) {
                return Err(err(key, format!("must be at least one second (1/3600 h), got {hours}")));
            }
        }
        let raw = &self.output.raw;
        if !(raw.rotate_minutes.is_finite() && raw.rotate_minutes > 0.0) {
            return Err(err(
                "output.raw.rotate_minutes",
                format!("must be a positive number of minutes, got {}", raw.rotate_minutes),
            ));
        }
        if !(raw.rotate_megabytes.is_finite() && raw.rotate_megabytes >= 0.01) {
            return Err(err(
                "output.raw.rotate_megabytes",
                format!("must be at least 0.01, got {}", raw.rotate_megabytes),
            ));
        }
        for (key, endpoints) in [
            ("zenoh.listen", &self.zenoh.listen),
            ("zenoh.connect", &self.zenoh.connect),
        ] {
            if let Some((i, e)) = endpoints
                .iter()
                .enumerate()
                .find(|(_, e)| !(e.starts_with("tcp/") || e.starts_with("tls/")))
            {
                return Err(err(
                    format!("{key}[{i}]"),
                    format!(
                        "{e:?}: this build speaks zenoh over TCP and TLS only (\"tcp/<host>:<port>\", \
                         \"tls/<host>:<port>\"; guide: docs/guide/src/deployment/tls.md)"
                    ),
                ));
            }
        }
        Ok(())
    }
}

/// "line L, column C" of a byte offset, for parse errors.
fn line_of(text: &str, offset: usize) -> String {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    format!("line {line}, column {column}")
}

#[cfg(test)]
mod tests {
    use super::*;

    const SINELLO: &str = include_str!("../../config/sinello.toml");

    fn error_of(edit: impl Fn(&str) -> String) -> String {
        let text = edit(SINELLO);
        match Config::from_toml(&text).and_then(|c| c.build_model().map(|_| c)) {
            Ok(_) => panic!("expected an error"),
            Err(e) => e.to_string(),
        }
    }

    #[test]
    fn a_validated_config_builds_its_model_once_and_never_a_stale_one() {
        let mut config = Config::from_toml(SINELLO).unwrap();
        assert!(!config.built_model.is_kept());
        config.validate().unwrap();
        assert!(config.built_model.is_kept(), "validating builds the model the run uses");
        let fresh = |c: &Config| format!("{:?}", c.build_model_anew().unwrap());
        let copy = config.clone();
        assert_eq!(format!("{:?}", copy.build_model().unwrap()), fresh(&config));
        // Changed after loading (as monitor, demo and soak do): its own model.
        config.model.material.as_mut().unwrap().e1 *= 1.1;
        let changed = format!("{:?}", config.build_model().unwrap());
        assert_eq!(changed, fresh(&config));
        assert_ne!(changed, fresh(&copy));
        // A change outside [model] does not touch the model.
        config.sensors.pop();
        assert_eq!(format!("{:?}", config.build_model().unwrap()), changed);
    }

    #[test]
    fn bundled_config_builds() {
        let model = Config::from_toml(SINELLO).unwrap().build_model().unwrap();
        assert_eq!(model.control_point_count(), 65);
        assert_eq!(model.springs.len(), 2);
    }

    #[test]
    fn errors_name_the_key() {
        let e = error_of(|t| t.replace("thickness = 1.6", "thickness = -1.6"));
        assert!(
            e.contains("config: model.geometry.thickness: ") && e.contains("-1.6"),
            "{e}"
        );
        let e = error_of(|t| {
            t.replacen(
                "knots_eta = [0.0, 0.0, 0.0, 0.5, 1.0, 1.0, 1.0]",
                "knots_eta = [0.0, 0.0, 0.0, 0.7, 0.5, 1.0, 1.0, 1.0]",
                1,
            )
        });
        assert!(
            e.contains("model.springs[0].knots_eta") && e.contains("not non-decreasing at index 4"),
            "{e}"
        );
        let e = error_of(|t| {
            t.replacen(
                "stiffness = [0.4e9, 1.5e9, 1.8e9, 0.6e9]",
                "stiffness = [0.4e9, 1.5e9, 1.8e9]",
                1,
            )
        });
        assert!(
            e.contains("model.springs[0].stiffness") && e.contains("3 stiffness coefficients given"),
            "{e}"
        );
        let e = error_of(|t| t.replace("[structure]", "[structure]\ncolour = \"red\""));
        // toml reports the span of the table holding the unknown key.
        assert!(e.contains("unknown field `colour`") && e.contains("line 9"), "{e}");
        let e = error_of(|t| t.replace("nu12 = 0.3", "nu12 = 3.0"));
        assert!(e.contains("model.material") && e.contains("nu12"), "{e}");
        let e = error_of(|t| t.replacen("direction = \"z\"", "direction = \"up\"", 1));
        assert!(e.contains("model.springs[0].direction"), "{e}");
        let e = error_of(|t| t.replace("control_points = [13, 5]", "control_points = [13, 4]"));
        assert!(
            e.contains("model.discretization.control_points") && e.contains("4 basis functions"),
            "{e}"
        );
        let e = error_of(|t| t.replace("control_points = [13, 5]", "control_points = [13, 99999]"));
        assert!(
            e.contains("model.discretization.control_points") && e.contains("exceed"),
            "{e}"
        );
        // 4 000 control points: the sparse path takes them, the dense one refuses.
        let big =
            Config::from_toml(&SINELLO.replace("control_points = [13, 5]", "control_points = [100, 40]")).unwrap();
        assert_eq!(big.build_model().unwrap().control_point_count(), 4000);
        let e = big.build_dense_model().unwrap_err().to_string();
        assert!(
            e.contains("model.discretization.control_points") && e.contains("--cutoff"),
            "{e}"
        );
        // `[model.solver]`: `auto` keeps the bundled deck dense and truncates
        // the big net at twice the 80 Hz band; `all` and a bad cut-off.
        assert_eq!(Config::from_toml(SINELLO).unwrap().modal_cutoff_hz().unwrap(), None);
        assert_eq!(big.modal_cutoff_hz().unwrap(), Some(160.0));
        let all = format!(
            "{}\n[model.solver]\nmodes = \"all\"\n",
            SINELLO.replace("control_points = [13, 5]", "control_points = [100, 40]")
        );
        assert_eq!(Config::from_toml(&all).unwrap().modal_cutoff_hz().unwrap(), None);
        let zero = format!("{SINELLO}\n[model.solver]\nmodes = \"truncated\"\ncutoff_hz = 0.0\n");
        let e = Config::from_toml(&zero)
            .unwrap()
            .modal_cutoff_hz()
            .unwrap_err()
            .to_string();
        assert!(e.contains("model.solver.cutoff_hz"), "{e}");
        let e = error_of(|t| format!("{t}\n[model.solver]\nmodes = \"some\"\n"));
        assert!(e.contains("modes") && e.contains("some"), "{e}");
        let e = error_of(|t| t.replace("name = \"east\"", "name = \"west\""));
        assert!(e.contains("model.springs[1].name") && e.contains("used twice"), "{e}");
        let e = error_of(|t| t.replacen("bounds = [1.0e7, 5.0e9]", "bounds = [1.0e7, 1.0e9]", 1));
        assert!(e.contains("outside bounds"), "{e}");
        let e = error_of(|t| t.replace("knots_xi = [0.97, 1.0]", "knots_xi = [0.97, 1.2]"));
        assert!(
            e.contains("model.springs[1]") && e.contains("not inside the shell"),
            "{e}"
        );
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]
        #[test]
        fn mutated_configs_never_panic(flips in proptest::collection::vec((proptest::prelude::any::<proptest::sample::Index>(), proptest::prelude::any::<u8>()), 1..4)) {
            let mut bytes = SINELLO.as_bytes().to_vec();
            for (i, b) in &flips {
                let k = i.index(bytes.len());
                bytes[k] = *b;
            }
            if let Ok(text) = std::str::from_utf8(&bytes) {
                if let Ok(c) = Config::from_toml(text) {
                    let _ = c.validate();
                }
            }
        }
    }

    #[test]
    fn knot_insertion_refines_the_net() {
        let text = SINELLO.replace(
            "control_points = [13, 5]",
            "control_points = [13, 5]\ninsert_knots_eta = [0.25, 0.75]",
        );
        let model = Config::from_toml(&text).unwrap().build_model().unwrap();
        assert_eq!(model.patches[0].shell.surface().net_size(), (13, 7));
        let e = error_of(|t| {
            t.replace(
                "control_points = [13, 5]",
                "control_points = [13, 5]\ninsert_knots_xi = [1.5]",
            )
        });
        assert!(e.contains("model.discretization.insert_knots_xi[0]"), "{e}");
    }
}
