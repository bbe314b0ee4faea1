//! `[frf]`: Welch FRF estimation from time series, and the channel roles.

use super::{err, Config, ConfigError};
use serde::{Deserialize, Serialize};
use splinewatch_core::identification::welch::{Averaging, Detrend, Estimator, Gates, WelchSettings, Window};
use splinewatch_core::response::frf::Quantity;

/// `[frf]`: Welch FRF estimation from time series.
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct FrfConfig {
    /// Welch segment length, seconds.
    pub segment_seconds: f64,
    /// Segment overlap, fraction in [0, 1).
    pub overlap: f64,
    /// "rectangular", "hann", "hamming", "blackman", "flattop" or "impact"
    /// (force window on the input, exponential on the outputs).
    pub window: String,
    /// Impact tests: length of the force window, fraction of a segment.
    pub force_window_width: f64,
    /// Impact tests: value of the exponential window at the segment end.
    pub exponential_end: f64,
    /// "constant" (scipy's default) or "none".
    pub detrend: String,
    /// "h1", "h2" or "hv".
    pub estimator: String,
    /// "linear" or "exponential".
    pub averaging: String,
    /// Weight α of a new segment with exponential averaging.
    pub exponential_weight: f64,
    /// Lines kept in FRF files, [f_min, f_max] Hz.
    pub band: [f64; 2],
    /// Analysis window of the daemon, seconds.
    pub window_seconds: f64,
    /// Time between the starts of consecutive windows, seconds (at most
    /// `window_seconds`; less gives overlapping windows). Default: the window
    /// length, back to back.
    pub window_hop_seconds: Option<f64>,
    /// Reject segments reaching this magnitude (overload), optional.
    pub full_scale: Option<f64>,
    /// Impact tests: reject segments with a second hit above this fraction of the peak.
    pub double_impact_fraction: Option<f64>,
    /// Quantity written to FRF files: "accelerance", "mobility" or "receptance".
    #[schemars(with = "super::schema::QuantityDef")]
    pub quantity: Quantity,
    /// Largest accepted block, samples.
    pub max_block_samples: usize,
}

impl Default for FrfConfig {
    fn default() -> Self {
        Self {
            segment_seconds: 8.0,
            overlap: 0.5,
            window: "hann".into(),
            force_window_width: 0.1,
            exponential_end: 0.01,
            detrend: "constant".into(),
            estimator: "h1".into(),
            averaging: "linear".into(),
            exponential_weight: 0.05,
            band: [0.5, 80.0],
            window_seconds: 600.0,
            window_hop_seconds: None,
            full_scale: None,
            double_impact_fraction: None,
            quantity: Quantity::Accelerance,
            max_block_samples: 1 << 20,
        }
    }
}

impl Config {
    /// `[frf]` as Welch settings for sampling frequency `fs`.
    pub fn welch_settings(&self, fs: f64) -> Result<(WelchSettings, Estimator), ConfigError> {
        self.frf.welch_settings(fs)
    }
}

impl FrfConfig {
    /// These settings as Welch settings for sampling frequency `fs` (errors
    /// name the `frf.*` key).
    pub fn welch_settings(&self, fs: f64) -> Result<(WelchSettings, Estimator), ConfigError> {
        let f = self;
        if !(f.segment_seconds.is_finite() && f.segment_seconds > 0.0) {
            return Err(err(
                "frf.segment_seconds",
                format!("must be positive, got {}", f.segment_seconds),
            ));
        }
        let segment = (f.segment_seconds * fs).round() as usize;
        if segment < 4 {
            return Err(err(
                "frf.segment_seconds",
                format!("{} s at {fs} Hz is only {segment} samples", f.segment_seconds),
            ));
        }
        if !(0.0..1.0).contains(&f.overlap) {
            return Err(err("frf.overlap", format!("must be in [0, 1), got {}", f.overlap)));
        }
        let overlap = (f.overlap * segment as f64).round() as usize;
        let (input_window, output_window) = windows(f)?;
        let (detrend, estimator, averaging) = methods(f)?;
        let [lo, hi] = f.band;
        if !(lo.is_finite() && hi.is_finite() && lo >= 0.0 && lo < hi) {
            return Err(err("frf.band", format!("[{lo}, {hi}] must satisfy 0 <= f_min < f_max")));
        }
        if !(f.window_seconds.is_finite() && f.window_seconds >= f.segment_seconds) {
            return Err(err("frf.window_seconds", "must be at least one segment long"));
        }
        if let Some(hop) = f.window_hop_seconds {
            if !(hop.is_finite() && hop * fs >= 1.0 && hop <= f.window_seconds) {
                return Err(err(
                    "frf.window_hop_seconds",
                    format!(
                        "must be between one sample and frf.window_seconds ({} s), got {hop}",
                        f.window_seconds
                    ),
                ));
            }
        }
        let settings = WelchSettings {
            fs,
            segment,
            overlap,
            input_window,
            output_window,
            detrend,
            averaging,
            gates: Gates {
                full_scale: f.full_scale,
                double_impact_fraction: f.double_impact_fraction,
            },
        };
        settings.validate().map_err(|e| err("frf", e))?;
        Ok((settings, estimator))
    }
}

impl Config {
    /// The sensor whose quantity includes "force" (the excitation), and the
    /// sensors measuring acceleration, by index into `[[sensors]]`.
    pub fn channel_roles(&self) -> Result<(usize, Vec<usize>), ConfigError> {
        let has = |i: usize, q: &str| self.sensors[i].quantity.as_slice().iter().any(|x| x == q);
        let forces: Vec<usize> = (0..self.deck_sensor_count()).filter(|&i| has(i, "force")).collect();
        let force = match forces.as_slice() {
            [one] => *one,
            [] => return Err(err("sensors", "no sensor has quantity \"force\" (the excitation)")),
            _ => {
                return Err(err(
                    "sensors",
                    "more than one force sensor: multiple-input FRFs are not supported",
                ))
            }
        };
        Ok((force, self.output_channels()?))
    }
}

/// `frf.window`: the input (force) and output windows.
fn windows(f: &FrfConfig) -> Result<(Window, Window), ConfigError> {
    let simple = |name: &str| match name {
        "rectangular" | "boxcar" => Some(Window::Rectangular),
        "hann" => Some(Window::Hann),
        "hamming" => Some(Window::Hamming),
        "blackman" => Some(Window::Blackman),
        "flattop" => Some(Window::FlatTop),
        _ => None,
    };
    match (f.window.as_str(), simple(&f.window)) {
        (_, Some(w)) => Ok((w, w)),
        ("impact", None) => Ok((
            Window::Force {
                width: f.force_window_width,
            },
            Window::Exponential { end: f.exponential_end },
        )),
        (other, None) => Err(err(
            "frf.window",
            format!("{other:?} is not rectangular, hann, hamming, blackman, flattop or impact"),
        )),
    }
}

/// `frf.detrend`, `frf.estimator` and `frf.averaging`.
fn methods(f: &FrfConfig) -> Result<(Detrend, Estimator, Averaging), ConfigError> {
    let detrend = match f.detrend.as_str() {
        "constant" => Detrend::Constant,
        "none" => Detrend::None,
        other => return Err(err("frf.detrend", format!("{other:?} is not constant or none"))),
    };
    let estimator = match f.estimator.as_str() {
        "h1" => Estimator::H1,
        "h2" => Estimator::H2,
        "hv" => Estimator::Hv,
        other => return Err(err("frf.estimator", format!("{other:?} is not h1, h2 or hv"))),
    };
    let averaging = match f.averaging.as_str() {
        "linear" => Averaging::Linear,
        "exponential" => Averaging::Exponential {
            alpha: f.exponential_weight,
        },
        other => return Err(err("frf.averaging", format!("{other:?} is not linear or exponential"))),
    };
    Ok((detrend, estimator, averaging))
}
