//! FRF and modal residues fitted together (`updating::joint`) on the Sinello
//! deck: the stacked residual is exactly the two blocks' own, each block's
//! weights are its variances (chi-squares of the right size under noise of
//! the stated variance), and the joint update follows a bearing loss.

use super::common::{
    bending_modes_below_80_hz, gaussian, sinello_model, sinello_sensors, spring_parameters, true_kappa,
};
use splinewatch_core::c64;
use splinewatch_core::model::damping::DampingCurve;
use splinewatch_core::response::frf::{FrfModel, FrfRequest, ModalState, Quantity};
use splinewatch_core::updating::frf_residual::{MeasuredFrf, MeasuredSet, UpdateProblem};
use splinewatch_core::updating::joint::JointUpdateProblem;
use splinewatch_core::updating::modal_residual::ObservedMode;
use splinewatch_core::updating::{ModalUpdateProblem, ResidualModel, UpdateSettings, Weighting};

const COHERENCE: f64 = 0.95;
const AVERAGES: f64 = 60.0;

/// Accelerances of `state` at P1..P6 for input P1 on 1–60 Hz (0.25 Hz),
/// with coherence 0.95 from 60 averages; each value plus complex noise of
/// the H1 estimator's variance `(1 − γ²)/(γ² n) |H|²` drawn from `seed`
/// (`None`: noise-free).
fn measured(model: &FrfModel, state: &ModalState, seed: Option<u64>) -> MeasuredSet {
    let freqs: Vec<f64> = (0..237).map(|k| 1.0 + 0.25 * k as f64).collect();
    let pairs: Vec<(usize, usize)> = (0..6).map(|r| (r, 0)).collect();
    let h = model
        .evaluate(
            state,
            FrfRequest {
                frequencies_hz: &freqs,
                pairs: &pairs,
                quantity: Quantity::Accelerance,
            },
            false,
        )
        .h;
    let draws = seed.map(|s| gaussian(2 * h.len(), s));
    let nf = freqs.len();
    let frfs = pairs
        .iter()
        .enumerate()
        .map(|(b, &(output, input))| MeasuredFrf {
            output,
            input,
            values: (0..nf)
                .map(|l| {
                    let k = b * nf + l;
                    let Some(d) = &draws else { return h[k] };
                    let std = ((1.0 - COHERENCE) / (COHERENCE * AVERAGES)).sqrt() * h[k].norm() / 2f64.sqrt();
                    h[k] + c64::new(std * d[2 * k], std * d[2 * k + 1])
                })
                .collect(),
            coherence: Some(vec![COHERENCE; nf]),
            n_averages: Some(AVERAGES),
        })
        .collect();
    MeasuredSet::new(Quantity::Accelerance, freqs, frfs).unwrap()
}

/// The bending modes below 60 Hz of `state` as identified with std 0.2 % of
/// f, 1e-3 of ζ and 0.02 of a shape component, perturbed by one draw of
/// each std from `seed` (`None`: exact).
fn observed(state: &ModalState, damping: &DampingCurve, seed: Option<u64>) -> Vec<ObservedMode> {
    let modes: Vec<usize> = bending_modes_below_80_hz(state)
        .into_iter()
        .filter(|&i| state.modes.frequency_hz(i) < 60.0)
        .collect();
    let draws = gaussian(modes.len() * 14, seed.unwrap_or(0));
    let mut draw = draws.iter().map(|d| if seed.is_some() { *d } else { 0.0 });
    let mut normal = move || draw.next().expect("one draw per value");
    modes
        .into_iter()
        .map(|i| {
            let f = state.modes.frequency_hz(i);
            let largest = (0..12).map(|s| state.amplitude(s, i).abs()).fold(0.0, f64::max);
            let (f_std, z_std, s_std) = (2e-3 * f, 1e-3, 0.02);
            ObservedMode {
                frequency_hz: f + f_std * normal(),
                frequency_std_hz: f_std,
                damping_ratio: damping.zeta(f) + z_std * normal(),
                damping_std: z_std,
                shape: (0..12)
                    .map(|s| (s, c64::new(state.amplitude(s, i) / largest + s_std * normal(), 0.0)))
                    .collect(),
                shape_std: s_std,
            }
        })
        .collect()
}

fn damaged_kappa() -> Vec<Vec<f64>> {
    let mut kappa = true_kappa();
    kappa[1][1] *= 0.6;
    kappa
}

/// The joint residual at any point is the H1-weighted FRF residual times √2
/// (the H1 variance is the complex value's: half of it per part) followed
/// by the modal residual, and so is the Jacobian, to the last bit but the
/// √2's rounding.
#[test]
fn the_joint_residual_is_both_blocks_each_in_its_own_standard_deviations() {
    let model = FrfModel::new(sinello_model().assemble().unwrap(), &sinello_sensors()).unwrap();
    let damping = DampingCurve::new(2, vec![0.02; 7], 0.0, 80.0).unwrap();
    let truth = model.modal_state(&damaged_kappa(), &damping).unwrap();
    let frfs = measured(&model, &truth, Some(3));
    let modes = observed(&truth, &damping, Some(5));
    let settings = UpdateSettings::default();
    let joint = JointUpdateProblem::new(
        &model,
        true_kappa(),
        damping.clone(),
        spring_parameters(),
        &frfs,
        &modes,
        settings.clone(),
        (0.8, 0.1),
    )
    .unwrap();
    let h1 = UpdateSettings {
        weighting: Weighting::H1Variance,
        ..settings.clone()
    };
    let frf = UpdateProblem::new(&model, true_kappa(), damping.clone(), spring_parameters(), &frfs, h1).unwrap();
    let modal = ModalUpdateProblem::new(
        &model,
        true_kappa(),
        damping.clone(),
        spring_parameters(),
        &modes,
        settings,
        (0.8, 0.1),
    )
    .unwrap();
    let p: Vec<f64> = true_kappa().concat();
    let (j, _) = joint.first(&p, None).unwrap();
    let (f, _) = frf.first(&p, None).unwrap();
    let (m, _) = modal.first(&p, None).unwrap();
    assert_eq!(j.residual.len(), f.residual.len() + m.residual.len());
    assert!(m.residual.len() > 20, "{} modal residues", m.residual.len());
    let expected: Vec<f64> = f
        .residual
        .iter()
        .map(|r| 2f64.sqrt() * r)
        .chain(m.residual.iter().copied())
        .collect();
    assert_eq!(j.residual, expected);
    for c in 0..p.len() {
        for i in 0..j.residual.len() {
            let e = if i < f.residual.len() {
                2f64.sqrt() * f.jacobian[(i, c)]
            } else {
                m.jacobian[(i - f.residual.len(), c)]
            };
            assert_eq!(j.jacobian[(i, c)], e, "row {i}, column {c}");
        }
    }
}

/// At the truth, with noise of exactly the stated variances, each block's
/// chi-square is about its number of residues (within 4 √(2m), the
/// chi-square's standard deviation); without the √2 the FRF block's would
/// be half of it. Updated from the undamaged start, every κ is within 4
/// reported std of the truth, and the damaged one within 5 %.
#[test]
fn a_joint_update_of_noisy_frfs_and_modes_finds_a_bearing_loss_with_calibrated_std() {
    let model = FrfModel::new(sinello_model().assemble().unwrap(), &sinello_sensors()).unwrap();
    let damping = DampingCurve::new(2, vec![0.02; 7], 0.0, 80.0).unwrap();
    let truth = model.modal_state(&damaged_kappa(), &damping).unwrap();
    let frfs = measured(&model, &truth, Some(11));
    let modes = observed(&truth, &damping, Some(13));
    let problem = |kappa: Vec<Vec<f64>>| {
        JointUpdateProblem::new(
            &model,
            kappa,
            damping.clone(),
            spring_parameters(),
            &frfs,
            &modes,
            UpdateSettings::default(),
            (0.8, 0.1),
        )
        .unwrap()
    };
    let at_truth = problem(damaged_kappa());
    let (e, _) = at_truth.first(&damaged_kappa().concat(), None).unwrap();
    let nf = 2 * 237 * 6;
    for (name, block) in [("FRF", &e.residual[..nf]), ("modal", &e.residual[nf..])] {
        let m = block.len() as f64;
        let chi2: f64 = block.iter().map(|r| r * r).sum();
        eprintln!("{name} block at the truth: chi-square {chi2:.0} over {m} residues");
        assert!((chi2 - m).abs() < 4.0 * (2.0 * m).sqrt(), "{name}: {chi2} vs {m}");
    }

    let solution = problem(true_kappa())
        .solve_from(&true_kappa().concat(), None, &mut |_| {})
        .unwrap();
    let result = &solution.result;
    assert!(result.converged, "{:?}", result.stop_reason);
    assert!(solution.pairs.len() >= 10, "{} pairs", solution.pairs.len());
    eprintln!("blocks at the solution: {:?}", solution.blocks);
    let truth_values = damaged_kappa().concat();
    for (k, estimate) in result.parameters.iter().enumerate() {
        let error = estimate.value / truth_values[k] - 1.0;
        let std = estimate.std.expect("every spring is informed") / truth_values[k];
        eprintln!("{}: {:+.3} % (std {:.3} %)", estimate.name, 100.0 * error, 100.0 * std);
        assert!(
            error.abs() < 4.0 * std,
            "{}: {error:+.4} beyond 4 std {std:.4}",
            estimate.name
        );
    }
    let damaged = (result.parameters[5].value / truth_values[5] - 1.0).abs();
    assert!(damaged < 0.05, "the damaged coefficient is off by {damaged}");
}

/// The FRF block needs the data its weights come from.
#[test]
fn a_joint_update_without_coherence_says_why() {
    let model = FrfModel::new(sinello_model().assemble().unwrap(), &sinello_sensors()).unwrap();
    let damping = DampingCurve::new(2, vec![0.02; 7], 0.0, 80.0).unwrap();
    let truth = model.modal_state(&true_kappa(), &damping).unwrap();
    let with = measured(&model, &truth, None);
    let without = MeasuredSet::new(
        with.quantity(),
        with.frequencies_hz().to_vec(),
        with.frfs()
            .iter()
            .map(|f| MeasuredFrf {
                coherence: None,
                ..f.clone()
            })
            .collect(),
    )
    .unwrap();
    let modes = observed(&truth, &damping, None);
    let e = JointUpdateProblem::new(
        &model,
        true_kappa(),
        damping,
        spring_parameters(),
        &without,
        &modes,
        UpdateSettings::default(),
        (0.8, 0.1),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("needs coherence and n_averages") && e.contains("joint update is weighted"),
        "{e}"
    );
}
