//! splinewatch: the application shell around `splinewatch-core`.
//!
//! Folders follow the data flow, and imports only point down
//! (ARCHITECTURE.md; checked by `tests/architecture.rs`):
//! `cli` → `service` → `outputs` → `pipeline`, `studies` → `config`, `io` →
//! `splinewatch-core`. The numerics live in `splinewatch-core`, which does no I/O.
#![forbid(unsafe_code)]
// No function longer than clippy.toml's too-many-lines-threshold without a written reason.
#![warn(clippy::too_many_lines)]

#[cfg(feature = "daemon")]
pub mod cli;
pub mod config;
pub mod io;
#[cfg(feature = "daemon")]
pub mod outputs;
pub mod pipeline;
#[cfg(feature = "daemon")]
pub mod service;
pub mod studies;
