//! The FRF residual model of paper §3: measured FRFs on common lines
//! ([`MeasuredSet`]), their weighted residues against the model's and the
//! Jacobian through the FRF sensitivities (eq. 36–39, 43), solved by the
//! shared Levenberg–Marquardt loop ([`super::levenberg_marquardt`]).

use super::solver;
use super::{
    base_values, check_parameters, fields_at, modal_state_at, model_at, Evaluated, IterationRecord, Parameter,
    ParameterKind, ResidualModel, UpdateError, UpdateResult, UpdateSettings, Weighting,
};
use crate::linalg::bitwise_equal;
use crate::model::damping::DampingCurve;
use crate::response::frf::{FrfEvaluation, FrfModel, FrfRequest, ModalState, Quantity};
use faer::{c64, Mat};

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

    /// The FRFs and sensitivities at this point, as evaluated.
    pub(super) fn evaluation(&self) -> &FrfEvaluation {
        &self.frfs
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
        let sqrt_weights = sqrt_weights(measured, &lines, settings.weighting)?;
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
    pub(super) fn evaluate_state(
        &self,
        p: &[f64],
        state: &ModalState,
        jacobian: bool,
    ) -> Result<Evaluation, UpdateError> {
        let frfs = self.frfs_at(p, state, jacobian)?;
        self.weighted(p, frfs, jacobian)
    }

    /// The model FRFs on this problem's lines at `state` (parameters `p`),
    /// with their sensitivities if `jacobian`.
    pub(super) fn frfs_at(&self, p: &[f64], state: &ModalState, jacobian: bool) -> Result<FrfEvaluation, UpdateError> {
        let mut frfs = self
            .model
            .evaluate_on_threads(state, self.request(), jacobian, self.settings.threads);
        let fields = super::updates_fields(&self.parameters);
        if jacobian && fields {
            let (_, damping) = self.model_at(p)?;
            frfs.dh_dtheta = self.model.field_frf_sensitivities(state, &damping, self.request());
        }
        Ok(frfs)
    }

    /// Residual and, if asked, Jacobian from model FRFs (and sensitivities) at `p`.
    pub(super) fn weighted(&self, p: &[f64], frfs: FrfEvaluation, jacobian: bool) -> Result<Evaluation, UpdateError> {
        let columns: Option<Vec<Vec<c64>>> = jacobian.then(|| {
            self.parameters
                .iter()
                .map(|par| {
                    parameter_column(
                        self.model,
                        par.kind,
                        &frfs.dh_dkappa,
                        &frfs.dh_dtheta,
                        (&self.damping, &frfs.dh_dgamma),
                    )
                })
                .collect()
        });
        let columns: Option<Vec<&[c64]>> = columns.as_ref().map(|c| c.iter().map(Vec::as_slice).collect());
        let (residual, jacobian) = weighted_residues(
            self.measured,
            &self.lines,
            &self.sqrt_weights,
            &frfs.h,
            columns.as_deref(),
            p,
        )?;
        Ok(Evaluation {
            residual,
            jacobian,
            extra: frfs,
        })
    }

    /// `previous` if it is this model at `p` on this problem's lines.
    pub(super) fn reusable<'p>(
        &self,
        previous: Option<&'p ModelPoint>,
        p: &[f64],
    ) -> Result<Option<&'p ModelPoint>, UpdateError> {
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

    pub(super) fn point(&self, p: &[f64], state: ModalState, frfs: FrfEvaluation) -> Result<ModelPoint, UpdateError> {
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

    pub(super) fn relative_residuals(&self, h: &[c64]) -> (f64, Vec<f64>) {
        relative_residuals(self.measured, &self.lines, h)
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
        let (relative_residual, per_block) = self.relative_residuals(&solved.at.extra.1.h);
        let fit = solver::FitMeasures {
            relative_residual,
            per_block,
            lines_used: self.lines.len(),
        };
        let (result, p, at) = solved.into_result(&self.parameters, fit);
        let (state, frfs) = at.extra;
        let point = self.point(&p, state, frfs)?;
        Ok(Solution { result, point })
    }
}

/// `∂h/∂p` of a parameter of kind `kind` from the sensitivities to every
/// spring coefficient (`dkappa`, flat order), stiffness-field coefficient
/// (`dtheta`) and damping parameter of `damping` (`dgamma`: the curve's
/// coefficients, then one loss factor per loss site when the damping has
/// them): a tied parameter's is the sum of its springs'.
pub(super) fn parameter_column(
    model: &FrfModel,
    kind: ParameterKind,
    dkappa: &[Vec<c64>],
    dtheta: &[Vec<c64>],
    (damping, dgamma): (&DampingCurve, &[Vec<c64>]),
) -> Vec<c64> {
    match kind {
        ParameterKind::Spring { .. } | ParameterKind::SpringRun { .. } => summed(
            kind.springs()
                .into_iter()
                .map(|(f, c)| dkappa[model.flat_spring_index(f, c)].as_slice()),
        ),
        ParameterKind::Stiffness { .. } | ParameterKind::StiffnessRun { .. } => summed(
            kind.fields()
                .into_iter()
                .map(|(f, c)| dtheta[model.flat_field_index(f, c)].as_slice()),
        ),
        ParameterKind::Damping { coefficient } => dgamma[coefficient].clone(),
        ParameterKind::LossFactor { field, count } => {
            let first = damping.loss_factor_column(field);
            summed(dgamma[first..first + count].iter().map(Vec::as_slice))
        }
    }
}

/// The element-wise sum of `columns` (the sensitivity of a tied parameter).
fn summed<'c>(mut columns: impl Iterator<Item = &'c [c64]>) -> Vec<c64> {
    let mut out = columns.next().map(<[c64]>::to_vec).unwrap_or_default();
    for c in columns {
        for (o, v) in out.iter_mut().zip(c) {
            *o += v;
        }
    }
    out
}

/// The weighted residues `√w (h_x − h)` of `measured` on `lines` stacked as
/// real and imaginary parts (eq. 36–39) and, with `columns` (`∂h/∂p_k` per
/// parameter, laid out as `h`), the Jacobian `−√w ∂h/∂p`.
pub(super) fn weighted_residues(
    measured: &MeasuredSet,
    lines: &[usize],
    sqrt_weights: &[f64],
    h: &[c64],
    columns: Option<&[&[c64]]>,
    p: &[f64],
) -> Result<(Vec<f64>, Mat<f64>), UpdateError> {
    let nl = lines.len();
    let nb = measured.frfs().len();
    let mut residual = Vec::with_capacity(2 * nl * nb);
    for (b, frf) in measured.frfs().iter().enumerate() {
        for (l, &line) in lines.iter().enumerate() {
            let k = b * nl + l;
            let d = (frf.values[line] - h[k]) * sqrt_weights[k];
            residual.push(d.re);
            residual.push(d.im);
        }
    }
    if residual.iter().any(|r| !r.is_finite()) {
        return Err(UpdateError::NonFinite(p.to_vec()));
    }
    let mut jac = Mat::<f64>::zeros(0, 0);
    if let Some(columns) = columns {
        jac = Mat::zeros(residual.len(), columns.len());
        for (c, column) in columns.iter().enumerate() {
            for k in 0..nl * nb {
                let d = -column[k] * sqrt_weights[k];
                jac[(2 * k, c)] = d.re;
                jac[(2 * k + 1, c)] = d.im;
            }
        }
    }
    Ok((residual, jac))
}

/// `√w` per complex residue of `measured` on `lines`, `[frf * n_lines + line]`.
pub(super) fn sqrt_weights(
    measured: &MeasuredSet,
    lines: &[usize],
    weighting: Weighting,
) -> Result<Vec<f64>, UpdateError> {
    let mut sqrt_weights = Vec::with_capacity(lines.len() * measured.frfs().len());
    for (b, frf) in measured.frfs().iter().enumerate() {
        for &i in lines {
            let w = match weighting {
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
    Ok(sqrt_weights)
}

/// `‖h_x − h‖ / ‖h_x‖` over every FRF of `measured` on `lines` (model
/// values `h`, `[frf * n_lines + line]`), and per FRF.
pub(super) fn relative_residuals(measured: &MeasuredSet, lines: &[usize], h: &[c64]) -> (f64, Vec<f64>) {
    let nl = lines.len();
    let (mut num, mut den) = (0.0, 0.0);
    let mut per = Vec::with_capacity(measured.frfs().len());
    for (b, frf) in measured.frfs().iter().enumerate() {
        let (mut n, mut d) = (0.0, 0.0);
        for (l, &line) in lines.iter().enumerate() {
            let x = frf.values[line];
            n += (x - h[b * nl + l]).norm_sqr();
            d += x.norm_sqr();
        }
        per.push((n / d).sqrt());
        num += n;
        den += d;
    }
    ((num / den).sqrt(), per)
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
