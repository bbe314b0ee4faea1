//! FRF-based model updating (paper §3, eq. 35–43), made robust.
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
//! Uncertainty: `Cov(p) = σ̂² (J_pᵀ W J_p)⁻¹` with `σ̂² = ‖r_w‖² / (m - n)`,
//! computed through the SVD of the column-normalised weighted Jacobian, whose
//! singular values (and condition number) are reported: a tiny singular
//! value flags a parameter combination the data cannot identify.

use crate::damping::{DampingCurve, DampingError};
use crate::frf::{FrfError, FrfEvaluation, FrfModel, FrfRequest, ModalState, Quantity};
use crate::linalg::bitwise_equal;
use faer::{c64, Mat};
use serde::{Deserialize, Serialize};
use thiserror::Error;

mod modal;
mod solver;
pub use modal::{ModalSolution, ModalUpdateProblem};

pub use solver::{levenberg_marquardt, Evaluated, ResidualModel, Solved, REPORTED_CORRELATIONS};
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
    /// Coefficient θ `coefficient` of stiffness field `field` of the deck
    /// ([`crate::stiffness_field`]).
    Stiffness { field: usize, coefficient: usize },
    /// Damping coefficient γ_z.
    Damping { coefficient: usize },
}

/// An updating parameter with its bounds.
#[derive(Debug, Clone, PartialEq)]
pub struct Parameter {
    pub name: String,
    pub kind: ParameterKind,
    pub lower: f64,
    pub upper: f64,
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
            ParameterKind::Stiffness { field, coefficient } => {
                if theta.get(field).is_none_or(|t| coefficient >= t.len()) {
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
        }
    }
    Ok(())
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
    for (par, &v) in parameters.iter().zip(p) {
        match par.kind {
            ParameterKind::Spring { field, coefficient } => kappa[field][coefficient] = v,
            ParameterKind::Damping { coefficient } => gamma[coefficient] = v,
            ParameterKind::Stiffness { .. } => {}
        }
    }
    Ok((kappa, damping.with_coefficients(gamma)?))
}

/// The base stiffness-field coefficients `theta` with the field
/// parameters among `parameters` set to `p`.
pub fn fields_at(parameters: &[Parameter], theta: &[Vec<f64>], p: &[f64]) -> Vec<Vec<f64>> {
    let mut theta = theta.to_vec();
    for (par, &v) in parameters.iter().zip(p) {
        if let ParameterKind::Stiffness { field, coefficient } = par.kind {
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
            ParameterKind::Spring { field, coefficient } => kappa[field][coefficient],
            ParameterKind::Stiffness { field, coefficient } => theta[field][coefficient],
            ParameterKind::Damping { coefficient } => damping.coefficients()[coefficient],
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

/// One measured FRF: output and input sensor indices and values per line.
#[derive(Debug, Clone, PartialEq)]
pub struct MeasuredFrf {
    pub output: usize,
    pub input: usize,
    pub values: Vec<c64>,
    /// Ordinary coherence per line, if the estimator provided it.
    pub coherence: Option<Vec<f64>>,
    /// Number of averages behind the estimate, if known.
    pub n_averages: Option<f64>,
}

/// A validated set of measured FRFs on common frequency lines.
#[derive(Debug, Clone, PartialEq)]
pub struct MeasuredSet {
    quantity: Quantity,
    frequencies_hz: Vec<f64>,
    frfs: Vec<MeasuredFrf>,
}

impl MeasuredSet {
    pub fn new(quantity: Quantity, frequencies_hz: Vec<f64>, frfs: Vec<MeasuredFrf>) -> Result<Self, UpdateError> {
        let data = |m: String| Err(UpdateError::Data(m));
        if frequencies_hz.is_empty() {
            return data("frequency_hz is empty".into());
        }
        if let Some(i) = frequencies_hz.iter().position(|f| !(f.is_finite() && *f > 0.0)) {
            return data(format!(
                "frequency_hz[{i}] = {} must be finite and positive",
                frequencies_hz[i]
            ));
        }
        if let Some(i) = (1..frequencies_hz.len()).find(|&i| frequencies_hz[i] <= frequencies_hz[i - 1]) {
            return data(format!("frequency_hz is not strictly increasing at index {i}"));
        }
        if frfs.is_empty() {
            return data("frfs is empty".into());
        }
        let n = frequencies_hz.len();
        for (b, frf) in frfs.iter().enumerate() {
            if frf.values.len() != n {
                return data(format!(
                    "frfs[{b}] has {} values, frequency_hz has {n}",
                    frf.values.len()
                ));
            }
            if let Some(i) = frf.values.iter().position(|v| !(v.re.is_finite() && v.im.is_finite())) {
                return data(format!("frfs[{b}] value {i} is not finite"));
            }
            if let Some(c) = &frf.coherence {
                if c.len() != n {
                    return data(format!(
                        "frfs[{b}].coherence has {} values, frequency_hz has {n}",
                        c.len()
                    ));
                }
                if let Some(i) = c.iter().position(|g| !(g.is_finite() && (0.0..=1.0).contains(g))) {
                    return data(format!("frfs[{b}].coherence[{i}] = {} is not in [0, 1]", c[i]));
                }
            }
            if let Some(na) = frf.n_averages {
                if !(na.is_finite() && na >= 1.0) {
                    return data(format!("frfs[{b}].n_averages = {na} must be at least 1"));
                }
            }
        }
        Ok(Self {
            quantity,
            frequencies_hz,
            frfs,
        })
    }

    pub fn quantity(&self) -> Quantity {
        self.quantity
    }

    pub fn frequencies_hz(&self) -> &[f64] {
        &self.frequencies_hz
    }

    pub fn frfs(&self) -> &[MeasuredFrf] {
        &self.frfs
    }
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
}

/// The model at one parameter point, with its FRFs and sensitivities on an
/// [`UpdateProblem`]'s lines: where a solve ends. Handed to the next
/// warm-started solve ([`UpdateProblem::solve_from`]), whose first point it
/// is when that solve starts from these parameters on the same lines of the
/// same model ([`FrfModel::id`]), it
/// saves the first modal solve and sensitivity evaluation; the result is the
/// same bit for bit as without it.
#[derive(Debug, Clone)]
pub struct ModelPoint {
    model_id: u64,
    kappa: Vec<Vec<f64>>,
    theta: Vec<Vec<f64>>,
    damping: DampingCurve,
    frequencies: Vec<f64>,
    pairs: Vec<(usize, usize)>,
    quantity: Quantity,
    state: ModalState,
    /// With sensitivities.
    frfs: FrfEvaluation,
}

impl ModelPoint {
    /// The modes and modal damping at this point.
    pub fn state(&self) -> &ModalState {
        &self.state
    }

    /// Model FRFs in the measured quantity on the problem's lines,
    /// `[frf * n_lines + line]`.
    pub fn frfs(&self) -> &[c64] {
        &self.frfs.h
    }

    /// Spring coefficients per field at this point.
    pub fn kappa(&self) -> &[Vec<f64>] {
        &self.kappa
    }

    /// Stiffness-field coefficients per field at this point.
    pub fn theta(&self) -> &[Vec<f64>] {
        &self.theta
    }

    /// The damping curve ζ(f) at this point.
    pub fn damping(&self) -> &DampingCurve {
        &self.damping
    }
}

/// What [`UpdateProblem::solve_from`] returns: the result and the model at
/// the returned parameters.
#[derive(Debug, Clone)]
pub struct Solution {
    pub result: UpdateResult,
    pub point: ModelPoint,
}

/// Everything needed to update a model against one measured set.
#[derive(Debug)]
pub struct UpdateProblem<'a> {
    model: &'a FrfModel,
    kappa: Vec<Vec<f64>>,
    damping: DampingCurve,
    parameters: Vec<Parameter>,
    measured: &'a MeasuredSet,
    settings: UpdateSettings,
    lines: Vec<usize>,
    frequencies: Vec<f64>,
    pairs: Vec<(usize, usize)>,
    /// √w per complex residue, `[frf * n_lines + line]`.
    sqrt_weights: Vec<f64>,
}

/// Residues and Jacobian with the model FRFs they came from.
type Evaluation = Evaluated<FrfEvaluation>;

impl<'a> UpdateProblem<'a> {
    /// `kappa` and `damping` (and the model's own stiffness-field
    /// coefficients) give the values of parameters that are not updated;
    /// `parameters` lists the updated ones.
    pub fn new(
        model: &'a FrfModel,
        kappa: Vec<Vec<f64>>,
        damping: DampingCurve,
        parameters: Vec<Parameter>,
        measured: &'a MeasuredSet,
        settings: UpdateSettings,
    ) -> Result<Self, UpdateError> {
        check_parameters(&parameters, &kappa, model, &damping)?;
        for frf in measured.frfs() {
            if frf.output >= model.sensor_count() || frf.input >= model.sensor_count() {
                return Err(UpdateError::Data(
                    "an FRF refers to a sensor the model does not have".into(),
                ));
            }
        }
        let lines = settings.lines.select(measured.frequencies_hz());
        if lines.is_empty() {
            return Err(UpdateError::NoLines);
        }
        let residuals = 2 * lines.len() * measured.frfs().len();
        if residuals <= parameters.len() {
            return Err(UpdateError::Underdetermined {
                residuals,
                parameters: parameters.len(),
            });
        }
        let frequencies = lines.iter().map(|&i| measured.frequencies_hz()[i]).collect();
        let pairs = measured.frfs().iter().map(|f| (f.output, f.input)).collect();
        let mut sqrt_weights = Vec::with_capacity(lines.len() * measured.frfs().len());
        for (b, frf) in measured.frfs().iter().enumerate() {
            for &i in &lines {
                let w = match settings.weighting {
                    Weighting::Uniform => 1.0,
                    Weighting::H1Variance => {
                        let (Some(c), Some(na)) = (&frf.coherence, frf.n_averages) else {
                            return Err(UpdateError::Data(format!(
                                "frfs[{b}]: h1_variance weighting needs coherence and n_averages"
                            )));
                        };
                        // Var(H1) = (1 - γ²)/(γ² n) |H|²; the coherence is floored and
                        // capped so a line with γ² → 1 cannot take all the weight.
                        let g2 = c[i].clamp(1e-3, 1.0 - 1e-6);
                        let magnitude = frf.values[i].norm().max(f64::MIN_POSITIVE);
                        let variance = (1.0 - g2) / (g2 * na) * magnitude * magnitude;
                        1.0 / variance
                    }
                };
                sqrt_weights.push(w.sqrt());
            }
        }
        Ok(Self {
            model,
            kappa,
            damping,
            parameters,
            measured,
            settings,
            lines,
            frequencies,
            pairs,
            sqrt_weights,
        })
    }

    pub fn parameters(&self) -> &[Parameter] {
        &self.parameters
    }

    /// The current value of each parameter in the base model.
    pub fn base_values(&self) -> Vec<f64> {
        base_values(
            &self.parameters,
            &self.kappa,
            self.model.field_coefficients(),
            &self.damping,
        )
    }

    /// Stiffness-field coefficients for parameter values `p`.
    pub fn fields_at(&self, p: &[f64]) -> Vec<Vec<f64>> {
        fields_at(&self.parameters, self.model.field_coefficients(), p)
    }

    /// Spring coefficients and damping curve for parameter values `p`.
    pub fn model_at(&self, p: &[f64]) -> Result<(Vec<Vec<f64>>, DampingCurve), UpdateError> {
        model_at(&self.parameters, &self.kappa, &self.damping, p)
    }

    /// Frequencies of the selected lines.
    pub fn line_frequencies(&self) -> &[f64] {
        &self.frequencies
    }

    /// Index of each selected line on the measured frequency axis.
    pub fn line_indices(&self) -> &[usize] {
        &self.lines
    }

    fn measured_value(&self, frf: usize, line: usize) -> c64 {
        self.measured.frfs()[frf].values[self.lines[line]]
    }

    /// The modal model at parameter values `p`.
    pub fn state_at(&self, p: &[f64]) -> Result<ModalState, UpdateError> {
        Ok(modal_state_at(self.model, &self.parameters, &self.kappa, &self.damping, p)?.0)
    }

    /// The FRFs this problem fits: its selected lines, the measured
    /// `(output, input)` pairs and the quantity.
    pub fn request(&self) -> FrfRequest<'_> {
        FrfRequest {
            frequencies_hz: &self.frequencies,
            pairs: &self.pairs,
            quantity: self.measured.quantity(),
        }
    }

    /// Weighted residual `r = √w (h_x - h_a)` at `p` and, if asked, `∂r/∂p`.
    fn evaluate(&self, p: &[f64], jacobian: bool) -> Result<(ModalState, Evaluation), UpdateError> {
        let state = self.state_at(p)?;
        let evaluation = self.evaluate_state(p, &state, jacobian)?;
        Ok((state, evaluation))
    }

    /// [`Self::evaluate`] for a computed modal state.
    fn evaluate_state(&self, p: &[f64], state: &ModalState, jacobian: bool) -> Result<Evaluation, UpdateError> {
        let mut frfs = self
            .model
            .evaluate_on_threads(state, self.request(), jacobian, self.settings.threads);
        let fields = self
            .parameters
            .iter()
            .any(|p| matches!(p.kind, ParameterKind::Stiffness { .. }));
        if jacobian && fields {
            let (_, damping) = self.model_at(p)?;
            frfs.dh_dtheta = self.model.field_frf_sensitivities(state, &damping, self.request());
        }
        self.weighted(p, frfs, jacobian)
    }

    /// Residual and, if asked, Jacobian from model FRFs (and sensitivities) at `p`.
    fn weighted(&self, p: &[f64], frfs: FrfEvaluation, jacobian: bool) -> Result<Evaluation, UpdateError> {
        let nl = self.lines.len();
        let nb = self.pairs.len();
        let mut residual = Vec::with_capacity(2 * nl * nb);
        for b in 0..nb {
            for l in 0..nl {
                let k = b * nl + l;
                let d = (self.measured_value(b, l) - frfs.h[k]) * self.sqrt_weights[k];
                residual.push(d.re);
                residual.push(d.im);
            }
        }
        if residual.iter().any(|r| !r.is_finite()) {
            return Err(UpdateError::NonFinite(p.to_vec()));
        }
        let mut jac = Mat::<f64>::zeros(0, 0);
        if jacobian {
            jac = Mat::zeros(residual.len(), self.parameters.len());
            for (c, par) in self.parameters.iter().enumerate() {
                let column = match par.kind {
                    ParameterKind::Spring { field, coefficient } => {
                        &frfs.dh_dkappa[self.model.flat_spring_index(field, coefficient)]
                    }
                    ParameterKind::Stiffness { field, coefficient } => {
                        &frfs.dh_dtheta[self.model.flat_field_index(field, coefficient)]
                    }
                    ParameterKind::Damping { coefficient } => &frfs.dh_dgamma[coefficient],
                };
                for k in 0..nl * nb {
                    let d = -column[k] * self.sqrt_weights[k];
                    jac[(2 * k, c)] = d.re;
                    jac[(2 * k + 1, c)] = d.im;
                }
            }
        }
        Ok(Evaluation {
            residual,
            jacobian: jac,
            extra: frfs,
        })
    }

    /// `previous` if it is this model at `p` on this problem's lines.
    fn reusable<'p>(&self, previous: Option<&'p ModelPoint>, p: &[f64]) -> Result<Option<&'p ModelPoint>, UpdateError> {
        let Some(point) = previous else {
            return Ok(None);
        };
        let (kappa, damping) = self.model_at(p)?;
        let theta = self.fields_at(p);
        let matches = point.model_id == self.model.id()
            && point.kappa.len() == kappa.len()
            && point.kappa.iter().zip(&kappa).all(|(a, b)| bitwise_equal(a, b))
            && point.theta.len() == theta.len()
            && point.theta.iter().zip(&theta).all(|(a, b)| bitwise_equal(a, b))
            && bitwise_equal(point.damping.coefficients(), damping.coefficients())
            && bitwise_equal(&point.frequencies, &self.frequencies)
            && point.pairs == self.pairs
            && point.quantity == self.measured.quantity();
        Ok(matches.then_some(point))
    }

    fn point(&self, p: &[f64], state: ModalState, frfs: FrfEvaluation) -> Result<ModelPoint, UpdateError> {
        let (kappa, damping) = self.model_at(p)?;
        Ok(ModelPoint {
            model_id: self.model.id(),
            kappa,
            theta: self.fields_at(p),
            damping,
            frequencies: self.frequencies.clone(),
            pairs: self.pairs.clone(),
            quantity: self.measured.quantity(),
            state,
            frfs,
        })
    }

    fn relative_residuals(&self, h: &[c64]) -> (f64, Vec<f64>) {
        let nl = self.lines.len();
        let (mut num, mut den) = (0.0, 0.0);
        let mut per = Vec::with_capacity(self.pairs.len());
        for b in 0..self.pairs.len() {
            let (mut n, mut d) = (0.0, 0.0);
            for l in 0..nl {
                let x = self.measured_value(b, l);
                n += (x - h[b * nl + l]).norm_sqr();
                d += x.norm_sqr();
            }
            per.push((n / d).sqrt());
            num += n;
            den += d;
        }
        ((num / den).sqrt(), per)
    }

    /// Runs the updating from parameter values `start` (warm start: the
    /// last accepted values). Values on or outside a bound are moved inside
    /// by 1e-6 of the range, where the transform of eq. (42) has a non-zero
    /// derivative.
    #[track_caller]
    pub fn solve(&self, start: &[f64]) -> Result<UpdateResult, UpdateError> {
        Ok(self.solve_from(start, None, &mut |_| {})?.result)
    }

    /// [`solve`](Self::solve), calling `observer` with the start and every
    /// accepted iterate as it happens (progress reporting).
    #[track_caller]
    pub fn solve_observed(
        &self,
        start: &[f64],
        observer: &mut dyn FnMut(&IterationRecord),
    ) -> Result<UpdateResult, UpdateError> {
        Ok(self.solve_from(start, None, observer)?.result)
    }

    /// [`solve_observed`](Self::solve_observed), also returning the model at
    /// the result. `previous` (the point the last solve ended on) is used
    /// instead of evaluating the model at `start` when it is that model on
    /// these lines — the usual warm start; otherwise it is ignored.
    #[track_caller]
    pub fn solve_from(
        &self,
        start: &[f64],
        previous: Option<&ModelPoint>,
        observer: &mut dyn FnMut(&IterationRecord),
    ) -> Result<Solution, UpdateError> {
        assert_eq!(start.len(), self.parameters.len(), "one start value per parameter");
        let solved = solver::levenberg_marquardt(self, start, previous, observer)?;
        let (p, current, cost, stop, converged, offset) = (
            solved.p,
            solved.at,
            solved.cost,
            solved.stop,
            solved.converged,
            solved.offset,
        );
        let (iterations, evaluations) = (solved.iterations, solved.evaluations);
        let (state, frfs) = current.extra;
        let (relative_residual, frf_relative_residuals) = self.relative_residuals(&frfs.h);
        let e = solver::estimates(&self.parameters, &p, &current.jacobian, cost);
        let result = UpdateResult {
            parameters: e.parameters,
            iterations,
            converged,
            stop_reason: stop,
            relative_residual,
            frf_relative_residuals,
            singular_values: e.singular_values,
            condition_number: e.condition_number,
            residual_variance: e.residual_variance,
            relative_offset: offset,
            evaluations,
            lines_used: self.lines.len(),
            correlations: e.correlations,
        };
        let point = self.point(&p, state, frfs)?;
        Ok(Solution { result, point })
    }
}

/// The FRF residues of eq. (36)–(39) as the shared solver's residual model.
impl ResidualModel for UpdateProblem<'_> {
    type Extra = (ModalState, FrfEvaluation);
    type Previous = ModelPoint;

    fn parameters(&self) -> &[Parameter] {
        &self.parameters
    }

    fn settings(&self) -> &UpdateSettings {
        &self.settings
    }

    fn first(&self, p: &[f64], previous: Option<&ModelPoint>) -> Result<(Evaluated<Self::Extra>, usize), UpdateError> {
        let (state, evaluation, evaluations) = match self.reusable(previous, p)? {
            Some(point) => (point.state.clone(), self.weighted(p, point.frfs.clone(), true)?, 0),
            None => {
                let (state, evaluation) = self.evaluate(p, true)?;
                (state, evaluation, 1)
            }
        };
        Ok((evaluated(state, evaluation), evaluations))
    }

    fn residual(&self, p: &[f64]) -> Result<Evaluated<Self::Extra>, UpdateError> {
        let state = self.state_at(p)?;
        let evaluation = self.evaluate_state(p, &state, false)?;
        Ok(evaluated(state, evaluation))
    }

    fn with_jacobian(&self, p: &[f64], trial: Evaluated<Self::Extra>) -> Result<Evaluated<Self::Extra>, UpdateError> {
        let (state, _) = trial.extra;
        let evaluation = self.evaluate_state(p, &state, true)?;
        Ok(evaluated(state, evaluation))
    }

    fn relative_residual(&self, at: &Evaluated<Self::Extra>) -> f64 {
        self.relative_residuals(&at.extra.1.h).0
    }
}

fn evaluated(state: ModalState, evaluation: Evaluation) -> Evaluated<(ModalState, FrfEvaluation)> {
    Evaluated {
        residual: evaluation.residual,
        jacobian: evaluation.jacobian,
        extra: (state, evaluation.extra),
    }
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

    #[test]
    fn measured_set_rejects_bad_data() {
        let frf = |n: usize| MeasuredFrf {
            output: 0,
            input: 0,
            values: vec![c64::new(1.0, 0.0); n],
            coherence: None,
            n_averages: None,
        };
        let q = Quantity::Accelerance;
        assert!(MeasuredSet::new(q, vec![1.0, 2.0], vec![frf(2)]).is_ok());
        let e = MeasuredSet::new(q, vec![1.0, 2.0], vec![frf(3)])
            .unwrap_err()
            .to_string();
        assert!(e.contains("frfs[0] has 3 values"), "{e}");
        let e = MeasuredSet::new(q, vec![2.0, 1.0], vec![frf(2)])
            .unwrap_err()
            .to_string();
        assert!(e.contains("not strictly increasing at index 1"), "{e}");
        let mut nan = frf(2);
        nan.values[1] = c64::new(f64::NAN, 0.0);
        let e = MeasuredSet::new(q, vec![1.0, 2.0], vec![nan]).unwrap_err().to_string();
        assert!(e.contains("value 1 is not finite"), "{e}");
        let e = MeasuredSet::new(q, vec![1.0, f64::INFINITY], vec![frf(2)])
            .unwrap_err()
            .to_string();
        assert!(e.contains("frequency_hz[1]"), "{e}");
    }
}
