//! FRF and modal residues fitted together: where a force is measured and a
//! window's modes are also identified output-only, one update can fit both
//! (`[updating] residues = "both"`).
//!
//! Each block is weighted by its own uncertainty, so that every residue is
//! a standard normal variable when the model is right and the blocks add up
//! as two chi-squares:
//! - FRF residues (eq. 36–39), real and imaginary parts, each divided by its
//!   random error: the H1 estimator's complex variance
//!   `(1 − γ²)/(γ² n_d) |H|²` (Bendat & Piersol, *Random Data*, §9.2,
//!   the [`Weighting::H1Variance`] weighting) splits evenly between the two
//!   parts, so the block is the H1-weighted residual times √2;
//! - modal residues of [`crate::updating::modal_residual`], already divided
//!   by the identification's standard deviations.
//!
//! The model is solved once per evaluation; the FRFs and the paired modes
//! come from the same modal state. Pairs are redone at every evaluation and
//! held within one Jacobian, as in [`super::ModalUpdateProblem`].

use super::frf_residual::{MeasuredSet, ModelPoint, UpdateProblem};
use super::modal_residual::{ModePair, ObservedMode};
use super::solver::{self, Evaluated, ResidualModel};
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
        let modal = self.modal.residue_at(&state, &damping, &pairs, jacobian);
        if modal.residual.iter().any(|r| !r.is_finite()) {
            return Err(UpdateError::NonFinite(p.to_vec()));
        }
        let frf_rows = frf.residual.len();
        let mut residual: Vec<f64> = frf.residual.iter().map(|r| SQRT_2 * r).collect();
        residual.extend_from_slice(&modal.residual);
        let n = self.frf.parameters().len();
        let jac = if jacobian {
            Mat::from_fn(residual.len(), n, |i, c| {
                if i < frf_rows {
                    SQRT_2 * frf.jacobian[(i, c)]
                } else {
                    modal.jacobian[(i - frf_rows, c)]
                }
            })
        } else {
            Mat::zeros(0, 0)
        };
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
        let chi_square = |r: &[f64]| r.iter().map(|v| v * v).sum::<f64>();
        let (frf_block, modal_block) = at.residual.split_at(at.extra.frf_rows);
        let blocks = [
            BlockFit {
                residues: frf_block.len(),
                chi_square: chi_square(frf_block),
            },
            BlockFit {
                residues: modal_block.len(),
                chi_square: chi_square(modal_block),
            },
        ];
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
