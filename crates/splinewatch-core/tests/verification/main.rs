//! Verification ladder of splinewatch-core: one test binary, shared fixtures.

mod beam;
mod common;
mod event_updating;
mod footing;
mod frames;
mod frf;
mod joint;
mod line_support;
mod members;
mod modal;
mod modal_residual;
mod modal_sensitivity;
mod oma;
mod patches;
mod realization;
mod shell;
mod simulate;
mod srim;
mod stiffness_field;
mod support_loss;
mod support_motion;
mod truncation;
mod updating;
mod welch;
