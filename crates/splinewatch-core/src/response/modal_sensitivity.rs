//! Derivatives of the modes with respect to the spring coefficients and
//! the stiffness-field coefficients: the sensitivities of a modal residue
//! (output-only updating).
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
//!
//! For a stiffness field `∂K/∂θ_k` is dense over the field's part of the
//! deck: the couplings `C = Φᵀ (∂K/∂θ_k) Φ` of every mode pair are formed
//! with two products per coefficient, and the same expansion applies. On a
//! truncated model (the modes below a cut-off, [`crate::solvers::truncation`]) the
//! product runs over `[Φ | ρ_0 | ρ_1]` (the residual responses to the sensor
//! loads on every dof): the discarded modes enter the eigenvector
//! derivatives as for the springs (Wang 1991) and the FRF derivatives
//! through `∂H_rs = −g_rᵀ (∂K/∂θ) g_s` with the sensors' complete
//! responses `g_s`.

use crate::model::damping::DampingCurve;
use crate::response::frf::{FrfModel, FrfRequest, ModalState, StiffnessChange};
use crate::solvers::modal::ModeKind;
use faer::linalg::matmul::matmul;
use faer::{c64, Accum, Mat, Par};
use std::f64::consts::PI;

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
    /// `∂ζ_i/∂κ_j`: `modes × coefficients` (the damping curve's slope
    /// through `f_i`, and the supports' loss factors' share,
    /// [`crate::model::damping`]).
    pub damping_ratio: Mat<f64>,
}

impl FrfModel {
    /// Eigenvalue and sensor-amplitude derivatives of `modes` at `state`.
    pub fn modal_sensitivities(&self, state: &ModalState, modes: &[usize]) -> ModalSensitivities {
        let blocks: Vec<_> = self.spring_blocks().iter().flatten().collect();
        let positions = self.spring_block_positions();
        let phi_u = state.spring_shapes();
        let sensors = self.sensor_count();
        let mut eigenvalue = Mat::zeros(modes.len(), blocks.len());
        let mut damping_ratio = Mat::zeros(modes.len(), blocks.len());
        let mut amplitude = Vec::with_capacity(modes.len());
        for (row, &i) in modes.iter().enumerate() {
            let mut da = Mat::zeros(sensors, blocks.len());
            for (j, (block, pos)) in blocks.iter().zip(positions).enumerate() {
                // w = (∂K/∂κ_j) φ_i on the block's dofs.
                let w: Vec<f64> = (0..pos.len())
                    .map(|a| (0..pos.len()).map(|b| block.values[(a, b)] * phi_u[(pos[b], i)]).sum())
                    .collect();
                let coupling = |k: usize| -> f64 { (0..pos.len()).map(|a| phi_u[(pos[a], k)] * w[a]).sum() };
                expand(state, i, coupling, &mut da, j);
                if let Some(residual) = state.residual() {
                    // The discarded modes' part (crate::solvers::truncation, Wang 1991).
                    let lambda = state.modes.omega2[i];
                    for s in 0..sensors {
                        let rho: f64 = (0..pos.len())
                            .map(|a| residual.expansion_on_springs(pos[a], s, lambda) * w[a])
                            .sum();
                        da[(s, j)] -= rho;
                    }
                }
                eigenvalue[(row, j)] = coupling(i);
                let on_springs: Vec<(usize, f64)> = pos.iter().copied().zip(w.iter().copied()).collect();
                damping_ratio[(row, j)] = state.zeta_eigenvalue_slope(i) * coupling(i)
                    + state.support_zeta_slope(i, StiffnessChange::Spring(j, &on_springs), coupling);
            }
            amplitude.push(da);
        }
        ModalSensitivities {
            modes: modes.to_vec(),
            eigenvalue,
            amplitude,
            damping_ratio,
        }
    }

    /// Eigenvalue and sensor-amplitude derivatives of `modes` at `state`
    /// with respect to every stiffness-field coefficient θ (fields flattened
    /// in order); `state` must come from the same coefficients
    /// ([`FrfModel::modal_state_with_fields`]). On a dense model the
    /// expansion runs over every mode (exact); on a truncated one over the
    /// kept modes, with the discarded modes' part from the residual on
    /// every dof (Wang 1991, as for the springs).
    pub fn field_sensitivities(&self, state: &ModalState, modes: &[usize]) -> ModalSensitivities {
        let couplings = self.field_couplings(state);
        field_derivatives(state, modes, &couplings, true)
    }

    /// Every stiffness-field coefficient's [`FieldCouplings`] at `state`.
    fn field_couplings(&self, state: &ModalState) -> Vec<FieldCouplings> {
        let phi = &state.modes.shapes;
        let everywhere = state.residual().and_then(|r| r.everywhere());
        (0..self.field_coefficient_count())
            .map(|k| match everywhere {
                None => FieldCouplings {
                    modes: self.field_quadratic(k, phi),
                    residual: None,
                },
                Some([rho0, rho1]) => {
                    // One product over [Φ | ρ_0 | ρ_1] gives every block.
                    let (nm, ns) = (phi.ncols(), rho0.ncols());
                    let mut basis = Mat::<f64>::zeros(phi.nrows(), nm + 2 * ns);
                    basis.subcols_mut(0, nm).copy_from(phi);
                    basis.subcols_mut(nm, ns).copy_from(rho0);
                    basis.subcols_mut(nm + ns, ns).copy_from(rho1);
                    let all = self.field_quadratic(k, &basis);
                    let block = |row: usize, col: usize, rows: usize, cols: usize| {
                        all.submatrix(row, col, rows, cols).to_owned()
                    };
                    FieldCouplings {
                        modes: block(0, 0, nm, nm),
                        residual: Some(ResidualCouplings {
                            with_modes: [block(nm, 0, ns, nm), block(nm + ns, 0, ns, nm)],
                            with_residual: [
                                block(nm, nm, ns, ns),
                                block(nm, nm + ns, ns, ns),
                                block(nm + ns, nm + ns, ns, ns),
                            ],
                        }),
                    }
                }
            })
            .collect()
    }
}

/// One stiffness-field coefficient's `∂K/∂θ` seen from the kept modes and,
/// on a truncated model, from the residual responses `ρ_0`, `ρ_1` to the
/// sensor loads ([`crate::solvers::truncation`]).
struct FieldCouplings {
    /// `C = Φᵀ (∂K/∂θ) Φ`: modes × modes.
    modes: Mat<f64>,
    residual: Option<ResidualCouplings>,
}

struct ResidualCouplings {
    /// `P_p = ρ_pᵀ (∂K/∂θ) Φ`, `p = 0, 1`: sensors × modes.
    with_modes: [Mat<f64>; 2],
    /// `S_pq = ρ_pᵀ (∂K/∂θ) ρ_q` for `(p, q) = (0, 0), (0, 1), (1, 1)`:
    /// sensors × sensors.
    with_residual: [Mat<f64>; 3],
}

/// Eigen-derivatives of `modes` from the couplings: `∂λ_i = C_ii`, `∂a_i`
/// expanded over the state's modes and, with `discarded`, the discarded
/// modes' part `−(P_0 + (λ_i − σ) P_1)_{s,i}`.
fn field_derivatives(
    state: &ModalState,
    modes: &[usize],
    couplings: &[FieldCouplings],
    discarded: bool,
) -> ModalSensitivities {
    let sensors = state.sensor_count();
    let mut eigenvalue = Mat::zeros(modes.len(), couplings.len());
    let mut damping_ratio = Mat::zeros(modes.len(), couplings.len());
    let mut amplitude = vec![Mat::zeros(sensors, couplings.len()); modes.len()];
    for (j, c) in couplings.iter().enumerate() {
        for (row, &i) in modes.iter().enumerate() {
            eigenvalue[(row, j)] = c.modes[(i, i)];
            damping_ratio[(row, j)] = state.zeta_eigenvalue_slope(i) * c.modes[(i, i)]
                + state.support_zeta_slope(i, StiffnessChange::Field(j), |k| c.modes[(k, i)]);
            expand(state, i, |k| c.modes[(k, i)], &mut amplitude[row], j);
            if let (true, Some(r), Some(residual)) = (discarded, &c.residual, state.residual()) {
                let shifted = state.modes.omega2[i] - residual.shift();
                for s in 0..sensors {
                    amplitude[row][(s, j)] -= r.with_modes[0][(s, i)] + shifted * r.with_modes[1][(s, i)];
                }
            }
        }
    }
    ModalSensitivities {
        modes: modes.to_vec(),
        eigenvalue,
        amplitude,
        damping_ratio,
    }
}

impl FrfModel {
    /// `∂H/∂θ_k` of the FRFs of `request` for every stiffness-field
    /// coefficient (fields flattened; pair-major `[pair * n_f + line]` as
    /// [`crate::response::frf::FrfEvaluation::h`]), by the chain rule through the
    /// modal superposition `H_rs = Σ_i a_ri a_si q_i`,
    /// `q_i = 1 / (ω_i² − ω² + 2j ζ_i ω_i ω)` (eq. 31 with eq. 28):
    /// `∂H_rs = Σ_i (∂a_ri a_si + a_ri ∂a_si) q_i
    ///        − a_ri a_si q_i² (∂λ_i + 2j ω (ζ_i ∂ω_i + ω_i ζ'(f_i) ∂f_i))`,
    /// with the eigen-derivatives of [`Self::field_sensitivities`] over every
    /// mode (the expansion is then exact) and `ζ'` the damping curve's slope:
    /// the derivative of exactly the FRF [`FrfModel::evaluate`] computes.
    ///
    /// On a truncated model the sum runs over the kept modes with their
    /// expansion over the kept modes only, and the discarded modes enter
    /// through the residual responses `ρ_s(ω) = ρ_0,s + γ(ω) ρ_1,s`
    /// ([`crate::solvers::truncation`]): with the sensors' complete responses
    /// `g_s = Σ_i φ_i a_si q_i + ρ_s`, `∂H_rs = −g_rᵀ (∂K/∂θ) g_s` adds
    /// the kept–discarded couplings
    /// `−Σ_i q_i (a_ri (P_0 + γ P_1)_si + a_si (P_0 + γ P_1)_ri)` and the
    /// discarded ones' own `−(S_00 + γ (S_01 + S_01ᵀ) + γ² S_11)_rs`
    /// (the field couplings); the kept–kept part is the expression above, so
    /// the result tends to the dense one as the cut-off rises.
    pub fn field_frf_sensitivities(
        &self,
        state: &ModalState,
        damping: &DampingCurve,
        request: FrfRequest<'_>,
    ) -> Vec<Vec<c64>> {
        let nm = state.modes.len();
        let all: Vec<usize> = (0..nm).collect();
        let couplings = self.field_couplings(state);
        let sens = field_derivatives(state, &all, &couplings, false);
        let (nf, np) = (request.frequencies_hz.len(), request.pairs.len());
        let omega: Vec<f64> = (0..nm).map(|i| state.modes.omega2[i].max(0.0).sqrt()).collect();
        let nk = sens.eigenvalue.ncols();
        let mut out = vec![vec![c64::new(0.0, 0.0); np * nf]; nk];
        let damping_terms = damping_terms(state, damping, &sens, &couplings, &omega);
        let omega_lines: Vec<f64> = request.frequencies_hz.iter().map(|hz| 2.0 * PI * hz).collect();
        // q_i(f), line-major (`f * nm + i`); `split` makes a modes × lines
        // pair of real and imaginary parts.
        let q: Vec<c64> = (0..nf * nm)
            .map(|n| {
                let (w, i) = (omega_lines[n / nm], n % nm);
                c64::new(omega[i] * omega[i] - w * w, 2.0 * state.zeta[i] * omega[i] * w).inv()
            })
            .collect();
        let split = |z: &[c64]| {
            [
                Mat::from_fn(nm, nf, |i, f| z[f * nm + i].re),
                Mat::from_fn(nm, nf, |i, f| z[f * nm + i].im),
            ]
        };
        let q_parts = split(&q);
        let residual = state.residual();
        let truncated = |k: usize| couplings[k].residual.as_ref().filter(|_| residual.is_some());
        // The sums over the modes as real-by-complex products:
        // `Σ_i ∂(a_r a_s)_i q_i` for every (coefficient, pair) at once, and
        // per coefficient `Σ_i a_ri a_si q_i² (∂λ_i + 2j ω ∂(ζ_i ω_i))`.
        // On a truncated model the kept–discarded couplings
        // `−Σ_i q_i (a_ri (P_0 + γ P_1)_si + a_si (P_0 + γ P_1)_ri)` join the
        // first sum: their `P_0` part directly, their `P_1` part as `γ · Σ_i`.
        let d_amplitudes = Mat::from_fn(nk * np, nm, |row, i| {
            let (k, (r, s)) = (row / np, request.pairs[row % np]);
            let (ar, as_) = (state.amplitude(r, i), state.amplitude(s, i));
            let direct = sens.amplitude[i][(r, k)] * as_ + ar * sens.amplitude[i][(s, k)];
            truncated(k).map_or(direct, |c| {
                direct - ar * c.with_modes[0][(s, i)] - as_ * c.with_modes[0][(r, i)]
            })
        });
        let first = real_times_complex(&d_amplitudes, &q_parts);
        let towards_residual = residual.map(|_| {
            let p1 = Mat::from_fn(nk * np, nm, |row, i| {
                let (k, (r, s)) = (row / np, request.pairs[row % np]);
                truncated(k).map_or(0.0, |c| {
                    state.amplitude(r, i) * c.with_modes[1][(s, i)] + state.amplitude(s, i) * c.with_modes[1][(r, i)]
                })
            });
            real_times_complex(&p1, &q_parts)
        });
        let pair_amplitudes = Mat::from_fn(np, nm, |p, i| {
            let (r, s) = request.pairs[p];
            state.amplitude(r, i) * state.amplitude(s, i)
        });
        let second: Vec<[Mat<f64>; 2]> = (0..nk)
            .map(|k| {
                let v: Vec<c64> = (0..nf * nm)
                    .map(|n| {
                        let (f, i) = (n / nm, n % nm);
                        q[n] * q[n] * c64::new(sens.eigenvalue[(i, k)], 2.0 * omega_lines[f] * damping_terms[(i, k)])
                    })
                    .collect();
                real_times_complex(&pair_amplitudes, &split(&v))
            })
            .collect();
        for (k, dh) in out.iter_mut().enumerate() {
            for (p, &(r, s)) in request.pairs.iter().enumerate() {
                for (f, &w) in omega_lines.iter().enumerate() {
                    let (row, line) = (k * np + p, p * nf + f);
                    let [first_re, first_im] = &first;
                    let [second_re, second_im] = &second[k];
                    let mut sum = c64::new(first_re[(row, f)], first_im[(row, f)])
                        - c64::new(second_re[(p, f)], second_im[(p, f)]);
                    if let (Some(c), Some(residual), Some([p1_re, p1_im])) = (truncated(k), residual, &towards_residual)
                    {
                        let gamma = residual.expansion_factor(w);
                        sum -= gamma * c64::new(p1_re[(row, f)], p1_im[(row, f)]);
                        // The discarded modes' own part.
                        let [s00, s01, s11] = &c.with_residual;
                        sum -= gamma * gamma * s11[(r, s)] + gamma * (s01[(r, s)] + s01[(s, r)]) + s00[(r, s)];
                    }
                    dh[line] = sum * request.quantity.factor(w);
                }
            }
        }
        out
    }
}

/// `∂(ζ_i ω_i)/∂θ_k` of every mode for every coefficient (modes ×
/// coefficients): `∂ω_i`, and `∂ζ_i = ζ'(f_i) ∂f_i` plus the supports'
/// loss factors' share.
fn damping_terms(
    state: &ModalState,
    damping: &DampingCurve,
    sens: &ModalSensitivities,
    couplings: &[FieldCouplings],
    omega: &[f64],
) -> Mat<f64> {
    let (nm, nk) = (omega.len(), sens.eigenvalue.ncols());
    // ∂ω_i and ∂ζ_i = ζ'(f_i) ∂f_i of every mode for every coefficient.
    let d_omega = Mat::from_fn(nm, nk, |i, k| {
        if omega[i] > 0.0 {
            sens.eigenvalue[(i, k)] / (2.0 * omega[i])
        } else {
            0.0
        }
    });
    let slope: Vec<f64> = (0..nm)
        .map(|i| match state.modes.kinds[i] {
            // Rigid modes carry no damping (eq. 28 is not applied to them).
            ModeKind::Rigid => 0.0,
            _ => damping.slope(omega[i] / (2.0 * PI)) / (2.0 * PI),
        })
        .collect();
    let support_slopes = Mat::from_fn(nm, nk, |i, k| {
        state.support_zeta_slope(i, StiffnessChange::Field(k), |m| couplings[k].modes[(m, i)])
    });
    // ∂(ζ_i ω_i): the curve's and the supports' loss factors' share
    // (crate::model::damping), whose shape part is `support_zeta_slope`.
    Mat::from_fn(nm, nk, |i, k| {
        let support = 2.0 * state.support_zeta(i);
        (state.zeta[i] - support) * d_omega[(i, k)]
            + omega[i] * slope[i] * d_omega[(i, k)]
            + omega[i] * support_slopes[(i, k)]
    })
}

/// `real · (re + j im)` as its real and imaginary parts: two real products.
fn real_times_complex(real: &Mat<f64>, [re, im]: &[Mat<f64>; 2]) -> [Mat<f64>; 2] {
    let times = |part: &Mat<f64>| {
        let mut product = Mat::zeros(real.nrows(), part.ncols());
        matmul(
            product.as_mut(),
            Accum::Replace,
            real.as_ref(),
            part.as_ref(),
            1.0,
            Par::Seq,
        );
        product
    };
    [times(re), times(im)]
}

/// Adds to column `j` of `da` the modal expansion of `∂a_{·,i}`:
/// `Σ_{k≠i} a_{·,k} coupling(k) / (λ_i − λ_k)`, skipping (nearly) repeated
/// eigenvalues.
fn expand(state: &ModalState, i: usize, coupling: impl Fn(usize) -> f64, da: &mut Mat<f64>, j: usize) {
    let lambda = &state.modes.omega2;
    for k in 0..state.modes.len() {
        let gap = lambda[i] - lambda[k];
        if k == i || gap.abs() <= 1e-9 * lambda[i].abs() {
            continue;
        }
        let factor = coupling(k) / gap;
        if factor == 0.0 {
            continue;
        }
        for s in 0..da.nrows() {
            da[(s, j)] += state.amplitude(s, k) * factor;
        }
    }
}
