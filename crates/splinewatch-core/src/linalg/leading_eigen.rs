//! The `k` largest eigenpairs of a dense symmetric matrix, when `k` is a
//! fraction of its size: Householder tridiagonalisation (faer), every
//! eigenvalue of the tridiagonal `T` by implicit QR without vectors (or
//! only the `k` largest by bisection, [`leading_eigenpairs`]), the
//! vectors of the `k` largest by inverse iteration on `T` (LAPACK's
//! `dstein`: Wilkinson 1965, §9.47; Jessup & Ipsen 1992), and only those
//! `k` back-transformed. A full decomposition forms and back-transforms all
//! `n` vectors.
//!
//! Accuracy is that of a full symmetric eigensolver: eigenvalues within
//! `O(ε‖A‖)`, each vector's residual `‖A z − λ z‖ = O(ε‖A‖)` (the stopping
//! test below), vectors whose eigenvalues lie within `√ε ‖T‖` of each other
//! orthogonalised against each other at every iteration, and the whole
//! block made orthonormal to round-off by one Cholesky QR at the end (see
//! `tridiagonal_vectors`; `dstein` orthogonalises within `10⁻³‖T‖` at every
//! iteration instead, which on a Hankel Gram is most of the leading values).

use faer::diag::Diag;
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::evd::tridiag::{tridiag_in_place, tridiag_in_place_scratch};
use faer::linalg::evd::{self, ComputeEigenvectors, SelfAdjointEvdParams};
use faer::linalg::householder::{
    apply_block_householder_sequence_on_the_left_in_place_scratch,
    apply_block_householder_sequence_on_the_left_in_place_with_conj,
};
use faer::linalg::triangular_solve;
use faer::{Auto, ColRef, Conj, Mat, MatRef, Par, Side, Spec};
use std::ops::Range;
use thiserror::Error;

/// The tridiagonal QR did not converge, or an input was not finite.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("the symmetric eigenvalue problem did not converge (or the matrix is not finite)")]
pub struct EigenNotConverged;

/// Every eigenvalue and the leading eigenvectors of a symmetric matrix.
#[derive(Debug, Clone)]
pub struct LeadingEigen {
    /// All `n` eigenvalues ([`leading_eigen`]), or those whose vectors are
    /// computed ([`leading_eigenpairs`], [`eigenpairs_above`]),
    /// non-increasing.
    pub values: Vec<f64>,
    /// `n × k`: column `j` belongs to `values[j]`, unit length, its largest
    /// component positive.
    pub vectors: Mat<f64>,
}

/// `dstein`'s constants: iterations allowed, and those done after the
/// growth test first passes.
const MAX_ITERATIONS: usize = 5;
const EXTRA_ITERATIONS: usize = 2;

/// The eigenvalues of the symmetric `a` (only its lower triangle is read)
/// and the eigenvectors of its `k` largest.
pub fn leading_eigen(a: MatRef<'_, f64>, k: usize) -> Result<LeadingEigen, EigenNotConverged> {
    eigen_of(a, Values::All(k))
}

/// The `k` largest eigenvalues of the symmetric `a` (only its lower
/// triangle is read) and their eigenvectors: [`leading_eigen`] with the
/// eigenvalues of the tridiagonal `T` found by bisection on its Sturm
/// sequence (LAPACK's `dstebz`; Barth, Martin & Wilkinson 1967), `k` of
/// them instead of all `n` by QR (on an 800-square information matrix
/// with `k = 60`, the QR was a third of the decomposition).
pub fn leading_eigenpairs(a: MatRef<'_, f64>, k: usize) -> Result<LeadingEigen, EigenNotConverged> {
    eigen_of(a, Values::Leading(k))
}

/// The eigenpairs of the symmetric `a` (only its lower triangle is read)
/// whose eigenvalues exceed `relative` times the largest, which must be
/// positive (none otherwise): a truncated pseudo-inverse's range. Their
/// number is the count of eigenvalues above the threshold on `T`'s Sturm
/// sequence, the values bisected as in [`leading_eigenpairs`].
pub fn eigenpairs_above(a: MatRef<'_, f64>, relative: f64) -> Result<LeadingEigen, EigenNotConverged> {
    eigen_of(a, Values::Above(relative))
}

/// Which eigenpairs are computed.
#[derive(Clone, Copy, PartialEq)]
enum Values {
    /// All `n` values (implicit QR), the vectors of the `k` largest.
    All(usize),
    /// The `k` largest (bisection).
    Leading(usize),
    /// Those above this fraction of the largest (bisection).
    Above(f64),
}

fn eigen_of(a: MatRef<'_, f64>, wanted: Values) -> Result<LeadingEigen, EigenNotConverged> {
    let n = a.nrows();
    assert_eq!(n, a.ncols(), "leading_eigen needs a square matrix");
    if n == 0 {
        return Ok(LeadingEigen {
            values: Vec::new(),
            vectors: Mat::zeros(0, 0),
        });
    }
    if !(0..n).all(|j| (j..n).all(|i| a[(i, j)].is_finite())) {
        return Err(EigenNotConverged);
    }
    let par = Par::Seq;
    let params: Spec<SelfAdjointEvdParams, f64> = <SelfAdjointEvdParams as Auto<f64>>::auto().into();
    let block = faer::linalg::qr::no_pivoting::factor::recommended_block_size::<f64>(n, n);
    let mut buffer = MemBuffer::new(StackReq::any_of(&[
        tridiag_in_place_scratch::<f64>(n, par, params.tridiag.into()),
        evd::self_adjoint_evd_scratch::<f64>(n, ComputeEigenvectors::No, par, params),
    ]));
    let stack = MemStack::new(&mut buffer);

    // A = Q T Qᵀ, the reflectors below T's subdiagonal.
    let mut reduced = Mat::<f64>::zeros(n, n);
    for j in 0..n {
        for i in j..n {
            reduced[(i, j)] = a[(i, j)];
        }
    }
    let mut householder = Mat::<f64>::zeros(block, n.saturating_sub(1));
    tridiag_in_place(
        reduced.as_mut(),
        householder.as_mut(),
        par,
        stack,
        params.tridiag.into(),
    );
    let diagonal: Vec<f64> = (0..n).map(|i| reduced[(i, i)]).collect();
    let off: Vec<f64> = (0..n.saturating_sub(1)).map(|i| reduced[(i + 1, i)]).collect();

    let (values, k) = tridiagonal_values(&diagonal, &off, wanted, stack)?;
    if k == 0 {
        return Ok(LeadingEigen {
            values,
            vectors: Mat::zeros(n, 0),
        });
    }
    let mut vectors = tridiagonal_vectors(&diagonal, &off, &values[..k]).ok_or(EigenNotConverged)?;
    if n > 1 {
        // Q Z, its columns in two halves on two threads.
        let (basis, factor) = (reduced.as_ref().submatrix(1, 0, n - 1, n - 1), householder.as_ref());
        let back_transform = |mut columns: faer::MatMut<'_, f64>| {
            let mut buffer = MemBuffer::new(apply_block_householder_sequence_on_the_left_in_place_scratch::<f64>(
                n - 1,
                block,
                columns.ncols(),
            ));
            apply_block_householder_sequence_on_the_left_in_place_with_conj(
                basis,
                factor,
                Conj::No,
                columns.as_mut(),
                par,
                MemStack::new(&mut buffer),
            );
        };
        let (left, right) = vectors.as_mut().subrows_mut(1, n - 1).split_at_col_mut(k / 2);
        super::join(|| back_transform(left), || back_transform(right));
    }
    Ok(LeadingEigen { values, vectors })
}

/// The eigenvalues `wanted` of the tridiagonal (`diagonal`, `off`),
/// non-increasing, and how many vectors are wanted.
fn tridiagonal_values(
    diagonal: &[f64],
    off: &[f64],
    wanted: Values,
    stack: &mut MemStack,
) -> Result<(Vec<f64>, usize), EigenNotConverged> {
    let n = diagonal.len();
    let par = Par::Seq;
    let params: Spec<SelfAdjointEvdParams, f64> = <SelfAdjointEvdParams as Auto<f64>>::auto().into();
    Ok(match wanted {
        Values::All(k) => {
            let mut ascending = Diag::<f64>::zeros(n);
            let (mut d, mut e) = (Diag::<f64>::zeros(n), Diag::<f64>::zeros(n));
            for i in 0..n {
                d[i] = diagonal[i];
                e[i] = off.get(i).copied().unwrap_or(0.0);
            }
            evd::tridiagonal_self_adjoint_evd(d.as_ref(), e.as_ref(), ascending.as_mut(), None, par, stack, params)
                .map_err(|_| EigenNotConverged)?;
            ((0..n).rev().map(|i| ascending[i]).collect(), k.min(n))
        }
        Values::Leading(k) => (largest_by_bisection(diagonal, off, k.min(n)), k.min(n)),
        Values::Above(relative) => {
            let largest = largest_by_bisection(diagonal, off, 1)[0];
            let k = if largest > 0.0 {
                n - eigenvalues_below(diagonal, off, relative * largest)
            } else {
                0
            };
            (largest_by_bisection(diagonal, off, k), k)
        }
    })
}

/// The `k` largest eigenvalues of the tridiagonal (`d`, `e`), non-increasing,
/// each bisected to `2ε‖T‖` on the count of eigenvalues below a shift
/// ([`Sturm`]), as `dstebz` does: the absolute accuracy of QR's. The pivots' recurrence is a
/// chain of divisions; [`BISECTION_LANES`] eigenvalues are bisected side by
/// side so that their chains overlap (one at a time took longer than the
/// QR of all `n`).
fn largest_by_bisection(d: &[f64], e: &[f64], k: usize) -> Vec<f64> {
    let n = d.len();
    // Gershgorin's interval holds the spectrum.
    let radius = |i: usize| if i > 0 { e[i - 1].abs() } else { 0.0 } + e.get(i).map_or(0.0, |v| v.abs());
    let low = (0..n).map(|i| d[i] - radius(i)).fold(f64::INFINITY, f64::min);
    let high = (0..n).map(|i| d[i] + radius(i)).fold(f64::NEG_INFINITY, f64::max);
    let tolerance = 2.0 * f64::EPSILON * low.abs().max(high.abs());
    let sturm = Sturm::new(d, e);
    let (low, high) = (low - tolerance, high + tolerance);
    let halvings = if tolerance > 0.0 {
        ((high - low) / tolerance).log2().ceil().clamp(0.0, 2100.0) as usize
    } else {
        0
    };
    let mut values = Vec::with_capacity(k);
    for first in (0..k).step_by(BISECTION_LANES) {
        // Lane l brackets the eigenvalue with `targets[l]` below it in [lo, hi).
        let lanes = BISECTION_LANES.min(k - first);
        let mut targets = [0usize; BISECTION_LANES];
        (0..BISECTION_LANES).for_each(|l| targets[l] = n - 1 - (first + l.min(lanes - 1)));
        let (mut lo, mut hi) = ([low; BISECTION_LANES], [high; BISECTION_LANES]);
        for _ in 0..halvings {
            let mut mid = [0.0; BISECTION_LANES];
            (0..BISECTION_LANES).for_each(|l| mid[l] = 0.5 * (lo[l] + hi[l]));
            let below = sturm.below(mid);
            for l in 0..BISECTION_LANES {
                if below[l] > targets[l] {
                    hi[l] = mid[l];
                } else {
                    lo[l] = mid[l];
                }
            }
        }
        values.extend((0..lanes).map(|l| 0.5 * (lo[l] + hi[l])));
    }
    values
}

/// How many eigenvalues of the tridiagonal (`d`, `e`) lie below `x`.
fn eigenvalues_below(d: &[f64], e: &[f64], x: f64) -> usize {
    Sturm::new(d, e).below([x])[0]
}

/// The Sturm count of a tridiagonal: the negative pivots of
/// `T − x I = L D Lᵀ` (Sylvester's law of inertia), as `dstebz` forms them.
struct Sturm<'a> {
    d: &'a [f64],
    /// `e_i²`.
    squares: Vec<f64>,
    /// A pivot is kept at least this far from zero (`dstebz`'s `pivmin`).
    pivot_floor: f64,
}

impl<'a> Sturm<'a> {
    fn new(d: &'a [f64], e: &[f64]) -> Self {
        let squares: Vec<f64> = e.iter().map(|v| v * v).collect();
        let pivot_floor = f64::MIN_POSITIVE * squares.iter().copied().fold(1.0, f64::max);
        Self {
            d,
            squares,
            pivot_floor,
        }
    }

    /// The eigenvalues below each of `shifts`, their recurrences side by
    /// side (a chain of divisions each).
    fn below<const L: usize>(&self, shifts: [f64; L]) -> [usize; L] {
        let mut below = [0usize; L];
        let mut q = [1.0; L];
        for (i, &d) in self.d.iter().enumerate() {
            let square = if i > 0 { self.squares[i - 1] } else { 0.0 };
            for l in 0..L {
                let pivot = d - shifts[l] - square / q[l];
                q[l] = if pivot.abs() < self.pivot_floor {
                    -self.pivot_floor
                } else {
                    pivot
                };
                below[l] += usize::from(q[l] < 0.0);
            }
        }
        below
    }
}

/// Eigenvalues bisected side by side (see [`largest_by_bisection`]).
const BISECTION_LANES: usize = 32;

/// `T − λ I` (`T`: diagonal `d`, off-diagonal `e`) factorised by Gaussian
/// elimination with partial pivoting (LAPACK's `dlagtf`): `P L U`, `U` with
/// two super-diagonals.
struct ShiftedFactor {
    /// `U`'s diagonal and super-diagonals.
    u0: Vec<f64>,
    u1: Vec<f64>,
    u2: Vec<f64>,
    /// Multipliers of `L`, and whether rows `i` and `i + 1` were swapped.
    multiplier: Vec<f64>,
    swapped: Vec<bool>,
    /// Pivots smaller than this are replaced by it (with their sign), as
    /// `dlagts` does with `job = −1`.
    tiny: f64,
}

impl ShiftedFactor {
    fn new(d: &[f64], e: &[f64], lambda: f64, tiny: f64) -> Self {
        let n = d.len();
        let mut f = Self {
            u0: vec![0.0; n],
            u1: vec![0.0; n],
            u2: vec![0.0; n],
            multiplier: vec![0.0; n],
            swapped: vec![false; n],
            tiny,
        };
        // The active row: its diagonal entry and the one to its right.
        let (mut diag, mut right) = (d[0] - lambda, e.first().copied().unwrap_or(0.0));
        for i in 0..n.saturating_sub(1) {
            let below = e[i];
            let next_diag = d[i + 1] - lambda;
            let next_right = e.get(i + 1).copied().unwrap_or(0.0);
            if below.abs() > diag.abs() {
                f.swapped[i] = true;
                f.u0[i] = below;
                f.u1[i] = next_diag;
                f.u2[i] = next_right;
                let m = diag / below;
                f.multiplier[i] = m;
                diag = right - m * next_diag;
                right = -m * next_right;
            } else {
                f.u0[i] = diag;
                f.u1[i] = right;
                let m = if diag == 0.0 { 0.0 } else { below / diag };
                f.multiplier[i] = m;
                diag = next_diag - m * right;
                right = next_right;
            }
        }
        f.u0[n - 1] = diag;
        f
    }

    /// The last pivot, `|u_nn|` (the scaling of `dstein`).
    fn last_pivot(&self) -> f64 {
        self.u0.last().map_or(0.0, |u| u.abs())
    }

    /// `x ← (T − λ I)⁻¹ x`, tiny pivots perturbed.
    fn solve(&self, x: &mut [f64]) {
        let n = x.len();
        for i in 0..n.saturating_sub(1) {
            if self.swapped[i] {
                x.swap(i, i + 1);
            }
            x[i + 1] -= self.multiplier[i] * x[i];
        }
        for i in (0..n).rev() {
            let mut v = x[i];
            if i + 1 < n {
                v -= self.u1[i] * x[i + 1];
            }
            if i + 2 < n {
                v -= self.u2[i] * x[i + 2];
            }
            let pivot = if self.u0[i].abs() < self.tiny {
                self.tiny.copysign(self.u0[i])
            } else {
                self.u0[i]
            };
            x[i] = v / pivot;
        }
    }
}

/// Unit eigenvectors of the tridiagonal (`d`, `e`) for the eigenvalues
/// `values` (non-increasing), by inverse iteration as `dstein` does it:
/// a pseudo-random start, the right-hand side scaled to
/// `n ‖T‖₁ max(ε, |u_nn|)` in the max-norm, iterations until the solve
/// grows it past `√(0.1/n)` and two more, and values closer than `10 ε |λ|`
/// to the previous one moved apart by that much. Orthogonality in two
/// steps, where `dstein` orthogonalises every iterate against its whole
/// cluster (values within `10⁻³ ‖T‖₁`; on a Hankel Gram that is most of the
/// leading values, and cost more than the rest together):
/// - iterates whose values lie within `√ε ‖T‖₁` of each other, where
///   inverse iteration cannot tell the vectors apart, are orthogonalised
///   against each other at every iteration (Gram–Schmidt twice);
/// - the others come out orthogonal to `ε‖T‖/gap ≤ √ε`, and one Cholesky
///   QR of the whole block at the end (`Z ← Z L⁻ᵀ`, `ZᵀZ = L Lᵀ`, well
///   conditioned as `Z` is nearly orthonormal) makes them orthonormal to
///   round-off while moving each by `O(ε‖T‖/gap)`, which keeps its
///   residual at `O(ε‖T‖)`.
///
/// `None` if the block is rank deficient (an iteration failed).
fn tridiagonal_vectors(d: &[f64], e: &[f64], values: &[f64]) -> Option<Mat<f64>> {
    let n = d.len();
    let k = values.len();
    let norm = (0..n)
        .map(|i| d[i].abs() + if i > 0 { e[i - 1].abs() } else { 0.0 } + e.get(i).map_or(0.0, |v| v.abs()))
        .fold(0.0, f64::max);
    if norm == 0.0 {
        // T = 0: any orthonormal basis.
        let mut z = Mat::<f64>::zeros(n, k);
        (0..k).for_each(|j| z[(j, j)] = 1.0);
        return Some(z);
    }
    let cluster_tolerance = f64::EPSILON.sqrt() * norm;
    // Two halves on two threads, cut between clusters (each vector's start
    // is its own, so the cut changes nothing).
    let mut cut = k / 2;
    while cut > 0 && cut < k && values[cut - 1] - values[cut] <= cluster_tolerance {
        cut += 1;
    }
    let (first, second) = super::join(
        || inverse_iteration(d, e, values, 0..cut, norm),
        || inverse_iteration(d, e, values, cut..k, norm),
    );
    let (first, second) = (first?, second?);
    let z = Mat::from_fn(n, k, |r, j| if j < cut { first[(r, j)] } else { second[(r, j - cut)] });
    let gram = z.transpose() * &z;
    let factor = gram.llt(Side::Lower).ok()?;
    let mut q = z.transpose().to_owned();
    // Zᵀ ← L⁻¹ Zᵀ.
    triangular_solve::solve_lower_triangular_in_place(factor.L(), q.as_mut(), Par::Seq);
    let mut z = q.transpose().to_owned();
    for j in 0..k {
        let largest = z
            .col(j)
            .iter()
            .copied()
            .fold(0.0f64, |m, v| if v.abs() > m.abs() { v } else { m });
        if largest < 0.0 {
            z.col_mut(j).iter_mut().for_each(|v| *v = -*v);
        }
    }
    Some(z)
}

/// Unit vectors for `values[range]` (see [`tridiagonal_vectors`]), the
/// range starting a cluster; `None` if an iteration failed.
fn inverse_iteration(d: &[f64], e: &[f64], values: &[f64], range: Range<usize>, norm: f64) -> Option<Mat<f64>> {
    let n = d.len();
    let eps = f64::EPSILON;
    let cluster_tolerance = eps.sqrt() * norm;
    let growth_target = (0.1 / n as f64).sqrt();
    let offset = range.start;
    let mut z = Mat::<f64>::zeros(n, range.len());
    let mut cluster_start = offset;
    let mut previous = f64::NAN;
    for j in range {
        let mut lambda = values[j];
        if j > offset {
            if previous - lambda > cluster_tolerance {
                cluster_start = j;
            } else if previous - lambda < 10.0 * (eps * lambda).abs() {
                lambda = previous - 10.0 * (eps * lambda).abs();
            }
        }
        previous = lambda;
        let factor = ShiftedFactor::new(d, e, lambda, eps * norm);
        // Each vector's own pseudo-random start (xorshift seeded by its index).
        let mut seed = 0x9e37_79b9_7f4a_7c15_u64 ^ (j as u64 + 1).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        let mut uniform = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            2.0 * (seed >> 11) as f64 / (1u64 << 53) as f64 - 1.0
        };
        let mut x: Vec<f64> = (0..n).map(|_| uniform()).collect();
        let mut passed = 0;
        for _ in 0..MAX_ITERATIONS {
            let largest = x.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let scale = n as f64 * norm * eps.max(factor.last_pivot()) / largest.max(f64::MIN_POSITIVE);
            x.iter_mut().for_each(|v| *v *= scale);
            factor.solve(&mut x);
            if j > cluster_start {
                // Classical Gram–Schmidt twice ("twice is enough": Giraud et
                // al. 2005).
                let basis = z.as_ref().subcols(cluster_start - offset, j - cluster_start);
                for _ in 0..2 {
                    let coefficients = basis.transpose() * ColRef::from_slice(&x);
                    let projection = basis * &coefficients;
                    x.iter_mut().zip(projection.iter()).for_each(|(v, p)| *v -= p);
                }
            }
            if x.iter().fold(0.0f64, |m, v| m.max(v.abs())) >= growth_target {
                passed += 1;
                if passed > EXTRA_ITERATIONS {
                    break;
                }
            }
        }
        // (As `dstein`, an iterate that never passed the test is kept: it is
        // the best available.)
        let length = x.iter().map(|v| v * v).sum::<f64>().sqrt();
        if !(length > 0.0 && length.is_finite()) {
            return None;
        }
        for r in 0..n {
            z[(r, j - offset)] = x[r] / length;
        }
    }
    Some(z)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A symmetric matrix with the given spectrum: `Q diag(λ) Qᵀ`, `Q` from
    /// the QR of a pseudo-random matrix.
    fn with_spectrum(spectrum: &[f64], seed: u64) -> Mat<f64> {
        let n = spectrum.len();
        let mut s = seed;
        let random = Mat::from_fn(n, n, |_, _| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        });
        let q = random.qr().compute_Q();
        let scaled = Mat::from_fn(n, n, |i, j| q[(i, j)] * spectrum[j]);
        &scaled * q.transpose()
    }

    /// Against faer's full decomposition, on a spectrum like a Hankel
    /// Gram's (graded over twelve decades, with near-equal pairs and an
    /// exactly repeated value): every eigenvalue within `1e-13 ‖A‖`, each
    /// leading vector's residual within `1e-12 ‖A‖` and the basis
    /// orthonormal within `1e-11` (round-off of a 200-square problem,
    /// `n ε ≈ 4e-14`, with room for the clusters' `ε‖A‖/gap`).
    #[test]
    fn leading_pairs_match_a_full_decomposition() {
        leading_pairs_match_a_full_decomposition_by(leading_eigen);
    }

    /// The same with the `k` eigenvalues bisected: only those returned.
    #[test]
    fn bisected_pairs_match_a_full_decomposition() {
        leading_pairs_match_a_full_decomposition_by(leading_eigenpairs);
    }

    fn leading_pairs_match_a_full_decomposition_by(
        solver: fn(MatRef<'_, f64>, usize) -> Result<LeadingEigen, EigenNotConverged>,
    ) {
        let n = 200;
        let mut spectrum: Vec<f64> = (0..n).map(|i| 10f64.powf(-12.0 * i as f64 / n as f64)).collect();
        spectrum[7] = spectrum[6] * (1.0 - 1e-9);
        spectrum[31] = spectrum[30];
        spectrum[50] = spectrum[49] * (1.0 - 1e-14);
        let a = with_spectrum(&spectrum, 3);
        let k = 60;
        let leading = solver(a.as_ref(), k).unwrap();
        let full = a.self_adjoint_eigen(Side::Lower).unwrap();
        let reference: Vec<f64> = (0..n).rev().map(|i| full.S()[i]).collect();
        assert!(leading.values.len() >= k);
        for (got, want) in leading.values.iter().zip(&reference) {
            assert!((got - want).abs() < 1e-13, "{got} vs {want}");
        }
        let residual = &a * &leading.vectors - Mat::from_fn(n, k, |i, j| leading.vectors[(i, j)] * leading.values[j]);
        for j in 0..k {
            assert!(
                residual.col(j).norm_l2() < 1e-12,
                "vector {j}: {}",
                residual.col(j).norm_l2()
            );
        }
        let gram = leading.vectors.transpose() * &leading.vectors;
        for i in 0..k {
            for j in 0..k {
                let expected = if i == j { 1.0 } else { 0.0 };
                assert!((gram[(i, j)] - expected).abs() < 1e-11, "({i}, {j}): {}", gram[(i, j)]);
            }
        }
        // Well-separated vectors are the decomposition's up to sign.
        for j in [0, 1, 2, 10, 40] {
            let want = full.U().col(n - 1 - j);
            let dot: f64 = (0..n).map(|r| want[r] * leading.vectors[(r, j)]).sum();
            assert!((dot.abs() - 1.0).abs() < 1e-10, "vector {j}: |cos| = {}", dot.abs());
        }
    }

    /// Bisection over a whole spectrum of both signs with repeated values
    /// (`k = n`): every eigenvalue within `1e-13 ‖A‖` of faer's.
    #[test]
    fn bisection_finds_every_value_of_both_signs() {
        let spectrum = [3.0, -2.0, 1.0, 1.0, 1.0, 0.0, -2.0, 1e-9, -7.5, 0.5];
        let a = with_spectrum(&spectrum, 11);
        let got = leading_eigenpairs(a.as_ref(), spectrum.len()).unwrap();
        let mut want = spectrum.to_vec();
        want.sort_by(|x, y| y.total_cmp(x));
        assert_eq!(got.values.len(), want.len());
        for (g, w) in got.values.iter().zip(&want) {
            assert!((g - w).abs() < 1e-13 * 7.5, "{g} vs {w}");
        }
        let one = Mat::from_fn(1, 1, |_, _| -2.5);
        let single = leading_eigenpairs(one.as_ref(), 1).unwrap().values;
        assert!(single.len() == 1 && (single[0] + 2.5).abs() < 1e-15, "{single:?}");
        let zero = Mat::<f64>::zeros(3, 3);
        assert_eq!(leading_eigenpairs(zero.as_ref(), 2).unwrap().values, vec![0.0, 0.0]);
    }

    /// The pairs above a fraction of the largest: exactly those of the
    /// spectrum (graded over 12 decades, a repeated value), residuals as a
    /// full decomposition's; none when the largest is not positive.
    #[test]
    fn pairs_above_a_fraction_of_the_largest() {
        let n = 120;
        let mut spectrum: Vec<f64> = (0..n).map(|i| 10f64.powf(-12.0 * i as f64 / n as f64)).collect();
        spectrum[20] = spectrum[19];
        let a = with_spectrum(&spectrum, 5);
        let got = eigenpairs_above(a.as_ref(), 3e-4).unwrap();
        let want = spectrum.iter().filter(|v| **v > 3e-4).count();
        assert_eq!(got.values.len(), want);
        assert_eq!(got.vectors.ncols(), want);
        for (j, (g, w)) in got.values.iter().zip(&spectrum).enumerate() {
            assert!((g - w).abs() < 1e-13, "{g} vs {w}");
            let residual = &a * got.vectors.col(j) - got.vectors.col(j) * *g;
            assert!(residual.norm_l2() < 1e-12, "vector {j}");
        }
        let negative = with_spectrum(&[-1.0, -2.0, -3.0], 2);
        assert!(eigenpairs_above(negative.as_ref(), 1e-4).unwrap().values.is_empty());
    }

    #[test]
    fn small_and_degenerate_sizes() {
        let one = Mat::from_fn(1, 1, |_, _| -2.5);
        let got = leading_eigen(one.as_ref(), 3).unwrap();
        assert_eq!(got.values, vec![-2.5]);
        assert_eq!(got.vectors.ncols(), 1);
        assert_eq!(got.vectors[(0, 0)], 1.0);
        let zero = Mat::<f64>::zeros(4, 4);
        let got = leading_eigen(zero.as_ref(), 2).unwrap();
        assert!(got.values.iter().all(|v| *v == 0.0));
        let gram = got.vectors.transpose() * &got.vectors;
        assert!((gram[(0, 0)] - 1.0).abs() < 1e-12 && gram[(0, 1)].abs() < 1e-12);
        let mut bad = Mat::<f64>::identity(3, 3);
        bad[(2, 1)] = f64::NAN;
        assert_eq!(leading_eigen(bad.as_ref(), 1).unwrap_err(), EigenNotConverged);
    }
}
