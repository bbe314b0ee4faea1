//! Line supports along patch edges: a plate strip whose ends are simply
//! supported and held against rotation by springs per metre goes from the
//! simply supported strip (no spring) to the clamped one (stiff springs).

use splinewatch_core::model::constraints::{Edge, EdgeConstraint, SupportKind};
use splinewatch_core::model::elastic_supports::{ElasticSupport, SupportComponent};
use splinewatch_core::model::material::OrthotropicMaterial;
use splinewatch_core::model::shell::Shell;
use splinewatch_core::model::BridgeModel;
use splinewatch_core::solvers::modal::ModeKind;

const GLOBAL: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// A 10 m × 2 m × 0.2 m strip, its ends `ξ = 0, 1` held as `kind`, with a
/// rotation spring `k` (N m/rad per metre) about y on each end.
fn strip(kind: SupportKind, k: Option<f64>) -> BridgeModel {
    let shell = Shell::rectangular_plate(10.0, 2.0, 0.2, [3, 3], [14, 5]).unwrap();
    let material = OrthotropicMaterial::isotropic(30e9, 0.2, 2500.0).unwrap();
    let mut model = BridgeModel::new(shell, material);
    model.constraints = [Edge::Xi0, Edge::Xi1]
        .map(|edge| EdgeConstraint { edge, kind, patch: 0 })
        .to_vec();
    if let Some(k) = k {
        model.elastic_supports = [("west", Edge::Xi0), ("east", Edge::Xi1)]
            .map(|(name, edge)| {
                ElasticSupport::along_edge(name, (0, edge), GLOBAL, vec![(SupportComponent::Rotation(1), k)]).unwrap()
            })
            .to_vec();
    }
    model
}

/// The first `count` bending frequencies.
fn bending(model: &BridgeModel, count: usize) -> Vec<f64> {
    let modes = model.assemble().unwrap().modes().unwrap();
    (0..modes.len())
        .filter(|&i| modes.kinds[i] == ModeKind::Bending)
        .take(count)
        .map(|i| modes.frequency_hz(i))
        .collect()
}

/// No spring: the simply supported strip exactly; springs stiff against
/// the strip's bending (`k L / D` ≈ 5e6): the clamped strip within 1e-5;
/// between, every frequency rises with `k`. The rotation spring about y
/// acts on `β`, the bending rotation at an edge along y.
#[test]
fn rotation_springs_take_a_strip_from_simply_supported_to_clamped() {
    let simply = bending(&strip(SupportKind::SimplySupported, None), 4);
    let clamped = bending(&strip(SupportKind::Clamped, None), 4);
    let free_spring = bending(&strip(SupportKind::SimplySupported, Some(0.0)), 4);
    let stiff = bending(&strip(SupportKind::SimplySupported, Some(1e13)), 4);
    let middle = bending(&strip(SupportKind::SimplySupported, Some(1e8)), 4);
    for i in 0..4 {
        assert_eq!(free_spring[i], simply[i], "mode {i}");
        let error = (stiff[i] / clamped[i] - 1.0).abs();
        assert!(
            error < 1e-5,
            "mode {i}: {} vs clamped {} ({error:.1e})",
            stiff[i],
            clamped[i]
        );
        assert!(simply[i] < middle[i] && middle[i] < clamped[i], "mode {i}: {middle:?}");
    }
    // The clamped strip is well apart from the simply supported one.
    assert!(clamped[0] > 1.5 * simply[0]);
}

/// A free 6 m × 3 m × 0.2 m plate on one point support at its centre,
/// on its bottom face (`τ = 0`), soft in `x, y, z, rx, ry`: its rigid
/// motions are those of a rigid body of the plate's mass and inertia on
/// those springs. Vertical: `ω² = k_z / m`; in the x–z plane the
/// translation `u` and the rotation `θ_y` couple through the face's offset
/// (the spring sees `u − θ_y h/2`):
/// `K = k_x [[1, −h/2], [−h/2, h²/4]] + diag(0, k_ry)`,
/// `M = diag(m, m (a² + h²)/12)`; in the y–z plane `v + θ_x h/2`, `k_y`,
/// `k_rx` and `m (b² + h²)/12`. The springs are soft (rigid motions at
/// 0.05–0.2 Hz, the plate's first elastic mode above 20 Hz), so the
/// elastic modes shift them by `(f_rigid / f_elastic)² ≈ 1e-4` at most:
/// the tolerance is 5e-4 relative (measured: 1e-5 to 5e-5). The drilling rotation has no spring
/// (the shell has no such dof): it stays a rigid mode.
#[test]
fn a_plate_on_a_point_support_moves_as_a_rigid_body_on_springs() {
    use splinewatch_core::model::bearings::PatchPoint;
    let (a, b, h, density) = (6.0, 3.0, 0.2, 2500.0);
    let shell = Shell::rectangular_plate(a, b, h, [3, 3], [8, 6]).unwrap();
    let material = OrthotropicMaterial::isotropic(30e9, 0.2, density).unwrap();
    let at = PatchPoint {
        patch: 0,
        xi: 0.5,
        eta: 0.5,
        tau: 0.0,
    };
    let centre = shell.position(at.xi, at.eta, 0.5);
    assert!((centre[0] - a / 2.0).abs() < 1e-12 && (centre[1] - b / 2.0).abs() < 1e-12);
    let k = [2.0e3, 3.0e3, 4.0e3, 5.0e3, 6.0e3];
    let components = SupportComponent::ALL[..5].iter().copied().zip(k).collect();
    let mut model = BridgeModel::new(shell, material);
    model.elastic_supports = vec![ElasticSupport::at_point("pot", at, GLOBAL, components).unwrap()];
    let modes = model.assemble().unwrap().modes().unwrap();
    let mut found: Vec<f64> = (0..modes.len())
        .filter(|&i| modes.omega2[i] > 1e-3)
        .take(5)
        .map(|i| modes.omega2[i])
        .collect();
    found.sort_by(f64::total_cmp);
    let m = density * a * b * h;
    // The 2 × 2 pencil `(K, diag(m, I))` for a translation spring `kt` on
    // the face's offset `e` and a rotation spring `kr`.
    let pair = |kt: f64, kr: f64, inertia: f64| {
        let e = h / 2.0;
        let (k11, k12, k22) = (kt / m, kt * e / (m * inertia).sqrt(), (kt * e * e + kr) / inertia);
        let (mean, half) = (0.5 * (k11 + k22), (0.25 * (k11 - k22).powi(2) + k12 * k12).sqrt());
        [mean - half, mean + half]
    };
    let mut expected = vec![k[2] / m];
    expected.extend(pair(k[0], k[4], m * (a * a + h * h) / 12.0));
    expected.extend(pair(k[1], k[3], m * (b * b + h * h) / 12.0));
    expected.sort_by(f64::total_cmp);
    for (f, e) in found.iter().zip(&expected) {
        let error = (f / e - 1.0).abs();
        assert!(
            error < 5e-4,
            "ω² {f} vs rigid body {e} ({error:.1e}); all {found:?} vs {expected:?}"
        );
    }
    let rigid = (0..modes.len()).filter(|&i| modes.kinds[i] == ModeKind::Rigid).count();
    assert_eq!(rigid, 1, "the drilling rotation only");
}

/// The sparse path assembles point supports as the dense one: a plate on
/// two soffit point supports in five components (its drilling rotation
/// free), its elastic modes below 60 Hz within 1e-8 of the dense solve's
/// (measured 3e-12).
#[test]
fn the_sparse_path_takes_point_supports_as_the_dense_one() {
    use splinewatch_core::model::bearings::PatchPoint;
    use splinewatch_core::solvers::sparse_model::SparseModel;
    let shell = Shell::rectangular_plate(6.0, 3.0, 0.2, [3, 3], [8, 6]).unwrap();
    let material = OrthotropicMaterial::isotropic(30e9, 0.2, 2500.0).unwrap();
    let mut model = BridgeModel::new(shell, material);
    model.elastic_supports = [("west", 0.2), ("east", 0.8)]
        .map(|(name, xi)| {
            let at = PatchPoint {
                patch: 0,
                xi,
                eta: 0.5,
                tau: 0.0,
            };
            let components = SupportComponent::ALL[..5].iter().map(|&c| (c, 1e8)).collect();
            ElasticSupport::at_point(name, at, GLOBAL, components).unwrap()
        })
        .to_vec();
    let dense = model.assemble().unwrap().modes().unwrap();
    let sparse = SparseModel::assemble(&model).unwrap();
    let theta = sparse.field_coefficients.clone();
    let partial = sparse.modes_below(&sparse.spring_stiffness, &theta, 60.0).unwrap();
    let elastic = |m: &splinewatch_core::solvers::modal::Modes| -> Vec<f64> {
        (0..m.len())
            .filter(|&i| m.kinds[i] != ModeKind::Rigid)
            .map(|i| m.frequency_hz(i))
            .filter(|f| *f < 60.0)
            .collect()
    };
    let (a, b) = (elastic(&dense), elastic(&partial));
    assert!(a.len() >= 6 && a.len() == b.len(), "{a:?} vs {b:?}");
    for (x, y) in a.iter().zip(&b) {
        assert!((y / x - 1.0).abs() < 1e-8, "sparse {y} Hz, dense {x} Hz");
    }
}
