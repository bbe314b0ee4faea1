//! The reference (training) model: compensation, residual scales and
//! covariance, and control limits calibrated on held-out windows.

use super::compensation::{regressors, Compensation};
use super::covariance::{ledoit_wolf, robust_scale};
use super::{LimitMethod, MonitoringError, Observation, Settings};
use faer::linalg::solvers::{DenseSolveCore, Solve};
use faer::Side;
use serde::{Deserialize, Serialize};
use statrs::distribution::{ChiSquared, ContinuousCDF, FisherSnedecor};

/// Scaled residuals are clipped here before their covariance (in robust
/// standard deviations).
const WINSOR: f64 = 3.0;

/// Compensation, scales and precision fitted on some training windows.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Fitted {
    pub compensation: Compensation,
    /// Robust scale of each feature's residual; 0: constant in training
    /// (a parameter at a bound), left out of the statistics.
    pub scales: Vec<f64>,
    /// Features in the statistics (non-zero scale).
    pub kept: Vec<usize>,
    /// Inverse of the shrunk covariance of the scaled residuals (`kept × kept`, rows).
    pub precision: Vec<Vec<f64>>,
    pub shrinkage: f64,
}

impl Fitted {
    /// A regression on `x` (one row per window), or PCA when `x` is empty.
    fn fit(settings: &Settings, features: &[&[f64]], x: &[Vec<f64>]) -> Result<Self, MonitoringError> {
        let compensation = if !x.is_empty() {
            Compensation::regression(features, x)
        } else {
            Compensation::pca(features, settings.pca_components)
        };
        let residuals: Vec<Vec<f64>> = features
            .iter()
            .enumerate()
            .map(|(i, y)| compensation.residual(y, x.get(i).map(Vec::as_slice)))
            .collect();
        let p = features[0].len();
        let scales: Vec<f64> = (0..p)
            .map(|f| robust_scale(&residuals.iter().map(|r| r[f]).collect::<Vec<_>>()))
            .collect();
        let kept: Vec<usize> = (0..p).filter(|&f| scales[f] > 0.0).collect();
        // Scaled residuals winsorised at ±WINSOR (Huber's idea): a few bad
        // training windows cannot inflate the covariance the MAD scales
        // were made robust against.
        let scaled: Vec<Vec<f64>> = residuals
            .iter()
            .map(|r| {
                kept.iter()
                    .map(|&f| (r[f] / scales[f]).clamp(-WINSOR, WINSOR))
                    .collect()
            })
            .collect();
        let (covariance, shrinkage) = ledoit_wolf(&scaled);
        let llt = covariance.llt(Side::Lower).map_err(|_| MonitoringError::Covariance)?;
        let inverse = llt.inverse();
        let precision = (0..kept.len())
            .map(|i| (0..kept.len()).map(|j| inverse[(i, j)]).collect())
            .collect();
        Ok(Self {
            compensation,
            scales,
            kept,
            precision,
            shrinkage,
        })
    }

    /// Every feature's residual over its scale (0 where the scale is).
    pub fn standardised(&self, features: &[f64], x: Option<&[f64]>) -> Vec<f64> {
        let r = self.compensation.residual(features, x);
        r.iter()
            .zip(&self.scales)
            .map(|(r, s)| if *s > 0.0 { r / s } else { 0.0 })
            .collect()
    }

    /// The standardised residual of `features` some of which may be
    /// missing, or `None` when every kept one is: with the regression, each
    /// residual is its feature's alone, and the missing ones are replaced by
    /// their conditional mean given the others' ([`Self::impute`]); with
    /// PCA, the missing features are filled in before the projection (their
    /// conditional mean under the training correlation), since every
    /// residual depends on every feature.
    pub fn standardised_with_gaps(&self, features: &[f64], x: Option<&[f64]>, missing: &[bool]) -> Option<Vec<f64>> {
        if self.kept.iter().all(|&f| missing[f]) {
            return None;
        }
        let mut e = self.standardised(features, x);
        match self.compensation {
            Compensation::Regression { .. } => self.impute(&mut e, missing).then_some(e),
            Compensation::Pca { .. } => Some(e),
        }
    }

    /// Replaces the standardised residuals of the `missing` features by
    /// their conditional mean given the others', `e_m = −P_mm⁻¹ P_mo e_o`
    /// with `P = Σ⁻¹`: then `eᵀPe = e_oᵀ Σ_oo⁻¹ e_o` (Schur complement), the
    /// T² of the observed features alone. False when every kept feature is
    /// missing.
    pub fn impute(&self, e: &mut [f64], missing: &[bool]) -> bool {
        let (m, o): (Vec<usize>, Vec<usize>) = (0..self.kept.len()).partition(|&i| missing[self.kept[i]]);
        if o.is_empty() {
            return false;
        }
        for (f, _) in missing.iter().enumerate().filter(|(_, &x)| x) {
            e[f] = 0.0;
        }
        if m.is_empty() {
            return true;
        }
        let p_mm = faer::Mat::from_fn(m.len(), m.len(), |i, j| self.precision[m[i]][m[j]]);
        let rhs = faer::Mat::from_fn(m.len(), 1, |i, _| {
            -o.iter()
                .map(|&j| self.precision[m[i]][j] * e[self.kept[j]])
                .sum::<f64>()
        });
        let Ok(llt) = p_mm.llt(Side::Lower) else {
            return false;
        };
        let solution = llt.solve(&rhs);
        for (i, &k) in m.iter().enumerate() {
            e[self.kept[k]] = solution[(i, 0)];
        }
        true
    }

    /// `eᵀ Σ⁻¹ e` over the kept features of a standardised residual.
    pub fn quadratic(&self, e: &[f64]) -> f64 {
        let v: Vec<f64> = self.kept.iter().map(|&f| e[f]).collect();
        self.precision
            .iter()
            .zip(&v)
            .map(|(row, vi)| vi * row.iter().zip(&v).map(|(a, b)| a * b).sum::<f64>())
            .sum()
    }
}

/// How the limits were calibrated, for the report.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Calibration {
    /// Held-out windows scored (T²) and MEWMA values used (after burn-in).
    pub held_out: usize,
    pub mewma_values: usize,
    /// Held-out exceedances of the final limits.
    pub t2_exceedances: usize,
    pub mewma_exceedances: usize,
}

/// A compensation model with its control limits.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Chart {
    pub fitted: Fitted,
    pub t2_limit: f64,
    pub mewma_limit: f64,
    pub calibration: Calibration,
}

impl Chart {
    fn train(settings: &Settings, y: &[&[f64]], x: &[Vec<f64>]) -> Result<Self, MonitoringError> {
        let fitted = Fitted::fit(settings, y, x)?;
        if settings.limits == LimitMethod::Theoretical {
            let (p, n) = (fitted.kept.len() as f64, y.len() as f64);
            let d2 = (n - p).max(1.0);
            let scale = p * (n + 1.0) * (n - 1.0) / (n * d2);
            let limit = FisherSnedecor::new(p.max(1.0), d2).map_or(f64::INFINITY, |f| {
                scale * f.inverse_cdf(1.0 - settings.false_alarm_rate)
            });
            return Ok(Self {
                fitted,
                t2_limit: limit,
                mewma_limit: limit,
                calibration: Calibration {
                    held_out: 0,
                    mewma_values: 0,
                    t2_exceedances: 0,
                    mewma_exceedances: 0,
                },
            });
        }
        let (t2, mewma) = held_out_statistics(settings, y, x)?;
        let (p, n) = (fitted.kept.len(), y.len());
        let (t2_limit, mewma_limit) = (
            limit(&t2, settings.false_alarm_rate, p, n),
            limit(&mewma, settings.false_alarm_rate, p, n),
        );
        Ok(Self {
            fitted,
            t2_limit,
            mewma_limit,
            calibration: Calibration {
                held_out: t2.len(),
                mewma_values: mewma.len(),
                t2_exceedances: t2.iter().filter(|&&v| v > t2_limit).count(),
                mewma_exceedances: mewma.iter().filter(|&&v| v > mewma_limit).count(),
            },
        })
    }
}

/// The trained reference.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Reference {
    pub settings: Settings,
    pub features: usize,
    /// The temperature regression (with temperature channels) or the PCA model.
    pub primary: Chart,
    /// With temperature channels, the PCA model on the same windows: it
    /// scores (T² only) a window whose temperature is missing.
    pub fallback: Option<Chart>,
    /// Per temperature channel, the training range `[min, max]`, °C.
    pub temperature_range: Vec<[f64; 2]>,
    /// Training windows used (with every needed temperature and every
    /// selected feature).
    pub windows: usize,
    /// The features in the statistics (indices into an observation's):
    /// those present in at least `feature_presence` of the training windows
    /// (an identified frequency the identification often misses is left
    /// out); `None`: every feature (a reference saved before selection).
    #[serde(default)]
    pub selected: Option<Vec<usize>>,
}

/// The `1 − α` limit of held-out statistic values: the larger of their
/// empirical quantile and the quantile of `c F(p, n − p)` with `c` matched
/// to their mean: the law of the T² of a future observation against a mean
/// and covariance estimated from `n` windows (Tracy, Young & Mason 1992),
/// whose tail is heavier than χ²'s and reaches beyond what a hundred
/// held-out windows can show.
fn limit(values: &[f64], alpha: f64, features: usize, windows: usize) -> f64 {
    let n = values.len() as f64;
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let position = (1.0 - alpha) * (n - 1.0);
    let (lo, frac) = (position.floor() as usize, position.fract());
    let empirical = sorted[lo] + frac * (sorted[(lo + 1).min(sorted.len() - 1)] - sorted[lo]);
    let mean = values.iter().sum::<f64>() / n;
    // F(d1, d2) has mean d2 / (d2 − 2); d2 ≥ 5 keeps the law's variance finite.
    let (d1, d2) = (
        features.max(1) as f64,
        (windows.saturating_sub(features) as f64).max(5.0),
    );
    let tail = FisherSnedecor::new(d1, d2).map_or(0.0, |f| mean * (d2 - 2.0) / d2 * f.inverse_cdf(1.0 - alpha));
    empirical.max(tail)
}

/// MEWMA statistic of `z` (the EWMA of standardised residuals) with the
/// asymptotic covariance `λ/(2 − λ) Σ` (Lowry et al. 1992).
pub fn mewma_statistic(fitted: &Fitted, z: &[f64], lambda: f64) -> f64 {
    (2.0 - lambda) / lambda * fitted.quadratic(z)
}

impl Reference {
    /// Trains on `observations` (time order): windows missing a needed
    /// temperature are left out of the fit (they still count as history
    /// for lags). Limits: contiguous `folds`-fold cross validation.
    pub fn train(settings: &Settings, observations: &[Observation]) -> Result<Self, MonitoringError> {
        settings.check()?;
        let features = observations.first().map_or(0, |o| o.features.len());
        if let Some(index) = observations.iter().position(|o| o.features.len() != features) {
            return Err(MonitoringError::FeatureCount {
                index,
                found: observations[index].features.len(),
                expected: features,
            });
        }
        let selected = select_features(settings, observations, features);
        let projected: Vec<Observation> = observations
            .iter()
            .map(|o| Observation {
                features: selected.iter().map(|&f| o.features[f]).collect(),
                temperatures: o.temperatures.clone(),
                time_ns: o.time_ns,
            })
            .collect();
        let (rows, x) = usable(settings, &projected);
        let q = x.first().map_or(1, Vec::len);
        let needed = (2 * settings.folds).max(q + 3).max(10);
        if rows.len() < needed || selected.is_empty() {
            return Err(MonitoringError::TooFewWindows {
                usable: rows.len(),
                total: observations.len(),
                needed,
                features: selected.len(),
            });
        }
        let y: Vec<&[f64]> = rows.iter().map(|&i| projected[i].features.as_slice()).collect();
        let primary = Chart::train(settings, &y, &x)?;
        let fallback = if settings.temperature_channels > 0 {
            Some(Chart::train(settings, &y, &[])?)
        } else {
            None
        };
        let temperature_range = (0..settings.temperature_channels)
            .map(|c| {
                let t = rows.iter().map(|&i| observations[i].temperatures[c]);
                [
                    t.clone().fold(f64::INFINITY, f64::min),
                    t.fold(f64::NEG_INFINITY, f64::max),
                ]
            })
            .collect();
        Ok(Self {
            settings: settings.clone(),
            features,
            primary,
            fallback,
            temperature_range,
            windows: rows.len(),
            selected: Some(selected),
        })
    }

    /// The features in the statistics (indices into an observation's).
    pub fn selected(&self) -> Vec<usize> {
        self.selected.clone().unwrap_or_else(|| (0..self.features).collect())
    }
}

/// The features finite in at least `feature_presence` of the observations.
fn select_features(settings: &Settings, observations: &[Observation], features: usize) -> Vec<usize> {
    let needed = settings.feature_presence * observations.len() as f64;
    (0..features)
        .filter(|&f| observations.iter().filter(|o| o.features[f].is_finite()).count() as f64 >= needed)
        .collect()
}

/// The training windows with every feature and every needed temperature,
/// and their regressors.
fn usable(settings: &Settings, observations: &[Observation]) -> (Vec<usize>, Vec<Vec<f64>>) {
    let complete = |i: &usize| observations[*i].features.iter().all(|v| v.is_finite());
    if settings.temperature_channels == 0 {
        return ((0..observations.len()).filter(complete).collect(), Vec::new());
    }
    let mut rows = Vec::new();
    let mut x = Vec::new();
    for i in (0..observations.len()).filter(complete) {
        let history: Vec<&[f64]> = (0..=settings.lags.min(i))
            .map(|l| observations[i - l].temperatures.as_slice())
            .collect();
        if let Some(r) = regressors(settings, &history) {
            rows.push(i);
            x.push(r);
        }
    }
    (rows, x)
}

/// T² and MEWMA of every training window scored by a reference fitted
/// without its fold (contiguous folds), in time order; the MEWMA's first
/// `⌈1/λ⌉` values (at most a quarter) are burn-in from `z = 0` and left out.
fn held_out_statistics(
    settings: &Settings,
    y: &[&[f64]],
    x: &[Vec<f64>],
) -> Result<(Vec<f64>, Vec<f64>), MonitoringError> {
    let n = y.len();
    let folds = settings.folds.min(n);
    let lambda = settings.ewma_lambda;
    let mut t2 = Vec::with_capacity(n);
    let mut mewma = Vec::with_capacity(n);
    let mut z = vec![0.0; y[0].len()];
    for f in 0..folds {
        let (start, end) = (f * n / folds, (f + 1) * n / folds);
        let keep: Vec<usize> = (0..n).filter(|i| !(start..end).contains(i)).collect();
        let ys: Vec<&[f64]> = keep.iter().map(|&i| y[i]).collect();
        let xs: Vec<Vec<f64>> = if x.is_empty() {
            Vec::new()
        } else {
            keep.iter().map(|&i| x[i].clone()).collect()
        };
        let fitted = Fitted::fit(settings, &ys, &xs)?;
        for i in start..end {
            let e = fitted.standardised(y[i], x.get(i).map(Vec::as_slice));
            t2.push(fitted.quadratic(&e));
            z.iter_mut()
                .zip(&e)
                .for_each(|(z, e)| *z = lambda * e + (1.0 - lambda) * *z);
            mewma.push(mewma_statistic(&fitted, &z, lambda));
        }
    }
    let burn_in = ((1.0 / lambda).ceil() as usize).min(n / 4);
    Ok((t2, mewma.split_off(burn_in)))
}

/// The standard χ² quantile, for tests and reports.
pub fn chi_squared_quantile(dof: f64, probability: f64) -> f64 {
    ChiSquared::new(dof).map_or(f64::NAN, |c| c.inverse_cdf(probability))
}
