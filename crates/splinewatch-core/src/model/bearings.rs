//! Discrete supports and masses at points of a patch.
//!
//! A bearing at `(ξ, η, τ)` is three springs along its axes `e_d` (the
//! global ones, or a frame skewed with its support line):
//! `ΔK = Σ_d k_d a_dᵀ a_d`, `a_d = Σ_g e_{d,g} N_g` with `N_g` the row of
//! eq. (3)'s `N` for global axis `g` at the point, so `∂K/∂k_d = a_dᵀ a_d`
//! (rank one) and the updating treats `k_x`, `k_y`, `k_z` like the spring
//! coefficients κ_j of eq. (22). A point mass
//! `m` at the mid-surface adds `m Σ_d a_dᵀ a_d` to `M` (translations only).

use crate::geometry::vec3::{is_right_handed_frame, Vec3};
use crate::model::shell::Shell;
use crate::model::springs::LowRankBlock;
use faer::Mat;
use thiserror::Error;

#[derive(Debug, Clone, PartialEq, Error)]
pub enum BearingError {
    #[error("({xi}, {eta}, {tau}) lies outside the patch's parameter domain")]
    Outside { xi: f64, eta: f64, tau: f64 },
    #[error("stiffness {axis} must be finite and not negative, got {value} N/m")]
    Stiffness { axis: &'static str, value: f64 },
    #[error("the mass must be finite and positive, got {0} kg")]
    Mass(f64),
    #[error("the bearing's axes must be three orthonormal, right-handed rows, got {0:?}")]
    Axes([Vec3; 3]),
}

/// Where on a patch: parameters and the thickness coordinate τ ∈ [0, 1].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PatchPoint {
    pub patch: usize,
    pub xi: f64,
    pub eta: f64,
    pub tau: f64,
}

impl PatchPoint {
    /// Whether `(ξ, η)` lies in `shell`'s parameter domain and τ in [0, 1].
    pub fn lies_on(&self, shell: &Shell) -> bool {
        let (kx, ke) = (shell.surface().xi(), shell.surface().eta());
        kx.contains(self.xi) && ke.contains(self.eta) && (0.0..=1.0).contains(&self.tau)
    }
}

/// An elastic bearing: springs `[k_x, k_y, k_z]` (N/m) along its axes
/// (the global ones unless [`Bearing::with_axes`] skews them).
#[derive(Debug, Clone, PartialEq)]
pub struct Bearing {
    at: PatchPoint,
    stiffness: [f64; 3],
    /// Rows: the axes of `k_x, k_y, k_z` in global coordinates.
    axes: [Vec3; 3],
}

/// A point mass (kg) at the mid-surface.
#[derive(Debug, Clone, PartialEq)]
pub struct PointMass {
    at: PatchPoint,
    mass: f64,
}

const AXES: [&str; 3] = ["kx", "ky", "kz"];

impl Bearing {
    pub fn new(at: PatchPoint, stiffness: [f64; 3]) -> Result<Self, BearingError> {
        if let Some(d) = (0..3).find(|&d| !(stiffness[d].is_finite() && stiffness[d] >= 0.0)) {
            return Err(BearingError::Stiffness {
                axis: AXES[d],
                value: stiffness[d],
            });
        }
        Ok(Self {
            at,
            stiffness,
            axes: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
        })
    }

    /// The same bearing with `k_x, k_y, k_z` along `axes` (rows,
    /// orthonormal and right-handed: along and across a skewed support
    /// line, and up).
    pub fn with_axes(self, axes: [Vec3; 3]) -> Result<Self, BearingError> {
        if !is_right_handed_frame(&axes) {
            return Err(BearingError::Axes(axes));
        }
        Ok(Self { axes, ..self })
    }

    /// The axes of `k_x, k_y, k_z` (rows, global coordinates).
    pub fn axes(&self) -> [Vec3; 3] {
        self.axes
    }

    pub fn at(&self) -> PatchPoint {
        self.at
    }

    pub fn stiffness(&self) -> &[f64] {
        &self.stiffness
    }

    /// `∂K/∂k_d` for `d` = x, y, z (its axes) on the patch's own dofs.
    pub fn coefficient_matrices(&self, shell: &Shell) -> Result<Vec<LowRankBlock>, BearingError> {
        let global = axis_rows(shell, self.at)?;
        Ok(self
            .axes
            .iter()
            .map(|e| {
                let mut row: std::collections::BTreeMap<usize, f64> = std::collections::BTreeMap::new();
                for (g, a) in global.iter().enumerate().filter(|&(g, _)| e[g] != 0.0) {
                    for &(dof, v) in a {
                        *row.entry(dof).or_insert(0.0) += e[g] * v;
                    }
                }
                let row: Vec<(usize, f64)> = row.into_iter().filter(|&(_, v)| v != 0.0).collect();
                outer(&row, 1.0)
            })
            .collect())
    }
}

impl PointMass {
    pub fn new(at: PatchPoint, mass: f64) -> Result<Self, BearingError> {
        if !(mass.is_finite() && mass > 0.0) {
            return Err(BearingError::Mass(mass));
        }
        Ok(Self {
            at: PatchPoint { tau: 0.5, ..at },
            mass,
        })
    }

    pub fn at(&self) -> PatchPoint {
        self.at
    }

    pub fn mass(&self) -> f64 {
        self.mass
    }

    /// `m Σ_d a_dᵀ a_d` on the patch's own dofs.
    pub fn mass_block(&self, shell: &Shell) -> Result<LowRankBlock, BearingError> {
        let rows = axis_rows(shell, self.at)?;
        let mut dofs: Vec<usize> = rows.iter().flatten().map(|&(d, _)| d).collect();
        dofs.sort_unstable();
        dofs.dedup();
        let mut values = Mat::zeros(dofs.len(), dofs.len());
        for a in &rows {
            for &(da, va) in a {
                let ia = dofs.binary_search(&da).expect("listed above");
                for &(db, vb) in a {
                    let ib = dofs.binary_search(&db).expect("listed above");
                    values[(ia, ib)] += self.mass * va * vb;
                }
            }
        }
        Ok(LowRankBlock { dofs, values })
    }
}

/// The rows `a_x, a_y, a_z` of eq. (3)'s `N` at the point, as `(dof, value)`.
fn axis_rows(shell: &Shell, at: PatchPoint) -> Result<[Vec<(usize, f64)>; 3], BearingError> {
    if !at.lies_on(shell) {
        return Err(BearingError::Outside {
            xi: at.xi,
            eta: at.eta,
            tau: at.tau,
        });
    }
    let columns: Vec<(usize, Vec3)> = shell.shape_functions(at.xi, at.eta, at.tau);
    Ok([0, 1, 2].map(|d| {
        columns
            .iter()
            .filter(|(_, c)| c[d] != 0.0)
            .map(|&(dof, c)| (dof, c[d]))
            .collect()
    }))
}

fn outer(a: &[(usize, f64)], scale: f64) -> LowRankBlock {
    let dofs: Vec<usize> = a.iter().map(|&(d, _)| d).collect();
    let values = Mat::from_fn(a.len(), a.len(), |r, c| scale * a[r].1 * a[c].1);
    LowRankBlock { dofs, values }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::shell::DOFS_PER_CONTROL_POINT;

    fn plate() -> Shell {
        Shell::rectangular_plate(10.0, 4.0, 0.3, [3, 3], [6, 5]).unwrap()
    }

    #[test]
    fn a_bearing_under_a_corner_loads_only_the_corner_control_point() {
        // Clamped knots interpolate the corner: N = 1 there for its control
        // point, and the bottom face adds the rotations' lever arm t/2.
        let at = PatchPoint {
            patch: 0,
            xi: 0.0,
            eta: 0.0,
            tau: 0.0,
        };
        let blocks = Bearing::new(at, [1.0, 2.0, 3.0])
            .unwrap()
            .coefficient_matrices(&plate())
            .unwrap();
        assert_eq!(blocks.len(), 3);
        assert_eq!(blocks[2].dofs, vec![2]);
        assert_eq!(blocks[2].values[(0, 0)], 1.0);
        // x at the bottom face: u − (t/2)·β (β turns v3 towards v1 = x).
        assert_eq!(blocks[0].dofs, vec![0, 4]);
        assert!((blocks[0].values[(0, 1)] + 0.15).abs() < 1e-15);
    }

    /// A bearing skewed 38.9° about z stores `Σ_d k_d (e_d · u)²` for the
    /// point's displacement `u` of any dof vector (against the global rows
    /// directly, 1e-12), equals the global-axes bearing when its three
    /// stiffnesses are equal (rotation invariance), and refuses axes that
    /// are not orthonormal and right-handed.
    #[test]
    fn a_skewed_bearing_acts_along_its_axes() {
        let shell = plate();
        let at = PatchPoint {
            patch: 0,
            xi: 0.37,
            eta: 0.61,
            tau: 0.0,
        };
        let (s, c) = 38.9f64.to_radians().sin_cos();
        let axes = [[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]];
        let k = [2e8, 7e7, 3e9];
        let skewed = Bearing::new(at, k).unwrap().with_axes(axes).unwrap();
        let blocks = skewed.coefficient_matrices(&shell).unwrap();
        let global = axis_rows(&shell, at).unwrap();
        let q: Vec<f64> = (0..shell.dof_count())
            .map(|i| ((i * 7919) % 97) as f64 / 97.0 - 0.5)
            .collect();
        let u: Vec<f64> = global.iter().map(|a| a.iter().map(|&(d, v)| v * q[d]).sum()).collect();
        let expected: f64 = (0..3)
            .map(|d| k[d] * (0..3).map(|g| axes[d][g] * u[g]).sum::<f64>().powi(2))
            .sum();
        let energy = |blocks: &[LowRankBlock], k: [f64; 3]| -> f64 {
            blocks
                .iter()
                .zip(k)
                .map(|(b, kd)| {
                    let x: Vec<f64> = b.dofs.iter().map(|&d| q[d]).collect();
                    kd * (0..x.len())
                        .flat_map(|r| (0..x.len()).map(move |c| (r, c)))
                        .map(|(r, c)| x[r] * b.values[(r, c)] * x[c])
                        .sum::<f64>()
                })
                .sum()
        };
        let ours = energy(&blocks, k);
        assert!((ours - expected).abs() <= 1e-12 * expected, "{ours} vs {expected}");
        let equal = [5e8; 3];
        let (a, b) = (
            energy(
                &Bearing::new(at, equal)
                    .unwrap()
                    .with_axes(axes)
                    .unwrap()
                    .coefficient_matrices(&shell)
                    .unwrap(),
                equal,
            ),
            energy(
                &Bearing::new(at, equal).unwrap().coefficient_matrices(&shell).unwrap(),
                equal,
            ),
        );
        assert!((a - b).abs() <= 1e-12 * b, "{a} vs {b}");
        let left_handed = [axes[1], axes[0], axes[2]];
        assert!(matches!(
            Bearing::new(at, k).unwrap().with_axes(left_handed),
            Err(BearingError::Axes(_))
        ));
        let sheared = [[1.0, 0.1, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        assert!(matches!(
            Bearing::new(at, k).unwrap().with_axes(sheared),
            Err(BearingError::Axes(_))
        ));
    }

    #[test]
    fn a_point_mass_adds_its_mass_to_every_rigid_translation() {
        let shell = plate();
        let at = PatchPoint {
            patch: 0,
            xi: 0.37,
            eta: 0.61,
            tau: 0.0,
        };
        let block = PointMass::new(at, 250.0).unwrap().mass_block(&shell).unwrap();
        for d in 0..3 {
            let idx: Vec<usize> = (0..block.dofs.len())
                .filter(|&i| block.dofs[i] % DOFS_PER_CONTROL_POINT == d)
                .collect();
            let total: f64 = idx
                .iter()
                .flat_map(|&a| idx.iter().map(move |&b| (a, b)))
                .map(|(a, b)| block.values[(a, b)])
                .sum();
            assert!((total - 250.0).abs() < 1e-10, "{total}");
        }
        assert!(matches!(PointMass::new(at, 0.0), Err(BearingError::Mass(_))));
        assert!(matches!(
            Bearing::new(at, [1.0, f64::NAN, 0.0]),
            Err(BearingError::Stiffness { axis: "ky", .. })
        ));
        let outside = PatchPoint { xi: 1.5, ..at };
        assert!(matches!(
            Bearing::new(outside, [1.0; 3]).unwrap().coefficient_matrices(&shell),
            Err(BearingError::Outside { .. })
        ));
    }
}
