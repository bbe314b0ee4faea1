//! Damping that follows the structure: the supports' loss factors weighed
//! by each mode's strain energy in them (modal strain energy, Johnson &
//! Kienholz 1982; [`crate::model::damping`]).
//!
//! With `K_s = Σ_{j∈s} κ_j B_j` (`B_j = ∂K/∂κ_j`, `K` linear in `κ`) and
//! mass-normalised modes, `P_{i,s} = φ_iᵀ K_s φ_i`, `e_{i,s} = P_{i,s}/λ_i`
//! and `ζ_i = ζ(f_i) + Q_i / (2 λ_i)`, `Q_i = Σ_s η_s P_{i,s}`.
//!
//! Derivatives (exact, the eigenvector derivatives of Fox & Kapoor 1968 by
//! modal expansion as in [`crate::response::modal_sensitivity`]):
//! - `∂ζ_i/∂η_s = ½ e_{i,s}`;
//! - through `λ_i` alone: `∂ζ_i/∂λ_i ∋ −Q_i / (2 λ_i²)`;
//! - with `λ_i` held, through `K_s` and `φ_i` (a coefficient `κ_j` of field
//!   `s(j)`, or a stiffness-field coefficient with `∂K_s = 0`):
//!   `∂Q_i = η_{s(j)} φ_iᵀ B_j φ_i + 2 Σ_{k≠i} G_{ik} C_{ki} / (λ_i − λ_k)`,
//!   `G = Φᵀ (Σ_s η_s K_s) Φ`, `C = Φᵀ (∂K) Φ`; the sum runs over the
//!   state's modes, so it is exact on the dense model (every mode) and
//!   leaves out the discarded modes on a truncated one; (nearly) repeated
//!   eigenvalues are skipped as there.

use super::{FrfModel, ModalState};
use crate::solvers::modal::{ModeKind, Modes};
use faer::Mat;

/// The supports' share of every mode's strain energy and their loss factors.
#[derive(Debug, Clone)]
pub(super) struct SupportLoss {
    /// `e_{i,s}`: modes × spring fields.
    pub(super) energy: Mat<f64>,
    /// `η_s`.
    factors: Vec<f64>,
    /// `Q_i = Σ_s η_s P_{i,s}` per mode.
    pub(super) weighted: Vec<f64>,
    /// `G = Φᵀ (Σ_s η_s K_s) Φ` over the state's modes (empty when every
    /// `η_s` is zero: no term depends on it then).
    coupling: Mat<f64>,
}

impl SupportLoss {
    /// The energies of `modes` (shapes on the spring dofs `phi_springs`)
    /// at spring coefficients `kappa`, with loss factors `factors`.
    pub(super) fn new(
        model: &FrfModel,
        modes: &Modes,
        phi_springs: &Mat<f64>,
        kappa: &[Vec<f64>],
        factors: &[f64],
    ) -> Self {
        let nm = modes.len();
        let fields = model.spring_blocks();
        let positions = model.spring_block_positions();
        let lossy = factors.iter().any(|&eta| eta > 0.0);
        let mut energy = Mat::<f64>::zeros(nm, fields.len());
        let mut coupling = if lossy { Mat::zeros(nm, nm) } else { Mat::zeros(0, 0) };
        let mut flat = 0;
        for (s, blocks) in fields.iter().enumerate() {
            for (j, block) in blocks.iter().enumerate() {
                let pos = &positions[flat + j];
                let shapes = Mat::from_fn(pos.len(), nm, |b, i| phi_springs[(pos[b], i)]);
                let product = &block.values * &shapes;
                let k = kappa[s][j];
                for i in 0..nm {
                    energy[(i, s)] += k * (0..pos.len()).map(|b| shapes[(b, i)] * product[(b, i)]).sum::<f64>();
                }
                if lossy && factors[s] > 0.0 {
                    coupling += (factors[s] * k) * (shapes.transpose() * &product);
                }
            }
            flat += blocks.len();
        }
        let mut weighted = vec![0.0; nm];
        for i in 0..nm {
            weighted[i] = (0..fields.len()).map(|s| factors[s] * energy[(i, s)]).sum();
            let lambda = modes.omega2[i];
            let scale = if modes.kinds[i] == ModeKind::Rigid || lambda <= 0.0 {
                0.0
            } else {
                1.0 / lambda
            };
            for s in 0..fields.len() {
                energy[(i, s)] *= scale;
            }
            if scale == 0.0 {
                weighted[i] = 0.0;
            }
        }
        Self {
            energy,
            factors: factors.to_vec(),
            weighted,
            coupling,
        }
    }

    /// `Σ_s η_s e_{i,s}`: twice the supports' share of `ζ_i`.
    pub(super) fn loss(&self, i: usize) -> f64 {
        (0..self.factors.len())
            .map(|s| self.factors[s] * self.energy[(i, s)])
            .sum()
    }

    /// `∂ζ_i` with `λ_i` held, through `φ_i` (and `K_s` by `direct =
    /// η_{s(j)} φ_iᵀ B_j φ_i`), for a stiffness change whose modal couplings
    /// `C_{ki}` are `coupling(k)`.
    pub(super) fn zeta_slope(&self, modes: &Modes, i: usize, direct: f64, coupling: impl Fn(usize) -> f64) -> f64 {
        let lambda = &modes.omega2;
        if self.weighted[i] == 0.0 && direct == 0.0 && self.coupling.nrows() == 0 {
            return 0.0;
        }
        if modes.kinds[i] == ModeKind::Rigid || lambda[i] <= 0.0 {
            return 0.0;
        }
        let mut dq = direct;
        if self.coupling.nrows() > 0 {
            for k in 0..modes.len() {
                let gap = lambda[i] - lambda[k];
                if k == i || gap.abs() <= 1e-9 * lambda[i].abs() {
                    continue;
                }
                dq += 2.0 * self.coupling[(i, k)] * coupling(k) / gap;
            }
        }
        dq / (2.0 * lambda[i])
    }

    /// `η_s`.
    pub(super) fn factor(&self, s: usize) -> f64 {
        self.factors[s]
    }
}

impl FrfModel {
    /// `∂ζ_i/∂κ_j` with `λ_i` held (the supports' loss factors' part,
    /// [`SupportLoss::zeta_slope`]) for the modes `modes` of `state` and the
    /// spring coefficients `blocks` (flat indices): modes × blocks, zero
    /// without loss factors.
    pub(super) fn loss_zeta_slopes(&self, state: &ModalState, modes: &[usize], blocks: &[usize]) -> Mat<f64> {
        let mut out = Mat::zeros(modes.len(), blocks.len());
        let Some(loss) = &state.loss else {
            return out;
        };
        let field_of: Vec<usize> = self
            .spring_blocks()
            .iter()
            .enumerate()
            .flat_map(|(s, b)| std::iter::repeat_n(s, b.len()))
            .collect();
        let all: Vec<_> = self.spring_blocks().iter().flatten().collect();
        let nm = state.modes.len();
        for (c, &j) in blocks.iter().enumerate() {
            let eta = loss.factor(field_of[j]);
            if eta == 0.0 && loss.coupling.nrows() == 0 {
                continue;
            }
            let pos = &self.spring_block_positions()[j];
            let shapes = Mat::from_fn(pos.len(), nm, |b, i| state.phi_springs[(pos[b], i)]);
            for (r, &i) in modes.iter().enumerate() {
                let bi: Vec<f64> = (0..pos.len())
                    .map(|a| (0..pos.len()).map(|b| all[j].values[(a, b)] * shapes[(b, i)]).sum())
                    .collect();
                let couple = |k: usize| (0..pos.len()).map(|a| shapes[(a, k)] * bi[a]).sum::<f64>();
                out[(r, c)] = loss.zeta_slope(&state.modes, i, eta * couple(i), couple);
            }
        }
        out
    }
}

impl ModalState {
    /// `∂ζ_i` with `λ_i` held for a stiffness change `∂K` that couples the
    /// modes by `coupling(k) = C_{ki}` and is a coefficient of spring field
    /// `field` (`None`: a stiffness field, which leaves the supports alone):
    /// the loss factors' share moving with the shape.
    pub(crate) fn support_zeta_slope(&self, i: usize, field: Option<usize>, coupling: impl Fn(usize) -> f64) -> f64 {
        self.loss.as_ref().map_or(0.0, |l| {
            let direct = field.map_or(0.0, |s| l.factor(s) * coupling(i));
            l.zeta_slope(&self.modes, i, direct, coupling)
        })
    }

    /// `∂ζ_i/∂λ_i` with the shape held: the damping curve's slope and the
    /// loss factors' `−Q_i/(2λ_i²)` (zero for a rigid mode).
    pub(crate) fn zeta_eigenvalue_slope(&self, i: usize) -> f64 {
        let omega = self.omega[i];
        if omega <= 0.0 {
            return 0.0;
        }
        (self.damping_rate_slope[i] - self.zeta[i] / omega) / (2.0 * omega)
    }
}
