//! The uncertainty of an update's estimates, to first order at the
//! solution: `C = σ̂² (JᵀJ)⁻¹` (weighted Jacobian) with `σ̂² = 2·cost/(m − n)`,
//! from the SVD of the column-normalised Jacobian: the standard deviations,
//! the correlations and the directions the data cannot determine.

use super::{HeldParameter, HoldReason, Parameter, ParameterCorrelation, ParameterEstimate};
use faer::Mat;

/// Standard deviations `√diag(σ̂² (JᵀJ)⁻¹)` and the singular values of the
/// column-normalised `J`. A direction with singular value below `1e-12` of
/// the largest makes every parameter it involves unidentifiable (`None`).
/// Standard deviations, singular values of the column-normalised Jacobian
/// and the parameters' correlation matrix `ρ_kl = C_kl / √(C_kk C_ll)`,
/// `C = (JᵀJ)⁻¹` from the same SVD (`None` when `JᵀJ` is singular).
fn covariance(j: &Mat<f64>, variance: f64) -> (Vec<Option<f64>>, Vec<f64>, Option<Mat<f64>>) {
    let n = j.ncols();
    let norms: Vec<f64> = (0..n)
        .map(|c| (0..j.nrows()).map(|r| j[(r, c)].powi(2)).sum::<f64>().sqrt())
        .collect();
    if norms.iter().any(|&c| c == 0.0 || !c.is_finite()) {
        let sv = vec![0.0; n];
        return (norms.iter().map(|_| None).collect(), sv, None);
    }
    let js = Mat::from_fn(j.nrows(), n, |r, c| j[(r, c)] / norms[c]);
    let Ok(svd) = js.thin_svd() else {
        return (vec![None; n], vec![f64::NAN; n], None);
    };
    let s: Vec<f64> = (0..n).map(|i| svd.S()[i]).collect();
    let v = svd.V();
    let smax = s[0];
    let kept: Vec<usize> = (0..n).filter(|&i| s[i] > 1e-12 * smax).collect();
    let std = (0..n)
        .map(|k| {
            if (0..n).any(|i| s[i] <= 1e-12 * smax && v[(k, i)].abs() > 1e-8) {
                return None;
            }
            let acc: f64 = kept.iter().map(|&i| v[(k, i)] * v[(k, i)] / (s[i] * s[i])).sum();
            Some((variance * acc).sqrt() / norms[k])
        })
        .collect();
    let correlation = (kept.len() == n).then(|| {
        let c = Mat::from_fn(n, n, |k, l| {
            kept.iter().map(|&i| v[(k, i)] * v[(l, i)] / (s[i] * s[i])).sum::<f64>()
        });
        Mat::from_fn(n, n, |k, l| c[(k, l)] / (c[(k, k)] * c[(l, l)]).sqrt())
    });
    (std, s, correlation)
}

/// How many of the most correlated parameter pairs a result reports.
pub const REPORTED_CORRELATIONS: usize = 10;

/// What [`estimates`] gives: the estimates with their standard deviations
/// (`σ̂² (JᵀJ)⁻¹`, `σ̂² = 2·cost/(m − n)`), the singular values of the
/// column-normalised Jacobian, its condition number, `σ̂²` and the most
/// correlated parameter pairs.
pub(super) struct Estimates {
    pub(super) parameters: Vec<ParameterEstimate>,
    pub(super) singular_values: Vec<f64>,
    pub(super) condition_number: f64,
    pub(super) residual_variance: f64,
    pub(super) correlations: Vec<ParameterCorrelation>,
    pub(super) held: Vec<HeldParameter>,
    /// `σ̂² (JᵀJ)⁻¹`, held parameters' rows and columns zero; `None`
    /// when `JᵀJ` is singular.
    pub(super) covariance: Option<Vec<Vec<f64>>>,
}

pub(super) fn estimates(
    parameters: &[Parameter],
    p: &[f64],
    jacobian: &Mat<f64>,
    cost: f64,
    held: &[Option<HoldReason>],
) -> Estimates {
    // The covariance of the free parameters; a held one has no std.
    let free: Vec<usize> = (0..p.len())
        .filter(|&k| held.get(k).is_none_or(Option::is_none))
        .collect();
    let (m, n) = (jacobian.nrows(), free.len());
    let residual_variance = 2.0 * cost / (m - n) as f64;
    let j_free = Mat::from_fn(m, n, |r, c| jacobian[(r, free[c])]);
    let (free_std, singular_values, free_correlation) = covariance(&j_free, residual_variance);
    let mut std = vec![None; p.len()];
    for (&k, s) in free.iter().zip(free_std) {
        std[k] = s;
    }
    let correlation = free_correlation.map(|rho| {
        let mut full = Mat::<f64>::zeros(p.len(), p.len());
        for (a, &k) in free.iter().enumerate() {
            for (b, &l) in free.iter().enumerate() {
                full[(k, l)] = rho[(a, b)];
            }
        }
        full
    });
    let covariance = correlation.as_ref().map(|rho| {
        let s = |k: usize| std[k].unwrap_or(0.0);
        (0..p.len())
            .map(|k| (0..p.len()).map(|l| rho[(k, l)] * s(k) * s(l)).collect())
            .collect()
    });
    let condition_number = match (singular_values.first(), singular_values.last()) {
        (Some(&hi), Some(&lo)) if lo > 0.0 => hi / lo,
        _ => f64::INFINITY,
    };
    let estimates = parameters
        .iter()
        .zip(p.iter().zip(std))
        .map(|(par, (&value, std))| ParameterEstimate {
            name: par.name.clone(),
            value,
            std,
            lower: par.lower,
            upper: par.upper,
        })
        .collect();
    let mut correlations: Vec<ParameterCorrelation> = match &correlation {
        Some(rho) => (0..n)
            .flat_map(|a| (a + 1..n).map(move |b| (a, b)))
            .map(|(a, b)| (free[a], free[b]))
            .map(|(k, l)| ParameterCorrelation {
                a: parameters[k].name.clone(),
                b: parameters[l].name.clone(),
                rho: rho[(k, l)],
            })
            .collect(),
        None => Vec::new(),
    };
    correlations.sort_by(|x, y| y.rho.abs().total_cmp(&x.rho.abs()));
    correlations.truncate(REPORTED_CORRELATIONS);
    let held = parameters
        .iter()
        .zip(p.iter().zip(held))
        .filter_map(|(par, (&value, reason))| {
            reason.map(|reason| HeldParameter {
                name: par.name.clone(),
                reason,
                value,
            })
        })
        .collect();
    Estimates {
        parameters: estimates,
        singular_values,
        condition_number,
        residual_variance,
        correlations,
        held,
        covariance,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::linalg::solvers::DenseSolveCore;
    use faer::Side;

    /// The correlations from the SVD equal those of `(JᵀJ)⁻¹` formed
    /// directly, the most correlated pair comes first, and the covariance
    /// is `σ̂² (JᵀJ)⁻¹`.
    #[test]
    fn correlations_are_those_of_the_inverse_normal_matrix() {
        // Columns 0 and 2 nearly collinear.
        let j = Mat::from_fn(12, 3, |r, c| {
            let x = r as f64;
            match c {
                0 => 1.0 + 0.3 * x,
                1 => (0.7 * x).sin(),
                _ => 2.0 + 0.61 * x + 0.05 * (1.3 * x).cos(),
            }
        });
        let (_, _, rho) = covariance(&j, 1.0);
        let rho = rho.unwrap();
        let jtj = j.transpose() * &j;
        let inverse = jtj.llt(Side::Lower).unwrap().inverse();
        for k in 0..3 {
            for l in 0..3 {
                let want = inverse[(k, l)] / (inverse[(k, k)] * inverse[(l, l)]).sqrt();
                assert!((rho[(k, l)] - want).abs() < 1e-9, "{k},{l}: {} vs {want}", rho[(k, l)]);
            }
        }
        let parameters: Vec<Parameter> = ["a", "b", "c"]
            .iter()
            .map(|n| Parameter {
                name: (*n).into(),
                kind: crate::updating::ParameterKind::Damping { coefficient: 0 },
                lower: 0.0,
                upper: 1.0,
            })
            .collect();
        let e = estimates(&parameters, &[0.5; 3], &j, 1.0, &[None; 3]);
        assert_eq!((e.correlations[0].a.as_str(), e.correlations[0].b.as_str()), ("a", "c"));
        assert!(e.correlations[0].rho.abs() > 0.9);
        assert_eq!(e.correlations.len(), 3);
        // The covariance is σ̂² (JᵀJ)⁻¹, σ̂² = 2·cost/(m − n) = 2/9.
        let covariance = e.covariance.unwrap();
        for k in 0..3 {
            for l in 0..3 {
                let want = 2.0 / 9.0 * inverse[(k, l)];
                assert!(
                    (covariance[k][l] - want).abs() < 1e-9 * want.abs().max(inverse[(k, k)]),
                    "{k},{l}: {} vs {want}",
                    covariance[k][l]
                );
            }
        }
    }
}
