//! Resampling a record to another number of points over the same span: the
//! discrete Fourier series truncated or zero-padded (band-limited, as
//! `scipy.signal.resample`). Exact for a signal band-limited below both
//! Nyquist lines and periodic over the span; a transient record gains edge
//! ripple only where it does not start and end near rest.

/// `x` (one span) resampled to `n` points over the same span: the discrete
/// Fourier series truncated or zero-padded (the Nyquist line of an even
/// length halved), as `scipy.signal.resample`.
pub fn fourier_resample(x: &[f64], n: usize) -> Vec<f64> {
    let m = x.len();
    if m == 0 || n == 0 {
        return vec![0.0; n];
    }
    let mut planner = realfft::RealFftPlanner::<f64>::new();
    let forward = planner.plan_fft_forward(m);
    let mut input = x.to_vec();
    let mut spectrum = forward.make_output_vec();
    forward
        .process(&mut input, &mut spectrum)
        .expect("lengths from the plan");
    let inverse = planner.plan_fft_inverse(n);
    let mut target = inverse.make_input_vec();
    let keep = target.len().min(spectrum.len());
    target[..keep].copy_from_slice(&spectrum[..keep]);
    // A Nyquist line present in only one of the two lengths is split or summed
    // so that the real signal stays real (its imaginary part is dropped).
    if m % 2 == 0 && keep == spectrum.len() && n > m {
        target[m / 2] *= 0.5;
    }
    if n % 2 == 0 && keep == target.len() {
        let nyquist = target.len() - 1;
        target[nyquist].im = 0.0;
        if n < m {
            target[nyquist] *= 2.0;
        }
    }
    target[0].im = 0.0;
    let mut out = inverse.make_output_vec();
    inverse.process(&mut target, &mut out).expect("lengths from the plan");
    let scale = 1.0 / m as f64;
    out.iter().map(|v| v * scale).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fourier_resampling_keeps_a_band_limited_periodic_signal() {
        // A sum of harmonics below both Nyquist lines of a periodic span.
        let signal = |n: usize| -> Vec<f64> {
            (0..n)
                .map(|i| {
                    let t = i as f64 / n as f64;
                    (2.0 * std::f64::consts::PI * 3.0 * t).sin() + 0.5 * (2.0 * std::f64::consts::PI * 7.0 * t).cos()
                })
                .collect()
        };
        for (from, to) in [(64, 40), (40, 64), (63, 41), (41, 63), (50, 50)] {
            let got = fourier_resample(&signal(from), to);
            let want = signal(to);
            let err = got.iter().zip(&want).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
            assert!(err < 1e-12, "{from} -> {to}: {err:.2e}");
        }
    }
}
