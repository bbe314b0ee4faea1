//! Residual scales and covariance estimated robustly from few windows.

use faer::Mat;

/// Median absolute deviation about the median, × 1.4826 (the standard
/// deviation of a normal sample), or the standard deviation when more than
/// half of the values are equal; 0 for a constant feature.
pub fn robust_scale(values: &[f64]) -> f64 {
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        let n = v.len();
        if n % 2 == 1 {
            v[n / 2]
        } else {
            0.5 * (v[n / 2 - 1] + v[n / 2])
        }
    };
    if values.is_empty() {
        return 0.0;
    }
    let mut v = values.to_vec();
    let m = median(&mut v);
    let mut dev: Vec<f64> = values.iter().map(|x| (x - m).abs()).collect();
    let mad = 1.4826 * median(&mut dev);
    if mad > 0.0 {
        return mad;
    }
    let mean = values.iter().sum::<f64>() / values.len() as f64;
    (values.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / values.len() as f64).sqrt()
}

/// Ledoit & Wolf (2004) shrinkage of the sample covariance of `rows`
/// (centred here) towards `μ I`, `μ` the mean variance: returns the
/// estimate and the shrinkage intensity in [0, 1]. Well conditioned even
/// with fewer windows than features.
pub fn ledoit_wolf(rows: &[Vec<f64>]) -> (Mat<f64>, f64) {
    let (n, p) = (rows.len(), rows.first().map_or(0, Vec::len));
    let mean: Vec<f64> = (0..p)
        .map(|j| rows.iter().map(|r| r[j]).sum::<f64>() / n as f64)
        .collect();
    let x = Mat::from_fn(n, p, |i, j| rows[i][j] - mean[j]);
    let s = x.transpose() * &x * (1.0 / n as f64);
    let mu = (0..p).map(|i| s[(i, i)]).sum::<f64>() / p as f64;
    // Squared Frobenius norms normalised by p, as in Ledoit & Wolf.
    let frob = |m: &Mat<f64>| m.squared_norm_l2() / p as f64;
    let mut target = s.clone();
    for i in 0..p {
        target[(i, i)] -= mu;
    }
    let d2 = frob(&target);
    let b2_bar = (0..n)
        .map(|k| {
            let xk = x.row(k);
            let outer = Mat::from_fn(p, p, |i, j| xk[i] * xk[j]);
            frob(&(&outer - &s))
        })
        .sum::<f64>()
        / (n as f64 * n as f64);
    let shrinkage = if d2 > 0.0 {
        (b2_bar.min(d2) / d2).clamp(0.0, 1.0)
    } else {
        1.0
    };
    let estimate = Mat::from_fn(p, p, |i, j| {
        let prior = if i == j { mu } else { 0.0 };
        shrinkage * prior + (1.0 - shrinkage) * s[(i, j)]
    });
    (estimate, shrinkage)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn robust_scale_ignores_an_outlier() {
        let v: Vec<f64> = (0..21).map(|k| k as f64 - 10.0).collect();
        let mut with_outlier = v.clone();
        with_outlier[3] = 1e6;
        let (a, b) = (robust_scale(&v), robust_scale(&with_outlier));
        assert!((a - 1.4826 * 5.0).abs() < 1e-12);
        assert!((b - a).abs() / a < 0.25, "{a} {b}");
        assert_eq!(robust_scale(&[2.0; 5]), 0.0);
    }

    /// Many windows of strongly correlated features: little shrinkage, the
    /// estimate near the truth; with independent ones (the target itself)
    /// full shrinkage; three windows of four features still positive definite.
    #[test]
    fn shrinkage_goes_with_the_evidence() {
        let mut state = 12345u64;
        let mut uniform = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 12f64.sqrt()
        };
        // x_j = 0.9 c + 0.436 e_j: unit variance, correlation 0.81.
        let rows: Vec<Vec<f64>> = (0..2000)
            .map(|_| {
                let c = uniform();
                (0..4).map(|_| 0.9 * c + 0.19f64.sqrt() * uniform()).collect()
            })
            .collect();
        let (s, shrink) = ledoit_wolf(&rows);
        for i in 0..4 {
            for j in 0..4 {
                let want = if i == j { 1.0 } else { 0.81 };
                assert!((s[(i, j)] - want).abs() < 0.08, "{i},{j}: {}", s[(i, j)]);
            }
        }
        assert!(shrink < 0.05, "{shrink}");
        let independent: Vec<Vec<f64>> = (0..2000).map(|_| (0..4).map(|_| uniform()).collect()).collect();
        assert!(ledoit_wolf(&independent).1 > 0.9);
        let (few, _) = ledoit_wolf(&rows[..3]);
        assert!(
            few.llt(faer::Side::Lower).is_ok(),
            "3 windows, 4 features: still positive definite"
        );
    }
}
