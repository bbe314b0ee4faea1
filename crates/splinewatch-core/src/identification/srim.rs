//! Input–output subspace identification of records with measured inputs
//! (ground channels in an earthquake, or a force): SRIM, the System
//! Realization using Information Matrix (Juang 1997, "System realization
//! using information matrix", J. Guidance, Control, and Dynamics 20(3)).
//!
//! With `z(t) = [y(t); u(t)]` (`m` outputs, `r` inputs) and the stacked
//! vectors `y_p(t) = [y(t); …; y(t+p−1)]`, `u_p(t)` likewise over the horizon
//! `p` (`block_rows`), the state-space model gives `y_p = O_p x + T_p u_p + v_p`
//! (`O_p` the observability matrix, `T_p` the Toeplitz matrix of Markov
//! parameters). The information matrix
//!
//! `R_hh = R_yy − R_yu R_uu⁻¹ R_yuᵀ`
//!
//! (`R_yy = E[y_p y_pᵀ]`, `R_yu = E[y_p u_pᵀ]`, `R_uu = E[u_p u_pᵀ]`) removes
//! what the inputs explain and leaves `O_p (R_xx − R_xu R_uu⁻¹ R_xuᵀ) O_pᵀ`
//! plus the noise's share: its leading eigenvectors span `O_p` (taken from
//! its own eigendecomposition, [`SubspaceModel::from_symmetric`]: the `HᵀH`
//! route of SSI squares the range of its eigenvalues, which for the coloured
//! inputs of an earthquake spans many decades). From there the
//! poles and the shapes at the outputs follow by the shift invariance of
//! SSI, through the same [`SubspaceModel`], stabilisation, clustering and
//! delete-one-batch uncertainty as [`crate::identification::oma`]
//! ([`oma::identify_model`]). The expectations are the products of the
//! block Hankel data matrices over their columns, exact for a transient
//! record (a block Toeplitz matrix of lagged correlations assumes a
//! stationary one), from one batched FFT pass and sums at the batches'
//! edges instead of a `p(m+r) × n` product ([`InformationMatrix`]); the
//! batches of columns give the replicates. `R_uu` is inverted on its range (eigenvalues
//! below `INPUT_RANGE` of the largest dropped): inputs too coherent to
//! separate (one ground motion recorded at several supports) then act as one.
//! A jackknife replicate is inverted on the record's range (a Galerkin
//! inverse, [`InformationMatrix::matrix`]): with its own threshold a
//! replicate also differs by which eigenvalues cross it, a jump the
//! jackknife (valid for smooth statistics, Efron & Tibshirani 1993, §11.6)
//! reads as spread. On the 2015 Painter Street record the 4.81 Hz mode's
//! std was 0.18 Hz with each replicate's own range and 0.009 Hz on the
//! record's (both with the block Toeplitz estimate and the replicates'
//! models through `HᵀH`); on the other records the two agreed within 30 %.
//! Each replicate's model is made as the record's, from its own
//! eigendecomposition ([`SubspaceModel::from_symmetric`]): through `HᵀH`
//! the replicates lost the high orders' poles, and with them the std of 13
//! of the 22 modes the Toeplitz estimate found on the Painter Street
//! records. With the data matrices every one of the 27 modes found there
//! has its std, and on simulated records the reported stds are within 2× of
//! the scatter over 50 records (verification `srim`; 2026-11-27).
//!
//! Why SRIM: it uses the measured inputs (unlike SSI-cov, which takes an
//! earthquake for white noise), needs no impulse response to be estimated
//! first (unlike OKID/ERA, whose Markov parameters of short, non-white
//! records are poorly conditioned), handles several inputs at once, and is
//! the method mdof applies to these records (the peer of the tests).

use super::oma::correlation::{centred_channels, ChunkPlan};
use super::oma::uncertainty::ReplicateSource;
use super::oma::{self, OmaError, OmaResult, OmaSettings, SubspaceModel};
use super::realization::{Realization, RealizationError};
use crate::linalg::leading_eigen::eigenpairs_above;
use faer::Mat;
use std::sync::OnceLock;

/// The smallest eigenvalue of `R_uu`, relative to the largest, whose
/// direction counts as input: below it the inputs' power is the measurement
/// noise's (a 1 % noise floor is 1e-4 in power), and inverting it would
/// amplify noise into `R_hh` (a truncated pseudo-inverse, the usual
/// regularisation). With 1e-10 the jackknife spreads of a simulated record
/// with 2 % noise came out 10 to 400 times its error (measured with the
/// `HᵀH` SVD, before the information matrix's own eigendecomposition).
const INPUT_RANGE: f64 = 1e-4;

/// The Gram matrices of the record's block Hankel data matrices, batched
/// by columns, and the horizon: `R_zz = (1/K) Σ_t z_p(t) z_p(t)ᵀ` over the
/// columns `t = 0..N−p` (`z_p(t) = [z(t); …; z(t+p−1)]`, `z = [y; u]`
/// centred), the SRIM data equation's own products (Juang 1997; mdof's
/// `srim`). Block `(i, j)` (`i ≥ j`, lag `d = i − j`) of a batch of columns
/// `[c_b, c_{b+1})` is `Σ_{t=c_b}^{c_{b+1}−1} z(t+i) z(t+j)ᵀ
/// = Φ_d^b − E_d^b(j) + E_d^{b+1}(j)`, with `Φ_d^b = Σ_{u=c_b}^{c_{b+1}−1}
/// z(u+d) z(u)ᵀ` (one batched FFT pass, the later sample past the batch's
/// end) and the edge sums `E_d^k(j) = Σ_{u=c_k}^{c_k+j−1} z(u+d) z(u)ᵀ`
/// (`O(p² l²)` per boundary, added while the matrix is filled): exact, where
/// the block Toeplitz matrix of lagged correlations (`R_{i−j}` for every
/// block) assumes a stationary record. On a noise-free simulation of the
/// Painter Street overpass driven by the 2015 record's nine ground channels
/// the Toeplitz estimate put the first modes 0.6–3 % off and their damping
/// 1–3 points high; these products give every mode within 0.5 % but the
/// 13.2 Hz (1.3 %) and the damping 4.3–5.1 % for 5 % (measured 2026-11-27).
/// A replicate leaves out a batch of columns; `K` counts each block's valid
/// column pairs (NaN marks a missing sample, zero in the sums).
pub struct InformationMatrix {
    outputs: usize,
    inputs: usize,
    horizon: usize,
    /// `z`, centred (outputs first), missing samples zero, sample-major:
    /// `z_a(t)` at `t l + a`.
    samples: Vec<f64>,
    /// The batches' first columns and the end, `c_0 = 0 … c_B = N − p + 1`.
    bounds: Vec<usize>,
    /// Per batch, `Φ_d^b`, lag-major then `l × l` row-major (later channel first).
    lagged: Vec<Vec<f64>>,
    /// Per lag `d`, `Q_d(s) = Σ_{u<s} m(u+d) m(u)` (`m` the validity mask), `s = 0..=N−d`.
    pair_prefix: Vec<Vec<f64>>,
    /// The whole record's input range: the eigenvectors of its `R_uu` kept
    /// by `INPUT_RANGE` (set by the first [`Self::matrix`] of the record).
    range: OnceLock<Mat<f64>>,
}

impl InformationMatrix {
    /// `outputs` and `inputs` (equal lengths; NaN marks a missing sample) in
    /// `batches` batches of columns, over the horizon `horizon`.
    pub fn new(outputs: &[&[f64]], inputs: &[&[f64]], horizon: usize, batches: usize) -> Result<Self, OmaError> {
        if outputs.is_empty() || inputs.is_empty() {
            return Err(OmaError::NoChannels);
        }
        if horizon < 2 {
            return Err(OmaError::InvalidSettings(
                "the horizon (block_rows) must be at least 2".into(),
            ));
        }
        let channels: Vec<&[f64]> = outputs.iter().chain(inputs).copied().collect();
        let n = oma::sample_length(&channels)?;
        let batches = batches.max(1);
        let columns = (n + 1).saturating_sub(horizon);
        let batch_len = columns / batches;
        if batch_len < 4 * horizon {
            return Err(OmaError::TooShort {
                samples: n,
                needed: 4 * horizon * batches + horizon - 1,
            });
        }
        let (centred, valid) = centred_channels(&channels);
        let mut bounds: Vec<usize> = (0..batches).map(|b| b * batch_len).collect();
        bounds.push(columns);
        let plan = ChunkPlan::new(horizon - 1);
        let all: Vec<usize> = (0..channels.len()).collect();
        let spans: Vec<(usize, usize)> = bounds.windows(2).map(|w| (w[0], w[1])).collect();
        let lagged = oma::ordered_map(&spans, |&(start, end)| {
            let slices: Vec<&[f64]> = centred.iter().map(|c| &c[start..n.min(end + horizon - 1)]).collect();
            plan.batch_sums(&slices, &all, end - start)
        });
        let pair_prefix = (0..horizon)
            .map(|d| {
                let mut prefix = Vec::with_capacity(n - d + 1);
                prefix.push(0.0);
                let mut total = 0.0;
                for u in 0..n - d {
                    total += f64::from(u8::from(valid[u] && valid[u + d]));
                    prefix.push(total);
                }
                prefix
            })
            .collect();
        let l = channels.len();
        let samples = (0..n * l).map(|k| centred[k % l][k / l]).collect();
        let information = Self {
            outputs: outputs.len(),
            inputs: inputs.len(),
            horizon,
            samples,
            bounds,
            lagged,
            pair_prefix,
            range: OnceLock::new(),
        };
        // The record and every replicate (with two batches or more) need
        // valid pairs in every block.
        let replicates = if batches >= 2 { batches } else { 0 };
        for left_out in (0..replicates).map(Some).chain([None]) {
            let counts = information.pair_counts(left_out);
            if (0..horizon).any(|i| (0..=i).any(|j| counts[i * horizon + j] <= 0.0)) {
                return Err(OmaError::TooShort {
                    samples: valid.iter().filter(|&&v| v).count(),
                    needed: 4 * horizon * batches + horizon - 1,
                });
            }
        }
        Ok(information)
    }

    /// Valid column pairs of block `(i, j)` (`i ≥ j`), at `[i * p + j]`, over
    /// every batch but `left_out`: `Σ_b Q_d(c_{b+1} + j) − Q_d(c_b + j)`.
    fn pair_counts(&self, left_out: Option<usize>) -> Vec<f64> {
        let p = self.horizon;
        let mut counts = vec![0.0; p * p];
        for i in 0..p {
            for j in 0..=i {
                let q = &self.pair_prefix[i - j];
                counts[i * p + j] = self
                    .bounds
                    .windows(2)
                    .enumerate()
                    .filter(|(b, _)| Some(*b) != left_out)
                    .map(|(_, w)| q[w[1] + j] - q[w[0] + j])
                    .sum();
            }
        }
        counts
    }

    /// `R_hh` of every batch but `left_out` (all of them with `None`).
    ///
    /// The record's own `R_uu` is inverted on its range (its eigenvectors
    /// of eigenvalues above `INPUT_RANGE` of the largest). A replicate's
    /// is inverted on that same range `V` (`R_uu⁺ ≈ V (Vᵀ R_uu V)⁻¹ Vᵀ`, a
    /// Galerkin inverse; exactly the record's own on the record): the
    /// replicates differ by their data, not by which directions count as
    /// input, and each costs a Cholesky of `Vᵀ R_uu V` instead of an
    /// eigendecomposition of `R_uu` (of `Vᵀ R_uu V` when a replicate is not
    /// positive on the whole range: two of eight on the 2023-05-21 Painter
    /// Street record with the block Toeplitz estimate of before; none on the
    /// 20 records with the data matrices, whose products are positive
    /// semi-definite, measured 2026-11-27).
    pub fn matrix(&self, left_out: Option<usize>) -> Result<Mat<f64>, OmaError> {
        let (r_yy, r_yu, r_uu) = self.blocks(left_out);
        if left_out.is_none() {
            let (w, range) = input_range(&r_yu, &r_uu)?;
            let _ = self.range.set(range);
            return Ok(r_yy - &w * w.transpose());
        }
        let range = match self.range.get() {
            Some(range) => range,
            None => {
                let range = self.record_range()?;
                self.range.get_or_init(|| range)
            }
        };
        let gram = range.transpose() * &r_uu * range;
        let Ok(llt) = gram.llt(faer::Side::Lower) else {
            // The replicate lost a direction the record has (the batch left
            // out held its power, and `VᵀR_uuV` is singular to round-off
            // there): the record's range less those directions, by the
            // same rule as the record's (`V U_k`, `U_k` the eigenvectors of
            // `VᵀR_uuV` above `INPUT_RANGE` of its largest).
            let (w, _) = input_range(&(&r_yu * range), &gram)?;
            return Ok(r_yy - &w * w.transpose());
        };
        // R_yu V (VᵀR_uuV)⁻¹ Vᵀ R_yuᵀ = X Xᵀ, X = R_yu V L⁻ᵀ.
        let mut xt = (&r_yu * range).transpose().to_owned();
        faer::linalg::triangular_solve::solve_lower_triangular_in_place(llt.L(), xt.as_mut(), faer::Par::Seq);
        Ok(r_yy - xt.transpose() * &xt)
    }

    /// The whole record's input range.
    fn record_range(&self) -> Result<Mat<f64>, OmaError> {
        let (_, r_yu, r_uu) = self.blocks(None);
        Ok(input_range(&r_yu, &r_uu)?.1)
    }

    /// `R_yy`, `R_yu`, `R_uu` of every batch but `left_out`: the Gram
    /// matrix's lower blocks (`i ≥ j`) routed by channel into the three and
    /// into `R_uy`'s lower blocks, which are `R_yu`'s upper ones transposed.
    fn blocks(&self, left_out: Option<usize>) -> (Mat<f64>, Mat<f64>, Mat<f64>) {
        let (m, r, p) = (self.outputs, self.inputs, self.horizon);
        let l = m + r;
        let batches = self.lagged.len();
        let counts = self.pair_counts(left_out);
        let mut lags = vec![0.0; p * l * l];
        for (b, sums) in self.lagged.iter().enumerate() {
            if Some(b) != left_out {
                lags.iter_mut().zip(sums).for_each(|(t, v)| *t += v);
            }
        }
        let mut parts = GramParts::zeros(m, r, p);
        // Φ_{i−j} / K, later channel `a` down each column.
        for j in 0..p {
            for c in 0..l {
                let (outputs, inputs) = parts.column(j, c);
                for i in j..p {
                    let scale = 1.0 / counts[i * p + j];
                    let lag = &lags[(i - j) * l * l..][..l * l];
                    outputs[i * m..][..m]
                        .iter_mut()
                        .enumerate()
                        .for_each(|(a, t)| *t = lag[a * l + c] * scale);
                    inputs[i * r..][..r]
                        .iter_mut()
                        .enumerate()
                        .for_each(|(a, t)| *t = lag[(m + a) * l + c] * scale);
                }
            }
        }
        // −E^0 + E^B, and for a replicate + E^ℓ − E^{ℓ+1} (the kept batches'
        // edges telescope).
        let mut edges = vec![(0, -1.0), (batches, 1.0)];
        if let Some(b) = left_out {
            edges.extend([(b, 1.0), (b + 1, -1.0)]);
        }
        for (k, sign) in edges {
            self.add_edge_sums(&mut parts, self.bounds[k], sign, &counts);
        }
        parts.finish()
    }

    /// The Gram matrix `(1/K) Σ_t z_p(t) z_p(t)ᵀ` of every batch's columns
    /// but `left_out`'s (see the type's documentation), assembled from
    /// [`Self::blocks`]: row `i l + a` is channel `a` (outputs first) at
    /// block `i`.
    #[cfg(test)]
    fn gram(&self, left_out: Option<usize>) -> Mat<f64> {
        let (m, r, p) = (self.outputs, self.inputs, self.horizon);
        let l = m + r;
        let (r_yy, r_yu, r_uu) = self.blocks(left_out);
        Mat::from_fn(p * l, p * l, |row, col| {
            let (i, a, j, c) = (row / l, row % l, col / l, col % l);
            match (a < m, c < m) {
                (true, true) => r_yy[(i * m + a, j * m + c)],
                (true, false) => r_yu[(i * m + a, j * r + c - m)],
                (false, true) => r_yu[(j * m + c, i * r + a - m)],
                (false, false) => r_uu[(i * r + a - m, j * r + c - m)],
            }
        })
    }

    /// Lower block `(j + d, j)` += `sign · E_d(j) / K`, `E_d(j) =
    /// Σ_{u=c}^{c+j−1} z(u+d) z(u)ᵀ`: one running sum per lag, advanced
    /// along `j`, so that each of the Gram's columns is written in order.
    fn add_edge_sums(&self, parts: &mut GramParts, c: usize, sign: f64, counts: &[f64]) {
        let (m, r, p) = (self.outputs, self.inputs, self.horizon);
        let l = m + r;
        let z = |t: usize| &self.samples[t * l..][..l];
        // `sums[d][b * l + a]`: later channel `a`, earlier channel `b`.
        let mut sums = vec![0.0; p * l * l];
        for j in 1..p {
            let earlier = z(c + j - 1);
            for d in 0..p - j {
                let later = z(c + j - 1 + d);
                let sum = &mut sums[d * l * l..][..l * l];
                for (column, &zb) in sum.chunks_exact_mut(l).zip(earlier) {
                    column.iter_mut().zip(later).for_each(|(s, za)| *s += za * zb);
                }
            }
            for b in 0..l {
                let (outputs, inputs) = parts.column(j, b);
                for d in 0..p - j {
                    let scale = sign / counts[(j + d) * p + j];
                    let column = &sums[d * l * l + b * l..][..l];
                    let (later_outputs, later_inputs) = column.split_at(m);
                    outputs[(j + d) * m..][..m]
                        .iter_mut()
                        .zip(later_outputs)
                        .for_each(|(t, s)| *t += scale * s);
                    inputs[(j + d) * r..][..r]
                        .iter_mut()
                        .zip(later_inputs)
                        .for_each(|(t, s)| *t += scale * s);
                }
            }
        }
    }
}

/// The Gram matrix's lower blocks, by channel: `R_yy`, `R_yu`, `R_uy`, `R_uu`
/// (rows `i m + a` or `i r + a` of block `i`).
struct GramParts {
    outputs: usize,
    inputs: usize,
    r_yy: Mat<f64>,
    r_yu: Mat<f64>,
    r_uy: Mat<f64>,
    r_uu: Mat<f64>,
}

impl GramParts {
    fn zeros(m: usize, r: usize, p: usize) -> Self {
        Self {
            outputs: m,
            inputs: r,
            r_yy: Mat::zeros(p * m, p * m),
            r_yu: Mat::zeros(p * m, p * r),
            r_uy: Mat::zeros(p * r, p * m),
            r_uu: Mat::zeros(p * r, p * r),
        }
    }

    /// The Gram's column of channel `c` at block `j`: its output rows and
    /// its input rows.
    fn column(&mut self, j: usize, c: usize) -> (&mut [f64], &mut [f64]) {
        let (m, r) = (self.outputs, self.inputs);
        if c < m {
            (
                self.r_yy.col_as_slice_mut(j * m + c),
                self.r_uy.col_as_slice_mut(j * m + c),
            )
        } else {
            (
                self.r_yu.col_as_slice_mut(j * r + c - m),
                self.r_uu.col_as_slice_mut(j * r + c - m),
            )
        }
    }

    /// `R_yy`, `R_yu`, `R_uu` whole: the symmetric two's upper triangles
    /// mirrored, `R_yu`'s upper blocks from `R_uy`.
    fn finish(mut self) -> (Mat<f64>, Mat<f64>, Mat<f64>) {
        let (m, r) = (self.outputs, self.inputs);
        mirror_lower(&mut self.r_yy);
        mirror_lower(&mut self.r_uu);
        let p = self.r_yy.nrows() / m;
        for i in 0..p {
            for a in 0..m {
                let row = i * m + a;
                let source = self.r_uy.col_as_slice(row);
                for col in (i + 1) * r..p * r {
                    self.r_yu[(row, col)] = source[col];
                }
            }
        }
        (self.r_yy, self.r_yu, self.r_uu)
    }
}

/// The upper triangle of the square `matrix` set to its lower's transpose,
/// tile by tile (a column-by-column copy strides the whole matrix at every
/// entry).
fn mirror_lower(matrix: &mut Mat<f64>) {
    const TILE: usize = 32;
    let n = matrix.nrows();
    for col_tile in (0..n).step_by(TILE) {
        for row_tile in (0..=col_tile).step_by(TILE) {
            for col in col_tile..n.min(col_tile + TILE) {
                for row in row_tile..col.min(row_tile + TILE) {
                    matrix[(row, col)] = matrix[(col, row)];
                }
            }
        }
    }
}

/// `R_uu`'s range (eigenvalues above [`INPUT_RANGE`] of the largest: their
/// eigenvectors `V`) and `W = R_yu V Λ^{-1/2}`, so that the truncated
/// `R_yu R_uu⁺ R_yuᵀ = W Wᵀ`.
fn input_range(r_yu: &Mat<f64>, r_uu: &Mat<f64>) -> Result<(Mat<f64>, Mat<f64>), OmaError> {
    // Only the kept eigenpairs (a full decomposition also formed the other
    // ~70 % of the vectors of a Painter Street record's 900-square `R_uu`).
    let eigen = eigenpairs_above(r_uu.as_ref(), INPUT_RANGE).map_err(|_| OmaError::SvdFailed)?;
    if eigen.values.is_empty() {
        return Err(OmaError::InvalidSettings("the inputs hold no signal".into()));
    }
    let range = eigen.vectors;
    let projected = r_yu * &range;
    let w = Mat::from_fn(projected.nrows(), range.ncols(), |i, c| {
        projected[(i, c)] / eigen.values[c].sqrt()
    });
    Ok((w, range))
}

impl ReplicateSource for InformationMatrix {
    fn batches(&self) -> usize {
        self.lagged.len()
    }

    fn matrix_without(&self, left_out: usize) -> Result<Mat<f64>, OmaError> {
        self.matrix(Some(left_out))
    }

    /// A replicate's `R_hh` is symmetric as the record's: its own
    /// eigendecomposition, as the record's model is made (the SVD through
    /// `HᵀH` squared the range of its eigenvalues, and cost a product of
    /// the matrix with itself per replicate).
    fn model(&self, matrix: &Mat<f64>, channels: usize, max_order: usize, fs: f64) -> Result<SubspaceModel, OmaError> {
        SubspaceModel::from_symmetric(matrix, channels, max_order, fs)
    }
}

/// The modes of a record with measured `inputs` (shapes at the `outputs`),
/// sampled at `fs`: SRIM over the horizon `settings.block_rows`, then the
/// OMA's orders, stabilisation, clustering and uncertainty (`settings`).
pub fn identify_io(
    inputs: &[&[f64]],
    outputs: &[&[f64]],
    fs: f64,
    settings: &OmaSettings,
) -> Result<OmaResult, OmaError> {
    settings.check()?;
    let information = InformationMatrix::new(outputs, inputs, settings.block_rows, settings.batches)?;
    let matrix = information.matrix(None)?;
    let model = SubspaceModel::from_symmetric(&matrix, outputs.len(), settings.max_order, fs)?;
    oma::identify_model(&model, &information, fs, settings)
}

/// The stable realization of order `order` of `outputs` driven by
/// `inputs` at `fs` (complete records): `A`, `C` by SRIM over the horizon
/// `horizon`, `B`, `D` by least squares on the same record
/// ([`Realization::fit`]).
pub fn realization(
    inputs: &[&[f64]],
    outputs: &[&[f64]],
    fs: f64,
    horizon: usize,
    order: usize,
) -> Result<Realization, RealizationFailure> {
    let information = InformationMatrix::new(outputs, inputs, horizon, 1)?;
    let model = SubspaceModel::from_symmetric(&information.matrix(None)?, outputs.len(), order, fs)?;
    let (a, c) = model.state_space(order)?;
    Ok(Realization::fit(a.as_ref(), c.as_ref(), inputs, outputs, fs)?)
}

/// Why [`realization`] failed: the subspace step or the least squares.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RealizationFailure {
    #[error(transparent)]
    Subspace(#[from] OmaError),
    #[error(transparent)]
    Fit(#[from] RealizationError),
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::identification::test_noise::uniform_noise as noise;
    use faer::linalg::solvers::DenseSolveCore;

    /// The batched sums and edge corrections give exactly the block Hankel
    /// data matrix's Gram `Σ_t z_p(t) z_p(t)ᵀ / K` over the kept columns
    /// (each block divided by its valid column pairs), with and without a
    /// left-out batch, with and without missing samples: to 1e-12 of the
    /// largest entry (round-off of sums of ~600 products).
    #[test]
    fn the_gram_is_the_block_hankel_data_matrix_product() {
        let n = 600;
        let (p, batches) = (5, 4);
        for gaps in [false, true] {
            let mut z: Vec<Vec<f64>> = (0..3).map(|k| noise(k + 20, n)).collect();
            if gaps {
                z[1][37] = f64::NAN;
                z[2][300..303].fill(f64::NAN);
            }
            let (outputs, inputs) = ([&z[0][..], &z[1][..]], [&z[2][..]]);
            let info = InformationMatrix::new(&outputs, &inputs, p, batches).unwrap();
            let channels: Vec<&[f64]> = z.iter().map(Vec::as_slice).collect();
            let (centred, valid) = centred_channels(&channels);
            let columns = n - p + 1;
            let batch_len = columns / batches;
            for left_out in [None, Some(0), Some(2), Some(3)] {
                let kept = |t: usize| {
                    left_out.is_none_or(|b| {
                        let end = if b + 1 == batches { columns } else { (b + 1) * batch_len };
                        !(b * batch_len..end).contains(&t)
                    })
                };
                let l = 3;
                let direct = Mat::from_fn(p * l, p * l, |row, col| {
                    let (i, a, j, c) = (row / l, row % l, col / l, col % l);
                    let (sum, count) = (0..columns).filter(|&t| kept(t)).fold((0.0, 0.0), |(s, k), t| {
                        let pair = valid[t + i] && valid[t + j];
                        (s + centred[a][t + i] * centred[c][t + j], k + f64::from(u8::from(pair)))
                    });
                    sum / count
                });
                let gram = info.gram(left_out);
                let scale = direct.norm_max();
                let error = (&gram - &direct).norm_max();
                assert!(
                    error <= 1e-12 * scale,
                    "gaps {gaps}, left out {left_out:?}: {error} of {scale}"
                );
            }
        }
    }

    /// With inputs that span every direction (white noise: `R_uu` well
    /// conditioned, every eigenvalue kept), the record's range is the whole
    /// space and a replicate's Galerkin inverse is its exact inverse:
    /// `R_hh = R_yy − R_yu R_uu⁻¹ R_yuᵀ` of the replicate's own blocks.
    #[test]
    fn a_replicate_on_a_full_range_is_the_exact_information_matrix() {
        let n = 4000;
        let u: Vec<Vec<f64>> = (0..2).map(|k| noise(k + 1, n)).collect();
        // Outputs: lagged mixtures of the inputs and a little noise.
        let y: Vec<Vec<f64>> = (0..2)
            .map(|o| {
                let e = noise(10 + o, n);
                (0..n)
                    .map(|t| {
                        let lag = |c: usize, k: usize| if t >= k { u[c][t - k] } else { 0.0 };
                        lag(0, 1 + o as usize) + 0.5 * lag(1, 2) + 0.1 * e[t]
                    })
                    .collect()
            })
            .collect();
        let (outputs, inputs): (Vec<&[f64]>, Vec<&[f64]>) = (
            y.iter().map(Vec::as_slice).collect(),
            u.iter().map(Vec::as_slice).collect(),
        );
        let info = InformationMatrix::new(&outputs, &inputs, 4, 4).unwrap();
        let full = info.matrix(None).unwrap();
        assert_eq!(info.range.get().unwrap().ncols(), 8, "every direction is input");
        let replicate = info.matrix(Some(2)).unwrap();
        let (r_yy, r_yu, r_uu) = info.blocks(Some(2));
        let inverse = r_uu.llt(faer::Side::Lower).unwrap().inverse();
        let exact = &r_yy - &r_yu * &inverse * r_yu.transpose();
        let scale = r_yy.norm_max();
        assert!((&replicate - &exact).norm_max() <= 1e-10 * scale);
        assert!(
            (&full - &replicate).norm_max() > 1e-6 * scale,
            "a replicate differs from the record"
        );
    }
}
