//! FRF estimation from recorded blocks: per-channel time alignment, Welch
//! cross spectra, estimator and quantity conversion, FRF JSON out.

use crate::config::Config;
use crate::io::frf_json::{FrfEntry, FrfFile};
use crate::io::recording::RecordedBlock;
use crate::io::wire::{format_timestamp, ChannelQuantity};
use anyhow::{bail, Result};
use splinewatch_core::c64;
use splinewatch_core::frf::Quantity;
use splinewatch_core::welch::{FrfEstimate, SegmentCounts, WelchEstimator};
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
        data: Vec::new(),
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
    let (f, xs) = channels(config, blocks, from_ns, to_ns, force, &accels)?;
    let fs = f.fs;
    let Some((start, samples)) = common_span(&f, &xs, from_ns, to_ns) else {
        bail!("the channels have no common time span in the requested interval");
    };
    let index = |c: &ContinuousChannel, t: i128| -> Result<usize> {
        let k = (t - c.start_ns) as f64 * c.fs / 1e9;
        let r = k.round();
        if (k - r).abs() > 0.01 {
            bail!("channels are not sample-aligned (offset {:.3} samples)", k - r);
        }
        Ok(r.max(0.0) as usize)
    };
    let (settings, estimator) = config.welch_settings(fs)?;
    if samples < settings.segment {
        bail!(
            "{samples} common samples are fewer than one Welch segment ({})",
            settings.segment
        );
    }
    let slice = |c: &ContinuousChannel| -> Result<Vec<f64>> {
        let a = index(c, start)?;
        Ok(c.data[a..a + samples].to_vec())
    };
    let f_data = slice(&f)?;
    let x_data: Vec<Vec<f64>> = xs.iter().map(slice).collect::<Result<_>>()?;
    let mut welch = WelchEstimator::new(settings, xs.len())?;
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

/// The force channel and the acceleration channels, each concatenated from
/// the blocks overlapping `[from_ns, to_ns)`, on one sampling rate.
fn channels(
    config: &Config,
    blocks: &[RecordedBlock],
    from_ns: Option<i128>,
    to_ns: Option<i128>,
    force: usize,
    accels: &[usize],
) -> Result<(ContinuousChannel, Vec<ContinuousChannel>)> {
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
    let channel = |name: &str, q: ChannelQuantity| -> Result<ContinuousChannel> {
        let list = by_channel
            .get(&(name.to_string(), q))
            .map(|v| v.as_slice())
            .unwrap_or(&[]);
        concatenate(name, q, list)
    };
    let f = channel(names[force], ChannelQuantity::Force)?;
    let xs: Vec<ContinuousChannel> = accels
        .iter()
        .map(|&i| channel(names[i], ChannelQuantity::Acceleration))
        .collect::<Result<_>>()?;
    let fs = f.fs;
    for (x, &i) in xs.iter().zip(accels) {
        if (x.fs - fs).abs() > 1e-9 * fs {
            bail!(
                "sample-rate mismatch: force {} at {fs} Hz, {} at {} Hz",
                names[force],
                names[i],
                x.fs
            );
        }
    }
    Ok((f, xs))
}

/// The channels' common span within `[from_ns, to_ns)`, its start snapped to
/// the force channel's grid: (start, samples); `None` if none is common.
fn common_span(
    f: &ContinuousChannel,
    xs: &[ContinuousChannel],
    from_ns: Option<i128>,
    to_ns: Option<i128>,
) -> Option<(i128, usize)> {
    let fs = f.fs;
    // Common span on the force channel's sample grid.
    let end = |c: &ContinuousChannel| c.start_ns + (c.data.len() as f64 * 1e9 / c.fs).round() as i128;
    let mut start = std::iter::once(f)
        .chain(xs)
        .map(|c| c.start_ns)
        .max()
        .expect("one channel");
    let mut stop = std::iter::once(f).chain(xs).map(end).min().expect("one channel");
    if let Some(t) = from_ns {
        start = start.max(t);
    }
    if let Some(t) = to_ns {
        stop = stop.min(t);
    }
    // Snap the start to the force grid.
    let k0 = ((start - f.start_ns) as f64 * fs / 1e9).ceil() as usize;
    let start = f.start_ns + (k0 as f64 * 1e9 / fs).round() as i128;
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
    })
}
