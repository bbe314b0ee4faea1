//! Orthotropic material under the Mindlin plane-stress assumption
//! (paper eq. 7–9).
//!
//! In the material frame (1, 2, 3), with 3 normal to the shell lamina and
//! engineering strains ordered `{ε1 ε2 ε3 γ12 γ23 γ13}` like eq. (5):
//!
//! ```text
//!        | Q11 Q12 0  0    0       0     |      Q11 = E1 / (1 - ν12 ν21)
//!        | Q12 Q22 0  0    0       0     |      Q22 = E2 / (1 - ν12 ν21)
//!  E'  = | 0   0   0  0    0       0     |      Q12 = ν12 E2 / (1 - ν12 ν21)
//!        | 0   0   0  G12  0       0     |      ν21 = ν12 E2 / E1
//!        | 0   0   0  0    k G23   0     |      k   = shear correction (5/6)
//!        | 0   0   0  0    0       k G13 |
//! ```
//!
//! σ3 = 0 (plane stress), so the ε3 row and column vanish. The transform of
//! eq. (8), `E = Tᵀ E' T`, is applied by evaluating strains directly in the
//! material frame at each quadrature point (see `shell`).

use serde::{Deserialize, Serialize};
use thiserror::Error;

#[derive(Debug, Clone, PartialEq, Error)]
pub enum MaterialError {
    #[error("{name} must be finite and positive, got {value}")]
    NotPositive { name: &'static str, value: f64 },
    #[error("nu12 = {nu12} violates 1 - nu12·nu21 > 0 (|nu12| must be below sqrt(e1/e2) = {limit})")]
    NotPositiveDefinite { nu12: f64, limit: f64 },
    #[error("shear_correction must lie in (0, 1], got {0}")]
    ShearCorrection(f64),
    #[error("angle must be finite, got {0}")]
    Angle(f64),
}

/// A validated orthotropic, linear-elastic material.
#[derive(Debug, Clone, PartialEq)]
pub struct OrthotropicMaterial {
    e1: f64,
    e2: f64,
    g12: f64,
    g13: f64,
    g23: f64,
    nu12: f64,
    density: f64,
    angle_rad: f64,
    shear_correction: f64,
}

/// Inputs of [`OrthotropicMaterial::new`]: also the configuration's
/// `[model.material]` table, key for key (unknown keys are refused).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OrthotropicParameters {
    pub e1: f64,
    pub e2: f64,
    pub g12: f64,
    pub g13: f64,
    pub g23: f64,
    pub nu12: f64,
    pub density: f64,
    /// Angle of material axis 1 from the `ξ` tangent, about the normal, in
    /// degrees (default 0).
    #[serde(default)]
    pub angle_deg: f64,
    /// Transverse shear correction factor, 5/6 for a homogeneous section
    /// (the default).
    #[serde(default = "default_shear_correction")]
    pub shear_correction: f64,
}

fn default_shear_correction() -> f64 {
    5.0 / 6.0
}

impl OrthotropicMaterial {
    pub fn new(p: OrthotropicParameters) -> Result<Self, MaterialError> {
        for (name, value) in [
            ("e1", p.e1),
            ("e2", p.e2),
            ("g12", p.g12),
            ("g13", p.g13),
            ("g23", p.g23),
            ("density", p.density),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(MaterialError::NotPositive { name, value });
            }
        }
        let limit = (p.e1 / p.e2).sqrt();
        if !(p.nu12.is_finite() && p.nu12.abs() < limit) {
            return Err(MaterialError::NotPositiveDefinite { nu12: p.nu12, limit });
        }
        if !(p.shear_correction > 0.0 && p.shear_correction <= 1.0) {
            return Err(MaterialError::ShearCorrection(p.shear_correction));
        }
        if !p.angle_deg.is_finite() {
            return Err(MaterialError::Angle(p.angle_deg));
        }
        Ok(Self {
            e1: p.e1,
            e2: p.e2,
            g12: p.g12,
            g13: p.g13,
            g23: p.g23,
            nu12: p.nu12,
            density: p.density,
            angle_rad: p.angle_deg.to_radians(),
            shear_correction: p.shear_correction,
        })
    }

    /// Isotropic material: `G = E / (2 (1 + ν))` in every plane.
    pub fn isotropic(e: f64, nu: f64, density: f64) -> Result<Self, MaterialError> {
        let g = e / (2.0 * (1.0 + nu));
        Self::new(OrthotropicParameters {
            e1: e,
            e2: e,
            g12: g,
            g13: g,
            g23: g,
            nu12: nu,
            density,
            angle_deg: 0.0,
            shear_correction: 5.0 / 6.0,
        })
    }

    pub fn density(&self) -> f64 {
        self.density
    }

    pub fn angle_rad(&self) -> f64 {
        self.angle_rad
    }

    pub fn e1(&self) -> f64 {
        self.e1
    }
    pub fn e2(&self) -> f64 {
        self.e2
    }
    pub fn g12(&self) -> f64 {
        self.g12
    }
    pub fn g13(&self) -> f64 {
        self.g13
    }
    pub fn g23(&self) -> f64 {
        self.g23
    }
    pub fn nu12(&self) -> f64 {
        self.nu12
    }
    pub fn shear_correction(&self) -> f64 {
        self.shear_correction
    }

    /// `ν21 = ν12 E2 / E1` (reciprocity of the compliance matrix).
    pub fn nu21(&self) -> f64 {
        self.nu12 * self.e2 / self.e1
    }

    /// Eq. (9): the 6×6 plane-stress matrix `E'` in the material frame.
    pub fn local_matrix(&self) -> [[f64; 6]; 6] {
        let den = 1.0 - self.nu12 * self.nu21();
        let mut e = [[0.0; 6]; 6];
        e[0][0] = self.e1 / den;
        e[1][1] = self.e2 / den;
        e[0][1] = self.nu12 * self.e2 / den;
        e[1][0] = e[0][1];
        e[3][3] = self.g12;
        e[4][4] = self.shear_correction * self.g23;
        e[5][5] = self.shear_correction * self.g13;
        e
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn isotropic_matrix_matches_closed_form() {
        let m = OrthotropicMaterial::isotropic(210e9, 0.3, 7850.0).unwrap();
        let e = m.local_matrix();
        let c = 210e9 / (1.0 - 0.09);
        assert!((e[0][0] - c).abs() < 1e-6 * c);
        assert!((e[0][1] - 0.3 * c).abs() < 1e-6 * c);
        assert!((e[3][3] - 210e9 / 2.6).abs() < 1e-3);
        assert!((e[4][4] - 5.0 / 6.0 * 210e9 / 2.6).abs() < 1e-3);
    }

    #[test]
    fn rejects_non_physical_values() {
        let ok = OrthotropicParameters {
            e1: 5.5e9,
            e2: 9.6e8,
            g12: 4.3e8,
            g13: 4.3e8,
            g23: 4.3e8,
            nu12: 0.3,
            density: 975.0,
            angle_deg: 0.0,
            shear_correction: 5.0 / 6.0,
        };
        assert!(OrthotropicMaterial::new(ok).is_ok());
        assert_eq!(
            OrthotropicMaterial::new(OrthotropicParameters { e2: -1.0, ..ok }),
            Err(MaterialError::NotPositive {
                name: "e2",
                value: -1.0
            })
        );
        assert!(matches!(
            OrthotropicMaterial::new(OrthotropicParameters { nu12: 3.0, ..ok }),
            Err(MaterialError::NotPositiveDefinite { .. })
        ));
        assert!(OrthotropicMaterial::new(OrthotropicParameters {
            shear_correction: 0.0,
            ..ok
        })
        .is_err());
    }
}
