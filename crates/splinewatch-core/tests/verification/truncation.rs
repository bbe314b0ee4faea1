//! Modal truncation with residual compensation (`FrfModel::truncated`)
//! against the dense model's every-mode sums on the Sinello deck: FRFs,
//! their spring and damping sensitivities, the eigen-sensitivities of the
//! output-only path, and an update.

use super::common::{bending_modes_below_80_hz, sinello_model, sinello_sensors, spring_parameters, true_kappa};
use splinewatch_core::c64;
use splinewatch_core::geometry::knots::KnotVector;
use splinewatch_core::model::damping::DampingCurve;
use splinewatch_core::model::stiffness_field::StiffnessField;
use splinewatch_core::model::BridgeModel;
use splinewatch_core::response::frf::{FrfEvaluation, FrfModel, FrfRequest, ModalState, Quantity};
use splinewatch_core::response::modal_sensitivity::ModalSensitivities;
use splinewatch_core::updating::frf_residual::{MeasuredFrf, MeasuredSet, UpdateProblem};
use splinewatch_core::updating::{Parameter, ParameterKind, UpdateSettings};

/// 2× the band's top, the default cut-off.
const CUTOFF_HZ: f64 = 160.0;

fn damping() -> DampingCurve {
    DampingCurve::new(2, vec![0.03, 0.012, 0.02, 0.015, 0.025, 0.018, 0.03], 0.0, 80.0).unwrap()
}

fn models() -> (FrfModel, FrfModel) {
    let dense = FrfModel::new(sinello_model().assemble().unwrap(), &sinello_sensors()).unwrap();
    let truncated = FrfModel::truncated(&sinello_model(), &sinello_sensors(), CUTOFF_HZ).unwrap();
    (dense, truncated)
}

/// The largest error of `found` against `reference` over each block of
/// `n` lines (one FRF or one sensitivity of one pair), relative to that
/// block's peak.
fn worst_relative(found: &[c64], reference: &[c64], n: usize) -> f64 {
    found
        .chunks(n)
        .zip(reference.chunks(n))
        .map(|(a, b)| {
            let peak = b.iter().map(|v| v.norm()).fold(0.0, f64::max);
            a.iter().zip(b).map(|(x, y)| (x - y).norm() / peak).fold(0.0, f64::max)
        })
        .fold(0.0, f64::max)
}

fn evaluate(model: &FrfModel, state: &ModalState, lines: &[f64], pairs: &[(usize, usize)]) -> FrfEvaluation {
    model.evaluate(
        state,
        FrfRequest {
            frequencies_hz: lines,
            pairs,
            quantity: Quantity::Accelerance,
        },
        true,
    )
}

/// Over the 0.5–80 Hz band (12 accelerances, input at the first sensor,
/// 73 of 325 modes kept) with ζ up to 3 % (held at 3 % beyond 80 Hz):
/// FRFs within 1.5e-3 of each FRF's peak, spring and damping sensitivities
/// within 3e-3 of each one's peak. What is left is the discarded modes'
/// damping beyond first order (measured: 2.3e-4 for FRFs with ζ ten times
/// smaller; the bundled 1 % deck meets 1e-3, `tests/integration/matrices.rs`).
/// Without the residual the FRFs miss by 5e-2: the compensation is what
/// makes truncation safe.
#[test]
fn truncated_frfs_and_sensitivities_match_the_every_mode_sums() {
    let (dense, truncated) = models();
    let kappa = true_kappa();
    let full = dense.modal_state(&kappa, &damping()).unwrap();
    let kept = truncated.modal_state(&kappa, &damping()).unwrap();
    assert!(
        kept.modes.len() < full.modes.len() / 2,
        "{} modes kept",
        kept.modes.len()
    );
    let lines: Vec<f64> = (1..=160).map(|k| 0.5 * k as f64).collect();
    let pairs: Vec<(usize, usize)> = (0..12).map(|s| (s, 0)).collect();
    let (reference, found) = (
        evaluate(&dense, &full, &lines, &pairs),
        evaluate(&truncated, &kept, &lines, &pairs),
    );
    let n = lines.len();
    let frf_error = worst_relative(&found.h, &reference.h, n);
    let spring_error = (0..reference.dh_dkappa.len())
        .map(|j| worst_relative(&found.dh_dkappa[j], &reference.dh_dkappa[j], n))
        .fold(0.0, f64::max);
    let damping_error = (0..reference.dh_dgamma.len())
        .map(|z| worst_relative(&found.dh_dgamma[z], &reference.dh_dgamma[z], n))
        .fold(0.0, f64::max);
    // The same kept modes without their residual.
    let residual = kept.residual().expect("a truncated state");
    let plain: Vec<c64> = pairs
        .iter()
        .enumerate()
        .flat_map(|(p, &(r, s))| {
            let found = &found.h;
            lines.iter().enumerate().map(move |(l, f)| {
                let w = 2.0 * std::f64::consts::PI * f;
                found[p * n + l] - Quantity::Accelerance.factor(w) * residual.at_sensors(r, s, w)
            })
        })
        .collect();
    let plain_error = worst_relative(&plain, &reference.h, n);
    eprintln!(
        "truncated at {CUTOFF_HZ} Hz ({} of {} modes): FRFs {frf_error:.2e} ({plain_error:.2e} without the residual), \
         ∂H/∂κ {spring_error:.2e}, ∂H/∂γ {damping_error:.2e}",
        kept.modes.len(),
        full.modes.len()
    );
    assert!(frf_error <= 1.5e-3, "FRFs {frf_error:.2e}");
    assert!(plain_error > 10.0 * frf_error, "without the residual {plain_error:.2e}");
    assert!(spring_error <= 3e-3, "∂H/∂κ {spring_error:.2e}");
    assert!(damping_error <= 3e-3, "∂H/∂γ {damping_error:.2e}");
}

/// Eigen-sensitivities of the bending modes below 80 Hz (the output-only
/// path's): `∂λ/∂κ` exact to round-off (1e-8; the same modes), `∂a/∂κ` at
/// the sensors from the kept modes plus the residual within 5e-3 of the
/// every-mode expansion (relative to each derivative's largest sensor value;
/// the residual's expansion about σ leaves terms of order
/// `((λ_i − σ)/(λ_d − σ))²` of the discarded part, up to 1/16 for an 80 Hz
/// mode against a 160 Hz cut-off), several times closer than the kept
/// modes' expansion alone.
#[test]
fn truncated_eigen_sensitivities_match_the_every_mode_expansion() {
    let (dense, truncated) = models();
    let kappa = true_kappa();
    let full = dense.modal_state(&kappa, &damping()).unwrap();
    let kept = truncated.modal_state(&kappa, &damping()).unwrap();
    let modes = bending_modes_below_80_hz(&full);
    assert_eq!(modes, bending_modes_below_80_hz(&kept));
    let reference = dense.modal_sensitivities(&full, &modes);
    let found = truncated.modal_sensitivities(&kept, &modes);
    // The kept modes alone (no residual): the same modes through the dense
    // model's state builder.
    let alone = dense.modal_sensitivities(&dense.restate(&kept, &damping()), &modes);
    check_eigen_sensitivities(("κ", &modes), (&full, &kept), (&reference, &found, &alone));
}

/// The eight spring coefficients updated from a start 30 % off against
/// noise-free accelerances of the dense model: the truncated model lands
/// within 1e-3 of the truth (its model error, not the solver, sets the
/// offset).
#[test]
fn a_truncated_update_recovers_the_springs() {
    let (dense, truncated) = models();
    let damping = damping();
    let lines: Vec<f64> = (0..300).map(|k| 1.0 + 0.25 * k as f64).collect();
    let pairs: Vec<(usize, usize)> = (0..12).map(|s| (s, 0)).collect();
    let truth = dense.modal_state(&true_kappa(), &damping).unwrap();
    let h = evaluate(&dense, &truth, &lines, &pairs).h;
    let frfs = pairs
        .iter()
        .enumerate()
        .map(|(p, &(output, input))| MeasuredFrf {
            output,
            input,
            values: h[p * lines.len()..(p + 1) * lines.len()].to_vec(),
            coherence: None,
            n_averages: None,
        })
        .collect();
    let measured = MeasuredSet::new(Quantity::Accelerance, lines, frfs).unwrap();
    let start: Vec<f64> = true_kappa().into_iter().flatten().map(|k| 0.7 * k).collect();
    let problem = UpdateProblem::new(
        &truncated,
        true_kappa(),
        damping.clone(),
        spring_parameters(),
        &measured,
        UpdateSettings::default(),
    )
    .unwrap();
    let result = problem.solve(&start).unwrap();
    let truth: Vec<f64> = true_kappa().into_iter().flatten().collect();
    let worst = result
        .parameters
        .iter()
        .zip(&truth)
        .map(|(p, t)| (p.value - t).abs() / t)
        .fold(0.0, f64::max);
    eprintln!(
        "truncated update: worst κ error {worst:.2e} in {} iterations",
        result.iterations.len()
    );
    assert!(result.converged, "{:?}", result.stop_reason);
    assert!(worst <= 1e-3, "worst κ error {worst:.2e}");
}

/// The deck in eight regions (ξ in quarters, η in halves, degree 0), one
/// of them 30 % softer: a point where every θ matters.
fn regions() -> (BridgeModel, Vec<f64>) {
    let regions = StiffnessField::new(
        KnotVector::new(vec![0.0, 0.25, 0.5, 0.75, 1.0], 0).unwrap(),
        KnotVector::new(vec![0.0, 0.5, 1.0], 0).unwrap(),
        vec![1.0; 8],
    )
    .unwrap();
    let mut theta = vec![1.0; 8];
    theta[5] = 0.7;
    let model = BridgeModel {
        stiffness_fields: vec![regions],
        member_stiffness: Vec::new(),
        ..sinello_model()
    };
    (model, theta)
}

fn region_models() -> (FrfModel, FrfModel, Vec<f64>) {
    let (model, theta) = regions();
    let dense = FrfModel::new(model.assemble().unwrap(), &sinello_sensors()).unwrap();
    let truncated = FrfModel::truncated(&model, &sinello_sensors(), CUTOFF_HZ).unwrap();
    (dense, truncated, theta)
}

/// Stiffness-field FRF sensitivities of the truncated model (kept modes,
/// their couplings to the residual and the residual's own, eq. 33 with
/// `crate::solvers::truncation`) against the dense model's every-mode chain rule,
/// 12 accelerances over 0.5–80 Hz, ζ up to 3 %: within 3e-3 of each
/// derivative's peak (the springs' tolerance above: the same residual
/// expansion), and several times closer than the kept modes alone.
#[test]
fn truncated_field_frf_sensitivities_match_the_every_mode_ones() {
    let (dense, truncated, theta) = region_models();
    let kappa = true_kappa();
    let full = dense
        .modal_state_with_fields(&kappa, std::slice::from_ref(&theta), &damping())
        .unwrap();
    let kept = truncated.modal_state_with_fields(&kappa, &[theta], &damping()).unwrap();
    let lines: Vec<f64> = (1..=160).map(|k| 0.5 * k as f64).collect();
    let pairs: Vec<(usize, usize)> = (0..12).map(|s| (s, 0)).collect();
    let request = FrfRequest {
        frequencies_hz: &lines,
        pairs: &pairs,
        quantity: Quantity::Accelerance,
    };
    let reference = dense.field_frf_sensitivities(&full, &damping(), request);
    let found = truncated.field_frf_sensitivities(&kept, &damping(), request);
    let alone_state = dense.restate(&kept, &damping());
    let alone = dense.field_frf_sensitivities(&alone_state, &damping(), request);
    assert_eq!(found.len(), 8);
    let n = lines.len();
    let worst = |x: &[Vec<c64>]| {
        (0..reference.len())
            .map(|k| worst_relative(&x[k], &reference[k], n))
            .fold(0.0, f64::max)
    };
    let (error, error_alone) = (worst(&found), worst(&alone));
    eprintln!(
        "field FRF sensitivities, {} of {} modes kept: {error:.2e} ({error_alone:.2e} from the kept modes alone)",
        kept.modes.len(),
        full.modes.len()
    );
    assert!(error <= 3e-3, "∂H/∂θ {error:.2e}");
    assert!(error_alone > 3.0 * error, "kept modes alone {error_alone:.2e}");
}

/// The output-only path's eigen-sensitivities to the eight θ on the
/// truncated model: `∂λ/∂θ` exact to round-off (1e-8), `∂a/∂θ` within 5e-3
/// of the every-mode expansion with the discarded modes' part from the
/// residual on every dof (the springs' tolerance, same expansion), several
/// times closer than the kept modes alone.
#[test]
fn truncated_field_eigen_sensitivities_match_the_every_mode_expansion() {
    let (dense, truncated, theta) = region_models();
    let kappa = true_kappa();
    let full = dense
        .modal_state_with_fields(&kappa, std::slice::from_ref(&theta), &damping())
        .unwrap();
    let kept = truncated.modal_state_with_fields(&kappa, &[theta], &damping()).unwrap();
    let modes = bending_modes_below_80_hz(&full);
    assert_eq!(modes, bending_modes_below_80_hz(&kept));
    let reference = dense.field_sensitivities(&full, &modes);
    let found = truncated.field_sensitivities(&kept, &modes);
    let alone = dense.field_sensitivities(&dense.restate(&kept, &damping()), &modes);
    check_eigen_sensitivities(("θ", &modes), (&full, &kept), (&reference, &found, &alone));
}

/// The local-loss case of the dense verification on the truncated model:
/// the eight θ and the eight κ updated together (κ from 1.3×, θ from 1)
/// against noise-free accelerances of the dense model with region 5 at
/// 0.7: every θ and κ within 5e-3 of the truth (the truncated model's own
/// error sets the offset, as for the springs alone).
#[test]
fn a_truncated_update_finds_a_local_stiffness_loss() {
    let (dense, truncated, theta) = region_models();
    let damping = damping();
    let lines: Vec<f64> = (2..=320).map(|k| 0.25 * k as f64).collect();
    let pairs: Vec<(usize, usize)> = (0..12).map(|r| (r, 0)).collect();
    let truth = dense
        .modal_state_with_fields(&true_kappa(), std::slice::from_ref(&theta), &damping)
        .unwrap();
    let h = evaluate(&dense, &truth, &lines, &pairs).h;
    let nf = lines.len();
    let frfs = pairs
        .iter()
        .enumerate()
        .map(|(p, &(output, input))| MeasuredFrf {
            output,
            input,
            values: h[p * nf..(p + 1) * nf].to_vec(),
            coherence: None,
            n_averages: None,
        })
        .collect();
    let measured = MeasuredSet::new(Quantity::Accelerance, lines, frfs).unwrap();
    let mut parameters = spring_parameters();
    parameters.extend((0..8).map(|coefficient| Parameter {
        name: format!("deck.s{}", coefficient + 1),
        kind: ParameterKind::Stiffness { field: 0, coefficient },
        lower: 0.3,
        upper: 1.5,
    }));
    let problem = UpdateProblem::new(
        &truncated,
        true_kappa(),
        damping,
        parameters,
        &measured,
        UpdateSettings::default(),
    )
    .unwrap();
    let start: Vec<f64> = true_kappa().iter().flatten().map(|k| 1.3 * k).chain([1.0; 8]).collect();
    let result = problem.solve(&start).unwrap();
    assert!(result.converged, "{:?}", result.stop_reason);
    let want: Vec<f64> = true_kappa().into_iter().flatten().chain(theta).collect();
    let worst = result
        .parameters
        .iter()
        .zip(&want)
        .map(|(p, t)| (p.value - t).abs() / t)
        .fold(0.0, f64::max);
    eprintln!(
        "truncated update with a stiffness field: worst error {worst:.2e} in {} iterations",
        result.iterations.len()
    );
    assert!(worst <= 5e-3, "worst error {worst:.2e}");
}

/// Eigen-sensitivities of the truncated model (`found`) against the
/// every-mode expansion (`reference`), and the kept modes' expansion alone
/// (`alone`): `∂λ` within 1e-8 relative, `∂a` at the sensors within 5e-3
/// of each derivative's largest sensor value, and `alone` more than three
/// times further off. Shapes are aligned in sign on the amplitudes of the
/// full and kept states.
fn check_eigen_sensitivities(
    (parameter, modes): (&str, &[usize]),
    (full, kept): (&ModalState, &ModalState),
    (reference, found, alone): (&ModalSensitivities, &ModalSensitivities, &ModalSensitivities),
) {
    let (mut eigen, mut amplitude, mut amplitude_alone) = (0.0f64, 0.0f64, 0.0f64);
    for (row, &mode) in modes.iter().enumerate() {
        let overlap: f64 = (0..full.sensor_count())
            .map(|s| kept.amplitude(s, mode) * full.amplitude(s, mode))
            .sum();
        let sign = overlap.signum();
        for j in 0..reference.eigenvalue.ncols() {
            let (a, b) = (found.eigenvalue[(row, j)], reference.eigenvalue[(row, j)]);
            eigen = eigen.max((a - b).abs() / b.abs().max(1e-300));
            let ra = &reference.amplitude[row];
            let peak = (0..ra.nrows()).map(|s| ra[(s, j)].abs()).fold(0.0, f64::max);
            for s in 0..ra.nrows() {
                amplitude = amplitude.max((sign * found.amplitude[row][(s, j)] - ra[(s, j)]).abs() / peak);
                amplitude_alone = amplitude_alone.max((sign * alone.amplitude[row][(s, j)] - ra[(s, j)]).abs() / peak);
            }
        }
    }
    eprintln!(
        "eigen-sensitivities to {parameter} of {} modes: ∂λ {eigen:.2e}, ∂a {amplitude:.2e} ({amplitude_alone:.2e} from the kept modes alone)",
        modes.len()
    );
    assert!(eigen <= 1e-8, "∂λ/∂{parameter} {eigen:.2e}");
    assert!(amplitude <= 5e-3, "∂a/∂{parameter} {amplitude:.2e}");
    assert!(
        amplitude_alone > 3.0 * amplitude,
        "kept modes alone {amplitude_alone:.2e}"
    );
}

/// The truncated model's `M x` (its sparse mass on the generalised dofs,
/// the simulator's state transfer when a scenario changes the model)
/// equals the dense model's to round-off (1e-13 of the largest entry).
#[test]
fn the_truncated_mass_product_equals_the_dense_one() {
    let (dense, truncated) = models();
    let n = sinello_model().assemble().unwrap().mass.nrows();
    let x: Vec<f64> = (0..n).map(|i| ((i * 37 % 101) as f64 - 50.0) * 1e-3).collect();
    let (a, b) = (dense.mass_times(&x), truncated.mass_times(&x));
    let scale = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let worst = a.iter().zip(&b).fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
    assert!(scale > 0.0 && worst <= 1e-13 * scale, "{worst:e} of {scale:e}");
}
