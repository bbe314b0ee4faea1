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

use crate::damping::DampingCurve;
use crate::linalg::{complex_solve, dense_rows};
use crate::modal::{ModalError, ModeKind, Modes};
use crate::model::{AssembledModel, ModelError, ShellModel};
use crate::shell::Shell;
use crate::sparse_model::SparseModel;
use crate::springs::LowRankBlock;
use crate::truncation::Residual;
use crate::vec3::{dot, normalize, Vec3};
use faer::linalg::matmul::matmul;
use faer::{c64, Accum, Mat, Par};
use std::f64::consts::PI;
use std::sync::atomic::{AtomicU64, Ordering};
use thiserror::Error;

#[derive(Debug, Clone, PartialEq, Error)]
pub enum FrfError {
    #[error("sensor {index}: (ξ, η, τ) = ({xi}, {eta}, {tau}) lies outside the shell's parameter domain")]
    SensorOutside { index: usize, xi: f64, eta: f64, tau: f64 },
    #[error("sensor {index}: direction must be a finite non-zero vector")]
    SensorDirection { index: usize },
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

/// A measurement point `P = s(ξ, η, τ)` and direction (eq. 32).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorPoint {
    pub xi: f64,
    pub eta: f64,
    pub tau: f64,
    pub direction: Vec3,
}

/// What to evaluate: the frequency lines and `(output, input)` sensor pairs.
#[derive(Debug, Clone, Copy)]
pub struct FrfRequest<'a> {
    pub frequencies_hz: &'a [f64],
    pub pairs: &'a [(usize, usize)],
    pub quantity: Quantity,
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

/// The modal model at one parameter point.
#[derive(Debug, Clone)]
pub struct ModalState {
    pub modes: Modes,
    /// ζ_i of every mode (eq. 28), zero for rigid modes.
    pub zeta: Vec<f64>,
    /// `∂ζ_i/∂γ_z`: `n_modes × n_z`.
    zeta_basis: Mat<f64>,
    /// `a_{s,i}`: `n_sensors × n_modes`.
    amplitudes: Mat<f64>,
    /// Mode shapes on the spring dofs `U`: `|U| × n_modes`.
    phi_springs: Mat<f64>,
    omega: Vec<f64>,
    /// The discarded modes' contribution when only the modes below a
    /// cut-off were solved ([`crate::truncation`]).
    residual: Option<Residual>,
}

impl ModalState {
    /// Mode shapes on the union of the spring dofs (`|U| × modes`).
    pub fn spring_shapes(&self) -> &Mat<f64> {
        &self.phi_springs
    }

    /// Modal amplitude of mode `i` at sensor `s` along its direction.
    pub fn amplitude(&self, sensor: usize, mode: usize) -> f64 {
        self.amplitudes[(sensor, mode)]
    }

    /// Number of sensors (the rows of the amplitudes).
    pub fn sensor_count(&self) -> usize {
        self.amplitudes.nrows()
    }

    /// The residual of the discarded modes (a truncated model's state).
    pub fn residual(&self) -> Option<&Residual> {
        self.residual.as_ref()
    }
}

/// The sparse rows `N_ψ(P_s)` of the sensors (eq. 32) on the generalised dofs.
pub fn sensor_rows(shell: &Shell, sensors: &[SensorPoint]) -> Result<Vec<Vec<(usize, f64)>>, FrfError> {
    let (kx, ke) = (shell.surface().xi(), shell.surface().eta());
    let mut rows = Vec::with_capacity(sensors.len());
    for (index, s) in sensors.iter().enumerate() {
        if !(kx.contains(s.xi) && ke.contains(s.eta) && (0.0..=1.0).contains(&s.tau)) {
            return Err(FrfError::SensorOutside {
                index,
                xi: s.xi,
                eta: s.eta,
                tau: s.tau,
            });
        }
        let dir = normalize(s.direction).ok_or(FrfError::SensorDirection { index })?;
        let row = shell
            .shape_functions(s.xi, s.eta, s.tau)
            .into_iter()
            .map(|(dof, col)| (dof, dot(dir, col)))
            .filter(|(_, v)| *v != 0.0)
            .collect();
        rows.push(row);
    }
    Ok(rows)
}

/// Where a model's modes come from.
#[derive(Debug, Clone)]
enum Source {
    /// Every mode of the dense model (the reference; eq. 31 exact).
    Dense(Box<AssembledModel>),
    /// The modes below `cutoff_hz` of the sparse model, the rest as a
    /// residual ([`crate::truncation`]).
    Truncated { model: Box<SparseModel>, cutoff_hz: f64 },
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
    pub fn new(assembled: AssembledModel, sensors: &[SensorPoint]) -> Result<Self, FrfError> {
        let sensor_rows = sensor_rows(&assembled.shell, sensors)?;
        Ok(Self::with_source(Source::Dense(Box::new(assembled)), sensor_rows))
    }

    /// The modes below `cutoff_hz` of the sparse model of `model`, the
    /// others by their residual ([`crate::truncation`]): for models too
    /// large for the dense path.
    pub fn truncated(model: &ShellModel, sensors: &[SensorPoint], cutoff_hz: f64) -> Result<Self, FrfError> {
        if !(cutoff_hz.is_finite() && cutoff_hz > 0.0) {
            return Err(FrfError::Cutoff(cutoff_hz));
        }
        let sensor_rows = sensor_rows(&model.shell, sensors)?;
        let source = Source::Truncated {
            model: Box::new(SparseModel::assemble(model)?),
            cutoff_hz,
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
        match &self.source {
            Source::Dense(assembled) => {
                let modes = assembled.modes_with_fields(kappa, theta)?;
                Ok(self.modal_state_from(modes, damping))
            }
            Source::Truncated { model, cutoff_hz, .. } => {
                let (modes, responses) = model.modes_and_responses(kappa, theta, *cutoff_hz, &self.sensor_rows)?;
                let shift = SparseModel::shift_for(*cutoff_hz);
                let mut state = self.modal_state_from(modes, damping);
                state.residual = Some(Residual::new(
                    &state.modes,
                    &state.amplitudes,
                    &self.sensor_rows,
                    &self.spring_dofs,
                    &responses,
                    shift,
                    damping,
                    model.field_products.iter().any(|f| !f.is_empty()),
                ));
                Ok(state)
            }
        }
    }

    /// Builds the modal state from already computed modes.
    pub fn modal_state_from(&self, modes: Modes, damping: &DampingCurve) -> ModalState {
        let nm = modes.len();
        let nz = damping.coefficients().len();
        let omega: Vec<f64> = modes.omega2.iter().map(|w2| w2.max(0.0).sqrt()).collect();
        let mut zeta = vec![0.0; nm];
        let mut zeta_basis = Mat::<f64>::zeros(nm, nz);
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
        }
        let amplitudes = Mat::from_fn(self.sensor_rows.len(), nm, |s, i| {
            self.sensor_rows[s].iter().map(|&(d, v)| v * modes.shapes[(d, i)]).sum()
        });
        let phi_springs = dense_rows(&modes.shapes, &self.spring_dofs);
        ModalState {
            modes,
            zeta,
            zeta_basis,
            amplitudes,
            phi_springs,
            omega,
            residual: None,
        }
    }

    /// FRFs (and, if asked, sensitivities) by modal superposition.
    ///
    /// The frequency axis is processed in blocks of [`FREQUENCY_BLOCK`]
    /// lines so that every intermediate matrix stays in cache and is
    /// allocated once per call; all products are real GEMMs on split
    /// real/imaginary parts.
    #[track_caller]
    pub fn evaluate(&self, state: &ModalState, request: FrfRequest<'_>, sensitivities: bool) -> FrfEvaluation {
        self.evaluate_on_threads(state, request, sensitivities, 1)
    }

    /// [`Self::evaluate`] on up to `threads` threads, each taking a
    /// contiguous run of whole frequency blocks. Every block is computed
    /// exactly as in the sequential call, so the result is the same bit for
    /// bit whatever the thread count.
    ///
    /// A truncated model's state adds the discarded modes' residual to the
    /// FRFs, and its spring sensitivities come from the spring dofs'
    /// complete responses ([`crate::truncation`]).
    #[track_caller]
    pub fn evaluate_on_threads(
        &self,
        state: &ModalState,
        request: FrfRequest<'_>,
        sensitivities: bool,
        threads: usize,
    ) -> FrfEvaluation {
        let mut evaluation = self.modal_sum(state, request, sensitivities, threads);
        if let Some(residual) = &state.residual {
            self.add_residual(state, residual, request, sensitivities, &mut evaluation);
        }
        evaluation
    }

    /// The modal superposition over the state's modes (eq. 31–33).
    #[track_caller]
    fn modal_sum(
        &self,
        state: &ModalState,
        request: FrfRequest<'_>,
        sensitivities: bool,
        threads: usize,
    ) -> FrfEvaluation {
        let nf = request.frequencies_hz.len();
        let blocks = nf.div_ceil(FREQUENCY_BLOCK);
        let threads = threads.clamp(1, blocks.max(1));
        let prepared = self.prepare(state, request, sensitivities);
        if threads == 1 {
            return self.evaluate_lines(&prepared, request);
        }
        let per_thread = blocks.div_ceil(threads) * FREQUENCY_BLOCK;
        let ranges: Vec<(usize, usize)> = (0..nf)
            .step_by(per_thread)
            .map(|a| (a, (a + per_thread).min(nf)))
            .collect();
        let parts: Vec<FrfEvaluation> = std::thread::scope(|scope| {
            let handles: Vec<_> = ranges
                .iter()
                .map(|&(a, b)| {
                    let part = FrfRequest {
                        frequencies_hz: &request.frequencies_hz[a..b],
                        ..request
                    };
                    let prepared = &prepared;
                    scope.spawn(move || self.evaluate_lines(prepared, part))
                })
                .collect();
            handles
                .into_iter()
                .map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
                .collect()
        });
        // Reassemble the pair-major layouts `[pair * n_f + line]`.
        let np = request.pairs.len();
        let merge = |column: &dyn Fn(&FrfEvaluation) -> &Vec<c64>| -> Vec<c64> {
            let mut all = vec![c64::new(0.0, 0.0); np * nf];
            for ((a, b), part) in ranges.iter().zip(&parts) {
                let n = b - a;
                for p in 0..np {
                    all[p * nf + a..p * nf + b].copy_from_slice(&column(part)[p * n..(p + 1) * n]);
                }
            }
            all
        };
        let first = &parts[0];
        FrfEvaluation {
            h: merge(&|e| &e.h),
            dh_dkappa: (0..first.dh_dkappa.len())
                .map(|j| merge(&|e| &e.dh_dkappa[j]))
                .collect(),
            dh_dtheta: Vec::new(),
            dh_dgamma: (0..first.dh_dgamma.len())
                .map(|z| merge(&|e| &e.dh_dgamma[z]))
                .collect(),
        }
    }

    /// The frequency-independent factors of an evaluation, computed once and
    /// shared by the threads.
    #[allow(
        clippy::too_many_lines,
        reason = "one pass forms every frequency-independent factor of eq. (31)-(33); each is a few lines and used by the next"
    )]
    #[track_caller]
    fn prepare(&self, state: &ModalState, request: FrfRequest<'_>, sensitivities: bool) -> Prepared {
        let np = request.pairs.len();
        for &(r, s) in request.pairs {
            assert!(
                r < self.sensor_count() && s < self.sensor_count(),
                "sensor index out of range"
            );
        }
        // Modes that no involved sensor sees (the membrane modes of a flat
        // deck under vertical sensors: their amplitudes are zero or
        // round-off, below 1e-10 of the largest) add nothing to H, g_s or
        // the sensitivities beyond that round-off: leave them out (195 of
        // 325 for Sinello).
        let mut sensors: Vec<usize> = request.pairs.iter().flat_map(|&(r, s)| [r, s]).collect();
        sensors.sort_unstable();
        sensors.dedup();
        let amax = sensors
            .iter()
            .flat_map(|&s| (0..state.modes.len()).map(move |i| state.amplitudes[(s, i)].abs()))
            .fold(0.0, f64::max);
        let active: Vec<usize> = (0..state.modes.len())
            .filter(|&i| sensors.iter().any(|&s| state.amplitudes[(s, i)].abs() > 1e-10 * amax))
            .collect();
        let nm = active.len();
        let omega: Vec<f64> = active.iter().map(|&i| state.omega[i]).collect();
        let omega2: Vec<f64> = omega.iter().map(|w| w * w).collect();
        let two_zeta_omega: Vec<f64> = active.iter().map(|&i| 2.0 * state.zeta[i] * state.omega[i]).collect();
        let amplitude = |sensor: usize, i: usize| state.amplitudes[(sensor, active[i])];

        // Frequency-independent factors. H_p = Σ_i a_r a_s q_i, p = (r, s).
        let coupling = Mat::from_fn(np, nm, |p, i| {
            let (r, s) = request.pairs[p];
            amplitude(r, i) * amplitude(s, i)
        });
        let nz = if sensitivities { state.zeta_basis.ncols() } else { 0 };
        // Damping: ∂H_p/∂γ_z = Σ_i a_r a_s B_z(f_i) e_i, e_i = -2j ω_i ω q_i².
        // B_z is non-zero on a contiguous range of modes (ascending
        // frequencies): one GEMM per z over that range only.
        let damping_terms: Vec<(usize, Mat<f64>)> = (0..nz)
            .map(|z| {
                let support: Vec<usize> = (0..nm).filter(|&i| state.zeta_basis[(active[i], z)] != 0.0).collect();
                let (lo, hi) = match (support.first(), support.last()) {
                    (Some(&lo), Some(&hi)) => (lo, hi + 1),
                    _ => (0, 0),
                };
                let weights = Mat::from_fn(np, hi - lo, |p, i| {
                    coupling[(p, lo + i)] * state.zeta_basis[(active[lo + i], z)]
                });
                (lo, weights)
            })
            .collect();
        // Springs (eq. 33, low rank): ∂H_rs/∂κ_j = -g_rᵀ B_j g_s on the
        // block's dofs, g_s = Φ_U diag(a_s) q the response of the spring dofs
        // U to input s. With g_r = Φ_U diag(a_r) q this is
        // -Σ_i a_{r,i} q_i c_{j,i}, c_j = Φ_{B_j}ᵀ B_j g_s: g_s only for the
        // inputs (not for every sensor), then per block one small GEMM for
        // c_j and one against the output amplitudes.
        let blocks: Vec<&LowRankBlock> = if sensitivities {
            self.spring_blocks().iter().flatten().collect()
        } else {
            Vec::new()
        };
        let mut inputs: Vec<usize> = request.pairs.iter().map(|&(_, s)| s).collect();
        inputs.sort_unstable();
        inputs.dedup();
        let nu = if sensitivities { state.phi_springs.nrows() } else { 0 };
        let phi_u = Mat::from_fn(nu, nm, |u, i| state.phi_springs[(u, active[i])]);
        let stacked = Mat::from_fn(inputs.len() * nu, nm, |row, i| {
            phi_u[(row % nu, i)] * amplitude(inputs[row / nu], i)
        });
        // Φ_{B_j}ᵀ B_j, frequency-independent: c_j = (Φ_{B_j}ᵀ B_j) g_s[B_j].
        let phi_b_blocks: Vec<Mat<f64>> = blocks
            .iter()
            .zip(&self.block_positions)
            .map(|(block, pos)| Mat::from_fn(nm, pos.len(), |i, a| phi_u[(pos[a], i)]) * &block.values)
            .collect();
        let by_input: Vec<(Vec<usize>, Mat<f64>)> = inputs
            .iter()
            .map(|&s| {
                let pairs: Vec<usize> = (0..np).filter(|&p| request.pairs[p].1 == s).collect();
                let outputs = Mat::from_fn(pairs.len(), nm, |row, i| amplitude(request.pairs[pairs[row]].0, i));
                (pairs, outputs)
            })
            .collect();

        Prepared {
            sensitivities,
            omega,
            omega2,
            two_zeta_omega,
            coupling,
            damping_terms,
            nu,
            stacked,
            phi_b_blocks,
            by_input,
        }
    }

    /// The evaluation on the lines of `request` (all or a thread's share).
    #[allow(
        clippy::too_many_lines,
        reason = "the hot loop over 32-line blocks: H, g_s and the sensitivities share the block's buffers, kept in one scope so they stay in cache"
    )]
    fn evaluate_lines(&self, prepared: &Prepared, request: FrfRequest<'_>) -> FrfEvaluation {
        let nf = request.frequencies_hz.len();
        let np = request.pairs.len();
        let Prepared {
            sensitivities,
            ref omega,
            ref omega2,
            ref two_zeta_omega,
            ref coupling,
            ref damping_terms,
            nu,
            ref stacked,
            ref phi_b_blocks,
            ref by_input,
        } = *prepared;
        let (nm, nz, nb) = (omega.len(), damping_terms.len(), phi_b_blocks.len());
        let widest = phi_b_blocks.iter().map(Mat::ncols).max().unwrap_or(0);
        let zero = c64::new(0.0, 0.0);
        let mut h = vec![zero; np * nf];
        let mut dh_dgamma = vec![vec![zero; np * nf]; nz];
        let mut dh_dkappa = vec![vec![zero; np * nf]; nb];
        let width = FREQUENCY_BLOCK.min(nf.max(1));
        let mut q = Split::zeros(nm, width);
        let mut e = Split::zeros(nm, width);
        let mut out = Split::zeros(np, width);
        let mut g = Split::zeros(by_input.len() * nu, width);
        let mut c = Split::zeros(nm, width);
        let mut gathered = Split::zeros(widest, width);
        let mut r = Split::zeros(np, width);
        for start in (0..nf).step_by(width) {
            let nc = width.min(nf - start);
            let w: Vec<f64> = request.frequencies_hz[start..start + nc]
                .iter()
                .map(|f| 2.0 * PI * f)
                .collect();
            let factor: Vec<c64> = w.iter().map(|&wf| request.quantity.factor(wf)).collect();
            // q_{i,f} = 1 / D_i(ω_f) = conj(D) / |D|², over contiguous columns.
            for (f, &wf) in w.iter().enumerate() {
                let (re, im) = q.col_mut(f);
                for (((re, im), &w2), &tzw) in re.iter_mut().zip(im.iter_mut()).zip(omega2).zip(two_zeta_omega) {
                    let d_re = w2 - wf * wf;
                    let d_im = tzw * wf;
                    let norm = d_re * d_re + d_im * d_im;
                    *re = d_re / norm;
                    *im = -d_im / norm;
                }
            }
            out.product(np, nc, coupling, &q);
            for p in 0..np {
                for f in 0..nc {
                    h[p * nf + start + f] = c64::new(out.re[(p, f)], out.im[(p, f)]) * factor[f];
                }
            }
            if !sensitivities {
                continue;
            }
            // e_{i,f} = -2j ω_i ω_f q_{i,f}².
            for (f, &wf) in w.iter().enumerate() {
                let (q_re, q_im) = (q.re.col_as_slice(f), q.im.col_as_slice(f));
                let (re, im) = e.col_mut(f);
                for ((((re, im), &a), &b), &w) in re.iter_mut().zip(im.iter_mut()).zip(q_re).zip(q_im).zip(omega) {
                    // j s (a + j b)² = j s (a² - b²) - 2 s a b, s = -2 ω_i ω
                    let s = -2.0 * w * wf;
                    *re = -2.0 * s * a * b;
                    *im = s * (a * a - b * b);
                }
            }
            for ((lo, weights), dz) in damping_terms.iter().zip(dh_dgamma.iter_mut()) {
                for (dst, src) in [(&mut out.re, &e.re), (&mut out.im, &e.im)] {
                    matmul(
                        dst.submatrix_mut(0, 0, np, nc),
                        Accum::Replace,
                        weights.as_ref(),
                        src.submatrix(*lo, 0, weights.ncols(), nc),
                        1.0,
                        Par::Seq,
                    );
                }
                for p in 0..np {
                    for f in 0..nc {
                        dz[p * nf + start + f] = c64::new(out.re[(p, f)], out.im[(p, f)]) * factor[f];
                    }
                }
            }
            if nb == 0 {
                continue;
            }
            g.product(by_input.len() * nu, nc, stacked, &q);
            for (k, (pairs, outputs)) in by_input.iter().enumerate() {
                for (j, (phi_b, pos)) in phi_b_blocks.iter().zip(&self.block_positions).enumerate() {
                    for f in 0..nc {
                        for (a, &u) in pos.iter().enumerate() {
                            gathered.re[(a, f)] = g.re[(k * nu + u, f)];
                            gathered.im[(a, f)] = g.im[(k * nu + u, f)];
                        }
                    }
                    for (dst, src) in [(&mut c.re, &gathered.re), (&mut c.im, &gathered.im)] {
                        matmul(
                            dst.subcols_mut(0, nc),
                            Accum::Replace,
                            phi_b.as_ref(),
                            src.submatrix(0, 0, pos.len(), nc),
                            1.0,
                            Par::Seq,
                        );
                    }
                    // c ← q ∘ c in place, then ∂H_p/∂κ_j = -Σ_i a_{r,i} c_i.
                    for f in 0..nc {
                        let (q_re, q_im) = (q.re.col_as_slice(f), q.im.col_as_slice(f));
                        let (c_re, c_im) = c.col_mut(f);
                        for (((cr, ci), &qr), &qi) in c_re.iter_mut().zip(c_im.iter_mut()).zip(q_re).zip(q_im) {
                            let (a, b) = (*cr, *ci);
                            *cr = qr * a - qi * b;
                            *ci = qr * b + qi * a;
                        }
                    }
                    r.product(pairs.len(), nc, outputs, &c);
                    let dj = &mut dh_dkappa[j];
                    for (row, &p) in pairs.iter().enumerate() {
                        for f in 0..nc {
                            let v = c64::new(r.re[(row, f)], r.im[(row, f)]);
                            dj[p * nf + start + f] = -v * factor[f];
                        }
                    }
                }
            }
        }
        FrfEvaluation {
            h,
            dh_dkappa,
            dh_dgamma,
            dh_dtheta: Vec::new(),
        }
    }

    /// Adds the residual of the discarded modes to `evaluation.h` and, with
    /// `sensitivities`, replaces `∂H_rs/∂κ_j` by `−g_rᵀ (∂K/∂κ_j) g_s` with
    /// the spring dofs' complete responses `g_s = Σ_i φ_i a_{s,i} q_i + ρ_s`
    /// ([`crate::truncation`]); the residual's damping term adds to `∂H/∂γ_z`.
    fn add_residual(
        &self,
        state: &ModalState,
        residual: &Residual,
        request: FrfRequest<'_>,
        sensitivities: bool,
        evaluation: &mut FrfEvaluation,
    ) {
        let nf = request.frequencies_hz.len();
        for (p, &(r, s)) in request.pairs.iter().enumerate() {
            for (f, &hz) in request.frequencies_hz.iter().enumerate() {
                let w = 2.0 * PI * hz;
                evaluation.h[p * nf + f] += request.quantity.factor(w) * residual.at_sensors(r, s, w);
            }
        }
        if !sensitivities {
            return;
        }
        for (z, dz) in evaluation.dh_dgamma.iter_mut().enumerate() {
            for (p, &(r, s)) in request.pairs.iter().enumerate() {
                for (f, &hz) in request.frequencies_hz.iter().enumerate() {
                    let w = 2.0 * PI * hz;
                    dz[p * nf + f] += request.quantity.factor(w) * residual.damping_sensitivity(r, s, w, z);
                }
            }
        }
        let mut sensors: Vec<usize> = request.pairs.iter().flat_map(|&(r, s)| [r, s]).collect();
        sensors.sort_unstable();
        sensors.dedup();
        let slot = |sensor: usize| sensors.binary_search(&sensor).expect("an involved sensor");
        let nm = state.modes.len();
        // Per block j (B = ∂K/∂κ_j on its dofs), with g_t = Φ_B x_t + ρ_0,t +
        // γ ρ_1,t, x_t = a_t ∘ q and γ(ω) the residual's frequency factor:
        // g_rᵀ B g_s = x_rᵀ P x_s + x_rᵀ (u_0,s + γ u_1,s) + (u_0,r + γ u_1,r)ᵀ x_s
        //            + c_00 + γ (c_01 + c_10) + γ² c_11,
        // P = Φ_Bᵀ B Φ_B, u_p,t = Φ_Bᵀ B ρ_p,t, c_pq = ρ_p,rᵀ B ρ_q,s: every
        // factor frequency-independent, so a line costs O(modes²) per block.
        let prepared = self.block_residuals(state, residual, &sensors);
        let mut inputs: Vec<usize> = request.pairs.iter().map(|&(_, s)| slot(s)).collect();
        inputs.sort_unstable();
        inputs.dedup();
        let zero = c64::new(0.0, 0.0);
        let mut x = vec![vec![zero; nm]; sensors.len()];
        let mut y = vec![vec![zero; nm]; sensors.len()];
        let mut u = vec![vec![zero; nm]; sensors.len()];
        let dot = |a: &[c64], b: &[c64]| a.iter().zip(b).map(|(a, b)| a * b).sum::<c64>();
        for (f, &hz) in request.frequencies_hz.iter().enumerate() {
            let w = 2.0 * PI * hz;
            let gamma = residual.expansion_factor(w);
            for (t, xt) in x.iter_mut().enumerate() {
                for (i, xi) in xt.iter_mut().enumerate() {
                    let d = c64::new(
                        state.omega[i] * state.omega[i] - w * w,
                        2.0 * state.zeta[i] * state.omega[i] * w,
                    );
                    *xi = state.amplitudes[(sensors[t], i)] / d;
                }
            }
            let factor = request.quantity.factor(w);
            for (b, dh) in prepared.iter().zip(&mut evaluation.dh_dkappa) {
                for &t in &inputs {
                    for (i, yi) in y[t].iter_mut().enumerate() {
                        *yi = (0..nm).map(|k| x[t][k] * b.coupling[(i, k)]).sum();
                    }
                }
                for (t, ut) in u.iter_mut().enumerate() {
                    for (i, ui) in ut.iter_mut().enumerate() {
                        *ui = gamma * b.u1[(i, t)] + b.u0[(i, t)];
                    }
                }
                for (p, &(r, s)) in request.pairs.iter().enumerate() {
                    let (r, s) = (slot(r), slot(s));
                    let c = |k: usize| b.c[k][(r, s)];
                    let value = dot(&x[r], &y[s])
                        + dot(&x[r], &u[s])
                        + dot(&u[r], &x[s])
                        + c(0)
                        + gamma * (c(1) + c(2))
                        + gamma * gamma * c(3);
                    dh[p * nf + f] = -value * factor;
                }
            }
        }
    }

    /// The [`BlockResidual`] factors of every spring block for the
    /// involved `sensors` (ascending).
    fn block_residuals(&self, state: &ModalState, residual: &Residual, sensors: &[usize]) -> Vec<BlockResidual> {
        let nm = state.modes.len();
        let (rho0, rho1) = residual.spring_terms();
        self.spring_blocks()
            .iter()
            .flatten()
            .zip(&self.block_positions)
            .map(|(block, positions)| {
                let phi_b = Mat::from_fn(positions.len(), nm, |a, i| state.phi_springs[(positions[a], i)]);
                let b_phi = &block.values * &phi_b;
                let rho = |terms: &Mat<f64>| {
                    Mat::from_fn(positions.len(), sensors.len(), |a, t| terms[(positions[a], sensors[t])])
                };
                let (r0, r1) = (rho(rho0), rho(rho1));
                let (b_r0, b_r1) = (&block.values * &r0, &block.values * &r1);
                BlockResidual {
                    coupling: phi_b.transpose() * &b_phi,
                    u0: phi_b.transpose() * &b_r0,
                    u1: phi_b.transpose() * &b_r1,
                    c: [
                        r0.transpose() * &b_r0,
                        r0.transpose() * &b_r1,
                        r1.transpose() * &b_r0,
                        r1.transpose() * &b_r1,
                    ],
                }
            })
            .collect()
    }

    /// The truncation error of FRFs `found` (a truncated model's, on the
    /// lines and pairs of `request`) against this model's, which solves
    /// every mode, at `(κ, θ)` and `damping`: the largest `|H − H_ref|`,
    /// relative to each FRF's peak (what the update report states for small
    /// models).
    #[track_caller]
    pub fn truncation_error(
        &self,
        found: &[c64],
        kappa: &[Vec<f64>],
        theta: &[Vec<f64>],
        damping: &DampingCurve,
        request: FrfRequest<'_>,
    ) -> Result<f64, FrfError> {
        let full = self.modal_state_with_fields(kappa, theta, damping)?;
        let expected = self.evaluate(&full, request, false);
        assert_eq!(found.len(), expected.h.len(), "FRFs on the request's lines and pairs");
        let n = request.frequencies_hz.len().max(1);
        Ok(found
            .chunks(n)
            .zip(expected.h.chunks(n))
            .map(|(a, b)| {
                let peak = b.iter().map(|v| v.norm()).fold(0.0, f64::max);
                a.iter().zip(b).map(|(x, y)| (x - y).norm() / peak).fold(0.0, f64::max)
            })
            .fold(0.0, f64::max))
    }

    /// The direct path of eq. (31)–(32): solves `Z(ω) x = N_sᵀ` with
    /// `Z = K - ω²M + jωC`, `C = M Φ diag(2ζω) Φᵀ M` (eq. 25 with
    /// `Φ⁻¹ = Φᵀ M`), and returns `N_r x` in the requested quantity.
    /// `C` comes from `state`; `kappa` sets `K`. For verification: `O(n³)`
    /// per frequency.
    pub fn direct(
        &self,
        kappa: &[Vec<f64>],
        state: &ModalState,
        frequency_hz: f64,
        pair: (usize, usize),
        quantity: Quantity,
    ) -> Result<c64, FrfError> {
        let dense = self.dense().ok_or(FrfError::DenseOnly("the direct FRF solve"))?;
        let k = dense.stiffness_with(kappa)?;
        let m = &dense.mass;
        let n = m.nrows();
        let phi = &state.modes.shapes;
        let d = Mat::from_fn(phi.ncols(), phi.ncols(), |i, j| {
            if i == j {
                2.0 * state.zeta[i] * state.omega[i]
            } else {
                0.0
            }
        });
        let mphi = m * phi;
        let c = &mphi * &d * mphi.transpose();
        let w = 2.0 * PI * frequency_hz;
        let red = &dense.reduction;
        let z_re = red.reduce(&Mat::from_fn(n, n, |i, j| k[(i, j)] - w * w * m[(i, j)]));
        let z_im = red.reduce(&Mat::from_fn(n, n, |i, j| w * c[(i, j)]));
        let full_rhs = |s: usize| {
            let mut v = Mat::<f64>::zeros(n, 1);
            for &(dof, val) in &self.sensor_rows[s] {
                v[(dof, 0)] += val;
            }
            v
        };
        let rhs = red.reduce_vector(&full_rhs(pair.1));
        let x = complex_solve(&z_re, &z_im, &rhs).ok_or(FrfError::SingularImpedance { frequency_hz })?;
        let (x_re, x_im) = (red.expand(&x.0), red.expand(&x.1));
        let response = self.sensor_rows[pair.0]
            .iter()
            .fold(c64::new(0.0, 0.0), |acc, &(dof, v)| {
                acc + c64::new(x_re[(dof, 0)], x_im[(dof, 0)]) * v
            });
        Ok(response * quantity.factor(w))
    }
}

/// Frequency lines per block in [`FrfModel::evaluate`]: every intermediate
/// (at most the active modes × 32 lines, re and im: 67 kB for Sinello) stays
/// in L2, and a typical 300-line band splits evenly over two threads.
pub const FREQUENCY_BLOCK: usize = 32;

/// The frequency-independent factors of one spring block's sensitivity
/// on a truncated model ([`FrfModel::add_residual`]).
struct BlockResidual {
    /// `Φ_Bᵀ B Φ_B`: modes × modes.
    coupling: Mat<f64>,
    /// `Φ_Bᵀ B ρ_0,t`, `Φ_Bᵀ B ρ_1,t`: modes × involved sensors.
    u0: Mat<f64>,
    u1: Mat<f64>,
    /// `ρ_pᵀ B ρ_q` for (p, q) = (0, 0), (0, 1), (1, 0), (1, 1): involved
    /// sensors × involved sensors.
    c: [Mat<f64>; 4],
}

/// See [`FrfModel::prepare`]: the active modes' data and the products
/// that do not depend on frequency.
struct Prepared {
    sensitivities: bool,
    /// ω of the active modes.
    omega: Vec<f64>,
    omega2: Vec<f64>,
    two_zeta_omega: Vec<f64>,
    /// `a_{r,i} a_{s,i}` per pair.
    coupling: Mat<f64>,
    /// Per damping coefficient: first mode of its support, weights.
    damping_terms: Vec<(usize, Mat<f64>)>,
    nu: usize,
    /// `Φ_U diag(a_s)` per input, stacked.
    stacked: Mat<f64>,
    /// `Φ_{B_j}ᵀ B_j` per spring coefficient (none without sensitivities).
    phi_b_blocks: Vec<Mat<f64>>,
    /// Per input: its pairs and their output amplitudes.
    by_input: Vec<(Vec<usize>, Mat<f64>)>,
}

/// A complex matrix stored as real and imaginary parts, for real GEMMs.
struct Split {
    re: Mat<f64>,
    im: Mat<f64>,
}

impl Split {
    fn zeros(rows: usize, cols: usize) -> Self {
        Self {
            re: Mat::zeros(rows, cols),
            im: Mat::zeros(rows, cols),
        }
    }

    /// Column `j` as contiguous real and imaginary slices.
    fn col_mut(&mut self, j: usize) -> (&mut [f64], &mut [f64]) {
        (self.re.col_as_slice_mut(j), self.im.col_as_slice_mut(j))
    }

    /// `self[..rows, ..cols] = a · b[.., ..cols]` for real `a`.
    fn product(&mut self, rows: usize, cols: usize, a: &Mat<f64>, b: &Split) {
        for (dst, src) in [(&mut self.re, &b.re), (&mut self.im, &b.im)] {
            matmul(
                dst.submatrix_mut(0, 0, rows, cols),
                Accum::Replace,
                a.as_ref(),
                src.subcols(0, cols),
                1.0,
                Par::Seq,
            );
        }
    }
}
