//! Clamped (open) knot vectors and the B-spline basis defined on them.
//!
//! A knot vector of degree `p` carrying `n` basis functions is
//! `U = {a,…,a, u_{p+1},…,u_{n-1}, b,…,b}` with `a` and `b` repeated exactly
//! `p + 1` times (paper eq. 1), non-decreasing, and interior multiplicities
//! at most `p` (at most 1 for degree 0), so the basis is C⁰ or smoother
//! inside `[a, b]`.
//!
//! Basis values follow Piegl & Tiller, *The NURBS Book*, 2nd ed.:
//! `span` is Algorithm A2.1 (p. 68), `basis` is A2.2 (p. 70) and the first
//! derivatives use eq. (2.7): `N'_{i,p} = p/(u_{i+p}-u_i) N_{i,p-1}
//! - p/(u_{i+p+1}-u_{i+1}) N_{i+1,p-1}`.

use thiserror::Error;

/// Largest degree supported by the fixed-size scratch buffers.
pub const MAX_DEGREE: usize = 10;

/// Why a knot vector was rejected.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum KnotError {
    #[error("degree {degree} exceeds the supported maximum {MAX_DEGREE}")]
    DegreeTooHigh { degree: usize },
    #[error("{len} knots cannot carry degree {degree}: at least {min} are needed")]
    TooShort { len: usize, degree: usize, min: usize },
    #[error("knot at index {index} is not finite")]
    NotFinite { index: usize },
    #[error("not non-decreasing at index {index}")]
    Decreasing { index: usize },
    #[error("first and last knot are equal: the parametric domain is empty")]
    EmptyDomain,
    #[error(
        "not clamped at the {end} end: the end knot must appear exactly {expected} times (degree + 1), found {found}"
    )]
    NotClamped {
        end: &'static str,
        expected: usize,
        found: usize,
    },
    #[error("interior knot {value} has multiplicity {multiplicity}, more than the allowed {allowed}")]
    InteriorMultiplicity {
        value: f64,
        multiplicity: usize,
        allowed: usize,
    },
    #[error("{count} basis functions requested for degree {degree}: at least {min} are needed")]
    TooFewBasisFunctions { count: usize, degree: usize, min: usize },
    #[error("domain [{start}, {end}] is not a finite, non-empty interval")]
    BadDomain { start: f64, end: f64 },
}

/// A validated clamped knot vector with its degree.
#[derive(Debug, Clone, PartialEq)]
pub struct KnotVector {
    knots: Vec<f64>,
    degree: usize,
}

impl KnotVector {
    /// Validates `knots` as a clamped knot vector of degree `degree`.
    pub fn new(knots: Vec<f64>, degree: usize) -> Result<Self, KnotError> {
        if degree > MAX_DEGREE {
            return Err(KnotError::DegreeTooHigh { degree });
        }
        let min = 2 * (degree + 1);
        if knots.len() < min {
            return Err(KnotError::TooShort {
                len: knots.len(),
                degree,
                min,
            });
        }
        if let Some(index) = knots.iter().position(|k| !k.is_finite()) {
            return Err(KnotError::NotFinite { index });
        }
        if let Some(index) = (1..knots.len()).find(|&i| knots[i] < knots[i - 1]) {
            return Err(KnotError::Decreasing { index });
        }
        let (first, last) = (knots[0], knots[knots.len() - 1]);
        if first == last {
            return Err(KnotError::EmptyDomain);
        }
        let start_mult = knots.iter().take_while(|&&k| k == first).count();
        let end_mult = knots.iter().rev().take_while(|&&k| k == last).count();
        for (end, found) in [("start", start_mult), ("end", end_mult)] {
            if found != degree + 1 {
                return Err(KnotError::NotClamped {
                    end,
                    expected: degree + 1,
                    found,
                });
            }
        }
        let allowed = degree.max(1);
        let interior = &knots[start_mult..knots.len() - end_mult];
        let mut i = 0;
        while i < interior.len() {
            let value = interior[i];
            let multiplicity = interior[i..].iter().take_while(|&&k| k == value).count();
            if multiplicity > allowed {
                return Err(KnotError::InteriorMultiplicity {
                    value,
                    multiplicity,
                    allowed,
                });
            }
            i += multiplicity;
        }
        Ok(Self { knots, degree })
    }

    /// Clamped knot vector with uniformly spaced interior knots on `[start, end]`
    /// carrying `count` basis functions of degree `degree`.
    pub fn uniform(degree: usize, count: usize, start: f64, end: f64) -> Result<Self, KnotError> {
        if !(start.is_finite() && end.is_finite() && start < end) {
            return Err(KnotError::BadDomain { start, end });
        }
        if count < degree + 1 {
            return Err(KnotError::TooFewBasisFunctions {
                count,
                degree,
                min: degree + 1,
            });
        }
        let spans = count - degree;
        let mut knots = vec![start; degree + 1];
        knots.extend((1..spans).map(|k| start + (end - start) * k as f64 / spans as f64));
        knots.extend(std::iter::repeat_n(end, degree + 1));
        Self::new(knots, degree)
    }

    pub fn degree(&self) -> usize {
        self.degree
    }

    pub fn knots(&self) -> &[f64] {
        &self.knots
    }

    /// Number of basis functions `n = len - p - 1`.
    pub fn basis_count(&self) -> usize {
        self.knots.len() - self.degree - 1
    }

    /// The parametric interval `[a, b]`.
    pub fn domain(&self) -> (f64, f64) {
        (self.knots[0], self.knots[self.knots.len() - 1])
    }

    /// Distinct knot values, ascending: the breakpoints between polynomial pieces.
    pub fn breakpoints(&self) -> Vec<f64> {
        let mut out: Vec<f64> = Vec::new();
        for &k in &self.knots {
            if out.last() != Some(&k) {
                out.push(k);
            }
        }
        out
    }

    /// Greville abscissae `g_i = (u_{i+1} + … + u_{i+p}) / p` (the interval
    /// midpoint for degree 0). Interpolating at them reproduces linear maps.
    pub fn greville(&self) -> Vec<f64> {
        let p = self.degree;
        (0..self.basis_count())
            .map(|i| {
                if p == 0 {
                    0.5 * (self.knots[i] + self.knots[i + 1])
                } else {
                    self.knots[i + 1..=i + p].iter().sum::<f64>() / p as f64
                }
            })
            .collect()
    }

    /// Algorithm A2.1: index `s` with `u_s <= u < u_{s+1}` and `p <= s < n`;
    /// `u` is clamped to the domain and `u = b` falls into the last span.
    pub fn span(&self, u: f64) -> usize {
        let n = self.basis_count();
        let (a, b) = self.domain();
        let u = u.clamp(a, b);
        if u >= self.knots[n] {
            return n - 1;
        }
        // Last index in [p, n) whose knot is <= u.
        let p = self.degree;
        p + self.knots[p + 1..=n].partition_point(|&k| k <= u)
    }

    /// Algorithm A2.2: the `p + 1` non-zero basis values at `u` in span `span`,
    /// written to `values[..=p]`; they belong to functions `span - p ..= span`.
    #[track_caller]
    pub fn basis(&self, span: usize, u: f64, values: &mut [f64]) {
        self.basis_of_degree(self.degree, span, u, values);
    }

    fn basis_of_degree(&self, degree: usize, span: usize, u: f64, values: &mut [f64]) {
        assert!(values.len() > degree, "basis buffer shorter than degree + 1");
        let u = u.clamp(self.domain().0, self.domain().1);
        let mut left = [0.0; MAX_DEGREE + 1];
        let mut right = [0.0; MAX_DEGREE + 1];
        values[0] = 1.0;
        for j in 1..=degree {
            left[j] = u - self.knots[span + 1 - j];
            right[j] = self.knots[span + j] - u;
            let mut saved = 0.0;
            for r in 0..j {
                let denom = right[r + 1] + left[j - r];
                let temp = if denom == 0.0 { 0.0 } else { values[r] / denom };
                values[r] = saved + right[r + 1] * temp;
                saved = left[j - r] * temp;
            }
            values[j] = saved;
        }
    }

    /// Basis values and first derivatives at `u` in span `span` (eq. 2.7 of
    /// Piegl & Tiller), written to `values[..=p]` and `derivatives[..=p]`.
    #[track_caller]
    pub fn basis_with_derivatives(&self, span: usize, u: f64, values: &mut [f64], derivatives: &mut [f64]) {
        let p = self.degree;
        assert!(derivatives.len() > p, "derivative buffer shorter than degree + 1");
        if p == 0 {
            self.basis(span, u, values);
            derivatives[0] = 0.0;
            return;
        }
        let mut lower = [0.0; MAX_DEGREE + 1];
        self.basis_of_degree(p - 1, span, u, &mut lower);
        let pf = p as f64;
        for r in 0..=p {
            let i = span - p + r;
            let mut d = 0.0;
            if r >= 1 {
                let denom = self.knots[i + p] - self.knots[i];
                if denom > 0.0 {
                    d += pf * lower[r - 1] / denom;
                }
            }
            if r < p {
                let denom = self.knots[i + p + 1] - self.knots[i + 1];
                if denom > 0.0 {
                    d -= pf * lower[r] / denom;
                }
            }
            derivatives[r] = d;
        }
        self.basis(span, u, values);
    }

    /// Value of every basis function at `u` (dense, length `n`); convenient
    /// for small systems such as interpolation matrices.
    pub fn dense_basis(&self, u: f64) -> Vec<f64> {
        let mut out = vec![0.0; self.basis_count()];
        let span = self.span(u);
        let mut values = [0.0; MAX_DEGREE + 1];
        self.basis(span, u, &mut values);
        for r in 0..=self.degree {
            out[span - self.degree + r] = values[r];
        }
        out
    }

    /// The non-zero tensor-product basis values `B_i(u) B_j(v)` of `self` ×
    /// `eta` at `(u, v)` as `(i·n_η + j, value)` (η fastest), into `out`
    /// (cleared first).
    pub fn tensor_basis_into(&self, eta: &KnotVector, u: f64, v: f64, out: &mut Vec<(usize, f64)>) {
        let (si, sj) = (self.span(u), eta.span(v));
        let (mut bx, mut be) = ([0.0; MAX_DEGREE + 1], [0.0; MAX_DEGREE + 1]);
        self.basis(si, u, &mut bx);
        eta.basis(sj, v, &mut be);
        let ne = eta.basis_count();
        out.clear();
        for a in 0..=self.degree {
            for b in 0..=eta.degree {
                let w = bx[a] * be[b];
                if w != 0.0 {
                    out.push(((si - self.degree + a) * ne + (sj - eta.degree + b), w));
                }
            }
        }
    }

    /// Whether `u` lies in the closed domain `[a, b]`.
    pub fn contains(&self, u: f64) -> bool {
        let (a, b) = self.domain();
        u >= a && u <= b
    }

    /// Knot insertion (Boehm; Piegl & Tiller Algorithm A5.1, p. 151) of the
    /// value `u` once: returns the refined knot vector and, for control values
    /// of dimension `dim` stored contiguously per basis function, the new
    /// control values. The represented function is unchanged.
    pub fn insert_knot(&self, u: f64, values: &[f64], dim: usize) -> Result<(Self, Vec<f64>), KnotError> {
        let p = self.degree;
        let n = self.basis_count();
        assert_eq!(values.len(), n * dim, "control values do not match the basis count");
        let (a, b) = self.domain();
        if !(u > a && u < b) {
            return Err(KnotError::BadDomain { start: u, end: u });
        }
        let k = self.span(u);
        let mut knots = self.knots.clone();
        knots.insert(k + 1, u);
        let refined = Self::new(knots, p)?;
        let mut out = vec![0.0; (n + 1) * dim];
        for i in 0..=n {
            let alpha = if i + p <= k {
                1.0
            } else if i > k {
                0.0
            } else {
                (u - self.knots[i]) / (self.knots[i + p] - self.knots[i])
            };
            for d in 0..dim {
                let here = if i < n { values[i * dim + d] } else { 0.0 };
                let before = if i > 0 { values[(i - 1) * dim + d] } else { 0.0 };
                out[i * dim + d] = alpha * here + (1.0 - alpha) * before;
            }
        }
        Ok((refined, out))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn binomial(n: usize, k: usize) -> f64 {
        (0..k).fold(1.0, |acc, i| acc * (n - i) as f64 / (i + 1) as f64)
    }

    #[test]
    fn rejects_bad_vectors_with_reasons() {
        assert_eq!(
            KnotVector::new(vec![0.0, 0.0, 1.0, 0.5, 1.0, 1.0], 1),
            Err(KnotError::Decreasing { index: 3 })
        );
        assert!(matches!(
            KnotVector::new(vec![0.0, 0.0, 0.5, 1.0, 1.0, 1.0], 2),
            Err(KnotError::NotClamped { end: "start", .. })
        ));
        assert!(matches!(
            KnotVector::new(vec![0.0, 0.0, 0.5, 0.5, 0.5, 1.0, 1.0], 1),
            Err(KnotError::InteriorMultiplicity { multiplicity: 3, .. })
        ));
        assert_eq!(
            KnotVector::new(vec![0.0, 1.0], 1),
            Err(KnotError::TooShort {
                len: 2,
                degree: 1,
                min: 4
            })
        );
        assert_eq!(
            KnotVector::new(vec![0.0, f64::NAN], 0),
            Err(KnotError::NotFinite { index: 1 })
        );
        assert_eq!(KnotVector::new(vec![1.0, 1.0], 0), Err(KnotError::EmptyDomain));
    }

    #[test]
    fn paper_spring_knot_vectors_are_valid() {
        let u = KnotVector::new(vec![0.0, 0.03], 0).unwrap();
        assert_eq!(u.basis_count(), 1);
        let v = KnotVector::new(vec![0.0, 0.0, 0.0, 0.5, 1.0, 1.0, 1.0], 2).unwrap();
        assert_eq!(v.basis_count(), 4);
    }

    #[test]
    fn single_span_basis_is_bernstein() {
        // On {0^(p+1), 1^(p+1)} the B-splines are the Bernstein polynomials.
        for p in 0..=6 {
            let kv = KnotVector::uniform(p, p + 1, 0.0, 1.0).unwrap();
            for &u in &[0.0, 0.13, 0.5, 0.77, 1.0] {
                let span = kv.span(u);
                let mut n = [0.0; MAX_DEGREE + 1];
                let mut dn = [0.0; MAX_DEGREE + 1];
                kv.basis_with_derivatives(span, u, &mut n, &mut dn);
                for i in 0..=p {
                    let b = binomial(p, i) * u.powi(i as i32) * (1.0 - u).powi((p - i) as i32);
                    assert!((n[i] - b).abs() < 1e-14, "p={p} i={i} u={u}");
                    let db = if p == 0 {
                        0.0
                    } else {
                        let lower = |k: isize| -> f64 {
                            if k < 0 || k as usize > p - 1 {
                                0.0
                            } else {
                                let k = k as usize;
                                binomial(p - 1, k) * u.powi(k as i32) * (1.0 - u).powi((p - 1 - k) as i32)
                            }
                        };
                        p as f64 * (lower(i as isize - 1) - lower(i as isize))
                    };
                    assert!((dn[i] - db).abs() < 1e-12, "derivative p={p} i={i} u={u}");
                }
            }
        }
    }

    #[test]
    fn greville_of_uniform_cubic() {
        let kv = KnotVector::uniform(3, 5, 0.0, 1.0).unwrap();
        let g = kv.greville();
        let expected = [0.0, 1.0 / 6.0, 0.5, 5.0 / 6.0, 1.0];
        for (a, b) in g.iter().zip(expected) {
            assert!((a - b).abs() < 1e-15);
        }
    }

    #[test]
    fn degree_zero_covers_right_end() {
        let kv = KnotVector::new(vec![0.97, 1.0], 0).unwrap();
        assert_eq!(kv.dense_basis(1.0), vec![1.0]);
        assert_eq!(kv.dense_basis(0.97), vec![1.0]);
    }

    #[test]
    fn knot_insertion_preserves_function() {
        let kv = KnotVector::new(vec![0.0, 0.0, 0.0, 0.0, 0.3, 0.6, 1.0, 1.0, 1.0, 1.0], 3).unwrap();
        let coeffs: Vec<f64> = (0..kv.basis_count()).map(|i| (i as f64 * 1.7).sin()).collect();
        let (refined, new) = kv.insert_knot(0.45, &coeffs, 1).unwrap();
        assert_eq!(refined.basis_count(), kv.basis_count() + 1);
        for k in 0..=50 {
            let u = k as f64 / 50.0;
            let f0: f64 = kv.dense_basis(u).iter().zip(&coeffs).map(|(b, c)| b * c).sum();
            let f1: f64 = refined.dense_basis(u).iter().zip(&new).map(|(b, c)| b * c).sum();
            assert!((f0 - f1).abs() < 1e-14, "u={u}");
        }
    }

    fn arbitrary_knots() -> impl Strategy<Value = KnotVector> {
        (0usize..=5, prop::collection::vec(0.01f64..1.0, 0..8)).prop_map(|(p, gaps)| {
            let mut interior = Vec::new();
            let mut acc = 0.0;
            for g in &gaps {
                acc += g;
                interior.push(acc);
            }
            let end = acc + 0.5;
            let mut knots = vec![0.0; p + 1];
            knots.extend(interior);
            knots.extend(std::iter::repeat_n(end, p + 1));
            KnotVector::new(knots, p).unwrap()
        })
    }

    proptest! {
        #[test]
        fn partition_of_unity_and_non_negativity(kv in arbitrary_knots(), t in 0.0f64..=1.0) {
            let (a, b) = kv.domain();
            let u = a + t * (b - a);
            let span = kv.span(u);
            let mut n = [0.0; MAX_DEGREE + 1];
            let mut dn = [0.0; MAX_DEGREE + 1];
            kv.basis_with_derivatives(span, u, &mut n, &mut dn);
            let p = kv.degree();
            let sum: f64 = n[..=p].iter().sum();
            prop_assert!((sum - 1.0).abs() < 1e-13);
            prop_assert!(n[..=p].iter().all(|&v| v >= -1e-15));
            // Derivatives of a partition of unity sum to zero.
            let dsum: f64 = dn[..=p].iter().sum();
            let scale: f64 = dn[..=p].iter().map(|d| d.abs()).sum::<f64>().max(1.0);
            prop_assert!(dsum.abs() < 1e-11 * scale);
        }

        #[test]
        fn derivative_matches_central_difference(kv in arbitrary_knots(), t in 0.02f64..0.98) {
            let (a, b) = kv.domain();
            let u = a + t * (b - a);
            // Stay clear of breakpoints, where the derivative may jump.
            let bp = kv.breakpoints();
            let h = 1e-6 * (b - a);
            prop_assume!(bp.iter().all(|k| (k - u).abs() > 100.0 * h));
            let span = kv.span(u);
            let mut n = [0.0; MAX_DEGREE + 1];
            let mut dn = [0.0; MAX_DEGREE + 1];
            kv.basis_with_derivatives(span, u, &mut n, &mut dn);
            let plus = kv.dense_basis(u + h);
            let minus = kv.dense_basis(u - h);
            let p = kv.degree();
            let scale: f64 = dn[..=p].iter().map(|d| d.abs()).fold(1.0, f64::max);
            for r in 0..=p {
                let i = span - p + r;
                let fd = (plus[i] - minus[i]) / (2.0 * h);
                // Central difference error O(h² f''') plus round-off O(eps/h).
                prop_assert!((fd - dn[r]).abs() < 1e-5 * scale, "r={} fd={} an={}", r, fd, dn[r]);
            }
        }
    }
}
