//! Output-only identification: of a span of recorded blocks (the `oma`
//! command: the acceleration channels aligned on one grid), and of one
//! pipeline window (with its modes paired to the model's); both run the
//! core's SSI-cov with the `[oma]` settings.

use super::estimate::aligned_span;
use crate::config::Config;
use crate::io::modes_json::{ModeEntry, ModesFile, ShapeEntry};
use crate::io::recording::RecordedBlock;
use crate::io::wire::{format_timestamp, ChannelQuantity};
use anyhow::{Context, Result};
use splinewatch_core::identification::oma::{
    identify, spectral_singular_values, OmaError, OmaResult, OmaSettings, OutputCorrelations, SpectralSingularValues,
};
use splinewatch_core::response::frf::ModalState;
use splinewatch_core::updating::modal_residual::pair_modes;

/// What one identification used and found.
#[derive(Debug, Clone)]
pub struct OmaReport {
    pub start_ns: i128,
    pub samples: usize,
    pub fs: f64,
    /// The acceleration sensors, in the order of the shapes.
    pub sensors: Vec<String>,
    pub result: OmaResult,
    /// Singular values of the output spectral matrix (the diagram's
    /// backdrop, for Rerun); `None` when not asked for or for a span
    /// shorter than one segment.
    pub spectrum: Option<SpectralSingularValues>,
}

/// Segments of the spectral matrix: 8 s (0.125 Hz lines, enough to part the
/// bundled deck's closest pair, 0.5 Hz apart).
const SPECTRUM_SEGMENT_SECONDS: f64 = 8.0;

fn spectrum(channels: &[&[f64]], fs: f64) -> Option<SpectralSingularValues> {
    spectral_singular_values(channels, fs, (SPECTRUM_SEGMENT_SECONDS * fs).round() as usize).ok()
}

/// Identifies the modes over `[from_ns, to_ns)` of the recording; with
/// `with_spectrum` also the spectral matrix's singular values (the
/// diagram's backdrop: 60 ms on a 10-minute, 12-channel window).
pub fn identify_span(
    config: &Config,
    blocks: &[RecordedBlock],
    from_ns: Option<i128>,
    to_ns: Option<i128>,
    with_spectrum: bool,
) -> Result<OmaReport> {
    let identification = Identification {
        with_spectrum,
        ..Identification::new(config)?
    };
    let outputs = config.output_channels()?;
    let wanted: Vec<(usize, ChannelQuantity)> = outputs.iter().map(|&i| (i, ChannelQuantity::Acceleration)).collect();
    let span = aligned_span(config, blocks, from_ns, to_ns, &wanted)?;
    identification
        .identify(&span.channels, span.start_ns, span.fs)
        .context("SSI-cov")
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
                method: None,
                model: None,
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

/// How the acceleration channels are identified (the `[oma]` settings and
/// the `[updating]` pairing): a recorded span, or a pipeline window.
#[derive(Debug, Clone)]
pub(super) struct Identification {
    pub(super) settings: OmaSettings,
    /// `[oma] horizon_seconds`: the block rows at each record's rate.
    horizon_seconds: Option<f64>,
    /// Reference channels (positions among the outputs).
    pub(super) references: Vec<usize>,
    /// The acceleration sensors, in channel order.
    pub(super) sensors: Vec<String>,
    /// Pairing: smallest MAC, largest relative frequency gap (`[updating]`).
    pub(super) min_mac: f64,
    pub(super) max_gap: f64,
    /// Whether reports carry the spectral singular values (only Rerun
    /// draws them; the pipeline's windows never do).
    pub(super) with_spectrum: bool,
}

/// The output-only identification of one window and the pairing of its
/// modes with the model's at the last accepted parameters.
#[derive(Debug, Clone)]
pub struct WindowModes {
    pub report: OmaReport,
    /// Per identified mode, its model mode, if one pairs.
    pub pairs: Vec<Option<ModelPair>>,
}

/// The model mode an identified mode pairs with (MAC ≥ `updating.min_mac`
/// within `updating.max_frequency_gap`, one model mode per identified one).
#[derive(Debug, Clone, PartialEq)]
pub struct ModelPair {
    /// Index into the model's modes (rigid, membrane and bending, ascending).
    pub model_mode: usize,
    pub model_frequency_hz: f64,
    pub mac: f64,
    /// The model mode at the identified mode's sensors (same order).
    pub model_shape: Vec<f64>,
}

impl Identification {
    pub(super) fn new(config: &Config) -> Result<Self> {
        let outputs = config.output_channels()?;
        let (settings, references) = config.oma_settings()?;
        Ok(Self {
            settings,
            horizon_seconds: config.oma().horizon_seconds,
            references,
            sensors: outputs.iter().map(|&i| config.sensors[i].name.clone()).collect(),
            min_mac: config.updating.min_mac,
            max_gap: config.updating.max_frequency_gap,
            with_spectrum: false,
        })
    }

    /// SSI-cov of `channels` (the acceleration sensors in order, sampled at
    /// `fs` from `start_ns`; NaN for missing samples).
    fn identify(&self, channels: &[Vec<f64>], start_ns: i128, fs: f64) -> Result<OmaReport, OmaError> {
        let views: Vec<&[f64]> = channels.iter().map(Vec::as_slice).collect();
        let mut settings = self.settings.clone();
        if let Some(seconds) = self.horizon_seconds {
            // Checked by the config: at least 2 rows at the configured rates.
            settings.block_rows = crate::config::horizon_rows(seconds, fs).max(2);
        }
        let correlations =
            OutputCorrelations::from_samples(&views, &self.references, settings.max_lag(), settings.batches)?;
        Ok(OmaReport {
            start_ns,
            samples: channels.first().map_or(0, Vec::len),
            fs,
            sensors: self.sensors.clone(),
            result: identify(&correlations, fs, &settings)?,
            spectrum: self.with_spectrum.then(|| spectrum(&views, fs)).flatten(),
        })
    }

    /// The identification alone (it needs no model); the error is the
    /// health reason.
    pub(super) fn identify_window(
        &self,
        channels: &[Vec<f64>],
        start_ns: i128,
        fs: f64,
    ) -> Result<OmaReport, &'static str> {
        self.identify(channels, start_ns, fs).map_err(|e| skip_reason(&e))
    }

    /// Pairs an identification's modes with `state`'s; the error is the
    /// health reason the window is skipped for.
    pub(super) fn pair(
        &self,
        report: OmaReport,
        state: &ModalState,
        sensor_names: &[String],
    ) -> Result<WindowModes, &'static str> {
        let observed = report
            .modes_file()
            .to_observed(sensor_names)
            .map_err(|_| "oma_failed")?;
        let mut pairs = vec![None; observed.len()];
        for p in pair_modes(state, &observed, self.min_mac, self.max_gap) {
            pairs[p.observed] = Some(ModelPair {
                model_mode: p.model,
                model_frequency_hz: state.modes.frequency_hz(p.model),
                mac: p.mac,
                model_shape: observed[p.observed]
                    .shape
                    .iter()
                    .map(|&(sensor, _)| state.amplitude(sensor, p.model))
                    .collect(),
            });
        }
        if pairs.iter().all(Option::is_none) {
            return Err("no_pairable_mode");
        }
        Ok(WindowModes { report, pairs })
    }
}

/// The health reason (`windows_skipped`) of a failed identification.
fn skip_reason(e: &OmaError) -> &'static str {
    match e {
        OmaError::TooShort { .. } | OmaError::TooFewLags { .. } => "too_little_data",
        OmaError::NoModes { .. } => "too_few_stable_poles",
        OmaError::SingularHankel { .. } => "singular_hankel",
        OmaError::SvdFailed | OmaError::EigenFailed { .. } => "oma_not_converged",
        _ => "oma_failed",
    }
}
