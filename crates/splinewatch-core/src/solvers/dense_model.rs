//! The dense assembled model and the errors of assembling and solving one.
//!
//! `K = K_f(θ) + ΔK(κ)` (eq. 23) with `ΔK(κ) = Σ_fields Σ_j κ_j ∂K/∂κ_j`
//! (eq. 22) and, for stiffness fields of the deck,
//! `K_f(θ) = K_f + Σ_fields Σ_k (θ_k − 1) ∂K/∂θ_k` ([`crate::model::stiffness_field`]).
//! [`AssembledModel`] keeps `K_f`, `M`, every `∂K/∂κ_j` and `∂K/∂θ_k` so that
//! a change of coefficients (the updating loop) costs only the weighted sums,
//! and its prepared eigen-solver ([`ModalSolver`]), built on the first solve.
//! [`BridgeModel::assemble`] is defined here, beside what it builds.

use crate::model::bearings::BearingError;
use crate::model::constraints::DofReduction;
use crate::model::dofs::DofMap;
use crate::model::elastic_supports::ElasticSupportError;
use crate::model::member_stiffness::MemberStiffnessError;
use crate::model::members::BeamNet;
use crate::model::patch::Patch;
use crate::model::rigid::RigidError;
use crate::model::shell::{self, Frame, Offset, ShellError};
use crate::model::sparse::SparseError;
use crate::model::springs::{LowRankBlock, SpringError};
use crate::model::stiffness_field::StiffnessField;
use crate::model::stiffness_field::StiffnessFieldError;
use crate::model::support::Support;
use crate::model::BridgeModel;
use crate::solvers::modal::{ModalError, ModalSolver, Modes};
use faer::Mat;
use std::sync::OnceLock;
use thiserror::Error;

#[derive(Debug, Clone, PartialEq, Error)]
pub enum ModelError {
    #[error("shell: {0}")]
    Shell(#[from] ShellError),
    #[error("patch {index}: {source}")]
    Patch { index: usize, source: ShellError },
    #[error("patch {patch} does not exist (the model has {count})")]
    UnknownPatch { patch: usize, count: usize },
    #[error("{0}")]
    Support(#[from] ElasticSupportError),
    #[error("bearing {index}: {source}")]
    Bearing { index: usize, source: BearingError },
    #[error("point mass {index}: {source}")]
    Mass { index: usize, source: BearingError },
    #[error("spring field {index}: {source}")]
    Spring { index: usize, source: SpringError },
    #[error("stiffness field {index}: {source}")]
    StiffnessField { index: usize, source: StiffnessFieldError },
    #[error("beams: {0}")]
    Beams(SparseError),
    #[error("member stiffness {index}: {source}")]
    MemberStiffness { index: usize, source: MemberStiffnessError },
    #[error("{0}")]
    Rigid(#[from] RigidError),
    #[error("modes: {0}")]
    Modal(#[from] ModalError),
    #[error("partial modes: {0}")]
    PartialEigen(crate::solvers::partial_eigen::PartialEigenError),
    #[error("spring coefficient {index} does not exist (the model has {count})")]
    UnknownSpringCoefficient { index: usize, count: usize },
    #[error("spring field {field}: {found} coefficients given, {expected} expected")]
    CoefficientCount {
        field: usize,
        found: usize,
        expected: usize,
    },
    #[error("stiffness field {field}: {found} coefficients given, {expected} expected")]
    FieldCoefficientCount {
        field: usize,
        found: usize,
        expected: usize,
    },
}

/// Assembled matrices of a [`BridgeModel`].
#[derive(Debug, Clone)]
pub struct AssembledModel {
    /// The patches, for the sensors' rows (global dofs by
    /// [`crate::model::dofs::DofMap`]).
    pub patches: Vec<Patch>,
    /// The beam members, for sensors on them.
    pub beams: BeamNet,
    /// Every control point's directors, in global order.
    pub frames: Vec<Frame>,
    /// `K_f`, eq. (16).
    pub free_stiffness: Mat<f64>,
    /// `M`, eq. (17).
    pub mass: Mat<f64>,
    /// `∂K/∂κ_j` per spring field and coefficient.
    pub spring_blocks: Vec<Vec<LowRankBlock>>,
    /// The spring coefficients the model was built with.
    pub spring_stiffness: Vec<Vec<f64>>,
    /// `∂K/∂θ_k` per stiffness field and coefficient (unconstrained dofs).
    pub field_matrices: Vec<Vec<Mat<f64>>>,
    /// The stiffness-field coefficients the model was built with.
    pub field_coefficients: Vec<Vec<f64>>,
    pub reduction: DofReduction,
    /// Built on the first modal solve from the fields above (read-only after
    /// assembly).
    modal: OnceLock<Result<ModalSolver, ModalError>>,
}

impl BridgeModel {
    /// The global `K_f`, `M`, `∂K/∂κ`, `∂K/∂θ` and `T`: each patch's eq.
    /// (16)–(17) on its own dofs ([`crate::model::patch`]), the beams'
    /// elements, then the non-structural and point masses, the joints' penalty, the spring
    /// fields followed by the bearings (three coefficients each), and the
    /// stiffness fields, each moved to its patch's dofs.
    pub fn assemble(&self) -> Result<AssembledModel, ModelError> {
        let dofs = self.dof_map();
        let (mut free_stiffness, mut mass) = self.patch_matrices(&dofs)?;
        self.beams
            .add_matrices(&mut free_stiffness, &mut mass, &dofs)
            .map_err(ModelError::Beams)?;
        for (index, p) in self.patches.iter().enumerate() {
            p.add_surface_mass(&mut Offset::new(&mut mass, dofs.first_dof(index)))
                .map_err(|e| ModelError::Patch {
                    index,
                    source: ShellError::Sparse(e),
                })?;
        }
        for block in self.point_mass_blocks(&dofs)? {
            block.add_scaled_to(&mut mass, 1.0);
        }
        for joint in &self.joints {
            self.patch_at(joint.patch, &dofs)?;
            self.patch_at(joint.other, &dofs)?;
            joint
                .penalty(&self.patches, &dofs, self.joint_penalty)
                .add_scaled_to(&mut free_stiffness, 1.0);
        }
        let spring_blocks = self.spring_blocks(&dofs)?;
        let n = dofs.dof_count();
        let mut field_matrices = Vec::with_capacity(self.stiffness_fields.len());
        for (index, f) in self.stiffness_fields.iter().enumerate() {
            let (p, offset) = self.patch_at(f.patch(), &dofs)?;
            let own = f
                .coefficient_matrices(&p.shell, &p.material)
                .map_err(|source| ModelError::StiffnessField { index, source })?;
            field_matrices.push(own.into_iter().map(|m| embed(m, offset, n)).collect());
        }
        for (index, member) in self.member_stiffness.iter().enumerate() {
            let mut derivative = Mat::<f64>::zeros(n, n);
            member
                .derivative_into(&self.beams, &dofs, &mut derivative)
                .map_err(|source| ModelError::MemberStiffness { index, source })?;
            field_matrices.push(vec![derivative]);
        }
        let spring_stiffness = self.spring_coefficients();
        Ok(AssembledModel {
            patches: self.patches.clone(),
            beams: self.beams.clone(),
            frames: self.frames(),
            free_stiffness,
            mass,
            spring_blocks,
            spring_stiffness,
            field_matrices,
            field_coefficients: self.field_coefficients(),
            reduction: self.reduction()?,
            modal: OnceLock::new(),
        })
    }

    /// Patch `patch` and its first global dof.
    pub(crate) fn patch_at(&self, patch: usize, dofs: &DofMap) -> Result<(&Patch, usize), ModelError> {
        self.patches
            .get(patch)
            .map(|p| (p, dofs.first_dof(patch)))
            .ok_or(ModelError::UnknownPatch {
                patch,
                count: self.patches.len(),
            })
    }

    /// `∂K/∂κ_j` on global dofs, per support in [`BridgeModel::supports`]'
    /// order: a spring field's coefficients, a bearing's `k_x, k_y, k_z`, an
    /// elastic support's components.
    pub(crate) fn spring_blocks(&self, dofs: &DofMap) -> Result<Vec<Vec<LowRankBlock>>, ModelError> {
        self.supports()
            .map(|support| {
                let shifted =
                    |blocks: Vec<LowRankBlock>, offset| blocks.into_iter().map(|b| b.shifted(offset)).collect();
                Ok(match support {
                    Support::Field(index, s) => {
                        let (p, offset) = self.patch_at(s.patch(), dofs)?;
                        let blocks = s
                            .coefficient_matrices(&p.shell)
                            .map_err(|source| ModelError::Spring { index, source })?;
                        shifted(blocks, offset)
                    }
                    Support::Bearing(index, b) => {
                        let (p, offset) = self.patch_at(b.at().patch, dofs)?;
                        let blocks = b
                            .coefficient_matrices(&p.shell)
                            .map_err(|source| ModelError::Bearing { index, source })?;
                        shifted(blocks, offset)
                    }
                    Support::Elastic(_, s) => s.matrices(dofs, |patch| {
                        self.patch_at(patch, dofs).map(|(p, offset)| (&p.shell, offset))
                    })?,
                })
            })
            .collect()
    }

    /// Every point mass's block on global dofs.
    pub(crate) fn point_mass_blocks(&self, dofs: &DofMap) -> Result<Vec<LowRankBlock>, ModelError> {
        self.masses
            .iter()
            .enumerate()
            .map(|(index, m)| {
                let (p, offset) = self.patch_at(m.at().patch, dofs)?;
                let block = m
                    .mass_block(&p.shell)
                    .map_err(|source| ModelError::Mass { index, source })?;
                Ok(block.shifted(offset))
            })
            .collect()
    }

    /// Every patch's eq. (16)–(17), side by side (one patch and no beams:
    /// its own), on the model's dofs.
    fn patch_matrices(&self, dofs: &DofMap) -> Result<(Mat<f64>, Mat<f64>), ModelError> {
        if let ([p], true) = (self.patches.as_slice(), self.beams.is_empty()) {
            let mats = shell::assemble(&p.shell, &p.material)?;
            return Ok((mats.stiffness, mats.mass));
        }
        let n = dofs.dof_count();
        let (mut k, mut m) = (Mat::zeros(n, n), Mat::zeros(n, n));
        for (index, p) in self.patches.iter().enumerate() {
            let offset = dofs.first_dof(index);
            let mats = shell::assemble(&p.shell, &p.material).map_err(|source| ModelError::Patch { index, source })?;
            let own = p.shell.dof_count();
            k.as_mut()
                .submatrix_mut(offset, offset, own, own)
                .copy_from(&mats.stiffness);
            m.as_mut().submatrix_mut(offset, offset, own, own).copy_from(&mats.mass);
        }
        Ok((k, m))
    }

    /// Every patch index of the attachments names a patch of the model.
    pub fn check_patch_indices(&self) -> Result<(), ModelError> {
        let used = self
            .stiffness_fields
            .iter()
            .map(StiffnessField::patch)
            .chain(self.constraints.iter().map(|c| c.patch))
            .chain(self.supports().filter_map(|s| s.patch()))
            .chain(self.masses.iter().map(|m| m.at().patch))
            .chain(self.joints.iter().flat_map(|j| [j.patch, j.other]));
        match used.into_iter().find(|&p| p >= self.patches.len()) {
            Some(patch) => Err(ModelError::UnknownPatch {
                patch,
                count: self.patches.len(),
            }),
            None => Ok(()),
        }
    }

    /// `T = diag(T_k, T_b)`, each patch's supported edges eliminated, and
    /// the beams' held bases; then every rigid body's held nodes tied to
    /// its reference node ([`crate::model::rigid`]).
    pub fn reduction(&self) -> Result<DofReduction, ModelError> {
        if let Some(c) = self.constraints.iter().find(|c| c.patch >= self.patches.len()) {
            return Err(ModelError::UnknownPatch {
                patch: c.patch,
                count: self.patches.len(),
            });
        }
        let dofs = self.dof_map();
        let beam_dofs = dofs.dof_count() - dofs.first_dof(self.patches.len());
        let held: Vec<usize> = self
            .beams
            .held_dofs(&dofs)
            .into_iter()
            .map(|d| d - dofs.first_dof(self.patches.len()))
            .collect();
        let mut reduction = DofReduction::block_diagonal(
            self.patches
                .iter()
                .enumerate()
                .map(|(k, p)| {
                    let own: Vec<_> = self.constraints.iter().filter(|c| c.patch == k).copied().collect();
                    DofReduction::new(&p.shell, &own)
                })
                .chain([DofReduction::holding(beam_dofs, &held)])
                .collect(),
        );
        for (k, body) in self.rigid_bodies.iter().enumerate() {
            let (slaves, extra) = body.ties(&self.patches, &self.beams, &dofs)?;
            let master = dofs.node_dofs(dofs.rigid_node(k));
            let master: [usize; 6] = std::array::from_fn(|c| master.start + c);
            reduction = reduction
                .tie(master, extra, &slaves)
                .map_err(|dof| RigidError::Conflict {
                    name: body.name().to_string(),
                    node: dofs.node_of(dof),
                })?;
        }
        Ok(reduction)
    }
}

/// A patch's `n_k × n_k` matrix in the global `n × n` at `offset` (itself
/// when the patch is the whole model).
fn embed(own: Mat<f64>, offset: usize, n: usize) -> Mat<f64> {
    if own.nrows() == n {
        return own;
    }
    let mut out = Mat::zeros(n, n);
    out.as_mut()
        .submatrix_mut(offset, offset, own.nrows(), own.ncols())
        .copy_from(&own);
    out
}

impl AssembledModel {
    pub fn dof_count(&self) -> usize {
        self.mass.nrows()
    }

    /// `K_f(θ) + ΔK(κ)` for the given spring coefficients (one vector per
    /// spring field) and the model's own stiffness-field coefficients.
    pub fn stiffness_with(&self, kappa: &[Vec<f64>]) -> Result<Mat<f64>, ModelError> {
        self.stiffness_with_fields(kappa, &self.field_coefficients)
    }

    /// `K_f(θ) + ΔK(κ)` for spring coefficients `kappa` and stiffness-field
    /// coefficients `theta` (one vector per field of each kind).
    pub fn stiffness_with_fields(&self, kappa: &[Vec<f64>], theta: &[Vec<f64>]) -> Result<Mat<f64>, ModelError> {
        self.check_coefficient_counts(kappa)?;
        self.check_field_counts(theta)?;
        let mut k = self.free_stiffness.clone();
        for (matrices, coefficients) in self.field_matrices.iter().zip(theta) {
            for (m, &t) in matrices.iter().zip(coefficients) {
                if t != 1.0 {
                    k += m * (t - 1.0);
                }
            }
        }
        for (blocks, coeffs) in self.spring_blocks.iter().zip(kappa) {
            for (b, &c) in blocks.iter().zip(coeffs) {
                b.add_scaled_to(&mut k, c);
            }
        }
        Ok(k)
    }

    fn check_coefficient_counts(&self, kappa: &[Vec<f64>]) -> Result<(), ModelError> {
        match count_mismatch(self.spring_blocks.iter().map(Vec::len), kappa) {
            Some((field, found, expected)) => Err(ModelError::CoefficientCount { field, found, expected }),
            None => Ok(()),
        }
    }

    fn check_field_counts(&self, theta: &[Vec<f64>]) -> Result<(), ModelError> {
        match count_mismatch(self.field_matrices.iter().map(Vec::len), theta) {
            Some((field, found, expected)) => Err(ModelError::FieldCoefficientCount { field, found, expected }),
            None => Ok(()),
        }
    }

    /// `K_f + ΔK` with the coefficients the model was built with.
    pub fn stiffness(&self) -> Mat<f64> {
        self.stiffness_with(&self.spring_stiffness)
            .expect("built with matching coefficient counts")
    }

    /// All modes for the given spring coefficients (the model's own
    /// stiffness-field coefficients).
    pub fn modes_with(&self, kappa: &[Vec<f64>]) -> Result<Modes, ModelError> {
        self.modes_with_fields(kappa, &self.field_coefficients)
    }

    /// All modes for spring coefficients `kappa` and stiffness-field
    /// coefficients `theta`.
    pub fn modes_with_fields(&self, kappa: &[Vec<f64>], theta: &[Vec<f64>]) -> Result<Modes, ModelError> {
        self.check_coefficient_counts(kappa)?;
        self.check_field_counts(theta)?;
        let flat: Vec<f64> = kappa.iter().flatten().copied().collect();
        let theta: Vec<f64> = theta.iter().flatten().copied().collect();
        let solver = self.modal_solver()?;
        Ok(solver.modes(&flat, &theta, &self.reduction, &self.mass, &self.frames)?)
    }

    /// The prepared eigen-solver (see [`ModalSolver`]).
    pub fn modal_solver(&self) -> Result<&ModalSolver, ModalError> {
        self.modal
            .get_or_init(|| {
                let blocks: Vec<&LowRankBlock> = self.spring_blocks.iter().flatten().collect();
                let fields: Vec<&Mat<f64>> = self.field_matrices.iter().flatten().collect();
                ModalSolver::with_fields(&self.free_stiffness, &self.mass, &blocks, &fields, &self.reduction)
            })
            .as_ref()
            .map_err(Clone::clone)
    }

    /// All modes with the model's own spring coefficients.
    pub fn modes(&self) -> Result<Modes, ModelError> {
        self.modes_with(&self.spring_stiffness)
    }
}

/// The first mismatch between the coefficient vectors `given` and the
/// `expected` count per field, as `(field, found, expected)`: the number of
/// fields first (reported at the shorter length), then each field's count.
fn count_mismatch(expected: impl ExactSizeIterator<Item = usize>, given: &[Vec<f64>]) -> Option<(usize, usize, usize)> {
    if expected.len() != given.len() {
        return Some((expected.len().min(given.len()), given.len(), expected.len()));
    }
    expected
        .zip(given)
        .enumerate()
        .find(|(_, (n, g))| g.len() != *n)
        .map(|(field, (n, g))| (field, g.len(), n))
}
