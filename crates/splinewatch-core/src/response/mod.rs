//! What the model answers to a load: FRFs (eq. 31–33), their sensitivities
//! to the parameters, and responses in time.
//!
//! May import: `solvers`, `model`, `geometry`, `linalg`.
//!
//! - [`frf`]: `FrfModel`, modal superposition at the sensors, `∂H/∂κ`, `∂H/∂γ`, the direct `Z(ω)` check;
//! - [`modal_sensitivity`]: eigenvalue and eigenvector derivatives at the sensors (Fox & Kapoor 1968);
//! - [`simulate`]: `ModalSimulator`, the exact first-order-hold modal recursion;
//! - [`support_motion`]: the deck driven by its grounds (influence, transmissibilities, recursion inputs).

pub mod frf;
pub mod modal_sensitivity;
pub mod simulate;
pub mod support_motion;
