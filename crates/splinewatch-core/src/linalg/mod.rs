//! Small dense helpers shared by the FRF and updating code, and
//! [`leading_eigen`] (the largest eigenpairs of a dense symmetric matrix,
//! for the SSI's truncated SVD).
//!
//! May import: nothing of the crate (it is the floor every other stands on).

pub mod leading_eigen;

use faer::prelude::Solve;
use faer::{c64, Mat};

/// Whether `a` and `b` hold the same values bit for bit (a cached result
/// is reused only for exactly the inputs it was computed from).
pub fn bitwise_equal(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
}

/// `(A + Aᵀ)/2`: a product that is symmetric in exact arithmetic made so
/// to round-off, before a symmetric eigensolver reads one triangle.
pub fn symmetric_part(a: &Mat<f64>) -> Mat<f64> {
    Mat::from_fn(a.nrows(), a.ncols(), |i, j| 0.5 * (a[(i, j)] + a[(j, i)]))
}

/// The rows `rows` of `a`, in order.
pub fn dense_rows(a: &Mat<f64>, rows: &[usize]) -> Mat<f64> {
    Mat::from_fn(rows.len(), a.ncols(), |r, c| a[(rows[r], c)])
}

/// Solves `(A_re + j A_im) x = b` for real `b` (one or more columns) by
/// partial-pivoting LU on the complex matrix. `None` if the result is not
/// finite (singular system).
pub fn complex_solve(a_re: &Mat<f64>, a_im: &Mat<f64>, b: &Mat<f64>) -> Option<(Mat<f64>, Mat<f64>)> {
    let n = a_re.nrows();
    let a = Mat::from_fn(n, n, |i, j| c64::new(a_re[(i, j)], a_im[(i, j)]));
    let rhs = Mat::from_fn(n, b.ncols(), |i, j| c64::new(b[(i, j)], 0.0));
    let x = a.partial_piv_lu().solve(&rhs);
    let re = Mat::from_fn(n, b.ncols(), |i, j| x[(i, j)].re);
    let im = Mat::from_fn(n, b.ncols(), |i, j| x[(i, j)].im);
    let finite = (0..n).all(|i| (0..b.ncols()).all(|j| re[(i, j)].is_finite() && im[(i, j)].is_finite()));
    finite.then_some((re, im))
}

/// `a()` and `b()`, on two threads when the machine has them (`a` on a
/// scoped thread, `b` on the caller's); the results do not depend on it.
pub fn join<A: Send, B>(a: impl FnOnce() -> A + Send, b: impl FnOnce() -> B) -> (A, B) {
    if std::thread::available_parallelism().map_or(1, |t| t.get()) < 2 {
        return (a(), b());
    }
    std::thread::scope(|scope| {
        let first = scope.spawn(a);
        let second = b();
        (first.join().expect("a joined computation panicked"), second)
    })
}
