//! Stiffness fields of the deck itself: a B-spline multiplier of the
//! material stiffness, `θ(ξ,η) = Σ_ij B_i(ξ) B_j(η) θ_ij` (the isogeometric
//! counterpart of the spring fields of eq. 20, and of Teughels & De Roeck's
//! "damage functions", J. Sound Vib. 2004). Coefficients are stored `η`
//! fastest, `θ = 1` is the nominal material.
//!
//! The stiffness of eq. (16) with the multiplier is `∫ θ Bᵀ E' B dV`, linear
//! in θ: `K_f(θ) = K_f + Σ_ij (θ_ij − 1) ∂K/∂θ_ij` with
//! `∂K/∂θ_ij = ∫_field B_ij(ξ,η) Bᵀ E' B dV`, assembled once in one
//! quadrature pass that splits the integrand by coefficient (the B-splines
//! of the field sum to one, so `Σ_ij ∂K/∂θ_ij` is the field's part of
//! `K_f`). Outside its rectangle a field leaves the material as it is; with
//! several fields their deviations `θ − 1` add. A single-coefficient field
//! over the whole deck is a global modulus scale: the temperature-driven
//! stiffness change of the deck material.
//!
//! A field scales all of `E'` (`StiffnessScale::All`), or one part of the
//! section's stiffness: with the two thickness Gauss points `ζ = ±c` of
//! eq. (16), the in-plane strain rows at a point are `B± = B₀ ± δ` with the
//! mid-surface (membrane) rows `B₀ = (B₊ + B₋)/2` and the bending rows
//! `δ = (B₊ − B₋)/2`, so the in-plane integrand splits exactly into
//! `(w₊ + w₋) B₀ᵀE'B₀` (membrane), `(w₊ + w₋) δᵀE'δ` (bending) and the
//! coupling `(w₊ − w₋)(B₀ᵀE'δ + δᵀE'B₀)`, which vanishes on a flat shell of
//! constant thickness and is shared half and half otherwise (so the three
//! parts add up to the whole); the transverse shear rows (γ₂₃, γ₁₃; `E'` has
//! no in-plane/shear coupling in the lamina frame) are the shear part.
//!
//! Quadrature splits at the knots of the shell and of the field, with
//! `⌈d/2⌉` Gauss points more per direction than eq. (16) needs for a field
//! of degree `d` (exact for a flat shell).

use crate::geometry::knots::KnotVector;
use crate::model::material::OrthotropicMaterial;
use crate::model::shell::{self, Assembly, OutsideDomain, QuadratureStep, Shell, ShellError, DOFS_PER_CONTROL_POINT};
use faer::linalg::matmul::matmul;
use faer::{unzip, zip, Accum, Mat, Par};
use thiserror::Error;

#[derive(Debug, Clone, PartialEq, Error)]
pub enum StiffnessFieldError {
    #[error("{found} coefficients given, the knot vectors define {expected} basis functions")]
    CoefficientCount { found: usize, expected: usize },
    #[error("coefficient {index} must be finite and positive, got {value}")]
    Coefficient { index: usize, value: f64 },
    #[error("{0}")]
    OutsideShell(#[from] OutsideDomain),
    #[error("shell: {0}")]
    Shell(#[from] ShellError),
}

/// What part of the section's stiffness a field multiplies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum StiffnessScale {
    /// Membrane, bending and shear together (the moduli themselves).
    #[default]
    All,
    /// The mid-surface (in-plane stretching) stiffness.
    Membrane,
    /// The bending stiffness (in-plane strains varying through the thickness).
    Bending,
    /// The transverse shear stiffness.
    Shear,
}

impl StiffnessScale {
    pub const NAMES: [&'static str; 4] = ["all", "membrane", "bending", "shear"];

    pub fn parse(name: &str) -> Option<Self> {
        match name {
            "all" => Some(Self::All),
            "membrane" => Some(Self::Membrane),
            "bending" => Some(Self::Bending),
            "shear" => Some(Self::Shear),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Self::All => "all",
            Self::Membrane => "membrane",
            Self::Bending => "bending",
            Self::Shear => "shear",
        }
    }
}

/// A validated stiffness multiplier field.
#[derive(Debug, Clone, PartialEq)]
pub struct StiffnessField {
    xi: KnotVector,
    eta: KnotVector,
    coefficients: Vec<f64>,
    scale: StiffnessScale,
    /// The patch the field lies on ([`crate::model::patch`]).
    patch: usize,
}

impl StiffnessField {
    pub fn new(xi: KnotVector, eta: KnotVector, coefficients: Vec<f64>) -> Result<Self, StiffnessFieldError> {
        let expected = xi.basis_count() * eta.basis_count();
        if coefficients.len() != expected {
            return Err(StiffnessFieldError::CoefficientCount {
                found: coefficients.len(),
                expected,
            });
        }
        if let Some(index) = coefficients.iter().position(|c| !(c.is_finite() && *c > 0.0)) {
            return Err(StiffnessFieldError::Coefficient {
                index,
                value: coefficients[index],
            });
        }
        Ok(Self {
            xi,
            eta,
            coefficients,
            scale: StiffnessScale::All,
            patch: 0,
        })
    }

    /// The same field on patch `patch` (default: the first).
    #[must_use]
    pub fn on_patch(self, patch: usize) -> Self {
        Self { patch, ..self }
    }

    pub fn patch(&self) -> usize {
        self.patch
    }

    /// The same field multiplying `scale` only.
    #[must_use]
    pub fn with_scale(self, scale: StiffnessScale) -> Self {
        Self { scale, ..self }
    }

    pub fn scale(&self) -> StiffnessScale {
        self.scale
    }

    pub fn coefficients(&self) -> &[f64] {
        &self.coefficients
    }

    pub fn coefficient_count(&self) -> usize {
        self.coefficients.len()
    }

    pub fn xi(&self) -> &KnotVector {
        &self.xi
    }

    pub fn eta(&self) -> &KnotVector {
        &self.eta
    }

    /// `θ(ξ, η)` for the coefficients `theta`; 1 outside the field's rectangle.
    #[track_caller]
    pub fn value_with(&self, theta: &[f64], xi: f64, eta: f64) -> f64 {
        assert_eq!(theta.len(), self.coefficients.len());
        if !(self.xi.contains(xi) && self.eta.contains(eta)) {
            return 1.0;
        }
        let mut basis = Vec::new();
        self.xi.tensor_basis_into(&self.eta, xi, eta, &mut basis);
        basis.iter().map(|&(k, w)| w * theta[k]).sum()
    }

    /// The field's rectangle must lie in the shell's parameter domain.
    pub fn check_inside(&self, shell: &Shell) -> Result<(), OutsideDomain> {
        shell.check_inside(&self.xi, &self.eta)
    }

    /// `∂K/∂θ_ij` for every coefficient (`ndof × ndof`, unconstrained dofs).
    pub fn coefficient_matrices(
        &self,
        shell: &Shell,
        material: &OrthotropicMaterial,
    ) -> Result<Vec<Mat<f64>>, StiffnessFieldError> {
        let ndof = shell.dof_count();
        let zeros = vec![Mat::<f64>::zeros(ndof, ndof); self.coefficient_count()];
        self.coefficient_matrices_into(shell, material, zeros)
    }

    /// `∂K/∂θ_ij` for every coefficient added into `out` (one zeroed
    /// target per coefficient: dense, or sparse on the shell's pattern).
    pub fn coefficient_matrices_into<A: Assembly>(
        &self,
        shell: &Shell,
        material: &OrthotropicMaterial,
        mut out: Vec<A>,
    ) -> Result<Vec<A>, StiffnessFieldError> {
        self.check_inside(shell)?;
        let (kx, ke) = (shell.surface().xi(), shell.surface().eta());
        let count = self.coefficient_count();
        assert_eq!(out.len(), count, "one target per coefficient");
        let nloc = DOFS_PER_CONTROL_POINT * (kx.degree() + 1) * (ke.degree() + 1);
        let mut outcome = Ok(());
        let mut local = vec![Mat::<f64>::zeros(nloc, nloc); count];
        let mut used = vec![false; count];
        let mut basis = Vec::new();
        let mut section = SectionSplit::new(self.scale, nloc);
        let quadrature = shell::Quadrature {
            extra: (self.xi.degree().div_ceil(2), self.eta.degree().div_ceil(2)),
            cuts: (self.xi.breakpoints(), self.eta.breakpoints()),
            xi_spans: None,
        };
        shell::integrate(shell, material, &quadrature, |step| match step {
            QuadratureStep::Point {
                xi,
                eta,
                layer,
                w,
                rows,
            } => {
                // Half-open spans: a point on the field's boundary belongs to
                // one side only, and Gauss points never sit on a cut.
                if !(self.xi.contains(xi) && self.eta.contains(eta)) {
                    return;
                }
                let Some(integrand) = section.integrand(layer, w, rows) else {
                    return;
                };
                self.xi.tensor_basis_into(&self.eta, xi, eta, &mut basis);
                for &(k, bk) in &basis {
                    zip!(local[k].as_mut(), integrand.as_ref()).for_each(|unzip!(l, i)| *l += bk * *i);
                    used[k] = true;
                }
            }
            QuadratureStep::SpanEnd { dofs } => {
                for k in 0..count {
                    if std::mem::replace(&mut used[k], false) {
                        if outcome.is_ok() {
                            outcome = out[k].add_local(&local[k], dofs);
                        }
                        local[k].fill(0.0);
                    }
                }
            }
        })?;
        outcome.map_err(|e| StiffnessFieldError::Shell(ShellError::Sparse(e)))?;
        Ok(out)
    }
}

/// Rows 0–3 of the strain (ε₁₁, ε₂₂, ε₃₃, γ₁₂) are in-plane, rows 4–5 (γ₂₃,
/// γ₁₃) transverse shear.
const IN_PLANE_ROWS: usize = 4;
const SHEAR_ROWS: usize = 2;

/// The weighted integrand `w Bᵀ E' B` of one `(ξ, η)`, or the part of it a
/// [`StiffnessScale`] selects (module docs): sums over the two thickness
/// layers, ready after the second.
struct SectionSplit {
    scale: StiffnessScale,
    integrand: Mat<f64>,
    /// The first layer's in-plane rows `B₋`, `E'B₋` and weight `w₋`.
    lower: (Mat<f64>, Mat<f64>, f64),
}

impl SectionSplit {
    fn new(scale: StiffnessScale, nloc: usize) -> Self {
        Self {
            scale,
            integrand: Mat::zeros(nloc, nloc),
            lower: (Mat::zeros(IN_PLANE_ROWS, nloc), Mat::zeros(IN_PLANE_ROWS, nloc), 0.0),
        }
    }

    fn integrand(&mut self, layer: usize, w: f64, rows: &shell::PointRows) -> Option<&Mat<f64>> {
        let add = |target: &mut Mat<f64>, b: faer::MatRef<'_, f64>, eb: faer::MatRef<'_, f64>, w: f64| {
            matmul(target.as_mut(), Accum::Add, b.transpose(), eb, w, Par::Seq);
        };
        if layer == 0 {
            self.integrand.fill(0.0);
        }
        match self.scale {
            StiffnessScale::All => add(&mut self.integrand, rows.b.as_ref(), rows.eb.as_ref(), w),
            StiffnessScale::Shear => add(
                &mut self.integrand,
                rows.b.subrows(IN_PLANE_ROWS, SHEAR_ROWS),
                rows.eb.subrows(IN_PLANE_ROWS, SHEAR_ROWS),
                w,
            ),
            StiffnessScale::Membrane | StiffnessScale::Bending if layer == 0 => {
                self.lower.0.copy_from(rows.b.subrows(0, IN_PLANE_ROWS));
                self.lower.1.copy_from(rows.eb.subrows(0, IN_PLANE_ROWS));
                self.lower.2 = w;
            }
            StiffnessScale::Membrane | StiffnessScale::Bending => {
                let (b_lo, eb_lo, w_lo) = (&self.lower.0, &self.lower.1, self.lower.2);
                let (b_hi, eb_hi) = (rows.b.subrows(0, IN_PLANE_ROWS), rows.eb.subrows(0, IN_PLANE_ROWS));
                let mid = (b_hi + b_lo) * 0.5;
                let e_mid = (eb_hi + eb_lo) * 0.5;
                let slope = (b_hi - b_lo) * 0.5;
                let e_slope = (eb_hi - eb_lo) * 0.5;
                let (own, other) = if self.scale == StiffnessScale::Membrane {
                    ((&mid, &e_mid), (&slope, &e_slope))
                } else {
                    ((&slope, &e_slope), (&mid, &e_mid))
                };
                add(&mut self.integrand, own.0.as_ref(), own.1.as_ref(), w + w_lo);
                // Half the coupling (w₊ − w₋)(B₀ᵀE'δ + δᵀE'B₀).
                let half = 0.5 * (w - w_lo);
                add(&mut self.integrand, own.0.as_ref(), other.1.as_ref(), half);
                add(&mut self.integrand, other.0.as_ref(), own.1.as_ref(), half);
            }
        }
        (layer == 1).then_some(&self.integrand)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_fields_are_named() {
        let k = |v: Vec<f64>, d| KnotVector::new(v, d).unwrap();
        let e = StiffnessField::new(k(vec![0.0, 0.0, 1.0, 1.0], 1), k(vec![0.0, 1.0], 0), vec![1.0]);
        assert!(matches!(
            e,
            Err(StiffnessFieldError::CoefficientCount { found: 1, expected: 2 })
        ));
        let e = StiffnessField::new(k(vec![0.0, 1.0], 0), k(vec![0.0, 1.0], 0), vec![0.0]);
        assert!(matches!(e, Err(StiffnessFieldError::Coefficient { index: 0, .. })));
        let f = StiffnessField::new(k(vec![0.0, 0.0, 1.0, 1.0], 1), k(vec![0.0, 1.0], 0), vec![0.5, 1.5]).unwrap();
        assert!((f.value_with(&[0.5, 1.5], 0.25, 0.3) - 0.75).abs() < 1e-15);
        assert_eq!(f.value_with(&[0.5, 1.5], 1.5, 0.3), 1.0);
    }

    fn plate() -> (Shell, OrthotropicMaterial) {
        let shell = Shell::rectangular_plate(4.0, 2.0, 0.2, [3, 3], [7, 5]).unwrap();
        (shell, OrthotropicMaterial::isotropic(30e9, 0.2, 2500.0).unwrap())
    }

    fn relative_difference(a: &Mat<f64>, b: &Mat<f64>) -> f64 {
        (a - b).norm_max() / b.norm_max()
    }

    fn uniform(degree: usize, count: usize) -> KnotVector {
        KnotVector::uniform(degree, count, 0.0, 1.0).unwrap()
    }

    /// θ = 0.8 on a one-coefficient field over the deck is the material
    /// with every modulus scaled by 0.8: E' is linear in the moduli at fixed ν.
    #[test]
    fn a_global_scale_is_the_scaled_material() {
        let (shell, material) = plate();
        let weak = OrthotropicMaterial::isotropic(0.8 * 30e9, 0.2, 2500.0).unwrap();
        let field = StiffnessField::new(uniform(0, 1), uniform(0, 1), vec![1.0]).unwrap();
        let d = field.coefficient_matrices(&shell, &material).unwrap();
        let nominal = shell::assemble(&shell, &material).unwrap().stiffness;
        let scaled = &nominal + &d[0] * (0.8 - 1.0);
        let want = shell::assemble(&shell, &weak).unwrap().stiffness;
        assert!(
            relative_difference(&scaled, &want) < 1e-13,
            "{}",
            relative_difference(&scaled, &want)
        );
    }

    /// The field's B-splines sum to one, so its derivative matrices sum to
    /// `K_f` (a 4 × 2 field of degree 1 whose knots cut the net's spans);
    /// each is symmetric.
    #[test]
    fn the_derivative_matrices_partition_the_stiffness() {
        let (shell, material) = plate();
        let field = StiffnessField::new(uniform(1, 4), uniform(1, 2), vec![1.0; 8]).unwrap();
        let d = field.coefficient_matrices(&shell, &material).unwrap();
        let nominal = shell::assemble(&shell, &material).unwrap().stiffness;
        let mut sum = Mat::<f64>::zeros(nominal.nrows(), nominal.ncols());
        for m in &d {
            assert!(relative_difference(&m.transpose().to_owned(), m) < 1e-14);
            sum += m;
        }
        assert!(
            relative_difference(&sum, &nominal) < 1e-12,
            "{}",
            relative_difference(&sum, &nominal)
        );
    }

    /// A degree-0 field cut at ξ = 0.5 (not a knot of the net): its first
    /// coefficient's matrix is the stiffness of the half ξ < 0.5 alone,
    /// integrated independently here point by point over that half.
    #[test]
    fn a_patch_is_the_stiffness_of_its_subdomain() {
        let (shell, material) = plate();
        let xi = KnotVector::new(vec![0.0, 0.5, 1.0], 0).unwrap();
        let field = StiffnessField::new(xi, uniform(0, 1), vec![0.7, 1.0]).unwrap();
        let d = field.coefficient_matrices(&shell, &material).unwrap();
        let ndof = shell.dof_count();
        let mut half = Mat::<f64>::zeros(ndof, ndof);
        let nloc = DOFS_PER_CONTROL_POINT * 4 * 4; // degree 3 × 3: 4 × 4 control points per span
        let mut local = Mat::<f64>::zeros(nloc, nloc);
        let quadrature = shell::Quadrature {
            extra: (0, 0),
            cuts: (vec![0.5], Vec::new()),
            xi_spans: None,
        };
        shell::integrate(&shell, &material, &quadrature, |step| match step {
            QuadratureStep::Point { xi, w, rows, .. } => {
                if xi < 0.5 {
                    matmul(
                        local.as_mut(),
                        Accum::Add,
                        rows.b.transpose(),
                        rows.eb.as_ref(),
                        w,
                        Par::Seq,
                    );
                }
            }
            QuadratureStep::SpanEnd { dofs } => {
                shell::scatter(&mut half, &local, dofs);
                local.fill(0.0);
            }
        })
        .unwrap();
        assert!(relative_difference(&d[0], &half) < 1e-13);
        // θ = (0.7, 1): the plate with its left half 30 % softer.
        let nominal = shell::assemble(&shell, &material).unwrap().stiffness;
        let softened = &nominal + &d[0] * (0.7 - 1.0);
        let energy = |k: &Mat<f64>| (0..ndof).map(|i| k[(i, i)]).sum::<f64>();
        assert!(energy(&softened) < energy(&nominal));
    }

    /// Membrane, bending and shear parts add up to the whole, on a curved
    /// panel (where the membrane–bending coupling is not zero and is shared)
    /// and on the flat plate (where it is zero: the membrane part has no
    /// entry on a rotation dof).
    #[test]
    fn the_section_parts_add_up_to_the_whole() {
        let material = OrthotropicMaterial::isotropic(30e9, 0.2, 2500.0).unwrap();
        let panel = Shell::cylindrical_panel(4.0, 3.0, 1.2, 0.2, [3, 3], [6, 5]).unwrap();
        let (plate, _) = plate();
        for shell in [&panel, &plate] {
            let part = |scale| {
                let field = StiffnessField::new(uniform(1, 2), uniform(0, 1), vec![1.0; 2])
                    .unwrap()
                    .with_scale(scale);
                field.coefficient_matrices(shell, &material).unwrap()
            };
            let all = part(StiffnessScale::All);
            let parts = [
                part(StiffnessScale::Membrane),
                part(StiffnessScale::Bending),
                part(StiffnessScale::Shear),
            ];
            for k in 0..2 {
                let sum = &parts[0][k] + &parts[1][k] + &parts[2][k];
                let error = relative_difference(&sum, &all[k]);
                assert!(error < 1e-12, "coefficient {k}: {error}");
                for p in &parts {
                    assert!(relative_difference(&p[k].transpose().to_owned(), &p[k]) < 1e-14);
                    assert!(p[k].norm_max() > 1e-3 * all[k].norm_max());
                }
            }
        }
        // Flat plate: dofs 3k..3k+2 translate control point k, 3k+3.. rotate it.
        let membrane = StiffnessField::new(uniform(0, 1), uniform(0, 1), vec![1.0])
            .unwrap()
            .with_scale(StiffnessScale::Membrane)
            .coefficient_matrices(&plate, &material)
            .unwrap();
        let rotations: Vec<usize> = (0..plate.dof_count())
            .filter(|d| d % DOFS_PER_CONTROL_POINT >= 3)
            .collect();
        let on_rotations = rotations.iter().map(|&d| membrane[0][(d, d)].abs()).fold(0.0, f64::max);
        assert!(on_rotations < 1e-12 * membrane[0].norm_max(), "{on_rotations}");
        assert_eq!(StiffnessScale::parse("bending"), Some(StiffnessScale::Bending));
        assert_eq!(StiffnessScale::parse("E1"), None);
        for name in StiffnessScale::NAMES {
            assert_eq!(StiffnessScale::parse(name).unwrap().name(), name);
        }
    }
}
