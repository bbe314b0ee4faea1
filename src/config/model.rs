//! `[model]` and `[[sensors]]`: the shell, its material, springs,
//! constraints, damping curve and measurement points, built into core types.

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
use splinewatch_core::model::ShellModel;
use splinewatch_core::response::frf::SensorPoint;
use std::collections::BTreeMap;

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
    /// `[model.materials.<name>]`, named by the patches.
    #[serde(default)]
    #[schemars(with = "BTreeMap<String, super::schema::OrthotropicParametersDef>")]
    pub materials: BTreeMap<String, OrthotropicParameters>,
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
    /// The node number of this measurement point in universal files
    /// (dataset 58 response/reference nodes; `update --frf FILE.uff`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub uff_node: Option<i64>,
    /// A ground sensor: the support group whose ground acceleration it
    /// measures along `direction` (an input; no position). Ground sensors
    /// are listed after the deck's once loaded.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub support: Option<String>,
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
    /// `"x"`, `"y"`, `"z"` or `"normal"`.
    Named(String),
    /// A vector in the global frame (normalised on load).
    Vector([f64; 3]),
}

impl DirectionConfig {
    /// The global axis (0 = x) the direction is nearest to.
    pub fn dominant_axis(&self) -> usize {
        match self {
            Self::Named(n) if n == "x" => 0,
            Self::Named(n) if n == "y" => 1,
            Self::Vector(v) => (0..3).max_by(|&a, &b| v[a].abs().total_cmp(&v[b].abs())).unwrap_or(2),
            _ => 2,
        }
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
}

impl StiffnessFieldConfig {
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

impl Config {
    /// The cut-off when the model is truncated (`[model.solver]`), `None`
    /// for every mode.
    pub fn modal_cutoff_hz(&self) -> Result<Option<f64>, ConfigError> {
        let solver = &self.model.solver;
        let truncated = match solver.modes {
            ModesChoice::All => false,
            ModesChoice::Truncated => true,
            ModesChoice::Auto => {
                let patches = self.build_model_patches()?;
                let points: usize = patches.iter().map(|p| p.shell.control_point_count()).sum();
                points > AUTO_TRUNCATED_CONTROL_POINTS
            }
        };
        if !truncated {
            return Ok(None);
        }
        match solver.cutoff_hz {
            Some(f) if !(f.is_finite() && f > 0.0) => Err(err(
                "model.solver.cutoff_hz",
                format!("{f} must be a positive frequency in Hz"),
            )),
            Some(f) => Ok(Some(f)),
            None => {
                let top = [
                    self.updating.band.map(|b| b[1]),
                    self.oma().band.map(|b| b[1]),
                    Some(self.frf.band[1]),
                ]
                .into_iter()
                .flatten()
                .fold(0.0, f64::max);
                Ok(Some(2.0 * top))
            }
        }
    }

    /// Validates the model section into a [`ShellModel`].
    /// The model for the dense path: refuses a net above
    /// [`MAX_DENSE_CONTROL_POINTS`] with the way out.
    pub fn build_dense_model(&self) -> Result<ShellModel, ConfigError> {
        let model = self.build_model()?;
        let total = model.control_point_count();
        if total > MAX_DENSE_CONTROL_POINTS {
            let key = if self.model.patches.is_empty() {
                "model.discretization.control_points"
            } else {
                "model.patches"
            };
            return Err(err(
                key,
                format!(
                    "{total} control points: every mode (`[model.solver] modes = \"all\"`, `modes` without --cutoff) is solved densely for at most {MAX_DENSE_CONTROL_POINTS}; `modes = \"truncated\"` or `\"auto\"`, `modes --cutoff` and `matrices` take up to {MAX_CONTROL_POINTS}"
                ),
            ));
        }
        Ok(model)
    }

    pub fn build_model(&self) -> Result<ShellModel, ConfigError> {
        let patches = self.build_model_patches()?;
        let m = &self.model;
        let index = |name: &Option<String>, key: String| patch_index(&patches, name.as_deref(), &key);
        let springs = m
            .springs
            .iter()
            .enumerate()
            .map(|(i, s)| Ok(build_spring(i, s)?.on_patch(index(&s.patch, format!("model.springs[{i}].patch"))?)))
            .collect::<Result<Vec<_>, ConfigError>>()?;
        let constraints = m
            .constraints
            .iter()
            .enumerate()
            .map(|(i, c)| {
                Ok(EdgeConstraint {
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
                    patch: index(&c.patch, format!("model.constraints[{i}].patch"))?,
                })
            })
            .collect::<Result<Vec<_>, ConfigError>>()?;
        let stiffness_fields = m
            .stiffness_fields
            .iter()
            .enumerate()
            .map(|(i, f)| {
                let patch = index(&f.patch, format!("model.stiffness_fields[{i}].patch"))?;
                Ok(build_stiffness_field(i, f, &patches[patch].shell)?.on_patch(patch))
            })
            .collect::<Result<Vec<_>, ConfigError>>()?;
        self.check_names()?;
        let (bearings, masses) = self.build_attachments(&patches)?;
        if !(m.joint_tolerance.is_finite() && m.joint_tolerance > 0.0) {
            return Err(err("model.joint_tolerance", "must be a positive distance in metres"));
        }
        if !(m.joint_penalty.is_finite() && m.joint_penalty >= 1.0) {
            return Err(err("model.joint_penalty", "must be a finite factor of at least 1"));
        }
        let model = ShellModel {
            joints: find_joints(&patches, m.joint_tolerance),
            joint_penalty: m.joint_penalty,
            patches,
            springs,
            stiffness_fields,
            constraints,
            bearings,
            masses,
        };
        // Surface the spring/shell compatibility errors here, with their key.
        for (i, s) in model.springs.iter().enumerate() {
            s.coefficient_matrices(&model.patches[s.patch()].shell)
                .map_err(|e| err(format!("model.springs[{i}]"), e))?;
        }
        self.check_every_patch_held(&model)?;
        Ok(model)
    }

    /// Names of springs, stiffness fields and bearings are distinct (they
    /// prefix the updating parameters).
    fn check_names(&self) -> Result<(), ConfigError> {
        let m = &self.model;
        let mut names: Vec<&str> = m.springs.iter().map(|s| s.name.as_str()).collect();
        let others = m
            .stiffness_fields
            .iter()
            .enumerate()
            .map(|(i, f)| (format!("model.stiffness_fields[{i}].name"), &f.name))
            .chain(
                m.bearings
                    .iter()
                    .enumerate()
                    .map(|(i, b)| (format!("model.bearings[{i}].name"), &b.name)),
            );
        for (key, name) in others {
            if names.contains(&name.as_str()) || name == "damping" {
                return Err(err(
                    key,
                    format!(
                        "{name:?} is already the name of a spring field, stiffness field, bearing or of the damping"
                    ),
                ));
            }
            names.push(name);
        }
        Ok(())
    }

    /// The bearings and point masses, each at the nearest point of its patch.
    fn build_attachments(&self, patches: &[Patch]) -> Result<(Vec<Bearing>, Vec<PointMass>), ConfigError> {
        let m = &self.model;
        let bearings = m
            .bearings
            .iter()
            .enumerate()
            .map(|(i, b)| {
                let key = |k: &str| format!("model.bearings[{i}].{k}");
                let patch = b
                    .patch
                    .as_deref()
                    .map(|n| patch_index(patches, Some(n), &key("patch")))
                    .transpose()?;
                let at = locate(patches, patch, b.at, face_tau(b.surface), &key("at"))?;
                if let Some([lo, hi]) = b.bounds {
                    if !(lo.is_finite() && hi.is_finite() && lo >= 0.0 && lo < hi) {
                        return Err(err(
                            key("bounds"),
                            format!("[{lo}, {hi}] must satisfy 0 <= lower < upper"),
                        ));
                    }
                    if let Some(k) = b.stiffness.iter().find(|&&k| !(k >= lo && k <= hi)) {
                        return Err(err(key("stiffness"), format!("{k} lies outside bounds [{lo}, {hi}]")));
                    }
                }
                Bearing::new(at, b.stiffness).map_err(|e| err(key("stiffness"), e))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let masses = m
            .masses
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let key = |k: &str| format!("model.masses[{i}].{k}");
                let patch = p
                    .patch
                    .as_deref()
                    .map(|n| patch_index(patches, Some(n), &key("patch")))
                    .transpose()?;
                let at = locate(patches, patch, p.at, 0.5, &key("at"))?;
                PointMass::new(at, p.mass).map_err(|e| err(key("mass"), e))
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok((bearings, masses))
    }

    /// Every patch of a deck of several is joined to another or carries a
    /// support (constraint, spring field or bearing).
    fn check_every_patch_held(&self, model: &ShellModel) -> Result<(), ConfigError> {
        if model.patches.len() < 2 {
            return Ok(());
        }
        for (k, p) in model.patches.iter().enumerate() {
            let joined = model.joints.iter().any(|j| j.patch == k || j.other == k);
            let supported = model.constraints.iter().any(|c| c.patch == k)
                || model.springs.iter().any(|s| s.patch() == k)
                || model.bearings.iter().any(|b| b.at().patch == k);
            if !(joined || supported) {
                return Err(err(
                    format!("model.patches[{k}]"),
                    format!(
                        "patch {:?} is joined to no other patch (no edge within joint_tolerance = {} m of another) and carries no support",
                        p.name(),
                        self.model.joint_tolerance
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The patches: `[[model.patches]]`, or the single-patch keys as one
    /// patch named `"deck"`.
    pub fn build_model_patches(&self) -> Result<Vec<Patch>, ConfigError> {
        let m = &self.model;
        let single = m.geometry.is_some() || m.discretization.is_some() || m.material.is_some();
        match (single, m.patches.is_empty()) {
            (true, false) => Err(err(
                "model.patches",
                "give either [[model.patches]] or [model.geometry], [model.discretization] and [model.material], not both",
            )),
            (false, true) => Err(err(
                "model",
                "no deck: give [model.geometry], [model.discretization] and [model.material], or [[model.patches]]",
            )),
            (false, false) => {
                let patches = build_patches(&m.patches, &m.materials)?;
                if let Some((a, b)) = find_overlap(&patches, m.joint_tolerance) {
                    return Err(err(
                        format!("model.patches[{a}]"),
                        format!(
                            "patch {:?} lies on patch {:?} (overlapping patches count the same material twice)",
                            patches[a].name(),
                            patches[b].name()
                        ),
                    ));
                }
                let total: usize = patches.iter().map(|p| p.shell.control_point_count()).sum();
                if total > MAX_CONTROL_POINTS {
                    return Err(err(
                        "model.patches",
                        format!("{total} control points in all: at most {MAX_CONTROL_POINTS} (the sparse path's limit)"),
                    ));
                }
                Ok(patches)
            }
            (true, true) => {
                let shell = self.build_shell()?;
                let material = self.build_material()?;
                Ok(vec![Patch::new("deck", shell, material).expect("a non-empty name")])
            }
        }
    }

    /// `[model.geometry]` on the `[model.discretization]` net, refined.
    fn build_shell(&self) -> Result<Shell, ConfigError> {
        let m = &self.model;
        let d = m
            .discretization
            .as_ref()
            .ok_or_else(|| err("model.discretization", "is required with [model.geometry]"))?;
        let geometry = m
            .geometry
            .as_ref()
            .ok_or_else(|| err("model.geometry", "is required with [model.discretization]"))?;
        // Refuse nets no path can hold rather than exhausting memory.
        let [cm, cn] = d.control_points;
        let total = cm
            .saturating_add(d.insert_knots_xi.len())
            .saturating_mul(cn.saturating_add(d.insert_knots_eta.len()));
        if total > MAX_CONTROL_POINTS {
            return Err(err(
                "model.discretization.control_points",
                format!("{total} control points (after knot insertion) exceed the supported {MAX_CONTROL_POINTS}"),
            ));
        }
        let mut shell = match *geometry {
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
        .map_err(|e| err(shell_error_key(&e), e))?;
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
        Ok(shell)
    }

    fn build_material(&self) -> Result<OrthotropicMaterial, ConfigError> {
        let parameters = self
            .model
            .material
            .ok_or_else(|| err("model.material", "is required with [model.geometry]"))?;
        OrthotropicMaterial::new(parameters).map_err(|e| err("model.material", e))
    }

    /// `[model.damping]` as a curve; an error if it is missing.
    pub fn build_damping(&self) -> Result<DampingCurve, ConfigError> {
        let d = self
            .model
            .damping
            .as_ref()
            .ok_or_else(|| err("model.damping", "is required for FRFs and updating"))?;
        if let Some([lo, hi]) = d.bounds {
            if !(lo.is_finite() && hi.is_finite() && lo >= 0.0 && lo < hi) {
                return Err(err(
                    "model.damping.bounds",
                    format!("[{lo}, {hi}] must satisfy 0 <= lower < upper"),
                ));
            }
            if let Some((j, g)) = d.coefficients.iter().enumerate().find(|(_, &g)| !(g >= lo && g <= hi)) {
                return Err(err(
                    "model.damping.coefficients",
                    format!("coefficient {} = {g} lies outside bounds [{lo}, {hi}]", j + 1),
                ));
            }
        }
        DampingCurve::new(d.degree, d.coefficients.clone(), d.f_start, d.f_end).map_err(|e| err("model.damping", e))
    }
}

/// The key a shell construction error is about.
fn shell_error_key(e: &ShellError) -> String {
    match e {
        ShellError::Thickness { .. } | ShellError::ThicknessCount { .. } => "model.geometry.thickness".into(),
        ShellError::Dimension { name: "angle", .. } => "model.geometry.angle_deg".into(),
        ShellError::Dimension { name, .. } => format!("model.geometry.{name}"),
        ShellError::Surface(_) | ShellError::Knot(_) => "model.discretization.control_points".into(),
        _ => "model.geometry".into(),
    }
}

fn build_stiffness_field(i: usize, f: &StiffnessFieldConfig, shell: &Shell) -> Result<StiffnessField, ConfigError> {
    let key = |k: &str| format!("model.stiffness_fields[{i}].{k}");
    let scale = StiffnessScale::parse(&f.scales).ok_or_else(|| {
        err(
            key("scales"),
            format!("{:?}: expected one of {:?}", f.scales, StiffnessScale::NAMES),
        )
    })?;
    let xi = KnotVector::new(f.knots_xi.clone(), f.degree_xi).map_err(|e| err(key("knots_xi"), e))?;
    let eta = KnotVector::new(f.knots_eta.clone(), f.degree_eta).map_err(|e| err(key("knots_eta"), e))?;
    let coefficients = f
        .coefficients
        .clone()
        .unwrap_or_else(|| vec![1.0; xi.basis_count() * eta.basis_count()]);
    if let Some([lo, hi]) = f.bounds {
        if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && lo < hi) {
            return Err(err(
                key("bounds"),
                format!("[{lo}, {hi}] must satisfy 0 < lower < upper"),
            ));
        }
    }
    let field = StiffnessField::new(xi, eta, coefficients)
        .map_err(|e| err(key("coefficients"), e))?
        .with_scale(scale);
    field
        .check_inside(shell)
        .map_err(|e| err(key(&format!("knots_{}", e.axis)), e))?;
    Ok(field)
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

impl Config {
    /// The sensors as model points, in config order, with their names.
    pub fn build_sensors(&self, model: &ShellModel) -> Result<Vec<(String, SensorPoint)>, ConfigError> {
        let mut out = Vec::with_capacity(self.sensors.len());
        for (i, s) in self.sensors.iter().enumerate().take(self.deck_sensor_count()) {
            let key = |k: &str| format!("sensors[{i}].{k}");
            for q in s.quantity.as_slice() {
                if !matches!(q.as_str(), "acceleration" | "force" | "displacement" | "velocity") {
                    return Err(err(
                        key("quantity"),
                        format!("{q:?} is not one of acceleration, force, displacement, velocity"),
                    ));
                }
            }
            let tau = face_tau(s.surface);
            let (patch, xi, eta) = self.sensor_position(model, i)?;
            let shell = &model.patches[patch].shell;
            let (kx, ke) = (shell.surface().xi(), shell.surface().eta());
            if !kx.contains(xi) || !ke.contains(eta) {
                return Err(err(
                    key("xi"),
                    format!("({xi}, {eta}) lies outside the parameter domain"),
                ));
            }
            let direction = match &s.direction {
                DirectionConfig::Named(n) => match n.as_str() {
                    "x" => [1.0, 0.0, 0.0],
                    "y" => [0.0, 1.0, 0.0],
                    "z" => [0.0, 0.0, 1.0],
                    "normal" => {
                        let e = shell.surface().evaluate(xi, eta);
                        splinewatch_core::geometry::vec3::cross(e.r_xi, e.r_eta)
                    }
                    other => {
                        return Err(err(
                            key("direction"),
                            format!("{other:?} is not one of \"x\", \"y\", \"z\", \"normal\" or a 3-vector"),
                        ))
                    }
                },
                DirectionConfig::Vector(v) => *v,
            };
            if splinewatch_core::geometry::vec3::normalize(direction).is_none() {
                return Err(err(key("direction"), "must be a finite non-zero vector"));
            }
            out.push((
                s.name.clone(),
                SensorPoint {
                    patch,
                    xi,
                    eta,
                    tau,
                    direction,
                },
            ));
        }
        Ok(out)
    }
}

impl Config {
    /// Sensor `i`'s patch and parameters: `xi, eta` on the named (or only)
    /// patch; `x, y, z` at the nearest point of the named or nearest patch
    /// (within 0.5 m); `x, y` on a single patch, located in plan.
    fn sensor_position(&self, model: &ShellModel, i: usize) -> Result<(usize, f64, f64), ConfigError> {
        let s = &self.sensors[i];
        let key = |k: &str| format!("sensors[{i}].{k}");
        let patches = &model.patches;
        let named = || patch_index(patches, s.patch.as_deref(), &key("patch"));
        match (s.xi, s.eta, s.x, s.y, s.z) {
            (Some(xi), Some(eta), None, None, None) => Ok((named()?, xi, eta)),
            (None, None, Some(x), Some(y), Some(z)) => {
                let patch = s
                    .patch
                    .as_deref()
                    .map(|n| patch_index(patches, Some(n), &key("patch")))
                    .transpose()?;
                let at = locate(patches, patch, [x, y, z], face_tau(s.surface), &key("x"))?;
                Ok((at.patch, at.xi, at.eta))
            }
            (None, None, Some(x), Some(y), None) => {
                let patch = named().map_err(|_| err(key("z"), "the model has several patches: give x, y and z"))?;
                let (xi, eta) = patches[patch].shell.surface().locate_xy(x, y).ok_or_else(|| {
                    err(
                        key("x"),
                        format!("point ({x}, {y}) m is not on the deck (outside the model's plan)"),
                    )
                })?;
                Ok((patch, xi, eta))
            }
            _ => Err(err(
                format!("sensors[{i}]"),
                "give either both xi and eta (parametric), x and y (metres, in plan on a single patch) or x, y and z",
            )),
        }
    }
}

#[cfg(test)]
mod stiffness_field_tests {
    use super::*;

    fn with_field(section: &str) -> Result<Config, ConfigError> {
        let text = format!("{}\n{section}", include_str!("../../config/sinello.toml"));
        let config = Config::from_toml(&text)?;
        config.build_model()?;
        Ok(config)
    }

    const REGIONS: &str = r#"
[[model.stiffness_fields]]
name = "deck"
knots_xi = [0.0, 0.25, 0.5, 0.75, 1.0]
degree_xi = 0
knots_eta = [0.0, 0.5, 1.0]
degree_eta = 0
bounds = [0.3, 1.5]
"#;

    #[test]
    fn a_field_becomes_model_coefficients_and_parameters() {
        let config = with_field(REGIONS).unwrap();
        let model = config.build_model().unwrap();
        assert_eq!(model.stiffness_fields.len(), 1);
        assert_eq!(model.stiffness_fields[0].coefficients(), &[1.0; 8]);
        let names: Vec<String> = config.build_parameters().unwrap().into_iter().map(|p| p.name).collect();
        let fields: Vec<&String> = names.iter().filter(|n| n.starts_with("deck.s")).collect();
        assert_eq!(fields.len(), 8);
        assert_eq!(fields[0], "deck.s1");
        assert_eq!(fields[7], "deck.s8");
        // Not updated: no parameters, the coefficients still set the model.
        let fixed = with_field(&REGIONS.replace(
            "bounds = [0.3, 1.5]",
            "update = false\ncoefficients = [1, 1, 1, 1, 1, 0.7, 1, 1]",
        ))
        .unwrap();
        assert!(!fixed
            .build_parameters()
            .unwrap()
            .iter()
            .any(|p| p.name.starts_with("deck.")));
        assert_eq!(fixed.build_model().unwrap().stiffness_fields[0].coefficients()[5], 0.7);
    }

    #[test]
    fn bad_fields_name_their_key() {
        let message = |section: String| with_field(&section).unwrap_err().to_string();
        assert!(
            message(REGIONS.replace("name = \"deck\"", "name = \"east\"")).contains("model.stiffness_fields[0].name")
        );
        assert!(
            message(REGIONS.replace("bounds", "scales = \"E1\"\nbounds")).contains("model.stiffness_fields[0].scales")
        );
        let bending = with_field(&REGIONS.replace("bounds", "scales = \"bending\"\nbounds")).unwrap();
        assert_eq!(
            bending.build_model().unwrap().stiffness_fields[0].scale(),
            StiffnessScale::Bending
        );
        assert!(
            message(REGIONS.replace("bounds = [0.3, 1.5]", "coefficients = [1.0, 2.0]"))
                .contains("model.stiffness_fields[0].coefficients")
        );
        assert!(message(REGIONS.replace("[0.3, 1.5]", "[0.0, 1.5]")).contains("model.stiffness_fields[0].bounds"));
        assert!(message(REGIONS.replace("[0.0, 0.5, 1.0]", "[0.0, 0.5, 1.2]"))
            .contains("model.stiffness_fields[0].knots_eta"));
        let no_bounds = Config::from_toml(&format!(
            "{}\n{}",
            include_str!("../../config/sinello.toml"),
            REGIONS.replace("bounds = [0.3, 1.5]", "")
        ))
        .unwrap();
        assert!(no_bounds
            .build_parameters()
            .unwrap_err()
            .to_string()
            .contains("model.stiffness_fields[0].bounds"));
    }
}
