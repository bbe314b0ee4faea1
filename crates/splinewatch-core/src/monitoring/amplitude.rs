//! Event verdicts that know amplitude (issue 45, item 4).
//!
//! The frequencies of real bridges drop with the shaking amplitude (soil,
//! abutments and cracked concrete soften) and recover after it: a feature of
//! an earthquake (an identified frequency, an updated parameter) is judged
//! against what the earlier events predict at this event's amplitude. Per
//! feature, the earlier events fit `y = a + b log10(A)` (A: the ground's peak
//! acceleration) by least squares, and the event's value is compared with the
//! prediction interval of a new observation (Montgomery, Peck & Vining,
//! *Introduction to Linear Regression Analysis*, §2.5):
//!
//! `ŷ ± t_{1−α/2m, n−2} s √(1 + 1/n + (x − x̄)² / S_xx)`,
//!
//! exact under independent normal scatter about the line; the false-alarm
//! rate `α` per event is shared by the `m` features judged (Bonferroni), so
//! an event of an unchanged bridge raises an alarm with probability at most
//! `α`. When the earlier events span too little amplitude for a slope
//! (`S_xx` below 1e-6 decades², or fewer than three), the line is a constant
//! (`t_{n−1}`, `√(1 + 1/n)`). With fewer earlier events than `min_events`
//! there is no verdict: "insufficient history".

use serde::Serialize;
use statrs::distribution::{ContinuousCDF, StudentsT};

/// A feature's band at an event's amplitude.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FeatureBand {
    pub predicted: f64,
    pub lower: f64,
    pub upper: f64,
    /// Earlier events the band was fitted on.
    pub events: usize,
}

impl FeatureBand {
    pub fn contains(&self, y: f64) -> bool {
        (self.lower..=self.upper).contains(&y)
    }
}

/// An event's verdict.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "state", rename_all = "snake_case")]
pub enum Verdict {
    /// Fewer earlier events than the bands need.
    InsufficientHistory { events: usize, needed: usize },
    /// Every feature inside its band.
    Normal,
    /// The features (indices) outside their bands.
    Alarm { features: Vec<usize> },
}

impl Verdict {
    pub fn name(&self) -> &'static str {
        match self {
            Self::InsufficientHistory { .. } => "insufficient history",
            Self::Normal => "normal",
            Self::Alarm { .. } => "alarm",
        }
    }
}

/// The least-squares line `y = ȳ + b (x − x̄)` of a feature's earlier
/// `(x, y)` pairs (non-finite ones left out); `b = 0` (a constant) with fewer
/// than `sloped_from` pairs or when they span too little amplitude.
struct AmplitudeLine {
    n: usize,
    mean_x: f64,
    mean_y: f64,
    sxx: f64,
    slope: f64,
    sloped: bool,
    sse: f64,
}

impl AmplitudeLine {
    fn fit(history: &[(f64, f64)], sloped_from: usize) -> Option<Self> {
        let pairs: Vec<(f64, f64)> = history
            .iter()
            .copied()
            .filter(|(a, y)| a.is_finite() && y.is_finite())
            .collect();
        let n = pairs.len();
        if n == 0 {
            return None;
        }
        let nf = n as f64;
        let mean_x = pairs.iter().map(|p| p.0).sum::<f64>() / nf;
        let mean_y = pairs.iter().map(|p| p.1).sum::<f64>() / nf;
        let sxx: f64 = pairs.iter().map(|p| (p.0 - mean_x).powi(2)).sum();
        let sloped = n >= sloped_from.max(3) && sxx > 1e-6;
        let slope = if sloped {
            pairs.iter().map(|p| (p.0 - mean_x) * (p.1 - mean_y)).sum::<f64>() / sxx
        } else {
            0.0
        };
        let sse = pairs
            .iter()
            .map(|p| (p.1 - mean_y - slope * (p.0 - mean_x)).powi(2))
            .sum();
        Some(Self {
            n,
            mean_x,
            mean_y,
            sxx,
            slope,
            sloped,
            sse,
        })
    }

    fn at(&self, x: f64) -> f64 {
        self.mean_y + self.slope * (x - self.mean_x)
    }
}

/// The band of a feature at amplitude `x` (log10 of the peak acceleration)
/// from earlier `(x, y)` pairs (non-finite ones left out), at two-sided
/// level `alpha`; `None` with fewer than two usable pairs.
pub fn band(history: &[(f64, f64)], x: f64, alpha: f64) -> Option<FeatureBand> {
    if !(alpha > 0.0 && alpha < 1.0 && x.is_finite()) {
        return None;
    }
    let line = AmplitudeLine::fit(history, 3).filter(|l| l.n >= 2)?;
    let nf = line.n as f64;
    let dof = if line.sloped { nf - 2.0 } else { nf - 1.0 };
    let s = (line.sse / dof).sqrt();
    let predicted = line.at(x);
    let leverage = if line.sloped {
        (x - line.mean_x).powi(2) / line.sxx
    } else {
        0.0
    };
    let t = StudentsT::new(0.0, 1.0, dof).ok()?.inverse_cdf(1.0 - alpha / 2.0);
    let half = t * s * (1.0 + 1.0 / nf + leverage).sqrt();
    Some(FeatureBand {
        predicted,
        lower: predicted - half,
        upper: predicted + half,
        events: line.n,
    })
}

/// What the earlier `(x, y)` pairs (non-finite ones left out) expect of a
/// feature at amplitude `x`: their least-squares line once there are
/// `sloped_from` of them (at least three, spanning some amplitude), their
/// mean before; `None` without one. The centre of [`band`] when
/// `sloped_from ≤ 3`.
pub fn expected(history: &[(f64, f64)], x: f64, sloped_from: usize) -> Option<f64> {
    let line = AmplitudeLine::fit(history, sloped_from)?;
    x.is_finite().then(|| line.at(x))
}

/// The verdict on an event with amplitude `x` and `features` (non-finite:
/// not measured this time, not judged), from the earlier events'
/// amplitudes `history_x` and features `history` (one row per event); the
/// per-event false-alarm rate `alpha` is shared by the features judged.
pub fn judge(
    history_x: &[f64],
    history: &[Vec<f64>],
    x: f64,
    features: &[f64],
    alpha: f64,
    min_events: usize,
) -> (Verdict, Vec<Option<FeatureBand>>) {
    if history_x.len() < min_events.max(2) {
        let verdict = Verdict::InsufficientHistory {
            events: history_x.len(),
            needed: min_events.max(2),
        };
        return (verdict, vec![None; features.len()]);
    }
    let judged = features.iter().filter(|y| y.is_finite()).count().max(1);
    let per_feature = alpha / judged as f64;
    let bands: Vec<Option<FeatureBand>> = (0..features.len())
        .map(|f| {
            if !features[f].is_finite() {
                return None;
            }
            let pairs: Vec<(f64, f64)> = history_x
                .iter()
                .zip(history)
                .map(|(&a, row)| (a, row.get(f).copied().unwrap_or(f64::NAN)))
                .collect();
            band(&pairs, x, per_feature).filter(|b| b.events >= min_events.max(2))
        })
        .collect();
    let outside: Vec<usize> = bands
        .iter()
        .enumerate()
        .filter_map(|(f, b)| b.filter(|b| !b.contains(features[f])).map(|_| f))
        .collect();
    let verdict = if outside.is_empty() {
        Verdict::Normal
    } else {
        Verdict::Alarm { features: outside }
    };
    (verdict, bands)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On exact straight-line data the band is the line (zero scatter).
    #[test]
    fn a_straight_line_is_predicted_exactly() {
        let history: Vec<(f64, f64)> = (0..6).map(|k| (k as f64 * 0.2, 3.8 - 0.1 * k as f64 * 0.2)).collect();
        let b = band(&history, 2.0, 0.01).unwrap();
        assert!((b.predicted - (3.8 - 0.2)).abs() < 1e-12, "{b:?}");
        assert!((b.upper - b.lower).abs() < 1e-9, "{b:?}");
    }

    /// The interval's coverage over many simulated histories is its level
    /// (a closed form: the t-distribution of the prediction error).
    #[test]
    fn the_prediction_interval_covers_at_its_level() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut uniform = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut normal = move || {
            let (u1, u2) = (uniform().max(1e-300), uniform());
            (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
        };
        let (trials, alpha) = (20_000, 0.1);
        let mut misses = 0;
        for t in 0..trials {
            let history: Vec<(f64, f64)> = (0..8)
                .map(|k| {
                    let x = -2.0 + 0.2 * k as f64 + 0.05 * (t % 3) as f64;
                    (x, 3.8 - 0.2 * x + 0.05 * normal())
                })
                .collect();
            let x = -0.5;
            let y = 3.8 - 0.2 * x + 0.05 * normal();
            if !band(&history, x, alpha).unwrap().contains(y) {
                misses += 1;
            }
        }
        let rate = misses as f64 / trials as f64;
        // Binomial standard error at 20 000 trials: 0.002.
        assert!((rate - alpha).abs() < 0.01, "miss rate {rate}");
    }

    /// The expectation is the band's centre; before `sloped_from` events
    /// it is their mean, with one event that event.
    #[test]
    fn the_expectation_is_the_mean_until_enough_events_then_the_line() {
        let history: Vec<(f64, f64)> = (0..6).map(|k| (k as f64 * 0.2, 3.8 - 0.1 * k as f64 * 0.2)).collect();
        assert_eq!(expected(&[], 0.5, 5), None);
        assert_eq!(expected(&history[..1], 0.5, 5), Some(3.8));
        let mean = history[..4].iter().map(|p| p.1).sum::<f64>() / 4.0;
        assert!((expected(&history[..4], 2.0, 5).unwrap() - mean).abs() < 1e-12);
        let line = expected(&history, 2.0, 5).unwrap();
        assert!((line - (3.8 - 0.2)).abs() < 1e-12, "{line}");
        assert!((line - band(&history, 2.0, 0.01).unwrap().predicted).abs() < 1e-12);
        // A missing value is left out, not taken as zero.
        let mut gaps = history.clone();
        gaps.push((3.0, f64::NAN));
        assert_eq!(expected(&gaps, 2.0, 5), expected(&history, 2.0, 5));
    }

    #[test]
    fn too_few_events_give_no_verdict_and_an_outlier_an_alarm() {
        let xs = [-1.0, -0.8, -0.6];
        let rows: Vec<Vec<f64>> = xs.iter().map(|_| vec![3.8, 1.0]).collect();
        let (v, _) = judge(&xs, &rows, -0.7, &[3.8, 1.0], 0.01, 5);
        assert_eq!(v, Verdict::InsufficientHistory { events: 3, needed: 5 });
        let xs = [-1.0, -0.9, -0.8, -0.7, -0.6, -0.5];
        let rows: Vec<Vec<f64>> = xs
            .iter()
            .enumerate()
            .map(|(k, x)| vec![3.8 - 0.2 * x + 0.01 * (k % 2) as f64, 1.0 + 0.01 * (k % 3) as f64])
            .collect();
        let (v, bands) = judge(&xs, &rows, -0.75, &[3.95, 1.01], 0.01, 5);
        assert_eq!(v, Verdict::Normal, "{bands:?}");
        let (v, _) = judge(&xs, &rows, -0.75, &[3.5, 1.01], 0.01, 5);
        assert_eq!(v, Verdict::Alarm { features: vec![0] });
        // A feature not measured this time is not judged.
        let (v, bands) = judge(&xs, &rows, -0.75, &[f64::NAN, 1.01], 0.01, 5);
        assert_eq!(v, Verdict::Normal);
        assert!(bands[0].is_none());
    }
}
