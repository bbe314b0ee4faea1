//! Support groups: which ground each support moves with.
//!
//! A bridge stands on several supports (two abutments, a bent) whose grounds
//! may move differently in an earthquake. Every spring field, bearing and
//! edge constraint belongs to one group; the ground of group `g` translates
//! rigidly by `u_g = (u_gx, u_gy, u_gz)`. A spring or bearing of the group acts
//! on the relative displacement `u − R u_g` (`R`: the rigid translation of
//! the deck's generalised dofs), a constrained edge of the group follows
//! `R u_g`, and so does a beam's held base
//! ([`crate::response::support_motion`] derives the motion). One
//! group is uniform excitation. [`RigidMotion`] is the one statement of
//! `R u_g` per support and ground input.

use crate::geometry::vec3::Vec3;
use crate::model::dofs::DofMap;
use crate::model::BridgeModel;
use thiserror::Error;

/// The group every support belongs to unless told otherwise.
pub const DEFAULT_GROUP: &str = "ground";

#[derive(Debug, Clone, PartialEq, Error)]
pub enum SupportError {
    #[error("support groups: {found} groups given for {expected} {what}")]
    Count {
        what: &'static str,
        found: usize,
        expected: usize,
    },
    #[error("support groups: {what} {index} names group {group}, but there are {count} groups")]
    UnknownGroup {
        what: &'static str,
        index: usize,
        group: usize,
        count: usize,
    },
    #[error("support groups: group names must be distinct and not empty (found {0:?})")]
    Name(String),
    #[error(
        "node {node} is held by the supports of two groups ({first:?} and {second:?}): it cannot follow two grounds"
    )]
    TwoGrounds { node: usize, first: String, second: String },
    #[error("support group {0:?} moves constrained patch edges: on a truncated model (the sparse path) only springs, bearings, line supports and beam bases may move with the ground; use [model.solver] modes = \"all\"")]
    TruncatedConstraint(String),
    #[error("support motion: the static solve failed: {0}")]
    Solve(String),
    #[error("ground input {index}: group {group} does not exist (there are {count}), or axis {axis} is not 0, 1 or 2")]
    Input {
        index: usize,
        group: usize,
        axis: usize,
        count: usize,
    },
}

/// A measured ground input: group `group`'s ground acceleration along global
/// axis `axis` (0 = x, 1 = y, 2 = z).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GroundInput {
    pub group: usize,
    pub axis: usize,
}

/// How the ground under one support (or one held node) moves when a
/// [`GroundInput`] moves by one: rigidly along the input's axis when the
/// support follows the input's group, not at all otherwise. Each support's
/// spring acts on `u − u_g` and each held node follows `u_g`, with `u_g` at
/// a dof given by [`Self::at`]; a ground rotation (rocking) would add its
/// lever arm here, and nowhere else.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RigidMotion {
    /// The axis it translates along, if it moves.
    axis: Option<usize>,
}

impl RigidMotion {
    /// The motion under `input` of the ground of group `group`.
    pub fn of_group(group: usize, input: &GroundInput) -> Self {
        Self {
            axis: (group == input.group).then_some(input.axis),
        }
    }

    /// Whether this ground moves at all.
    pub fn moves(&self) -> bool {
        self.axis.is_some()
    }

    /// `u_g` at `dof` (of `dofs`): one on the translations along the axis.
    pub fn at(&self, dofs: &DofMap, dof: usize) -> f64 {
        match self.axis {
            Some(axis) if dofs.is_translation(dof, axis) => 1.0,
            _ => 0.0,
        }
    }
}

/// The support group of every spring field, bearing and edge constraint of
/// a [`BridgeModel`], validated against it.
#[derive(Debug, Clone, PartialEq)]
pub struct SupportGroups {
    names: Vec<String>,
    /// Per support, in [`BridgeModel::supports`]' order (the
    /// assembled model's order of `∂K/∂κ` fields).
    of_springs: Vec<usize>,
    of_constraints: Vec<usize>,
    /// Per beam member, the group its held base follows.
    of_beam_bases: Vec<usize>,
}

impl SupportGroups {
    /// `of_springs`: a group per support, in [`BridgeModel::supports`]'
    /// order;
    /// `of_constraints`: a group per edge constraint.
    pub fn new(
        names: Vec<String>,
        of_springs: Vec<usize>,
        of_constraints: Vec<usize>,
        model: &BridgeModel,
    ) -> Result<Self, SupportError> {
        for (k, name) in names.iter().enumerate() {
            if name.is_empty() || names[..k].contains(name) {
                return Err(SupportError::Name(name.clone()));
            }
        }
        let springs = model.support_count();
        for (what, given, expected) in [
            ("spring fields, bearings and line supports", &of_springs, springs),
            ("edge constraints", &of_constraints, model.constraints.len()),
        ] {
            if given.len() != expected {
                return Err(SupportError::Count {
                    what,
                    found: given.len(),
                    expected,
                });
            }
            if let Some(index) = given.iter().position(|&g| g >= names.len()) {
                return Err(SupportError::UnknownGroup {
                    what,
                    index,
                    group: given[index],
                    count: names.len(),
                });
            }
        }
        Ok(Self {
            names,
            of_springs,
            of_constraints,
            of_beam_bases: vec![0; model.beams.members().len()],
        })
    }

    /// The same groups with `of_beam_bases`, a group per beam member (its
    /// base follows that group's ground; a free base's entry is unused).
    /// Until given, every base follows group 0.
    pub fn with_beam_bases(mut self, of_beam_bases: Vec<usize>, model: &BridgeModel) -> Result<Self, SupportError> {
        let what = "beam members";
        let expected = model.beams.members().len();
        if of_beam_bases.len() != expected {
            return Err(SupportError::Count {
                what,
                found: of_beam_bases.len(),
                expected,
            });
        }
        if let Some(index) = of_beam_bases.iter().position(|&g| g >= self.names.len()) {
            return Err(SupportError::UnknownGroup {
                what,
                index,
                group: of_beam_bases[index],
                count: self.names.len(),
            });
        }
        self.of_beam_bases = of_beam_bases;
        Ok(self)
    }

    /// Every support on one ground named [`DEFAULT_GROUP`].
    pub fn uniform(model: &BridgeModel) -> Self {
        Self {
            names: vec![DEFAULT_GROUP.to_string()],
            of_springs: vec![0; model.support_count()],
            of_constraints: vec![0; model.constraints.len()],
            of_beam_bases: vec![0; model.beams.members().len()],
        }
    }

    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// The group of spring field or bearing `k` (assembled order).
    pub fn of_spring(&self, k: usize) -> usize {
        self.of_springs[k]
    }

    /// The motion of support `k`'s ground (in [`BridgeModel::supports`]'
    /// order) under `input`.
    pub fn rigid_motion(&self, k: usize, input: &GroundInput) -> RigidMotion {
        RigidMotion::of_group(self.of_springs[k], input)
    }

    /// The group of edge constraint `k`.
    pub fn of_constraint(&self, k: usize) -> usize {
        self.of_constraints[k]
    }

    /// The group beam member `k`'s base follows.
    pub fn of_beam_base(&self, k: usize) -> usize {
        self.of_beam_bases[k]
    }
}

impl SupportGroups {
    /// Where each group holds `model` (the centroid of its bearings, of its
    /// line supports' control points and of its held beam bases; `None` for
    /// a group of spring fields or edge constraints only): the support a
    /// deck point lies nearest, for a "deck moves with its ground" baseline.
    pub fn anchors(&self, model: &BridgeModel) -> Vec<Option<Vec3>> {
        let mut points: Vec<Vec<Vec3>> = vec![Vec::new(); self.names.len()];
        for (j, support) in model.supports().enumerate() {
            if let Some(held) = support.holds(model) {
                points[self.of_springs[j]].push(centroid(&held));
            }
        }
        for (node, member) in model.beams.base_nodes() {
            points[self.of_beam_bases[member]].push(model.beams.position(node));
        }
        points
            .into_iter()
            .map(|p| (!p.is_empty()).then(|| centroid(&p)))
            .collect()
    }
}

/// The mean of `points` (not empty).
fn centroid(points: &[Vec3]) -> Vec3 {
    let n = points.len() as f64;
    [0, 1, 2].map(|d| points.iter().map(|x| x[d]).sum::<f64>() / n)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::material::OrthotropicMaterial;
    use crate::model::shell::Shell;
    use crate::model::Patch;

    #[test]
    fn a_ground_moves_the_translations_along_its_input_of_its_own_group_only() {
        let shell = Shell::rectangular_plate(4.0, 2.0, 0.2, [2, 2], [3, 3]).unwrap();
        let patch = Patch::new("p", shell, OrthotropicMaterial::isotropic(30e9, 0.2, 2500.0).unwrap()).unwrap();
        // Nine 5-dof control points, then one 6-dof beam node.
        let dofs = DofMap::of_model(&[patch], 1, 0);
        let input = GroundInput { group: 1, axis: 2 };
        let own = RigidMotion::of_group(1, &input);
        assert!(own.moves());
        let moved: Vec<f64> = (0..dofs.dof_count()).map(|d| own.at(&dofs, d)).collect();
        for (dof, &u) in moved.iter().enumerate() {
            assert_eq!(u, f64::from(u8::from(dofs.is_translation(dof, 2))), "dof {dof}");
        }
        // One per node: its z translation, on a control point and on the beam node.
        assert_eq!(moved.iter().sum::<f64>(), 10.0);
        assert_eq!(&moved[45..51], &[0.0, 0.0, 1.0, 0.0, 0.0, 0.0]);
        let other = RigidMotion::of_group(0, &input);
        assert!(!other.moves());
        assert!((0..dofs.dof_count()).all(|d| other.at(&dofs, d) == 0.0));
    }
}
