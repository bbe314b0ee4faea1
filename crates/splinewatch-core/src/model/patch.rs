//! One patch of a multi-patch deck: a degenerate shell (eq. 2–3) with its own
//! material and a non-structural mass per unit area (pavement, ballast,
//! services), and the global dof numbering of several patches.
//!
//! Patches are numbered in the order given; patch `k`'s dofs follow those of
//! patches `0..k` (its offset is `5 Σ_{j<k} n_cp(j)`), each in its shell's
//! own order (eq. 4). One patch keeps exactly the single-shell numbering.

use crate::geometry::quadrature::GaussLegendre;
use crate::geometry::vec3::{cross, norm};
use crate::model::material::OrthotropicMaterial;
use crate::model::shell::{Shell, DOFS_PER_CONTROL_POINT};
use crate::model::springs::LowRankBlock;
use faer::Mat;
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

    /// The non-structural mass `μ ∫_A N₀ᵀ N₀ dA` on the patch's dofs, `N₀`
    /// the mid-surface (τ = ½) displacement rows of eq. (3): translations
    /// only, no rotary inertia. `None` when `μ = 0`. Gauss with `p + 1`
    /// points per span integrates it exactly on a flat patch.
    pub fn surface_mass(&self) -> Option<LowRankBlock> {
        let mu = self.non_structural_mass;
        if mu == 0.0 {
            return None;
        }
        let surface = self.shell.surface();
        let (kx, ke) = (surface.xi(), surface.eta());
        let (gx, ge) = (GaussLegendre::new(kx.degree() + 1), GaussLegendre::new(ke.degree() + 1));
        let cps = self.shell.control_point_count();
        // The translational block is the same for u, v, w: assemble the
        // scalar `∫ N_a N_b dA` once and spread it.
        let mut scalar = Mat::<f64>::zeros(cps, cps);
        let mut basis = Vec::new();
        for sx in kx.breakpoints().windows(2) {
            for se in ke.breakpoints().windows(2) {
                for (xi, wx) in gx.mapped(sx[0], sx[1]) {
                    for (eta, we) in ge.mapped(se[0], se[1]) {
                        let e = surface.evaluate(xi, eta);
                        let w = wx * we * norm(cross(e.r_xi, e.r_eta)) * mu;
                        kx.tensor_basis_into(ke, xi, eta, &mut basis);
                        for &(a, na) in &basis {
                            for &(b, nb) in &basis {
                                scalar[(a, b)] += w * na * nb;
                            }
                        }
                    }
                }
            }
        }
        let dofs: Vec<usize> = (0..cps)
            .flat_map(|cp| (0..3).map(move |d| DOFS_PER_CONTROL_POINT * cp + d))
            .collect();
        let values = Mat::from_fn(dofs.len(), dofs.len(), |r, c| {
            if r % 3 == c % 3 {
                scalar[(r / 3, c / 3)]
            } else {
                0.0
            }
        });
        Some(LowRankBlock { dofs, values })
    }
}

/// First global dof of every patch, and the total as the last entry.
pub fn dof_offsets(patches: &[Patch]) -> Vec<usize> {
    let mut out = Vec::with_capacity(patches.len() + 1);
    let mut at = 0;
    out.push(0);
    for p in patches {
        at += p.shell.dof_count();
        out.push(at);
    }
    out
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
        let block = patch.surface_mass().unwrap();
        // A rigid translation: the sum of one direction's entries. The arc is
        // interpolated, so its length (and area) is exact to ~1e-5.
        let area = 6.0 * 4.0 * 1.2;
        for d in 0..3 {
            let total: f64 = (0..block.dofs.len())
                .filter(|r| r % 3 == d)
                .flat_map(|r| (0..block.dofs.len()).filter(|c| c % 3 == d).map(move |c| (r, c)))
                .map(|(r, c)| block.values[(r, c)])
                .sum();
            assert!((total / (150.0 * area) - 1.0).abs() < 1e-4, "{total}");
        }
        assert!(matches!(
            patch.clone().with_non_structural_mass(-1.0),
            Err(PatchError::NonStructuralMass(_))
        ));
        assert!(patch.with_non_structural_mass(0.0).unwrap().surface_mass().is_none());
    }
}
