//! Small fixed-size vector helpers for 3-D geometry.

pub type Vec3 = [f64; 3];

pub fn dot(a: Vec3, b: Vec3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

pub fn cross(a: Vec3, b: Vec3) -> Vec3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

pub fn norm(a: Vec3) -> f64 {
    dot(a, a).sqrt()
}

pub fn scale(a: Vec3, s: f64) -> Vec3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

pub fn add(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

pub fn sub(a: Vec3, b: Vec3) -> Vec3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// `a + s b`.
pub fn axpy(a: Vec3, s: f64, b: Vec3) -> Vec3 {
    [a[0] + s * b[0], a[1] + s * b[1], a[2] + s * b[2]]
}

/// Unit vector along `a`, or `None` if `a` is (numerically) zero or not finite.
/// Whether the rows `axes` are orthonormal (to 1e-9) and right-handed: a
/// local frame a support's or a bearing's springs act along.
pub fn is_right_handed_frame(axes: &[Vec3; 3]) -> bool {
    let orthonormal = (0..3).all(|i| (0..3).all(|j| (dot(axes[i], axes[j]) - f64::from(i == j)).abs() < 1e-9));
    orthonormal && dot(cross(axes[0], axes[1]), axes[2]) >= 0.0
}

pub fn normalize(a: Vec3) -> Option<Vec3> {
    let n = norm(a);
    (n.is_finite() && n > 1e-300).then(|| scale(a, 1.0 / n))
}

/// `M v` for a 3×3 matrix stored by rows.
pub fn mat_vec(m: &[Vec3; 3], v: Vec3) -> Vec3 {
    [dot(m[0], v), dot(m[1], v), dot(m[2], v)]
}

/// Determinant and inverse of a 3×3 matrix stored by rows.
pub fn det_inverse(m: &[Vec3; 3]) -> (f64, [Vec3; 3]) {
    let c0 = cross(m[1], m[2]);
    let c1 = cross(m[2], m[0]);
    let c2 = cross(m[0], m[1]);
    let det = dot(m[0], c0);
    let inv_det = 1.0 / det;
    // Columns of the inverse are the cofactor rows divided by det.
    let inv = [
        [c0[0] * inv_det, c1[0] * inv_det, c2[0] * inv_det],
        [c0[1] * inv_det, c1[1] * inv_det, c2[1] * inv_det],
        [c0[2] * inv_det, c1[2] * inv_det, c2[2] * inv_det],
    ];
    (det, inv)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_times_matrix_is_identity() {
        let m = [[2.0, 0.3, -1.0], [0.1, 1.5, 0.2], [0.4, -0.7, 3.0]];
        let (det, inv) = det_inverse(&m);
        assert!(det.abs() > 0.0);
        for i in 0..3 {
            for j in 0..3 {
                let v: f64 = (0..3).map(|k| m[i][k] * inv[k][j]).sum();
                assert!((v - if i == j { 1.0 } else { 0.0 }).abs() < 1e-14);
            }
        }
    }
}
