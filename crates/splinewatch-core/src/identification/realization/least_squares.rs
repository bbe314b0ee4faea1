//! Linear least squares over rows given one at a time, on the range of
//! its columns (see the parent module's `REGRESSOR_RANGE`).

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
