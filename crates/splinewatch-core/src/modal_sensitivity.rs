//! Derivatives of the modes with respect to the spring coefficients: the
//! sensitivities of a modal residue (output-only updating).
//!
//! With mass-normalised modes and `M` independent of `κ` (eq. 23: only `K`
//! depends on the springs), Fox & Kapoor (1968) give
//! `∂λ_i/∂κ_j = φ_iᵀ (∂K/∂κ_j) φ_i` (`λ = ω²`) and, by modal expansion,
//! `∂φ_i/∂κ_j = Σ_{k≠i} φ_k (φ_kᵀ ∂K/∂κ_j φ_i) / (λ_i − λ_k)`
//! (the `−½ φ_i φ_iᵀ ∂M φ_i` term vanishes). The expansion is exact here:
//! the modal solver returns every mode of the reduced model. Only the few
//! dofs of each low-rank `∂K/∂κ_j` are touched (the modes on the spring
//! dofs, `ModalState::phi_springs`). Modes nearly equal to `λ_i`
//! (`|λ_i − λ_k| ≤ 1e-9 λ_i`: a repeated eigenvalue, where the derivative of
//! an individual eigenvector is not defined) are left out of the sum.

use crate::frf::{FrfModel, ModalState};
use faer::Mat;

/// Derivatives of selected modes with respect to every spring coefficient
/// (fields flattened in order, as `FrfEvaluation::dh_dkappa`).
#[derive(Debug, Clone)]
pub struct ModalSensitivities {
    /// The modes (indices into the modal state) in the rows below.
    pub modes: Vec<usize>,
    /// `∂λ_i/∂κ_j`: `modes × coefficients`, rad²/s² per unit of κ.
    pub eigenvalue: Mat<f64>,
    /// Per selected mode, `∂a_{s,i}/∂κ_j` at the sensors: `sensors × coefficients`.
    pub amplitude: Vec<Mat<f64>>,
}

impl FrfModel {
    /// Eigenvalue and sensor-amplitude derivatives of `modes` at `state`.
    pub fn modal_sensitivities(&self, state: &ModalState, modes: &[usize]) -> ModalSensitivities {
        let nm = state.modes.len();
        let blocks: Vec<_> = self.assembled().spring_blocks.iter().flatten().collect();
        let positions = self.spring_block_positions();
        let phi_u = state.spring_shapes();
        let lambda = &state.modes.omega2;
        let sensors = self.sensor_count();
        let mut eigenvalue = Mat::zeros(modes.len(), blocks.len());
        let mut amplitude = Vec::with_capacity(modes.len());
        for (row, &i) in modes.iter().enumerate() {
            let mut da = Mat::zeros(sensors, blocks.len());
            for (j, (block, pos)) in blocks.iter().zip(positions).enumerate() {
                // w = (∂K/∂κ_j) φ_i on the block's dofs.
                let w: Vec<f64> = (0..pos.len())
                    .map(|a| (0..pos.len()).map(|b| block.values[(a, b)] * phi_u[(pos[b], i)]).sum())
                    .collect();
                let coupling = |k: usize| -> f64 { (0..pos.len()).map(|a| phi_u[(pos[a], k)] * w[a]).sum() };
                eigenvalue[(row, j)] = coupling(i);
                for k in 0..nm {
                    let gap = lambda[i] - lambda[k];
                    if k == i || gap.abs() <= 1e-9 * lambda[i].abs() {
                        continue;
                    }
                    let factor = coupling(k) / gap;
                    if factor == 0.0 {
                        continue;
                    }
                    for s in 0..sensors {
                        da[(s, j)] += state.amplitude(s, k) * factor;
                    }
                }
            }
            amplitude.push(da);
        }
        ModalSensitivities {
            modes: modes.to_vec(),
            eigenvalue,
            amplitude,
        }
    }
}
