//! Line supports along patch edges: a plate strip whose ends are simply
//! supported and held against rotation by springs per metre goes from the
//! simply supported strip (no spring) to the clamped one (stiff springs).

use splinewatch_core::model::constraints::{Edge, EdgeConstraint, SupportKind};
use splinewatch_core::model::elastic_supports::{ElasticSupport, SupportComponent};
use splinewatch_core::model::material::OrthotropicMaterial;
use splinewatch_core::model::shell::Shell;
use splinewatch_core::model::ShellModel;
use splinewatch_core::solvers::modal::ModeKind;

const GLOBAL: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// A 10 m × 2 m × 0.2 m strip, its ends `ξ = 0, 1` held as `kind`, with a
/// rotation spring `k` (N m/rad per metre) about y on each end.
fn strip(kind: SupportKind, k: Option<f64>) -> ShellModel {
    let shell = Shell::rectangular_plate(10.0, 2.0, 0.2, [3, 3], [14, 5]).unwrap();
    let material = OrthotropicMaterial::isotropic(30e9, 0.2, 2500.0).unwrap();
    let mut model = ShellModel::new(shell, material);
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
fn bending(model: &ShellModel, count: usize) -> Vec<f64> {
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
