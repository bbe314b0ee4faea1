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
use crate::geometry::surface::{BSplineSurface, Direction, SurfaceError};
use crate::geometry::vec3::{axpy, cross, dot, normalize, scale, Vec3};
use crate::model::sparse::{Pattern, SparseError};
use thiserror::Error;

mod assembly;

#[cfg(test)]
pub(crate) use assembly::scatter;
pub use assembly::{
    assemble, assemble_into, assemble_sparse, assemble_sparse_patches, Assembly, Offset, ShellMatrices,
};
pub(crate) use assembly::{integrate, PointRows, Quadrature, QuadratureStep};

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

#[cfg(test)]
mod tests;
