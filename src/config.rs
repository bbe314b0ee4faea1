//! The TOML configuration: parsed with serde (unknown keys rejected), then
//! validated into the core crate's types. Every error names the key path.
//!
//! Physics (`[model.geometry]`, `[model.material]`, `[[model.springs]]`,
//! `[[model.constraints]]`) is kept apart from discretisation
//! (`[model.discretization]`); see README.md for every key.

use serde::Deserialize;
use splinewatch_core::constraints::{Edge, EdgeConstraint, SupportKind};
use splinewatch_core::damping::DampingCurve;
use splinewatch_core::frf::{Quantity, SensorPoint};
use splinewatch_core::knots::KnotVector;
use splinewatch_core::material::{OrthotropicMaterial, OrthotropicParameters};
use splinewatch_core::model::ShellModel;
use splinewatch_core::shell::Shell;
use splinewatch_core::springs::{Face, SpringDirection, SpringField};
use splinewatch_core::surface::Direction;
use splinewatch_core::updating::{LineSelection, Method, Parameter, ParameterKind, UpdateSettings, Weighting};
use splinewatch_core::welch::{Averaging, Detrend, Estimator, Gates, WelchSettings, Window};
use std::fmt::Display;
use thiserror::Error;

/// A configuration error: the key path and what is wrong with it.
#[derive(Debug, Error)]
#[error("config: {path}: {message}")]
pub struct ConfigError {
    pub path: String,
    pub message: String,
}

/// Largest control net accepted (5 dofs each; the dense eigen-solve of
/// 10 000 dofs already takes minutes).
pub const MAX_CONTROL_POINTS: usize = 2000;

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
    #[serde(default)]
    pub sensors: Vec<SensorConfig>,
    #[serde(default)]
    pub updating: UpdatingConfig,
    #[serde(default)]
    pub frf: FrfConfig,
    #[serde(default)]
    pub schedule: crate::pipeline::ScheduleConfig,
    #[serde(default)]
    pub output: OutputConfig,
    #[serde(default)]
    pub zenoh: crate::daemon::ZenohConfig,
}

/// `[output]`: where results go.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OutputConfig {
    /// Folder for results MCAP files and the state file (default `out/<structure.name>`).
    pub dir: Option<std::path::PathBuf>,
    /// State file (default `<dir>/state.json`).
    pub state_file: Option<std::path::PathBuf>,
    /// Rerun `.rrd` file (relative to `dir`); none by default.
    pub rerun_save: Option<std::path::PathBuf>,
    /// A Rerun viewer to stream to, e.g. "rerun+http://127.0.0.1:9876/proxy".
    pub rerun_connect: Option<String>,
    /// `[output.raw]`: optional raw-input recording.
    pub raw: crate::recorder::RawRecordingConfig,
    /// Start a new `.rrd` file after this much measurement time.
    pub rerun_rotate_hours: f64,
    /// Finalise the results MCAP file and start a new one after this much
    /// measurement time.
    pub results_rotate_hours: f64,
}

impl Default for OutputConfig {
    fn default() -> Self {
        Self {
            dir: None,
            state_file: None,
            rerun_save: None,
            rerun_connect: None,
            raw: Default::default(),
            rerun_rotate_hours: 24.0,
            results_rotate_hours: 24.0,
        }
    }
}

/// `[frf]`: Welch FRF estimation from time series.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FrfConfig {
    /// Welch segment length, seconds.
    pub segment_seconds: f64,
    /// Segment overlap, fraction in [0, 1).
    pub overlap: f64,
    /// "rectangular", "hann", "hamming", "blackman", "flattop" or "impact"
    /// (force window on the input, exponential on the outputs).
    pub window: String,
    /// Impact tests: length of the force window, fraction of a segment.
    pub force_window_width: f64,
    /// Impact tests: value of the exponential window at the segment end.
    pub exponential_end: f64,
    /// "constant" (scipy's default) or "none".
    pub detrend: String,
    /// "h1", "h2" or "hv".
    pub estimator: String,
    /// "linear" or "exponential".
    pub averaging: String,
    /// Weight α of a new segment with exponential averaging.
    pub exponential_weight: f64,
    /// Lines kept in FRF files, [f_min, f_max] Hz.
    pub band: [f64; 2],
    /// Analysis window of the daemon, seconds.
    pub window_seconds: f64,
    /// Time between the starts of consecutive windows, seconds (at most
    /// `window_seconds`; less gives overlapping windows). Default: the window
    /// length, back to back.
    pub window_hop_seconds: Option<f64>,
    /// Reject segments reaching this magnitude (overload), optional.
    pub full_scale: Option<f64>,
    /// Impact tests: reject segments with a second hit above this fraction of the peak.
    pub double_impact_fraction: Option<f64>,
    /// Quantity written to FRF files: "accelerance", "mobility" or "receptance".
    pub quantity: Quantity,
    /// Largest accepted block, samples.
    pub max_block_samples: usize,
}

impl Default for FrfConfig {
    fn default() -> Self {
        Self {
            segment_seconds: 8.0,
            overlap: 0.5,
            window: "hann".into(),
            force_window_width: 0.1,
            exponential_end: 0.01,
            detrend: "constant".into(),
            estimator: "h1".into(),
            averaging: "linear".into(),
            exponential_weight: 0.05,
            band: [0.5, 80.0],
            window_seconds: 600.0,
            window_hop_seconds: None,
            full_scale: None,
            double_impact_fraction: None,
            quantity: Quantity::Accelerance,
            max_block_samples: 1 << 20,
        }
    }
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
    pub damping: Option<DampingConfig>,
}

/// `[model.damping]`: the B-spline ζ(f) of eq. (29).
#[derive(Debug, Clone, Deserialize)]
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
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SensorConfig {
    pub name: String,
    pub xi: Option<f64>,
    pub eta: Option<f64>,
    pub x: Option<f64>,
    pub y: Option<f64>,
    pub direction: DirectionConfig,
    /// What is measured there: one of, or a list of, "acceleration",
    /// "force", "displacement", "velocity".
    #[serde(default = "default_quantity")]
    pub quantity: QuantityList,
    /// Face the sensor sits on (default: the mid-surface).
    #[serde(default = "default_face")]
    pub surface: FaceConfig,
}

fn default_quantity() -> QuantityList {
    QuantityList::One("acceleration".into())
}

fn default_face() -> FaceConfig {
    FaceConfig::Middle
}

#[derive(Debug, Clone, Deserialize)]
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

fn default_max_iterations() -> usize {
    50
}
fn default_cost_tolerance() -> f64 {
    1e-8
}
fn default_step_tolerance() -> f64 {
    1e-9
}
fn default_offset_tolerance() -> f64 {
    1e-2
}
fn default_initial_damping() -> f64 {
    1e-3
}
fn default_decimation() -> usize {
    1
}

/// `[updating]`: solver and data selection.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UpdatingConfig {
    #[serde(default = "default_max_iterations")]
    pub max_iterations: usize,
    /// Stop when an accepted step lowers the cost by less than this fraction.
    #[serde(default = "default_cost_tolerance")]
    pub cost_tolerance: f64,
    /// Stop when the step in the transformed variables is this small.
    #[serde(default = "default_step_tolerance")]
    pub step_tolerance: f64,
    /// Stop when the Gauss–Newton step is below this many standard errors,
    /// root mean square over the parameters (Bates & Watts' relative offset).
    #[serde(default = "default_offset_tolerance")]
    pub offset_tolerance: f64,
    /// Threads for the FRF evaluation (results do not depend on it); default:
    /// the available cores, at most 4.
    pub threads: Option<usize>,
    #[serde(default = "default_method")]
    pub method: Method,
    #[serde(default = "default_weighting")]
    pub weighting: Weighting,
    /// Frequency band [f_min, f_max] in Hz used for the residues.
    pub band: Option<[f64; 2]>,
    /// Keep every n-th line of the band.
    #[serde(default = "default_decimation")]
    pub decimation: usize,
    /// Bands [a, b] in Hz left out.
    #[serde(default)]
    pub exclude: Vec<[f64; 2]>,
    /// Initial Levenberg–Marquardt damping λ0, dimensionless (see `UpdateSettings::initial_damping`).
    #[serde(default = "default_initial_damping")]
    pub initial_damping: f64,
}

fn default_method() -> Method {
    Method::LevenbergMarquardt
}
fn default_weighting() -> Weighting {
    Weighting::Uniform
}

impl Default for UpdatingConfig {
    fn default() -> Self {
        toml::from_str("").expect("every key has a default")
    }
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
        for (i, s) in self.sensors.iter().enumerate() {
            if s.name.trim().is_empty() || s.name.contains('/') || s.name.contains(char::is_whitespace) {
                return Err(err(
                    format!("sensors[{i}].name"),
                    format!("{:?} must be non-empty without '/' or spaces", s.name),
                ));
            }
            if !seen.insert(s.name.as_str()) {
                return Err(err(format!("sensors[{i}].name"), format!("{:?} is used twice", s.name)));
            }
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
        // The dense model path stores n_dof² matrices: refuse nets it cannot hold
        // rather than exhausting memory.
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

impl Config {
    /// The sensors as model points, in config order, with their names.
    pub fn build_sensors(&self, shell: &Shell) -> Result<Vec<(String, SensorPoint)>, ConfigError> {
        let mut out = Vec::with_capacity(self.sensors.len());
        for (i, s) in self.sensors.iter().enumerate() {
            let key = |k: &str| format!("sensors[{i}].{k}");
            for q in s.quantity.as_slice() {
                if !matches!(q.as_str(), "acceleration" | "force" | "displacement" | "velocity") {
                    return Err(err(
                        key("quantity"),
                        format!("{q:?} is not one of acceleration, force, displacement, velocity"),
                    ));
                }
            }
            let (xi, eta) = match (s.xi, s.eta, s.x, s.y) {
                (Some(xi), Some(eta), None, None) => (xi, eta),
                (None, None, Some(x), Some(y)) => shell.surface().locate_xy(x, y).ok_or_else(|| {
                    err(
                        key("x"),
                        format!("point ({x}, {y}) m is not on the deck (outside the model's plan)"),
                    )
                })?,
                _ => {
                    return Err(err(
                        format!("sensors[{i}]"),
                        "give either both xi and eta (parametric) or both x and y (metres)",
                    ))
                }
            };
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
                        splinewatch_core::vec3::cross(e.r_xi, e.r_eta)
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
            if splinewatch_core::vec3::normalize(direction).is_none() {
                return Err(err(key("direction"), "must be a finite non-zero vector"));
            }
            let tau = match s.surface {
                FaceConfig::Bottom => 0.0,
                FaceConfig::Middle => 0.5,
                FaceConfig::Top => 1.0,
            };
            out.push((
                s.name.clone(),
                SensorPoint {
                    xi,
                    eta,
                    tau,
                    direction,
                },
            ));
        }
        Ok(out)
    }

    /// Results folder: `[output] dir`, default `out/<structure.name>`.
    pub fn output_dir(&self) -> std::path::PathBuf {
        self.output
            .dir
            .clone()
            .unwrap_or_else(|| std::path::Path::new("out").join(&self.structure.name))
    }

    /// Topic / key-expression prefix: `bridge/<structure.name>`.
    pub fn topic_prefix(&self) -> String {
        format!("bridge/{}", self.structure.name)
    }

    /// Builds every section, so all errors surface at load time.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let model = self.build_model()?;
        self.build_sensors(&model.shell)?;
        if self.model.damping.is_some() {
            self.build_damping()?;
        }
        self.build_parameters()?;
        self.update_settings()?;
        // The sampling rate is only known from the data; check with a nominal one.
        self.welch_settings(256.0)?;
        for (key, hours) in [
            ("output.rerun_rotate_hours", self.output.rerun_rotate_hours),
            ("output.results_rotate_hours", self.output.results_rotate_hours),
        ] {
            if !(hours.is_finite() && hours >= 1.0 / 3600.0) {
                return Err(err(key, format!("must be at least one second (1/3600 h), got {hours}")));
            }
        }
        let raw = &self.output.raw;
        if !(raw.rotate_minutes.is_finite() && raw.rotate_minutes > 0.0) {
            return Err(err(
                "output.raw.rotate_minutes",
                format!("must be a positive number of minutes, got {}", raw.rotate_minutes),
            ));
        }
        if !(raw.rotate_megabytes.is_finite() && raw.rotate_megabytes >= 0.01) {
            return Err(err(
                "output.raw.rotate_megabytes",
                format!("must be at least 0.01, got {}", raw.rotate_megabytes),
            ));
        }
        for (key, endpoints) in [
            ("zenoh.listen", &self.zenoh.listen),
            ("zenoh.connect", &self.zenoh.connect),
        ] {
            if let Some((i, e)) = endpoints.iter().enumerate().find(|(_, e)| !e.starts_with("tcp/")) {
                return Err(err(
                    format!("{key}[{i}]"),
                    format!(
                        "{e:?}: this build speaks zenoh over TCP only (\"tcp/<host>:<port>\"); \
                         for encryption see README, \"Transport security\""
                    ),
                ));
            }
        }
        Ok(())
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

    /// The updating parameters: `<spring>.k<j>` for spring fields with
    /// `update = true` (j from 1, η fastest) and `damping.g<z>`.
    pub fn build_parameters(&self) -> Result<Vec<Parameter>, ConfigError> {
        let mut out = Vec::new();
        for (field, s) in self.model.springs.iter().enumerate() {
            if !s.update {
                continue;
            }
            let [lower, upper] = s
                .bounds
                .ok_or_else(|| err(format!("model.springs[{field}].bounds"), "required when update = true"))?;
            for coefficient in 0..s.stiffness.len() {
                out.push(Parameter {
                    name: format!("{}.k{}", s.name, coefficient + 1),
                    kind: ParameterKind::Spring { field, coefficient },
                    lower,
                    upper,
                });
            }
        }
        if let Some(d) = self.model.damping.as_ref().filter(|d| d.update) {
            let [lower, upper] = d
                .bounds
                .ok_or_else(|| err("model.damping.bounds", "required when update = true"))?;
            for coefficient in 0..d.coefficients.len() {
                out.push(Parameter {
                    name: format!("damping.g{}", coefficient + 1),
                    kind: ParameterKind::Damping { coefficient },
                    lower,
                    upper,
                });
            }
        }
        Ok(out)
    }

    /// `[frf]` as Welch settings for sampling frequency `fs`.
    pub fn welch_settings(&self, fs: f64) -> Result<(WelchSettings, Estimator), ConfigError> {
        let f = &self.frf;
        if !(f.segment_seconds.is_finite() && f.segment_seconds > 0.0) {
            return Err(err(
                "frf.segment_seconds",
                format!("must be positive, got {}", f.segment_seconds),
            ));
        }
        let segment = (f.segment_seconds * fs).round() as usize;
        if segment < 4 {
            return Err(err(
                "frf.segment_seconds",
                format!("{} s at {fs} Hz is only {segment} samples", f.segment_seconds),
            ));
        }
        if !(0.0..1.0).contains(&f.overlap) {
            return Err(err("frf.overlap", format!("must be in [0, 1), got {}", f.overlap)));
        }
        let overlap = (f.overlap * segment as f64).round() as usize;
        let simple = |name: &str| match name {
            "rectangular" | "boxcar" => Some(Window::Rectangular),
            "hann" => Some(Window::Hann),
            "hamming" => Some(Window::Hamming),
            "blackman" => Some(Window::Blackman),
            "flattop" => Some(Window::FlatTop),
            _ => None,
        };
        let (input_window, output_window) = match (f.window.as_str(), simple(&f.window)) {
            (_, Some(w)) => (w, w),
            ("impact", None) => (
                Window::Force {
                    width: f.force_window_width,
                },
                Window::Exponential { end: f.exponential_end },
            ),
            (other, None) => {
                return Err(err(
                    "frf.window",
                    format!("{other:?} is not rectangular, hann, hamming, blackman, flattop or impact"),
                ))
            }
        };
        let detrend = match f.detrend.as_str() {
            "constant" => Detrend::Constant,
            "none" => Detrend::None,
            other => return Err(err("frf.detrend", format!("{other:?} is not constant or none"))),
        };
        let estimator = match f.estimator.as_str() {
            "h1" => Estimator::H1,
            "h2" => Estimator::H2,
            "hv" => Estimator::Hv,
            other => return Err(err("frf.estimator", format!("{other:?} is not h1, h2 or hv"))),
        };
        let averaging = match f.averaging.as_str() {
            "linear" => Averaging::Linear,
            "exponential" => Averaging::Exponential {
                alpha: f.exponential_weight,
            },
            other => return Err(err("frf.averaging", format!("{other:?} is not linear or exponential"))),
        };
        let [lo, hi] = f.band;
        if !(lo.is_finite() && hi.is_finite() && lo >= 0.0 && lo < hi) {
            return Err(err("frf.band", format!("[{lo}, {hi}] must satisfy 0 <= f_min < f_max")));
        }
        if !(f.window_seconds.is_finite() && f.window_seconds >= f.segment_seconds) {
            return Err(err("frf.window_seconds", "must be at least one segment long"));
        }
        if let Some(hop) = f.window_hop_seconds {
            if !(hop.is_finite() && hop * fs >= 1.0 && hop <= f.window_seconds) {
                return Err(err(
                    "frf.window_hop_seconds",
                    format!(
                        "must be between one sample and frf.window_seconds ({} s), got {hop}",
                        f.window_seconds
                    ),
                ));
            }
        }
        let settings = WelchSettings {
            fs,
            segment,
            overlap,
            input_window,
            output_window,
            detrend,
            averaging,
            gates: Gates {
                full_scale: f.full_scale,
                double_impact_fraction: f.double_impact_fraction,
            },
        };
        settings.validate().map_err(|e| err("frf", e))?;
        Ok((settings, estimator))
    }

    /// The sensor whose quantity includes "force" (the excitation), and the
    /// sensors measuring acceleration, by index into `[[sensors]]`.
    pub fn channel_roles(&self) -> Result<(usize, Vec<usize>), ConfigError> {
        let has = |i: usize, q: &str| self.sensors[i].quantity.as_slice().iter().any(|x| x == q);
        let forces: Vec<usize> = (0..self.sensors.len()).filter(|&i| has(i, "force")).collect();
        let force = match forces.as_slice() {
            [one] => *one,
            [] => return Err(err("sensors", "no sensor has quantity \"force\" (the excitation)")),
            _ => {
                return Err(err(
                    "sensors",
                    "more than one force sensor: multiple-input FRFs are not supported",
                ))
            }
        };
        let accelerations = (0..self.sensors.len())
            .filter(|&i| has(i, "acceleration"))
            .collect::<Vec<_>>();
        if accelerations.is_empty() {
            return Err(err("sensors", "no sensor measures acceleration"));
        }
        Ok((force, accelerations))
    }

    /// `[updating]` as solver settings.
    pub fn update_settings(&self) -> Result<UpdateSettings, ConfigError> {
        let u = &self.updating;
        let positive = |key: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(err(
                    format!("updating.{key}"),
                    format!("must be finite and positive, got {v}"),
                ))
            }
        };
        positive("cost_tolerance", u.cost_tolerance)?;
        positive("step_tolerance", u.step_tolerance)?;
        positive("offset_tolerance", u.offset_tolerance)?;
        positive("initial_damping", u.initial_damping)?;
        if u.max_iterations == 0 {
            return Err(err("updating.max_iterations", "must be at least 1"));
        }
        let threads = match u.threads {
            Some(n @ 1..=64) => n,
            Some(n) => return Err(err("updating.threads", format!("must be between 1 and 64, got {n}"))),
            None => std::thread::available_parallelism().map_or(1, |n| n.get().min(4)),
        };
        if u.decimation == 0 {
            return Err(err("updating.decimation", "must be at least 1"));
        }
        let interval = |key: String, [a, b]: [f64; 2]| {
            if a.is_finite() && b.is_finite() && a >= 0.0 && a <= b {
                Ok((a, b))
            } else {
                Err(err(key, format!("[{a}, {b}] must satisfy 0 <= a <= b")))
            }
        };
        let band = u.band.map(|b| interval("updating.band".into(), b)).transpose()?;
        let exclude = u
            .exclude
            .iter()
            .enumerate()
            .map(|(i, &b)| interval(format!("updating.exclude[{i}]"), b))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(UpdateSettings {
            method: u.method,
            max_iterations: u.max_iterations,
            cost_tolerance: u.cost_tolerance,
            step_tolerance: u.step_tolerance,
            offset_tolerance: u.offset_tolerance,
            weighting: u.weighting,
            lines: LineSelection {
                band,
                decimation: u.decimation,
                exclude,
            },
            initial_damping: u.initial_damping,
            threads,
        })
    }
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
        let e = error_of(|t| t.replace("control_points = [13, 5]", "control_points = [13, 99999]"));
        assert!(
            e.contains("model.discretization.control_points") && e.contains("exceed"),
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

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]
        #[test]
        fn mutated_configs_never_panic(flips in proptest::collection::vec((proptest::prelude::any::<proptest::sample::Index>(), proptest::prelude::any::<u8>()), 1..4)) {
            let mut bytes = SINELLO.as_bytes().to_vec();
            for (i, b) in &flips {
                let k = i.index(bytes.len());
                bytes[k] = *b;
            }
            if let Ok(text) = std::str::from_utf8(&bytes) {
                if let Ok(c) = Config::from_toml(text) {
                    let _ = c.validate();
                }
            }
        }
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
