//! `splinewatch predict`: the model driven by a record's ground channels,
//! scored against the deck channels measured in the same record.
//!
//! Per deck channel: the NRMSE (rms of predicted − measured over the rms
//! measured), the correlation coefficient and the ratio of peaks (predicted
//! over measured), over the whole record and the NRMSE over its strong-motion
//! part: the span holding 5–95 % of the ground's energy (Trifunac & Brady
//! 1975's significant duration, on the sum of the squared ground
//! accelerations of every ground sensor). The baseline a skeptic asks for is
//! scored beside it: the deck moving with its nearest ground (the ground
//! input of the support group whose bearings lie nearest to the sensor, along
//! the sensor's direction; the mean of every group's when no bearing places
//! them).

use super::ground_motion::GroundModel;
use crate::config::{Config, GroundInputPlan};
use serde::Serialize;

/// One deck channel's figures.
#[derive(Debug, Clone, Serialize)]
pub struct ChannelScore {
    pub sensor: String,
    pub nrmse: f64,
    pub nrmse_strong: f64,
    pub correlation: f64,
    pub peak_ratio: f64,
}

/// What `predict --json` prints.
#[derive(Debug, Clone, Serialize)]
pub struct PredictionReport {
    /// The record's first sample (RFC 3339), set by the caller that knows it.
    pub start: Option<String>,
    pub channels: Vec<ChannelScore>,
    pub strong_span_s: [f64; 2],
    /// "deck = nearest ground": the same figures of the baseline, with the
    /// ground input each channel took.
    pub baseline: Vec<BaselineScore>,
    pub record_seconds: f64,
    pub fs: f64,
    /// The largest absolute ground acceleration over every ground sensor, m/s².
    pub pga_ground: f64,
    /// The largest absolute deck acceleration over the deck channels scored, m/s².
    pub peak_deck: f64,
}

#[derive(Debug, Clone, Serialize)]
pub struct BaselineScore {
    #[serde(flatten)]
    pub score: ChannelScore,
    /// The ground input(s) the channel was taken to move with.
    pub ground: String,
}

/// The measured and predicted series behind a report.
pub struct Prediction {
    pub report: PredictionReport,
    /// Deck sensors scored (config indices) and their series.
    pub sensors: Vec<usize>,
    pub measured: Vec<Vec<f64>>,
    pub predicted: Vec<Vec<f64>>,
    pub baseline: Vec<Vec<f64>>,
}

/// Drives `model` with the ground sensors' series and scores the deck
/// sensors `deck` (config indices, each with its measured series).
/// `channel(i)` gives config sensor `i`'s samples (ground sensors included).
pub fn predict<'a>(
    config: &Config,
    model: &GroundModel,
    deck: &[usize],
    channel: impl Fn(usize) -> &'a [f64] + Copy,
    fs: f64,
) -> Prediction {
    let predicted_all = model.respond(channel, fs);
    let predicted: Vec<Vec<f64>> = deck.iter().map(|&s| predicted_all[s].clone()).collect();
    let grounds = GroundsOf {
        plan: &model.plan,
        anchors: &model.anchors,
    };
    score_forecast(config, &grounds, deck, channel, fs, predicted)
}

/// The ground inputs a forecast was driven by, and where each support
/// group holds the structure (none known without a model): the baseline's
/// "nearest ground".
pub struct GroundsOf<'p> {
    pub plan: &'p [GroundInputPlan],
    pub anchors: &'p [(String, Option<[f64; 3]>)],
}

/// Scores `predicted` (one series per sensor of `deck`, config indices)
/// against the deck's measured series, beside the "deck = nearest ground"
/// baseline of `grounds`: a model's forecast ([`predict`]) or a
/// realization's.
pub fn score_forecast<'a>(
    config: &Config,
    grounds: &GroundsOf<'_>,
    deck: &[usize],
    channel: impl Fn(usize) -> &'a [f64] + Copy,
    fs: f64,
    predicted: Vec<Vec<f64>>,
) -> Prediction {
    let ground_sensors = crate::config::ground_sensors(grounds.plan);
    let samples = channel(ground_sensors[0]).len();
    let (i0, i1) = significant_span(ground_sensors.iter().map(|&i| channel(i)), samples);
    let inputs = crate::config::ground_signals(grounds.plan, channel);
    let mut report = PredictionReport {
        start: None,
        channels: Vec::new(),
        strong_span_s: [i0 as f64 / fs, i1 as f64 / fs],
        baseline: Vec::new(),
        record_seconds: samples as f64 / fs,
        fs,
        pga_ground: ground_sensors.iter().map(|&i| peak(channel(i))).fold(0.0, f64::max),
        peak_deck: deck.iter().map(|&i| peak(channel(i))).fold(0.0, f64::max),
    };
    let (mut measured, mut baseline) = (Vec::new(), Vec::new());
    for (&s, p) in deck.iter().zip(&predicted) {
        let name = &config.sensors[s].name;
        let m = channel(s);
        report.channels.push(score(name, m, p, (i0, i1)));
        let (ground, b) = nearest_ground(config, grounds, s, &inputs);
        report.baseline.push(BaselineScore {
            score: score(name, m, &b, (i0, i1)),
            ground,
        });
        measured.push(m.to_vec());
        baseline.push(b);
    }
    Prediction {
        report,
        sensors: deck.to_vec(),
        measured,
        predicted,
        baseline,
    }
}

fn peak(x: &[f64]) -> f64 {
    x.iter().fold(0.0f64, |a, v| a.max(v.abs()))
}

/// The figures of `p` against `m`, the NRMSE also over `strong` samples.
pub fn score(sensor: &str, m: &[f64], p: &[f64], strong: (usize, usize)) -> ChannelScore {
    let rms = |x: &[f64]| (x.iter().map(|v| v * v).sum::<f64>() / x.len().max(1) as f64).sqrt();
    let nrmse = |a: &[f64], b: &[f64]| {
        let d: Vec<f64> = a.iter().zip(b).map(|(x, y)| x - y).collect();
        rms(&d) / rms(b)
    };
    let (s0, s1) = strong;
    ChannelScore {
        sensor: sensor.to_string(),
        nrmse: nrmse(p, m),
        nrmse_strong: nrmse(&p[s0..s1], &m[s0..s1]),
        correlation: correlation(p, m),
        peak_ratio: peak(p) / peak(m),
    }
}

fn correlation(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len() as f64;
    let (ma, mb) = (a.iter().sum::<f64>() / n, b.iter().sum::<f64>() / n);
    let (mut ab, mut aa, mut bb) = (0.0, 0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        ab += (x - ma) * (y - mb);
        aa += (x - ma) * (x - ma);
        bb += (y - mb) * (y - mb);
    }
    ab / (aa * bb).sqrt()
}

/// The samples `[i0, i1)` between 5 % and 95 % of the cumulative energy
/// `Σ_channels a²` (the whole record if it has none).
pub fn significant_span<'a>(channels: impl Iterator<Item = &'a [f64]>, samples: usize) -> (usize, usize) {
    let mut energy = vec![0.0; samples];
    for c in channels {
        for (e, v) in energy.iter_mut().zip(c) {
            *e += v * v;
        }
    }
    let total: f64 = energy.iter().sum();
    if total.is_nan() || total <= 0.0 {
        return (0, samples);
    }
    let (mut acc, mut i0, mut i1) = (0.0, 0, samples);
    for (k, e) in energy.iter().enumerate() {
        let before = acc;
        acc += e;
        if before < 0.05 * total && acc >= 0.05 * total {
            i0 = k;
        }
        if before < 0.95 * total && acc >= 0.95 * total {
            i1 = k + 1;
        }
    }
    (i0, i1.max(i0 + 1))
}

/// The baseline series of deck sensor `s`: the ground input (along the
/// sensor's direction) of the group whose supports (bearings, line
/// supports, column bases) lie nearest.
fn nearest_ground(config: &Config, grounds: &GroundsOf<'_>, s: usize, inputs: &[Vec<f64>]) -> (String, Vec<f64>) {
    let sensor = &config.sensors[s];
    let direction = sensor.direction.unit_vector();
    let group_of = |name: &str| name.rsplit_once('.').map_or(name, |(g, _)| g).to_string();
    let mut groups: Vec<String> = Vec::new();
    for g in grounds.plan.iter().map(|p| group_of(&p.name)) {
        if !groups.contains(&g) {
            groups.push(g);
        }
    }
    let position = match (sensor.x, sensor.y, sensor.z) {
        (Some(x), Some(y), z) => Some([x, y, z.unwrap_or(0.0)]),
        _ => None,
    };
    let centroid = |group: &str| -> Option<[f64; 3]> {
        grounds
            .anchors
            .iter()
            .find(|(name, _)| name == group)
            .and_then(|(_, at)| *at)
    };
    let nearest = position.and_then(|p| {
        groups
            .iter()
            .filter_map(|g| centroid(g).map(|c| (g, (0..3).map(|d| (c[d] - p[d]).powi(2)).sum::<f64>())))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(g, _)| g.clone())
    });
    let chosen: Vec<String> = match nearest {
        Some(g) => vec![g],
        None => groups.clone(),
    };
    let samples = inputs.first().map_or(0, Vec::len);
    let mut out = vec![0.0; samples];
    let mut used = Vec::new();
    for (k, p) in grounds.plan.iter().enumerate() {
        let weight = direction[p.input.axis];
        if weight == 0.0 || !chosen.contains(&group_of(&p.name)) {
            continue;
        }
        used.push(p.name.clone());
        for (o, v) in out.iter_mut().zip(&inputs[k]) {
            *o += weight * v / chosen.len() as f64;
        }
    }
    (used.join(" + "), out)
}
