use super::*;
use crate::geometry::knots::KnotVector;
use crate::model::damping::DampingCurve;
use crate::model::material::{OrthotropicMaterial, OrthotropicParameters};
use crate::model::shell::Shell;
use crate::model::springs::{Face, SpringDirection, SpringField};
use crate::model::BridgeModel;
use crate::response::frf::{Quantity, SensorPoint};

/// A square isotropic plate on four equal edge strips of springs:
/// symmetric under `x ↔ y`, so its modes come in exactly repeated pairs.
fn square_plate_on_springs() -> (FrfModel, Vec<Vec<f64>>) {
    let (model, sensors) = square_plate();
    let frf = FrfModel::new(model.assemble().unwrap(), &sensors).unwrap();
    (frf, vec![vec![2.0e8]; 4])
}

/// The plate of [`square_plate_on_springs`] and its three sensors.
fn square_plate() -> (BridgeModel, Vec<SensorPoint>) {
    let material = OrthotropicMaterial::new(OrthotropicParameters {
        e1: 3.0e10,
        e2: 3.0e10,
        g12: 1.25e10,
        g13: 1.25e10,
        g23: 1.25e10,
        nu12: 0.2,
        density: 2500.0,
        angle_deg: 0.0,
        shear_correction: 5.0 / 6.0,
    })
    .unwrap();
    let z = SpringDirection::fixed([0.0, 0.0, 1.0]).unwrap();
    let knots = |a: f64, b: f64| KnotVector::new(vec![a, b], 0).unwrap();
    let strip = |xi: KnotVector, eta: KnotVector| SpringField::new(xi, eta, vec![2.0e8], z, Face::Bottom).unwrap();
    let springs = vec![
        strip(knots(0.0, 0.05), knots(0.0, 1.0)),
        strip(knots(0.95, 1.0), knots(0.0, 1.0)),
        strip(knots(0.0, 1.0), knots(0.0, 0.05)),
        strip(knots(0.0, 1.0), knots(0.95, 1.0)),
    ];
    let model = BridgeModel {
        springs,
        stiffness_fields: vec![],
        member_stiffness: Vec::new(),
        constraints: vec![],
        ..BridgeModel::new(
            Shell::rectangular_plate(6.0, 6.0, 0.15, [3, 3], [7, 7]).unwrap(),
            material,
        )
    };
    let sensors: Vec<SensorPoint> = [(0.21, 0.33), (0.67, 0.18), (0.41, 0.77)]
        .iter()
        .map(|&(xi, eta)| SensorPoint {
            patch: 0,
            xi,
            eta,
            tau: 0.5,
            direction: [0.0, 0.0, 1.0],
        })
        .collect();
    (model, sensors)
}

/// The sensitivities of a few spring coefficients are those of the
/// complete evaluation, bit for bit, on the dense and the truncated
/// model (its residual's share too); the others are left empty.
#[test]
fn a_subset_of_springs_gives_their_sensitivities_alone() {
    let (shell, sensors) = square_plate();
    let kappa = vec![vec![2.0e8]; 4];
    let curve = DampingCurve::new(1, vec![0.02, 0.04], 0.0, 200.0).unwrap();
    let freqs: Vec<f64> = (1..=40).map(|k| 3.1 * k as f64).collect();
    let pairs = [(0, 0), (2, 1)];
    let request = FrfRequest {
        frequencies_hz: &freqs,
        pairs: &pairs,
        quantity: Quantity::Accelerance,
    };
    let dense = FrfModel::new(shell.assemble().unwrap(), &sensors).unwrap();
    let truncated = FrfModel::truncated(&shell, &sensors, 150.0).unwrap();
    for model in [dense, truncated] {
        let state = model.modal_state(&kappa, &curve).unwrap();
        let all = model.evaluate(&state, request, true);
        let some = model.evaluate_springs(&state, request, &[3, 1]);
        assert_eq!(some.h, all.h);
        assert_eq!(some.dh_dgamma, all.dh_dgamma);
        assert_eq!(some.dh_dkappa.len(), 4);
        for j in 0..4 {
            if j % 2 == 1 {
                assert!(!all.dh_dkappa[j].is_empty());
                assert_eq!(some.dh_dkappa[j], all.dh_dkappa[j], "κ_{j}");
            } else {
                assert!(some.dh_dkappa[j].is_empty(), "κ_{j}");
            }
        }
    }
}

/// The far pairs' difference quotient (linear in `q`) and the product
/// form `Σ_ik a_ri a_sk M_ik q_i q_k (jω E_ik − 1)` on every pair give
/// the same `∂H/∂κ_j` to round-off, with exactly repeated modes among
/// the near pairs.
#[test]
fn the_difference_quotient_equals_the_product_form() {
    let (model, kappa) = square_plate_on_springs();
    let curve = DampingCurve::new(2, vec![0.005, 0.03, 0.01, 0.06, 0.02], 0.0, 200.0).unwrap();
    let state = model.modal_state(&kappa, &curve).unwrap();
    let freqs: Vec<f64> = (1..=70).map(|k| 2.7 * k as f64).collect();
    let pairs = [(0, 0), (1, 0), (2, 0), (2, 1)];
    let request = FrfRequest {
        frequencies_hz: &freqs,
        pairs: &pairs,
        quantity: Quantity::Accelerance,
    };
    let all = model.wanted_blocks(Wanted::All);
    let split = model.prepare_with(&state, request, (Wanted::All, &all), NEAR_EIGENVALUES);
    let product = model.prepare_with(&state, request, (Wanted::All, &all), f64::INFINITY);
    let repeated = split.springs.near_pairs.len();
    assert!(repeated > 0, "the square plate has repeated modes");
    assert_eq!(product.springs.far.norm_l2(), 0.0);
    let (a, b) = (
        model.evaluate_lines(&split, request),
        model.evaluate_lines(&product, request),
    );
    for (j, (x, y)) in a.dh_dkappa.iter().zip(&b.dh_dkappa).enumerate() {
        let scale = y.iter().map(|v| v.norm()).fold(0.0, f64::max);
        let error = x.iter().zip(y).map(|(x, y)| (x - y).norm()).fold(0.0, f64::max);
        assert!(scale > 0.0 && error < 1e-11 * scale, "κ_{j}: {error:e} of {scale:e}");
    }
}
