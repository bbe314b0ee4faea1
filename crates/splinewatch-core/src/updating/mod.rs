//! FRF-based model updating (paper §3, eq. 35–43), made robust.
//!
//! May import: `identification`, `response`, `solvers`, `model`, `geometry`, `linalg`.
//!
//! Residues `h_x(ω_l) - h_a(ω_l, p)` over the selected lines of every
//! measured FRF are stacked as real and imaginary parts (eq. 36–39) and
//! weighted. Every parameter `p_k` (spring coefficient κ or damping
//! coefficient γ) is confined to `[p_min, p_max]` by eq. (42):
//! `p = p0 + ½(p_min + p_max - 2p0 + (p_max - p_min) sin y) = ½(p_min + p_max)
//! + ½(p_max - p_min) sin y`, and the solver works on the unbounded `y` with
//! the chain rule of eq. (43), `∂h/∂y = ½(p_max - p_min) cos y ∂h/∂p`. Since
//! `y` is dimensionless this also provides the normalisation of eq. (40).
//!
//! The paper iterates the linearised least squares (Gauss–Newton). Here it is
//! damped: Levenberg–Marquardt with Moré's column scaling, step acceptance on
//! the gain ratio and Nielsen's damping update; stopping on the relative
//! change of the cost, the step size or the iteration budget. Plain
//! Gauss–Newton is available for comparison.
//!
//! Residual models: FRF residues ([`frf_residual`]), modal residues of
//! identified modes ([`ModalUpdateProblem`]), or both stacked, each block in
//! its own standard deviations ([`joint`]).
//!
//! Uncertainty: `Cov(p) = σ̂² (J_pᵀ W J_p)⁻¹` with `σ̂² = ‖r_w‖² / (m - n)`,
//! computed through the SVD of the column-normalised weighted Jacobian, whose
//! singular values (and condition number) are reported: a tiny singular
//! value flags a parameter combination the data cannot identify.

use crate::model::damping::{DampingCurve, DampingError};
use crate::response::frf::{FrfError, FrfModel, ModalState};
#[cfg(test)]
use faer::Mat;
use serde::{Deserialize, Serialize};
use thiserror::Error;

mod estimates;
pub mod frf_residual;
pub mod joint;
mod modal;
pub mod modal_residual;
mod solver;
pub mod transmissibility_residual;
pub use modal::{ModalSolution, ModalUpdateProblem};

pub use estimates::REPORTED_CORRELATIONS;
pub use solver::{
    levenberg_marquardt, levenberg_marquardt_continued, levenberg_marquardt_staged, Continuation, Evaluated,
    ResidualModel, Solved,
};
#[cfg(test)]
use solver::{norm2, normal_equations, quadratic, relative_offset, solve_damped};

#[derive(Debug, Clone, PartialEq, Error)]
pub enum UpdateError {
    #[error("measured data: {0}")]
    Data(String),
    #[error("parameter {name}: {reason}")]
    Parameter { name: String, reason: String },
    #[error("no frequency line is left after the band, decimation and exclusions")]
    NoLines,
    #[error("no parameter is selected for updating")]
    NoParameters,
    #[error("{residuals} residuals cannot determine {parameters} parameters")]
    Underdetermined { residuals: usize, parameters: usize },
    #[error("model evaluation failed: {0}")]
    Model(#[from] FrfError),
    #[error("damping: {0}")]
    Damping(#[from] DampingError),
    #[error("the model produced non-finite FRFs at the parameters {0:?}")]
    NonFinite(Vec<f64>),
}

/// What a parameter is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ParameterKind {
    /// Coefficient `coefficient` of spring field `field`.
    Spring { field: usize, coefficient: usize },
    /// Coefficient `coefficient` of the `count` consecutive spring fields
    /// from `field`, all set to the parameter's value (the bearings of one
    /// support line tied together): `∂h/∂p = Σ ∂h/∂κ` over them.
    SpringRun {
        field: usize,
        count: usize,
        coefficient: usize,
    },
    /// Coefficient θ `coefficient` of stiffness field `field` of the deck
    /// ([`crate::model::stiffness_field`]).
    Stiffness { field: usize, coefficient: usize },
    /// Coefficient θ `coefficient` of the `count` consecutive stiffness
    /// fields from `field`, all set to the parameter's value (one modulus
    /// over several patches): `∂h/∂p = Σ ∂h/∂θ` over them.
    StiffnessRun {
        field: usize,
        count: usize,
        coefficient: usize,
    },
    /// Damping coefficient γ_z.
    Damping { coefficient: usize },
    /// The loss factor η of the `count` consecutive spring fields from
    /// `field` (spring fields, bearings or line supports; a run of tied
    /// bearings shares one; [`crate::model::damping`]), all set to the
    /// parameter's value.
    LossFactor { field: usize, count: usize },
}

/// An updating parameter with its bounds.
#[derive(Debug, Clone, PartialEq)]
pub struct Parameter {
    pub name: String,
    pub kind: ParameterKind,
    pub lower: f64,
    pub upper: f64,
}

/// Whether any of `parameters` is a stiffness-field coefficient (whose
/// derivatives are dense over the deck, formed only then).
pub(crate) fn updates_fields(parameters: &[Parameter]) -> bool {
    parameters.iter().any(|p| !p.kind.fields().is_empty())
}

/// The spring coefficients (flat indices, each once) `parameters` move,
/// when a Ritz basis of the start point can serve their search on `model`
/// ([`FrfModel::with_reanalysis`]): the model is truncated and no parameter
/// is a stiffness field (those change the deck everywhere); `None`
/// otherwise.
pub(crate) fn reanalysed_springs(parameters: &[Parameter], model: &FrfModel) -> Option<Vec<usize>> {
    if model.sparse().is_none() || updates_fields(parameters) {
        return None;
    }
    let mut varied: Vec<usize> = parameters
        .iter()
        .flat_map(|p| p.kind.springs())
        .map(|(f, c)| model.flat_spring_index(f, c))
        .collect();
    varied.sort_unstable();
    varied.dedup();
    Some(varied)
}

/// Every parameter names an existing coefficient of `model` and has
/// finite, ordered, non-negative bounds; at least one is updated.
pub(crate) fn check_parameters(
    parameters: &[Parameter],
    kappa: &[Vec<f64>],
    model: &FrfModel,
    damping: &DampingCurve,
) -> Result<(), UpdateError> {
    if parameters.is_empty() {
        return Err(UpdateError::NoParameters);
    }
    let theta = model.field_coefficients();
    for p in parameters {
        let bad = |reason: String| {
            Err(UpdateError::Parameter {
                name: p.name.clone(),
                reason,
            })
        };
        if !(p.lower.is_finite() && p.upper.is_finite() && p.lower < p.upper) {
            return bad(format!(
                "bounds [{}, {}] must be finite with lower < upper",
                p.lower, p.upper
            ));
        }
        match p.kind {
            ParameterKind::Spring { field, coefficient } => {
                if kappa.get(field).is_none_or(|k| coefficient >= k.len()) {
                    return bad("refers to a spring coefficient that does not exist".into());
                }
                if p.lower < 0.0 {
                    return bad("a stiffness lower bound must be non-negative".into());
                }
            }
            ParameterKind::SpringRun {
                field,
                count,
                coefficient,
            } => {
                if count == 0 || (field..field + count).any(|f| kappa.get(f).is_none_or(|k| coefficient >= k.len())) {
                    return bad("refers to a spring coefficient that does not exist".into());
                }
                if p.lower < 0.0 {
                    return bad("a stiffness lower bound must be non-negative".into());
                }
            }
            ParameterKind::Stiffness { .. } | ParameterKind::StiffnessRun { .. } => {
                let fields = p.kind.fields();
                if fields.is_empty() || fields.iter().any(|&(f, c)| theta.get(f).is_none_or(|t| c >= t.len())) {
                    return bad("refers to a stiffness-field coefficient that does not exist".into());
                }
                if p.lower <= 0.0 {
                    return bad("a stiffness multiplier's lower bound must be positive".into());
                }
            }
            ParameterKind::Damping { coefficient } => {
                if coefficient >= damping.coefficients().len() {
                    return bad("refers to a damping coefficient that does not exist".into());
                }
                if p.lower < 0.0 {
                    return bad("a damping lower bound must be non-negative".into());
                }
            }
            ParameterKind::LossFactor { field, count } => {
                if count == 0 || field + count > damping.loss_factors().len() {
                    return bad("refers to a loss factor the damping does not have".into());
                }
                if p.lower < 0.0 {
                    return bad("a loss factor's lower bound must be non-negative".into());
                }
            }
        }
    }
    Ok(())
}

impl ParameterKind {
    /// The spring coefficients `(field, coefficient)` the parameter sets
    /// (none for a stiffness field or damping parameter).
    pub fn springs(self) -> Vec<(usize, usize)> {
        match self {
            Self::Spring { field, coefficient } => vec![(field, coefficient)],
            Self::SpringRun {
                field,
                count,
                coefficient,
            } => (field..field + count).map(|f| (f, coefficient)).collect(),
            Self::Stiffness { .. } | Self::StiffnessRun { .. } | Self::Damping { .. } | Self::LossFactor { .. } => {
                Vec::new()
            }
        }
    }

    /// The stiffness-field coefficients `(field, coefficient)` the
    /// parameter sets (none for a spring or damping parameter).
    pub fn fields(self) -> Vec<(usize, usize)> {
        match self {
            Self::Stiffness { field, coefficient } => vec![(field, coefficient)],
            Self::StiffnessRun {
                field,
                count,
                coefficient,
            } => (field..field + count).map(|f| (f, coefficient)).collect(),
            Self::Spring { .. } | Self::SpringRun { .. } | Self::Damping { .. } | Self::LossFactor { .. } => Vec::new(),
        }
    }
}

/// The base model's spring coefficients and damping curve (`kappa`,
/// `damping`) with `parameters` set to `p`; stiffness-field parameters are
/// set by [`fields_at`].
pub fn model_at(
    parameters: &[Parameter],
    kappa: &[Vec<f64>],
    damping: &DampingCurve,
    p: &[f64],
) -> Result<(Vec<Vec<f64>>, DampingCurve), UpdateError> {
    let mut kappa = kappa.to_vec();
    let mut gamma = damping.coefficients().to_vec();
    let mut eta = damping.loss_factors().to_vec();
    for (par, &v) in parameters.iter().zip(p) {
        match par.kind {
            ParameterKind::Spring { field, coefficient } => kappa[field][coefficient] = v,
            ParameterKind::SpringRun {
                field,
                count,
                coefficient,
            } => {
                for k in &mut kappa[field..field + count] {
                    k[coefficient] = v;
                }
            }
            ParameterKind::Damping { coefficient } => gamma[coefficient] = v,
            ParameterKind::LossFactor { field, count } => eta[field..field + count].fill(v),
            ParameterKind::Stiffness { .. } | ParameterKind::StiffnessRun { .. } => {}
        }
    }
    Ok((kappa, damping.with_coefficients(gamma)?.with_loss_factors(eta)?))
}

/// The base stiffness-field coefficients `theta` with the field
/// parameters among `parameters` set to `p`.
pub fn fields_at(parameters: &[Parameter], theta: &[Vec<f64>], p: &[f64]) -> Vec<Vec<f64>> {
    let mut theta = theta.to_vec();
    for (par, &v) in parameters.iter().zip(p) {
        for (field, coefficient) in par.kind.fields() {
            theta[field][coefficient] = v;
        }
    }
    theta
}

/// The modal state of `model` with `parameters` set to `p` over the base
/// spring coefficients `kappa`, `damping` and the model's own stiffness-field
/// coefficients, with the damping curve there.
pub fn modal_state_at(
    model: &FrfModel,
    parameters: &[Parameter],
    kappa: &[Vec<f64>],
    damping: &DampingCurve,
    p: &[f64],
) -> Result<(ModalState, DampingCurve), UpdateError> {
    let (kappa, damping) = model_at(parameters, kappa, damping, p)?;
    let theta = fields_at(parameters, model.field_coefficients(), p);
    Ok((model.modal_state_with_fields(&kappa, &theta, &damping)?, damping))
}

/// The values `parameters` take in the model given by spring coefficients
/// `kappa` (one vector per field), stiffness-field coefficients `theta` and
/// `damping`.
#[track_caller]
pub fn base_values(
    parameters: &[Parameter],
    kappa: &[Vec<f64>],
    theta: &[Vec<f64>],
    damping: &DampingCurve,
) -> Vec<f64> {
    parameters
        .iter()
        .map(|p| match p.kind {
            ParameterKind::Spring { field, coefficient } | ParameterKind::SpringRun { field, coefficient, .. } => {
                kappa[field][coefficient]
            }
            ParameterKind::Stiffness { field, coefficient }
            | ParameterKind::StiffnessRun { field, coefficient, .. } => theta[field][coefficient],
            ParameterKind::Damping { coefficient } => damping.coefficients()[coefficient],
            ParameterKind::LossFactor { field, .. } => damping.loss_factors()[field],
        })
        .collect()
}

/// Eq. (42): `p(y)`.
pub fn bounded_value(y: f64, lower: f64, upper: f64) -> f64 {
    0.5 * (lower + upper) + 0.5 * (upper - lower) * y.sin()
}

/// Eq. (43): `∂p/∂y`.
pub fn bounded_derivative(y: f64, lower: f64, upper: f64) -> f64 {
    0.5 * (upper - lower) * y.cos()
}

/// Inverse of eq. (42) on `y ∈ [-π/2, π/2]`.
pub fn unbounded_value(p: f64, lower: f64, upper: f64) -> f64 {
    ((2.0 * p - lower - upper) / (upper - lower)).clamp(-1.0, 1.0).asin()
}

/// Residual weighting.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Weighting {
    /// Every residue counts the same (the paper).
    Uniform,
    /// Inverse of the H1 estimator variance `(1 - γ²)/(γ² n_avg) |H|²`
    /// (Bendat & Piersol); needs coherence and the number of averages.
    H1Variance,
}

/// Which frequency lines take part.
#[derive(Debug, Clone, PartialEq)]
pub struct LineSelection {
    /// `[f_min, f_max]` in Hz, inclusive.
    pub band: Option<(f64, f64)>,
    /// Keep every `decimation`-th line of the band (≥ 1).
    pub decimation: usize,
    /// Bands `[a, b]` to leave out (e.g. mains harmonics, known disturbances).
    pub exclude: Vec<(f64, f64)>,
}

impl Default for LineSelection {
    fn default() -> Self {
        Self {
            band: None,
            decimation: 1,
            exclude: Vec::new(),
        }
    }
}

impl LineSelection {
    pub fn select(&self, frequencies_hz: &[f64]) -> Vec<usize> {
        frequencies_hz
            .iter()
            .enumerate()
            .filter(|(_, &f)| self.band.is_none_or(|(a, b)| f >= a && f <= b))
            .filter(|(_, &f)| !self.exclude.iter().any(|&(a, b)| f >= a && f <= b))
            .map(|(i, _)| i)
            .enumerate()
            .filter(|(k, _)| k % self.decimation.max(1) == 0)
            .map(|(_, i)| i)
            .collect()
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    LevenbergMarquardt,
    /// The paper's plain iterated linearised least squares.
    GaussNewton,
}

#[derive(Debug, Clone, PartialEq)]
pub struct UpdateSettings {
    pub method: Method,
    pub max_iterations: usize,
    /// Stop when the relative decrease of the cost in an accepted step is below this.
    pub cost_tolerance: f64,
    /// Stop when `‖Δy‖ ≤ step_tolerance (‖y‖ + step_tolerance)`.
    pub step_tolerance: f64,
    /// Stop when the relative offset of Bates & Watts (1981) is below this:
    /// the full Gauss–Newton step is below this many standard errors, in root
    /// mean square over the parameters (`UpdateResult::relative_offset`).
    pub offset_tolerance: f64,
    pub weighting: Weighting,
    pub lines: LineSelection,
    /// Initial Levenberg–Marquardt damping λ0, relative: steps solve
    /// `(JᵀJ + λ D) s = -Jᵀr` with `D` the largest `diag(JᵀJ)` seen so far
    /// (Moré's scaling), so λ is dimensionless and the iterates do not depend
    /// on the units of the FRFs.
    pub initial_damping: f64,
    /// Threads for the FRF evaluation; the result does not depend on it.
    pub threads: usize,
}

impl Default for UpdateSettings {
    fn default() -> Self {
        Self {
            method: Method::LevenbergMarquardt,
            max_iterations: 50,
            cost_tolerance: 1e-8,
            step_tolerance: 1e-9,
            offset_tolerance: 1e-2,
            weighting: Weighting::Uniform,
            lines: LineSelection::default(),
            initial_damping: 1e-3,
            threads: 1,
        }
    }
}

/// A parameter in the result.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParameterEstimate {
    pub name: String,
    pub value: f64,
    /// One standard deviation; `None` when the parameter is not identifiable.
    pub std: Option<f64>,
    pub lower: f64,
    pub upper: f64,
}

/// One accepted (or, for the start, initial) iterate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct IterationRecord {
    pub iteration: usize,
    pub relative_residual: f64,
    pub cost: f64,
    pub parameters: Vec<f64>,
    /// `‖Δy‖` of the step that led here (0 for the start).
    pub step_norm: f64,
    /// LM damping factor used for that step.
    pub damping: f64,
    /// Trial steps rejected before this one was accepted.
    pub rejected_steps: usize,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    /// The remaining Gauss–Newton step is statistically negligible.
    RelativeOffset,
    CostTolerance,
    StepTolerance,
    ZeroResidual,
    MaxIterations,
    /// No step reduced the cost, even with a very large damping.
    Stalled,
    /// Gauss–Newton produced a step that increased the cost.
    Diverged,
    /// Every parameter was held: the data inform none of them.
    NothingToUpdate,
}

/// Why the solver held a parameter (at its start value, or where it is for
/// [`HoldReason::AtBound`]) instead of updating it: the stop test and the
/// covariance then refer to the parameters the data determine.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum HoldReason {
    /// No residue depends on it: its whole range moves them by less than
    /// 1e-8 of what the most influential parameter's range does (a damping
    /// coefficient whose support holds no identified mode or line).
    NoGradient,
    /// It sits on a bound, where the transform of eq. (42) leaves it no
    /// gradient: held there.
    AtBound,
    /// It loads most on a direction of the column-normalised Jacobian whose
    /// singular value is below 1e-6 of the largest: the data determine only
    /// a combination of it with others.
    Unresolved,
}

/// A parameter the solver held, with the reason and the value it kept.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HeldParameter {
    pub name: String,
    pub reason: HoldReason,
    pub value: f64,
}

/// The correlation of two parameters' estimates, `ρ = C_ab / √(C_aa C_bb)`
/// with `C = σ̂² (JᵀJ)⁻¹`: near ±1 the data cannot tell them apart (a
/// stiffness field trading off against a spring field).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParameterCorrelation {
    pub a: String,
    pub b: String,
    pub rho: f64,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct UpdateResult {
    pub parameters: Vec<ParameterEstimate>,
    pub iterations: Vec<IterationRecord>,
    pub converged: bool,
    pub stop_reason: StopReason,
    /// `‖h_x - h_a‖ / ‖h_x‖` over the selected lines (unweighted).
    pub relative_residual: f64,
    /// The same per measured FRF.
    pub frf_relative_residuals: Vec<f64>,
    /// Singular values of the column-normalised weighted Jacobian, descending.
    pub singular_values: Vec<f64>,
    pub condition_number: f64,
    /// `σ̂²`, the weighted residual variance.
    pub residual_variance: f64,
    /// Relative offset of Bates & Watts (1981) at the returned point: the
    /// full Gauss–Newton step from there in standard errors, root mean square
    /// over the parameters, `√(gᵀA⁻¹g / n) / σ̂`. `None` when `JᵀJ` is singular or the residual is zero.
    pub relative_offset: Option<f64>,
    /// Model evaluations (modes + FRFs) this solve did; a start point reused
    /// from the previous solve is not one.
    pub evaluations: usize,
    pub lines_used: usize,
    /// The most correlated parameter pairs (at most
    /// [`REPORTED_CORRELATIONS`], largest |ρ| first); empty when
    /// `JᵀJ` is singular.
    #[serde(default)]
    pub correlations: Vec<ParameterCorrelation>,
    /// Parameters the data could not inform, held during the solve (their
    /// `std` is `None`); the singular values, condition number, correlations
    /// and `residual_variance` refer to the others.
    #[serde(default)]
    pub held: Vec<HeldParameter>,
    /// `σ̂² (JᵀJ)⁻¹` of the parameters, in their order (held ones' rows and
    /// columns zero); `None` when `JᵀJ` is singular. Not written (the stds
    /// and the correlations are): for propagating the uncertainty to what
    /// the model predicts (e.g. [`modal_residual::frequency_gradient`]).
    #[serde(skip)]
    pub covariance: Option<Vec<Vec<f64>>>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_offset_is_the_gauss_newton_step_in_standard_errors() {
        // Linear model r(p) = b - J p at p = 0: the least-squares point is
        // p* = (JᵀJ)⁻¹Jᵀb, σ̂² = ‖b - J p*‖² / (m - n), and the relative offset
        // must be √(p*ᵀ JᵀJ p* / n) / σ̂.
        let (m, n) = (40, 3);
        let j = Mat::from_fn(m, n, |r, c| {
            ((r * (c + 2)) as f64 * 0.37).sin() + if r % n == c { 2.0 } else { 0.0 }
        });
        let b: Vec<f64> = (0..m).map(|r| 1.0 + 0.1 * (r as f64 * 1.3).cos()).collect();
        // Residual r = b - Jp has Jacobian -J; at p = 0: A = JᵀJ, g = -Jᵀb.
        let (a, g) = normal_equations(&(-&j), &b);
        let cost = 0.5 * norm2(&b);
        let p_star = solve_damped(&a, &g, &[0.0; 3], 0.0).unwrap();
        let fitted: Vec<f64> = (0..m)
            .map(|r| b[r] - (0..n).map(|c| j[(r, c)] * p_star[c]).sum::<f64>())
            .collect();
        let sigma2 = norm2(&fitted) / (m - n) as f64;
        let expected = (quadratic(&a, &p_star) / n as f64).sqrt() / sigma2.sqrt();
        let got = relative_offset(&a, &g, cost, m).unwrap();
        assert!((got - expected).abs() < 1e-10 * expected, "{got} vs {expected}");
        // At the least-squares point itself the offset vanishes.
        let (a0, g0) = normal_equations(&(-&j), &fitted);
        assert!(relative_offset(&a0, &g0, 0.5 * norm2(&fitted), m).unwrap() < 1e-12);
        // Singular A and a zero residual have no offset.
        assert_eq!(relative_offset(&Mat::zeros(3, 3), &[1.0, 0.0, 0.0], 1.0, m), None);
        assert_eq!(relative_offset(&a, &[0.0; 3], 0.0, m), None);
    }

    #[test]
    fn bounded_transform_round_trips_and_stays_inside() {
        for &(lo, hi) in &[(1e7, 5e9), (0.0, 0.2)] {
            for k in 0..=20 {
                let p = lo + (hi - lo) * k as f64 / 20.0;
                let y = unbounded_value(p, lo, hi);
                assert!((bounded_value(y, lo, hi) - p).abs() <= 1e-12 * (hi - lo));
            }
            for y in [-100.0, -3.0, 0.0, 1.0, 7.0, 1e3] {
                let p = bounded_value(y, lo, hi);
                assert!(p >= lo && p <= hi);
                let h = 1e-6;
                let fd = (bounded_value(y + h, lo, hi) - bounded_value(y - h, lo, hi)) / (2.0 * h);
                assert!((fd - bounded_derivative(y, lo, hi)).abs() < 1e-6 * (hi - lo));
            }
        }
    }

    #[test]
    fn line_selection_band_decimation_and_exclusions() {
        let f: Vec<f64> = (1..=100).map(|i| i as f64).collect();
        let sel = LineSelection {
            band: Some((10.0, 40.0)),
            decimation: 2,
            exclude: vec![(20.0, 24.0)],
        };
        let idx = sel.select(&f);
        let freqs: Vec<f64> = idx.iter().map(|&i| f[i]).collect();
        assert_eq!(freqs.first(), Some(&10.0));
        assert!(freqs
            .iter()
            .all(|&x| (10.0..=40.0).contains(&x) && !(20.0..=24.0).contains(&x)));
        assert_eq!(freqs.len(), 13);
    }
}
