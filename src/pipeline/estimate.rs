//! FRF estimation from recorded blocks: per-channel time alignment, Welch
//! cross spectra, estimator and quantity conversion, FRF JSON out.

use crate::config::Config;
use crate::io::frf_json::{FrfEntry, FrfFile};
use crate::io::recording::RecordedBlock;
use crate::io::wire::{format_timestamp, ChannelQuantity};
use anyhow::{bail, Result};
use splinewatch_core::c64;
use splinewatch_core::identification::welch::{FrfEstimate, SegmentCounts, WelchEstimator};
use splinewatch_core::response::frf::Quantity;
use std::collections::BTreeMap;
use std::f64::consts::PI;

/// One channel's samples on a regular grid.
#[derive(Debug, Clone)]
pub struct ContinuousChannel {
    pub start_ns: i128,
    pub fs: f64,
    pub data: Vec<f64>,
}

/// What the estimate used.
#[derive(Debug, Clone)]
pub struct EstimateReport {
    pub frf: FrfFile,
    pub segments: SegmentCounts,
    pub start_ns: i128,
    pub samples: usize,
    pub effective_averages: f64,
}

/// Concatenates one channel's blocks, requiring a constant rate and no gaps
/// or overlaps (tolerance: half a sample).
pub fn concatenate(name: &str, quantity: ChannelQuantity, blocks: &[&RecordedBlock]) -> Result<ContinuousChannel> {
    let mut sorted: Vec<&RecordedBlock> = blocks.to_vec();
    sorted.sort_by_key(|b| b.block.start_ns);
    let Some(first) = sorted.first() else {
        bail!("no {quantity:?} data for channel {name:?}");
    };
    let fs = first.block.fs;
    let mut out = ContinuousChannel {
        start_ns: first.block.start_ns,
        fs,
        // Sized once: growing it block by block reallocated and copied a
        // 10-minute channel about twenty times (4 % of `oma`'s instructions).
        data: Vec::with_capacity(sorted.iter().map(|b| b.block.data.len()).sum()),
    };
    for b in sorted {
        if (b.block.fs - fs).abs() > 1e-9 * fs {
            bail!(
                "channel {name:?}: sample rate changes from {fs} Hz to {} Hz at {}",
                b.block.fs,
                format_timestamp(b.block.start_ns)
            );
        }
        let expected = out.start_ns + (out.data.len() as f64 * 1e9 / fs).round() as i128;
        let offset_samples = (b.block.start_ns - expected) as f64 * fs / 1e9;
        if offset_samples.abs() > 0.5 {
            let what = if offset_samples > 0.0 { "gap" } else { "overlap" };
            bail!(
                "channel {name:?}: {what} of {:.3} s at {} (expected {}); split the analysis around it with --from/--to",
                offset_samples.abs() / fs,
                format_timestamp(b.block.start_ns),
                format_timestamp(expected)
            );
        }
        out.data.extend_from_slice(&b.block.data);
    }
    Ok(out)
}

/// Estimates FRFs (force sensor → every acceleration sensor) over
/// `[from_ns, to_ns)` of the recording.
pub fn estimate(
    config: &Config,
    blocks: &[RecordedBlock],
    from_ns: Option<i128>,
    to_ns: Option<i128>,
) -> Result<EstimateReport> {
    let (force, accels) = config.channel_roles()?;
    let wanted: Vec<(usize, ChannelQuantity)> = std::iter::once((force, ChannelQuantity::Force))
        .chain(accels.iter().map(|&i| (i, ChannelQuantity::Acceleration)))
        .collect();
    let span = aligned_span(config, blocks, from_ns, to_ns, &wanted)?;
    let (start, samples, fs) = (span.start_ns, span.samples, span.fs);
    let (settings, estimator) = config.welch_settings(fs)?;
    if samples < settings.segment {
        bail!(
            "{samples} common samples are fewer than one Welch segment ({})",
            settings.segment
        );
    }
    let mut data = span.channels.into_iter();
    let f_data = data.next().expect("the force channel comes first");
    let x_data: Vec<Vec<f64>> = data.collect();
    let mut welch = WelchEstimator::new(settings, accels.len())?;
    let refs: Vec<&[f64]> = x_data.iter().map(|v| v.as_slice()).collect();
    welch.push(&f_data, &refs)?;
    let counts = welch.counts();
    if counts.accepted == 0 {
        bail!(
            "every Welch segment was rejected ({} non-finite, {} clipped, {} double impacts)",
            counts.non_finite,
            counts.clipped,
            counts.double_impact
        );
    }
    let spectra = welch.spectra();
    let est = spectra.frf(estimator);
    let frf = frf_file(config, &est, force, &accels)
        .ok_or_else(|| anyhow::anyhow!("no spectral line in frf.band {:?} Hz", config.frf.band))?;
    Ok(EstimateReport {
        frf,
        segments: counts,
        start_ns: start,
        samples,
        effective_averages: est.effective_averages,
    })
}

/// Channels cut to their common span on one sample grid.
#[derive(Debug, Clone)]
pub struct AlignedSpan {
    pub start_ns: i128,
    pub samples: usize,
    pub fs: f64,
    /// In the order asked for.
    pub channels: Vec<Vec<f64>>,
}

/// The channels `wanted` (sensor index into `[[sensors]]`, quantity), each
/// concatenated from the blocks overlapping `[from_ns, to_ns)`, on one
/// sampling rate, cut to their common span (snapped to the first channel's
/// grid).
pub fn aligned_span(
    config: &Config,
    blocks: &[RecordedBlock],
    from_ns: Option<i128>,
    to_ns: Option<i128>,
    wanted: &[(usize, ChannelQuantity)],
) -> Result<AlignedSpan> {
    let continuous = channels(config, blocks, from_ns, to_ns, wanted)?;
    let Some((start, samples)) = common_span(&continuous, from_ns, to_ns) else {
        bail!("the channels have no common time span in the requested interval");
    };
    let fs = continuous[0].fs;
    // Each channel cut in place (a second copy of a 10-minute window cost
    // as much as the first, most of it page faults).
    let cut = |c: ContinuousChannel| -> Result<Vec<f64>> {
        let k = (start - c.start_ns) as f64 * c.fs / 1e9;
        let r = k.round();
        if (k - r).abs() > 0.01 {
            bail!("channels are not sample-aligned (offset {:.3} samples)", k - r);
        }
        let mut data = c.data;
        data.drain(..r.max(0.0) as usize);
        data.truncate(samples);
        Ok(data)
    };
    Ok(AlignedSpan {
        start_ns: start,
        samples,
        fs,
        channels: continuous.into_iter().map(cut).collect::<Result<_>>()?,
    })
}

/// The `wanted` channels, each concatenated from the blocks overlapping
/// `[from_ns, to_ns)`, on one sampling rate.
fn channels(
    config: &Config,
    blocks: &[RecordedBlock],
    from_ns: Option<i128>,
    to_ns: Option<i128>,
    wanted: &[(usize, ChannelQuantity)],
) -> Result<Vec<ContinuousChannel>> {
    let names: Vec<&str> = config.sensors.iter().map(|s| s.name.as_str()).collect();
    let mut by_channel: BTreeMap<(String, ChannelQuantity), Vec<&RecordedBlock>> = BTreeMap::new();
    // Only blocks overlapping the requested span take part, so a gap outside
    // it does not matter.
    let overlaps = |b: &RecordedBlock| {
        let end = b.block.start_ns + (b.block.data.len() as f64 * 1e9 / b.block.fs).round() as i128;
        from_ns.is_none_or(|t| end > t) && to_ns.is_none_or(|t| b.block.start_ns < t)
    };
    for b in blocks.iter().filter(|b| overlaps(b)) {
        by_channel
            .entry((b.block.name.clone(), b.block.quantity))
            .or_default()
            .push(b);
    }
    let out: Vec<ContinuousChannel> = wanted
        .iter()
        .map(|&(i, q)| {
            let list = by_channel
                .get(&(names[i].to_string(), q))
                .map(|v| v.as_slice())
                .unwrap_or(&[]);
            concatenate(names[i], q, list)
        })
        .collect::<Result<_>>()?;
    let fs = out[0].fs;
    for (x, &(i, _)) in out.iter().zip(wanted) {
        if (x.fs - fs).abs() > 1e-9 * fs {
            bail!(
                "sample-rate mismatch: {} at {fs} Hz, {} at {} Hz",
                names[wanted[0].0],
                names[i],
                x.fs
            );
        }
    }
    Ok(out)
}

/// The channels' common span within `[from_ns, to_ns)`, its start snapped to
/// the first channel's grid: (start, samples); `None` if none is common.
fn common_span(channels: &[ContinuousChannel], from_ns: Option<i128>, to_ns: Option<i128>) -> Option<(i128, usize)> {
    let first = &channels[0];
    let fs = first.fs;
    let end = |c: &ContinuousChannel| c.start_ns + (c.data.len() as f64 * 1e9 / c.fs).round() as i128;
    let mut start = channels.iter().map(|c| c.start_ns).max()?;
    let mut stop = channels.iter().map(end).min()?;
    if let Some(t) = from_ns {
        start = start.max(t);
    }
    if let Some(t) = to_ns {
        stop = stop.min(t);
    }
    let k0 = ((start - first.start_ns) as f64 * fs / 1e9).ceil() as usize;
    let start = first.start_ns + (k0 as f64 * 1e9 / fs).round() as i128;
    (stop > start).then(|| (start, ((stop - start) as f64 * fs / 1e9).floor() as usize))
}

/// The FRF file of an estimate (input: the force sensor, outputs: the
/// acceleration sensors, by index into `[[sensors]]`): lines of `frf.band`
/// above 0 Hz, converted from accelerance to `frf.quantity`, with coherence
/// and effective averages. `None` if the band holds no line.
pub fn frf_file(config: &Config, est: &FrfEstimate, force: usize, accels: &[usize]) -> Option<FrfFile> {
    let [lo, hi] = config.frf.band;
    let lines: Vec<usize> = (0..est.frequencies.len())
        .filter(|&k| est.frequencies[k] > 0.0 && est.frequencies[k] >= lo && est.frequencies[k] <= hi)
        .collect();
    if lines.is_empty() {
        return None;
    }
    let quantity = config.frf.quantity;
    let convert = |a: c64, f_hz: f64| -> c64 {
        let w = 2.0 * PI * f_hz;
        match quantity {
            Quantity::Accelerance => a,
            Quantity::Mobility => a / c64::new(0.0, w),
            Quantity::Receptance => a / c64::new(-w * w, 0.0),
        }
    };
    let name = |i: usize| config.sensors[i].name.clone();
    let frfs = accels
        .iter()
        .enumerate()
        .map(|(o, &i)| {
            let h: Vec<c64> = lines
                .iter()
                .map(|&k| convert(est.h[o][k], est.frequencies[k]))
                .collect();
            FrfEntry {
                input: name(force),
                output: name(i),
                re: h.iter().map(|v| v.re).collect(),
                im: h.iter().map(|v| v.im).collect(),
                coherence: Some(lines.iter().map(|&k| est.coherence[o][k].clamp(0.0, 1.0)).collect()),
                n_averages: Some(est.effective_averages),
            }
        })
        .collect();
    Some(FrfFile {
        quantity,
        frequency_hz: lines.iter().map(|&k| est.frequencies[k]).collect(),
        frfs,
        start_timestamp: None,
        end_timestamp: None,
    })
}
