//! The B-spline degenerate shell (paper §2.1, eq. 2–17).
//!
//! Geometry, eq. (2): `s(ξ,η,τ) = Σ_ij B_i(ξ) B_j(η) [P_ij + t_ij (τ - ½) v3_ij]`.
//! Displacement, eq. (3): `d = Σ_ij B_i B_j [ (u,v,w)_ij + t_ij (τ - ½)(-v2_ij α_ij + v1_ij β_ij) ]`,
//! so `α` is a rotation about `v1` and `β` a rotation about `v2`. Dofs are
//! ordered as eq. (4): `δ = {u v w α β}` per control point, control points
//! in the surface's storage order (`η` fastest).
//!
//! Directors: `v3_ij` is the unit surface normal `r_ξ × r_η` at the control
//! point's Greville abscissae; `v1_ij` is the unit projection of `r_ξ` on the
//! tangent plane and `v2 = v3 × v1`. For a flat plate in the `xy` plane this
//! gives `v1 = x`, `v2 = y`, `v3 = z`, hence `α = θx`, `β = θy`.
//!
//! Stiffness (eq. 16) and consistent mass (eq. 17) are integrated with
//! `p + 1` Gauss points per knot span along `ξ`, `q + 1` along `η` and two
//! through the thickness. Strains are evaluated in the local lamina frame
//! (e1 rotated by the material angle from the `ξ` tangent, e3 normal), where
//! the plane-stress matrix of eq. (9) applies; this is eq. (8) without
//! forming `T` explicitly.

use crate::geometry::knots::{KnotError, KnotVector, MAX_DEGREE};
use crate::geometry::quadrature::GaussLegendre;
use crate::geometry::surface::{BSplineSurface, Direction, SurfaceError};
use crate::geometry::vec3::{axpy, cross, det_inverse, dot, mat_vec, normalize, scale, Vec3};
use crate::model::material::OrthotropicMaterial;
use crate::model::sparse::{Pattern, SparseAccumulator, SparseError, SparseSymmetric};
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, Par};
use std::sync::Arc;
use thiserror::Error;

/// Generalised dofs per control point: `u, v, w, α, β`.
pub const DOFS_PER_CONTROL_POINT: usize = 5;
/// Most control points with non-zero basis functions at one point.
pub const MAX_LOCAL: usize = (MAX_DEGREE + 1) * (MAX_DEGREE + 1);

/// A field's rectangle reaching outside the shell's parameter domain.
#[derive(Debug, Clone, PartialEq, Error)]
#[error("the field's {axis} domain [{start}, {end}] is not inside the shell's [{shell_start}, {shell_end}]")]
pub struct OutsideDomain {
    /// `"xi"` or `"eta"`.
    pub axis: &'static str,
    pub start: f64,
    pub end: f64,
    pub shell_start: f64,
    pub shell_end: f64,
}

#[derive(Debug, Clone, PartialEq, Error)]
pub enum ShellError {
    #[error("{0}")]
    Surface(#[from] SurfaceError),
    #[error("{0}")]
    Knot(#[from] KnotError),
    #[error("{found} thickness values given, the net has {expected} control points")]
    ThicknessCount { found: usize, expected: usize },
    #[error("thickness at control point {index} must be finite and positive, got {value}")]
    Thickness { index: usize, value: f64 },
    #[error("{name} must be finite and positive, got {value}")]
    Dimension { name: &'static str, value: f64 },
    #[error("the surface normal is degenerate at control point {index} (collapsed edge or zero tangent)")]
    DegenerateNormal { index: usize },
    #[error("the shell Jacobian is not positive at (ξ, η, τ) = ({xi}, {eta}, {tau}): the geometry folds over itself or the thickness is too large for its curvature")]
    InvertedJacobian { xi: f64, eta: f64, tau: f64 },
    #[error("sparse assembly: {0}")]
    Sparse(SparseError),
}

/// Orthonormal director triad at a control point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    pub v1: Vec3,
    pub v2: Vec3,
    pub v3: Vec3,
}

/// A degenerate shell: a mid-surface, thicknesses and directors per control point.
#[derive(Debug, Clone, PartialEq)]
pub struct Shell {
    surface: BSplineSurface,
    thickness: Vec<f64>,
    frames: Vec<Frame>,
}

/// Everything eq. (2)–(3) need at one point `(ξ, η, τ)`.
#[derive(Debug, Clone)]
pub struct ShellPoint {
    /// Number of control points with non-zero basis at this point.
    pub count: usize,
    pub control_points: [usize; MAX_LOCAL],
    pub n: [f64; MAX_LOCAL],
    pub n_xi: [f64; MAX_LOCAL],
    pub n_eta: [f64; MAX_LOCAL],
    /// `τ - ½`.
    pub zeta: f64,
    /// Rows `∂s/∂ξ`, `∂s/∂η`, `∂s/∂τ`.
    pub jacobian: [Vec3; 3],
}

/// The displacement contributed by one unit dof: `ψ(ξ,η,τ) g` with a fixed
/// vector `g` and its parametric gradient `(ψ_ξ, ψ_η, ψ_τ)`.
#[derive(Debug, Clone, Copy)]
pub struct DofShape {
    pub dof: usize,
    pub g: Vec3,
    pub psi: f64,
    pub dpsi: Vec3,
}

impl ShellPoint {
    pub fn new_empty() -> Self {
        Self {
            count: 0,
            control_points: [0; MAX_LOCAL],
            n: [0.0; MAX_LOCAL],
            n_xi: [0.0; MAX_LOCAL],
            n_eta: [0.0; MAX_LOCAL],
            zeta: 0.0,
            jacobian: [[0.0; 3]; 3],
        }
    }
}

impl Shell {
    /// A shell on `surface` with per-control-point `thickness`; directors come
    /// from the surface normal at the Greville abscissae.
    pub fn new(surface: BSplineSurface, thickness: Vec<f64>) -> Result<Self, ShellError> {
        let (m, n) = surface.net_size();
        if thickness.len() != m * n {
            return Err(ShellError::ThicknessCount {
                found: thickness.len(),
                expected: m * n,
            });
        }
        if let Some(index) = thickness.iter().position(|t| !(t.is_finite() && *t > 0.0)) {
            return Err(ShellError::Thickness {
                index,
                value: thickness[index],
            });
        }
        let gx = surface.xi().greville();
        let ge = surface.eta().greville();
        let mut frames = Vec::with_capacity(m * n);
        for (i, &u) in gx.iter().enumerate() {
            for (j, &v) in ge.iter().enumerate() {
                let index = i * n + j;
                let e = surface.evaluate(u, v);
                let v3 = normalize(cross(e.r_xi, e.r_eta)).ok_or(ShellError::DegenerateNormal { index })?;
                let v1 = normalize(axpy(e.r_xi, -dot(e.r_xi, v3), v3)).ok_or(ShellError::DegenerateNormal { index })?;
                let v2 = cross(v3, v1);
                frames.push(Frame { v1, v2, v3 });
            }
        }
        Ok(Self {
            surface,
            thickness,
            frames,
        })
    }

    /// Flat rectangular plate `[0, length] × [0, width]` in the `xy` plane,
    /// `x` along `ξ`, linear parametrisation, uniform clamped knots, control
    /// points at the Greville abscissae, constant thickness.
    pub fn rectangular_plate(
        length: f64,
        width: f64,
        thickness: f64,
        degree: [usize; 2],
        control_points: [usize; 2],
    ) -> Result<Self, ShellError> {
        positive("length", length)?;
        positive("width", width)?;
        positive("thickness", thickness)?;
        let xi = KnotVector::uniform(degree[0], control_points[0], 0.0, 1.0)?;
        let eta = KnotVector::uniform(degree[1], control_points[1], 0.0, 1.0)?;
        let surface = BSplineSurface::interpolate(xi, eta, |u, v| [length * u, width * v, 0.0])?;
        let count = control_points[0] * control_points[1];
        Self::new(surface, vec![thickness; count])
    }

    /// A bilinear patch through `corners` in the order (ξ=0,η=0), (ξ=1,η=0),
    /// (ξ=1,η=1), (ξ=0,η=1): skewed or tapered slabs, webs, flanges. The
    /// bilinear map is reproduced exactly (interpolation at the Greville
    /// abscissae), constant thickness.
    pub fn quadrilateral(
        corners: [Vec3; 4],
        thickness: f64,
        degree: [usize; 2],
        control_points: [usize; 2],
    ) -> Result<Self, ShellError> {
        positive("thickness", thickness)?;
        let xi = KnotVector::uniform(degree[0], control_points[0], 0.0, 1.0)?;
        let eta = KnotVector::uniform(degree[1], control_points[1], 0.0, 1.0)?;
        let [a, b, c, d] = corners;
        let surface = BSplineSurface::interpolate(xi, eta, |u, v| {
            let w = [(1.0 - u) * (1.0 - v), u * (1.0 - v), u * v, (1.0 - u) * v];
            std::array::from_fn(|k| w[0] * a[k] + w[1] * b[k] + w[2] * c[k] + w[3] * d[k])
        })?;
        let count = control_points[0] * control_points[1];
        Self::new(surface, vec![thickness; count])
    }

    /// Open circular-cylindrical panel: axis along `x` (`ξ`, length `length`),
    /// arc of radius `radius` and opening angle `angle` (radians) along `η`,
    /// symmetric about the `xz` plane, crown at `z = 0`. The arc is
    /// interpolated at the Greville abscissae (B-splines cannot represent a
    /// circle exactly; the error decreases like `h^(q+1)`).
    pub fn cylindrical_panel(
        length: f64,
        radius: f64,
        angle: f64,
        thickness: f64,
        degree: [usize; 2],
        control_points: [usize; 2],
    ) -> Result<Self, ShellError> {
        positive("length", length)?;
        positive("radius", radius)?;
        positive("angle", angle)?;
        positive("thickness", thickness)?;
        let xi = KnotVector::uniform(degree[0], control_points[0], 0.0, 1.0)?;
        let eta = KnotVector::uniform(degree[1], control_points[1], 0.0, 1.0)?;
        let surface = BSplineSurface::interpolate(xi, eta, |u, v| {
            let theta = (v - 0.5) * angle;
            [length * u, radius * theta.sin(), radius * (theta.cos() - 1.0)]
        })?;
        let count = control_points[0] * control_points[1];
        Self::new(surface, vec![thickness; count])
    }

    /// The same mid-surface with the thickness `thickness` per control point.
    pub fn with_thickness(&self, thickness: Vec<f64>) -> Result<Self, ShellError> {
        Self::new(self.surface.clone(), thickness)
    }

    /// The same shell moved by `by` (m).
    pub fn translated(&self, by: Vec3) -> Result<Self, ShellError> {
        let s = &self.surface;
        let surface = s.with_points(s.points().iter().map(|&p| axpy(p, 1.0, by)).collect())?;
        Self::new(surface, self.thickness.clone())
    }

    /// h-refinement: inserts the knot `u` once along `direction`. The
    /// geometry and thickness field are unchanged; directors are recomputed.
    pub fn insert_knot(&self, direction: Direction, u: f64) -> Result<Self, ShellError> {
        let (surface, thickness) = self.surface.insert_knot(direction, u, &self.thickness, 1)?;
        Self::new(surface, thickness)
    }

    /// The sparsity pattern of the shell's generalised dofs (five per
    /// control point).
    pub fn pattern(&self) -> Pattern {
        let s = self.surface();
        Pattern::control_net(
            s.net_size(),
            (s.xi().degree(), s.eta().degree()),
            &vec![DOFS_PER_CONTROL_POINT; self.control_point_count()],
        )
    }

    pub fn surface(&self) -> &BSplineSurface {
        &self.surface
    }

    pub fn thickness(&self) -> &[f64] {
        &self.thickness
    }

    pub fn frames(&self) -> &[Frame] {
        &self.frames
    }

    pub fn control_point_count(&self) -> usize {
        self.thickness.len()
    }

    pub fn dof_count(&self) -> usize {
        DOFS_PER_CONTROL_POINT * self.control_point_count()
    }

    /// Basis values, derivatives and the Jacobian of eq. (2) at `(ξ, η, τ)`.
    pub fn evaluate_into(&self, xi: f64, eta: f64, tau: f64, out: &mut ShellPoint) {
        let (kx, ke) = (self.surface.xi(), self.surface.eta());
        let (p, q) = (kx.degree(), ke.degree());
        let n_eta = ke.basis_count();
        let (si, sj) = (kx.span(xi), ke.span(eta));
        let (mut bx, mut dbx, mut be, mut dbe) = (
            [0.0; MAX_DEGREE + 1],
            [0.0; MAX_DEGREE + 1],
            [0.0; MAX_DEGREE + 1],
            [0.0; MAX_DEGREE + 1],
        );
        kx.basis_with_derivatives(si, xi, &mut bx, &mut dbx);
        ke.basis_with_derivatives(sj, eta, &mut be, &mut dbe);
        let mut k = 0;
        for a in 0..=p {
            for b in 0..=q {
                out.control_points[k] = (si - p + a) * n_eta + (sj - q + b);
                (out.n[k], out.n_xi[k], out.n_eta[k]) = (bx[a] * be[b], dbx[a] * be[b], bx[a] * dbe[b]);
                k += 1;
            }
        }
        self.surface.rationalise(
            &out.control_points[..k],
            &mut out.n[..k],
            &mut out.n_xi[..k],
            &mut out.n_eta[..k],
        );
        let zeta = tau - 0.5;
        let points = self.surface.points();
        let mut jac = [[0.0; 3]; 3];
        for j in 0..k {
            let cp = out.control_points[j];
            let t = self.thickness[cp];
            let v3 = self.frames[cp].v3;
            let pos = axpy(points[cp], t * zeta, v3);
            jac[0] = axpy(jac[0], out.n_xi[j], pos);
            jac[1] = axpy(jac[1], out.n_eta[j], pos);
            jac[2] = axpy(jac[2], out.n[j] * t, v3);
        }
        out.count = k;
        out.zeta = zeta;
        out.jacobian = jac;
    }

    /// Eq. (2): position of the material point `(ξ, η, τ)`.
    pub fn position(&self, xi: f64, eta: f64, tau: f64) -> Vec3 {
        let mut pt = ShellPoint::new_empty();
        self.evaluate_into(xi, eta, tau, &mut pt);
        let mut r = [0.0; 3];
        for k in 0..pt.count {
            let cp = pt.control_points[k];
            let pos = axpy(
                self.surface.points()[cp],
                self.thickness[cp] * pt.zeta,
                self.frames[cp].v3,
            );
            r = axpy(r, pt.n[k], pos);
        }
        r
    }

    /// The five unit-dof shapes of local control point `k` at `pt` (eq. 3).
    pub fn dof_shapes(&self, pt: &ShellPoint, k: usize) -> [DofShape; DOFS_PER_CONTROL_POINT] {
        let cp = pt.control_points[k];
        let (n, nx, ne) = (pt.n[k], pt.n_xi[k], pt.n_eta[k]);
        let f = self.frames[cp];
        let tz = self.thickness[cp] * pt.zeta;
        let t = self.thickness[cp];
        let base = DOFS_PER_CONTROL_POINT * cp;
        let translation = |d: usize| {
            let mut g = [0.0; 3];
            g[d] = 1.0;
            DofShape {
                dof: base + d,
                g,
                psi: n,
                dpsi: [nx, ne, 0.0],
            }
        };
        let rotation = |d: usize, g: Vec3| DofShape {
            dof: base + d,
            g,
            psi: n * tz,
            dpsi: [nx * tz, ne * tz, n * t],
        };
        [
            translation(0),
            translation(1),
            translation(2),
            rotation(3, scale(f.v2, -1.0)),
            rotation(4, f.v1),
        ]
    }

    /// Checks that the rectangle of the knot vectors `xi` × `eta` (a spring
    /// or stiffness field's) lies in the shell's parameter domain.
    pub fn check_inside(&self, xi: &KnotVector, eta: &KnotVector) -> Result<(), OutsideDomain> {
        let (kx, ke) = (self.surface.xi(), self.surface.eta());
        for (axis, own, of_shell) in [("xi", xi, kx), ("eta", eta, ke)] {
            let ((start, end), (shell_start, shell_end)) = (own.domain(), of_shell.domain());
            if start < shell_start || end > shell_end {
                return Err(OutsideDomain {
                    axis,
                    start,
                    end,
                    shell_start,
                    shell_end,
                });
            }
        }
        Ok(())
    }

    /// Eq. (3) at one point: the non-zero columns of `N` as `(dof, N column)`.
    pub fn shape_functions(&self, xi: f64, eta: f64, tau: f64) -> Vec<(usize, Vec3)> {
        let mut pt = ShellPoint::new_empty();
        self.evaluate_into(xi, eta, tau, &mut pt);
        (0..pt.count)
            .flat_map(|k| self.dof_shapes(&pt, k))
            .map(|s| (s.dof, scale(s.g, s.psi)))
            .filter(|(_, c)| c.iter().any(|&x| x != 0.0))
            .collect()
    }
}

fn positive(name: &'static str, value: f64) -> Result<(), ShellError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(ShellError::Dimension { name, value })
    }
}

/// Unconstrained stiffness `K_f` (eq. 16) and consistent mass `M` (eq. 17).
#[derive(Debug, Clone)]
pub struct ShellMatrices {
    pub stiffness: Mat<f64>,
    pub mass: Mat<f64>,
}

/// Lamina frame at a point: rows `e1, e2, e3`, `e3` normal to the lamina and
/// `e1` the material axis (the `ξ` tangent rotated by `angle` about `e3`).
fn lamina_frame(jac: &[Vec3; 3], angle: f64) -> Option<[Vec3; 3]> {
    let e3 = normalize(cross(jac[0], jac[1]))?;
    let r1 = normalize(axpy(jac[0], -dot(jac[0], e3), e3))?;
    let r2 = cross(e3, r1);
    let (s, c) = angle.sin_cos();
    let e1 = axpy(scale(r1, c), s, r2);
    let e2 = cross(e3, e1);
    Some([e1, e2, e3])
}

/// What the quadrature of eq. (16)–(17) gives at one point: the strain rows
/// `B` (6 × n, lamina frame), `E' B`, the displacement rows `N` (3 × n) and
/// the global dof of every column.
pub(crate) struct PointRows {
    pub(crate) b: Mat<f64>,
    pub(crate) eb: Mat<f64>,
    pub(crate) n: Mat<f64>,
    pub(crate) dofs: Vec<usize>,
}

/// Gauss points per direction: `extra` more than the `p + 1` that integrate
/// eq. (16)–(17) of a flat shell exactly (a stiffness field of degree `d`
/// multiplies the integrand by a polynomial of degree `d`: `⌈d/2⌉` more).
pub(crate) struct Quadrature {
    pub(crate) extra: (usize, usize),
    /// Cuts of the ξ and η domains besides the shell's own breakpoints.
    pub(crate) cuts: (Vec<f64>, Vec<f64>),
    /// Only the ξ spans `[a, b)` (indices among the cut spans); `None`: all.
    pub(crate) xi_spans: Option<(usize, usize)>,
}

/// A step of the quadrature loop ([`integrate`]).
pub(crate) enum QuadratureStep<'a> {
    /// A Gauss point at `(ξ, η)` with volume weight `w`; `layer` is 0 or 1,
    /// the thickness Gauss point (the two layers of one `(ξ, η)` come in a row).
    Point {
        xi: f64,
        eta: f64,
        layer: usize,
        w: f64,
        rows: &'a PointRows,
    },
    /// The end of a span whose local columns map to `dofs`.
    SpanEnd { dofs: &'a [usize] },
}

/// The quadrature loop of eq. (16)–(17): every knot span of the shell (cut
/// further at `quadrature.cuts`), every Gauss point, then the span's end.
#[allow(
    clippy::too_many_lines,
    reason = "the quadrature loop of eq. (16)-(17): span, Gauss point, local frame and strain rows read as one nest"
)]
pub(crate) fn integrate(
    shell: &Shell,
    material: &OrthotropicMaterial,
    quadrature: &Quadrature,
    mut visit: impl FnMut(QuadratureStep<'_>),
) -> Result<(), ShellError> {
    let (p, q) = (shell.surface.xi().degree(), shell.surface.eta().degree());
    let (gx, ge, gt) = (
        GaussLegendre::new(p + 1 + quadrature.extra.0),
        GaussLegendre::new(q + 1 + quadrature.extra.1),
        GaussLegendre::new(2),
    );
    let nloc = DOFS_PER_CONTROL_POINT * (p + 1) * (q + 1);
    let e_local = material.local_matrix();
    let mut rows = PointRows {
        b: Mat::<f64>::zeros(6, nloc),
        eb: Mat::<f64>::zeros(6, nloc),
        n: Mat::<f64>::zeros(3, nloc),
        dofs: vec![0usize; nloc],
    };
    let mut pt = ShellPoint::new_empty();
    let cut = |own: Vec<f64>, extra: &[f64]| {
        let (a, b) = (own[0], own[own.len() - 1]);
        let mut all: Vec<f64> = own;
        all.extend(extra.iter().copied().filter(|&k| k > a && k < b));
        all.sort_by(f64::total_cmp);
        all.dedup();
        all
    };
    let bx = cut(shell.surface.xi().breakpoints(), &quadrature.cuts.0);
    let be = cut(shell.surface.eta().breakpoints(), &quadrature.cuts.1);
    for (ix, wx) in bx.windows(2).enumerate() {
        if quadrature.xi_spans.is_some_and(|(a, b)| ix < a || ix >= b) {
            continue;
        }
        for we in be.windows(2) {
            for (xi, wxi) in gx.mapped(wx[0], wx[1]) {
                for (eta, weta) in ge.mapped(we[0], we[1]) {
                    for (layer, (tau, wt)) in gt.mapped(0.0, 1.0).enumerate() {
                        shell.evaluate_into(xi, eta, tau, &mut pt);
                        let (det, jinv) = det_inverse(&pt.jacobian);
                        let frame = lamina_frame(&pt.jacobian, material.angle_rad());
                        let Some(frame) = frame.filter(|_| det > 0.0 && det.is_finite()) else {
                            return Err(ShellError::InvertedJacobian { xi, eta, tau });
                        };
                        for k in 0..pt.count {
                            for (d, s) in shell.dof_shapes(&pt, k).into_iter().enumerate() {
                                let col = DOFS_PER_CONTROL_POINT * k + d;
                                rows.dofs[col] = s.dof;
                                // G = g ⊗ ∇ψ; in the lamina frame G' = (R g) ⊗ (R ∇ψ).
                                let grad = mat_vec(&jinv, s.dpsi);
                                let a = mat_vec(&frame, s.g);
                                let c = mat_vec(&frame, grad);
                                let strain = [
                                    a[0] * c[0],
                                    a[1] * c[1],
                                    a[2] * c[2],
                                    a[0] * c[1] + a[1] * c[0],
                                    a[1] * c[2] + a[2] * c[1],
                                    a[0] * c[2] + a[2] * c[0],
                                ];
                                for r in 0..6 {
                                    rows.b[(r, col)] = strain[r];
                                    rows.eb[(r, col)] = (0..6).map(|s| e_local[r][s] * strain[s]).sum();
                                }
                                let nc = scale(s.g, s.psi);
                                for r in 0..3 {
                                    rows.n[(r, col)] = nc[r];
                                }
                            }
                        }
                        visit(QuadratureStep::Point {
                            xi,
                            eta,
                            layer,
                            w: wxi * weta * wt * det,
                            rows: &rows,
                        });
                    }
                }
            }
            visit(QuadratureStep::SpanEnd { dofs: &rows.dofs });
        }
    }
    Ok(())
}

/// `target[dofs, dofs] += local`.
pub(crate) fn scatter(target: &mut Mat<f64>, local: &Mat<f64>, dofs: &[usize]) {
    for (r, &dr) in dofs.iter().enumerate() {
        for (c, &dc) in dofs.iter().enumerate() {
            target[(dr, dc)] += local[(r, c)];
        }
    }
}

/// Where assembled element matrices go: a dense matrix, or a sparse one on
/// the control net's pattern ([`crate::model::sparse`]).
pub trait Assembly {
    /// `self[dofs, dofs] += local`.
    fn add_local(&mut self, local: &Mat<f64>, dofs: &[usize]) -> Result<(), SparseError>;
}

impl<A: Assembly + ?Sized> Assembly for &mut A {
    fn add_local(&mut self, local: &Mat<f64>, dofs: &[usize]) -> Result<(), SparseError> {
        (**self).add_local(local, dofs)
    }
}

impl Assembly for Mat<f64> {
    fn add_local(&mut self, local: &Mat<f64>, dofs: &[usize]) -> Result<(), SparseError> {
        scatter(self, local, dofs);
        Ok(())
    }
}

impl Assembly for SparseSymmetric {
    fn add_local(&mut self, local: &Mat<f64>, dofs: &[usize]) -> Result<(), SparseError> {
        SparseSymmetric::add_local(self, local, dofs)
    }
}

impl Assembly for SparseAccumulator {
    fn add_local(&mut self, local: &Mat<f64>, dofs: &[usize]) -> Result<(), SparseError> {
        SparseAccumulator::add_local(self, local, dofs)
    }
}

/// An assembly target whose element dofs are shifted by `offset`: a
/// patch's own numbering placed in a model of several patches.
#[derive(Debug, Clone)]
pub struct Offset<A> {
    pub inner: A,
    pub offset: usize,
}

impl<A> Offset<A> {
    pub fn new(inner: A, offset: usize) -> Self {
        Self { inner, offset }
    }
}

impl<A: Assembly> Assembly for Offset<A> {
    fn add_local(&mut self, local: &Mat<f64>, dofs: &[usize]) -> Result<(), SparseError> {
        if self.offset == 0 {
            return self.inner.add_local(local, dofs);
        }
        let shifted: Vec<usize> = dofs.iter().map(|d| d + self.offset).collect();
        self.inner.add_local(local, &shifted)
    }
}

/// Assembles eq. (16) and eq. (17) over every knot span.
pub fn assemble(shell: &Shell, material: &OrthotropicMaterial) -> Result<ShellMatrices, ShellError> {
    let ndof = shell.dof_count();
    let mut stiffness = Mat::<f64>::zeros(ndof, ndof);
    let mut mass = Mat::<f64>::zeros(ndof, ndof);
    assemble_into(shell, material, &mut stiffness, &mut mass)?;
    Ok(ShellMatrices { stiffness, mass })
}

/// Eq. (16) and (17) on the shell's sparse pattern: memory and time linear
/// in the number of control points.
pub fn assemble_sparse(
    shell: &Shell,
    material: &OrthotropicMaterial,
    pattern: &Arc<Pattern>,
) -> Result<(SparseSymmetric, SparseSymmetric), ShellError> {
    assemble_sparse_patches(&[(shell, material, 0)], pattern)
}

/// [`assemble_sparse`] of several patches, each `(shell, material, offset)`
/// with its dofs from `offset` in `pattern`, into one `K` and one `M`.
pub fn assemble_sparse_patches(
    patches: &[(&Shell, &OrthotropicMaterial, usize)],
    pattern: &Arc<Pattern>,
) -> Result<(SparseSymmetric, SparseSymmetric), ShellError> {
    // Two threads, each on half of every patch's ξ spans into matrices of
    // its own, added at the end: a fixed split, so the sums do not depend
    // on the machine.
    let part = |second_half: bool| -> Result<(SparseSymmetric, SparseSymmetric), ShellError> {
        let mut stiffness = SparseSymmetric::zeros(Arc::clone(pattern));
        let mut mass = SparseSymmetric::zeros(Arc::clone(pattern));
        for &(shell, material, offset) in patches {
            let spans = shell.surface.xi().breakpoints().len() - 1;
            let half = spans / 2;
            let range = if second_half { (half, spans) } else { (0, half) };
            let (mut k, mut m) = (Offset::new(&mut stiffness, offset), Offset::new(&mut mass, offset));
            assemble_spans(shell, material, &mut k, &mut m, Some(range))?;
        }
        Ok((stiffness, mass))
    };
    let (first, second) = std::thread::scope(|scope| {
        let other = scope.spawn(|| part(true));
        let first = part(false);
        (first, other.join().expect("assembly thread"))
    });
    let ((mut stiffness, mut mass), (k2, m2)) = (first?, second?);
    stiffness.add_scaled(&k2, 1.0);
    mass.add_scaled(&m2, 1.0);
    Ok((stiffness, mass))
}

/// Eq. (16) into `stiffness` and eq. (17) into `mass`, span by span.
pub fn assemble_into<A: Assembly>(
    shell: &Shell,
    material: &OrthotropicMaterial,
    stiffness: &mut A,
    mass: &mut A,
) -> Result<(), ShellError> {
    assemble_spans(shell, material, stiffness, mass, None)
}

/// [`assemble_into`] over the ξ spans `[a, b)` only (`None`: all).
fn assemble_spans<A: Assembly>(
    shell: &Shell,
    material: &OrthotropicMaterial,
    stiffness: &mut A,
    mass: &mut A,
    xi_spans: Option<(usize, usize)>,
) -> Result<(), ShellError> {
    let (p, q) = (shell.surface.xi().degree(), shell.surface.eta().degree());
    let nloc = DOFS_PER_CONTROL_POINT * (p + 1) * (q + 1);
    let rho = material.density();
    let mut k_loc = Mat::<f64>::zeros(nloc, nloc);
    let mut m_loc = Mat::<f64>::zeros(nloc, nloc);
    let exact = Quadrature {
        extra: (0, 0),
        cuts: (Vec::new(), Vec::new()),
        xi_spans,
    };
    let mut outcome = Ok(());
    integrate(shell, material, &exact, |step| match step {
        QuadratureStep::Point { w, rows, .. } => {
            matmul(
                k_loc.as_mut(),
                Accum::Add,
                rows.b.transpose(),
                rows.eb.as_ref(),
                w,
                Par::Seq,
            );
            matmul(
                m_loc.as_mut(),
                Accum::Add,
                rows.n.transpose(),
                rows.n.as_ref(),
                rho * w,
                Par::Seq,
            );
        }
        QuadratureStep::SpanEnd { dofs } => {
            if outcome.is_ok() {
                outcome = stiffness
                    .add_local(&k_loc, dofs)
                    .and_then(|()| mass.add_local(&m_loc, dofs));
            }
            k_loc.fill(0.0);
            m_loc.fill(0.0);
        }
    })?;
    outcome.map_err(ShellError::Sparse)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plate() -> Shell {
        Shell::rectangular_plate(16.0, 9.0, 1.6, [4, 4], [13, 5]).unwrap()
    }

    #[test]
    fn plate_directors_are_the_global_axes() {
        for f in plate().frames() {
            assert!((f.v1[0] - 1.0).abs() < 1e-14 && (f.v2[1] - 1.0).abs() < 1e-14 && (f.v3[2] - 1.0).abs() < 1e-14);
        }
    }

    #[test]
    fn total_mass_is_rho_h_area() {
        let shell = plate();
        let mat = OrthotropicMaterial::isotropic(30e9, 0.2, 975.0).unwrap();
        let mats = assemble(&shell, &mat).unwrap();
        let exact = 975.0 * 1.6 * 16.0 * 9.0;
        for dir in 0..3 {
            // Rigid translation: every control point moves by one along `dir`.
            let mut total = 0.0;
            for a in (dir..shell.dof_count()).step_by(DOFS_PER_CONTROL_POINT) {
                for b in (dir..shell.dof_count()).step_by(DOFS_PER_CONTROL_POINT) {
                    total += mats.mass[(a, b)];
                }
            }
            assert!((total - exact).abs() < 1e-10 * exact, "dir {dir}: {total} vs {exact}");
        }
    }

    #[test]
    fn rigid_motions_carry_no_strain_energy() {
        // A rigid rotation of a curved panel about an arbitrary axis: the
        // dofs are u = θ × P and the director rotations that turn v3 with it.
        let shell = Shell::cylindrical_panel(2.0, 3.0, 0.8, 0.05, [3, 3], [6, 7]).unwrap();
        let mat = OrthotropicMaterial::isotropic(70e9, 0.33, 2700.0).unwrap();
        let mats = assemble(&shell, &mat).unwrap();
        let theta = [0.3, -0.2, 0.5];
        let mut x = vec![0.0; shell.dof_count()];
        for (cp, (pt, f)) in shell.surface().points().iter().zip(shell.frames()).enumerate() {
            let u = cross(theta, *pt);
            // v3 turns by θ × v3 = -α v2 + β v1  ⇒  α = -(θ×v3)·v2, β = (θ×v3)·v1.
            let dv3 = cross(theta, f.v3);
            let b = DOFS_PER_CONTROL_POINT * cp;
            x[b..b + 3].copy_from_slice(&u);
            x[b + 3] = -dot(dv3, f.v2);
            x[b + 4] = dot(dv3, f.v1);
        }
        let kx: f64 = (0..x.len())
            .map(|i| (0..x.len()).map(|j| mats.stiffness[(i, j)] * x[j]).sum::<f64>() * x[i])
            .sum();
        let kdiag: f64 = (0..x.len()).map(|i| mats.stiffness[(i, i)] * x[i] * x[i]).sum();
        // Directors are interpolated, not exactly rotated with the arc, so the
        // energy is small rather than zero: bounded relative to the diagonal.
        assert!(kx.abs() < 1e-6 * kdiag, "{kx} vs {kdiag}");
    }
}
