//! Residues of a measured response and modal residues fitted together:
//! where a force is measured and a window's modes are also identified
//! output-only, one update can fit both (`[updating] residues = "both"`,
//! [`JointUpdateProblem`]); on an earthquake, the record's transmissibilities
//! or spectra and the modes identified from it (`[events] residues =
//! "both"`, [`JointTransmissibilityProblem`]).
//!
//! Each block is weighted by its own uncertainty, so that every residue is
//! a standard normal variable when the model is right and the blocks add up
//! as two chi-squares:
//! - FRF residues (eq. 36–39), real and imaginary parts, each divided by its
//!   random error: the H1 estimator's complex variance
//!   `(1 − γ²)/(γ² n_d) |H|²` (Bendat & Piersol, *Random Data*, §9.2,
//!   the [`Weighting::H1Variance`] weighting) splits evenly between the two
//!   parts, so the block is the H1-weighted residual times √2; the same
//!   holds for H1 transmissibilities. A record's spectra have no estimator
//!   variance: their block is divided by the prediction-error standard
//!   deviation `σ̂` of a fit of the spectra alone, the maximum-likelihood
//!   estimate `‖r‖²/(m − n)` (Beck & Katafygiotis, "Updating models and
//!   their uncertainties. I: Bayesian statistical framework", *J. Eng.
//!   Mech.* 124(4), 1998), which the caller passes as the block's scale;
//! - modal residues of [`crate::updating::modal_residual`], already divided
//!   by the identification's standard deviations.
//!
//! The model is solved once per evaluation; the response and the paired
//! modes come from the same modal state. Pairs are redone at every
//! evaluation and held within one Jacobian, as in [`super::ModalUpdateProblem`].

use super::frf_residual::{MeasuredSet, ModelPoint, UpdateProblem};
use super::modal_residual::{ModalResidue, ModePair, ObservedMode};
use super::solver::{self, Evaluated, ResidualModel};
use super::transmissibility_residual::{self as transmissibility, TransmissibilityProblem, TransmissibilitySolution};
use super::{IterationRecord, ModalUpdateProblem, Parameter, UpdateError, UpdateResult, UpdateSettings, Weighting};
use crate::model::damping::DampingCurve;
use crate::response::frf::{FrfEvaluation, FrfModel, ModalState};
use faer::Mat;
use std::f64::consts::SQRT_2;

/// Updating a model against measured FRFs and identified modes at once.
#[derive(Debug)]
pub struct JointUpdateProblem<'a> {
    frf: UpdateProblem<'a>,
    modal: ModalUpdateProblem<'a>,
}

/// The result, the model at it (a [`ModelPoint`] of the FRF block, for the
/// next warm start) and the mode pairs there.
#[derive(Debug, Clone)]
pub struct JointSolution {
    pub result: UpdateResult,
    pub point: ModelPoint,
    pub pairs: Vec<ModePair>,
    /// Rows of the FRF block (`2 × lines × FRFs`) and of the modal block at
    /// the solution, and each block's share of the cost `½‖r‖²`.
    pub blocks: [BlockFit; 2],
}

/// One block's size and cost at the solution.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlockFit {
    pub residues: usize,
    /// `‖r_b‖²`: about `residues` when the block's weights are its variances
    /// and the model fits.
    pub chi_square: f64,
}

/// What a joint evaluation keeps: the modal state, the model FRFs (with
/// sensitivities when the Jacobian was asked for), the damping curve, the
/// pairs and where the FRF block ends.
#[derive(Debug, Clone)]
pub struct Extra {
    pub state: ModalState,
    pub frfs: FrfEvaluation,
    pub damping: DampingCurve,
    pub pairs: Vec<ModePair>,
    pub frf_rows: usize,
}

impl<'a> JointUpdateProblem<'a> {
    /// `measured` must carry coherence and the number of averages (the FRF
    /// block's weights); `settings.weighting` is replaced by them.
    /// `(min_mac, max_gap)` pair the identified modes as in
    /// [`ModalUpdateProblem::new`].
    #[allow(
        clippy::too_many_arguments,
        reason = "the two problems' inputs: one model, its parameters, each block's data, the settings and the pairing"
    )]
    pub fn new(
        model: &'a FrfModel,
        kappa: Vec<Vec<f64>>,
        damping: DampingCurve,
        parameters: Vec<Parameter>,
        measured: &'a MeasuredSet,
        observed: &'a [ObservedMode],
        settings: UpdateSettings,
        pairing: (f64, f64),
    ) -> Result<Self, UpdateError> {
        let weighted = UpdateSettings {
            weighting: Weighting::H1Variance,
            ..settings.clone()
        };
        let frf = UpdateProblem::new(
            model,
            kappa.clone(),
            damping.clone(),
            parameters.clone(),
            measured,
            weighted,
        )
        .map_err(|e| match e {
            UpdateError::Data(m) if m.contains("h1_variance") => UpdateError::Data(format!(
                "{m}: the FRF block of a joint update is weighted by the H1 estimator's variance"
            )),
            e => e,
        })?;
        let modal = ModalUpdateProblem::new(model, kappa, damping, parameters, observed, settings, pairing)?;
        Ok(Self { frf, modal })
    }

    /// The FRF block's problem (its lines, request, model at `p`).
    pub fn frf(&self) -> &UpdateProblem<'a> {
        &self.frf
    }

    /// The stacked residues at `state`, from the FRF block's evaluation
    /// there (`frfs`, with sensitivities if `jacobian`) and the modal
    /// residues of `pairs` (found at `state` when `None`).
    fn stack(
        &self,
        p: &[f64],
        state: ModalState,
        frfs: FrfEvaluation,
        pairs: Option<Vec<ModePair>>,
        jacobian: bool,
    ) -> Result<Evaluated<Extra>, UpdateError> {
        let frf = self.frf.weighted(p, frfs, jacobian)?;
        let (_, damping) = self.frf.model_at(p)?;
        let pairs = pairs.unwrap_or_else(|| self.modal.pairs_at(&state));
        let modal = self.modal.residue_at(&state, &pairs, jacobian);
        if modal.residual.iter().any(|r| !r.is_finite()) {
            return Err(UpdateError::NonFinite(p.to_vec()));
        }
        let frf_rows = frf.residual.len();
        let n = self.frf.parameters().len();
        let (residual, jac) = stack_blocks(SQRT_2, (&frf.residual, &frf.jacobian), &modal, jacobian, n);
        Ok(Evaluated {
            residual,
            jacobian: jac,
            extra: Extra {
                state,
                frfs: frf.extra,
                damping,
                pairs,
                frf_rows,
            },
        })
    }

    /// Runs the updating from `start`; `previous` (the point the last solve
    /// ended on) saves the first evaluation when it is this model at `start`
    /// on these lines, as in [`UpdateProblem::solve_from`].
    #[track_caller]
    pub fn solve_from(
        &self,
        start: &[f64],
        previous: Option<&ModelPoint>,
        observer: &mut dyn FnMut(&IterationRecord),
    ) -> Result<JointSolution, UpdateError> {
        let solved = solver::levenberg_marquardt(self, start, previous, observer)?;
        let (relative_residual, per_block) = self.frf.relative_residuals(&solved.at.extra.frfs.h);
        let fit = solver::FitMeasures {
            relative_residual,
            per_block,
            lines_used: self.frf.line_frequencies().len(),
        };
        let (result, p, at) = solved.into_result(self.frf.parameters(), fit);
        let blocks = block_fits(&at.residual, at.extra.frf_rows);
        let Extra { state, frfs, pairs, .. } = at.extra;
        let point = self.frf.point(&p, state, frfs)?;
        Ok(JointSolution {
            result,
            point,
            pairs,
            blocks,
        })
    }

    /// The identified modes.
    pub fn observed(&self) -> &[ObservedMode] {
        self.modal.observed()
    }
}

impl ResidualModel for JointUpdateProblem<'_> {
    type Extra = Extra;
    type Previous = ModelPoint;

    fn parameters(&self) -> &[Parameter] {
        self.frf.parameters()
    }

    fn settings(&self) -> &UpdateSettings {
        ResidualModel::settings(&self.modal)
    }

    fn first(&self, p: &[f64], previous: Option<&ModelPoint>) -> Result<(Evaluated<Extra>, usize), UpdateError> {
        if let Some(point) = self.frf.reusable(previous, p)? {
            let at = self.stack(p, point.state().clone(), point.evaluation().clone(), None, true)?;
            return Ok((at, 0));
        }
        let state = self.frf.state_at(p)?;
        let frfs = self.frf.frfs_at(p, &state, true)?;
        Ok((self.stack(p, state, frfs, None, true)?, 1))
    }

    fn residual(&self, p: &[f64]) -> Result<Evaluated<Extra>, UpdateError> {
        let state = self.frf.state_at(p)?;
        let frfs = self.frf.frfs_at(p, &state, false)?;
        self.stack(p, state, frfs, None, false)
    }

    fn with_jacobian(&self, p: &[f64], trial: Evaluated<Extra>) -> Result<Evaluated<Extra>, UpdateError> {
        let Extra { state, pairs, .. } = trial.extra;
        let frfs = self.frf.frfs_at(p, &state, true)?;
        self.stack(p, state, frfs, Some(pairs), true)
    }

    /// The FRF block's unweighted relative residual (the modal block's fit
    /// is reported per pair).
    fn relative_residual(&self, at: &Evaluated<Extra>) -> f64 {
        self.frf.relative_residuals(&at.extra.frfs.h).0
    }
}

/// `[scale · r; r_modal]` and, when `jacobian`, `[scale · J; J_modal]`
/// (`n` parameters).
fn stack_blocks(
    scale: f64,
    (response, response_jacobian): (&[f64], &Mat<f64>),
    modal: &ModalResidue,
    jacobian: bool,
    n: usize,
) -> (Vec<f64>, Mat<f64>) {
    let rows = response.len();
    let mut residual: Vec<f64> = response.iter().map(|r| scale * r).collect();
    residual.extend_from_slice(&modal.residual);
    let jac = if jacobian {
        Mat::from_fn(residual.len(), n, |i, c| {
            if i < rows {
                scale * response_jacobian[(i, c)]
            } else {
                modal.jacobian[(i - rows, c)]
            }
        })
    } else {
        Mat::zeros(0, 0)
    };
    (residual, jac)
}

/// Each block's size and chi-square, the response block the first `rows`.
fn block_fits(residual: &[f64], rows: usize) -> [BlockFit; 2] {
    let (response, modal) = residual.split_at(rows);
    [response, modal].map(|r| BlockFit {
        residues: r.len(),
        chi_square: r.iter().map(|v| v * v).sum(),
    })
}

/// An earthquake record's transmissibilities (or spectra) and the modes
/// identified from it, fitted together.
#[derive(Debug, Clone)]
pub struct JointTransmissibilityProblem<'a> {
    response: TransmissibilityProblem<'a>,
    modal: ModalUpdateProblem<'a>,
    /// The factor that makes the response block's residues standard normal.
    scale: f64,
}

/// The response block's solution, the mode pairs and the blocks' fits.
#[derive(Debug, Clone)]
pub struct JointTransmissibilitySolution {
    pub response: TransmissibilitySolution,
    pub pairs: Vec<ModePair>,
    /// The response block (`2 × lines × FRFs` rows) and the modal block.
    pub blocks: [BlockFit; 2],
}

/// What a joint evaluation of a record keeps.
#[derive(Debug, Clone)]
pub struct RecordExtra {
    response: transmissibility::Extra,
    pairs: Vec<ModePair>,
    rows: usize,
}

impl<'a> JointTransmissibilityProblem<'a> {
    /// `response`'s residues times `scale` (√2 for H1-weighted
    /// transmissibilities, `1/σ̂` for a record's spectra: see the module
    /// doc) with the modal residues of `observed`, paired as
    /// [`ModalUpdateProblem::new`] says.
    pub fn new(
        response: TransmissibilityProblem<'a>,
        observed: &'a [ObservedMode],
        pairing: (f64, f64),
        scale: f64,
    ) -> Result<Self, UpdateError> {
        if !(scale.is_finite() && scale > 0.0) {
            return Err(UpdateError::Data(format!(
                "the response block's scale must be positive and finite, got {scale}"
            )));
        }
        let modal = response.modal_problem(observed, pairing)?;
        Ok(Self { response, modal, scale })
    }

    /// The stacked residues of the response evaluation `at` at `p` and the
    /// modal residues of `pairs` (found at its state when `None`).
    fn stack(
        &self,
        p: &[f64],
        at: Evaluated<transmissibility::Extra>,
        pairs: Option<Vec<ModePair>>,
        jacobian: bool,
    ) -> Result<Evaluated<RecordExtra>, UpdateError> {
        let pairs = pairs.unwrap_or_else(|| self.modal.pairs_at(&at.extra.state));
        let modal = self.modal.residue_at(&at.extra.state, &pairs, jacobian);
        if modal.residual.iter().any(|r| !r.is_finite()) {
            return Err(UpdateError::NonFinite(p.to_vec()));
        }
        let n = self.updated().len();
        let (residual, jacobian) = stack_blocks(self.scale, (&at.residual, &at.jacobian), &modal, jacobian, n);
        Ok(Evaluated {
            residual,
            jacobian,
            extra: RecordExtra {
                rows: at.residual.len(),
                response: at.extra,
                pairs,
            },
        })
    }

    /// The parameters updated (the response block's).
    fn updated(&self) -> &[Parameter] {
        ResidualModel::parameters(&self.response)
    }

    /// Runs the updating from `start` (the previous event's values); on a
    /// truncated model whose parameters are springs and damping, on a Ritz
    /// basis of `start` first, as [`TransmissibilityProblem::solve`] does.
    pub fn solve(
        &self,
        start: &[f64],
        observer: &mut dyn FnMut(&IterationRecord),
    ) -> Result<JointTransmissibilitySolution, UpdateError> {
        let solved = match self.response.reanalysed_at(start)? {
            Some(reduced) => {
                let coarse = JointTransmissibilityProblem {
                    response: self.response.on_model(&reduced),
                    modal: self.modal.on_model(&reduced),
                    scale: self.scale,
                };
                solver::levenberg_marquardt_staged(&coarse, self, start, observer)?
            }
            None => solver::levenberg_marquardt(self, start, None, observer)?,
        };
        let (relative_residual, per_block) = self.response.fit_of(&solved.at.extra.response.h);
        let fit = solver::FitMeasures {
            relative_residual,
            per_block,
            lines_used: self.response.line_frequencies().len(),
        };
        let (result, _, at) = solved.into_result(self.updated(), fit);
        let blocks = block_fits(&at.residual, at.extra.rows);
        let RecordExtra { response, pairs, .. } = at.extra;
        Ok(JointTransmissibilitySolution {
            response: TransmissibilitySolution {
                result,
                state: response.state,
                motion: response.motion,
                transmissibilities: response.h,
            },
            pairs,
            blocks,
        })
    }
}

impl ResidualModel for JointTransmissibilityProblem<'_> {
    type Extra = RecordExtra;
    type Previous = ();

    fn parameters(&self) -> &[Parameter] {
        self.updated()
    }

    fn settings(&self) -> &UpdateSettings {
        ResidualModel::settings(&self.response)
    }

    fn first(&self, p: &[f64], _previous: Option<&()>) -> Result<(Evaluated<RecordExtra>, usize), UpdateError> {
        Ok((self.stack(p, self.response.evaluate(p, true)?, None, true)?, 1))
    }

    fn residual(&self, p: &[f64]) -> Result<Evaluated<RecordExtra>, UpdateError> {
        self.stack(p, self.response.evaluate(p, false)?, None, false)
    }

    fn with_jacobian(&self, p: &[f64], trial: Evaluated<RecordExtra>) -> Result<Evaluated<RecordExtra>, UpdateError> {
        let RecordExtra { response, pairs, .. } = trial.extra;
        let at = self
            .response
            .evaluate_motion(p, response.state, response.motion, true)?;
        self.stack(p, at, Some(pairs), true)
    }

    /// The response block's unweighted relative residual (the modal
    /// block's fit is reported per pair).
    fn relative_residual(&self, at: &Evaluated<RecordExtra>) -> f64 {
        self.response.fit_of(&at.extra.response.h).0
    }
}
