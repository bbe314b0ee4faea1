//! Environmental compensation: what the features would be at a window's
//! temperature, so the residual is what the environment does not explain.
//!
//! With temperatures, every feature is regressed on
//! `x = [1, T_c, max(knee − T_c, 0), T_c(t−1), …, T_c(t−lags)]` over the
//! channels `c` (Peeters & De Roeck 2001 fit ARX models of the Z24
//! frequencies on temperatures; the hinge is their bilinear freezing
//! behaviour, Z24's asphalt below 0 °C). Without temperatures the first `k`
//! principal components of the standardised features, the directions the
//! unmeasured environment moves them along, are removed (Yan et al. 2005).

use super::Settings;
use faer::Mat;
use serde::{Deserialize, Serialize};

/// The regressors of a window from its temperatures and those of the
/// `lags` windows before it (`history[0]` the window itself, then older);
/// `None` when a needed temperature is missing (`NaN` or no history yet).
pub fn regressors(settings: &Settings, history: &[&[f64]]) -> Option<Vec<f64>> {
    let now = history.first()?;
    let mut x = vec![1.0];
    x.extend(now.iter());
    x.extend(now.iter().map(|t| (settings.knee_c - t).max(0.0)));
    for lag in 1..=settings.lags {
        x.extend(history.get(lag)?.iter());
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// A fitted compensation model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Compensation {
    /// `y ≈ Bᵀ x`: `coefficients[f]` are feature `f`'s regression coefficients.
    Regression { coefficients: Vec<Vec<f64>> },
    /// Residual `(I − V Vᵀ) z` of the standardised features `z = (y − mean) / scale`.
    Pca {
        mean: Vec<f64>,
        scale: Vec<f64>,
        /// The removed principal directions (unit vectors, one per component).
        loadings: Vec<Vec<f64>>,
        /// The training correlation of `z` (rows), to fill in a missing
        /// feature; empty in a reference saved before it was kept.
        #[serde(default)]
        correlation: Vec<Vec<f64>>,
    },
}

/// Least squares `B = X⁺ Y` by a thin SVD, dropping singular values below
/// 1e-10 of the largest (a hinge never active in training, collinear
/// channels) so those combinations get no coefficient.
fn least_squares(x: &Mat<f64>, y: &Mat<f64>) -> Mat<f64> {
    let q = x.ncols();
    // Column scaling keeps the truncation threshold meaningful.
    let norms: Vec<f64> = (0..q)
        .map(|c| (0..x.nrows()).map(|r| x[(r, c)] * x[(r, c)]).sum::<f64>().sqrt())
        .collect();
    let xs = Mat::from_fn(
        x.nrows(),
        q,
        |r, c| if norms[c] > 0.0 { x[(r, c)] / norms[c] } else { 0.0 },
    );
    let Ok(svd) = xs.thin_svd() else {
        return Mat::zeros(q, y.ncols());
    };
    let s: Vec<f64> = (0..q.min(x.nrows())).map(|i| svd.S()[i]).collect();
    let top = s.iter().copied().fold(0.0, f64::max);
    let (u, v) = (svd.U(), svd.V());
    let uty = u.transpose() * y;
    Mat::from_fn(q, y.ncols(), |row, col| {
        if norms[row] == 0.0 {
            return 0.0;
        }
        let sum: f64 = (0..s.len())
            .filter(|&i| s[i] > 1e-10 * top)
            .map(|i| v[(row, i)] * uty[(i, col)] / s[i])
            .sum();
        sum / norms[row]
    })
}

/// Replaces the missing (not finite) entries of standardised features `z`
/// by their conditional mean given the observed ones under the training
/// correlation `C`: `z_m = C_mo C_oo⁻¹ z_o` ("conditional mean
/// replacement", Nelson, Taylor & MacGregor 1996, which keeps the PCA
/// residual's structure; a 1e-8 ridge for a correlation of rank < p).
fn fill_conditional_mean(z: &mut [f64], correlation: &[Vec<f64>]) {
    use faer::linalg::solvers::Solve;
    let (m, o): (Vec<usize>, Vec<usize>) = (0..z.len()).partition(|&f| !z[f].is_finite());
    if correlation.len() != z.len() {
        // A reference saved without the correlation: the training mean.
        return m.iter().for_each(|&f| z[f] = 0.0);
    }
    let c_oo = Mat::from_fn(o.len(), o.len(), |i, j| {
        correlation[o[i]][o[j]] + if i == j { 1e-8 } else { 0.0 }
    });
    let z_o = Mat::from_fn(o.len(), 1, |i, _| z[o[i]]);
    let Ok(llt) = c_oo.llt(faer::Side::Lower) else {
        return m.iter().for_each(|&f| z[f] = 0.0);
    };
    let w = llt.solve(&z_o);
    for &f in &m {
        z[f] = (0..o.len()).map(|i| correlation[f][o[i]] * w[(i, 0)]).sum();
    }
}

impl Compensation {
    /// Fits the regression of `features` (one row per window) on `regressors`.
    pub fn regression(features: &[&[f64]], regressors: &[Vec<f64>]) -> Self {
        let (n, p, q) = (features.len(), features[0].len(), regressors[0].len());
        let x = Mat::from_fn(n, q, |r, c| regressors[r][c]);
        let y = Mat::from_fn(n, p, |r, c| features[r][c]);
        let b = least_squares(&x, &y);
        Self::Regression {
            coefficients: (0..p).map(|f| (0..q).map(|c| b[(c, f)]).collect()).collect(),
        }
    }

    /// Fits the PCA model removing `components` principal directions.
    pub fn pca(features: &[&[f64]], components: usize) -> Self {
        let (n, p) = (features.len(), features[0].len());
        let mean: Vec<f64> = (0..p)
            .map(|f| features.iter().map(|y| y[f]).sum::<f64>() / n as f64)
            .collect();
        let scale: Vec<f64> = (0..p)
            .map(|f| {
                let var = features.iter().map(|y| (y[f] - mean[f]).powi(2)).sum::<f64>() / (n.max(2) - 1) as f64;
                let sd = var.sqrt();
                if sd > 1e-12 * mean[f].abs().max(f64::MIN_POSITIVE) {
                    sd
                } else {
                    1.0
                }
            })
            .collect();
        let z = Mat::from_fn(n, p, |r, c| (features[r][c] - mean[c]) / scale[c]);
        let k = components.min(p.saturating_sub(1)).min(n.saturating_sub(1));
        let loadings = match z.thin_svd() {
            Ok(svd) => (0..k).map(|i| (0..p).map(|f| svd.V()[(f, i)]).collect()).collect(),
            Err(_) => Vec::new(),
        };
        let correlation = (0..p)
            .map(|a| {
                (0..p)
                    .map(|b| (0..n).map(|r| z[(r, a)] * z[(r, b)]).sum::<f64>() / (n.max(2) - 1) as f64)
                    .collect()
            })
            .collect();
        Self::Pca {
            mean,
            scale,
            loadings,
            correlation,
        }
    }

    /// The residual of one window (`regressors` for the regression model).
    #[track_caller]
    pub fn residual(&self, features: &[f64], regressors: Option<&[f64]>) -> Vec<f64> {
        match self {
            Self::Regression { coefficients } => {
                let x = regressors.expect("a regression model needs the window's regressors");
                features
                    .iter()
                    .zip(coefficients)
                    .map(|(y, b)| y - b.iter().zip(x).map(|(b, x)| b * x).sum::<f64>())
                    .collect()
            }
            Self::Pca {
                mean,
                scale,
                loadings,
                correlation,
            } => {
                let mut z: Vec<f64> = features
                    .iter()
                    .zip(mean)
                    .zip(scale)
                    .map(|((y, m), s)| (y - m) / s)
                    .collect();
                if !z.iter().all(|v| v.is_finite()) {
                    fill_conditional_mean(&mut z, correlation);
                }
                for v in loadings {
                    let proj: f64 = z.iter().zip(v).map(|(a, b)| a * b).sum();
                    z.iter_mut().zip(v).for_each(|(a, b)| *a -= proj * b);
                }
                z
            }
        }
    }

    /// Regressors per window this model needs (0 for PCA).
    pub fn regressor_count(&self) -> usize {
        match self {
            Self::Regression { coefficients } => coefficients.first().map_or(0, Vec::len),
            Self::Pca { .. } => 0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Features built exactly from the regressors (one with a hinge below
    /// 0 °C) are recovered to round-off, and their residual is zero.
    #[test]
    fn regression_recovers_a_bilinear_law() {
        let settings = Settings {
            temperature_channels: 1,
            ..Settings::default()
        };
        let temps: Vec<f64> = (0..40).map(|k| -6.0 + 0.6 * k as f64 + (k % 3) as f64).collect();
        let law = |t: f64| [2.0 - 0.01 * t + 0.05 * (0.0 - t).max(0.0), 5.0 + 0.3 * t];
        let features: Vec<[f64; 2]> = temps.iter().map(|&t| law(t)).collect();
        let x: Vec<Vec<f64>> = temps.iter().map(|t| regressors(&settings, &[&[*t]]).unwrap()).collect();
        let rows: Vec<&[f64]> = features.iter().map(|f| f.as_slice()).collect();
        let model = Compensation::regression(&rows, &x);
        let Compensation::Regression { coefficients } = &model else {
            unreachable!()
        };
        let want = [[2.0, -0.01, 0.05], [5.0, 0.3, 0.0]];
        for (got, want) in coefficients.iter().zip(want) {
            for (g, w) in got.iter().zip(want) {
                assert!((g - w).abs() < 1e-10, "{g} vs {w}");
            }
        }
        let r = model.residual(&law(-3.0), Some(&regressors(&settings, &[&[-3.0]]).unwrap()));
        assert!(r.iter().all(|v| v.abs() < 1e-10), "{r:?}");
    }

    /// Without a window below the knee the hinge column is zero: it gets no
    /// coefficient instead of a singular solve.
    #[test]
    fn an_inactive_hinge_is_left_out() {
        let settings = Settings::default();
        let x: Vec<Vec<f64>> = (0..10)
            .map(|k| regressors(&settings, &[&[5.0 + k as f64]]).unwrap())
            .collect();
        let features: Vec<[f64; 1]> = (0..10).map(|k| [1.0 + 0.1 * k as f64]).collect();
        let rows: Vec<&[f64]> = features.iter().map(|f| f.as_slice()).collect();
        let Compensation::Regression { coefficients } = Compensation::regression(&rows, &x) else {
            unreachable!()
        };
        assert!(coefficients[0].iter().all(|c| c.is_finite()));
        assert_eq!(coefficients[0][2], 0.0);
        assert!((coefficients[0][1] - 0.1).abs() < 1e-12);
    }

    /// Lags need history; a NaN temperature gives no regressors.
    #[test]
    fn missing_history_or_temperature_gives_none() {
        let settings = Settings {
            lags: 1,
            ..Settings::default()
        };
        assert!(regressors(&settings, &[&[3.0]]).is_none());
        assert_eq!(
            regressors(&settings, &[&[3.0], &[1.0]]).unwrap(),
            vec![1.0, 3.0, 0.0, 1.0]
        );
        assert!(regressors(&settings, &[&[f64::NAN], &[1.0]]).is_none());
    }

    /// Two features driven by one hidden factor: removing one principal
    /// component leaves only the independent noise.
    #[test]
    fn pca_removes_a_common_factor() {
        let rows: Vec<[f64; 3]> = (0..50)
            .map(|k| {
                let f = (k as f64 * 0.37).sin() * 10.0;
                let e = ((k * 7919) % 13) as f64 * 0.01;
                [1.0 + f, 2.0 - 2.0 * f + e, 3.0 + f - e]
            })
            .collect();
        let refs: Vec<&[f64]> = rows.iter().map(|r| r.as_slice()).collect();
        let model = Compensation::pca(&refs, 1);
        let f = 4.0;
        let r = model.residual(&[1.0 + f, 2.0 - 2.0 * f, 3.0 + f], None);
        let norm = r.iter().map(|v| v * v).sum::<f64>().sqrt();
        assert!(norm < 0.05, "{r:?}");
        // A feature missing: filled in from the other two by the training
        // correlation, the residual stays as small.
        let r = model.residual(&[1.0 + f, f64::NAN, 3.0 + f], None);
        assert!(r.iter().all(|v| v.abs() < 0.05), "{r:?}");
    }
}
