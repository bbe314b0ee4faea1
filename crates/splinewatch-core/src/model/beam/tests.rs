//! The element against closed forms: rigid motions, a cantilever's end
//! displacements (exact for the interdependent interpolation with one
//! element) and the kinetic energy of rigid motions.

use super::*;
use faer::linalg::solvers::DenseSolveCore;

fn column() -> BeamElement {
    let material = BeamMaterial::isotropic(3.0e10, 0.2, 2500.0).unwrap();
    // A rectangle (different I_y, I_z, shear areas), skewed in space, so a
    // wrong plane, sign or frame shows.
    let section = Section::rectangle(0.8, 1.5, 0.2).unwrap();
    BeamElement::new([1.0, -2.0, 0.5], [2.5, 1.0, 4.5], [0.3, 0.2, -0.1], section, material).unwrap()
}

fn times(a: &Mat<f64>, x: &[f64]) -> Vec<f64> {
    (0..a.nrows())
        .map(|r| (0..a.ncols()).map(|c| a[(r, c)] * x[c]).sum())
        .collect()
}

fn quadratic(a: &Mat<f64>, x: &[f64]) -> f64 {
    times(a, x).iter().zip(x).map(|(ax, x)| ax * x).sum()
}

/// The global dofs of a rigid motion: translation `t` and rotation `w`
/// about the origin (`u = t + w × x`, `θ = w`).
fn rigid(e: &BeamElement, t: Vec3, w: Vec3) -> Vec<f64> {
    let end = axpy(e.start(), e.length(), e.axes()[0]);
    [e.start(), end]
        .iter()
        .flat_map(|&x| {
            let u = axpy(t, 1.0, cross(w, x));
            [u[0], u[1], u[2], w[0], w[1], w[2]]
        })
        .collect()
}

#[test]
fn rigid_motions_carry_no_strain_energy() {
    let e = column();
    let k = e.stiffness();
    let scale = k.norm_max();
    for (t, w) in [
        ([1.0, 0.0, 0.0], [0.0; 3]),
        ([0.0, 1.0, 0.0], [0.0; 3]),
        ([0.0, 0.0, 1.0], [0.0; 3]),
        ([0.0; 3], [1.0, 0.0, 0.0]),
        ([0.0; 3], [0.0, 1.0, 0.0]),
        ([0.0; 3], [0.0, 0.0, 1.0]),
    ] {
        let force = times(&k, &rigid(&e, t, w));
        let largest = force.iter().fold(0.0f64, |m, f| m.max(f.abs()));
        assert!(largest < 1e-9 * scale * 5.0, "{t:?} {w:?}: {largest:e}");
    }
    for r in 0..12 {
        for c in 0..12 {
            assert!((k[(r, c)] - k[(c, r)]).abs() <= 1e-12 * scale);
        }
    }
}

/// Tip loads on a cantilever (start fixed): `δ = P L³/(3EI) + P L/(G A_s)`,
/// `θ = P L²/(2EI)` in each plane, `P L/(EA)` axial, `T L/(GJ)` in torsion.
#[test]
fn a_cantilever_of_one_element_has_the_exact_tip_displacements() {
    let e = column();
    let (s, m, l) = (e.section, e.material, e.length());
    // The free end's 6 × 6 block in the element's frame.
    let k = e.local_stiffness();
    let free = Mat::<f64>::from_fn(6, 6, |r, c| k[(6 + r, 6 + c)]);
    let flexibility = free.llt(faer::Side::Lower).unwrap().inverse();
    let bending = |i: f64, shear: f64| l.powi(3) / (3.0 * m.young * i) + l / (m.shear_modulus * shear);
    let expected = [
        (0, 0, l / (m.young * s.area)),
        (1, 1, bending(s.iz, s.shear_area_y)),
        (2, 2, bending(s.iy, s.shear_area_z)),
        (3, 3, l / (m.shear_modulus * s.torsion)),
        // Rotation under a tip force: θ_z = +P_y L²/(2 E I_z), θ_y = −P_z L²/(2 E I_y).
        (5, 1, l * l / (2.0 * m.young * s.iz)),
        (4, 2, -l * l / (2.0 * m.young * s.iy)),
        (4, 4, l / (m.young * s.iy)),
        (5, 5, l / (m.young * s.iz)),
    ];
    for (r, c, value) in expected {
        assert!(
            (flexibility[(r, c)] - value).abs() <= 1e-9 * value.abs(),
            "({r}, {c}): {} against {value}",
            flexibility[(r, c)]
        );
    }
}

/// The consistent mass reproduces the kinetic energy of rigid motions
/// exactly: `ρ A L` per translation, `ρ I_p L` about the axis, and
/// `ρ A L³/12 + ρ I L` about a normal axis through the middle.
#[test]
fn rigid_motions_have_the_exact_kinetic_energy() {
    let e = column();
    let (s, rho, l) = (e.section, e.material.density, e.length());
    let mass = e.mass();
    for t in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]] {
        let value = quadratic(&mass, &rigid(&e, t, [0.0; 3]));
        assert!((value - rho * s.area * l).abs() < 1e-12 * value, "{t:?}: {value}");
    }
    let [x, y, z] = e.axes();
    let middle = axpy(e.start(), 0.5 * l, x);
    // A rotation about `w` through `middle`: translation −w × middle.
    let about_middle = |w: Vec3| rigid(&e, scale(cross(w, middle), -1.0), w);
    let cases = [
        (x, rho * s.polar() * l),
        (y, rho * s.area * l.powi(3) / 12.0 + rho * s.iy * l),
        (z, rho * s.area * l.powi(3) / 12.0 + rho * s.iz * l),
    ];
    for (w, expected) in cases {
        let value = quadratic(&mass, &about_middle(w));
        assert!(
            (value - expected).abs() < 1e-10 * expected,
            "{w:?}: {value} against {expected}"
        );
    }
}

#[test]
fn bad_beams_are_refused_by_name() {
    let material = BeamMaterial::isotropic(3.0e10, 0.2, 2500.0).unwrap();
    let section = Section::circle(1.2, 0.2).unwrap();
    assert!(matches!(
        BeamElement::new([1.0, 2.0, 3.0], [1.0, 2.0, 3.0], [0.0, 1.0, 0.0], section, material),
        Err(BeamError::ZeroLength(_))
    ));
    assert!(matches!(
        BeamElement::new([0.0; 3], [0.0, 0.0, 7.0], [0.0, 0.0, 2.0], section, material),
        Err(BeamError::Orientation { .. })
    ));
    assert!(matches!(
        Section::circle(0.0, 0.2),
        Err(BeamError::Section { name: "circle", .. })
    ));
    assert!(matches!(Section::circle(1.0, 0.5), Err(BeamError::Poisson(_))));
    assert!(matches!(
        BeamMaterial::isotropic(3.0e10, 0.2, -1.0),
        Err(BeamError::Material { name: "density", .. })
    ));
    let circle = Section::circle(1.2, 0.2).unwrap();
    assert!((circle.torsion - circle.polar()).abs() < 1e-15);
}
