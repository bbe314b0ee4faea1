//! A weighted least-squares fit of a pole–residue model to several
//! frequency response functions that share their poles: the frequency-domain
//! modal estimate that holds heavily damped modes, with the standard
//! deviations of their frequencies and damping ratios.
//!
//! Function `j` at line `k` (`s = iω_k`) is modelled as
//! `Ĥ_j(ω) = Σ_m [A_jm/(s − λ_m) + Ā_jm/(s − λ̄_m)] + c_j`, the modes'
//! poles `λ_m = −ζ_m ω_m + iω_m √(1 − ζ_m²)` shared by every function, the
//! residues `A_jm` and the complex constant `c_j` (the modes outside the
//! band and the sensors' phase) each function's own. The cost is
//! `Σ_j Σ_k |H_j(ω_k) − Ĥ_j(ω_k)|² / σ_jk²`, with `σ_jk` the estimate's
//! standard deviation (for an H1 estimate, `|H| √((1 − γ²)/(2 n_d γ²))`,
//! Bendat & Piersol 2010, eq. 9.90): with Gaussian errors of those
//! variances it is the maximum-likelihood estimate (Pintelon & Schoukens
//! 2012, *System Identification*, §9; the pole–residue form of the
//! maximum-likelihood modal model, El-kafafy, Guillaume & Peeters 2013).
//!
//! The residues enter linearly and are projected out (variable projection,
//! Golub & Pereyra 1973); the poles are found by Levenberg–Marquardt from
//! a greedy grid of start values, one mode at a time, on Kaufman's (1975)
//! Jacobian of the projected residual, `−P⊥ ∂A/∂θ c` (analytic: the
//! gradient `Jᵀr` it gives is the exact one, so the optimum is the same;
//! only the curvature's second-order term is left out). The covariance of
//! `(f_m, ζ_m)` is `s² ((P⊥J)ᵀ(P⊥J))⁻¹`, the Gauss–Newton covariance of
//! the whole problem with the residues eliminated: `J` the model's
//! derivative in the poles at fixed residues, `P⊥` the projection off the
//! residues' columns, `s²` the weighted residual sum of squares over its
//! degrees of freedom (so a misfit beyond the weights' widens the stds).
//!
//! Where it holds: the modes in the band are the model's (none left out
//! that carries comparable energy), and the estimate's errors are
//! independent across lines; unlike a subspace method it needs no stable
//! poles over model orders, so a mode damped 10–30 % that does not recur
//! over the orders is still estimated.

use faer::linalg::solvers::{Qr, Solve, SolveLstsq};
use faer::{c64, Mat};
use std::f64::consts::PI;
use thiserror::Error;

/// The smallest and largest damping ratio a fitted mode may take.
pub const DAMPING_BOUNDS: (f64, f64) = (1e-4, 0.7);

#[derive(Debug, Clone, PartialEq, Error)]
pub enum PoleResidueError {
    #[error("no functions to fit")]
    NoFunctions,
    #[error("{functions} functions and {deviations} rows of standard deviations: give one row per function")]
    UnequalCounts { functions: usize, deviations: usize },
    #[error("function {function} has {len} lines and standard deviations, the frequencies {expected}")]
    UnequalLengths {
        function: usize,
        len: usize,
        expected: usize,
    },
    #[error("the frequencies must be positive, finite and increasing")]
    Frequencies,
    #[error("function {function}, line {line}: the value must be finite and its standard deviation positive")]
    BadLine { function: usize, line: usize },
    #[error("{modes} modes need more lines than {lines} (at least 4 per mode and 4 more)")]
    TooFewLines { modes: usize, lines: usize },
    #[error("at least one mode must be fitted")]
    NoModes,
    #[error("the fit is singular: the modes are not separable from the data")]
    Singular,
}

/// One mode of the fit.
#[derive(Debug, Clone, PartialEq)]
pub struct FittedMode {
    pub frequency_hz: f64,
    pub damping_ratio: f64,
    pub frequency_std_hz: f64,
    pub damping_std: f64,
    /// `A_jm` per function `j`.
    pub residues: Vec<c64>,
    /// Whether the fit stopped at a bound (the band's edge or
    /// [`DAMPING_BOUNDS`]): the band does not hold the mode.
    pub at_bound: bool,
}

/// The fit of all the functions.
#[derive(Debug, Clone, PartialEq)]
pub struct PoleResidueFit {
    /// By frequency.
    pub modes: Vec<FittedMode>,
    /// `s²`: the weighted residual sum of squares over its degrees of
    /// freedom (1 when the weights are the errors' standard deviations and
    /// the model holds).
    pub residual_scale: f64,
    pub iterations: usize,
}

/// The functions to fit: `h[j][k]` at `frequencies_hz[k]`, with standard
/// deviations `sigma[j][k]`.
#[derive(Debug, Clone, Copy)]
pub struct Functions<'a> {
    pub frequencies_hz: &'a [f64],
    pub h: &'a [Vec<c64>],
    pub sigma: &'a [Vec<f64>],
}

/// The standard deviation of one line of an H1 estimate from its
/// (multiple) coherence `γ²` over `averages` Welch averages with `inputs`
/// inputs: `|H| √((1 − γ²)/(2 n γ²))`, `n` the averages less the inputs
/// (at least 1; Bendat & Piersol 2010, eq. 9.90), `γ²` held within
/// [1e-4, 0.9999] so that no line weighs infinitely or not at all.
pub fn h1_standard_deviation(h: c64, coherence: f64, averages: usize, inputs: usize) -> f64 {
    let n = averages.saturating_sub(inputs).max(1) as f64;
    let g = coherence.clamp(1e-4, 0.9999);
    h.norm() * ((1.0 - g) / (2.0 * n * g)).sqrt()
}

/// Fits `modes` modes to `functions` over their band (the first to the last
/// line).
pub fn fit(functions: Functions<'_>, modes: usize) -> Result<PoleResidueFit, PoleResidueError> {
    check(functions, modes)?;
    let problem = Problem::new(functions);
    let (low, high) = problem.band;
    // Start values: a grid over the band's inner 90 % and the damping
    // ratios a bridge shows, one mode at a time with those before held.
    let margin = 0.05 * (high - low);
    let candidates: Vec<f64> = (0..=48)
        .map(|i| low + margin + (high - low - 2.0 * margin) * f64::from(i) / 48.0)
        .collect();
    let mut theta: Vec<f64> = Vec::with_capacity(2 * modes);
    let mut iterations = 0;
    for _ in 0..modes {
        let mut best: Option<(f64, f64, f64)> = None;
        for &f in &candidates {
            for zeta in [0.01, 0.03, 0.08, 0.15, 0.3] {
                let mut trial = theta.clone();
                trial.extend([f, zeta]);
                if let Some(cost) = problem.cost(&trial) {
                    if best.is_none_or(|(c, _, _)| cost < c) {
                        best = Some((cost, f, zeta));
                    }
                }
            }
        }
        let (_, f, zeta) = best.ok_or(PoleResidueError::Singular)?;
        theta.extend([f, zeta]);
        iterations += problem.levenberg_marquardt(&mut theta)?;
    }
    problem.finish(&theta, iterations)
}

/// Fits modes starting from `start` (frequency in Hz, damping ratio), e.g.
/// another method's poles.
pub fn fit_from(functions: Functions<'_>, start: &[(f64, f64)]) -> Result<PoleResidueFit, PoleResidueError> {
    check(functions, start.len())?;
    let problem = Problem::new(functions);
    let mut theta: Vec<f64> = start.iter().flat_map(|&(f, z)| [f, z]).collect();
    problem.clamp(&mut theta);
    let iterations = problem.levenberg_marquardt(&mut theta)?;
    problem.finish(&theta, iterations)
}

fn check(functions: Functions<'_>, modes: usize) -> Result<(), PoleResidueError> {
    let Functions {
        frequencies_hz,
        h,
        sigma,
    } = functions;
    if h.is_empty() {
        return Err(PoleResidueError::NoFunctions);
    }
    if sigma.len() != h.len() {
        return Err(PoleResidueError::UnequalCounts {
            functions: h.len(),
            deviations: sigma.len(),
        });
    }
    if modes == 0 {
        return Err(PoleResidueError::NoModes);
    }
    let lines = frequencies_hz.len();
    if lines < 4 * modes + 4 {
        return Err(PoleResidueError::TooFewLines { modes, lines });
    }
    if frequencies_hz.iter().any(|f| !(f.is_finite() && *f > 0.0)) || frequencies_hz.windows(2).any(|w| w[1] <= w[0]) {
        return Err(PoleResidueError::Frequencies);
    }
    for (function, (hj, sj)) in h.iter().zip(sigma).enumerate() {
        if hj.len() != lines || sj.len() != lines {
            return Err(PoleResidueError::UnequalLengths {
                function,
                len: hj.len().min(sj.len()),
                expected: lines,
            });
        }
        if let Some(line) =
            (0..lines).find(|&k| !(hj[k].re.is_finite() && hj[k].im.is_finite() && sj[k].is_finite() && sj[k] > 0.0))
        {
            return Err(PoleResidueError::BadLine { function, line });
        }
    }
    Ok(())
}

struct Problem<'a> {
    functions: Functions<'a>,
    band: (f64, f64),
}

/// One evaluation: per function, the weighted real design matrix and its
/// QR factors, the residues' least-squares coefficients, and the weighted
/// residual stacked over the functions.
struct Evaluation {
    designs: Vec<Mat<f64>>,
    factors: Vec<Qr<f64>>,
    coefficients: Vec<Mat<f64>>,
    residual: Vec<f64>,
}

impl Evaluation {
    fn cost(&self) -> f64 {
        self.residual.iter().map(|r| r * r).sum()
    }
}

impl<'a> Problem<'a> {
    fn new(functions: Functions<'a>) -> Self {
        let f = functions.frequencies_hz;
        Self {
            functions,
            band: (f[0], f[f.len() - 1]),
        }
    }

    fn lines(&self) -> usize {
        self.functions.frequencies_hz.len()
    }

    fn clamp(&self, theta: &mut [f64]) {
        for pair in theta.chunks_mut(2) {
            pair[0] = pair[0].clamp(self.band.0, self.band.1);
            pair[1] = pair[1].clamp(DAMPING_BOUNDS.0, DAMPING_BOUNDS.1);
        }
    }

    /// The complex basis at every line: per mode `g + ḡ` and `i(g − ḡ)`
    /// (`g = 1/(s − λ)`; coefficients α, β give `A = α + iβ`), then `1`
    /// and `i` (the constant).
    fn basis(&self, theta: &[f64]) -> Vec<Vec<c64>> {
        let poles: Vec<c64> = theta
            .chunks(2)
            .map(|p| {
                let w = 2.0 * PI * p[0];
                c64::new(-p[1] * w, w * (1.0 - p[1] * p[1]).sqrt())
            })
            .collect();
        self.functions
            .frequencies_hz
            .iter()
            .map(|&f| {
                let s = c64::new(0.0, 2.0 * PI * f);
                let mut row = Vec::with_capacity(2 * poles.len() + 2);
                for &lambda in &poles {
                    let g = c64::new(1.0, 0.0) / (s - lambda);
                    let gb = c64::new(1.0, 0.0) / (s - lambda.conj());
                    row.push(g + gb);
                    row.push(c64::new(0.0, 1.0) * (g - gb));
                }
                row.push(c64::new(1.0, 0.0));
                row.push(c64::new(0.0, 1.0));
                row
            })
            .collect()
    }

    /// Function `j`'s weighted design matrix (rows: real parts, then
    /// imaginary parts) and data.
    fn design(&self, basis: &[Vec<c64>], j: usize) -> (Mat<f64>, Mat<f64>) {
        let lines = self.lines();
        let columns = basis[0].len();
        let (h, sigma) = (&self.functions.h[j], &self.functions.sigma[j]);
        let a = Mat::<f64>::from_fn(2 * lines, columns, |r, c| {
            let k = r % lines;
            let v = basis[k][c] / sigma[k];
            if r < lines {
                v.re
            } else {
                v.im
            }
        });
        let y = Mat::<f64>::from_fn(2 * lines, 1, |r, _| {
            let k = r % lines;
            let v = h[k] / sigma[k];
            if r < lines {
                v.re
            } else {
                v.im
            }
        });
        (a, y)
    }

    fn evaluate(&self, theta: &[f64]) -> Option<Evaluation> {
        let basis = self.basis(theta);
        let mut evaluation = Evaluation {
            designs: Vec::new(),
            factors: Vec::new(),
            coefficients: Vec::new(),
            residual: Vec::new(),
        };
        for j in 0..self.functions.h.len() {
            let (a, y) = self.design(&basis, j);
            let qr = a.qr();
            let c = qr.solve_lstsq(&y);
            if !c.norm_max().is_finite() {
                return None;
            }
            let r = &y - &a * &c;
            evaluation.residual.extend((0..r.nrows()).map(|i| r[(i, 0)]));
            evaluation.designs.push(a);
            evaluation.factors.push(qr);
            evaluation.coefficients.push(c);
        }
        Some(evaluation)
    }

    fn cost(&self, theta: &[f64]) -> Option<f64> {
        self.evaluate(theta).map(|e| e.cost())
    }

    /// Per parameter (`f_m`, then `ζ_m`, per mode) and line, the derivatives
    /// of mode `m`'s two basis columns, `g + ḡ` and `i(g − ḡ)`:
    /// `∂g/∂θ = g² ∂λ/∂θ`, with `∂λ/∂f = 2π(−ζ + i√(1 − ζ²))` and
    /// `∂λ/∂ζ = −ω(1 + iζ/√(1 − ζ²))`.
    fn basis_derivatives(&self, theta: &[f64]) -> Vec<Vec<(c64, c64)>> {
        let i = c64::new(0.0, 1.0);
        theta
            .chunks(2)
            .flat_map(|p| {
                let (w, zeta) = (2.0 * PI * p[0], p[1]);
                let root = (1.0 - zeta * zeta).sqrt();
                let lambda = c64::new(-zeta * w, w * root);
                let by_frequency = c64::new(-zeta, root) * (2.0 * PI);
                let by_damping = c64::new(-1.0, -zeta / root) * w;
                [by_frequency, by_damping].map(|d_lambda| {
                    self.functions
                        .frequencies_hz
                        .iter()
                        .map(|&f| {
                            let s = c64::new(0.0, 2.0 * PI * f);
                            let g = c64::new(1.0, 0.0) / (s - lambda);
                            let gb = c64::new(1.0, 0.0) / (s - lambda.conj());
                            let (dg, dgb) = (g * g * d_lambda, gb * gb * d_lambda.conj());
                            (dg + dgb, i * (dg - dgb))
                        })
                        .collect()
                })
            })
            .collect()
    }

    /// The Jacobian of the projected residual at `theta` (Kaufman's form,
    /// `−P⊥ ∂A/∂θ c`, per function at its fitted residues `c`), stacked
    /// over the functions as the residual is.
    fn jacobian(&self, theta: &[f64], evaluation: &Evaluation) -> Mat<f64> {
        let lines = self.lines();
        let derivatives = self.basis_derivatives(theta);
        let mut jacobian = Mat::<f64>::zeros(evaluation.residual.len(), theta.len());
        for (j, c) in evaluation.coefficients.iter().enumerate() {
            let sigma = &self.functions.sigma[j];
            // ∂(A c)/∂θ_p: only mode m = p/2's residue α + iβ multiplies its columns.
            let d = Mat::<f64>::from_fn(2 * lines, theta.len(), |r, p| {
                let k = r % lines;
                let m = p / 2;
                let (d_sum, d_difference) = derivatives[p][k];
                let v = (d_sum * c[(2 * m, 0)] + d_difference * c[(2 * m + 1, 0)]) / sigma[k];
                if r < lines {
                    v.re
                } else {
                    v.im
                }
            });
            let a = &evaluation.designs[j];
            let off = &d - a * evaluation.factors[j].solve_lstsq(&d);
            for p in 0..theta.len() {
                for r in 0..2 * lines {
                    jacobian[(j * 2 * lines + r, p)] = -off[(r, p)];
                }
            }
        }
        jacobian
    }

    /// Levenberg–Marquardt on the projected cost from `theta` (kept within
    /// the bounds); returns the iterations taken.
    fn levenberg_marquardt(&self, theta: &mut Vec<f64>) -> Result<usize, PoleResidueError> {
        let mut current = self.evaluate(theta).ok_or(PoleResidueError::Singular)?;
        let mut cost = current.cost();
        let mut mu = 1e-3;
        let n = theta.len();
        for iteration in 1..=200 {
            let jac = self.jacobian(theta, &current);
            let jtj = jac.transpose() * &jac;
            let r = Mat::<f64>::from_fn(current.residual.len(), 1, |i, _| current.residual[i]);
            let gradient = jac.transpose() * &r;
            let mut improved = false;
            for _ in 0..30 {
                let damped = Mat::<f64>::from_fn(n, n, |i, k| {
                    jtj[(i, k)] + if i == k { mu * jtj[(i, i)].max(1e-12) } else { 0.0 }
                });
                let step = damped.partial_piv_lu().solve(&gradient);
                let mut trial: Vec<f64> = theta.iter().enumerate().map(|(i, v)| v - step[(i, 0)]).collect();
                self.clamp(&mut trial);
                match self.evaluate(&trial) {
                    Some(e) if e.cost() < cost => {
                        let c = e.cost();
                        let change = trial
                            .iter()
                            .zip(theta.iter())
                            .map(|(a, b)| (a - b).abs())
                            .fold(0.0, f64::max);
                        let relative = (cost - c) / cost.max(f64::MIN_POSITIVE);
                        *theta = trial;
                        current = e;
                        cost = c;
                        mu = (mu / 3.0).max(1e-12);
                        improved = true;
                        if relative < 1e-12 || change < 1e-10 {
                            return Ok(iteration);
                        }
                        break;
                    }
                    _ => mu *= 4.0,
                }
            }
            if !improved {
                return Ok(iteration);
            }
        }
        Ok(200)
    }

    /// The modes, residues and covariance at the optimum `theta`.
    fn finish(&self, theta: &[f64], iterations: usize) -> Result<PoleResidueFit, PoleResidueError> {
        let evaluation = self.evaluate(theta).ok_or(PoleResidueError::Singular)?;
        let functions = self.functions.h.len();
        let columns = evaluation.coefficients[0].nrows();
        let observations = evaluation.residual.len();
        let parameters = theta.len() + functions * columns;
        let scale = evaluation.cost() / (observations.saturating_sub(parameters).max(1)) as f64;
        // P⊥ ∂(A(θ) c)/∂θ at the fitted residues c, stacked over functions
        // (its sign does not enter the covariance).
        let projected = self.jacobian(theta, &evaluation);
        let information = projected.transpose() * &projected;
        let identity = Mat::<f64>::identity(theta.len(), theta.len());
        let inverse = information.partial_piv_lu().solve(&identity);
        if !inverse.norm_max().is_finite() {
            return Err(PoleResidueError::Singular);
        }
        let edge = |v: f64, (lo, hi): (f64, f64)| (v - lo).abs() <= 1e-9 * hi || (hi - v).abs() <= 1e-9 * hi;
        let mut modes: Vec<FittedMode> = theta
            .chunks(2)
            .enumerate()
            .map(|(m, p)| FittedMode {
                frequency_hz: p[0],
                damping_ratio: p[1],
                frequency_std_hz: (scale * inverse[(2 * m, 2 * m)]).max(0.0).sqrt(),
                damping_std: (scale * inverse[(2 * m + 1, 2 * m + 1)]).max(0.0).sqrt(),
                residues: evaluation
                    .coefficients
                    .iter()
                    .map(|c| c64::new(c[(2 * m, 0)], c[(2 * m + 1, 0)]))
                    .collect(),
                at_bound: edge(p[0], self.band) || edge(p[1], DAMPING_BOUNDS),
            })
            .collect();
        modes.sort_by(|a, b| a.frequency_hz.total_cmp(&b.frequency_hz));
        Ok(PoleResidueFit {
            modes,
            residual_scale: scale,
            iterations,
        })
    }
}

#[cfg(test)]
mod tests;
