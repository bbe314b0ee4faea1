//! The direct path of eq. (31)–(32), `Z(ω) x = N_sᵀ`: the reference the
//! modal superposition is checked against.

use super::{FrfError, FrfModel, ModalState, Quantity};
use crate::linalg::complex_solve;
use faer::{c64, Mat};
use std::f64::consts::PI;

impl FrfModel {
    /// The direct path of eq. (31)–(32): solves `Z(ω) x = N_sᵀ` with
    /// `Z = K - ω²M + jωC`, `C = M Φ diag(2ζω) Φᵀ M` (eq. 25 with
    /// `Φ⁻¹ = Φᵀ M`), and returns `N_r x` in the requested quantity.
    /// `C` comes from `state`; `kappa` sets `K`. For verification: `O(n³)`
    /// per frequency.
    pub fn direct(
        &self,
        kappa: &[Vec<f64>],
        state: &ModalState,
        frequency_hz: f64,
        pair: (usize, usize),
        quantity: Quantity,
    ) -> Result<c64, FrfError> {
        let dense = self.dense().ok_or(FrfError::DenseOnly("the direct FRF solve"))?;
        let k = dense.stiffness_with(kappa)?;
        let m = &dense.mass;
        let n = m.nrows();
        let phi = &state.modes.shapes;
        let d = Mat::from_fn(phi.ncols(), phi.ncols(), |i, j| {
            if i == j {
                2.0 * state.zeta[i] * state.omega[i]
            } else {
                0.0
            }
        });
        let mphi = m * phi;
        let c = &mphi * &d * mphi.transpose();
        let w = 2.0 * PI * frequency_hz;
        let red = &dense.reduction;
        let z_re = red.reduce(&Mat::from_fn(n, n, |i, j| k[(i, j)] - w * w * m[(i, j)]));
        let z_im = red.reduce(&Mat::from_fn(n, n, |i, j| w * c[(i, j)]));
        let full_rhs = |s: usize| {
            let mut v = Mat::<f64>::zeros(n, 1);
            for &(dof, val) in &self.sensor_rows[s] {
                v[(dof, 0)] += val;
            }
            v
        };
        let rhs = red.reduce_vector(&full_rhs(pair.1));
        let x = complex_solve(&z_re, &z_im, &rhs).ok_or(FrfError::SingularImpedance { frequency_hz })?;
        let (x_re, x_im) = (red.expand(&x.0), red.expand(&x.1));
        let response = self.sensor_rows[pair.0]
            .iter()
            .fold(c64::new(0.0, 0.0), |acc, &(dof, v)| {
                acc + c64::new(x_re[(dof, 0)], x_im[(dof, 0)]) * v
            });
        Ok(response * quantity.factor(w))
    }
}
