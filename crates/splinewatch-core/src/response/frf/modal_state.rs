//! The modal model at one parameter point: modes, damping ratios and
//! their derivatives, amplitudes at the sensors and on the spring dofs.

use super::support_loss;
use crate::solvers::modal::Modes;
use crate::solvers::truncation::Residual;
use faer::Mat;

/// The modal model at one parameter point.
#[derive(Debug, Clone)]
pub struct ModalState {
    pub modes: Modes,
    /// ζ_i of every mode (eq. 28, and the supports' loss factors' share,
    /// [`crate::model::damping`]), zero for rigid modes.
    pub zeta: Vec<f64>,
    /// `∂ζ_i/∂γ_z`, then `∂ζ_i/∂η_s`: `n_modes × (n_z + n_η)`.
    pub(super) zeta_basis: Mat<f64>,
    /// `dc_i/dλ_i` of the modal damping rate `c_i = 2 ζ_i ω_i` as the
    /// mode's eigenvalue `λ_i = ω_i²` changes with its shape held:
    /// `ζ_i/ω_i + ζ'(f_i)/(2π) − Σ_s η_s e_{i,s}/ω_i`, zero for rigid modes
    /// (the spring sensitivities' damping term).
    pub(super) damping_rate_slope: Vec<f64>,
    /// The supports' strain energies and loss factors, when the damping
    /// has loss factors ([`support_loss`]).
    pub(super) loss: Option<support_loss::SupportLoss>,
    /// The spring coefficients the modes were solved at.
    pub(super) kappa: Vec<Vec<f64>>,
    /// The stiffness-field coefficients the modes were solved at.
    pub(super) theta: Vec<Vec<f64>>,
    /// `a_{s,i}`: `n_sensors × n_modes`.
    pub(super) amplitudes: Mat<f64>,
    /// Mode shapes on the spring dofs `U`: `|U| × n_modes`.
    pub(super) phi_springs: Mat<f64>,
    pub(super) omega: Vec<f64>,
    /// The discarded modes' contribution when only the modes below a
    /// cut-off were solved ([`crate::solvers::truncation`]).
    pub(super) residual: Option<Residual>,
}

impl ModalState {
    /// Mode shapes on the union of the spring dofs (`|U| × modes`).
    pub fn spring_shapes(&self) -> &Mat<f64> {
        &self.phi_springs
    }

    /// Modal amplitude of mode `i` at sensor `s` along its direction.
    pub fn amplitude(&self, sensor: usize, mode: usize) -> f64 {
        self.amplitudes[(sensor, mode)]
    }

    /// Number of sensors (the rows of the amplitudes).
    pub fn sensor_count(&self) -> usize {
        self.amplitudes.nrows()
    }

    /// The residual of the discarded modes (a truncated model's state).
    pub fn residual(&self) -> Option<&Residual> {
        self.residual.as_ref()
    }

    /// The share of mode `i`'s strain energy in loss site `s` (`e_{i,s}`;
    /// by default spring field `s`), when the damping has loss factors.
    pub fn support_energy(&self, i: usize, s: usize) -> Option<f64> {
        self.loss.as_ref().map(|l| l.energy[(i, s)])
    }

    /// The column of loss site `site`'s `η` in [`Self::zeta_gradient`].
    #[track_caller]
    pub fn loss_factor_column(&self, site: usize) -> usize {
        let sites = self.loss.as_ref().map_or(0, |l| l.energy.ncols());
        assert!(site < sites, "no such loss site");
        self.zeta_basis.ncols() - sites + site
    }

    /// The supports' share of `ζ_i` (`½ Σ_s η_s e_{i,s}`; zero without
    /// loss factors).
    pub fn support_zeta(&self, i: usize) -> f64 {
        self.loss.as_ref().map_or(0.0, |l| 0.5 * l.loss(i))
    }

    /// `∂ζ_i/∂γ_z` for every damping parameter (the curve's, then the loss
    /// factors).
    pub fn zeta_gradient(&self, i: usize) -> Vec<f64> {
        (0..self.zeta_basis.ncols()).map(|z| self.zeta_basis[(i, z)]).collect()
    }
}
