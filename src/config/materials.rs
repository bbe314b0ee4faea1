//! `[model.materials.<name>]`: a named material, isotropic (`young`,
//! `poisson`, `density`: patches and beams) or orthotropic (the
//! `[model.material]` keys: patches only).

use super::{err, ConfigError};
use serde::{Deserialize, Serialize};
use splinewatch_core::model::beam::BeamMaterial;
use splinewatch_core::model::material::{OrthotropicMaterial, OrthotropicParameters};

/// `[model.materials.<name>]`: either `young`, `poisson` and `density`
/// (isotropic, for patches and beams) or `e1`, `e2`, `g12`, `g13`, `g23`,
/// `nu12` and `density` (an orthotropic plate, for patches).
#[derive(Debug, Clone, Default, PartialEq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MaterialConfig {
    /// Young's modulus of an isotropic material (Pa).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub young: Option<f64>,
    /// Poisson's ratio of an isotropic material.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub poisson: Option<f64>,
    /// Young's modulus along material axis 1 (Pa).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub e1: Option<f64>,
    /// Young's modulus along material axis 2 (Pa).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub e2: Option<f64>,
    /// In-plane shear modulus (Pa).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub g12: Option<f64>,
    /// Transverse shear modulus, plane 1–3 (Pa).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub g13: Option<f64>,
    /// Transverse shear modulus, plane 2–3 (Pa).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub g23: Option<f64>,
    /// Poisson's ratio of an orthotropic plate.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub nu12: Option<f64>,
    /// Density (kg/m³).
    pub density: f64,
    /// Angle of material axis 1 from the ξ tangent, about the normal
    /// (degrees; patches; default 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub angle_deg: Option<f64>,
    /// Transverse shear correction factor of a patch (default 5/6).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shear_correction: Option<f64>,
}

impl MaterialConfig {
    fn orthotropic_keys(&self) -> [(&'static str, Option<f64>); 6] {
        [
            ("e1", self.e1),
            ("e2", self.e2),
            ("g12", self.g12),
            ("g13", self.g13),
            ("g23", self.g23),
            ("nu12", self.nu12),
        ]
    }

    /// The isotropic `(young, poisson)`, `None` for an orthotropic
    /// material; both kinds at once, or half of one, refused.
    fn isotropic_moduli(&self, key: &str) -> Result<Option<(f64, f64)>, ConfigError> {
        let orthotropic = self.orthotropic_keys();
        let given: Vec<&str> = orthotropic.iter().filter(|k| k.1.is_some()).map(|k| k.0).collect();
        match (self.young, self.poisson, given.is_empty()) {
            (Some(young), Some(poisson), true) => Ok(Some((young, poisson))),
            (None, None, false) => Ok(None),
            (Some(_), _, false) | (_, Some(_), false) => Err(err(
                key,
                format!("give young and poisson (isotropic) or e1, e2, g12, g13, g23 and nu12 (orthotropic), not both (found {})", given.join(", ")),
            )),
            (None, Some(_), true) => Err(err(format!("{key}.young"), "an isotropic material needs young and poisson")),
            (_, None, true) => Err(err(
                format!("{key}.poisson"),
                "give young and poisson (isotropic) or e1, e2, g12, g13, g23 and nu12 (orthotropic)",
            )),
        }
    }

    /// The patch material of this table (`key` names it in errors).
    pub fn plate(&self, key: &str) -> Result<OrthotropicMaterial, ConfigError> {
        let parameters = match self.isotropic_moduli(key)? {
            Some((young, poisson)) => {
                let g = young / (2.0 * (1.0 + poisson));
                OrthotropicParameters {
                    e1: young,
                    e2: young,
                    g12: g,
                    g13: g,
                    g23: g,
                    nu12: poisson,
                    density: self.density,
                    angle_deg: 0.0,
                    shear_correction: 5.0 / 6.0,
                }
            }
            None => {
                let value = |(name, v): (&str, Option<f64>)| {
                    v.ok_or_else(|| {
                        err(
                            format!("{key}.{name}"),
                            "an orthotropic material needs e1, e2, g12, g13, g23 and nu12",
                        )
                    })
                };
                let [e1, e2, g12, g13, g23, nu12] = self.orthotropic_keys();
                OrthotropicParameters {
                    e1: value(e1)?,
                    e2: value(e2)?,
                    g12: value(g12)?,
                    g13: value(g13)?,
                    g23: value(g23)?,
                    nu12: value(nu12)?,
                    density: self.density,
                    angle_deg: 0.0,
                    shear_correction: 5.0 / 6.0,
                }
            }
        };
        let parameters = OrthotropicParameters {
            angle_deg: self.angle_deg.unwrap_or(parameters.angle_deg),
            shear_correction: self.shear_correction.unwrap_or(parameters.shear_correction),
            ..parameters
        };
        OrthotropicMaterial::new(parameters).map_err(|e| err(key, e))
    }

    /// The beam material of this table: isotropic only.
    pub fn beam(&self, key: &str) -> Result<BeamMaterial, ConfigError> {
        let Some((young, poisson)) = self.isotropic_moduli(key)? else {
            return Err(err(
                key,
                "a beam needs an isotropic material: young, poisson and density",
            ));
        };
        if self.angle_deg.is_some() || self.shear_correction.is_some() {
            return Err(err(
                key,
                "angle_deg and shear_correction are a patch's: a beam's section gives its shear areas",
            ));
        }
        BeamMaterial::isotropic(young, poisson, self.density).map_err(|e| err(key, e))
    }
}
