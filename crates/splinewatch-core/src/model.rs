//! The complete structural model: shell + material + springs + supports.
//!
//! `K = K_f + ΔK(κ)` (eq. 23) with `ΔK(κ) = Σ_fields Σ_j κ_j ∂K/∂κ_j` (eq. 22).
//! [`AssembledModel`] keeps `K_f`, `M` and every `∂K/∂κ_j` so that a change
//! of spring coefficients (the updating loop) costs only the low-rank sums.

use crate::constraints::{DofReduction, EdgeConstraint};
use crate::material::OrthotropicMaterial;
use crate::modal::{ModalError, ModalSolver, Modes};
use crate::shell::{self, Shell, ShellError};
use crate::springs::{LowRankBlock, SpringError, SpringField};
use faer::Mat;
use std::sync::OnceLock;
use thiserror::Error;

#[derive(Debug, Clone, PartialEq, Error)]
pub enum ModelError {
    #[error("shell: {0}")]
    Shell(#[from] ShellError),
    #[error("spring field {index}: {source}")]
    Spring { index: usize, source: SpringError },
    #[error("modes: {0}")]
    Modal(#[from] ModalError),
    #[error("spring field {field}: {found} coefficients given, {expected} expected")]
    CoefficientCount {
        field: usize,
        found: usize,
        expected: usize,
    },
}

/// Physics and discretisation of a deck, validated.
#[derive(Debug, Clone)]
pub struct ShellModel {
    pub shell: Shell,
    pub material: OrthotropicMaterial,
    pub springs: Vec<SpringField>,
    pub constraints: Vec<EdgeConstraint>,
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
        Ok(AssembledModel {
            shell: self.shell.clone(),
            free_stiffness: mats.stiffness,
            mass: mats.mass,
            spring_blocks,
            spring_stiffness: self.springs.iter().map(|s| s.stiffness().to_vec()).collect(),
            reduction: DofReduction::new(&self.shell, &self.constraints),
            modal: OnceLock::new(),
        })
    }
}

impl AssembledModel {
    pub fn dof_count(&self) -> usize {
        self.mass.nrows()
    }

    /// `K_f + ΔK(κ)` for the given coefficients, one vector per spring field.
    pub fn stiffness_with(&self, kappa: &[Vec<f64>]) -> Result<Mat<f64>, ModelError> {
        self.check_coefficient_counts(kappa)?;
        let mut k = self.free_stiffness.clone();
        for (blocks, coeffs) in self.spring_blocks.iter().zip(kappa) {
            for (b, &c) in blocks.iter().zip(coeffs) {
                b.add_scaled_to(&mut k, c);
            }
        }
        Ok(k)
    }

    fn check_coefficient_counts(&self, kappa: &[Vec<f64>]) -> Result<(), ModelError> {
        if kappa.len() != self.spring_blocks.len() {
            return Err(ModelError::CoefficientCount {
                field: kappa.len().min(self.spring_blocks.len()),
                found: kappa.len(),
                expected: self.spring_blocks.len(),
            });
        }
        for (field, (blocks, coeffs)) in self.spring_blocks.iter().zip(kappa).enumerate() {
            if coeffs.len() != blocks.len() {
                return Err(ModelError::CoefficientCount {
                    field,
                    found: coeffs.len(),
                    expected: blocks.len(),
                });
            }
        }
        Ok(())
    }

    /// `K_f + ΔK` with the coefficients the model was built with.
    pub fn stiffness(&self) -> Mat<f64> {
        self.stiffness_with(&self.spring_stiffness)
            .expect("built with matching coefficient counts")
    }

    /// All modes for the given spring coefficients.
    pub fn modes_with(&self, kappa: &[Vec<f64>]) -> Result<Modes, ModelError> {
        self.check_coefficient_counts(kappa)?;
        let flat: Vec<f64> = kappa.iter().flatten().copied().collect();
        let solver = self.modal_solver()?;
        Ok(solver.modes(&flat, &self.reduction, &self.mass, &self.shell)?)
    }

    /// The prepared eigen-solver (see [`ModalSolver`]).
    pub fn modal_solver(&self) -> Result<&ModalSolver, ModalError> {
        self.modal
            .get_or_init(|| {
                let blocks: Vec<&LowRankBlock> = self.spring_blocks.iter().flatten().collect();
                ModalSolver::new(&self.free_stiffness, &self.mass, &blocks, &self.reduction)
            })
            .as_ref()
            .map_err(Clone::clone)
    }

    /// All modes with the model's own spring coefficients.
    pub fn modes(&self) -> Result<Modes, ModelError> {
        self.modes_with(&self.spring_stiffness)
    }
}
