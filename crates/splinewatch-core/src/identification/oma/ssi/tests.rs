use super::*;

/// Exact correlations of a two-mode system: `R_k = C Aᵏ G` with known
/// poles, so SSI must return them to round-off.
#[test]
fn exact_correlations_give_the_exact_poles() {
    let fs = 100.0;
    let modes = [(3.0, 0.02), (11.0, 0.05)];
    let shapes = [[1.0, 0.5, -0.3], [0.2, -1.0, 0.7]];
    let (l, max_lag) = (3, 21);
    let mut r = vec![0.0; (max_lag + 1) * l * l];
    for ((f, zeta), shape) in modes.iter().zip(&shapes) {
        let omega = 2.0 * PI * f;
        let lambda = c64::new(-zeta * omega, omega * (1.0f64 - zeta * zeta).sqrt());
        for k in 0..=max_lag {
            // R_k = Re(φ e^{λ k Δt} gᵀ), g = φ (a symmetric, real-mode model).
            let decay = (lambda * (k as f64 / fs)).exp();
            for a in 0..l {
                for b in 0..l {
                    r[(k * l + a) * l + b] += (decay * c64::new(shape[a] * shape[b], 0.0)).re;
                }
            }
        }
    }
    let model = SubspaceModel::new(&r, l, l, 10, usize::MAX, fs).unwrap();
    let poles = model.poles(4).unwrap();
    assert_eq!(poles.len(), 2);
    for (pole, ((f, zeta), shape)) in poles.iter().zip(modes.iter().zip(&shapes)) {
        assert!((pole.frequency_hz - f).abs() < 1e-9 * f, "{pole:?}");
        assert!((pole.damping_ratio - zeta).abs() < 1e-9, "{pole:?}");
        let real: Vec<f64> = shape.to_vec();
        assert!((super::super::shape::mac_real(&pole.shape, &real) - 1.0).abs() < 1e-9);
        assert!((pole.mpc - 1.0).abs() < 1e-9);
    }
    assert!(model.singular_values()[4] < 1e-10 * model.singular_values()[0]);
    assert!(matches!(model.poles(6), Err(OmaError::SingularHankel { order: 6 })));
    assert!(matches!(model.poles(31), Err(OmaError::OrderTooHigh { .. })));
}

/// `n` samples at `fs` of two damped oscillators (2.3 and 7.1 Hz,
/// explicit integration) driven by noise, seen by `l` channels with
/// 1 % noise (the first three with fixed shapes, more on a phase).
fn two_oscillators(seed: u64, n: usize, l: usize, fs: f64) -> Vec<Vec<f64>> {
    let mut seed = seed;
    let mut noise = move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        seed as f64 / u64::MAX as f64 - 0.5
    };
    let (mut x1, mut v1, mut x2, mut v2) = (0.0, 0.0, 0.0, 0.0);
    let dt = 1.0 / fs;
    let (w1, w2) = (2.0 * PI * 2.3, 2.0 * PI * 7.1);
    let mut y = vec![vec![0.0; n]; l];
    for t in 0..n {
        let (f1, f2) = (noise(), noise());
        v1 += dt * (-w1 * w1 * x1 - 2.0 * 0.02 * w1 * v1 + 40.0 * f1);
        x1 += dt * v1;
        v2 += dt * (-w2 * w2 * x2 - 2.0 * 0.03 * w2 * v2 + 40.0 * f2);
        x2 += dt * v2;
        for (a, channel) in y.iter_mut().enumerate() {
            let phase = a as f64 * 0.7;
            let shape = [[1.0, 0.4], [0.6, -1.0], [-0.3, 0.8]]
                .get(a)
                .copied()
                .unwrap_or([phase.cos(), (1.3 * phase).sin()]);
            channel[t] = shape[0] * x1 + shape[1] * x2 + 0.01 * noise();
        }
    }
    y
}

/// A replicate on the model's own correlations is the model; on a
/// slightly different record's (a tenth of it left out), the physical
/// poles move as with that record's own SVD: within 2 % of the change
/// at order 4 (the signal's rank), frequencies within 20 % at order 8,
/// where four noise directions join the subspace and the rotation of
/// the right singular vectors into them (weighed by their `σ`) is left
/// out (measured: 11 % of the change of the 2.3 Hz pole there). The
/// first-order continuation matches the replicate's own eigenvalues.
#[test]
fn a_replicate_projects_on_the_right_singular_vectors() {
    let (l, p, fs) = (3, 12, 50.0);
    let record = |seed: u64, n: usize| two_oscillators(seed, n, l, fs);
    let correlations = |y: &[Vec<f64>]| {
        let views: Vec<&[f64]> = y.iter().map(Vec::as_slice).collect();
        super::super::OutputCorrelations::from_samples(&views, &[], 2 * p, 1)
            .unwrap()
            .estimate()
    };
    let full = record(7, 20000);
    let r = correlations(&full);
    let model = SubspaceModel::new(&r, l, l, p, 20, fs).unwrap();
    let same = model.replicate(&r, l, p).unwrap();
    // The record without its last tenth: a replicate-sized change.
    let r_b = correlations(&full.iter().map(|c| c[..18000].to_vec()).collect::<Vec<_>>());
    let own = SubspaceModel::new(&r_b, l, l, p, 20, fs).unwrap();
    let projected = model.replicate(&r_b, l, p).unwrap();
    for (order, share) in [(4, 0.02), (8, 0.2)] {
        let (a, b) = (model.poles(order).unwrap(), same.poles(order).unwrap());
        for (a, b) in a.iter().zip(&b) {
            assert!((a.frequency_hz - b.frequency_hz).abs() < 1e-10 * a.frequency_hz);
            assert!((a.damping_ratio - b.damping_ratio).abs() < 1e-10);
        }
        // The two physical poles (beyond order 4 the rest is noise,
        // which no first-order argument holds for).
        let (exact, approx) = (own.poles(order).unwrap(), projected.poles(order).unwrap());
        let nearest = |poles: &[Pole], f: f64| {
            poles
                .iter()
                .min_by(|x, y| (x.frequency_hz - f).abs().total_cmp(&(y.frequency_hz - f).abs()))
                .cloned()
                .unwrap()
        };
        // (The explicit integration moves the oscillators to ~2.3 and
        // ~7.5 Hz; order 4 holds just the two.)
        let physical: Vec<f64> = model.poles(4).unwrap().iter().map(|p| p.frequency_hz).collect();
        assert_eq!(physical.len(), 2);
        for f in physical {
            let (o, e, x) = (nearest(&a, f), nearest(&exact, f), nearest(&approx, f));
            assert!((o.frequency_hz - f).abs() < 0.01 * f, "{o:?}");
            let change = (e.frequency_hz - o.frequency_hz).abs();
            assert!(
                (x.frequency_hz - e.frequency_hz).abs() < share * change + 1e-7 * f,
                "{o:?} {e:?} {x:?}"
            );
            // Damping: at order 4 as close; at order 8 this toy's
            // damping change is carried by the noise directions' rotation
            // (exact +1.8e-5, projected −2e-6 for the 2.3 Hz pole), so
            // only the frequency is held there. On the deck, where the
            // modes dominate the subspace, the damping std of both
            // methods matches the scatter over 100 records
            // (tests/verification/oma.rs).
            if order == 4 {
                let change = (e.damping_ratio - o.damping_ratio).abs();
                assert!(
                    (x.damping_ratio - e.damping_ratio).abs() < 0.05 * change + 1e-7,
                    "{o:?} {e:?} {x:?}"
                );
            }
            // The first-order continuation of the model's eigenpair on
            // the projected replicate: the replicate's own eigenvalue
            // to second order (within 1 % of the change at order 4; at
            // order 8, where noise poles come close, measured 2.3090 Hz
            // against 2.3075 from 2.3052: this tenth of the record is a
            // larger change than a replicate's sixteenth, and the
            // verification holds the stds, not single poles).
            if order != 4 {
                continue;
            }
            let eigen = model.eigen(order).unwrap();
            let j = model.eigen_index(&eigen, &o).unwrap();
            let base = model.continuation(eigen).unwrap();
            let continued = projected.continued(&base, &[j], &[j]).unwrap();
            let c = &continued[1];
            assert_eq!(continued[0].frequency_hz, c.frequency_hz);
            let change = (x.frequency_hz - o.frequency_hz).abs();
            assert!(
                (c.frequency_hz - x.frequency_hz).abs() < 0.01 * change + 1e-9 * f,
                "{c:?} {x:?}"
            );
            let change = (x.damping_ratio - o.damping_ratio).abs();
            assert!(
                (c.damping_ratio - x.damping_ratio).abs() < 0.01 * change + 1e-9,
                "{c:?} {x:?}"
            );
            assert!((super::super::shape::mac(c.shape.as_ref().unwrap(), &x.shape) - 1.0).abs() < 1e-6);
        }
    }
}

/// The truncated SVD of a noisy Hankel matrix (two oscillators seen by
/// six channels, 1 % noise, 12 block rows: 78 × 72, rank 4 plus noise)
/// against faer's full SVD: the `cap` leading singular values (`‖H v_i‖`)
/// within `1e-12 σ₁`, those beyond (`√λ_i` of `HᵀH`, reported only)
/// within `10 ε σ₁²/σ_i`, their documented accuracy; each leading right
/// vector the SVD's up to sign, within the angle `100 ε σ₁²/gap` (`gap`
/// to the neighbouring eigenvalues of `HᵀH`; checked where that is below
/// 0.01 rad), and `‖H v_i‖ = σ_i`.
#[test]
fn leading_vectors_are_the_full_svds() {
    let (l, p) = (6, 12);
    let y = two_oscillators(11, 20000, l, 50.0);
    let views: Vec<&[f64]> = y.iter().map(Vec::as_slice).collect();
    let r = super::super::OutputCorrelations::from_samples(&views, &[], 2 * p, 1)
        .unwrap()
        .estimate();
    let hankel = block_hankel(&r, l, l, p).unwrap();
    let cap = 30;
    let (values, truncated) = truncated_svd(&hankel, cap).unwrap();
    let svd = hankel.thin_svd().unwrap();
    let sigma_1 = svd.S()[0];
    for (i, got) in values.iter().enumerate() {
        let want = svd.S()[i];
        let bound = if i < cap {
            1e-12 * sigma_1
        } else {
            10.0 * f64::EPSILON * sigma_1 * sigma_1 / want
        };
        assert!((got - want).abs() < bound, "σ_{i}: {got} vs {want}");
    }
    let mut compared = 0;
    let lambda = |i: usize| svd.S()[i] * svd.S()[i];
    for i in 0..cap {
        // `HᵀH`'s eigenvalue gap, and the angle it allows: `ε σ₁²/gap`
        // (with a factor 100 for the tridiagonalisation's growth).
        let gap = (lambda(i) - lambda(i + 1)).min(if i > 0 { lambda(i - 1) - lambda(i) } else { f64::MAX });
        let allowed = 100.0 * f64::EPSILON * sigma_1 * sigma_1 / gap;
        if allowed > 1e-2 {
            continue;
        }
        // The angle as `‖v − ±v_svd‖` (1 − cos² loses it below √ε).
        let cos: f64 = (0..hankel.ncols())
            .map(|k| svd.V()[(k, i)] * truncated.right[(k, i)])
            .sum();
        let angle = (0..hankel.ncols())
            .map(|k| (truncated.right[(k, i)] - cos.signum() * svd.V()[(k, i)]).powi(2))
            .sum::<f64>()
            .sqrt();
        assert!(angle <= allowed, "v_{i}: angle {angle:e}, allowed {allowed:e}");
        compared += 1;
        // H v_i = σ_i u_i.
        let norm = truncated.left.col(i).norm_l2();
        assert!((norm - values[i]).abs() < 1e-12 * sigma_1);
    }
    assert!(compared >= 4, "only {compared} vectors apart from their neighbours");
}

#[test]
fn too_few_lags_and_zero_data_are_errors() {
    assert!(matches!(
        SubspaceModel::new(&[0.0; 9], 1, 1, 5, usize::MAX, 10.0),
        Err(OmaError::TooFewLags { block_rows: 5 })
    ));
    assert!(matches!(
        SubspaceModel::new(&[0.0; 11], 1, 1, 5, usize::MAX, 10.0),
        Err(OmaError::SingularHankel { order: 1 })
    ));
}
