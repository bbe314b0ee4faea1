//! Modal residues for output-only updating: identified modes (from OMA)
//! against the model's, paired by MAC, each residue scaled by the standard
//! deviation the identification reported.
//!
//! Per paired mode, with `r = (model − identified)/σ`:
//! - frequency: `(f_m − f_x)/σ_f`;
//! - shape, the scaled shape difference at the sensors,
//!   `(α a_m − φ_x)/σ_φ` with `φ_x` the identified shape rotated to its
//!   max-real form (real part kept) and `α = a_mᵀφ_x / a_mᵀa_m` the
//!   least-squares scale. Chosen over `1 − MAC`: one residue per sensor
//!   instead of one per mode, weighted by each component's std, and a
//!   non-zero gradient at the solution (1 − MAC is quadratic there, which
//!   starves Gauss–Newton);
//! - damping, against the model's ζ_m (the curve ζ(f_m) and the supports'
//!   loss factors' share, [`crate::model::damping`]) so both are identified:
//!   `(ζ_m − ζ_x)/σ_ζ`.
//!
//! The Jacobian uses the eigen-derivatives of [`crate::response::modal_sensitivity`]
//! (`∂f/∂κ = ∂λ/∂κ / (8π² f)`, `∂(α a)/∂κ = α ∂a + a ∂α`,
//! `∂α = (φ_xᵀ∂a − 2α a_mᵀ∂a)/a_mᵀa_m`), `∂ζ_m/∂κ` (the curve's
//! `ζ'(f_m) ∂f/∂κ` and the loss factors' share) and `∂ζ_m/∂γ_z` (`B_z(f_m)`,
//! or `½ e_{m,s}` for a loss factor). The pairing is redone at every evaluation (modes
//! swap order as κ changes) and held fixed within one Jacobian.

use crate::identification::oma::shape::mac_real;
use crate::response::frf::{FrfModel, ModalState};
use crate::solvers::modal::ModeKind;
use crate::updating::{updates_fields, Parameter, ParameterKind};
use faer::{c64, Mat};
use std::f64::consts::PI;

/// An identified mode as the updating sees it.
#[derive(Debug, Clone, PartialEq)]
pub struct ObservedMode {
    pub frequency_hz: f64,
    pub frequency_std_hz: f64,
    pub damping_ratio: f64,
    pub damping_std: f64,
    /// `(model sensor index, component)` pairs.
    pub shape: Vec<(usize, c64)>,
    /// Standard deviation of every component of the shape scaled to a
    /// largest component of 1.
    pub shape_std: f64,
}

/// A pairing of an identified mode with a model mode.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModePair {
    pub observed: usize,
    /// Index into the modal state's modes.
    pub model: usize,
    pub mac: f64,
}

/// Residues (and, if asked, `∂r/∂p`) at one model state.
#[derive(Debug, Clone)]
pub struct ModalResidue {
    pub residual: Vec<f64>,
    /// `residual.len() × parameters`; empty when not asked for.
    pub jacobian: Mat<f64>,
    pub pairs: Vec<ModePair>,
}

/// The flexible model mode of largest MAC with `mode` (at its sensors)
/// among those `admit` lets through, and that MAC.
fn best_mac(state: &ModalState, mode: &ObservedMode, admit: impl Fn(usize) -> bool) -> Option<(usize, f64)> {
    let shape: Vec<c64> = mode.shape.iter().map(|&(_, v)| v).collect();
    (0..state.modes.len())
        .filter(|&i| state.modes.kinds[i] != ModeKind::Rigid && admit(i))
        .map(|i| {
            let a: Vec<f64> = mode.shape.iter().map(|&(s, _)| state.amplitude(s, i)).collect();
            (i, mac_real(&shape, &a))
        })
        .max_by(|a, b| a.1.total_cmp(&b.1))
}

/// Each observed mode's nearest model mode by shape alone: the flexible
/// mode of largest MAC at its sensors, whatever its frequency (`None` when
/// the model has no flexible mode). Not a pairing for updating (see
/// [`pair_modes`] for why the frequency gate matters there): what a modal
/// analyst compares to tell which model mode an identified one is, and by
/// how much their frequencies differ.
pub fn nearest_by_shape(state: &ModalState, observed: &[ObservedMode]) -> Vec<Option<ModePair>> {
    observed
        .iter()
        .enumerate()
        .map(|(o, mode)| {
            best_mac(state, mode, |_| true).map(|(model, mac)| ModePair {
                observed: o,
                model,
                mac,
            })
        })
        .collect()
}

/// Pairs each observed mode with the flexible model mode of largest MAC
/// (at the observed sensors) among those within `max_gap` relative
/// frequency, if that MAC is at least `min_mac`; a model mode claimed twice
/// goes to the higher MAC. The frequency gate matters: twelve sensors
/// cannot tell a low mode from some mode ten times higher (spatial
/// aliasing), and a spurious identified mode would otherwise pair with it.
pub fn pair_modes(state: &ModalState, observed: &[ObservedMode], min_mac: f64, max_gap: f64) -> Vec<ModePair> {
    let mut pairs: Vec<ModePair> = Vec::new();
    for (o, mode) in observed.iter().enumerate() {
        let best = best_mac(state, mode, |i| {
            (state.modes.frequency_hz(i) - mode.frequency_hz).abs() <= max_gap * mode.frequency_hz
        });
        let Some((model, mac)) = best.filter(|b| b.1 >= min_mac) else {
            continue;
        };
        match pairs.iter().position(|p| p.model == model) {
            Some(k) if pairs[k].mac >= mac => {}
            Some(k) => {
                pairs[k] = ModePair {
                    observed: o,
                    model,
                    mac,
                }
            }
            None => pairs.push(ModePair {
                observed: o,
                model,
                mac,
            }),
        }
    }
    pairs.sort_by_key(|p| p.observed);
    pairs
}

/// The identified shape as a real vector: rotated by `e^{−iθ}`,
/// `θ = ½ arg Σ φ²` (the max-real rotation), real part kept.
fn real_shape(shape: &[(usize, c64)]) -> Vec<f64> {
    let sum: c64 = shape.iter().map(|&(_, v)| v * v).sum();
    let theta = 0.5 * sum.im.atan2(sum.re);
    let rotate = c64::new(theta.cos(), -theta.sin());
    shape.iter().map(|&(_, v)| (v * rotate).re).collect()
}

/// Residues of the `pairs` at `state` (see the module documentation).
#[allow(
    clippy::too_many_lines,
    reason = "one pass per paired mode writing its frequency, shape and damping rows and their Jacobian columns side by side, as the module documentation derives them"
)]
pub fn modal_residue(
    model: &FrfModel,
    state: &ModalState,
    observed: &[ObservedMode],
    pairs: &[ModePair],
    parameters: &[Parameter],
    jacobian: bool,
) -> ModalResidue {
    let modes: Vec<usize> = pairs.iter().map(|p| p.model).collect();
    let sens = jacobian.then(|| model.modal_sensitivities(state, &modes));
    let field_sens = (jacobian && updates_fields(parameters)).then(|| model.field_sensitivities(state, &modes));
    let rows: usize = pairs.iter().map(|p| 2 + observed[p.observed].shape.len()).sum();
    let mut residual = Vec::with_capacity(rows);
    let mut jac = if jacobian {
        Mat::zeros(rows, parameters.len())
    } else {
        Mat::zeros(0, 0)
    };
    for (k, pair) in pairs.iter().enumerate() {
        let x = &observed[pair.observed];
        let i = pair.model;
        let f = state.modes.frequency_hz(i);
        let phi = real_shape(&x.shape);
        let a: Vec<f64> = x.shape.iter().map(|&(s, _)| state.amplitude(s, i)).collect();
        let aa: f64 = a.iter().map(|v| v * v).sum();
        let alpha = a.iter().zip(&phi).map(|(a, p)| a * p).sum::<f64>() / aa;
        let zeta = state.zeta[i];
        let row0 = residual.len();
        residual.push((f - x.frequency_hz) / x.frequency_std_hz);
        residual.extend(a.iter().zip(&phi).map(|(a, p)| (alpha * a - p) / x.shape_std));
        residual.push((zeta - x.damping_ratio) / x.damping_std);
        let Some(sens) = &sens else {
            continue;
        };
        let gradient = state.zeta_gradient(i);
        let n = a.len();
        for (c, par) in parameters.iter().enumerate() {
            // The rows of a stiffness parameter (spring κ or field θ) from
            // the mode's ∂λ and ∂a at the sensors in column j of `s`.
            let mut stiffness_rows = |s: &crate::response::modal_sensitivity::ModalSensitivities, j: usize| {
                let df = s.eigenvalue[(k, j)] / (8.0 * PI * PI * f);
                jac[(row0, c)] += df / x.frequency_std_hz;
                let da: Vec<f64> = x.shape.iter().map(|&(sensor, _)| s.amplitude[k][(sensor, j)]).collect();
                let phi_da: f64 = phi.iter().zip(&da).map(|(p, d)| p * d).sum();
                let a_da: f64 = a.iter().zip(&da).map(|(a, d)| a * d).sum();
                let dalpha = (phi_da - 2.0 * alpha * a_da) / aa;
                for r in 0..n {
                    jac[(row0 + 1 + r, c)] += (alpha * da[r] + a[r] * dalpha) / x.shape_std;
                }
                jac[(row0 + 1 + n, c)] += s.damping_ratio[(k, j)] / x.damping_std;
            };
            match stiffness_columns(model, par.kind) {
                // A tied parameter's rows add up its springs' (the rows are linear in them).
                StiffnessColumns::Springs(columns) => columns.into_iter().for_each(|j| stiffness_rows(sens, j)),
                StiffnessColumns::Fields(columns) => {
                    let field_sens = field_sens.as_ref().expect("computed when a field is updated");
                    columns.into_iter().for_each(|j| stiffness_rows(field_sens, j));
                }
                StiffnessColumns::LossFactor(field, count) => {
                    let first = state.loss_factor_column(field);
                    jac[(row0 + 1 + n, c)] = gradient[first..first + count].iter().sum::<f64>() / x.damping_std;
                }
                StiffnessColumns::Damping(coefficient) => {
                    jac[(row0 + 1 + n, c)] = gradient[coefficient] / x.damping_std;
                }
            }
        }
    }
    ModalResidue {
        residual,
        jacobian: jac,
        pairs: pairs.to_vec(),
    }
}

/// The sensitivity columns a parameter's derivative sums: its springs'
/// (flat indices of [`FrfModel::modal_sensitivities`]) or its field
/// coefficient's ([`FrfModel::field_sensitivities`]); a damping
/// coefficient moves no mode.
enum StiffnessColumns {
    Springs(Vec<usize>),
    Fields(Vec<usize>),
    Damping(usize),
    /// The first spring field and how many share the loss factor.
    LossFactor(usize, usize),
}

fn stiffness_columns(model: &FrfModel, kind: ParameterKind) -> StiffnessColumns {
    match kind {
        ParameterKind::Spring { .. } | ParameterKind::SpringRun { .. } => StiffnessColumns::Springs(
            kind.springs()
                .into_iter()
                .map(|(field, coefficient)| model.flat_spring_index(field, coefficient))
                .collect(),
        ),
        ParameterKind::Stiffness { .. } | ParameterKind::StiffnessRun { .. } => StiffnessColumns::Fields(
            kind.fields()
                .into_iter()
                .map(|(field, coefficient)| model.flat_field_index(field, coefficient))
                .collect(),
        ),
        ParameterKind::Damping { coefficient } => StiffnessColumns::Damping(coefficient),
        // The loss factors follow the curve's coefficients in ζ's gradient.
        ParameterKind::LossFactor { field, count } => StiffnessColumns::LossFactor(field, count),
    }
}

/// `∂f/∂p` of `state`'s mode `mode` for each parameter (Hz per unit of the
/// parameter; 0 for damping): Fox & Kapoor's `∂λ/∂κ` or `∂λ/∂θ` as in
/// [`modal_residue`], `∂f = ∂λ / (8π² f)`.
pub fn frequency_gradient(model: &FrfModel, state: &ModalState, mode: usize, parameters: &[Parameter]) -> Vec<f64> {
    let springs = model.modal_sensitivities(state, &[mode]);
    let fields = updates_fields(parameters).then(|| model.field_sensitivities(state, &[mode]));
    let scale = 1.0 / (8.0 * PI * PI * state.modes.frequency_hz(mode));
    parameters
        .iter()
        .map(|par| match stiffness_columns(model, par.kind) {
            StiffnessColumns::Springs(columns) => {
                columns.iter().map(|&j| springs.eigenvalue[(0, j)]).sum::<f64>() * scale
            }
            StiffnessColumns::Fields(columns) => {
                let fields = fields.as_ref().expect("computed when a field is updated");
                columns.iter().map(|&j| fields.eigenvalue[(0, j)]).sum::<f64>() * scale
            }
            StiffnessColumns::Damping(_) | StiffnessColumns::LossFactor(..) => 0.0,
        })
        .collect()
}
