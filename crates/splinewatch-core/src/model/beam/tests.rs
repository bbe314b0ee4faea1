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

fn apply(rows: &[[f64; 12]; 6], q: &[f64]) -> [f64; 6] {
    std::array::from_fn(|r| rows[r].iter().zip(q).map(|(a, b)| a * b).sum())
}

/// The axis's motion inside the element: a rigid motion's `t + w × P(x)`
/// and `w` exactly; the nodes' own dofs at the ends.
#[test]
fn the_motion_inside_follows_a_rigid_motion_and_the_nodes() {
    let e = column();
    let (t, w) = ([0.3, -0.2, 0.7], [0.05, 0.11, -0.07]);
    let q = rigid(&e, t, w);
    for x in [0.0, 0.2, 0.5, 0.9, 1.0] {
        let motion = apply(&e.motion_rows(x), &q);
        let at = axpy(e.start(), x * e.length(), e.axes()[0]);
        let u = axpy(t, 1.0, cross(w, at));
        for d in 0..3 {
            assert!((motion[d] - u[d]).abs() < 1e-12, "x {x}: {motion:?} against {u:?}");
            assert!((motion[3 + d] - w[d]).abs() < 1e-12, "x {x}: {motion:?} against {w:?}");
        }
    }
    for (x, node) in [(0.0, 0), (1.0, 6)] {
        let rows = e.motion_rows(x);
        for (r, row) in rows.iter().enumerate() {
            for (c, &value) in row.iter().enumerate() {
                let expected = if c == node + r { 1.0 } else { 0.0 };
                assert!((value - expected).abs() < 1e-12, "x {x} ({r}, {c}): {value}");
            }
        }
    }
}

/// A cantilever of one element under tip forces: the interpolation solves
/// the Timoshenko beam under end loads, so the deflection and the section
/// rotation inside equal the closed forms `v(s) = P (L s²/2 − s³/6)/(E I)
/// + P s/(G A_s)`, `θ(s) = P (L s − s²/2)/(E I)` in both planes (1e-9).
#[test]
fn a_cantilever_deflects_inside_as_the_closed_form() {
    let e = column();
    let (s, m, l) = (e.section, e.material, e.length());
    let k = e.stiffness();
    let free = Mat::<f64>::from_fn(6, 6, |r, c| k[(6 + r, 6 + c)]);
    let flexibility = free.llt(faer::Side::Lower).unwrap().inverse();
    let [_, y, z] = e.axes();
    let p = 1.0e6;
    for (direction, inertia, shear_area, rotation_axis, sign) in
        [(y, s.iz, s.shear_area_y, z, 1.0), (z, s.iy, s.shear_area_z, y, -1.0)]
    {
        let load: Vec<f64> = direction.iter().map(|d| p * d).chain([0.0; 3]).collect();
        let tip: Vec<f64> = (0..6)
            .map(|r| (0..6).map(|c| flexibility[(r, c)] * load[c]).sum())
            .collect();
        let q: Vec<f64> = [0.0; 6].into_iter().chain(tip).collect();
        for x in [0.25, 0.5, 0.8] {
            let at = x * l;
            let deflection = p * (l * at * at / 2.0 - at.powi(3) / 6.0) / (m.young * inertia)
                + p * at / (m.shear_modulus * shear_area);
            let rotation = sign * p * (l * at - at * at / 2.0) / (m.young * inertia);
            let motion = apply(&e.motion_rows(x), &q);
            let (v, theta) = (
                dot([motion[0], motion[1], motion[2]], direction),
                dot([motion[3], motion[4], motion[5]], rotation_axis),
            );
            assert!(
                (v - deflection).abs() <= 1e-9 * deflection.abs(),
                "x {x}: {v} against {deflection}"
            );
            assert!(
                (theta - rotation).abs() <= 1e-9 * rotation.abs(),
                "x {x}: {theta} against {rotation}"
            );
        }
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
