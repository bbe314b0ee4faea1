//! The TOML configuration: parsed with serde (unknown keys rejected), then
//! validated into the core crate's types. Every error names the key path.
//!
//! Physics (`[model.geometry]`, `[model.material]`, `[[model.springs]]`,
//! `[[model.constraints]]`) is kept apart from discretisation
//! (`[model.discretization]`); see README.md for every key.

use serde::Deserialize;
use splinewatch_core::constraints::{Edge, EdgeConstraint, SupportKind};
use splinewatch_core::knots::KnotVector;
use splinewatch_core::material::{OrthotropicMaterial, OrthotropicParameters};
use splinewatch_core::model::ShellModel;
use splinewatch_core::shell::Shell;
use splinewatch_core::springs::{Face, SpringDirection, SpringField};
use splinewatch_core::surface::Direction;
use std::fmt::Display;
use thiserror::Error;

/// A configuration error: the key path and what is wrong with it.
#[derive(Debug, Error)]
#[error("config: {path}: {message}")]
pub struct ConfigError {
    pub path: String,
    pub message: String,
}

fn err(path: impl Into<String>, message: impl Display) -> ConfigError {
    ConfigError {
        path: path.into(),
        message: message.to_string(),
    }
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Config {
    pub structure: StructureConfig,
    pub model: ModelConfig,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StructureConfig {
    /// Identifier of the monitored structure; also the default zenoh/MCAP prefix
    /// `bridge/<name>`.
    pub name: String,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelConfig {
    pub geometry: GeometryConfig,
    pub discretization: DiscretizationConfig,
    pub material: MaterialConfig,
    #[serde(default)]
    pub springs: Vec<SpringConfig>,
    #[serde(default)]
    pub constraints: Vec<ConstraintConfig>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum GeometryConfig {
    /// `[0, length] × [0, width]` in the xy plane, x along ξ.
    RectangularPlate { length: f64, width: f64, thickness: f64 },
    /// Circular-cylindrical panel, axis along x (ξ), arc along η.
    CylindricalPanel {
        length: f64,
        radius: f64,
        angle_deg: f64,
        thickness: f64,
    },
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DiscretizationConfig {
    /// B-spline degrees `[p, q]` along ξ and η.
    pub degree: [usize; 2],
    /// Control points `[m, n]` along ξ and η (uniform clamped knots).
    pub control_points: [usize; 2],
    /// Knots inserted into the net afterwards (h-refinement), along ξ.
    #[serde(default)]
    pub insert_knots_xi: Vec<f64>,
    /// Knots inserted along η.
    #[serde(default)]
    pub insert_knots_eta: Vec<f64>,
}

fn default_shear_correction() -> f64 {
    5.0 / 6.0
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialConfig {
    pub e1: f64,
    pub e2: f64,
    pub g12: f64,
    pub g13: f64,
    pub g23: f64,
    pub nu12: f64,
    pub density: f64,
    #[serde(default)]
    pub angle_deg: f64,
    #[serde(default = "default_shear_correction")]
    pub shear_correction: f64,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(untagged)]
pub enum DirectionConfig {
    /// `"x"`, `"y"`, `"z"` or `"normal"`.
    Named(String),
    /// A vector in the global frame (normalised on load).
    Vector([f64; 3]),
}

#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum FaceConfig {
    Bottom,
    #[serde(alias = "mid")]
    Middle,
    Top,
}

fn default_true() -> bool {
    true
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpringConfig {
    pub name: String,
    pub direction: DirectionConfig,
    pub surface: FaceConfig,
    pub knots_xi: Vec<f64>,
    pub degree_xi: usize,
    pub knots_eta: Vec<f64>,
    pub degree_eta: usize,
    /// Coefficients κ in N/m³, η fastest.
    pub stiffness: Vec<f64>,
    /// `[lower, upper]` for every coefficient when updating.
    pub bounds: Option<[f64; 2]>,
    /// Whether the updating identifies these coefficients.
    #[serde(default = "default_true")]
    pub update: bool,
}

#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum EdgeConfig {
    Xi0,
    Xi1,
    Eta0,
    Eta1,
}

#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum SupportConfig {
    SimplySupported,
    ShearDiaphragm,
    Clamped,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConstraintConfig {
    pub edge: EdgeConfig,
    pub kind: SupportConfig,
}

impl Config {
    /// Parses TOML text; `origin` names the source in errors.
    pub fn from_toml(text: &str) -> Result<Self, ConfigError> {
        let config: Config = toml::from_str(text).map_err(|e| {
            let path = e
                .span()
                .map(|s| line_of(text, s.start))
                .unwrap_or_else(|| "(document)".into());
            err(path, e.message())
        })?;
        config.validate_names()?;
        Ok(config)
    }

    fn validate_names(&self) -> Result<(), ConfigError> {
        if self.structure.name.trim().is_empty() {
            return Err(err("structure.name", "must not be empty"));
        }
        let mut seen = std::collections::BTreeSet::new();
        for (i, s) in self.model.springs.iter().enumerate() {
            let valid = !s.name.is_empty()
                && s.name
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
            if !valid {
                return Err(err(
                    format!("model.springs[{i}].name"),
                    format!("{:?} must be non-empty ASCII letters, digits, '_' or '-'", s.name),
                ));
            }
            if !seen.insert(s.name.as_str()) {
                return Err(err(
                    format!("model.springs[{i}].name"),
                    format!("{:?} is used twice", s.name),
                ));
            }
        }
        Ok(())
    }

    /// Validates the model section into a [`ShellModel`].
    pub fn build_model(&self) -> Result<ShellModel, ConfigError> {
        let m = &self.model;
        let d = &m.discretization;
        let mut shell = match m.geometry {
            GeometryConfig::RectangularPlate {
                length,
                width,
                thickness,
            } => Shell::rectangular_plate(length, width, thickness, d.degree, d.control_points),
            GeometryConfig::CylindricalPanel {
                length,
                radius,
                angle_deg,
                thickness,
            } => Shell::cylindrical_panel(
                length,
                radius,
                angle_deg.to_radians(),
                thickness,
                d.degree,
                d.control_points,
            ),
        }
        .map_err(|e| err("model.geometry / model.discretization", e))?;
        for (key, direction, knots) in [
            ("insert_knots_xi", Direction::Xi, &d.insert_knots_xi),
            ("insert_knots_eta", Direction::Eta, &d.insert_knots_eta),
        ] {
            for (i, &u) in knots.iter().enumerate() {
                shell = shell.insert_knot(direction, u).map_err(|e| {
                    err(
                        format!("model.discretization.{key}[{i}]"),
                        format!("cannot insert {u}: {e} (knots must lie strictly inside (0, 1))"),
                    )
                })?;
            }
        }
        let mat = &m.material;
        let material = OrthotropicMaterial::new(OrthotropicParameters {
            e1: mat.e1,
            e2: mat.e2,
            g12: mat.g12,
            g13: mat.g13,
            g23: mat.g23,
            nu12: mat.nu12,
            density: mat.density,
            angle_deg: mat.angle_deg,
            shear_correction: mat.shear_correction,
        })
        .map_err(|e| err("model.material", e))?;
        let springs = m
            .springs
            .iter()
            .enumerate()
            .map(|(i, s)| build_spring(i, s))
            .collect::<Result<Vec<_>, _>>()?;
        let constraints = m
            .constraints
            .iter()
            .map(|c| EdgeConstraint {
                edge: match c.edge {
                    EdgeConfig::Xi0 => Edge::Xi0,
                    EdgeConfig::Xi1 => Edge::Xi1,
                    EdgeConfig::Eta0 => Edge::Eta0,
                    EdgeConfig::Eta1 => Edge::Eta1,
                },
                kind: match c.kind {
                    SupportConfig::SimplySupported => SupportKind::SimplySupported,
                    SupportConfig::ShearDiaphragm => SupportKind::ShearDiaphragm,
                    SupportConfig::Clamped => SupportKind::Clamped,
                },
            })
            .collect();
        let model = ShellModel {
            shell,
            material,
            springs,
            constraints,
        };
        // Surface the spring/shell compatibility errors here, with their key.
        for (i, s) in model.springs.iter().enumerate() {
            s.coefficient_matrices(&model.shell)
                .map_err(|e| err(format!("model.springs[{i}]"), e))?;
        }
        Ok(model)
    }
}

fn build_spring(i: usize, s: &SpringConfig) -> Result<SpringField, ConfigError> {
    let key = |k: &str| format!("model.springs[{i}].{k}");
    let xi = KnotVector::new(s.knots_xi.clone(), s.degree_xi).map_err(|e| err(key("knots_xi"), e))?;
    let eta = KnotVector::new(s.knots_eta.clone(), s.degree_eta).map_err(|e| err(key("knots_eta"), e))?;
    let direction = match &s.direction {
        DirectionConfig::Named(n) => match n.as_str() {
            "x" => SpringDirection::Fixed([1.0, 0.0, 0.0]),
            "y" => SpringDirection::Fixed([0.0, 1.0, 0.0]),
            "z" => SpringDirection::Fixed([0.0, 0.0, 1.0]),
            "normal" => SpringDirection::Normal,
            other => {
                return Err(err(
                    key("direction"),
                    format!("{other:?} is not one of \"x\", \"y\", \"z\", \"normal\" or a 3-vector"),
                ))
            }
        },
        DirectionConfig::Vector(v) => SpringDirection::fixed(*v).map_err(|e| err(key("direction"), e))?,
    };
    let face = match s.surface {
        FaceConfig::Bottom => Face::Bottom,
        FaceConfig::Middle => Face::Middle,
        FaceConfig::Top => Face::Top,
    };
    if let Some([lo, hi]) = s.bounds {
        if !(lo.is_finite() && hi.is_finite() && lo >= 0.0 && lo < hi) {
            return Err(err(
                key("bounds"),
                format!("[{lo}, {hi}] must satisfy 0 <= lower < upper"),
            ));
        }
        if let Some((j, k)) = s.stiffness.iter().enumerate().find(|(_, &k)| !(k >= lo && k <= hi)) {
            return Err(err(
                key("stiffness"),
                format!("coefficient {} = {k} lies outside bounds [{lo}, {hi}]", j + 1),
            ));
        }
    }
    SpringField::new(xi, eta, s.stiffness.clone(), direction, face).map_err(|e| err(key("stiffness"), e))
}

/// "line L, column C" of a byte offset, for parse errors.
fn line_of(text: &str, offset: usize) -> String {
    let before = &text[..offset.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    format!("line {line}, column {column}")
}

#[cfg(test)]
mod tests {
    use super::*;

    const SINELLO: &str = include_str!("../config/sinello.toml");

    fn error_of(edit: impl Fn(&str) -> String) -> String {
        let text = edit(SINELLO);
        match Config::from_toml(&text).and_then(|c| c.build_model().map(|_| c)) {
            Ok(_) => panic!("expected an error"),
            Err(e) => e.to_string(),
        }
    }

    #[test]
    fn bundled_config_builds() {
        let model = Config::from_toml(SINELLO).unwrap().build_model().unwrap();
        assert_eq!(model.shell.control_point_count(), 65);
        assert_eq!(model.springs.len(), 2);
    }

    #[test]
    fn errors_name_the_key() {
        let e = error_of(|t| t.replace("thickness = 1.6", "thickness = -1.6"));
        assert!(
            e.contains("model.geometry") && e.contains("thickness") && e.contains("-1.6"),
            "{e}"
        );
        let e = error_of(|t| {
            t.replacen(
                "knots_eta = [0.0, 0.0, 0.0, 0.5, 1.0, 1.0, 1.0]",
                "knots_eta = [0.0, 0.0, 0.0, 0.7, 0.5, 1.0, 1.0, 1.0]",
                1,
            )
        });
        assert!(
            e.contains("model.springs[0].knots_eta") && e.contains("not non-decreasing at index 4"),
            "{e}"
        );
        let e = error_of(|t| {
            t.replacen(
                "stiffness = [0.4e9, 1.5e9, 1.8e9, 0.6e9]",
                "stiffness = [0.4e9, 1.5e9, 1.8e9]",
                1,
            )
        });
        assert!(
            e.contains("model.springs[0].stiffness") && e.contains("3 stiffness coefficients given"),
            "{e}"
        );
        let e = error_of(|t| t.replace("[structure]", "[structure]\ncolour = \"red\""));
        // toml reports the span of the table holding the unknown key.
        assert!(e.contains("unknown field `colour`") && e.contains("line 9"), "{e}");
        let e = error_of(|t| t.replace("nu12 = 0.3", "nu12 = 3.0"));
        assert!(e.contains("model.material") && e.contains("nu12"), "{e}");
        let e = error_of(|t| t.replacen("direction = \"z\"", "direction = \"up\"", 1));
        assert!(e.contains("model.springs[0].direction"), "{e}");
        let e = error_of(|t| t.replace("control_points = [13, 5]", "control_points = [13, 4]"));
        assert!(
            e.contains("model.geometry / model.discretization") && e.contains("4 basis functions"),
            "{e}"
        );
        let e = error_of(|t| t.replace("name = \"east\"", "name = \"west\""));
        assert!(e.contains("model.springs[1].name") && e.contains("used twice"), "{e}");
        let e = error_of(|t| t.replacen("bounds = [1.0e7, 5.0e9]", "bounds = [1.0e7, 1.0e9]", 1));
        assert!(e.contains("outside bounds"), "{e}");
        let e = error_of(|t| t.replace("knots_xi = [0.97, 1.0]", "knots_xi = [0.97, 1.2]"));
        assert!(
            e.contains("model.springs[1]") && e.contains("not inside the shell"),
            "{e}"
        );
    }

    #[test]
    fn knot_insertion_refines_the_net() {
        let text = SINELLO.replace(
            "control_points = [13, 5]",
            "control_points = [13, 5]\ninsert_knots_eta = [0.25, 0.75]",
        );
        let model = Config::from_toml(&text).unwrap().build_model().unwrap();
        assert_eq!(model.shell.surface().net_size(), (13, 7));
        let e = error_of(|t| {
            t.replace(
                "control_points = [13, 5]",
                "control_points = [13, 5]\ninsert_knots_xi = [1.5]",
            )
        });
        assert!(e.contains("model.discretization.insert_knots_xi[0]"), "{e}");
    }
}
