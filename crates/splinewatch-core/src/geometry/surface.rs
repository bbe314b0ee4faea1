//! Tensor-product B-spline surfaces, paper eq. (1):
//! `r(ξ, η) = Σ_i Σ_j B_i^p(ξ) B_j^q(η) P_ij`, and their rational
//! generalisation (NURBS, Piegl & Tiller, The NURBS Book, §4.4):
//! `r = Σ R_ij P_ij` with `R_ij = w_ij B_i B_j / W`, `W = Σ w_kl B_k B_l`, so
//! circles and arcs from CAD are exact. An isogeometric shell interpolates
//! its displacements with the same `R_ij` (Hughes et al. 2005), so the
//! rational basis is applied wherever the basis is evaluated
//! ([`BSplineSurface::rationalise`]); equal weights are stored as a plain
//! B-spline, whose results stay bit for bit.
//!
//! Control points are stored with `η` running fastest: `P_ij` is
//! `points[i * n + j]`, `i < m` along `ξ`, `j < n` along `η`.

use crate::geometry::knots::{KnotError, KnotVector, MAX_DEGREE};
use crate::geometry::vec3::{axpy, dot, Vec3};
use faer::prelude::Solve;
use faer::Mat;
use thiserror::Error;

#[derive(Debug, Clone, PartialEq, Error)]
pub enum SurfaceError {
    #[error("{found} control points given, the knot vectors need {m} × {n} = {}", m * n)]
    ControlPointCount { found: usize, m: usize, n: usize },
    #[error("control point {index} has a non-finite coordinate")]
    NotFinite { index: usize },
    #[error("interpolation at the Greville abscissae is singular")]
    SingularInterpolation,
    #[error("control point {index} has weight {weight}: weights must be finite and positive")]
    BadWeight { index: usize, weight: f64 },
    #[error("{found} weights given for {points} control points")]
    WeightCount { found: usize, points: usize },
    #[error("knot insertion: {0}")]
    Knot(#[from] KnotError),
}

/// Which parametric direction an operation acts along.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Direction {
    Xi,
    Eta,
}

/// A B-spline surface patch with validated knot vectors and control net.
#[derive(Debug, Clone, PartialEq)]
pub struct BSplineSurface {
    xi: KnotVector,
    eta: KnotVector,
    points: Vec<Vec3>,
    /// NURBS weights per control point; `None` for a B-spline (all equal).
    weights: Option<Vec<f64>>,
}

/// Position and first parametric derivatives at a point of a surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfacePoint {
    pub r: Vec3,
    pub r_xi: Vec3,
    pub r_eta: Vec3,
}

impl BSplineSurface {
    pub fn new(xi: KnotVector, eta: KnotVector, points: Vec<Vec3>) -> Result<Self, SurfaceError> {
        let (m, n) = (xi.basis_count(), eta.basis_count());
        if points.len() != m * n {
            return Err(SurfaceError::ControlPointCount {
                found: points.len(),
                m,
                n,
            });
        }
        if let Some(index) = points.iter().position(|p| p.iter().any(|c| !c.is_finite())) {
            return Err(SurfaceError::NotFinite { index });
        }
        Ok(Self {
            xi,
            eta,
            points,
            weights: None,
        })
    }

    /// A NURBS surface with `weights` per control point (finite, positive);
    /// equal weights give the B-spline surface.
    pub fn rational(
        xi: KnotVector,
        eta: KnotVector,
        points: Vec<Vec3>,
        weights: Vec<f64>,
    ) -> Result<Self, SurfaceError> {
        let mut surface = Self::new(xi, eta, points)?;
        if weights.len() != surface.points.len() {
            return Err(SurfaceError::WeightCount {
                found: weights.len(),
                points: surface.points.len(),
            });
        }
        if let Some(index) = weights.iter().position(|w| !(w.is_finite() && *w > 0.0)) {
            return Err(SurfaceError::BadWeight {
                index,
                weight: weights[index],
            });
        }
        if weights.iter().any(|&w| w != weights[0]) {
            surface.weights = Some(weights);
        }
        Ok(surface)
    }

    /// The same knots and weights with other control points.
    pub fn with_points(&self, points: Vec<Vec3>) -> Result<Self, SurfaceError> {
        match &self.weights {
            None => Self::new(self.xi.clone(), self.eta.clone(), points),
            Some(w) => Self::rational(self.xi.clone(), self.eta.clone(), points, w.clone()),
        }
    }

    /// The NURBS weights, `None` for a B-spline.
    pub fn weights(&self) -> Option<&[f64]> {
        self.weights.as_deref()
    }

    /// Turns the tensor products `B_i B_j` (`n`) and their derivatives
    /// (`n_xi`, `n_eta`) at the control points `cps` into the rational
    /// basis `R = w B_i B_j / W` and its derivatives
    /// `R_ξ = w (B_ξ W − B W_ξ) / W²`; nothing changes on a B-spline.
    pub fn rationalise(&self, cps: &[usize], n: &mut [f64], n_xi: &mut [f64], n_eta: &mut [f64]) {
        let Some(weights) = &self.weights else {
            return;
        };
        let (mut w, mut w_xi, mut w_eta) = (0.0, 0.0, 0.0);
        for (k, &cp) in cps.iter().enumerate() {
            w += weights[cp] * n[k];
            w_xi += weights[cp] * n_xi[k];
            w_eta += weights[cp] * n_eta[k];
        }
        for (k, &cp) in cps.iter().enumerate() {
            let c = weights[cp] / (w * w);
            n_xi[k] = c * (n_xi[k] * w - n[k] * w_xi);
            n_eta[k] = c * (n_eta[k] * w - n[k] * w_eta);
            n[k] *= weights[cp] / w;
        }
    }

    /// The surface interpolating `map` at the tensor grid of Greville
    /// abscissae. Linear maps are reproduced exactly; smooth maps converge
    /// at order `p + 1`.
    pub fn interpolate(xi: KnotVector, eta: KnotVector, map: impl Fn(f64, f64) -> Vec3) -> Result<Self, SurfaceError> {
        let gx = xi.greville();
        let ge = eta.greville();
        let mut values = vec![[0.0; 3]; gx.len() * ge.len()];
        for (i, &u) in gx.iter().enumerate() {
            for (j, &v) in ge.iter().enumerate() {
                values[i * ge.len() + j] = map(u, v);
            }
        }
        let flat: Vec<f64> = values.iter().flatten().copied().collect();
        let solved = interpolate_tensor(&xi, &eta, &flat, 3)?;
        let points = solved.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        Self::new(xi, eta, points)
    }

    pub fn xi(&self) -> &KnotVector {
        &self.xi
    }

    pub fn eta(&self) -> &KnotVector {
        &self.eta
    }

    pub fn points(&self) -> &[Vec3] {
        &self.points
    }

    /// `(m, n)`: control points along `ξ` and `η`.
    pub fn net_size(&self) -> (usize, usize) {
        (self.xi.basis_count(), self.eta.basis_count())
    }

    /// Eq. (1) and its first derivatives at `(ξ, η)`.
    pub fn evaluate(&self, xi: f64, eta: f64) -> SurfacePoint {
        const LOCAL: usize = (MAX_DEGREE + 1) * (MAX_DEGREE + 1);
        let (p, q) = (self.xi.degree(), self.eta.degree());
        let n = self.eta.basis_count();
        let (si, sj) = (self.xi.span(xi), self.eta.span(eta));
        let (mut bx, mut dbx, mut be, mut dbe) = (
            [0.0; MAX_DEGREE + 1],
            [0.0; MAX_DEGREE + 1],
            [0.0; MAX_DEGREE + 1],
            [0.0; MAX_DEGREE + 1],
        );
        self.xi.basis_with_derivatives(si, xi, &mut bx, &mut dbx);
        self.eta.basis_with_derivatives(sj, eta, &mut be, &mut dbe);
        let (mut cps, mut nv, mut nx, mut ne) = ([0; LOCAL], [0.0; LOCAL], [0.0; LOCAL], [0.0; LOCAL]);
        let mut count = 0;
        for a in 0..=p {
            for b in 0..=q {
                cps[count] = (si - p + a) * n + (sj - q + b);
                (nv[count], nx[count], ne[count]) = (bx[a] * be[b], dbx[a] * be[b], bx[a] * dbe[b]);
                count += 1;
            }
        }
        self.rationalise(&cps[..count], &mut nv[..count], &mut nx[..count], &mut ne[..count]);
        let mut out = SurfacePoint {
            r: [0.0; 3],
            r_xi: [0.0; 3],
            r_eta: [0.0; 3],
        };
        for k in 0..count {
            let pt = self.points[cps[k]];
            out.r = axpy(out.r, nv[k], pt);
            out.r_xi = axpy(out.r_xi, nx[k], pt);
            out.r_eta = axpy(out.r_eta, ne[k], pt);
        }
        out
    }

    /// Parameters `(ξ, η)` whose point projects onto `(x, y)` in the xy
    /// plane (Newton's method on the first two coordinates of eq. 1), or
    /// `None` when no such point lies in the parameter domain.
    pub fn locate_xy(&self, x: f64, y: f64) -> Option<(f64, f64)> {
        let (a, b) = self.xi.domain();
        let (c, d) = self.eta.domain();
        let (mut u, mut v) = (0.5 * (a + b), 0.5 * (c + d));
        for _ in 0..50 {
            let e = self.evaluate(u, v);
            let (fx, fy) = (e.r[0] - x, e.r[1] - y);
            let det = e.r_xi[0] * e.r_eta[1] - e.r_xi[1] * e.r_eta[0];
            if !(det.is_finite() && det.abs() > 0.0) {
                return None;
            }
            let du = (fx * e.r_eta[1] - fy * e.r_eta[0]) / det;
            let dv = (e.r_xi[0] * fy - e.r_xi[1] * fx) / det;
            u = (u - du).clamp(a, b);
            v = (v - dv).clamp(c, d);
            let scale = e.r_xi[0].abs() + e.r_xi[1].abs() + e.r_eta[0].abs() + e.r_eta[1].abs();
            if fx.abs() + fy.abs() <= 1e-12 * scale.max(1.0) && du.abs() + dv.abs() < 1e-14 {
                break;
            }
        }
        let e = self.evaluate(u, v);
        let scale = (e.r_xi[0].abs() + e.r_eta[1].abs()).max(1.0);
        ((e.r[0] - x).abs() + (e.r[1] - y).abs() <= 1e-9 * scale).then_some((u, v))
    }

    /// The point of the surface nearest to `x`: `(ξ, η, distance)`. A grid
    /// search seeds Gauss–Newton on `|r(ξ, η) − x|²` (the surface's second
    /// derivatives dropped), clamped to the parameter domain, so a point
    /// beyond an edge projects onto the edge.
    pub fn closest_point(&self, x: Vec3) -> (f64, f64, f64) {
        const SEEDS: usize = 16;
        let (a, b) = self.xi.domain();
        let (c, d) = self.eta.domain();
        let distance2 = |u: f64, v: f64| {
            let r = self.evaluate(u, v).r;
            (0..3).map(|k| (r[k] - x[k]).powi(2)).sum::<f64>()
        };
        let mut best = (a, c, f64::INFINITY);
        for i in 0..=SEEDS {
            for j in 0..=SEEDS {
                let u = a + (b - a) * i as f64 / SEEDS as f64;
                let v = c + (d - c) * j as f64 / SEEDS as f64;
                let e = distance2(u, v);
                if e < best.2 {
                    best = (u, v, e);
                }
            }
        }
        let (mut u, mut v) = (best.0, best.1);
        for _ in 0..60 {
            let e = self.evaluate(u, v);
            let f = [x[0] - e.r[0], x[1] - e.r[1], x[2] - e.r[2]];
            let (g11, g12, g22) = (dot(e.r_xi, e.r_xi), dot(e.r_xi, e.r_eta), dot(e.r_eta, e.r_eta));
            let (h1, h2) = (dot(e.r_xi, f), dot(e.r_eta, f));
            let det = g11 * g22 - g12 * g12;
            if !(det.is_finite() && det > 0.0) {
                break;
            }
            let du = (g22 * h1 - g12 * h2) / det;
            let dv = (g11 * h2 - g12 * h1) / det;
            let (u2, v2) = ((u + du).clamp(a, b), (v + dv).clamp(c, d));
            let moved = (u2 - u).abs() + (v2 - v).abs();
            (u, v) = (u2, v2);
            if moved < 1e-15 {
                break;
            }
        }
        (u, v, distance2(u, v).sqrt())
    }

    /// The same surface with the knot `u` inserted once along `direction`
    /// (h-refinement); `extra` carries further per-control-point values of
    /// dimension `extra_dim` (e.g. thickness) refined the same way. A NURBS
    /// surface is refined in homogeneous coordinates (`w P`, `w`, `w e`:
    /// P&T §5.2), so both the geometry and the fields `Σ R e` are kept.
    pub fn insert_knot(
        &self,
        direction: Direction,
        u: f64,
        extra: &[f64],
        extra_dim: usize,
    ) -> Result<(Self, Vec<f64>), SurfaceError> {
        let (m, n) = self.net_size();
        // Coordinates, then the weight when rational, then the extras.
        let rational = usize::from(self.weights.is_some());
        let dim = 3 + rational + extra_dim;
        let value = |i: usize, j: usize, d: usize| {
            let k = i * n + j;
            let w = self.weights.as_ref().map_or(1.0, |w| w[k]);
            match d {
                0..=2 => w * self.points[k][d],
                3 if rational == 1 => w,
                _ => w * extra[k * extra_dim + d - 3 - rational],
            }
        };
        let (lines, along, kv) = match direction {
            Direction::Xi => (n, m, &self.xi),
            Direction::Eta => (m, n, &self.eta),
        };
        let mut refined_kv = None;
        let mut columns = Vec::with_capacity(lines);
        for line in 0..lines {
            let mut coeffs = Vec::with_capacity(along * dim);
            for k in 0..along {
                let (i, j) = match direction {
                    Direction::Xi => (k, line),
                    Direction::Eta => (line, k),
                };
                coeffs.extend((0..dim).map(|d| value(i, j, d)));
            }
            let (kv2, new) = kv.insert_knot(u, &coeffs, dim)?;
            refined_kv = Some(kv2);
            columns.push(new);
        }
        let refined_kv = refined_kv.expect("a surface has at least one line");
        let (xi, eta) = match direction {
            Direction::Xi => (refined_kv, self.eta.clone()),
            Direction::Eta => (self.xi.clone(), refined_kv),
        };
        let (m2, n2) = (xi.basis_count(), eta.basis_count());
        let mut points = vec![[0.0; 3]; m2 * n2];
        let mut weights = vec![1.0; m2 * n2];
        let mut extra_out = vec![0.0; m2 * n2 * extra_dim];
        for (line, col) in columns.iter().enumerate() {
            for (k, c) in col.chunks_exact(dim).enumerate() {
                let (i, j) = match direction {
                    Direction::Xi => (k, line),
                    Direction::Eta => (line, k),
                };
                let idx = i * n2 + j;
                let w = if rational == 1 { c[3] } else { 1.0 };
                points[idx] = [c[0] / w, c[1] / w, c[2] / w];
                weights[idx] = w;
                for (out, e) in extra_out[idx * extra_dim..(idx + 1) * extra_dim]
                    .iter_mut()
                    .zip(&c[3 + rational..])
                {
                    *out = e / w;
                }
            }
        }
        let refined = match rational {
            0 => Self::new(xi, eta, points)?,
            _ => Self::rational(xi, eta, points, weights)?,
        };
        Ok((refined, extra_out))
    }
}

/// Solves the tensor-product interpolation `A_ξ X A_ηᵀ = F` for control values
/// of dimension `dim` given at the Greville grid (`F` stored like the net).
pub fn interpolate_tensor(
    xi: &KnotVector,
    eta: &KnotVector,
    values: &[f64],
    dim: usize,
) -> Result<Vec<f64>, SurfaceError> {
    let (m, n) = (xi.basis_count(), eta.basis_count());
    let collocation = |kv: &KnotVector| {
        let g = kv.greville();
        let rows: Vec<Vec<f64>> = g.iter().map(|&u| kv.dense_basis(u)).collect();
        Mat::from_fn(g.len(), g.len(), |r, c| rows[r][c])
    };
    let (ax, ae) = (collocation(xi), collocation(eta));
    let (lx, le) = (ax.partial_piv_lu(), ae.partial_piv_lu());
    let mut out = vec![0.0; m * n * dim];
    for d in 0..dim {
        let f = Mat::from_fn(m, n, |i, j| values[(i * n + j) * dim + d]);
        let y = lx.solve(&f); // A_ξ⁻¹ F
        let xt = le.solve(y.transpose()); // A_η⁻¹ Yᵀ = Xᵀ
        for i in 0..m {
            for j in 0..n {
                let v = xt[(j, i)];
                if !v.is_finite() {
                    return Err(SurfaceError::SingularInterpolation);
                }
                out[(i * n + j) * dim + d] = v;
            }
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolation_reproduces_a_bilinear_map_and_its_derivatives() {
        let xi = KnotVector::uniform(4, 9, 0.0, 1.0).unwrap();
        let eta = KnotVector::uniform(3, 6, 0.0, 1.0).unwrap();
        let map = |u: f64, v: f64| [16.0 * u, 9.0 * v, 0.5 * u * v];
        let s = BSplineSurface::interpolate(xi, eta, map).unwrap();
        for &(u, v) in &[(0.0, 0.0), (0.31, 0.72), (1.0, 1.0), (0.5, 0.05)] {
            let e = s.evaluate(u, v);
            let r = map(u, v);
            for k in 0..3 {
                assert!((e.r[k] - r[k]).abs() < 1e-12);
            }
            assert!((e.r_xi[0] - 16.0).abs() < 1e-11 && (e.r_eta[1] - 9.0).abs() < 1e-11);
            assert!((e.r_xi[2] - 0.5 * v).abs() < 1e-11 && (e.r_eta[2] - 0.5 * u).abs() < 1e-11);
        }
    }

    #[test]
    fn locate_xy_inverts_the_map() {
        let xi = KnotVector::uniform(3, 6, 0.0, 1.0).unwrap();
        let eta = KnotVector::uniform(3, 5, 0.0, 1.0).unwrap();
        let s = BSplineSurface::interpolate(xi, eta, |u, v| [16.0 * u + 0.3 * v * v, 9.0 * v, u * v]).unwrap();
        for &(u, v) in &[(0.2, 0.7), (0.0, 0.0), (1.0, 0.35), (0.61, 1.0)] {
            let r = s.evaluate(u, v).r;
            let (u2, v2) = s.locate_xy(r[0], r[1]).unwrap();
            assert!(
                (u - u2).abs() < 1e-10 && (v - v2).abs() < 1e-10,
                "({u}, {v}) -> ({u2}, {v2})"
            );
        }
        assert_eq!(s.locate_xy(-5.0, 3.0), None);
    }

    #[test]
    fn closest_point_projects_onto_a_curved_surface_and_its_edges() {
        let xi = KnotVector::uniform(3, 6, 0.0, 1.0).unwrap();
        let eta = KnotVector::uniform(3, 5, 0.0, 1.0).unwrap();
        let s = BSplineSurface::interpolate(xi, eta, |u, v| [16.0 * u, 9.0 * v, 0.8 * (u * 3.0).sin()]).unwrap();
        for &(u, v) in &[(0.2, 0.7), (0.0, 0.0), (1.0, 0.35), (0.61, 1.0)] {
            let e = s.evaluate(u, v);
            // Off the surface along its normal: projects back onto (u, v).
            let n = crate::geometry::vec3::normalize(crate::geometry::vec3::cross(e.r_xi, e.r_eta)).unwrap();
            let (u2, v2, dist) = s.closest_point(axpy(e.r, 0.05, n));
            assert!(
                (u - u2).abs() < 1e-9 && (v - v2).abs() < 1e-9,
                "({u}, {v}) -> ({u2}, {v2})"
            );
            assert!((dist - 0.05).abs() < 1e-9, "{dist}");
        }
        // Beyond the η = 1 edge: onto the edge, at the distance from it.
        let edge = s.evaluate(0.5, 1.0).r;
        let (u, v, dist) = s.closest_point([edge[0], edge[1] + 2.0, edge[2]]);
        assert!((u - 0.5).abs() < 1e-9 && v == 1.0 && (dist - 2.0).abs() < 1e-9);
    }

    /// A quarter of a cylinder (radius 2, length 3) as the textbook NURBS:
    /// degree 2 over the arc with weights 1, √½, 1 (P&T Ex. 7.1), degree 1
    /// along the axis.
    fn quarter_cylinder() -> BSplineSurface {
        let xi = KnotVector::new(vec![0.0, 0.0, 0.0, 1.0, 1.0, 1.0], 2).unwrap();
        let eta = KnotVector::new(vec![0.0, 0.0, 1.0, 1.0], 1).unwrap();
        let arc = [[2.0, 0.0], [2.0, 2.0], [0.0, 2.0]];
        let w = [1.0, 0.5f64.sqrt(), 1.0];
        let points = arc.iter().flat_map(|&[x, y]| [[x, y, 0.0], [x, y, 3.0]]).collect();
        let weights = w.iter().flat_map(|&w| [w, w]).collect();
        BSplineSurface::rational(xi, eta, points, weights).unwrap()
    }

    #[test]
    fn a_nurbs_cylinder_is_exact_and_stays_so_under_knot_insertion() {
        let s = quarter_cylinder();
        let thickness: Vec<f64> = (0..6).map(|k| 0.1 + 0.01 * k as f64).collect();
        let (r1, t1) = s.insert_knot(Direction::Xi, 0.3, &thickness, 1).unwrap();
        let (r2, t2) = r1.insert_knot(Direction::Xi, 0.3, &t1, 1).unwrap();
        let (r3, t3) = r2.insert_knot(Direction::Eta, 0.6, &t2, 1).unwrap();
        assert_eq!(r3.net_size(), (5, 3));
        // The thickness field Σ R t as a surface of its own: kept as well.
        let field = |surface: &BSplineSurface, t: &[f64], u: f64, v: f64| {
            let pts = t.iter().map(|&t| [t, 0.0, 0.0]).collect();
            surface.with_points(pts).unwrap().evaluate(u, v).r[0]
        };
        for &(u, v) in &[(0.0, 0.0), (0.17, 0.4), (0.3, 0.6), (0.77, 0.93), (1.0, 1.0)] {
            for surface in [&s, &r3] {
                let e = surface.evaluate(u, v);
                assert!(((e.r[0].hypot(e.r[1])) - 2.0).abs() < 1e-14, "off the circle: {e:?}");
                assert!((e.r[2] - 3.0 * v).abs() < 1e-14);
                // The tangent is square to the radius and along the axis.
                assert!(dot(e.r_xi, [e.r[0], e.r[1], 0.0]).abs() < 1e-13);
                assert!((e.r_eta[2] - 3.0).abs() < 1e-13);
            }
            let (a, b) = (s.evaluate(u, v), r3.evaluate(u, v));
            for k in 0..3 {
                assert!((a.r[k] - b.r[k]).abs() < 1e-14 && (a.r_xi[k] - b.r_xi[k]).abs() < 1e-12);
            }
            assert!((field(&s, &thickness, u, v) - field(&r3, &t3, u, v)).abs() < 1e-15);
        }
        // The rational derivatives against central differences.
        let (u, v, h) = (0.41, 0.27, 1e-6);
        let e = r3.evaluate(u, v);
        let (xp, xm) = (r3.evaluate(u + h, v).r, r3.evaluate(u - h, v).r);
        let (ep, em) = (r3.evaluate(u, v + h).r, r3.evaluate(u, v - h).r);
        for k in 0..3 {
            assert!((e.r_xi[k] - (xp[k] - xm[k]) / (2.0 * h)).abs() < 1e-8);
            assert!((e.r_eta[k] - (ep[k] - em[k]) / (2.0 * h)).abs() < 1e-8);
        }
    }

    #[test]
    fn weights_are_checked_and_equal_ones_give_a_b_spline() {
        let s = quarter_cylinder();
        let (xi, eta, pts) = (s.xi().clone(), s.eta().clone(), s.points().to_vec());
        assert!(matches!(
            BSplineSurface::rational(xi.clone(), eta.clone(), pts.clone(), vec![1.0; 5]),
            Err(SurfaceError::WeightCount { found: 5, points: 6 })
        ));
        let mut bad = vec![1.0; 6];
        bad[3] = 0.0;
        assert!(matches!(
            BSplineSurface::rational(xi.clone(), eta.clone(), pts.clone(), bad),
            Err(SurfaceError::BadWeight { index: 3, .. })
        ));
        let equal = BSplineSurface::rational(xi.clone(), eta.clone(), pts.clone(), vec![2.5; 6]).unwrap();
        assert_eq!(equal, BSplineSurface::new(xi, eta, pts).unwrap());
        assert_eq!(equal.weights(), None);
    }

    #[test]
    fn knot_insertion_keeps_the_surface() {
        let xi = KnotVector::uniform(3, 5, 0.0, 1.0).unwrap();
        let eta = KnotVector::uniform(2, 4, 0.0, 1.0).unwrap();
        let s = BSplineSurface::interpolate(xi, eta, |u, v| [u, v, (3.0 * u).sin() * v * v]).unwrap();
        let thickness: Vec<f64> = (0..20).map(|k| 1.0 + 0.01 * k as f64).collect();
        let (r1, t1) = s.insert_knot(Direction::Xi, 0.37, &thickness, 1).unwrap();
        let (r2, _) = r1.insert_knot(Direction::Eta, 0.81, &t1, 1).unwrap();
        assert_eq!(r2.net_size(), (6, 5));
        for &(u, v) in &[(0.1, 0.2), (0.37, 0.81), (0.9, 0.99)] {
            let (a, b) = (s.evaluate(u, v), r2.evaluate(u, v));
            for k in 0..3 {
                assert!((a.r[k] - b.r[k]).abs() < 1e-13);
                assert!((a.r_xi[k] - b.r_xi[k]).abs() < 1e-12);
            }
        }
        assert!(matches!(
            BSplineSurface::new(s.xi().clone(), s.eta().clone(), vec![[0.0; 3]; 3]),
            Err(SurfaceError::ControlPointCount { found: 3, m: 5, n: 4 })
        ));
    }
}
