//! The monitoring messages: `<prefix>/monitoring/status` per scored update
//! and `<prefix>/monitoring/alarm` on each change to or from alarm.
//!
//! Status contract: `{"window":…, "time":…, "state":"training"|"normal"|
//! "outside_training_range"|"alarm", "t2":…, "t2_limit":…, "mewma":…,
//! "mewma_limit":…, "temperature_c":…, "residuals":[{"name":…,
//! "standardised":…},…]}`; a statistic not computed is `null`.
//! `temperature_c` is the mean of the channels with a valid temperature.
//! Extra keys: `temperatures` (per channel, `null` when missing),
//! `features` (the scored values, so `splinewatch monitor` can re-score a
//! results file; `null` for a frequency not identified), `flags`, `exceedances` (among the last `m` scored
//! windows), `scored_by` (`"temperature_regression"`, `"pca"`, or
//! `"pca_fallback"` when a temperature was missing). Readers ignore keys
//! they do not know.

use super::named_value::NamedValue;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Residual {
    pub name: String,
    pub standardised: f64,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StatusMessage {
    pub window: u64,
    pub time: String,
    pub state: String,
    pub t2: Option<f64>,
    pub t2_limit: Option<f64>,
    pub mewma: Option<f64>,
    pub mewma_limit: Option<f64>,
    pub temperature_c: Option<f64>,
    pub residuals: Vec<Residual>,
    #[serde(default)]
    pub temperatures: BTreeMap<String, Option<f64>>,
    #[serde(default)]
    pub features: Vec<NamedValue>,
    #[serde(default)]
    pub flags: Vec<String>,
    #[serde(default)]
    pub exceedances: usize,
    #[serde(default)]
    pub scored_by: Option<String>,
}

/// `<prefix>/monitoring/alarm`: the state changed to or from `"alarm"`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AlarmMessage {
    pub window: u64,
    pub time: String,
    pub state: String,
    pub previous: String,
    pub t2: Option<f64>,
    pub mewma: Option<f64>,
    /// The features with the largest |standardised residual| first (up to 5).
    pub largest_residuals: Vec<Residual>,
}
