//! Mode-shape metrics for identified (complex) shapes.

use faer::c64;

/// Modal assurance criterion `|φ₁ᴴ φ₂|² / ((φ₁ᴴ φ₁)(φ₂ᴴ φ₂))` (Allemang &
/// Brown 1982), in `[0, 1]`; 0 when either shape is zero.
pub fn mac(a: &[c64], b: &[c64]) -> f64 {
    let cross: c64 = a.iter().zip(b).map(|(x, y)| x.conj() * y).sum();
    let na: f64 = a.iter().map(|x| x.norm_sqr()).sum();
    let nb: f64 = b.iter().map(|x| x.norm_sqr()).sum();
    if na == 0.0 || nb == 0.0 {
        return 0.0;
    }
    cross.norm_sqr() / (na * nb)
}

/// MAC between a complex shape and a real one.
pub fn mac_real(a: &[c64], b: &[f64]) -> f64 {
    let b: Vec<c64> = b.iter().map(|&v| c64::new(v, 0.0)).collect();
    mac(a, &b)
}

/// Modal phase collinearity (Pappa, Elliott & Schenk 1993):
/// `((λ₁ − λ₂)/(λ₁ + λ₂))²` with `λ₁,₂` the eigenvalues of the 2 × 2 scatter
/// matrix of (Re φ, Im φ). 1 for a real (normal) mode up to a complex
/// factor, near 0 for noise.
pub fn mpc(phi: &[c64]) -> f64 {
    let sxx: f64 = phi.iter().map(|v| v.re * v.re).sum();
    let syy: f64 = phi.iter().map(|v| v.im * v.im).sum();
    let sxy: f64 = phi.iter().map(|v| v.re * v.im).sum();
    let total = sxx + syy;
    if total == 0.0 {
        return 0.0;
    }
    let spread = 2.0 * (0.25 * (sxx - syy).powi(2) + sxy * sxy).sqrt();
    (spread / total).powi(2)
}

/// Scales `phi` so its largest-modulus component is `1 + 0i` (exactly: the
/// product with the reciprocal leaves it within rounding of that).
pub fn normalise(phi: &mut [c64]) {
    let Some((index, largest)) = phi
        .iter()
        .copied()
        .enumerate()
        .max_by(|a, b| a.1.norm().total_cmp(&b.1.norm()))
    else {
        return;
    };
    if largest.norm() == 0.0 {
        return;
    }
    let inverse = c64::new(1.0, 0.0) / largest;
    phi.iter_mut().for_each(|v| *v *= inverse);
    phi[index] = c64::new(1.0, 0.0);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mac_is_one_for_scaled_shapes_and_zero_for_orthogonal() {
        let a = [c64::new(1.0, 0.0), c64::new(-2.0, 0.0), c64::new(0.5, 0.0)];
        let scaled: Vec<c64> = a.iter().map(|v| v * c64::new(0.3, -1.2)).collect();
        assert!((mac(&a, &scaled) - 1.0).abs() < 1e-14);
        let b = [c64::new(2.0, 0.0), c64::new(1.0, 0.0), c64::new(0.0, 0.0)];
        assert!(mac(&a, &b).abs() < 1e-14);
        assert!((mac_real(&scaled, &[1.0, -2.0, 0.5]) - 1.0).abs() < 1e-14);
    }

    #[test]
    fn mpc_of_a_rotated_real_shape_is_one_and_of_a_circle_zero() {
        let rotated: Vec<c64> = [1.0, -0.4, 2.0]
            .iter()
            .map(|&v| c64::new(v, 0.0) * c64::new(0.6, 0.8))
            .collect();
        assert!((mpc(&rotated) - 1.0).abs() < 1e-14);
        let circle = [
            c64::new(1.0, 0.0),
            c64::new(0.0, 1.0),
            c64::new(-1.0, 0.0),
            c64::new(0.0, -1.0),
        ];
        assert!(mpc(&circle).abs() < 1e-14);
    }

    #[test]
    fn normalise_makes_the_largest_component_one() {
        let mut phi = vec![c64::new(0.1, 0.2), c64::new(-3.0, 4.0), c64::new(1.0, 0.0)];
        normalise(&mut phi);
        assert_eq!(phi[1], c64::new(1.0, 0.0));
        assert!(phi.iter().all(|v| v.norm() <= 1.0 + 1e-15));
        // A component whose reciprocal's product rounds off 1 is 1 all the same.
        let odd = c64::new(0.11585926857179238, 0.23051628235920657) * 3.7;
        let mut phi = vec![odd, c64::new(0.1, 0.0)];
        normalise(&mut phi);
        assert_eq!(phi[0], c64::new(1.0, 0.0));
    }
}
