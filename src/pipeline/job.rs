//! Update jobs: everything one updating run needs, so it can run on another
//! thread, and what it produced.

use crate::config::FrfSetup;
use crate::io::frf_json::{FrfEntry, FrfFile};
use anyhow::{bail, Result};
use splinewatch_core::damping::DampingCurve;
use splinewatch_core::modal::ModeKind;
use splinewatch_core::updating::{ModelPoint, Parameter, UpdateProblem, UpdateResult, UpdateSettings};
use std::sync::Arc;

/// An updating run to do: owns everything it needs, so it can run on
/// another thread.
pub struct UpdateJob {
    pub window: u64,
    pub time_ns: i128,
    pub measured: FrfFile,
    pub(super) setup: Arc<FrfSetup>,
    pub(super) parameters: Vec<Parameter>,
    pub(super) settings: UpdateSettings,
    pub(super) start: Vec<f64>,
    /// The model at the last accepted parameters, if known: the solve starts
    /// from it instead of re-evaluating the model there.
    pub(super) previous: Option<Arc<ModelPoint>>,
}

/// What an update produced.
#[derive(Debug, Clone)]
pub struct UpdateOutcome {
    pub window: u64,
    pub time_ns: i128,
    pub measured: FrfFile,
    pub result: Result<UpdateReport, String>,
    /// The model at the identified parameters, taken by [`Pipeline::apply`]
    /// for the next warm start (kept outcomes do not hold it: ~2 MB).
    pub(super) point: Option<Arc<ModelPoint>>,
}

/// How many bending mode shapes an update report carries (for the views).
pub const BENDING_MODES_KEPT: usize = 4;

/// A mode of the updated model with its shape on every (full) dof.
#[derive(Debug, Clone)]
pub struct ModeShape {
    pub frequency_hz: f64,
    pub damping_ratio: f64,
    pub shape: Vec<f64>,
}

#[derive(Debug, Clone)]
pub struct UpdateReport {
    pub result: UpdateResult,
    /// Model FRFs at the identified parameters, on the measured lines.
    pub model: FrfFile,
    /// `(frequency Hz, damping ratio, kind)` of the updated model below the band's top.
    pub modes: Vec<(f64, f64, ModeKind)>,
    /// The first [`BENDING_MODES_KEPT`] bending modes, with their shapes.
    pub bending_modes: Vec<ModeShape>,
    /// `|h_x - h_a| / |h_x|` per FRF and line.
    pub residue: Vec<Vec<f64>>,
    /// The identified spring coefficients (per field) and damping curve.
    pub kappa: Vec<Vec<f64>>,
    pub damping: DampingCurve,
}

impl UpdateJob {
    pub fn run(self) -> UpdateOutcome {
        let (result, point) = match self.compute() {
            Ok((report, point)) => (Ok(report), Some(Arc::new(point))),
            Err(e) => (Err(format!("{e:#}")), None),
        };
        UpdateOutcome {
            window: self.window,
            time_ns: self.time_ns,
            measured: self.measured,
            result,
            point,
        }
    }

    fn compute(&self) -> Result<(UpdateReport, ModelPoint)> {
        let measured = self.measured.to_measured(&self.setup.sensor_names)?;
        let problem = UpdateProblem::new(
            &self.setup.model,
            self.setup.kappa.clone(),
            self.setup.damping.clone(),
            self.parameters.clone(),
            &measured,
            self.settings.clone(),
        )?;
        let solution = problem.solve_from(&self.start, self.previous.as_deref(), &mut |_| {})?;
        let (result, point) = (solution.result, solution.point);
        if result.parameters.iter().any(|p| !p.value.is_finite()) {
            bail!("non-finite parameters");
        }
        if !result.converged {
            bail!("the updating did not converge ({:?})", result.stop_reason);
        }
        let (state, h) = (point.state(), point.frfs());
        let lines = problem.line_frequencies().to_vec();
        let sel = problem.line_indices();
        let nl = lines.len();
        let mut model_entries = Vec::new();
        let mut residue = Vec::new();
        for (b, m) in measured.frfs().iter().enumerate() {
            let hs = &h[b * nl..(b + 1) * nl];
            model_entries.push(FrfEntry {
                input: self.setup.sensor_names[m.input].clone(),
                output: self.setup.sensor_names[m.output].clone(),
                re: hs.iter().map(|v| v.re).collect(),
                im: hs.iter().map(|v| v.im).collect(),
                coherence: None,
                n_averages: None,
            });
            residue.push(
                sel.iter()
                    .zip(hs)
                    .map(|(&i, a)| {
                        let x = m.values[i];
                        (x - a).norm() / x.norm().max(f64::MIN_POSITIVE)
                    })
                    .collect(),
            );
        }
        let (kappa, damping) = (point.kappa().to_vec(), point.damping().clone());
        let top = lines.last().copied().unwrap_or(0.0);
        let modes = (0..state.modes.len())
            .filter(|&i| state.modes.frequency_hz(i) <= top)
            .map(|i| (state.modes.frequency_hz(i), state.zeta[i], state.modes.kinds[i]))
            .collect();
        let bending_modes = (0..state.modes.len())
            .filter(|&i| state.modes.kinds[i] == ModeKind::Bending)
            .take(BENDING_MODES_KEPT)
            .map(|i| ModeShape {
                frequency_hz: state.modes.frequency_hz(i),
                damping_ratio: state.zeta[i],
                shape: (0..state.modes.shapes.nrows())
                    .map(|d| state.modes.shapes[(d, i)])
                    .collect(),
            })
            .collect();
        let report = UpdateReport {
            result,
            model: FrfFile {
                quantity: self.measured.quantity,
                frequency_hz: lines,
                frfs: model_entries,
            },
            modes,
            bending_modes,
            residue,
            kappa,
            damping,
        };
        Ok((report, point))
    }
}
