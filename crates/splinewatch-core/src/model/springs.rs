//! Distributed elastic constraints (paper §2.2, eq. 19–22).
//!
//! A spring field applies the surface traction `Q_C = -R d` (eq. 19) on one
//! face of the shell (`τ = 0`, `½` or `1`). Here `R = r(ξ,η) n nᵀ`, with a
//! fixed unit direction `n` (the paper's `R` with only `r33`, eq. 45, is
//! `n = z`) or the local surface normal, and the stiffness per unit area is a
//! B-spline field (eq. 20) over its own sub-rectangle of the parameter domain:
//! `r(ξ,η) = Σ_ij B_i(ξ) B_j(η) κ_ij`. Coefficients are stored `η` fastest:
//! `κ_ij` is `stiffness[i * n_η + j]`.
//!
//! `ΔK = ∫_S Nᵀ R N dS` (eq. 22) is linear in κ: `ΔK = Σ_j κ_j ∂K/∂κ_j`, and
//! each `∂K/∂κ_j = ∫_S B_j (nᵀN)ᵀ(nᵀN) dS` touches only the dofs of the shell
//! control points under the support of `B_j`. It is returned as a
//! [`LowRankBlock`]. Quadrature splits at the knots of both the shell and the
//! spring field, with enough Gauss points to integrate the polynomial
//! integrand of a flat shell exactly.

use crate::geometry::knots::{KnotVector, MAX_DEGREE};
use crate::geometry::quadrature::GaussLegendre;
use crate::geometry::vec3::{cross, dot, norm, normalize, scale, Vec3};
use crate::model::shell::{OutsideDomain, Shell, ShellPoint, DOFS_PER_CONTROL_POINT};
use faer::Mat;
use std::collections::BTreeSet;
use thiserror::Error;

#[derive(Debug, Clone, PartialEq, Error)]
pub enum SpringError {
    #[error("{found} stiffness coefficients given, the knot vectors define {expected} basis functions")]
    CoefficientCount { found: usize, expected: usize },
    #[error("stiffness coefficient {index} must be finite and non-negative, got {value}")]
    Coefficient { index: usize, value: f64 },
    #[error("direction must be a finite non-zero vector")]
    Direction,
    #[error("{0}")]
    OutsideShell(#[from] OutsideDomain),
}

/// Which face of the shell the springs act on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Face {
    /// `τ = 0`
    Bottom,
    /// `τ = ½`
    Middle,
    /// `τ = 1`
    Top,
}

impl Face {
    pub fn tau(self) -> f64 {
        match self {
            Face::Bottom => 0.0,
            Face::Middle => 0.5,
            Face::Top => 1.0,
        }
    }
}

/// Direction `n` of the spring force.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SpringDirection {
    /// A fixed unit vector in the global frame.
    Fixed(Vec3),
    /// The unit normal of the face at each point.
    Normal,
}

impl SpringDirection {
    pub fn fixed(v: Vec3) -> Result<Self, SpringError> {
        normalize(v).map(SpringDirection::Fixed).ok_or(SpringError::Direction)
    }
}

/// A validated spring field.
#[derive(Debug, Clone, PartialEq)]
pub struct SpringField {
    xi: KnotVector,
    eta: KnotVector,
    stiffness: Vec<f64>,
    direction: SpringDirection,
    face: Face,
    /// The patch the field lies on ([`crate::model::patch`]).
    patch: usize,
}

/// A symmetric matrix that is zero outside the rows and columns `dofs`.
#[derive(Debug, Clone, PartialEq)]
pub struct LowRankBlock {
    pub dofs: Vec<usize>,
    pub values: Mat<f64>,
}

impl LowRankBlock {
    /// The same block with every dof moved by `offset` (a patch's first
    /// global dof).
    #[must_use]
    pub fn shifted(mut self, offset: usize) -> Self {
        for d in &mut self.dofs {
            *d += offset;
        }
        self
    }

    /// `target[dofs, dofs] += scale * values`.
    pub fn add_scaled_to(&self, target: &mut Mat<f64>, scale: f64) {
        for (a, &ra) in self.dofs.iter().enumerate() {
            for (b, &rb) in self.dofs.iter().enumerate() {
                target[(ra, rb)] += scale * self.values[(a, b)];
            }
        }
    }

    /// `vᵀ B v` with `v(d)` the vector's entry at global dof `d`.
    pub fn quadratic_form(&self, v: impl Fn(usize) -> f64) -> f64 {
        let local: Vec<f64> = self.dofs.iter().map(|&d| v(d)).collect();
        let mut sum = 0.0;
        for (a, va) in local.iter().enumerate() {
            for (b, vb) in local.iter().enumerate() {
                sum += va * self.values[(a, b)] * vb;
            }
        }
        sum
    }
}

impl SpringField {
    pub fn new(
        xi: KnotVector,
        eta: KnotVector,
        stiffness: Vec<f64>,
        direction: SpringDirection,
        face: Face,
    ) -> Result<Self, SpringError> {
        let expected = xi.basis_count() * eta.basis_count();
        if stiffness.len() != expected {
            return Err(SpringError::CoefficientCount {
                found: stiffness.len(),
                expected,
            });
        }
        if let Some(index) = stiffness.iter().position(|k| !(k.is_finite() && *k >= 0.0)) {
            return Err(SpringError::Coefficient {
                index,
                value: stiffness[index],
            });
        }
        if let SpringDirection::Fixed(v) = direction {
            if (norm(v) - 1.0).abs() >= 1e-12 || !v.iter().all(|c| c.is_finite()) {
                return Err(SpringError::Direction);
            }
        }
        Ok(Self {
            xi,
            eta,
            stiffness,
            direction,
            face,
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

    pub fn stiffness(&self) -> &[f64] {
        &self.stiffness
    }

    pub fn coefficient_count(&self) -> usize {
        self.stiffness.len()
    }

    pub fn xi(&self) -> &KnotVector {
        &self.xi
    }

    pub fn eta(&self) -> &KnotVector {
        &self.eta
    }

    pub fn face(&self) -> Face {
        self.face
    }

    /// Eq. (20) at `(ξ, η)` for the coefficients `kappa`; zero outside the
    /// field's rectangle.
    #[track_caller]
    pub fn value_with(&self, kappa: &[f64], xi: f64, eta: f64) -> f64 {
        assert_eq!(kappa.len(), self.stiffness.len());
        if !(self.xi.contains(xi) && self.eta.contains(eta)) {
            return 0.0;
        }
        let mut basis = Vec::new();
        self.xi.tensor_basis_into(&self.eta, xi, eta, &mut basis);
        basis.iter().map(|&(k, w)| w * kappa[k]).sum()
    }

    /// Eq. (20) with the field's own coefficients.
    pub fn value(&self, xi: f64, eta: f64) -> f64 {
        self.value_with(&self.stiffness, xi, eta)
    }

    /// `∂ΔK/∂κ_j` for every coefficient `j` (eq. 22 with a unit κ_j).
    pub fn coefficient_matrices(&self, shell: &Shell) -> Result<Vec<LowRankBlock>, SpringError> {
        shell.check_inside(&self.xi, &self.eta)?;
        let count = self.coefficient_count();
        // Pass 1: which dofs each block touches.
        let mut touched: Vec<BTreeSet<usize>> = vec![BTreeSet::new(); count];
        self.for_each_point(shell, |pt, _, _, basis| {
            for &(j, _) in basis {
                for k in 0..pt.count {
                    let cp = pt.control_points[k];
                    touched[j].extend((0..DOFS_PER_CONTROL_POINT).map(|d| DOFS_PER_CONTROL_POINT * cp + d));
                }
            }
        });
        let dof_lists: Vec<Vec<usize>> = touched.into_iter().map(|s| s.into_iter().collect()).collect();
        let mut blocks: Vec<LowRankBlock> = dof_lists
            .iter()
            .map(|d| LowRankBlock {
                dofs: d.clone(),
                values: Mat::zeros(d.len(), d.len()),
            })
            .collect();
        // Pass 2: accumulate B_j (nᵀN)ᵀ(nᵀN) dS.
        let mut a = Vec::new();
        self.for_each_point(shell, |pt, weight, normal, basis| {
            a.clear();
            for k in 0..pt.count {
                for s in shell.dof_shapes(pt, k) {
                    let v = s.psi * dot(normal, s.g);
                    if v != 0.0 {
                        a.push((s.dof, v));
                    }
                }
            }
            for &(j, bj) in basis {
                let block = &mut blocks[j];
                let w = weight * bj;
                for &(da, va) in &a {
                    let ia = block.dofs.binary_search(&da).expect("touched in pass 1");
                    for &(db, vb) in &a {
                        let ib = block.dofs.binary_search(&db).expect("touched in pass 1");
                        block.values[(ia, ib)] += w * va * vb;
                    }
                }
            }
        });
        Ok(blocks.into_iter().map(drop_zero_rows).collect())
    }

    /// Visits every quadrature point of the field's rectangle with the shell
    /// point at the face, the area weight `dS`, the force direction and the
    /// non-zero spring basis values `(j, B_j)`.
    fn for_each_point(&self, shell: &Shell, mut f: impl FnMut(&ShellPoint, f64, Vec3, &[(usize, f64)])) {
        let (kx, ke) = (shell.surface().xi(), shell.surface().eta());
        let split = |own: &KnotVector, of_shell: &KnotVector| {
            let (a, b) = own.domain();
            let mut cuts: Vec<f64> = own.breakpoints();
            cuts.extend(of_shell.breakpoints().into_iter().filter(|&k| k > a && k < b));
            cuts.sort_by(f64::total_cmp);
            cuts.dedup();
            cuts
        };
        let (cx, ce) = (split(&self.xi, kx), split(&self.eta, ke));
        let points =
            |shell_degree: usize, spring_degree: usize| GaussLegendre::new(shell_degree + spring_degree / 2 + 1);
        let (gx, ge) = (
            points(kx.degree(), self.xi.degree()),
            points(ke.degree(), self.eta.degree()),
        );
        let tau = self.face.tau();
        let mut pt = crate::model::shell::ShellPoint::new_empty();
        let mut basis: Vec<(usize, f64)> = Vec::with_capacity((MAX_DEGREE + 1) * (MAX_DEGREE + 1));
        for wx in cx.windows(2) {
            for we in ce.windows(2) {
                for (xi, wxi) in gx.mapped(wx[0], wx[1]) {
                    for (eta, weta) in ge.mapped(we[0], we[1]) {
                        shell.evaluate_into(xi, eta, tau, &mut pt);
                        let area = cross(pt.jacobian[0], pt.jacobian[1]);
                        let weight = norm(area) * wxi * weta;
                        let normal = match self.direction {
                            SpringDirection::Fixed(v) => v,
                            SpringDirection::Normal => scale(area, 1.0 / norm(area)),
                        };
                        self.xi.tensor_basis_into(&self.eta, xi, eta, &mut basis);
                        f(&pt, weight, normal, &basis);
                    }
                }
            }
        }
    }
}

/// Removes rows and columns whose diagonal is zero (for a positive
/// semi-definite block those rows are zero).
fn drop_zero_rows(block: LowRankBlock) -> LowRankBlock {
    let keep: Vec<usize> = (0..block.dofs.len()).filter(|&i| block.values[(i, i)] > 0.0).collect();
    LowRankBlock {
        dofs: keep.iter().map(|&i| block.dofs[i]).collect(),
        values: Mat::from_fn(keep.len(), keep.len(), |r, c| block.values[(keep[r], keep[c])]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn paper_field(start: f64, end: f64, kappa: Vec<f64>) -> SpringField {
        SpringField::new(
            KnotVector::new(vec![start, end], 0).unwrap(),
            KnotVector::new(vec![0.0, 0.0, 0.0, 0.5, 1.0, 1.0, 1.0], 2).unwrap(),
            kappa,
            SpringDirection::fixed([0.0, 0.0, 1.0]).unwrap(),
            Face::Bottom,
        )
        .unwrap()
    }

    #[test]
    fn vertical_translation_energy_equals_integral_of_r33() {
        // For a rigid unit translation along z, δᵀ ΔK δ = ∫ r33 dS exactly.
        let shell = Shell::rectangular_plate(16.0, 9.0, 1.6, [4, 4], [13, 5]).unwrap();
        let kappa = vec![0.4e9, 1.5e9, 1.8e9, 0.6e9];
        let field = paper_field(0.0, 0.03, kappa.clone());
        let blocks = field.coefficient_matrices(&shell).unwrap();
        let mut energy = 0.0;
        for (b, k) in blocks.iter().zip(&kappa) {
            for (ia, &da) in b.dofs.iter().enumerate() {
                for (ib, &db) in b.dofs.iter().enumerate() {
                    if da % 5 == 2 && db % 5 == 2 {
                        energy += k * b.values[(ia, ib)];
                    }
                }
            }
        }
        // ∫ over ξ∈[0,0.03] (length 0.48 m) and η (width 9 m): the quadratic
        // B-splines on {0,0,0,.5,1,1,1} integrate to (1/6, 1/3, 1/3, 1/6).
        let exact = 0.03 * 16.0 * 9.0 * (kappa[0] / 6.0 + kappa[1] / 3.0 + kappa[2] / 3.0 + kappa[3] / 6.0);
        assert!((energy - exact).abs() < 1e-12 * exact, "{energy} vs {exact}");
        // Only w dofs of the first five ξ control-point columns are touched.
        for b in &blocks {
            assert!(b.dofs.iter().all(|d| d % 5 == 2 && (d / 5) / 5 < 5));
        }
    }

    #[test]
    fn rejects_bad_fields() {
        let kv = || KnotVector::new(vec![0.0, 0.0, 1.0, 1.0], 1).unwrap();
        let dir = SpringDirection::fixed([0.0, 0.0, 1.0]).unwrap();
        assert_eq!(
            SpringField::new(kv(), kv(), vec![1.0; 3], dir, Face::Bottom),
            Err(SpringError::CoefficientCount { found: 3, expected: 4 })
        );
        assert!(matches!(
            SpringField::new(kv(), kv(), vec![1.0, -1.0, 1.0, 1.0], dir, Face::Bottom),
            Err(SpringError::Coefficient { index: 1, .. })
        ));
        assert_eq!(SpringDirection::fixed([0.0; 3]), Err(SpringError::Direction));
    }
}
