//! Modal truncation with residual compensation: FRFs at the sensors from
//! the modes below a cut-off plus the static contribution of every mode
//! above it (the "residual flexibility", MacNeal 1971; Craig & Kurdila,
//! *Fundamentals of Structural Dynamics*, §14.4).
//!
//! Over all modes `X = (K − σM)⁻¹ = Σ_i φ_i φ_iᵀ / (ω_i² − σ)` and
//! `X M X = Σ_i φ_i φ_iᵀ / (ω_i² − σ)²` exactly, so with the kept modes
//! `i ≤ m` the discarded ones' `1/(ω_i² − ω²)`, expanded about the shift as
//! `1/(ω_i² − σ) + (ω² − σ)/(ω_i² − σ)² + …`, contribute at the sensor rows
//! `N` (eq. 32, `a_i = N φ_i`)
//! `R_0 = N X Nᵀ − Σ_{i ≤ m} a_i a_iᵀ / (ω_i² − σ)` (the residual
//! flexibility, MacNeal 1971) and `(ω² − σ) R_1` with
//! `R_1 = N X M X Nᵀ − Σ_{i ≤ m} a_i a_iᵀ / (ω_i² − σ)²` (its first dynamic
//! correction, the residual inertia of Rubin 1975): one sparse solve per
//! sensor with the factorisation of the eigen-solve's shift. Then
//! `H_rs(ω) ≈ Σ_{i ≤ m} a_{r,i} a_{s,i} / D_i(ω) + R_0,rs + (ω² − σ) R_1,rs`
//! (eq. 31), whose error is of order `((ω² − σ) / ω²_{m+1})²` of the
//! discarded part (damping of the discarded modes neglected): small in a
//! band well below the cut-off (2× the band's top by default).

use crate::frf::Quantity;
use crate::modal::Modes;
use faer::{c64, Mat};

/// The truncated modal model at the sensors.
#[derive(Debug, Clone)]
pub struct TruncatedFrf {
    omega2: Vec<f64>,
    zeta: Vec<f64>,
    /// `a_{s,i}`: sensors × kept modes.
    amplitudes: Mat<f64>,
    /// `R_0`, `R_1`: sensors × sensors.
    residual: Mat<f64>,
    inertia: Mat<f64>,
    shift: f64,
}

impl TruncatedFrf {
    /// From the kept `modes` (their damping ratios `zeta`), the sensor rows
    /// on the generalised dofs, `N X Nᵀ` and `N X M X Nᵀ` at the sensors
    /// (`crate::sparse_model::SparseModel::flexibility`) and the shift `σ`.
    #[track_caller]
    pub fn new(
        modes: &Modes,
        zeta: Vec<f64>,
        sensor_rows: &[Vec<(usize, f64)>],
        flexibility: &(Mat<f64>, Mat<f64>),
        shift: f64,
    ) -> Self {
        let ns = sensor_rows.len();
        let (x, xmx) = flexibility;
        assert_eq!((x.nrows(), x.ncols()), (ns, ns), "a flexibility per sensor pair");
        assert_eq!(zeta.len(), modes.len(), "a damping ratio per mode");
        let amplitudes = Mat::from_fn(ns, modes.len(), |s, i| {
            sensor_rows[s].iter().map(|&(d, v)| v * modes.shapes[(d, i)]).sum()
        });
        let kept = |power: i32| {
            Mat::from_fn(ns, ns, |r, s| {
                (0..modes.len())
                    .map(|i| amplitudes[(r, i)] * amplitudes[(s, i)] / (modes.omega2[i] - shift).powi(power))
                    .sum::<f64>()
            })
        };
        Self {
            residual: x - kept(1),
            inertia: xmx - kept(2),
            omega2: modes.omega2.clone(),
            zeta,
            amplitudes,
            shift,
        }
    }

    /// `H_rs` at `omega` rad/s, with (`compensated`) or without the residual.
    pub fn frf(&self, r: usize, s: usize, omega: f64, quantity: Quantity, compensated: bool) -> c64 {
        let mut h = c64::new(0.0, 0.0);
        for i in 0..self.omega2.len() {
            let w2 = self.omega2[i].max(0.0);
            let d = c64::new(w2 - omega * omega, 2.0 * self.zeta[i] * w2.sqrt() * omega);
            h += self.amplitudes[(r, i)] * self.amplitudes[(s, i)] / d;
        }
        if compensated {
            h += self.residual[(r, s)] + (omega * omega - self.shift) * self.inertia[(r, s)];
        }
        h * quantity.factor(omega)
    }

    /// The residual flexibility `R_0` and inertia `R_1` at the sensors.
    pub fn residuals(&self) -> (&Mat<f64>, &Mat<f64>) {
        (&self.residual, &self.inertia)
    }
}
