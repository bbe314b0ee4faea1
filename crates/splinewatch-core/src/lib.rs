//! splinewatch-core: the pure numerics of splinewatch.
//!
//! A B-spline (isogeometric) degenerate-shell finite element model after
//! Carminelli & Catania (2011), with distributed B-spline spring supports,
//! rigid edge constraints and modal analysis. No I/O, no async, no network:
//! every function here is a deterministic computation on its arguments.
//!
//! The folders follow the data, each importing only from those above it:
//!
//! 1. [`geometry`]: knot vectors, B-spline surfaces, quadrature, small vectors;
//! 2. [`model`]: the deck: material, shell, supports, springs, stiffness fields, damping curve, sparse patterns;
//! 3. [`solvers`]: assembled models and their eigen-solves (dense, shift-invert Lanczos), truncation;
//! 4. [`response`]: FRFs, their sensitivities, time-domain simulation;
//! 5. [`identification`]: Welch spectra and FRF estimates, output-only modal analysis;
//! 6. [`updating`]: FRF and modal residues and the one bounded least-squares solver;
//! 7. [`monitoring`]: environmental compensation, control charts, alarms.
//!
//! [`linalg`] holds small dense helpers every floor may use.
#![forbid(unsafe_code)]
// Index loops mirror the summations of the paper; iterator chains would hide them.
#![allow(clippy::needless_range_loop)]
// No function longer than clippy.toml's too-many-lines-threshold without a written reason.
#![warn(clippy::too_many_lines)]

// The floors in pipeline order (each on its own line group, so rustfmt keeps
// the order; tests/integration/architecture.rs checks it).
pub mod linalg;

pub mod geometry;

pub mod model;

pub mod solvers;

pub mod response;

pub mod identification;

pub mod updating;

pub mod monitoring;

/// Complex scalar used for FRFs (re-exported so callers need not depend on faer).
pub use faer::c64;
/// Dense matrix type used in the public API (re-exported from faer).
pub use faer::Mat;
