//! One update in the Rerun stream: parameter trends, FRFs, ζ(f), the
//! identified spring field on the deck and the bending modes.

use super::deck::colormap;
use super::{rerun_error, RerunOutput};
use crate::io::frf_json::FrfFile;
use crate::pipeline::UpdateReport;
use anyhow::Result;
use splinewatch_core::model::damping::DampingCurve;

/// `value` and `value ± sigma` as three series under `path` on `rec`,
/// their names and colours logged once per recording (`named`: the paths
/// already given them).
pub(super) fn log_band(
    rec: &rerun::RecordingStream,
    named: &mut std::collections::BTreeSet<String>,
    path: &str,
    (value, sigma): (f64, f64),
) -> Result<()> {
    if named.insert(path.to_string()) {
        rec.log_static(
            path,
            &rerun::SeriesLines::new()
                .with_names(["value", "+1σ", "−1σ"])
                .with_colors([
                    rerun::Color::from_rgb(30, 110, 200),
                    rerun::Color::from_rgb(150, 180, 220),
                    rerun::Color::from_rgb(150, 180, 220),
                ]),
        )
        .map_err(rerun_error)?;
    }
    rec.log(path, &rerun::Scalars::new([value, value + sigma, value - sigma]))
        .map_err(rerun_error)
}

impl RerunOutput {
    /// Value and ±1σ of every parameter, and the relative residual.
    pub(super) fn log_parameters(&mut self, report: &UpdateReport) -> Result<()> {
        for p in &report.result.parameters {
            let group = self.parameter_groups.get(&p.name).copied().unwrap_or("other");
            let path = format!("parameters/{group}/{}", p.name);
            self.log_band(&path, p.value, p.std.unwrap_or(0.0))?;
        }
        self.rec
            .log(
                "residual/relative",
                &rerun::Scalars::new([report.result.relative_residual]),
            )
            .map_err(rerun_error)?;
        Ok(())
    }

    /// A trend with its ±1σ band at `path`: three series, named and
    /// coloured once per file.
    pub(super) fn log_band(&mut self, path: &str, value: f64, sigma: f64) -> Result<()> {
        log_band(&self.rec, &mut self.named, path, (value, sigma))
    }

    /// ζ(f) over its band, in %, and the control coefficients.
    pub(super) fn log_damping(&self, damping: &DampingCurve) -> Result<()> {
        let (f0, f1) = damping.band();
        let n = 161;
        let fs: Vec<f64> = (0..n).map(|k| f0 + (f1 - f0) * k as f64 / (n - 1) as f64).collect();
        let zeta: Vec<f64> = fs.iter().map(|&f| 100.0 * damping.zeta(f)).collect();
        self.rec
            .log(
                "damping/zeta",
                &rerun::BarChart::new(zeta.as_slice())
                    .with_abscissa(fs.as_slice())
                    .with_widths([((f1 - f0) / (n - 1) as f64) as f32]),
            )
            .map_err(rerun_error)?;
        let at = damping.coefficient_frequencies();
        let gamma: Vec<f64> = damping.coefficients().iter().map(|g| 100.0 * g).collect();
        self.rec
            .log(
                "damping/coefficients",
                &rerun::BarChart::new(gamma.as_slice())
                    .with_abscissa(at.as_slice())
                    .with_widths([((f1 - f0) / (4 * gamma.len().max(1)) as f64) as f32]),
            )
            .map_err(rerun_error)?;
        Ok(())
    }

    /// The identified stiffness multiplier θ on the deck (only with
    /// stiffness fields): colour 0.5 → 1.5 over the map, 1 in the middle;
    /// from the second update on also the standardised change from the
    /// first, `(θ − θ₀)/√(σ² + σ₀²)` per coefficient, on its own mesh
    /// (−3 → +3 over the map).
    pub(super) fn log_stiffness_field(&mut self, report: &UpdateReport) -> Result<()> {
        if self.model.stiffness_fields.is_empty() {
            return Ok(());
        }
        let theta = &report.theta;
        let multiplier = self.grid.stiffness_multiplier(&self.model, theta);
        self.log_deck_colours("deck/stiffness", multiplier.iter().map(|&v| colormap(v - 0.5)))?;
        // σ of every coefficient (0 when not updated or unidentifiable).
        let sigma: Vec<Vec<f64>> = self
            .field_names
            .iter()
            .zip(theta)
            .map(|(name, values)| {
                (0..values.len())
                    .map(|j| {
                        let key = format!("{name}.s{}", j + 1);
                        let p = report.result.parameters.iter().find(|p| p.name == key);
                        p.and_then(|p| p.std).unwrap_or(0.0)
                    })
                    .collect()
            })
            .collect();
        let Some((theta0, sigma0)) = &self.first_fields else {
            self.first_fields = Some((theta.clone(), sigma));
            return Ok(());
        };
        // θ' = 1 + z evaluates the standardised change as a multiplier field.
        let shifted: Vec<Vec<f64>> = theta
            .iter()
            .zip(theta0)
            .zip(sigma.iter().zip(sigma0))
            .map(|((t, t0), (s, s0))| {
                (0..t.len())
                    .map(|j| {
                        let scale = (s[j] * s[j] + s0[j] * s0[j]).sqrt();
                        1.0 + if scale > 0.0 { (t[j] - t0[j]) / scale } else { 0.0 }
                    })
                    .collect()
            })
            .collect();
        let z = self.grid.stiffness_multiplier(&self.model, &shifted);
        self.log_deck_colours(
            "deck/stiffness_change",
            z.iter().map(|&v| colormap(0.5 + (v - 1.0) / 6.0)),
        )
    }

    /// The deck mesh at `path` with one colour per vertex.
    pub(super) fn log_deck_colours(&self, path: &str, colors: impl Iterator<Item = rerun::Color>) -> Result<()> {
        self.rec
            .log(
                path,
                &rerun::Mesh3D::update_fields()
                    .with_vertex_positions(self.grid.positions.clone())
                    .with_vertex_colors(colors.collect::<Vec<_>>()),
            )
            .map_err(rerun_error)?;
        Ok(())
    }

    /// The identified spring field on the deck.
    pub(super) fn log_spring_field(&self, kappa: &[Vec<f64>]) -> Result<()> {
        let r33 = self.grid.spring_field(&self.model, kappa);
        let top = r33.iter().copied().fold(0.0f64, f64::max).max(f64::MIN_POSITIVE);
        let colors: Vec<rerun::Color> = r33.iter().map(|&v| colormap(v / top)).collect();
        self.rec
            .log(
                "deck/springs",
                &rerun::Mesh3D::update_fields()
                    .with_vertex_positions(self.grid.positions.clone())
                    .with_vertex_colors(colors),
            )
            .map_err(rerun_error)?;
        Ok(())
    }

    pub(super) fn log_frfs(&self, frfs: &FrfFile, which: &str) -> Result<()> {
        let frequencies: Vec<f32> = frfs.frequency_hz.iter().map(|&f| f as f32).collect();
        let width = frfs
            .frequency_hz
            .windows(2)
            .map(|w| w[1] - w[0])
            .fold(f64::INFINITY, f64::min);
        let width = if width.is_finite() { width as f32 } else { 1.0 };
        for entry in &frfs.frfs {
            let magnitude: Vec<f64> = entry
                .re
                .iter()
                .zip(&entry.im)
                .map(|(re, im)| 20.0 * re.hypot(*im).max(1e-300).log10())
                .collect();
            let phase: Vec<f64> = entry
                .re
                .iter()
                .zip(&entry.im)
                .map(|(re, im)| im.atan2(*re).to_degrees())
                .collect();
            for (what, values) in [("magnitude", magnitude), ("phase", phase)] {
                self.rec
                    .log(
                        format!("frf/{}/{what}/{which}", entry.output).as_str(),
                        &rerun::BarChart::new(values.as_slice())
                            .with_abscissa(frequencies.as_slice())
                            .with_widths([width]),
                    )
                    .map_err(rerun_error)?;
            }
        }
        Ok(())
    }

    pub(super) fn log_modes(&self, report: &UpdateReport) -> Result<()> {
        for (k, mode) in report.bending_modes.iter().enumerate() {
            let w = self.grid.normal_displacement(&self.model, |dof| mode.shape[dof]);
            let peak = w.iter().map(|v| v.abs()).fold(0.0f64, f64::max).max(f64::MIN_POSITIVE);
            let scale = 0.1 * self.grid.span / peak;
            let positions: Vec<[f32; 3]> = self
                .grid
                .positions
                .iter()
                .zip(&self.grid.normals)
                .zip(&w)
                .map(|((p, n), w)| {
                    [
                        p[0] + (scale * w) as f32 * n[0],
                        p[1] + (scale * w) as f32 * n[1],
                        p[2] + (scale * w) as f32 * n[2],
                    ]
                })
                .collect();
            let colors: Vec<rerun::Color> = w.iter().map(|v| colormap(0.5 + 0.5 * v / peak)).collect();
            let label = format!("{:.2} Hz, ζ = {:.2} %", mode.frequency_hz, 100.0 * mode.damping_ratio);
            let path = format!("modes/{}", k + 1);
            self.rec
                .log(
                    path.as_str(),
                    &rerun::Mesh3D::update_fields()
                        .with_vertex_positions(positions)
                        .with_vertex_colors(colors),
                )
                .map_err(rerun_error)?;
            self.rec
                .log(format!("{path}/label").as_str(), &rerun::TextDocument::new(label))
                .map_err(rerun_error)?;
        }
        Ok(())
    }
}

/// The trend group of a parameter of `family`: `springs` (`<spring>.k<j>`),
/// `bearings`, `supports` (line supports' components), `fields`
/// (stiffness multipliers `<field>.s<j>`), `members` (`<beam>.stiffness`),
/// `damping` (`damping.g<z>`), `loss_factors` (`<support>.eta`), or
/// `other` for a name the config does not give.
pub(super) fn parameter_group(family: Option<crate::config::ParameterFamily>) -> &'static str {
    use crate::config::ParameterFamily;
    match family {
        Some(ParameterFamily::Spring) => "springs",
        Some(ParameterFamily::Bearing) => "bearings",
        Some(ParameterFamily::ElasticSupport) => "supports",
        Some(ParameterFamily::StiffnessField) => "fields",
        Some(ParameterFamily::MemberStiffness) => "members",
        Some(ParameterFamily::Damping) => "damping",
        Some(ParameterFamily::LossFactor) => "loss_factors",
        None => "other",
    }
}
