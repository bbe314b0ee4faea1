//! The deck driven by its grounds: quasi-static influence, transmissibilities
//! from ground to deck acceleration, and the inputs of the time recursion.
//!
//! Absolute coordinates `u` (the generalised dofs of eq. 4). The supports of
//! group `g` ([`crate::model::supports`]) connect to a ground translating by
//! `u_g`; its springs and bearings act on `u − R u_g` (`R_d`: unit
//! translation along axis `d` of every control point, rotations zero), its
//! constrained edges follow `R u_g`. With `ΔK_g = Σ_{j∈g} κ_j ∂K/∂κ_j` (eq. 22)
//! the equations of motion are
//!
//! `M ü + C (u̇ − Γ u̇_g) + K u = Σ_g ΔK_g R u_g`, `u = ℓ_g u_g` on group `g`'s
//! constrained dofs.
//!
//! The quasi-static influence `Γ_{g,d}` (the deck's static displacement for a
//! unit ground displacement of `g` along `d`) lifts the constraints with
//! `ℓ_{g,d}` (`e_d` at every control point on `g`'s constrained edges) and
//! solves the rest on the free coordinates (`δ = T q`):
//! `Γ = ℓ + T (TᵀKT)⁻¹ Tᵀ f`, `f = ΔK_g R_d − K ℓ`; by the mass-normalised
//! modes of the whole model (every mode: the dense path)
//! `Γ = ℓ + Σ_i φ_i P_i / λ_i`, `P_i = φ_iᵀ f`. One group holding every
//! support gives `Γ = R_d` (a deck moving with its ground).
//!
//! With `u = Γ u_g + y`, `y = T q`, the relative motion obeys
//! `M ÿ + C ẏ + K y = −M Γ ü_g`: the classical relative formulation
//! (Clough & Penzien 2003, §26-2), with the damping acting on the motion
//! relative to the quasi-static one. This is the damping term kept for the
//! support velocity: `C Γ u̇_g`, so that a rigid body on a damped spring has
//! the textbook transmissibility `(ω_n² + 2jζω_nω)/(ω_n² − ω² + 2jζω_nω)`.
//! Modal damping is eq. (28)'s ζ(f). Per mode, with the participation
//! `L_i = φ_iᵀ M Γ = φ_iᵀ M ℓ + P_i/λ_i`:
//!
//! `q̈_i + 2ζ_iω_i q̇_i + ω_i² q_i = −L_i ü_g`, and the absolute acceleration
//! at sensor `r` is `N_r Γ ü_g + Σ_i a_{r,i} q̈_i`, so the transmissibility
//! (deck acceleration per ground acceleration) is
//!
//! `T_r(ω) = N_r Γ + ω² Σ_i a_{r,i} L_i / D_i(ω)`, `D_i` of eq. (31).

mod ground_forces;
mod grounded;

use crate::model::damping::DampingCurve;
use crate::model::dofs::DofMap;
use crate::model::supports::{SupportError, SupportGroups};
use crate::response::frf::{FrfModel, FrfRequest, ModalState, Quantity};
use crate::response::simulate::ModalSimulator;
use crate::solvers::modal::ModeKind;
use faer::{c64, Mat};
use ground_forces::{ground_force, truncated_forces, GroundLifts};
pub use grounded::GroundedStructure;
use std::f64::consts::PI;

/// A load as a sparse row on the generalised dofs `(dof, value)`.
type LoadRow = Vec<(usize, f64)>;

pub use crate::model::supports::GroundInput;

/// The support motion of a modal state: per ground input its quasi-static
/// response at the sensors and its modal participations.
#[derive(Debug, Clone)]
pub struct SupportMotion {
    inputs: Vec<GroundInput>,
    /// `N Γ`: sensors × inputs.
    quasi_static: Mat<f64>,
    /// `L = Φᵀ M Γ`: modes × inputs.
    participation: Mat<f64>,
    /// `Γ` of every input on the generalised dofs: dofs × inputs.
    influence: Mat<f64>,
    /// `M Γ_c` of every input, its non-zero entries (the load rows).
    inertial_loads: Vec<LoadRow>,
    /// The numbering of those dofs (which are translations along which axis).
    dofs: DofMap,
}

/// Which coefficients [`SupportMotion::sensitivities_for`] differentiates
/// by.
#[derive(Debug, Clone, Copy)]
pub struct SensitivitySelection<'a> {
    /// The spring coefficients (flat indices,
    /// [`FrfModel::flat_spring_index`]); every one when `None`.
    pub springs: Option<&'a [usize]>,
    /// The stiffness fields' coefficients, all of them or none.
    pub fields: bool,
}

impl SensitivitySelection<'_> {
    /// Every spring and field coefficient.
    pub const EVERY: Self = Self {
        springs: None,
        fields: true,
    };
}

/// `∂T/∂p` of every `(sensor, input)` pair, pair-major as the FRFs.
#[derive(Debug, Clone)]
pub struct TransmissibilitySensitivities {
    /// One vector per spring coefficient (spring fields, then bearings).
    pub dkappa: Vec<Vec<c64>>,
    /// One vector per stiffness-field coefficient.
    pub dtheta: Vec<Vec<c64>>,
    /// One vector per damping coefficient.
    pub dgamma: Vec<Vec<c64>>,
}

impl SupportMotion {
    /// The motion for `inputs` of the model `frf` (dense, or truncated: see
    /// `truncated_influence`) of the structure `grounded`, with spring
    /// coefficients `kappa` and stiffness-field coefficients `theta` at
    /// which `state` was solved.
    pub fn new(
        (frf, grounded): (&FrfModel, &GroundedStructure),
        kappa: &[Vec<f64>],
        theta: &[Vec<f64>],
        state: &ModalState,
        inputs: &[GroundInput],
    ) -> Result<Self, SupportError> {
        check_inputs(frf, kappa, grounded, inputs)?;
        let (lifts, groups) = (grounded.lifts(), grounded.groups());
        let influence = match frf.dense() {
            Some(assembled) => dense_influence(assembled, groups, kappa, theta, state, inputs, lifts),
            None => {
                let forces = truncated_forces(frf, grounded.structure(), groups, (kappa, theta), inputs, lifts)?;
                let (model, cutoff_hz) = frf.sparse().expect("a model is dense or truncated");
                let (_, responses) = model
                    .modes_and_responses(kappa, theta, cutoff_hz, &forces)
                    .map_err(|e| SupportError::Solve(e.to_string()))?;
                truncated_influence(state, &forces, &responses, cutoff_hz, (lifts, inputs))
            }
        };
        Ok(Self::from_influence(frf, state, inputs, influence, lifts.dofs.clone()))
    }

    /// The modal state at `kappa`, `theta` and `damping`
    /// ([`FrfModel::modal_state_with_fields`]) and the motion for `inputs`
    /// on it ([`Self::new`]), from one eigen-solve: on a truncated model the
    /// static responses to the ground forces come from the modes' own
    /// factorisation instead of a second solve.
    pub fn with_state(
        (frf, grounded): (&FrfModel, &GroundedStructure),
        (kappa, theta, damping): (&[Vec<f64>], &[Vec<f64>], &DampingCurve),
        inputs: &[GroundInput],
    ) -> Result<(ModalState, Self), SupportError> {
        check_inputs(frf, kappa, grounded, inputs)?;
        let (lifts, groups) = (grounded.lifts(), grounded.groups());
        let solve_error = |e: crate::response::frf::FrfError| SupportError::Solve(e.to_string());
        let (state, influence) = match frf.dense() {
            Some(assembled) => {
                let state = frf
                    .modal_state_with_fields(kappa, theta, damping)
                    .map_err(solve_error)?;
                let influence = dense_influence(assembled, groups, kappa, theta, &state, inputs, lifts);
                (state, influence)
            }
            None => {
                let forces = truncated_forces(frf, grounded.structure(), groups, (kappa, theta), inputs, lifts)?;
                let (state, responses) = frf
                    .modal_state_with_loads(kappa, theta, damping, &forces)
                    .map_err(solve_error)?;
                let (_, cutoff_hz) = frf.sparse().expect("a model is dense or truncated");
                let responses = responses.expect("a truncated model gives the loads' responses");
                let influence = truncated_influence(&state, &forces, &responses, cutoff_hz, (lifts, inputs));
                (state, influence)
            }
        };
        let motion = Self::from_influence(frf, &state, inputs, influence, lifts.dofs.clone());
        Ok((state, motion))
    }

    /// `frf` with a Ritz basis at `(kappa, theta)` for the ground forces of
    /// `inputs`, the `extra` loads (the loss factors',
    /// [`FrfModel::loss_factor_loads`]) and the spring coefficients `varied`
    /// (flat indices): the model [`Self::with_state`] solves on by
    /// projection wherever only those springs move
    /// ([`FrfModel::with_reanalysis`]); a dense model as it is.
    pub fn reanalysed(
        (frf, grounded): (&FrfModel, &GroundedStructure),
        (kappa, theta): (&[Vec<f64>], &[Vec<f64>]),
        (inputs, extra): (&[GroundInput], &[LoadRow]),
        varied: &[usize],
    ) -> Result<FrfModel, SupportError> {
        if frf.dense().is_some() {
            return Ok(frf.clone());
        }
        check_inputs(frf, kappa, grounded, inputs)?;
        let mut forces = truncated_forces(
            frf,
            grounded.structure(),
            grounded.groups(),
            (kappa, theta),
            inputs,
            grounded.lifts(),
        )?;
        forces.extend_from_slice(extra);
        frf.with_reanalysis((kappa, theta), &forces, varied)
            .map_err(|e| SupportError::Solve(e.to_string()))
    }

    /// `N Γ` and `L = Φᵀ M Γ` of the influence `Γ` (dofs × inputs).
    fn from_influence(
        frf: &FrfModel,
        state: &ModalState,
        inputs: &[GroundInput],
        influence: Mat<f64>,
        dofs: DofMap,
    ) -> Self {
        let n = influence.nrows();
        let shapes = &state.modes.shapes;
        let nm = state.modes.len();
        let mut quasi_static = Mat::<f64>::zeros(frf.sensor_count(), inputs.len());
        let mut participation = Mat::<f64>::zeros(nm, inputs.len());
        let mut inertial_loads = Vec::with_capacity(inputs.len());
        for c in 0..inputs.len() {
            let gamma: Vec<f64> = (0..n).map(|d| influence[(d, c)]).collect();
            for (r, row) in frf.sensor_rows().iter().enumerate() {
                quasi_static[(r, c)] = row.iter().map(|&(d, v)| v * gamma[d]).sum();
            }
            let mass_gamma = frf.mass_times(&gamma);
            for i in 0..nm {
                participation[(i, c)] = (0..n).map(|d| shapes[(d, i)] * mass_gamma[d]).sum();
            }
            inertial_loads.push(mass_gamma.into_iter().enumerate().filter(|(_, v)| *v != 0.0).collect());
        }
        Self {
            inputs: inputs.to_vec(),
            quasi_static,
            participation,
            influence,
            inertial_loads,
            dofs,
        }
    }

    pub fn inputs(&self) -> &[GroundInput] {
        &self.inputs
    }

    /// `N_r Γ` of input `c` at sensor `r`: the deck's quasi-static
    /// displacement per unit ground displacement.
    pub fn quasi_static(&self, sensor: usize, input: usize) -> f64 {
        self.quasi_static[(sensor, input)]
    }

    /// `L_i` of input `c`.
    pub fn participation(&self, mode: usize, input: usize) -> f64 {
        self.participation[(mode, input)]
    }

    /// `T_r(ω)` of every `(sensor, input)` pair at `frequencies_hz`,
    /// pair-major (`[pair * n_f + line]`), as the FRFs are stored.
    #[track_caller]
    pub fn transmissibility(&self, state: &ModalState, pairs: &[(usize, usize)], frequencies_hz: &[f64]) -> Vec<c64> {
        assert_eq!(
            state.modes.len(),
            self.participation.nrows(),
            "the modal state of this motion"
        );
        let mut out = Vec::with_capacity(pairs.len() * frequencies_hz.len());
        for &(r, c) in pairs {
            for &f in frequencies_hz {
                let w = 2.0 * PI * f;
                let mut sum = c64::new(0.0, 0.0);
                for i in 0..state.modes.len() {
                    let d = denominator(state, i, w);
                    sum += c64::new(state.amplitude(r, i) * self.participation[(i, c)], 0.0) / d;
                }
                out.push(c64::new(self.quasi_static[(r, c)], 0.0) + sum * (w * w));
            }
        }
        out
    }

    /// `T_r(ω) = N_r Γ + ω² H_r,v(ω)` with `H_r,v` the receptance from the
    /// inertial load row `v = M Γ` to sensor `r` by the shared FRF evaluation
    /// of `loads` (`frf` with [`Self::load_rows`] appended): on a truncated
    /// model the discarded modes' residual (flexibility, first dynamic
    /// correction and damping, [`crate::solvers::truncation`]) is included;
    /// on the dense path it equals [`Self::transmissibility`].
    #[track_caller]
    pub fn transmissibility_with_residual(
        &self,
        frf: &FrfModel,
        loads: &FrfModel,
        load_state: &ModalState,
        pairs: &[(usize, usize)],
        frequencies_hz: &[f64],
    ) -> Vec<c64> {
        let sensors = frf.sensor_count();
        let load_pairs: Vec<(usize, usize)> = pairs.iter().map(|&(r, c)| (r, sensors + c)).collect();
        let request = FrfRequest {
            frequencies_hz,
            pairs: &load_pairs,
            quantity: Quantity::Receptance,
        };
        let h = loads.evaluate(load_state, request, false).h;
        let nf = frequencies_hz.len();
        h.into_iter()
            .enumerate()
            .map(|(k, x)| {
                let (r, c) = pairs[k / nf];
                let w = 2.0 * PI * frequencies_hz[k % nf];
                c64::new(self.quasi_static[(r, c)], 0.0) + x * (w * w)
            })
            .collect()
    }

    /// The exact recursion of [`ModalSimulator`] driven by the ground
    /// accelerations of every input (its "forces", m/s²), giving the absolute
    /// accelerations at every sensor.
    pub fn simulator(&self, state: &ModalState, dt: f64) -> ModalSimulator {
        let gains = Mat::from_fn(self.participation.nrows(), self.participation.ncols(), |i, c| {
            -self.participation[(i, c)]
        });
        ModalSimulator::with_gains(
            state,
            self.quasi_static.nrows(),
            &gains,
            Some(self.quasi_static.clone()),
            dt,
        )
    }

    /// The inertial loads `(M Γ_c)ᵀ` of every input (`M` the mass of the
    /// model this motion was made on) as rows of their non-zero entries, to
    /// append to that model's sensors ([`FrfModel::with_extra_rows`]): the
    /// transmissibility's dynamic part is `ω²` times the receptance from that
    /// row to the deck sensors. Formed once, with the participations.
    pub fn load_rows(&self) -> Vec<LoadRow> {
        self.inertial_loads.clone()
    }

    /// `∂T_r/∂p` for every spring coefficient, stiffness-field coefficient
    /// and damping coefficient, exact on the dense path. With
    /// `T = N Γ + ω² N Z⁻¹ M Γ`:
    ///
    /// `∂T = ω² ∂(N Z⁻¹ v)|_{v = MΓ fixed} + N ∂Γ + ω² N Z⁻¹ M ∂Γ`.
    ///
    /// The first term is the receptance sensitivity of the shared FRF
    /// evaluation (eq. 33 with the modal damping's exact share,
    /// [`FrfModel::evaluate`], [`FrfModel::field_frf_sensitivities`]) from the
    /// load row `v` (`loads`: `frf` with [`Self::load_rows`] appended). The
    /// others follow from `∂Γ = K⁻¹ w`, `w = ∂(ΔK_g) R − (∂K) Γ` (zero for
    /// damping), by the modes: `Σ_i a_ri (φ_iᵀ w / λ_i)(1 + ω²/D_i)`.
    /// Uniform excitation has `∂Γ = 0` (Γ = R).
    #[allow(clippy::too_many_arguments)] // the model, its loads, the groups, the state and the request
    pub fn sensitivities(
        &self,
        frf: &FrfModel,
        loads: &FrfModel,
        groups: &SupportGroups,
        state: &ModalState,
        damping: &DampingCurve,
        pairs: &[(usize, usize)],
        frequencies_hz: &[f64],
    ) -> TransmissibilitySensitivities {
        let load_state = loads.restate(state, damping);
        self.sensitivities_for(
            frf,
            (loads, &load_state),
            groups,
            state,
            damping,
            pairs,
            frequencies_hz,
            SensitivitySelection::EVERY,
        )
    }

    /// [`Self::sensitivities`], the loads' modal state given, of the
    /// coefficients `wanted` selects; the others' vectors are left empty
    /// (an update needs its parameters', and the influence change of each
    /// costs a sum over the modes at every line and pair; a held field's,
    /// over every mode and dof).
    #[allow(clippy::too_many_arguments)] // as sensitivities, and the selection
    pub fn sensitivities_for(
        &self,
        frf: &FrfModel,
        (loads, load_state): (&FrfModel, &ModalState),
        groups: &SupportGroups,
        state: &ModalState,
        damping: &DampingCurve,
        pairs: &[(usize, usize)],
        frequencies_hz: &[f64],
        wanted: SensitivitySelection<'_>,
    ) -> TransmissibilitySensitivities {
        let SensitivitySelection { springs, fields } = wanted;
        let sensors = frf.sensor_count();
        let load_pairs: Vec<(usize, usize)> = pairs.iter().map(|&(r, c)| (r, sensors + c)).collect();
        let request = FrfRequest {
            frequencies_hz,
            pairs: &load_pairs,
            quantity: Quantity::Receptance,
        };
        let evaluation = match springs {
            Some(springs) => loads.evaluate_springs(load_state, request, springs),
            None => loads.evaluate(load_state, request, true),
        };
        // ω² per line, the receptances' factor to accelerances.
        let omega2: Vec<f64> = frequencies_hz.iter().map(|&f| (2.0 * PI * f).powi(2)).collect();
        let scaled = |mut v: Vec<c64>| -> Vec<c64> {
            for pair in v.chunks_mut(omega2.len().max(1)) {
                pair.iter_mut().zip(&omega2).for_each(|(x, &w2)| *x *= w2);
            }
            v
        };
        let wanted = |flat: usize| springs.is_none_or(|list| list.contains(&flat));
        let mut dkappa: Vec<Vec<c64>> = evaluation
            .dh_dkappa
            .into_iter()
            .enumerate()
            .map(|(flat, v)| if wanted(flat) { scaled(v) } else { Vec::new() })
            .collect();
        let dgamma: Vec<Vec<c64>> = evaluation.dh_dgamma.into_iter().map(scaled).collect();
        let mut dtheta: Vec<Vec<c64>> = if fields && frf.field_coefficient_count() > 0 {
            loads
                .field_frf_sensitivities(load_state, damping, request)
                .into_iter()
                .map(scaled)
                .collect()
        } else {
            Vec::new()
        };
        // The influence's own change: w = B_j (δ_{j∈g} R − Γ) for a spring
        // coefficient, −(∂K/∂θ_k) Γ for a field coefficient; every one's
        // modal weights first, then one product with the dynamic factors.
        let mut change = InfluenceChange::new(state, pairs.len());
        let mut flat = 0;
        for (field, blocks) in frf.spring_blocks().iter().enumerate() {
            for b in blocks {
                if !wanted(flat) {
                    flat += 1;
                    continue;
                }
                let w = |c: usize| -> Vec<(usize, f64)> {
                    let ground = groups.rigid_motion(field, &self.inputs[c]);
                    b.dofs
                        .iter()
                        .enumerate()
                        .map(|(a, &ra)| {
                            let v = b.dofs.iter().enumerate().map(|(e, &re)| {
                                b.values[(a, e)] * (ground.at(&self.dofs, re) - self.influence[(re, c)])
                            });
                            (ra, v.sum())
                        })
                        .collect()
                };
                change.push(state, pairs, self.inputs.len(), w, Target::Spring(flat));
                flat += 1;
            }
        }
        for k in 0..dtheta.len() {
            let product = frf.field_times(k, &self.influence);
            let w = |c: usize| -> Vec<(usize, f64)> { (0..product.nrows()).map(|d| (d, -product[(d, c)])).collect() };
            change.push(state, pairs, self.inputs.len(), w, Target::Field(k));
        }
        change.add_to(state, frequencies_hz, &mut dkappa, &mut dtheta);
        TransmissibilitySensitivities { dkappa, dtheta, dgamma }
    }
}

/// Which sensitivity an [`InfluenceChange`] row block adds to.
#[derive(Clone, Copy)]
enum Target {
    Spring(usize),
    Field(usize),
}

/// The change of the quasi-static influence, `Σ_i a_ri (φ_iᵀ w_c / λ_i)
/// (1 + ω²/D_i)` for every pair `(r, c)` and line, of several
/// coefficients at once: per coefficient and pair the modal weights
/// `a_ri φ_iᵀ w_c / λ_i` (a row), then one real product of all rows with
/// the real and imaginary parts of the dynamic factors `1 + ω²/D_i(ω)`
/// (modes × lines): a matrix product where a loop per coefficient, pair,
/// mode and line waited on its memory.
struct InfluenceChange {
    /// The coefficient of each block of `pairs` rows, in row order.
    targets: Vec<Target>,
    /// The rows: coefficients × pairs, each `n_modes` long.
    weights: Vec<f64>,
    pairs: usize,
    modes: usize,
    flexible: Vec<usize>,
}

impl InfluenceChange {
    fn new(state: &ModalState, pairs: usize) -> Self {
        Self {
            targets: Vec::new(),
            weights: Vec::new(),
            pairs,
            modes: state.modes.len(),
            flexible: flexible_modes(state),
        }
    }

    /// The rows of one coefficient whose load `w_c` is given sparse per
    /// input.
    fn push(
        &mut self,
        state: &ModalState,
        pairs: &[(usize, usize)],
        inputs: usize,
        w: impl Fn(usize) -> Vec<(usize, f64)>,
        target: Target,
    ) {
        let nm = self.modes;
        let per_input: Vec<Vec<f64>> = (0..inputs)
            .map(|c| {
                let w = w(c);
                let mut weights = vec![0.0; nm];
                for &i in &self.flexible {
                    let p: f64 = w.iter().map(|&(d, v)| state.modes.shapes[(d, i)] * v).sum();
                    weights[i] = p / state.modes.omega2[i];
                }
                weights
            })
            .collect();
        for &(r, c) in pairs {
            self.weights
                .extend((0..nm).map(|i| state.amplitude(r, i) * per_input[c][i]));
        }
        self.targets.push(target);
    }

    /// Adds every coefficient's change to its sensitivity (pair-major,
    /// `[pair * n_lines + line]`).
    fn add_to(self, state: &ModalState, frequencies_hz: &[f64], dkappa: &mut [Vec<c64>], dtheta: &mut [Vec<c64>]) {
        let (nm, nf, np) = (self.modes, frequencies_hz.len(), self.pairs);
        if self.targets.is_empty() || nm == 0 || nf == 0 {
            return;
        }
        let (re, im) = influence_factors(state, frequencies_hz);
        let rows = Mat::from_fn(self.targets.len() * np, nm, |row, i| self.weights[row * nm + i]);
        let (out_re, out_im) = (&rows * &re, &rows * &im);
        for (t, target) in self.targets.iter().enumerate() {
            let out = match *target {
                Target::Spring(flat) => &mut dkappa[flat],
                Target::Field(k) => &mut dtheta[k],
            };
            for p in 0..np {
                let row = t * np + p;
                for (k, o) in out[p * nf..(p + 1) * nf].iter_mut().enumerate() {
                    *o += c64::new(out_re[(row, k)], out_im[(row, k)]);
                }
            }
        }
    }
}

/// `1 + ω²/D_i(ω)` per mode (rows) and line, its real and imaginary
/// parts: the dynamic amplification of a static load's change.
fn influence_factors(state: &ModalState, frequencies_hz: &[f64]) -> (Mat<f64>, Mat<f64>) {
    let (nm, nf) = (state.modes.len(), frequencies_hz.len());
    let (mut re, mut im) = (Mat::zeros(nm, nf), Mat::zeros(nm, nf));
    for i in 0..nm {
        for (k, &f) in frequencies_hz.iter().enumerate() {
            let w = 2.0 * PI * f;
            let factor = c64::new(1.0, 0.0) + c64::new(w * w, 0.0) / denominator(state, i, w);
            (re[(i, k)], im[(i, k)]) = (factor.re, factor.im);
        }
    }
    (re, im)
}

/// The modes that carry static load: all but the rigid ones (classified
/// rigid, or `|λ|` below 1e-12 of the largest). A rigid mode `φ` has
/// `Kφ = 0`, so `ΔK_g φ = 0` (every part of `K` is positive semi-definite)
/// and `φᵀ(ΔK_g R − K ℓ) = 0`, as for any change of stiffness: it takes no
/// part in a static response or its change.
fn flexible_modes(state: &ModalState) -> Vec<usize> {
    let largest = state.modes.omega2.iter().fold(0.0f64, |a, &l| a.max(l.abs()));
    (0..state.modes.len())
        .filter(|&i| state.modes.kinds[i] != ModeKind::Rigid && state.modes.omega2[i].abs() > 1e-12 * largest)
        .collect()
}

/// `D_i(ω) = ω_i² − ω² + 2j ζ_i ω_i ω` of mode `i` (eq. 31).
fn denominator(state: &ModalState, i: usize, omega: f64) -> c64 {
    let lambda = state.modes.omega2[i].max(0.0);
    c64::new(lambda - omega * omega, 2.0 * state.zeta[i] * lambda.sqrt() * omega)
}

/// `T (TᵀKT)⁻¹ Tᵀ f` by every mode of the state (the dense path): the
/// static response `Σ_i φ_i (φ_iᵀ f) / λ_i` over the flexible modes.
fn static_by_modes(state: &ModalState, force: &[f64]) -> Vec<f64> {
    let shapes = &state.modes.shapes;
    let mut x = vec![0.0; force.len()];
    for i in flexible_modes(state) {
        let lambda = state.modes.omega2[i];
        let p: f64 = force.iter().enumerate().map(|(d, f)| shapes[(d, i)] * f).sum();
        for (d, xd) in x.iter_mut().enumerate() {
            *xd += shapes[(d, i)] * p / lambda;
        }
    }
    x
}

/// The inputs name groups and axes of `grounded` that exist, and `kappa`
/// holds a vector per spring field of `frf` (a short one would silently
/// leave springs out of the ground's forces).
fn check_inputs(
    frf: &FrfModel,
    kappa: &[Vec<f64>],
    grounded: &GroundedStructure,
    inputs: &[GroundInput],
) -> Result<(), SupportError> {
    let fields = frf.spring_blocks().len();
    if kappa.len() != fields {
        return Err(SupportError::Count {
            what: "spring coefficient vectors",
            found: kappa.len(),
            expected: fields,
        });
    }
    grounded.check_inputs(inputs)
}

/// `Γ` on the dense path: `ℓ + Σ_i φ_i P_i / λ_i` over every mode.
fn dense_influence(
    assembled: &crate::solvers::dense_model::AssembledModel,
    groups: &SupportGroups,
    kappa: &[Vec<f64>],
    theta: &[Vec<f64>],
    state: &ModalState,
    inputs: &[GroundInput],
    lifts: &GroundLifts,
) -> Mat<f64> {
    let mut influence = Mat::<f64>::zeros(assembled.free_stiffness.nrows(), inputs.len());
    for (c, input) in inputs.iter().enumerate() {
        let lift = lifts.lift(input);
        let force = ground_force(assembled, groups, (kappa, theta), input, &lift, &lifts.dofs);
        let solved = static_by_modes(state, &force);
        for (d, (l, x)) in lift.iter().zip(solved).enumerate() {
            influence[(d, c)] = l + x;
        }
    }
    influence
}

/// `Γ` on a truncated model: the static response `K⁻¹ f` from the
/// eigen-solve's factorisation at its shift `σ` (`X = (K − σM)⁻¹`, with
/// `X M X`, the `responses` of
/// [`crate::solvers::sparse_model::SparseModel::modes_and_responses`] to
/// the `forces`), brought to `σ = 0` by
/// `1/λ = 1/(λ−σ) − σ/(λ−σ)² + σ²/(λ(λ−σ)²)`:
/// `K⁻¹ f = X f − σ X M X f + Σ φ_i P_i σ²/(λ_i (λ_i−σ)²)`, the last sum
/// over the kept modes (for a discarded one it is `(σ/λ)² ≤ 1/2500²` of its
/// share).
fn truncated_influence(
    state: &ModalState,
    forces: &[Vec<(usize, f64)>],
    (x, xmx): &crate::solvers::partial_eigen::Responses,
    cutoff_hz: f64,
    (lifts, inputs): (&GroundLifts, &[GroundInput]),
) -> Mat<f64> {
    let sigma = crate::solvers::sparse_model::SparseModel::shift_for(cutoff_hz);
    let shapes = &state.modes.shapes;
    let flexible = flexible_modes(state);
    let n = x.nrows();
    let mut influence = Mat::from_fn(n, forces.len(), |d, c| x[(d, c)] - sigma * xmx[(d, c)]);
    for (c, force) in forces.iter().enumerate() {
        for &i in &flexible {
            let lambda = state.modes.omega2[i];
            let p: f64 = force.iter().map(|&(d, f)| shapes[(d, i)] * f).sum();
            let weight = p * (1.0 / lambda - 1.0 / (lambda - sigma) + sigma / (lambda - sigma).powi(2));
            for d in 0..n {
                influence[(d, c)] += shapes[(d, i)] * weight;
            }
        }
        if lifts.moves(inputs[c].group) {
            for (d, l) in lifts.lift(&inputs[c]).into_iter().enumerate() {
                influence[(d, c)] += l;
            }
        }
    }
    influence
}
