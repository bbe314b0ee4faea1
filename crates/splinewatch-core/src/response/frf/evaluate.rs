//! Modal superposition of FRFs and their sensitivities (eq. 31–33), in
//! blocks of [`FREQUENCY_BLOCK`] lines on one or more threads.

use super::{FrfEvaluation, FrfModel, FrfRequest, ModalState, FREQUENCY_BLOCK};
use crate::model::springs::LowRankBlock;
use faer::linalg::matmul::matmul;
use faer::{c64, Accum, Mat, Par};
use std::f64::consts::PI;

impl FrfModel {
    /// FRFs (and, if asked, sensitivities) by modal superposition.
    ///
    /// The frequency axis is processed in blocks of [`FREQUENCY_BLOCK`]
    /// lines so that every intermediate matrix stays in cache and is
    /// allocated once per call; all products are real GEMMs on split
    /// real/imaginary parts.
    #[track_caller]
    pub fn evaluate(&self, state: &ModalState, request: FrfRequest<'_>, sensitivities: bool) -> FrfEvaluation {
        self.evaluate_on_threads(state, request, sensitivities, 1)
    }

    /// [`Self::evaluate`] on up to `threads` threads, each taking a
    /// contiguous run of whole frequency blocks. Every block is computed
    /// exactly as in the sequential call, so the result is the same bit for
    /// bit whatever the thread count.
    ///
    /// A truncated model's state adds the discarded modes' residual to the
    /// FRFs, and its spring sensitivities come from the spring dofs'
    /// complete responses ([`crate::solvers::truncation`]).
    #[track_caller]
    pub fn evaluate_on_threads(
        &self,
        state: &ModalState,
        request: FrfRequest<'_>,
        sensitivities: bool,
        threads: usize,
    ) -> FrfEvaluation {
        let mut evaluation = self.modal_sum(state, request, sensitivities, threads);
        if let Some(residual) = &state.residual {
            self.add_residual(state, residual, request, sensitivities, &mut evaluation);
        }
        evaluation
    }

    /// The modal superposition over the state's modes (eq. 31–33).
    #[track_caller]
    fn modal_sum(
        &self,
        state: &ModalState,
        request: FrfRequest<'_>,
        sensitivities: bool,
        threads: usize,
    ) -> FrfEvaluation {
        let nf = request.frequencies_hz.len();
        let blocks = nf.div_ceil(FREQUENCY_BLOCK);
        let threads = threads.clamp(1, blocks.max(1));
        let prepared = self.prepare(state, request, sensitivities);
        if threads == 1 {
            return self.evaluate_lines(&prepared, request);
        }
        let per_thread = blocks.div_ceil(threads) * FREQUENCY_BLOCK;
        let ranges: Vec<(usize, usize)> = (0..nf)
            .step_by(per_thread)
            .map(|a| (a, (a + per_thread).min(nf)))
            .collect();
        let parts: Vec<FrfEvaluation> = std::thread::scope(|scope| {
            let handles: Vec<_> = ranges
                .iter()
                .map(|&(a, b)| {
                    let part = FrfRequest {
                        frequencies_hz: &request.frequencies_hz[a..b],
                        ..request
                    };
                    let prepared = &prepared;
                    scope.spawn(move || self.evaluate_lines(prepared, part))
                })
                .collect();
            handles
                .into_iter()
                .map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
                .collect()
        });
        // Reassemble the pair-major layouts `[pair * n_f + line]`.
        let np = request.pairs.len();
        let merge = |column: &dyn Fn(&FrfEvaluation) -> &Vec<c64>| -> Vec<c64> {
            let mut all = vec![c64::new(0.0, 0.0); np * nf];
            for ((a, b), part) in ranges.iter().zip(&parts) {
                let n = b - a;
                for p in 0..np {
                    all[p * nf + a..p * nf + b].copy_from_slice(&column(part)[p * n..(p + 1) * n]);
                }
            }
            all
        };
        let first = &parts[0];
        FrfEvaluation {
            h: merge(&|e| &e.h),
            dh_dkappa: (0..first.dh_dkappa.len())
                .map(|j| merge(&|e| &e.dh_dkappa[j]))
                .collect(),
            dh_dtheta: Vec::new(),
            dh_dgamma: (0..first.dh_dgamma.len())
                .map(|z| merge(&|e| &e.dh_dgamma[z]))
                .collect(),
        }
    }

    /// The frequency-independent factors of an evaluation, computed once and
    /// shared by the threads.
    #[allow(
        clippy::too_many_lines,
        reason = "one pass forms every frequency-independent factor of eq. (31)-(33); each is a few lines and used by the next"
    )]
    #[track_caller]
    fn prepare(&self, state: &ModalState, request: FrfRequest<'_>, sensitivities: bool) -> Prepared {
        let np = request.pairs.len();
        for &(r, s) in request.pairs {
            assert!(
                r < self.sensor_count() && s < self.sensor_count(),
                "sensor index out of range"
            );
        }
        // Modes that no involved sensor sees (the membrane modes of a flat
        // deck under vertical sensors: their amplitudes are zero or
        // round-off, below 1e-10 of the largest) add nothing to H, g_s or
        // the sensitivities beyond that round-off: leave them out (195 of
        // 325 for Sinello).
        let mut sensors: Vec<usize> = request.pairs.iter().flat_map(|&(r, s)| [r, s]).collect();
        sensors.sort_unstable();
        sensors.dedup();
        let amax = sensors
            .iter()
            .flat_map(|&s| (0..state.modes.len()).map(move |i| state.amplitudes[(s, i)].abs()))
            .fold(0.0, f64::max);
        let active: Vec<usize> = (0..state.modes.len())
            .filter(|&i| sensors.iter().any(|&s| state.amplitudes[(s, i)].abs() > 1e-10 * amax))
            .collect();
        let nm = active.len();
        let omega: Vec<f64> = active.iter().map(|&i| state.omega[i]).collect();
        let omega2: Vec<f64> = omega.iter().map(|w| w * w).collect();
        let two_zeta_omega: Vec<f64> = active.iter().map(|&i| 2.0 * state.zeta[i] * state.omega[i]).collect();
        let amplitude = |sensor: usize, i: usize| state.amplitudes[(sensor, active[i])];

        // Frequency-independent factors. H_p = Σ_i a_r a_s q_i, p = (r, s).
        let coupling = Mat::from_fn(np, nm, |p, i| {
            let (r, s) = request.pairs[p];
            amplitude(r, i) * amplitude(s, i)
        });
        let nz = if sensitivities { state.zeta_basis.ncols() } else { 0 };
        // Damping: ∂H_p/∂γ_z = Σ_i a_r a_s B_z(f_i) e_i, e_i = -2j ω_i ω q_i².
        // B_z is non-zero on a contiguous range of modes (ascending
        // frequencies): one GEMM per z over that range only.
        let damping_terms: Vec<(usize, Mat<f64>)> = (0..nz)
            .map(|z| {
                let support: Vec<usize> = (0..nm).filter(|&i| state.zeta_basis[(active[i], z)] != 0.0).collect();
                let (lo, hi) = match (support.first(), support.last()) {
                    (Some(&lo), Some(&hi)) => (lo, hi + 1),
                    _ => (0, 0),
                };
                let weights = Mat::from_fn(np, hi - lo, |p, i| {
                    coupling[(p, lo + i)] * state.zeta_basis[(active[lo + i], z)]
                });
                (lo, weights)
            })
            .collect();
        // Springs (eq. 33, low rank): ∂H_rs/∂κ_j = -g_rᵀ B_j g_s on the
        // block's dofs, g_s = Φ_U diag(a_s) q the response of the spring dofs
        // U to input s. With g_r = Φ_U diag(a_r) q this is
        // -Σ_i a_{r,i} q_i c_{j,i}, c_j = Φ_{B_j}ᵀ B_j g_s: g_s only for the
        // inputs (not for every sensor), then per block one small GEMM for
        // c_j and one against the output amplitudes.
        let blocks: Vec<&LowRankBlock> = if sensitivities {
            self.spring_blocks().iter().flatten().collect()
        } else {
            Vec::new()
        };
        let mut inputs: Vec<usize> = request.pairs.iter().map(|&(_, s)| s).collect();
        inputs.sort_unstable();
        inputs.dedup();
        let nu = if sensitivities { state.phi_springs.nrows() } else { 0 };
        let phi_u = Mat::from_fn(nu, nm, |u, i| state.phi_springs[(u, active[i])]);
        let stacked = Mat::from_fn(inputs.len() * nu, nm, |row, i| {
            phi_u[(row % nu, i)] * amplitude(inputs[row / nu], i)
        });
        // Φ_{B_j}ᵀ B_j, frequency-independent: c_j = (Φ_{B_j}ᵀ B_j) g_s[B_j].
        let phi_b_blocks: Vec<Mat<f64>> = blocks
            .iter()
            .zip(&self.block_positions)
            .map(|(block, pos)| Mat::from_fn(nm, pos.len(), |i, a| phi_u[(pos[a], i)]) * &block.values)
            .collect();
        let by_input: Vec<(Vec<usize>, Mat<f64>)> = inputs
            .iter()
            .map(|&s| {
                let pairs: Vec<usize> = (0..np).filter(|&p| request.pairs[p].1 == s).collect();
                let outputs = Mat::from_fn(pairs.len(), nm, |row, i| amplitude(request.pairs[pairs[row]].0, i));
                (pairs, outputs)
            })
            .collect();
        let input_amplitudes: Vec<Vec<f64>> = inputs
            .iter()
            .map(|&s| (0..nm).map(|i| amplitude(s, i)).collect())
            .collect();
        let damping_couplings = self.damping_couplings(state, &active, &phi_u, &phi_b_blocks);

        Prepared {
            sensitivities,
            omega,
            omega2,
            two_zeta_omega,
            coupling,
            damping_terms,
            nu,
            stacked,
            phi_b_blocks,
            by_input,
            input_amplitudes,
            damping_couplings,
        }
    }

    /// `(Φᵀ (∂K/∂κ_j) Φ) ∘ E` on the active modes for every spring
    /// coefficient, stacked (`j`'s rows at `j·n_m`, one GEMM per input and
    /// block of lines): the damping part of the exact `∂H/∂κ_j`
    /// ([`super::damping_rate_differences`]).
    fn damping_couplings(
        &self,
        state: &ModalState,
        active: &[usize],
        phi_u: &Mat<f64>,
        phi_b_blocks: &[Mat<f64>],
    ) -> Mat<f64> {
        let nm = active.len();
        if phi_b_blocks.is_empty() {
            return Mat::zeros(0, nm);
        }
        let e = super::damping_rate_differences(state, active);
        let mut stacked = Mat::<f64>::zeros(phi_b_blocks.len() * nm, nm);
        for (j, (phi_b, pos)) in phi_b_blocks.iter().zip(&self.block_positions).enumerate() {
            let shapes = Mat::from_fn(pos.len(), nm, |a, i| phi_u[(pos[a], i)]);
            let coupling = phi_b * &shapes;
            for k in 0..nm {
                for i in 0..nm {
                    stacked[(j * nm + i, k)] = coupling[(i, k)] * e[(i, k)];
                }
            }
        }
        stacked
    }

    /// The evaluation on the lines of `request` (all or a thread's share),
    /// block by block; the block's buffers ([`Scratch`]) are allocated once
    /// per call and stay in cache.
    fn evaluate_lines(&self, prepared: &Prepared, request: FrfRequest<'_>) -> FrfEvaluation {
        let nf = request.frequencies_hz.len();
        let np = request.pairs.len();
        let zero = c64::new(0.0, 0.0);
        let mut h = vec![zero; np * nf];
        let mut dh_dgamma = vec![vec![zero; np * nf]; prepared.damping_terms.len()];
        let mut dh_dkappa = vec![vec![zero; np * nf]; prepared.phi_b_blocks.len()];
        let width = FREQUENCY_BLOCK.min(nf.max(1));
        let mut s = Scratch::new(prepared, np, width);
        for start in (0..nf).step_by(width) {
            let nc = width.min(nf - start);
            let w: Vec<f64> = request.frequencies_hz[start..start + nc]
                .iter()
                .map(|f| 2.0 * PI * f)
                .collect();
            let factor: Vec<c64> = w.iter().map(|&wf| request.quantity.factor(wf)).collect();
            // q_{i,f} = 1 / D_i(ω_f) = conj(D) / |D|², over contiguous columns.
            for (f, &wf) in w.iter().enumerate() {
                let (re, im) = s.q.col_mut(f);
                for (((re, im), &w2), &tzw) in re
                    .iter_mut()
                    .zip(im.iter_mut())
                    .zip(&prepared.omega2)
                    .zip(&prepared.two_zeta_omega)
                {
                    let d_re = w2 - wf * wf;
                    let d_im = tzw * wf;
                    let norm = d_re * d_re + d_im * d_im;
                    *re = d_re / norm;
                    *im = -d_im / norm;
                }
            }
            s.out.product(np, nc, &prepared.coupling, &s.q);
            for p in 0..np {
                for f in 0..nc {
                    h[p * nf + start + f] = c64::new(s.out.re[(p, f)], s.out.im[(p, f)]) * factor[f];
                }
            }
            if !prepared.sensitivities {
                continue;
            }
            let lines = Lines {
                start,
                count: nc,
                total: nf,
                omega: &w,
                factor: &factor,
            };
            damping_lines(prepared, &mut s, &w, &lines, &mut dh_dgamma);
            if !dh_dkappa.is_empty() {
                self.spring_lines(prepared, &mut s, &lines, &mut dh_dkappa);
            }
        }
        FrfEvaluation {
            h,
            dh_dkappa,
            dh_dgamma,
            dh_dtheta: Vec::new(),
        }
    }

    /// `∂H/∂κ_j` on one block of lines (eq. 33): `g_s` for every input, then
    /// per spring block `c_j = (Φ_{B_j}ᵀ B_j) g_s[B_j]`, `c ← q ∘ c` and
    /// `∂H_p/∂κ_j = −Σ_i a_{r,i} c_i`; `s.q` holds the block's `1/D_i`.
    fn spring_lines(&self, prepared: &Prepared, s: &mut Scratch, lines: &Lines<'_>, dh_dkappa: &mut [Vec<c64>]) {
        let (nc, nu) = (lines.count, prepared.nu);
        s.g.product(prepared.by_input.len() * nu, nc, &prepared.stacked, &s.q);
        for (k, (pairs, outputs)) in prepared.by_input.iter().enumerate() {
            // y = a_s ∘ q, and P_j y for every coefficient j in one GEMM
            // (the damping part).
            let amplitudes = &prepared.input_amplitudes[k];
            let nm = amplitudes.len();
            for f in 0..nc {
                for (i, &a) in amplitudes.iter().enumerate() {
                    s.y.re[(i, f)] = a * s.q.re[(i, f)];
                    s.y.im[(i, f)] = a * s.q.im[(i, f)];
                }
            }
            s.z.product(
                prepared.damping_couplings.nrows(),
                nc,
                &prepared.damping_couplings,
                &s.y,
            );
            for (j, (phi_b, pos)) in prepared.phi_b_blocks.iter().zip(&self.block_positions).enumerate() {
                for f in 0..nc {
                    for (a, &u) in pos.iter().enumerate() {
                        s.gathered.re[(a, f)] = s.g.re[(k * nu + u, f)];
                        s.gathered.im[(a, f)] = s.g.im[(k * nu + u, f)];
                    }
                }
                for (dst, src) in [(&mut s.c.re, &s.gathered.re), (&mut s.c.im, &s.gathered.im)] {
                    matmul(
                        dst.subcols_mut(0, nc),
                        Accum::Replace,
                        phi_b.as_ref(),
                        src.submatrix(0, 0, pos.len(), nc),
                        1.0,
                        Par::Seq,
                    );
                }
                // c ← c − jω (P_j y): the modal damping's share
                // ([`super::damping_rate_differences`]).
                for f in 0..nc {
                    let w = lines.omega[f];
                    for i in 0..nm {
                        s.c.re[(i, f)] += w * s.z.im[(j * nm + i, f)];
                        s.c.im[(i, f)] -= w * s.z.re[(j * nm + i, f)];
                    }
                }
                // c ← q ∘ c in place, then ∂H_p/∂κ_j = -Σ_i a_{r,i} c_i.
                for f in 0..nc {
                    let (q_re, q_im) = (s.q.re.col_as_slice(f), s.q.im.col_as_slice(f));
                    let (c_re, c_im) = s.c.col_mut(f);
                    for (((cr, ci), &qr), &qi) in c_re.iter_mut().zip(c_im.iter_mut()).zip(q_re).zip(q_im) {
                        let (a, b) = (*cr, *ci);
                        *cr = qr * a - qi * b;
                        *ci = qr * b + qi * a;
                    }
                }
                s.r.product(pairs.len(), nc, outputs, &s.c);
                let dj = &mut dh_dkappa[j];
                for (row, &p) in pairs.iter().enumerate() {
                    for f in 0..nc {
                        let v = c64::new(s.r.re[(row, f)], s.r.im[(row, f)]);
                        dj[p * lines.total + lines.start + f] = -v * lines.factor[f];
                    }
                }
            }
        }
    }
}

/// One block of frequency lines: where it starts, how many, the total, and
/// the quantity's factor (`1`, `jω`, `−ω²`) per line.
struct Lines<'a> {
    start: usize,
    count: usize,
    total: usize,
    /// `ω` per line (rad/s).
    omega: &'a [f64],
    factor: &'a [c64],
}

/// `∂H/∂γ_z` on one block of lines: `e_{i,f} = −2j ω_i ω_f q_{i,f}²`, then
/// one GEMM per damping coefficient over its modes; `s.q` holds `1/D_i`.
fn damping_lines(prepared: &Prepared, s: &mut Scratch, w: &[f64], lines: &Lines<'_>, dh_dgamma: &mut [Vec<c64>]) {
    let (np, nc) = (prepared.coupling.nrows(), lines.count);
    for (f, &wf) in w.iter().enumerate() {
        let (q_re, q_im) = (s.q.re.col_as_slice(f), s.q.im.col_as_slice(f));
        let (re, im) = s.e.col_mut(f);
        for ((((re, im), &a), &b), &w) in re
            .iter_mut()
            .zip(im.iter_mut())
            .zip(q_re)
            .zip(q_im)
            .zip(&prepared.omega)
        {
            // j s (a + j b)² = j s (a² - b²) - 2 s a b, s = -2 ω_i ω
            let s = -2.0 * w * wf;
            *re = -2.0 * s * a * b;
            *im = s * (a * a - b * b);
        }
    }
    for ((lo, weights), dz) in prepared.damping_terms.iter().zip(dh_dgamma.iter_mut()) {
        for (dst, src) in [(&mut s.out.re, &s.e.re), (&mut s.out.im, &s.e.im)] {
            matmul(
                dst.submatrix_mut(0, 0, np, nc),
                Accum::Replace,
                weights.as_ref(),
                src.submatrix(*lo, 0, weights.ncols(), nc),
                1.0,
                Par::Seq,
            );
        }
        for p in 0..np {
            for f in 0..nc {
                dz[p * lines.total + lines.start + f] = c64::new(s.out.re[(p, f)], s.out.im[(p, f)]) * lines.factor[f];
            }
        }
    }
}

/// The buffers of one block of lines in [`FrfModel::evaluate`].
struct Scratch {
    /// `1/D_i(ω_f)`: active modes × lines.
    q: Split,
    /// `−2j ω_i ω_f q²` (damping sensitivities).
    e: Split,
    /// Pair rows of a product.
    out: Split,
    /// `g_s` on the spring dofs, stacked per input.
    g: Split,
    c: Split,
    gathered: Split,
    r: Split,
    /// `a_s ∘ q` of one input, and `P_j` times it (damping part).
    y: Split,
    z: Split,
}

impl Scratch {
    fn new(prepared: &Prepared, pairs: usize, width: usize) -> Self {
        let nm = prepared.omega.len();
        let widest = prepared.phi_b_blocks.iter().map(Mat::ncols).max().unwrap_or(0);
        Self {
            q: Split::zeros(nm, width),
            e: Split::zeros(nm, width),
            out: Split::zeros(pairs, width),
            g: Split::zeros(prepared.by_input.len() * prepared.nu, width),
            c: Split::zeros(nm, width),
            gathered: Split::zeros(widest, width),
            r: Split::zeros(pairs, width),
            y: Split::zeros(nm, width),
            z: Split::zeros(prepared.damping_couplings.nrows(), width),
        }
    }
}

/// See [`FrfModel::prepare`]: the active modes' data and the products
/// that do not depend on frequency.
struct Prepared {
    sensitivities: bool,
    /// ω of the active modes.
    omega: Vec<f64>,
    omega2: Vec<f64>,
    two_zeta_omega: Vec<f64>,
    /// `a_{r,i} a_{s,i}` per pair.
    coupling: Mat<f64>,
    /// Per damping coefficient: first mode of its support, weights.
    damping_terms: Vec<(usize, Mat<f64>)>,
    nu: usize,
    /// `Φ_U diag(a_s)` per input, stacked.
    stacked: Mat<f64>,
    /// `Φ_{B_j}ᵀ B_j` per spring coefficient (none without sensitivities).
    phi_b_blocks: Vec<Mat<f64>>,
    /// Per input: its pairs and their output amplitudes.
    by_input: Vec<(Vec<usize>, Mat<f64>)>,
    /// Per input (as `by_input`): its own amplitudes `a_{s,i}`.
    input_amplitudes: Vec<Vec<f64>>,
    /// `(Φᵀ ∂K/∂κ_j Φ) ∘ E` of every spring coefficient, stacked (no rows
    /// without sensitivities).
    damping_couplings: Mat<f64>,
}

/// A complex matrix stored as real and imaginary parts, for real GEMMs.
struct Split {
    re: Mat<f64>,
    im: Mat<f64>,
}

impl Split {
    fn zeros(rows: usize, cols: usize) -> Self {
        Self {
            re: Mat::zeros(rows, cols),
            im: Mat::zeros(rows, cols),
        }
    }

    /// Column `j` as contiguous real and imaginary slices.
    fn col_mut(&mut self, j: usize) -> (&mut [f64], &mut [f64]) {
        (self.re.col_as_slice_mut(j), self.im.col_as_slice_mut(j))
    }

    /// `self[..rows, ..cols] = a · b[.., ..cols]` for real `a`.
    fn product(&mut self, rows: usize, cols: usize, a: &Mat<f64>, b: &Split) {
        for (dst, src) in [(&mut self.re, &b.re), (&mut self.im, &b.im)] {
            matmul(
                dst.submatrix_mut(0, 0, rows, cols),
                Accum::Replace,
                a.as_ref(),
                src.subcols(0, cols),
                1.0,
                Par::Seq,
            );
        }
    }
}
