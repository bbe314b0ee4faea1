use super::*;
use crate::model::material::OrthotropicMaterial;

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
