//! The updating loop on the Sinello deck: weighting and error paths.

use super::common::{sinello_model, sinello_sensors, spring_parameters, true_kappa};
use splinewatch_core::c64;
use splinewatch_core::model::damping::DampingCurve;
use splinewatch_core::response::frf::{FrfModel, FrfRequest, Quantity};
use splinewatch_core::updating::frf_residual::{MeasuredFrf, MeasuredSet, UpdateProblem};
use splinewatch_core::updating::{LineSelection, UpdateError, UpdateSettings, Weighting};

/// Noise-free accelerances of the true model at P1..P4 for input P1, with a
/// band of lines (30–40 Hz) corrupted by a 30 % error and flagged by low
/// coherence, as a shaker drop-out or a disturbance would.
fn corrupted_measurements(model: &FrfModel, damping: &DampingCurve) -> MeasuredSet {
    let freqs: Vec<f64> = (0..300).map(|k| 1.0 + 0.25 * k as f64).collect();
    let pairs: Vec<(usize, usize)> = (0..4).map(|r| (r, 0)).collect();
    let state = model.modal_state(&true_kappa(), damping).unwrap();
    let eval = model.evaluate(
        &state,
        FrfRequest {
            frequencies_hz: &freqs,
            pairs: &pairs,
            quantity: Quantity::Accelerance,
        },
        false,
    );
    let nf = freqs.len();
    let frfs = pairs
        .iter()
        .enumerate()
        .map(|(p, &(r, s))| {
            let bad = |f: f64| (30.0..=40.0).contains(&f);
            MeasuredFrf {
                output: r,
                input: s,
                values: (0..nf)
                    .map(|l| {
                        let h = eval.h[p * nf + l];
                        if bad(freqs[l]) {
                            h * c64::new(1.3, 0.0)
                        } else {
                            h
                        }
                    })
                    .collect(),
                coherence: Some(freqs.iter().map(|&f| if bad(f) { 0.2 } else { 0.999 }).collect()),
                n_averages: Some(40.0),
            }
        })
        .collect();
    MeasuredSet::new(Quantity::Accelerance, freqs, frfs).unwrap()
}

/// The eight spring coefficients updated against `measured`, the truth as
/// the base model.
fn spring_problem<'a>(
    model: &'a FrfModel,
    damping: &DampingCurve,
    measured: &'a MeasuredSet,
    settings: UpdateSettings,
) -> UpdateProblem<'a> {
    UpdateProblem::new(
        model,
        true_kappa(),
        damping.clone(),
        spring_parameters(),
        measured,
        settings,
    )
    .unwrap()
}

/// `measured` with every FRF replaced by `change` of it.
fn with_each_frf(measured: &MeasuredSet, change: impl Fn(&MeasuredFrf) -> MeasuredFrf) -> MeasuredSet {
    let frfs = measured.frfs().iter().map(change).collect();
    MeasuredSet::new(measured.quantity(), measured.frequencies_hz().to_vec(), frfs).unwrap()
}

fn worst_kappa_error(values: &[f64]) -> f64 {
    let truth: Vec<f64> = true_kappa().into_iter().flatten().collect();
    values
        .iter()
        .zip(&truth)
        .map(|(v, t)| (v - t).abs() / t)
        .fold(0.0, f64::max)
}

#[test]
fn h1_variance_weighting_discounts_low_coherence_lines() {
    let model = FrfModel::new(sinello_model().assemble().unwrap(), &sinello_sensors()).unwrap();
    let damping = DampingCurve::new(2, vec![0.02; 7], 0.0, 80.0).unwrap();
    let measured = corrupted_measurements(&model, &damping);
    let solve = |weighting| {
        let settings = UpdateSettings {
            weighting,
            ..UpdateSettings::default()
        };
        let problem = spring_problem(&model, &damping, &measured, settings);
        let result = problem.solve(&[1e9; 8]).unwrap();
        assert!(result.converged, "{:?}", result.stop_reason);
        worst_kappa_error(&result.parameters.iter().map(|p| p.value).collect::<Vec<_>>())
    };
    let uniform = solve(Weighting::Uniform);
    let weighted = solve(Weighting::H1Variance);
    eprintln!("worst κ error: uniform {uniform:.2e}, H1-variance weighted {weighted:.2e}");
    assert!(weighted < 1e-3, "weighted {weighted}");
    assert!(uniform > 10.0 * weighted, "uniform {uniform} vs weighted {weighted}");
}

#[test]
fn excluding_the_corrupted_band_recovers_the_truth() {
    let model = FrfModel::new(sinello_model().assemble().unwrap(), &sinello_sensors()).unwrap();
    let damping = DampingCurve::new(2, vec![0.02; 7], 0.0, 80.0).unwrap();
    let measured = corrupted_measurements(&model, &damping);
    let settings = UpdateSettings {
        lines: LineSelection {
            band: Some((2.0, 70.0)),
            decimation: 2,
            exclude: vec![(29.9, 40.1)],
        },
        ..UpdateSettings::default()
    };
    let problem = spring_problem(&model, &damping, &measured, settings);
    let result = problem.solve(&[1e9; 8]).unwrap();
    let values: Vec<f64> = result.parameters.iter().map(|p| p.value).collect();
    assert!(worst_kappa_error(&values) < 1e-6, "{values:?}");
    assert!(result.relative_residual < 1e-6);
    assert!(result.condition_number.is_finite() && result.singular_values.len() == 8);
}

#[test]
fn h1_weighting_without_coherence_is_an_error() {
    let model = FrfModel::new(sinello_model().assemble().unwrap(), &sinello_sensors()).unwrap();
    let damping = DampingCurve::new(2, vec![0.02; 7], 0.0, 80.0).unwrap();
    let measured = MeasuredSet::new(
        Quantity::Accelerance,
        vec![1.0, 2.0, 3.0, 4.0, 5.0],
        vec![MeasuredFrf {
            output: 1,
            input: 0,
            values: vec![c64::new(1.0, 0.0); 5],
            coherence: None,
            n_averages: None,
        }],
    )
    .unwrap();
    let settings = UpdateSettings {
        weighting: Weighting::H1Variance,
        ..UpdateSettings::default()
    };
    let err = UpdateProblem::new(
        &model,
        true_kappa(),
        damping.clone(),
        spring_parameters(),
        &measured,
        settings,
    )
    .unwrap_err();
    assert!(err.to_string().contains("needs coherence and n_averages"), "{err}");
    let err = UpdateProblem::new(
        &model,
        true_kappa(),
        damping,
        vec![],
        &measured,
        UpdateSettings::default(),
    )
    .unwrap_err();
    assert_eq!(err, UpdateError::NoParameters);
}

/// Two measured sets in sequence, as the daemon's windows: the second solve
/// warm-starts from the first's result. Handing it the first solve's end
/// point skips the model evaluation at the start and changes nothing else,
/// bit for bit; a point at other parameters or on other lines is ignored.
#[test]
fn warm_start_from_the_previous_point_is_exact_and_saves_an_evaluation() {
    let model = FrfModel::new(sinello_model().assemble().unwrap(), &sinello_sensors()).unwrap();
    let damping = DampingCurve::new(2, vec![0.02; 7], 0.0, 80.0).unwrap();
    let first = corrupted_measurements(&model, &damping);
    // The second "window": the same deck measured with a 2 % gain error.
    let second = with_each_frf(&first, |f| MeasuredFrf {
        values: f.values.iter().map(|v| v * c64::new(1.02, 0.0)).collect(),
        ..f.clone()
    });
    let problem = |measured| spring_problem(&model, &damping, measured, UpdateSettings::default());
    let earlier = problem(&first).solve_from(&[1e9; 8], None, &mut |_| {}).unwrap();
    let start: Vec<f64> = earlier.result.parameters.iter().map(|p| p.value).collect();
    assert_eq!(
        earlier.point.kappa().concat(),
        start,
        "the point is the model at the result"
    );

    let cold = problem(&second).solve_from(&start, None, &mut |_| {}).unwrap();
    let warm = problem(&second)
        .solve_from(&start, Some(&earlier.point), &mut |_| {})
        .unwrap();
    assert!(cold.result.iterations.len() > 1, "the second set moves the parameters");
    assert_eq!(warm.result.evaluations + 1, cold.result.evaluations);
    let without_count = |r: &splinewatch_core::updating::UpdateResult| {
        let mut r = r.clone();
        r.evaluations = 0;
        r
    };
    assert_eq!(without_count(&warm.result), without_count(&cold.result));
    assert_eq!(warm.point.frfs(), cold.point.frfs());

    // Elsewhere: the point of the cold start is not the model at 1e9.
    let elsewhere = problem(&second)
        .solve_from(&[1e9; 8], Some(&earlier.point), &mut |_| {})
        .unwrap();
    let fresh = problem(&second).solve_from(&[1e9; 8], None, &mut |_| {}).unwrap();
    assert_eq!(elsewhere.result, fresh.result);
    // Other lines: a decimated problem cannot use it either.
    let decimated = UpdateSettings {
        lines: LineSelection {
            decimation: 2,
            ..LineSelection::default()
        },
        ..UpdateSettings::default()
    };
    let other = spring_problem(&model, &damping, &second, decimated.clone());
    let with_point = other.solve_from(&start, Some(&earlier.point), &mut |_| {}).unwrap();
    let without = other.solve_from(&start, None, &mut |_| {}).unwrap();
    assert_eq!(with_point.result, without.result);
    // Another model, even one built alike, cannot use it either; a clone can.
    let twin = FrfModel::new(sinello_model().assemble().unwrap(), &sinello_sensors()).unwrap();
    let on = |model: &FrfModel| {
        let problem = spring_problem(model, &damping, &second, UpdateSettings::default());
        problem
            .solve_from(&start, Some(&earlier.point), &mut |_| {})
            .unwrap()
            .result
    };
    assert_eq!(on(&twin).evaluations, cold.result.evaluations);
    assert_eq!(on(&model.clone()).evaluations, warm.result.evaluations);
}

/// The iterates do not depend on the units of the residual: scaling every
/// weight by 10⁶ (here through the number of averages of the H1-variance
/// weighting) scales JᵀJ, Jᵀr and the cost alike, and the damped steps, the
/// acceptance ratios and the stopping tests are ratios of those.
#[test]
fn iterates_do_not_depend_on_the_scale_of_the_residual() {
    let model = FrfModel::new(sinello_model().assemble().unwrap(), &sinello_sensors()).unwrap();
    let damping = DampingCurve::new(2, vec![0.02; 7], 0.0, 80.0).unwrap();
    let measured = corrupted_measurements(&model, &damping);
    let scaled = with_each_frf(&measured, |f| MeasuredFrf {
        n_averages: f.n_averages.map(|n| n * 1e6),
        ..f.clone()
    });
    let solve = |measured| {
        let settings = UpdateSettings {
            weighting: Weighting::H1Variance,
            ..UpdateSettings::default()
        };
        spring_problem(&model, &damping, measured, settings)
            .solve(&[1e9; 8])
            .unwrap()
    };
    let (base, large) = (solve(&measured), solve(&scaled));
    assert_eq!(base.iterations.len(), large.iterations.len());
    assert_eq!(base.evaluations, large.evaluations);
    for (a, b) in base.iterations.iter().zip(&large.iterations) {
        assert_eq!(a.rejected_steps, b.rejected_steps);
        for (x, y) in a.parameters.iter().zip(&b.parameters) {
            assert!((x - y).abs() <= 1e-9 * x.abs(), "iteration {}: {x} vs {y}", a.iteration);
        }
    }
}
