//! Output correlations `R_k = E[y_{t+k} y_ref,tᵀ]` (`l × r`, lags
//! `k = 0..=max_lag`), the data of covariance-driven SSI (Peeters & De Roeck
//! 1999, eq. 8).
//!
//! The window is cut into `B` contiguous batches; each batch keeps the sums
//! `S_k^b = Σ_t y_{t+k} y_ref,tᵀ` over the pairs inside it and their count
//! `c_k^b = n_b − k`. The estimate is `R_k = Σ_b S_k^b / Σ_b c_k^b` (the
//! unbiased estimate, as KOMA's `xcorr_lag`, up to the pairs that straddle a
//! batch boundary), and the leave-one-batch-out estimates
//! `(Σ S − S^b) / (Σ c − c^b)` feed the jackknife of [`super::uncertainty`].
//! Sums are computed per batch by FFT in chunks (overlap-save): a chunk of
//! `m − K` reference samples (`K` the largest lag), zero padded to `m`,
//! against the `m` samples of each channel from the same start (cut at the
//! batch's end), so the circular correlation's first `K + 1` lags are the
//! chunk's sums exactly; the cross spectra `Y_a X_refᴴ` add up over the
//! chunks and one inverse FFT of length `m` per pair and batch gives `S_k`.
//! With `m ≈ 8 (K + 1)` the work is `O(n l r)` products plus short FFTs,
//! where transforms of whole batches cost `l r` long inverse FFTs per batch
//! (95 → ~20 ms on a 10-minute, 12-channel window). Batches run on up to
//! four threads (`ordered_map`), so the sums do not depend on the
//! thread count.
//!
//! **Missing samples.** A NaN marks a missing sample (the pipeline fills a
//! gap with NaN). An instant is valid when every channel is finite there;
//! means are taken over valid instants, invalid ones are set to zero, and a
//! batch's count becomes the number of valid pairs `c_k^b = Σ_t m_{t+k} m_t`
//! (`m` the validity mask): the estimate of correlations from gappy records
//! (Parzen 1963, "On spectral analysis with missing observations"), which
//! reduces to the one above without gaps.

use super::OmaError;
use faer::c64;
use realfft::RealFftPlanner;

/// Batched sums of lagged output products; see the module documentation.
#[derive(Debug, Clone)]
pub struct OutputCorrelations {
    channels: usize,
    references: Vec<usize>,
    max_lag: usize,
    /// Per batch, `(max_lag + 1) × l × r` sums, lag-major then row-major.
    sums: Vec<Vec<f64>>,
    /// Per batch, pairs per lag (`n_b − k`).
    counts: Vec<Vec<f64>>,
}

impl OutputCorrelations {
    /// Correlations of `channels` (equal lengths, mean removed here; NaN
    /// marks a missing sample) against the reference channels `references`
    /// (indices into `channels`; empty means all), for lags `0..=max_lag`,
    /// in `batches` batches. Too few valid pairs (fewer than two batches
    /// with pairs at every lag, for the jackknife) is [`OmaError::TooShort`].
    pub fn from_samples(
        channels: &[&[f64]],
        references: &[usize],
        max_lag: usize,
        batches: usize,
    ) -> Result<Self, OmaError> {
        let n = super::sample_length(channels)?;
        let l = channels.len();
        let references: Vec<usize> = if references.is_empty() {
            (0..l).collect()
        } else {
            references.to_vec()
        };
        if let Some(&bad) = references.iter().find(|&&r| r >= l) {
            return Err(OmaError::BadReference {
                index: bad,
                channels: l,
            });
        }
        let batches = batches.max(1);
        let batch_len = n / batches;
        if batch_len < 4 * (max_lag + 1) {
            return Err(OmaError::TooShort {
                samples: n,
                needed: 4 * (max_lag + 1) * batches,
            });
        }
        let (centred, valid) = centred_channels(channels);
        let valid_count = valid.iter().filter(|&&v| v).count();
        let mut out = Self {
            channels: l,
            references,
            max_lag,
            sums: Vec::with_capacity(batches),
            counts: Vec::with_capacity(batches),
        };
        let plan = ChunkPlan::new(max_lag);
        let bounds: Vec<(usize, usize)> = (0..batches)
            .map(|b| {
                // The last batch takes the remainder.
                let start = b * batch_len;
                (start, if b + 1 == batches { n } else { start + batch_len })
            })
            .collect();
        let references = &out.references;
        out.sums = super::ordered_map(&bounds, |&(start, end)| {
            let slices: Vec<&[f64]> = centred.iter().map(|c| &c[start..end]).collect();
            plan.batch_sums(&slices, references, end - start)
        });
        out.counts = bounds
            .iter()
            .map(|&(start, end)| pair_counts(&valid[start..end], max_lag))
            .collect();
        // Every jackknife replicate (every batch but one) needs pairs at every lag.
        let needed_batches = 2.min(batches);
        let short = (0..=max_lag).any(|k| out.counts.iter().filter(|c| c[k] > 0.0).count() < needed_batches);
        if short {
            return Err(OmaError::TooShort {
                samples: valid_count,
                needed: 4 * (max_lag + 1) * batches,
            });
        }
        Ok(out)
    }

    pub fn channels(&self) -> usize {
        self.channels
    }

    pub fn references(&self) -> &[usize] {
        &self.references
    }

    pub fn max_lag(&self) -> usize {
        self.max_lag
    }

    pub fn batches(&self) -> usize {
        self.sums.len()
    }

    /// `R_k` of the whole window: `(max_lag + 1) × l × r`, lag-major.
    pub fn estimate(&self) -> Vec<f64> {
        self.estimate_without(None)
    }

    /// `R_k` with batch `left_out` removed (the jackknife's replicate).
    pub fn estimate_without(&self, left_out: Option<usize>) -> Vec<f64> {
        let block = self.channels * self.references.len();
        let mut sum = vec![0.0; self.sums[0].len()];
        let mut count = vec![0.0; self.max_lag + 1];
        for (b, (s, c)) in self.sums.iter().zip(&self.counts).enumerate() {
            if Some(b) == left_out {
                continue;
            }
            sum.iter_mut().zip(s).for_each(|(t, v)| *t += v);
            count.iter_mut().zip(c).for_each(|(t, v)| *t += v);
        }
        for (i, v) in sum.iter_mut().enumerate() {
            *v /= count[i / block];
        }
        sum
    }
}

/// The channels less their means over the valid instants (every channel
/// finite there), zero at the others, and the validity mask. Channel by
/// channel on the workers (a 10-minute window's mask and means took ~6 ms on
/// one thread); without a NaN the mask is all set.
pub(crate) fn centred_channels(channels: &[&[f64]]) -> (Vec<Vec<f64>>, Vec<bool>) {
    let n = channels.first().map_or(0, |c| c.len());
    let gappy = super::ordered_map(channels, |c| c.iter().any(|v| v.is_nan()));
    let valid: Vec<bool> = if gappy.iter().any(|&g| g) {
        (0..n).map(|t| channels.iter().all(|c| !c[t].is_nan())).collect()
    } else {
        vec![true; n]
    };
    let valid_count = valid.iter().filter(|&&v| v).count();
    let centred = super::ordered_map(channels, |c| {
        let mean = c.iter().zip(&valid).filter(|(_, &v)| v).map(|(x, _)| x).sum::<f64>() / valid_count.max(1) as f64;
        c.iter()
            .zip(&valid)
            .map(|(x, &v)| if v { x - mean } else { 0.0 })
            .collect()
    });
    (centred, valid)
}

/// The FFTs of the chunked sums (see the module documentation).
pub(crate) struct ChunkPlan {
    max_lag: usize,
    /// FFT length `m`; chunks start every `m − max_lag` samples.
    len: usize,
    forward: std::sync::Arc<dyn realfft::RealToComplex<f64>>,
    inverse: std::sync::Arc<dyn realfft::ComplexToReal<f64>>,
}

impl ChunkPlan {
    pub(crate) fn new(max_lag: usize) -> Self {
        let len = (8 * (max_lag + 1)).next_power_of_two();
        let mut planner = RealFftPlanner::<f64>::new();
        Self {
            max_lag,
            len,
            forward: planner.plan_fft_forward(len),
            inverse: planner.plan_fft_inverse(len),
        }
    }

    /// `S_k = Σ_t y_{t+k} y_ref,tᵀ` over the reference instants
    /// `t < reference_len` of `batch` (its later samples only lagged into),
    /// lag-major then row-major (missing samples are zeros, so they add
    /// nothing).
    pub(crate) fn batch_sums(&self, batch: &[&[f64]], references: &[usize], reference_len: usize) -> Vec<f64> {
        let (l, r, n, m) = (batch.len(), references.len(), batch[0].len(), self.len);
        let (hop, bins) = (m - self.max_lag, m / 2 + 1);
        let zero = c64::new(0.0, 0.0);
        // Per pair (a, j), the cross spectrum summed over the chunks, real
        // and imaginary parts apart (so the products vectorise).
        let (mut cross_re, mut cross_im) = (vec![0.0; l * r * bins], vec![0.0; l * r * bins]);
        let mut buffer = vec![0.0; m];
        let mut spectrum = vec![zero; bins];
        let mut scratch = vec![zero; self.forward.get_scratch_len()];
        let (mut outputs_re, mut outputs_im) = (vec![0.0; l * bins], vec![0.0; l * bins]);
        let (mut refs_re, mut refs_im) = (vec![0.0; r * bins], vec![0.0; r * bins]);
        let mut transform = |samples: &[f64], re: &mut [f64], im: &mut [f64]| {
            buffer[..samples.len()].copy_from_slice(samples);
            buffer[samples.len()..].fill(0.0);
            self.forward
                .process_with_scratch(&mut buffer, &mut spectrum, &mut scratch)
                .expect("sized by the plan");
            for ((z, re), im) in spectrum.iter().zip(re).zip(im) {
                (*re, *im) = (z.re, z.im);
            }
        };
        for start in (0..reference_len).step_by(hop) {
            for (a, y) in batch.iter().enumerate() {
                let part = a * bins..(a + 1) * bins;
                transform(
                    &y[start..n.min(start + m)],
                    &mut outputs_re[part.clone()],
                    &mut outputs_im[part],
                );
            }
            for (j, &reference) in references.iter().enumerate() {
                let part = j * bins..(j + 1) * bins;
                transform(
                    &batch[reference][start..reference_len.min(start + hop)],
                    &mut refs_re[part.clone()],
                    &mut refs_im[part],
                );
            }
            // Y_a X_jᴴ: (yr + i yi)(xr − i xi).
            for a in 0..l {
                let (yr, yi) = (
                    &outputs_re[a * bins..(a + 1) * bins],
                    &outputs_im[a * bins..(a + 1) * bins],
                );
                for j in 0..r {
                    let (xr, xi) = (&refs_re[j * bins..(j + 1) * bins], &refs_im[j * bins..(j + 1) * bins]);
                    let pair = (a * r + j) * bins..(a * r + j + 1) * bins;
                    let (sr, si) = (&mut cross_re[pair.clone()], &mut cross_im[pair]);
                    for f in 0..bins {
                        sr[f] += yr[f] * xr[f] + yi[f] * xi[f];
                        si[f] += yr[f] * -xi[f] + yi[f] * xr[f];
                    }
                }
            }
        }
        let mut sums = vec![0.0; (self.max_lag + 1) * l * r];
        let mut lagged = vec![0.0; m];
        let mut scratch = vec![zero; self.inverse.get_scratch_len()];
        for pair in 0..l * r {
            let (a, j) = (pair / r, pair % r);
            for (f, z) in spectrum.iter_mut().enumerate() {
                *z = c64::new(cross_re[pair * bins + f], cross_im[pair * bins + f]);
            }
            spectrum[0].im = 0.0;
            spectrum[bins - 1].im = 0.0;
            self.inverse
                .process_with_scratch(&mut spectrum, &mut lagged, &mut scratch)
                .expect("sized by the plan");
            for k in 0..=self.max_lag {
                sums[(k * l + a) * r + j] = lagged[k] / m as f64;
            }
        }
        sums
    }
}

/// Valid pairs per lag, `Σ_t m_{t+k} m_t`: `n − k` without gaps.
fn pair_counts(valid: &[bool], max_lag: usize) -> Vec<f64> {
    let n = valid.len();
    if valid.iter().all(|&v| v) {
        return (0..=max_lag).map(|k| n.saturating_sub(k) as f64).collect();
    }
    (0..=max_lag)
        .map(|k| (0..n.saturating_sub(k)).filter(|&t| valid[t] && valid[t + k]).count() as f64)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn signals() -> Vec<Vec<f64>> {
        // Deterministic, non-periodic, correlated channels.
        let base: Vec<f64> = (0..997).map(|t| ((t * t) as f64 * 0.37).sin() + 0.3).collect();
        vec![
            base.clone(),
            base.iter()
                .enumerate()
                .map(|(t, v)| 0.5 * v + (t as f64 * 0.11).cos())
                .collect(),
            (0..997).map(|t| ((t as f64).sqrt() * 1.7).sin()).collect(),
        ]
    }

    #[test]
    fn fft_sums_equal_the_definition() {
        let y = signals();
        let views: Vec<&[f64]> = y.iter().map(Vec::as_slice).collect();
        for batches in [1, 3] {
            let c = OutputCorrelations::from_samples(&views, &[], 20, batches).unwrap();
            let want = direct_with_gaps(&y, 20, batches, None);
            for (g, w) in c.estimate().iter().zip(&want) {
                assert!((g - w).abs() < 1e-12, "{g} vs {w}");
            }
        }
    }

    #[test]
    fn references_pick_columns() {
        let y = signals();
        let views: Vec<&[f64]> = y.iter().map(Vec::as_slice).collect();
        let all = OutputCorrelations::from_samples(&views, &[], 5, 2).unwrap().estimate();
        let one = OutputCorrelations::from_samples(&views, &[2], 5, 2).unwrap().estimate();
        for k in 0..=5 {
            for a in 0..3 {
                assert!((one[k * 3 + a] - all[(k * 3 + a) * 3 + 2]).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn leave_one_out_is_the_estimate_of_the_other_batches() {
        let y = signals();
        let views: Vec<&[f64]> = y.iter().map(Vec::as_slice).collect();
        let c = OutputCorrelations::from_samples(&views, &[], 4, 4).unwrap();
        for b in 0..4 {
            let want = direct_with_gaps(&y, 4, 4, Some(b));
            for (g, w) in c.estimate_without(Some(b)).iter().zip(&want) {
                assert!((g - w).abs() < 1e-12, "{g} vs {w}");
            }
        }
    }

    /// Direct `O(n · lags)` sums, the definition, restricted to valid pairs:
    /// instants where every channel is finite, means over those instants.
    fn direct_with_gaps(y: &[Vec<f64>], max_lag: usize, batches: usize, skip: Option<usize>) -> Vec<f64> {
        let (l, n) = (y.len(), y[0].len());
        let valid: Vec<bool> = (0..n).map(|t| y.iter().all(|c| c[t].is_finite())).collect();
        let count = valid.iter().filter(|&&v| v).count() as f64;
        let means: Vec<f64> = y
            .iter()
            .map(|c| (0..n).filter(|&t| valid[t]).map(|t| c[t]).sum::<f64>() / count)
            .collect();
        let len = n / batches;
        let mut out = vec![0.0; (max_lag + 1) * l * l];
        for k in 0..=max_lag {
            for a in 0..l {
                for r in 0..l {
                    let (mut s, mut c) = (0.0, 0.0);
                    for b in (0..batches).filter(|&b| Some(b) != skip) {
                        let end = if b + 1 == batches { n } else { (b + 1) * len };
                        for t in (b * len..end - k).filter(|&t| valid[t] && valid[t + k]) {
                            s += (y[a][t + k] - means[a]) * (y[r][t] - means[r]);
                            c += 1.0;
                        }
                    }
                    out[(k * l + a) * l + r] = s / c;
                }
            }
        }
        out
    }

    #[test]
    fn missing_samples_leave_out_exactly_their_pairs() {
        let mut y = signals();
        // A gap on one channel, a gap on all, and a lone missing sample.
        y[1][100..180].fill(f64::NAN);
        for c in &mut y {
            c[600..640].fill(f64::NAN);
        }
        y[2][900] = f64::NAN;
        let views: Vec<&[f64]> = y.iter().map(Vec::as_slice).collect();
        let c = OutputCorrelations::from_samples(&views, &[], 12, 4).unwrap();
        for skip in [None, Some(0), Some(2)] {
            let want = direct_with_gaps(&y, 12, 4, skip);
            for (g, w) in c.estimate_without(skip).iter().zip(&want) {
                assert!((g - w).abs() < 1e-12, "{g} vs {w}");
            }
        }
    }

    #[test]
    fn bad_input_is_named() {
        let y = signals();
        let short: Vec<&[f64]> = vec![&y[0][..10], &y[1][..10]];
        assert!(matches!(
            OutputCorrelations::from_samples(&short, &[], 5, 1),
            Err(OmaError::TooShort { .. })
        ));
        let uneven: Vec<&[f64]> = vec![&y[0], &y[1][..50]];
        assert!(matches!(
            OutputCorrelations::from_samples(&uneven, &[], 5, 1),
            Err(OmaError::UnequalLengths { channel: 1, .. })
        ));
        let infinite: Vec<f64> = y[1].iter().map(|v| v / 0.0).collect();
        let with_inf: Vec<&[f64]> = vec![&y[0], &infinite];
        assert!(matches!(
            OutputCorrelations::from_samples(&with_inf, &[], 5, 1),
            Err(OmaError::NonFinite { channel: 1 })
        ));
        // A channel that is missing throughout leaves no valid pair.
        let nan = vec![f64::NAN; 997];
        let with_nan: Vec<&[f64]> = vec![&y[0], &nan];
        assert!(matches!(
            OutputCorrelations::from_samples(&with_nan, &[], 5, 2),
            Err(OmaError::TooShort { samples: 0, .. })
        ));
        let views: Vec<&[f64]> = y.iter().map(Vec::as_slice).collect();
        assert!(matches!(
            OutputCorrelations::from_samples(&views, &[7], 5, 1),
            Err(OmaError::BadReference { index: 7, .. })
        ));
    }
}
