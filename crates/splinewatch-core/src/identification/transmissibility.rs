//! Multi-input H1 estimates of the frequency response from several measured
//! inputs (the ground accelerations of an earthquake's support groups, or
//! forces) to every output (Bendat & Piersol 2010, *Random Data*, §7.2–7.3).
//!
//! Per frequency line, from Welch-averaged cross spectra (segments of
//! `segment` samples, `overlap` shared, the periodic Hann window, linear
//! averaging): `G_xx` (inputs × inputs), `G_xy` (inputs × outputs), `G_yy`
//! (each output's auto spectrum), and
//!
//! - `H1 = G_yx G_xx⁻¹` (outputs × inputs; `G_yx = G_xyᴴ`),
//! - the multiple coherence of output `o`, `γ²_o = (H G_xx Hᴴ)_oo / G_yy,oo`,
//!   the share of its power the inputs explain together,
//! - the condition number of `G_xx` (largest over smallest eigenvalue): how
//!   well the inputs separate at that line.
//!
//! Inputs too coherent to separate (one ground motion recorded at several
//! supports: their band coherence above `COMBINE_COHERENCE`) are combined:
//! each group of them becomes its mean before the estimate, and
//! [`Transmissibility::combined`] says which.

use faer::{c64, Mat};
use realfft::RealFftPlanner;
use thiserror::Error;

/// Above this band coherence (`Σ|G_ab|² / Σ G_aa G_bb` over the lines) two
/// inputs are one.
pub const COMBINE_COHERENCE: f64 = 0.98;

#[derive(Debug, Clone, PartialEq, Error)]
pub enum TransmissibilityError {
    #[error("no inputs or no outputs")]
    NoChannels,
    #[error("channel {channel} has {len} samples, the first has {expected}")]
    UnequalLengths {
        channel: usize,
        len: usize,
        expected: usize,
    },
    #[error("the record ({samples} samples) is shorter than one segment ({segment})")]
    TooShort { samples: usize, segment: usize },
    #[error("a segment must have at least 8 samples and the overlap fewer than the segment ({segment}, {overlap})")]
    Segments { segment: usize, overlap: usize },
    #[error("channel {channel} holds a value that is not finite")]
    NonFinite { channel: usize },
}

/// The estimates of one record.
#[derive(Debug, Clone)]
pub struct Transmissibility {
    pub frequencies_hz: Vec<f64>,
    /// `h[o][i][line]`: output `o` per (combined) input `i`.
    pub h: Vec<Vec<Vec<c64>>>,
    /// `coherence[o][line]`: the multiple coherence of output `o`.
    pub coherence: Vec<Vec<f64>>,
    /// `condition[line]`: of `G_xx` of the (combined) inputs.
    pub condition: Vec<f64>,
    /// The inputs behind each estimated input (indices into the inputs
    /// given): one each, or a group made one.
    pub combined: Vec<Vec<usize>>,
    /// Segments averaged.
    pub averages: usize,
}

/// Estimates the transmissibilities of `outputs` per `inputs` (all of one
/// length) sampled at `fs`.
pub fn estimate(
    inputs: &[&[f64]],
    outputs: &[&[f64]],
    fs: f64,
    segment: usize,
    overlap: usize,
) -> Result<Transmissibility, TransmissibilityError> {
    if inputs.is_empty() || outputs.is_empty() {
        return Err(TransmissibilityError::NoChannels);
    }
    if segment < 8 || overlap >= segment {
        return Err(TransmissibilityError::Segments { segment, overlap });
    }
    let n = inputs[0].len();
    for (channel, c) in inputs.iter().chain(outputs).enumerate() {
        if c.len() != n {
            return Err(TransmissibilityError::UnequalLengths {
                channel,
                len: c.len(),
                expected: n,
            });
        }
        if c.iter().any(|v| !v.is_finite()) {
            return Err(TransmissibilityError::NonFinite { channel });
        }
    }
    if n < segment {
        return Err(TransmissibilityError::TooShort { samples: n, segment });
    }
    let raw = spectra(inputs, outputs, segment, overlap);
    let groups = coherent_groups(&raw, inputs.len());
    let s = if groups.len() == inputs.len() {
        raw
    } else {
        let merged: Vec<Vec<f64>> = groups
            .iter()
            .map(|g| {
                (0..n)
                    .map(|t| g.iter().map(|&i| inputs[i][t]).sum::<f64>() / g.len() as f64)
                    .collect()
            })
            .collect();
        let merged_views: Vec<&[f64]> = merged.iter().map(Vec::as_slice).collect();
        spectra(&merged_views, outputs, segment, overlap)
    };
    let r = groups.len();
    let lines = segment / 2 + 1;
    let mut h = vec![vec![vec![c64::new(0.0, 0.0); lines]; r]; outputs.len()];
    let mut coherence = vec![vec![0.0; lines]; outputs.len()];
    let mut condition = vec![0.0; lines];
    for k in 0..lines {
        condition[k] = solve_line(
            &s,
            k,
            r,
            outputs.len(),
            |o, i, v| h[o][i][k] = v,
            |o, c| coherence[o][k] = c,
        );
    }
    Ok(Transmissibility {
        frequencies_hz: (0..lines).map(|k| k as f64 * fs / segment as f64).collect(),
        h,
        coherence,
        condition,
        combined: groups,
        averages: s.averages,
    })
}

/// Line `k`: `H1` and the multiple coherences through `set_h(o, i, value)` and
/// `set_coherence(o, value)`; returns the condition number of `G_xx` (infinite
/// when it is singular: nothing is set then).
fn solve_line(
    s: &Spectra,
    k: usize,
    r: usize,
    outputs: usize,
    mut set_h: impl FnMut(usize, usize, c64),
    mut set_coherence: impl FnMut(usize, f64),
) -> f64 {
    let gxx = Mat::from_fn(r, r, |a, b| s.cross[k][a][b]);
    let Ok(eigen) = gxx.self_adjoint_eigen(faer::Side::Lower) else {
        return f64::INFINITY;
    };
    let values: Vec<f64> = (0..r).map(|j| eigen.S().column_vector()[j].re).collect();
    let (low, high) = values
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    if low.is_nan() || low <= 0.0 {
        return f64::INFINITY;
    }
    // G_xx⁻¹ = U Λ⁻¹ Uᴴ.
    let u = eigen.U();
    let inverse = Mat::from_fn(r, r, |a, b| {
        (0..r).fold(c64::new(0.0, 0.0), |acc, j| {
            acc + u[(a, j)] * u[(b, j)].conj() / values[j]
        })
    });
    for o in 0..outputs {
        // H1_o = G_y_o x G_xx⁻¹, G_yx = conj(G_xy).
        let row: Vec<c64> = (0..r)
            .map(|b| {
                (0..r).fold(c64::new(0.0, 0.0), |acc, a| {
                    acc + s.input_output[k][a][o].conj() * inverse[(a, b)]
                })
            })
            .collect();
        let explained: f64 = (0..r)
            .map(|a| {
                (0..r)
                    .fold(c64::new(0.0, 0.0), |acc, b| acc + row[a] * gxx[(a, b)] * row[b].conj())
                    .re
            })
            .sum();
        let power = s.output_power[k][o];
        set_coherence(
            o,
            if power > 0.0 {
                (explained / power).clamp(0.0, 1.0)
            } else {
                0.0
            },
        );
        for (i, v) in row.into_iter().enumerate() {
            set_h(o, i, v);
        }
    }
    high / low
}

/// Averaged one-sided cross spectra (common scale factors left out: they
/// cancel in every ratio above).
struct Spectra {
    /// `[line][a][b]`: `E[X_a X_b*]`.
    cross: Vec<Vec<Vec<c64>>>,
    /// `[line][a][o]`: `E[X_a Y_o*]`.
    input_output: Vec<Vec<Vec<c64>>>,
    /// `[line][o]`: `E[|Y_o|²]`.
    output_power: Vec<Vec<f64>>,
    averages: usize,
}

fn spectra(inputs: &[&[f64]], outputs: &[&[f64]], segment: usize, overlap: usize) -> Spectra {
    let n = inputs[0].len();
    let lines = segment / 2 + 1;
    let (r, m) = (inputs.len(), outputs.len());
    let window = super::welch::Window::Hann.samples(segment);
    let mut planner = RealFftPlanner::<f64>::new();
    let fft = planner.plan_fft_forward(segment);
    let mut buffer = fft.make_input_vec();
    let mut scratch = fft.make_scratch_vec();
    let mut transform = |x: &[f64], out: &mut Vec<c64>| {
        let mean = x.iter().sum::<f64>() / x.len() as f64;
        for (b, (v, w)) in buffer.iter_mut().zip(x.iter().zip(&window)) {
            *b = (v - mean) * w;
        }
        out.resize(lines, c64::new(0.0, 0.0));
        fft.process_with_scratch(&mut buffer, out, &mut scratch)
            .expect("lengths from the plan");
    };
    let mut s = Spectra {
        cross: vec![vec![vec![c64::new(0.0, 0.0); r]; r]; lines],
        input_output: vec![vec![vec![c64::new(0.0, 0.0); m]; r]; lines],
        output_power: vec![vec![0.0; m]; lines],
        averages: 0,
    };
    let step = segment - overlap;
    let (mut xs, mut ys) = (vec![Vec::new(); r], vec![Vec::new(); m]);
    let mut start = 0;
    while start + segment <= n {
        for (x, c) in xs.iter_mut().zip(inputs) {
            transform(&c[start..start + segment], x);
        }
        for (y, c) in ys.iter_mut().zip(outputs) {
            transform(&c[start..start + segment], y);
        }
        for k in 0..lines {
            for a in 0..r {
                for b in 0..r {
                    s.cross[k][a][b] += xs[a][k] * xs[b][k].conj();
                }
                for o in 0..m {
                    s.input_output[k][a][o] += xs[a][k] * ys[o][k].conj();
                }
            }
            for o in 0..m {
                s.output_power[k][o] += ys[o][k].norm_sqr();
            }
        }
        s.averages += 1;
        start += step;
    }
    s
}

/// Groups of inputs whose band coherence `Σ|G_ab|² / Σ G_aa G_bb` (the
/// lines weighted by their power, so that empty parts of the band do not
/// count) exceeds [`COMBINE_COHERENCE`] (single linkage), in input order.
fn coherent_groups(s: &Spectra, r: usize) -> Vec<Vec<usize>> {
    let coherence = |a: usize, b: usize| {
        let (num, den) = s.cross.iter().fold((0.0, 0.0), |(n, d), g| {
            (n + g[a][b].norm_sqr(), d + g[a][a].re * g[b][b].re)
        });
        if den > 0.0 {
            num / den
        } else {
            0.0
        }
    };
    let mut group: Vec<usize> = (0..r).collect();
    for a in 0..r {
        for b in a + 1..r {
            if coherence(a, b) > COMBINE_COHERENCE {
                let (from, to) = (group[b], group[a]);
                group.iter_mut().filter(|g| **g == from).for_each(|g| *g = to);
            }
        }
    }
    let mut out: Vec<Vec<usize>> = Vec::new();
    for i in 0..r {
        match out.iter_mut().find(|g| group[g[0]] == group[i]) {
            Some(g) => g.push(i),
            None => out.push(vec![i]),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// Deterministic uniform noise in [-0.5, 0.5) (64-bit LCG, high bits).
    fn noise(n: usize, mut seed: u64) -> Vec<f64> {
        (0..n)
            .map(|_| {
                seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                ((seed >> 11) as f64) / ((1u64 << 53) as f64) - 0.5
            })
            .collect()
    }

    fn filtered(x: &[f64], taps: &[f64]) -> Vec<f64> {
        (0..x.len())
            .map(|t| {
                taps.iter()
                    .enumerate()
                    .filter(|(k, _)| *k <= t)
                    .map(|(k, h)| h * x[t - k])
                    .sum()
            })
            .collect()
    }

    fn response(taps: &[f64], f: f64, fs: f64) -> c64 {
        taps.iter()
            .enumerate()
            .map(|(k, h)| c64::from_polar(*h, -2.0 * PI * f * k as f64 / fs))
            .sum()
    }

    /// Two independent inputs through two known FIR filters into one output
    /// (and their sum into a second): H1 recovers each filter's response and
    /// the multiple coherence is 1 (no output noise); bias of the short
    /// filters against 256-sample segments with a Hann window, below 1e-2.
    #[test]
    fn two_inputs_are_separated() {
        let n = 40_000;
        let (x1, x2) = (noise(n, 1), noise(n, 2));
        let (h1, h2) = ([1.0, 0.5, -0.25], [0.3, -0.2, 0.1, 0.05]);
        let y1: Vec<f64> = filtered(&x1, &h1)
            .iter()
            .zip(filtered(&x2, &h2))
            .map(|(a, b)| a + b)
            .collect();
        let y2 = filtered(&x1, &h1);
        let est = estimate(&[&x1, &x2], &[&y1, &y2], 100.0, 256, 128).unwrap();
        assert_eq!(est.combined, vec![vec![0], vec![1]]);
        for (k, &f) in est.frequencies_hz.iter().enumerate().skip(1) {
            for (i, taps) in [&h1[..], &h2[..]].iter().enumerate() {
                let want = response(taps, f, 100.0);
                assert!(
                    (est.h[0][i][k] - want).norm() < 1e-2,
                    "{f} Hz, input {i}: {} vs {want}",
                    est.h[0][i][k]
                );
            }
            assert!(est.h[1][1][k].norm() < 1e-2, "y2 does not depend on x2");
            assert!(est.coherence[0][k] > 0.999 && est.condition[k] < 10.0, "{f} Hz");
        }
    }

    /// The same ground motion recorded twice (plus 1 % noise) is one input:
    /// combined and said so, the estimate the filter's response.
    #[test]
    fn coherent_inputs_are_combined() {
        let n = 20_000;
        let x = noise(n, 3);
        let e = noise(n, 4);
        let x_twice: Vec<f64> = x.iter().zip(&e).map(|(a, b)| a + 0.01 * b).collect();
        let taps = [0.8, 0.4];
        let y = filtered(&x, &taps);
        let est = estimate(&[&x, &x_twice], &[&y], 50.0, 128, 64).unwrap();
        assert_eq!(est.combined, vec![vec![0, 1]]);
        let k = 10;
        let want = response(&taps, est.frequencies_hz[k], 50.0);
        assert!((est.h[0][0][k] - want).norm() < 2e-2, "{} vs {want}", est.h[0][0][k]);
        let e = estimate(&[&x], &[&y[..100]], 50.0, 128, 64).unwrap_err();
        assert!(matches!(e, TransmissibilityError::UnequalLengths { .. }), "{e}");
    }
}
