//! Covariance-driven stochastic subspace identification (SSI-cov; Peeters &
//! De Roeck 1999, Döhler & Mevel 2013 for the notation).
//!
//! With `p` block rows and the correlations `R_k` (`l × r`), the block
//! Hankel matrix `H = [R_{i+j+1}]`, `i = 0..=p`, `j = 0..p−1`
//! (`l(p+1) × rp`), factorises as `H = O C_ref`. Its SVD `H = U Σ Vᵀ`
//! gives, at model order `n`, the observability matrix `O = U_n Σ_n^{1/2}`,
//! the output matrix `C` (its first `l` rows) and the state matrix by shift
//! invariance, `A = O↑⁺ O↓` (least squares; `O↑`/`O↓` drop the last/first
//! block row). Each eigenpair `(μ, ψ)` of `A` is a pole
//! `λ = ln(μ) f_s`, frequency `|λ|/2π`, damping ratio `−Re λ/|λ|`, shape
//! `φ = C ψ` at the sensors. One SVD serves every order.
//!
//! Every order from one pair of Gram matrices: `A = Σ^{-1/2} B Σ^{1/2}` with
//! `B = U↑⁺ U↓ = (U↑ᵀU↑)⁻¹ U↑ᵀU↓` on the first `n` columns, so the
//! eigenvalues are those of `B`, `ψ = Σ^{-1/2} ψ_B` and `φ = C ψ = U_top ψ_B`
//! (`U_top`: the first `l` rows of `U`). `G↑ = U↑ᵀU↑ = I − U_lastᵀU_last` is
//! well conditioned (`U` is orthonormal), so its leading `n × n` block is
//! factorised by Cholesky at each order: a small solve and an eigenvalue
//! problem per order instead of a least-squares solve on the tall `O↑`.

use super::shape::{mpc, normalise};
use super::OmaError;
use faer::linalg::solvers::Solve;
use faer::{c64, Mat, Side};
use std::f64::consts::PI;

/// One pole of the identified state-space model at one order.
#[derive(Debug, Clone, PartialEq)]
pub struct Pole {
    pub order: usize,
    pub frequency_hz: f64,
    pub damping_ratio: f64,
    /// At the sensors (all channels), largest component `1 + 0i`.
    pub shape: Vec<c64>,
    /// Modal phase collinearity of the shape.
    pub mpc: f64,
}

/// The SVD of the block Hankel matrix: poles at any order.
#[derive(Debug, Clone)]
pub struct SubspaceModel {
    /// First `l` rows of `U`.
    u_top: Mat<f64>,
    /// `U↑ᵀU↑` and `U↑ᵀU↓`, both `max_order × max_order`.
    gram_up: Mat<f64>,
    gram_shift: Mat<f64>,
    singular_values: Vec<f64>,
    /// Orders whose singular value is below `floor σ₁` are singular.
    floor: f64,
    channels: usize,
    fs: f64,
}

/// Below this fraction of `σ₁`, a singular value of the SVD is zero.
const SVD_FLOOR: f64 = 1e-13;
/// The same for [`Factorisation::GramEigen`] (√ε of the squared matrix).
const GRAM_FLOOR: f64 = 1e-7;

/// How [`SubspaceModel`] factorises the block Hankel matrix `H`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Factorisation {
    /// The thin SVD of `H` (the reported identification).
    Svd,
    /// The symmetric eigendecomposition of `HᵀH = V Σ² Vᵀ`, then
    /// `U_n = H V_n Σ_n⁻¹` on the columns asked for: about half the SVD's
    /// time on a 492 × 480 Hankel matrix. Squaring `H` costs precision: a
    /// singular value is accurate to `ε σ₁² / σ_i` and orders whose `σ_n`
    /// is below `1e-7 σ₁` are refused as singular (the jackknife's
    /// replicates, whose orders the full window's SVD has already passed).
    GramEigen,
}

impl SubspaceModel {
    /// `correlations` as [`super::OutputCorrelations::estimate`] lays them
    /// out (`(max_lag + 1) × l × r`, lag-major), `max_lag ≥ 2p`; poles will
    /// be asked for up to `max_order` (the Gram matrices are formed on that
    /// many columns only).
    pub fn new(
        correlations: &[f64],
        channels: usize,
        references: usize,
        block_rows: usize,
        max_order: usize,
        fs: f64,
    ) -> Result<Self, OmaError> {
        Self::factorised(
            correlations,
            channels,
            references,
            block_rows,
            max_order,
            fs,
            Factorisation::Svd,
        )
    }

    /// [`SubspaceModel::new`] by the chosen [`Factorisation`].
    pub fn factorised(
        correlations: &[f64],
        channels: usize,
        references: usize,
        block_rows: usize,
        max_order: usize,
        fs: f64,
        factorisation: Factorisation,
    ) -> Result<Self, OmaError> {
        let (l, r, p) = (channels, references, block_rows);
        if p == 0 || correlations.len() < (2 * p + 1) * l * r {
            return Err(OmaError::TooFewLags { block_rows: p });
        }
        let lag = |k: usize, a: usize, b: usize| correlations[(k * l + a) * r + b];
        let hankel = Mat::from_fn(l * (p + 1), r * p, |row, col| {
            lag(row / l + col / r + 1, row % l, col % r)
        });
        let cap = (l * p).min(max_order.max(1));
        let (u, singular_values, floor) = match factorisation {
            Factorisation::Svd => {
                let svd = hankel.thin_svd().map_err(|_| OmaError::SvdFailed)?;
                let values: Vec<f64> = svd.S().column_vector().iter().copied().collect();
                let cap = cap.min(values.len());
                (svd.U().subcols(0, cap).to_owned(), values, SVD_FLOOR)
            }
            Factorisation::GramEigen => {
                let gram = hankel.transpose() * &hankel;
                let eigen = gram.self_adjoint_eigen(Side::Lower).map_err(|_| OmaError::SvdFailed)?;
                // Ascending eigenvalues: the largest singular value last.
                let k = eigen.S().dim();
                let values: Vec<f64> = (0..k).rev().map(|i| eigen.S()[i].max(0.0).sqrt()).collect();
                let cap = cap.min(values.len());
                let v = Mat::from_fn(hankel.ncols(), cap, |row, col| eigen.U()[(row, k - 1 - col)]);
                let mut u = &hankel * &v;
                for (col, &sigma) in values.iter().take(cap).enumerate() {
                    let scale = if sigma > GRAM_FLOOR * values[0] {
                        1.0 / sigma
                    } else {
                        0.0
                    };
                    u.col_mut(col).iter_mut().for_each(|x| *x *= scale);
                }
                (u, values, GRAM_FLOOR)
            }
        };
        if !singular_values.iter().all(|s| s.is_finite()) || singular_values[0] <= 0.0 {
            return Err(OmaError::SingularHankel { order: 1 });
        }
        let rows = u.nrows();
        let (up, down) = (u.subrows(0, rows - l), u.subrows(l, rows - l));
        Ok(Self {
            u_top: u.subrows(0, l).to_owned(),
            gram_up: up.transpose() * up,
            gram_shift: up.transpose() * down,
            singular_values,
            floor,
            channels: l,
            fs,
        })
    }

    /// Singular values of `H`, non-increasing.
    pub fn singular_values(&self) -> &[f64] {
        &self.singular_values
    }

    /// Largest usable order: `O↑` (`lp` rows) must have full column rank,
    /// and at most the `max_order` given.
    pub fn max_order(&self) -> usize {
        self.gram_up.ncols()
    }

    /// The oscillating poles (one of each conjugate pair) at order `n`.
    pub fn poles(&self, order: usize) -> Result<Vec<Pole>, OmaError> {
        let l = self.channels;
        if order == 0 || order > self.max_order() {
            return Err(OmaError::OrderTooHigh {
                order,
                max: self.max_order(),
            });
        }
        if self.singular_values[order - 1] <= self.floor * self.singular_values[0] {
            return Err(OmaError::SingularHankel { order });
        }
        let n = order;
        let shift = self
            .gram_up
            .submatrix(0, 0, n, n)
            .llt(Side::Lower)
            .map_err(|_| OmaError::SingularHankel { order })?
            .solve(self.gram_shift.submatrix(0, 0, n, n));
        let eigen = shift.eigen().map_err(|_| OmaError::EigenFailed { order })?;
        let (values, vectors) = (eigen.S().column_vector(), eigen.U());
        let mut poles = Vec::new();
        for j in 0..order {
            let mu = values[j];
            if mu.im <= 0.0 || mu.norm() == 0.0 {
                continue; // the conjugate, a real pole or a pure delay
            }
            let lambda = c64::new(mu.norm().ln(), mu.im.atan2(mu.re)) * self.fs;
            let mut shape: Vec<c64> = (0..l)
                .map(|a| (0..n).map(|k| vectors[(k, j)] * self.u_top[(a, k)]).sum())
                .collect();
            normalise(&mut shape);
            poles.push(Pole {
                order,
                frequency_hz: lambda.norm() / (2.0 * PI),
                damping_ratio: -lambda.re / lambda.norm(),
                mpc: mpc(&shape),
                shape,
            });
        }
        poles.sort_by(|a, b| a.frequency_hz.total_cmp(&b.frequency_hz));
        Ok(poles)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Exact correlations of a two-mode system: `R_k = C Aᵏ G` with known
    /// poles, so SSI must return them to round-off.
    #[test]
    fn exact_correlations_give_the_exact_poles() {
        let fs = 100.0;
        let modes = [(3.0, 0.02), (11.0, 0.05)];
        let shapes = [[1.0, 0.5, -0.3], [0.2, -1.0, 0.7]];
        let (l, max_lag) = (3, 21);
        let mut r = vec![0.0; (max_lag + 1) * l * l];
        for ((f, zeta), shape) in modes.iter().zip(&shapes) {
            let omega = 2.0 * PI * f;
            let lambda = c64::new(-zeta * omega, omega * (1.0f64 - zeta * zeta).sqrt());
            for k in 0..=max_lag {
                // R_k = Re(φ e^{λ k Δt} gᵀ), g = φ (a symmetric, real-mode model).
                let decay = (lambda * (k as f64 / fs)).exp();
                for a in 0..l {
                    for b in 0..l {
                        r[(k * l + a) * l + b] += (decay * c64::new(shape[a] * shape[b], 0.0)).re;
                    }
                }
            }
        }
        let model = SubspaceModel::new(&r, l, l, 10, usize::MAX, fs).unwrap();
        let poles = model.poles(4).unwrap();
        assert_eq!(poles.len(), 2);
        for (pole, ((f, zeta), shape)) in poles.iter().zip(modes.iter().zip(&shapes)) {
            assert!((pole.frequency_hz - f).abs() < 1e-9 * f, "{pole:?}");
            assert!((pole.damping_ratio - zeta).abs() < 1e-9, "{pole:?}");
            let real: Vec<f64> = shape.to_vec();
            assert!((super::super::shape::mac_real(&pole.shape, &real) - 1.0).abs() < 1e-9);
            assert!((pole.mpc - 1.0).abs() < 1e-9);
        }
        assert!(model.singular_values()[4] < 1e-10 * model.singular_values()[0]);
        assert!(matches!(model.poles(6), Err(OmaError::SingularHankel { order: 6 })));
        assert!(matches!(model.poles(31), Err(OmaError::OrderTooHigh { .. })));
    }

    /// The Gram factorisation gives the SVD's poles on a noisy record's
    /// correlations (to the precision it states), and refuses orders below
    /// its floor.
    #[test]
    fn the_gram_factorisation_gives_the_svd_poles() {
        let (l, p, fs) = (3, 12, 50.0);
        let mut seed = 7u64;
        let mut noise = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed as f64 / u64::MAX as f64 - 0.5
        };
        // Two damped oscillators seen by three channels, plus noise.
        let n = 6000;
        let (mut x1, mut v1, mut x2, mut v2) = (0.0, 0.0, 0.0, 0.0);
        let dt = 1.0 / fs;
        let (w1, w2) = (2.0 * PI * 2.3, 2.0 * PI * 7.1);
        let mut y = vec![vec![0.0; n]; l];
        for t in 0..n {
            let (f1, f2) = (noise(), noise());
            v1 += dt * (-w1 * w1 * x1 - 2.0 * 0.02 * w1 * v1 + 40.0 * f1);
            x1 += dt * v1;
            v2 += dt * (-w2 * w2 * x2 - 2.0 * 0.03 * w2 * v2 + 40.0 * f2);
            x2 += dt * v2;
            for (a, shape) in [[1.0, 0.4], [0.6, -1.0], [-0.3, 0.8]].iter().enumerate() {
                y[a][t] = shape[0] * x1 + shape[1] * x2 + 0.01 * noise();
            }
        }
        let views: Vec<&[f64]> = y.iter().map(Vec::as_slice).collect();
        let r = super::super::OutputCorrelations::from_samples(&views, &[], 2 * p, 1)
            .unwrap()
            .estimate();
        let exact = SubspaceModel::new(&r, l, l, p, 20, fs).unwrap();
        let gram = SubspaceModel::factorised(&r, l, l, p, 20, fs, Factorisation::GramEigen).unwrap();
        for (a, b) in exact.singular_values().iter().zip(gram.singular_values()).take(8) {
            assert!((a - b).abs() < 1e-9 * exact.singular_values()[0], "{a} vs {b}");
        }
        for order in [4, 8, 12] {
            let (a, b) = (exact.poles(order).unwrap(), gram.poles(order).unwrap());
            assert_eq!(a.len(), b.len());
            for (a, b) in a.iter().zip(&b) {
                assert!(
                    (a.frequency_hz - b.frequency_hz).abs() < 1e-7 * a.frequency_hz,
                    "{a:?} {b:?}"
                );
                assert!((a.damping_ratio - b.damping_ratio).abs() < 1e-7, "{a:?} {b:?}");
                assert!((super::super::shape::mac(&a.shape, &b.shape) - 1.0).abs() < 1e-9);
            }
        }
    }

    #[test]
    fn too_few_lags_and_zero_data_are_errors() {
        assert!(matches!(
            SubspaceModel::new(&[0.0; 9], 1, 1, 5, usize::MAX, 10.0),
            Err(OmaError::TooFewLags { block_rows: 5 })
        ));
        assert!(matches!(
            SubspaceModel::new(&[0.0; 11], 1, 1, 5, usize::MAX, 10.0),
            Err(OmaError::SingularHankel { order: 1 })
        ));
    }
}
