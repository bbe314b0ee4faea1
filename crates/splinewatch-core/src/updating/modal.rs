//! Modal-residue updating (output-only): the residues of
//! [`crate::updating::modal_residual`] as a [`ResidualModel`] of the shared solver.
//! The pairing is redone at every evaluation, so a mode that changes order
//! as κ moves is followed; the cost is compared across steps on whatever
//! pairs each step has.

use super::solver::{self, Evaluated, ResidualModel};
use super::{check_parameters, IterationRecord, Parameter, UpdateError, UpdateResult, UpdateSettings};
use crate::model::damping::DampingCurve;
use crate::response::frf::{FrfModel, ModalState};
use crate::updating::modal_residual::{modal_residue, pair_modes, ModalResidue, ModePair, ObservedMode};

/// Updating a model against identified modes.
#[derive(Debug, Clone)]
pub struct ModalUpdateProblem<'a> {
    model: &'a FrfModel,
    kappa: Vec<Vec<f64>>,
    damping: DampingCurve,
    parameters: Vec<Parameter>,
    observed: &'a [ObservedMode],
    settings: UpdateSettings,
    /// Smallest MAC of a pair, largest relative frequency gap.
    min_mac: f64,
    max_gap: f64,
}

/// The result, the pairs and the model's modal state at the solution.
#[derive(Debug, Clone)]
pub struct ModalSolution {
    pub result: UpdateResult,
    pub pairs: Vec<ModePair>,
    pub state: ModalState,
}

impl<'a> ModalUpdateProblem<'a> {
    /// `kappa` and `damping` give the values of parameters not updated;
    /// identified modes must be finite with positive standard deviations;
    /// pairs need a MAC of at least `min_mac` within `max_gap` relative
    /// frequency (see [`pair_modes`]).
    pub fn new(
        model: &'a FrfModel,
        kappa: Vec<Vec<f64>>,
        damping: DampingCurve,
        parameters: Vec<Parameter>,
        observed: &'a [ObservedMode],
        settings: UpdateSettings,
        (min_mac, max_gap): (f64, f64),
    ) -> Result<Self, UpdateError> {
        check_parameters(&parameters, &kappa, model, &damping)?;
        for (k, m) in observed.iter().enumerate() {
            let positive = |v: f64| v.is_finite() && v > 0.0;
            if !(positive(m.frequency_hz)
                && positive(m.frequency_std_hz)
                && positive(m.damping_std)
                && positive(m.shape_std)
                && m.damping_ratio.is_finite())
            {
                return Err(UpdateError::Data(format!(
                    "identified mode {k}: frequency and the standard deviations must be positive and finite"
                )));
            }
            if m.shape.is_empty()
                || m.shape
                    .iter()
                    .any(|&(s, v)| s >= model.sensor_count() || !v.re.is_finite() || !v.im.is_finite())
            {
                return Err(UpdateError::Data(format!(
                    "identified mode {k}: its shape must name model sensors and be finite"
                )));
            }
        }
        if !(0.0..1.0).contains(&min_mac) {
            return Err(UpdateError::Data(format!(
                "the pairing MAC threshold {min_mac} must be in [0, 1)"
            )));
        }
        Ok(Self {
            model,
            kappa,
            damping,
            parameters,
            observed,
            settings,
            min_mac,
            max_gap,
        })
    }

    /// Spring coefficients and damping curve at parameter values `p`.
    pub fn model_at(&self, p: &[f64]) -> Result<(Vec<Vec<f64>>, DampingCurve), UpdateError> {
        super::model_at(&self.parameters, &self.kappa, &self.damping, p)
    }

    /// Stiffness-field coefficients at parameter values `p`.
    pub fn fields_at(&self, p: &[f64]) -> Vec<Vec<f64>> {
        super::fields_at(&self.parameters, self.model.field_coefficients(), p)
    }

    /// The model with a Ritz basis at `start` for the springs the
    /// parameters move, where one serves ([`super::reanalysed_springs`]
    /// and a basis much smaller than the model); `None` otherwise.
    fn reanalysed_at(&self, start: &[f64]) -> Result<Option<FrfModel>, UpdateError> {
        let Some(varied) = super::reanalysed_springs(&self.parameters, self.model) else {
            return Ok(None);
        };
        let (kappa, damping) = self.model_at(start)?;
        let loads = self.model.loss_factor_loads(&damping);
        let reduced = self
            .model
            .with_reanalysis((&kappa, &self.fields_at(start)), &loads, &varied)?;
        Ok(reduced.reanalysis().is_some().then_some(reduced))
    }

    /// The same problem on `model` (a Ritz basis of this one's).
    pub(super) fn on_model<'b>(&self, model: &'b FrfModel) -> ModalUpdateProblem<'b>
    where
        'a: 'b,
    {
        ModalUpdateProblem { model, ..self.clone() }
    }

    /// The identified modes paired with `state`'s ([`pair_modes`]).
    pub(super) fn pairs_at(&self, state: &ModalState) -> Vec<ModePair> {
        pair_modes(state, self.observed, self.min_mac, self.max_gap)
    }

    /// The residues of `pairs` at `state` ([`modal_residue`]).
    pub(super) fn residue_at(&self, state: &ModalState, pairs: &[ModePair], jacobian: bool) -> ModalResidue {
        modal_residue(self.model, state, self.observed, pairs, &self.parameters, jacobian)
    }

    /// The identified modes.
    pub(super) fn observed(&self) -> &[ObservedMode] {
        self.observed
    }

    fn evaluate(&self, p: &[f64], jacobian: bool) -> Result<Evaluated<Extra>, UpdateError> {
        let (kappa, damping) = self.model_at(p)?;
        let state = self
            .model
            .modal_state_with_fields(&kappa, &self.fields_at(p), &damping)?;
        let pairs = self.pairs_at(&state);
        let residue = self.residue_at(&state, &pairs, jacobian);
        if residue.residual.len() <= self.parameters.len() {
            return Err(UpdateError::Underdetermined {
                residuals: residue.residual.len(),
                parameters: self.parameters.len(),
            });
        }
        if residue.residual.iter().any(|r| !r.is_finite()) {
            return Err(UpdateError::NonFinite(p.to_vec()));
        }
        Ok(Evaluated {
            residual: residue.residual,
            jacobian: residue.jacobian,
            extra: Extra { state, damping, pairs },
        })
    }

    /// Runs the updating from `start` (warm start: the last accepted
    /// values). On a truncated model whose parameters are springs and
    /// damping, the search runs on a Ritz basis of `start` and finishes on
    /// the complete model ([`solver::levenberg_marquardt_staged`]).
    pub fn solve(
        &self,
        start: &[f64],
        observer: &mut dyn FnMut(&IterationRecord),
    ) -> Result<ModalSolution, UpdateError> {
        let solved = match self.reanalysed_at(start)? {
            Some(reduced) => {
                let coarse = self.on_model(&reduced);
                solver::levenberg_marquardt_staged(&coarse, self, start, observer)?
            }
            None => solver::levenberg_marquardt(self, start, None, observer)?,
        };
        let relative_residual = self.relative_residual(&solved.at);
        let Extra { state, pairs, .. } = &solved.at.extra;
        let fit = solver::FitMeasures {
            relative_residual,
            per_block: pairs
                .iter()
                .map(|p| {
                    let f = state.modes.frequency_hz(p.model);
                    let x = self.observed[p.observed].frequency_hz;
                    ((f - x) / x).abs()
                })
                .collect(),
            lines_used: pairs.len(),
        };
        let (result, _, at) = solved.into_result(&self.parameters, fit);
        let Extra { state, pairs, .. } = at.extra;
        Ok(ModalSolution { result, pairs, state })
    }
}

/// What a modal evaluation keeps.
#[derive(Debug, Clone)]
pub struct Extra {
    pub state: ModalState,
    pub damping: DampingCurve,
    pub pairs: Vec<ModePair>,
}

impl ResidualModel for ModalUpdateProblem<'_> {
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

    fn with_jacobian(&self, _p: &[f64], trial: Evaluated<Extra>) -> Result<Evaluated<Extra>, UpdateError> {
        let residue = self.residue_at(&trial.extra.state, &trial.extra.pairs, true);
        Ok(Evaluated {
            residual: residue.residual,
            jacobian: residue.jacobian,
            extra: trial.extra,
        })
    }

    /// Root mean square relative frequency error over the paired modes.
    fn relative_residual(&self, at: &Evaluated<Extra>) -> f64 {
        let pairs = &at.extra.pairs;
        let sum: f64 = pairs
            .iter()
            .map(|p| {
                let f = at.extra.state.modes.frequency_hz(p.model);
                let x = self.observed[p.observed].frequency_hz;
                ((f - x) / x).powi(2)
            })
            .sum();
        (sum / pairs.len().max(1) as f64).sqrt()
    }
}
