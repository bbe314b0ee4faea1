//! The generalised dofs of a model: its nodes in order, patch by patch,
//! each node's components numbered together.
//!
//! A shell control point carries five components (eq. 3): the translations
//! `u, v, w` of its reference point along the global axes and the rotations
//! `α, β` of its director. The map is the one place that knows this layout:
//! a ground's rigid translation, a support's lifted dofs or a patch's first
//! dof are asked of it, not computed from the count per node.

use std::ops::Range;

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
}

/// The numbering of a model's generalised dofs: patch after patch (patch
/// `k`'s dofs follow those of patches `0..k`), in each patch its control
/// points in the shell's own order (eq. 4), in each control point
/// `u, v, w, α, β`. One patch keeps exactly the single-shell numbering.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DofMap {
    /// The first node of every patch, and the node count as the last entry.
    first_nodes: Vec<usize>,
}

impl DofMap {
    /// The numbering of `patches`, in their order.
    pub fn of_patches(patches: &[Patch]) -> Self {
        let mut first_nodes = Vec::with_capacity(patches.len() + 1);
        let mut at = 0;
        first_nodes.push(0);
        for p in patches {
            at += p.shell.control_point_count();
            first_nodes.push(at);
        }
        Self { first_nodes }
    }

    pub fn dof_count(&self) -> usize {
        DOFS_PER_CONTROL_POINT * self.node_count()
    }

    pub fn node_count(&self) -> usize {
        *self.first_nodes.last().expect("one entry past the last patch")
    }

    /// The first global dof of patch `patch`.
    pub fn first_dof(&self, patch: usize) -> usize {
        DOFS_PER_CONTROL_POINT * self.first_nodes[patch]
    }

    /// The dof count of every node, in order (a pattern's block sizes).
    pub fn dofs_per_node(&self) -> Vec<usize> {
        vec![DOFS_PER_CONTROL_POINT; self.node_count()]
    }

    /// The global node of control point `control_point` of patch `patch`.
    pub fn node(&self, patch: usize, control_point: usize) -> usize {
        debug_assert!(self.first_nodes[patch] + control_point < self.first_nodes[patch + 1]);
        self.first_nodes[patch] + control_point
    }

    /// The global node a dof belongs to.
    pub fn node_of(&self, dof: usize) -> usize {
        dof / DOFS_PER_CONTROL_POINT
    }

    /// The global dofs of node `node`.
    pub fn node_dofs(&self, node: usize) -> Range<usize> {
        DOFS_PER_CONTROL_POINT * node..DOFS_PER_CONTROL_POINT * (node + 1)
    }

    pub fn kind(&self, dof: usize) -> DofKind {
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
}
