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
//! `φ = C ψ` at the sensors. One SVD serves every order, and only its
//! leading `max_order` vectors are formed (from the eigenproblem of `HᵀH`,
//! see [`SubspaceModel::new`]).
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
use crate::linalg::join;
use crate::linalg::leading_eigen::{leading_eigen, leading_eigenpairs};
use faer::linalg::matmul::triangular::{self, BlockStructure};
use faer::linalg::solvers::{DenseSolveCore, Solve};
use faer::{c64, Accum, Mat, MatRef, Par, Side};
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
    /// `U↑ᵀU↑` (its lower triangle; the Cholesky factor reads no more) and
    /// `U↑ᵀU↓`, both `max_order × max_order`.
    gram_up: Mat<f64>,
    gram_shift: Mat<f64>,
    singular_values: Vec<f64>,
    /// `V Σ⁻¹` on the orders' columns (zero beyond the floor), for
    /// [`SubspaceModel::replicate`].
    right: Mat<f64>,
    channels: usize,
    fs: f64,
}

/// Below this fraction of `σ₁`, a singular value of the SVD is zero.
const SVD_FLOOR: f64 = 1e-13;

/// The leading `cap` right singular vectors `V` of `H` and `H V` (the left
/// ones times `Σ`).
struct Truncated {
    right: Mat<f64>,
    left: Mat<f64>,
}

/// The singular values of `hankel` (non-increasing) with its `cap` leading
/// right singular vectors, from the symmetric eigenproblem of `HᵀH` (its
/// lower triangle formed; tridiagonalised, every eigenvalue, and only the
/// leading `cap` vectors by inverse iteration and back-transformed, as the
/// orders need no more: [`leading_eigen`]). The leading singular values are
/// `‖H v_i‖`, accurate to round-off relative to `σ₁` even where
/// `σ_i² < ε σ₁²` (so a rank-deficient `H` is still seen as one); the
/// eigenvectors have the same backward error as an SVD's (`ε σ₁²/gap` in
/// angle). The values beyond `cap` (reported only) are `√λ_i`, accurate to
/// `ε σ₁²/σ_i`.
fn truncated_svd(hankel: &Mat<f64>, cap: usize) -> Result<(Vec<f64>, Truncated), OmaError> {
    let cols = hankel.ncols();
    let gram = lower_gram(hankel.as_ref());
    let eigen = leading_eigen(gram.as_ref(), cap).map_err(|_| OmaError::SvdFailed)?;
    let (values, v) = (eigen.values, eigen.vectors);
    // H V, its columns in two halves on two threads.
    let half = cap / 2;
    let mut hv = Mat::<f64>::zeros(hankel.nrows(), cap);
    let (first, second) = hv.as_mut().split_at_col_mut(half);
    let product = |dst: faer::MatMut<'_, f64>, columns: MatRef<'_, f64>| {
        faer::linalg::matmul::matmul(dst, Accum::Replace, hankel, columns, 1.0, Par::Seq)
    };
    join(
        || product(first, v.subcols(0, half)),
        || product(second, v.subcols(half, cap - half)),
    );
    let norms: Vec<f64> = (0..cap).map(|c| hv.col(c).norm_l2()).collect();
    let mut order: Vec<usize> = (0..cap).collect();
    order.sort_by(|&a, &b| norms[b].total_cmp(&norms[a]));
    let last = order.last().map_or(0.0, |&c| norms[c]);
    let singular_values: Vec<f64> = order
        .iter()
        .map(|&c| norms[c])
        .chain((cap..cols).map(|c| values[c].max(0.0).sqrt().min(last)))
        .collect();
    if !singular_values.iter().all(|s| s.is_finite()) || singular_values[0] <= 0.0 {
        return Err(OmaError::SingularHankel { order: 1 });
    }
    Ok((
        singular_values,
        Truncated {
            right: Mat::from_fn(cols, cap, |row, col| v[(row, order[col])]),
            left: Mat::from_fn(hv.nrows(), cap, |row, col| hv[(row, order[col])]),
        },
    ))
}

/// The lower triangle of `HᵀH` (the rest zero), in two parts of equal
/// work on two threads: the leading `c` columns (`c = n(1 − 1/√2)`: their
/// triangle and the block below it) and the trailing triangle.
fn lower_gram(hankel: MatRef<'_, f64>) -> Mat<f64> {
    let n = hankel.ncols();
    let c = ((n as f64) * (1.0 - std::f64::consts::FRAC_1_SQRT_2)).round() as usize;
    let mut gram = Mat::<f64>::zeros(n, n);
    let (left, right) = gram.as_mut().split_at_col_mut(c);
    let (leading, below) = left.split_at_row_mut(c);
    let (_, trailing) = right.split_at_row_mut(c);
    let (h1, h2) = (hankel.subcols(0, c), hankel.subcols(c, n - c));
    let lower = |dst: faer::MatMut<'_, f64>, h: MatRef<'_, f64>| {
        triangular::matmul(
            dst,
            BlockStructure::TriangularLower,
            Accum::Replace,
            h.transpose(),
            BlockStructure::Rectangular,
            h,
            BlockStructure::Rectangular,
            1.0,
            Par::Seq,
        )
    };
    join(
        || {
            lower(leading, h1);
            faer::linalg::matmul::matmul(below, Accum::Replace, h2.transpose(), h1, 1.0, Par::Seq);
        },
        || lower(trailing, h2),
    );
    gram
}

/// The block Hankel matrix `[R_{i+j+1}]`, `i = 0..=p`, `j = 0..p−1`.
pub(crate) fn block_hankel(correlations: &[f64], l: usize, r: usize, p: usize) -> Result<Mat<f64>, OmaError> {
    if p == 0 || correlations.len() < (2 * p + 1) * l * r {
        return Err(OmaError::TooFewLags { block_rows: p });
    }
    // Block by block (column-major), `R_k` row-major `l × r` at `k l r`.
    let mut hankel = Mat::<f64>::zeros(l * (p + 1), r * p);
    for j in 0..p {
        for b in 0..r {
            let column = hankel
                .col_mut(j * r + b)
                .try_as_col_major_mut()
                .expect("a Mat's column is contiguous");
            let column = column.as_slice_mut();
            for i in 0..=p {
                let lag = &correlations[(i + j + 1) * l * r..(i + j + 2) * l * r];
                for a in 0..l {
                    column[i * l + a] = lag[a * r + b];
                }
            }
        }
    }
    Ok(hankel)
}

impl SubspaceModel {
    /// `correlations` as [`super::OutputCorrelations::estimate`] lays them
    /// out (`(max_lag + 1) × l × r`, lag-major), `max_lag ≥ 2p`; poles will
    /// be asked for up to `max_order` (the Gram matrices are formed on that
    /// many columns only). The SVD is truncated to those columns and comes
    /// from the symmetric eigenproblem of `HᵀH` (about half the cost of a
    /// full SVD; the leading singular values are `‖H v_i‖`, accurate to
    /// round-off, so a rank-deficient `H` is still seen as one).
    pub fn new(
        correlations: &[f64],
        channels: usize,
        references: usize,
        block_rows: usize,
        max_order: usize,
        fs: f64,
    ) -> Result<Self, OmaError> {
        let hankel = block_hankel(correlations, channels, references, block_rows)?;
        Self::from_matrix(&hankel, channels, max_order, fs)
    }

    /// The model of any matrix `H` whose column space is the range of the
    /// observability matrix, stacked by `channels` rows per block (SSI's
    /// block Hankel matrix; SRIM's information matrix, in the `srim`
    /// module beside this one).
    pub fn from_matrix(hankel: &Mat<f64>, channels: usize, max_order: usize, fs: f64) -> Result<Self, OmaError> {
        // `O↑` has all rows but the last block's: at most that many orders.
        let cap = (hankel.nrows().saturating_sub(channels))
            .min(hankel.ncols())
            .min(max_order.max(1));
        let (singular_values, right_vectors) = truncated_svd(hankel, cap)?;
        let sigma_1 = singular_values[0];
        let kept = |col: usize| singular_values[col] > SVD_FLOOR * sigma_1;
        let left = Mat::from_fn(hankel.nrows(), cap, |row, col| {
            if kept(col) {
                right_vectors.left[(row, col)] / singular_values[col]
            } else {
                0.0
            }
        });
        let right = Mat::from_fn(hankel.ncols(), cap, |row, col| {
            if kept(col) {
                right_vectors.right[(row, col)] / singular_values[col]
            } else {
                0.0
            }
        });
        Ok(Self::from_left(left.as_ref(), singular_values, right, channels, fs))
    }

    /// [`Self::from_matrix`] for a symmetric positive semi-definite `H`
    /// (SRIM's information matrix): its SVD is its eigendecomposition
    /// `H = U Λ Uᵀ`, taken directly, so the small singular values keep their
    /// accuracy (the `HᵀH` route squares their range).
    pub fn from_symmetric(matrix: &Mat<f64>, channels: usize, max_order: usize, fs: f64) -> Result<Self, OmaError> {
        let n = matrix.nrows();
        let cap = n.saturating_sub(channels).min(max_order.max(1));
        // The `cap` leading eigenpairs only (descending).
        let eigen = leading_eigenpairs(matrix.as_ref(), cap).map_err(|_| OmaError::SvdFailed)?;
        let singular_values: Vec<f64> = eigen.values[..cap].iter().map(|v| v.max(0.0)).collect();
        let sigma_1 = singular_values.first().copied().unwrap_or(0.0);
        if sigma_1.is_nan() || sigma_1 <= 0.0 {
            return Err(OmaError::SingularHankel { order: 1 });
        }
        let kept = |col: usize| singular_values[col] > SVD_FLOOR * sigma_1;
        let left = Mat::from_fn(
            n,
            cap,
            |row, col| if kept(col) { eigen.vectors[(row, col)] } else { 0.0 },
        );
        let right = Mat::from_fn(n, cap, |row, col| {
            if kept(col) {
                eigen.vectors[(row, col)] / singular_values[col]
            } else {
                0.0
            }
        });
        Ok(Self::from_left(left.as_ref(), singular_values, right, channels, fs))
    }

    /// The model of a perturbed Hankel matrix `H_b` (a jackknife replicate's
    /// `correlations`) on this model's right singular vectors:
    /// `U_b = H_b V Σ⁻¹`, which is `U` for `H_b = H`. Its poles differ from
    /// those of `H_b`'s own SVD only in second order of `H_b − H`, or in
    /// first order times `σ_{n+1}/σ_i` (the rotation of the right singular
    /// vectors into those beyond the order, which the full window's
    /// singular values weigh by `σ_{n+1}`); the first-order perturbation of
    /// `U` that Döhler & Mevel (2013) propagate has the same leading terms.
    /// One product instead of an SVD per replicate, and no sign or rotation
    /// ambiguity between replicates.
    pub fn replicate(&self, correlations: &[f64], references: usize, block_rows: usize) -> Result<Self, OmaError> {
        let hankel = block_hankel(correlations, self.channels, references, block_rows)?;
        if hankel.ncols() != self.right.nrows() {
            return Err(OmaError::TooFewLags { block_rows });
        }
        self.replicate_matrix(&hankel)
    }

    /// [`Self::replicate`] for a perturbed matrix of any kind
    /// ([`Self::from_matrix`]), of this model's shape.
    #[track_caller]
    pub fn replicate_matrix(&self, hankel: &Mat<f64>) -> Result<Self, OmaError> {
        assert_eq!(hankel.ncols(), self.right.nrows(), "a replicate of the model's matrix");
        let left = hankel * &self.right;
        Ok(Self::from_left(
            left.as_ref(),
            self.singular_values.clone(),
            self.right.clone(),
            self.channels,
            self.fs,
        ))
    }

    /// The model on the left basis `u` (its columns the orders).
    fn from_left(u: MatRef<'_, f64>, singular_values: Vec<f64>, right: Mat<f64>, channels: usize, fs: f64) -> Self {
        let (rows, l) = (u.nrows(), channels);
        let (up, down) = (u.subrows(0, rows - l), u.subrows(l, rows - l));
        let mut gram_up = Mat::<f64>::zeros(u.ncols(), u.ncols());
        triangular::matmul(
            gram_up.as_mut(),
            BlockStructure::TriangularLower,
            Accum::Replace,
            up.transpose(),
            BlockStructure::Rectangular,
            up,
            BlockStructure::Rectangular,
            1.0,
            Par::Seq,
        );
        Self {
            u_top: u.subrows(0, l).to_owned(),
            gram_up,
            gram_shift: up.transpose() * down,
            singular_values,
            right,
            channels: l,
            fs,
        }
    }

    /// Columns of the matrix the model was identified from (a replicate's
    /// must have as many, [`Self::replicate_matrix`]).
    pub fn right_rows(&self) -> usize {
        self.right.nrows()
    }

    /// Rows per block (the channels of the shapes).
    pub fn channels(&self) -> usize {
        self.channels
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

    /// `(A, C)` at `order` in `B_n`'s basis: `B_n` and `U_top`, similar to the module's.
    pub fn state_space(&self, order: usize) -> Result<(Mat<f64>, Mat<f64>), OmaError> {
        Ok((self.shift_matrix(order)?, self.u_top.subcols(0, order).to_owned()))
    }

    /// The oscillating poles (one of each conjugate pair) at order `n`.
    pub fn poles(&self, order: usize) -> Result<Vec<Pole>, OmaError> {
        Ok(self.poles_of(&self.eigen(order)?))
    }

    /// The eigendecomposition of `B_n` at `order`: its poles
    /// ([`SubspaceModel::poles_of`]) and the base of their first-order
    /// continuation ([`SubspaceModel::continuation`]).
    pub fn eigen(&self, order: usize) -> Result<OrderEigen, OmaError> {
        let shift = self.shift_matrix(order)?;
        let eigen = shift.eigen().map_err(|_| OmaError::EigenFailed { order })?;
        Ok(OrderEigen {
            order,
            values: eigen.S().column_vector().iter().copied().collect(),
            vectors: eigen.U().to_owned(),
        })
    }

    /// The oscillating poles of `eigen` (one of each conjugate pair), by
    /// frequency.
    pub fn poles_of(&self, eigen: &OrderEigen) -> Vec<Pole> {
        let mut poles: Vec<Pole> = (0..eigen.order)
            .filter_map(|j| self.pole(eigen.order, eigen.values[j], |k| eigen.vectors[(k, j)]))
            .collect();
        poles.sort_by(|a, b| a.frequency_hz.total_cmp(&b.frequency_hz));
        poles
    }

    /// `B_n = (G↑)⁻¹ S` on the first `order` columns (see the module
    /// documentation), after the order's checks.
    fn shift_matrix(&self, order: usize) -> Result<Mat<f64>, OmaError> {
        Ok(self
            .gram_factor(order)?
            .solve(self.gram_shift.submatrix(0, 0, order, order)))
    }

    /// The Cholesky factor of `G↑` on the first `order` columns.
    fn gram_factor(&self, order: usize) -> Result<faer::linalg::solvers::Llt<f64>, OmaError> {
        if order == 0 || order > self.max_order() {
            return Err(OmaError::OrderTooHigh {
                order,
                max: self.max_order(),
            });
        }
        if self.singular_values[order - 1] <= SVD_FLOOR * self.singular_values[0] {
            return Err(OmaError::SingularHankel { order });
        }
        self.gram_up
            .submatrix(0, 0, order, order)
            .llt(Side::Lower)
            .map_err(|_| OmaError::SingularHankel { order })
    }

    /// The pole of the eigenvalue `mu` of `B_n` with eigenvector `psi`;
    /// `None` for the conjugate of an oscillating pole (`Im μ ≤ 0`), a real
    /// pole or a pure delay.
    fn pole(&self, order: usize, mu: c64, psi: impl Fn(usize) -> c64) -> Option<Pole> {
        let (frequency_hz, damping_ratio) = self.modal(mu)?;
        let mut shape: Vec<c64> = (0..self.channels)
            .map(|a| (0..order).map(|k| psi(k) * self.u_top[(a, k)]).sum())
            .collect();
        normalise(&mut shape);
        Some(Pole {
            order,
            frequency_hz,
            damping_ratio,
            mpc: mpc(&shape),
            shape,
        })
    }

    /// Frequency (Hz) and damping ratio of the eigenvalue `mu` of `B_n`
    /// (`λ = ln(μ) f_s`); `None` unless `Im μ > 0`.
    fn modal(&self, mu: c64) -> Option<(f64, f64)> {
        if mu.im <= 0.0 || mu.norm() == 0.0 {
            return None;
        }
        let lambda = c64::new(mu.norm().ln(), mu.im.atan2(mu.re)) * self.fs;
        Some((lambda.norm() / (2.0 * PI), -lambda.re / lambda.norm()))
    }

    /// The index of `pole` (one of [`SubspaceModel::poles_of`]`(eigen)`)
    /// among `eigen`'s eigenvalues: the one it was made from.
    pub fn eigen_index(&self, eigen: &OrderEigen, pole: &Pole) -> Option<usize> {
        (0..eigen.values.len())
            .filter_map(|j| {
                let (f, zeta) = self.modal(eigen.values[j])?;
                let d = (f - pole.frequency_hz).abs() / pole.frequency_hz.max(f64::MIN_POSITIVE)
                    + (zeta - pole.damping_ratio).abs();
                Some((d, j))
            })
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map(|(_, j)| j)
    }

    /// What the first-order continuation of `eigen`'s poles needs
    /// ([`SubspaceModel::continued`]): `Ψ⁻¹`.
    pub fn continuation(&self, eigen: OrderEigen) -> Result<Continuation, OmaError> {
        let inverse = eigen.vectors.partial_piv_lu().inverse();
        if !inverse
            .col_iter()
            .all(|c| c.iter().all(|v| v.re.is_finite() && v.im.is_finite()))
        {
            return Err(OmaError::EigenFailed { order: eigen.order });
        }
        Ok(Continuation { eigen, inverse })
    }

    /// The eigenvalues `indices` of `base` continued to first order onto
    /// this model (a [`SubspaceModel::replicate`] of the one `base` was
    /// taken from), as frequency and damping ratio; the shapes of those
    /// also in `shaped`. With `ΔB = B_n − B_n^base` (Wilkinson 1965;
    /// Döhler & Mevel 2013, §3), `y_j = ΔB ψ_j = B_n ψ_j − μ_j ψ_j` and
    /// `c = Ψ⁻¹ y_j`: `μ = μ_j + c_j`, `ψ = ψ_j + Σ_{k≠j} ψ_k c_k / (μ_j − μ_k)`,
    /// the shape `U_top ψ` on this model's basis. `B_n ψ_j = G↑⁻¹ S ψ_j`
    /// for all members at once (a Cholesky factor and one product per
    /// order), then `O(n)` per pole (`O(n²)` for a shape), where an
    /// eigendecomposition costs `~25 n³`; the error is second order in `ΔB`
    /// (relative to the eigenvalue gaps).
    pub fn continued(&self, base: &Continuation, indices: &[usize], shaped: &[usize]) -> Option<Vec<ContinuedPole>> {
        let (n, order) = (base.eigen.values.len(), base.eigen.order);
        if indices.iter().chain(shaped).any(|&j| j >= n) {
            return None;
        }
        let all: Vec<usize> = indices.iter().chain(shaped).copied().collect();
        let vectors = &base.eigen.vectors;
        let parts = Mat::from_fn(n, 2 * all.len(), |r, c| {
            let v = vectors[(r, all[c / 2])];
            if c % 2 == 0 {
                v.re
            } else {
                v.im
            }
        });
        let shifted = self
            .gram_factor(order)
            .ok()?
            .solve(self.gram_shift.submatrix(0, 0, n, n) * &parts);
        let y = |i: usize, k: usize| {
            c64::new(shifted[(k, 2 * i)], shifted[(k, 2 * i + 1)]) - base.eigen.values[all[i]] * vectors[(k, all[i])]
        };
        let c_of = |i: usize, row: usize| -> c64 { (0..n).map(|k| base.inverse[(row, k)] * y(i, k)).sum() };
        let mut continued: Vec<ContinuedPole> = indices
            .iter()
            .enumerate()
            .map(|(i, &j)| {
                let (frequency_hz, damping_ratio) = self.modal(base.eigen.values[j] + c_of(i, j))?;
                Some(ContinuedPole {
                    frequency_hz,
                    damping_ratio,
                    shape: None,
                })
            })
            .collect::<Option<_>>()?;
        for (i, &j) in shaped.iter().enumerate() {
            let i = indices.len() + i;
            let c: Vec<c64> = (0..n).map(|row| c_of(i, row)).collect();
            let mu_j = base.eigen.values[j];
            let weights: Vec<c64> = (0..n)
                .map(|k| {
                    let gap = mu_j - base.eigen.values[k];
                    if k == j || gap.norm() <= 1e-12 * mu_j.norm() {
                        c64::new(0.0, 0.0)
                    } else {
                        c[k] / gap
                    }
                })
                .collect();
            let vectors = &base.eigen.vectors;
            let psi: Vec<c64> = (0..n)
                .map(|r| vectors[(r, j)] + (0..n).map(|k| vectors[(r, k)] * weights[k]).sum::<c64>())
                .collect();
            let pole = self.pole(order, mu_j + c[j], |k| psi[k])?;
            continued.push(ContinuedPole {
                frequency_hz: pole.frequency_hz,
                damping_ratio: pole.damping_ratio,
                shape: Some(pole.shape),
            });
        }
        Some(continued)
    }
}

/// The eigendecomposition `B_n = Ψ diag(μ) Ψ⁻¹` of one order.
#[derive(Debug, Clone)]
pub struct OrderEigen {
    pub order: usize,
    values: Vec<c64>,
    vectors: Mat<c64>,
}

/// The base of a first-order continuation at one order
/// ([`SubspaceModel::continuation`]).
#[derive(Debug, Clone)]
pub struct Continuation {
    eigen: OrderEigen,
    /// `Ψ⁻¹`.
    inverse: Mat<c64>,
}

impl Continuation {
    pub fn order(&self) -> usize {
        self.eigen.order
    }
}

/// A pole continued to a replicate: frequency, damping and, where asked
/// for, the shape (scaled as [`Pole::shape`]).
#[derive(Debug, Clone, PartialEq)]
pub struct ContinuedPole {
    pub frequency_hz: f64,
    pub damping_ratio: f64,
    pub shape: Option<Vec<c64>>,
}

#[cfg(test)]
mod tests;
