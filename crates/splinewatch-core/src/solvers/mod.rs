//! Assembled models and their eigen-solves (eq. 23, 27).
//!
//! May import: `model`, `geometry`, `linalg`.
//!
//! - [`dense_model`]: `AssembledModel` (dense `K_f`, `M`, `∂K/∂κ_j`, `∂K/∂θ_k`) and `BridgeModel::assemble`;
//! - [`modal`]: the prepared dense eigen-solver (`ModalSolver`) and the reference `solve`;
//! - [`mode_motion`]: where a mode moves the deck (along, across, vertical, torsion);
//! - [`sparse_model`]: the sparse, reduced model and the modes below a cut-off;
//! - [`reanalysis`]: the Ritz basis of a start point answering spring changes without a new factorisation;
//! - [`partial_eigen`]: shift-invert Lanczos with a supernodal Cholesky factor, Sturm counts;
//! - [`subtree_solve`]: triangular solves with that factor on two threads;
//! - [`truncation`]: the discarded modes' residual flexibility, inertia and damping.

pub mod dense_model;
pub mod modal;
pub mod mode_motion;
pub mod partial_eigen;
pub mod reanalysis;
pub mod sparse_model;
pub mod subtree_solve;
pub mod truncation;
