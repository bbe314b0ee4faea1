//! Assembly and eigen-solve of the bundled Sinello model (13 × 5 net, 325
//! dofs) and of a refined 40 × 16 net (3 200 dofs), dense; and the sparse
//! path (sparse assembly, modes below 160 Hz) up to 100 × 40 (20 000 dofs).
//! Run: `cargo bench --bench model`. The side-by-side with scipy and peak
//! memory: `benches/sparse_scaling.sh`.

use splinewatch::config::Config;
use splinewatch_core::model::ShellModel;
use splinewatch_core::solvers::sparse_model::SparseModel;

const SINELLO: &str = include_str!("../config/sinello.toml");

fn model(net: [usize; 2]) -> ShellModel {
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

fn main() {
    divan::main();
}
