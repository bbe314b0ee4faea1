//! Singular values of the output spectral matrix `G_yy(f)` (`l × l`,
//! Hermitian, positive semi-definite): the backdrop of a stabilisation
//! diagram, where a peak of the first singular value marks a mode (the
//! frequency-domain decomposition view of Brincker, Zhang & Andersen 2001).
//!
//! `G_yy` is Welch's one-sided density estimate, as `scipy.signal.csd`
//! with `scaling="density"`: periodic Hann segments, 50 % overlap, mean
//! removed per segment, `G = 2 X X^H / (fs Σw²)` (not doubled at DC and
//! Nyquist), averaged over the segments. A segment holding a missing sample
//! (NaN) is left out. For a Hermitian positive semi-definite matrix the
//! singular values are its eigenvalues.

use super::OmaError;
use crate::identification::welch::Window;
use faer::{c64, Mat, Side};
use realfft::RealFftPlanner;

/// The singular values of `G_yy` per frequency line, largest first.
#[derive(Debug, Clone, PartialEq)]
pub struct SpectralSingularValues {
    pub frequencies_hz: Vec<f64>,
    /// Per line, the `l` singular values, non-increasing.
    pub values: Vec<Vec<f64>>,
    /// Segments averaged.
    pub segments: usize,
}

impl SpectralSingularValues {
    /// The first singular value at every line.
    pub fn first(&self) -> Vec<f64> {
        self.values.iter().map(|v| v.first().copied().unwrap_or(0.0)).collect()
    }
}

/// `G_yy(f)` of `channels` (equal lengths, sampled at `fs`) from
/// `segment`-sample segments, and its singular values per line.
pub fn spectral_singular_values(
    channels: &[&[f64]],
    fs: f64,
    segment: usize,
) -> Result<SpectralSingularValues, OmaError> {
    let n = super::channel_length(channels)?;
    let l = channels.len();
    if segment < 2 || n < segment {
        return Err(OmaError::TooShort {
            samples: n,
            needed: segment.max(2),
        });
    }
    let window = Window::Hann.samples(segment);
    let scale = 1.0 / (fs * window.iter().map(|w| w * w).sum::<f64>());
    let fft = RealFftPlanner::<f64>::new().plan_fft_forward(segment);
    let lines = segment / 2 + 1;
    // Σ over segments of X_a X_b^*, line-major, then row-major (a, b).
    let mut sums = vec![c64::new(0.0, 0.0); lines * l * l];
    let mut segments = 0;
    let mut buffer = fft.make_input_vec();
    let mut spectra = vec![fft.make_output_vec(); l];
    let step = segment / 2;
    for start in (0..=n - segment).step_by(step.max(1)) {
        if channels
            .iter()
            .any(|c| c[start..start + segment].iter().any(|v| !v.is_finite()))
        {
            continue;
        }
        for (c, spectrum) in channels.iter().zip(&mut spectra) {
            let piece = &c[start..start + segment];
            let mean = piece.iter().sum::<f64>() / segment as f64;
            for ((b, v), w) in buffer.iter_mut().zip(piece).zip(&window) {
                *b = (v - mean) * w;
            }
            fft.process(&mut buffer, spectrum).expect("sized by the plan");
        }
        for k in 0..lines {
            for a in 0..l {
                for b in 0..l {
                    sums[(k * l + a) * l + b] += spectra[a][k] * spectra[b][k].conj();
                }
            }
        }
        segments += 1;
    }
    if segments == 0 {
        return Err(OmaError::TooShort {
            samples: 0,
            needed: segment,
        });
    }
    let mut values = Vec::with_capacity(lines);
    for k in 0..lines {
        let one_sided = if k == 0 || (segment % 2 == 0 && k == lines - 1) {
            1.0
        } else {
            2.0
        };
        let factor = one_sided * scale / segments as f64;
        let g = Mat::<c64>::from_fn(l, l, |a, b| sums[(k * l + a) * l + b] * factor);
        let mut eigen = g
            .self_adjoint_eigenvalues(Side::Lower)
            .map_err(|_| OmaError::EigenFailed { order: 0 })?;
        // Non-increasing, and never below zero (round-off of a PSD matrix).
        eigen.reverse();
        values.push(eigen.into_iter().map(|v| v.max(0.0)).collect());
    }
    Ok(SpectralSingularValues {
        frequencies_hz: (0..lines).map(|k| k as f64 * fs / segment as f64).collect(),
        values,
        segments,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn noise(n: usize, seed: u64) -> Vec<f64> {
        let mut s = seed;
        (0..n)
            .map(|_| {
                s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            })
            .collect()
    }

    #[test]
    fn a_fully_coherent_pair_has_rank_one_and_the_trace_is_the_autospectra() {
        // y2 = 2 y1: G = [[1, 2], [2, 4]] G11, singular values 5 G11 and 0.
        let y1 = noise(8192, 1);
        let y2: Vec<f64> = y1.iter().map(|v| 2.0 * v).collect();
        let s = spectral_singular_values(&[&y1, &y2], 100.0, 256).unwrap();
        let alone = spectral_singular_values(&[&y1], 100.0, 256).unwrap();
        assert_eq!(s.segments, 8192 / 128 - 1);
        for (v, g11) in s.values.iter().zip(alone.first()) {
            assert!(
                (v[0] - 5.0 * g11).abs() <= 1e-9 * v[0].max(1e-300),
                "{} vs {}",
                v[0],
                5.0 * g11
            );
            assert!(v[1] <= 1e-9 * v[0]);
        }
    }

    #[test]
    fn white_noise_has_the_density_of_its_variance() {
        // Uniform on [-1/2, 1/2): variance 1/12, one-sided density 2σ²/fs.
        let y = noise(1 << 18, 7);
        let fs = 200.0;
        let s = spectral_singular_values(&[&y], fs, 512).unwrap();
        let inner = &s.first()[5..250];
        let mean = inner.iter().sum::<f64>() / inner.len() as f64;
        let want = 2.0 / 12.0 / fs;
        // 1023 segments with 50 % overlap, 245 lines: the mean is within 1 %.
        assert!((mean / want - 1.0).abs() < 0.01, "{mean} vs {want}");
    }

    #[test]
    fn a_segment_with_a_missing_sample_is_left_out() {
        let mut y = noise(4096, 3);
        y[1000] = f64::NAN;
        let s = spectral_singular_values(&[&y], 100.0, 256).unwrap();
        // 31 segments, of which the two that hold sample 1000 are skipped.
        assert_eq!(s.segments, 29);
        assert!(s.values.iter().flatten().all(|v| v.is_finite()));
        let short = spectral_singular_values(&[&y[..100]], 100.0, 256);
        assert!(matches!(short, Err(OmaError::TooShort { .. })));
    }
}
