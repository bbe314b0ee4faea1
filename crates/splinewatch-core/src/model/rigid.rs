//! Rigid bodies: a bent cap or diaphragm monolithic with the deck, a
//! column's top held at the deck's mid-surface by a rigid offset.
//!
//! A body has a reference node of six dofs (`u, θ` about the global axes)
//! at the centroid of what it holds; deck edges and beam nodes follow it
//! exactly, eliminated from the dofs (`δ = T q`,
//! [`crate::model::constraints::DofReduction::tie`]): a point at `x` moves
//! by `u + θ × (x − x_ref)`. A shell control point's translations follow
//! at its mid-surface point `P` (the basis sums to one and reproduces
//! positions, so the whole edge curve moves rigidly) and its director
//! rotations are `α = θ·v1`, `β = θ·v2` (eq. 3: the director `v3` turns by
//! `θ × v3 = −α v2 + β v1`); a beam node's rotations are `θ`.

use thiserror::Error;

use crate::geometry::vec3::{cross, sub, Vec3};
use crate::model::constraints::Edge;
use crate::model::dofs::DofMap;
use crate::model::members::BeamNet;
use crate::model::patch::Patch;

#[derive(Debug, Clone, PartialEq, Error)]
pub enum RigidError {
    #[error("a rigid body's name must not be empty")]
    EmptyName,
    #[error("rigid body {0:?} holds nothing: give deck edges or beam ends")]
    Empty(String),
    #[error("rigid body {name:?}: patch {patch} does not exist (the model has {count})")]
    UnknownPatch { name: String, patch: usize, count: usize },
    #[error("rigid body {name:?}: beam node {node} does not exist (the beams have {count})")]
    UnknownBeamNode { name: String, node: usize, count: usize },
    #[error("rigid body {name:?}: node {node} is already held by a support or by another rigid body")]
    Conflict { name: String, node: usize },
}

/// A named rigid body and what follows it.
#[derive(Debug, Clone, PartialEq)]
pub struct RigidBody {
    name: String,
    /// Deck edges, as (patch, edge).
    edges: Vec<(usize, Edge)>,
    /// Beam nodes, in the beams' own numbering ([`BeamNet`]).
    beam_nodes: Vec<usize>,
}

/// A node a body holds.
#[derive(Clone, Copy)]
struct HeldNode {
    /// Global node.
    node: usize,
    position: Vec3,
    /// A control point's directors `v1, v2` (none for a beam node).
    directors: Option<(Vec3, Vec3)>,
}

impl RigidBody {
    pub fn new(name: impl Into<String>, edges: Vec<(usize, Edge)>, beam_nodes: Vec<usize>) -> Result<Self, RigidError> {
        let name = name.into();
        if name.is_empty() {
            return Err(RigidError::EmptyName);
        }
        if edges.is_empty() && beam_nodes.is_empty() {
            return Err(RigidError::Empty(name));
        }
        Ok(Self {
            name,
            edges,
            beam_nodes,
        })
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    /// How many deck edges and beam nodes it holds, as given.
    pub fn counts(&self) -> (usize, usize) {
        (self.edges.len(), self.beam_nodes.len())
    }

    /// The held nodes, each once, in order: the edges' control points,
    /// then the beam nodes.
    fn held(&self, patches: &[Patch], beams: &BeamNet, dofs: &DofMap) -> Result<Vec<HeldNode>, RigidError> {
        let mut nodes = Vec::new();
        for &(patch, edge) in &self.edges {
            let shell = &patches
                .get(patch)
                .ok_or_else(|| RigidError::UnknownPatch {
                    name: self.name.clone(),
                    patch,
                    count: patches.len(),
                })?
                .shell;
            for cp in edge.control_points(shell) {
                let frame = shell.frames()[cp];
                nodes.push(HeldNode {
                    node: dofs.node(patch, cp),
                    position: shell.surface().points()[cp],
                    directors: Some((frame.v1, frame.v2)),
                });
            }
        }
        for &b in &self.beam_nodes {
            if b >= beams.node_count() {
                return Err(RigidError::UnknownBeamNode {
                    name: self.name.clone(),
                    node: b,
                    count: beams.node_count(),
                });
            }
            nodes.push(HeldNode {
                node: dofs.beam_node(b),
                position: beams.position(b),
                directors: None,
            });
        }
        let mut seen = std::collections::BTreeSet::new();
        nodes.retain(|n| seen.insert(n.node));
        Ok(nodes)
    }

    /// The centroid of the held nodes: the reference node's position.
    pub fn reference(&self, patches: &[Patch], beams: &BeamNet, dofs: &DofMap) -> Result<Vec3, RigidError> {
        Ok(centroid(&self.held(patches, beams, dofs)?))
    }

    /// The held nodes' global dofs and, per component `c` of the reference
    /// node (`0..3` translations, `3..6` rotations), the held dofs' motion
    /// under its unit value: the entries [`DofReduction::tie`] adds.
    ///
    /// [`DofReduction::tie`]: crate::model::constraints::DofReduction::tie
    #[allow(clippy::type_complexity)]
    pub fn ties(
        &self,
        patches: &[Patch],
        beams: &BeamNet,
        dofs: &DofMap,
    ) -> Result<(Vec<usize>, [Vec<(usize, f64)>; 6]), RigidError> {
        let held = self.held(patches, beams, dofs)?;
        let reference = centroid(&held);
        let mut slaves = Vec::new();
        let mut extra: [Vec<(usize, f64)>; 6] = Default::default();
        for n in &held {
            let own = dofs.node_dofs(n.node);
            slaves.extend(own.clone());
            let first = own.start;
            let r = sub(n.position, reference);
            for axis in 0..3 {
                extra[axis].push((first + axis, 1.0));
                let mut e = [0.0; 3];
                e[axis] = 1.0;
                let moved = cross(e, r);
                extra[3 + axis].extend((0..3).map(|d| (first + d, moved[d])));
                match n.directors {
                    Some((v1, v2)) => extra[3 + axis].extend([(first + 3, v1[axis]), (first + 4, v2[axis])]),
                    None => extra[3 + axis].push((first + 3 + axis, 1.0)),
                }
            }
        }
        for column in &mut extra {
            column.retain(|&(_, w)| w != 0.0);
        }
        Ok((slaves, extra))
    }

    /// The held nodes (global numbering).
    pub fn held_nodes(&self, patches: &[Patch], beams: &BeamNet, dofs: &DofMap) -> Result<Vec<usize>, RigidError> {
        Ok(self.held(patches, beams, dofs)?.iter().map(|n| n.node).collect())
    }
}

/// The centroid of the held nodes (a body holds at least one).
fn centroid(held: &[HeldNode]) -> Vec3 {
    let count = held.len() as f64;
    std::array::from_fn(|d| held.iter().map(|n| n.position[d]).sum::<f64>() / count)
}
