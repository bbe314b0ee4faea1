//! Assembly and eigen-solve of the bundled Sinello model (13 × 5 net, 325
//! dofs) and of a refined 40 × 16 net (3 200 dofs), dense; and the sparse
//! path (sparse assembly, modes below 160 Hz) up to 100 × 40 (20 000 dofs).
//! Run: `cargo bench --bench model`. The side-by-side with scipy and peak
//! memory: `benches/sparse_scaling.sh`. And a deck of several patches
//! against a single cylindrical panel of as many dofs (issue 30): the
//! bundled overpass refined to 4 100 control points (nine patches, 14
//! joints, 9 bearings) and two panels of 4 100 points, 100 × 41 (the
//! overpass's span and width) and 50 × 82 (as many points along and across
//! as the overpass's nets side by side: its section's perimeter), and the
//! 100 × 41 panel cut into four patches of 25 × 41 joined across the span
//! (the patches' own cost, shape and size unchanged), each assembled sparse
//! and solved for its modes below 40 Hz (twice the overpass's 20 Hz band).

use splinewatch::config::Config;
use splinewatch_core::model::constraints::{Edge, EdgeConstraint, SupportKind};
use splinewatch_core::model::joints::find_joints;
use splinewatch_core::model::material::OrthotropicMaterial;
use splinewatch_core::model::patch::Patch;
use splinewatch_core::model::shell::Shell;
use splinewatch_core::model::BridgeModel;
use splinewatch_core::solvers::sparse_model::SparseModel;

const SINELLO: &str = include_str!("../config/sinello.toml");
const OVERPASS: &str = include_str!("../config/overpass.toml");

fn model(net: [usize; 2]) -> BridgeModel {
    let text = SINELLO.replace(
        "control_points = [13, 5]",
        &format!("control_points = [{}, {}]", net[0], net[1]),
    );
    Config::from_toml(&text).unwrap().build_model().unwrap()
}

#[divan::bench(args = [[13, 5], [40, 16]], sample_count = 5, sample_size = 1)]
fn assemble(bencher: divan::Bencher, net: [usize; 2]) {
    let m = model(net);
    bencher.bench(|| m.assemble().unwrap());
}

#[divan::bench(args = [[13, 5], [40, 16]], sample_count = 3, sample_size = 1)]
fn eigen_solve(bencher: divan::Bencher, net: [usize; 2]) {
    let assembled = model(net).assemble().unwrap();
    bencher.bench(|| assembled.modes().unwrap());
}

#[divan::bench(args = [[13, 5], [40, 16], [100, 40]], sample_count = 3, sample_size = 1)]
fn sparse_assemble(bencher: divan::Bencher, net: [usize; 2]) {
    let m = model(net);
    bencher.bench(|| SparseModel::assemble(&m).unwrap());
}

#[divan::bench(args = [[13, 5], [40, 16], [100, 40]], sample_count = 3, sample_size = 1)]
fn modes_below_160_hz(bencher: divan::Bencher, net: [usize; 2]) {
    let sparse = SparseModel::assemble(&model(net)).unwrap();
    bencher.bench(|| {
        sparse
            .modes_below(&sparse.spring_stiffness, &sparse.field_coefficients, 160.0)
            .unwrap()
    });
}

/// The overpass with every net refined (ξ 28 → 50, η doubled): 4 100
/// control points, 20 500 dofs.
fn overpass_refined() -> BridgeModel {
    let text = OVERPASS
        .replace("control_points = [28, 12]", "control_points = [50, 24]")
        .replace("control_points = [28, 8]", "control_points = [50, 16]")
        .replace("control_points = [28, 3]", "control_points = [50, 6]");
    Config::from_toml(&text).unwrap().build_model().unwrap()
}

/// A cylindrical panel of the overpass's length (radius 30 m), 0.5 m
/// thick, cubic, `net` control points (4 100: 20 500 dofs), arc `width`,
/// both ends clamped: curved, so membrane and bending couple as in folded
/// patches.
fn panel(net: [usize; 2], width: f64) -> BridgeModel {
    let shell = Shell::cylindrical_panel(80.8, 30.0, width / 30.0, 0.5, [3, 3], net).unwrap();
    let material = OrthotropicMaterial::isotropic(28e9, 0.2, 2400.0).unwrap();
    BridgeModel {
        constraints: [Edge::Xi0, Edge::Xi1]
            .map(|edge| EdgeConstraint {
                edge,
                kind: SupportKind::Clamped,
                patch: 0,
            })
            .to_vec(),
        ..BridgeModel::new(shell, material)
    }
}

#[divan::bench(
    args = ["overpass, 9 patches", "panel 100 x 41", "panel 100 x 41 in 4 patches", "panel 50 x 82"],
    sample_count = 3,
    sample_size = 1
)]
fn deck_20k_dofs_assembled_and_modes_below_40_hz(bencher: divan::Bencher, deck: &str) {
    let model = match deck {
        "panel 100 x 41" => panel([100, 41], 15.85),
        "panel 100 x 41 in 4 patches" => split_panel(4, [25, 41], 15.85),
        // The box's perimeter: both slabs and the seven webs' depths.
        "panel 50 x 82" => panel([50, 82], 15.85 + 12.0 + 7.0 * 1.575),
        _ => overpass_refined(),
    };
    let solve = || {
        let sparse = SparseModel::assemble(&model).unwrap();
        let modes = sparse
            .modes_below(&sparse.spring_stiffness, &sparse.field_coefficients, 40.0)
            .unwrap();
        (sparse.dof_count(), modes.len())
    };
    let (dofs, modes) = solve();
    eprintln!("{deck}: {dofs} dofs, {modes} modes below 40 Hz");
    bencher.bench(solve);
}

/// The same panel as `panel` cut across its span into `pieces` patches of
/// `net` points each, joined where they meet (penalty coupling,
/// `joints::find_joints`): the cost of the patches alone, the deck's shape
/// and size unchanged.
fn split_panel(pieces: usize, net: [usize; 2], width: f64) -> BridgeModel {
    let length = 80.8 / pieces as f64;
    let material = OrthotropicMaterial::isotropic(28e9, 0.2, 2400.0).unwrap();
    let piece = Shell::cylindrical_panel(length, 30.0, width / 30.0, 0.5, [3, 3], net).unwrap();
    let patches: Vec<Patch> = (0..pieces)
        .map(|k| {
            let shell = piece.translated([k as f64 * length, 0.0, 0.0]).unwrap();
            Patch::new(format!("piece_{k}"), shell, material.clone()).unwrap()
        })
        .collect();
    let joints = find_joints(&patches, 1e-3);
    assert_eq!(joints.len(), pieces - 1, "one joint between neighbours");
    BridgeModel {
        patches,
        joints,
        constraints: [(Edge::Xi0, 0), (Edge::Xi1, pieces - 1)]
            .map(|(edge, patch)| EdgeConstraint {
                edge,
                kind: SupportKind::Clamped,
                patch,
            })
            .to_vec(),
        ..BridgeModel::new(piece, material)
    }
}

fn main() {
    divan::main();
}
