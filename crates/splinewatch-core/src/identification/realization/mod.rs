//! A discrete-time state-space realization of a structure driven by
//! measured inputs, `x(k+1) = A x(k) + B u(k)`, `y(k) = C x(k) + D u(k)`
//! (`n` states, `r` inputs, `m` outputs, sampled at `fs`): what an
//! input–output identification gives when no physical model exists, and
//! what forecasts the next record from its inputs alone.
//!
//! SRIM ([`super::srim`]) gives `A` and `C` from the range of the
//! observability matrix (Juang 1997). [`Realization::fit`] takes them to a
//! real modal form (one 1 × 1 block per real pole, one 2 × 2 block per
//! conjugate pair) and reflects every pole outside the unit circle to
//! `1/μ̄`, which keeps its frequency and makes the realization stable by
//! construction (Juang 1994, "Applied system identification", §6: an
//! unstable pole of an identified structure is an artefact of a finite
//! record). `B`, `D` and the initial state `x₀` then follow by linear least
//! squares on the record: the output is linear in them,
//!
//! `y(k) = C Aᵏ x₀ + Σ_{j<k} C A^{k−1−j} B u(j) + D u(k)`
//!
//! (Verhaegen & Verdult 2007, "Filtering and system identification", §9.2.4,
//! the subspace methods' usual last step). With `A` block diagonal each
//! regressor column is a one- or two-state recursion; `D`'s columns (the
//! inputs themselves, one output's each) are eliminated first, so the
//! factorised least squares is over `x₀` and `B` alone. Coherent inputs (one
//! ground motion recorded at several supports) make the columns nearly
//! dependent: the least squares is solved on the columns' range (a
//! truncated SVD of the unit-norm columns, [`REGRESSOR_RANGE`]), as SRIM
//! inverts `R_uu` on its range.

use super::resample::fourier_resample;
use faer::{Mat, MatRef};
use modal_form::ModalForm;
use serde::{Deserialize, Serialize};

mod least_squares;
mod modal_form;
#[cfg(test)]
mod tests;
use thiserror::Error;

/// The smallest singular value of the unit-norm regressor columns, relative
/// to the largest, whose direction is fitted: below it a direction is the
/// difference of nearly equal inputs, which the record cannot tell from
/// noise and a forecast on another record would amplify.
pub const REGRESSOR_RANGE: f64 = 1e-6;

/// A pole on or outside the unit circle is reflected inside; one that lands
/// closer to it than this (a pure integrator) is pulled in to `1 − MARGIN`.
const MARGIN: f64 = 1e-6;

/// Rows of the least squares factorised at once (the regressor is never
/// formed whole: `samples × outputs` rows).
const CHUNK_ROWS: usize = 4096;

#[derive(Debug, Clone, PartialEq, Error)]
pub enum RealizationError {
    #[error("the realization's matrices do not conform: {0}")]
    Dimensions(String),
    #[error("the realization's {0} holds a NaN or an infinity")]
    NonFinite(&'static str),
    #[error("the sampling rate must be positive and finite, not {0}")]
    BadRate(f64),
    #[error("input {input} has {len} samples, {expected} expected (the record's length)")]
    UnequalLengths { input: usize, len: usize, expected: usize },
    #[error("input {0} has a missing sample (NaN) or an infinity: a realization is driven by complete inputs")]
    MissingInput(usize),
    #[error("{samples} samples of {outputs} outputs cannot fit {unknowns} unknowns")]
    TooShort {
        samples: usize,
        outputs: usize,
        unknowns: usize,
    },
    #[error("the eigenvalues of the state matrix did not converge")]
    EigenFailed,
    #[error("the least squares for B and D did not converge")]
    LeastSquaresFailed,
}

/// `(A, B, C, D)` at the rate `fs`, invariants checked on construction
/// (and when read: serialised as the four matrices' rows and the rate).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RealizationRows", into = "RealizationRows")]
pub struct Realization {
    a: Mat<f64>,
    b: Mat<f64>,
    c: Mat<f64>,
    d: Mat<f64>,
    fs: f64,
}

impl Realization {
    /// The realization of the four matrices (`A` `n × n`, `B` `n × r`,
    /// `C` `m × n`, `D` `m × r`, all finite) at the rate `fs`.
    pub fn new(a: Mat<f64>, b: Mat<f64>, c: Mat<f64>, d: Mat<f64>, fs: f64) -> Result<Self, RealizationError> {
        let n = a.nrows();
        let conform =
            a.ncols() == n && b.nrows() == n && c.ncols() == n && d.nrows() == c.nrows() && d.ncols() == b.ncols();
        if !conform || n == 0 || c.nrows() == 0 || b.ncols() == 0 {
            return Err(RealizationError::Dimensions(format!(
                "A {}×{}, B {}×{}, C {}×{}, D {}×{} (A n×n, B n×r, C m×n, D m×r, none empty)",
                a.nrows(),
                a.ncols(),
                b.nrows(),
                b.ncols(),
                c.nrows(),
                c.ncols(),
                d.nrows(),
                d.ncols()
            )));
        }
        for (name, matrix) in [("A", &a), ("B", &b), ("C", &c), ("D", &d)] {
            if !matrix.col_iter().all(|col| col.iter().all(|v| v.is_finite())) {
                return Err(RealizationError::NonFinite(name));
            }
        }
        if !(fs.is_finite() && fs > 0.0) {
            return Err(RealizationError::BadRate(fs));
        }
        Ok(Self { a, b, c, d, fs })
    }

    /// The stable realization with the poles of `(a, c)` (reflected inside
    /// the unit circle where outside) whose `B` and `D` fit `outputs` driven
    /// by `inputs` (equal lengths; a NaN output sample is left out of the
    /// fit, the inputs must be complete) at the rate `fs`; the record's
    /// initial state is fitted with them and dropped.
    pub fn fit(
        a: MatRef<'_, f64>,
        c: MatRef<'_, f64>,
        inputs: &[&[f64]],
        outputs: &[&[f64]],
        fs: f64,
    ) -> Result<Self, RealizationError> {
        if a.nrows() != a.ncols() || c.ncols() != a.nrows() || c.nrows() != outputs.len() || inputs.is_empty() {
            return Err(RealizationError::Dimensions(format!(
                "A {}×{}, C {}×{}, {} outputs, {} inputs",
                a.nrows(),
                a.ncols(),
                c.nrows(),
                c.ncols(),
                outputs.len(),
                inputs.len()
            )));
        }
        let samples = outputs.first().map_or(0, |o| o.len());
        for (k, o) in outputs.iter().enumerate() {
            if o.len() != samples {
                return Err(RealizationError::Dimensions(format!(
                    "output {k} has {} samples, the first {samples}",
                    o.len()
                )));
            }
        }
        complete_inputs(inputs, samples)?;
        let modal = ModalForm::of(a, c)?;
        let (b, d) = modal.fit_inputs(inputs, outputs)?;
        Self::new(modal.a(), b, modal.c, d, fs)
    }

    pub fn states(&self) -> usize {
        self.a.nrows()
    }

    pub fn inputs(&self) -> usize {
        self.b.ncols()
    }

    pub fn outputs(&self) -> usize {
        self.c.nrows()
    }

    pub fn fs(&self) -> f64 {
        self.fs
    }

    pub fn a(&self) -> MatRef<'_, f64> {
        self.a.as_ref()
    }

    pub fn b(&self) -> MatRef<'_, f64> {
        self.b.as_ref()
    }

    pub fn c(&self) -> MatRef<'_, f64> {
        self.c.as_ref()
    }

    pub fn d(&self) -> MatRef<'_, f64> {
        self.d.as_ref()
    }

    /// The largest modulus of `A`'s eigenvalues (below 1: stable).
    pub fn spectral_radius(&self) -> Result<f64, RealizationError> {
        let eigen = self.a.eigen().map_err(|_| RealizationError::EigenFailed)?;
        Ok(eigen.S().column_vector().iter().map(|z| z.norm()).fold(0.0, f64::max))
    }

    /// [`Self::simulate`] of inputs sampled at `fs`: at another rate than
    /// the realization's, the inputs are resampled to its rate over the same
    /// span ([`fourier_resample`]), simulated, and the outputs resampled back
    /// to the inputs' samples (band-limited: exact below both Nyquist lines
    /// for a record that starts and ends at rest).
    pub fn simulate_at(&self, inputs: &[&[f64]], fs: f64) -> Result<Vec<Vec<f64>>, RealizationError> {
        if !(fs.is_finite() && fs > 0.0) {
            return Err(RealizationError::BadRate(fs));
        }
        if fs == self.fs {
            return self.simulate(inputs);
        }
        let samples = inputs.first().map_or(0, |u| u.len());
        complete_inputs(inputs, samples)?;
        let points = (samples as f64 * self.fs / fs).round() as usize;
        let resampled: Vec<Vec<f64>> = inputs.iter().map(|u| fourier_resample(u, points)).collect();
        let views: Vec<&[f64]> = resampled.iter().map(Vec::as_slice).collect();
        Ok(self
            .simulate(&views)?
            .iter()
            .map(|y| fourier_resample(y, samples))
            .collect())
    }

    /// The outputs driven by `inputs` (one series per input, equal lengths,
    /// complete) from rest, one series per output.
    pub fn simulate(&self, inputs: &[&[f64]]) -> Result<Vec<Vec<f64>>, RealizationError> {
        if inputs.len() != self.inputs() {
            return Err(RealizationError::Dimensions(format!(
                "{} input series for a realization of {} inputs",
                inputs.len(),
                self.inputs()
            )));
        }
        let samples = inputs[0].len();
        complete_inputs(inputs, samples)?;
        let (n, m) = (self.states(), self.outputs());
        let mut x = vec![0.0; n];
        let mut next = vec![0.0; n];
        let mut y = vec![vec![0.0; samples]; m];
        let mut u = vec![0.0; self.inputs()];
        for k in 0..samples {
            for (value, series) in u.iter_mut().zip(inputs) {
                *value = series[k];
            }
            for (o, out) in y.iter_mut().enumerate() {
                let state: f64 = (0..n).map(|s| self.c[(o, s)] * x[s]).sum();
                let direct: f64 = u.iter().enumerate().map(|(i, v)| self.d[(o, i)] * v).sum();
                out[k] = state + direct;
            }
            for (s, value) in next.iter_mut().enumerate() {
                *value = (0..n).map(|t| self.a[(s, t)] * x[t]).sum::<f64>()
                    + u.iter().enumerate().map(|(i, v)| self.b[(s, i)] * v).sum::<f64>();
            }
            std::mem::swap(&mut x, &mut next);
        }
        Ok(y)
    }
}

/// Every input `samples` long and complete (finite): what drives a
/// realization.
fn complete_inputs(inputs: &[&[f64]], samples: usize) -> Result<(), RealizationError> {
    for (input, u) in inputs.iter().enumerate() {
        if u.len() != samples {
            return Err(RealizationError::UnequalLengths {
                input,
                len: u.len(),
                expected: samples,
            });
        }
        if !u.iter().all(|v| v.is_finite()) {
            return Err(RealizationError::MissingInput(input));
        }
    }
    Ok(())
}

/// [`Realization`] as stored: each matrix by rows.
#[derive(Serialize, Deserialize)]
struct RealizationRows {
    fs: f64,
    a: Vec<Vec<f64>>,
    b: Vec<Vec<f64>>,
    c: Vec<Vec<f64>>,
    d: Vec<Vec<f64>>,
}

impl From<Realization> for RealizationRows {
    fn from(r: Realization) -> Self {
        let rows = |m: &Mat<f64>| -> Vec<Vec<f64>> {
            (0..m.nrows())
                .map(|i| (0..m.ncols()).map(|j| m[(i, j)]).collect())
                .collect()
        };
        Self {
            fs: r.fs,
            a: rows(&r.a),
            b: rows(&r.b),
            c: rows(&r.c),
            d: rows(&r.d),
        }
    }
}

impl TryFrom<RealizationRows> for Realization {
    type Error = RealizationError;

    fn try_from(r: RealizationRows) -> Result<Self, Self::Error> {
        let matrix = |name: &'static str, rows: &[Vec<f64>]| -> Result<Mat<f64>, RealizationError> {
            let columns = rows.first().map_or(0, Vec::len);
            if rows.iter().any(|row| row.len() != columns) {
                return Err(RealizationError::Dimensions(format!(
                    "{name} has rows of unequal lengths"
                )));
            }
            Ok(Mat::from_fn(rows.len(), columns, |i, j| rows[i][j]))
        };
        Self::new(
            matrix("A", &r.a)?,
            matrix("B", &r.b)?,
            matrix("C", &r.c)?,
            matrix("D", &r.d)?,
            r.fs,
        )
    }
}
