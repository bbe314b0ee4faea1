//! `[monitoring]`: environmental compensation and alarms on the updated
//! parameters (the core's `monitoring`).

use super::{err, Config, ConfigError};
use serde::{Deserialize, Serialize};
use splinewatch_core::monitoring::{LimitMethod, MonitoringError, Settings};

/// `[monitoring]`; present: every accepted update is scored. Every key but
/// the section itself is optional.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct MonitoringConfig {
    /// Channels on `<prefix>/temperature/<name>` (°C); none: the PCA variant.
    pub temperature_channels: Vec<String>,
    /// Accepted updates that train the reference.
    pub training_windows: usize,
    /// Train instead on the updates from this time (RFC 3339) …
    pub training_from: Option<String>,
    /// … until this one (exclusive); both or neither.
    pub training_until: Option<String>,
    /// Knee of the hinge term (°C): stiffening below it.
    pub knee_c: f64,
    /// Lagged temperature terms (windows).
    pub lags: usize,
    /// Principal components removed without temperatures.
    pub pca_components: usize,
    /// MEWMA smoothing λ.
    pub ewma_lambda: f64,
    /// Target false-alarm probability per window of each chart.
    pub false_alarm_rate: f64,
    /// `[k, m]`: an alarm after `k` exceedances in the last `m` scored windows.
    pub persistence: [usize; 2],
    /// Margin around the training temperature range (°C).
    pub range_margin_c: f64,
    /// Cross-validation folds of the control limits.
    pub folds: usize,
    /// A channel repeating one value exactly over this many windows is stuck
    /// (treated as missing).
    pub stuck_windows: usize,
    /// The persisted reference (default `monitoring.json` beside the state file).
    pub state_file: Option<std::path::PathBuf>,
    /// `"held_out"` (default): limits from cross-validated training windows;
    /// `"theoretical"`: the textbook F law (trusts the model).
    #[schemars(with = "super::schema::LimitMethodDef")]
    pub limits: LimitMethod,
    /// Output-only: an identified frequency is monitored when its mode was
    /// identified in at least this share of the training windows.
    pub feature_presence: f64,
    /// `[monitoring.notify]`: tell the owner when the alarm state changes.
    pub notify: Option<NotifyConfig>,
}

/// `[monitoring.notify]`: a command run with the monitoring status JSON on
/// its standard input, and/or a webhook it is POSTed to, whenever the alarm
/// state changes (raised, cleared, outside the training range entered or
/// left).
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct NotifyConfig {
    /// The program and its arguments (no shell unless named); empty: none.
    #[serde(default)]
    pub command: Vec<String>,
    /// An `https://` URL the status JSON is POSTed to (TLS verified).
    #[serde(default)]
    pub webhook: Option<String>,
    /// A file whose first line is the webhook's bearer token (read at each
    /// delivery, so a rotated token needs no restart).
    #[serde(default)]
    pub bearer_token_file: Option<std::path::PathBuf>,
    /// CA certificates (PEM) the webhook's server certificate must chain
    /// to, in place of the Mozilla roots (a site's own CA).
    #[serde(default)]
    pub ca_file: Option<std::path::PathBuf>,
    /// Further runs after a failure, 0.5, 1, 2, … s apart.
    #[serde(default = "default_notify_retries")]
    pub retries: u32,
    /// A run longer than this is killed and counts as failed.
    #[serde(default = "default_notify_timeout")]
    pub timeout_seconds: f64,
}

impl NotifyConfig {
    /// A command or a webhook (or both), `https` and files that can be
    /// read, a positive time limit, at most 10 retries.
    fn check(&self) -> Result<(), ConfigError> {
        if self.command.is_empty() && self.webhook.is_none() {
            return Err(err(
                "monitoring.notify",
                "give a command = [\"/path/prog\", \"arg\", …] or a webhook = \"https://…\"",
            ));
        }
        if !self.command.is_empty() && self.command[0].is_empty() {
            return Err(err(
                "monitoring.notify.command",
                "must name a program: [\"/path/prog\", \"arg\", …]",
            ));
        }
        if let Some(url) = &self.webhook {
            let rest = url.strip_prefix("https://").unwrap_or_default();
            if rest.is_empty() || rest.starts_with('/') {
                return Err(err(
                    "monitoring.notify.webhook",
                    format!("must be an https:// URL with a host (the status is sent over verified TLS), got {url:?}"),
                ));
            }
        } else if self.bearer_token_file.is_some() || self.ca_file.is_some() {
            return Err(err(
                "monitoring.notify",
                "bearer_token_file and ca_file are for a webhook: give webhook = \"https://…\"",
            ));
        }
        if let Some(path) = &self.bearer_token_file {
            self.bearer_token(path)
                .map_err(|e| err("monitoring.notify.bearer_token_file", e))?;
        }
        if let Some(path) = &self.ca_file {
            let pem = std::fs::read(path)
                .map_err(|e| err("monitoring.notify.ca_file", format!("{}: {e}", path.display())))?;
            if !String::from_utf8_lossy(&pem).contains("-----BEGIN CERTIFICATE-----") {
                return Err(err(
                    "monitoring.notify.ca_file",
                    format!("{}: no PEM certificate in it", path.display()),
                ));
            }
        }
        if !(self.timeout_seconds.is_finite() && self.timeout_seconds > 0.0) {
            return Err(err(
                "monitoring.notify.timeout_seconds",
                "must be a positive number of seconds",
            ));
        }
        if self.retries > 10 {
            return Err(err("monitoring.notify.retries", "at most 10"));
        }
        Ok(())
    }

    /// The bearer token: the first line of `path`, trimmed, not empty.
    pub fn bearer_token(&self, path: &std::path::Path) -> Result<String, String> {
        let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let token = text.lines().next().unwrap_or_default().trim();
        if token.is_empty() {
            return Err(format!("{}: the first line holds no token", path.display()));
        }
        Ok(token.to_string())
    }
}

impl Default for NotifyConfig {
    /// No target yet; the defaults of `retries` and `timeout_seconds`.
    fn default() -> Self {
        Self {
            command: Vec::new(),
            webhook: None,
            bearer_token_file: None,
            ca_file: None,
            retries: default_notify_retries(),
            timeout_seconds: default_notify_timeout(),
        }
    }
}

fn default_notify_retries() -> u32 {
    3
}

fn default_notify_timeout() -> f64 {
    30.0
}

impl Default for MonitoringConfig {
    fn default() -> Self {
        let d = Settings::default();
        Self {
            temperature_channels: Vec::new(),
            training_windows: 100,
            training_from: None,
            training_until: None,
            knee_c: d.knee_c,
            lags: d.lags,
            pca_components: d.pca_components,
            ewma_lambda: d.ewma_lambda,
            false_alarm_rate: d.false_alarm_rate,
            persistence: d.persistence,
            range_margin_c: d.range_margin_c,
            folds: d.folds,
            stuck_windows: 3,
            state_file: None,
            limits: d.limits,
            feature_presence: d.feature_presence,
            notify: None,
        }
    }
}

impl MonitoringConfig {
    /// `(from, until)` in ns when training on a time span.
    pub fn training_span(&self) -> Result<Option<(i128, i128)>, ConfigError> {
        let at = |key: &str, t: &String| {
            time::OffsetDateTime::parse(t, &time::format_description::well_known::Rfc3339)
                .map(|t| t.unix_timestamp_nanos())
                .map_err(|e| {
                    err(
                        format!("monitoring.{key}"),
                        format!("{t:?} is not an RFC 3339 timestamp: {e}"),
                    )
                })
        };
        match (&self.training_from, &self.training_until) {
            (None, None) => Ok(None),
            (Some(from), Some(until)) => {
                let (from, until) = (at("training_from", from)?, at("training_until", until)?);
                if from >= until {
                    return Err(err("monitoring.training_until", "must be after training_from"));
                }
                Ok(Some((from, until)))
            }
            (Some(_), None) => Err(err("monitoring.training_until", "needed with training_from")),
            (None, Some(_)) => Err(err("monitoring.training_from", "needed with training_until")),
        }
    }

    /// The core's settings.
    pub fn settings(&self) -> Settings {
        Settings {
            temperature_channels: self.temperature_channels.len(),
            knee_c: self.knee_c,
            lags: self.lags,
            pca_components: self.pca_components,
            ewma_lambda: self.ewma_lambda,
            false_alarm_rate: self.false_alarm_rate,
            persistence: self.persistence,
            range_margin_c: self.range_margin_c,
            folds: self.folds,
            limits: self.limits,
            feature_presence: self.feature_presence,
        }
    }
}

impl Config {
    /// Checks `[monitoring]`, if present.
    pub fn validate_monitoring(&self) -> Result<(), ConfigError> {
        let Some(m) = &self.monitoring else {
            return Ok(());
        };
        let mut seen = std::collections::BTreeSet::new();
        for (i, name) in m.temperature_channels.iter().enumerate() {
            if name.is_empty() || name.contains('/') || name.contains(char::is_whitespace) || !seen.insert(name) {
                return Err(err(
                    format!("monitoring.temperature_channels[{i}]"),
                    format!("{name:?} must be a unique non-empty name without '/' or spaces"),
                ));
            }
        }
        if m.training_windows < 10 {
            return Err(err("monitoring.training_windows", "must be at least 10"));
        }
        m.training_span()?;
        if m.stuck_windows < 2 {
            return Err(err("monitoring.stuck_windows", "must be at least 2"));
        }
        if let Some(n) = &m.notify {
            n.check()?;
        }
        m.settings().check().map_err(|e| match e {
            MonitoringError::Setting { name, .. } => err(format!("monitoring.{name}"), e),
            other => err("monitoring", other),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn with(section: &str) -> Result<(), ConfigError> {
        let text = format!(
            "{}\n[monitoring]\n{section}\n",
            include_str!("../../config/sinello.toml")
        );
        Config::from_toml(&text)?.validate_monitoring()
    }

    #[test]
    fn bad_monitoring_keys_are_named() {
        assert!(with("temperature_channels = [\"T1\", \"T2\"]").is_ok());
        for (section, key) in [
            (
                "temperature_channels = [\"T1\", \"T1\"]",
                "monitoring.temperature_channels[1]",
            ),
            ("temperature_channels = [\"a/b\"]", "monitoring.temperature_channels[0]"),
            ("training_windows = 3", "monitoring.training_windows"),
            ("ewma_lambda = 0.0", "monitoring.ewma_lambda"),
            ("persistence = [4, 3]", "monitoring.persistence"),
            ("false_alarm_rate = 0.7", "monitoring.false_alarm_rate"),
            ("feature_presence = 0.0", "monitoring.feature_presence"),
            ("training_from = \"2026-11-21T10:00:00Z\"", "monitoring.training_until"),
            (
                "training_from = \"2026-11-22T10:00:00Z\"\ntraining_until = \"2026-11-21T10:00:00Z\"",
                "monitoring.training_until",
            ),
            (
                "training_from = \"noon\"\ntraining_until = \"2026-11-21T10:00:00Z\"",
                "monitoring.training_from",
            ),
        ] {
            let e = with(section).unwrap_err().to_string();
            assert!(e.contains(key), "{section}: {e}");
        }
        let e = Config::from_toml(&format!(
            "{}\n[monitoring]\nalpha = 1\n",
            include_str!("../../config/sinello.toml")
        ))
        .unwrap_err()
        .to_string();
        assert!(e.contains("monitoring"), "{e}");
    }

    /// The bundled monitoring example is the bundled deck plus a global
    /// modulus scale and `[monitoring]`.
    #[test]
    fn the_monitoring_example_is_the_bundled_deck_with_a_modulus_scale() {
        let monitoring = Config::from_toml(include_str!("../../config/sinello-monitoring.toml")).unwrap();
        let bundled = Config::from_toml(include_str!("../../config/sinello.toml")).unwrap();
        monitoring.validate().unwrap();
        let mut model = serde_json::to_value(&monitoring.model).unwrap();
        let fields = model["stiffness_fields"].as_array().unwrap().clone();
        assert_eq!(fields.len(), 1);
        assert_eq!(fields[0]["name"], "deck");
        model["stiffness_fields"] = serde_json::json!([]);
        assert_eq!(model, serde_json::to_value(&bundled.model).unwrap());
        assert_eq!(
            serde_json::to_value(&monitoring.sensors).unwrap(),
            serde_json::to_value(&bundled.sensors).unwrap()
        );
        let m = monitoring.monitoring.unwrap();
        assert_eq!(
            (m.temperature_channels, m.training_windows),
            (vec!["T1".to_string()], 100)
        );
    }
}
