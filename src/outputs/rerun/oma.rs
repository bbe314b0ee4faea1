//! Output-only identifications in the Rerun stream: the stabilisation
//! diagram (every pole at its order over frequency; grey unstable, blue
//! stable, orange in a mode) over the first singular value of the output
//! spectral matrix, the Hankel matrix's leading singular values, the identified frequencies and damping ratios with ±1σ
//! (and those of the modes fitted in the frequency domain, with their lines on the diagram); per
//! pipeline window also the trends by paired model mode and the identified
//! and model shapes at the sensors.

use super::update::log_band;
use super::{rerun_error, saved_recording, set_measurement_time, RerunOutput};
use crate::io::modes_json::ModeEntry;
use crate::pipeline::oma::OmaReport;
use crate::pipeline::{WindowModes, WindowReport};
use anyhow::{anyhow, Result};
use rerun::blueprint::{BarChartView, Blueprint, Horizontal, Spatial2DView, TimeSeriesView, Vertical};
use std::collections::BTreeSet;
use std::path::Path;

impl RerunOutput {
    /// Logs `report` at its span's start time.
    pub fn log_oma(&mut self, report: &OmaReport) -> Result<()> {
        self.set_time(report.start_ns);
        self.log_identification(report)
    }

    /// Logs the modes fitted in the frequency domain (`[oma.frequency_domain]`)
    /// beside `report`'s, at its span's start time: each a vertical line on
    /// the stabilisation diagram (±1σ paler) and its frequency and damping
    /// under `oma/fitted/<k>`.
    pub fn log_fitted(&mut self, report: &OmaReport, fitted: &[ModeEntry]) -> Result<()> {
        self.set_time(report.start_ns);
        log_fitted(&self.rec, &mut self.named, report, fitted)
    }

    /// Logs an output-only window's identification at the window's end (FRF
    /// windows and skipped windows log nothing here).
    pub fn log_window(&mut self, window: &WindowReport) -> Result<()> {
        let Some(modes) = &window.modes else {
            return Ok(());
        };
        self.rotate_if_due(window.end_ns)?;
        self.set_time(window.end_ns);
        self.log_identification(&modes.report)?;
        self.log_trends(modes)?;
        self.log_shapes(modes)
    }

    /// Frequency and damping (value, ±1σ) of each paired mode, by model mode.
    fn log_trends(&mut self, modes: &WindowModes) -> Result<()> {
        for (m, pair) in modes.report.result.modes.iter().zip(&modes.pairs) {
            let Some(pair) = pair else { continue };
            self.log_frequency_and_damping(
                &format!("oma/trends/mode_{}", pair.model_mode + 1),
                (m.frequency_hz, m.frequency_std_hz),
                (m.damping_ratio, m.damping_std),
            )?;
        }
        Ok(())
    }

    /// Identified (real part; the shape is normalised to a largest component
    /// of 1 + 0i) and model shapes (least-squares scaled to it) as arrows at
    /// the sensors, along each sensor's direction.
    fn log_shapes(&self, modes: &WindowModes) -> Result<()> {
        let sensors: Vec<_> = modes
            .report
            .sensors
            .iter()
            .map(|name| self.sensors.iter().find(|(n, _)| n == name).map(|(_, s)| s))
            .collect();
        for (m, pair) in modes.report.result.modes.iter().zip(&modes.pairs) {
            let Some(pair) = pair else { continue };
            let identified: Vec<f64> = m.shape.iter().map(|v| v.re).collect();
            let mm: f64 = pair.model_shape.iter().map(|v| v * v).sum();
            let scale = identified
                .iter()
                .zip(&pair.model_shape)
                .map(|(a, b)| a * b)
                .sum::<f64>()
                / mm.max(f64::MIN_POSITIVE);
            let model: Vec<f64> = pair.model_shape.iter().map(|v| scale * v).collect();
            let length = 0.1 * self.grid.span;
            for (which, values, color) in [
                ("identified", &identified, rerun::Color::from_rgb(230, 120, 20)),
                ("model", &model, rerun::Color::from_rgb(30, 110, 200)),
            ] {
                let (origins, vectors): (Vec<[f32; 3]>, Vec<[f32; 3]>) = sensors
                    .iter()
                    .zip(values)
                    .filter_map(|(s, v)| s.map(|s| (s, v)))
                    .map(|(s, v)| {
                        let d = s.direction();
                        (
                            super::deck::sensor_position(&self.model, s),
                            [
                                (length * v * d[0]) as f32,
                                (length * v * d[1]) as f32,
                                (length * v * d[2]) as f32,
                            ],
                        )
                    })
                    .unzip();
                self.rec
                    .log(
                        format!("oma/shapes/mode_{}/{which}", pair.model_mode + 1).as_str(),
                        &rerun::Arrows3D::from_vectors(vectors)
                            .with_origins(origins)
                            .with_colors([color]),
                    )
                    .map_err(rerun_error)?;
            }
        }
        Ok(())
    }

    fn log_identification(&mut self, report: &OmaReport) -> Result<()> {
        log_identification(&self.rec, &mut self.named, report)
    }

    fn log_frequency_and_damping(
        &mut self,
        base: &str,
        frequency: (f64, Option<f64>),
        damping: (f64, Option<f64>),
    ) -> Result<()> {
        log_frequency_and_damping(&self.rec, &mut self.named, base, frequency, damping)
    }
}

/// An identification alone, for a config without a `[model]` (`identify`
/// or `oma --rerun-save` on a station's starter config): the stabilisation
/// diagram over the first singular value, the Hankel matrix's singular
/// values and the modes with ±1σ (and the fitted ones), no deck and no
/// model views.
pub struct IdentificationFile {
    rec: rerun::RecordingStream,
    named: BTreeSet<String>,
}

impl IdentificationFile {
    /// A recording saved to `path`, with its layout.
    pub fn save(path: &Path) -> Result<Self> {
        let layout = Blueprint::new(Horizontal::new([
            Spatial2DView::new("Stabilisation diagram (order × Hz) over the spectral matrix's first singular value")
                .with_origin("/oma/stabilisation")
                .into(),
            Vertical::new([
                TimeSeriesView::new("Identified modes: frequency (Hz) and damping (%), ±1σ")
                    .with_origin("/oma")
                    .with_contents(["/oma/modes/**", "/oma/fitted/**"])
                    .into(),
                BarChartView::new("Hankel matrix's singular values")
                    .with_origin("/oma/singular_values")
                    .into(),
            ])
            .into(),
        ]));
        Ok(Self {
            rec: saved_recording(path, &layout)?,
            named: BTreeSet::new(),
        })
    }

    /// Logs `report` and the modes fitted beside it at its span's start.
    pub fn log(&mut self, report: &OmaReport, fitted: &[ModeEntry]) -> Result<()> {
        set_measurement_time(&self.rec, report.start_ns);
        log_identification(&self.rec, &mut self.named, report)?;
        log_fitted(&self.rec, &mut self.named, report, fitted)
    }

    /// Flushes and closes the recording (the `.rrd` gets its footer).
    pub fn close(self) -> Result<()> {
        self.rec
            .flush_blocking()
            .map_err(|e| anyhow!("flushing the Rerun output: {e}"))
    }
}

/// The diagram, singular values and modes of one identification on `rec`,
/// at the time already set.
fn log_identification(rec: &rerun::RecordingStream, named: &mut BTreeSet<String>, report: &OmaReport) -> Result<()> {
    let poles = &report.result.diagram;
    let positions: Vec<[f32; 2]> = poles.iter().map(|p| [p.frequency_hz as f32, p.order as f32]).collect();
    let colors: Vec<rerun::Color> = poles
        .iter()
        .map(|p| match (p.mode, p.stable) {
            (Some(_), _) => rerun::Color::from_rgb(230, 120, 20),
            (None, true) => rerun::Color::from_rgb(30, 110, 200),
            (None, false) => rerun::Color::from_rgb(170, 170, 170),
        })
        .collect();
    rec.log(
        "oma/stabilisation",
        &rerun::Points2D::new(positions)
            .with_colors(colors)
            .with_radii([rerun::Radius::new_ui_points(2.0)]),
    )
    .map_err(rerun_error)?;
    if let Some(line) = first_singular_value_line(report) {
        rec.log(
            "oma/stabilisation/first_singular_value",
            &rerun::LineStrips2D::new([line]).with_colors([rerun::Color::from_rgb(90, 90, 90)]),
        )
        .map_err(rerun_error)?;
    }
    let singular: Vec<f64> = report.result.singular_values.iter().take(200).copied().collect();
    rec.log("oma/singular_values", &rerun::BarChart::new(singular))
        .map_err(rerun_error)?;
    for (k, m) in report.result.modes.iter().enumerate() {
        log_frequency_and_damping(
            rec,
            named,
            &format!("oma/modes/{}", k + 1),
            (m.frequency_hz, m.frequency_std_hz),
            (m.damping_ratio, m.damping_std),
        )?;
    }
    Ok(())
}

/// The modes fitted in the frequency domain (`[oma.frequency_domain]`)
/// beside `report`'s, on `rec` at the time already set: on the
/// stabilisation diagram a vertical line at each fitted frequency over the
/// diagram's orders (green) with its ±1σ (pale green), and each mode's
/// frequency and damping with ±1σ under `oma/fitted/<k>` (by frequency).
fn log_fitted(
    rec: &rerun::RecordingStream,
    named: &mut BTreeSet<String>,
    report: &OmaReport,
    fitted: &[ModeEntry],
) -> Result<()> {
    if fitted.is_empty() {
        return Ok(());
    }
    let top = report.result.diagram.iter().map(|p| p.order).max().unwrap_or(1).max(1) as f32;
    let mut strips: Vec<Vec<[f32; 2]>> = Vec::new();
    let mut colors = Vec::new();
    for m in fitted {
        let sigma = m.frequency_std_hz.unwrap_or(0.0);
        for (f, color) in [
            (m.frequency_hz, rerun::Color::from_rgb(40, 160, 60)),
            (m.frequency_hz - sigma, rerun::Color::from_rgb(160, 210, 160)),
            (m.frequency_hz + sigma, rerun::Color::from_rgb(160, 210, 160)),
        ] {
            strips.push(vec![[f as f32, 0.0], [f as f32, top]]);
            colors.push(color);
        }
    }
    rec.log(
        "oma/stabilisation/fitted",
        &rerun::LineStrips2D::new(strips).with_colors(colors),
    )
    .map_err(rerun_error)?;
    for (k, m) in fitted.iter().enumerate() {
        log_frequency_and_damping(
            rec,
            named,
            &format!("oma/fitted/{}", k + 1),
            (m.frequency_hz, m.frequency_std_hz),
            (m.damping_ratio, m.damping_std),
        )?;
    }
    Ok(())
}

/// A mode's `frequency_hz` and `damping_percent` under `base`, each with
/// ±1σ (a missing std drawn as 0): (value, std) of the frequency in Hz
/// and of the damping ratio.
fn log_frequency_and_damping(
    rec: &rerun::RecordingStream,
    named: &mut BTreeSet<String>,
    base: &str,
    (frequency_hz, frequency_std_hz): (f64, Option<f64>),
    (damping_ratio, damping_std): (f64, Option<f64>),
) -> Result<()> {
    let path = format!("{base}/frequency_hz");
    log_band(rec, named, &path, (frequency_hz, frequency_std_hz.unwrap_or(0.0)))?;
    let path = format!("{base}/damping_percent");
    log_band(
        rec,
        named,
        &path,
        (100.0 * damping_ratio, 100.0 * damping_std.unwrap_or(0.0)),
    )
}

/// The first singular value of the spectral matrix over the diagram's
/// frequencies, on its order axis: `log10` mapped onto `[0, highest order]`
/// (the secondary axis of ARTeMIS's and pyOMA2's diagrams).
fn first_singular_value_line(report: &OmaReport) -> Option<Vec<[f32; 2]>> {
    let spectrum = report.spectrum.as_ref()?;
    let top_order = report.result.diagram.iter().map(|p| p.order).max()? as f64;
    let top_frequency = 1.05 * report.result.diagram.iter().map(|p| p.frequency_hz).fold(0.0, f64::max);
    let points: Vec<(f64, f64)> = spectrum
        .frequencies_hz
        .iter()
        .zip(spectrum.first())
        .filter(|(f, v)| **f > 0.0 && **f <= top_frequency && *v > 0.0)
        .map(|(f, v)| (*f, v.log10()))
        .collect();
    let (lo, hi) = points
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), (_, v)| {
            (lo.min(*v), hi.max(*v))
        });
    if points.len() < 2 || hi <= lo {
        return None;
    }
    Some(
        points
            .iter()
            .map(|(f, v)| [*f as f32, (top_order * (v - lo) / (hi - lo)) as f32])
            .collect(),
    )
}
