//! Support groups and ground sensors (issue 44): `support = "<group>"` on
//! `[[model.springs]]`, `[[model.bearings]]` and `[[model.constraints]]`
//! (default `"ground"`), and `[[sensors]]` entries with `support` that measure
//! a group's ground acceleration along `x`, `y` or `z`.
//!
//! The model's ground inputs are every group along every axis some ground
//! sensor measures: a group's own sensors along that axis averaged, or, when
//! it has none, the mean of the groups measured along it. An axis no ground
//! sensor measures is no input (that ground does not move).

use super::{err, Config, ConfigError, DirectionConfig};
use splinewatch_core::model::supports::{SupportGroups, DEFAULT_GROUP};
use splinewatch_core::model::BridgeModel;
use splinewatch_core::response::support_motion::GroundInput;

const AXES: [&str; 3] = ["x", "y", "z"];

/// A ground sensor's axis and polarity from its `direction`: `"x"` or
/// `"-x"` (a channel whose positive sense points along −x, as a station's
/// "Long" channels may), likewise y and z.
fn ground_axis(direction: &DirectionConfig) -> Option<(usize, bool)> {
    let v = direction.axis_vector()?;
    let axis = v.iter().position(|c| *c != 0.0)?;
    Some((axis, v[axis] < 0.0))
}

/// One ground input of the model and the ground sensors it is made of.
#[derive(Debug, Clone, PartialEq)]
pub struct GroundInputPlan {
    pub input: GroundInput,
    /// `<group>.<axis>`, e.g. `bent.y`.
    pub name: String,
    /// Indices into `[[sensors]]` averaged for this input.
    pub sensors: Vec<usize>,
    /// Those of `sensors` whose positive sense is the axis' negative one
    /// (`direction = "-x"`): their samples enter with the opposite sign.
    pub inverted: Vec<usize>,
    /// The groups whose mean it takes when it has no sensor of its own
    /// (empty when it has).
    pub borrowed_from: Vec<String>,
}

impl GroundInputPlan {
    /// What `check-config` prints: `bent.y ← ch3` or `west.x ← mean of east.x, bent.x`.
    pub fn describe(&self, config: &Config) -> String {
        if self.borrowed_from.is_empty() {
            let names: Vec<String> = self
                .sensors
                .iter()
                .map(|&i| {
                    let sign = if self.inverted.contains(&i) { "−" } else { "" };
                    format!("{sign}{}", config.sensors[i].name)
                })
                .collect();
            let how = if names.len() > 1 { "mean of " } else { "" };
            format!("{} ← {how}{}", self.name, names.join(", "))
        } else {
            let axis = AXES[self.input.axis];
            let from: Vec<String> = self.borrowed_from.iter().map(|g| format!("{g}.{axis}")).collect();
            format!("{} ← mean of {} (no sensor of its own)", self.name, from.join(", "))
        }
    }
}

impl Config {
    /// The number of deck sensors: they come first in `sensors`.
    pub fn deck_sensor_count(&self) -> usize {
        self.sensors.iter().take_while(|s| s.support.is_none()).count()
    }

    /// Whether any `[[sensors]]` entry measures a ground (support motion).
    pub fn has_ground_sensors(&self) -> bool {
        self.deck_sensor_count() < self.sensors.len()
    }

    /// Checks the ground sensors (keys as written) and moves them after the
    /// deck's, keeping both orders.
    pub(super) fn place_ground_sensors_last(&mut self) -> Result<(), ConfigError> {
        for (i, s) in self.sensors.iter().enumerate() {
            let Some(group) = &s.support else { continue };
            let key = |k: &str| format!("sensors[{i}].{k}");
            if group.trim().is_empty() {
                return Err(err(key("support"), "must name a support group"));
            }
            if s.patch.is_some()
                || s.xi.is_some()
                || s.eta.is_some()
                || s.x.is_some()
                || s.y.is_some()
                || s.z.is_some()
                || s.offset.is_some()
            {
                return Err(err(
                    key("support"),
                    "a ground sensor has no position on the deck: remove patch, xi, eta, x, y, z and offset",
                ));
            }
            if ground_axis(&s.direction).is_none() {
                return Err(err(
                    key("direction"),
                    "a ground sensor measures along \"x\", \"y\" or \"z\" (or \"-x\", \"-y\", \"-z\" for a channel pointing the other way)",
                ));
            }
            if s.quantity.as_slice() != ["acceleration"] {
                return Err(err(key("quantity"), "a ground sensor measures acceleration only"));
            }
        }
        let (deck, ground): (Vec<_>, Vec<_>) = std::mem::take(&mut self.sensors)
            .into_iter()
            .partition(|s| s.support.is_none());
        self.sensors = deck.into_iter().chain(ground).collect();
        Ok(())
    }

    /// The support group of every spring field, bearing, constraint and
    /// held beam base of `model` (built from this config), groups in order
    /// of first mention.
    pub fn support_groups(&self, model: &BridgeModel) -> Result<SupportGroups, ConfigError> {
        let m = &self.model;
        let named = |s: &Option<String>| s.clone().unwrap_or_else(|| DEFAULT_GROUP.to_string());
        let springs: Vec<String> = m
            .springs
            .iter()
            .map(|s| named(&s.support))
            .chain(m.bearings.iter().map(|b| named(&b.support)))
            .chain(m.supports.iter().map(|s| named(&s.support)))
            .collect();
        let constraints: Vec<String> = m.constraints.iter().map(|c| named(&c.support)).collect();
        // Only a held beam base follows a ground: a free one, or one on a
        // support (that support's springs do), names none.
        let bases: Vec<Option<String>> = m
            .beams
            .iter()
            .map(|b| matches!(b.base.as_str(), "fixed" | "pinned").then(|| named(&b.support)))
            .collect();
        let mut names: Vec<String> = Vec::new();
        for n in springs.iter().chain(&constraints).chain(bases.iter().flatten()) {
            if !names.contains(n) {
                names.push(n.clone());
            }
        }
        let index = |n: &String| names.iter().position(|g| g == n).expect("listed above");
        let of_springs = springs.iter().map(index).collect();
        let of_constraints = constraints.iter().map(index).collect();
        let of_bases = bases.iter().map(|b| b.as_ref().map_or(0, index)).collect();
        SupportGroups::new(names.clone(), of_springs, of_constraints, model)
            .and_then(|groups| groups.with_beam_bases(of_bases, model))
            .map_err(|e| err("model", e))
    }

    /// The ground inputs and the sensors behind each (empty without ground
    /// sensors).
    pub fn ground_plan(&self, groups: &SupportGroups) -> Result<Vec<GroundInputPlan>, ConfigError> {
        self.ground_plan_of(groups.names())
    }

    /// The ground inputs of a config without a model (identification and
    /// the events' verdicts): each support group a ground sensor names, in
    /// the order they are first named.
    pub fn ground_plan_of_sensors(&self) -> Result<Vec<GroundInputPlan>, ConfigError> {
        let mut names: Vec<String> = Vec::new();
        for s in &self.sensors {
            if let Some(group) = &s.support {
                if !names.contains(group) {
                    names.push(group.clone());
                }
            }
        }
        self.ground_plan_of(&names)
    }

    /// The ground inputs of the support groups `names` (the model's, or
    /// the sensors' own).
    fn ground_plan_of(&self, names: &[String]) -> Result<Vec<GroundInputPlan>, ConfigError> {
        let first = self.deck_sensor_count();
        let mut own: Vec<[Vec<usize>; 3]> = vec![Default::default(); names.len()];
        let mut inverted = Vec::new();
        for (i, s) in self.sensors.iter().enumerate().skip(first) {
            let group = s.support.as_deref().unwrap_or_default();
            let Some(g) = names.iter().position(|n| n == group) else {
                return Err(err(
                    format!("sensors[{i}].support"),
                    format!(
                        "{group:?} is no support group of the model (its springs, bearings, line supports, constraints and beam bases name {})",
                        names.join(", ")
                    ),
                ));
            };
            let (axis, flipped) = ground_axis(&s.direction).expect("checked on load");
            if flipped {
                inverted.push(i);
            }
            own[g][axis].push(i);
        }
        let mut plan = Vec::new();
        for axis in 0..3 {
            let measured: Vec<String> = (0..own.len())
                .filter(|&g| !own[g][axis].is_empty())
                .map(|g| names[g].clone())
                .collect();
            if measured.is_empty() {
                continue;
            }
            for (g, name) in names.iter().enumerate() {
                let sensors = own[g][axis].clone();
                let borrowed_from = if sensors.is_empty() {
                    measured.clone()
                } else {
                    Vec::new()
                };
                plan.push(GroundInputPlan {
                    input: GroundInput { group: g, axis },
                    name: format!("{name}.{}", AXES[axis]),
                    inverted: sensors.iter().copied().filter(|i| inverted.contains(i)).collect(),
                    sensors,
                    borrowed_from,
                });
            }
        }
        Ok(plan)
    }
}

/// The config indices of the ground sensors `plan` reads, ascending.
pub fn ground_sensors(plan: &[GroundInputPlan]) -> Vec<usize> {
    let mut all: Vec<usize> = plan.iter().flat_map(|p| p.sensors.iter().copied()).collect();
    all.sort_unstable();
    all.dedup();
    all
}

/// `plan` with only the ground sensors `available` (a record may lack a
/// channel): an input that loses all its sensors takes the mean of the groups
/// still measured along its axis, or none (zero ground motion) when no group
/// is; each change is said in the returned notes.
pub fn restrict_plan(
    plan: &[GroundInputPlan],
    available: impl Fn(usize) -> bool,
    names: impl Fn(usize) -> String,
) -> (Vec<GroundInputPlan>, Vec<String>) {
    let mut notes = Vec::new();
    let mut out: Vec<GroundInputPlan> = plan.to_vec();
    for p in &mut out {
        let missing: Vec<usize> = p.sensors.iter().copied().filter(|&i| !available(i)).collect();
        if !missing.is_empty() {
            let list: Vec<String> = missing.iter().map(|&i| names(i)).collect();
            notes.push(format!("{}: the record has no {}", p.name, list.join(", ")));
            p.sensors.retain(|&i| available(i));
        }
    }
    for k in 0..out.len() {
        if !out[k].sensors.is_empty() {
            continue;
        }
        let axis = out[k].input.axis;
        let measured: Vec<String> = out
            .iter()
            .filter(|q| q.input.axis == axis && !q.sensors.is_empty())
            .map(|q| q.name.rsplit_once('.').map_or(q.name.clone(), |(g, _)| g.to_string()))
            .collect();
        if measured != out[k].borrowed_from {
            notes.push(if measured.is_empty() {
                format!(
                    "{}: no ground sensor along this axis in the record: taken as still",
                    out[k].name
                )
            } else {
                format!("{}: takes the mean of {}", out[k].name, measured.join(", "))
            });
        }
        out[k].borrowed_from = measured;
    }
    (out, notes)
}

/// The input signals of `plan` from the ground sensors' samples
/// (`channel(i)` the samples of `[[sensors]]` entry `i`, all of one length).
pub fn ground_signals<'a>(plan: &[GroundInputPlan], channel: impl Fn(usize) -> &'a [f64]) -> Vec<Vec<f64>> {
    let mean = |p: &GroundInputPlan| -> Vec<f64> {
        let indices = &p.sensors;
        let n = channel(indices[0]).len();
        let mut out = vec![0.0; n];
        for &i in indices {
            let sign = if p.inverted.contains(&i) { -1.0 } else { 1.0 };
            for (o, v) in out.iter_mut().zip(channel(i)) {
                *o += sign * v / indices.len() as f64;
            }
        }
        out
    };
    let own: Vec<Option<Vec<f64>>> = plan.iter().map(|p| (!p.sensors.is_empty()).then(|| mean(p))).collect();
    plan.iter()
        .enumerate()
        .map(|(k, p)| match &own[k] {
            Some(signal) => signal.clone(),
            None => {
                let donors: Vec<&Vec<f64>> = plan
                    .iter()
                    .zip(&own)
                    .filter(|(q, s)| q.input.axis == p.input.axis && s.is_some())
                    .filter_map(|(_, s)| s.as_ref())
                    .collect();
                let Some(first) = donors.first() else {
                    // No ground sensor along this axis: the ground is still.
                    let n = own.iter().flatten().next().map_or(0, Vec::len);
                    return vec![0.0; n];
                };
                let n = first.len();
                (0..n)
                    .map(|t| donors.iter().map(|d| d[t]).sum::<f64>() / donors.len() as f64)
                    .collect()
            }
        })
        .collect()
}
