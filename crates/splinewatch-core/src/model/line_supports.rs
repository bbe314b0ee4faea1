//! Line supports: springs per metre along a patch edge, in up to six
//! components (translations and rotations about three axes, the global
//! ones or a skewed frame such as an abutment's line): an integral
//! abutment's backfill and piles, an embankment.
//!
//! Component `c` with stiffness `k_c` (N/m per metre, or N m/rad per metre)
//! adds `ΔK = k_c ∫_edge n_cᵀ n_c ds`, `n_c` the row of eq. (3) that gives
//! the mid-surface's translation along the component's axis `a`
//! (`Σ N_i a·(u, v, w)_i`) or its rotation about `a`
//! (`Σ N_i (a·v1_i α_i + a·v2_i β_i)`: the director turns by
//! `α v1 + β v2`). So `∂K/∂k_c` is the integral itself and the updating
//! treats every `k_c` like a spring coefficient κ (eq. 22). On the ground's
//! motion a translation spring acts on the relative displacement, a
//! rotation spring on the rotation (the ground translates only).

use faer::Mat;
use thiserror::Error;

use crate::geometry::quadrature::GaussLegendre;
use crate::geometry::vec3::{cross, dot, norm, Vec3};
use crate::model::constraints::Edge;
use crate::model::shell::{Shell, ShellPoint, DOFS_PER_CONTROL_POINT};
use crate::model::springs::LowRankBlock;

#[derive(Debug, Clone, PartialEq, Error)]
pub enum LineSupportError {
    #[error("line support {name:?}: give at least one stiffness component")]
    NoComponent { name: String },
    #[error("line support {name:?}: stiffness {component} must be finite and not negative, got {value}")]
    Stiffness {
        name: String,
        component: &'static str,
        value: f64,
    },
    #[error("line support {name:?}: component {component} is given twice")]
    Twice { name: String, component: &'static str },
    #[error("line support {name:?}: its axes must be three orthonormal vectors")]
    Axes { name: String },
    #[error("a line support's name must not be empty")]
    EmptyName,
}

/// One stiffness component: a translation along, or a rotation about, axis
/// `0`, `1` or `2` of the support's frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SupportComponent {
    Translation(usize),
    Rotation(usize),
}

impl SupportComponent {
    /// Every component, in the order `x, y, z, rx, ry, rz`.
    pub const ALL: [Self; 6] = [
        Self::Translation(0),
        Self::Translation(1),
        Self::Translation(2),
        Self::Rotation(0),
        Self::Rotation(1),
        Self::Rotation(2),
    ];

    /// `x, y, z` or `rx, ry, rz`: the configuration's keys and the updating
    /// parameters' suffixes.
    pub fn name(self) -> &'static str {
        match self {
            Self::Translation(a) => ["x", "y", "z"][a],
            Self::Rotation(a) => ["rx", "ry", "rz"][a],
        }
    }
}

/// Springs per metre along one edge of a patch, validated.
#[derive(Debug, Clone, PartialEq)]
pub struct LineSupport {
    name: String,
    patch: usize,
    edge: Edge,
    /// Rows: the support's axes in global coordinates.
    axes: [Vec3; 3],
    components: Vec<SupportComponent>,
    stiffness: Vec<f64>,
}

impl LineSupport {
    /// `components` with their `stiffness` along `axes` (rows, orthonormal).
    pub fn new(
        name: impl Into<String>,
        (patch, edge): (usize, Edge),
        axes: [Vec3; 3],
        components: Vec<(SupportComponent, f64)>,
    ) -> Result<Self, LineSupportError> {
        let name = name.into();
        if name.is_empty() {
            return Err(LineSupportError::EmptyName);
        }
        if components.is_empty() {
            return Err(LineSupportError::NoComponent { name });
        }
        for (k, &(c, value)) in components.iter().enumerate() {
            if !(value.is_finite() && value >= 0.0) {
                return Err(LineSupportError::Stiffness {
                    name,
                    component: c.name(),
                    value,
                });
            }
            if components[..k].iter().any(|o| o.0 == c) {
                return Err(LineSupportError::Twice {
                    name,
                    component: c.name(),
                });
            }
        }
        let orthonormal = (0..3).all(|i| (0..3).all(|j| (dot(axes[i], axes[j]) - f64::from(i == j)).abs() < 1e-9));
        if !orthonormal || dot(cross(axes[0], axes[1]), axes[2]) < 0.0 {
            return Err(LineSupportError::Axes { name });
        }
        let (components, stiffness) = components.into_iter().unzip();
        Ok(Self {
            name,
            patch,
            edge,
            axes,
            components,
            stiffness,
        })
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    pub fn patch(&self) -> usize {
        self.patch
    }

    pub fn edge(&self) -> Edge {
        self.edge
    }

    pub fn components(&self) -> &[SupportComponent] {
        &self.components
    }

    /// Each component's stiffness, in [`Self::components`]' order.
    pub fn stiffness(&self) -> &[f64] {
        &self.stiffness
    }

    /// `∂K/∂k_c` per component on the patch's own dofs: the edge's control
    /// points (clamped knots: nothing else is non-zero on the edge),
    /// Gauss with `p + 1` points per knot span of the edge.
    pub fn coefficient_matrices(&self, shell: &Shell) -> Vec<LowRankBlock> {
        let surface = shell.surface();
        let (kx, ke) = (surface.xi(), surface.eta());
        let (xs, es) = (kx.breakpoints(), ke.breakpoints());
        let along_eta = matches!(self.edge, Edge::Xi0 | Edge::Xi1);
        let fixed = match self.edge {
            Edge::Xi0 => xs[0],
            Edge::Xi1 => xs[xs.len() - 1],
            Edge::Eta0 => es[0],
            Edge::Eta1 => es[es.len() - 1],
        };
        let (breaks, degree) = if along_eta {
            (es, ke.degree())
        } else {
            (xs, kx.degree())
        };
        let points = self.edge.control_points(shell);
        let dofs: Vec<usize> = points
            .iter()
            .flat_map(|&cp| (0..DOFS_PER_CONTROL_POINT).map(move |d| DOFS_PER_CONTROL_POINT * cp + d))
            .collect();
        let local = |cp: usize| points.iter().position(|&p| p == cp);
        let gauss = GaussLegendre::new(degree + 1);
        let mut blocks: Vec<Mat<f64>> = vec![Mat::zeros(dofs.len(), dofs.len()); self.components.len()];
        let mut pt = ShellPoint::new_empty();
        let mut row = vec![0.0; dofs.len()];
        for span in breaks.windows(2) {
            for (t, w) in gauss.mapped(span[0], span[1]) {
                let (xi, eta) = if along_eta { (fixed, t) } else { (t, fixed) };
                let e = surface.evaluate(xi, eta);
                let ds = w * norm(if along_eta { e.r_eta } else { e.r_xi });
                shell.evaluate_into(xi, eta, 0.5, &mut pt);
                for (c, block) in self.components.iter().zip(&mut blocks) {
                    row.iter_mut().for_each(|r| *r = 0.0);
                    for k in 0..pt.count {
                        let (cp, n) = (pt.control_points[k], pt.n[k]);
                        let Some(i) = local(cp).filter(|_| n != 0.0) else {
                            continue;
                        };
                        let at = DOFS_PER_CONTROL_POINT * i;
                        match *c {
                            SupportComponent::Translation(a) => {
                                for d in 0..3 {
                                    row[at + d] += n * self.axes[a][d];
                                }
                            }
                            SupportComponent::Rotation(a) => {
                                let frame = shell.frames()[cp];
                                row[at + 3] += n * dot(self.axes[a], frame.v1);
                                row[at + 4] += n * dot(self.axes[a], frame.v2);
                            }
                        }
                    }
                    for (i, &ri) in row.iter().enumerate().filter(|r| *r.1 != 0.0) {
                        for (j, &rj) in row.iter().enumerate().filter(|r| *r.1 != 0.0) {
                            block[(i, j)] += ds * ri * rj;
                        }
                    }
                }
            }
        }
        blocks
            .into_iter()
            .map(|values| LowRankBlock {
                dofs: dofs.clone(),
                values,
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn global() -> [Vec3; 3] {
        [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
    }

    /// `½ vᵀ B v` of a block for the patch's dof vector `v`.
    fn energy(block: &LowRankBlock, v: &[f64]) -> f64 {
        let mut e = 0.0;
        for (a, &ra) in block.dofs.iter().enumerate() {
            for (b, &rb) in block.dofs.iter().enumerate() {
                e += 0.5 * v[ra] * block.values[(a, b)] * v[rb];
            }
        }
        e
    }

    /// On a 6 m × 3 m plate's `ξ = 0` edge (3 m along y): a unit rigid
    /// translation stores `½ L` per unit stiffness in its own component
    /// and nothing in the others; a unit rotation about the edge (x for
    /// a plate in the xy plane, α) `½ L` in `rx`; skewed axes see the
    /// translation's projection.
    #[test]
    fn rigid_motions_of_an_edge_store_half_the_length_per_unit_stiffness() {
        let shell = Shell::rectangular_plate(6.0, 3.0, 0.2, [3, 2], [6, 5]).unwrap();
        let all: Vec<(SupportComponent, f64)> = SupportComponent::ALL.iter().map(|&c| (c, 1.0)).collect();
        let support = LineSupport::new("west", (0, Edge::Xi0), global(), all.clone()).unwrap();
        let blocks = support.coefficient_matrices(&shell);
        let n = shell.dof_count();
        let unit = |d: usize| -> Vec<f64> { (0..n).map(|i| f64::from(i % 5 == d)).collect() };
        for (c, block) in blocks.iter().enumerate() {
            for d in 0..5 {
                // Components x, y, z, rx, ry; rz (a drilling rotation) has
                // no dof of the shell: nothing.
                let expected = if c == d && c < 5 { 1.5 } else { 0.0 };
                let e = energy(block, &unit(d));
                assert!((e - expected).abs() < 1e-12, "component {c}, dof {d}: {e}");
            }
        }
        let c = std::f64::consts::FRAC_1_SQRT_2;
        let skewed = [[c, c, 0.0], [-c, c, 0.0], [0.0, 0.0, 1.0]];
        let support = LineSupport::new("skewed", (0, Edge::Xi0), skewed, all).unwrap();
        let blocks = support.coefficient_matrices(&shell);
        let e = energy(&blocks[0], &unit(0));
        assert!((e - 1.5 * 0.5).abs() < 1e-12, "{e}");
    }

    #[test]
    fn bad_supports_are_refused_by_name() {
        let edge = (0, Edge::Xi0);
        let error = |components: Vec<(SupportComponent, f64)>, axes: [Vec3; 3]| {
            LineSupport::new("east", edge, axes, components)
                .unwrap_err()
                .to_string()
        };
        assert!(error(vec![], global()).contains("\"east\""));
        let negative = error(vec![(SupportComponent::Rotation(1), -1.0)], global());
        assert!(negative.contains("ry") && negative.contains("-1"), "{negative}");
        let twice = vec![
            (SupportComponent::Translation(2), 1.0),
            (SupportComponent::Translation(2), 2.0),
        ];
        assert!(error(twice, global()).contains("given twice"));
        let sheared = [[1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        assert!(error(vec![(SupportComponent::Translation(0), 1.0)], sheared).contains("orthonormal"));
    }
}
