//! `[updating]`: the solver's settings and the updating parameters.

use super::{err, Config, ConfigError};
use serde::{Deserialize, Serialize};
use splinewatch_core::updating::{LineSelection, Method, Parameter, ParameterKind, UpdateSettings, Weighting};

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
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
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
    /// Threads over the frequency lines of each evaluation (FRFs,
    /// transmissibilities, a record's spectra, their sensitivities; results
    /// do not depend on it); default: the available cores, at most 4.
    pub threads: Option<usize>,
    #[serde(default = "default_method")]
    #[schemars(with = "super::schema::MethodDef")]
    pub method: Method,
    #[serde(default = "default_weighting")]
    #[schemars(with = "super::schema::WeightingDef")]
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
    /// Modal-residue updating (`update --modes`): an identified mode pairs
    /// with the model mode of largest MAC if it is at least this.
    #[serde(default = "default_min_mac")]
    pub min_mac: f64,
    /// … and if their frequencies differ by at most this fraction.
    #[serde(default = "default_max_frequency_gap")]
    pub max_frequency_gap: f64,
    /// What the pipeline's updates fit; default: `"frf"` with a force
    /// sensor, `"modes"` without ([`Config::residues`]).
    pub residues: Option<Residues>,
}

/// What an update fits (`[updating] residues`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum Residues {
    /// The window's FRFs (eq. 36–39), weighted by `weighting`.
    Frf,
    /// The window's identified modes, in their std (modal residues).
    Modes,
    /// Both, each block in its own standard deviations: the FRFs by the H1
    /// estimator's variance whatever `weighting` says, the modes by theirs
    /// (`splinewatch_core::updating::joint`).
    Both,
}

impl Residues {
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Frf => "frf",
            Self::Modes => "modes",
            Self::Both => "both",
        }
    }
}

fn default_max_frequency_gap() -> f64 {
    0.1
}

fn default_min_mac() -> f64 {
    0.8
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

/// The parameters `<prefix><j>` (j from 1) of one updated group of `count`
/// coefficients, with the group's bounds (required: `bounds_key` names them).
fn coefficient_parameters(
    bounds_key: &str,
    bounds: Option<[f64; 2]>,
    prefix: &str,
    count: usize,
    kind: impl Fn(usize) -> ParameterKind,
) -> Result<Vec<Parameter>, ConfigError> {
    let [lower, upper] = bounds.ok_or_else(|| err(bounds_key, "required when update = true"))?;
    Ok((0..count)
        .map(|coefficient| Parameter {
            name: format!("{prefix}{}", coefficient + 1),
            kind: kind(coefficient),
            lower,
            upper,
        })
        .collect())
}

/// What an updating parameter's name (as [`Config::build_parameters`]
/// makes them) stands for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ParameterFamily {
    /// `<spring>.k<j>`: a spring coefficient κ, N/m³.
    Spring,
    /// `<bearing>.kx`, `.ky`, `.kz`: a bearing's stiffness, N/m.
    Bearing,
    /// `<support>.x`, `.y`, `.z` and `.rx`, `.ry`, `.rz`: a support's
    /// component (per metre along an edge; at a beam base, N/m and N m/rad).
    ElasticSupport,
    /// `<field>.s<j>`: a stiffness-field multiplier θ, a ratio.
    StiffnessField,
    /// `<beam>.stiffness`: a beam member's stiffness multiplier θ, a ratio.
    MemberStiffness,
    /// `damping.g<z>`: a damping-curve coefficient γ, a ratio.
    Damping,
    /// `<support>.eta` or `<support>.<component>.eta`: a spring field's,
    /// bearing's or support's loss factor η, a ratio.
    LossFactor,
}

impl Config {
    /// The unit of updating parameter `name`: spring coefficients κ
    /// (`<spring>.k<j>`) in N/m³ (eq. 19), bearings in N/m, supports along
    /// an edge per metre (N/m² for a translation, N m/rad per metre = N/rad
    /// for a rotation), supports at points and beam bases in N/m and N m/rad; the
    /// damping curve's γ (`damping.g<z>`), loss factors (`<support>.eta`)
    /// and stiffness-field multipliers θ (`<field>.s<j>`) are ratios.
    pub fn parameter_unit(&self, name: &str) -> &'static str {
        match self.parameter_family(name) {
            Some(ParameterFamily::Spring) => "N/m³",
            Some(ParameterFamily::Bearing) => "N/m",
            Some(ParameterFamily::ElasticSupport) => {
                let (support, component) = name.rsplit_once('.').unwrap_or((name, ""));
                let along_edge = self
                    .model
                    .supports
                    .iter()
                    .find(|s| s.name == support)
                    .is_none_or(|s| s.edge.is_some());
                match (along_edge, component.starts_with('r')) {
                    (true, true) => "N/rad",
                    (true, false) => "N/m²",
                    (false, true) => "Nm/rad",
                    (false, false) => "N/m",
                }
            }
            _ => "-",
        }
    }

    /// The family of updating parameter `name`, from the entry it is
    /// attached to (the spring field, bearing, support, stiffness field or
    /// beam its name starts with, or the damping curve) and a component that
    /// entry has, not from how the name ends; `None` when no entry of the
    /// config gives it.
    pub fn parameter_family(&self, name: &str) -> Option<ParameterFamily> {
        let m = &self.model;
        let (entry, component) = name.rsplit_once('.')?;
        let numbered = |prefix: char| {
            component
                .strip_prefix(prefix)
                .is_some_and(|j| !j.is_empty() && j.bytes().all(|b| b.is_ascii_digit()))
        };
        let spring = |n: &str| m.springs.iter().any(|s| s.name == n);
        let bearing = |n: &str| m.bearings.iter().any(|b| b.name == n);
        let support = |n: &str| m.supports.iter().any(|s| s.name == n);
        // A component the support itself gives.
        let support_component = |n: &str, c: &str| {
            m.supports
                .iter()
                .any(|s| s.name == n && s.component_names().contains(&c))
        };
        let field = |n: &str| m.stiffness_fields.iter().any(|f| f.name == n);
        let beam = |n: &str| m.beams.iter().any(|b| b.name == n);
        if component == "eta" {
            // `<entry>.eta`, or `<support>.<component>.eta` (`<bearing>.<axis>.eta`).
            let lossy = |n: &str| spring(n) || bearing(n) || support(n) || field(n) || beam(n);
            let by_component = entry.rsplit_once('.').is_some_and(|(owner, c)| {
                support_component(owner, c) || (bearing(owner) && super::patches::BEARING_AXES.contains(&c))
            });
            return (lossy(entry) || by_component).then_some(ParameterFamily::LossFactor);
        }
        if entry == "damping" && m.damping.is_some() && numbered('g') {
            Some(ParameterFamily::Damping)
        } else if spring(entry) && numbered('k') {
            Some(ParameterFamily::Spring)
        } else if bearing(entry) && super::patches::BEARING_AXES.contains(&component) {
            Some(ParameterFamily::Bearing)
        } else if support_component(entry, component) {
            Some(ParameterFamily::ElasticSupport)
        } else if field(entry) && numbered('s') {
            Some(ParameterFamily::StiffnessField)
        } else if beam(entry) && component == "stiffness" {
            Some(ParameterFamily::MemberStiffness)
        } else {
            None
        }
    }
}

impl Config {
    /// The updating parameters: `<spring>.k<j>` for spring fields with
    /// `update = true` (j from 1, η fastest), `<bearing>.kx`, `.ky`, `.kz`
    /// for bearings with `update = true` (those listed with `update = ["ky"]`),
    /// `<support>.<component>` for line supports' updated components, `<field>.s<j>` for stiffness
    /// fields with `update = true`, and `damping.g<z>`.
    pub fn build_parameters(&self) -> Result<Vec<Parameter>, ConfigError> {
        let mut out = Vec::new();
        for (field, s) in self.model.springs.iter().enumerate().filter(|(_, s)| s.update) {
            out.extend(coefficient_parameters(
                &format!("model.springs[{field}].bounds"),
                s.bounds,
                &format!("{}.k", s.name),
                s.stiffness.len(),
                |coefficient| ParameterKind::Spring { field, coefficient },
            )?);
        }
        // The κ fields of bearings and supports (`KappaOrder`).
        let order = super::kappa_order::KappaOrder::of(&self.model);
        let runs = self.bearing_runs()?;
        for (b, count) in runs {
            let bearing = &self.model.bearings[b];
            let [lower, upper] = bearing
                .bounds
                .ok_or_else(|| err(format!("model.bearings[{b}].bounds"), "required when it is updated"))?;
            out.extend(
                super::patches::BEARING_AXES
                    .into_iter()
                    .enumerate()
                    .filter(|&(a, _)| bearing.update.axis(a))
                    .map(|(coefficient, axis)| Parameter {
                        name: format!("{}.{axis}", bearing.name),
                        kind: if count == 1 {
                            ParameterKind::Spring {
                                field: order.bearing_field(b),
                                coefficient,
                            }
                        } else {
                            ParameterKind::SpringRun {
                                field: order.bearing_field(b),
                                count,
                                coefficient,
                            }
                        },
                        lower,
                        upper,
                    }),
            );
        }
        for (s, count) in self.support_runs()? {
            out.extend(self.model.supports[s].parameters(s, order.support_field(s), count)?);
        }
        for (field, count) in self.stiffness_field_runs()? {
            let f = &self.model.stiffness_fields[field];
            if !f.update {
                continue;
            }
            out.extend(coefficient_parameters(
                &format!("model.stiffness_fields[{field}].bounds"),
                f.bounds,
                &format!("{}.s", f.name),
                f.coefficient_count(),
                |coefficient| {
                    if count == 1 {
                        ParameterKind::Stiffness { field, coefficient }
                    } else {
                        ParameterKind::StiffnessRun {
                            field,
                            count,
                            coefficient,
                        }
                    }
                },
            )?);
        }
        out.extend(self.member_stiffness_parameters()?);
        if let Some(d) = self.model.damping.as_ref().filter(|d| d.update) {
            out.extend(coefficient_parameters(
                "model.damping.bounds",
                d.bounds,
                "damping.g",
                d.coefficients.len(),
                |coefficient| ParameterKind::Damping { coefficient },
            )?);
        }
        out.extend(self.loss_factor_parameters()?);
        Ok(out)
    }

    /// `<name>.eta` (or `<name>.<component>.eta`) for every updated
    /// `loss_factor`: one per loss site, tied bearings or supports sharing
    /// their leader's.
    fn loss_factor_parameters(&self) -> Result<Vec<Parameter>, ConfigError> {
        let sites = self.loss_sites()?;
        Ok(sites
            .iter()
            .enumerate()
            .filter_map(|(site, s)| {
                let [lower, upper] = s.factor.updated()?;
                Some(Parameter {
                    name: format!("{}.eta", s.name),
                    kind: ParameterKind::LossFactor { field: site, count: 1 },
                    lower,
                    upper,
                })
            })
            .collect())
    }

    /// Every stiffness field with the number of fields tied to it after it,
    /// plus one (`tie`; a tied field is in its leader's run, not listed).
    fn stiffness_field_runs(&self) -> Result<Vec<(usize, usize)>, ConfigError> {
        super::tie::tied_runs(
            &self.model.stiffness_fields,
            "model.stiffness_fields",
            "field",
            super::model::StiffnessFieldConfig::tie_mismatch,
        )
    }

    /// The updated bearings that lead a run (`tie`), with the run's length
    /// (1: no bearing tied to it). A tied bearing follows its leader or
    /// another bearing tied to it, updates the same axes and has the same
    /// stiffness along them.
    fn bearing_runs(&self) -> Result<Vec<(usize, usize)>, ConfigError> {
        let bearings = &self.model.bearings;
        let mut runs: Vec<(usize, usize)> = Vec::new();
        for (b, bearing) in bearings.iter().enumerate() {
            bearing.update.check(&format!("model.bearings[{b}].update"))?;
            let Some(leader) = &bearing.tie else {
                if (0..3).any(|a| bearing.update.axis(a)) {
                    runs.push((b, 1));
                }
                continue;
            };
            let key = format!("model.bearings[{b}].tie");
            let run = runs
                .last_mut()
                .filter(|(l, count)| bearings[*l].name == *leader && l + *count == b)
                .ok_or_else(|| {
                    err(
                        &key,
                        format!(
                            "{leader:?} must be an updated bearing just before this one (or before bearings tied to it)"
                        ),
                    )
                })?;
            let first = &bearings[run.0];
            if let Some(a) = (0..3).find(|&a| {
                first.update.axis(a) != bearing.update.axis(a)
                    || (first.update.axis(a) && first.stiffness[a] != bearing.stiffness[a])
            }) {
                return Err(err(
                    &key,
                    format!(
                        "a tied bearing updates the same axes with the same stiffness as {leader:?}: {} differs",
                        super::patches::BEARING_AXES[a]
                    ),
                ));
            }
            run.1 += 1;
        }
        Ok(runs)
    }

    /// `[updating]` as solver settings.
    /// What the pipeline's updates fit: `[updating] residues`, or `"frf"`
    /// with a force sensor and `"modes"` without. FRF residues need a force
    /// sensor; modal residues need the windows' modes, identified
    /// output-only or, with a force sensor, when `[oma]` is given.
    pub fn residues(&self) -> Result<Residues, ConfigError> {
        let output_only = self.is_output_only();
        let residues = self
            .updating
            .residues
            .unwrap_or(if output_only { Residues::Modes } else { Residues::Frf });
        let needs_force = matches!(residues, Residues::Frf | Residues::Both);
        if needs_force && output_only {
            return Err(err(
                "updating.residues",
                format!("{:?} needs a force sensor: no sensor measures force", residues.as_str()),
            ));
        }
        if residues != Residues::Frf && !self.runs_oma() {
            return Err(err(
                "updating.residues",
                format!(
                    "{:?} fits the windows' identified modes: with a force sensor, add [oma] to identify them",
                    residues.as_str()
                ),
            ));
        }
        Ok(residues)
    }

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
        if !(0.0..1.0).contains(&u.min_mac) {
            return Err(err("updating.min_mac", format!("must be in [0, 1), got {}", u.min_mac)));
        }
        positive("max_frequency_gap", u.max_frequency_gap)?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use splinewatch_core::updating::ParameterKind;

    /// Every parameter of every bundled config has the family of what it is
    /// built on: the family found from the entry its name starts with agrees
    /// with the kind `build_parameters` gives it (κ fields where
    /// `KappaOrder` puts them).
    #[test]
    fn each_parameter_has_the_family_of_what_it_is_attached_to() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let mut seen = std::collections::BTreeSet::new();
        for dir in ["config", "config/examples"] {
            for entry in std::fs::read_dir(root.join(dir)).unwrap() {
                let path = entry.unwrap().path();
                if path.extension().is_none_or(|e| e != "toml") {
                    continue;
                }
                let config = Config::from_toml(&std::fs::read_to_string(&path).unwrap()).unwrap();
                let order = crate::config::kappa_order::KappaOrder::of(&config.model);
                for p in config.build_parameters().unwrap() {
                    let family = config.parameter_family(&p.name);
                    let expected = match p.kind {
                        ParameterKind::Spring { field, .. } | ParameterKind::SpringRun { field, .. } => {
                            if field < order.bearing_field(0) {
                                ParameterFamily::Spring
                            } else if field < order.support_field(0) {
                                ParameterFamily::Bearing
                            } else {
                                ParameterFamily::ElasticSupport
                            }
                        }
                        ParameterKind::Stiffness { field, .. } | ParameterKind::StiffnessRun { field, .. } => {
                            if field < config.model.stiffness_fields.len() {
                                ParameterFamily::StiffnessField
                            } else {
                                ParameterFamily::MemberStiffness
                            }
                        }
                        ParameterKind::Damping { .. } => ParameterFamily::Damping,
                        ParameterKind::LossFactor { .. } => ParameterFamily::LossFactor,
                    };
                    assert_eq!(family, Some(expected), "{}: {}", path.display(), p.name);
                    seen.insert(format!("{expected:?}"));
                }
            }
        }
        // The bundled configs update springs, bearings, supports, beams,
        // the damping curve and loss factors.
        assert!(seen.len() >= 5, "only {seen:?}");
        let config = Config::from_toml(include_str!("../../config/painter-street-bridge.toml")).unwrap();
        assert_eq!(config.parameter_family("no_such_support.ry"), None);
        assert_eq!(config.parameter_family("damping"), None);
    }
}
