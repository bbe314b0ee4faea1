//! Linear least squares over rows given one at a time, on the range of
//! its columns (see the parent module's `REGRESSOR_RANGE`), and the range
//! of the inputs' own columns, which the direct terms `D u` eliminate.

use super::{RealizationError, CHUNK_ROWS, REGRESSOR_RANGE};
use faer::Mat;

/// The least squares `min ‖Φ θ − y‖` over rows given one at a time: the
/// triangular factor of `[Φ y]` updated chunk by chunk (QR of the previous
/// factor stacked on the chunk), then solved on the range of the
/// unit-norm columns ([`REGRESSOR_RANGE`]).
pub(super) struct RegressorRows {
    unknowns: usize,
    /// `[R z]` so far, `(p + 1) × (p + 1)` upper triangular (empty at first).
    factor: Mat<f64>,
    chunk: Vec<f64>,
    rows: usize,
}

impl RegressorRows {
    pub(super) fn new(unknowns: usize) -> Self {
        Self {
            unknowns,
            factor: Mat::zeros(0, unknowns + 1),
            chunk: Vec::with_capacity(CHUNK_ROWS * (unknowns + 1)),
            rows: 0,
        }
    }

    pub(super) fn push(&mut self, row: &[f64], y: f64) -> Result<(), RealizationError> {
        self.chunk.extend_from_slice(row);
        self.chunk.push(y);
        self.rows += 1;
        if self.rows == CHUNK_ROWS {
            self.fold()?;
        }
        Ok(())
    }

    /// The chunk folded into the factor.
    fn fold(&mut self) -> Result<(), RealizationError> {
        let width = self.unknowns + 1;
        let above = self.factor.nrows();
        let stacked = Mat::from_fn(above + self.rows, width, |row, col| {
            if row < above {
                self.factor[(row, col)]
            } else {
                self.chunk[(row - above) * width + col]
            }
        });
        let qr = stacked.qr();
        let r = qr.thin_R();
        if !r.col_iter().all(|col| col.iter().all(|v| v.is_finite())) {
            return Err(RealizationError::LeastSquaresFailed);
        }
        self.factor = r.to_owned();
        self.chunk.clear();
        self.rows = 0;
        Ok(())
    }

    /// `θ` on the range of the columns: `R D⁻¹ = U Σ Vᵀ` (`D` the columns'
    /// norms), `θ = D⁻¹ V Σ⁺ Uᵀ z` with `Σ⁺` zero below
    /// [`REGRESSOR_RANGE`] of the largest.
    pub(super) fn solve(mut self) -> Result<Vec<f64>, RealizationError> {
        if self.rows > 0 {
            self.fold()?;
        }
        let p = self.unknowns;
        let r = self.factor.subrows(0, self.factor.nrows().min(p)).to_owned();
        let norms: Vec<f64> = (0..p)
            .map(|col| (0..r.nrows()).map(|row| r[(row, col)].powi(2)).sum::<f64>().sqrt())
            .collect();
        let scaled = Mat::from_fn(r.nrows(), p, |row, col| {
            if norms[col] > 0.0 {
                r[(row, col)] / norms[col]
            } else {
                0.0
            }
        });
        let svd = scaled.thin_svd().map_err(|_| RealizationError::LeastSquaresFailed)?;
        let sigma: Vec<f64> = svd.S().column_vector().iter().copied().collect();
        let top = sigma.first().copied().unwrap_or(0.0);
        let z: Vec<f64> = (0..r.nrows()).map(|row| self.factor[(row, p)]).collect();
        let mut theta = vec![0.0; p];
        for (k, &s) in sigma.iter().enumerate() {
            if s <= REGRESSOR_RANGE * top || s == 0.0 {
                continue;
            }
            let projection: f64 = (0..r.nrows()).map(|row| svd.U()[(row, k)] * z[row]).sum::<f64>() / s;
            for (col, value) in theta.iter_mut().enumerate() {
                *value += svd.V()[(col, k)] * projection;
            }
        }
        for (value, norm) in theta.iter_mut().zip(&norms) {
            *value = if *norm > 0.0 { *value / norm } else { 0.0 };
        }
        Ok(theta)
    }
}

/// The range of the inputs' columns over the samples one output observes
/// (the regressors of its row of `D`): `Q` (samples × kept, orthonormal,
/// zero rows where the output is not observed) spans the unit-norm
/// columns' range above [`REGRESSOR_RANGE`], and `to_d` maps a residual's
/// projection `Qᵀ r` to that row of `D` (the truncated pseudo-inverse:
/// `U D⁻¹ = Q_U R`, `R = W Σ Vᵀ`, `Q = Q_U W_kept`, `to_d = D⁻¹ V_kept Σ_kept⁻¹`).
pub(super) struct InputRange {
    pub(super) q: Mat<f64>,
    pub(super) to_d: Mat<f64>,
}

impl InputRange {
    pub(super) fn of(inputs: &[&[f64]], observed: &[bool]) -> Result<Self, RealizationError> {
        let (samples, r) = (observed.len(), inputs.len());
        let norms: Vec<f64> = inputs
            .iter()
            .map(|u| {
                u.iter()
                    .zip(observed)
                    .filter(|(_, seen)| **seen)
                    .map(|(v, _)| v * v)
                    .sum::<f64>()
                    .sqrt()
            })
            .collect();
        let scaled = Mat::from_fn(samples, r, |k, i| {
            if observed[k] && norms[i] > 0.0 {
                inputs[i][k] / norms[i]
            } else {
                0.0
            }
        });
        let qr = scaled.qr();
        let q_u = qr.compute_thin_Q();
        let svd = qr
            .thin_R()
            .to_owned()
            .thin_svd()
            .map_err(|_| RealizationError::LeastSquaresFailed)?;
        let sigma: Vec<f64> = svd.S().column_vector().iter().copied().collect();
        let top = sigma.first().copied().unwrap_or(0.0);
        let kept: Vec<usize> = (0..sigma.len())
            .filter(|&j| sigma[j] > REGRESSOR_RANGE * top && sigma[j] > 0.0)
            .collect();
        let rotation = Mat::from_fn(q_u.ncols(), kept.len(), |row, j| svd.U()[(row, kept[j])]);
        let q = &q_u * &rotation;
        let to_d = Mat::from_fn(r, kept.len(), |i, j| {
            if norms[i] > 0.0 {
                svd.V()[(i, kept[j])] / sigma[kept[j]] / norms[i]
            } else {
                0.0
            }
        });
        if !q.col_iter().all(|col| col.iter().all(|v| v.is_finite())) {
            return Err(RealizationError::LeastSquaresFailed);
        }
        Ok(Self { q, to_d })
    }

    pub(super) fn kept(&self) -> usize {
        self.q.ncols()
    }

    /// `Q`'s rows at `samples`.
    pub(super) fn rows_at(&self, samples: &[usize]) -> Mat<f64> {
        Mat::from_fn(samples.len(), self.kept(), |row, j| self.q[(samples[row], j)])
    }
}
