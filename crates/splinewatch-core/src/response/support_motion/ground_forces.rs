//! The ground's pull on the model: the nodes a support holds and the
//! ground each follows (`ℓ`), and the forces `f = ΔK_g R_d − K ℓ` of every
//! ground input, on the dense path from the assembled stiffness, on the
//! truncated one from the springs' blocks and the columns' elements.

use super::GroundInput;
use crate::model::dofs::DofMap;
use crate::model::shell::Assembly;
use crate::model::supports::{RigidMotion, SupportError, SupportGroups};
use crate::model::BridgeModel;
use crate::response::frf::FrfModel;
use faer::Mat;

/// The ground forces `f = ΔK_g R_d − K ℓ` of every input on a truncated
/// model (sparse, full dofs) at `(kappa, theta)`. `K ℓ` is taken where the
/// sparse model keeps no unreduced stiffness: a held beam base couples to
/// its neighbours through its beam elements only, whose matrices are
/// assembled again here for the lifted columns, plus `(θ_k − 1) ∂K/∂θ_k ℓ`
/// of every multiplier that reaches them (a column's own); a constrained
/// patch edge would need the shell's (and its stiffness fields'), so a
/// moving group with one is refused.
pub(super) fn truncated_forces(
    frf: &FrfModel,
    model: &BridgeModel,
    groups: &SupportGroups,
    (kappa, theta): (&[Vec<f64>], &[Vec<f64>]),
    inputs: &[GroundInput],
    lifts: &GroundLifts,
) -> Result<Vec<Vec<(usize, f64)>>, SupportError> {
    let (sparse, _) = frf.sparse().expect("a model is dense or truncated");
    if let Some(input) = inputs.iter().find(|i| lifts.moves_edges(i.group)) {
        return Err(SupportError::TruncatedConstraint(groups.names()[input.group].clone()));
    }
    let n = sparse.dof_count();
    inputs
        .iter()
        .map(|input| {
            let mut force = vec![0.0; n];
            for (field, (blocks, coefficients)) in frf.spring_blocks().iter().zip(kappa).enumerate() {
                let ground = groups.rigid_motion(field, input);
                if !ground.moves() {
                    continue;
                }
                for (b, &k) in blocks.iter().zip(coefficients) {
                    for (a, &ra) in b.dofs.iter().enumerate() {
                        for (e, &re) in b.dofs.iter().enumerate() {
                            let moved = ground.at(&lifts.dofs, re);
                            if moved != 0.0 {
                                force[ra] += k * b.values[(a, e)] * moved;
                            }
                        }
                    }
                }
            }
            if lifts.moves(input.group) {
                let lift = lifts.lift(input);
                let mut columns = LiftedColumns {
                    lift: &lift,
                    force: &mut force,
                };
                // The mass goes to a target that lifts nothing.
                let nothing = vec![0.0; n];
                let mut unused = LiftedColumns {
                    lift: &nothing,
                    force: &mut [],
                };
                model
                    .beams
                    .add_matrices(&mut columns, &mut unused, &lifts.dofs)
                    .map_err(|e| SupportError::Solve(e.to_string()))?;
                let lift_column = Mat::from_fn(n, 1, |d, _| lift[d]);
                for (k, &t) in theta.iter().flatten().enumerate().filter(|&(_, &t)| t != 1.0) {
                    let product = frf.field_times(k, &lift_column);
                    for (d, f) in force.iter_mut().enumerate() {
                        *f -= (t - 1.0) * product[(d, 0)];
                    }
                }
            }
            Ok(force.into_iter().enumerate().filter(|(_, v)| *v != 0.0).collect())
        })
        .collect()
}

/// An assembly target that keeps `force −= K ℓ` only (`K` added element by
/// element): the lifted columns of the matrix, never the matrix.
struct LiftedColumns<'a> {
    lift: &'a [f64],
    force: &'a mut [f64],
}

impl Assembly for LiftedColumns<'_> {
    fn add_local(&mut self, local: &Mat<f64>, dofs: &[usize]) -> Result<(), crate::model::sparse::SparseError> {
        for (b, &column) in dofs.iter().enumerate() {
            let l = self.lift[column];
            if l == 0.0 {
                continue;
            }
            for (a, &row) in dofs.iter().enumerate() {
                self.force[row] -= local[(a, b)] * l;
            }
        }
        Ok(())
    }
}

/// The nodes on constrained edges and at held beam bases, and the ground
/// each follows (`ℓ`).
#[derive(Debug, Clone)]
pub(super) struct GroundLifts {
    pub(super) dofs: DofMap,
    /// Per node, the group whose ground it follows, if a support holds it.
    owner: Vec<Option<usize>>,
}

impl GroundLifts {
    /// The held nodes of `model`; a node held by two groups' supports is
    /// refused (it cannot follow two grounds).
    pub(super) fn new(model: &BridgeModel, groups: &SupportGroups) -> Result<Self, SupportError> {
        let dofs = model.dof_map();
        let mut owner: Vec<Option<usize>> = vec![None; dofs.node_count()];
        let mut claim = |node: usize, g: usize| match owner[node] {
            Some(other) if other != g => Err(SupportError::TwoGrounds {
                node,
                first: groups.names()[other].clone(),
                second: groups.names()[g].clone(),
            }),
            _ => {
                owner[node] = Some(g);
                Ok(())
            }
        };
        for (k, c) in model.constraints.iter().enumerate() {
            for cp in c.control_points(&model.patches[c.patch].shell) {
                claim(dofs.node(c.patch, cp), groups.of_constraint(k))?;
            }
        }
        for (node, member) in model.beams.base_nodes() {
            claim(dofs.beam_node(node), groups.of_beam_base(member))?;
        }
        Ok(Self { dofs, owner })
    }

    /// Whether group `group` has constrained nodes (its ground lifts some).
    pub(super) fn moves(&self, group: usize) -> bool {
        self.owner.contains(&Some(group))
    }

    /// Whether group `group` holds control points of a constrained edge.
    fn moves_edges(&self, group: usize) -> bool {
        (0..self.owner.len()).any(|node| self.owner[node] == Some(group) && self.dofs.is_control_point(node))
    }

    /// `ℓ` of `input`: 1 on the translations along its axis of its group's
    /// constrained nodes.
    pub(super) fn lift(&self, input: &GroundInput) -> Vec<f64> {
        (0..self.dofs.dof_count())
            .map(|dof| match self.owner[self.dofs.node_of(dof)] {
                Some(group) => RigidMotion::of_group(group, input).at(&self.dofs, dof),
                None => 0.0,
            })
            .collect()
    }
}

/// `f = ΔK_g R_d − K ℓ` at the coefficients `kappa`, `theta` (full dofs).
pub(super) fn ground_force(
    assembled: &crate::solvers::dense_model::AssembledModel,
    groups: &SupportGroups,
    (kappa, theta): (&[Vec<f64>], &[Vec<f64>]),
    input: &GroundInput,
    lift: &[f64],
    dofs: &DofMap,
) -> Vec<f64> {
    let n = lift.len();
    let lifted: Vec<usize> = (0..n).filter(|&d| lift[d] != 0.0).collect();
    let mut force = vec![0.0; n];
    let mut k_lift = |matrix: &Mat<f64>, scale: f64| {
        for (r, f) in force.iter_mut().enumerate() {
            *f -= scale * lifted.iter().map(|&d| matrix[(r, d)] * lift[d]).sum::<f64>();
        }
    };
    k_lift(&assembled.free_stiffness, 1.0);
    for (matrices, coefficients) in assembled.field_matrices.iter().zip(theta) {
        for (m, &t) in matrices.iter().zip(coefficients) {
            k_lift(m, t - 1.0);
        }
    }
    for (field, (blocks, coefficients)) in assembled.spring_blocks.iter().zip(kappa).enumerate() {
        let ground = groups.rigid_motion(field, input);
        for (b, &k) in blocks.iter().zip(coefficients) {
            for (a, &ra) in b.dofs.iter().enumerate() {
                for (c, &rc) in b.dofs.iter().enumerate() {
                    force[ra] += k * b.values[(a, c)] * (ground.at(dofs, rc) - lift[rc]);
                }
            }
        }
    }
    force
}
