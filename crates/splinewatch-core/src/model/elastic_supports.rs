//! Elastic supports in up to six components (translations and rotations
//! about three axes, the global ones or a skewed frame such as an
//! abutment's line): springs per metre along a patch edge (an integral
//! abutment's backfill and piles, an embankment), springs at a point of a
//! patch (a bearing that also restrains rotations, a pile cap under a
//! slab), or springs at beam nodes (a column's footing on its piles and
//! soil).
//!
//! Along an edge, component `c` with stiffness `k_c` (N/m per metre, or N m/rad per metre)
//! adds `ΔK = k_c ∫_edge n_cᵀ n_c ds`, `n_c` the row of eq. (3) that gives
//! the mid-surface's translation along the component's axis `a`
//! (`Σ N_i a·(u, v, w)_i`) or its rotation about `a`
//! (`Σ N_i (a·v1_i α_i + a·v2_i β_i)`: the director turns by
//! `α v1 + β v2`). So `∂K/∂k_c` is the integral itself and the updating
//! treats every `k_c` like a spring coefficient κ (eq. 22). At a point
//! `(ξ, η, τ)` of a patch it adds `k_c n_cᵀ n_c` there (N/m, N m/rad), the
//! translation's row that of the point at `τ` (eq. 2–3: off the
//! mid-surface it also turns with the director). At a beam node
//! (6 dofs: `u, v, w, rx, ry, rz`) it adds `k_c a aᵀ` on the node's three
//! translations or three rotations (N/m, N m/rad). On the ground's
//! motion a translation spring acts on the relative displacement, a
//! rotation spring on the rotation (the ground translates only).

use faer::Mat;
use thiserror::Error;

use crate::geometry::quadrature::GaussLegendre;
use crate::geometry::vec3::{dot, is_right_handed_frame, norm, Vec3};
use crate::model::bearings::PatchPoint;
use crate::model::constraints::Edge;
use crate::model::dofs::DofMap;
use crate::model::shell::{Shell, ShellPoint, DOFS_PER_CONTROL_POINT};
use crate::model::springs::LowRankBlock;

#[derive(Debug, Clone, PartialEq, Error)]
pub enum ElasticSupportError {
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
    #[error("support {name:?}: give at least one beam node")]
    NoNode { name: String },
    #[error("a support's name must not be empty")]
    EmptyName,
    #[error("support {name:?}: ({xi}, {eta}, {tau}) lies outside its patch's parameter domain")]
    Outside { name: String, xi: f64, eta: f64, tau: f64 },
    #[error("support {name:?} names beam node {node}, but the beams have {count} nodes")]
    UnknownBeamNode { name: String, node: usize, count: usize },
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

/// Where a support acts.
#[derive(Debug, Clone, PartialEq)]
pub enum SupportSite {
    /// Along edge `edge` of patch `patch`, per metre.
    Edge { patch: usize, edge: Edge },
    /// At one point of a patch.
    Point(PatchPoint),
    /// At each of these beam nodes (the net's numbering), the same springs.
    BeamNodes(Vec<usize>),
}

/// Springs in up to six components along a patch edge, at a point of a
/// patch or at beam nodes, validated.
#[derive(Debug, Clone, PartialEq)]
pub struct ElasticSupport {
    name: String,
    site: SupportSite,
    /// Rows: the support's axes in global coordinates.
    axes: [Vec3; 3],
    components: Vec<SupportComponent>,
    stiffness: Vec<f64>,
}

impl ElasticSupport {
    /// Springs per metre along edge `edge` of patch `patch`: `components`
    /// with their `stiffness` along `axes` (rows, orthonormal).
    pub fn along_edge(
        name: impl Into<String>,
        (patch, edge): (usize, Edge),
        axes: [Vec3; 3],
        components: Vec<(SupportComponent, f64)>,
    ) -> Result<Self, ElasticSupportError> {
        Self::new(name.into(), SupportSite::Edge { patch, edge }, axes, components)
    }

    /// Springs at point `at` of a patch: `components` with their
    /// `stiffness` (N/m, N m/rad) along `axes` (rows, orthonormal).
    pub fn at_point(
        name: impl Into<String>,
        at: PatchPoint,
        axes: [Vec3; 3],
        components: Vec<(SupportComponent, f64)>,
    ) -> Result<Self, ElasticSupportError> {
        Self::new(name.into(), SupportSite::Point(at), axes, components)
    }

    /// The same springs at each of the beam nodes `nodes`.
    pub fn at_beam_nodes(
        name: impl Into<String>,
        nodes: Vec<usize>,
        axes: [Vec3; 3],
        components: Vec<(SupportComponent, f64)>,
    ) -> Result<Self, ElasticSupportError> {
        let name = name.into();
        if nodes.is_empty() {
            return Err(ElasticSupportError::NoNode { name });
        }
        Self::new(name, SupportSite::BeamNodes(nodes), axes, components)
    }

    fn new(
        name: String,
        site: SupportSite,
        axes: [Vec3; 3],
        components: Vec<(SupportComponent, f64)>,
    ) -> Result<Self, ElasticSupportError> {
        if name.is_empty() {
            return Err(ElasticSupportError::EmptyName);
        }
        if components.is_empty() {
            return Err(ElasticSupportError::NoComponent { name });
        }
        for (k, &(c, value)) in components.iter().enumerate() {
            if !(value.is_finite() && value >= 0.0) {
                return Err(ElasticSupportError::Stiffness {
                    name,
                    component: c.name(),
                    value,
                });
            }
            if components[..k].iter().any(|o| o.0 == c) {
                return Err(ElasticSupportError::Twice {
                    name,
                    component: c.name(),
                });
            }
        }
        if !is_right_handed_frame(&axes) {
            return Err(ElasticSupportError::Axes { name });
        }
        let (components, stiffness) = components.into_iter().unzip();
        Ok(Self {
            name,
            site,
            axes,
            components,
            stiffness,
        })
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    pub fn site(&self) -> &SupportSite {
        &self.site
    }

    /// The patch of a support along an edge or at a point of a patch.
    pub fn patch(&self) -> Option<usize> {
        match self.site {
            SupportSite::Edge { patch, .. } | SupportSite::Point(PatchPoint { patch, .. }) => Some(patch),
            SupportSite::BeamNodes(_) => None,
        }
    }

    pub fn components(&self) -> &[SupportComponent] {
        &self.components
    }

    /// Each component's stiffness, in [`Self::components`]' order.
    pub fn stiffness(&self) -> &[f64] {
        &self.stiffness
    }

    /// `∂K/∂k_c` per component on global dofs: along an edge (integrated)
    /// or at a point, on the patch `patch_of` gives (its shell and its
    /// first global dof; a point outside the patch is refused);
    /// at beam nodes, on `dofs`' beam nodes (one it does not have is
    /// refused).
    pub fn matrices<'s, E: From<ElasticSupportError>>(
        &self,
        dofs: &DofMap,
        patch_of: impl FnOnce(usize) -> Result<(&'s Shell, usize), E>,
    ) -> Result<Vec<LowRankBlock>, E> {
        match &self.site {
            SupportSite::Edge { patch, edge } => {
                let (shell, offset) = patch_of(*patch)?;
                Ok(self
                    .edge_matrices(*edge, shell)
                    .into_iter()
                    .map(|b| b.shifted(offset))
                    .collect())
            }
            SupportSite::Point(at) => {
                let (shell, offset) = patch_of(at.patch)?;
                if !at.lies_on(shell) {
                    return Err(ElasticSupportError::Outside {
                        name: self.name.clone(),
                        xi: at.xi,
                        eta: at.eta,
                        tau: at.tau,
                    }
                    .into());
                }
                Ok(self
                    .point_matrices(*at, shell)
                    .into_iter()
                    .map(|b| b.shifted(offset))
                    .collect())
            }
            SupportSite::BeamNodes(nodes) => {
                let count = dofs.beam_node_count();
                if let Some(&node) = nodes.iter().find(|&&n| n >= count) {
                    return Err(ElasticSupportError::UnknownBeamNode {
                        name: self.name.clone(),
                        node,
                        count,
                    }
                    .into());
                }
                Ok(self.node_matrices(nodes, dofs))
            }
        }
    }

    /// At beam `nodes`: `a aᵀ` on each node's translations or rotations.
    fn node_matrices(&self, nodes: &[usize], dofs: &DofMap) -> Vec<LowRankBlock> {
        let global: Vec<usize> = nodes.iter().flat_map(|&n| dofs.node_dofs(dofs.beam_node(n))).collect();
        self.components
            .iter()
            .map(|&c| {
                let (axis, first) = match c {
                    SupportComponent::Translation(a) => (a, 0),
                    SupportComponent::Rotation(a) => (a, 3),
                };
                let a = self.axes[axis];
                let mut values = Mat::zeros(global.len(), global.len());
                for k in 0..nodes.len() {
                    for i in 0..3 {
                        for j in 0..3 {
                            values[(6 * k + first + i, 6 * k + first + j)] = a[i] * a[j];
                        }
                    }
                }
                LowRankBlock {
                    dofs: global.clone(),
                    values,
                }
            })
            .collect()
    }

    /// Along `edge`, on the patch's own dofs: the edge's control points
    /// (clamped knots: nothing else is non-zero on the edge), Gauss with
    /// `p + 1` points per knot span of the edge.
    fn edge_matrices(&self, edge: Edge, shell: &Shell) -> Vec<LowRankBlock> {
        let surface = shell.surface();
        let (kx, ke) = (surface.xi(), surface.eta());
        let (xs, es) = (kx.breakpoints(), ke.breakpoints());
        let along_eta = matches!(edge, Edge::Xi0 | Edge::Xi1);
        let fixed = match edge {
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
        let points = edge.control_points(shell);
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
                for (&c, block) in self.components.iter().zip(&mut blocks) {
                    self.component_row(c, shell, &pt, local, &mut row);
                    add_outer(block, ds, &row);
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

    /// At point `at`, on the patch's own dofs: the control points whose
    /// basis is non-zero there.
    fn point_matrices(&self, at: PatchPoint, shell: &Shell) -> Vec<LowRankBlock> {
        let mut pt = ShellPoint::new_empty();
        shell.evaluate_into(at.xi, at.eta, at.tau, &mut pt);
        let points: Vec<usize> = (0..pt.count)
            .filter(|&k| pt.n[k] != 0.0)
            .map(|k| pt.control_points[k])
            .collect();
        let dofs: Vec<usize> = points
            .iter()
            .flat_map(|&cp| (0..DOFS_PER_CONTROL_POINT).map(move |d| DOFS_PER_CONTROL_POINT * cp + d))
            .collect();
        let local = |cp: usize| points.iter().position(|&p| p == cp);
        let mut row = vec![0.0; dofs.len()];
        self.components
            .iter()
            .map(|&c| {
                let mut values = Mat::zeros(dofs.len(), dofs.len());
                self.component_row(c, shell, &pt, local, &mut row);
                add_outer(&mut values, 1.0, &row);
                LowRankBlock {
                    dofs: dofs.clone(),
                    values,
                }
            })
            .collect()
    }

    /// `n_c` at `pt` on the local dofs `local` numbers (5 per control
    /// point): the point's translation along the component's axis `a`
    /// (eq. 2–3, at the point's τ), or the director's rotation about it,
    /// `Σ N_i (a·v1_i α_i + a·v2_i β_i)`.
    fn component_row(
        &self,
        c: SupportComponent,
        shell: &Shell,
        pt: &ShellPoint,
        local: impl Fn(usize) -> Option<usize>,
        row: &mut [f64],
    ) {
        row.iter_mut().for_each(|r| *r = 0.0);
        for k in 0..pt.count {
            let (cp, n) = (pt.control_points[k], pt.n[k]);
            let Some(i) = local(cp).filter(|_| n != 0.0) else {
                continue;
            };
            let at = DOFS_PER_CONTROL_POINT * i;
            match c {
                SupportComponent::Translation(a) => {
                    for (d, shape) in shell.dof_shapes(pt, k).into_iter().enumerate() {
                        row[at + d] += shape.psi * dot(self.axes[a], shape.g);
                    }
                }
                SupportComponent::Rotation(a) => {
                    let frame = shell.frames()[cp];
                    row[at + 3] += n * dot(self.axes[a], frame.v1);
                    row[at + 4] += n * dot(self.axes[a], frame.v2);
                }
            }
        }
    }
}

/// `block += scale row rowᵀ` over the non-zero entries of `row`.
fn add_outer(block: &mut Mat<f64>, scale: f64, row: &[f64]) {
    for (i, &ri) in row.iter().enumerate().filter(|r| *r.1 != 0.0) {
        for (j, &rj) in row.iter().enumerate().filter(|r| *r.1 != 0.0) {
            block[(i, j)] += scale * ri * rj;
        }
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
        let support = ElasticSupport::along_edge("west", (0, Edge::Xi0), global(), all.clone()).unwrap();
        let blocks = support.edge_matrices(Edge::Xi0, &shell);
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
        let support = ElasticSupport::along_edge("skewed", (0, Edge::Xi0), skewed, all).unwrap();
        let blocks = support.edge_matrices(Edge::Xi0, &shell);
        let e = energy(&blocks[0], &unit(0));
        assert!((e - 1.5 * 0.5).abs() < 1e-12, "{e}");
    }

    /// At two beam nodes: a unit translation of both nodes along a
    /// component's axis stores `½` per node and unit stiffness in that
    /// component (and nothing in the rotations'); a unit rotation about it
    /// the same in the rotation's; on skewed axes the projection.
    #[test]
    fn springs_at_beam_nodes_store_half_the_stiffness_per_node() {
        let dofs = DofMap::of_model(&[], 3, 0);
        let all: Vec<(SupportComponent, f64)> = SupportComponent::ALL.iter().map(|&c| (c, 1.0)).collect();
        let support = ElasticSupport::at_beam_nodes("footings", vec![0, 2], global(), all.clone()).unwrap();
        let blocks = support.node_matrices(&[0, 2], &dofs);
        let n = dofs.dof_count();
        // Dof d of beam nodes 0 and 2 (not 1) moved by 1.
        let unit = |d: usize| -> Vec<f64> { (0..n).map(|i| f64::from(i % 6 == d && i / 6 != 1)).collect() };
        for (c, block) in blocks.iter().enumerate() {
            for d in 0..6 {
                let expected = if c == d { 1.0 } else { 0.0 };
                let e = energy(block, &unit(d));
                assert!((e - expected).abs() < 1e-12, "component {c}, dof {d}: {e}");
            }
        }
        let c = std::f64::consts::FRAC_1_SQRT_2;
        let skewed = [[c, c, 0.0], [-c, c, 0.0], [0.0, 0.0, 1.0]];
        let support = ElasticSupport::at_beam_nodes("skewed", vec![1], skewed, all).unwrap();
        let blocks = support.node_matrices(&[1], &dofs);
        let rotated: Vec<f64> = (0..n).map(|i| f64::from(i == 6 + 3)).collect();
        assert!((energy(&blocks[3], &rotated) - 0.25).abs() < 1e-12);
        assert!((energy(&blocks[0], &rotated)).abs() < 1e-12);
        // Through `matrices`, the same blocks; a node the beams lack is refused by name.
        let through = support
            .matrices(&dofs, |_| Err(ElasticSupportError::EmptyName))
            .unwrap();
        assert_eq!(through, blocks);
        let beyond =
            ElasticSupport::at_beam_nodes("far", vec![5], global(), vec![(SupportComponent::ALL[0], 1.0)]).unwrap();
        let e = beyond
            .matrices(&dofs, |_| Err(ElasticSupportError::EmptyName))
            .unwrap_err();
        assert_eq!(
            e.to_string(),
            "support \"far\" names beam node 5, but the beams have 3 nodes"
        );
        let none = ElasticSupport::at_beam_nodes(
            "nowhere",
            vec![],
            global(),
            vec![(SupportComponent::Translation(2), 1.0)],
        );
        assert!(none
            .unwrap_err()
            .to_string()
            .contains("\"nowhere\": give at least one beam node"));
    }

    /// At a plate's centre (its frame the global axes): a unit rigid
    /// translation stores `½` per unit stiffness in its own component, a
    /// unit rotation about x (α) `½` in `rx`; on the bottom face a unit
    /// rotation about y (β) moves the point by `−h/2` along x, so it
    /// stores `½ (h/2)²` in `x`. A point beyond the patch is refused.
    #[test]
    fn a_point_support_stores_half_its_stiffness_under_unit_motions() {
        let h = 0.2;
        let shell = Shell::rectangular_plate(6.0, 3.0, h, [3, 2], [6, 5]).unwrap();
        let all: Vec<(SupportComponent, f64)> = SupportComponent::ALL.iter().map(|&c| (c, 1.0)).collect();
        let n = shell.dof_count();
        let unit = |d: usize| -> Vec<f64> { (0..n).map(|i| f64::from(i % 5 == d)).collect() };
        let centre = |tau| PatchPoint {
            patch: 0,
            xi: 0.37,
            eta: 0.61,
            tau,
        };
        let mid = ElasticSupport::at_point("pot", centre(0.5), global(), all.clone()).unwrap();
        let blocks = mid.point_matrices(centre(0.5), &shell);
        for (c, block) in blocks.iter().enumerate() {
            for d in 0..5 {
                let expected = if c == d && c < 5 { 0.5 } else { 0.0 };
                let e = energy(block, &unit(d));
                assert!((e - expected).abs() < 1e-12, "component {c}, dof {d}: {e}");
            }
        }
        let bottom = ElasticSupport::at_point("pot", centre(0.0), global(), all).unwrap();
        let blocks = bottom.point_matrices(centre(0.0), &shell);
        let e = energy(&blocks[0], &unit(4));
        assert!((e - 0.5 * (h / 2.0) * (h / 2.0)).abs() < 1e-12, "{e}");
        let dofs = DofMap::of_model(&[], 0, 0);
        let beyond = PatchPoint { xi: 1.5, ..centre(0.5) };
        let e = ElasticSupport::at_point("far", beyond, global(), vec![(SupportComponent::ALL[2], 1.0)])
            .unwrap()
            .matrices(&dofs, |_| Ok::<_, ElasticSupportError>((&shell, 0)))
            .unwrap_err();
        assert!(e.to_string().contains("\"far\": (1.5, 0.61, 0.5) lies outside"), "{e}");
    }

    #[test]
    fn bad_supports_are_refused_by_name() {
        let edge = (0, Edge::Xi0);
        let error = |components: Vec<(SupportComponent, f64)>, axes: [Vec3; 3]| {
            ElasticSupport::along_edge("east", edge, axes, components)
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
