//! Decks of many patches: `[[model.patches]]` with `[model.materials.<name>]`,
//! `[[model.bearings]]` and `[[model.masses]]`, built into core types; and
//! where a point given in metres lies on the model.

use super::loss_factor::ComponentLossFactor;
use super::{err, ConfigError};
use serde::{Deserialize, Serialize};
use splinewatch_core::geometry::knots::KnotVector;
use splinewatch_core::geometry::surface::{BSplineSurface, Direction};
use splinewatch_core::geometry::swept::{swept_surface, Centreline};
use splinewatch_core::geometry::vec3::Vec3;
use splinewatch_core::model::bearings::PatchPoint;
use splinewatch_core::model::patch::Patch;
use splinewatch_core::model::shell::Shell;
use std::collections::BTreeMap;

/// `[[model.patches]]`: one B-spline patch with its own net and material.
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PatchConfig {
    pub name: String,
    /// A name from `[model.materials]`.
    pub material: String,
    /// m: a number, or a B-spline field over the patch (haunches, tapered webs).
    pub thickness: ThicknessConfig,
    /// B-spline degrees `[p, q]` along ξ and η.
    pub degree: [usize; 2],
    /// Control points `[m, n]` along ξ and η (uniform clamped knots).
    pub control_points: [usize; 2],
    #[serde(default)]
    pub insert_knots_xi: Vec<f64>,
    #[serde(default)]
    pub insert_knots_eta: Vec<f64>,
    /// kg/m² on the mid-surface: pavement, ballast, services.
    #[serde(default)]
    pub non_structural_mass: f64,
    pub geometry: PatchGeometryConfig,
}

/// A patch's thickness: constant, or `{ knots_xi, degree_xi, knots_eta,
/// degree_eta, values }` (η fastest), sampled at the analysis net's
/// Greville abscissae (a linear taper is reproduced exactly).
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(untagged)]
pub enum ThicknessConfig {
    Constant(f64),
    Field {
        knots_xi: Vec<f64>,
        degree_xi: usize,
        knots_eta: Vec<f64>,
        degree_eta: usize,
        values: Vec<f64>,
    },
}

impl ThicknessConfig {
    /// The thickness at every control point of `shell`'s net.
    fn per_control_point(&self, shell: &Shell) -> Result<Vec<f64>, (&'static str, String)> {
        let count = shell.control_point_count();
        let (knots_xi, degree_xi, knots_eta, degree_eta, values) = match self {
            ThicknessConfig::Constant(t) => return Ok(vec![*t; count]),
            ThicknessConfig::Field {
                knots_xi,
                degree_xi,
                knots_eta,
                degree_eta,
                values,
            } => (knots_xi, *degree_xi, knots_eta, *degree_eta, values),
        };
        let kx = KnotVector::new(knots_xi.clone(), degree_xi).map_err(|e| ("thickness.knots_xi", e.to_string()))?;
        let ke = KnotVector::new(knots_eta.clone(), degree_eta).map_err(|e| ("thickness.knots_eta", e.to_string()))?;
        if values.len() != kx.basis_count() * ke.basis_count() {
            return Err((
                "thickness.values",
                format!(
                    "{} values given, the knot vectors need {} × {}",
                    values.len(),
                    kx.basis_count(),
                    ke.basis_count()
                ),
            ));
        }
        let surface = shell.surface();
        let (gx, ge) = (surface.xi().greville(), surface.eta().greville());
        let mut basis = Vec::new();
        let mut out = Vec::with_capacity(count);
        for &u in &gx {
            for &v in &ge {
                kx.tensor_basis_into(&ke, u, v, &mut basis);
                out.push(basis.iter().map(|&(k, b)| b * values[k]).sum());
            }
        }
        Ok(out)
    }
}

/// `[model.patches.geometry]`.
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum PatchGeometryConfig {
    /// Four corners, (ξ=0,η=0), (ξ=1,η=0), (ξ=1,η=1), (ξ=0,η=1), mapped bilinearly.
    Quadrilateral { corners: [Vec3; 4] },
    /// A straight section segment `[[a0, b0], [a1, b1]]` (lateral, vertical)
    /// swept along a `centreline` interpolated by a B-spline of the patch's
    /// ξ degree: decks curved in plan or in elevation, their webs and slabs.
    Swept {
        centreline: Vec<Vec3>,
        section: [[f64; 2]; 2],
    },
    /// A B-spline surface from CAD: `degree_xi`, `degree_eta`, clamped
    /// `knots_xi`, `knots_eta`, `control_points` (η fastest, `[x, y, z]` or
    /// `[x, y, z, w]`: a NURBS surface, weights finite and positive),
    /// refined to the patch's analysis net by knot insertion (the geometry
    /// unchanged, arcs exact).
    Nurbs {
        degree_xi: usize,
        degree_eta: usize,
        knots_xi: Vec<f64>,
        knots_eta: Vec<f64>,
        control_points: Vec<Vec<f64>>,
    },
    /// `[0, length] × [0, width]` in the xy plane from `origin`.
    RectangularPlate {
        length: f64,
        width: f64,
        #[serde(default)]
        origin: Vec3,
    },
    /// A circular-cylindrical panel, axis along x, crown at `origin`.
    CylindricalPanel {
        length: f64,
        radius: f64,
        angle_deg: f64,
        #[serde(default)]
        origin: Vec3,
    },
}

/// `[[model.bearings]]`: a discrete elastic bearing.
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct BearingConfig {
    pub name: String,
    /// m: on or under a patch.
    pub at: Vec3,
    /// The patch it supports (default: the nearest).
    pub patch: Option<String>,
    /// The face it acts on (default: the bottom).
    #[serde(default = "bottom")]
    pub surface: FaceConfig,
    /// `[k_x, k_y, k_z]` in N/m, along the global axes or `axes`.
    pub stiffness: [f64; 3],
    /// The axes of `k_x, k_y, k_z` as three orthonormal, right-handed rows
    /// (along and across a skewed support line, and up); default the
    /// global axes.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub axes: Option<[[f64; 3]; 3]>,
    /// The support line's skew in degrees, instead of `axes`: `kx` across
    /// the line, `ky` along it (turned by this angle from the global y axis,
    /// counter-clockwise seen from above), `kz` up.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub skew_deg: Option<f64>,
    /// `[lower, upper]` for each of k_x, k_y, k_z when updating.
    pub bounds: Option<[f64; 2]>,
    /// `true` (default): `kx`, `ky` and `kz` are updated; `false`: none; a
    /// list (`["ky"]`): those axes only.
    #[serde(default)]
    pub update: BearingUpdate,
    /// The support group whose ground the bearing stands on (default "ground").
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub support: Option<String>,
    /// Tied to the bearing of this name, which comes just before it (or
    /// before bearings tied to it): its updated stiffnesses are that
    /// bearing's parameters (one value for a support line's bearings).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tie: Option<String>,
    /// The bearing's loss factor η (hysteretic damping: 0.1 = 10 %): modes
    /// whose strain energy sits in it are damped more, by
    /// `½ η × (its share of the mode's strain energy)` on top of
    /// `[model.damping]`'s ζ(f). A number is held; `{ value, bounds }` is
    /// updated (parameter `<name>.eta`); `{ ky = 0.3 }` acts on the axes
    /// named only, each its own (parameter `<name>.ky.eta`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub loss_factor: Option<ComponentLossFactor>,
}

/// `[[model.bearings]] update`: every axis, none, or the axes listed.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(untagged)]
pub enum BearingUpdate {
    Every(bool),
    Axes(Vec<String>),
}

impl Default for BearingUpdate {
    fn default() -> Self {
        Self::Every(true)
    }
}

/// The stiffness names of a bearing's axes, in `stiffness` order.
pub const BEARING_AXES: [&str; 3] = ["kx", "ky", "kz"];

impl BearingUpdate {
    /// Whether axis `a` (0 = x) is updated; an unknown name is refused by
    /// [`Self::check`].
    pub fn axis(&self, a: usize) -> bool {
        match self {
            Self::Every(on) => *on,
            Self::Axes(list) => list.iter().any(|n| n == BEARING_AXES[a]),
        }
    }

    pub fn check(&self, key: &str) -> Result<(), super::ConfigError> {
        if let Self::Axes(list) = self {
            if let Some(bad) = list.iter().find(|n| !BEARING_AXES.contains(&n.as_str())) {
                return Err(super::err(
                    key,
                    format!("{bad:?} is not an axis: give true, false or a list of \"kx\", \"ky\", \"kz\""),
                ));
            }
        }
        Ok(())
    }
}

fn bottom() -> FaceConfig {
    FaceConfig::Bottom
}

/// `[[model.masses]]`: a point mass at the mid-surface.
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MassConfig {
    /// m.
    pub at: Vec3,
    /// kg.
    pub mass: f64,
    pub patch: Option<String>,
}

/// τ of a face: 0 bottom, ½ middle, 1 top.
pub fn face_tau(face: FaceConfig) -> f64 {
    match face {
        FaceConfig::Bottom => 0.0,
        FaceConfig::Middle => 0.5,
        FaceConfig::Top => 1.0,
    }
}

#[derive(Debug, Clone, Copy, Deserialize, Serialize, PartialEq, Eq, schemars::JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum FaceConfig {
    Bottom,
    #[serde(alias = "mid")]
    Middle,
    Top,
}

pub fn default_true() -> bool {
    true
}

/// How far (m) from a patch's mid-surface a point given in metres may lie
/// (beyond half the thickness).
pub const MAX_DISTANCE: f64 = 0.5;

/// The `[model.materials]` table `name`, which `key` names.
pub fn material_table<'a>(
    materials: &'a BTreeMap<String, super::materials::MaterialConfig>,
    name: &str,
    key: &str,
) -> Result<&'a super::materials::MaterialConfig, ConfigError> {
    materials.get(name).ok_or_else(|| {
        err(
            key,
            format!(
                "{name:?} is not in [model.materials] (known: {:?})",
                materials.keys().collect::<Vec<_>>()
            ),
        )
    })
}

/// Builds the patches of `[[model.patches]]`.
pub fn build_patches(
    patches: &[PatchConfig],
    materials: &BTreeMap<String, super::materials::MaterialConfig>,
) -> Result<Vec<Patch>, ConfigError> {
    let mut out: Vec<Patch> = Vec::with_capacity(patches.len());
    for (i, p) in patches.iter().enumerate() {
        let key = |k: &str| format!("model.patches[{i}].{k}");
        if out.iter().any(|q| q.name() == p.name) {
            return Err(err(key("name"), format!("{:?} names two patches", p.name)));
        }
        let material = material_table(materials, &p.material, &key("material"))?
            .plate(&format!("model.materials.{}", p.material))?;
        let shell = build_shell(p).map_err(|(k, e)| err(key(k), e))?;
        let patch = Patch::new(&p.name, shell, material)
            .and_then(|patch| patch.with_non_structural_mass(p.non_structural_mass))
            .map_err(|e| err(key("non_structural_mass"), e))?;
        out.push(patch);
    }
    Ok(out)
}

fn build_shell(p: &PatchConfig) -> Result<Shell, (&'static str, String)> {
    let translated = |shell: Shell, origin: Vec3| shell.translated(origin);
    let shell = match &p.geometry {
        PatchGeometryConfig::Swept { centreline, section } => return swept_shell(p, centreline, *section),
        PatchGeometryConfig::Nurbs { .. } => return refine(p, nurbs_shell(p)?),
        &PatchGeometryConfig::Quadrilateral { corners } => {
            Shell::quadrilateral(corners, 1.0, p.degree, p.control_points)
        }
        &PatchGeometryConfig::RectangularPlate { length, width, origin } => {
            Shell::rectangular_plate(length, width, 1.0, p.degree, p.control_points).and_then(|s| translated(s, origin))
        }
        &PatchGeometryConfig::CylindricalPanel {
            length,
            radius,
            angle_deg,
            origin,
        } => Shell::cylindrical_panel(length, radius, angle_deg.to_radians(), 1.0, p.degree, p.control_points)
            .and_then(|s| translated(s, origin)),
    }
    .map_err(|e| ("geometry", e.to_string()))?;
    refine(p, shell)
}

/// A swept patch on its analysis net, refined.
fn swept_shell(p: &PatchConfig, centreline: &[Vec3], section: [[f64; 2]; 2]) -> Result<Shell, (&'static str, String)> {
    let curve = Centreline::interpolate(centreline, p.degree[0]).map_err(|e| ("geometry.centreline", e.to_string()))?;
    let [m, n] = p.control_points;
    let xi = KnotVector::uniform(p.degree[0], m, 0.0, 1.0).map_err(|e| ("control_points", e.to_string()))?;
    let eta = KnotVector::uniform(p.degree[1], n, 0.0, 1.0).map_err(|e| ("control_points", e.to_string()))?;
    let surface = swept_surface(&curve, section, xi, eta).map_err(|e| ("geometry", e.to_string()))?;
    let shell = Shell::new(surface, vec![1.0; m * n]).map_err(|e| ("geometry", e.to_string()))?;
    refine(p, shell)
}

/// A CAD surface (NURBS: weights optional, equal weights a B-spline)
/// refined to the patch's `degree` and `control_points` by inserting the
/// midpoint of its longest span until the net has the requested size; knot
/// insertion in homogeneous coordinates keeps the geometry exactly, arcs
/// included, and the analysis uses the rational basis.
fn nurbs_shell(p: &PatchConfig) -> Result<Shell, (&'static str, String)> {
    let PatchGeometryConfig::Nurbs {
        degree_xi,
        degree_eta,
        knots_xi,
        knots_eta,
        control_points,
    } = &p.geometry
    else {
        unreachable!("called for nurbs geometry only")
    };
    let xi = KnotVector::new(knots_xi.clone(), *degree_xi).map_err(|e| ("geometry.knots_xi", e.to_string()))?;
    let eta = KnotVector::new(knots_eta.clone(), *degree_eta).map_err(|e| ("geometry.knots_eta", e.to_string()))?;
    let mut weights = Vec::with_capacity(control_points.len());
    let mut points = Vec::with_capacity(control_points.len());
    for (k, c) in control_points.iter().enumerate() {
        match c.as_slice() {
            &[x, y, z] => {
                points.push([x, y, z]);
                weights.push(1.0);
            }
            &[x, y, z, w] if w.is_finite() && w > 0.0 => {
                points.push([x, y, z]);
                weights.push(w);
            }
            &[_, _, _, w] => {
                return Err((
                    "geometry.control_points",
                    format!("point {k}: weight {w} must be finite and positive"),
                ))
            }
            other => {
                return Err((
                    "geometry.control_points",
                    format!(
                        "point {k}: {} coordinates, expected [x, y, z] or [x, y, z, w]",
                        other.len()
                    ),
                ))
            }
        }
    }
    if [*degree_xi, *degree_eta] != p.degree {
        return Err((
            "degree",
            format!("must equal the surface's degrees [{degree_xi}, {degree_eta}] (no degree elevation)"),
        ));
    }
    let surface =
        BSplineSurface::rational(xi, eta, points, weights).map_err(|e| ("geometry.control_points", e.to_string()))?;
    let (m, n) = surface.net_size();
    let shell = Shell::new(surface, vec![1.0; m * n]).map_err(|e| ("geometry", e.to_string()))?;
    refine_to_net(shell, p.control_points)
}

/// `shell` with the midpoint of its longest span inserted, along ξ then η,
/// until its net is `net` (an error if it is larger already).
fn refine_to_net(mut shell: Shell, net: [usize; 2]) -> Result<Shell, (&'static str, String)> {
    for (direction, want) in [(Direction::Xi, net[0]), (Direction::Eta, net[1])] {
        loop {
            let kv = match direction {
                Direction::Xi => shell.surface().xi(),
                Direction::Eta => shell.surface().eta(),
            };
            let have = kv.basis_count();
            if have > want {
                return Err((
                    "control_points",
                    format!("the surface already has {have} control points along {direction:?}, more than {want}"),
                ));
            }
            if have == want {
                break;
            }
            let breaks = kv.breakpoints();
            let longest = breaks
                .windows(2)
                .max_by(|a, b| (a[1] - a[0]).total_cmp(&(b[1] - b[0])))
                .expect("a span");
            let mid = 0.5 * (longest[0] + longest[1]);
            shell = shell
                .insert_knot(direction, mid)
                .map_err(|e| ("control_points", e.to_string()))?;
        }
    }
    Ok(shell)
}

/// The patch's knot insertions.
fn refine(p: &PatchConfig, shell: Shell) -> Result<Shell, (&'static str, String)> {
    let mut shell = shell;
    for (key, direction, knots) in [
        ("insert_knots_xi", Direction::Xi, &p.insert_knots_xi),
        ("insert_knots_eta", Direction::Eta, &p.insert_knots_eta),
    ] {
        for &u in knots {
            shell = shell.insert_knot(direction, u).map_err(|e| {
                (
                    key,
                    format!("cannot insert {u}: {e} (knots must lie strictly inside (0, 1))"),
                )
            })?;
        }
    }
    let thickness = p.thickness.per_control_point(&shell)?;
    shell
        .with_thickness(thickness)
        .map_err(|e| ("thickness", e.to_string()))
}

/// The patch index a `patch = "name"` key names; with no name, the only
/// patch (an error naming `key` when there are several).
pub fn patch_index(patches: &[Patch], name: Option<&str>, key: &str) -> Result<usize, ConfigError> {
    match name {
        Some(name) => patches.iter().position(|p| p.name() == name).ok_or_else(|| {
            err(
                key,
                format!(
                    "{name:?} is not a patch (patches: {:?})",
                    patches.iter().map(Patch::name).collect::<Vec<_>>()
                ),
            )
        }),
        None if patches.len() == 1 => Ok(0),
        None => Err(err(
            key,
            format!("the model has {} patches: name one with `patch = \"…\"`", patches.len()),
        )),
    }
}

/// The point of the named patch (or of the nearest one) nearest to `at`,
/// at face `tau`; an error naming `key` when it is farther than
/// [`MAX_DISTANCE`] beyond the patch's half thickness.
pub fn locate(
    patches: &[Patch],
    patch: Option<usize>,
    at: Vec3,
    tau: f64,
    key: &str,
) -> Result<PatchPoint, ConfigError> {
    locate_within(patches, patch, at, tau, 0.0, key)
}

/// [`locate`], for a point that may lie `beyond` metres off the
/// mid-surface (a sensor's `offset`) rather than within the half thickness.
pub fn locate_within(
    patches: &[Patch],
    patch: Option<usize>,
    at: Vec3,
    tau: f64,
    beyond: f64,
    key: &str,
) -> Result<PatchPoint, ConfigError> {
    let candidates: Vec<usize> = patch.map_or_else(|| (0..patches.len()).collect(), |k| vec![k]);
    let (best, (xi, eta, distance)) = candidates
        .into_iter()
        .map(|k| (k, patches[k].shell.surface().closest_point(at)))
        .min_by(|a, b| a.1 .2.total_cmp(&b.1 .2))
        .ok_or_else(|| err(key, "the model has no patch"))?;
    let half = (0.5 * patches[best].shell.thickness().iter().copied().fold(0.0, f64::max)).max(beyond);
    if distance.is_nan() || distance > MAX_DISTANCE + half {
        return Err(err(
            key,
            format!(
                "({}, {}, {}) m is {distance:.3} m from the nearest patch ({:?}): more than {MAX_DISTANCE} m off every patch",
                at[0],
                at[1],
                at[2],
                patches[best].name()
            ),
        ));
    }
    Ok(PatchPoint {
        patch: best,
        xi,
        eta,
        tau,
    })
}

/// The axes `axes` or `skew_deg` give (the keys `key("axes")` and
/// `key("skew_deg")`): across the line `[cos φ, sin φ, 0]`, along it
/// `[−sin φ, cos φ, 0]`, up; the global axes when neither is given.
pub(crate) fn support_axes(
    axes: Option<[[f64; 3]; 3]>,
    skew_deg: Option<f64>,
    key: impl Fn(&str) -> String,
) -> Result<[[f64; 3]; 3], ConfigError> {
    match (axes, skew_deg) {
        (Some(_), Some(_)) => Err(err(key("skew_deg"), "give `axes` or `skew_deg`, not both")),
        (Some(axes), None) => Ok(axes),
        (None, Some(skew)) if skew.is_finite() && skew.abs() < 90.0 => {
            let (s, c) = skew.to_radians().sin_cos();
            Ok([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
        }
        (None, Some(skew)) => Err(err(
            key("skew_deg"),
            format!("{skew}: a skew angle lies strictly between −90 and 90 degrees"),
        )),
        (None, None) => Ok([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]),
    }
}

impl super::tie::Tied for BearingConfig {
    fn name(&self) -> &str {
        &self.name
    }

    fn tie(&self) -> Option<&str> {
        self.tie.as_deref()
    }
}

#[cfg(test)]
mod tests;
