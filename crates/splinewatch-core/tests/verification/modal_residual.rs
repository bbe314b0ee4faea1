//! The modal residue's Jacobian against central differences, and the
//! pairing, on the Sinello deck.

use super::common::{
    bending_modes_below_80_hz, gaussian, sinello_model, sinello_sensors, spring_parameters, tied_second_coefficients,
    true_kappa,
};
use splinewatch_core::c64;
use splinewatch_core::model::damping::DampingCurve;
use splinewatch_core::response::frf::{FrfModel, ModalState};
use splinewatch_core::updating::modal_residual::{modal_residue, nearest_by_shape, pair_modes, ObservedMode};
use splinewatch_core::updating::{Parameter, ParameterKind};

fn parameters() -> Vec<Parameter> {
    let damping = (0..7).map(|coefficient| Parameter {
        name: format!("damping.g{}", coefficient + 1),
        kind: ParameterKind::Damping { coefficient },
        lower: 1e-4,
        upper: 0.1,
    });
    spring_parameters().into_iter().chain(damping).collect()
}

/// The bending modes below 80 Hz of `state` as identified modes, with a
/// rotated (complex) shape and typical standard deviations.
fn observed_from(state: &ModalState) -> Vec<ObservedMode> {
    bending_modes_below_80_hz(state)
        .into_iter()
        .map(|i| {
            let f = state.modes.frequency_hz(i);
            let largest = (0..12).map(|s| state.amplitude(s, i).abs()).fold(0.0, f64::max);
            ObservedMode {
                frequency_hz: f,
                frequency_std_hz: 1e-3 * f,
                damping_ratio: state.zeta[i] * 1.1,
                damping_std: 5e-4,
                shape: (0..12)
                    .map(|s| (s, c64::new(0.6, 0.8) * (state.amplitude(s, i) / largest)))
                    .collect(),
                shape_std: 0.02,
            }
        })
        .collect()
}

/// Nearest by shape ignores the frequency that the pairing gates on: the
/// bending modes below 80 Hz as identified (exact shapes, complex-rotated),
/// every other one reported at 1.6× its frequency. The pairing (10 % gate)
/// keeps the others only; the nearest by shape finds every one's own model
/// mode at MAC 1 (the rotation is undone by the modulus), and names the
/// model mode, not the index into the identified list.
#[test]
fn the_nearest_model_mode_by_shape_is_found_whatever_the_frequency() {
    let model = FrfModel::new(sinello_model().assemble().unwrap(), &sinello_sensors()).unwrap();
    let damping = DampingCurve::new(2, vec![0.01; 7], 0.0, 80.0).unwrap();
    let state = model.modal_state(&true_kappa(), &damping).unwrap();
    let bending = bending_modes_below_80_hz(&state);
    let mut observed = observed_from(&state);
    for mode in observed.iter_mut().skip(1).step_by(2) {
        mode.frequency_hz *= 1.6;
    }
    let paired: Vec<usize> = pair_modes(&state, &observed, 0.8, 0.1)
        .iter()
        .map(|p| p.observed)
        .collect();
    assert_eq!(paired, (0..observed.len()).step_by(2).collect::<Vec<_>>());
    let nearest = nearest_by_shape(&state, &observed);
    assert_eq!(nearest.len(), observed.len());
    for (o, (found, &own)) in nearest.iter().zip(&bending).enumerate() {
        let found = found.expect("a flexible model mode");
        assert_eq!((found.observed, found.model), (o, own), "identified mode {o}");
        assert!((found.mac - 1.0).abs() < 1e-9, "identified mode {o}: MAC {}", found.mac);
    }
}

/// Every column of `jacobian` against central differences of `residual`
/// (step `step(c)` on parameter `c` of `p0`), within 1e-5 of the column's
/// largest entry; returns the worst relative error.
fn check_columns(
    jacobian: &splinewatch_core::Mat<f64>,
    p0: &[f64],
    names: &[String],
    step: impl Fn(usize) -> f64,
    residual: impl Fn(&[f64]) -> Vec<f64>,
    tolerance: f64,
) -> f64 {
    let mut worst = 0.0f64;
    for c in 0..p0.len() {
        let h = step(c);
        let at = |sign: f64| {
            let mut p = p0.to_vec();
            p[c] += sign * h;
            residual(&p)
        };
        let (plus, minus) = (at(1.0), at(-1.0));
        let column_scale = (0..jacobian.nrows())
            .map(|r| jacobian[(r, c)].abs())
            .fold(0.0, f64::max)
            .max(1e-30);
        for r in 0..jacobian.nrows() {
            let fd = (plus[r] - minus[r]) / (2.0 * h);
            let error = (jacobian[(r, c)] - fd).abs() / column_scale;
            worst = worst.max(error);
            assert!(error < tolerance, "row {r}, {}: {} vs {fd}", names[c], jacobian[(r, c)]);
        }
    }
    worst
}

#[test]
fn modal_residue_jacobian_matches_central_differences() {
    let model = FrfModel::new(sinello_model().assemble().unwrap(), &sinello_sensors()).unwrap();
    let damping = DampingCurve::new(2, vec![0.01, 0.012, 0.011, 0.01, 0.009, 0.01, 0.011], 0.0, 80.0).unwrap();
    let mut damaged = true_kappa();
    damaged[1][1] *= 0.6;
    let observed = observed_from(&model.modal_state(&damaged, &damping).unwrap());
    let parameters = parameters();
    let kappa = true_kappa();
    let at = |p: &[f64]| {
        let k = vec![p[0..4].to_vec(), p[4..8].to_vec()];
        let d = damping.with_coefficients(p[8..15].to_vec()).unwrap();
        model.modal_state(&k, &d).unwrap()
    };
    let p0: Vec<f64> = kappa.iter().flatten().chain(damping.coefficients()).copied().collect();
    let state = at(&p0);
    let pairs = pair_modes(&state, &observed, 0.8, 0.1);
    assert_eq!(pairs.len(), 18, "every identified mode pairs with its model mode");
    // A 40 % loss of east.k2 mixes the close pair (73.5/74.0 Hz): MAC 0.92–0.95 there.
    assert!(pairs.iter().all(|p| p.mac > 0.9), "{pairs:?}");
    let base = modal_residue(&model, &state, &observed, &pairs, &parameters, true);
    assert_eq!(base.residual.len(), 18 * 14);
    let names: Vec<String> = parameters.iter().map(|p| p.name.clone()).collect();
    let step = |c: usize| if c < 8 { 1e-5 * p0[c] } else { 1e-6 };
    let worst = check_columns(
        &base.jacobian,
        &p0,
        &names,
        step,
        |p| modal_residue(&model, &at(p), &observed, &pairs, &parameters, false).residual,
        1e-5,
    );
    eprintln!("worst Jacobian error relative to its column's largest entry: {worst:.1e}");
}

/// The same check for the coefficients of a 4 × 2 stiffness field of the
/// deck (degree 1) with a spring: `∂r/∂θ` from the field's
/// eigen-derivatives within 1e-5 of each column's largest entry on the
/// every-mode model; on the model truncated at 160 Hz (against central
/// differences of its own residue) within 5e-3, the expansion error of the
/// discarded modes' part of `∂a/∂θ` (`tests/verification/truncation.rs`).
#[test]
fn modal_residue_jacobian_for_a_stiffness_field_matches_central_differences() {
    use splinewatch_core::geometry::knots::KnotVector;
    use splinewatch_core::model::stiffness_field::StiffnessField;
    use splinewatch_core::model::BridgeModel;
    let knots = |d, n| KnotVector::uniform(d, n, 0.0, 1.0).unwrap();
    let field = StiffnessField::new(knots(1, 4), knots(1, 2), vec![1.0; 8]).unwrap();
    let deck = BridgeModel {
        stiffness_fields: vec![field],
        member_stiffness: Vec::new(),
        ..sinello_model()
    };
    let dense = FrfModel::new(deck.assemble().unwrap(), &sinello_sensors()).unwrap();
    let truncated = FrfModel::truncated(&deck, &sinello_sensors(), 160.0).unwrap();
    for (name, model, tolerance) in [("every mode", dense, 1e-5), ("truncated", truncated, 5e-3)] {
        let worst = field_jacobian_error(&model, tolerance);
        eprintln!("{name}: worst field Jacobian error relative to its column's largest entry: {worst:.1e}");
    }
}

fn field_jacobian_error(model: &FrfModel, tolerance: f64) -> f64 {
    let damping = DampingCurve::new(2, vec![0.01, 0.012, 0.011, 0.01, 0.009, 0.01, 0.011], 0.0, 80.0).unwrap();
    let kappa = true_kappa();
    let truth = vec![vec![1.0, 0.9, 1.1, 0.8, 1.0, 1.2, 0.95, 1.05]];
    let observed = observed_from(&model.modal_state_with_fields(&kappa, &truth, &damping).unwrap());
    let mut parameters: Vec<Parameter> = (0..8)
        .map(|coefficient| Parameter {
            name: format!("deck.s{}", coefficient + 1),
            kind: ParameterKind::Stiffness { field: 0, coefficient },
            lower: 0.3,
            upper: 1.5,
        })
        .collect();
    parameters.push(Parameter {
        name: "east.k2".into(),
        kind: ParameterKind::Spring {
            field: 1,
            coefficient: 1,
        },
        lower: 1e7,
        upper: 5e9,
    });
    let at = |p: &[f64]| {
        let mut k = kappa.clone();
        k[1][1] = p[8];
        model.modal_state_with_fields(&k, &[p[..8].to_vec()], &damping).unwrap()
    };
    let p0: Vec<f64> = vec![1.0; 8].into_iter().chain([kappa[1][1]]).collect();
    let state = at(&p0);
    let pairs = pair_modes(&state, &observed, 0.8, 0.1);
    assert!(pairs.len() >= 15, "{} pairs", pairs.len());
    let base = modal_residue(model, &state, &observed, &pairs, &parameters, true);
    let names: Vec<String> = parameters.iter().map(|p| p.name.clone()).collect();
    check_columns(
        &base.jacobian,
        &p0,
        &names,
        |c| 1e-5 * p0[c],
        |p| modal_residue(model, &at(p), &observed, &pairs, &parameters, false).residual,
        tolerance,
    )
}

/// Output-only updating through the shared solver: the 18 bending modes of
/// the model with `east.k2` at 60 % (frequencies, damping and shapes as an
/// identification reports them, std 0.1 % of f, 1e-3 of ζ, 0.02 of a shape
/// component) pull the model from the undamaged start to the damaged κ:
/// `east.k2` within 10 %, every other κ within 15 % (the issue's
/// targets), and the damping curve's coefficients move towards 1.1 × the
/// truth.
#[test]
fn modal_updating_follows_a_bearing_loss() {
    use splinewatch_core::updating::{ModalUpdateProblem, UpdateSettings};
    let model = FrfModel::new(sinello_model().assemble().unwrap(), &sinello_sensors()).unwrap();
    let damping = DampingCurve::new(2, vec![0.01; 7], 0.0, 80.0).unwrap();
    let mut damaged = true_kappa();
    damaged[1][1] *= 0.6;
    let observed = observed_from(&model.modal_state(&damaged, &damping).unwrap());
    let parameters = parameters();
    let problem = ModalUpdateProblem::new(
        &model,
        true_kappa(),
        damping.clone(),
        parameters.clone(),
        &observed,
        UpdateSettings::default(),
        (0.8, 0.1),
    )
    .unwrap();
    let start: Vec<f64> = true_kappa()
        .iter()
        .flatten()
        .chain(damping.coefficients())
        .copied()
        .collect();
    let solution = problem.solve(&start, &mut |_| {}).unwrap();
    let result = &solution.result;
    assert_eq!(solution.pairs.len(), 18);
    let truth: Vec<f64> = damaged.iter().flatten().copied().collect();
    for (k, estimate) in result.parameters.iter().take(8).enumerate() {
        let error = (estimate.value / truth[k] - 1.0).abs();
        eprintln!(
            "{}: {:.4e} (truth {:.4e}, {:+.2} %)",
            estimate.name,
            estimate.value,
            truth[k],
            100.0 * error
        );
        let allowed = if k == 5 { 0.10 } else { 0.15 };
        assert!(error < allowed, "{}: {} vs {}", estimate.name, estimate.value, truth[k]);
    }
    assert!(result.converged, "{:?}", result.stop_reason);
    assert!(result.relative_residual < 1e-3, "{}", result.relative_residual);

    // The same with the identification's noise: every frequency, damping
    // ratio and shape component perturbed by one draw of its std.
    let draws = gaussian(observed.len() * 14, 17);
    let mut draw = draws.iter();
    let mut normal = || *draw.next().expect("one draw per perturbed value");
    let noisy: Vec<ObservedMode> = observed
        .iter()
        .map(|m| ObservedMode {
            frequency_hz: m.frequency_hz + m.frequency_std_hz * normal(),
            damping_ratio: m.damping_ratio + m.damping_std * normal(),
            shape: m
                .shape
                .iter()
                .map(|&(s, v)| (s, v + c64::new(0.6, 0.8) * (m.shape_std * normal())))
                .collect(),
            ..m.clone()
        })
        .collect();
    let problem = ModalUpdateProblem::new(
        &model,
        true_kappa(),
        damping.clone(),
        parameters,
        &noisy,
        UpdateSettings::default(),
        (0.8, 0.1),
    )
    .unwrap();
    let result = problem.solve(&start, &mut |_| {}).unwrap().result;
    for (k, estimate) in result.parameters.iter().take(8).enumerate() {
        let error = estimate.value / truth[k] - 1.0;
        let std = estimate.std.expect("identifiable from 18 modes") / truth[k];
        eprintln!(
            "noisy {}: {:+.2} % (reported std {:.2} %)",
            estimate.name,
            100.0 * error,
            100.0 * std
        );
        let allowed = if k == 5 { 0.10 } else { 0.15 };
        assert!(error.abs() < allowed, "{}: {:+.3}", estimate.name, error);
        assert!(
            error.abs() < 4.0 * std,
            "{}: error {error:+.3} beyond 4 reported std {std:.3}",
            estimate.name
        );
    }
}

/// The same search on the truncated model (the modes below 150 Hz, the
/// rest by their residual), two springs updated (`east.k2` at 60 % of the
/// start, `west.k2` unchanged): it runs on a Ritz basis of the start point
/// and finishes on the complete model, and both come back within 1e-4 of
/// the damaged truth (noise-free modes; the damping residues, 10 % off and
/// flat in frequency, pull no spring).
#[test]
fn modal_updating_of_a_truncated_model_searches_on_its_ritz_basis() {
    use splinewatch_core::updating::{ModalUpdateProblem, UpdateSettings};
    let model = FrfModel::truncated(&sinello_model(), &sinello_sensors(), 150.0).unwrap();
    let damping = DampingCurve::new(2, vec![0.01; 7], 0.0, 80.0).unwrap();
    let mut damaged = true_kappa();
    damaged[1][1] *= 0.6;
    let observed = observed_from(&model.modal_state(&damaged, &damping).unwrap());
    let reduced = model.with_reanalysis((&true_kappa(), &[]), &[], &[1, 5]).unwrap();
    assert!(reduced.reanalysis().is_some(), "two springs take a Ritz basis");
    let parameters = vec![spring_parameters()[1].clone(), spring_parameters()[5].clone()];
    let problem = ModalUpdateProblem::new(
        &model,
        true_kappa(),
        damping,
        parameters,
        &observed,
        UpdateSettings::default(),
        (0.8, 0.1),
    )
    .unwrap();
    let start = [true_kappa()[0][1], true_kappa()[1][1]];
    let solution = problem.solve(&start, &mut |_| {}).unwrap();
    assert!(solution.result.converged, "{:?}", solution.result.stop_reason);
    for (estimate, truth) in solution.result.parameters.iter().zip([damaged[0][1], damaged[1][1]]) {
        let error = (estimate.value / truth - 1.0).abs();
        assert!(
            error < 1e-4,
            "{}: {} vs {truth} ({error:.1e})",
            estimate.name,
            estimate.value
        );
    }
}

/// `frequency_gradient` (`∂f/∂p` of one mode, the modal residue's own
/// eigen-derivatives) against central differences of the frequency, for
/// the eight springs, a tied pair and a damping coefficient (zero): within
/// 1e-6 of the largest entry (Fox & Kapoor are exact on the every-mode model;
/// the steps' truncation error is below that).
#[test]
fn a_modes_frequency_gradient_matches_central_differences() {
    use splinewatch_core::updating::modal_residual::frequency_gradient;
    let model = FrfModel::new(sinello_model().assemble().unwrap(), &sinello_sensors()).unwrap();
    let damping = DampingCurve::new(1, vec![0.01, 0.012], 0.0, 80.0).unwrap();
    let mut parameters = spring_parameters();
    parameters.push(tied_second_coefficients());
    parameters.push(Parameter {
        name: "damping.g1".into(),
        kind: ParameterKind::Damping { coefficient: 0 },
        lower: 1e-4,
        upper: 0.1,
    });
    let kappa = true_kappa();
    let state = model.modal_state(&kappa, &damping).unwrap();
    let mode = bending_modes_below_80_hz(&state)[2];
    let gradient = frequency_gradient(&model, &state, mode, &parameters);
    let frequency = |k: &[Vec<f64>]| model.modal_state(k, &damping).unwrap().modes.frequency_hz(mode);
    let numeric: Vec<f64> = parameters
        .iter()
        .map(|p| {
            let springs = p.kind.springs();
            if springs.is_empty() {
                return 0.0;
            }
            let h = 1e-4 * kappa[springs[0].0][springs[0].1];
            let shifted = |sign: f64| {
                let mut k = kappa.clone();
                for &(f, c) in &springs {
                    k[f][c] += sign * h;
                }
                frequency(&k)
            };
            (shifted(1.0) - shifted(-1.0)) / (2.0 * h)
        })
        .collect();
    let largest = numeric.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    assert!(largest > 0.0);
    for ((p, g), n) in parameters.iter().zip(&gradient).zip(&numeric) {
        assert!((g - n).abs() <= 1e-6 * largest, "{}: {g:e} against {n:e}", p.name);
    }
    assert_eq!(gradient[9], 0.0, "damping does not move a frequency");
}
