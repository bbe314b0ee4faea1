//! Gauss–Legendre quadrature: `n` points integrate polynomials of degree
//! `2n - 1` exactly. Nodes are the roots of `P_n`, found by Newton's method
//! from the Tricomi initial guess `cos(π (i - 1/4) / (n + 1/2))`; weights are
//! `2 / ((1 - x²) P'_n(x)²)` (Abramowitz & Stegun 25.4.29).

/// Nodes and weights on the reference interval `[-1, 1]`.
#[derive(Debug, Clone, PartialEq)]
pub struct GaussLegendre {
    nodes: Vec<f64>,
    weights: Vec<f64>,
}

impl GaussLegendre {
    /// The `n`-point rule, `n >= 1`. Nodes ascend.
    #[track_caller]
    pub fn new(n: usize) -> Self {
        assert!(n >= 1, "a Gauss rule needs at least one point");
        let mut nodes = vec![0.0; n];
        let mut weights = vec![0.0; n];
        for i in 0..n.div_ceil(2) {
            let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
            let mut dp = 0.0;
            for _ in 0..100 {
                let (p, d) = legendre_with_derivative(n, x);
                dp = d;
                let dx = p / d;
                x -= dx;
                if dx.abs() < 1e-16 {
                    break;
                }
            }
            let (_, d) = legendre_with_derivative(n, x);
            dp = if d != 0.0 { d } else { dp };
            let w = 2.0 / ((1.0 - x * x) * dp * dp);
            nodes[i] = -x;
            nodes[n - 1 - i] = x;
            weights[i] = w;
            weights[n - 1 - i] = w;
        }
        if n % 2 == 1 {
            nodes[n / 2] = 0.0;
        }
        Self { nodes, weights }
    }

    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Points and weights mapped to `[a, b]`.
    pub fn mapped(&self, a: f64, b: f64) -> impl Iterator<Item = (f64, f64)> + '_ {
        let half = 0.5 * (b - a);
        let mid = 0.5 * (a + b);
        self.nodes
            .iter()
            .zip(&self.weights)
            .map(move |(x, w)| (mid + half * x, half * w))
    }
}

/// `P_n(x)` and `P'_n(x)` by the three-term recurrence.
fn legendre_with_derivative(n: usize, x: f64) -> (f64, f64) {
    let (mut p0, mut p1) = (1.0, x);
    for k in 2..=n {
        let k = k as f64;
        let p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
    }
    if n == 0 {
        return (1.0, 0.0);
    }
    let d = n as f64 * (x * p1 - p0) / (x * x - 1.0);
    (p1, d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_three_point_rule() {
        let g = GaussLegendre::new(3);
        let r = (0.6f64).sqrt();
        let expected = [(-r, 5.0 / 9.0), (0.0, 8.0 / 9.0), (r, 5.0 / 9.0)];
        for ((x, w), (ex, ew)) in g.mapped(-1.0, 1.0).zip(expected) {
            assert!((x - ex).abs() < 1e-15 && (w - ew).abs() < 1e-15);
        }
    }

    #[test]
    fn integrates_monomials_exactly_up_to_degree_2n_minus_1() {
        for n in 1..=12 {
            let g = GaussLegendre::new(n);
            for k in 0..2 * n {
                let exact = (2.0f64.powi(k as i32 + 1) - 0.0) / (k as f64 + 1.0);
                let approx: f64 = g.mapped(0.0, 2.0).map(|(x, w)| w * x.powi(k as i32)).sum();
                assert!((approx - exact).abs() < 1e-13 * exact.max(1.0), "n={n} k={k}");
            }
        }
    }
}
