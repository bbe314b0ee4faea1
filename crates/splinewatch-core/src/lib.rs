//! splinewatch-core: the pure numerics of splinewatch.
//!
//! A B-spline (isogeometric) degenerate-shell finite element model after
//! Carminelli & Catania (2011), with distributed B-spline spring supports,
//! rigid edge constraints and modal analysis. No I/O, no async, no network:
//! every function here is a deterministic computation on its arguments.
#![forbid(unsafe_code)]
// Index loops mirror the summations of the paper; iterator chains would hide them.
#![allow(clippy::needless_range_loop)]
// No function longer than clippy.toml's too-many-lines-threshold without a written reason.
#![warn(clippy::too_many_lines)]

pub mod constraints;
pub mod damping;
pub mod frf;
pub mod knots;
pub mod linalg;
pub mod material;
pub mod modal;
pub mod modal_residual;
pub mod modal_sensitivity;
pub mod model;
pub mod monitoring;
pub mod oma;
pub mod partial_eigen;
pub mod quadrature;
pub mod shell;
pub mod sparse;
pub mod sparse_model;
pub mod springs;
pub mod stiffness_field;
pub mod subtree_solve;
pub mod surface;
pub mod truncation;
pub mod updating;
pub mod vec3;

/// Complex scalar used for FRFs (re-exported so callers need not depend on faer).
pub use faer::c64;
pub mod simulate;
pub mod welch;

/// Dense matrix type used in the public API (re-exported from faer).
pub use faer::Mat;
