//! `[[model.beams]]`, `[[model.rigid]]` and `[[model.supports]]`: the
//! columns, piers, caps, footings and abutments under the deck, built into
//! the core's beam members, rigid bodies and elastic supports.

use super::super::patches::{default_true, face_tau, locate, material_table, BearingUpdate, FaceConfig};
use super::*;
use crate::config::ComponentLossFactor;
use splinewatch_core::model::beam::{BeamError, Section};
use splinewatch_core::model::elastic_supports::{ElasticSupport, ElasticSupportError, SupportComponent};
use splinewatch_core::model::members::{BeamBase, BeamMember, BeamNet, MemberError};
use splinewatch_core::model::rigid::{RigidBody, RigidError};
use splinewatch_core::solvers::dense_model::ModelError;
use splinewatch_core::updating::{Parameter, ParameterKind};

/// `[[model.beams]]`: a straight member from `start` to `end` (a column, a
/// pier), cut into `elements` Timoshenko elements. Members whose nodes
/// coincide (within `joint_tolerance`) are joined rigidly there.
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BeamConfig {
    /// Unique among the beams; `"<name>:start"` and `"<name>:end"` name its
    /// ends in `[[model.rigid]] beam_ends`.
    pub name: String,
    /// The start (the base), metres, global axes.
    pub start: [f64; 3],
    pub end: [f64; 3],
    pub section: SectionConfig,
    /// The section's local y axis (made normal to the member).
    pub orientation: [f64; 3],
    /// A name from `[model.materials]` (isotropic).
    pub material: String,
    /// Elements along the member (default 8).
    #[serde(default = "default_elements")]
    pub elements: usize,
    /// How the start is held: `"fixed"`, `"pinned"` (translations),
    /// `"free"` (the default: it meets another member or a rigid body), or
    /// the name of a `[[model.supports]]` entry without an `edge`: a
    /// footing's springs in six components to that support's ground.
    #[serde(default = "default_base")]
    pub base: String,
    /// The support group whose ground a fixed or pinned base follows
    /// (default "ground"; a base on a support follows the support's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub support: Option<String>,
    /// A multiplier θ on part of the member's stiffness, held or updated
    /// (`<name>.stiffness`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stiffness: Option<BeamStiffnessConfig>,
    /// Another beam's name, just before this one in `[[model.beams]]` (or
    /// before beams tied to it): this one takes its `stiffness` parameter
    /// (one cracked-section factor for every column of a bent) and its
    /// `loss_factor`. Both give `stiffness` with the same `value` and
    /// `scales`, both updated or both held (then they share the loss factor
    /// alone); this one no `bounds` or `loss_factor`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tie: Option<String>,
    /// The loss factor η of the part of the member's stiffness `stiffness`
    /// scales (a column's cracking hysteresis; needs `stiffness`): modes
    /// whose strain energy sits in it are damped by `½ η × its share`, on
    /// top of `[model.damping]`'s ζ(f). A number is held;
    /// `{ value, bounds }` is updated (parameter `<name>.eta`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub loss_factor: Option<crate::config::LossFactorConfig>,
}

/// `stiffness = { value, scales, bounds, update }` of a `[[model.beams]]`
/// entry: θ multiplies the part `scales` names of the member's stiffness
/// (`"all"`: E and G; `"bending"`: E I with its shear stiffness, a cracked
/// section's effective stiffness; `"axial"`: E A; `"torsion"`: G J).
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BeamStiffnessConfig {
    /// The start value of θ (default 1: the section and material as given).
    #[serde(default = "one")]
    pub value: f64,
    /// `"all"` (the default), `"bending"`, `"axial"` or `"torsion"`.
    #[serde(default = "all")]
    pub scales: String,
    /// `[lower, upper]` of θ when it is updated (required then).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bounds: Option<[f64; 2]>,
    /// Whether updating takes θ (default true; false holds it at `value`).
    #[serde(default = "default_true")]
    pub update: bool,
}

fn one() -> f64 {
    1.0
}

fn all() -> String {
    "all".into()
}

fn default_elements() -> usize {
    8
}

fn default_base() -> String {
    "free".into()
}

/// A beam's section: `{ circle = d }` (a solid circle of diameter `d`),
/// `{ rectangle = [width, depth] }` (width along the local y axis), or its
/// properties `{ area, iy, iz, torsion, shear_area_y, shear_area_z }` (m², m⁴).
#[derive(Debug, Clone, Default, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SectionConfig {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub circle: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rectangle: Option<[f64; 2]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub area: Option<f64>,
    /// Second moment for bending in the local x–z plane (m⁴).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub iy: Option<f64>,
    /// Second moment for bending in the local x–y plane (m⁴).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub iz: Option<f64>,
    /// Saint-Venant torsion constant (m⁴).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub torsion: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shear_area_y: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shear_area_z: Option<f64>,
}

/// `[[model.rigid]]`: a rigid body (a bent cap, a diaphragm) that deck edges
/// and beam ends follow exactly.
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RigidConfig {
    pub name: String,
    /// Patch edges that move with it.
    #[serde(default)]
    pub edges: Vec<EdgeRefConfig>,
    /// Beam ends that move with it: `"<beam>:start"` or `"<beam>:end"`.
    #[serde(default)]
    pub beam_ends: Vec<String>,
}

/// One edge of a patch: `{ patch = "span1", edge = "xi1" }`.
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct EdgeRefConfig {
    /// The patch (default: the only patch).
    pub patch: Option<String>,
    pub edge: EdgeConfig,
}

impl SectionConfig {
    fn build(&self, poisson: f64, key: &str) -> Result<Section, ConfigError> {
        let properties = [
            self.area,
            self.iy,
            self.iz,
            self.torsion,
            self.shear_area_y,
            self.shear_area_z,
        ];
        let given = properties.iter().filter(|p| p.is_some()).count();
        let section = match (self.circle, self.rectangle, given) {
            (Some(d), None, 0) => Section::circle(d, poisson),
            (None, Some([w, d]), 0) => Section::rectangle(w, d, poisson),
            (None, None, 6) => {
                let [area, iy, iz, torsion, ay, az] = properties.map(|p| p.expect("all six given"));
                Section::new(area, iy, iz, torsion, ay, az)
            }
            _ => {
                return Err(err(
                    key,
                    "give { circle = d }, { rectangle = [width, depth] }, or all of area, iy, iz, torsion, shear_area_y and shear_area_z",
                ))
            }
        };
        section.map_err(|e| err(key, e))
    }
}

impl Config {
    /// The beam members of `[[model.beams]]` and their net.
    pub(super) fn build_beams(&self) -> Result<BeamNet, ConfigError> {
        let m = &self.model;
        let mut members = Vec::with_capacity(m.beams.len());
        for (i, b) in m.beams.iter().enumerate() {
            let key = |k: &str| format!("model.beams[{i}].{k}");
            if m.beams[..i].iter().any(|o| o.name == b.name) {
                return Err(err(key("name"), format!("{:?} names two beams", b.name)));
            }
            let material_key = format!("model.materials.{}", b.material);
            let table = material_table(&m.materials, &b.material, &key("material"))?;
            let material = table.beam(&material_key)?;
            let poisson = table.poisson.expect("a beam's material is isotropic");
            let section = b.section.build(poisson, &key("section"))?;
            let base = match b.base.as_str() {
                "fixed" => BeamBase::Fixed,
                "pinned" => BeamBase::Pinned,
                "free" => BeamBase::Free,
                other => match m.supports.iter().find(|s| s.name == other) {
                    Some(s) if s.edge.is_some() || s.at.is_some() => {
                        return Err(err(
                            key("base"),
                            format!("{other:?} is a support on a patch (it has an `edge` or `at`): a base stands on a support without either"),
                        ))
                    }
                    Some(s) if b.support.is_some() && b.support != s.support => {
                        return Err(err(
                            key("support"),
                            format!("the base stands on support {other:?}, whose own `support` key names its ground: leave this out"),
                        ))
                    }
                    // The support's springs hold it: free in the member.
                    Some(_) => BeamBase::Free,
                    None => {
                        return Err(err(
                            key("base"),
                            format!("{other:?}: give \"fixed\", \"pinned\", \"free\" or the name of a [[model.supports]] entry without an `edge`"),
                        ))
                    }
                },
            };
            let member = BeamMember::new(
                &b.name,
                (b.start, b.end),
                b.orientation,
                section,
                material,
                b.elements,
                base,
            )
            .map_err(|e| match &e {
                MemberError::NoElements { .. } => err(key("elements"), e),
                MemberError::EmptyName => err(key("name"), e),
                MemberError::Beam { source, .. } => match source {
                    BeamError::ZeroLength(_) => err(key("end"), e),
                    BeamError::Orientation { .. } => err(key("orientation"), e),
                    _ => err(key("section"), e),
                },
            })?;
            members.push(member);
        }
        BeamNet::new(members, m.joint_tolerance).map_err(|e| err("model.beams", e))
    }

    /// The rigid bodies of `[[model.rigid]]` on `patches` and `beams`.
    pub(super) fn build_rigid_bodies(&self, patches: &[Patch], beams: &BeamNet) -> Result<Vec<RigidBody>, ConfigError> {
        let m = &self.model;
        let mut bodies = Vec::with_capacity(m.rigid.len());
        for (i, r) in m.rigid.iter().enumerate() {
            let key = |k: String| format!("model.rigid[{i}].{k}");
            if m.rigid[..i].iter().any(|o| o.name == r.name) {
                return Err(err(key("name".into()), format!("{:?} names two rigid bodies", r.name)));
            }
            let edges = r
                .edges
                .iter()
                .enumerate()
                .map(|(j, e)| {
                    let patch = patch_index(patches, e.patch.as_deref(), &key(format!("edges[{j}].patch")))?;
                    Ok((patch, e.edge.into()))
                })
                .collect::<Result<Vec<_>, ConfigError>>()?;
            let nodes = r
                .beam_ends
                .iter()
                .enumerate()
                .map(|(j, end)| beam_end(beams, end).map_err(|why| err(key(format!("beam_ends[{j}]")), why)))
                .collect::<Result<Vec<_>, ConfigError>>()?;
            let body = RigidBody::new(&r.name, edges, nodes).map_err(|e| match e {
                RigidError::Empty(_) => err(key("edges".into()), format!("{e}")),
                _ => err(key("name".into()), e),
            })?;
            bodies.push(body);
        }
        Ok(bodies)
    }

    /// Surfaces a rigid body holding what a support or another body holds,
    /// with the body's key.
    pub(super) fn check_rigid_bodies(&self, model: &BridgeModel) -> Result<(), ConfigError> {
        match model.reduction() {
            Err(ModelError::Rigid(e)) => {
                let name = match &e {
                    RigidError::Conflict { name, .. }
                    | RigidError::UnknownPatch { name, .. }
                    | RigidError::UnknownBeamNode { name, .. }
                    | RigidError::Empty(name) => name.clone(),
                    RigidError::EmptyName => String::new(),
                };
                let i = self.model.rigid.iter().position(|r| r.name == name).unwrap_or(0);
                Err(err(format!("model.rigid[{i}]"), e))
            }
            Err(e) => Err(err("model", e)),
            Ok(_) => Ok(()),
        }
    }
}

/// The beam node `"<beam>:start"` or `"<beam>:end"` names.
fn beam_end(beams: &BeamNet, end: &str) -> Result<usize, String> {
    let (name, which) = end
        .rsplit_once(':')
        .ok_or_else(|| format!("{end:?}: write \"<beam>:start\" or \"<beam>:end\""))?;
    let member = beams.members().iter().position(|m| m.name() == name).ok_or_else(|| {
        let known: Vec<&str> = beams.members().iter().map(BeamMember::name).collect();
        format!("{name:?} is not a beam (beams: {known:?})")
    })?;
    let nodes = beams.member_nodes(member);
    match which {
        "start" => Ok(nodes[0]),
        "end" => Ok(nodes[nodes.len() - 1]),
        other => Err(format!("{other:?}: a beam end is \"start\" or \"end\"")),
    }
}

/// `[[model.supports]]`: springs in up to six components, per metre along a
/// patch edge (an integral abutment's backfill and piles, an embankment),
/// at a point of a patch (`at`: a bearing that also restrains rotations, a
/// pile cap), or, without `edge` or `at`, at the base of every beam whose
/// `base` names it (a column's footing on its piles and soil).
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SupportConfig {
    /// Unique among springs, bearings, fields and supports: it prefixes the
    /// updating parameters `<name>.<component>`.
    pub name: String,
    /// The patch edge it acts along; neither this nor `at`: it acts at the
    /// bases of the beams whose `base` names it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub edge: Option<EdgeRefConfig>,
    /// m: the point of a patch it acts at, instead of an edge (within
    /// 0.5 m of the patch, as a bearing's).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub at: Option<[f64; 3]>,
    /// With `at`: the patch (default: the nearest).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub patch: Option<String>,
    /// With `at`: the face it acts on (default: the bottom, as a
    /// bearing's); its translations then follow the section's rotation.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub surface: Option<FaceConfig>,
    /// The support group whose ground it stands on (default "ground").
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub support: Option<String>,
    /// Components: `x`, `y`, `z` (N/m per metre along an edge, N/m at a
    /// point or a base) and `rx`, `ry`, `rz` (N m/rad per metre, N m/rad),
    /// along the support's axes.
    pub stiffness: ComponentsConfig,
    /// The support's axes as three orthonormal rows, right-handed (a skewed
    /// abutment's line); default the global axes.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub axes: Option<[[f64; 3]; 3]>,
    /// The abutment line's skew in degrees, instead of `axes`: `x` across
    /// the line, `y` along it (turned by this angle from the global y
    /// axis, counter-clockwise seen from above), `z` up.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub skew_deg: Option<f64>,
    /// `[lower, upper]` for each updated component.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bounds: Option<[f64; 2]>,
    /// `true` (default): every given component is updated; `false`: none;
    /// a list (`["z", "ry"]`): those.
    #[serde(default)]
    pub update: BearingUpdate,
    /// The support's loss factor η (hysteretic damping: 0.1 = 10 %): modes
    /// whose strain energy sits in it are damped more, by
    /// `½ η × (its share of the mode's strain energy)` on top of
    /// `[model.damping]`'s ζ(f). A number is held; `{ value, bounds }` is
    /// updated (parameter `<name>.eta`); `{ y = 0.3, z = 0.05 }` acts on
    /// the components named only, each its own (parameter
    /// `<name>.<component>.eta` when updated: an abutment's soil damping
    /// its lateral motion, not its bearing's vertical one).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub loss_factor: Option<ComponentLossFactor>,
    /// Another support's name, just before this one in `[[model.supports]]`
    /// (or before supports tied to it): this one takes its updating
    /// parameters and its loss factor (one soil under both abutments). It
    /// gives the same components with the same stiffness, updates the same
    /// ones, on the same kind of site, and no `bounds` or `loss_factor` of
    /// its own.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tie: Option<String>,
}

/// A line support's stiffness per component.
#[derive(Debug, Clone, Default, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ComponentsConfig {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub x: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub y: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub z: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rx: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ry: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rz: Option<f64>,
}

impl ComponentsConfig {
    /// The given components in the order `x, y, z, rx, ry, rz`.
    fn given(&self) -> Vec<(SupportComponent, f64)> {
        let values = [self.x, self.y, self.z, self.rx, self.ry, self.rz];
        SupportComponent::ALL
            .into_iter()
            .zip(values)
            .filter_map(|(c, v)| v.map(|v| (c, v)))
            .collect()
    }
}

impl SupportConfig {
    /// The names of the given components, in κ order (`x, y, z, rx, ry, rz`).
    pub fn component_names(&self) -> Vec<&'static str> {
        self.stiffness.given().iter().map(|(c, _)| c.name()).collect()
    }

    /// Whether component `c` is updated.
    fn updates(&self, c: SupportComponent) -> bool {
        match &self.update {
            BearingUpdate::Every(on) => *on,
            BearingUpdate::Axes(list) => list.iter().any(|n| n == c.name()),
        }
    }

    /// The updating parameters of support `index`, κ field `field`, with
    /// the `count − 1` supports tied to it after it.
    pub fn parameters(&self, index: usize, field: usize, count: usize) -> Result<Vec<Parameter>, ConfigError> {
        let key = |k: &str| format!("model.supports[{index}].{k}");
        let given = self.stiffness.given();
        if let BearingUpdate::Axes(list) = &self.update {
            if let Some(bad) = list.iter().find(|n| !given.iter().any(|(c, _)| c.name() == n.as_str())) {
                return Err(err(
                    key("update"),
                    format!("{bad:?} is not a component of this support's stiffness"),
                ));
            }
        }
        let updated: Vec<(usize, SupportComponent)> = given
            .iter()
            .enumerate()
            .filter(|(_, (c, _))| self.updates(*c))
            .map(|(k, (c, _))| (k, *c))
            .collect();
        if updated.is_empty() {
            return Ok(Vec::new());
        }
        let [lower, upper] = self
            .bounds
            .ok_or_else(|| err(key("bounds"), "required when it is updated"))?;
        Ok(updated
            .into_iter()
            .map(|(coefficient, c)| Parameter {
                name: format!("{}.{}", self.name, c.name()),
                kind: if count == 1 {
                    ParameterKind::Spring { field, coefficient }
                } else {
                    ParameterKind::SpringRun {
                        field,
                        count,
                        coefficient,
                    }
                },
                lower,
                upper,
            })
            .collect())
    }

    /// Why `self` (support `index`) cannot be tied to `leader`, if it cannot.
    fn tie_mismatch(&self, leader: &SupportConfig) -> Option<String> {
        let components = |s: &SupportConfig| -> Vec<(&'static str, f64, bool)> {
            s.stiffness
                .given()
                .iter()
                .map(|&(c, v)| (c.name(), v, s.updates(c)))
                .collect()
        };
        if self.bounds.is_some() {
            return Some(format!(
                "a tied support takes the bounds of {:?}: remove its own",
                leader.name
            ));
        }
        if (self.edge.is_some(), self.at.is_some()) != (leader.edge.is_some(), leader.at.is_some()) {
            return Some(format!(
                "a tied support stands on the same kind of site as {:?} (along an edge, at a point, or under beams)",
                leader.name
            ));
        }
        (components(self) != components(leader)).then(|| {
            format!(
                "a tied support gives the same components with the same stiffness as {:?}, and updates the same ones",
                leader.name
            )
        })
    }
}

impl Config {
    /// Every support with the number of supports tied to it after it, plus
    /// one (`tie`; a tied support is in its leader's run, not listed).
    pub(crate) fn support_runs(&self) -> Result<Vec<(usize, usize)>, ConfigError> {
        crate::config::tie::tied_runs(
            &self.model.supports,
            "model.supports",
            "support",
            SupportConfig::tie_mismatch,
        )
    }
}

impl crate::config::tie::Tied for SupportConfig {
    fn name(&self) -> &str {
        &self.name
    }

    fn tie(&self) -> Option<&str> {
        self.tie.as_deref()
    }
}

impl Config {
    /// The supports of `[[model.supports]]`: along edges of `patches`, at
    /// points of them, or at the bases of the `beams` that name them.
    pub(super) fn build_supports(
        &self,
        patches: &[Patch],
        beams: &BeamNet,
    ) -> Result<Vec<ElasticSupport>, ConfigError> {
        self.model
            .supports
            .iter()
            .enumerate()
            .map(|(i, s)| {
                let key = |k: &str| format!("model.supports[{i}].{k}");
                let axes = super::super::patches::support_axes(s.axes, s.skew_deg, key)?;
                if s.at.is_none() && (s.patch.is_some() || s.surface.is_some()) {
                    return Err(err(
                        key("patch"),
                        "`patch` and `surface` go with `at`: give `at` or remove them",
                    ));
                }
                let built = match (&s.edge, s.at) {
                    (Some(_), Some(_)) => {
                        return Err(err(
                            key("at"),
                            "give `edge` (a line support) or `at` (a point), not both",
                        ));
                    }
                    (Some(edge), None) => {
                        let patch = patch_index(patches, edge.patch.as_deref(), &key("edge.patch"))?;
                        ElasticSupport::along_edge(&s.name, (patch, edge.edge.into()), axes, s.stiffness.given())
                    }
                    (None, Some(at)) => {
                        let patch = s
                            .patch
                            .as_deref()
                            .map(|n| patch_index(patches, Some(n), &key("patch")))
                            .transpose()?;
                        let face = s.surface.unwrap_or(FaceConfig::Bottom);
                        let point = locate(patches, patch, at, face_tau(face), &key("at"))?;
                        ElasticSupport::at_point(&s.name, point, axes, s.stiffness.given())
                    }
                    (None, None) => {
                        let nodes: Vec<usize> = self
                            .model
                            .beams
                            .iter()
                            .enumerate()
                            .filter(|(_, b)| b.base == s.name)
                            .map(|(member, _)| beams.member_nodes(member)[0])
                            .collect();
                        if nodes.is_empty() {
                            return Err(err(
                                key("edge"),
                                format!(
                                    "{:?} has no edge, no point `at` and no beam's `base` names it: give one of them",
                                    s.name
                                ),
                            ));
                        }
                        ElasticSupport::at_beam_nodes(&s.name, nodes, axes, s.stiffness.given())
                    }
                };
                built.map_err(|e| {
                    let at = match e {
                        ElasticSupportError::Axes { .. } => "axes",
                        ElasticSupportError::EmptyName => "name",
                        _ => "stiffness",
                    };
                    err(key(at), e)
                })
            })
            .collect()
    }
}
