//! Reproduction of the paper's experiments (§4.1–4.3) on the bundled Sinello
//! model: measured FRFs synthesised from `config/sinello-truth.toml` (true κ
//! of eq. 47, a damping curve the updating model cannot represent), input at
//! P1 along z, accelerance on 0.5–80 Hz every 0.1 Hz; updating of
//! `config/sinello.toml` started from κ = 1e9 N/m³ and γ = 0.01.

use super::synth::{synth, SynthOptions};
use super::update::update;
use crate::config::{frf_setup, load_config, Config};
use anyhow::{Context, Result};
use plotters::prelude::*;
use splinewatch_core::geometry::knots::KnotVector;
use splinewatch_core::response::frf::Quantity;
use splinewatch_core::updating::UpdateResult;
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

/// One of the paper's cases.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Experiment {
    pub name: &'static str,
    pub section: &'static str,
    /// Response sensors P1..Pn.
    pub outputs: usize,
    /// Noise, fraction of each FRF's RMS.
    pub noise: f64,
    pub seed: u64,
}

pub const EXPERIMENTS: [Experiment; 4] = [
    Experiment {
        name: "12 sensors, no noise",
        section: "4.1",
        outputs: 12,
        noise: 0.0,
        seed: 1,
    },
    Experiment {
        name: "4 sensors, no noise",
        section: "4.2",
        outputs: 4,
        noise: 0.0,
        seed: 2,
    },
    Experiment {
        name: "4 sensors, 3 % noise",
        section: "4.3",
        outputs: 4,
        noise: 0.03,
        seed: 3,
    },
    Experiment {
        name: "4 sensors, 10 % noise",
        section: "4.3",
        outputs: 4,
        noise: 0.10,
        seed: 4,
    },
];

/// The start of every run (paper §4.1).
pub const START_KAPPA: f64 = 1e9;

#[derive(Debug, Clone)]
pub struct Outcome {
    pub experiment: Experiment,
    pub result: UpdateResult,
    /// True spring coefficients, in parameter order (`west.k1…east.k4`).
    pub kappa_true: Vec<f64>,
    pub seconds: f64,
    /// `(f, ζ_true(f), ζ_identified(f))` on 0–80 Hz.
    pub zeta: Vec<(f64, f64, f64)>,
    /// `(f_i, ζ_true(f_i))` at the true model's modes in the band.
    pub modal_zeta: Vec<(f64, f64)>,
    /// Identified control coefficients γ_z at their Greville frequencies.
    pub coefficients: Vec<(f64, f64)>,
}

impl Outcome {
    /// `|κ̂ - κ| / κ` per spring coefficient.
    pub fn kappa_errors(&self) -> Vec<f64> {
        self.kappa_true
            .iter()
            .zip(&self.result.parameters)
            .map(|(t, p)| (p.value - t).abs() / t)
            .collect()
    }

    /// `|κ̂ - κ| / σ̂` per spring coefficient (∞ without a std).
    pub fn kappa_sigmas(&self) -> Vec<f64> {
        self.kappa_true
            .iter()
            .zip(&self.result.parameters)
            .map(|(t, p)| p.std.map_or(f64::INFINITY, |s| (p.value - t).abs() / s))
            .collect()
    }
}

/// Runs one experiment; `truth` makes the data, `model` is updated.
pub fn run(truth: &Config, model: &Config, experiment: &Experiment) -> Result<Outcome> {
    let outputs: Vec<String> = (1..=experiment.outputs).map(|i| format!("P{i}")).collect();
    let frf = synth(
        truth,
        &SynthOptions {
            inputs: vec!["P1".into()],
            outputs,
            quantity: Quantity::Accelerance,
            f_min: 0.5,
            f_max: 80.0,
            step: 0.1,
            noise: experiment.noise,
            seed: experiment.seed,
        },
    )?;
    let frf_text = serde_json::to_string(&frf)?;
    let parameters = model.build_parameters()?;
    let start = serde_json::json!({
        "parameters": parameters
            .iter()
            .filter(|p| !p.name.starts_with("damping."))
            .map(|p| serde_json::json!({"name": p.name, "value": START_KAPPA}))
            .collect::<Vec<_>>()
    })
    .to_string();
    let t0 = Instant::now();
    let (result, _) = update(model, frf_text.as_bytes(), Some(&start), &mut |_| {})?;
    let seconds = t0.elapsed().as_secs_f64();
    let kappa_true: Vec<f64> = truth
        .model
        .springs
        .iter()
        .flat_map(|s| s.stiffness.iter().copied())
        .collect();
    let truth_curve = truth.build_damping()?;
    let gamma: Vec<f64> = result
        .parameters
        .iter()
        .filter(|p| p.name.starts_with("damping."))
        .map(|p| p.value)
        .collect();
    let identified = model
        .build_damping()?
        .with_coefficients(gamma.clone())
        .context("identified damping")?;
    let (f_start, f_end) = identified.band();
    let greville = KnotVector::uniform(identified.degree(), gamma.len(), f_start, f_end)?.greville();
    let coefficients = greville.into_iter().zip(gamma).collect();
    let zeta = (0..=160)
        .map(|k| {
            let f = 0.5 * k as f64;
            (f, truth_curve.zeta(f), identified.zeta(f))
        })
        .collect();
    let setup = frf_setup(truth)?;
    let state = setup.model.modal_state(&setup.kappa, &setup.damping)?;
    let modal_zeta = (0..state.modes.len())
        .filter(|&i| state.zeta[i] > 0.0 && state.modes.frequency_hz(i) <= 80.0)
        .map(|i| (state.modes.frequency_hz(i), state.zeta[i]))
        .collect();
    Ok(Outcome {
        experiment: *experiment,
        result,
        kappa_true,
        seconds,
        zeta,
        modal_zeta,
        coefficients,
    })
}

/// Loads the two bundled configurations from the repository root `root`.
pub fn bundled_configs(root: &Path) -> Result<(Config, Config)> {
    let truth = load_config(&root.join("config/sinello-truth.toml"))?;
    let model = load_config(&root.join("config/sinello.toml"))?;
    Ok((truth, model))
}

/// Markdown table of the outcomes.
pub fn report_markdown(outcomes: &[Outcome]) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "| case (paper §) | iterations | evaluations | time s | final relative residual | worst κ error | worst κ error / σ̂ | stop |"
    );
    let _ = writeln!(s, "| --- | --- | --- | --- | --- | --- | --- | --- |");
    for o in outcomes {
        let worst = o.kappa_errors().into_iter().fold(0.0, f64::max);
        let sig = o.kappa_sigmas().into_iter().fold(0.0, f64::max);
        let _ = writeln!(
            s,
            "| {} ({}) | {} | {} | {:.2} | {:.4} | {:.2} % | {:.2} | {:?} |",
            o.experiment.name,
            o.experiment.section,
            o.result.iterations.len() - 1,
            o.result.evaluations,
            o.seconds,
            o.result.relative_residual,
            100.0 * worst,
            sig,
            o.result.stop_reason
        );
    }
    let _ = writeln!(s);
    let _ = writeln!(s, "Identified spring coefficients (1e9 N/m³), truth in the first row:");
    let _ = writeln!(s);
    let names: Vec<&str> = outcomes[0]
        .result
        .parameters
        .iter()
        .take(outcomes[0].kappa_true.len())
        .map(|p| p.name.as_str())
        .collect();
    let _ = writeln!(s, "| case | {} |", names.join(" | "));
    let _ = writeln!(s, "| --- |{}", " --- |".repeat(names.len()));
    let truth: Vec<String> = outcomes[0]
        .kappa_true
        .iter()
        .map(|k| format!("{:.3}", k / 1e9))
        .collect();
    let _ = writeln!(s, "| truth | {} |", truth.join(" | "));
    for o in outcomes {
        let row: Vec<String> = o
            .result
            .parameters
            .iter()
            .take(o.kappa_true.len())
            .map(|p| match p.std {
                Some(sd) => format!("{:.3} ± {:.3}", p.value / 1e9, sd / 1e9),
                None => format!("{:.3}", p.value / 1e9),
            })
            .collect();
        let _ = writeln!(s, "| {} | {} |", o.experiment.name, row.join(" | "));
    }
    s
}

/// SVG plot of ζ(f): truth curve, modal values, identified curve.
pub fn plot_damping(outcome: &Outcome, path: &Path) -> Result<()> {
    let root = SVGBackend::new(path, (720, 420)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| anyhow::anyhow!("{e}"))?;
    let ymax = outcome.zeta.iter().map(|&(_, a, b)| a.max(b)).fold(0.0, f64::max) * 1.15;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!(
                "ζ(f), {} (paper §{})",
                outcome.experiment.name, outcome.experiment.section
            ),
            ("sans-serif", 18),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..80.0, 0.0..ymax)
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    chart
        .configure_mesh()
        .x_desc("frequency, Hz")
        .y_desc("damping ratio ζ")
        .draw()
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    chart
        .draw_series(LineSeries::new(
            outcome.zeta.iter().map(|&(f, t, _)| (f, t)),
            RED.stroke_width(2),
        ))
        .map_err(|e| anyhow::anyhow!("{e}"))?
        .label("true ζ(f)")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED));
    chart
        .draw_series(
            outcome
                .modal_zeta
                .iter()
                .map(|&(f, z)| Rectangle::new([(f - 0.5, z - 0.0004), (f + 0.5, z + 0.0004)], RED.filled())),
        )
        .map_err(|e| anyhow::anyhow!("{e}"))?
        .label("true ζ_i at the modes")
        .legend(|(x, y)| Rectangle::new([(x + 6, y - 4), (x + 14, y + 4)], RED.filled()));
    chart
        .draw_series(LineSeries::new(
            outcome.zeta.iter().map(|&(f, _, i)| (f, i)),
            BLACK.stroke_width(2),
        ))
        .map_err(|e| anyhow::anyhow!("{e}"))?
        .label("identified ζ(f)")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK));
    chart
        .draw_series(
            outcome
                .coefficients
                .iter()
                .map(|&(f, g)| Rectangle::new([(f - 0.6, g - 0.0005), (f + 0.6, g + 0.0005)], GREEN.filled())),
        )
        .map_err(|e| anyhow::anyhow!("{e}"))?
        .label("identified coefficients γ_z")
        .legend(|(x, y)| Rectangle::new([(x + 6, y - 4), (x + 14, y + 4)], GREEN.filled()));
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerLeft)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(|e| anyhow::anyhow!("{e}"))?;
    root.present().map_err(|e| anyhow::anyhow!("{e}"))?;
    Ok(())
}
