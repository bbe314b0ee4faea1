//! Update jobs: everything one updating run needs, so it can run on another
//! thread, and what it produced. Two residual models share the job: FRF
//! residues against measured FRFs, modal residues against the modes a
//! window identified output-only.

use super::monitoring::Environment;
use crate::config::FrfSetup;
use crate::io::frf_json::{FrfEntry, FrfFile};
use crate::io::modes_json::ModesFile;
use anyhow::{bail, Result};
use splinewatch_core::model::damping::DampingCurve;
use splinewatch_core::response::frf::ModalState;
use splinewatch_core::solvers::modal::ModeKind;
use splinewatch_core::updating::frf_residual::{MeasuredSet, ModelPoint, UpdateProblem};
use splinewatch_core::updating::joint::{BlockFit, JointUpdateProblem};
use splinewatch_core::updating::modal_residual::{ModePair, ObservedMode};
use splinewatch_core::updating::{ModalUpdateProblem, Parameter, UpdateResult, UpdateSettings};
use std::sync::Arc;

/// What an update is fitted to.
#[derive(Debug, Clone)]
pub enum Measured {
    /// FRFs estimated in a window, or received pre-computed.
    Frf(FrfFile),
    /// Modes identified output-only in a window (with their std).
    Modes(ModesFile),
    /// Both, of one window (`[updating] residues = "both"`).
    Both(FrfFile, ModesFile),
}

impl Measured {
    /// The measured FRFs, if the update fits them.
    pub fn frf(&self) -> Option<&FrfFile> {
        match self {
            Self::Frf(frf) | Self::Both(frf, _) => Some(frf),
            Self::Modes(_) => None,
        }
    }

    /// What the update fits: `"frf"`, `"modes"` or `"both"`
    /// (`updating/parameters`' `residues`).
    pub fn residues(&self) -> &'static str {
        match self {
            Self::Frf(_) => "frf",
            Self::Modes(_) => "modes",
            Self::Both(..) => "both",
        }
    }
}

/// An updating run to do: owns everything it needs, so it can run on
/// another thread.
pub struct UpdateJob {
    pub window: u64,
    pub time_ns: i128,
    pub measured: Measured,
    /// The window's temperatures (`[monitoring]`).
    pub environment: Environment,
    /// Pairing of identified and model modes: smallest MAC, largest
    /// relative frequency gap (modal residues only).
    pub(super) pairing: (f64, f64),
    pub(super) setup: Arc<FrfSetup>,
    pub(super) parameters: Vec<Parameter>,
    pub(super) settings: UpdateSettings,
    pub(super) start: Vec<f64>,
    /// The model at the last accepted parameters, if known: the solve starts
    /// from it instead of re-evaluating the model there.
    pub(super) previous: Option<Arc<ModelPoint>>,
    /// When the window's last block was taken (the ingest-to-result latency).
    pub created: std::time::Instant,
}

/// What an update produced.
#[derive(Debug, Clone)]
pub struct UpdateOutcome {
    pub window: u64,
    pub time_ns: i128,
    pub measured: Measured,
    pub environment: Environment,
    pub result: Result<UpdateReport, String>,
    /// When the job was made (its window's last block taken) and how long
    /// its run took: the metrics' latency and duration.
    pub created: std::time::Instant,
    pub duration: std::time::Duration,
    /// The model at the identified parameters, taken by [`Pipeline::apply`]
    /// for the next warm start (kept outcomes do not hold it: ~2 MB).
    pub(super) point: Option<Arc<ModelPoint>>,
    /// The modal state there (modal residues), taken by
    /// [`Pipeline::apply`] to pair the next windows' modes.
    pub(super) state: Option<Arc<ModalState>>,
}

/// How the model fits what was measured: the FRFs, the identified modes,
/// or both.
#[derive(Debug, Clone, Default)]
pub struct Fit {
    pub frf: Option<FrfFit>,
    /// One entry per paired mode.
    pub modes: Option<Vec<PairedMode>>,
    /// With both: each block's residue count and chi-square at the solution.
    pub blocks: Option<[BlockFit; 2]>,
}

/// The model's FRFs against the measured ones.
#[derive(Debug, Clone)]
pub struct FrfFit {
    /// Model FRFs at the identified parameters, on the measured lines.
    pub model: FrfFile,
    /// `|h_x - h_a| / |h_x|` per FRF and line.
    pub residue: Vec<Vec<f64>>,
}

/// An identified mode and its model mode at the identified parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct PairedMode {
    /// Index into the identified modes (the window's `oma/modes`).
    pub identified: usize,
    /// Index into the model's modes.
    pub model_mode: usize,
    pub identified_frequency_hz: f64,
    pub model_frequency_hz: f64,
    pub frequency_std_hz: f64,
    pub identified_damping: f64,
    /// ζ(f) of the damping curve at the model mode.
    pub model_damping: f64,
    pub mac: f64,
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
    pub fit: Fit,
    /// `(frequency Hz, damping ratio, kind)` of the updated model below the band's top.
    pub modes: Vec<(f64, f64, ModeKind)>,
    /// The first [`BENDING_MODES_KEPT`] bending modes, with their shapes.
    pub bending_modes: Vec<ModeShape>,
    /// The identified spring coefficients (per field) and damping curve.
    pub kappa: Vec<Vec<f64>>,
    /// The identified stiffness-field coefficients (per field; empty
    /// without stiffness fields).
    pub theta: Vec<Vec<f64>>,
    pub damping: DampingCurve,
    /// How the modes were truncated, for a `[model.solver]` truncated model.
    pub truncation: Option<splinewatch_core::solvers::truncation::TruncationReport>,
}

impl UpdateJob {
    pub fn run(self) -> UpdateOutcome {
        let started = std::time::Instant::now();
        let computed = match &self.measured {
            Measured::Frf(frf) => self.compute_frf(frf).map(|(r, p)| (r, Some(Arc::new(p)), None)),
            Measured::Modes(modes) => self.compute_modal(modes).map(|(r, s)| (r, None, Some(Arc::new(s)))),
            Measured::Both(frf, modes) => self
                .compute_joint(frf, modes)
                .map(|(r, p)| (r, Some(Arc::new(p)), None)),
        };
        let (result, point, state) = match computed {
            Ok((report, point, state)) => (Ok(report), point, state),
            Err(e) => (Err(format!("{e:#}")), None, None),
        };
        UpdateOutcome {
            window: self.window,
            time_ns: self.time_ns,
            measured: self.measured,
            environment: self.environment,
            result,
            created: self.created,
            duration: started.elapsed(),
            point,
            state,
        }
    }

    /// Modal-residue updating against the modes a window identified.
    fn compute_modal(&self, modes: &ModesFile) -> Result<(UpdateReport, ModalState)> {
        let observed = modes.to_observed(&self.setup.sensor_names)?;
        let problem = ModalUpdateProblem::new(
            &self.setup.model,
            self.setup.kappa.clone(),
            self.setup.damping.clone(),
            self.parameters.clone(),
            &observed,
            self.settings.clone(),
            self.pairing,
        )?;
        let solution = problem.solve(&self.start, &mut |_| {})?;
        let result = accepted(solution.result)?;
        let values: Vec<f64> = result.parameters.iter().map(|p| p.value).collect();
        let (kappa, damping) = problem.model_at(&values)?;
        let theta = problem.fields_at(&values);
        let state = solution.state;
        let fit = Fit {
            modes: Some(paired(&observed, &solution.pairs, &state)),
            ..Fit::default()
        };
        let top = self.modes_top(&observed);
        let truncation = self
            .setup
            .truncation_report(&kappa, &theta, &damping, state.modes.len(), None)?;
        let (modes, bending_modes) = model_modes(&state, top);
        let report = UpdateReport {
            result,
            fit,
            modes,
            bending_modes,
            kappa,
            theta,
            damping,
            truncation,
        };
        Ok((report, state))
    }

    /// The model's modes are reported up to the highest identified one, and
    /// a little above.
    fn modes_top(&self, observed: &[ObservedMode]) -> f64 {
        observed.iter().map(|m| m.frequency_hz).fold(0.0, f64::max) * (1.0 + self.pairing.1)
    }

    fn compute_frf(&self, frf: &FrfFile) -> Result<(UpdateReport, ModelPoint)> {
        let measured = frf.to_measured(&self.setup.sensor_names)?;
        let problem = UpdateProblem::new(
            &self.setup.model,
            self.setup.kappa.clone(),
            self.setup.damping.clone(),
            self.parameters.clone(),
            &measured,
            self.settings.clone(),
        )?;
        let solution = problem.solve_from(&self.start, self.previous.as_deref(), &mut |_| {})?;
        let result = accepted(solution.result)?;
        self.frf_report(result, frf, &measured, &problem, solution.point, Fit::default(), 0.0)
    }

    /// FRF and modal residues together, each block in its own std
    /// (`splinewatch_core::updating::joint`).
    fn compute_joint(&self, frf: &FrfFile, modes: &ModesFile) -> Result<(UpdateReport, ModelPoint)> {
        let measured = frf.to_measured(&self.setup.sensor_names)?;
        let observed = modes.to_observed(&self.setup.sensor_names)?;
        let problem = JointUpdateProblem::new(
            &self.setup.model,
            self.setup.kappa.clone(),
            self.setup.damping.clone(),
            self.parameters.clone(),
            &measured,
            &observed,
            self.settings.clone(),
            self.pairing,
        )?;
        let solution = problem.solve_from(&self.start, self.previous.as_deref(), &mut |_| {})?;
        let result = accepted(solution.result)?;
        let fit = Fit {
            modes: Some(paired(&observed, &solution.pairs, solution.point.state())),
            blocks: Some(solution.blocks),
            frf: None,
        };
        let top = self.modes_top(&observed);
        self.frf_report(result, frf, &measured, problem.frf(), solution.point, fit, top)
    }

    /// The report of an update that fitted FRFs (`fit` holds any other
    /// part): the model FRFs and residues on the fitted lines, the model's
    /// modes up to the highest line or `top`, the truncation.
    #[allow(
        clippy::too_many_arguments,
        reason = "what the FRF and joint updates share: the result, the measured set in both forms, the problem, the model at the result and the rest of the fit"
    )]
    fn frf_report(
        &self,
        result: UpdateResult,
        frf: &FrfFile,
        measured: &MeasuredSet,
        problem: &UpdateProblem,
        point: ModelPoint,
        mut fit: Fit,
        top: f64,
    ) -> Result<(UpdateReport, ModelPoint)> {
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
        let theta = point.theta().to_vec();
        let top = lines.last().copied().unwrap_or(0.0).max(top);
        let (modes, bending_modes) = model_modes(state, top);
        let fitted = Some((h, problem.request()));
        let truncation = self
            .setup
            .truncation_report(&kappa, &theta, &damping, state.modes.len(), fitted)?;
        fit.frf = Some(FrfFit {
            model: FrfFile {
                quantity: frf.quantity,
                frequency_hz: lines,
                frfs: model_entries,
                start_timestamp: None,
                end_timestamp: None,
            },
            residue,
        });
        let report = UpdateReport {
            result,
            fit,
            modes,
            bending_modes,
            kappa,
            theta,
            damping,
            truncation,
        };
        Ok((report, point))
    }
}

/// The paired modes of a modal fit, with the model's frequency and damping
/// at `state`.
fn paired(observed: &[ObservedMode], pairs: &[ModePair], state: &ModalState) -> Vec<PairedMode> {
    pairs
        .iter()
        .map(|p| {
            let (x, f) = (&observed[p.observed], state.modes.frequency_hz(p.model));
            PairedMode {
                identified: p.observed,
                model_mode: p.model,
                identified_frequency_hz: x.frequency_hz,
                model_frequency_hz: f,
                frequency_std_hz: x.frequency_std_hz,
                identified_damping: x.damping_ratio,
                model_damping: state.zeta[p.model],
                mac: p.mac,
            }
        })
        .collect()
}

/// A result the pipeline accepts: finite, and converged or at least better
/// than where it started (a solve stopped by `max_iterations` or a stall
/// that lowered the residual is published with `"converged": false` and its
/// stop reason, and becomes the next warm start: it fits the window better
/// than the last parameters do).
fn accepted(result: UpdateResult) -> Result<UpdateResult> {
    if result.parameters.iter().any(|p| !p.value.is_finite()) {
        bail!("non-finite parameters");
    }
    let improved = match (result.iterations.first(), result.iterations.last()) {
        (Some(first), Some(last)) => last.cost < first.cost,
        _ => false,
    };
    if !result.converged && !improved {
        bail!(
            "the updating did not converge ({:?}) and did not lower the residual",
            result.stop_reason
        );
    }
    Ok(result)
}

/// The model's modes up to `top` Hz, and its first
/// [`BENDING_MODES_KEPT`] bending modes with their shapes.
fn model_modes(state: &ModalState, top: f64) -> (Vec<(f64, f64, ModeKind)>, Vec<ModeShape>) {
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
    (modes, bending_modes)
}

#[cfg(test)]
mod tests {
    use super::*;
    use splinewatch_core::updating::{IterationRecord, StopReason};

    fn result(converged: bool, costs: &[f64]) -> UpdateResult {
        UpdateResult {
            parameters: Vec::new(),
            iterations: costs
                .iter()
                .enumerate()
                .map(|(iteration, &cost)| IterationRecord {
                    iteration,
                    relative_residual: cost,
                    cost,
                    parameters: Vec::new(),
                    step_norm: 0.0,
                    damping: 0.0,
                    rejected_steps: 0,
                })
                .collect(),
            converged,
            stop_reason: if converged {
                StopReason::RelativeOffset
            } else {
                StopReason::MaxIterations
            },
            relative_residual: 0.0,
            frf_relative_residuals: Vec::new(),
            singular_values: Vec::new(),
            condition_number: 1.0,
            residual_variance: 0.0,
            relative_offset: None,
            evaluations: costs.len(),
            lines_used: 0,
            correlations: Vec::new(),
            held: Vec::new(),
            covariance: None,
        }
    }

    /// Issue 31's warm-start policy: converged, or not converged but
    /// better than the start, is an update; neither is a failure that says so.
    #[test]
    fn an_update_is_accepted_when_converged_or_improved() {
        assert!(accepted(result(true, &[2.0, 1.0])).is_ok());
        assert!(accepted(result(false, &[2.0, 1.0])).is_ok());
        let e = accepted(result(false, &[2.0, 2.5])).unwrap_err().to_string();
        assert!(
            e.contains("did not converge (MaxIterations) and did not lower the residual"),
            "{e}"
        );
        assert!(accepted(result(false, &[2.0])).is_err());
    }
}
