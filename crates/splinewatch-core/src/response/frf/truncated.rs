//! FRFs of a truncated model: the discarded modes' residual added to the
//! kept modes' sum, and the spring sensitivities from the spring dofs'
//! complete responses ([`crate::solvers::truncation`]); the truncation error
//! against a model that keeps every mode.

use super::evaluate::Wanted;
use super::{FrfError, FrfEvaluation, FrfModel, FrfRequest, ModalState};
use crate::model::damping::DampingCurve;
use crate::solvers::truncation::Residual;
use faer::{c64, Mat};
use std::f64::consts::PI;

impl FrfModel {
    /// Adds the residual of the discarded modes to `evaluation.h` and, with
    /// `sensitivities`, completes `∂H_rs/∂κ_j` to `−g_rᵀ (∂K/∂κ_j) g_s` with
    /// the spring dofs' complete responses `g_s = Σ_i φ_i a_{s,i} q_i + ρ_s`
    /// ([`crate::solvers::truncation`]) (the kept modes' part, with their
    /// damping share, is the modal sum's); the residual's damping term adds
    /// to `∂H/∂γ_z`.
    pub(super) fn add_residual(
        &self,
        state: &ModalState,
        residual: &Residual,
        request: FrfRequest<'_>,
        (wanted, blocks): (Wanted<'_>, &[usize]),
        evaluation: &mut FrfEvaluation,
    ) {
        let nf = request.frequencies_hz.len();
        for (p, &(r, s)) in request.pairs.iter().enumerate() {
            for (f, &hz) in request.frequencies_hz.iter().enumerate() {
                let w = 2.0 * PI * hz;
                evaluation.h[p * nf + f] += request.quantity.factor(w) * residual.at_sensors(r, s, w);
            }
        }
        if matches!(wanted, Wanted::Nothing) {
            return;
        }
        let curve = residual.damping_coefficient_count();
        for (z, dz) in evaluation.dh_dgamma.iter_mut().enumerate().take(curve) {
            for (p, &(r, s)) in request.pairs.iter().enumerate() {
                for (f, &hz) in request.frequencies_hz.iter().enumerate() {
                    let w = 2.0 * PI * hz;
                    dz[p * nf + f] += request.quantity.factor(w) * residual.damping_sensitivity(r, s, w, z);
                }
            }
        }
        let sensors = request.involved_sensors();
        let slot = |sensor: usize| sensors.binary_search(&sensor).expect("an involved sensor");
        let nm = state.modes.len();
        // Per block j (B = ∂K/∂κ_j on its dofs), with g_t = Φ_B x_t + ρ_0,t +
        // γ ρ_1,t, x_t = a_t ∘ q and γ(ω) the residual's frequency factor:
        // g_rᵀ B g_s = x_rᵀ P x_s + x_rᵀ (u_0,s + γ u_1,s) + (u_0,r + γ u_1,r)ᵀ x_s
        //            + c_00 + γ (c_01 + c_10) + γ² c_11,
        // P = Φ_Bᵀ B Φ_B, u_p,t = Φ_Bᵀ B ρ_p,t, c_pq = ρ_p,rᵀ B ρ_q,s: every
        // factor frequency-independent. The modal sum holds the x_rᵀ P x_s
        // part (and the kept modes' damping share); the rest costs O(modes)
        // a line per block.
        let prepared = self.block_residuals(state, residual, &sensors, blocks);
        let mut inputs: Vec<usize> = request.pairs.iter().map(|&(_, s)| slot(s)).collect();
        inputs.sort_unstable();
        inputs.dedup();
        let zero = c64::new(0.0, 0.0);
        let mut x = vec![vec![zero; nm]; sensors.len()];
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
                for (t, ut) in u.iter_mut().enumerate() {
                    for (i, ui) in ut.iter_mut().enumerate() {
                        *ui = gamma * b.u1[(i, t)] + b.u0[(i, t)];
                    }
                }
                for (p, &(r, s)) in request.pairs.iter().enumerate() {
                    let (r, s) = (slot(r), slot(s));
                    let c = |k: usize| b.c[k][(r, s)];
                    let value =
                        dot(&x[r], &u[s]) + dot(&u[r], &x[s]) + c(0) + gamma * (c(1) + c(2)) + gamma * gamma * c(3);
                    dh[p * nf + f] -= value * factor;
                }
            }
        }
    }

    /// The [`BlockResidual`] factors of the spring blocks `wanted` (flat
    /// indices) for the involved `sensors` (ascending).
    fn block_residuals(
        &self,
        state: &ModalState,
        residual: &Residual,
        sensors: &[usize],
        wanted: &[usize],
    ) -> Vec<BlockResidual> {
        let nm = state.modes.len();
        let (rho0, rho1) = residual.spring_terms();
        let blocks: Vec<_> = self.spring_blocks().iter().flatten().collect();
        wanted
            .iter()
            .map(|&j| (blocks[j], &self.block_positions[j]))
            .map(|(block, positions)| {
                let phi_b = Mat::from_fn(positions.len(), nm, |a, i| state.phi_springs[(positions[a], i)]);
                let rho = |terms: &Mat<f64>| {
                    Mat::from_fn(positions.len(), sensors.len(), |a, t| terms[(positions[a], sensors[t])])
                };
                let (r0, r1) = (rho(rho0), rho(rho1));
                let (b_r0, b_r1) = (&block.values * &r0, &block.values * &r1);
                BlockResidual {
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
}

/// The frequency-independent factors of one spring block's sensitivity
/// on a truncated model ([`FrfModel::add_residual`]).
struct BlockResidual {
    /// `Φ_Bᵀ B ρ_0,t`, `Φ_Bᵀ B ρ_1,t`: modes × involved sensors.
    u0: Mat<f64>,
    u1: Mat<f64>,
    /// `ρ_pᵀ B ρ_q` for (p, q) = (0, 0), (0, 1), (1, 0), (1, 1): involved
    /// sensors × involved sensors.
    c: [Mat<f64>; 4],
}
