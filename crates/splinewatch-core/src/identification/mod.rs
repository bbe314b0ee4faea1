//! What the measurements say on their own: FRF estimates from forces and
//! responses, and output-only modal analysis.
//!
//! May import: `linalg` (identification needs no model).
//!
//! - [`welch`]: streaming cross spectra, H1/H2/Hv and coherence;
//! - [`oma`]: SSI-cov with stabilisation, clustering and uncertainty;
//! - [`srim`]: input–output identification (SRIM) on the same subspace model, stabilisation and uncertainty;
//! - [`transmissibility`]: multi-input H1 estimates with multiple coherence and the inputs' conditioning;
//! - [`realization`]: a stable state-space realization whose `B`, `D` fit a record, and its response to other inputs;
//! - [`resample`]: a record on another number of points over its span (Fourier);
//! - [`lscf`]: the poles common to several frequency response functions (least-squares complex frequency);
//! - [`pole_residue`]: a weighted least-squares (maximum-likelihood) fit of shared poles and residues to several functions, with the poles' standard deviations.

pub mod lscf;
pub mod oma;
pub mod pole_residue;
pub mod realization;
pub mod resample;
pub mod srim;
#[cfg(test)]
mod test_noise;
pub mod transmissibility;
pub mod welch;
