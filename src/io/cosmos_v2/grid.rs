//! A station's channels on one time grid.

use super::{error, V2Channel};
use crate::io::import::{ImportError, ImportedChannel, ImportedSeries};
use crate::io::wire::ChannelQuantity;
use splinewatch_core::identification::resample::fourier_resample;

/// The channels on one grid. Channels of several recorders may differ in
/// rate, start and length: the grid is the lowest rate over the span all
/// channels cover (from the latest start to the earliest end; channels
/// without a start time must all lack one and then start together). Each
/// channel is cut to that span at its own nearest sample (an offset below
/// half a sample of its own rate stays) and, when its rate differs,
/// resampled to the grid by Fourier interpolation over the span (the
/// spectrum truncated at the new Nyquist frequency or padded with zeros, as
/// `scipy.signal.resample`), which is exact for a band-limited periodic
/// signal and low-pass filters a channel brought down.
pub(super) fn to_series(channels: Vec<V2Channel>) -> Result<ImportedSeries, ImportError> {
    let first = &channels[0];
    if let Some(c) = channels
        .iter()
        .find(|c| c.start_ns.is_some() != first.start_ns.is_some())
    {
        let (with, without) = if c.start_ns.is_some() { (c, first) } else { (first, c) };
        return Err(error(
            &without.file,
            format!(
                "channel {} has no record start time (\"Rcrd of …\" in UTC or PST/PDT) but channel {} of {} has one: the channels cannot be put on one time line",
                without.number, with.number, with.file
            ),
        ));
    }
    let dt = channels.iter().map(|c| c.time_step).fold(0.0, f64::max);
    let span_start = channels.iter().filter_map(|c| c.start_ns).max();
    // Times in seconds from the span's start (absolute seconds since 1970 in
    // an f64 would round off a sample's fraction and lose the last one).
    let start = |c: &V2Channel| (c.start_ns.unwrap_or(0) - span_start.unwrap_or(0)) as f64 * 1e-9;
    let end = |c: &V2Channel| start(c) + c.values.len() as f64 * c.time_step;
    let span_end = channels.iter().map(end).fold(f64::INFINITY, f64::min);
    let points = (span_end / dt + 1e-6).floor();
    if points.is_nan() || points < 2.0 {
        let (a, b) = (
            channels.iter().max_by_key(|c| c.start_ns).unwrap_or(first),
            channels
                .iter()
                .min_by(|a, b| end(a).total_cmp(&end(b)))
                .unwrap_or(first),
        );
        return Err(error(
            &a.file,
            format!(
                "channel {} starts after channel {} of {} ends: the channels share no time span",
                a.number, b.number, b.file
            ),
        ));
    }
    let points = points as usize;
    let seconds = points as f64 * dt;
    let cut: Vec<&V2Channel> = channels
        .iter()
        .filter(|c| end(c) - seconds >= 0.999 * c.time_step || -start(c) >= 0.999 * c.time_step)
        .collect();
    let notes = cut_note(&cut, seconds);
    let columns = channels
        .into_iter()
        .map(|c| {
            let skip = (-start(&c) / c.time_step).round().max(0.0) as usize;
            let own = ((points as f64 * dt / c.time_step).round() as usize).min(c.values.len() - skip);
            let cut = &c.values[skip..skip + own];
            let data = if (c.time_step - dt).abs() <= 1e-9 * dt {
                cut[..points.min(cut.len())].to_vec()
            } else {
                fourier_resample(cut, points)
            };
            ImportedChannel {
                name: format!("ch{}", c.number),
                unit: Some(c.unit),
                quantity: Some(ChannelQuantity::Acceleration),
                data,
            }
        })
        .collect();
    Ok(ImportedSeries {
        fs: Some(1.0 / dt),
        start_ns: span_start,
        offset_seconds: 0.0,
        channels: columns,
        notes,
    })
}

/// A sentence naming the channels `cut` (each holds a sample or more
/// outside the `seconds` all channels share), if any: the data the grid
/// leaves out.
pub(super) fn cut_note(cut: &[&V2Channel], seconds: f64) -> Vec<String> {
    if cut.is_empty() {
        return Vec::new();
    }
    let named: Vec<String> = cut
        .iter()
        .map(|c| format!("ch{} ({:.2} s)", c.number, c.values.len() as f64 * c.time_step))
        .collect();
    vec![format!(
        "the channels share {seconds:.2} s: {} cut to it (the record's other channels are shorter or start later)",
        named.join(", ")
    )]
}
