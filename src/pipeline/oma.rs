//! Output-only identification of a span of recorded blocks: the acceleration
//! channels aligned on one grid, then the core's SSI-cov (`[oma]` settings).

use super::estimate::aligned_span;
use crate::config::Config;
use crate::io::modes_json::{ModeEntry, ModesFile, ShapeEntry};
use crate::io::recording::RecordedBlock;
use crate::io::wire::{format_timestamp, ChannelQuantity};
use anyhow::{Context, Result};
use splinewatch_core::oma::{identify, OmaResult, OutputCorrelations};

/// What one identification used and found.
#[derive(Debug, Clone)]
pub struct OmaReport {
    pub start_ns: i128,
    pub samples: usize,
    pub fs: f64,
    /// The acceleration sensors, in the order of the shapes.
    pub sensors: Vec<String>,
    pub result: OmaResult,
}

/// Identifies the modes over `[from_ns, to_ns)` of the recording.
pub fn identify_span(
    config: &Config,
    blocks: &[RecordedBlock],
    from_ns: Option<i128>,
    to_ns: Option<i128>,
) -> Result<OmaReport> {
    let outputs = config.output_channels()?;
    let (settings, references) = config.oma_settings()?;
    let wanted: Vec<(usize, ChannelQuantity)> = outputs.iter().map(|&i| (i, ChannelQuantity::Acceleration)).collect();
    let span = aligned_span(config, blocks, from_ns, to_ns, &wanted)?;
    let views: Vec<&[f64]> = span.channels.iter().map(Vec::as_slice).collect();
    let correlations = OutputCorrelations::from_samples(&views, &references, settings.max_lag(), settings.batches)
        .context("output correlations")?;
    let result = identify(&correlations, span.fs, &settings).context("SSI-cov")?;
    Ok(OmaReport {
        start_ns: span.start_ns,
        samples: span.samples,
        fs: span.fs,
        sensors: outputs.iter().map(|&i| config.sensors[i].name.clone()).collect(),
        result,
    })
}

impl OmaReport {
    /// The modes file of this identification.
    pub fn modes_file(&self) -> ModesFile {
        let modes = self
            .result
            .modes
            .iter()
            .map(|m| ModeEntry {
                frequency_hz: m.frequency_hz,
                damping_ratio: m.damping_ratio,
                frequency_std_hz: m.frequency_std_hz,
                damping_std: m.damping_std,
                shape: m
                    .shape
                    .iter()
                    .enumerate()
                    .map(|(s, v)| ShapeEntry {
                        sensor: self.sensors[s].clone(),
                        re: v.re,
                        im: v.im,
                        std: m.shape_std.as_ref().map(|d| d[s]),
                    })
                    .collect(),
                mpc: Some(m.mpc),
                order: Some(m.order),
                stable_orders: Some(m.stable_orders),
            })
            .collect();
        ModesFile {
            modes,
            start: Some(format_timestamp(self.start_ns)),
            duration_s: Some(self.samples as f64 / self.fs),
            fs_hz: Some(self.fs),
        }
    }
}
