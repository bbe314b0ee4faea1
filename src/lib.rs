//! splinewatch: the application shell around `splinewatch-core`.
//!
//! This library holds what the binary needs and tests reuse: configuration
//! loading and validation, and the command implementations. The numerics
//! live in `splinewatch-core`, which does no I/O.
#![forbid(unsafe_code)]

pub mod commands;
pub mod config;
pub mod daemon;
pub mod demo;
pub mod estimate;
pub mod files;
pub mod frf_json;
pub mod paper;
pub mod pipeline;
pub mod recorder;
pub mod recording;
pub mod recover;
pub mod replay;
pub mod results;
pub mod simulation;
pub mod viewer;
pub mod wire;
