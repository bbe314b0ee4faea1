//! Beam members (columns, piers, pile extensions, frame girders): each a
//! straight line from its start to its end cut into equal Timoshenko
//! elements ([`crate::model::beam`]), its start held as its base says.
//!
//! Members meet where their nodes coincide: nodes closer than a tolerance
//! are one node, so a portal frame's corner or a column's top shared by two
//! members is a rigid connection, as in OpenSees where elements share a
//! node. The nodes are numbered in the order members first reach them and
//! follow the shell's control points in the model's numbering
//! ([`crate::model::dofs::DofMap`]).

use faer::Mat;
use thiserror::Error;

use crate::geometry::vec3::{axpy, cross, dot, norm, sub, Vec3};
use crate::model::beam::{BeamElement, BeamError, BeamMaterial, Section, StiffnessPart, DOFS_PER_BEAM_NODE};
use crate::model::dofs::DofMap;
use crate::model::shell::Assembly;
use crate::model::sparse::SparseError;

#[derive(Debug, Clone, PartialEq, Error)]
pub enum MemberError {
    #[error("beam {name:?}: {source}")]
    Beam { name: String, source: BeamError },
    #[error("beam {name:?}: at least one element, got 0")]
    NoElements { name: String },
    #[error("a beam's name must not be empty")]
    EmptyName,
}

/// How a member's start is held.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BeamBase {
    /// Not held: the start is free or meets another member.
    Free,
    /// Every translation and rotation held (a column built into its footing).
    Fixed,
    /// The translations held, the rotations free.
    Pinned,
}

impl BeamBase {
    /// Whether the base holds component `c` (`0..3` translations, `3..6`
    /// rotations) of its node.
    pub fn holds(self, c: usize) -> bool {
        match self {
            Self::Free => false,
            Self::Fixed => true,
            Self::Pinned => c < 3,
        }
    }
}

/// One straight member, validated.
#[derive(Debug, Clone, PartialEq)]
pub struct BeamMember {
    name: String,
    start: Vec3,
    end: Vec3,
    orientation: Vec3,
    section: Section,
    material: BeamMaterial,
    elements: usize,
    base: BeamBase,
}

impl BeamMember {
    /// The member from `start` to `end` in `elements` equal elements, its
    /// section's `y` axis along `orientation` ([`BeamElement::new`]).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        name: impl Into<String>,
        (start, end): (Vec3, Vec3),
        orientation: Vec3,
        section: Section,
        material: BeamMaterial,
        elements: usize,
        base: BeamBase,
    ) -> Result<Self, MemberError> {
        let name = name.into();
        if name.is_empty() {
            return Err(MemberError::EmptyName);
        }
        if elements == 0 {
            return Err(MemberError::NoElements { name });
        }
        // The whole member's element validates length and orientation.
        if let Err(source) = BeamElement::new(start, end, orientation, section, material) {
            return Err(MemberError::Beam { name, source });
        }
        Ok(Self {
            name,
            start,
            end,
            orientation,
            section,
            material,
            elements,
            base,
        })
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    pub fn start(&self) -> Vec3 {
        self.start
    }

    pub fn end(&self) -> Vec3 {
        self.end
    }

    pub fn length(&self) -> f64 {
        norm(sub(self.end, self.start))
    }

    pub fn base(&self) -> BeamBase {
        self.base
    }

    pub fn section(&self) -> Section {
        self.section
    }

    /// The same member with its start held as `base` says.
    pub fn with_base(mut self, base: BeamBase) -> Self {
        self.base = base;
        self
    }

    pub fn elements(&self) -> usize {
        self.elements
    }

    /// Point `i` of `0..=elements` along the member.
    fn point(&self, i: usize) -> Vec3 {
        self.point_at(i as f64 / self.elements as f64)
    }

    /// The point a fraction `t` of the length from the start.
    fn point_at(&self, t: f64) -> Vec3 {
        std::array::from_fn(|d| self.start[d] + t * (self.end[d] - self.start[d]))
    }
}

/// The members, their nodes and elements: coinciding nodes merged.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct BeamNet {
    members: Vec<BeamMember>,
    positions: Vec<Vec3>,
    /// Per member, its nodes from start to end.
    member_nodes: Vec<Vec<usize>>,
    /// Per element, its two nodes and the element.
    elements: Vec<(usize, usize, BeamElement)>,
    /// Per element, the member it belongs to.
    element_members: Vec<usize>,
    /// Per node, the components its members' bases hold.
    held: Vec<[bool; DOFS_PER_BEAM_NODE]>,
}

impl BeamNet {
    /// The net of `members`, nodes closer than `tolerance` (m) merged.
    pub fn new(members: Vec<BeamMember>, tolerance: f64) -> Result<Self, MemberError> {
        let mut net = Self {
            members: Vec::new(),
            positions: Vec::new(),
            member_nodes: Vec::with_capacity(members.len()),
            elements: Vec::new(),
            element_members: Vec::new(),
            held: Vec::new(),
        };
        for (k, m) in members.iter().enumerate() {
            let nodes: Vec<usize> = (0..=m.elements).map(|i| net.node_at(m.point(i), tolerance)).collect();
            for (c, held) in net.held[nodes[0]].iter_mut().enumerate() {
                *held |= m.base.holds(c);
            }
            for (i, pair) in nodes.windows(2).enumerate() {
                let element = BeamElement::new(m.point(i), m.point(i + 1), m.orientation, m.section, m.material)
                    .map_err(|source| MemberError::Beam {
                        name: m.name.clone(),
                        source,
                    })?;
                net.elements.push((pair[0], pair[1], element));
                net.element_members.push(k);
            }
            net.member_nodes.push(nodes);
        }
        net.members = members;
        Ok(net)
    }

    /// The node at `point`: an existing one within `tolerance`, or a new one.
    fn node_at(&mut self, point: Vec3, tolerance: f64) -> usize {
        if let Some(node) = self.positions.iter().position(|&p| norm(sub(p, point)) <= tolerance) {
            return node;
        }
        self.positions.push(point);
        self.held.push([false; DOFS_PER_BEAM_NODE]);
        self.positions.len() - 1
    }

    pub fn node_count(&self) -> usize {
        self.positions.len()
    }

    pub fn members(&self) -> &[BeamMember] {
        &self.members
    }

    pub fn is_empty(&self) -> bool {
        self.members.is_empty()
    }

    pub fn position(&self, node: usize) -> Vec3 {
        self.positions[node]
    }

    /// Member `member`'s nodes from its start to its end.
    pub fn member_nodes(&self, member: usize) -> &[usize] {
        &self.member_nodes[member]
    }

    /// Per element, its two beam nodes (the net's numbering).
    pub fn element_nodes(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        self.elements.iter().map(|&(a, b, _)| (a, b))
    }

    /// Whether component `c` of beam node `node` is held by a base.
    pub fn is_held(&self, node: usize, c: usize) -> bool {
        self.held[node][c]
    }

    /// Every element's global dofs in `dofs`' numbering: its start node's
    /// six, then its end node's.
    fn element_dofs(&self, (a, b): (usize, usize), dofs: &DofMap) -> Vec<usize> {
        dofs.node_dofs(dofs.beam_node(a))
            .chain(dofs.node_dofs(dofs.beam_node(b)))
            .collect()
    }

    /// Adds every element's stiffness to `stiffness` and consistent mass to
    /// `mass` on the global dofs of `dofs`.
    pub fn add_matrices<A: Assembly>(&self, stiffness: &mut A, mass: &mut A, dofs: &DofMap) -> Result<(), SparseError> {
        for &(a, b, ref element) in &self.elements {
            let at = self.element_dofs((a, b), dofs);
            stiffness.add_local(&element.stiffness(), &at)?;
            mass.add_local(&element.mass(), &at)?;
        }
        Ok(())
    }

    /// Adds part `part` of member `member`'s stiffness to `stiffness` on
    /// the global dofs of `dofs` (nothing for a member that does not exist).
    pub fn add_member_stiffness<A: Assembly>(
        &self,
        member: usize,
        part: StiffnessPart,
        stiffness: &mut A,
        dofs: &DofMap,
    ) -> Result<(), SparseError> {
        for (&(a, b, ref element), _) in self
            .elements
            .iter()
            .zip(&self.element_members)
            .filter(|(_, &m)| m == member)
        {
            stiffness.add_local(&element.stiffness_part(part), &self.element_dofs((a, b), dofs))?;
        }
        Ok(())
    }

    /// The point of member `member`'s axis nearest `at` (m).
    pub fn nearest_on_axis(&self, member: usize, at: Vec3) -> Option<Vec3> {
        let m = self.members.get(member)?;
        let t = (dot(sub(at, m.start), sub(m.end, m.start)) / m.length().powi(2)).clamp(0.0, 1.0);
        Some(m.point_at(t))
    }

    /// The row of a sensor at `at` (m) along `direction` (unit) on member
    /// `member`: the member's axis point nearest `at` moves by its element's
    /// interpolation ([`BeamElement::motion_rows`]) and `at` follows it
    /// rigidly, `u + θ × r` (`r` from the axis point to `at`: a sensor on
    /// the column's face, on a bracket or just past an end); `None` when
    /// the member does not exist.
    pub fn sensor_row(&self, member: usize, at: Vec3, direction: Vec3, dofs: &DofMap) -> Option<Vec<(usize, f64)>> {
        let m = self.members.get(member)?;
        let along = dot(sub(at, m.start), sub(m.end, m.start)) / m.length();
        let s = (along / m.length()).clamp(0.0, 1.0) * m.elements as f64;
        let k = (s.floor() as usize).min(m.elements - 1);
        let x = s - k as f64;
        let element = self
            .elements
            .iter()
            .zip(&self.element_members)
            .filter(|&(_, &owner)| owner == member)
            .nth(k)
            .map(|(e, _)| e)?;
        let (a, b, ref beam) = *element;
        let on_axis = axpy(beam.start(), x * beam.length(), beam.axes()[0]);
        let moment_arm = cross(sub(at, on_axis), direction);
        let rows = beam.motion_rows(x);
        let row = self
            .element_dofs((a, b), dofs)
            .into_iter()
            .enumerate()
            .map(|(c, dof)| {
                let value = (0..3)
                    .map(|g| direction[g] * rows[g][c] + moment_arm[g] * rows[3 + g][c])
                    .sum::<f64>();
                (dof, value)
            })
            .filter(|&(_, v)| v != 0.0)
            .collect();
        Some(row)
    }

    /// The held dofs, in `dofs`' numbering.
    pub fn held_dofs(&self, dofs: &DofMap) -> Vec<usize> {
        (0..self.node_count())
            .flat_map(|node| {
                dofs.node_dofs(dofs.beam_node(node))
                    .enumerate()
                    .filter(move |&(c, _)| self.held[node][c])
                    .map(|(_, d)| d)
            })
            .collect()
    }

    /// The nodes some base holds, with the member whose base it is (the
    /// first such member when several meet there).
    pub fn base_nodes(&self) -> Vec<(usize, usize)> {
        let mut out: Vec<(usize, usize)> = Vec::new();
        for (k, m) in self.members.iter().enumerate() {
            let node = self.member_nodes[k][0];
            if m.base != BeamBase::Free && !out.iter().any(|&(n, _)| n == node) {
                out.push((node, k));
            }
        }
        out
    }

    /// `K` and `M` of the net alone (`6 × nodes` square), for checks.
    pub fn matrices(&self) -> (Mat<f64>, Mat<f64>) {
        let n = DOFS_PER_BEAM_NODE * self.node_count();
        let dofs = DofMap::of_model(&[], self.node_count(), 0);
        let (mut k, mut m) = (Mat::zeros(n, n), Mat::zeros(n, n));
        self.add_matrices(&mut k, &mut m, &dofs)
            .expect("a dense matrix takes every entry");
        (k, m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn member(name: &str, start: Vec3, end: Vec3, elements: usize, base: BeamBase) -> BeamMember {
        let material = BeamMaterial::isotropic(30e9, 0.2, 2500.0).unwrap();
        let section = Section::circle(1.0, 0.2).unwrap();
        BeamMember::new(name, (start, end), [0.0, 1.0, 0.0], section, material, elements, base).unwrap()
    }

    /// A portal frame: two columns and a girder share the corner nodes.
    #[test]
    fn members_share_the_nodes_where_they_meet() {
        let members = vec![
            member("left", [0.0; 3], [0.0, 0.0, 5.0], 4, BeamBase::Fixed),
            member("right", [8.0, 0.0, 0.0], [8.0, 0.0, 5.0], 4, BeamBase::Pinned),
            member("girder", [0.0, 0.0, 5.0], [8.0, 0.0, 5.0], 6, BeamBase::Free),
        ];
        let net = BeamNet::new(members, 1e-3).unwrap();
        assert_eq!(net.node_count(), 5 + 5 + 5);
        assert_eq!(net.member_nodes(2)[0], net.member_nodes(0)[4]);
        assert_eq!(net.member_nodes(2)[6], net.member_nodes(1)[4]);
        assert_eq!(net.element_nodes().count(), 14);
        let dofs = DofMap::of_model(&[], net.node_count(), 0);
        let right = net.member_nodes(1)[0];
        assert_eq!(
            net.held_dofs(&dofs),
            (0..6).chain((0..3).map(|c| 6 * right + c)).collect::<Vec<_>>()
        );
        assert_eq!(net.base_nodes(), [(0, 0), (right, 1)]);
        // A net's stiffness is symmetric and its mass sums to the members'.
        let (k, m) = net.matrices();
        assert!((&k - k.transpose()).norm_max() <= 1e-9 * k.norm_max());
        let total: f64 = (0..net.node_count())
            .flat_map(|a| (0..net.node_count()).map(move |b| (a, b)))
            .map(|(a, b)| m[(6 * a, 6 * b)])
            .sum();
        let area = std::f64::consts::PI / 4.0;
        assert!((total - 2500.0 * area * 18.0).abs() <= 1e-9 * total);
    }

    #[test]
    fn bad_members_are_refused_by_name() {
        let material = BeamMaterial::isotropic(30e9, 0.2, 2500.0).unwrap();
        let section = Section::circle(1.0, 0.2).unwrap();
        let make = |end: Vec3, elements: usize| {
            BeamMember::new(
                "pier",
                ([1.0; 3], end),
                [0.0, 1.0, 0.0],
                section,
                material,
                elements,
                BeamBase::Fixed,
            )
        };
        assert!(matches!(
            make([1.0; 3], 4),
            Err(MemberError::Beam { ref name, source: BeamError::ZeroLength(_) }) if name == "pier"
        ));
        assert!(matches!(make([1.0, 1.0, 3.0], 0), Err(MemberError::NoElements { .. })));
        assert!(matches!(
            make([1.0, 3.0, 1.0], 2),
            Err(MemberError::Beam {
                source: BeamError::Orientation { .. },
                ..
            })
        ));
    }
}
