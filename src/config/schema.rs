//! The JSON Schema of a configuration file (`splinewatch config-schema`),
//! generated from the config types so it cannot drift: editors that read
//! JSON Schema for TOML (Taplo / Even Better TOML) complete and check keys.
//! The core's types that appear in the config are described here by
//! remote definitions (the core crate does not depend on schemars).

use super::Config;
use schemars::JsonSchema;
use splinewatch_core::identification::oma::{ClusterCriteria, StabilityCriteria};

/// The configuration's JSON Schema (draft 2020-12), pretty-printed.
pub fn config_schema() -> String {
    let schema = schemars::schema_for!(Config);
    serde_json::to_string_pretty(&schema).expect("a schema serialises")
}

/// `[model.material]`: the single-patch deck's orthotropic plate.
#[derive(JsonSchema)]
#[schemars(remote = "splinewatch_core::model::material::OrthotropicParameters")]
#[serde(deny_unknown_fields)]
#[allow(dead_code)]
pub(super) struct OrthotropicParametersDef {
    /// Young's modulus along material axis 1 (Pa).
    e1: f64,
    /// Young's modulus along material axis 2 (Pa).
    e2: f64,
    /// In-plane shear modulus (Pa).
    g12: f64,
    /// Transverse shear modulus, plane 1–3 (Pa).
    g13: f64,
    /// Transverse shear modulus, plane 2–3 (Pa).
    g23: f64,
    /// Poisson's ratio.
    nu12: f64,
    /// Density (kg/m³).
    density: f64,
    /// Angle of material axis 1 from the ξ tangent, about the normal (degrees; default 0).
    #[serde(default)]
    angle_deg: f64,
    /// Transverse shear correction factor (default 5/6).
    #[serde(default = "shear_correction")]
    shear_correction: f64,
}

fn shear_correction() -> f64 {
    5.0 / 6.0
}

/// `[oma.stability]`: when a pole is stable and physical.
#[derive(JsonSchema)]
#[schemars(remote = "splinewatch_core::identification::oma::StabilityCriteria")]
#[serde(deny_unknown_fields)]
#[allow(dead_code)]
pub(super) struct StabilityCriteriaDef {
    /// Number of consecutive lower orders a pole must recur at.
    #[serde(default = "stability_level")]
    level: usize,
    /// Relative frequency tolerance between orders.
    #[serde(default = "stability_frequency")]
    frequency: f64,
    /// Relative damping tolerance between orders.
    #[serde(default = "stability_damping")]
    damping: f64,
    /// `1 − MAC` tolerance between orders.
    #[serde(default = "stability_mac")]
    mac: f64,
    /// Largest plausible damping ratio.
    #[serde(default = "stability_max_damping")]
    max_damping: f64,
    /// Smallest modal phase collinearity of a structural mode.
    #[serde(default = "stability_min_mpc")]
    min_mpc: f64,
}

// The schema's defaults are the core's (one source).
fn stability() -> StabilityCriteria {
    StabilityCriteria::default()
}
fn stability_level() -> usize {
    stability().level
}
fn stability_frequency() -> f64 {
    stability().frequency
}
fn stability_damping() -> f64 {
    stability().damping
}
fn stability_mac() -> f64 {
    stability().mac
}
fn stability_max_damping() -> f64 {
    stability().max_damping
}
fn stability_min_mpc() -> f64 {
    stability().min_mpc
}

/// `[oma.clustering]`: how stable poles group into modes.
#[derive(JsonSchema)]
#[schemars(remote = "splinewatch_core::identification::oma::ClusterCriteria")]
#[serde(deny_unknown_fields)]
#[allow(dead_code)]
pub(super) struct ClusterCriteriaDef {
    /// Single-linkage threshold on `Δf/f + (1 − MAC)`.
    #[serde(default = "clustering_distance")]
    distance: f64,
    /// Fewest poles (distinct orders) of a physical mode, as a fraction of the orders computed.
    #[serde(default = "clustering_min_fraction")]
    min_fraction: f64,
    /// A jackknife replicate has found a mode when its nearest pole is within this distance of the record's
    /// (`Δf/f + 1 − MAC`); default: `distance`. Wider for SRIM on short earthquake records (0.1 on Painter Street).
    #[serde(default)]
    replicate_distance: Option<f64>,
}

fn clustering_distance() -> f64 {
    ClusterCriteria::default().distance
}
fn clustering_min_fraction() -> f64 {
    ClusterCriteria::default().min_fraction
}

/// How the replicates' poles are obtained.
#[derive(JsonSchema)]
#[schemars(remote = "splinewatch_core::identification::oma::UncertaintyMethod")]
#[serde(rename_all = "snake_case")]
#[allow(dead_code)]
pub(super) enum UncertaintyMethodDef {
    /// Each replicate continued to first order from the full window.
    FirstOrder,
    /// Each replicate re-identified.
    Jackknife,
}

/// Which FRF quantity: displacement, velocity or acceleration per force.
#[derive(JsonSchema)]
#[schemars(remote = "splinewatch_core::response::frf::Quantity")]
#[serde(rename_all = "lowercase")]
#[allow(dead_code)]
pub(super) enum QuantityDef {
    Receptance,
    Mobility,
    Accelerance,
}

/// How control limits are set.
#[derive(JsonSchema)]
#[schemars(remote = "splinewatch_core::monitoring::LimitMethod")]
#[serde(rename_all = "snake_case")]
#[allow(dead_code)]
pub(super) enum LimitMethodDef {
    /// From held-out training windows (cross validation), with a scaled-F tail.
    HeldOut,
    /// The textbook phase-II F law (trusts the model).
    Theoretical,
}

/// The solver.
#[derive(JsonSchema)]
#[schemars(remote = "splinewatch_core::updating::Method")]
#[serde(rename_all = "snake_case")]
#[allow(dead_code)]
pub(super) enum MethodDef {
    LevenbergMarquardt,
    /// The paper's plain iterated linearised least squares.
    GaussNewton,
}

/// Residual weighting.
#[derive(JsonSchema)]
#[schemars(remote = "splinewatch_core::updating::Weighting")]
#[serde(rename_all = "snake_case")]
#[allow(dead_code)]
pub(super) enum WeightingDef {
    /// Every residue counts the same (the paper).
    Uniform,
    /// Inverse of the H1 estimator variance `(1 − γ²)/(γ² n_avg) |H|²` (Bendat & Piersol).
    H1Variance,
}
