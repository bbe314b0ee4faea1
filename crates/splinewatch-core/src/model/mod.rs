//! The deck as physics and discretisation: what is assembled.
//!
//! May import: `geometry`, `linalg`.
//!
//! - [`material`]: the plane-stress Mindlin matrix `E'` (eq. 7–9);
//! - [`sparse`]: the control net's sparsity pattern and the symmetric matrices on it (eq. 16–17 at scale);
//! - [`shell`]: the degenerate shell, its displacement shapes and the one quadrature loop of eq. (16)–(17);
//! - [`constraints`]: rigid edge supports as the dof reduction `δ = T q`;
//! - [`springs`]: B-spline spring fields on a face and their `∂K/∂κ_j` (eq. 19–22);
//! - [`stiffness_field`]: B-spline multipliers of the deck's stiffness and their `∂K/∂θ_k`;
//! - [`damping`]: the damping curve ζ(f) (eq. 25–29).
//!
//! [`ShellModel`] gathers them; the solvers assemble it
//! ([`crate::solvers::dense_model`], [`crate::solvers::sparse_model`]).

pub mod constraints;
pub mod damping;
pub mod material;
pub mod shell;
pub mod sparse;
pub mod springs;
pub mod stiffness_field;

use constraints::EdgeConstraint;
use material::OrthotropicMaterial;
use shell::Shell;
use springs::SpringField;
use stiffness_field::StiffnessField;

/// Physics and discretisation of a deck, validated.
#[derive(Debug, Clone)]
pub struct ShellModel {
    pub shell: Shell,
    pub material: OrthotropicMaterial,
    pub springs: Vec<SpringField>,
    /// Stiffness multiplier fields of the deck (none: the nominal material).
    pub stiffness_fields: Vec<StiffnessField>,
    pub constraints: Vec<EdgeConstraint>,
}
