//! Damping that follows the structure: the supports' loss factors weighed
//! by each mode's strain energy in them (modal strain energy, Johnson &
//! Kienholz 1982; [`crate::model::damping`]).
//!
//! With `K_s = Σ_{j∈s} κ_j B_j` over the spring coefficients `j` of loss
//! site `s` ([`crate::model::loss_sites`]; `B_j = ∂K/∂κ_j`, `K` linear in `κ`) and
//! mass-normalised modes, `P_{i,s} = φ_iᵀ K_s φ_i`, `e_{i,s} = P_{i,s}/λ_i`
//! and `ζ_i = ζ(f_i) + Q_i / (2 λ_i)`, `Q_i = Σ_s η_s P_{i,s}`.
//!
//! Derivatives (exact, the eigenvector derivatives of Fox & Kapoor 1968 by
//! modal expansion as in [`crate::response::modal_sensitivity`]):
//! - `∂ζ_i/∂η_s = ½ e_{i,s}`;
//! - through `λ_i` alone: `∂ζ_i/∂λ_i ∋ −Q_i / (2 λ_i²)`;
//! - with `λ_i` held, through `K_s` and `φ_i` (a coefficient `κ_j` of site
//!   `s(j)`, with `η_{s(j)} = 0` in no site, or a stiffness-field
//!   coefficient with `∂K_s = 0`):
//!   `∂Q_i = η_{s(j)} φ_iᵀ B_j φ_i + 2 Σ_{k≠i} G_{ik} C_{ki} / (λ_i − λ_k)`,
//!   `G = Φᵀ (Σ_s η_s K_s) Φ`, `C = Φᵀ (∂K) Φ`; the sum runs over the
//!   state's modes, so it is exact on the dense model (every mode); on a
//!   truncated one the discarded modes' part
//!   `Σ_d (wᵀφ_d)(φ_dᵀ b)/(λ_i − λ_d)`, `w = (Σ_s η_s K_s) φ_i`,
//!   `b = ∂K φ_i`, is `−wᵀ (R_0 + (λ_i − σ) R_1) b` to first order, with the
//!   discarded modes' flexibility `R_p` on the spring dofs from unit loads
//!   there (the modified modal method, Wang 1991, as
//!   [`crate::solvers::truncation`] does for the sensors) when `∂K` is a
//!   spring coefficient's (a stiffness field's reaches beyond the spring
//!   dofs: its discarded part is left out); (nearly) repeated eigenvalues
//!   are skipped as there.

use super::{FrfModel, ModalState};
use crate::model::loss_sites::SiteOf;
use crate::solvers::modal::{ModeKind, Modes};
use faer::Mat;

/// The supports' share of every mode's strain energy and their loss factors.
#[derive(Debug, Clone)]
pub(super) struct SupportLoss {
    /// `e_{i,s}`: modes × loss sites.
    pub(super) energy: Mat<f64>,
    /// `η_s`.
    factors: Vec<f64>,
    /// The loss site of each spring and stiffness-field coefficient (flat), if any.
    site_of: SiteOf,
    /// `Q_i = Σ_s η_s P_{i,s}` per mode.
    pub(super) weighted: Vec<f64>,
    /// `G = Φᵀ (Σ_s η_s K_s) Φ` over the state's modes (empty when every
    /// `η_s` is zero: no term depends on it then).
    coupling: Mat<f64>,
    /// `Σ_s η_s K_s` on the spring dofs (`|U| × |U|`; empty as `coupling`).
    hysteretic: Mat<f64>,
    /// The discarded modes' flexibility on the spring dofs, on a truncated
    /// model with loss factors.
    discarded: Option<Discarded>,
}

/// The discarded modes seen from the spring dofs `U` ([`SupportLoss::add_discarded`]).
#[derive(Debug, Clone)]
struct Discarded {
    /// `R_0`, `R_1`: `|U| × |U|`.
    flexibility: [Mat<f64>; 2],
    shift: f64,
    /// `w_i = (Σ_s η_s K_s) φ_i` on `U`: `|U| × modes`.
    hysteretic_shapes: Mat<f64>,
}

impl SupportLoss {
    /// The energies of `modes` (shapes on the spring dofs `phi_springs`)
    /// at spring coefficients `kappa` and stiffness-field coefficients
    /// `theta`, with loss factors `factors` on the sites `site_of` gives
    /// each coefficient.
    pub(super) fn new(
        model: &FrfModel,
        modes: &Modes,
        phi_springs: &Mat<f64>,
        (kappa, theta): (&[Vec<f64>], &[Vec<f64>]),
        (factors, site_of): (&[f64], SiteOf),
    ) -> Self {
        let nm = modes.len();
        let fields = model.spring_blocks();
        let positions = model.spring_block_positions();
        let lossy = factors.iter().any(|&eta| eta > 0.0);
        let mut energy = Mat::<f64>::zeros(nm, factors.len());
        let mut coupling = if lossy { Mat::zeros(nm, nm) } else { Mat::zeros(0, 0) };
        let units = if lossy { phi_springs.nrows() } else { 0 };
        let mut hysteretic = Mat::<f64>::zeros(units, units);
        let mut flat = 0;
        for (s, blocks) in fields.iter().enumerate() {
            for (j, block) in blocks.iter().enumerate() {
                let Some(site) = site_of.springs[flat + j] else {
                    continue;
                };
                let pos = &positions[flat + j];
                let shapes = Mat::from_fn(pos.len(), nm, |b, i| phi_springs[(pos[b], i)]);
                let product = &block.values * &shapes;
                let k = kappa[s][j];
                for i in 0..nm {
                    energy[(i, site)] += k * (0..pos.len()).map(|b| shapes[(b, i)] * product[(b, i)]).sum::<f64>();
                }
                let eta = factors[site];
                if lossy && eta > 0.0 {
                    coupling += (eta * k) * (shapes.transpose() * &product);
                    for (a, &pa) in pos.iter().enumerate() {
                        for (b, &pb) in pos.iter().enumerate() {
                            hysteretic[(pa, pb)] += eta * k * block.values[(a, b)];
                        }
                    }
                }
            }
            flat += blocks.len();
        }
        // Stiffness-field sites: `P = θ_k Φᵀ (∂K/∂θ_k) Φ` over every dof
        // (not on the spring dofs alone: no part in `hysteretic`).
        for (k, &theta_k) in theta.iter().flatten().enumerate() {
            let Some(site) = site_of.fields[k] else { continue };
            let product = theta_k * model.field_quadratic(k, &modes.shapes);
            for i in 0..nm {
                energy[(i, site)] += product[(i, i)];
            }
            let eta = factors[site];
            if lossy && eta > 0.0 {
                coupling += eta * &product;
            }
        }
        let mut weighted = vec![0.0; nm];
        for i in 0..nm {
            weighted[i] = (0..factors.len()).map(|s| factors[s] * energy[(i, s)]).sum();
            let lambda = modes.omega2[i];
            let scale = if modes.kinds[i] == ModeKind::Rigid || lambda <= 0.0 {
                0.0
            } else {
                1.0 / lambda
            };
            for s in 0..factors.len() {
                energy[(i, s)] *= scale;
            }
            if scale == 0.0 {
                weighted[i] = 0.0;
            }
        }
        Self {
            energy,
            factors: factors.to_vec(),
            site_of,
            weighted,
            coupling,
            hysteretic,
            discarded: None,
        }
    }

    /// The discarded modes' flexibility on the spring dofs `spring_dofs`
    /// from `responses` (`(K − σM)⁻¹` and `(K − σM)⁻¹ M (K − σM)⁻¹` applied
    /// to a unit load at each, on every dof) less the kept modes' part.
    pub(super) fn add_discarded(
        &mut self,
        modes: &Modes,
        phi_springs: &Mat<f64>,
        spring_dofs: &[usize],
        responses: &(Mat<f64>, Mat<f64>),
        shift: f64,
    ) {
        let nu = spring_dofs.len();
        // Column `a` holds dof `a`'s row of the kept shapes, contiguous.
        let shapes = phi_springs.transpose().to_owned();
        let flexibility = |response: &Mat<f64>, power: i32| {
            let denominators: Vec<f64> = modes.omega2.iter().map(|&l| (l - shift).powi(power)).collect();
            let mut r = Mat::<f64>::zeros(nu, nu);
            // The kept part is symmetric in (a, b): formed once per pair,
            // the two responses averaged (the same sums as entry by entry).
            for b in 0..nu {
                let phi_b = shapes.col_as_slice(b);
                for a in b..nu {
                    let kept: f64 = shapes
                        .col_as_slice(a)
                        .iter()
                        .zip(phi_b)
                        .zip(&denominators)
                        .map(|((pa, pb), d)| pa * pb / d)
                        .sum();
                    let (ab, ba) = (
                        response[(spring_dofs[a], b)] - kept,
                        response[(spring_dofs[b], a)] - kept,
                    );
                    r[(a, b)] = 0.5 * (ab + ba);
                    r[(b, a)] = 0.5 * (ba + ab);
                }
            }
            r
        };
        self.discarded = Some(Discarded {
            flexibility: [flexibility(&responses.0, 1), flexibility(&responses.1, 2)],
            shift,
            hysteretic_shapes: &self.hysteretic * phi_springs,
        });
    }

    /// `Σ_s η_s e_{i,s}`: twice the supports' share of `ζ_i`.
    pub(super) fn loss(&self, i: usize) -> f64 {
        (0..self.factors.len())
            .map(|s| self.factors[s] * self.energy[(i, s)])
            .sum()
    }

    /// `∂ζ_i` with `λ_i` held, through `φ_i` (and `K_s` by `direct =
    /// η_{s(j)} φ_iᵀ B_j φ_i`), for a stiffness change whose modal couplings
    /// `C_{ki}` are `coupling(k)` and, for a spring coefficient, whose
    /// `∂K φ_i` on the spring dofs is `on_springs` (`(index in U, value)`:
    /// the discarded modes' part on a truncated model).
    pub(super) fn zeta_slope(
        &self,
        modes: &Modes,
        i: usize,
        direct: f64,
        coupling: impl Fn(usize) -> f64,
        on_springs: Option<&[(usize, f64)]>,
    ) -> f64 {
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
            if let (Some(discarded), Some(b)) = (&self.discarded, on_springs) {
                dq -= 2.0 * discarded.product(i, lambda[i], b);
            }
        }
        dq / (2.0 * lambda[i])
    }

    /// `η_{s(j)}` of spring coefficient `j` (flat; zero in no site).
    pub(super) fn factor_of(&self, j: usize) -> f64 {
        self.site_of.springs[j].map_or(0.0, |s| self.factors[s])
    }

    /// `η_{s(k)}` of stiffness-field coefficient `k` (flat; zero in no site).
    fn field_factor_of(&self, k: usize) -> f64 {
        self.site_of.fields[k].map_or(0.0, |s| self.factors[s])
    }
}

impl Discarded {
    /// `w_iᵀ (R_0 + (λ_i − σ) R_1) b` for `b` on the spring dofs.
    fn product(&self, i: usize, lambda: f64, b: &[(usize, f64)]) -> f64 {
        let [r0, r1] = &self.flexibility;
        let t = lambda - self.shift;
        let w = self.hysteretic_shapes.col(i);
        b.iter()
            .map(|&(u, value)| {
                value
                    * (0..w.nrows())
                        .map(|a| w[a] * (r0[(a, u)] + t * r1[(a, u)]))
                        .sum::<f64>()
            })
            .sum()
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
        let all: Vec<_> = self.spring_blocks().iter().flatten().collect();
        let nm = state.modes.len();
        for (c, &j) in blocks.iter().enumerate() {
            let eta = loss.factor_of(j);
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
                let on_springs: Vec<(usize, f64)> = pos.iter().copied().zip(bi.iter().copied()).collect();
                out[(r, c)] = loss.zeta_slope(&state.modes, i, eta * couple(i), couple, Some(&on_springs));
            }
        }
        out
    }
}

impl ModalState {
    /// `∂ζ_i` with `λ_i` held for a stiffness change `∂K` (`change`) that
    /// couples the modes by `coupling(k) = C_{ki}`: the loss factors' share
    /// moving with the shape, and with `K_s` when the coefficient is in a
    /// loss site.
    pub(crate) fn support_zeta_slope(
        &self,
        i: usize,
        change: StiffnessChange<'_>,
        coupling: impl Fn(usize) -> f64,
    ) -> f64 {
        self.loss.as_ref().map_or(0.0, |l| {
            let (eta, on_springs) = match change {
                StiffnessChange::Spring(j, on_springs) => (l.factor_of(j), Some(on_springs)),
                StiffnessChange::Field(k) => (l.field_factor_of(k), None),
            };
            l.zeta_slope(&self.modes, i, eta * coupling(i), coupling, on_springs)
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

/// A stiffness change whose effect on the loss factors' share of `ζ_i` is
/// asked ([`ModalState::support_zeta_slope`]).
#[derive(Debug, Clone, Copy)]
pub(crate) enum StiffnessChange<'a> {
    /// Spring coefficient `j` (flat), with `∂K φ_i` on the spring dofs
    /// (`(index in U, value)`: the discarded modes' part on a truncated
    /// model).
    Spring(usize, &'a [(usize, f64)]),
    /// Stiffness-field coefficient `k` (flat); its discarded modes' part is
    /// left out (it reaches beyond the spring dofs).
    Field(usize),
}
