//! Model FRFs at physical points and their sensitivities (paper §3,
//! eq. 31–33).
//!
//! With mass-normalised modes `φ_i` and the damping of eq. (25), the
//! receptance matrix is exactly `H(ω) = Σ_i φ_i φ_iᵀ / D_i(ω)`,
//! `D_i = ω_i² - ω² + 2j ζ_i ω_i ω`, when every mode is kept (this module
//! keeps every mode). At physical points (eq. 32), with the sensor rows
//! `N_ψ(P_r)` of the shell shape functions and modal amplitudes
//! `a_{r,i} = N_ψ(P_r) φ_i`: `H_rs(ω) = Σ_i a_{r,i} a_{s,i} / D_i(ω)`.
//!
//! Sensitivities:
//! - spring coefficients, eq. (33) with `∂C/∂κ ≈ 0` as in the paper:
//!   `∂H_rs/∂κ_j = -g_rᵀ (∂K/∂κ_j) g_s`, `g_s = H N_sᵀ`, evaluated only on the
//!   few dofs where the low-rank `∂K/∂κ_j` lives;
//! - damping coefficients, exact: `∂H_rs/∂γ_z = Σ_i a_{r,i} a_{s,i}
//!   (-2j ω_i ω / D_i²) B_z(f_i)`.
//!
//! Mobility and accelerance are `jω H` and `-ω² H`; their sensitivities
//! scale the same way.

use crate::linalg::dense_rows;
use crate::model::damping::DampingCurve;
use crate::model::loss_sites::SiteOf;
use crate::model::springs::LowRankBlock;
use crate::model::BridgeModel;
use crate::solvers::dense_model::{AssembledModel, ModelError};
use crate::solvers::modal::{ModalError, ModeKind, Modes};
use crate::solvers::partial_eigen::Responses;
use crate::solvers::reanalysis::Reanalysis;
use crate::solvers::sparse_model::SparseModel;
use crate::solvers::truncation::Residual;

use faer::{c64, Mat};
use std::f64::consts::PI;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Arc;
use thiserror::Error;

mod direct;
mod evaluate;
mod line_runs;
mod modal_state;
mod sensors;
mod support_loss;
pub(crate) use support_loss::StiffnessChange;
mod truncated;

pub use line_runs::LineRuns;
pub use modal_state::ModalState;
pub use sensors::{sensor_rows, sensor_rows_of, BeamSensor, Sensor, SensorPoint};

#[derive(Debug, Clone, PartialEq, Error)]
pub enum FrfError {
    #[error("sensor {index}: (ξ, η, τ) = ({xi}, {eta}, {tau}) lies outside the shell's parameter domain")]
    SensorOutside { index: usize, xi: f64, eta: f64, tau: f64 },
    #[error("sensor {index}: patch {patch} does not exist (the model has {count})")]
    SensorPatch { index: usize, patch: usize, count: usize },
    #[error("sensor {index}: direction must be a finite non-zero vector")]
    SensorDirection { index: usize },
    #[error("sensor {index}: beam member {member} does not exist (the model has {count})")]
    SensorMember { index: usize, member: usize, count: usize },
    #[error("{0}")]
    Model(#[from] ModelError),
    #[error("{0}")]
    Modal(#[from] ModalError),
    #[error("damping curve has {found} coefficients, {expected} expected")]
    DampingCount { found: usize, expected: usize },
    #[error("the direct FRF solve failed at {frequency_hz} Hz: Z(ω) is singular")]
    SingularImpedance { frequency_hz: f64 },
    #[error("the modal cut-off must be a positive frequency, got {0} Hz")]
    Cutoff(f64),
    #[error("{0} needs every mode (the dense model); this model is truncated")]
    DenseOnly(&'static str),
    #[error(
        "{found} loss factors for {expected} loss sites (one per site: by default per spring field, bearing and line support; or none)"
    )]
    LossFactorCount { found: usize, expected: usize },
    #[error("{0}")]
    LossSites(#[from] crate::model::loss_sites::LossSitesError),
}

/// Which FRF is measured: displacement, velocity or acceleration per force.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Quantity {
    Receptance,
    Mobility,
    Accelerance,
}

impl Quantity {
    /// Factor turning receptance into this quantity at `ω` rad/s.
    pub fn factor(self, omega: f64) -> c64 {
        match self {
            Quantity::Receptance => c64::new(1.0, 0.0),
            Quantity::Mobility => c64::new(0.0, omega),
            Quantity::Accelerance => c64::new(-omega * omega, 0.0),
        }
    }
}

/// What to evaluate: the frequency lines and `(output, input)` sensor pairs.
#[derive(Debug, Clone, Copy)]
pub struct FrfRequest<'a> {
    pub frequencies_hz: &'a [f64],
    pub pairs: &'a [(usize, usize)],
    pub quantity: Quantity,
}

impl FrfRequest<'_> {
    /// The sensors of the pairs, ascending, each once.
    pub(super) fn involved_sensors(&self) -> Vec<usize> {
        let mut sensors: Vec<usize> = self.pairs.iter().flat_map(|&(r, s)| [r, s]).collect();
        sensors.sort_unstable();
        sensors.dedup();
        sensors
    }
}

/// FRFs and sensitivities, each stored pair-major: `[pair * n_f + line]`.
#[derive(Debug, Clone)]
pub struct FrfEvaluation {
    pub h: Vec<c64>,
    /// One vector per spring coefficient, fields in order, coefficients flattened.
    pub dh_dkappa: Vec<Vec<c64>>,
    /// One vector per damping coefficient.
    pub dh_dgamma: Vec<Vec<c64>>,
    /// One vector per stiffness-field coefficient (fields flattened): filled
    /// by the updating when it updates fields
    /// ([`FrfModel::field_frf_sensitivities`]), empty otherwise.
    pub dh_dtheta: Vec<Vec<c64>>,
}

/// Where a model's modes come from.
#[derive(Debug, Clone)]
enum Source {
    /// Every mode of the dense model (the reference; eq. 31 exact).
    Dense(Arc<AssembledModel>),
    /// The modes below `cutoff_hz` of the sparse model, the rest as a
    /// residual ([`crate::solvers::truncation`]).
    Truncated {
        model: Arc<SparseModel>,
        cutoff_hz: f64,
        /// A Ritz basis answering the solves it was built for
        /// ([`FrfModel::with_reanalysis`]).
        reanalysis: Option<Arc<Reanalysis>>,
    },
}

/// An assembled model with sensors: evaluates FRFs and sensitivities.
#[derive(Debug, Clone)]
pub struct FrfModel {
    source: Source,
    /// Sparse rows `N_ψ(P_s)`.
    sensor_rows: Vec<Vec<(usize, f64)>>,
    /// Union `U` of the dofs of all `∂K/∂κ_j`.
    spring_dofs: Vec<usize>,
    /// Positions in `U` of each block's dofs, blocks flattened over fields.
    block_positions: Vec<Vec<usize>>,
    /// Distinct for every model built (clones share it): results computed
    /// on one model are not mistaken for another's.
    id: u64,
}

static NEXT_MODEL_ID: AtomicU64 = AtomicU64::new(0);

impl FrfModel {
    /// Every mode of the dense model.
    pub fn new(assembled: AssembledModel, sensors: &[impl Into<Sensor> + Copy]) -> Result<Self, FrfError> {
        let sensor_rows = sensors::rows(&assembled.patches, &assembled.beams, sensors)?;
        Ok(Self::with_source(Source::Dense(Arc::new(assembled)), sensor_rows))
    }

    /// The modes below `cutoff_hz` of the sparse model of `model`, the
    /// others by their residual ([`crate::solvers::truncation`]): for models too
    /// large for the dense path.
    pub fn truncated(
        model: &BridgeModel,
        sensors: &[impl Into<Sensor> + Copy],
        cutoff_hz: f64,
    ) -> Result<Self, FrfError> {
        if !(cutoff_hz.is_finite() && cutoff_hz > 0.0) {
            return Err(FrfError::Cutoff(cutoff_hz));
        }
        let sensor_rows = sensors::rows(&model.patches, &model.beams, sensors)?;
        let source = Source::Truncated {
            model: Arc::new(SparseModel::assemble(model)?),
            cutoff_hz,
            reanalysis: None,
        };
        Ok(Self::with_source(source, sensor_rows))
    }

    fn with_source(source: Source, sensor_rows: Vec<Vec<(usize, f64)>>) -> Self {
        let blocks = match &source {
            Source::Dense(assembled) => &assembled.spring_blocks,
            Source::Truncated { model, .. } => &model.spring_blocks,
        };
        let mut spring_dofs: Vec<usize> = blocks.iter().flatten().flat_map(|b| b.dofs.iter().copied()).collect();
        spring_dofs.sort_unstable();
        spring_dofs.dedup();
        let block_positions = blocks
            .iter()
            .flatten()
            .map(|b| {
                b.dofs
                    .iter()
                    .map(|d| spring_dofs.binary_search(d).expect("in the union"))
                    .collect()
            })
            .collect();
        Self {
            source,
            sensor_rows,
            spring_dofs,
            block_positions,
            id: NEXT_MODEL_ID.fetch_add(1, Ordering::Relaxed),
        }
    }

    /// This model's identity (see the field).
    pub fn id(&self) -> u64 {
        self.id
    }

    /// The dense model, when every mode is solved (`None` for a
    /// [`FrfModel::truncated`] one).
    pub fn dense(&self) -> Option<&AssembledModel> {
        match &self.source {
            Source::Dense(assembled) => Some(assembled),
            Source::Truncated { .. } => None,
        }
    }

    /// The sparse model and the cut-off of a truncated model.
    pub fn sparse(&self) -> Option<(&SparseModel, f64)> {
        match &self.source {
            Source::Dense(_) => None,
            Source::Truncated { model, cutoff_hz, .. } => Some((model, *cutoff_hz)),
        }
    }

    /// The cut-off of a truncated model.
    pub fn cutoff_hz(&self) -> Option<f64> {
        match &self.source {
            Source::Dense(_) => None,
            Source::Truncated { cutoff_hz, .. } => Some(*cutoff_hz),
        }
    }

    /// `∂K/∂κ_j` per spring field and coefficient, on the generalised dofs.
    pub fn spring_blocks(&self) -> &[Vec<LowRankBlock>] {
        match &self.source {
            Source::Dense(assembled) => &assembled.spring_blocks,
            Source::Truncated { model, .. } => &model.spring_blocks,
        }
    }

    /// The model's own stiffness-field coefficients, one vector per field.
    pub fn field_coefficients(&self) -> &[Vec<f64>] {
        match &self.source {
            Source::Dense(assembled) => &assembled.field_coefficients,
            Source::Truncated { model, .. } => &model.field_coefficients,
        }
    }

    pub fn sensor_count(&self) -> usize {
        self.sensor_rows.len()
    }

    /// The sparse rows `N_ψ(P_s)` of the sensors (eq. 32).
    pub fn sensor_rows(&self) -> &[Vec<(usize, f64)>] {
        &self.sensor_rows
    }

    /// This model with `extra` rows after its sensors': loads that are not
    /// at a point (support motion's inertial loads `M Γ`,
    /// [`crate::response::support_motion`]), so that FRFs and their
    /// sensitivities to them come from the same evaluation.
    pub fn with_extra_rows(&self, extra: Vec<Vec<(usize, f64)>>) -> Self {
        let mut rows = self.sensor_rows.clone();
        rows.extend(extra);
        Self::with_source(self.source.clone(), rows)
    }

    /// Positions of each `∂K/∂κ_j` block's dofs in the union of spring dofs
    /// (the rows of [`ModalState::spring_shapes`]), blocks flattened over fields.
    pub fn spring_block_positions(&self) -> &[Vec<usize>] {
        &self.block_positions
    }

    /// Position of coefficient `coefficient` of spring field `field` among
    /// all spring coefficients, fields flattened in order (the order of
    /// `FrfEvaluation::dh_dkappa` and of the modal sensitivities).
    #[track_caller]
    pub fn flat_spring_index(&self, field: usize, coefficient: usize) -> usize {
        let blocks = self.spring_blocks();
        assert!(coefficient < blocks[field].len(), "spring coefficient out of range");
        blocks[..field].iter().map(Vec::len).sum::<usize>() + coefficient
    }

    /// Index of stiffness-field coefficient `coefficient` of field `field`
    /// among all fields' coefficients (the columns of
    /// [`FrfModel::field_sensitivities`]).
    #[track_caller]
    pub fn flat_field_index(&self, field: usize, coefficient: usize) -> usize {
        let fields = self.field_coefficients();
        assert!(coefficient < fields[field].len(), "no such stiffness-field coefficient");
        fields[..field].iter().map(Vec::len).sum::<usize>() + coefficient
    }

    /// `M x` on the generalised dofs (the consistent mass, eq. 17).
    #[track_caller]
    pub fn mass_times(&self, x: &[f64]) -> Vec<f64> {
        match &self.source {
            Source::Dense(assembled) => {
                let mass = &assembled.mass;
                assert_eq!(x.len(), mass.ncols(), "a value per generalised dof");
                (0..mass.nrows())
                    .map(|r| (0..x.len()).map(|c| mass[(r, c)] * x[c]).sum())
                    .collect()
            }
            Source::Truncated { model, .. } => {
                assert_eq!(x.len(), model.dof_count(), "a value per generalised dof");
                let column = Mat::from_fn(x.len(), 1, |r, _| x[r]);
                model.generalised_mass.mul(&column).col_as_slice(0).to_vec()
            }
        }
    }

    /// Number of stiffness-field coefficients over all fields.
    pub fn field_coefficient_count(&self) -> usize {
        self.field_coefficients().iter().map(Vec::len).sum()
    }

    /// `(∂K/∂θ_k) X` on the generalised dofs, `k` the coefficient's flat
    /// index ([`Self::flat_field_index`]).
    #[track_caller]
    pub(crate) fn field_times(&self, k: usize, x: &Mat<f64>) -> Mat<f64> {
        match &self.source {
            Source::Dense(assembled) => {
                let matrix = assembled.field_matrices.iter().flatten().nth(k);
                matrix.expect("no such stiffness-field coefficient") * x
            }
            Source::Truncated { model, .. } => {
                let matrix = model.field_products.iter().flatten().nth(k);
                matrix.expect("no such stiffness-field coefficient").mul(x)
            }
        }
    }

    /// `Xᵀ (∂K/∂θ_k) X` on the generalised dofs (a truncated model's over
    /// the coefficient's own entries only).
    #[track_caller]
    pub(crate) fn field_quadratic(&self, k: usize, x: &Mat<f64>) -> Mat<f64> {
        match &self.source {
            Source::Dense(_) => x.transpose() * self.field_times(k, x),
            Source::Truncated { model, .. } => {
                let matrix = model.field_products.iter().flatten().nth(k);
                matrix.expect("no such stiffness-field coefficient").quadratic(x)
            }
        }
    }

    /// A unit load at each spring dof (sparse rows on the generalised
    /// dofs) when `damping` has loss factors, none otherwise: the loads
    /// whose responses give a truncated model the discarded modes' part of
    /// the loss factors' sensitivities ([`crate::model::damping`]), for a
    /// Ritz basis that answers them ([`Self::with_reanalysis`]).
    pub fn loss_factor_loads(&self, damping: &DampingCurve) -> Vec<Vec<(usize, f64)>> {
        if damping.loss_factors().iter().any(|&eta| eta > 0.0) {
            self.spring_dofs.iter().map(|&d| vec![(d, 1.0)]).collect()
        } else {
            Vec::new()
        }
    }

    /// Total number of spring coefficients over all fields.
    pub fn spring_coefficient_count(&self) -> usize {
        self.block_positions.len()
    }

    /// Solves the modes for spring coefficients `kappa` (one vector per
    /// field) and evaluates ζ_i on `damping`.
    pub fn modal_state(&self, kappa: &[Vec<f64>], damping: &DampingCurve) -> Result<ModalState, FrfError> {
        self.modal_state_with_fields(kappa, self.field_coefficients(), damping)
    }

    /// [`Self::modal_state`] with stiffness-field coefficients `theta` (one
    /// vector per field of the assembled model).
    pub fn modal_state_with_fields(
        &self,
        kappa: &[Vec<f64>],
        theta: &[Vec<f64>],
        damping: &DampingCurve,
    ) -> Result<ModalState, FrfError> {
        self.check_loss_factors(damping)?;
        match &self.source {
            Source::Dense(assembled) => {
                let modes = assembled.modes_with_fields(kappa, theta)?;
                Ok(self.modal_state_from(modes, (kappa, theta), damping))
            }
            Source::Truncated { .. } => Ok(self.modal_state_with_loads(kappa, theta, damping, &[])?.0),
        }
    }

    /// [`Self::modal_state_with_fields`] and, on a truncated model, the
    /// static responses to `loads` (as
    /// [`SparseModel::modes_and_responses`] gives them) from the same
    /// eigen-solve; `None` on the dense path, which solves every mode.
    pub fn modal_state_with_loads(
        &self,
        kappa: &[Vec<f64>],
        theta: &[Vec<f64>],
        damping: &DampingCurve,
        loads: &[Vec<(usize, f64)>],
    ) -> Result<(ModalState, Option<Responses>), FrfError> {
        let Source::Truncated {
            model,
            cutoff_hz,
            reanalysis,
        } = &self.source
        else {
            return Ok((self.modal_state_with_fields(kappa, theta, damping)?, None));
        };
        // The sensors' responses (the truncation residual), the loads' and,
        // with loss factors, unit loads at the spring dofs' (the discarded
        // modes' flexibility there, support_loss) from one solve; without
        // loads, the sensors' as they come.
        let sensors = self.sensor_rows.len();
        let units = self.loss_factor_loads(damping);
        let (modes, own, theirs, at_springs) = if loads.is_empty() && units.is_empty() {
            let (modes, own) = truncated_solve(
                (model, *cutoff_hz, reanalysis.as_deref()),
                (kappa, theta),
                &self.sensor_rows,
            )?;
            let none = Mat::<f64>::zeros(own.0.nrows(), 0);
            (modes, own, (none.clone(), none), None)
        } else {
            let all: Vec<Vec<(usize, f64)>> = self.sensor_rows.iter().chain(loads).chain(&units).cloned().collect();
            let (modes, (x, xmx)) = truncated_solve((model, *cutoff_hz, reanalysis.as_deref()), (kappa, theta), &all)?;
            let part = |m: &Mat<f64>, from: usize, count: usize| m.subcols(from, count).to_owned();
            let split = |m: &Mat<f64>| {
                (
                    part(m, 0, sensors),
                    part(m, sensors, loads.len()),
                    part(m, sensors + loads.len(), units.len()),
                )
            };
            let ((x_own, x_loads, x_units), (xmx_own, xmx_loads, xmx_units)) = (split(&x), split(&xmx));
            let at_springs = (!units.is_empty()).then_some((x_units, xmx_units));
            (modes, (x_own, xmx_own), (x_loads, xmx_loads), at_springs)
        };
        self.check_loss_factors(damping)?;
        let shift = SparseModel::shift_for(*cutoff_hz);
        let mut state = self.modal_state_from(modes, (kappa, theta), damping);
        if let (Some(loss), Some(responses)) = (state.loss.as_mut(), at_springs) {
            loss.add_discarded(&state.modes, &state.phi_springs, &self.spring_dofs, &responses, shift);
        }
        state.residual = Some(Residual::new(
            &state.modes,
            &state.amplitudes,
            &self.sensor_rows,
            &self.spring_dofs,
            &own,
            shift,
            damping,
            model.field_products.iter().any(|f| !f.is_empty()),
        ));
        Ok((state, Some(theirs)))
    }

    /// The Ritz basis its truncated solves use, if any
    /// ([`Self::with_reanalysis`]).
    pub fn reanalysis(&self) -> Option<&Reanalysis> {
        match &self.source {
            Source::Truncated { reanalysis, .. } => reanalysis.as_deref(),
            Source::Dense(_) => None,
        }
    }

    /// This model with a Ritz basis at `(kappa0, theta0)` for the sensors
    /// and `loads` (sparse rows on the generalised dofs) and the spring
    /// coefficients `varied` (flat indices): its modal states at spring
    /// values differing from `kappa0` in those alone come from the
    /// projection ([`Reanalysis`]: static responses exact, modes Ritz
    /// approximations), at a dense eigen-solve of the basis' size instead
    /// of a factorisation and Lanczos. A dense model, or one whose basis
    /// would not be much smaller than it ([`Reanalysis::new`]), is returned
    /// as it is.
    /// The copy is a model of its own ([`Self::id`]).
    pub fn with_reanalysis(
        &self,
        (kappa0, theta0): (&[Vec<f64>], &[Vec<f64>]),
        loads: &[Vec<(usize, f64)>],
        varied: &[usize],
    ) -> Result<Self, FrfError> {
        let Source::Truncated { model, cutoff_hz, .. } = &self.source else {
            return Ok(self.clone());
        };
        let rows: Vec<Vec<(usize, f64)>> = self.sensor_rows.iter().chain(loads).cloned().collect();
        let Some(basis) = Reanalysis::new(model, (kappa0, theta0), *cutoff_hz, &rows, varied)? else {
            return Ok(self.clone());
        };
        let source = Source::Truncated {
            model: model.clone(),
            cutoff_hz: *cutoff_hz,
            reanalysis: Some(Arc::new(basis)),
        };
        Ok(Self::with_source(source, self.sensor_rows.clone()))
    }

    /// The spring fields' coefficient counts.
    pub fn spring_field_sizes(&self) -> Vec<usize> {
        self.spring_blocks().iter().map(Vec::len).collect()
    }

    /// For each spring and stiffness-field coefficient (flat), the loss
    /// site of `damping` it is in; `damping`'s loss factors, if any, must be
    /// one per site (by default one per spring field) and its sites within
    /// the model.
    fn loss_site_of(&self, damping: &DampingCurve) -> Result<SiteOf, FrfError> {
        let sites = damping.loss_sites(&self.spring_field_sizes());
        let counts = (self.spring_coefficient_count(), self.field_coefficient_count());
        let (found, expected) = (damping.loss_factors().len(), sites.len());
        if found == 0 {
            return Ok(SiteOf {
                springs: vec![None; counts.0],
                fields: vec![None; counts.1],
            });
        }
        if found != expected {
            return Err(FrfError::LossFactorCount { found, expected });
        }
        Ok(sites.site_of(counts.0, counts.1)?)
    }

    /// One loss factor per loss site, or none.
    fn check_loss_factors(&self, damping: &DampingCurve) -> Result<(), FrfError> {
        self.loss_site_of(damping).map(|_| ())
    }

    /// Builds the modal state from modes already computed at spring
    /// coefficients `kappa` and stiffness-field coefficients `theta`.
    /// `damping`'s loss factors, if any, must be one per loss site, within
    /// the model (the constructors that solve the modes check it).
    #[track_caller]
    pub fn modal_state_from(
        &self,
        modes: Modes,
        (kappa, theta): (&[Vec<f64>], &[Vec<f64>]),
        damping: &DampingCurve,
    ) -> ModalState {
        let nm = modes.len();
        let nz = damping.coefficients().len();
        let factors = damping.loss_factors();
        let site_of = self
            .loss_site_of(damping)
            .expect("one loss factor per loss site, within the model");
        let omega: Vec<f64> = modes.omega2.iter().map(|w2| w2.max(0.0).sqrt()).collect();
        let phi_springs = dense_rows(&modes.shapes, &self.spring_dofs);
        let loss = (!factors.is_empty())
            .then(|| support_loss::SupportLoss::new(self, &modes, &phi_springs, (kappa, theta), (factors, site_of)));
        let mut zeta = vec![0.0; nm];
        let mut zeta_basis = Mat::<f64>::zeros(nm, nz + factors.len());
        let mut damping_rate_slope = vec![0.0; nm];
        let mut b = vec![0.0; nz];
        for i in 0..nm {
            if modes.kinds[i] == ModeKind::Rigid {
                continue;
            }
            damping.basis_at(omega[i] / (2.0 * PI), &mut b);
            for z in 0..nz {
                zeta_basis[(i, z)] = b[z];
            }
            zeta[i] = b.iter().zip(damping.coefficients()).map(|(b, g)| b * g).sum();
            let mut support = 0.0;
            if let Some(loss) = &loss {
                for s in 0..factors.len() {
                    zeta_basis[(i, nz + s)] = 0.5 * loss.energy[(i, s)];
                }
                support = loss.loss(i);
                zeta[i] += 0.5 * support;
            }
            if omega[i] > 0.0 {
                damping_rate_slope[i] =
                    (zeta[i] - support) / omega[i] + damping.slope(omega[i] / (2.0 * PI)) / (2.0 * PI);
            }
        }
        let amplitudes = Mat::from_fn(self.sensor_rows.len(), nm, |s, i| {
            self.sensor_rows[s].iter().map(|&(d, v)| v * modes.shapes[(d, i)]).sum()
        });
        ModalState {
            modes,
            zeta,
            zeta_basis,
            damping_rate_slope,
            loss,
            kappa: kappa.to_vec(),
            theta: theta.to_vec(),
            amplitudes,
            phi_springs,
            omega,
            residual: None,
        }
    }

    /// `state`'s modes as a state of this model (the same structure with
    /// other sensor rows, [`Self::with_extra_rows`]) on `damping`.
    pub fn restate(&self, state: &ModalState, damping: &DampingCurve) -> ModalState {
        self.modal_state_from(state.modes.clone(), (&state.kappa, &state.theta), damping)
    }
}

/// The modes below the cut-off and the static responses to `loads` of a
/// truncated model: from its Ritz basis where that answers them exactly
/// ([`Reanalysis::modes_and_responses`]), else the complete solve.
fn truncated_solve(
    (model, cutoff_hz, reanalysis): (&SparseModel, f64, Option<&Reanalysis>),
    (kappa, theta): (&[Vec<f64>], &[Vec<f64>]),
    loads: &[Vec<(usize, f64)>],
) -> Result<(Modes, Responses), FrfError> {
    if let Some(found) = reanalysis.and_then(|r| r.modes_and_responses(model, (kappa, theta), cutoff_hz, loads)) {
        return Ok(found);
    }
    Ok(model.modes_and_responses(kappa, theta, cutoff_hz, loads)?)
}

/// Frequency lines per block in [`FrfModel::evaluate`]: every intermediate
/// (at most the active modes × 32 lines, re and im: 67 kB for Sinello) stays
/// in L2, and a typical 300-line band splits evenly over two threads.
pub const FREQUENCY_BLOCK: usize = 32;

/// `E_ik = −(c_k − c_i)/(λ_k − λ_i)`, and `−dc/dλ` at `λ_i` where the two
/// eigenvalues (nearly) coincide, for the modes `active` of `state`, with
/// the modal damping rates `c_i = 2 ζ_i ω_i`: the factor by which a
/// stiffness coupling `φ_iᵀ (∂K/∂κ) φ_k` changes the modal damping of the
/// superposition. The FRFs `Σ_i a_ri a_si / D_i`, `D_i = λ_i − ω² + j ω c_i`,
/// `c_i = c(λ_i)` through ζ(f), have the exact derivative
/// `−g_rᵀ (∂K/∂κ) g_s + jω Σ_ik x_ri (φ_iᵀ ∂K/∂κ φ_k) E_ik x_sk`,
/// `x = a ∘ q`: the first term holds the damping matrix fixed (eq. 33 with
/// `∂C/∂κ ≈ 0`); the second is what the modal damping's dependence on
/// `λ` adds: on the diagonal `dD_i/dκ ∋ jω c'(λ_i) ∂λ_i/∂κ` (with the
/// damping curve's slope `ζ'(f_i) ∂f_i/∂κ`), off it the eigenvector
/// derivatives `Σ_k φ_k (φ_kᵀ ∂K φ_i)/(λ_i − λ_k)` (Fox & Kapoor 1968)
/// meeting different `c_i`, `c_k`.
pub(super) fn damping_rate_differences(state: &ModalState, active: &[usize]) -> Mat<f64> {
    let rate = |i: usize| 2.0 * state.zeta[i] * state.omega[i];
    Mat::from_fn(active.len(), active.len(), |a, b| {
        let (i, k) = (active[a], active[b]);
        let (li, lk) = (state.modes.omega2[i], state.modes.omega2[k]);
        let gap = lk - li;
        if i == k || gap.abs() <= 1e-9 * li.abs().max(lk.abs()) {
            -0.5 * (state.damping_rate_slope[i] + state.damping_rate_slope[k])
        } else {
            -(rate(k) - rate(i)) / gap
        }
    })
}
