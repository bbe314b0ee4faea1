//! The complete model at real scale (10⁴–10⁵ dofs): eq. (23) on the sparse
//! control-net pattern, reduced to the free coordinates, and its modes below
//! a cut-off by shift-invert Lanczos ([`crate::solvers::partial_eigen`]).
//!
//! `K(κ, θ) = K_f + Σ (θ_k − 1) ∂K/∂θ_k + Σ κ_j ∂K/∂κ_j` is a sum of value
//! arrays on one pattern, so a parameter change costs a weighted sum and a
//! numeric re-factorisation, never a re-assembly or a new symbolic analysis.
//! [`crate::solvers::dense_model::AssembledModel`] stays the dense reference for small
//! models and the tests.

mod blocks;

use crate::model::constraints::DofReduction;
use crate::model::dofs::DofMap;
use crate::model::patch::Patch;
use crate::model::shell::{self, Frame, Offset};
use crate::model::sparse::{NonZeros, Pattern, SparseAccumulator, SparseError, SparseSymmetric};
use crate::model::springs::LowRankBlock;
use crate::model::BridgeModel;
use crate::solvers::dense_model::ModelError;
use crate::solvers::modal::Modes;
use crate::solvers::partial_eigen::{PartialSettings, Responses};
use blocks::{decoupled_blocks, Block};
use std::collections::BTreeMap;
use std::f64::consts::PI;
use std::sync::Arc;

/// A derivative matrix `∂K/∂p` on the reduced pattern: its non-zero entries
/// only (a spring coefficient reaches a strip of the deck).
#[derive(Debug, Clone, PartialEq)]
pub struct SparseTerm {
    positions: Vec<usize>,
    values: Vec<f64>,
}

impl SparseTerm {
    fn from_entries(entries: BTreeMap<usize, f64>) -> Self {
        let (positions, values) = entries.into_iter().filter(|(_, v)| *v != 0.0).unzip();
        Self { positions, values }
    }

    fn from_matrix(m: &SparseSymmetric) -> Self {
        Self::from_entries(m.values().iter().copied().enumerate().collect())
    }

    /// `target += scale · self`.
    pub fn add_scaled_to(&self, target: &mut SparseSymmetric, scale: f64) {
        let values = target.values_mut();
        for (&p, &v) in self.positions.iter().zip(&self.values) {
            values[p] += scale * v;
        }
    }

    /// Stored entries.
    pub fn nnz(&self) -> usize {
        self.positions.len()
    }

    /// The matrix on `pattern` (export, tests).
    pub fn to_matrix(&self, pattern: &Arc<Pattern>) -> SparseSymmetric {
        let mut m = SparseSymmetric::zeros(Arc::clone(pattern));
        self.add_scaled_to(&mut m, 1.0);
        m
    }
}

/// Eq. (23) assembled sparse and reduced to the free coordinates.
#[derive(Debug, Clone)]
pub struct SparseModel {
    /// The patches, for the sensors' rows and the export (global dofs by
    /// [`crate::model::dofs::DofMap`]).
    pub patches: Vec<Patch>,
    /// Every control point's directors, in global order.
    pub frames: Vec<Frame>,
    pub reduction: DofReduction,
    /// The pattern of the free coordinates.
    pub pattern: Arc<Pattern>,
    /// `Tᵀ K_f T`.
    pub free_stiffness: SparseSymmetric,
    /// `Tᵀ M T`.
    pub mass: SparseSymmetric,
    /// `M` on the generalised dofs, its non-zeros (the simulator's state
    /// transfer between models, [`crate::response::frf::FrfModel::mass_times`]).
    pub generalised_mass: NonZeros,
    /// `∂K/∂κ_j` per spring field and coefficient on the generalised dofs
    /// (eq. 22, low rank).
    pub spring_blocks: Vec<Vec<LowRankBlock>>,
    /// `Tᵀ ∂K/∂κ_j T` per spring field and coefficient.
    pub spring_terms: Vec<Vec<SparseTerm>>,
    pub spring_stiffness: Vec<Vec<f64>>,
    /// `Tᵀ ∂K/∂θ_k T` per stiffness field and coefficient.
    pub field_terms: Vec<Vec<SparseTerm>>,
    /// `∂K/∂θ_k` on the generalised dofs, its non-zeros only (products
    /// with the modes and residuals of the field sensitivities).
    pub field_products: Vec<Vec<NonZeros>>,
    pub field_coefficients: Vec<Vec<f64>>,
    /// Row-sum translational mass per control point (mode classification).
    lumped: Vec<f64>,
    /// The pencil's decoupled blocks, each with its own factorisation.
    blocks: Vec<Block>,
}

/// Per stiffness field and coefficient, `Tᵀ ∂K/∂θ_k T` on `pattern` and
/// `∂K/∂θ_k`'s non-zeros on the generalised dofs (`full`).
#[allow(
    clippy::type_complexity,
    reason = "the two forms of the same matrices, per field and coefficient"
)]
fn field_matrices(
    model: &BridgeModel,
    dofs: &DofMap,
    full: &Arc<Pattern>,
    reduction: &DofReduction,
    pattern: &Arc<Pattern>,
) -> Result<(Vec<Vec<SparseTerm>>, Vec<Vec<NonZeros>>), ModelError> {
    let reduced = |d: &SparseSymmetric| -> Result<(SparseTerm, NonZeros), ModelError> {
        let term = SparseTerm::from_matrix(&reduction.reduce_sparse(d, pattern).map_err(sparse_error)?);
        Ok((term, d.nonzeros()))
    };
    let members = model.member_stiffness.iter().enumerate().map(|(index, member)| {
        let mut derivative = SparseAccumulator::new(Arc::clone(full));
        member
            .derivative_into(&model.beams, dofs, &mut derivative)
            .map_err(|source| ModelError::MemberStiffness { index, source })?;
        let (term, product) = reduced(&derivative.to_matrix())?;
        Ok((vec![term], vec![product]))
    });
    let (terms, products): (Vec<_>, Vec<_>) = model
        .stiffness_fields
        .iter()
        .enumerate()
        .map(|(index, f)| {
            let (patch, offset) = model.patch_at(f.patch(), dofs)?;
            // Each coefficient's matrix holds its non-zeros only until it
            // is reduced, one at a time (on the whole pattern, 32
            // coefficients of a 20 000-dof deck took 2.5 GB).
            let empty = vec![Offset::new(SparseAccumulator::new(Arc::clone(full)), offset); f.coefficient_count()];
            let accumulated = f
                .coefficient_matrices_into(&patch.shell, &patch.material, empty)
                .map_err(|source| ModelError::StiffnessField { index, source })?;
            let mut terms = Vec::with_capacity(accumulated.len());
            let mut products = Vec::with_capacity(accumulated.len());
            for a in accumulated {
                let (term, product) = reduced(&a.inner.to_matrix())?;
                terms.push(term);
                products.push(product);
            }
            Ok((terms, products))
        })
        .chain(members)
        .collect::<Result<Vec<_>, ModelError>>()?
        .into_iter()
        .unzip();
    Ok((terms, products))
}

pub(super) fn sparse_error(e: SparseError) -> ModelError {
    ModelError::Shell(shell::ShellError::Sparse(e))
}

/// The pattern of a model's generalised dofs: each patch's control net
/// (one patch alone: its own, [`crate::model::shell::Shell::pattern`]), the
/// control points a joint's penalty couples across patches (`joints`: each
/// joint's entries), the beam nodes along their elements, and each rigid
/// body's reference node with everything its held nodes couple to (the
/// pattern `Tᵀ A T` needs).
fn model_pattern(
    model: &BridgeModel,
    dofs: &DofMap,
    joints: &[BTreeMap<(usize, usize), f64>],
) -> Result<Pattern, ModelError> {
    if let ([p], true) = (
        model.patches.as_slice(),
        dofs.node_count() == dofs.control_point_count(),
    ) {
        return Ok(p.shell.pattern());
    }
    let mut graph: Vec<Vec<usize>> = Vec::with_capacity(dofs.node_count());
    for p in &model.patches {
        let first = graph.len();
        let own = p.shell.pattern();
        graph.extend(
            own.graph()
                .iter()
                .map(|n| n.iter().map(|c| c + first).collect::<Vec<_>>()),
        );
    }
    graph.extend((0..model.beams.node_count()).map(|b| vec![dofs.beam_node(b)]));
    for (a, b) in model.beams.element_nodes() {
        let (a, b) = (dofs.beam_node(a), dofs.beam_node(b));
        graph[a].push(b);
        graph[b].push(a);
    }
    for &(i, j) in joints.iter().flat_map(BTreeMap::keys) {
        graph[dofs.node_of(i)].push(dofs.node_of(j));
    }
    // A rigid body's reference node takes over its held nodes' couplings.
    for (k, body) in model.rigid_bodies.iter().enumerate() {
        let reference = dofs.rigid_node(k);
        graph.push(vec![reference]);
        let held = body.held_nodes(&model.patches, &model.beams, dofs)?;
        let reached: Vec<usize> = held.iter().flat_map(|&h| graph[h].iter().copied()).collect();
        for n in reached {
            graph[reference].push(n);
            graph[n].push(reference);
        }
    }
    for neighbours in &mut graph {
        neighbours.sort_unstable();
        neighbours.dedup();
    }
    Ok(Pattern::control_graph(Arc::new(graph), &dofs.dofs_per_node()))
}

/// `target += B` for the non-zero entries of a block on global dofs.
fn add_block(target: &mut SparseSymmetric, block: &LowRankBlock) -> Result<(), ModelError> {
    add_entries(
        target,
        block.dofs.iter().enumerate().flat_map(|(c, &dc)| {
            block
                .dofs
                .iter()
                .enumerate()
                .map(move |(r, &dr)| ((dr, dc), block.values[(r, c)]))
        }),
    )
}

/// `target[i, j] += v` for the non-zero entries `((i, j), v)`.
fn add_entries(
    target: &mut SparseSymmetric,
    entries: impl IntoIterator<Item = ((usize, usize), f64)>,
) -> Result<(), ModelError> {
    for ((i, j), v) in entries {
        if v == 0.0 {
            continue;
        }
        let at = target
            .pattern()
            .position(i, j)
            .ok_or(SparseError::OutsidePattern { row: i, col: j })
            .map_err(sparse_error)?;
        target.values_mut()[at] += v;
    }
    Ok(())
}

/// `K_f` and `M` on the generalised dofs (`full`): every patch's eq.
/// (16)–(17), the non-structural and point masses, the joints' penalty
/// (`joints`: each joint's entries), as [`BridgeModel::assemble`] does dense.
fn assemble_matrices(
    model: &BridgeModel,
    dofs: &DofMap,
    full: &Arc<Pattern>,
    joints: &[BTreeMap<(usize, usize), f64>],
) -> Result<(SparseSymmetric, SparseSymmetric), ModelError> {
    let parts: Vec<_> = model
        .patches
        .iter()
        .enumerate()
        .map(|(index, p)| (&p.shell, &p.material, dofs.first_dof(index)))
        .collect();
    let (mut k, mut m) = shell::assemble_sparse_patches(&parts, full)?;
    model
        .beams
        .add_matrices(&mut k, &mut m, dofs)
        .map_err(ModelError::Beams)?;
    for (index, p) in model.patches.iter().enumerate() {
        p.add_surface_mass(&mut Offset::new(&mut m, dofs.first_dof(index)))
            .map_err(|e| ModelError::Patch {
                index,
                source: shell::ShellError::Sparse(e),
            })?;
    }
    for block in model.point_mass_blocks(dofs)? {
        add_block(&mut m, &block)?;
    }
    for entries in joints {
        add_entries(&mut k, entries.iter().map(|(&at, &v)| (at, v)))?;
    }
    Ok((k, m))
}

impl SparseModel {
    /// The sparse model of `model`: one or several patches, joints,
    /// springs, bearings, masses and stiffness fields, as
    /// [`BridgeModel::assemble`] builds dense.
    pub fn assemble(model: &BridgeModel) -> Result<Self, ModelError> {
        model.check_patch_indices()?;
        let dofs = model.dof_map();
        let joints: Vec<_> = model
            .joints
            .iter()
            .map(|j| j.penalty_entries(&model.patches, &dofs, model.joint_penalty))
            .collect();
        let full = Arc::new(model_pattern(model, &dofs, &joints)?);
        let reduction = model.reduction()?;
        let pattern = Arc::new(reduction.reduced_pattern(&full));
        let (k, m) = assemble_matrices(model, &dofs, &full, &joints)?;
        let lumped = lumped_translational_mass(&full, &m, &dofs);
        let owners = owners(&reduction);
        let spring_blocks = model.spring_blocks(&dofs)?;
        let spring_terms = spring_blocks
            .iter()
            .map(|blocks| {
                blocks
                    .iter()
                    .map(|b| reduce_block(&b.dofs, &b.values, &owners, &pattern))
                    .collect::<Result<Vec<_>, _>>()
                    .map_err(sparse_error)
            })
            .collect::<Result<Vec<_>, _>>()?;
        let (field_terms, field_products) = field_matrices(model, &dofs, &full, &reduction, &pattern)?;
        let free_stiffness = reduction.reduce_sparse(&k, &pattern).map_err(sparse_error)?;
        let mass = reduction.reduce_sparse(&m, &pattern).map_err(sparse_error)?;
        let generalised_mass = m.nonzeros();
        let mut coupled: Vec<bool> = free_stiffness
            .values()
            .iter()
            .zip(mass.values())
            .map(|(k, m)| *k != 0.0 || *m != 0.0)
            .collect();
        for term in spring_terms.iter().chain(&field_terms).flatten() {
            term.positions.iter().for_each(|&p| coupled[p] = true);
        }
        let blocks = decoupled_blocks(&pattern, &coupled)?;
        Ok(Self {
            patches: model.patches.clone(),
            frames: model.frames(),
            free_stiffness,
            mass,
            generalised_mass,
            reduction,
            pattern,
            spring_blocks,
            spring_terms,
            spring_stiffness: model.spring_coefficients(),
            field_terms,
            field_products,
            field_coefficients: model.field_coefficients(),
            lumped,
            blocks,
        })
    }

    /// Generalised dofs (before the constraints).
    pub fn dof_count(&self) -> usize {
        self.reduction.full_count()
    }

    /// Sizes of the decoupled blocks the eigenproblem splits into.
    pub fn block_sizes(&self) -> Vec<usize> {
        self.blocks.iter().map(|b| b.dofs.len()).collect()
    }

    /// Free coordinates (the size of the eigenproblem).
    pub fn free_count(&self) -> usize {
        self.pattern.dim()
    }

    /// `Tᵀ K(κ, θ) T`.
    pub fn stiffness_with_fields(&self, kappa: &[Vec<f64>], theta: &[Vec<f64>]) -> Result<SparseSymmetric, ModelError> {
        check_counts(&self.spring_terms, kappa, true)?;
        check_counts(&self.field_terms, theta, false)?;
        let mut k = self.free_stiffness.clone();
        for (terms, coefficients) in self.field_terms.iter().zip(theta) {
            for (t, &c) in terms.iter().zip(coefficients) {
                if c != 1.0 {
                    t.add_scaled_to(&mut k, c - 1.0);
                }
            }
        }
        for (terms, coefficients) in self.spring_terms.iter().zip(kappa) {
            for (t, &c) in terms.iter().zip(coefficients) {
                t.add_scaled_to(&mut k, c);
            }
        }
        Ok(k)
    }

    /// The modes with `f ≤ cutoff_hz` at `(κ, θ)`, mass-normalised on the
    /// full dofs and classified.
    pub fn modes_below(&self, kappa: &[Vec<f64>], theta: &[Vec<f64>], cutoff_hz: f64) -> Result<Modes, ModelError> {
        Ok(self.solve(kappa, theta, cutoff_hz, None)?.0)
    }

    /// [`Self::modes_below`] and the static responses `X Fᵀ` to the unit
    /// loads `F` (sparse rows on the generalised dofs: the sensor rows `N`
    /// of eq. 32), `X = (K − σM)⁻¹` at the eigen-solve's shift
    /// ([`Self::shift_for`]), with their first dynamic correction
    /// `X M X Fᵀ`, both on the generalised dofs (one column per load), from
    /// the eigen-solve's factorisation ([`crate::solvers::truncation`]).
    pub fn modes_and_responses(
        &self,
        kappa: &[Vec<f64>],
        theta: &[Vec<f64>],
        cutoff_hz: f64,
        loads: &[Vec<(usize, f64)>],
    ) -> Result<(Modes, Responses), ModelError> {
        let (modes, responses) = self.solve(kappa, theta, cutoff_hz, Some(loads))?;
        Ok((modes, responses.expect("loads given")))
    }

    fn solve(
        &self,
        kappa: &[Vec<f64>],
        theta: &[Vec<f64>],
        cutoff_hz: f64,
        loads: Option<&[Vec<(usize, f64)>]>,
    ) -> Result<(Modes, Option<Responses>), ModelError> {
        Ok(self.finish(self.solve_free(kappa, theta, cutoff_hz, loads)?))
    }

    /// The loads `F` (sparse rows on the generalised dofs) on the free
    /// coordinates: `Tᵀ F`, one column per load.
    pub(crate) fn free_loads(&self, loads: &[Vec<(usize, f64)>]) -> faer::Mat<f64> {
        let mut full = faer::Mat::<f64>::zeros(self.dof_count(), loads.len());
        for (s, row) in loads.iter().enumerate() {
            for &(d, v) in row {
                full[(d, s)] += v;
            }
        }
        self.reduction.reduce_vector(&full)
    }

    /// [`Self::solve`] on the free coordinates, block by block.
    pub(crate) fn solve_free(
        &self,
        kappa: &[Vec<f64>],
        theta: &[Vec<f64>],
        cutoff_hz: f64,
        loads: Option<&[Vec<(usize, f64)>]>,
    ) -> Result<FreeSolve, ModelError> {
        let k = self.stiffness_with_fields(kappa, theta)?;
        let cutoff_omega2 = (2.0 * PI * cutoff_hz).powi(2);
        let settings = PartialSettings {
            cutoff_omega2,
            shift: Self::shift_for(cutoff_hz),
            tolerance: RESIDUAL_TOLERANCE,
        };
        let rhs = loads.map(|loads| self.free_loads(loads));
        let nl = loads.map_or(0, <[_]>::len);
        let mut x = faer::Mat::<f64>::zeros(self.free_count(), nl);
        let mut xmx = faer::Mat::<f64>::zeros(self.free_count(), nl);
        // Each block's modes (merged in ascending order below) and the
        // responses of the blocks a load reaches.
        let mut found = Vec::new();
        for block in &self.blocks {
            let part = rhs
                .as_ref()
                .map(|rhs| faer::Mat::from_fn(block.dofs.len(), nl, |r, s| rhs[(block.dofs[r], s)]))
                .filter(|part| part.norm_max() > 0.0);
            let (modes, responses) = block.solve(
                &block.restrict(&k),
                &block.restrict(&self.mass),
                &settings,
                part.as_ref(),
            )?;
            if let Some((solved, dynamic)) = responses {
                for (r, &d) in block.dofs.iter().enumerate() {
                    for s in 0..nl {
                        x[(d, s)] = solved[(r, s)];
                        xmx[(d, s)] = dynamic[(r, s)];
                    }
                }
            }
            found.push(modes);
        }
        let mut order: Vec<(usize, usize)> = (0..found.len())
            .flat_map(|b| (0..found[b].omega2.len()).map(move |i| (b, i)))
            .collect();
        order.sort_by(|&(a, i), &(b, j)| found[a].omega2[i].total_cmp(&found[b].omega2[j]));
        let mut shapes = faer::Mat::<f64>::zeros(self.free_count(), order.len());
        for (c, &(b, i)) in order.iter().enumerate() {
            for (r, &d) in self.blocks[b].dofs.iter().enumerate() {
                shapes[(d, c)] = found[b].shapes[(r, i)];
            }
        }
        let omega2: Vec<f64> = order.iter().map(|&(b, i)| found[b].omega2[i]).collect();
        Ok(FreeSolve {
            omega2,
            shapes,
            responses: loads.map(|_| (x, xmx)),
        })
    }

    /// The modes and responses of a solve on the free coordinates, expanded
    /// to the generalised dofs, the modes classified.
    pub(crate) fn finish(&self, solved: FreeSolve) -> (Modes, Option<Responses>) {
        let shapes = self.reduction.expand(&solved.shapes);
        let responses = solved
            .responses
            .map(|(x, xmx)| (self.reduction.expand(&x), self.reduction.expand(&xmx)));
        (
            Modes::classified(solved.omega2, shapes, &self.lumped, &self.frames),
            responses,
        )
    }
}

/// A solve on the free coordinates: the modes (ascending, mass-normalised)
/// and, for loads, `(X F, X M X F)` at the solve's shift.
#[derive(Debug, Clone)]
pub(crate) struct FreeSolve {
    pub(crate) omega2: Vec<f64>,
    pub(crate) shapes: faer::Mat<f64>,
    pub(crate) responses: Option<Responses>,
}

impl SparseModel {
    /// The shift the eigen-solve below `cutoff_hz` uses.
    pub fn shift_for(cutoff_hz: f64) -> f64 {
        -(2.0 * PI * cutoff_hz).powi(2) / SHIFT_RATIO
    }
}

/// `σ = −ω²_cut / SHIFT_RATIO`: below every eigenvalue, and close enough to
/// the lowest modes that `K − σM` stays well conditioned with rigid modes.
const SHIFT_RATIO: f64 = 2500.0;

/// Largest relative residual of an accepted mode.
const RESIDUAL_TOLERANCE: f64 = 1e-8;

/// Row-sum translational mass per control point (its `x` translation's row
/// of `M`): the deck's, which the modes' kinds and shares weigh.
fn lumped_translational_mass(pattern: &Pattern, m: &SparseSymmetric, dofs: &DofMap) -> Vec<f64> {
    (0..dofs.control_point_count())
        .map(|node| {
            let r = dofs.node_dofs(node).start;
            (pattern.col_ptr()[r]..pattern.col_ptr()[r + 1])
                .filter(|&e| dofs.is_translation(pattern.row_idx()[e], 0))
                .map(|e| m.values()[e])
                .sum()
        })
        .collect()
}

/// Per full dof, the free coordinates it enters and their weights in `T`.
fn owners(reduction: &DofReduction) -> Vec<Vec<(usize, f64)>> {
    let mut owners = vec![Vec::new(); reduction.full_count()];
    for (i, column) in reduction.columns().iter().enumerate() {
        for &(d, t) in column {
            owners[d].push((i, t));
        }
    }
    owners
}

/// `Tᵀ B T` of a dense block `B` on full `dofs`, on the reduced pattern.
fn reduce_block(
    dofs: &[usize],
    block: &faer::Mat<f64>,
    owners: &[Vec<(usize, f64)>],
    pattern: &Pattern,
) -> Result<SparseTerm, SparseError> {
    let mut entries = BTreeMap::new();
    for (b, &db) in dofs.iter().enumerate() {
        for (a, &da) in dofs.iter().enumerate() {
            let v = block[(a, b)];
            if v == 0.0 {
                continue;
            }
            for &(j, tj) in &owners[db] {
                for &(i, ti) in &owners[da] {
                    let p = pattern
                        .position(i, j)
                        .ok_or(SparseError::OutsidePattern { row: i, col: j })?;
                    *entries.entry(p).or_insert(0.0) += ti * tj * v;
                }
            }
        }
    }
    Ok(SparseTerm::from_entries(entries))
}

/// The coefficient vectors `given` against the terms' counts per field.
fn check_counts(terms: &[Vec<SparseTerm>], given: &[Vec<f64>], springs: bool) -> Result<(), ModelError> {
    let mismatch = if terms.len() != given.len() {
        Some((terms.len().min(given.len()), given.len(), terms.len()))
    } else {
        terms
            .iter()
            .zip(given)
            .enumerate()
            .find(|(_, (t, g))| t.len() != g.len())
            .map(|(field, (t, g))| (field, g.len(), t.len()))
    };
    match (mismatch, springs) {
        (None, _) => Ok(()),
        (Some((field, found, expected)), true) => Err(ModelError::CoefficientCount { field, found, expected }),
        (Some((field, found, expected)), false) => Err(ModelError::FieldCoefficientCount { field, found, expected }),
    }
}

#[cfg(test)]
mod tests;
