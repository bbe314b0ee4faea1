//! `[model]` and `[[sensors]]`: the shell, its material, springs,
//! constraints, damping curve and measurement points, built into core types.

use super::loss_factor::LossFactorConfig;
use super::materials::MaterialConfig;
use super::patches::{
    build_patches, default_true, face_tau, locate, patch_index, BearingConfig, FaceConfig, MassConfig, PatchConfig,
};
use super::{err, Config, ConfigError};
use serde::{Deserialize, Serialize};
use splinewatch_core::geometry::knots::KnotVector;
use splinewatch_core::geometry::surface::Direction;
use splinewatch_core::model::bearings::{Bearing, PointMass};
use splinewatch_core::model::constraints::{Edge, EdgeConstraint, SupportKind};
use splinewatch_core::model::damping::DampingCurve;
use splinewatch_core::model::joints::{find_joints, find_overlap};
use splinewatch_core::model::material::{OrthotropicMaterial, OrthotropicParameters};
use splinewatch_core::model::patch::Patch;
use splinewatch_core::model::shell::{Shell, ShellError};
use splinewatch_core::model::springs::{Face, SpringDirection, SpringField};
use splinewatch_core::model::stiffness_field::{StiffnessField, StiffnessScale};
use splinewatch_core::model::BridgeModel;
use splinewatch_core::response::frf::SensorPoint;
use std::collections::BTreeMap;

mod build;
mod member_stiffness;
mod sensors;
pub(crate) mod substructure;
#[cfg(test)]
mod tests;

/// Largest control net accepted (5 dofs each): the sparse path
/// (`modes --cutoff`, `matrices`) holds 200 000 dofs in a few GB.
pub const MAX_CONTROL_POINTS: usize = 40_000;

/// Largest control net of the dense path (FRFs, updating, `modes` without
/// `--cutoff`): it stores n_dof² matrices, and the dense eigen-solve of
/// 10 000 dofs already takes minutes.
pub const MAX_DENSE_CONTROL_POINTS: usize = 2000;

#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ModelConfig {
    /// One patch named `"deck"` (with `discretization` and `material`), or
    /// [`ModelConfig::patches`].
    pub geometry: Option<GeometryConfig>,
    pub discretization: Option<DiscretizationConfig>,
    #[schemars(with = "Option<super::schema::OrthotropicParametersDef>")]
    pub material: Option<OrthotropicParameters>,
    /// `[[model.patches]]`: a deck of many patches.
    #[serde(default)]
    pub patches: Vec<PatchConfig>,
    /// `[model.materials.<name>]`, named by the patches and the beams.
    #[serde(default)]
    pub materials: BTreeMap<String, MaterialConfig>,
    /// Patches whose edge lies within this distance (m) of another patch's
    /// mid-surface are joined rigidly there.
    #[serde(default = "default_joint_tolerance")]
    pub joint_tolerance: f64,
    /// The joints' dimensionless penalty factor (see `model::joints`).
    #[serde(default = "default_joint_penalty")]
    pub joint_penalty: f64,
    #[serde(default)]
    pub bearings: Vec<BearingConfig>,
    #[serde(default)]
    pub masses: Vec<MassConfig>,
    #[serde(default)]
    pub springs: Vec<SpringConfig>,
    #[serde(default)]
    pub stiffness_fields: Vec<StiffnessFieldConfig>,
    #[serde(default)]
    pub constraints: Vec<ConstraintConfig>,
    /// `[[model.beams]]`: columns, piers (Timoshenko beam members).
    #[serde(default)]
    pub beams: Vec<substructure::BeamConfig>,
    /// `[[model.rigid]]`: rigid bodies (bent caps, diaphragms).
    #[serde(default)]
    pub rigid: Vec<substructure::RigidConfig>,
    /// `[[model.supports]]`: springs along patch edges in six components
    /// (abutments, embankments).
    #[serde(default)]
    pub supports: Vec<substructure::SupportConfig>,
    pub damping: Option<DampingConfig>,
    /// `[model.solver]`: every mode (dense) or the modes below a cut-off
    /// (sparse, with the residual of the rest).
    #[serde(default)]
    pub solver: SolverConfig,
}

impl Default for ModelConfig {
    /// No deck.
    fn default() -> Self {
        Self {
            geometry: None,
            discretization: None,
            material: None,
            patches: Vec::new(),
            materials: BTreeMap::new(),
            joint_tolerance: default_joint_tolerance(),
            joint_penalty: default_joint_penalty(),
            bearings: Vec::new(),
            masses: Vec::new(),
            springs: Vec::new(),
            stiffness_fields: Vec::new(),
            constraints: Vec::new(),
            beams: Vec::new(),
            rigid: Vec::new(),
            supports: Vec::new(),
            damping: None,
            solver: SolverConfig::default(),
        }
    }
}

fn default_joint_tolerance() -> f64 {
    1e-3
}

fn default_joint_penalty() -> f64 {
    splinewatch_core::model::joints::DEFAULT_PENALTY
}

/// `[model.solver] modes`: which eigen-solution the FRFs and updates use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum ModesChoice {
    /// Every mode of the dense model (exact modal sums; small models).
    All,
    /// The modes below `cutoff_hz` by shift-invert Lanczos on the sparse
    /// model, the rest as residual flexibility.
    Truncated,
    /// `truncated` above [`AUTO_TRUNCATED_CONTROL_POINTS`], else `all`.
    #[default]
    Auto,
}

/// Above this many control points over all patches (2 000 dofs: a dense eigen-solve takes
/// about a second there and grows as n³, the sparse one about linearly)
/// `modes = "auto"` truncates.
pub const AUTO_TRUNCATED_CONTROL_POINTS: usize = 400;

/// `[model.solver]`.
#[derive(Debug, Clone, Default, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SolverConfig {
    #[serde(default)]
    pub modes: ModesChoice,
    /// Modes up to this frequency are solved when truncating; default:
    /// twice the top of the widest analysis band (`updating.band`,
    /// `oma.band`, `frf.band`).
    pub cutoff_hz: Option<f64>,
}

/// `[model.damping]`: the B-spline ζ(f) of eq. (29).
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DampingConfig {
    pub degree: usize,
    /// Start values γ_z; their count is n_z.
    pub coefficients: Vec<f64>,
    /// Band [f_start, f_end] in Hz over which the curve is defined.
    pub f_start: f64,
    pub f_end: f64,
    /// `[lower, upper]` for every γ_z when updating.
    pub bounds: Option<[f64; 2]>,
    #[serde(default = "default_true")]
    pub update: bool,
}

/// A measurement point: parametric `xi`/`eta` or physical `x`/`y`.
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SensorConfig {
    pub name: String,
    /// The patch `xi`/`eta` (or the nearest point to `x, y, z`) is on.
    pub patch: Option<String>,
    pub xi: Option<f64>,
    pub eta: Option<f64>,
    pub x: Option<f64>,
    pub y: Option<f64>,
    pub z: Option<f64>,
    pub direction: DirectionConfig,
    /// What is measured there: one of, or a list of, "acceleration",
    /// "force", "displacement", "velocity".
    #[serde(default = "default_quantity")]
    pub quantity: QuantityList,
    /// Face the sensor sits on (default: the mid-surface).
    #[serde(default = "default_face")]
    pub surface: FaceConfig,
    /// m: the sensor's distance from the patch's mid-surface along its
    /// normal (the director: up on a deck whose ξ, η run along x, y),
    /// instead of `surface`: a girder's soffit below the deck slab, a
    /// barrier's top. The point follows the section rigidly.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub offset: Option<f64>,
    /// The node number of this measurement point in universal files
    /// (dataset 58 response/reference nodes; `update --frf FILE.uff`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub uff_node: Option<i64>,
    /// A ground sensor: the support group whose ground acceleration it
    /// measures along `direction` (an input; no position). Ground sensors
    /// are listed after the deck's once loaded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub support: Option<String>,
    /// A sensor on a beam: the `[[model.beams]]` member it is fixed to, at
    /// `x, y, z` (on its axis, its face or a bracket: the nearest axis
    /// point carries it rigidly).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub beam: Option<String>,
}

fn default_quantity() -> QuantityList {
    QuantityList::One("acceleration".into())
}

fn default_face() -> FaceConfig {
    FaceConfig::Middle
}

#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(untagged)]
pub enum QuantityList {
    One(String),
    Many(Vec<String>),
}

impl QuantityList {
    pub fn as_slice(&self) -> &[String] {
        match self {
            QuantityList::One(q) => std::slice::from_ref(q),
            QuantityList::Many(v) => v,
        }
    }
}

#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
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

#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
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

#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(untagged)]
pub enum DirectionConfig {
    /// `"x"`, `"y"`, `"z"`, `"-x"`, `"-y"`, `"-z"` or `"normal"`.
    Named(String),
    /// A vector in the global frame (normalised on load).
    Vector([f64; 3]),
}

impl DirectionConfig {
    /// The unit vector of a named axis, `"x"` … `"-z"` (`None` for
    /// `"normal"`, a vector or an unknown name).
    pub fn axis_vector(&self) -> Option<[f64; 3]> {
        let Self::Named(name) = self else { return None };
        let (sign, axis) = match name.strip_prefix('-') {
            Some(axis) => (-1.0, axis),
            None => (1.0, name.as_str()),
        };
        let a = ["x", "y", "z"].iter().position(|n| *n == axis)?;
        let mut v = [0.0; 3];
        v[a] = sign;
        Some(v)
    }

    /// The direction as a unit vector in the global frame: a named axis,
    /// or a vector normalised; z for `"normal"` (which depends on where on
    /// the surface it is taken) and for a zero vector (refused on load).
    pub fn unit_vector(&self) -> [f64; 3] {
        let z = [0.0, 0.0, 1.0];
        match self {
            Self::Vector(v) => splinewatch_core::geometry::vec3::normalize(*v).unwrap_or(z),
            named => named.axis_vector().unwrap_or(z),
        }
    }

    /// The global axis (0 = x) the direction is nearest to.
    pub fn dominant_axis(&self) -> usize {
        let v = self.unit_vector();
        (0..3).max_by(|&a, &b| v[a].abs().total_cmp(&v[b].abs())).unwrap_or(2)
    }
}

#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SpringConfig {
    pub name: String,
    /// The patch it lies on (default: the only patch).
    pub patch: Option<String>,
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
    /// The support group whose ground the springs connect to (default "ground").
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub support: Option<String>,
    /// The support's loss factor η (hysteretic damping: 0.1 = 10 %): modes
    /// whose strain energy sits in it are damped more, by
    /// `½ η × (its share of the mode's strain energy)` on top of
    /// `[model.damping]`'s ζ(f). A number is held; `{ value, bounds }` is
    /// updated (parameter `<name>.eta`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub loss_factor: Option<LossFactorConfig>,
}

/// `[[model.stiffness_fields]]`: a B-spline multiplier θ(ξ, η) of the deck's
/// material stiffness over its own clamped knot vectors (1.0 = nominal).
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct StiffnessFieldConfig {
    pub name: String,
    /// The patch it multiplies (default: the only patch).
    pub patch: Option<String>,
    pub knots_xi: Vec<f64>,
    pub degree_xi: usize,
    pub knots_eta: Vec<f64>,
    pub degree_eta: usize,
    /// What θ multiplies: `"all"` (membrane, bending and shear together),
    /// `"membrane"`, `"bending"` or `"shear"`.
    #[serde(default = "default_scales")]
    pub scales: String,
    /// Start values θ, η fastest; default 1.0 everywhere.
    pub coefficients: Option<Vec<f64>>,
    /// `[lower, upper]` for every coefficient when updating.
    pub bounds: Option<[f64; 2]>,
    #[serde(default = "default_true")]
    pub update: bool,
    /// Another field's name, just before this one in
    /// `[[model.stiffness_fields]]` (or before fields tied to it): this one
    /// takes its updating parameters (one modulus over several patches).
    /// Both are updated, with as many coefficients, the same start values
    /// and `scales`; it gives no `bounds` or `loss_factor` of its own.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tie: Option<String>,
    /// The loss factor η of the part of the patch's stiffness the field
    /// scales (a cracked or jointed deck's own hysteresis): modes whose
    /// strain energy sits in it are damped by `½ η × its share`, on top of
    /// `[model.damping]`'s ζ(f). A number is held; `{ value, bounds }` is
    /// updated (parameter `<name>.eta`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub loss_factor: Option<LossFactorConfig>,
}

impl crate::config::tie::Tied for StiffnessFieldConfig {
    fn name(&self) -> &str {
        &self.name
    }

    fn tie(&self) -> Option<&str> {
        self.tie.as_deref()
    }
}

impl StiffnessFieldConfig {
    /// Why `self` cannot be tied to `leader`, if it cannot.
    pub(crate) fn tie_mismatch(&self, leader: &StiffnessFieldConfig) -> Option<String> {
        let start = |f: &StiffnessFieldConfig| {
            f.coefficients
                .clone()
                .unwrap_or_else(|| vec![1.0; f.coefficient_count()])
        };
        if self.bounds.is_some() {
            Some(format!(
                "a tied field takes the bounds of {:?}: remove its own",
                leader.name
            ))
        } else if !(self.update && leader.update) {
            Some(format!(
                "a tied field and {:?} are both updated (update = true)",
                leader.name
            ))
        } else if self.coefficient_count() != leader.coefficient_count() || start(self) != start(leader) {
            Some(format!(
                "a tied field has as many coefficients as {:?}, with the same start values",
                leader.name
            ))
        } else if self.scales != leader.scales {
            Some(format!("a tied field scales what {:?} scales", leader.name))
        } else {
            None
        }
    }

    /// Coefficients the clamped knot vectors define (as
    /// `KnotVector::basis_count`; the vectors are validated by `build_model`),
    /// or the count of `coefficients` when given.
    pub fn coefficient_count(&self) -> usize {
        let n = |knots: &[f64], degree: usize| knots.len().saturating_sub(degree + 1);
        self.coefficients.as_ref().map_or_else(
            || n(&self.knots_xi, self.degree_xi) * n(&self.knots_eta, self.degree_eta),
            Vec::len,
        )
    }
}

fn default_scales() -> String {
    "all".into()
}

#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum EdgeConfig {
    Xi0,
    Xi1,
    Eta0,
    Eta1,
}

impl From<EdgeConfig> for Edge {
    fn from(e: EdgeConfig) -> Self {
        match e {
            EdgeConfig::Xi0 => Edge::Xi0,
            EdgeConfig::Xi1 => Edge::Xi1,
            EdgeConfig::Eta0 => Edge::Eta0,
            EdgeConfig::Eta1 => Edge::Eta1,
        }
    }
}

#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum SupportConfig {
    SimplySupported,
    ShearDiaphragm,
    Clamped,
}

#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ConstraintConfig {
    pub edge: EdgeConfig,
    pub kind: SupportConfig,
    /// The patch whose edge is supported (default: the only patch).
    pub patch: Option<String>,
    /// The support group whose ground the edge follows (default "ground").
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub support: Option<String>,
}
