//! Rigid joints between patches by penalty coupling at the interface's
//! quadrature points (Herrema, Johnson, Proserpio, Wu, Kiendl & Hsu 2019,
//! "Penalty coupling of non-matching isogeometric Kirchhoff–Love shell
//! patches", CMAME 346, eq. 10–14, here for the Reissner–Mindlin directors
//! of eq. 3).
//!
//! A joint is an edge of patch `a` lying on the mid-surface of patch `b`, at
//! an edge of `b` (a box's corner, two slabs side by side) or along an
//! interior line (a web under a slab, a diaphragm). Along the edge, with `t`
//! its unit tangent and `n_a`, `n_b` the patches' unit normals,
//!
//! `Π = ½ ∫ α_u |u_a − u_b|² + α_r (ω_a·t − ω_b·t)² ds`,
//!
//! where `u` is the mid-surface displacement and `ω·t = Δd·(t × n)` the
//! rotation about the junction line (`Δd = Σ N_k (−v2 α + v1 β)_k` the
//! director's change, eq. 3), so displacements and the rotation about the
//! line are continuous also where patches meet at an angle. The penalties
//! scale with the stiffer patch: `α_u = c E t / h`, `α_r = c E t³ / (12 h)`,
//! `E` the larger modulus, `t` the larger thickness at the point, `h` the
//! smaller patch's element size, `c` the dimensionless factor (default
//! [`DEFAULT_PENALTY`]). The coupling's error decreases like `1/c`.

use crate::geometry::knots::KnotVector;
use crate::geometry::quadrature::GaussLegendre;
use crate::geometry::vec3::{cross, dot, norm, normalize, sub, Vec3};
use crate::model::constraints::Edge;
use crate::model::dofs::DofMap;
use crate::model::patch::Patch;
use crate::model::shell::{Shell, ShellPoint, DOFS_PER_CONTROL_POINT};
use crate::model::springs::LowRankBlock;
use faer::Mat;
use std::collections::BTreeMap;

/// Default penalty factor `c`: the modes move by less than 1e-4 relative
/// when it grows tenfold (tested on folded decks).
pub const DEFAULT_PENALTY: f64 = 1e4;

/// Points sampled along an edge to decide whether it lies on a patch.
const SAMPLES: usize = 9;

/// An edge of `patch` lying on the mid-surface of `other`.
#[derive(Debug, Clone, PartialEq)]
pub struct Joint {
    pub patch: usize,
    pub edge: Edge,
    pub other: usize,
    /// m.
    pub length: f64,
}

/// `(ξ, η)` of the parameter `s ∈ [0, 1]` along `edge`.
fn on_edge(shell: &Shell, edge: Edge, s: f64) -> (f64, f64) {
    let (a, b) = shell.surface().xi().domain();
    let (c, d) = shell.surface().eta().domain();
    match edge {
        Edge::Xi0 => (a, c + s * (d - c)),
        Edge::Xi1 => (b, c + s * (d - c)),
        Edge::Eta0 => (a + s * (b - a), c),
        Edge::Eta1 => (a + s * (b - a), d),
    }
}

/// The knot vector the edge runs along.
fn along(shell: &Shell, edge: Edge) -> &KnotVector {
    match edge {
        Edge::Xi0 | Edge::Xi1 => shell.surface().eta(),
        Edge::Eta0 | Edge::Eta1 => shell.surface().xi(),
    }
}

const EDGES: [Edge; 4] = [Edge::Xi0, Edge::Xi1, Edge::Eta0, Edge::Eta1];

/// Every joint of `patches` within `tolerance` (m). An edge-to-edge joint
/// (the two edges coincide) is found from both sides; it is kept once, from
/// the patch listed first.
pub fn find_joints(patches: &[Patch], tolerance: f64) -> Vec<Joint> {
    let ends = |p: &Patch, edge: Edge| {
        let at = |s: f64| {
            let (u, v) = on_edge(&p.shell, edge, s);
            p.shell.surface().evaluate(u, v).r
        };
        [at(0.0), at(1.0)]
    };
    let mut joints: Vec<Joint> = Vec::new();
    for (a, pa) in patches.iter().enumerate() {
        for edge in EDGES {
            let samples: Vec<Vec3> = (0..SAMPLES)
                .map(|i| {
                    let (u, v) = on_edge(&pa.shell, edge, i as f64 / (SAMPLES - 1) as f64);
                    pa.shell.surface().evaluate(u, v).r
                })
                .collect();
            let [s0, s1] = ends(pa, edge);
            for (b, pb) in patches.iter().enumerate().filter(|&(b, _)| b != a) {
                let lies = samples
                    .iter()
                    .all(|&x| pb.shell.surface().closest_point(x).2 <= tolerance);
                let same_line_as_found = joints.iter().any(|j| {
                    let [e0, e1] = ends(pb, j.edge);
                    let close = |x: Vec3, y: Vec3| norm(sub(x, y)) <= tolerance;
                    j.patch == b && j.other == a && (close(s0, e0) && close(s1, e1) || close(s0, e1) && close(s1, e0))
                });
                if lies && !same_line_as_found {
                    joints.push(Joint {
                        patch: a,
                        edge,
                        other: b,
                        length: edge_length(&pa.shell, edge),
                    });
                }
            }
        }
    }
    joints
}

/// The first pair `(a, b)` where patch `a` lies on patch `b` (nine interior
/// points of `a` within `tolerance` of `b`'s mid-surface): overlapping
/// patches, which would count the same material twice.
pub fn find_overlap(patches: &[Patch], tolerance: f64) -> Option<(usize, usize)> {
    let inside = [0.25, 0.5, 0.75];
    for (a, pa) in patches.iter().enumerate() {
        let s = pa.shell.surface();
        let ((u0, u1), (v0, v1)) = (s.xi().domain(), s.eta().domain());
        let points: Vec<Vec3> = inside
            .iter()
            .flat_map(|&u| inside.iter().map(move |&v| (u, v)))
            .map(|(u, v)| s.evaluate(u0 + u * (u1 - u0), v0 + v * (v1 - v0)).r)
            .collect();
        for (b, pb) in patches.iter().enumerate().filter(|&(b, _)| b != a) {
            if points
                .iter()
                .all(|&x| pb.shell.surface().closest_point(x).2 <= tolerance)
            {
                return Some((a, b));
            }
        }
    }
    None
}

fn edge_length(shell: &Shell, edge: Edge) -> f64 {
    let gauss = GaussLegendre::new(along(shell, edge).degree() + 2);
    let breaks = along(shell, edge).breakpoints();
    let (lo, hi) = (breaks[0], breaks[breaks.len() - 1]);
    breaks
        .windows(2)
        .flat_map(|w| gauss.mapped(w[0], w[1]).collect::<Vec<_>>())
        .map(|(s, w)| {
            let (u, v) = on_edge(shell, edge, (s - lo) / (hi - lo));
            let e = shell.surface().evaluate(u, v);
            let tangent = match edge {
                Edge::Xi0 | Edge::Xi1 => e.r_eta,
                Edge::Eta0 | Edge::Eta1 => e.r_xi,
            };
            w * norm(tangent)
        })
        .sum()
}

/// The element size of a patch: `√(area / spans)`.
fn element_size(shell: &Shell) -> f64 {
    let s = shell.surface();
    let spans = (s.xi().breakpoints().len() - 1) * (s.eta().breakpoints().len() - 1);
    let gx = GaussLegendre::new(s.xi().degree() + 1);
    let ge = GaussLegendre::new(s.eta().degree() + 1);
    let mut area = 0.0;
    for wx in s.xi().breakpoints().windows(2) {
        for we in s.eta().breakpoints().windows(2) {
            for (u, a) in gx.mapped(wx[0], wx[1]) {
                for (v, b) in ge.mapped(we[0], we[1]) {
                    let e = s.evaluate(u, v);
                    area += a * b * norm(cross(e.r_xi, e.r_eta));
                }
            }
        }
    }
    (area / spans as f64).sqrt()
}

/// Rows at one side of the interface: mid-surface displacement per axis and
/// the rotation about `t`, as `(global dof, value)`.
struct SideRows {
    u: [Vec<(usize, f64)>; 3],
    rotation: Vec<(usize, f64)>,
    thickness: f64,
}

fn side_rows(shell: &Shell, offset: usize, xi: f64, eta: f64, t: Vec3) -> SideRows {
    let mut pt = ShellPoint::new_empty();
    shell.evaluate_into(xi, eta, 0.5, &mut pt);
    let e = shell.surface().evaluate(xi, eta);
    let n = normalize(cross(e.r_xi, e.r_eta)).unwrap_or([0.0, 0.0, 1.0]);
    let axis = cross(t, n);
    let mut rows = SideRows {
        u: [Vec::new(), Vec::new(), Vec::new()],
        rotation: Vec::new(),
        thickness: 0.0,
    };
    for k in 0..pt.count {
        let cp = pt.control_points[k];
        let nk = pt.n[k];
        if nk == 0.0 {
            continue;
        }
        rows.thickness += nk * shell.thickness()[cp];
        let base = offset + DOFS_PER_CONTROL_POINT * cp;
        for (d, row) in rows.u.iter_mut().enumerate() {
            row.push((base + d, nk));
        }
        let f = shell.frames()[cp];
        rows.rotation.push((base + 3, -nk * dot(f.v2, axis)));
        rows.rotation.push((base + 4, nk * dot(f.v1, axis)));
    }
    rows
}

impl Joint {
    /// The penalty stiffness of eq. (above) on the global dofs `dofs`,
    /// penalty factor `c`.
    pub fn penalty(&self, patches: &[Patch], dofs: &DofMap, c: f64) -> LowRankBlock {
        let entries = self.penalty_entries(patches, dofs, c);
        let mut dofs: Vec<usize> = entries.keys().map(|&(i, _)| i).collect();
        dofs.dedup();
        let mut values = Mat::zeros(dofs.len(), dofs.len());
        for (&(i, j), &x) in &entries {
            let (a, b) = (
                dofs.binary_search(&i).expect("listed"),
                dofs.binary_search(&j).expect("listed"),
            );
            values[(a, b)] = x;
        }
        LowRankBlock { dofs, values }
    }

    /// [`Self::penalty`]'s entries `(row, column) → value` alone: a long
    /// joint couples each point of one edge to a few of the other's, not
    /// all (the sparse path's pattern).
    pub fn penalty_entries(&self, patches: &[Patch], dofs: &DofMap, c: f64) -> BTreeMap<(usize, usize), f64> {
        let (pa, pb) = (&patches[self.patch], &patches[self.other]);
        let modulus = pa
            .material
            .e1()
            .max(pa.material.e2())
            .max(pb.material.e1())
            .max(pb.material.e2());
        let h = element_size(&pa.shell).min(element_size(&pb.shell));
        let kv = along(&pa.shell, self.edge);
        // Two points more than the edge's degree needs: the other patch's
        // basis is smooth across the edge's spans but not aligned with them.
        let gauss = GaussLegendre::new(kv.degree() + 3);
        let breaks = kv.breakpoints();
        let (lo, hi) = (breaks[0], breaks[breaks.len() - 1]);
        let mut entries: BTreeMap<(usize, usize), f64> = BTreeMap::new();
        let mut add = |row: &[(usize, f64)], w: f64| {
            for &(i, a) in row {
                for &(j, b) in row {
                    *entries.entry((i, j)).or_insert(0.0) += w * a * b;
                }
            }
        };
        for span in breaks.windows(2) {
            for (s, w) in gauss.mapped(span[0], span[1]) {
                let (u, v) = on_edge(&pa.shell, self.edge, (s - lo) / (hi - lo));
                let e = pa.shell.surface().evaluate(u, v);
                let tangent = match self.edge {
                    Edge::Xi0 | Edge::Xi1 => e.r_eta,
                    Edge::Eta0 | Edge::Eta1 => e.r_xi,
                };
                let ds = w * norm(tangent);
                let t = normalize(tangent).unwrap_or([1.0, 0.0, 0.0]);
                let (ub, vb, _) = pb.shell.surface().closest_point(e.r);
                let ra = side_rows(&pa.shell, dofs.first_dof(self.patch), u, v, t);
                let rb = side_rows(&pb.shell, dofs.first_dof(self.other), ub, vb, t);
                let thickness = ra.thickness.max(rb.thickness);
                let alpha_u = c * modulus * thickness / h;
                let alpha_r = c * modulus * thickness.powi(3) / (12.0 * h);
                for d in 0..3 {
                    let row: Vec<(usize, f64)> = ra.u[d]
                        .iter()
                        .copied()
                        .chain(rb.u[d].iter().map(|&(i, x)| (i, -x)))
                        .collect();
                    add(&row, alpha_u * ds);
                }
                let row: Vec<(usize, f64)> = ra
                    .rotation
                    .iter()
                    .copied()
                    .chain(rb.rotation.iter().map(|&(i, x)| (i, -x)))
                    .collect();
                add(&row, alpha_r * ds);
            }
        }
        entries
    }
}
