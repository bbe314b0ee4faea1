//! Welch cross-spectral estimation and FRF estimators.
//!
//! Segments of `n` samples start at the first sample and advance by
//! `n - overlap`, an incomplete tail being left for later (streaming) or
//! dropped (batch), exactly as `scipy.signal.csd`. Each segment is
//! detrended, windowed and transformed with a real FFT; the one-sided
//! density `S_ab = 2 conj(A) B / (fs Σw²)` (not doubled at DC and, for even
//! `n`, at Nyquist) is averaged linearly or exponentially.
//!
//! With input (force) `f` and output (response) `x`, `S_fx = E[F* X]`:
//! - `H1 = S_fx / S_ff` (noise on the output),
//! - `H2 = S_xx / S_xf`, `S_xf = conj(S_fx)` (noise on the input; the
//!   conjugation matters: `S_xx / S_fx` would be `conj(H)`),
//! - `Hv`, the total-least-squares estimator of a single input: the
//!   principal eigenvector of `[[S_ff, S_xf], [S_fx, S_xx]]`,
//!   `Hv = (S_xx - S_ff + √((S_xx - S_ff)² + 4|S_fx|²)) / (2 S_xf)`,
//! - ordinary coherence `γ² = |S_fx|² / (S_ff S_xx)`.
//!
//! Exponential averaging with weight `α` keeps
//! `S_k = S_{k-1} + (P_k - S_{k-1}) / W_k`, `W_k = (1 - α) W_{k-1} + 1`, and
//! reports the effective number of averages `W² / Σ w²`, which tends to
//! `(2 - α) / α`.

use faer::c64;
use realfft::{RealFftPlanner, RealToComplex};
use std::f64::consts::PI;
use std::sync::Arc;
use thiserror::Error;

#[derive(Debug, Clone, PartialEq, Error)]
pub enum WelchError {
    #[error("sampling frequency must be finite and positive, got {0}")]
    SampleRate(f64),
    #[error("segment length {0} must be at least 4 samples")]
    SegmentLength(usize),
    #[error("overlap of {overlap} samples must be smaller than the segment ({segment})")]
    Overlap { overlap: usize, segment: usize },
    #[error("exponential averaging weight must be in (0, 1], got {0}")]
    Alpha(f64),
    #[error("window parameter {name} = {value} is out of range")]
    WindowParameter { name: &'static str, value: f64 },
    #[error("{found} output channels given, the estimator has {expected}")]
    ChannelCount { found: usize, expected: usize },
    #[error("channel lengths differ: input has {input}, output {channel} has {found}")]
    ChannelLength { input: usize, channel: usize, found: usize },
}

/// Segment window.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Window {
    Rectangular,
    /// Periodic Hann, as `scipy.signal.get_window("hann", n)`.
    Hann,
    Hamming,
    Blackman,
    /// scipy's five-term flat-top.
    FlatTop,
    /// Impact testing: ones over the first `width` fraction, zero after.
    Force {
        width: f64,
    },
    /// Impact testing: `exp(-k/n · ln(1/end))`, decaying to `end` at the segment end.
    Exponential {
        end: f64,
    },
}

impl Window {
    pub fn validate(self) -> Result<(), WelchError> {
        match self {
            Window::Force { width } if !(width > 0.0 && width <= 1.0) => Err(WelchError::WindowParameter {
                name: "force width",
                value: width,
            }),
            Window::Exponential { end } if !(end > 0.0 && end <= 1.0) => Err(WelchError::WindowParameter {
                name: "exponential end",
                value: end,
            }),
            _ => Ok(()),
        }
    }

    /// The `n` window samples (periodic, "DFT-even", like scipy's default).
    pub fn samples(self, n: usize) -> Vec<f64> {
        let cosine = |a: &[f64]| -> Vec<f64> {
            (0..n)
                .map(|k| {
                    let x = 2.0 * PI * k as f64 / n as f64;
                    a.iter()
                        .enumerate()
                        .map(|(j, &c)| if j % 2 == 0 { c } else { -c } * (j as f64 * x).cos())
                        .sum()
                })
                .collect()
        };
        match self {
            Window::Rectangular => vec![1.0; n],
            Window::Hann => cosine(&[0.5, 0.5]),
            Window::Hamming => cosine(&[0.54, 0.46]),
            Window::Blackman => cosine(&[0.42, 0.5, 0.08]),
            Window::FlatTop => cosine(&[0.21557895, 0.41663158, 0.277263158, 0.083578947, 0.006947368]),
            Window::Force { width } => {
                let m = ((width * n as f64).round() as usize).clamp(1, n);
                (0..n).map(|k| if k < m { 1.0 } else { 0.0 }).collect()
            }
            Window::Exponential { end } => {
                let rate = (1.0 / end).ln() / n as f64;
                (0..n).map(|k| (-rate * k as f64).exp()).collect()
            }
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Detrend {
    None,
    /// Subtract each segment's mean (scipy's "constant", the default).
    Constant,
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Averaging {
    Linear,
    Exponential { alpha: f64 },
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Estimator {
    H1,
    H2,
    Hv,
}

/// Data-quality gates applied to every segment.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Gates {
    /// Reject a segment in which any sample reaches this magnitude (overload).
    pub full_scale: Option<f64>,
    /// Impact tests: reject a segment whose force has a second hit above
    /// this fraction of its peak, after the force first fell below it.
    pub double_impact_fraction: Option<f64>,
}

/// Estimator settings.
#[derive(Debug, Clone, PartialEq)]
pub struct WelchSettings {
    pub fs: f64,
    pub segment: usize,
    pub overlap: usize,
    /// Window of the input (force) channel.
    pub input_window: Window,
    /// Window of the output (response) channels.
    pub output_window: Window,
    pub detrend: Detrend,
    pub averaging: Averaging,
    pub gates: Gates,
}

impl WelchSettings {
    pub fn validate(&self) -> Result<(), WelchError> {
        if !(self.fs.is_finite() && self.fs > 0.0) {
            return Err(WelchError::SampleRate(self.fs));
        }
        if self.segment < 4 {
            return Err(WelchError::SegmentLength(self.segment));
        }
        if self.overlap >= self.segment {
            return Err(WelchError::Overlap {
                overlap: self.overlap,
                segment: self.segment,
            });
        }
        if let Averaging::Exponential { alpha } = self.averaging {
            if !(alpha > 0.0 && alpha <= 1.0) {
                return Err(WelchError::Alpha(alpha));
            }
        }
        self.input_window.validate()?;
        self.output_window.validate()
    }

    pub fn step(&self) -> usize {
        self.segment - self.overlap
    }

    /// Frequencies of the one-sided spectrum, `k fs / n`.
    pub fn frequencies(&self) -> Vec<f64> {
        (0..self.segment / 2 + 1)
            .map(|k| k as f64 * self.fs / self.segment as f64)
            .collect()
    }
}

/// Why segments were rejected.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub struct SegmentCounts {
    pub accepted: u64,
    pub non_finite: u64,
    pub clipped: u64,
    pub double_impact: u64,
}

impl SegmentCounts {
    pub fn rejected(&self) -> u64 {
        self.non_finite + self.clipped + self.double_impact
    }
}

/// Averaged one-sided densities for one input and several outputs.
#[derive(Debug, Clone, PartialEq)]
pub struct CrossSpectra {
    pub frequencies: Vec<f64>,
    pub s_ff: Vec<f64>,
    /// `S_fx = E[F* X]` per output.
    pub s_fx: Vec<Vec<c64>>,
    pub s_xx: Vec<Vec<f64>>,
    /// Effective number of averages (segments for linear averaging).
    pub effective_averages: f64,
}

/// FRFs estimated from cross spectra.
#[derive(Debug, Clone, PartialEq)]
pub struct FrfEstimate {
    pub frequencies: Vec<f64>,
    /// Per output: output / input at every line.
    pub h: Vec<Vec<c64>>,
    pub coherence: Vec<Vec<f64>>,
    pub effective_averages: f64,
}

impl CrossSpectra {
    pub fn frf(&self, estimator: Estimator) -> FrfEstimate {
        let nl = self.frequencies.len();
        let mut h = Vec::with_capacity(self.s_fx.len());
        let mut coherence = Vec::with_capacity(self.s_fx.len());
        for (sfx, sxx) in self.s_fx.iter().zip(&self.s_xx) {
            let mut hr = Vec::with_capacity(nl);
            let mut cr = Vec::with_capacity(nl);
            for l in 0..nl {
                let (ff, fx, xx) = (self.s_ff[l], sfx[l], sxx[l]);
                let value = match estimator {
                    Estimator::H1 => fx / ff,
                    Estimator::H2 => xx / fx.conj(),
                    Estimator::Hv => {
                        let d = xx - ff;
                        (d + (d * d + 4.0 * fx.norm_sqr()).sqrt()) / (2.0 * fx.conj())
                    }
                };
                hr.push(value);
                cr.push(fx.norm_sqr() / (ff * xx));
            }
            h.push(hr);
            coherence.push(cr);
        }
        FrfEstimate {
            frequencies: self.frequencies.clone(),
            h,
            coherence,
            effective_averages: self.effective_averages,
        }
    }
}

/// Streaming Welch estimator: feed aligned samples as they arrive; memory is
/// bounded by one segment per channel plus the spectra.
pub struct WelchEstimator {
    settings: WelchSettings,
    fft: Arc<dyn RealToComplex<f64>>,
    input_window: Vec<f64>,
    output_window: Vec<f64>,
    /// Pending samples: channel 0 is the input.
    pending: Vec<Vec<f64>>,
    s_ff: Vec<f64>,
    s_fx: Vec<Vec<c64>>,
    s_xx: Vec<Vec<f64>>,
    weight_sum: f64,
    weight_square_sum: f64,
    counts: SegmentCounts,
    scratch_in: Vec<f64>,
    /// The input's spectrum of the segment being averaged, and one output's.
    input_spectrum: Vec<c64>,
    spectrum: Vec<c64>,
    fft_scratch: Vec<c64>,
    /// Per bin: the density scale, doubled except at DC and (even `n`) Nyquist.
    bin_scale: Vec<f64>,
    /// Per channel: the pending segment's sum.
    sums: Vec<f64>,
}

impl std::fmt::Debug for WelchEstimator {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("WelchEstimator")
            .field("settings", &self.settings)
            .field("counts", &self.counts)
            .finish_non_exhaustive()
    }
}

impl WelchEstimator {
    pub fn new(settings: WelchSettings, outputs: usize) -> Result<Self, WelchError> {
        settings.validate()?;
        let n = settings.segment;
        let fft = RealFftPlanner::<f64>::new().plan_fft_forward(n);
        let input_window = settings.input_window.samples(n);
        let output_window = settings.output_window.samples(n);
        // Density scaling per channel pair uses √(Σw_a² Σw_b²); equal windows give fs Σw².
        let sum_in: f64 = input_window.iter().map(|w| w * w).sum();
        let sum_out: f64 = output_window.iter().map(|w| w * w).sum();
        let scale = 1.0 / (settings.fs * (sum_in * sum_out).sqrt());
        let bins = n / 2 + 1;
        let fft_scratch = fft.make_scratch_vec();
        let bin_scale = (0..bins)
            .map(|k| {
                let one_sided = if k == 0 || (n % 2 == 0 && k == bins - 1) {
                    1.0
                } else {
                    2.0
                };
                scale * one_sided
            })
            .collect();
        Ok(Self {
            fft,
            input_window,
            output_window,
            pending: vec![Vec::with_capacity(2 * n); outputs + 1],
            s_ff: vec![0.0; bins],
            s_fx: vec![vec![c64::new(0.0, 0.0); bins]; outputs],
            s_xx: vec![vec![0.0; bins]; outputs],
            weight_sum: 0.0,
            weight_square_sum: 0.0,
            counts: SegmentCounts::default(),
            scratch_in: vec![0.0; n],
            input_spectrum: vec![c64::new(0.0, 0.0); bins],
            spectrum: vec![c64::new(0.0, 0.0); bins],
            fft_scratch,
            bin_scale,
            sums: Vec::with_capacity(outputs + 1),
            settings,
        })
    }

    pub fn settings(&self) -> &WelchSettings {
        &self.settings
    }

    pub fn counts(&self) -> SegmentCounts {
        self.counts
    }

    /// Samples buffered and not yet part of a segment, per channel.
    pub fn pending_samples(&self) -> usize {
        self.pending[0].len()
    }

    /// Appends time-aligned samples (same length on every channel) and
    /// processes every segment that became complete.
    pub fn push(&mut self, input: &[f64], outputs: &[&[f64]]) -> Result<(), WelchError> {
        if outputs.len() != self.s_fx.len() {
            return Err(WelchError::ChannelCount {
                found: outputs.len(),
                expected: self.s_fx.len(),
            });
        }
        if let Some((channel, o)) = outputs.iter().enumerate().find(|(_, o)| o.len() != input.len()) {
            return Err(WelchError::ChannelLength {
                input: input.len(),
                channel,
                found: o.len(),
            });
        }
        let n = self.settings.segment;
        let step = self.settings.step();
        let mut offset = 0;
        while offset < input.len() {
            // Fill up to one segment, process it, drop `step` samples.
            let take = (n - self.pending[0].len()).min(input.len() - offset);
            self.pending[0].extend_from_slice(&input[offset..offset + take]);
            for (c, o) in outputs.iter().enumerate() {
                self.pending[c + 1].extend_from_slice(&o[offset..offset + take]);
            }
            offset += take;
            if self.pending[0].len() == n {
                self.process_segment();
                for p in &mut self.pending {
                    p.drain(..step);
                }
            }
        }
        Ok(())
    }

    /// Why the pending segment is rejected, if it is. A channel's sum
    /// (`sums`) is finite exactly when none of its samples is NaN or
    /// infinite, or the exact check runs (a finite sum overflowing).
    fn gate(&self) -> Option<fn(&mut SegmentCounts)> {
        if self.sums.iter().any(|s| !s.is_finite()) && self.pending.iter().any(|c| c.iter().any(|v| !v.is_finite())) {
            return Some(|c| c.non_finite += 1);
        }
        if let Some(fs) = self.settings.gates.full_scale {
            if self.pending.iter().any(|c| c.iter().any(|v| v.abs() >= fs)) {
                return Some(|c| c.clipped += 1);
            }
        }
        if let Some(fraction) = self.settings.gates.double_impact_fraction {
            let force = &self.pending[0];
            let peak = force.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let threshold = fraction * peak;
            let mut hits = 0;
            let mut above = false;
            for v in force {
                let now = v.abs() >= threshold;
                if now && !above {
                    hits += 1;
                }
                above = now;
            }
            if peak > 0.0 && hits > 1 {
                return Some(|c| c.double_impact += 1);
            }
        }
        None
    }

    fn process_segment(&mut self) {
        channel_sums(&self.pending, &mut self.sums);
        if let Some(count) = self.gate() {
            count(&mut self.counts);
            return;
        }
        self.counts.accepted += 1;
        // The running-average weight of this segment.
        let w = match self.settings.averaging {
            Averaging::Linear => {
                self.weight_sum += 1.0;
                self.weight_square_sum += 1.0;
                1.0 / self.weight_sum
            }
            Averaging::Exponential { alpha } => {
                self.weight_sum = (1.0 - alpha) * self.weight_sum + 1.0;
                self.weight_square_sum = (1.0 - alpha) * (1.0 - alpha) * self.weight_square_sum + 1.0;
                1.0 / self.weight_sum
            }
        };
        // One channel at a time: its spectrum, then its one-sided densities
        // into the running averages while the spectrum is still in cache
        // (each bin's arithmetic as in one pass over the bins: the same bits).
        self.transform(0);
        for ((s_ff, fk), &s) in self.s_ff.iter_mut().zip(&self.input_spectrum).zip(&self.bin_scale) {
            let pff = fk.norm_sqr() * s;
            *s_ff += (pff - *s_ff) * w;
        }
        for o in 0..self.s_fx.len() {
            self.transform(o + 1);
            let (f, x) = (&self.input_spectrum, &self.spectrum);
            let (s_fx, s_xx) = (&mut self.s_fx[o], &mut self.s_xx[o]);
            for ((((fx, xx), fk), xk), &s) in s_fx.iter_mut().zip(s_xx.iter_mut()).zip(f).zip(x).zip(&self.bin_scale) {
                let pfx = fk.conj() * xk * s;
                let pxx = xk.norm_sqr() * s;
                *fx = *fx + (pfx - *fx) * w;
                *xx += (pxx - *xx) * w;
            }
        }
    }

    /// The spectrum of pending channel `c` (mean removed, windowed): into
    /// `input_spectrum` for the input (`c = 0`), `spectrum` otherwise.
    fn transform(&mut self, c: usize) {
        let (window, spectrum) = if c == 0 {
            (&self.input_window, &mut self.input_spectrum)
        } else {
            (&self.output_window, &mut self.spectrum)
        };
        let mean = match self.settings.detrend {
            Detrend::None => 0.0,
            Detrend::Constant => self.sums[c] / self.settings.segment as f64,
        };
        for ((out, &x), &w) in self.scratch_in.iter_mut().zip(&self.pending[c]).zip(window) {
            *out = (x - mean) * w;
        }
        self.fft
            .process_with_scratch(&mut self.scratch_in, spectrum, &mut self.fft_scratch)
            .expect("buffers sized by the plan");
    }

    /// The averaged spectra so far.
    pub fn spectra(&self) -> CrossSpectra {
        CrossSpectra {
            frequencies: self.settings.frequencies(),
            s_ff: self.s_ff.clone(),
            s_fx: self.s_fx.clone(),
            s_xx: self.s_xx.clone(),
            effective_averages: if self.weight_square_sum > 0.0 {
                self.weight_sum * self.weight_sum / self.weight_square_sum
            } else {
                0.0
            },
        }
    }
}

/// The sum of every channel's samples, each in index order from `-0.0`
/// exactly as `Iterator::sum` adds them (so the means keep their bits),
/// eight channels at a time so that the additions of different channels
/// overlap instead of waiting on each other.
fn channel_sums(channels: &[Vec<f64>], sums: &mut Vec<f64>) {
    const LANES: usize = 8;
    sums.clear();
    let len = channels.first().map_or(0, Vec::len);
    for group in channels.chunks(LANES) {
        // A short last group repeats its first channel in the spare lanes
        // (their sums are dropped): the loop keeps eight fixed lanes.
        let lanes: [&[f64]; LANES] = std::array::from_fn(|l| &group[l.min(group.len() - 1)][..len]);
        let mut acc = [-0.0f64; LANES];
        for k in 0..len {
            for l in 0..LANES {
                acc[l] += lanes[l][k];
            }
        }
        sums.extend_from_slice(&acc[..group.len()]);
    }
}

#[cfg(test)]
mod tests;
