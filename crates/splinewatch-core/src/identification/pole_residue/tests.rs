use super::*;
use crate::identification::test_noise::uniform_noise;
use crate::identification::transmissibility;

fn pole(f: f64, zeta: f64) -> c64 {
    let w = 2.0 * PI * f;
    c64::new(-zeta * w, w * (1.0 - zeta * zeta).sqrt())
}

/// The one mode fitted to `h` (standard deviations `sigma`).
fn one_mode(frequencies: &[f64], h: &[Vec<c64>], sigma: &[Vec<f64>]) -> FittedMode {
    let functions = Functions {
        frequencies_hz: frequencies,
        h,
        sigma,
    };
    fit(functions, 1).unwrap().modes.remove(0)
}

/// The mean and the sample standard deviation of `values`.
fn mean_and_scatter(values: impl Iterator<Item = f64> + Clone) -> (f64, f64) {
    let n = values.clone().count() as f64;
    let mean = values.clone().sum::<f64>() / n;
    let scatter = (values.map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    (mean, scatter)
}

/// `Σ_m A/(s−λ) + Ā/(s−λ̄) + c` at `frequencies`.
fn exact(frequencies: &[f64], modes: &[(f64, f64)], residues: &[c64], constant: c64) -> Vec<c64> {
    frequencies
        .iter()
        .map(|&f| {
            let s = c64::new(0.0, 2.0 * PI * f);
            modes
                .iter()
                .zip(residues)
                .map(|(&(fm, z), &a)| {
                    let l = pole(fm, z);
                    a / (s - l) + a.conj() / (s - l.conj())
                })
                .sum::<c64>()
                + constant
        })
        .collect()
}

/// Two modes 12 % and 8 % damped, 13 % apart, in three functions with
/// their own constants: recovered to 1e-7 from exact data, the residues
/// too, and nothing left (s² at rounding level).
#[test]
fn close_heavily_damped_modes_are_recovered_from_exact_functions() {
    let truth = [(3.8, 0.12), (4.3, 0.08)];
    let residues = [
        [c64::new(10.0, 3.0), c64::new(5.0, -2.0)],
        [c64::new(7.0, -1.0), c64::new(-6.0, 1.0)],
        [c64::new(2.0, 0.0), c64::new(10.0, 0.0)],
    ];
    let frequencies: Vec<f64> = (0..81).map(|k| 2.0 + 0.05 * f64::from(k)).collect();
    let h: Vec<Vec<c64>> = residues
        .iter()
        .enumerate()
        .map(|(j, r)| exact(&frequencies, &truth, r, c64::new(1.0 + j as f64, -0.1)))
        .collect();
    let sigma = vec![vec![0.01; frequencies.len()]; 3];
    let functions = Functions {
        frequencies_hz: &frequencies,
        h: &h,
        sigma: &sigma,
    };
    let fitted = fit(functions, 2).unwrap();
    for (mode, &(f, z)) in fitted.modes.iter().zip(&truth) {
        assert!((mode.frequency_hz - f).abs() < 1e-7 * f, "{mode:?} for {f}");
        assert!((mode.damping_ratio - z).abs() < 1e-7, "{mode:?} for {z}");
        assert!(!mode.at_bound);
    }
    for (j, r) in residues.iter().enumerate() {
        for (m, a) in r.iter().enumerate() {
            assert!((fitted.modes[m].residues[j] - a).norm() < 1e-5 * a.norm(), "{j} {m}");
        }
    }
    assert!(fitted.residual_scale < 1e-12, "{}", fitted.residual_scale);
    // Bad input is named.
    let short = Functions {
        frequencies_hz: &frequencies[..6],
        ..functions
    };
    assert!(matches!(fit(short, 1), Err(PoleResidueError::TooFewLines { .. })));
    let two = &sigma[..2];
    assert_eq!(
        fit(
            Functions {
                sigma: two,
                ..functions
            },
            1
        ),
        Err(PoleResidueError::UnequalCounts {
            functions: 3,
            deviations: 2
        })
    );
    let zero = vec![vec![0.0; frequencies.len()]; 3];
    let unweighted = Functions {
        sigma: &zero,
        ..functions
    };
    assert!(matches!(
        fit(unweighted, 1),
        Err(PoleResidueError::BadLine { function: 0, line: 0 })
    ));
}

/// The analytic Jacobian of the projected residual (Kaufman's form) gives
/// the exact gradient of the cost: `2 Jᵀr` equals the cost's central
/// differences (steps 1e-6 of f, 1e-7 of ζ) to 1e-6 of the gradient's
/// largest component, away from the optimum on noisy data (two modes in
/// two functions, 5 % noise) where the omitted second-order term is not
/// zero. A wrong derivative of the poles' columns breaks this.
#[test]
fn the_jacobian_gives_the_exact_gradient_of_the_cost() {
    let truth = [(3.8, 0.12), (4.3, 0.08)];
    let frequencies: Vec<f64> = (0..61).map(|k| 2.5 + 0.05 * f64::from(k)).collect();
    let noise = uniform_noise(7, 4 * frequencies.len());
    let h: Vec<Vec<c64>> = [
        [c64::new(10.0, 3.0), c64::new(5.0, -2.0)],
        [c64::new(7.0, -1.0), c64::new(-6.0, 1.0)],
    ]
    .iter()
    .enumerate()
    .map(|(j, r)| {
        let clean = exact(&frequencies, &truth, r, c64::new(1.0, 0.5));
        clean
            .iter()
            .enumerate()
            .map(|(k, v)| v + c64::new(noise[4 * k + 2 * j], noise[4 * k + 2 * j + 1]) * (0.1 * v.norm()))
            .collect()
    })
    .collect();
    let sigma: Vec<Vec<f64>> = h.iter().map(|f| f.iter().map(|v| 0.05 * v.norm()).collect()).collect();
    let problem = Problem::new(Functions {
        frequencies_hz: &frequencies,
        h: &h,
        sigma: &sigma,
    });
    let theta = [3.7, 0.10, 4.45, 0.09];
    let evaluation = problem.evaluate(&theta).unwrap();
    let jacobian = problem.jacobian(&theta, &evaluation);
    let gradient: Vec<f64> = (0..theta.len())
        .map(|p| {
            2.0 * (0..jacobian.nrows())
                .map(|r| jacobian[(r, p)] * evaluation.residual[r])
                .sum::<f64>()
        })
        .collect();
    let largest = gradient.iter().fold(0.0f64, |m, g| m.max(g.abs()));
    for (p, g) in gradient.iter().enumerate() {
        let step = if p % 2 == 0 { 1e-6 } else { 1e-7 };
        let (mut plus, mut minus) = (theta, theta);
        plus[p] += step;
        minus[p] -= step;
        let difference = (problem.cost(&plus).unwrap() - problem.cost(&minus).unwrap()) / (2.0 * step);
        assert!(
            (g - difference).abs() < 1e-6 * largest,
            "parameter {p}: 2Jᵀr {g}, differences {difference}"
        );
    }
}

/// The reported standard deviations are the scatter: one 10 %-damped mode
/// in two functions, complex Gaussian-like noise of a known level (the sum
/// of 12 uniforms, Irwin–Hall) on every line; over 200 noise draws the mean
/// reported std of f and ζ is within 20 % of the draws' scatter (the scatter
/// of 200 draws is itself known to about 5 %), and the mean estimate is
/// within one scatter of the truth.
#[test]
fn reported_standard_deviations_match_the_scatter_over_noise_draws() {
    let truth = [(4.0, 0.10)];
    let frequencies: Vec<f64> = (0..41).map(|k| 2.0 + 0.125 * f64::from(k)).collect();
    let clean = [
        exact(&frequencies, &truth, &[c64::new(5.0, 1.0)], c64::new(1.0, 0.0)),
        exact(&frequencies, &truth, &[c64::new(3.0, -1.0)], c64::new(0.8, 0.1)),
    ];
    let level = 0.15;
    let sigma = vec![vec![level; frequencies.len()]; 2];
    let gaussian = |seed: u64, n: usize| -> Vec<f64> {
        let u = uniform_noise(seed, 12 * n);
        u.chunks(12).map(|c| c.iter().sum::<f64>()).collect()
    };
    let draws = 200;
    let mut estimates = Vec::new();
    let mut reported = (0.0, 0.0);
    for seed in 0..draws {
        let noise = gaussian(seed + 1, 4 * frequencies.len());
        let scale = level / 2f64.sqrt();
        let h: Vec<Vec<c64>> = clean
            .iter()
            .enumerate()
            .map(|(j, hj)| {
                hj.iter()
                    .enumerate()
                    .map(|(k, v)| {
                        let i = 2 * (j * frequencies.len() + k);
                        v + c64::new(scale * noise[i], scale * noise[i + 1])
                    })
                    .collect()
            })
            .collect();
        let m = &one_mode(&frequencies, &h, &sigma);
        estimates.push((m.frequency_hz, m.damping_ratio));
        reported.0 += m.frequency_std_hz / f64::from(draws as u32);
        reported.1 += m.damping_std / f64::from(draws as u32);
    }
    let (mf, sf) = mean_and_scatter(estimates.iter().map(|e| e.0));
    let (mz, sz) = mean_and_scatter(estimates.iter().map(|e| e.1));
    assert!(
        (reported.0 / sf - 1.0).abs() < 0.2,
        "f: reported {} scatter {sf}",
        reported.0
    );
    assert!(
        (reported.1 / sz - 1.0).abs() < 0.2,
        "ζ: reported {} scatter {sz}",
        reported.1
    );
    assert!(
        (mf - truth[0].0).abs() < sf && (mz - truth[0].1).abs() < sz,
        "{mf} {mz}"
    );
}

/// A simulated record: a 10 %-damped base-excited oscillator at 4 Hz
/// (absolute acceleration, `H = (2ζωs + ω²)/(s² + 2ζωs + ω²)`, matched
/// poles `z = e^{λT}`) driven by a random ground at 50 Hz for 120 s, its
/// output with 30 % noise; the H1 estimate's standard deviations from the
/// coherence ([`h1_standard_deviation`], as the commands give them). Over 40 records the mean reported std is within a factor 1.6
/// of the records' scatter (40 records know their scatter to about 11 %;
/// the H1 errors are correlated across lines by the window, which the
/// residual scale only partly absorbs), and the mean estimate within 2 %
/// of 4 Hz and 0.02 of ζ (the discrete system is not the continuous one).
#[test]
fn reported_standard_deviations_hold_on_simulated_records() {
    let fs = 50.0;
    let samples = 6000;
    let (f0, zeta) = (4.0, 0.10);
    let lambda = pole(f0, zeta);
    let t = 1.0 / fs;
    let z = (lambda * t).exp();
    let (a1, a2) = (2.0 * z.re, -z.norm_sqr());
    let mut estimates = Vec::new();
    let mut reported = (0.0, 0.0);
    let records = 40;
    for seed in 0..records {
        let ground = uniform_noise(1000 + seed, samples);
        // Numerator from the continuous one at zero frequency and the
        // damping term (a first difference): gain 1 at 0 Hz.
        let w = 2.0 * PI * f0;
        let (b0, b1) = (2.0 * zeta * w * t, (1.0 - a1 - a2) - 2.0 * zeta * w * t);
        let mut response = vec![0.0; samples];
        for k in 0..samples {
            let y1 = if k >= 1 { response[k - 1] } else { 0.0 };
            let y2 = if k >= 2 { response[k - 2] } else { 0.0 };
            let x1 = if k >= 1 { ground[k - 1] } else { 0.0 };
            response[k] = a1 * y1 + a2 * y2 + b0 * ground[k] + b1 * x1;
        }
        let rms = (response.iter().map(|v| v * v).sum::<f64>() / samples as f64).sqrt();
        let noise = uniform_noise(5000 + seed, samples);
        let measured: Vec<f64> = response
            .iter()
            .zip(&noise)
            .map(|(r, e)| r + 0.3 * rms * e * 12f64.sqrt())
            .collect();
        let est = transmissibility::estimate(&[&ground], &[&measured], fs, 400, 200).unwrap();
        let band: Vec<usize> = (0..est.frequencies_hz.len())
            .filter(|&k| (2.0..=7.0).contains(&est.frequencies_hz[k]))
            .collect();
        let frequencies: Vec<f64> = band.iter().map(|&k| est.frequencies_hz[k]).collect();
        let h = vec![band.iter().map(|&k| est.h[0][0][k]).collect::<Vec<_>>()];
        let sigma = vec![band
            .iter()
            .map(|&k| h1_standard_deviation(est.h[0][0][k], est.coherence[0][k], est.averages, 1))
            .collect::<Vec<_>>()];
        let m = &one_mode(&frequencies, &h, &sigma);
        estimates.push((m.frequency_hz, m.damping_ratio));
        reported.0 += m.frequency_std_hz / f64::from(records as u32);
        reported.1 += m.damping_std / f64::from(records as u32);
    }
    let (mf, sf) = mean_and_scatter(estimates.iter().map(|e| e.0));
    let (mz, sz) = mean_and_scatter(estimates.iter().map(|e| e.1));
    assert!(
        (reported.0 / sf).ln().abs() < 1.6f64.ln(),
        "f: reported {} scatter {sf}",
        reported.0
    );
    assert!(
        (reported.1 / sz).ln().abs() < 1.6f64.ln(),
        "ζ: reported {} scatter {sz}",
        reported.1
    );
    assert!((mf - f0).abs() < 0.02 * f0 && (mz - zeta).abs() < 0.02, "{mf} {mz}");
}
