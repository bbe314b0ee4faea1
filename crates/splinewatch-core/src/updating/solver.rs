//! The bounded Levenberg–Marquardt solver shared by every residual model
//! (FRF residues, modal residues): eq. (40)–(43) with Moré's column scaling,
//! gain-ratio acceptance, Nielsen's damping update and the stopping rules of
//! [`UpdateSettings`]. A residual model only says how to evaluate residues
//! and their Jacobian; the loop and the bounds transform are here, once
//! (the estimates' uncertainty in [`super::estimates`]).

use super::estimates::estimates;
use super::{
    bounded_derivative, bounded_value, unbounded_value, HoldReason, IterationRecord, Method, Parameter, StopReason,
    UpdateError, UpdateResult, UpdateSettings,
};
use faer::{Mat, Side};

/// Residues (and the Jacobian `∂r/∂p` when asked) at one parameter point,
/// with whatever else the model computed there (`extra`: the modal state,
/// the FRFs…).
#[derive(Debug, Clone)]
pub struct Evaluated<E> {
    pub residual: Vec<f64>,
    /// `residual.len() × parameters`; empty when not asked for.
    pub jacobian: Mat<f64>,
    pub extra: E,
}

/// What the solver needs of a residual model; it minimises `½‖r(p)‖²` over
/// the bounded parameters.
pub trait ResidualModel {
    /// What an evaluation carries besides the residues.
    type Extra;
    /// A previous solution the first evaluation may reuse (warm start).
    type Previous;
    fn parameters(&self) -> &[Parameter];
    fn settings(&self) -> &UpdateSettings;
    /// The first point, with its Jacobian, and the model evaluations it cost
    /// (0 when `previous` is that point).
    fn first(
        &self,
        p: &[f64],
        previous: Option<&Self::Previous>,
    ) -> Result<(Evaluated<Self::Extra>, usize), UpdateError>;
    /// Residues only (a trial step).
    fn residual(&self, p: &[f64]) -> Result<Evaluated<Self::Extra>, UpdateError>;
    /// The Jacobian added to an accepted trial.
    fn with_jacobian(&self, p: &[f64], trial: Evaluated<Self::Extra>) -> Result<Evaluated<Self::Extra>, UpdateError>;
    /// The unweighted relative residual reported per iteration.
    fn relative_residual(&self, at: &Evaluated<Self::Extra>) -> f64;
}

/// Where the solver stopped and how it got there.
#[derive(Debug, Clone)]
pub struct Solved<E> {
    pub p: Vec<f64>,
    pub at: Evaluated<E>,
    pub iterations: Vec<IterationRecord>,
    pub converged: bool,
    pub stop: StopReason,
    pub cost: f64,
    pub offset: Option<f64>,
    pub evaluations: usize,
    /// Per parameter, why it was held (`None`: free).
    pub held: Vec<Option<HoldReason>>,
    /// The search's state where it stopped, to go on from
    /// ([`levenberg_marquardt_continued`]).
    pub continuation: Continuation,
}

/// Where a search stopped and what it learnt that the next one from there
/// should not learn again: the damping and Moré's column scales (a restart with the
/// initial damping spends its first evaluations on rejected steps before it
/// finds the damping again), and the held parameters.
#[derive(Debug, Clone)]
pub struct Continuation {
    /// The iterations done: the next search numbers on from here and has
    /// what is left of `max_iterations`.
    iteration: usize,
    p: Vec<f64>,
    y: Vec<f64>,
    damping: f64,
    scale: Vec<f64>,
    held: Vec<Option<HoldReason>>,
}

/// How well a residual model fits at a solution, for its [`UpdateResult`].
pub(super) struct FitMeasures {
    /// The unweighted relative residual ([`ResidualModel::relative_residual`]).
    pub(super) relative_residual: f64,
    /// Per block: per measured FRF, or per paired mode.
    pub(super) per_block: Vec<f64>,
    /// Frequency lines (FRF residues) or pairs (modal residues) used.
    pub(super) lines_used: usize,
}

impl<E> Solved<E> {
    /// This solve continued from `earlier`, which ended where this one
    /// started ([`levenberg_marquardt_continued`]): `earlier`'s history, then
    /// this one's (its start replacing `earlier`'s last record: the same
    /// point, evaluated again), the evaluations of both.
    #[must_use]
    pub fn after<F>(mut self, earlier: Solved<F>) -> Self {
        let mut iterations = earlier.iterations;
        iterations.pop();
        iterations.append(&mut self.iterations);
        self.iterations = iterations;
        self.evaluations += earlier.evaluations;
        self
    }

    /// The [`UpdateResult`] of this solve (the estimates at its point, its
    /// history and stop) with the model's `fit`; its point and evaluation
    /// are handed back.
    pub(super) fn into_result(
        self,
        parameters: &[Parameter],
        fit: FitMeasures,
    ) -> (UpdateResult, Vec<f64>, Evaluated<E>) {
        let e = estimates(parameters, &self.p, &self.at.jacobian, self.cost, &self.held);
        let result = UpdateResult {
            parameters: e.parameters,
            iterations: self.iterations,
            converged: self.converged,
            stop_reason: self.stop,
            relative_residual: fit.relative_residual,
            frf_relative_residuals: fit.per_block,
            singular_values: e.singular_values,
            condition_number: e.condition_number,
            residual_variance: e.residual_variance,
            relative_offset: self.offset,
            evaluations: self.evaluations,
            lines_used: fit.lines_used,
            correlations: e.correlations,
            held: e.held,
            covariance: e.covariance,
        };
        (result, self.p, self.at)
    }
}

/// Runs the bounded LM from `start` (warm start: values on or outside a
/// bound are moved inside by 1e-6 of the range, where the transform of eq.
/// (42) has a non-zero derivative).
#[track_caller]
pub fn levenberg_marquardt<M: ResidualModel>(
    model: &M,
    start: &[f64],
    previous: Option<&M::Previous>,
    observer: &mut dyn FnMut(&IterationRecord),
) -> Result<Solved<M::Extra>, UpdateError> {
    assert_eq!(start.len(), model.parameters().len(), "one start value per parameter");
    let search = Search::start(model, start, previous)?;
    search.run(observer)
}

/// [`levenberg_marquardt`] from where a search (of this model or another
/// with the same parameters) stopped, `continuation`: its point, damping,
/// column scales and held parameters carried over, its iterations counted
/// (the two share `max_iterations`, and this one's records number on).
#[track_caller]
pub fn levenberg_marquardt_continued<M: ResidualModel>(
    model: &M,
    continuation: &Continuation,
    observer: &mut dyn FnMut(&IterationRecord),
) -> Result<Solved<M::Extra>, UpdateError> {
    assert_eq!(
        continuation.y.len(),
        model.parameters().len(),
        "a continuation of these parameters"
    );
    // Exactly where the search stopped (no margin from the bounds: a
    // parameter held on its bound stays there).
    let mut search = Search::begin(model, (continuation.p.clone(), continuation.y.clone()), None)?;
    search.iteration = continuation.iteration;
    search.iterations[0].iteration = continuation.iteration;
    if model.settings().method == Method::LevenbergMarquardt {
        search.lambda = continuation.damping;
    }
    for (s, &c) in search.scale.iter_mut().zip(&continuation.scale) {
        *s = s.max(c);
    }
    for (h, c) in search.held.iter_mut().zip(&continuation.held) {
        if h.is_none() {
            *h = *c;
        }
    }
    search.hold_uninformed()?;
    search.run(observer)
}

/// The search on `coarse`, a cheaper approximation of `complete` with the
/// same parameters (a Ritz basis of the start point,
/// [`crate::solvers::reanalysis`]), from `start`, then on `complete` from
/// where it stopped ([`levenberg_marquardt_continued`]) until the stopping
/// rules hold there: the point, its evaluation and the uncertainty are
/// `complete`'s; the history and the evaluations both stages'.
pub fn levenberg_marquardt_staged<C: ResidualModel, M: ResidualModel>(
    coarse: &C,
    complete: &M,
    start: &[f64],
    observer: &mut dyn FnMut(&IterationRecord),
) -> Result<Solved<M::Extra>, UpdateError> {
    let first = levenberg_marquardt(coarse, start, None, observer)?;
    Ok(levenberg_marquardt_continued(complete, &first.continuation, observer)?.after(first))
}

/// The state of one Levenberg–Marquardt search: the point in the bounded
/// parameters `p` and their unbounded images `y` (eq. 42), the evaluation
/// there, the normal equations of the chained Jacobian (eq. 43) and the
/// damping.
struct Search<'m, M: ResidualModel> {
    model: &'m M,
    bounds: Vec<(f64, f64)>,
    p: Vec<f64>,
    y: Vec<f64>,
    current: Evaluated<M::Extra>,
    cost: f64,
    /// `JᵀJ` and `Jᵀr` in `y`.
    a: Mat<f64>,
    g: Vec<f64>,
    offset: Option<f64>,
    /// The residual count at the start (the relative offset's `m`).
    m: usize,
    lambda: f64,
    nu: f64,
    /// Moré's column scaling: the largest diagonal of `JᵀJ` seen.
    scale: Vec<f64>,
    /// Steps rejected since the last accepted one.
    rejected: usize,
    iteration: usize,
    evaluations: usize,
    iterations: Vec<IterationRecord>,
    /// Per parameter, why it is held (sticky for the solve); held
    /// parameters take no step and leave the stop test and the covariance.
    held: Vec<Option<HoldReason>>,
    /// The values held parameters return to (the start, after the margin).
    start_p: Vec<f64>,
}

impl<'m, M: ResidualModel> Search<'m, M> {
    fn start(model: &'m M, start: &[f64], previous: Option<&M::Previous>) -> Result<Self, UpdateError> {
        let bounds: Vec<(f64, f64)> = model.parameters().iter().map(|p| (p.lower, p.upper)).collect();
        // The model is evaluated at the start values themselves (not at
        // p(y(start)), which differs in the last bits), so that a warm start
        // lands exactly on the point the previous solve ended on.
        let p: Vec<f64> = start
            .iter()
            .zip(&bounds)
            .map(|(&p, &(a, b))| {
                let margin = 1e-6 * (b - a);
                p.clamp(a + margin, b - margin)
            })
            .collect();
        let y: Vec<f64> = p
            .iter()
            .zip(&bounds)
            .map(|(&p, &(a, b))| unbounded_value(p, a, b))
            .collect();
        Self::begin(model, (p, y), previous)
    }

    /// The search from the point `p` with its unbounded image `y`.
    fn begin(model: &'m M, (p, y): (Vec<f64>, Vec<f64>), previous: Option<&M::Previous>) -> Result<Self, UpdateError> {
        let bounds: Vec<(f64, f64)> = model.parameters().iter().map(|p| (p.lower, p.upper)).collect();
        let settings = model.settings();
        let (current, evaluations) = model.first(&p, previous)?;
        let cost = 0.5 * norm2(&current.residual);
        let iterations = vec![IterationRecord {
            iteration: 0,
            relative_residual: model.relative_residual(&current),
            cost,
            parameters: p.clone(),
            step_norm: 0.0,
            damping: 0.0,
            rejected_steps: 0,
        }];
        let jy = chain(&current.jacobian, &y, &bounds);
        let (a, g) = normal_equations(&jy, &current.residual);
        let lambda = match settings.method {
            Method::LevenbergMarquardt => settings.initial_damping,
            Method::GaussNewton => 0.0,
        };
        let scale: Vec<f64> = (0..y.len()).map(|i| a[(i, i)]).collect();
        let m = current.residual.len();
        let n = y.len();
        let mut search = Self {
            model,
            bounds,
            y,
            current,
            cost,
            a,
            g,
            offset: None,
            m,
            lambda,
            nu: 2.0,
            scale,
            rejected: 0,
            iteration: 0,
            evaluations,
            iterations,
            held: vec![None; n],
            start_p: p.clone(),
            p,
        };
        search.hold_uninformed()?;
        Ok(search)
    }

    /// Iterates until a stopping rule holds or the iterations run out.
    fn run(mut self, observer: &mut dyn FnMut(&IterationRecord)) -> Result<Solved<M::Extra>, UpdateError> {
        observer(&self.iterations[0]);
        let (mut stop, mut converged) = (StopReason::MaxIterations, false);
        while self.iteration < self.model.settings().max_iterations {
            if let Some((reason, done)) = self.step(observer)? {
                (stop, converged) = (reason, done);
                break;
            }
        }
        Ok(Solved {
            continuation: Continuation {
                iteration: self.iteration,
                p: self.p.clone(),
                y: self.y,
                damping: self.lambda,
                scale: self.scale,
                held: self.held.clone(),
            },
            p: self.p,
            at: self.current,
            iterations: self.iterations,
            converged,
            stop,
            cost: self.cost,
            offset: self.offset,
            evaluations: self.evaluations,
            held: self.held,
        })
    }

    /// `A = JᵀJ`, `g = Jᵀr` of the chained Jacobian (eq. 43) at the current point.
    fn refresh_normal_equations(&mut self) {
        let jy = chain(&self.current.jacobian, &self.y, &self.bounds);
        (self.a, self.g) = normal_equations(&jy, &self.current.residual);
    }

    /// A step this short (in `y`) resolves no better point.
    fn within_step_tolerance(&self, step_norm: f64) -> bool {
        let settings = self.model.settings();
        step_norm <= settings.step_tolerance * (norm2(&self.y).sqrt() + settings.step_tolerance)
    }

    /// The indices of the free (not held) parameters.
    fn free(&self) -> Vec<usize> {
        (0..self.held.len()).filter(|&k| self.held[k].is_none()).collect()
    }

    /// `A` and `g` on the free parameters.
    fn free_normal_equations(&self, free: &[usize]) -> (Mat<f64>, Vec<f64>) {
        let a = Mat::from_fn(free.len(), free.len(), |i, j| self.a[(free[i], free[j])]);
        (a, free.iter().map(|&k| self.g[k]).collect())
    }

    /// Holds the parameters the data cannot inform at the current point
    /// (see [`HoldReason`]), moves those that must return to their start
    /// value there (one more evaluation), and forms the relative offset on
    /// the free parameters. With nothing held every number is the one of the
    /// plain search.
    fn hold_uninformed(&mut self) -> Result<(), UpdateError> {
        loop {
            let reset = self.find_holds();
            if !reset.is_empty() {
                for &k in &reset {
                    let (lo, hi) = self.bounds[k];
                    self.p[k] = self.start_p[k];
                    self.y[k] = unbounded_value(self.p[k], lo, hi);
                }
                let trial = self.model.residual(&self.p)?;
                self.current = self.model.with_jacobian(&self.p, trial)?;
                self.evaluations += 1;
                self.cost = 0.5 * norm2(&self.current.residual);
                self.refresh_normal_equations();
                continue;
            }
            let free = self.free();
            let (a, g) = self.free_normal_equations(&free);
            self.offset = relative_offset(&a, &g, self.cost, self.m);
            return Ok(());
        }
    }

    /// Marks newly held parameters; returns those whose value must go back
    /// to the start (the moved ones held for no gradient or as unresolved).
    fn find_holds(&mut self) -> Vec<usize> {
        let j = &self.current.jacobian;
        let n = self.held.len();
        if j.ncols() != n {
            return Vec::new();
        }
        // Each column of ∂r/∂p times its half range: how much the whole
        // range of the parameter moves the residues (dimensionless, so
        // parameters of every kind compare).
        let reach: Vec<f64> = (0..n)
            .map(|k| {
                let half = 0.5 * (self.bounds[k].1 - self.bounds[k].0);
                half * (0..j.nrows()).map(|r| j[(r, k)].powi(2)).sum::<f64>().sqrt()
            })
            .collect();
        let largest = reach.iter().copied().filter(|v| v.is_finite()).fold(0.0, f64::max);
        let mut reset = Vec::new();
        for k in 0..n {
            if self.held[k].is_some() {
                continue;
            }
            let (lo, hi) = self.bounds[k];
            // A NaN reach is no gradient either.
            let informed = reach[k] > NO_GRADIENT * largest;
            if !informed {
                self.held[k] = Some(HoldReason::NoGradient);
                if self.p[k] != self.start_p[k] {
                    reset.push(k);
                }
            } else if bounded_derivative(self.y[k], lo, hi).abs() <= BOUND_SLOPE * 0.5 * (hi - lo) {
                self.held[k] = Some(HoldReason::AtBound);
            }
        }
        while let Some(k) = self.unresolved() {
            self.held[k] = Some(HoldReason::Unresolved);
            if self.p[k] != self.start_p[k] {
                reset.push(k);
            }
        }
        reset
    }

    /// The free parameter that loads most on a direction of the
    /// column-normalised Jacobian (in `y`) whose singular value is below
    /// [`UNRESOLVED`] of the largest, if any.
    fn unresolved(&self) -> Option<usize> {
        let free = self.free();
        if free.len() < 2 {
            return None;
        }
        // The column-normalised `Jᵀ J` in `y` on the free parameters: its
        // eigenvalues are the squares of the normalised Jacobian's singular
        // values (a `p × p` problem instead of an SVD of the tall `J`; the
        // ratio at the threshold, 1e-12, is resolved to ~1e-4 relative).
        let a = &self.a;
        let gram = Mat::from_fn(free.len(), free.len(), |i, j| {
            let (k, l) = (free[i], free[j]);
            a[(k, l)] / (a[(k, k)] * a[(l, l)]).sqrt()
        });
        let eigen = gram.self_adjoint_eigen(Side::Lower).ok()?;
        let values = eigen.S().column_vector();
        let (smallest, largest) = (values[0].max(0.0), values[free.len() - 1]);
        if !(smallest.is_finite() && largest.is_finite()) || smallest > UNRESOLVED * UNRESOLVED * largest {
            return None;
        }
        let v = eigen.U();
        (0..free.len())
            .max_by(|&a, &b| v[(a, 0)].abs().total_cmp(&v[(b, 0)].abs()))
            .map(|c| free[c])
    }

    /// One trial step: `Some((reason, converged))` when the search stops.
    fn step(&mut self, observer: &mut dyn FnMut(&IterationRecord)) -> Result<Option<(StopReason, bool)>, UpdateError> {
        let settings = self.model.settings();
        if self.cost == 0.0 {
            return Ok(Some((StopReason::ZeroResidual, true)));
        }
        if self.offset.is_some_and(|o| o < settings.offset_tolerance) {
            return Ok(Some((StopReason::RelativeOffset, true)));
        }
        for i in 0..self.y.len() {
            self.scale[i] = self.scale[i].max(self.a[(i, i)]);
        }
        let free = self.free();
        if free.is_empty() {
            return Ok(Some((StopReason::NothingToUpdate, true)));
        }
        let (a, g) = self.free_normal_equations(&free);
        let scale: Vec<f64> = free.iter().map(|&k| self.scale[k]).collect();
        let Some(free_step) = solve_damped(&a, &g, &scale, self.lambda) else {
            self.lambda = (self.lambda * self.nu).max(1e-12);
            self.nu *= 2.0;
            // A system no damping makes positive definite (a NaN in the
            // Jacobian): stop rather than loop.
            if self.lambda > 1e16 {
                return Ok(Some((StopReason::Stalled, false)));
            }
            return Ok(None);
        };
        let mut step = vec![0.0; self.y.len()];
        for (&k, s) in free.iter().zip(free_step) {
            step[k] = s;
        }
        let y_new: Vec<f64> = self.y.iter().zip(&step).map(|(y, s)| y + s).collect();
        self.evaluations += 1;
        // Residual only: the Jacobian is computed once a step is accepted.
        let p_new: Vec<f64> = y_new
            .iter()
            .zip(&self.bounds)
            .map(|(&y, &(a, b))| bounded_value(y, a, b))
            .collect();
        // A trial that fails to evaluate counts as a rejected step.
        let (trial, new_cost) = match self.model.residual(&p_new) {
            Ok(t) => {
                let c = 0.5 * norm2(&t.residual);
                (Some(t), c)
            }
            Err(UpdateError::NonFinite(_)) | Err(UpdateError::Model(_)) => (None, f64::INFINITY),
            Err(e) => return Err(e),
        };
        // Predicted decrease of the linear model: -gᵀs - ½ sᵀAs.
        let predicted = -dot(&self.g, &step) - 0.5 * quadratic(&self.a, &step);
        let rho = (self.cost - new_cost) / predicted.max(f64::MIN_POSITIVE);
        let accept = match settings.method {
            Method::LevenbergMarquardt => rho > 1e-4,
            Method::GaussNewton => trial.is_some(),
        };
        if !accept {
            self.rejected += 1;
            // As in MINPACK, a trust region shrunk below the step tolerance
            // means no better point is resolvable: converged.
            if self.within_step_tolerance(norm2(&step).sqrt()) {
                return Ok(Some((StopReason::StepTolerance, true)));
            }
            self.lambda *= self.nu;
            self.nu *= 2.0;
            if self.lambda > 1e16 {
                return Ok(Some((StopReason::Stalled, false)));
            }
            return Ok(None);
        }
        let trial = self
            .model
            .with_jacobian(&p_new, trial.expect("accepted steps evaluated"))?;
        let accepted = Accepted {
            y: y_new,
            p: p_new,
            at: trial,
            cost: new_cost,
            step_norm: norm2(&step).sqrt(),
            rho,
        };
        self.accept(accepted, observer)
    }

    /// Moves to an accepted point, records the iteration, updates the
    /// damping (Nielsen) and applies the stopping rules.
    fn accept(
        &mut self,
        accepted: Accepted<M::Extra>,
        observer: &mut dyn FnMut(&IterationRecord),
    ) -> Result<Option<(StopReason, bool)>, UpdateError> {
        let settings = self.model.settings();
        self.iteration += 1;
        let relative_decrease = (self.cost - accepted.cost) / self.cost;
        let diverged = accepted.cost > self.cost;
        self.y = accepted.y;
        self.p = accepted.p;
        self.current = accepted.at;
        self.cost = accepted.cost;
        self.iterations.push(IterationRecord {
            iteration: self.iteration,
            relative_residual: self.model.relative_residual(&self.current),
            cost: self.cost,
            parameters: self.p.clone(),
            step_norm: accepted.step_norm,
            damping: self.lambda,
            rejected_steps: self.rejected,
        });
        observer(self.iterations.last().expect("just pushed"));
        self.rejected = 0;
        self.refresh_normal_equations();
        self.hold_uninformed()?;
        if settings.method == Method::LevenbergMarquardt {
            self.lambda *= (1.0f64 / 3.0).max(1.0 - (2.0 * accepted.rho - 1.0).powi(3));
            self.nu = 2.0;
        }
        // A change within the tolerance, up or down, is convergence; only a
        // real increase means Gauss–Newton diverged.
        if relative_decrease.abs() < settings.cost_tolerance {
            return Ok(Some((StopReason::CostTolerance, true)));
        }
        if diverged {
            return Ok(Some((StopReason::Diverged, false)));
        }
        if self.within_step_tolerance(accepted.step_norm) {
            return Ok(Some((StopReason::StepTolerance, true)));
        }
        Ok(None)
    }
}

/// An accepted trial step: the new point, its evaluation with the
/// Jacobian, its cost, the step's length and its gain ratio.
struct Accepted<E> {
    y: Vec<f64>,
    p: Vec<f64>,
    at: Evaluated<E>,
    cost: f64,
    step_norm: f64,
    rho: f64,
}

/// A parameter whose whole range moves the residues by less than this
/// fraction of what the most influential parameter's range does has no
/// gradient: no residue depends on it (a damping coefficient whose support
/// holds no identified mode).
const NO_GRADIENT: f64 = 1e-8;

/// `|dp/dy| / ½(p_max − p_min) = |cos y|` below this: the parameter sits on
/// its bound (within 5e-7 of its range), where eq. (42) gives it no gradient.
const BOUND_SLOPE: f64 = 1e-3;

/// A direction of the column-normalised Jacobian with a singular value below
/// this fraction of the largest is not determined by the data (a condition
/// number of 10⁶; the covariance's own cut is 10¹²).
const UNRESOLVED: f64 = 1e-6;

/// `∂r/∂y = ∂r/∂p · dp/dy` column by column (eq. 43).
fn chain(jp: &Mat<f64>, y: &[f64], bounds: &[(f64, f64)]) -> Mat<f64> {
    let dp_dy: Vec<f64> = y
        .iter()
        .zip(bounds)
        .map(|(&y, &(a, b))| bounded_derivative(y, a, b))
        .collect();
    Mat::from_fn(jp.nrows(), y.len(), |r, c| jp[(r, c)] * dp_dy[c])
}

pub(super) fn norm2(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum()
}

pub(super) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

pub(super) fn quadratic(a: &Mat<f64>, s: &[f64]) -> f64 {
    (0..s.len())
        .map(|i| s[i] * (0..s.len()).map(|j| a[(i, j)] * s[j]).sum::<f64>())
        .sum()
}

/// Relative offset of Bates & Watts (1981, Technometrics 23(2)):
/// `√(‖P r‖² / n) / √(‖(I - P) r‖² / (m - n))` with `P` the projection on the
/// columns of `J`, i.e. the length of the full Gauss–Newton step
/// `δ = -A⁻¹g` measured in standard errors, `√(δᵀAδ / n) / σ̂`, since
/// `‖P r‖² = gᵀA⁻¹g`. Below 0.01 the remaining step is a hundredth of a
/// standard error in root mean square over the `n` directions (no single
/// parameter moves by more than `√n / 100` of its standard deviation), far
/// below the statistical uncertainty, so further iterations change nothing
/// that matters. Invariant to the parametrisation (`y` or `p`). `None` when `A`
/// is singular or the residual vanishes.
pub(super) fn relative_offset(a: &Mat<f64>, g: &[f64], cost: f64, m: usize) -> Option<f64> {
    let n = g.len();
    let step = solve_damped(a, g, &vec![0.0; n], 0.0)?;
    let projected = -dot(g, &step);
    let unexplained = 2.0 * cost - projected;
    let usable = m > n && projected.is_finite() && projected >= 0.0 && unexplained > 0.0;
    if !usable {
        return None;
    }
    Some((projected / n as f64).sqrt() / (unexplained / (m - n) as f64).sqrt())
}

/// `A = JᵀJ`, `g = Jᵀr` (gradient of ½‖r‖²).
pub(super) fn normal_equations(j: &Mat<f64>, r: &[f64]) -> (Mat<f64>, Vec<f64>) {
    let a = j.transpose() * j;
    let g = (0..j.ncols())
        .map(|c| (0..j.nrows()).map(|k| j[(k, c)] * r[k]).sum())
        .collect();
    (a, g)
}

/// Solves `(A + λ diag(scale)) s = -g` by Cholesky; `None` if not positive definite.
pub(super) fn solve_damped(a: &Mat<f64>, g: &[f64], scale: &[f64], lambda: f64) -> Option<Vec<f64>> {
    let n = g.len();
    let m = Mat::from_fn(n, n, |i, j| a[(i, j)] + if i == j { lambda * scale[i] } else { 0.0 });
    let llt = m.llt(Side::Lower).ok()?;
    let rhs = Mat::from_fn(n, 1, |i, _| -g[i]);
    let s = faer::prelude::Solve::solve(&llt, &rhs);
    let s: Vec<f64> = (0..n).map(|i| s[(i, 0)]).collect();
    s.iter().all(|v| v.is_finite()).then_some(s)
}
