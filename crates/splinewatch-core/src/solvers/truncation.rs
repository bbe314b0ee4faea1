//! Modal truncation with residual compensation: the modes above a cut-off
//! enter FRFs and their sensitivities through their static contribution
//! (the "residual flexibility", MacNeal 1971; Craig & Kurdila,
//! *Fundamentals of Structural Dynamics*, §14.4) and its first dynamic
//! correction (the residual inertia, Rubin 1975).
//!
//! Over all modes `X = (K − σM)⁻¹ = Σ_i φ_i φ_iᵀ / (ω_i² − σ)` and
//! `X M X = Σ_i φ_i φ_iᵀ / (ω_i² − σ)²` exactly, so with the kept modes
//! `i ≤ m` the discarded ones' `1/(ω_i² − ω²)`, expanded about the shift as
//! `1/(ω_i² − σ) + (ω² − σ)/(ω_i² − σ)² + …`, give the response of the
//! generalised dofs to a unit load at sensor `s` (row `N_s`, eq. 32)
//! `ρ_s(ω) = ρ_0,s + (ω² − σ) ρ_1,s` with
//! `ρ_0,s = X N_sᵀ − Σ_{i ≤ m} φ_i a_{s,i} / (ω_i² − σ)` and
//! `ρ_1,s = X M X N_sᵀ − Σ_{i ≤ m} φ_i a_{s,i} / (ω_i² − σ)²`: one sparse
//! solve pair per sensor with the factorisation of the eigen-solve's shift.
//! At the sensors `R_p = N ρ_p`, and (eq. 31)
//! `H_rs(ω) ≈ Σ_{i ≤ m} a_{r,i} a_{s,i} / D_i(ω) + R_0,rs + (ω² − σ) R_1,rs`,
//! whose error is of order `((ω² − σ) / ω²_{m+1})²` of the discarded part:
//! small in a band well below the cut-off (2× the band's top by default).
//!
//! Damping of the discarded modes: to first order their
//! `−2j ζ_d ω_d ω / (ω_d² − ω²)²` adds `−2j ω Σ_d ζ_d ω_d a a / (ω_d² − σ)²`;
//! with one effective mode for all of them this is `−2j ω ζ_e ω_e R_1`,
//! `ω_e² = σ + tr R_0 / tr R_1` (exact when a single mode is discarded) and
//! `ζ_e = ζ(ω_e / 2π)` from the damping curve (eq. 29, held constant beyond
//! its band as for every mode). Without it a damped deck's FRFs miss by the
//! discarded modes' damping (2e-3 of the peak for ζ = 3 % at the cut-off,
//! against 2e-4 for ζ = 0.3 %).
//!
//! Sensitivities (eq. 33): the spring dofs' responses `g_s = Σ φ_i a_{s,i}
//! q_i + ρ_s` keep `∂H_rs/∂κ_j = −g_rᵀ (∂K/∂κ_j) g_s` accurate; an
//! eigenvector derivative's expansion over the kept modes gets the discarded
//! modes' part as `−(ρ_0,s + (λ_i − σ) ρ_1,s)ᵀ (∂K/∂κ_j) φ_i` (the modified
//! modal method, Wang 1991, with the same first-order correction). A
//! stiffness field's `∂K/∂θ` reaches the whole deck, so models with fields
//! keep `ρ_0`, `ρ_1` on every dof ([`Residual::everywhere`], one product
//! each) and the same two formulas apply there
//! ([`crate::response::modal_sensitivity`]).

use crate::model::damping::DampingCurve;
use crate::solvers::modal::Modes;
use faer::{c64, Mat};
use std::f64::consts::PI;

/// A truncated model's modal basis at a parameter point, as an update
/// reports it.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct TruncationReport {
    pub cutoff_hz: f64,
    /// Modes solved below the cut-off (the rest enter as the residual).
    pub modes_kept: usize,
    /// Largest error of the fitted FRFs against the every-mode model,
    /// relative to each FRF's peak, where that model was evaluated (small
    /// models, FRF fits).
    pub frf_error: Option<f64>,
}

/// What the modes above the cut-off contribute, seen from the sensors and
/// the spring dofs.
#[derive(Debug, Clone)]
pub struct Residual {
    shift: f64,
    /// `R_0`, `R_1`: sensors × sensors.
    sensors: [Mat<f64>; 2],
    /// `ρ_0`, `ρ_1` on the spring dofs `U`: `|U|` × sensors.
    springs: [Mat<f64>; 2],
    /// `ρ_0`, `ρ_1` on every generalised dof (models with stiffness
    /// fields, whose `∂K/∂θ` reach the whole deck): dofs × sensors.
    everywhere: Option<[Mat<f64>; 2]>,
    /// `ζ_e ω_e` of the effective discarded mode.
    damping_rate: f64,
    /// `∂(ζ_e ω_e)/∂γ_z = B_z(f_e) ω_e`.
    damping_gradient: Vec<f64>,
}

impl Residual {
    /// From the kept `modes` (full generalised dofs), their sensor
    /// amplitudes `a_{s,i}` (sensors × modes), the sensor rows, the
    /// spring dofs `U`, the responses `(X Nᵀ, X M X Nᵀ)` on the generalised
    /// dofs ([`crate::solvers::sparse_model::SparseModel::modes_and_responses`]) and the
    /// shift `σ` they were solved at; `damping` gives the discarded modes'
    /// damping ratio. With `everywhere`, `ρ_0` and `ρ_1` are kept on every
    /// generalised dof too (stiffness-field sensitivities).
    #[allow(
        clippy::too_many_arguments,
        reason = "the residual's inputs, each a different quantity of eq. 31"
    )]
    #[track_caller]
    pub fn new(
        modes: &Modes,
        amplitudes: &Mat<f64>,
        sensor_rows: &[Vec<(usize, f64)>],
        spring_dofs: &[usize],
        responses: &(Mat<f64>, Mat<f64>),
        shift: f64,
        damping: &DampingCurve,
        everywhere: bool,
    ) -> Self {
        let ns = sensor_rows.len();
        let nm = modes.len();
        let phi = &modes.shapes;
        assert_eq!(responses.0.ncols(), ns, "a response per sensor");
        assert_eq!(responses.0.nrows(), phi.nrows(), "responses on the generalised dofs");
        assert_eq!(
            (amplitudes.nrows(), amplitudes.ncols()),
            (ns, nm),
            "an amplitude per sensor and mode"
        );
        let at = |response: &Mat<f64>, power: i32, d: usize, s: usize| {
            response[(d, s)]
                - (0..nm)
                    .map(|i| phi[(d, i)] * amplitudes[(s, i)] / (modes.omega2[i] - shift).powi(power))
                    .sum::<f64>()
        };
        let on_sensors = |response: &Mat<f64>, power: i32| {
            let r = Mat::from_fn(ns, ns, |r, s| {
                sensor_rows[r]
                    .iter()
                    .map(|&(d, v)| v * at(response, power, d, s))
                    .sum::<f64>()
            });
            Mat::from_fn(ns, ns, |a, b| 0.5 * (r[(a, b)] + r[(b, a)]))
        };
        let on_springs = |response: &Mat<f64>, power: i32| {
            Mat::from_fn(spring_dofs.len(), ns, |u, s| at(response, power, spring_dofs[u], s))
        };
        let sensors = [on_sensors(&responses.0, 1), on_sensors(&responses.1, 2)];
        let trace = |m: &Mat<f64>| (0..ns).map(|s| m[(s, s)]).sum::<f64>();
        let (t0, t1) = (trace(&sensors[0]), trace(&sensors[1]));
        let mut damping_gradient = vec![0.0; damping.coefficients().len()];
        let mut damping_rate = 0.0;
        if t0 > 0.0 && t1 > 0.0 {
            let omega_e = (shift + t0 / t1).max(0.0).sqrt();
            damping.basis_at(omega_e / (2.0 * PI), &mut damping_gradient);
            damping_gradient.iter_mut().for_each(|b| *b *= omega_e);
            damping_rate = damping_gradient
                .iter()
                .zip(damping.coefficients())
                .map(|(b, g)| b * g)
                .sum();
        }
        // ρ_p = R_p − Φ diag((λ − σ)^−p) Aᵀ on every dof: one product each.
        let everywhere = everywhere.then(|| {
            [(&responses.0, 1), (&responses.1, 2)].map(|(response, power)| {
                let scaled = Mat::from_fn(nm, ns, |i, s| {
                    amplitudes[(s, i)] / (modes.omega2[i] - shift).powi(power)
                });
                response - phi * scaled
            })
        });
        Self {
            shift,
            sensors,
            everywhere,
            springs: [on_springs(&responses.0, 1), on_springs(&responses.1, 2)],
            damping_rate,
            damping_gradient,
        }
    }

    /// The receptance `R_0,rs + (ω² − σ − 2j ζ_e ω_e ω) R_1,rs` at `omega` rad/s.
    pub fn at_sensors(&self, r: usize, s: usize, omega: f64) -> c64 {
        self.expansion_factor(omega) * self.sensors[1][(r, s)] + self.sensors[0][(r, s)]
    }

    /// `γ(ω) = ω² − σ − 2j ζ_e ω_e ω`: a residual at `ω` is `ρ_0 + γ ρ_1`.
    pub fn expansion_factor(&self, omega: f64) -> c64 {
        c64::new(omega * omega - self.shift, -2.0 * omega * self.damping_rate)
    }

    /// `ρ_0`, `ρ_1` on the spring dofs `U` (`|U|` × sensors).
    pub fn spring_terms(&self) -> (&Mat<f64>, &Mat<f64>) {
        (&self.springs[0], &self.springs[1])
    }

    /// `ρ_0,s + (λ − σ) ρ_1,s` at spring dof `u`: the discarded modes'
    /// undamped `Σ_d φ_d a_{s,d} / (λ_d − λ)` to first order (eigenvector
    /// derivatives).
    pub fn expansion_on_springs(&self, u: usize, s: usize, lambda: f64) -> f64 {
        self.springs[0][(u, s)] + (lambda - self.shift) * self.springs[1][(u, s)]
    }

    /// The shift `σ` the residual is expanded about.
    pub fn shift(&self) -> f64 {
        self.shift
    }

    /// `ρ_0`, `ρ_1` on every generalised dof (dofs × sensors), when kept.
    pub fn everywhere(&self) -> Option<&[Mat<f64>; 2]> {
        self.everywhere.as_ref()
    }

    /// The damping curve's coefficients the residual depends on (the
    /// discarded modes are damped by the curve alone: the supports' loss
    /// factors, which need each mode's shape, do not reach them).
    pub fn damping_coefficient_count(&self) -> usize {
        self.damping_gradient.len()
    }

    /// `∂/∂γ_z` of [`Self::at_sensors`]: `−2j ω B_z(f_e) ω_e R_1,rs`.
    pub fn damping_sensitivity(&self, r: usize, s: usize, omega: f64, z: usize) -> c64 {
        c64::new(0.0, -2.0 * omega * self.damping_gradient[z] * self.sensors[1][(r, s)])
    }
}
