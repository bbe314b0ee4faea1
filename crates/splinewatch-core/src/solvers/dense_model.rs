//! The dense assembled model and the errors of assembling and solving one.
//!
//! `K = K_f(θ) + ΔK(κ)` (eq. 23) with `ΔK(κ) = Σ_fields Σ_j κ_j ∂K/∂κ_j`
//! (eq. 22) and, for stiffness fields of the deck,
//! `K_f(θ) = K_f + Σ_fields Σ_k (θ_k − 1) ∂K/∂θ_k` ([`crate::model::stiffness_field`]).
//! [`AssembledModel`] keeps `K_f`, `M`, every `∂K/∂κ_j` and `∂K/∂θ_k` so that
//! a change of coefficients (the updating loop) costs only the weighted sums,
//! and its prepared eigen-solver ([`ModalSolver`]), built on the first solve.
//! [`ShellModel::assemble`] is defined here, beside what it builds.

use crate::model::constraints::DofReduction;
use crate::model::shell::{self, Shell, ShellError};
use crate::model::springs::{LowRankBlock, SpringError};
use crate::model::stiffness_field::StiffnessFieldError;
use crate::model::ShellModel;
use crate::solvers::modal::{ModalError, ModalSolver, Modes};
use faer::Mat;
use std::sync::OnceLock;
use thiserror::Error;

#[derive(Debug, Clone, PartialEq, Error)]
pub enum ModelError {
    #[error("shell: {0}")]
    Shell(#[from] ShellError),
    #[error("spring field {index}: {source}")]
    Spring { index: usize, source: SpringError },
    #[error("stiffness field {index}: {source}")]
    StiffnessField { index: usize, source: StiffnessFieldError },
    #[error("modes: {0}")]
    Modal(#[from] ModalError),
    #[error("partial modes: {0}")]
    PartialEigen(crate::solvers::partial_eigen::PartialEigenError),
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

/// Assembled matrices of a [`ShellModel`].
#[derive(Debug, Clone)]
pub struct AssembledModel {
    pub shell: Shell,
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

impl ShellModel {
    pub fn assemble(&self) -> Result<AssembledModel, ModelError> {
        let mats = shell::assemble(&self.shell, &self.material)?;
        let spring_blocks = self
            .springs
            .iter()
            .enumerate()
            .map(|(index, s)| {
                s.coefficient_matrices(&self.shell)
                    .map_err(|source| ModelError::Spring { index, source })
            })
            .collect::<Result<Vec<_>, _>>()?;
        let field_matrices = self
            .stiffness_fields
            .iter()
            .enumerate()
            .map(|(index, f)| {
                f.coefficient_matrices(&self.shell, &self.material)
                    .map_err(|source| ModelError::StiffnessField { index, source })
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(AssembledModel {
            shell: self.shell.clone(),
            free_stiffness: mats.stiffness,
            mass: mats.mass,
            spring_blocks,
            spring_stiffness: self.springs.iter().map(|s| s.stiffness().to_vec()).collect(),
            field_matrices,
            field_coefficients: self
                .stiffness_fields
                .iter()
                .map(|f| f.coefficients().to_vec())
                .collect(),
            reduction: DofReduction::new(&self.shell, &self.constraints),
            modal: OnceLock::new(),
        })
    }
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
        Ok(solver.modes(&flat, &theta, &self.reduction, &self.mass, &self.shell)?)
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
