//! The real modal form of `(A, C)`, its poles made stable, and the least
//! squares for `B` and `D` on it (see the parent module).

use super::least_squares::{InputRange, RegressorRows};
use super::{RealizationError, CHUNK_ROWS, MARGIN};
use faer::{c64, Mat, MatRef};

/// One block of the real modal form: a real pole, or a conjugate pair
/// `σ ± iω` as `[[σ, ω], [−ω, σ]]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum ModalBlock {
    Real(f64),
    Pair { sigma: f64, omega: f64 },
}

impl ModalBlock {
    fn size(self) -> usize {
        match self {
            Self::Real(_) => 1,
            Self::Pair { .. } => 2,
        }
    }

    /// The pole `μ` reflected to `1/μ̄` when on or outside the unit circle.
    pub(super) fn stable(self) -> Self {
        let pulled = |radius: f64| {
            if radius < 1.0 - MARGIN {
                1.0
            } else {
                (1.0 / radius).min(1.0 - MARGIN) / radius
            }
        };
        match self {
            Self::Real(mu) => Self::Real(mu * pulled(mu.abs())),
            Self::Pair { sigma, omega } => {
                let scale = pulled(sigma.hypot(omega));
                Self::Pair {
                    sigma: sigma * scale,
                    omega: omega * scale,
                }
            }
        }
    }

    /// `x ← block · x` on the block's states.
    fn apply(self, x: &mut [f64]) {
        match self {
            Self::Real(mu) => x[0] *= mu,
            Self::Pair { sigma, omega } => {
                let (p, q) = (x[0], x[1]);
                x[0] = sigma * p + omega * q;
                x[1] = -omega * p + sigma * q;
            }
        }
    }
}

/// `(A, C)` in the real modal form, the poles stable.
pub(super) struct ModalForm {
    blocks: Vec<ModalBlock>,
    /// Each block's first state.
    starts: Vec<usize>,
    pub(super) c: Mat<f64>,
}

impl ModalForm {
    /// `A = T Λ T⁻¹` with `T`'s columns the eigenvectors' real and
    /// imaginary parts (a real eigenvector rotated real by its largest
    /// component), `Λ` block diagonal; `C T` the output matrix.
    pub(super) fn of(a: MatRef<'_, f64>, c: MatRef<'_, f64>) -> Result<Self, RealizationError> {
        let n = a.nrows();
        let eigen = a.eigen().map_err(|_| RealizationError::EigenFailed)?;
        let values: Vec<c64> = eigen.S().column_vector().iter().copied().collect();
        let scale = values
            .iter()
            .map(|z| z.norm())
            .fold(0.0, f64::max)
            .max(f64::MIN_POSITIVE);
        let mut blocks = Vec::new();
        let mut columns: Vec<Vec<f64>> = Vec::with_capacity(n);
        for (k, mu) in values.iter().enumerate() {
            let vector: Vec<c64> = (0..n).map(|row| eigen.U()[(row, k)]).collect();
            if mu.im.abs() <= 1e-12 * scale {
                let peak =
                    vector.iter().copied().fold(
                        c64::new(0.0, 0.0),
                        |best, v| {
                            if v.norm() > best.norm() {
                                v
                            } else {
                                best
                            }
                        },
                    );
                let rotation = peak.conj() / peak.norm().max(f64::MIN_POSITIVE);
                columns.push(vector.iter().map(|v| (v * rotation).re).collect());
                blocks.push(ModalBlock::Real(mu.re));
            } else if mu.im > 0.0 {
                columns.push(vector.iter().map(|v| v.re).collect());
                columns.push(vector.iter().map(|v| v.im).collect());
                blocks.push(ModalBlock::Pair {
                    sigma: mu.re,
                    omega: mu.im,
                });
            }
        }
        if columns.len() != n {
            return Err(RealizationError::EigenFailed);
        }
        let t = Mat::from_fn(n, n, |row, col| columns[col][row]);
        let blocks: Vec<ModalBlock> = blocks.into_iter().map(ModalBlock::stable).collect();
        let mut starts = Vec::with_capacity(blocks.len());
        let mut next = 0;
        for block in &blocks {
            starts.push(next);
            next += block.size();
        }
        Ok(Self {
            blocks,
            starts,
            c: c * &t,
        })
    }

    fn states(&self) -> usize {
        self.c.ncols()
    }

    /// The block-diagonal state matrix.
    pub(super) fn a(&self) -> Mat<f64> {
        let n = self.states();
        let mut a = Mat::zeros(n, n);
        for (&start, &block) in self.starts.iter().zip(&self.blocks) {
            match block {
                ModalBlock::Real(mu) => a[(start, start)] = mu,
                ModalBlock::Pair { sigma, omega } => {
                    a[(start, start)] = sigma;
                    a[(start, start + 1)] = omega;
                    a[(start + 1, start)] = -omega;
                    a[(start + 1, start + 1)] = sigma;
                }
            }
        }
        a
    }

    /// `B` and `D` (and the record's `x₀`) by least squares on the record:
    /// each output's row of `D` multiplies the inputs alone, so its
    /// regressors are eliminated first (each output's rows projected off
    /// the inputs' range, [`InputRange`]) and the least squares left is
    /// over `x₀` and `B`, shared by every output; `D`'s rows follow from
    /// the residuals' projections. The same solution as the whole least
    /// squares at a third of its cost (its columns `n + n r` of
    /// `n + n r + m r`).
    pub(super) fn fit_inputs(
        &self,
        inputs: &[&[f64]],
        outputs: &[&[f64]],
    ) -> Result<(Mat<f64>, Mat<f64>), RealizationError> {
        let (n, r, m) = (self.states(), inputs.len(), outputs.len());
        let samples = inputs[0].len();
        let shared = n + n * r;
        let unknowns = shared + m * r;
        let observed = outputs
            .iter()
            .map(|o| o.iter().filter(|v| v.is_finite()).count())
            .sum::<usize>();
        if observed < 2 * unknowns {
            return Err(RealizationError::TooShort {
                samples,
                outputs: m,
                unknowns,
            });
        }
        let ranges = outputs
            .iter()
            .map(|o| InputRange::of(inputs, &o.iter().map(|v| v.is_finite()).collect::<Vec<_>>()))
            .collect::<Result<Vec<_>, _>>()?;
        // `[W w]_o = Q_oᵀ [Φ_o y_o]`: each output's regressors and record
        // on the inputs' range.
        let mut on_range: Vec<Mat<f64>> = ranges.iter().map(|q| Mat::zeros(q.kept(), shared + 1)).collect();
        self.for_each_chunk(inputs, outputs, |o, samples, rows| {
            on_range[o] += ranges[o].rows_at(samples).transpose() * rows;
            Ok(())
        })?;
        // The rows off that range, `[Φ_o y_o] − Q_o [W w]_o`, over `x₀` and `B`.
        let mut regressors = RegressorRows::new(shared);
        let mut values = vec![0.0; shared];
        self.for_each_chunk(inputs, outputs, |o, samples, rows| {
            let projected = rows - ranges[o].rows_at(samples) * &on_range[o];
            for row in 0..projected.nrows() {
                for (c, value) in values.iter_mut().enumerate() {
                    *value = projected[(row, c)];
                }
                regressors.push(&values, projected[(row, shared)])?;
            }
            Ok(())
        })?;
        let theta = regressors.solve()?;
        let b = Mat::from_fn(n, r, |s, i| theta[n + i * n + s]);
        let mut d = Mat::<f64>::zeros(m, r);
        for (o, (range, w)) in ranges.iter().zip(&on_range).enumerate() {
            // `Q_oᵀ (y_o − Φ_o θ) = w_o − W_o θ`.
            let residual: Vec<f64> = (0..range.kept())
                .map(|j| w[(j, shared)] - (0..shared).map(|c| w[(j, c)] * theta[c]).sum::<f64>())
                .collect();
            for i in 0..r {
                d[(o, i)] = (0..range.kept()).map(|j| range.to_d[(i, j)] * residual[j]).sum();
            }
        }
        Ok((b, d))
    }

    /// [`Self::for_each_row`] a chunk at a time per output:
    /// `f(o, samples, [Φ_o y_o])` on up to `CHUNK_ROWS` of its rows.
    fn for_each_chunk(
        &self,
        inputs: &[&[f64]],
        outputs: &[&[f64]],
        mut f: impl FnMut(usize, &[usize], MatRef<'_, f64>) -> Result<(), RealizationError>,
    ) -> Result<(), RealizationError> {
        let width = self.states() * (1 + inputs.len()) + 1;
        let mut pending = vec![PendingRows::default(); outputs.len()];
        self.for_each_row(inputs, outputs, |o, k, row, y| {
            let rows = &mut pending[o];
            rows.samples.push(k);
            rows.values.extend_from_slice(row);
            rows.values.push(y);
            if rows.samples.len() == CHUNK_ROWS {
                rows.flush(o, width, &mut f)?;
            }
            Ok(())
        })?;
        for (o, rows) in pending.iter_mut().enumerate() {
            if !rows.samples.is_empty() {
                rows.flush(o, width, &mut f)?;
            }
        }
        Ok(())
    }

    /// `f(o, k, Φ_o(k), y_o(k))` for every observed sample `k` of every
    /// output `o`: the regressors of `x₀` (the free response to `x₀ = e_s`)
    /// and of `B` (the response to `e_s u_i`), each a recursion on its
    /// state's block.
    pub(super) fn for_each_row(
        &self,
        inputs: &[&[f64]],
        outputs: &[&[f64]],
        mut f: impl FnMut(usize, usize, &[f64], f64) -> Result<(), RealizationError>,
    ) -> Result<(), RealizationError> {
        let (n, r) = (self.states(), inputs.len());
        // Each regressor column `j` (`x₀`'s `s = j`, or `B`'s `(i, s)` at
        // `n + i n + s`) is its state's block's one or two states.
        let spans: Vec<(usize, ModalBlock)> = (0..n).map(|s| self.block_of(s)).collect();
        let mut states = vec![[0.0f64; 2]; n + n * r];
        for (s, &(start, _)) in spans.iter().enumerate() {
            states[s][s - start] = 1.0;
        }
        let c: Vec<Vec<f64>> = (0..outputs.len())
            .map(|o| (0..n).map(|t| self.c[(o, t)]).collect())
            .collect();
        let mut row = vec![0.0; n + n * r];
        for k in 0..inputs[0].len() {
            for (o, output) in outputs.iter().enumerate() {
                let y = output[k];
                if !y.is_finite() {
                    continue;
                }
                let c = &c[o];
                for (j, (value, x)) in row.iter_mut().zip(&states).enumerate() {
                    let (start, block) = spans[j % n];
                    *value = match block {
                        ModalBlock::Real(_) => c[start] * x[0],
                        ModalBlock::Pair { .. } => c[start] * x[0] + c[start + 1] * x[1],
                    };
                }
                f(o, k, &row, y)?;
            }
            for (j, x) in states.iter_mut().enumerate() {
                let (start, block) = spans[j % n];
                block.apply(&mut x[..block.size()]);
                if j >= n {
                    let (i, s) = ((j - n) / n, j % n);
                    x[s - start] += inputs[i][k];
                }
            }
        }
        Ok(())
    }

    /// The block holding state `s`: its first state and the block.
    fn block_of(&self, s: usize) -> (usize, ModalBlock) {
        let b = self.starts.partition_point(|&start| start <= s) - 1;
        (self.starts[b], self.blocks[b])
    }
}

/// One output's rows waiting for their chunk: their samples and `[Φ y]`,
/// row-major.
#[derive(Debug, Clone, Default)]
struct PendingRows {
    samples: Vec<usize>,
    values: Vec<f64>,
}

impl PendingRows {
    fn flush<F>(&mut self, output: usize, width: usize, f: &mut F) -> Result<(), RealizationError>
    where
        F: FnMut(usize, &[usize], MatRef<'_, f64>) -> Result<(), RealizationError>,
    {
        let rows = MatRef::from_row_major_slice(&self.values, self.samples.len(), width);
        f(output, &self.samples, rows)?;
        self.samples.clear();
        self.values.clear();
        Ok(())
    }
}
