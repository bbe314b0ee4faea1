//! Modal superposition of FRFs and their sensitivities (eq. 31–33), in
//! blocks of [`FREQUENCY_BLOCK`] lines on one or more threads.

use super::{FrfEvaluation, FrfModel, FrfRequest, LineRuns, ModalState, FREQUENCY_BLOCK};
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
        let wanted = if sensitivities { Wanted::All } else { Wanted::Nothing };
        self.evaluate_wanted(state, request, wanted, threads)
    }

    /// [`Self::evaluate`] with the damping sensitivities and those of the
    /// spring coefficients `springs` (flat indices) alone: the others'
    /// vectors in `dh_dkappa` are left empty, at none of their cost (an
    /// update of a few bearings of many).
    #[track_caller]
    pub fn evaluate_springs(&self, state: &ModalState, request: FrfRequest<'_>, springs: &[usize]) -> FrfEvaluation {
        self.evaluate_wanted(state, request, Wanted::Springs(springs), 1)
    }

    #[track_caller]
    fn evaluate_wanted(
        &self,
        state: &ModalState,
        request: FrfRequest<'_>,
        wanted: Wanted<'_>,
        threads: usize,
    ) -> FrfEvaluation {
        let blocks = self.wanted_blocks(wanted);
        let mut evaluation = self.modal_sum(state, request, (wanted, &blocks), threads);
        if let Some(residual) = &state.residual {
            self.add_residual(state, residual, request, (wanted, &blocks), &mut evaluation);
        }
        if let Wanted::Springs(_) = wanted {
            let mut all = vec![Vec::new(); self.spring_coefficient_count()];
            for (&j, dh) in blocks.iter().zip(std::mem::take(&mut evaluation.dh_dkappa)) {
                all[j] = dh;
            }
            evaluation.dh_dkappa = all;
        }
        evaluation
    }

    /// The flat indices of the spring coefficients whose sensitivities are
    /// `wanted`, ascending.
    fn wanted_blocks(&self, wanted: Wanted<'_>) -> Vec<usize> {
        match wanted {
            Wanted::Nothing => Vec::new(),
            Wanted::All => (0..self.spring_coefficient_count()).collect(),
            Wanted::Springs(springs) => {
                let mut blocks: Vec<usize> = springs
                    .iter()
                    .copied()
                    .filter(|&j| j < self.spring_coefficient_count())
                    .collect();
                blocks.sort_unstable();
                blocks.dedup();
                blocks
            }
        }
    }

    /// The modal superposition over the state's modes (eq. 31–33).
    #[track_caller]
    fn modal_sum(
        &self,
        state: &ModalState,
        request: FrfRequest<'_>,
        wanted: (Wanted<'_>, &[usize]),
        threads: usize,
    ) -> FrfEvaluation {
        let runs = LineRuns::new(request.frequencies_hz.len(), threads);
        let prepared = self.prepare(state, request, wanted);
        let parts = runs.map(|run| {
            let part = FrfRequest {
                frequencies_hz: &request.frequencies_hz[run],
                ..request
            };
            self.evaluate_lines(&prepared, part)
        });
        merge_evaluations(&runs, parts)
    }

    /// The frequency-independent factors of an evaluation, computed once and
    /// shared by the threads.
    #[track_caller]
    fn prepare(&self, state: &ModalState, request: FrfRequest<'_>, wanted: (Wanted<'_>, &[usize])) -> Prepared {
        self.prepare_with(state, request, wanted, NEAR_EIGENVALUES)
    }

    /// [`Self::prepare`] with pairs of modes closer than `near_fraction`
    /// in the spring sensitivities' product form ([`Self::spring_terms`]).
    #[allow(
        clippy::too_many_lines,
        reason = "one pass forms every frequency-independent factor of eq. (31)-(33); each is a few lines and used by the next"
    )]
    #[track_caller]
    fn prepare_with(
        &self,
        state: &ModalState,
        request: FrfRequest<'_>,
        (wanted, blocks): (Wanted<'_>, &[usize]),
        near_fraction: f64,
    ) -> Prepared {
        let sensitivities = !matches!(wanted, Wanted::Nothing);
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
        let sensors = request.involved_sensors();
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
        let springs = if sensitivities {
            self.spring_terms(state, request, &active, near_fraction, blocks)
        } else {
            SpringTerms {
                count: 0,
                far: Mat::zeros(0, 0),
                diagonal: Mat::zeros(0, 0),
                diagonal_rate: Vec::new(),
                near_pairs: Vec::new(),
                loss: Mat::zeros(0, 0),
            }
        };
        Prepared {
            sensitivities,
            omega,
            omega2,
            two_zeta_omega,
            coupling,
            damping_terms,
            springs,
        }
    }

    /// The frequency-independent factors of the exact `∂H/∂κ_j` (eq. 33
    /// with the modal damping's dependence on `λ`, see
    /// [`super::damping_rate_differences`]) on the `active` modes:
    /// `∂H_rs/∂κ_j = Σ_ik a_ri a_sk M_ik q_i q_k (jω E_ik − 1)`,
    /// `M = Φᵀ (∂K/∂κ_j) Φ`. For two modes apart (`λ_i ≠ λ_k`),
    /// `D_k − D_i = (λ_k − λ_i) + jω (c_k − c_i)` turns the pair's factor
    /// into `q_i q_k (jω E_ik − 1) = (q_k − q_i)/(λ_k − λ_i)`, so with the
    /// antisymmetric `F = M ∘ W`, `W_ik = 1/(λ_k − λ_i)` on those pairs,
    /// their share is `−Σ_i q_i (a_si (F a_r)_i + a_ri (F a_s)_i)`: linear in
    /// `q`, one GEMM per block of lines like `H` itself. Pairs closer than
    /// [`NEAR_EIGENVALUES`] (the diagonal, and repeated modes) keep the
    /// product form, where the difference quotient would cancel: the
    /// diagonal as one more GEMM on `q_i² (jω E_ii − 1)`, the rest pair by
    /// pair. Exact to round-off (amplified at most `1/NEAR_EIGENVALUES` in
    /// the far pairs' cancellation).
    fn spring_terms(
        &self,
        state: &ModalState,
        request: FrfRequest<'_>,
        active: &[usize],
        near_fraction: f64,
        wanted: &[usize],
    ) -> SpringTerms {
        let (np, nm) = (request.pairs.len(), active.len());
        let amplitude = |sensor: usize, i: usize| state.amplitudes[(sensor, active[i])];
        let lambda: Vec<f64> = active.iter().map(|&i| state.modes.omega2[i]).collect();
        // Far pairs' cancellation grows as max(λ, ω²)/|λ_k − λ_i| over the lines.
        let top = request
            .frequencies_hz
            .iter()
            .fold(0.0f64, |m, f| m.max((2.0 * PI * f).powi(2)));
        let near = |i: usize, k: usize| {
            (lambda[k] - lambda[i]).abs() <= near_fraction * lambda[i].abs().max(lambda[k].abs()).max(top)
        };
        // W (zero on the near pairs) and the near pairs: the same for every
        // coefficient.
        let inverse_gaps = Mat::from_fn(
            nm,
            nm,
            |i, k| {
                if near(i, k) {
                    0.0
                } else {
                    1.0 / (lambda[k] - lambda[i])
                }
            },
        );
        let near_pairs: Vec<(usize, usize)> = (0..nm)
            .flat_map(|i| (0..nm).map(move |k| (i, k)))
            .filter(|&(i, k)| i != k && near(i, k))
            .collect();
        let e = super::damping_rate_differences(state, active);
        let sensors = request.involved_sensors();
        let slot = |sensor: usize| sensors.binary_search(&sensor).expect("an involved sensor");
        let a = Mat::from_fn(nm, sensors.len(), |i, t| amplitude(sensors[t], i));
        let all: Vec<&LowRankBlock> = self.spring_blocks().iter().flatten().collect();
        let blocks: Vec<&LowRankBlock> = wanted.iter().map(|&j| all[j]).collect();
        let positions: Vec<&Vec<usize>> = wanted.iter().map(|&j| &self.block_positions[j]).collect();
        let count = blocks.len();
        // The supports' loss factors' share of ζ_i moves with the shapes:
        // ∂H_rs ∋ Σ_i a_ri a_si (∂H/∂ζ_i) ∂ζ_i/∂κ_j (super::support_loss).
        let slopes = state
            .loss
            .is_some()
            .then(|| self.loss_zeta_slopes(state, active, wanted));
        let mut terms = SpringTerms {
            count,
            far: Mat::zeros(count * np, nm),
            diagonal: Mat::zeros(count * np, nm),
            diagonal_rate: (0..nm).map(|i| e[(i, i)]).collect(),
            near_pairs: Vec::new(),
            loss: Mat::zeros(if slopes.is_some() { count * np } else { 0 }, nm),
        };
        for (j, (block, pos)) in blocks.iter().zip(positions).enumerate() {
            let shapes = Mat::from_fn(pos.len(), nm, |b, i| state.phi_springs[(pos[b], active[i])]);
            let m = shapes.transpose() * (&block.values * &shapes);
            let mut f = m.clone();
            for k in 0..nm {
                for (fik, wik) in f.col_as_slice_mut(k).iter_mut().zip(inverse_gaps.col_as_slice(k)) {
                    *fik *= wik;
                }
            }
            let fa = &f * &a;
            for (p, &(r, s)) in request.pairs.iter().enumerate() {
                let (tr, ts) = (slot(r), slot(s));
                for i in 0..nm {
                    terms.far[(j * np + p, i)] = a[(i, ts)] * fa[(i, tr)] + a[(i, tr)] * fa[(i, ts)];
                    terms.diagonal[(j * np + p, i)] = a[(i, tr)] * a[(i, ts)] * m[(i, i)];
                    if let Some(slopes) = &slopes {
                        terms.loss[(j * np + p, i)] = a[(i, tr)] * a[(i, ts)] * slopes[(i, j)];
                    }
                }
            }
            for &(i, k) in &near_pairs {
                terms.near_pairs.push(NearPair {
                    coefficient: j,
                    modes: (i, k),
                    rate: e[(i, k)],
                    weights: request
                        .pairs
                        .iter()
                        .map(|&(r, s)| a[(i, slot(r))] * a[(k, slot(s))] * m[(i, k)])
                        .collect(),
                });
            }
        }
        terms
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
        let mut dh_dkappa = vec![vec![zero; np * nf]; prepared.springs.count];
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
                spring_lines(prepared, &mut s, &lines, &mut dh_dkappa);
            }
        }
        FrfEvaluation {
            h,
            dh_dkappa,
            dh_dgamma,
            dh_dtheta: Vec::new(),
        }
    }
}

/// `∂H/∂κ_j` on one block of lines ([`FrfModel::spring_terms`]): the far
/// pairs' `−F q` and the diagonal's `G (q² ∘ (jω E_ii − 1))` as GEMMs, the
/// near off-diagonal pairs one by one; `s.q` holds the block's `1/D_i`.
fn spring_lines(prepared: &Prepared, s: &mut Scratch, lines: &Lines<'_>, dh_dkappa: &mut [Vec<c64>]) {
    let terms = &prepared.springs;
    let (np, nc) = (prepared.coupling.nrows(), lines.count);
    for (f, &w) in lines.omega.iter().enumerate() {
        let (q_re, q_im) = (s.q.re.col_as_slice(f), s.q.im.col_as_slice(f));
        let (re, im) = s.squared.col_mut(f);
        for ((((re, im), &a), &b), &rate) in re
            .iter_mut()
            .zip(im.iter_mut())
            .zip(q_re)
            .zip(q_im)
            .zip(&terms.diagonal_rate)
        {
            // (a + jb)² (−1 + jωE)
            let (sq_re, sq_im) = (a * a - b * b, 2.0 * a * b);
            *re = -sq_re - w * rate * sq_im;
            *im = w * rate * sq_re - sq_im;
        }
    }
    s.far.product(terms.count * np, nc, &terms.far, &s.q);
    s.diagonal.product(terms.count * np, nc, &terms.diagonal, &s.squared);
    if terms.loss.nrows() > 0 {
        // `s.e` holds −2j ω_i ω q² = ∂q_i/∂ζ_i (damping_lines ran first).
        s.loss.product(terms.count * np, nc, &terms.loss, &s.e);
        for (dst, src) in [(&mut s.far.re, &s.loss.re), (&mut s.far.im, &s.loss.im)] {
            let mut part = dst.submatrix_mut(0, 0, terms.count * np, nc);
            part -= src.submatrix(0, 0, terms.count * np, nc);
        }
    }
    // The near pairs into the diagonal's rows (contiguous per line).
    for pair in &terms.near_pairs {
        let (i, k) = pair.modes;
        let rows = pair.coefficient * np;
        for f in 0..nc {
            let qi = c64::new(s.q.re[(i, f)], s.q.im[(i, f)]);
            let qk = c64::new(s.q.re[(k, f)], s.q.im[(k, f)]);
            let t = qi * qk * c64::new(-1.0, lines.omega[f] * pair.rate);
            let (re, im) = s.diagonal.col_mut(f);
            for (p, &weight) in pair.weights.iter().enumerate() {
                re[rows + p] += t.re * weight;
                im[rows + p] += t.im * weight;
            }
        }
    }
    for (j, dj) in dh_dkappa.iter_mut().enumerate() {
        for p in 0..np {
            let row = j * np + p;
            let out = &mut dj[p * lines.total + lines.start..][..nc];
            for (f, v) in out.iter_mut().enumerate() {
                *v = c64::new(
                    s.diagonal.re[(row, f)] - s.far.re[(row, f)],
                    s.diagonal.im[(row, f)] - s.far.im[(row, f)],
                ) * lines.factor[f];
            }
        }
    }
}

/// Which sensitivities an evaluation computes.
#[derive(Debug, Clone, Copy)]
pub(super) enum Wanted<'a> {
    Nothing,
    /// The damping and every spring coefficient.
    All,
    /// The damping and these spring coefficients (flat indices).
    Springs(&'a [usize]),
}

/// Pairs of modes whose eigenvalues differ by less than this fraction of
/// `max(λ_i, λ_k, ω²_max)` keep the product form in [`FrfModel::spring_terms`].
const NEAR_EIGENVALUES: f64 = 1e-3;

/// The frequency-independent factors of the spring sensitivities
/// ([`FrfModel::spring_terms`]); rows `j · n_pairs + p`.
struct SpringTerms {
    /// Spring coefficients.
    count: usize,
    /// `a_si (F_j a_r)_i + a_ri (F_j a_s)_i`.
    far: Mat<f64>,
    /// `a_ri a_si M_j,ii`.
    diagonal: Mat<f64>,
    /// `E_ii` of every active mode.
    diagonal_rate: Vec<f64>,
    near_pairs: Vec<NearPair>,
    /// `a_ri a_si ∂ζ_i/∂κ_j` with `λ_i` held (the supports' loss factors,
    /// [`super::support_loss`]); empty without loss factors.
    loss: Mat<f64>,
}

/// One ordered pair of distinct modes with (nearly) equal eigenvalues.
struct NearPair {
    coefficient: usize,
    modes: (usize, usize),
    /// `E_ik`.
    rate: f64,
    /// `a_ri a_sk M_ik` per pair `(r, s)`.
    weights: Vec<f64>,
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
    /// `q² (jω E_ii − 1)`, and the spring products' rows.
    squared: Split,
    far: Split,
    diagonal: Split,
    /// The loss factors' rows of the spring products.
    loss: Split,
}

impl Scratch {
    fn new(prepared: &Prepared, pairs: usize, width: usize) -> Self {
        let nm = prepared.omega.len();
        let springs = if prepared.springs.count > 0 { nm } else { 0 };
        let rows = prepared.springs.count * pairs;
        Self {
            q: Split::zeros(nm, width),
            e: Split::zeros(nm, width),
            out: Split::zeros(pairs, width),
            squared: Split::zeros(springs, width),
            far: Split::zeros(rows, width),
            diagonal: Split::zeros(rows, width),
            loss: Split::zeros(if prepared.springs.loss.nrows() > 0 { rows } else { 0 }, width),
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
    /// The spring sensitivities' factors (empty without sensitivities).
    springs: SpringTerms,
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

/// The runs' evaluations as one, in the pair-major layouts
/// `[pair * n_f + line]`.
fn merge_evaluations(runs: &LineRuns, mut parts: Vec<FrfEvaluation>) -> FrfEvaluation {
    if parts.len() == 1 {
        return parts.pop().expect("one part");
    }
    let mut h = Vec::with_capacity(parts.len());
    let mut dh_dkappa = vec![Vec::with_capacity(parts.len()); parts[0].dh_dkappa.len()];
    let mut dh_dtheta = vec![Vec::with_capacity(parts.len()); parts[0].dh_dtheta.len()];
    let mut dh_dgamma = vec![Vec::with_capacity(parts.len()); parts[0].dh_dgamma.len()];
    for part in parts {
        h.push(part.h);
        for (all, v) in [
            (&mut dh_dkappa, part.dh_dkappa),
            (&mut dh_dtheta, part.dh_dtheta),
            (&mut dh_dgamma, part.dh_dgamma),
        ] {
            all.iter_mut().zip(v).for_each(|(a, v)| a.push(v));
        }
    }
    let merged = |all: Vec<Vec<Vec<c64>>>| all.into_iter().map(|p| runs.merge(p)).collect();
    FrfEvaluation {
        h: runs.merge(h),
        dh_dkappa: merged(dh_dkappa),
        dh_dtheta: merged(dh_dtheta),
        dh_dgamma: merged(dh_dgamma),
    }
}

#[cfg(test)]
mod tests;
