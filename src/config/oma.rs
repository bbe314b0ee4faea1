//! `[oma]`: output-only (operational) modal analysis, SSI-cov.

use super::{err, Config, ConfigError};
use serde::{Deserialize, Serialize};
use splinewatch_core::identification::oma::{ClusterCriteria, OmaSettings, StabilityCriteria, UncertaintyMethod};

/// Settings of the identification (`[oma]`); every key is optional. The
/// defaults suit a deck with modes from a few Hz to the band's top at 12
/// channels: 40 block rows, orders 2–120, KOMA-like stabilisation.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct OmaConfig {
    /// Reference sensors (names); empty: every acceleration sensor.
    pub references: Vec<String>,
    /// Length of an identification window (s) for an output-only config;
    /// default: `frf.window_seconds`. SSI-cov wants long windows: 10–30
    /// minutes on a deck (≥ 1000 periods of the first mode).
    pub window_seconds: Option<f64>,
    /// Hop between window starts (s); default: the window (no overlap).
    pub window_hop_seconds: Option<f64>,
    /// Horizon: block rows of the Hankel (SSI-cov) or data (SRIM) matrices,
    /// in samples; the orders computed are capped at the size it gives.
    pub block_rows: usize,
    /// The horizon in seconds instead: `block_rows` is this times the
    /// record's rate, so one config holds records at 50, 100 and 200 Hz
    /// (a station's recorders of several vintages) with the same horizon
    /// and the same shortest usable record.
    pub horizon_seconds: Option<f64>,
    /// SRIM of records (`identify` with ground inputs, `events`, the
    /// realization): a record sampled faster than this rate (Hz) is first
    /// resampled to it (Fourier series truncated: an ideal low-pass at half
    /// of it; mdof's `decimate`, anti-aliased). The information matrix
    /// shrinks with the square of the ratio and its decomposition with the
    /// cube: strong-motion records at 100–200 Hz of bridges whose modes lie
    /// below 20 Hz lose nothing. The modes are sought below half of it:
    /// `band` must end there; the band taken from `frf.band` is cut there.
    pub resample_hz: Option<f64>,
    /// Lowest model order of the stabilisation diagram.
    pub min_order: usize,
    /// Highest model order of the stabilisation diagram.
    pub max_order: usize,
    /// Step between the orders computed.
    pub order_step: usize,
    /// Band of the reported modes (Hz); default: `frf.band`.
    pub band: Option<[f64; 2]>,
    /// Correlation batches of the uncertainty (delete-one replicates).
    pub batches: usize,
    /// `"first_order"` (default) or `"jackknife"`: how each replicate's
    /// poles are obtained.
    #[schemars(with = "super::schema::UncertaintyMethodDef")]
    pub uncertainty: UncertaintyMethod,
    #[schemars(with = "super::schema::StabilityCriteriaDef")]
    pub stability: StabilityCriteria,
    #[schemars(with = "super::schema::ClusterCriteriaDef")]
    pub clustering: ClusterCriteria,
    /// `[oma.frequency_domain]`: records with measured inputs (`identify`,
    /// `events`) also get the modes a pole–residue fit of their H1
    /// transmissibilities finds in this band; absent: SRIM's alone.
    pub frequency_domain: Option<super::FrequencyDomainConfig>,
}

impl Default for OmaConfig {
    fn default() -> Self {
        let d = OmaSettings::default();
        Self {
            references: Vec::new(),
            window_seconds: None,
            window_hop_seconds: None,
            block_rows: d.block_rows,
            horizon_seconds: None,
            resample_hz: None,
            min_order: d.min_order,
            max_order: d.max_order,
            order_step: d.order_step,
            band: None,
            batches: d.batches,
            uncertainty: d.uncertainty,
            stability: d.stability,
            clustering: d.clustering,
            frequency_domain: None,
        }
    }
}

impl OmaConfig {
    /// The core settings, checked; `default_band` when `band` is not given.
    pub fn settings(&self, default_band: [f64; 2]) -> Result<OmaSettings, ConfigError> {
        let settings = OmaSettings {
            block_rows: self.block_rows,
            min_order: self.min_order,
            max_order: self.max_order,
            order_step: self.order_step,
            band: self.band.unwrap_or(default_band),
            stability: self.stability,
            clustering: self.clustering,
            batches: self.batches,
            uncertainty: self.uncertainty,
        };
        settings.check().map_err(|e| err("oma", e))?;
        Ok(settings)
    }
}

impl Config {
    /// The acceleration sensors (indices into `[[sensors]]`): the OMA outputs.
    pub fn output_channels(&self) -> Result<Vec<usize>, ConfigError> {
        let outputs: Vec<usize> = (0..self.deck_sensor_count())
            .filter(|&i| self.sensors[i].quantity.as_slice().iter().any(|q| q == "acceleration"))
            .collect();
        if outputs.is_empty() {
            return Err(err("sensors", "no sensor measures acceleration"));
        }
        Ok(outputs)
    }

    /// True when no sensor measures force: the daemon then runs output-only.
    pub fn is_output_only(&self) -> bool {
        !self
            .sensors
            .iter()
            .any(|s| s.quantity.as_slice().iter().any(|q| q == "force"))
    }

    /// The `[oma]` settings (the defaults when the section is absent).
    pub fn oma(&self) -> &OmaConfig {
        static DEFAULT: std::sync::LazyLock<OmaConfig> = std::sync::LazyLock::new(OmaConfig::default);
        self.oma_section.as_ref().unwrap_or(&DEFAULT)
    }

    /// True when the pipeline identifies each window's modes output-only:
    /// an output-only config, or one with a force sensor and an `[oma]`
    /// section (both paths: FRFs and identified modes per window).
    pub fn runs_oma(&self) -> bool {
        self.is_output_only() || self.oma_section.is_some()
    }

    /// The pipeline's analysis window and hop (s): `[oma]`'s when the
    /// pipeline identifies modes and `[oma]` gives one (with both paths the
    /// FRFs are estimated over that window too), `[frf]`'s otherwise.
    pub fn analysis_window(&self) -> (f64, Option<f64>) {
        if self.runs_oma() {
            if let Some(w) = self.oma().window_seconds {
                return (w, self.oma().window_hop_seconds);
            }
        }
        (self.frf.window_seconds, self.frf.window_hop_seconds)
    }

    /// The core settings and the reference channels (positions among
    /// [`Self::output_channels`]).
    pub fn oma_settings(&self) -> Result<(OmaSettings, Vec<usize>), ConfigError> {
        let o = self.oma();
        let outputs = self.output_channels()?;
        let references = o
            .references
            .iter()
            .map(|name| {
                outputs
                    .iter()
                    .position(|&i| &self.sensors[i].name == name)
                    .ok_or_else(|| err("oma.references", format!("{name:?} is not an acceleration sensor")))
            })
            .collect::<Result<Vec<usize>, _>>()?;
        let settings = o.settings(self.frf.band)?;
        if let Some(h) = o.horizon_seconds {
            if !(h.is_finite() && h > 0.0) {
                return Err(err("oma.horizon_seconds", format!("must be positive, got {h}")));
            }
        }
        if let Some(rate) = o.resample_hz {
            if !(rate.is_finite() && rate > 0.0) {
                return Err(err("oma.resample_hz", format!("must be positive, got {rate}")));
            }
            if let Some([_, top]) = o.band {
                if top > rate / 2.0 {
                    return Err(err(
                        "oma.band",
                        format!("ends at {top} Hz, above half of oma.resample_hz ({rate} Hz): the modes are sought below {} Hz", rate / 2.0),
                    ));
                }
            }
        }
        if let Some(w) = o.window_seconds {
            if !(w.is_finite() && w > 0.0) {
                return Err(err("oma.window_seconds", format!("must be positive, got {w}")));
            }
        }
        if let Some(hop) = o.window_hop_seconds {
            let window = o.window_seconds.unwrap_or(self.frf.window_seconds);
            if !(hop.is_finite() && hop > 0.0 && hop <= window) {
                return Err(err(
                    "oma.window_hop_seconds",
                    format!("must be positive and at most the window ({window} s), got {hop}"),
                ));
            }
        }
        Ok((settings, references))
    }

    /// The rate SRIM identifies a record at `fs` Hz at: `[oma] resample_hz`
    /// when the record is faster, its own otherwise.
    pub fn identification_rate(&self, fs: f64) -> f64 {
        match self.oma().resample_hz {
            Some(rate) if rate < fs => rate,
            _ => fs,
        }
    }

    /// [`Config::oma_settings`] for a record at `fs` Hz: the horizon from
    /// `[oma] horizon_seconds` when given; the band cut at half of `fs`
    /// when it comes from `frf.band` and `[oma] resample_hz` is given.
    pub fn oma_settings_at(&self, fs: f64) -> Result<(OmaSettings, Vec<usize>), ConfigError> {
        let (mut settings, references) = self.oma_settings()?;
        if let Some(seconds) = self.oma().horizon_seconds {
            let rows = horizon_rows(seconds, fs);
            if !(seconds.is_finite() && rows >= 2) {
                return Err(err(
                    "oma.horizon_seconds",
                    format!("must give 2 block rows or more at {fs} Hz, got {seconds} s"),
                ));
            }
            settings.block_rows = rows;
            settings.check().map_err(|e| err("oma.horizon_seconds", e))?;
        }
        if self.oma().resample_hz.is_some() && self.oma().band.is_none() {
            settings.band[1] = settings.band[1].min(fs / 2.0);
            settings.check().map_err(|e| err("oma.resample_hz", e))?;
        }
        Ok((settings, references))
    }
}

/// The block rows of a horizon of `seconds` at `fs` Hz (`[oma] horizon_seconds`).
pub fn horizon_rows(seconds: f64, fs: f64) -> usize {
    (seconds * fs).round() as usize
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_ambient_example_is_the_bundled_deck_without_its_force_sensor() {
        let ambient = Config::from_toml(include_str!("../../config/sinello-ambient.toml")).unwrap();
        let bundled = Config::from_toml(include_str!("../../config/sinello.toml")).unwrap();
        assert!(ambient.is_output_only() && !bundled.is_output_only());
        assert_eq!(
            serde_json::to_value(&ambient.model).unwrap(),
            serde_json::to_value(&bundled.model).unwrap()
        );
        let sensors = |c: &Config| -> Vec<serde_json::Value> {
            c.sensors
                .iter()
                .map(|s| {
                    let mut v = serde_json::to_value(s).unwrap();
                    v["quantity"] = serde_json::Value::Null;
                    v
                })
                .collect()
        };
        assert_eq!(sensors(&ambient), sensors(&bundled));
        assert_eq!(ambient.analysis_window(), (1200.0, None));
        assert_eq!(bundled.analysis_window(), (20.0, None));
    }

    /// `[oma] horizon_seconds` gives the same horizon in seconds at any
    /// rate: 0.5 s is 25 block rows at 50 Hz and 100 at 200 Hz; without it
    /// `block_rows` counts samples; a horizon of less than 2 rows, or not
    /// positive, is refused naming the key.
    #[test]
    fn a_horizon_in_seconds_is_the_same_at_any_rate() {
        let base = include_str!("../../config/painter-street.toml");
        let with = |line: &str| Config::from_toml(&base.replace("block_rows = 100", line));
        let seconds = with("horizon_seconds = 0.5").unwrap();
        assert_eq!(seconds.oma_settings_at(50.0).unwrap().0.block_rows, 25);
        assert_eq!(seconds.oma_settings_at(200.0).unwrap().0.block_rows, 100);
        let rows = with("block_rows = 100").unwrap();
        assert_eq!(rows.oma_settings_at(50.0).unwrap().0.block_rows, 100);
        assert_eq!(rows.oma_settings_at(200.0).unwrap().0.block_rows, 100);
        let e = seconds.oma_settings_at(2.0).unwrap_err().to_string();
        assert!(e.contains("oma.horizon_seconds") && e.contains("2 block rows"), "{e}");
        let e = with("horizon_seconds = -1.0")
            .unwrap()
            .oma_settings()
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("oma.horizon_seconds") && e.contains("must be positive"),
            "{e}"
        );
    }

    /// `[oma] resample_hz`: a faster record is identified at that rate, a
    /// slower one at its own; the band from `frf.band` is cut at
    /// half the rate (25 → 20 Hz), an explicit band above it refused naming both keys,
    /// as is a rate that is not positive.
    #[test]
    fn a_resampling_rate_sets_the_identification_rate_and_the_band() {
        let base = include_str!("../../config/painter-street.toml");
        let with = |line: &str| Config::from_toml(&base.replace("block_rows = 100", line)).unwrap();
        let cfg = with("horizon_seconds = 1.0\nresample_hz = 40.0");
        assert_eq!(cfg.identification_rate(200.0), 40.0);
        assert_eq!(cfg.identification_rate(20.0), 20.0);
        let (settings, _) = cfg.oma_settings_at(cfg.identification_rate(200.0)).unwrap();
        assert_eq!((settings.block_rows, settings.band[1]), (40, 20.0));
        assert_eq!(with("horizon_seconds = 1.0").identification_rate(200.0), 200.0);
        let e = with("resample_hz = 40.0\nband = [0.5, 30.0]")
            .oma_settings()
            .unwrap_err()
            .to_string();
        assert!(e.contains("oma.band") && e.contains("oma.resample_hz"), "{e}");
        let e = with("resample_hz = 0.0").oma_settings().unwrap_err().to_string();
        assert!(e.contains("oma.resample_hz") && e.contains("must be positive"), "{e}");
    }
}
