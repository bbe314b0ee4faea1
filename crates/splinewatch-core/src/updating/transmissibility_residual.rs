//! Updating on an earthquake (issue 45): the FRF residues of eq. (36)–(39)
//! with measured transmissibilities (deck acceleration per ground
//! acceleration, [`crate::identification::transmissibility`]) in place of
//! accelerances, the model's from [`SupportMotion`] at every parameter point
//! (the quasi-static influence Γ moves with the bearings), its Jacobian from
//! the exact `∂T/∂p` of [`SupportMotion::sensitivities`]; solved by the shared
//! Levenberg–Marquardt loop with its bounds (eq. 42–43) and uncertainty.
//!
//! A measured input may stand for several model inputs: ground channels too
//! coherent to separate are combined into their mean, whose transmissibility
//! to a deck sensor is the sum of theirs (the deck responds to `Σ_c T_c u`
//! with every `u_c` equal). The weighting is the set's own
//! ([`Weighting::H1Variance`] with the multiple coherence for a short record).

use super::frf_residual::{relative_residuals, sqrt_weights, weighted_residues, MeasuredSet};
use super::solver::{self, Evaluated, ResidualModel};
use super::{
    check_parameters, fields_at, model_at, IterationRecord, Parameter, ParameterKind, UpdateError, UpdateResult,
    UpdateSettings,
};
use crate::model::damping::DampingCurve;
use crate::model::supports::SupportGroups;
use crate::model::ShellModel;
use crate::response::frf::{FrfModel, ModalState};
use crate::response::support_motion::{GroundInput, SupportMotion};
use faer::c64;

/// Updating a model against measured transmissibilities.
#[derive(Debug)]
pub struct TransmissibilityProblem<'a> {
    model: &'a FrfModel,
    shell: &'a ShellModel,
    groups: &'a SupportGroups,
    inputs: Vec<GroundInput>,
    /// Per measured input, the model inputs (indices into `inputs`) it sums.
    combined: Vec<Vec<usize>>,
    kappa: Vec<Vec<f64>>,
    damping: DampingCurve,
    parameters: Vec<Parameter>,
    measured: &'a MeasuredSet,
    settings: UpdateSettings,
    lines: Vec<usize>,
    frequencies: Vec<f64>,
    /// Every `(sensor, model input)` pair the measured FRFs need.
    model_pairs: Vec<(usize, usize)>,
    sqrt_weights: Vec<f64>,
}

/// The result and the model's modal state and support motion at it.
#[derive(Debug, Clone)]
pub struct TransmissibilitySolution {
    pub result: UpdateResult,
    pub state: ModalState,
    pub motion: SupportMotion,
    /// The model's transmissibilities of the measured FRFs on the selected
    /// lines, `[frf * n_lines + line]`.
    pub transmissibilities: Vec<c64>,
}

/// What an evaluation keeps.
#[derive(Debug, Clone)]
pub struct Extra {
    state: ModalState,
    motion: SupportMotion,
    h: Vec<c64>,
}

impl<'a> TransmissibilityProblem<'a> {
    /// The model `model` (built from `shell`) driven by `inputs`; the
    /// measured FRFs' `input` indexes `combined` (the model inputs each
    /// measured input sums, see the module), `output` the model's sensors.
    #[allow(clippy::too_many_arguments)] // the model, its supports and inputs, the start and the data
    pub fn new(
        (model, shell, groups): (&'a FrfModel, &'a ShellModel, &'a SupportGroups),
        inputs: Vec<GroundInput>,
        combined: Vec<Vec<usize>>,
        kappa: Vec<Vec<f64>>,
        damping: DampingCurve,
        parameters: Vec<Parameter>,
        measured: &'a MeasuredSet,
        settings: UpdateSettings,
    ) -> Result<Self, UpdateError> {
        check_parameters(&parameters, &kappa, model, &damping)?;
        if let Some(c) = combined
            .iter()
            .position(|g| g.is_empty() || g.iter().any(|&i| i >= inputs.len()))
        {
            return Err(UpdateError::Data(format!(
                "measured input {c} must name at least one of the {} model inputs",
                inputs.len()
            )));
        }
        for (b, frf) in measured.frfs().iter().enumerate() {
            if frf.output >= model.sensor_count() || frf.input >= combined.len() {
                return Err(UpdateError::Data(format!(
                    "frfs[{b}] refers to output {} or input {} the model does not have",
                    frf.output, frf.input
                )));
            }
        }
        let lines = settings.lines.select(measured.frequencies_hz());
        if lines.is_empty() {
            return Err(UpdateError::NoLines);
        }
        let residuals = 2 * lines.len() * measured.frfs().len();
        if residuals <= parameters.len() {
            return Err(UpdateError::Underdetermined {
                residuals,
                parameters: parameters.len(),
            });
        }
        let mut model_pairs = Vec::new();
        for frf in measured.frfs() {
            for &c in &combined[frf.input] {
                if !model_pairs.contains(&(frf.output, c)) {
                    model_pairs.push((frf.output, c));
                }
            }
        }
        let frequencies = lines.iter().map(|&i| measured.frequencies_hz()[i]).collect();
        let sqrt_weights = sqrt_weights(measured, &lines, settings.weighting)?;
        Ok(Self {
            model,
            shell,
            groups,
            inputs,
            combined,
            kappa,
            damping,
            parameters,
            measured,
            settings,
            lines,
            frequencies,
            model_pairs,
            sqrt_weights,
        })
    }

    /// Frequencies of the selected lines.
    pub fn line_frequencies(&self) -> &[f64] {
        &self.frequencies
    }

    /// Sums the model pairs' values `per_pair` (`[pair * n_lines + line]`)
    /// into the measured FRFs' layout.
    fn combine(&self, per_pair: &[c64]) -> Vec<c64> {
        let nl = self.lines.len();
        let mut out = vec![c64::new(0.0, 0.0); nl * self.measured.frfs().len()];
        for (b, frf) in self.measured.frfs().iter().enumerate() {
            for &c in &self.combined[frf.input] {
                let pair = self
                    .model_pairs
                    .iter()
                    .position(|&q| q == (frf.output, c))
                    .expect("listed in new");
                for l in 0..nl {
                    out[b * nl + l] += per_pair[pair * nl + l];
                }
            }
        }
        out
    }

    fn evaluate(&self, p: &[f64], jacobian: bool) -> Result<Evaluated<Extra>, UpdateError> {
        let (kappa, damping) = model_at(&self.parameters, &self.kappa, &self.damping, p)?;
        let theta = fields_at(&self.parameters, self.model.field_coefficients(), p);
        let state = self.model.modal_state_with_fields(&kappa, &theta, &damping)?;
        self.evaluate_state(p, state, jacobian)
    }

    fn evaluate_state(&self, p: &[f64], state: ModalState, jacobian: bool) -> Result<Evaluated<Extra>, UpdateError> {
        let (kappa, damping) = model_at(&self.parameters, &self.kappa, &self.damping, p)?;
        let theta = fields_at(&self.parameters, self.model.field_coefficients(), p);
        let motion = SupportMotion::new(
            self.model,
            self.shell,
            self.groups,
            &kappa,
            &theta,
            &state,
            &self.inputs,
        )
        .map_err(|e| UpdateError::Data(format!("support motion: {e}")))?;
        let loads = self.model.with_extra_rows(motion.load_rows(self.model));
        let load_state = loads.modal_state_from(state.modes.clone(), &damping);
        let per_pair = motion.transmissibility_with_residual(
            self.model,
            &loads,
            &load_state,
            &self.model_pairs,
            &self.frequencies,
        );
        let h = self.combine(&per_pair);
        let derivatives = jacobian.then(|| {
            let s = motion.sensitivities(
                self.model,
                &loads,
                self.groups,
                &state,
                &damping,
                &self.model_pairs,
                &self.frequencies,
            );
            self.parameters
                .iter()
                .map(|par| {
                    self.combine(match par.kind {
                        ParameterKind::Spring { field, coefficient } => {
                            &s.dkappa[self.model.flat_spring_index(field, coefficient)]
                        }
                        ParameterKind::Stiffness { field, coefficient } => {
                            &s.dtheta[self.model.flat_field_index(field, coefficient)]
                        }
                        ParameterKind::Damping { coefficient } => &s.dgamma[coefficient],
                    })
                })
                .collect::<Vec<_>>()
        });
        let columns: Option<Vec<&[c64]>> = derivatives.as_ref().map(|d| d.iter().map(Vec::as_slice).collect());
        let (residual, jacobian) = weighted_residues(
            self.measured,
            &self.lines,
            &self.sqrt_weights,
            &h,
            columns.as_deref(),
            p,
        )?;
        Ok(Evaluated {
            residual,
            jacobian,
            extra: Extra { state, motion, h },
        })
    }

    /// Runs the updating from `start` (warm start: the previous event's values).
    pub fn solve(
        &self,
        start: &[f64],
        observer: &mut dyn FnMut(&IterationRecord),
    ) -> Result<TransmissibilitySolution, UpdateError> {
        let solved = solver::levenberg_marquardt(self, start, None, observer)?;
        let (relative_residual, per_block) = relative_residuals(self.measured, &self.lines, &solved.at.extra.h);
        let fit = solver::FitMeasures {
            relative_residual,
            per_block,
            lines_used: self.lines.len(),
        };
        let (result, _, at) = solved.into_result(&self.parameters, fit);
        Ok(TransmissibilitySolution {
            result,
            state: at.extra.state,
            motion: at.extra.motion,
            transmissibilities: at.extra.h,
        })
    }
}

impl ResidualModel for TransmissibilityProblem<'_> {
    type Extra = Extra;
    type Previous = ();

    fn parameters(&self) -> &[Parameter] {
        &self.parameters
    }

    fn settings(&self) -> &UpdateSettings {
        &self.settings
    }

    fn first(&self, p: &[f64], _previous: Option<&()>) -> Result<(Evaluated<Extra>, usize), UpdateError> {
        Ok((self.evaluate(p, true)?, 1))
    }

    fn residual(&self, p: &[f64]) -> Result<Evaluated<Extra>, UpdateError> {
        self.evaluate(p, false)
    }

    fn with_jacobian(&self, p: &[f64], trial: Evaluated<Extra>) -> Result<Evaluated<Extra>, UpdateError> {
        self.evaluate_state(p, trial.extra.state, true)
    }

    fn relative_residual(&self, at: &Evaluated<Extra>) -> f64 {
        relative_residuals(self.measured, &self.lines, &at.extra.h).0
    }
}
