//! `splinewatch matrices` and the sparse path at the bundled deck: the
//! exported Matrix Market files read back to eq. (23), and the sparse
//! shift-invert Lanczos modes agree with scipy's `eigsh` (ARPACK) on the
//! same matrices (`tests/fixtures/eigsh_sinello.json`, made by
//! `tests/fixtures/make_eigsh_fixture.py`).

use crate::common::{fresh_dir, splinewatch};
use splinewatch::config::load_config;
use splinewatch::io::matrix_market::{read_symmetric, Entry};
use splinewatch_core::sparse_model::SparseModel;
use std::collections::BTreeMap;
use std::path::Path;

fn read(path: &Path) -> (usize, BTreeMap<(usize, usize), f64>) {
    let file = std::io::BufReader::new(std::fs::File::open(path).unwrap());
    let (n, entries): (usize, Vec<Entry>) = read_symmetric(file).unwrap();
    (n, entries.into_iter().map(|(r, c, v)| ((r, c), v)).collect())
}

/// The export of the bundled deck: K, K_f, M and the eight ∂K/∂κ_j on its
/// 325 free coordinates, lower triangles; `K = K_f + Σ κ_j ∂K/∂κ_j` holds
/// entry by entry to 1e-14 of the largest (the values read back exactly,
/// only the sum rounds); `index.json` names every row.
#[test]
fn exported_matrices_read_back_to_equation_23() {
    let dir = fresh_dir("matrices");
    let o = splinewatch(&[
        "matrices",
        "--config",
        "config/sinello.toml",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let index: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.join("index.json")).unwrap()).unwrap();
    assert_eq!(index["free_dofs"], 325);
    let dofs = index["dofs"].as_array().unwrap();
    assert_eq!(dofs.len(), 325);
    assert!(dofs.iter().all(|d| !d["components"].as_array().unwrap().is_empty()));
    assert_eq!(dofs[2]["components"][0]["dof"], "w");
    let parameters = index["parameters"].as_array().unwrap();
    let names: Vec<&str> = parameters.iter().map(|p| p["name"].as_str().unwrap()).collect();
    assert_eq!(
        names,
        ["west.k1", "west.k2", "west.k3", "west.k4", "east.k1", "east.k2", "east.k3", "east.k4"]
    );
    let (n, k) = read(&dir.join("K.mtx"));
    let (_, k_f) = read(&dir.join("K_f.mtx"));
    assert_eq!(n, 325);
    let mut sum = k_f.clone();
    for p in parameters {
        let (_, dk) = read(&dir.join(p["file"].as_str().unwrap()));
        assert_eq!(dk.len(), p["nnz_lower"].as_u64().unwrap() as usize);
        let kappa = p["value"].as_f64().unwrap();
        for (at, v) in dk {
            *sum.entry(at).or_insert(0.0) += kappa * v;
        }
    }
    let top = k.values().fold(0.0f64, |a, v| a.max(v.abs()));
    for (at, v) in &sum {
        let exported = k.get(at).copied().unwrap_or(0.0);
        assert!((exported - v).abs() <= 1e-14 * top, "{at:?}: {exported} vs {v}");
    }
    assert!(k.keys().all(|at| sum.contains_key(at)));
    let (_, m) = read(&dir.join("M.mtx"));
    assert!(m.iter().filter(|((r, c), _)| r == c).all(|(_, &v)| v > 0.0));
}

/// The sparse path (decoupled blocks, nested dissection, supernodal
/// Cholesky, Sturm count, faer's Lanczos) finds the modes below 100 Hz that scipy's `eigsh` finds
/// on the exported matrices: the same count, elastic ω² within 1e-9
/// relative (ARPACK's and our residual tolerances are both far below),
/// the three in-plane rigid modes at zero to 1e-6 rad²/s².
#[test]
fn sparse_modes_agree_with_scipy_eigsh() {
    let fixture: serde_json::Value = serde_json::from_slice(
        &std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/eigsh_sinello.json")).unwrap(),
    )
    .unwrap();
    let reference: Vec<f64> = fixture["omega2"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    let config = load_config(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("config/sinello.toml")
            .as_path(),
    )
    .unwrap();
    let model = SparseModel::assemble(&config.build_model().unwrap()).unwrap();
    // A flat deck on vertical springs: in-plane and out-of-plane blocks, as
    // the dense ModalSolver finds them.
    let mut blocks = model.block_sizes();
    blocks.sort_unstable();
    assert_eq!(blocks, [130, 195]);
    let cutoff_hz = 100.0;
    let modes = model
        .modes_below(&model.spring_stiffness, &model.field_coefficients, cutoff_hz, 10)
        .unwrap();
    let cutoff = (2.0 * std::f64::consts::PI * cutoff_hz).powi(2);
    let expected: Vec<f64> = reference.into_iter().filter(|&w| w <= cutoff).collect();
    assert!(expected.len() < 40, "the fixture reaches past the cut-off");
    assert_eq!(modes.len(), expected.len());
    for (i, (&a, &b)) in modes.omega2.iter().zip(&expected).enumerate() {
        if b.abs() < 1e-3 {
            assert!(a.abs() < 1e-6, "rigid mode {i}: {a}");
        } else {
            assert!((a - b).abs() <= 1e-9 * b, "mode {i}: {a} vs scipy {b}");
        }
    }
}

/// Bad input: an output folder that cannot be made is named, exit 1.
#[test]
fn matrices_into_an_impossible_folder_is_a_clear_error() {
    let dir = fresh_dir("matrices-bad");
    let blocker = dir.join("file");
    std::fs::write(&blocker, "not a folder").unwrap();
    let out = blocker.join("sub");
    let o = splinewatch(&[
        "matrices",
        "--config",
        "config/sinello.toml",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("sub") && err.lines().count() <= 3, "{err}");
}

/// Modal truncation with residual compensation on the bundled deck: the
/// modes below 160 Hz (2× the 80 Hz band) from the sparse path plus the
/// residual flexibility of the discarded ones give the 12 accelerances of
/// the paper's case (input at the first sensor) over the band within 1e-3
/// of the full modal sum over all 325 modes (the dense path), relative to
/// each FRF's peak; without the residual the error is larger: the
/// compensation is what makes truncation safe.
#[test]
fn truncated_frfs_with_residual_compensation_match_the_full_modal_sum() {
    use splinewatch_core::frf::{sensor_rows, FrfRequest, Quantity};
    use splinewatch_core::truncation::TruncatedFrf;
    let config = load_config(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("config/sinello.toml")
            .as_path(),
    )
    .unwrap();
    let setup = splinewatch::config::frf_setup(&config).unwrap();
    let full = setup.model.modal_state(&setup.kappa, &setup.damping).unwrap();
    let lines: Vec<f64> = (2..=320).map(|k| 0.25 * k as f64).collect();
    let pairs: Vec<(usize, usize)> = (0..12).map(|s| (s, 0)).collect();
    let request = FrfRequest {
        frequencies_hz: &lines,
        pairs: &pairs,
        quantity: Quantity::Accelerance,
    };
    let reference = setup.model.evaluate(&full, request, false).h;
    let model = config.build_model().unwrap();
    let sparse = SparseModel::assemble(&model).unwrap();
    let cutoff_hz = 160.0;
    let modes = sparse
        .modes_below(&setup.kappa, &sparse.field_coefficients, cutoff_hz, 10)
        .unwrap();
    for i in 0..modes.len() {
        let (a, b) = (modes.frequency_hz(i), full.modes.frequency_hz(i));
        // Rigid modes (zero to round-off) compare absolutely.
        assert!((a - b).abs() <= 1e-6 * b.max(100.0), "mode {i}: {a} vs {b} Hz");
    }
    let zeta = full.zeta[..modes.len()].to_vec();
    let points: Vec<_> = config
        .build_sensors(&model.shell)
        .unwrap()
        .into_iter()
        .map(|(_, p)| p)
        .collect();
    let rows = sensor_rows(&model.shell, &points).unwrap();
    let shift = SparseModel::shift_for(cutoff_hz);
    let flexibility = sparse
        .flexibility(&setup.kappa, &sparse.field_coefficients, &rows, shift)
        .unwrap();
    let truncated = TruncatedFrf::new(&modes, zeta, &rows, &flexibility, shift);
    let (mut worst, mut worst_plain) = (0.0f64, 0.0f64);
    for (p, &(r, s)) in pairs.iter().enumerate() {
        let h = &reference[p * lines.len()..(p + 1) * lines.len()];
        let peak = h.iter().map(|v| v.norm()).fold(0.0, f64::max);
        for (line, f) in lines.iter().enumerate() {
            let omega = 2.0 * std::f64::consts::PI * f;
            let compensated = truncated.frf(r, s, omega, Quantity::Accelerance, true);
            let plain = truncated.frf(r, s, omega, Quantity::Accelerance, false);
            worst = worst.max((compensated - h[line]).norm() / peak);
            worst_plain = worst_plain.max((plain - h[line]).norm() / peak);
        }
    }
    assert!(worst <= 1e-3, "compensated: {worst:.2e} of the peak");
    assert!(
        worst_plain > 2.0 * worst,
        "truncated without the residual: {worst_plain:.2e}, with: {worst:.2e}"
    );
    eprintln!(
        "truncation at {cutoff_hz} Hz ({} of 325 modes): {worst:.2e} with the residual, {worst_plain:.2e} without",
        modes.len()
    );
}
