use super::modal_form::{ModalBlock, ModalForm};
use super::*;
use crate::identification::test_noise::uniform_noise as noise;
use faer::linalg::solvers::{DenseSolveCore, SolveLstsq};

/// Two damped modes (2.1 Hz 3 %, 5.3 Hz 6 %) at 50 Hz, two inputs,
/// three outputs, with feedthrough: a realization in a rotated
/// (non-modal) basis.
fn truth() -> Realization {
    let fs = 50.0;
    let pair = |f: f64, zeta: f64| {
        let w = 2.0 * std::f64::consts::PI * f;
        let radius = (-zeta * w / fs).exp();
        let angle = w * (1.0 - zeta * zeta).sqrt() / fs;
        (radius * angle.cos(), radius * angle.sin())
    };
    let (s1, w1) = pair(2.1, 0.03);
    let (s2, w2) = pair(5.3, 0.06);
    let lambda = Mat::from_fn(4, 4, |i, j| match (i, j) {
        (0, 0) | (1, 1) => s1,
        (0, 1) => w1,
        (1, 0) => -w1,
        (2, 2) | (3, 3) => s2,
        (2, 3) => w2,
        (3, 2) => -w2,
        _ => 0.0,
    });
    let t = Mat::from_fn(4, 4, |i, j| if i == j { 1.0 } else { 0.3 / (1.0 + (i + 2 * j) as f64) });
    let t_inv = t.partial_piv_lu().inverse();
    let a = &t * &lambda * &t_inv;
    let b = Mat::from_fn(4, 2, |i, j| [[0.4, -0.1], [1.0, 0.2], [-0.3, 0.7], [0.5, 0.9]][i][j]);
    let c = Mat::from_fn(3, 4, |i, j| {
        [[1.0, 0.2, 0.5, -0.3], [0.1, 0.8, -0.4, 0.6], [0.7, -0.5, 0.3, 0.2]][i][j]
    });
    let d = Mat::from_fn(3, 2, |i, j| [[0.05, 0.0], [0.0, -0.02], [0.01, 0.03]][i][j]);
    Realization::new(a, b, c, d, fs).unwrap()
}

/// Given the true `(A, C)`, the least squares recovers the input–output
/// map of a noise-free record: the fitted realization reproduces the
/// true one's response to other inputs (an input–output invariant: `B`
/// and `D` themselves depend on the basis) to 1e-8 of its rms.
#[test]
fn the_least_squares_recovers_the_input_map_of_a_noise_free_record() {
    let system = truth();
    let fitting: Vec<Vec<f64>> = (0..2).map(|k| noise(k + 1, 3000)).collect();
    let views: Vec<&[f64]> = fitting.iter().map(Vec::as_slice).collect();
    let outputs = system.simulate(&views).unwrap();
    let out_views: Vec<&[f64]> = outputs.iter().map(Vec::as_slice).collect();
    let fitted = Realization::fit(system.a(), system.c(), &views, &out_views, system.fs()).unwrap();
    let other: Vec<Vec<f64>> = (0..2).map(|k| noise(k + 7, 2000)).collect();
    let other_views: Vec<&[f64]> = other.iter().map(Vec::as_slice).collect();
    let (expected, got) = (
        system.simulate(&other_views).unwrap(),
        fitted.simulate(&other_views).unwrap(),
    );
    for (e, g) in expected.iter().zip(&got) {
        let rms = (e.iter().map(|v| v * v).sum::<f64>() / e.len() as f64).sqrt();
        let error = e.iter().zip(g).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        assert!(error <= 1e-8 * rms, "{error} of rms {rms}");
    }
    assert!(fitted.spectral_radius().unwrap() < 1.0);
}

/// The least squares with `D` eliminated is the whole least squares: on a
/// noisy record (5 % noise, one output sample missing) `B` and `D` equal
/// those of the dense least squares over every column (`x₀`, `B`, `D`) to
/// 1e-9 of their largest.
#[test]
fn eliminating_the_direct_terms_gives_the_whole_least_squares() {
    let system = truth();
    let inputs: Vec<Vec<f64>> = (0..2).map(|k| noise(k + 3, 600)).collect();
    let views: Vec<&[f64]> = inputs.iter().map(Vec::as_slice).collect();
    let mut outputs = system.simulate(&views).unwrap();
    for (o, output) in outputs.iter_mut().enumerate() {
        for (v, e) in output.iter_mut().zip(noise(o as u64 + 11, 600)) {
            *v += 0.05 * e;
        }
    }
    outputs[1][123] = f64::NAN;
    let out_views: Vec<&[f64]> = outputs.iter().map(Vec::as_slice).collect();
    let modal = ModalForm::of(system.a(), system.c()).unwrap();
    let (b, d) = modal.fit_inputs(&views, &out_views).unwrap();

    let (n, r, m) = (4, 2, 3);
    let shared = n + n * r;
    let mut rows: Vec<Vec<f64>> = Vec::new();
    let mut targets = Vec::new();
    modal
        .for_each_row(&views, &out_views, |o, k, row, y| {
            let mut full = row.to_vec();
            full.extend((0..r * m).map(|c| if c % m == o { views[c / m][k] } else { 0.0 }));
            rows.push(full);
            targets.push(y);
            Ok(())
        })
        .unwrap();
    let phi = Mat::from_fn(rows.len(), shared + m * r, |i, j| rows[i][j]);
    let y = Mat::from_fn(rows.len(), 1, |i, _| targets[i]);
    let theta = phi.qr().solve_lstsq(&y);
    let scale = b.norm_max().max(d.norm_max());
    for s in 0..n {
        for i in 0..r {
            assert!((b[(s, i)] - theta[(n + i * n + s, 0)]).abs() <= 1e-9 * scale);
        }
    }
    for p in 0..m {
        for i in 0..r {
            assert!(
                (d[(p, i)] - theta[(shared + i * m + p, 0)]).abs() <= 1e-9 * scale,
                "D {p} {i}"
            );
        }
    }
}

/// A pole outside the unit circle is reflected to `1/μ̄`: the same
/// angle (frequency), radius `1/|μ|`; one inside is kept.
#[test]
fn poles_outside_the_unit_circle_are_reflected_inside() {
    let unstable = ModalBlock::Pair {
        sigma: 1.02 * 0.6,
        omega: 1.02 * 0.8,
    }
    .stable();
    let ModalBlock::Pair { sigma, omega } = unstable else {
        panic!("a pair stays a pair")
    };
    assert!((sigma.hypot(omega) - 1.0 / 1.02).abs() < 1e-14);
    assert!((omega.atan2(sigma) - 0.8f64.atan2(0.6)).abs() < 1e-14);
    assert_eq!(ModalBlock::Real(-1.25).stable(), ModalBlock::Real(-0.8));
    assert_eq!(ModalBlock::Real(0.5).stable(), ModalBlock::Real(0.5));
    let ModalBlock::Real(on) = ModalBlock::Real(1.0).stable() else {
        panic!("a real pole stays real")
    };
    assert!((on - (1.0 - MARGIN)).abs() < 1e-15);
}

/// The modal form of a stable state matrix has its eigenvalues (to
/// round-off of the 4 × 4 eigenproblem).
#[test]
fn the_modal_form_keeps_the_poles() {
    let system = truth();
    let modal = ModalForm::of(system.a(), system.c()).unwrap();
    let moduli = |a: MatRef<'_, f64>| -> Vec<f64> {
        let mut moduli: Vec<f64> = a
            .eigen()
            .unwrap()
            .S()
            .column_vector()
            .iter()
            .map(|z| z.norm())
            .collect();
        moduli.sort_by(f64::total_cmp);
        moduli
    };
    let (expected, got) = (moduli(system.a()), moduli(modal.a().as_ref()));
    for (e, g) in expected.iter().zip(&got) {
        assert!((e - g).abs() < 1e-12, "{e} {g}");
    }
}

/// Inputs at twice the realization's rate (a Hann-windowed band-limited
/// burst, then rest): every second output sample equals the
/// realization's response to the same inputs at its own rate, to 1e-6
/// of the outputs' rms (what the band-limited resampling leaves of the
/// response's content near the Nyquist line).
#[test]
fn inputs_at_another_rate_are_resampled_to_the_realizations() {
    let system = truth();
    let burst = |fs: f64, phase: f64| -> Vec<f64> {
        let (on, total) = ((8.0 * fs) as usize, (20.0 * fs) as usize);
        (0..total)
            .map(|k| {
                if k >= on {
                    return 0.0;
                }
                let t = k as f64 / fs;
                let window = (std::f64::consts::PI * k as f64 / on as f64).sin().powi(2);
                window
                    * ((2.0 * std::f64::consts::PI * 1.3 * t + phase).sin()
                        + 0.4 * (2.0 * std::f64::consts::PI * 4.1 * t).cos())
            })
            .collect()
    };
    let (slow, fast): (Vec<Vec<f64>>, Vec<Vec<f64>>) =
        (0..2).map(|i| (burst(50.0, i as f64), burst(100.0, i as f64))).unzip();
    let slow_views: Vec<&[f64]> = slow.iter().map(Vec::as_slice).collect();
    let fast_views: Vec<&[f64]> = fast.iter().map(Vec::as_slice).collect();
    let expected = system.simulate(&slow_views).unwrap();
    let got = system.simulate_at(&fast_views, 100.0).unwrap();
    for (e, g) in expected.iter().zip(&got) {
        assert_eq!(g.len(), 2 * e.len());
        let rms = (e.iter().map(|v| v * v).sum::<f64>() / e.len() as f64).sqrt();
        let error = e
            .iter()
            .zip(g.iter().step_by(2))
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(error <= 1e-6 * rms, "{error:e} of rms {rms}");
    }
    assert_eq!(
        system.simulate_at(&fast_views, -1.0),
        Err(RealizationError::BadRate(-1.0))
    );
}

#[test]
fn bad_matrices_and_inputs_are_refused_by_name() {
    let system = truth();
    let b = system.b().to_owned();
    let wrong = Realization::new(
        system.a().to_owned(),
        b.clone(),
        system.c().to_owned(),
        Mat::zeros(3, 3),
        50.0,
    );
    assert!(matches!(wrong, Err(RealizationError::Dimensions(_))));
    let mut nan = b.clone();
    nan[(0, 0)] = f64::NAN;
    let wrong = Realization::new(
        system.a().to_owned(),
        nan,
        system.c().to_owned(),
        system.d().to_owned(),
        50.0,
    );
    assert_eq!(wrong, Err(RealizationError::NonFinite("B")));
    let wrong = Realization::new(
        system.a().to_owned(),
        b,
        system.c().to_owned(),
        system.d().to_owned(),
        0.0,
    );
    assert_eq!(wrong, Err(RealizationError::BadRate(0.0)));
    let mut gap = noise(1, 100);
    gap[10] = f64::NAN;
    let ok = noise(2, 100);
    assert_eq!(system.simulate(&[&gap, &ok]), Err(RealizationError::MissingInput(0)));
    assert!(matches!(system.simulate(&[&ok]), Err(RealizationError::Dimensions(_))));
    let short = system.simulate(&[&ok[..5], &ok[..5]]).unwrap();
    let views: Vec<&[f64]> = short.iter().map(Vec::as_slice).collect();
    let fitted = Realization::fit(system.a(), system.c(), &[&ok[..5], &ok[..5]], &views, 50.0);
    assert!(matches!(fitted, Err(RealizationError::TooShort { .. })));
}
