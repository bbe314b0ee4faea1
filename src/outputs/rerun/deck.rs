//! The deck mesh shown in the viewer: the mid-surface on a (ξ, η) grid, the
//! spring field and mode shapes evaluated on it, and the colour ramp.

use super::GRID;
use splinewatch_core::geometry::vec3::Vec3;
use splinewatch_core::model::elastic_supports::SupportSite;
use splinewatch_core::model::BridgeModel;
use splinewatch_core::response::frf::Sensor;

pub(super) fn f32x3(v: Vec3) -> [f32; 3] {
    [v[0] as f32, v[1] as f32, v[2] as f32]
}

/// Where sensor `s` is drawn: a patch sensor on the top face, a beam
/// sensor at its point.
pub(super) fn sensor_position(model: &BridgeModel, s: &Sensor) -> [f32; 3] {
    match s {
        Sensor::Shell(p) => f32x3(model.patches[p.patch].shell.position(p.xi, p.eta, 1.0)),
        Sensor::Beam(b) => f32x3(b.at),
    }
}

/// A blue → green → yellow ramp for `t ∈ [0, 1]`.
pub(super) fn colormap(t: f64) -> rerun::Color {
    let t = t.clamp(0.0, 1.0);
    let (r, g, b) = if t < 0.5 {
        let u = 2.0 * t;
        (0.15 * (1.0 - u), 0.2 + 0.55 * u, 0.7 * (1.0 - u) + 0.35 * u)
    } else {
        let u = 2.0 * t - 1.0;
        (0.95 * u, 0.75 + 0.2 * u, 0.35 * (1.0 - u))
    };
    rerun::Color::from_rgb((255.0 * r) as u8, (255.0 * g) as u8, (255.0 * b) as u8)
}

/// The deck's mid-surface sampled on a (ξ, η) grid that includes every
/// spring field's knots, so narrow spring strips are visible.
pub(super) struct DeckGrid {
    /// `(patch, ξ, η)` of every vertex, patch after patch.
    pub(super) params: Vec<(usize, f64, f64)>,
    pub(super) positions: Vec<[f32; 3]>,
    pub(super) normals: Vec<[f32; 3]>,
    pub(super) triangles: Vec<[u32; 3]>,
    /// Largest extent of the deck, for scaling mode shapes.
    pub(super) span: f64,
}

impl DeckGrid {
    pub(super) fn new(model: &BridgeModel) -> Self {
        let axis = |n: usize, knots: &mut dyn Iterator<Item = f64>| -> Vec<f64> {
            let mut v: Vec<f64> = (0..n).map(|k| k as f64 / (n - 1) as f64).collect();
            v.extend(knots.filter(|u| (0.0..=1.0).contains(u)));
            v.sort_by(f64::total_cmp);
            v.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
            v
        };
        let mut params = Vec::new();
        let mut positions = Vec::new();
        let mut normals = Vec::new();
        let mut triangles = Vec::new();
        for (k, patch) in model.patches.iter().enumerate() {
            let on_patch = || model.springs.iter().filter(move |s| s.patch() == k);
            let xs = axis(GRID.0, &mut on_patch().flat_map(|s| s.xi().knots().to_vec()));
            let ys = axis(GRID.1, &mut on_patch().flat_map(|s| s.eta().knots().to_vec()));
            let shell = &patch.shell;
            let first = positions.len() as u32;
            for &x in &xs {
                for &y in &ys {
                    params.push((k, x, y));
                    let p = shell.position(x, y, 0.5);
                    let q = shell.position(x, y, 1.0);
                    let d = [q[0] - p[0], q[1] - p[1], q[2] - p[2]];
                    let norm = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt().max(f64::MIN_POSITIVE);
                    positions.push(f32x3(p));
                    normals.push([(d[0] / norm) as f32, (d[1] / norm) as f32, (d[2] / norm) as f32]);
                }
            }
            let ny = ys.len();
            for i in 0..xs.len() - 1 {
                for j in 0..ny - 1 {
                    let a = first + (i * ny + j) as u32;
                    let b = first + ((i + 1) * ny + j) as u32;
                    triangles.push([a, b, b + 1]);
                    triangles.push([a, b + 1, a + 1]);
                }
            }
        }
        let extent = |k: usize| {
            let (lo, hi) = positions
                .iter()
                .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), p| {
                    (lo.min(p[k]), hi.max(p[k]))
                });
            f64::from(hi - lo)
        };
        let span = extent(0).max(extent(1)).max(extent(2));
        Self {
            params,
            positions,
            normals,
            triangles,
            span,
        }
    }

    /// Σ over spring fields of the stiffness per unit area at each vertex.
    pub(super) fn spring_field(&self, model: &BridgeModel, kappa: &[Vec<f64>]) -> Vec<f64> {
        self.params
            .iter()
            .map(|&(patch, x, y)| {
                model
                    .springs
                    .iter()
                    .zip(kappa)
                    .filter(|(s, _)| s.patch() == patch)
                    .map(|(s, k)| s.value_with(k, x, y))
                    .sum()
            })
            .collect()
    }

    /// The stiffness multiplier `1 + Σ_fields (θ_f(ξ,η) − 1)` at each vertex.
    pub(super) fn stiffness_multiplier(&self, model: &BridgeModel, theta: &[Vec<f64>]) -> Vec<f64> {
        self.params
            .iter()
            .map(|&(patch, x, y)| {
                1.0 + model
                    .stiffness_fields
                    .iter()
                    .zip(theta)
                    .filter(|(f, _)| f.patch() == patch)
                    .map(|(f, t)| f.value_with(t, x, y) - 1.0)
                    .sum::<f64>()
            })
            .collect()
    }

    /// Displacement along the surface normal at each vertex of the shape
    /// with generalised dof values `shape(dof)`.
    pub(super) fn normal_displacement(&self, model: &BridgeModel, shape: impl Fn(usize) -> f64) -> Vec<f64> {
        let dofs = model.dof_map();
        self.params
            .iter()
            .zip(&self.normals)
            .map(|(&(patch, x, y), n)| {
                model.patches[patch]
                    .shell
                    .shape_functions(x, y, 0.5)
                    .into_iter()
                    .map(|(dof, col)| {
                        shape(dofs.first_dof(patch) + dof)
                            * (col[0] * f64::from(n[0]) + col[1] * f64::from(n[1]) + col[2] * f64::from(n[2]))
                    })
                    .sum()
            })
            .collect()
    }
}

/// A qualitative palette (Tableau 10) for telling patches apart.
const PATCH_COLOURS: [[u8; 3]; 10] = [
    [78, 121, 167],
    [242, 142, 43],
    [225, 87, 89],
    [118, 183, 178],
    [89, 161, 79],
    [237, 201, 72],
    [176, 122, 161],
    [255, 157, 167],
    [156, 117, 95],
    [186, 176, 172],
];

/// Element edges drawn per knot span (sampled along the other direction).
const EDGE_SAMPLES: usize = 16;

/// The model as built, for checking it: `deck/model` (the mid-surface of
/// every patch in its own colour), `deck/model/elements` (the knot lines of
/// each patch's analysis net, i.e. the element edges),
/// `deck/model/bearings` (the bearings and the point supports) and
/// `deck/model/masses` (at their points), and
/// with beams `deck/model/beams` (each member through its nodes, as thick
/// as its section, labelled) and `deck/model/beam_bases` (the bases held
/// or on springs).
pub(super) fn log_model(
    rec: &rerun::RecordingStream,
    model: &BridgeModel,
    grid: &DeckGrid,
) -> Result<(), rerun::RecordingStreamError> {
    let colours: Vec<rerun::Color> = grid
        .params
        .iter()
        .map(|&(patch, _, _)| {
            let [r, g, b] = PATCH_COLOURS[patch % PATCH_COLOURS.len()];
            rerun::Color::from_rgb(r, g, b)
        })
        .collect();
    rec.log_static(
        "deck/model",
        &rerun::Mesh3D::new(grid.positions.clone())
            .with_vertex_normals(grid.normals.clone())
            .with_triangle_indices(grid.triangles.clone())
            .with_vertex_colors(colours),
    )?;
    let mut edges: Vec<Vec<[f32; 3]>> = Vec::new();
    for patch in &model.patches {
        let shell = &patch.shell;
        let surface = shell.surface();
        let samples = |breaks: &[f64]| -> Vec<f64> {
            breaks
                .windows(2)
                .flat_map(|w| (0..EDGE_SAMPLES).map(move |k| w[0] + (w[1] - w[0]) * k as f64 / EDGE_SAMPLES as f64))
                .chain(breaks.last().copied())
                .collect()
        };
        let (xi_breaks, eta_breaks) = (surface.xi().breakpoints(), surface.eta().breakpoints());
        let (along_eta, along_xi) = (samples(&eta_breaks), samples(&xi_breaks));
        for &x in &xi_breaks {
            edges.push(along_eta.iter().map(|&y| f32x3(shell.position(x, y, 0.5))).collect());
        }
        for &y in &eta_breaks {
            edges.push(along_xi.iter().map(|&x| f32x3(shell.position(x, y, 0.5))).collect());
        }
    }
    rec.log_static(
        "deck/model/elements",
        &rerun::LineStrips3D::new(edges)
            .with_colors([rerun::Color::from_rgb(40, 40, 40)])
            .with_radii([rerun::Radius::new_ui_points(0.6)]),
    )?;
    let at = |p: splinewatch_core::model::bearings::PatchPoint| f32x3(model.position_of(p));
    let radius = (grid.span / 150.0) as f32;
    rec.log_static(
        "deck/model/bearings",
        &rerun::Points3D::new(model.bearings.iter().map(|b| at(b.at())).chain(
            model.elastic_supports.iter().filter_map(|s| match s.site() {
                SupportSite::Point(p) => Some(at(*p)),
                SupportSite::Edge { .. } | SupportSite::BeamNodes(_) => None,
            }),
        ))
        .with_colors([rerun::Color::from_rgb(20, 20, 20)])
        .with_radii([radius]),
    )?;
    rec.log_static(
        "deck/model/masses",
        &rerun::Points3D::new(model.masses.iter().map(|m| at(m.at())))
            .with_colors([rerun::Color::from_rgb(150, 0, 150)])
            .with_radii([radius]),
    )?;
    log_beams(rec, model, radius)
}

/// `deck/model/beams` and `deck/model/beam_bases` (nothing without beams).
fn log_beams(
    rec: &rerun::RecordingStream,
    model: &BridgeModel,
    radius: f32,
) -> Result<(), rerun::RecordingStreamError> {
    let beams = &model.beams;
    if beams.is_empty() {
        return Ok(());
    }
    let members = beams.members();
    let strips: Vec<Vec<[f32; 3]>> = (0..members.len())
        .map(|m| {
            beams
                .member_nodes(m)
                .iter()
                .map(|&n| f32x3(beams.position(n)))
                .collect()
        })
        .collect();
    // Drawn as thick as a circle of the section's area.
    let thickness = members
        .iter()
        .map(|m| rerun::Radius::new_scene_units((m.section().area / std::f64::consts::PI).sqrt() as f32));
    rec.log_static(
        "deck/model/beams",
        &rerun::LineStrips3D::new(strips)
            .with_radii(thickness)
            .with_colors([rerun::Color::from_rgb(120, 120, 120)])
            .with_labels(members.iter().map(|m| m.name().to_string())),
    )?;
    let bases: Vec<[f32; 3]> = beams
        .base_nodes()
        .into_iter()
        .map(|(node, _)| f32x3(beams.position(node)))
        .chain(model.elastic_supports.iter().flat_map(|s| match s.site() {
            SupportSite::BeamNodes(nodes) => nodes.iter().map(|&n| f32x3(beams.position(n))).collect(),
            SupportSite::Edge { .. } | SupportSite::Point(_) => Vec::new(),
        }))
        .collect();
    rec.log_static(
        "deck/model/beam_bases",
        &rerun::Points3D::new(bases)
            .with_colors([rerun::Color::from_rgb(20, 20, 20)])
            .with_radii([2.0 * radius]),
    )
}
