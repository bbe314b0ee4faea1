//! One output-only identification in the Rerun stream: the stabilisation
//! diagram (every pole at its order over frequency; grey unstable, blue
//! stable, orange in a mode) over the Hankel matrix's leading singular
//! values, and the identified frequencies and damping ratios with ±1σ.

use super::{rerun_error, RerunOutput};
use crate::pipeline::oma::OmaReport;
use anyhow::Result;

impl RerunOutput {
    /// Logs `report` at its span's start time.
    pub fn log_oma(&mut self, report: &OmaReport) -> Result<()> {
        self.set_time(report.start_ns);
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
        self.rec
            .log(
                "oma/stabilisation",
                &rerun::Points2D::new(positions)
                    .with_colors(colors)
                    .with_radii([rerun::Radius::new_ui_points(2.0)]),
            )
            .map_err(rerun_error)?;
        let singular: Vec<f64> = report.result.singular_values.iter().take(200).copied().collect();
        self.rec
            .log("oma/singular_values", &rerun::BarChart::new(singular))
            .map_err(rerun_error)?;
        for (k, m) in report.result.modes.iter().enumerate() {
            let sigma_f = m.frequency_std_hz.unwrap_or(0.0);
            let sigma_z = m.damping_std.unwrap_or(0.0);
            self.rec
                .log(
                    format!("oma/modes/{}/frequency_hz", k + 1).as_str(),
                    &rerun::Scalars::new([m.frequency_hz, m.frequency_hz + sigma_f, m.frequency_hz - sigma_f]),
                )
                .map_err(rerun_error)?;
            self.rec
                .log(
                    format!("oma/modes/{}/damping_percent", k + 1).as_str(),
                    &rerun::Scalars::new([
                        100.0 * m.damping_ratio,
                        100.0 * (m.damping_ratio + sigma_z),
                        100.0 * (m.damping_ratio - sigma_z),
                    ]),
                )
                .map_err(rerun_error)?;
        }
        Ok(())
    }
}
