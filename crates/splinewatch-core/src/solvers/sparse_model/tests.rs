use super::*;
use crate::geometry::knots::KnotVector;
use crate::model::material::OrthotropicMaterial;
use crate::model::shell::Shell;
use crate::model::springs::{Face, SpringDirection, SpringField};

/// A plate on two B-spline spring fields: the
/// sparse model's K(κ) equals the dense one's reduced (1e-12), and its
/// modes below 60 Hz the dense solver's (ω² 1e-9, every one found).
#[test]
fn the_sparse_model_matches_the_dense_one() {
    let shell = Shell::rectangular_plate(20.0, 8.0, 0.5, [3, 3], [12, 6]).unwrap();
    let material = OrthotropicMaterial::isotropic(30e9, 0.2, 2500.0).unwrap();
    // The paper's supports: vertical springs on strips at both ends,
    // quadratic across the width (no rigid constraint: the in-plane
    // rigid modes stay, three zero eigenvalues).
    let spring = |start: f64, end: f64, k: f64| {
        SpringField::new(
            KnotVector::new(vec![start, end], 0).unwrap(),
            KnotVector::new(vec![0.0, 0.0, 0.0, 0.5, 1.0, 1.0, 1.0], 2).unwrap(),
            vec![k, 2.0 * k, 1.5 * k, 0.8 * k],
            SpringDirection::fixed([0.0, 0.0, 1.0]).unwrap(),
            Face::Bottom,
        )
        .unwrap()
    };
    let model = BridgeModel {
        springs: vec![spring(0.0, 0.05, 1e9), spring(0.95, 1.0, 3e9)],
        stiffness_fields: Vec::new(),
        member_stiffness: Vec::new(),
        constraints: Vec::new(),
        ..BridgeModel::new(shell, material)
    };
    let dense = model.assemble().unwrap();
    let sparse = SparseModel::assemble(&model).unwrap();
    let kappa = vec![vec![1.2e9, 0.7e9, 2.0e9, 1.0e9], vec![3.0e9, 1.0e9, 0.5e9, 2.5e9]];
    let kd = dense.stiffness_with(&kappa).unwrap();
    let ks = sparse.stiffness_with_fields(&kappa, &[]).unwrap().to_dense();
    let top = (0..kd.nrows()).map(|i| kd[(i, i)].abs()).fold(0.0, f64::max);
    for i in 0..kd.nrows() {
        for j in 0..kd.ncols() {
            assert!((ks[(i, j)] - kd[(i, j)]).abs() <= 1e-12 * top, "({i}, {j})");
        }
    }
    let reference = dense.modes_with(&kappa).unwrap();
    let found = sparse.modes_below(&kappa, &[], 60.0).unwrap();
    let expected = reference.frequencies_hz().iter().filter(|&&f| f <= 60.0).count();
    assert_eq!(found.len(), expected);
    for i in 0..expected {
        let (a, b) = (found.omega2[i], reference.omega2[i]);
        if b < 1e-6 * reference.omega2[expected - 1] {
            assert!(a.abs() < 1e-6 * reference.omega2[expected - 1], "rigid mode {i}: {a}");
            continue;
        }
        assert!((a - b).abs() <= 1e-9 * b, "mode {i}: {a} vs {b}");
        assert_eq!(found.kinds[i], reference.kinds[i], "mode {i}");
    }
}
