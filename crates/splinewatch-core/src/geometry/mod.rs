//! The geometry of B-spline surfaces: where the model's shapes come from.
//!
//! May import: `linalg` (nothing else of the crate).
//!
//! - [`knots`]: validated clamped knot vectors, basis values and derivatives, knot insertion (eq. 1);
//! - [`surface`]: tensor-product B-spline surfaces, interpolation at Greville points, refinement (eq. 1);
//! - [`swept`]: a section segment swept along an interpolated centreline (curved decks);
//! - [`quadrature`]: Gauss–Legendre rules;
//! - [`vec3`]: small 3-vector helpers.

pub mod knots;
pub mod quadrature;
pub mod surface;
pub mod swept;
pub mod vec3;
