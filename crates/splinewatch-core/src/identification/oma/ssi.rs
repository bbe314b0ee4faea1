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
    channels: usize,
    fs: f64,
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
        let (l, r, p) = (channels, references, block_rows);
        if p == 0 || correlations.len() < (2 * p + 1) * l * r {
            return Err(OmaError::TooFewLags { block_rows: p });
        }
        let lag = |k: usize, a: usize, b: usize| correlations[(k * l + a) * r + b];
        let hankel = Mat::from_fn(l * (p + 1), r * p, |row, col| {
            lag(row / l + col / r + 1, row % l, col % r)
        });
        let svd = hankel.thin_svd().map_err(|_| OmaError::SvdFailed)?;
        let singular_values: Vec<f64> = svd.S().column_vector().iter().copied().collect();
        if !singular_values.iter().all(|s| s.is_finite()) || singular_values[0] <= 0.0 {
            return Err(OmaError::SingularHankel { order: 1 });
        }
        let order_cap = (l * p).min(singular_values.len()).min(max_order.max(1));
        let u = svd.U().subcols(0, order_cap);
        let rows = u.nrows();
        let (up, down) = (u.subrows(0, rows - l), u.subrows(l, rows - l));
        Ok(Self {
            u_top: u.subrows(0, l).to_owned(),
            gram_up: up.transpose() * up,
            gram_shift: up.transpose() * down,
            singular_values,
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
        if self.singular_values[order - 1] <= 1e-13 * self.singular_values[0] {
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
