//! The real modal form of `(A, C)`, its poles made stable, and the least
//! squares for `B` and `D` on it (see the parent module).

use super::least_squares::RegressorRows;
use super::{RealizationError, MARGIN};
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

    /// `B` and `D` (and the dropped initial state) by least squares on the
    /// record; see the module's equation. Unknowns: `x₀` (`n`), `B` column
    /// by column (`n r`), `D` column by column (`m r`).
    pub(super) fn fit_inputs(
        &self,
        inputs: &[&[f64]],
        outputs: &[&[f64]],
    ) -> Result<(Mat<f64>, Mat<f64>), RealizationError> {
        let (n, r, m) = (self.states(), inputs.len(), outputs.len());
        let samples = inputs[0].len();
        let unknowns = n + n * r + m * r;
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
        // Per state s, its response at its block's states: to x₀ = e_s
        // (free), and to e_s u_i (forced by input i).
        let mut free: Vec<Vec<f64>> = (0..n).map(|s| unit(n, s)).collect();
        let mut forced: Vec<Vec<Vec<f64>>> = vec![vec![vec![0.0; n]; n]; r];
        let mut regressors = RegressorRows::new(unknowns);
        let mut row = vec![0.0; unknowns];
        for k in 0..samples {
            for (o, output) in outputs.iter().enumerate() {
                let y = output[k];
                if !y.is_finite() {
                    continue;
                }
                for s in 0..n {
                    row[s] = self.output_of(o, s, &free[s]);
                    for i in 0..r {
                        row[n + i * n + s] = self.output_of(o, s, &forced[i][s]);
                    }
                }
                for i in 0..r {
                    for p in 0..m {
                        row[n + n * r + i * m + p] = if p == o { inputs[i][k] } else { 0.0 };
                    }
                }
                regressors.push(&row, y)?;
            }
            for s in 0..n {
                self.advance(s, &mut free[s]);
                for i in 0..r {
                    self.advance(s, &mut forced[i][s]);
                    forced[i][s][s] += inputs[i][k];
                }
            }
        }
        let theta = regressors.solve()?;
        let b = Mat::from_fn(n, r, |s, i| theta[n + i * n + s]);
        let d = Mat::from_fn(m, r, |p, i| theta[n + n * r + i * m + p]);
        Ok((b, d))
    }

    /// The block holding state `s`: its first state and the block.
    fn block_of(&self, s: usize) -> (usize, ModalBlock) {
        let b = self.starts.partition_point(|&start| start <= s) - 1;
        (self.starts[b], self.blocks[b])
    }

    /// Output `o` of the state vector `x` that is non-zero on `s`'s block only.
    fn output_of(&self, o: usize, s: usize, x: &[f64]) -> f64 {
        let (start, block) = self.block_of(s);
        (start..start + block.size()).map(|t| self.c[(o, t)] * x[t]).sum()
    }

    /// `x ← A x` for `x` non-zero on `s`'s block only.
    fn advance(&self, s: usize, x: &mut [f64]) {
        let (start, block) = self.block_of(s);
        block.apply(&mut x[start..start + block.size()]);
    }
}

fn unit(n: usize, s: usize) -> Vec<f64> {
    let mut e = vec![0.0; n];
    e[s] = 1.0;
    e
}
