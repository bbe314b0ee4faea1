//! One patch of a multi-patch deck: a degenerate shell (eq. 2–3) with its own
//! material and a non-structural mass per unit area (pavement, ballast,
//! services). Several patches are numbered one after the other
//! ([`crate::model::dofs::DofMap`]).

use crate::geometry::quadrature::GaussLegendre;
use crate::geometry::vec3::{cross, norm};
use crate::model::material::OrthotropicMaterial;
use crate::model::shell::{Assembly, Shell, ShellPoint, DOFS_PER_CONTROL_POINT};
use crate::model::sparse::SparseError;
use faer::Mat;
use std::collections::BTreeMap;
use thiserror::Error;

#[derive(Debug, Clone, PartialEq, Error)]
pub enum PatchError {
    #[error("the non-structural mass must be finite and not negative, got {0} kg/m²")]
    NonStructuralMass(f64),
    #[error("a patch name must not be empty")]
    EmptyName,
}

/// A shell patch with its material and added mass.
#[derive(Debug, Clone)]
pub struct Patch {
    name: String,
    pub shell: Shell,
    pub material: OrthotropicMaterial,
    non_structural_mass: f64,
}

impl Patch {
    pub fn new(name: impl Into<String>, shell: Shell, material: OrthotropicMaterial) -> Result<Self, PatchError> {
        let name = name.into();
        if name.is_empty() {
            return Err(PatchError::EmptyName);
        }
        Ok(Self {
            name,
            shell,
            material,
            non_structural_mass: 0.0,
        })
    }

    /// The same patch carrying `mass` kg/m² on its mid-surface.
    pub fn with_non_structural_mass(mut self, mass: f64) -> Result<Self, PatchError> {
        if !(mass.is_finite() && mass >= 0.0) {
            return Err(PatchError::NonStructuralMass(mass));
        }
        self.non_structural_mass = mass;
        Ok(self)
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    /// kg/m².
    pub fn non_structural_mass(&self) -> f64 {
        self.non_structural_mass
    }

    /// Adds the non-structural mass `μ ∫_A N₀ᵀ N₀ dA` on the patch's dofs
    /// to `target`, span by span, `N₀` the mid-surface (τ = ½) displacement
    /// rows of eq. (3): translations only, no rotary inertia; nothing when
    /// `μ = 0`. Gauss with `p + 1` points per span integrates it exactly on
    /// a flat patch.
    pub fn add_surface_mass<A: Assembly>(&self, target: &mut A) -> Result<(), SparseError> {
        let mu = self.non_structural_mass;
        if mu == 0.0 {
            return Ok(());
        }
        let surface = self.shell.surface();
        let (kx, ke) = (surface.xi(), surface.eta());
        let (gx, ge) = (GaussLegendre::new(kx.degree() + 1), GaussLegendre::new(ke.degree() + 1));
        let (mut basis, mut pt) = (Vec::new(), ShellPoint::new_empty());
        for sx in kx.breakpoints().windows(2) {
            for se in ke.breakpoints().windows(2) {
                // The translational block is the same for u, v, w: the
                // scalar `∫ N_a N_b dA` over the span, spread over them.
                let mut scalar: BTreeMap<(usize, usize), f64> = BTreeMap::new();
                for (xi, wx) in gx.mapped(sx[0], sx[1]) {
                    for (eta, we) in ge.mapped(se[0], se[1]) {
                        let e = surface.evaluate(xi, eta);
                        let w = wx * we * norm(cross(e.r_xi, e.r_eta)) * mu;
                        // The mid-surface basis (rational on a NURBS patch).
                        self.shell.evaluate_into(xi, eta, 0.5, &mut pt);
                        basis.clear();
                        basis.extend(
                            (0..pt.count)
                                .map(|k| (pt.control_points[k], pt.n[k]))
                                .filter(|b| b.1 != 0.0),
                        );
                        for &(a, na) in &basis {
                            for &(b, nb) in &basis {
                                *scalar.entry((a, b)).or_insert(0.0) += w * na * nb;
                            }
                        }
                    }
                }
                let mut cps: Vec<usize> = scalar.keys().map(|&(a, _)| a).collect();
                cps.dedup();
                let dofs: Vec<usize> = cps
                    .iter()
                    .flat_map(|&cp| (0..3).map(move |d| DOFS_PER_CONTROL_POINT * cp + d))
                    .collect();
                let mut local = Mat::<f64>::zeros(dofs.len(), dofs.len());
                for (&(a, b), &v) in &scalar {
                    let (ia, ib) = (cps.binary_search(&a), cps.binary_search(&b));
                    let (ia, ib) = (ia.expect("listed"), ib.expect("listed"));
                    for d in 0..3 {
                        local[(3 * ia + d, 3 * ib + d)] = v;
                    }
                }
                target.add_local(&local, &dofs)?;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn surface_mass_is_mu_times_area_in_each_direction() {
        let shell = Shell::cylindrical_panel(6.0, 4.0, 1.2, 0.05, [3, 2], [7, 5]).unwrap();
        let material = OrthotropicMaterial::isotropic(30e9, 0.2, 2500.0).unwrap();
        let patch = Patch::new("slab", shell, material)
            .unwrap()
            .with_non_structural_mass(150.0)
            .unwrap();
        let n = patch.shell.dof_count();
        let mut mass = Mat::<f64>::zeros(n, n);
        patch.add_surface_mass(&mut mass).unwrap();
        // A rigid translation: the sum of one direction's entries. The arc is
        // interpolated, so its length (and area) is exact to ~1e-5.
        let area = 6.0 * 4.0 * 1.2;
        for d in 0..DOFS_PER_CONTROL_POINT {
            let total: f64 = (0..n)
                .filter(|r| r % DOFS_PER_CONTROL_POINT == d)
                .flat_map(|r| (0..n).map(move |c| (r, c)))
                .map(|(r, c)| mass[(r, c)])
                .sum();
            let expected = if d < 3 { 150.0 * area } else { 0.0 };
            assert!((total - expected).abs() <= 1e-4 * 150.0 * area, "{d}: {total}");
        }
        // Every direction's mass stays in its own direction.
        for r in 0..n {
            for c in 0..n {
                if r % DOFS_PER_CONTROL_POINT != c % DOFS_PER_CONTROL_POINT {
                    assert_eq!(mass[(r, c)], 0.0);
                }
            }
        }
        assert!(matches!(
            patch.clone().with_non_structural_mass(-1.0),
            Err(PatchError::NonStructuralMass(_))
        ));
        let mut untouched = Mat::<f64>::zeros(n, n);
        let bare = patch.with_non_structural_mass(0.0).unwrap();
        bare.add_surface_mass(&mut untouched).unwrap();
        assert_eq!(untouched.norm_max(), 0.0);
    }
}
