//! Environmental compensation and statistical novelty detection on the
//! identified parameters (the layer real SHM systems put on top of system
//! identification: Peeters & De Roeck 2001, Z24; Kullaa 2003; Magalhães,
//! Cunha & Caetano 2012).
//!
//! May import: every floor above it (`updating`, …, `geometry`, `linalg`); it uses none of them.
//!
//! Each scored update is an [`Observation`]: its features (updated
//! parameters, identified frequencies) and the mean temperature of every
//! channel over its span. The first observations train a [`Reference`]:
//!
//! - **compensation** ([`compensation`]): with temperatures, a least-squares
//!   regression of every feature on `1, T_c, max(knee − T_c, 0)` (a hinge:
//!   frozen bearings and asphalt stiffen below the knee) and optionally
//!   `T_c` of earlier windows; without, a PCA model whose first `k`
//!   principal components (the environment's hidden factors) are removed;
//! - **residual covariance** ([`covariance`]): residuals scaled by their
//!   median absolute deviation, then a Ledoit–Wolf (2004) shrinkage
//!   covariance, well conditioned with few windows and robust to a few
//!   outliers;
//! - **control limits** ([`mod@reference`]): Hotelling T² and the MEWMA of
//!   Lowry et al. (1992) of held-out residuals (contiguous k-fold cross
//!   validation over the training span: each fold scored by a reference
//!   trained without it), their limits at the target false-alarm rate per
//!   window from the larger of the empirical quantile and a moment-matched
//!   scaled χ² (Box 1954), which extrapolates the tail beyond what a
//!   hundred held-out windows show.
//!
//! A [`Monitor`] ([`chart`]) scores every later observation against the
//! reference and raises an alarm after `k` of the last `m` scored windows
//! exceed a limit; a window whose temperature lies outside the training
//! range is flagged, not scored; a window without a temperature is scored
//! (T² only, flagged) by a PCA model trained on the same windows. Features
//! missing in more than `1 − feature_presence` of the training windows are
//! left out; a later window missing a feature is scored on the others, the
//! missing residual replaced by its conditional mean given them, so its T²
//! is exactly the observed features' own (flagged).

pub mod amplitude;
pub mod chart;
pub mod compensation;
pub mod covariance;
pub mod reference;

pub use chart::{Monitor, MonitorState, Status};
pub use reference::Reference;

use serde::{Deserialize, Serialize};
use thiserror::Error;

#[derive(Debug, Clone, PartialEq, Error)]
pub enum MonitoringError {
    #[error("{name} = {value}: {expected}")]
    Setting {
        name: &'static str,
        value: f64,
        expected: &'static str,
    },
    #[error("{usable} usable training windows (of {total}); at least {needed} are needed for {features} features")]
    TooFewWindows {
        usable: usize,
        total: usize,
        needed: usize,
        features: usize,
    },
    #[error("observation {index} has {found} features, the reference has {expected}")]
    FeatureCount {
        index: usize,
        found: usize,
        expected: usize,
    },
    #[error("the residual covariance is not positive definite")]
    Covariance,
}

/// How the statistical layer is trained and scored.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Settings {
    /// Temperature channels (0: the PCA variant).
    pub temperature_channels: usize,
    /// Knee of the hinge term `max(knee − T, 0)`, °C.
    pub knee_c: f64,
    /// Lagged temperature terms: `T` of the `lags` previous windows.
    pub lags: usize,
    /// Principal components removed without temperatures.
    pub pca_components: usize,
    /// MEWMA smoothing λ in (0, 1].
    pub ewma_lambda: f64,
    /// Target false-alarm probability per window of each chart.
    pub false_alarm_rate: f64,
    /// An alarm needs `k` exceedances among the last `m` scored windows.
    pub persistence: [usize; 2],
    /// Margin around the training temperature range, °C.
    pub range_margin_c: f64,
    /// Contiguous cross-validation folds for the control limits.
    pub folds: usize,
    /// How the control limits are set.
    #[serde(default)]
    pub limits: LimitMethod,
    /// A feature enters the reference when finite in at least this share
    /// of the training windows (identified frequencies of modes the
    /// identification sometimes misses); later windows missing one are
    /// scored on the others (its conditional mean given them imputed).
    #[serde(default = "default_feature_presence")]
    pub feature_presence: f64,
}

fn default_feature_presence() -> f64 {
    0.8
}

/// How control limits are set.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LimitMethod {
    /// From held-out training windows (cross validation), with a scaled-F tail.
    #[default]
    HeldOut,
    /// The textbook phase-II law: `p(n+1)(n−1)/(n(n−p)) F(p, n−p)` for T²
    /// of a future window (Tracy, Young & Mason 1992), the same for the
    /// MEWMA; it trusts the model, so a misfit becomes false alarms.
    Theoretical,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            temperature_channels: 0,
            knee_c: 0.0,
            lags: 0,
            pca_components: 1,
            ewma_lambda: 0.2,
            false_alarm_rate: 0.001,
            persistence: [3, 5],
            range_margin_c: 1.0,
            folds: 5,
            limits: LimitMethod::HeldOut,
            feature_presence: default_feature_presence(),
        }
    }
}

impl Settings {
    pub fn check(&self) -> Result<(), MonitoringError> {
        let bad = |name, value: f64, expected| Err(MonitoringError::Setting { name, value, expected });
        if !(self.ewma_lambda > 0.0 && self.ewma_lambda <= 1.0) {
            return bad("ewma_lambda", self.ewma_lambda, "must be in (0, 1]");
        }
        if !(self.false_alarm_rate > 0.0 && self.false_alarm_rate < 0.5) {
            return bad("false_alarm_rate", self.false_alarm_rate, "must be in (0, 0.5)");
        }
        let [k, m] = self.persistence;
        if k == 0 || k > m {
            return bad("persistence", k as f64, "needs 1 ≤ k ≤ m");
        }
        if !self.knee_c.is_finite() {
            return bad("knee_c", self.knee_c, "must be finite");
        }
        if !(self.range_margin_c.is_finite() && self.range_margin_c >= 0.0) {
            return bad("range_margin_c", self.range_margin_c, "must be ≥ 0");
        }
        if !(self.feature_presence > 0.0 && self.feature_presence <= 1.0) {
            return bad("feature_presence", self.feature_presence, "must be in (0, 1]");
        }
        if self.folds < 2 {
            return bad("folds", self.folds as f64, "must be at least 2");
        }
        Ok(())
    }
}

/// One scored update: its features and the window's mean temperature per
/// channel (`NaN`: no valid sample in the span).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Observation {
    #[serde(with = "nullable")]
    pub features: Vec<f64>,
    #[serde(with = "nullable")]
    pub temperatures: Vec<f64>,
    /// The window's time (ns since the epoch), for training on a time span.
    #[serde(default)]
    pub time_ns: i128,
}

/// Serde for values that may be `NaN` (a missing temperature): `null` in
/// JSON, `NaN` in memory, so a saved monitor resumes bit for bit.
pub(crate) mod nullable {
    use serde::{Deserialize, Deserializer, Serialize, Serializer};
    use std::collections::VecDeque;

    fn wrap(v: &[f64]) -> Vec<Option<f64>> {
        v.iter().map(|x| x.is_finite().then_some(*x)).collect()
    }

    fn unwrap(v: Vec<Option<f64>>) -> Vec<f64> {
        v.into_iter().map(|x| x.unwrap_or(f64::NAN)).collect()
    }

    pub fn serialize<S: Serializer>(v: &[f64], s: S) -> Result<S::Ok, S::Error> {
        wrap(v).serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Vec<f64>, D::Error> {
        Vec::<Option<f64>>::deserialize(d).map(unwrap)
    }

    pub mod rows {
        use super::*;

        pub fn serialize<S: Serializer>(v: &VecDeque<Vec<f64>>, s: S) -> Result<S::Ok, S::Error> {
            v.iter().map(|r| wrap(r)).collect::<Vec<_>>().serialize(s)
        }

        pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<VecDeque<Vec<f64>>, D::Error> {
            Vec::<Vec<Option<f64>>>::deserialize(d).map(|rows| rows.into_iter().map(unwrap).collect())
        }
    }
}
