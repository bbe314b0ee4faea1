//! A straight section segment swept along a centreline: decks curved in
//! plan or in elevation, their webs and slabs.
//!
//! The centreline `c(s)`, `s ∈ [0, 1]`, interpolates the given points by a
//! B-spline (chord-length parameters, knots by averaging: Piegl & Tiller,
//! The NURBS Book, eq. 9.5 and 9.8). The surface is
//! `r(ξ, η) = c(ξ) + a(η) l(ξ) + b(η) e_z`, with `l = e_z × t / |e_z × t|`
//! the horizontal lateral axis square to the tangent `t = c'` in plan (to
//! the left of the direction of travel) and `(a, b)` running linearly from
//! the section's first point to its second.

use crate::geometry::knots::{KnotError, KnotVector, MAX_DEGREE};
use crate::geometry::surface::{BSplineSurface, SurfaceError};
use crate::geometry::vec3::{axpy, norm, sub, Vec3};
use faer::prelude::Solve;
use faer::Mat;
use thiserror::Error;

#[derive(Debug, Clone, PartialEq, Error)]
pub enum SweptError {
    #[error("a centreline needs at least two distinct points, got {0}")]
    TooFewPoints(usize),
    #[error("centreline point {0} coincides with the next one")]
    RepeatedPoint(usize),
    #[error("the centreline is vertical at s = {0}: no lateral axis in plan")]
    Vertical(f64),
    #[error("the centreline's interpolation is singular")]
    Singular,
    #[error("{0}")]
    Knot(#[from] KnotError),
    #[error("{0}")]
    Surface(#[from] SurfaceError),
}

/// A B-spline curve through points.
#[derive(Debug, Clone)]
pub struct Centreline {
    knots: KnotVector,
    points: Vec<Vec3>,
}

impl Centreline {
    /// The curve of degree `min(degree, k − 1)` through the `k` points.
    pub fn interpolate(points: &[Vec3], degree: usize) -> Result<Self, SweptError> {
        let k = points.len();
        if k < 2 {
            return Err(SweptError::TooFewPoints(k));
        }
        let chords: Vec<f64> = points.windows(2).map(|w| norm(sub(w[1], w[0]))).collect();
        if let Some(i) = chords.iter().position(|&c| c.is_nan() || c <= 0.0) {
            return Err(SweptError::RepeatedPoint(i));
        }
        let total: f64 = chords.iter().sum();
        let mut params = vec![0.0; k];
        for i in 1..k {
            params[i] = params[i - 1] + chords[i - 1] / total;
        }
        params[k - 1] = 1.0;
        let p = degree.min(k - 1).min(MAX_DEGREE);
        let mut knots = vec![0.0; p + 1];
        for j in 1..k - p {
            knots.push(params[j..j + p].iter().sum::<f64>() / p as f64);
        }
        knots.extend(std::iter::repeat_n(1.0, p + 1));
        let knots = KnotVector::new(knots, p)?;
        let a = Mat::from_fn(k, k, |r, c| knots.dense_basis(params[r])[c]);
        let rhs = Mat::from_fn(k, 3, |r, d| points[r][d]);
        let solved = a.partial_piv_lu().solve(&rhs);
        let control: Vec<Vec3> = (0..k)
            .map(|r| [solved[(r, 0)], solved[(r, 1)], solved[(r, 2)]])
            .collect();
        if control.iter().flatten().any(|v| !v.is_finite()) {
            return Err(SweptError::Singular);
        }
        Ok(Self { knots, points: control })
    }

    /// `(c(s), c'(s))`.
    pub fn evaluate(&self, s: f64) -> (Vec3, Vec3) {
        let p = self.knots.degree();
        let span = self.knots.span(s);
        let (mut b, mut db) = ([0.0; MAX_DEGREE + 1], [0.0; MAX_DEGREE + 1]);
        self.knots.basis_with_derivatives(span, s, &mut b, &mut db);
        let (mut c, mut t) = ([0.0; 3], [0.0; 3]);
        for r in 0..=p {
            let q = self.points[span - p + r];
            c = axpy(c, b[r], q);
            t = axpy(t, db[r], q);
        }
        (c, t)
    }
}

/// The swept surface on the analysis net `xi` × `eta`, interpolating the
/// exact map at its Greville abscissae (converging like `h^(p+1)`).
pub fn swept_surface(
    centreline: &Centreline,
    section: [[f64; 2]; 2],
    xi: KnotVector,
    eta: KnotVector,
) -> Result<BSplineSurface, SweptError> {
    for s in xi.greville() {
        let (_, t) = centreline.evaluate(s);
        if t[0].hypot(t[1]) <= 1e-12 * norm(t) {
            return Err(SweptError::Vertical(s));
        }
    }
    let [[a0, b0], [a1, b1]] = section;
    Ok(BSplineSurface::interpolate(xi, eta, |u, v| {
        let (c, t) = centreline.evaluate(u);
        let h = t[0].hypot(t[1]);
        let lateral = [-t[1] / h, t[0] / h, 0.0];
        let (a, b) = (a0 + v * (a1 - a0), b0 + v * (b1 - b0));
        axpy(axpy(c, a, lateral), b, [0.0, 0.0, 1.0])
    })?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_swept_web_follows_a_circular_centreline() {
        // Nine points on a 30° arc of radius 60 m: the interpolated curve
        // stays within 1e-5 m of the circle, and a web 1.5 m below the
        // centreline's left offset of 2 m is at radius 58 m.
        let (radius, angle) = (60.0, 30f64.to_radians());
        let points: Vec<Vec3> = (0..9)
            .map(|i| {
                let phi = angle * i as f64 / 8.0;
                [radius * phi.sin(), radius * (1.0 - phi.cos()), 0.0]
            })
            .collect();
        let curve = Centreline::interpolate(&points, 3).unwrap();
        let xi = KnotVector::uniform(3, 12, 0.0, 1.0).unwrap();
        let eta = KnotVector::uniform(1, 2, 0.0, 1.0).unwrap();
        let web = swept_surface(&curve, [[2.0, 0.0], [2.0, -1.5]], xi, eta).unwrap();
        for &(u, v) in &[(0.0, 0.0), (0.37, 0.5), (0.81, 1.0), (1.0, 0.2)] {
            let r = web.evaluate(u, v).r;
            let from_centre = (r[0].powi(2) + (r[1] - radius).powi(2)).sqrt();
            assert!((from_centre - (radius - 2.0)).abs() < 1e-4, "{from_centre}");
            assert!((r[2] + 1.5 * v).abs() < 1e-12);
        }
        assert!(matches!(
            Centreline::interpolate(&[[0.0; 3], [0.0; 3]], 3),
            Err(SweptError::RepeatedPoint(0))
        ));
        assert!(matches!(
            Centreline::interpolate(&[[0.0; 3]], 3),
            Err(SweptError::TooFewPoints(1))
        ));
    }
}
