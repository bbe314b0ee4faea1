//! The generalised dofs of a model: its nodes in order, the shell patches'
//! control points first, patch by patch, then the beams' nodes; each node's
//! components numbered together.
//!
//! A shell control point carries five components (eq. 3): the translations
//! `u, v, w` of its reference point along the global axes and the rotations
//! `α, β` of its director. A beam node carries six: three translations and
//! three rotations about the global axes ([`crate::model::beam`]); so does a
//! rigid body's reference node ([`crate::model::rigid`]), numbered after
//! the beam nodes. The map is
//! the one place that knows this layout: a ground's rigid translation, a
//! support's lifted dofs or a patch's first dof are asked of it, not
//! computed from a count per node.

use std::ops::Range;

use crate::model::beam::DOFS_PER_BEAM_NODE;
use crate::model::patch::Patch;
use crate::model::shell::DOFS_PER_CONTROL_POINT;

/// What one generalised dof is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DofKind {
    /// A translation along the global axis `0` (x), `1` (y) or `2` (z).
    Translation(usize),
    /// A rotation of a shell control point's director: `0` for `α`, `1`
    /// for `β` (eq. 3).
    DirectorRotation(usize),
    /// A beam node's rotation about the global axis `0`, `1` or `2`.
    Rotation(usize),
}

/// The numbering of a model's generalised dofs: patch after patch (patch
/// `k`'s dofs follow those of patches `0..k`), in each patch its control
/// points in the shell's own order (eq. 4), in each control point
/// `u, v, w, α, β`; then the beam nodes and the rigid bodies' reference
/// nodes, each `u_x, u_y, u_z, θ_x, θ_y, θ_z`. One patch keeps exactly the
/// single-shell numbering.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DofMap {
    /// The first node of every patch, and the control-point count as the
    /// last entry (the first beam node).
    first_nodes: Vec<usize>,
    beam_nodes: usize,
    rigid_bodies: usize,
}

impl DofMap {
    /// The numbering of `patches`, in their order, and no beams.
    pub fn of_patches(patches: &[Patch]) -> Self {
        Self::of_model(patches, 0, 0)
    }

    /// The numbering of `patches` followed by `beam_nodes` beam nodes and
    /// the reference nodes of `rigid_bodies` rigid bodies.
    pub fn of_model(patches: &[Patch], beam_nodes: usize, rigid_bodies: usize) -> Self {
        let mut first_nodes = Vec::with_capacity(patches.len() + 1);
        let mut at = 0;
        first_nodes.push(0);
        for p in patches {
            at += p.shell.control_point_count();
            first_nodes.push(at);
        }
        Self {
            first_nodes,
            beam_nodes,
            rigid_bodies,
        }
    }

    pub fn dof_count(&self) -> usize {
        self.first_beam_dof() + DOFS_PER_BEAM_NODE * (self.beam_nodes + self.rigid_bodies)
    }

    pub fn node_count(&self) -> usize {
        self.control_point_count() + self.beam_nodes + self.rigid_bodies
    }

    /// The shell control points (nodes `0..` this).
    pub fn control_point_count(&self) -> usize {
        *self.first_nodes.last().expect("one entry past the last patch")
    }

    pub fn beam_node_count(&self) -> usize {
        self.beam_nodes
    }

    fn first_beam_dof(&self) -> usize {
        DOFS_PER_CONTROL_POINT * self.control_point_count()
    }

    /// The first global dof of patch `patch`.
    pub fn first_dof(&self, patch: usize) -> usize {
        DOFS_PER_CONTROL_POINT * self.first_nodes[patch]
    }

    /// The dof count of every node, in order (a pattern's block sizes).
    pub fn dofs_per_node(&self) -> Vec<usize> {
        let mut counts = vec![DOFS_PER_CONTROL_POINT; self.control_point_count()];
        counts.resize(self.node_count(), DOFS_PER_BEAM_NODE);
        counts
    }

    /// The global node of control point `control_point` of patch `patch`.
    pub fn node(&self, patch: usize, control_point: usize) -> usize {
        debug_assert!(self.first_nodes[patch] + control_point < self.first_nodes[patch + 1]);
        self.first_nodes[patch] + control_point
    }

    /// The global node of beam node `beam_node`.
    pub fn beam_node(&self, beam_node: usize) -> usize {
        debug_assert!(beam_node < self.beam_nodes);
        self.control_point_count() + beam_node
    }

    /// The global node of rigid body `body`'s reference node.
    pub fn rigid_node(&self, body: usize) -> usize {
        debug_assert!(body < self.rigid_bodies);
        self.control_point_count() + self.beam_nodes + body
    }

    /// The global node a dof belongs to.
    pub fn node_of(&self, dof: usize) -> usize {
        let beams = self.first_beam_dof();
        if dof < beams {
            dof / DOFS_PER_CONTROL_POINT
        } else {
            self.control_point_count() + (dof - beams) / DOFS_PER_BEAM_NODE
        }
    }

    /// The global dofs of node `node`.
    pub fn node_dofs(&self, node: usize) -> Range<usize> {
        let cps = self.control_point_count();
        if node < cps {
            DOFS_PER_CONTROL_POINT * node..DOFS_PER_CONTROL_POINT * (node + 1)
        } else {
            let first = self.first_beam_dof() + DOFS_PER_BEAM_NODE * (node - cps);
            first..first + DOFS_PER_BEAM_NODE
        }
    }

    /// Whether `node` is a shell control point (not a six-dof node).
    pub fn is_control_point(&self, node: usize) -> bool {
        node < self.control_point_count()
    }

    pub fn kind(&self, dof: usize) -> DofKind {
        let beams = self.first_beam_dof();
        if dof >= beams {
            return match (dof - beams) % DOFS_PER_BEAM_NODE {
                c @ 0..=2 => DofKind::Translation(c),
                c => DofKind::Rotation(c - 3),
            };
        }
        match dof % DOFS_PER_CONTROL_POINT {
            c @ 0..=2 => DofKind::Translation(c),
            c => DofKind::DirectorRotation(c - 3),
        }
    }

    /// Whether `dof` is a translation along global axis `axis`: the dofs a
    /// rigid translation of the ground along `axis` moves by one.
    pub fn is_translation(&self, dof: usize, axis: usize) -> bool {
        self.kind(dof) == DofKind::Translation(axis)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::material::OrthotropicMaterial;
    use crate::model::shell::Shell;

    fn patch(controls: [usize; 2]) -> Patch {
        let shell = Shell::rectangular_plate(4.0, 2.0, 0.2, [2, 2], controls).unwrap();
        Patch::new("p", shell, OrthotropicMaterial::isotropic(30e9, 0.2, 2500.0).unwrap()).unwrap()
    }

    #[test]
    fn patches_are_numbered_one_after_the_other_node_by_node() {
        let patches = [patch([4, 3]), patch([3, 3])];
        let map = DofMap::of_patches(&patches);
        assert_eq!(map.node_count(), 12 + 9);
        assert_eq!(
            map.dof_count(),
            patches.iter().map(|p| p.shell.dof_count()).sum::<usize>()
        );
        assert_eq!((map.first_dof(0), map.first_dof(1), map.dof_count()), (0, 60, 105));
        let node = map.node(1, 2);
        assert_eq!(node, 14);
        assert_eq!(map.node_dofs(node), 70..75);
        for dof in map.node_dofs(node) {
            assert_eq!(map.node_of(dof), node);
        }
        let kinds: Vec<DofKind> = map.node_dofs(node).map(|d| map.kind(d)).collect();
        assert_eq!(
            kinds,
            [
                DofKind::Translation(0),
                DofKind::Translation(1),
                DofKind::Translation(2),
                DofKind::DirectorRotation(0),
                DofKind::DirectorRotation(1),
            ]
        );
        assert!(map.is_translation(72, 2) && !map.is_translation(72, 1) && !map.is_translation(73, 0));
    }

    #[test]
    fn beam_nodes_follow_the_control_points_with_six_dofs_each() {
        let patches = [patch([4, 3])];
        let map = DofMap::of_model(&patches, 3, 1);
        assert_eq!(
            (map.control_point_count(), map.beam_node_count(), map.node_count()),
            (12, 3, 16)
        );
        assert_eq!(map.dof_count(), 60 + 18 + 6);
        assert_eq!(map.rigid_node(0), 15);
        assert_eq!(map.node_dofs(15), 78..84);
        let node = map.beam_node(1);
        assert_eq!(node, 13);
        assert!(!map.is_control_point(node) && map.is_control_point(11));
        assert_eq!(map.node_dofs(node), 66..72);
        for dof in map.node_dofs(node) {
            assert_eq!(map.node_of(dof), node);
        }
        assert_eq!(map.node_of(59), 11);
        let kinds: Vec<DofKind> = map.node_dofs(node).map(|d| map.kind(d)).collect();
        assert_eq!(
            kinds,
            [0, 1, 2]
                .map(DofKind::Translation)
                .into_iter()
                .chain([0, 1, 2].map(DofKind::Rotation))
                .collect::<Vec<_>>()
        );
        assert_eq!(map.dofs_per_node()[11..], [5, 6, 6, 6, 6]);
        assert!(map.is_translation(68, 2) && !map.is_translation(69, 0));
    }
}
