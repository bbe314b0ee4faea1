//! Stiffness fields of the deck (B-spline multipliers of the material
//! stiffness) on the Sinello deck: a global scale against the scaled
//! material, the modal solver's fast path against the dense solve, and the
//! eigen-derivatives against central differences.

use super::common::{
    bending_modes_below_80_hz, check_eigen_derivatives, gaussian, sinello_material, sinello_model, sinello_sensors,
    spring_parameters, true_kappa,
};
use splinewatch_core::c64;
use splinewatch_core::geometry::knots::KnotVector;
use splinewatch_core::model::damping::DampingCurve;
use splinewatch_core::model::material::{OrthotropicMaterial, OrthotropicParameters};
use splinewatch_core::model::stiffness_field::StiffnessField;
use splinewatch_core::model::BridgeModel;
use splinewatch_core::response::frf::{FrfModel, FrfRequest, Quantity};
use splinewatch_core::solvers::modal::{self, ModeKind};
use splinewatch_core::updating::frf_residual::{MeasuredFrf, MeasuredSet, UpdateProblem};
use splinewatch_core::updating::{Parameter, ParameterKind, UpdateSettings};

fn field(degree: [usize; 2], count: [usize; 2]) -> StiffnessField {
    let knots = |d, n| KnotVector::uniform(d, n, 0.0, 1.0).unwrap();
    StiffnessField::new(
        knots(degree[0], count[0]),
        knots(degree[1], count[1]),
        vec![1.0; count[0] * count[1]],
    )
    .unwrap()
}

fn with_fields(fields: Vec<StiffnessField>) -> BridgeModel {
    BridgeModel {
        stiffness_fields: fields,
        member_stiffness: Vec::new(),
        ..sinello_model()
    }
}

/// θ = 0.8 on a one-coefficient field over the deck gives the modes of the
/// deck whose moduli are all scaled by 0.8 (the springs unchanged): every
/// frequency within 1e-10 relative (the tolerance; round-off of two
/// different sums of the same matrices).
#[test]
fn a_global_scale_gives_the_modes_of_the_scaled_material() {
    let scaled = with_fields(vec![field([0, 0], [1, 1])]).assemble().unwrap();
    let modes = scaled.modes_with_fields(&true_kappa(), &[vec![0.8]]).unwrap();
    let m = sinello_material();
    let weak = OrthotropicMaterial::new(OrthotropicParameters {
        e1: 0.8 * m.e1(),
        e2: 0.8 * m.e2(),
        g12: 0.8 * m.g12(),
        g13: 0.8 * m.g13(),
        g23: 0.8 * m.g23(),
        nu12: 0.3,
        density: 975.0,
        angle_deg: 0.0,
        shear_correction: 5.0 / 6.0,
    })
    .unwrap();
    let mut reference = sinello_model();
    reference.patches[0].material = weak;
    let reference = reference.assemble().unwrap().modes_with(&true_kappa()).unwrap();
    let top = reference.omega2.iter().copied().fold(0.0, f64::max);
    for i in 0..modes.len() {
        if modes.kinds[i] == ModeKind::Rigid {
            continue;
        }
        let (a, b) = (modes.omega2[i], reference.omega2[i]);
        assert!(
            (a - b).abs() <= 1e-10 * b.abs().max(1e-12 * top),
            "mode {i}: {a} vs {b}"
        );
    }
}

/// A 4 × 2 field of degree 1 with coefficients between 0.6 and 1.3: the
/// modal solver's transformed derivative blocks give the dense solve's
/// eigenvalues (1e-10 relative for every elastic mode).
#[test]
fn the_fast_path_equals_the_dense_solve() {
    let assembled = with_fields(vec![field([1, 1], [4, 2])]).assemble().unwrap();
    let theta = vec![vec![0.6, 1.1, 0.9, 1.3, 1.0, 0.7, 1.2, 0.8]];
    let fast = assembled.modes_with_fields(&true_kappa(), &theta).unwrap();
    let k = assembled.stiffness_with_fields(&true_kappa(), &theta).unwrap();
    let dense = modal::solve(&k, &assembled.mass, &assembled.reduction, &assembled.frames).unwrap();
    assert_eq!(fast.len(), dense.len());
    let top = dense.omega2.iter().copied().fold(0.0, f64::max);
    for i in 0..fast.len() {
        if dense.kinds[i] == ModeKind::Rigid {
            continue;
        }
        let (a, b) = (fast.omega2[i], dense.omega2[i]);
        assert!(
            (a - b).abs() <= 1e-10 * b.abs().max(1e-12 * top),
            "mode {i}: {a} vs {b}"
        );
    }
}

/// `∂λ/∂θ` and the sensor amplitudes' derivatives of every bending mode
/// below 80 Hz, for every coefficient of a 4 × 2 field, against central
/// differences (step 1e-4: truncation ~1e-8); tolerances as for the springs:
/// 1e-7 relative for λ, 1e-6 of the largest amplitude for the shapes.
#[test]
fn field_derivatives_match_central_differences() {
    let model = FrfModel::new(
        with_fields(vec![field([1, 1], [4, 2])]).assemble().unwrap(),
        &sinello_sensors(),
    )
    .unwrap();
    let damping = DampingCurve::new(2, vec![0.01; 7], 0.0, 80.0).unwrap();
    let kappa = true_kappa();
    let theta = vec![vec![1.0, 0.9, 1.1, 0.8, 1.0, 1.2, 0.95, 1.05]];
    let state = model.modal_state_with_fields(&kappa, &theta, &damping).unwrap();
    let modes = bending_modes_below_80_hz(&state);
    assert!(modes.len() >= 15, "{} bending modes", modes.len());
    let analytic = model.field_sensitivities(&state, &modes);
    let (mut worst_lambda, mut worst_shape) = (0.0f64, 0.0f64);
    for j in 0..theta[0].len() {
        let h = 1e-4;
        let at = |sign: f64| {
            let mut t = theta.clone();
            t[0][j] += sign * h;
            model.modal_state_with_fields(&kappa, &t, &damping).unwrap()
        };
        let (plus, minus) = (at(1.0), at(-1.0));
        let (l, a) = check_eigen_derivatives(&state, (&plus, &minus), h, 1.0, &analytic, j);
        worst_lambda = worst_lambda.max(l);
        worst_shape = worst_shape.max(a);
    }
    eprintln!("worst relative error: λ {worst_lambda:.1e}, amplitudes {worst_shape:.1e}");
}

/// `∂H/∂θ` (accelerance, P1 → every sensor, 0.5–80 Hz every 0.25 Hz) on a
/// sloped damping curve, so the chain through ζ(f_i) counts, against
/// central differences of the FRFs themselves (step 1e-5). Tolerance: 1e-5
/// of the largest |∂H| of each FRF (truncation of the differences near
/// the lightly damped peaks dominates); reached 9.8e-7. Without the
/// damping-curve term the check fails (1e-3 near the first mode).
#[test]
fn field_frf_derivatives_match_central_differences() {
    let model = FrfModel::new(
        with_fields(vec![field([1, 1], [4, 2])]).assemble().unwrap(),
        &sinello_sensors(),
    )
    .unwrap();
    let damping = DampingCurve::new(2, vec![0.008, 0.012, 0.009, 0.015, 0.011, 0.02, 0.013], 0.0, 80.0).unwrap();
    let kappa = true_kappa();
    let theta = vec![vec![1.0, 0.9, 1.1, 0.8, 1.0, 1.2, 0.95, 1.05]];
    let lines: Vec<f64> = (2..=320).map(|k| 0.25 * k as f64).collect();
    let pairs: Vec<(usize, usize)> = (0..12).map(|s| (s, 0)).collect();
    let request = FrfRequest {
        frequencies_hz: &lines,
        pairs: &pairs,
        quantity: Quantity::Accelerance,
    };
    let state = model.modal_state_with_fields(&kappa, &theta, &damping).unwrap();
    let analytic = model.field_frf_sensitivities(&state, &damping, request);
    let mut worst = 0.0f64;
    for j in 0..theta[0].len() {
        let h = 1e-5;
        let frfs = |sign: f64| {
            let mut t = theta.clone();
            t[0][j] += sign * h;
            let s = model.modal_state_with_fields(&kappa, &t, &damping).unwrap();
            model.evaluate(&s, request, false).h
        };
        let (plus, minus) = (frfs(1.0), frfs(-1.0));
        let nf = lines.len();
        for p in 0..pairs.len() {
            let fd: Vec<_> = (0..nf)
                .map(|f| (plus[p * nf + f] - minus[p * nf + f]) / (2.0 * h))
                .collect();
            let largest = fd.iter().map(|v| v.norm()).fold(0.0, f64::max);
            for f in 0..nf {
                let error = (analytic[j][p * nf + f] - fd[f]).norm() / largest;
                worst = worst.max(error);
                assert!(
                    error <= 1e-5,
                    "θ{j} pair {p} line {}: {} vs {}",
                    lines[f],
                    analytic[j][p * nf + f],
                    fd[f]
                );
            }
        }
    }
    eprintln!("worst error of ∂H/∂θ: {worst:.1e} of the largest |∂H| per FRF");
}

/// Damage localisation (FRF path): the deck with a 4 × 2 field of
/// piecewise-constant regions (degree 0), region (ξ 2/4–3/4, η upper half)
/// 30 % softer; accelerances P1 → P1…P12, 0.5–80 Hz every 0.25 Hz, 2 %
/// complex Gaussian noise. Updating the 8 θ and the 8 spring κ together
/// (κ from 1.3× their values, θ from 1): the softened region comes out
/// within 10 points of 0.7, every other within 5 points of 1.0, and the
/// springs within 10 %.
#[test]
fn a_local_stiffness_loss_is_found_in_its_region_with_the_springs_updated() {
    let regions = StiffnessField::new(
        KnotVector::new(vec![0.0, 0.25, 0.5, 0.75, 1.0], 0).unwrap(),
        KnotVector::new(vec![0.0, 0.5, 1.0], 0).unwrap(),
        vec![1.0; 8],
    )
    .unwrap();
    let model = FrfModel::new(with_fields(vec![regions]).assemble().unwrap(), &sinello_sensors()).unwrap();
    let damping = DampingCurve::new(2, vec![0.01; 7], 0.0, 80.0).unwrap();
    let damaged = 5; // i = 2 (ξ in [0.5, 0.75]), j = 1 (η in [0.5, 1]): η fastest
    let mut truth = vec![1.0; 8];
    truth[damaged] = 0.7;
    let lines: Vec<f64> = (2..=320).map(|k| 0.25 * k as f64).collect();
    let pairs: Vec<(usize, usize)> = (0..12).map(|r| (r, 0)).collect();
    let state = model
        .modal_state_with_fields(&true_kappa(), &[truth.clone()], &damping)
        .unwrap();
    let h = model
        .evaluate(
            &state,
            FrfRequest {
                frequencies_hz: &lines,
                pairs: &pairs,
                quantity: Quantity::Accelerance,
            },
            false,
        )
        .h;
    let nf = lines.len();
    let (re, im) = (gaussian(h.len(), 11), gaussian(h.len(), 12));
    let frfs = pairs
        .iter()
        .enumerate()
        .map(|(p, &(r, s))| MeasuredFrf {
            output: r,
            input: s,
            values: (0..nf)
                .map(|l| {
                    let k = p * nf + l;
                    h[k] * (c64::new(1.0, 0.0) + c64::new(re[k], im[k]) * (0.02 / 2f64.sqrt()))
                })
                .collect(),
            coherence: None,
            n_averages: None,
        })
        .collect();
    let measured = MeasuredSet::new(Quantity::Accelerance, lines.clone(), frfs).unwrap();
    let mut parameters = spring_parameters();
    parameters.extend((0..8).map(|coefficient| Parameter {
        name: format!("deck.s{}", coefficient + 1),
        kind: ParameterKind::Stiffness { field: 0, coefficient },
        lower: 0.3,
        upper: 1.5,
    }));
    let problem = UpdateProblem::new(
        &model,
        true_kappa(),
        damping.clone(),
        parameters,
        &measured,
        UpdateSettings::default(),
    )
    .unwrap();
    let start: Vec<f64> = true_kappa().iter().flatten().map(|k| 1.3 * k).chain([1.0; 8]).collect();
    let result = problem.solve(&start).unwrap();
    assert!(result.converged, "{:?}", result.stop_reason);
    let values: Vec<f64> = result.parameters.iter().map(|p| p.value).collect();
    for (k, want) in true_kappa().iter().flatten().enumerate() {
        assert!((values[k] / want - 1.0).abs() < 0.10, "κ{k}: {} vs {want}", values[k]);
    }
    for (j, &want) in truth.iter().enumerate() {
        let got = values[8 + j];
        let allowed = if j == damaged { 0.10 } else { 0.05 };
        assert!((got - want).abs() < allowed, "θ{j}: {got:.3} vs {want}");
    }
    eprintln!(
        "θ = {:?}",
        values[8..].iter().map(|v| format!("{v:.3}")).collect::<Vec<_>>()
    );
}

/// Which section scales the Sinello deck's bending modes below 80 Hz can
/// identify, from the relative eigenvalue sensitivities `∂λ/∂θ / λ` of
/// three global fields (membrane, bending, shear). On a flat deck the
/// bending modes carry no membrane strain: the membrane column is zero (a
/// membrane scale is not identifiable from them). Bending and shear move
/// the modes in different proportions (shear matters more for the higher,
/// shorter modes): the two columns are far from parallel (cosine 0.80),
/// and each mode's shares add up to at most 1 (the deck's share of its
/// strain energy; the springs hold the rest).
#[test]
fn section_scales_identifiability_on_the_deck() {
    use splinewatch_core::model::stiffness_field::StiffnessScale;
    let scaled = |scale| field([0, 0], [1, 1]).with_scale(scale);
    let model = FrfModel::new(
        with_fields(vec![
            scaled(StiffnessScale::Membrane),
            scaled(StiffnessScale::Bending),
            scaled(StiffnessScale::Shear),
        ])
        .assemble()
        .unwrap(),
        &sinello_sensors(),
    )
    .unwrap();
    let damping = DampingCurve::new(2, vec![0.01; 7], 0.0, 80.0).unwrap();
    let state = model
        .modal_state_with_fields(&true_kappa(), &[vec![1.0], vec![1.0], vec![1.0]], &damping)
        .unwrap();
    let modes = bending_modes_below_80_hz(&state);
    let s = model.field_sensitivities(&state, &modes);
    let column = |c: usize| -> Vec<f64> {
        (0..modes.len())
            .map(|r| s.eigenvalue[(r, c)] / state.modes.omega2[modes[r]])
            .collect()
    };
    let (membrane, bending, shear) = (column(0), column(1), column(2));
    let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    let cosine = bending.iter().zip(&shear).map(|(a, b)| a * b).sum::<f64>() / (norm(&bending) * norm(&shear));
    eprintln!(
        "{} modes: membrane share ≤ {:.1e}, bending share {:.3}–{:.3}, cos(bending, shear) = {cosine:.4}",
        modes.len(),
        membrane.iter().map(|x| x.abs()).fold(0.0, f64::max),
        bending.iter().copied().fold(f64::INFINITY, f64::min),
        bending.iter().copied().fold(0.0, f64::max),
    );
    assert!(membrane.iter().all(|x| x.abs() < 1e-9), "{membrane:?}");
    // ∂λ/∂θ / λ of a part is its share of the mode's strain energy.
    for r in 0..modes.len() {
        let sum = membrane[r] + bending[r] + shear[r];
        assert!(sum > 0.0 && sum <= 1.0 + 1e-9, "mode {}: {sum}", modes[r]);
    }
    assert!(cosine < 0.9, "bending and shear scales indistinguishable: cos {cosine}");
}

/// One modulus over two fields (`ParameterKind::StiffnessRun`: two 2 × 1
/// fields, coefficient 1 of both set to the parameter): the frequency
/// gradient of every bending mode below 80 Hz is the sum of the two fields'
/// own and matches central differences of the frequency with both
/// coefficients moved together (step 1e-4; 1e-6 relative to the largest).
#[test]
fn a_run_of_tied_fields_moves_them_together() {
    use splinewatch_core::updating::modal_residual::frequency_gradient;
    let model = FrfModel::new(
        with_fields(vec![field([0, 0], [2, 1]), field([0, 0], [2, 1])])
            .assemble()
            .unwrap(),
        &sinello_sensors(),
    )
    .unwrap();
    let damping = DampingCurve::new(2, vec![0.01; 7], 0.0, 80.0).unwrap();
    let kappa = true_kappa();
    let theta = vec![vec![1.0, 0.9], vec![1.1, 0.9]];
    let state = model.modal_state_with_fields(&kappa, &theta, &damping).unwrap();
    let parameter = |kind| Parameter {
        name: "deck.s2".into(),
        kind,
        lower: 0.3,
        upper: 1.5,
    };
    let run = [parameter(ParameterKind::StiffnessRun {
        field: 0,
        count: 2,
        coefficient: 1,
    })];
    let single = |field| [parameter(ParameterKind::Stiffness { field, coefficient: 1 })];
    let h = 1e-4;
    let at = |sign: f64| {
        let mut t = theta.clone();
        t[0][1] += sign * h;
        t[1][1] += sign * h;
        model.modal_state_with_fields(&kappa, &t, &damping).unwrap()
    };
    let (plus, minus) = (at(1.0), at(-1.0));
    let modes = bending_modes_below_80_hz(&state);
    assert!(modes.len() >= 15, "{} bending modes", modes.len());
    let gradients: Vec<(f64, f64, f64)> = modes
        .iter()
        .map(|&m| {
            let tied = frequency_gradient(&model, &state, m, &run)[0];
            let sum = frequency_gradient(&model, &state, m, &single(0))[0]
                + frequency_gradient(&model, &state, m, &single(1))[0];
            let fd = (plus.modes.frequency_hz(m) - minus.modes.frequency_hz(m)) / (2.0 * h);
            (tied, sum, fd)
        })
        .collect();
    let largest = gradients.iter().map(|g| g.2.abs()).fold(0.0, f64::max);
    assert!(largest > 0.0);
    for (m, (tied, sum, fd)) in modes.iter().zip(&gradients) {
        assert!((tied - sum).abs() <= 1e-12 * largest, "mode {m}: {tied} vs {sum}");
        assert!((tied - fd).abs() <= 1e-6 * largest, "mode {m}: {tied} vs {fd}");
    }
}
