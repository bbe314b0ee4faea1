//! The monitoring layer in the Rerun stream: control charts with their
//! limits, temperature against every scored parameter (coloured by time),
//! and the deck coloured by the standardised residuals of the spring and
//! stiffness-field coefficients (where the change is).

use super::deck::colormap;
use super::{rerun_error, RerunOutput};
use crate::io::monitoring_json::StatusMessage;
use anyhow::Result;

/// Points kept per temperature scatter (the latest).
pub(super) const SCATTER_POINTS: usize = 2000;

/// State codes of the `monitoring/state` series.
fn state_code(state: &str) -> f64 {
    match state {
        "training" => 0.0,
        "normal" => 1.0,
        "outside_training_range" => 2.0,
        _ => 3.0,
    }
}

impl RerunOutput {
    /// Logs one monitoring status.
    pub fn log_monitoring(&mut self, time_ns: i128, status: &StatusMessage) -> Result<()> {
        self.rotate_if_due(time_ns)?;
        self.set_time(time_ns);
        for (chart, value, limit) in [
            ("t2", status.t2, status.t2_limit),
            ("mewma", status.mewma, status.mewma_limit),
        ] {
            let path = format!("monitoring/charts/{chart}");
            if self.named.insert(path.clone()) {
                self.rec
                    .log_static(
                        path.as_str(),
                        &rerun::SeriesLines::new()
                            .with_names(["statistic", "limit"])
                            .with_colors([
                                rerun::Color::from_rgb(30, 110, 200),
                                rerun::Color::from_rgb(220, 40, 40),
                            ]),
                    )
                    .map_err(rerun_error)?;
            }
            if let (Some(v), Some(l)) = (value, limit) {
                self.rec
                    .log(path.as_str(), &rerun::Scalars::new([v, l]))
                    .map_err(rerun_error)?;
            }
        }
        self.rec
            .log("monitoring/state", &rerun::Scalars::new([state_code(&status.state)]))
            .map_err(rerun_error)?;
        if let Some(t) = status.temperature_c {
            self.rec
                .log("monitoring/temperature_c", &rerun::Scalars::new([t]))
                .map_err(rerun_error)?;
        }
        if status.state == "alarm" || status.flags.iter().any(|f| f.starts_with("outside")) {
            self.rec
                .log(
                    "monitoring/log",
                    &rerun::TextLog::new(format!(
                        "window {}: {} {}",
                        status.window,
                        status.state,
                        status.flags.join(", ")
                    )),
                )
                .map_err(rerun_error)?;
        }
        self.log_scatter(status)?;
        if !status.residuals.is_empty() {
            self.log_residual_deck(status)?;
        }
        Ok(())
    }

    /// Temperature (x) against every scored parameter (y), the latest
    /// [`SCATTER_POINTS`] windows, coloured from blue (oldest) to red.
    fn log_scatter(&mut self, status: &StatusMessage) -> Result<()> {
        let Some(t) = status.temperature_c else {
            return Ok(());
        };
        self.scatter
            .push_back((t, status.features.iter().map(|f| f.value).collect()));
        if self.scatter.len() > SCATTER_POINTS {
            self.scatter.pop_front();
        }
        let n = self.scatter.len();
        let color = |k: usize| colormap(k as f64 / n.max(2).saturating_sub(1) as f64);
        for (f, feature) in status.features.iter().enumerate() {
            // A feature missing in a window (a frequency not identified) has no point.
            let (points, colors): (Vec<[f32; 2]>, Vec<rerun::Color>) = self
                .scatter
                .iter()
                .enumerate()
                .filter_map(|(k, (t, v))| {
                    let v = v.get(f).filter(|v| v.is_finite())?;
                    Some(([*t as f32, *v as f32], color(k)))
                })
                .unzip();
            self.rec
                .log(
                    format!("monitoring/temperature/{}", feature.name).as_str(),
                    &rerun::Points2D::new(points)
                        .with_colors(colors)
                        .with_radii([rerun::Radius::new_ui_points(3.0)]),
                )
                .map_err(rerun_error)?;
        }
        Ok(())
    }

    /// The standardised residuals of the spring (`<spring>.k<j>`) and
    /// stiffness-field (`<field>.s<j>`) coefficients evaluated as fields
    /// over the deck and added: −4 → +4 over the colour map.
    fn log_residual_deck(&mut self, status: &StatusMessage) -> Result<()> {
        let z = |name: &str| {
            status
                .residuals
                .iter()
                .find(|r| r.name == name)
                .map_or(0.0, |r| r.standardised)
        };
        let springs: Vec<Vec<f64>> = self
            .spring_names
            .iter()
            .zip(&self.setup.kappa)
            .map(|(name, k)| (0..k.len()).map(|j| z(&format!("{name}.k{}", j + 1))).collect())
            .collect();
        let fields: Vec<Vec<f64>> = self
            .field_names
            .iter()
            .zip(&self.model.stiffness_fields)
            .map(|(name, f)| {
                (0..f.coefficient_count())
                    .map(|j| 1.0 + z(&format!("{name}.s{}", j + 1)))
                    .collect()
            })
            .collect();
        let spring_z = self.grid.spring_field(&self.model, &springs);
        let field_z = self.grid.stiffness_multiplier(&self.model, &fields);
        let colors = spring_z
            .iter()
            .zip(&field_z)
            .map(|(s, f)| colormap(0.5 + (s + f - 1.0) / 8.0));
        self.log_deck_colours("deck/monitoring_residual", colors)
    }
}
