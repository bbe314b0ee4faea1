//! Updating on an earthquake (issue 45): the FRF residues of eq. (36)–(39)
//! with measured transmissibilities (deck acceleration per ground
//! acceleration, [`crate::identification::transmissibility`]) in place of
//! accelerances, the model's from [`SupportMotion`] at every parameter point
//! (the quasi-static influence Γ moves with the bearings), its Jacobian from
//! the exact `∂T/∂p` of [`SupportMotion::sensitivities`]; solved by the shared
//! Levenberg–Marquardt loop with its bounds (eq. 42–43) and uncertainty.
//!
//! Two kinds of measured data ([`Combination`]):
//!
//! - **transmissibilities** (H1 estimates): a measured input may stand for
//!   several model inputs: ground channels too coherent to separate are
//!   combined into their mean, whose transmissibility to a deck sensor is the
//!   sum of theirs (the deck responds to `Σ_c T_c u` with every `u_c` equal);
//!   weighted as the set says ([`super::Weighting::H1Variance`] from the multiple
//!   coherence for a short record);
//! - **the record's spectra**: the measured values are the deck's output
//!   spectra `Y_o(ω)` (the DFT of the whole record) and the model's are
//!   `Σ_c T_oc(ω, p) U_c(ω)` with the ground inputs' spectra `U_c`: the
//!   frequency-domain output error of a system with known inputs (Pintelon &
//!   Schoukens, *System Identification: A Frequency Domain Approach*, 2012,
//!   §7–9), exact for a record that starts and ends at rest, with every input
//!   at once and no averaging: what a minute-long earthquake record with
//!   partially coherent grounds allows (a multi-input H1 of it has a few
//!   averages per input). Its relative residual is the NRMSE of the deck's
//!   response over the band (Parseval).

use super::frf_residual::{parameter_column, relative_residuals, sqrt_weights, weighted_residues, MeasuredSet};
use super::modal_residual::ObservedMode;
use super::solver::{self, Evaluated, ResidualModel};
use super::{
    check_parameters, fields_at, model_at, reanalysed_springs, IterationRecord, ModalUpdateProblem, Parameter,
    UpdateError, UpdateResult, UpdateSettings,
};
use crate::model::damping::DampingCurve;
use crate::response::frf::{FrfModel, LineRuns, ModalState};
use crate::response::support_motion::{GroundInput, GroundedStructure, SensitivitySelection, SupportMotion};
use faer::c64;
use std::ops::Range;

/// How the model's transmissibilities make the measured values.
#[derive(Debug, Clone, PartialEq)]
pub enum Combination {
    /// Measured transmissibilities: per measured input, the model inputs
    /// (indices into the ground inputs) whose transmissibilities it sums.
    Sum(Vec<Vec<usize>>),
    /// Measured output spectra (every FRF's `input` is 0): per model input,
    /// its spectrum on the measured frequency axis; the model's value is
    /// `Σ_c T_oc U_c`.
    Spectra(Vec<Vec<c64>>),
}

/// Updating a model against measured transmissibilities or a record's spectra.
#[derive(Debug, Clone)]
pub struct TransmissibilityProblem<'a> {
    model: &'a FrfModel,
    grounded: &'a GroundedStructure,
    inputs: Vec<GroundInput>,
    /// How the model pairs' values make the measured ones ([`Self::combine`]).
    terms: CombineTerms,
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
    pub(super) state: ModalState,
    pub(super) motion: SupportMotion,
    pub(super) h: Vec<c64>,
}

/// A parameter point's model, shared by the threads of an evaluation.
struct LinePoint<'p> {
    state: &'p ModalState,
    motion: &'p SupportMotion,
    loads: &'p FrfModel,
    load_state: &'p ModalState,
    damping: &'p DampingCurve,
}

impl<'a> TransmissibilityProblem<'a> {
    /// The model `model` (of the structure `grounded`) driven by `inputs`; the
    /// measured FRFs' `output` indexes the model's sensors, their `input`
    /// the measured inputs of `combination` (see [`Combination`]).
    #[allow(clippy::too_many_arguments)] // the model, its supports and inputs, the start and the data
    pub fn new(
        (model, grounded): (&'a FrfModel, &'a GroundedStructure),
        inputs: Vec<GroundInput>,
        combination: Combination,
        kappa: Vec<Vec<f64>>,
        damping: DampingCurve,
        parameters: Vec<Parameter>,
        measured: &'a MeasuredSet,
        settings: UpdateSettings,
    ) -> Result<Self, UpdateError> {
        check_parameters(&parameters, &kappa, model, &damping)?;
        grounded
            .check_inputs(&inputs)
            .map_err(|e| UpdateError::Data(format!("support motion: {e}")))?;
        let measured_inputs = match &combination {
            Combination::Sum(groups) => {
                if let Some(c) = groups
                    .iter()
                    .position(|g| g.is_empty() || g.iter().any(|&i| i >= inputs.len()))
                {
                    return Err(UpdateError::Data(format!(
                        "measured input {c} must name at least one of the {} model inputs",
                        inputs.len()
                    )));
                }
                groups.len()
            }
            Combination::Spectra(spectra) => {
                let n = measured.frequencies_hz().len();
                if spectra.len() != inputs.len() || spectra.iter().any(|u| u.len() != n) {
                    return Err(UpdateError::Data(format!(
                        "one input spectrum of {n} lines per model input ({}) is needed",
                        inputs.len()
                    )));
                }
                1
            }
        };
        for (b, frf) in measured.frfs().iter().enumerate() {
            if frf.output >= model.sensor_count() || frf.input >= measured_inputs {
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
            for c in model_inputs(&combination, frf.input, inputs.len()) {
                if !model_pairs.contains(&(frf.output, c)) {
                    model_pairs.push((frf.output, c));
                }
            }
        }
        let frequencies = lines.iter().map(|&i| measured.frequencies_hz()[i]).collect();
        let sqrt_weights = sqrt_weights(measured, &lines, settings.weighting)?;
        let terms = CombineTerms::new(&combination, measured, &model_pairs, &lines, inputs.len());
        Ok(Self {
            model,
            grounded,
            inputs,
            terms,
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

    /// The same problem on `model` (a Ritz basis of this one's).
    pub(super) fn on_model<'b>(&self, model: &'b FrfModel) -> TransmissibilityProblem<'b>
    where
        'a: 'b,
    {
        TransmissibilityProblem { model, ..self.clone() }
    }

    /// The modal residues of `observed` on this problem's model and
    /// parameters, paired as [`ModalUpdateProblem::new`] says.
    pub(super) fn modal_problem(
        &self,
        observed: &'a [ObservedMode],
        pairing: (f64, f64),
    ) -> Result<ModalUpdateProblem<'a>, UpdateError> {
        ModalUpdateProblem::new(
            self.model,
            self.kappa.clone(),
            self.damping.clone(),
            self.parameters.clone(),
            observed,
            self.settings.clone(),
            pairing,
        )
    }

    /// The unweighted relative residual of the model values `h` on the
    /// selected lines, over all and per measured FRF.
    pub(super) fn fit_of(&self, h: &[c64]) -> (f64, Vec<f64>) {
        relative_residuals(self.measured, &self.lines, h)
    }

    /// The model pairs' values `per_pair` (`[pair * n + k]` on the `n`
    /// selected lines `run`) made into the measured FRFs' layout
    /// (`[frf * n + k]`): summed, or weighted by the inputs' spectra
    /// ([`Combination`]).
    fn combine(&self, per_pair: &[c64], run: Range<usize>) -> Vec<c64> {
        let nl = run.len();
        let mut out = vec![c64::new(0.0, 0.0); nl * self.measured.frfs().len()];
        for &(b, pair, c) in &self.terms.terms {
            let (out, values) = (&mut out[b * nl..][..nl], &per_pair[pair * nl..][..nl]);
            match &self.terms.input_weights {
                None => out
                    .iter_mut()
                    .zip(values)
                    .for_each(|(o, v)| *o += v * c64::new(1.0, 0.0)),
                Some(weights) => out
                    .iter_mut()
                    .zip(values)
                    .zip(&weights[c][run.clone()])
                    .for_each(|((o, v), w)| *o += v * w),
            }
        }
        out
    }

    /// The residual (and Jacobian) at `p`: the modal state and the support
    /// motion from one eigen-solve ([`SupportMotion::with_state`]).
    pub(super) fn evaluate(&self, p: &[f64], jacobian: bool) -> Result<Evaluated<Extra>, UpdateError> {
        let (kappa, damping) = model_at(&self.parameters, &self.kappa, &self.damping, p)?;
        let theta = fields_at(&self.parameters, self.model.field_coefficients(), p);
        let (state, motion) =
            SupportMotion::with_state((self.model, self.grounded), (&kappa, &theta, &damping), &self.inputs)
                .map_err(|e| UpdateError::Data(format!("support motion: {e}")))?;
        self.evaluate_motion(p, state, motion, jacobian)
    }

    /// The residual (and Jacobian) at `p` from its modal state and motion:
    /// the lines in runs on up to `threads` threads ([`LineRuns`]; the same
    /// bits whatever their number).
    pub(super) fn evaluate_motion(
        &self,
        p: &[f64],
        state: ModalState,
        motion: SupportMotion,
        jacobian: bool,
    ) -> Result<Evaluated<Extra>, UpdateError> {
        let (_, damping) = model_at(&self.parameters, &self.kappa, &self.damping, p)?;
        let loads = self.model.with_extra_rows(motion.load_rows());
        let load_state = loads.restate(&state, &damping);
        let springs: Option<Vec<usize>> = jacobian.then(|| {
            self.parameters
                .iter()
                .flat_map(|p| p.kind.springs())
                .map(|(f, c)| self.model.flat_spring_index(f, c))
                .collect()
        });
        let runs = LineRuns::new(self.frequencies.len(), self.settings.threads);
        let at = LinePoint {
            state: &state,
            motion: &motion,
            loads: &loads,
            load_state: &load_state,
            damping: &damping,
        };
        let parts = runs.map(|run| self.on_lines(run, &at, springs.as_deref()));
        let mut values = Vec::with_capacity(parts.len());
        let mut columns = vec![Vec::with_capacity(parts.len()); if jacobian { self.parameters.len() } else { 0 }];
        for (h, part_columns) in parts {
            values.push(h);
            columns.iter_mut().zip(part_columns).for_each(|(c, v)| c.push(v));
        }
        let h = runs.merge(values);
        let derivatives: Option<Vec<Vec<c64>>> = jacobian.then(|| columns.into_iter().map(|c| runs.merge(c)).collect());
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

    /// The model's values on the selected lines `run` (`[frf * n + k]`)
    /// and, given the parameters' `springs` (flat indices), every
    /// parameter's column of them.
    fn on_lines(&self, run: Range<usize>, at: &LinePoint<'_>, springs: Option<&[usize]>) -> (Vec<c64>, Vec<Vec<c64>>) {
        let frequencies = &self.frequencies[run.clone()];
        let per_pair = at.motion.transmissibility_with_residual(
            self.model,
            at.loads,
            at.load_state,
            &self.model_pairs,
            frequencies,
        );
        let h = self.combine(&per_pair, run.clone());
        let Some(springs) = springs else {
            return (h, Vec::new());
        };
        let s = at.motion.sensitivities_for(
            self.model,
            (at.loads, at.load_state),
            self.grounded.groups(),
            at.state,
            at.damping,
            &self.model_pairs,
            frequencies,
            SensitivitySelection {
                springs: Some(springs),
                fields: super::updates_fields(&self.parameters),
            },
        );
        let columns = self
            .parameters
            .iter()
            .map(|par| {
                self.combine(
                    &parameter_column(self.model, par.kind, &s.dkappa, &s.dtheta, (&self.damping, &s.dgamma)),
                    run.clone(),
                )
            })
            .collect();
        (h, columns)
    }

    /// Runs the updating from `start` (warm start: the previous event's
    /// values). On a truncated model whose parameters are springs and
    /// damping, the search runs on a Ritz basis built at `start`
    /// ([`SupportMotion::reanalysed`]: one complete solve instead of one per
    /// evaluation), then goes on from where it stopped on the complete model
    /// until the stopping rules hold there (`max_iterations` bounds both
    /// stages together): the result, its uncertainty and the state it
    /// returns are the complete model's.
    pub fn solve(
        &self,
        start: &[f64],
        observer: &mut dyn FnMut(&IterationRecord),
    ) -> Result<TransmissibilitySolution, UpdateError> {
        let solved = match self.reanalysed_at(start)? {
            Some(reduced) => {
                let coarse = self.on_model(&reduced);
                solver::levenberg_marquardt_staged(&coarse, self, start, observer)?
            }
            None => solver::levenberg_marquardt(self, start, None, observer)?,
        };
        let (relative_residual, per_block) = self.fit_of(&solved.at.extra.h);
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

    /// The model with a Ritz basis at `start` for the springs the
    /// parameters move, when it is truncated, no parameter is a stiffness
    /// field (those change the deck everywhere) and the basis is much
    /// smaller than the model; `None` otherwise.
    pub(super) fn reanalysed_at(&self, start: &[f64]) -> Result<Option<FrfModel>, UpdateError> {
        let Some(varied) = reanalysed_springs(&self.parameters, self.model) else {
            return Ok(None);
        };
        let (kappa, damping) = model_at(&self.parameters, &self.kappa, &self.damping, start)?;
        let theta = fields_at(&self.parameters, self.model.field_coefficients(), start);
        SupportMotion::reanalysed(
            (self.model, self.grounded),
            (&kappa, &theta),
            (&self.inputs, &self.model.loss_factor_loads(&damping)),
            &varied,
        )
        .map(|reduced| reduced.reanalysis().is_some().then_some(reduced))
        .map_err(|e| UpdateError::Data(format!("support motion: {e}")))
    }
}

/// The model inputs behind measured input `input`.
/// [`TransmissibilityProblem::combine`]'s plan: `(measured FRF, model pair,
/// model input)` per term, in the measured FRFs' order, and with spectra
/// each model input's spectrum on the selected lines.
#[derive(Debug, Clone)]
struct CombineTerms {
    terms: Vec<(usize, usize, usize)>,
    input_weights: Option<Vec<Vec<c64>>>,
}

impl CombineTerms {
    fn new(
        combination: &Combination,
        measured: &MeasuredSet,
        model_pairs: &[(usize, usize)],
        lines: &[usize],
        count: usize,
    ) -> Self {
        let mut terms = Vec::new();
        for (b, frf) in measured.frfs().iter().enumerate() {
            for c in model_inputs(combination, frf.input, count) {
                let pair = model_pairs
                    .iter()
                    .position(|&q| q == (frf.output, c))
                    .expect("every measured FRF's pairs are listed");
                terms.push((b, pair, c));
            }
        }
        let input_weights = match combination {
            Combination::Sum(_) => None,
            Combination::Spectra(u) => Some(u.iter().map(|u| lines.iter().map(|&l| u[l]).collect()).collect()),
        };
        Self { terms, input_weights }
    }
}

fn model_inputs(combination: &Combination, input: usize, count: usize) -> Vec<usize> {
    match combination {
        Combination::Sum(groups) => groups[input].clone(),
        Combination::Spectra(_) => (0..count).collect(),
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
        self.evaluate_motion(p, trial.extra.state, trial.extra.motion, true)
    }

    fn relative_residual(&self, at: &Evaluated<Extra>) -> f64 {
        self.fit_of(&at.extra.h).0
    }
}
