//! B-spline modal damping curve (paper §2.3, eq. 25–29).
//!
//! `ζ(f) = Σ_z B_z(u) γ_z` with `u = (f - f_start) / (f_end - f_start)` on a
//! uniform clamped knot vector over `[0, 1]` (eq. 29); outside the band `u`
//! is clamped, so ζ keeps its end values. Mode `i` gets `ζ_i = ζ(f_i)` with
//! `f_i = ω_i / 2π` (eq. 28 prints `2π·ω_i`, a typo). The damping matrix of
//! eq. (25), `C = Φ⁻ᵀ diag(2 ζ_i ω_i) Φ⁻¹`, is diagonal in modal coordinates,
//! so the FRF code never forms it except for the direct verification path.
//!
//! Loss factors on the supports (modal strain energy, Johnson & Kienholz
//! 1982): site `s` (by default a whole spring field, bearing or line
//! support, in the model's order of spring fields; or any set of spring
//! coefficients, [`LossSites`]: one component of a support, or of several)
//! may carry a loss factor `η_s`, and mode
//! `i` then gets `ζ_i = ζ(f_i) + ½ Σ_s η_s e_{i,s}`, `e_{i,s}` the share of
//! the mode's strain energy in site `s` (`φ_iᵀ K_s φ_i / ω_i²`): modes
//! whose energy sits in the abutments are damped more. It is the first
//! order of the complex modes of `K + j Σ_s η_s K_s`: exact to `O(η²)` when
//! the hysteretic matrix couples modes far apart in frequency only weakly
//! (`|η φ_iᵀ K_s φ_k| ≪ |λ_i − λ_k|`), as the verification checks.

use super::loss_sites::LossSites;
use crate::geometry::knots::{KnotError, KnotVector, MAX_DEGREE};
use thiserror::Error;

#[derive(Debug, Clone, PartialEq, Error)]
pub enum DampingError {
    #[error("band [{f_start}, {f_end}] Hz must be finite with f_start < f_end")]
    Band { f_start: f64, f_end: f64 },
    #[error("{0}")]
    Knots(#[from] KnotError),
    #[error("coefficient {index} must be finite and non-negative, got {value}")]
    Coefficient { index: usize, value: f64 },
    #[error("loss factor {index} must be finite and non-negative, got {value}")]
    LossFactor { index: usize, value: f64 },
    #[error("{factors} loss factors for {sites} loss sites: one factor per site")]
    LossSiteCount { factors: usize, sites: usize },
}

/// A validated damping curve ζ(f).
#[derive(Debug, Clone, PartialEq)]
pub struct DampingCurve {
    knots: KnotVector,
    f_start: f64,
    f_end: f64,
    gamma: Vec<f64>,
    /// `η_s` per loss site; empty without support damping.
    loss_factors: Vec<f64>,
    /// Where each `η_s` acts; `None`: one site per spring field.
    loss_sites: Option<LossSites>,
}

impl DampingCurve {
    /// Degree `degree`, coefficients `gamma` (their count sets `n_z`), band in Hz.
    pub fn new(degree: usize, gamma: Vec<f64>, f_start: f64, f_end: f64) -> Result<Self, DampingError> {
        if !(f_start.is_finite() && f_end.is_finite() && f_start < f_end) {
            return Err(DampingError::Band { f_start, f_end });
        }
        let knots = KnotVector::uniform(degree, gamma.len(), 0.0, 1.0)?;
        let curve = Self {
            knots,
            f_start,
            f_end,
            gamma: Vec::new(),
            loss_factors: Vec::new(),
            loss_sites: None,
        };
        curve.with_coefficients(gamma)
    }

    /// The same curve with other coefficients (same count).
    #[track_caller]
    pub fn with_coefficients(&self, gamma: Vec<f64>) -> Result<Self, DampingError> {
        if !self.gamma.is_empty() {
            assert_eq!(gamma.len(), self.gamma.len(), "coefficient count is fixed");
        }
        if let Some(index) = gamma.iter().position(|g| !(g.is_finite() && *g >= 0.0)) {
            return Err(DampingError::Coefficient {
                index,
                value: gamma[index],
            });
        }
        Ok(Self { gamma, ..self.clone() })
    }

    pub fn coefficients(&self) -> &[f64] {
        &self.gamma
    }

    /// The same curve with loss factors `η_s`, one per loss site (empty:
    /// none). Without [`Self::with_loss_sites`] a site is a spring field of
    /// the model and any count is taken here: the model checks it against
    /// its spring fields.
    pub fn with_loss_factors(&self, loss_factors: Vec<f64>) -> Result<Self, DampingError> {
        if let Some(index) = loss_factors.iter().position(|g| !(g.is_finite() && *g >= 0.0)) {
            return Err(DampingError::LossFactor {
                index,
                value: loss_factors[index],
            });
        }
        if let Some(sites) = self.loss_sites.as_ref().filter(|s| s.len() != loss_factors.len()) {
            return Err(DampingError::LossSiteCount {
                factors: loss_factors.len(),
                sites: sites.len(),
            });
        }
        Ok(Self {
            loss_factors,
            ..self.clone()
        })
    }

    /// The same curve with its loss factors acting on `sites` (one site per
    /// loss factor) instead of one spring field each.
    pub fn with_loss_sites(&self, sites: LossSites) -> Result<Self, DampingError> {
        if sites.len() != self.loss_factors.len() {
            return Err(DampingError::LossSiteCount {
                factors: self.loss_factors.len(),
                sites: sites.len(),
            });
        }
        Ok(Self {
            loss_sites: Some(sites),
            ..self.clone()
        })
    }

    /// `η_s` per loss site (empty without support damping).
    pub fn loss_factors(&self) -> &[f64] {
        &self.loss_factors
    }

    /// Where the loss factors act, for a model whose spring fields have
    /// `field_sizes` coefficients: the sites given, or one per field.
    pub fn loss_sites(&self, field_sizes: &[usize]) -> LossSites {
        self.loss_sites
            .clone()
            .unwrap_or_else(|| LossSites::per_field(field_sizes))
    }

    /// Whether a loss factor weighs stiffness-field coefficients (a patch's
    /// or a beam member's part of the stiffness).
    pub fn has_field_sites(&self) -> bool {
        self.loss_sites.as_ref().is_some_and(LossSites::has_fields)
    }

    /// Twice the supports' share of a mode's damping, `Σ_s η_s e_s`, from
    /// its strain-energy share `springs[j]` in each spring coefficient and
    /// `fields[k]` in each stiffness-field coefficient's part
    /// (`field_sizes` as [`Self::loss_sites`]).
    #[track_caller]
    pub fn support_loss(&self, (springs, fields): (&[f64], &[f64]), field_sizes: &[usize]) -> f64 {
        let sites = self.loss_sites(field_sizes);
        self.loss_factors
            .iter()
            .enumerate()
            .map(|(s, eta)| {
                let site = sites.site(s);
                let energy = site.springs.iter().map(|&j| springs[j]).sum::<f64>()
                    + site.fields.iter().map(|&k| fields[k]).sum::<f64>();
                eta * energy
            })
            .sum()
    }

    /// The column of loss site `site`'s `η` among the damping parameters
    /// ([`Self::parameter_count`]).
    pub fn loss_factor_column(&self, site: usize) -> usize {
        self.gamma.len() + site
    }

    /// Every damping parameter: the curve's `γ_z`, then the loss factors
    /// `η_s` (the columns of the damping sensitivities).
    pub fn parameter_count(&self) -> usize {
        self.gamma.len() + self.loss_factors.len()
    }

    pub fn degree(&self) -> usize {
        self.knots.degree()
    }

    /// Greville abscissa of each coefficient in Hz: where γ_z "sits" on the
    /// curve (for plotting the control polygon).
    pub fn coefficient_frequencies(&self) -> Vec<f64> {
        let (f0, f1) = self.band();
        self.knots.greville().iter().map(|u| f0 + (f1 - f0) * u).collect()
    }

    pub fn band(&self) -> (f64, f64) {
        (self.f_start, self.f_end)
    }

    fn parameter(&self, f: f64) -> f64 {
        ((f - self.f_start) / (self.f_end - self.f_start)).clamp(0.0, 1.0)
    }

    /// `∂ζ/∂γ_z` at `f`: the basis values, written densely to `out` (length `n_z`).
    #[track_caller]
    pub fn basis_at(&self, f: f64, out: &mut [f64]) {
        assert_eq!(out.len(), self.gamma.len());
        out.fill(0.0);
        let u = self.parameter(f);
        let span = self.knots.span(u);
        let mut values = [0.0; MAX_DEGREE + 1];
        self.knots.basis(span, u, &mut values);
        let p = self.knots.degree();
        for r in 0..=p {
            out[span - p + r] = values[r];
        }
    }

    /// `dζ/df` at `f` (1/Hz); zero outside the band, where ζ is held constant.
    pub fn slope(&self, f: f64) -> f64 {
        let width = self.f_end - self.f_start;
        let u = (f - self.f_start) / width;
        if !(0.0..=1.0).contains(&u) {
            return 0.0;
        }
        let span = self.knots.span(u);
        let (mut values, mut derivatives) = ([0.0; MAX_DEGREE + 1], [0.0; MAX_DEGREE + 1]);
        self.knots
            .basis_with_derivatives(span, u, &mut values, &mut derivatives);
        let p = self.knots.degree();
        (0..=p).map(|r| derivatives[r] * self.gamma[span - p + r]).sum::<f64>() / width
    }

    /// Eq. (29): ζ(f).
    pub fn zeta(&self, f: f64) -> f64 {
        let mut b = vec![0.0; self.gamma.len()];
        self.basis_at(f, &mut b);
        b.iter().zip(&self.gamma).map(|(b, g)| b * g).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::loss_sites::LossSite;

    #[test]
    fn slope_is_the_derivative_of_zeta_and_zero_outside_the_band() {
        let c = DampingCurve::new(3, vec![0.01, 0.03, 0.012, 0.02, 0.008, 0.015], 5.0, 85.0).unwrap();
        for f in [5.5, 17.3, 40.0, 61.2, 84.1] {
            let h = 1e-5;
            let fd = (c.zeta(f + h) - c.zeta(f - h)) / (2.0 * h);
            assert!((c.slope(f) - fd).abs() < 1e-8, "{f}: {} vs {fd}", c.slope(f));
        }
        assert_eq!(c.slope(2.0), 0.0);
        assert_eq!(c.slope(90.0), 0.0);
    }

    #[test]
    fn constant_coefficients_give_constant_damping_and_clamp_outside() {
        let c = DampingCurve::new(2, vec![0.02; 7], 0.0, 80.0).unwrap();
        for f in [-5.0, 0.0, 13.3, 79.9, 80.0, 200.0] {
            assert!((c.zeta(f) - 0.02).abs() < 1e-15);
        }
    }

    #[test]
    fn linear_coefficients_reproduce_a_line() {
        // Greville-placed linear coefficients reproduce ζ linear in f.
        let kv = KnotVector::uniform(2, 7, 0.0, 1.0).unwrap();
        let gamma: Vec<f64> = kv.greville().iter().map(|u| 0.01 + 0.02 * u).collect();
        let c = DampingCurve::new(2, gamma, 10.0, 90.0).unwrap();
        assert!((c.zeta(50.0) - 0.02).abs() < 1e-15);
        assert!((c.zeta(5.0) - 0.01).abs() < 1e-15);
        assert!((c.zeta(95.0) - 0.03).abs() < 1e-15);
    }

    #[test]
    fn rejects_bad_input() {
        assert!(matches!(
            DampingCurve::new(2, vec![0.01; 7], 80.0, 0.0),
            Err(DampingError::Band { .. })
        ));
        assert!(matches!(
            DampingCurve::new(2, vec![0.01; 2], 0.0, 80.0),
            Err(DampingError::Knots(_))
        ));
        assert!(matches!(
            DampingCurve::new(2, vec![0.01, f64::NAN, 0.01], 0.0, 80.0),
            Err(DampingError::Coefficient { index: 1, .. })
        ));
        let curve = DampingCurve::new(1, vec![0.01; 2], 0.0, 80.0).unwrap();
        assert!(matches!(
            curve.with_loss_factors(vec![0.1, -0.2]),
            Err(DampingError::LossFactor { index: 1, .. })
        ));
        let lossy = curve.with_loss_factors(vec![0.1, 0.0]).unwrap();
        assert_eq!(lossy.parameter_count(), 4);
        assert_eq!(
            lossy.with_coefficients(vec![0.02; 2]).unwrap().loss_factors(),
            &[0.1, 0.0]
        );
        let one_site = LossSites::new(vec![LossSite::springs(vec![2])]).unwrap();
        assert!(matches!(
            lossy.with_loss_sites(one_site.clone()),
            Err(DampingError::LossSiteCount { factors: 2, sites: 1 })
        ));
        let sited = curve
            .with_loss_factors(vec![0.3])
            .unwrap()
            .with_loss_sites(one_site)
            .unwrap();
        assert!(matches!(
            sited.with_loss_factors(vec![0.1, 0.2]),
            Err(DampingError::LossSiteCount { factors: 2, sites: 1 })
        ));
    }

    #[test]
    fn the_support_loss_weighs_each_sites_coefficients() {
        let curve = DampingCurve::new(1, vec![0.01; 2], 0.0, 80.0).unwrap();
        let shares = [0.1, 0.2, 0.3, 0.4];
        // One site per field: fields of 1 and 3 coefficients.
        let per_field = curve.with_loss_factors(vec![0.5, 0.2]).unwrap();
        assert!((per_field.support_loss((&shares, &[]), &[1, 3]) - (0.05 + 0.2 * 0.9)).abs() < 1e-15);
        // The second and last coefficients only, and a stiffness field's
        // second coefficient.
        let sited = curve
            .with_loss_factors(vec![0.4, 0.1])
            .unwrap()
            .with_loss_sites(LossSites::new(vec![LossSite::springs(vec![1, 3]), LossSite::fields(vec![1])]).unwrap())
            .unwrap();
        let found = sited.support_loss((&shares, &[0.5, 0.7]), &[1, 3]);
        assert!((found - (0.4 * 0.6 + 0.1 * 0.7)).abs() < 1e-15);
    }
}
