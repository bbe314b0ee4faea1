//! Eigenvalue and eigenvector derivatives (Fox & Kapoor, modal expansion)
//! against central finite differences on the Sinello deck.

use super::common::{bending_modes_below_80_hz, check_eigen_derivatives, sinello_model, sinello_sensors, true_kappa};
use splinewatch_core::model::damping::DampingCurve;
use splinewatch_core::response::frf::FrfModel;

/// Every bending mode below 80 Hz, every spring coefficient: `∂λ/∂κ` within
/// 1e-7 relative and the sensor amplitudes' derivatives within 1e-6 of the
/// largest amplitude per unit relative change of κ (central differences,
/// step 1e-4 κ: truncation ~1e-8, round-off ~1e-12/1e-4). Reached: 1.2e-8
/// and 7.0e-8.
#[test]
fn eigen_derivatives_match_central_differences() {
    let model = FrfModel::new(sinello_model().assemble().unwrap(), &sinello_sensors()).unwrap();
    let damping = DampingCurve::new(2, vec![0.01; 7], 0.0, 80.0).unwrap();
    let kappa = true_kappa();
    let state = model.modal_state(&kappa, &damping).unwrap();
    let modes = bending_modes_below_80_hz(&state);
    assert_eq!(modes.len(), 18);
    let analytic = model.modal_sensitivities(&state, &modes);
    let mut j = 0;
    let (mut worst_lambda, mut worst_shape) = (0.0f64, 0.0f64);
    for (field, values) in kappa.iter().enumerate() {
        for c in 0..values.len() {
            let h = 1e-4 * values[c];
            let at = |sign: f64| {
                let mut k = kappa.clone();
                k[field][c] += sign * h;
                model.modal_state(&k, &damping).unwrap()
            };
            let (plus, minus) = (at(1.0), at(-1.0));
            let (l, a) = check_eigen_derivatives(&state, (&plus, &minus), h, values[c], &analytic, j);
            worst_lambda = worst_lambda.max(l);
            worst_shape = worst_shape.max(a);
            j += 1;
        }
    }
    eprintln!("worst relative error: eigenvalues {worst_lambda:.1e}, amplitudes {worst_shape:.1e}");
}
