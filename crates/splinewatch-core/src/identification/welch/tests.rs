use super::*;

fn settings(n: usize, overlap: usize, window: Window) -> WelchSettings {
    WelchSettings {
        fs: 100.0,
        segment: n,
        overlap,
        input_window: window,
        output_window: window,
        detrend: Detrend::Constant,
        averaging: Averaging::Linear,
        gates: Gates::default(),
    }
}

#[test]
fn hann_matches_closed_form_and_scipy_periodicity() {
    let w = Window::Hann.samples(8);
    let expected = [
        0.0,
        0.1464466094067262,
        0.5,
        0.8535533905932737,
        1.0,
        0.8535533905932737,
        0.5,
        0.1464466094067262,
    ];
    for (a, b) in w.iter().zip(expected) {
        assert!((a - b).abs() < 1e-15);
    }
}

#[test]
fn streaming_in_odd_chunks_equals_one_push() {
    let x: Vec<f64> = (0..1000)
        .map(|k| (k as f64 * 0.37).sin() + 0.1 * (k as f64 * 1.3).cos())
        .collect();
    let y: Vec<f64> = (0..1000).map(|k| (k as f64 * 0.37 + 0.4).sin()).collect();
    let mut one = WelchEstimator::new(settings(64, 32, Window::Hann), 1).unwrap();
    one.push(&x, &[&y]).unwrap();
    let mut many = WelchEstimator::new(settings(64, 32, Window::Hann), 1).unwrap();
    let mut k = 0;
    for len in [1, 7, 63, 64, 65, 100, 3].iter().cycle() {
        if k >= x.len() {
            break;
        }
        let end = (k + len).min(x.len());
        many.push(&x[k..end], &[&y[k..end]]).unwrap();
        k = end;
    }
    assert_eq!(one.counts().accepted, ((1000 - 32) / 32) as u64);
    assert_eq!(one.spectra(), many.spectra());
    assert!(many.pending_samples() < 64);
}

/// The streaming estimator (channel sums eight at a time, channel-major
/// averaging) gives exactly the bits of the textbook loop: per segment,
/// per channel `mean = Σx / n` (`Iterator::sum`), window, FFT; then per
/// bin the running averages. Ten channels, so one group of eight lanes
/// and one of two.
#[test]
fn streaming_estimator_is_bit_identical_to_the_plain_loop() {
    let (n, overlap, outputs) = (64, 24, 9);
    let len = 1000;
    let channel = |c: usize| -> Vec<f64> {
        (0..len)
            .map(|k| ((k * (c + 3)) as f64 * 0.173).sin() * (1.0 + c as f64) + 0.3 * c as f64)
            .collect()
    };
    let input = channel(0);
    let outs: Vec<Vec<f64>> = (1..=outputs).map(channel).collect();
    let mut s = settings(n, overlap, Window::Hann);
    s.output_window = Window::Hamming;
    let mut est = WelchEstimator::new(s.clone(), outputs).unwrap();
    let refs: Vec<&[f64]> = outs.iter().map(Vec::as_slice).collect();
    est.push(&input, &refs).unwrap();

    let fft = RealFftPlanner::<f64>::new().plan_fft_forward(n);
    let (w_in, w_out) = (s.input_window.samples(n), s.output_window.samples(n));
    let sum_sq = |w: &[f64]| w.iter().map(|v| v * v).sum::<f64>();
    let scale = 1.0 / (s.fs * (sum_sq(&w_in) * sum_sq(&w_out)).sqrt());
    let bins = n / 2 + 1;
    let mut s_ff = vec![0.0; bins];
    let mut s_fx = vec![vec![c64::new(0.0, 0.0); bins]; outputs];
    let mut s_xx = vec![vec![0.0; bins]; outputs];
    let mut count = 0.0;
    let mut start = 0;
    while start + n <= len {
        let spectrum = |x: &[f64], w: &[f64]| {
            let seg = &x[start..start + n];
            let mean = seg.iter().sum::<f64>() / n as f64;
            let mut buf: Vec<f64> = (0..n).map(|k| (seg[k] - mean) * w[k]).collect();
            let mut out = fft.make_output_vec();
            fft.process(&mut buf, &mut out).unwrap();
            out
        };
        let f = spectrum(&input, &w_in);
        let xs: Vec<Vec<c64>> = outs.iter().map(|x| spectrum(x, &w_out)).collect();
        count += 1.0;
        let w = 1.0 / count;
        for k in 0..bins {
            let s = scale * if k == 0 || k == bins - 1 { 1.0 } else { 2.0 };
            s_ff[k] += (f[k].norm_sqr() * s - s_ff[k]) * w;
            for o in 0..outputs {
                let pfx = f[k].conj() * xs[o][k] * s;
                s_fx[o][k] = s_fx[o][k] + (pfx - s_fx[o][k]) * w;
                s_xx[o][k] += (xs[o][k].norm_sqr() * s - s_xx[o][k]) * w;
            }
        }
        start += n - overlap;
    }
    let spectra = est.spectra();
    assert_eq!(est.counts().accepted, count as u64);
    assert_eq!(spectra.s_ff, s_ff);
    assert_eq!(spectra.s_fx, s_fx);
    assert_eq!(spectra.s_xx, s_xx);
}

#[test]
fn noiseless_siso_estimators_recover_the_system() {
    // x = 2 f delayed by 3 samples: H = 2 e^{-jω 3/fs} exactly for a
    // circular shift; with a rectangular window and non-overlapping
    // segments of a periodic input, H1 = H2 = Hv = H to round-off.
    let n = 128;
    let f: Vec<f64> = (0..n * 8).map(|k| ((k * 7919) % 97) as f64 / 97.0 - 0.5).collect();
    // Periodic input with period n, so each segment is a circular shift.
    let f: Vec<f64> = (0..n * 8).map(|k| f[k % n]).collect();
    let x: Vec<f64> = (0..n * 8).map(|k| 2.0 * f[(k + n - 3) % n]).collect();
    let mut s = settings(n, 0, Window::Rectangular);
    s.detrend = Detrend::None;
    let mut est = WelchEstimator::new(s.clone(), 1).unwrap();
    est.push(&f, &[&x]).unwrap();
    let spectra = est.spectra();
    for estimator in [Estimator::H1, Estimator::H2, Estimator::Hv] {
        let frf = spectra.frf(estimator);
        for (k, h) in frf.h[0].iter().enumerate() {
            if spectra.s_ff[k] < 1e-12 {
                continue;
            }
            let w = 2.0 * PI * k as f64 / n as f64;
            let exact = c64::new(2.0 * (3.0 * w).cos(), -2.0 * (3.0 * w).sin());
            assert!((h - exact).norm() < 1e-9, "{estimator:?} bin {k}: {h} vs {exact}");
            assert!((frf.coherence[0][k] - 1.0).abs() < 1e-9);
        }
    }
}

#[test]
fn h2_and_hv_reject_output_noise_differently() {
    // Output noise biases H2 upward in magnitude, leaves H1 unbiased;
    // Hv lies between them.
    let n = 64;
    let mut seed = 7u64;
    let mut rnd = || {
        seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((seed >> 11) as f64) / ((1u64 << 53) as f64) - 0.5
    };
    let f: Vec<f64> = (0..n * 400).map(|_| rnd()).collect();
    let x: Vec<f64> = f.iter().map(|v| 3.0 * v + 1.5 * rnd()).collect();
    let mut est = WelchEstimator::new(settings(n, 32, Window::Hann), 1).unwrap();
    est.push(&f, &[&x]).unwrap();
    let sp = est.spectra();
    let mean = |e: Estimator| {
        let h = &sp.frf(e).h[0];
        h[1..n / 2].iter().map(|v| v.norm()).sum::<f64>() / (n / 2 - 1) as f64
    };
    let (h1, h2, hv) = (mean(Estimator::H1), mean(Estimator::H2), mean(Estimator::Hv));
    assert!((h1 - 3.0).abs() < 0.05, "H1 {h1}");
    // E|H2| = 3 (1 + σ²/(9 σf²)) = 3 · 1.25 for σ = 1.5 σf.
    assert!((h2 - 3.75).abs() < 0.1, "H2 {h2}");
    assert!(hv > h1 && hv < h2, "Hv {hv}");
}

#[test]
fn exponential_averaging_effective_count() {
    let alpha = 0.1;
    let mut s = settings(32, 0, Window::Hann);
    s.averaging = Averaging::Exponential { alpha };
    let mut est = WelchEstimator::new(s, 1).unwrap();
    let x: Vec<f64> = (0..32 * 500).map(|k| (k as f64 * 0.7).sin()).collect();
    est.push(&x, &[&x]).unwrap();
    let n_eff = est.spectra().effective_averages;
    assert!((n_eff - (2.0 - alpha) / alpha).abs() < 1e-9, "{n_eff}");
    let mut short = WelchEstimator::new(settings(32, 0, Window::Hann), 1).unwrap();
    short.push(&x[..32 * 3], &[&x[..32 * 3]]).unwrap();
    assert_eq!(short.spectra().effective_averages, 3.0);
}

#[test]
fn gates_reject_bad_segments_and_count_them() {
    let mut s = settings(16, 0, Window::Hann);
    s.gates.full_scale = Some(10.0);
    s.gates.double_impact_fraction = Some(0.5);
    let mut est = WelchEstimator::new(s, 1).unwrap();
    let mut f = vec![0.0; 16 * 4];
    f[0] = 1.0; // segment 0: single impact
    f[16] = 1.0; // segment 1: double impact
    f[24] = 0.8;
    f[32] = f64::NAN; // segment 2: non-finite
    f[48] = 12.0; // segment 3: clipped
    est.push(&f, &[&f.clone()]).unwrap();
    let c = est.counts();
    assert_eq!((c.accepted, c.double_impact, c.non_finite, c.clipped), (1, 1, 1, 1));
    assert_eq!(c.rejected(), 3);
}

#[test]
fn invalid_settings_are_typed_errors() {
    let mut s = settings(16, 16, Window::Hann);
    assert!(matches!(
        WelchEstimator::new(s.clone(), 1),
        Err(WelchError::Overlap { .. })
    ));
    s.overlap = 0;
    s.fs = 0.0;
    assert_eq!(
        WelchEstimator::new(s.clone(), 1).unwrap_err(),
        WelchError::SampleRate(0.0)
    );
    s.fs = 10.0;
    s.averaging = Averaging::Exponential { alpha: 0.0 };
    assert_eq!(WelchEstimator::new(s, 1).unwrap_err(), WelchError::Alpha(0.0));
    let mut est = WelchEstimator::new(settings(16, 0, Window::Hann), 2).unwrap();
    assert!(matches!(
        est.push(&[0.0; 4], &[&[0.0; 4]]),
        Err(WelchError::ChannelCount { .. })
    ));
    assert!(matches!(
        est.push(&[0.0; 4], &[&[0.0; 4], &[0.0; 3]]),
        Err(WelchError::ChannelLength { .. })
    ));
}
