//! The prepared eigen-solver (per decoupled block, low-rank spring update)
//! against the single dense solve of the whole pencil.
//!
//! Both are backward stable, so eigenvalues may differ by a few eps·cond
//! relative (observed ≤ 1.4e-12) and isolated mass-normalised shapes by
//! round-off (observed ≤ 3e-15): the bounds are 1e-11 and 1e-12.

use super::common::{clamped_curved_panel, sinello_model, true_kappa};
use splinewatch_core::solvers::dense_model::AssembledModel;
use splinewatch_core::solvers::modal::{self, Modes};

/// Worst relative eigenvalue difference and worst `1 - |φ_aᵀ M φ_b|` over
/// the modes below `f_max_hz` whose eigenvalue is isolated (relative gap
/// above 1e-6; a shape inside a degenerate cluster is not unique).
fn compare(asm: &AssembledModel, kappa: &[Vec<f64>], f_max_hz: f64) -> (f64, f64, usize) {
    let k = asm.stiffness_with(kappa).unwrap();
    let dense: Modes = modal::solve(&k, &asm.mass, &asm.reduction, &asm.frames).unwrap();
    let fast = asm.modes_with(kappa).unwrap();
    assert_eq!(dense.len(), fast.len());
    assert_eq!(dense.kinds, fast.kinds);
    let w2max = dense.omega2.iter().copied().fold(0.0, f64::max);
    let (mut eig, mut shape, mut compared) = (0.0f64, 0.0f64, 0);
    for i in 0..dense.len() {
        if dense.frequency_hz(i) > f_max_hz {
            break;
        }
        // Round-off zeros (rigid modes) are compared on the scale of ω²_max,
        // the backward-error scale of a symmetric eigensolver.
        let rigid = dense.omega2[i] < 1e-12 * w2max;
        let scale = if rigid { w2max } else { dense.omega2[i] };
        eig = eig.max((dense.omega2[i] - fast.omega2[i]).abs() / scale);
        let gap = |j: usize| (dense.omega2[j] - dense.omega2[i]).abs() / scale;
        let isolated = (i == 0 || gap(i - 1) > 1e-6) && (i + 1 == dense.len() || gap(i + 1) > 1e-6);
        if !isolated || rigid {
            continue;
        }
        let a = dense.shapes.col(i);
        let b = fast.shapes.col(i);
        let mb = &asm.mass * b;
        shape = shape.max(1.0 - (a.transpose() * &mb).abs());
        compared += 1;
    }
    (eig, shape, compared)
}

#[test]
fn sinello_splits_into_in_plane_and_out_of_plane_blocks() {
    let asm = sinello_model().assemble().unwrap();
    assert_eq!(asm.modal_solver().unwrap().component_sizes(), vec![130, 195]);
    let mut kappa = true_kappa();
    for scale in [1.0, 3.0] {
        kappa[0][1] *= scale;
        let (eig, shape, compared) = compare(&asm, &kappa, 200.0);
        eprintln!("Sinello ×{scale}: eig {eig:.1e}, shape {shape:.1e} over {compared} modes");
        assert!(compared >= 40);
        assert!(eig < 1e-11, "eigenvalues differ by {eig:e}");
        assert!(shape < 1e-12, "shapes differ by {shape:e}");
    }
}

#[test]
fn curved_clamped_panel_is_one_block_and_matches() {
    let model = clamped_curved_panel();
    let asm = model.assemble().unwrap();
    assert_eq!(asm.modal_solver().unwrap().component_sizes().len(), 1);
    let (eig, shape, compared) = compare(&asm, &true_kappa(), f64::INFINITY);
    eprintln!("panel: eig {eig:.1e}, shape {shape:.1e} over {compared} modes");
    assert!(eig < 1e-11 && shape < 1e-12, "eig {eig:e}, shape {shape:e}");
}
