//! `splinewatch matrices` and the sparse path at the bundled deck: the
//! exported Matrix Market files read back to eq. (23), and the sparse
//! shift-invert Lanczos modes agree with scipy's `eigsh` (ARPACK) on the
//! same matrices (`tests/fixtures/eigsh_sinello.json`, made by
//! `tests/fixtures/make_eigsh_fixture.py`).

use crate::common::{fresh_dir, splinewatch};
use splinewatch::config::load_config;
use splinewatch::io::matrix_market::{read_symmetric, Entry};
use splinewatch_core::solvers::sparse_model::SparseModel;
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
    assert_eq!(assert_equation_23(&dir, parameters), 325);
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
        .modes_below(&model.spring_stiffness, &model.field_coefficients, cutoff_hz)
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

/// The bundled deck with `[model.solver] modes = "truncated"` (the
/// modes below 160 Hz, 2× the 80 Hz band, from the sparse path plus the
/// residual of the others) gives the 12 accelerances of the paper's case
/// (input at the first sensor) over the band within 1e-3 of the full modal
/// sum over all 325 modes (the dense path), relative to each FRF's peak;
/// without the residual the error is larger: the compensation is what makes
/// truncation safe.
#[test]
fn truncated_frfs_with_residual_compensation_match_the_full_modal_sum() {
    use splinewatch::config::ModesChoice;
    use splinewatch_core::response::frf::{FrfRequest, Quantity};
    let mut config = load_config(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("config/sinello.toml")
            .as_path(),
    )
    .unwrap();
    config.model.solver.modes = ModesChoice::Truncated;
    let setup = splinewatch::config::frf_setup(&config).unwrap();
    assert_eq!(setup.model.cutoff_hz(), Some(160.0));
    let reference = setup
        .reference
        .as_ref()
        .expect("the small deck keeps its every-mode twin");
    let lines: Vec<f64> = (2..=320).map(|k| 0.25 * k as f64).collect();
    let pairs: Vec<(usize, usize)> = (0..12).map(|s| (s, 0)).collect();
    let request = FrfRequest {
        frequencies_hz: &lines,
        pairs: &pairs,
        quantity: Quantity::Accelerance,
    };
    let full = reference.modal_state(&setup.kappa, &setup.damping).unwrap();
    let expected = reference.evaluate(&full, request, false).h;
    let kept = setup.model.modal_state(&setup.kappa, &setup.damping).unwrap();
    for i in 0..kept.modes.len() {
        let (a, b) = (kept.modes.frequency_hz(i), full.modes.frequency_hz(i));
        // Rigid modes (zero to round-off) compare absolutely.
        assert!((a - b).abs() <= 1e-6 * b.max(100.0), "mode {i}: {a} vs {b} Hz");
    }
    let found = setup.model.evaluate(&kept, request, false).h;
    let residual = kept.residual().expect("a truncated state");
    let (mut worst, mut worst_plain) = (0.0f64, 0.0f64);
    for (p, &(r, s)) in pairs.iter().enumerate() {
        let h = &expected[p * lines.len()..(p + 1) * lines.len()];
        let peak = h.iter().map(|v| v.norm()).fold(0.0, f64::max);
        for (line, f) in lines.iter().enumerate() {
            let omega = 2.0 * std::f64::consts::PI * f;
            let compensated = found[p * lines.len() + line];
            let plain = compensated - Quantity::Accelerance.factor(omega) * residual.at_sensors(r, s, omega);
            worst = worst.max((compensated - h[line]).norm() / peak);
            worst_plain = worst_plain.max((plain - h[line]).norm() / peak);
        }
    }
    let reported = reference
        .truncation_error(
            &found,
            &setup.kappa,
            setup.model.field_coefficients(),
            &setup.damping,
            request,
        )
        .unwrap();
    assert_eq!(reported, worst, "the update report's figure is this one");
    assert!(worst <= 1e-3, "compensated: {worst:.2e} of the peak");
    assert!(
        worst_plain > 10.0 * worst,
        "truncated without the residual: {worst_plain:.2e}, with: {worst:.2e}"
    );
    eprintln!(
        "truncation at 160 Hz ({} of 325 modes): {worst:.2e} with the residual, {worst_plain:.2e} without",
        kept.modes.len()
    );
}

/// `splinewatch update` on a truncated deck (`[model.solver] modes =
/// "truncated"` in the config file) against synthetic FRFs of the true
/// deck: the same spring coefficients as the every-mode update within
/// 1e-3, and the report names the cut-off, the modes kept and the
/// truncation error; bad solver keys are refused with their path.
#[test]
fn a_truncated_update_from_the_cli_matches_the_every_mode_one() {
    let dir = fresh_dir("truncated-update");
    let frf = dir.join("frf.json");
    let out = splinewatch(&[
        "synth",
        "--config",
        "config/sinello-truth.toml",
        "--inputs",
        "P1",
        "--outputs",
        "P1,P2,P3,P4,P5,P6",
        "--from",
        "1",
        "--to",
        "80",
        "--step",
        "0.25",
        "--out",
        frf.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let bundled = std::fs::read_to_string("config/sinello.toml").unwrap();
    let truncated = dir.join("truncated.toml");
    std::fs::write(
        &truncated,
        format!("{bundled}\n[model.solver]\nmodes = \"truncated\"\n"),
    )
    .unwrap();
    let update = |config: &Path| {
        let out = splinewatch(&[
            "update",
            "--config",
            config.to_str().unwrap(),
            "--frf",
            frf.to_str().unwrap(),
            "--json",
        ]);
        let stderr = String::from_utf8_lossy(&out.stderr).to_string();
        assert!(out.status.success(), "{stderr}");
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(v["converged"], true, "{stderr}");
        let values: Vec<(String, f64)> = v["parameters"]
            .as_array()
            .unwrap()
            .iter()
            .map(|p| (p["name"].as_str().unwrap().to_string(), p["value"].as_f64().unwrap()))
            .collect();
        (values, stderr)
    };
    let (every, _) = update(Path::new("config/sinello.toml"));
    let (kept, stderr) = update(&truncated);
    assert!(
        stderr.contains("modal truncation: 73 modes below 160 Hz") && stderr.contains("FRF error against every mode: "),
        "{stderr}"
    );
    let mut worst = 0.0f64;
    for ((name, a), (other, b)) in kept.iter().zip(&every) {
        assert_eq!(name, other);
        if name.contains(".k") {
            worst = worst.max((a - b).abs() / b.abs());
        }
    }
    eprintln!("truncated vs every-mode update: springs within {worst:.2e}");
    assert!(worst <= 1e-3, "springs differ by {worst:.2e}");

    let bad = dir.join("bad.toml");
    std::fs::write(
        &bad,
        format!("{bundled}\n[model.solver]\nmodes = \"truncated\"\ncutoff_hz = -5.0\n"),
    )
    .unwrap();
    let out = splinewatch(&["check-config", bad.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.contains("model.solver.cutoff_hz"),
        "{stderr}"
    );
}

/// Issue 30: `matrices` of a deck of several patches (the slab on two
/// webs on four bearings): every row names its patch and its control point
/// there, the bearings' `∂K/∂k` come after the spring fields' as
/// `<name>.kx/ky/kz`, and `K = K_f + Σ k ∂K/∂k` holds on the export.
#[test]
fn issue_30_matrices_of_several_patches_name_their_patch_and_bearings() {
    let dir = fresh_dir("matrices-patches");
    let o = splinewatch(&[
        "matrices",
        "--config",
        "tests/fixtures/slab_on_webs.toml",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let index: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.join("index.json")).unwrap()).unwrap();
    let dofs = index["dofs"].as_array().unwrap();
    let patches: std::collections::BTreeSet<&str> = dofs.iter().map(|d| d["patch"].as_str().unwrap()).collect();
    assert_eq!(patches, ["slab", "web_north", "web_south"].into_iter().collect());
    let first_web_row = dofs.iter().find(|d| d["patch"] == "web_south").unwrap();
    assert_eq!(first_web_row["control_point"], 0);
    assert_eq!(first_web_row["net_index"], serde_json::json!([0, 0]));
    let parameters = index["parameters"].as_array().unwrap();
    let bearings: Vec<&str> = parameters
        .iter()
        .filter(|p| p["kind"] == "bearing")
        .map(|p| p["name"].as_str().unwrap())
        .collect();
    assert_eq!(bearings.len(), 12, "{bearings:?}");
    assert_eq!(bearings[..3], ["west_south.kx", "west_south.ky", "west_south.kz"]);
    assert_eq!(
        assert_equation_23(&dir, parameters),
        index["free_dofs"].as_u64().unwrap() as usize
    );
}

/// `K = K_f + Σ value · ∂K/∂parameter` (`value − 1` for a multiplier θ) on
/// the export in `dir`, entry by
/// entry to 1e-14 of K's largest (the values read back exactly, only the
/// sum rounds), every parameter file holding its `nnz_lower` entries and
/// every entry of K in the sum; returns the matrices' size.
fn assert_equation_23(dir: &Path, parameters: &[serde_json::Value]) -> usize {
    let (n, k) = read(&dir.join("K.mtx"));
    let (_, mut sum) = read(&dir.join("K_f.mtx"));
    for p in parameters {
        let (_, dk) = read(&dir.join(p["file"].as_str().unwrap()));
        assert_eq!(dk.len(), p["nnz_lower"].as_u64().unwrap() as usize);
        // A multiplier θ adds (θ − 1) ∂K/∂θ (index.json's `relation`).
        let multiplier = matches!(p["kind"].as_str(), Some("stiffness_field" | "member_stiffness"));
        let value = p["value"].as_f64().unwrap() - if multiplier { 1.0 } else { 0.0 };
        for (at, v) in dk {
            *sum.entry(at).or_insert(0.0) += value * v;
        }
    }
    let top = k.values().fold(0.0f64, |a, v| a.max(v.abs()));
    for (at, v) in &sum {
        let exported = k.get(at).copied().unwrap_or(0.0);
        assert!((exported - v).abs() <= 1e-14 * top, "{at:?}: {exported} vs {v}");
    }
    assert!(k.keys().all(|at| sum.contains_key(at)));
    n
}

/// `matrices` of a deck on a bent with an abutment's line support: the
/// beam nodes' rows name their member and their number along it (their
/// rotations `rx, ry, rz`), the cap's rows its rigid body, the line
/// support's `∂K/∂k` follow as `<name>.<component>`, a column's held
/// stiffness multiplier as `<beam>.stiffness` at its value, and equation
/// (23) holds on the export (with θ = 0.8 on that column's bending).
#[test]
fn matrices_of_a_deck_on_a_bent_name_beam_nodes_rigid_bodies_and_line_supports() {
    let dir = fresh_dir("matrices-bent");
    let base = std::fs::read_to_string("config/examples/deck-on-bent.toml")
        .unwrap()
        .replacen(
            "support = \"bent\"\n",
            "support = \"bent\"\nstiffness = { value = 0.8, scales = \"bending\", update = false }\n",
            1,
        );
    let config = dir.join("deck-on-bent.toml");
    std::fs::write(
        &config,
        format!(
            "{base}\n[[model.supports]]\nname = \"west_abutment\"\nedge = {{ patch = \"span1\", edge = \"xi0\" }}\nsupport = \"west\"\nstiffness = {{ y = 2e8, ry = 5e8 }}\nbounds = [1e5, 1e12]\n"
        ),
    )
    .unwrap();
    let o = splinewatch(&[
        "matrices",
        "--config",
        config.to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let index: serde_json::Value = serde_json::from_slice(&std::fs::read(dir.join("index.json")).unwrap()).unwrap();
    let dofs = index["dofs"].as_array().unwrap();
    // Each column: 8 free nodes of 6 (its base is fixed), the top held by the cap.
    let south: Vec<&serde_json::Value> = dofs.iter().filter(|d| d["beam"] == "bent.south").collect();
    assert_eq!(south.len(), 7 * 6, "{south:?}");
    assert_eq!(south[0]["beam_node"], 1);
    let names: Vec<&str> = south[..6]
        .iter()
        .map(|d| d["components"][0]["dof"].as_str().unwrap())
        .collect();
    assert_eq!(names, ["u", "v", "w", "rx", "ry", "rz"]);
    let cap: Vec<&serde_json::Value> = dofs.iter().filter(|d| d["rigid_body"] == "cap").collect();
    assert_eq!(cap.len(), 6);
    assert!(dofs
        .iter()
        .filter(|d| d["patch"].is_string())
        .all(|d| d["beam"].is_null()));
    let parameters = index["parameters"].as_array().unwrap();
    let supports: Vec<&str> = parameters
        .iter()
        .filter(|p| p["kind"] == "support")
        .map(|p| p["name"].as_str().unwrap())
        .collect();
    assert_eq!(supports, ["west_abutment.y", "west_abutment.ry"]);
    let members: Vec<(&str, f64)> = parameters
        .iter()
        .filter(|p| p["kind"] == "member_stiffness")
        .map(|p| (p["name"].as_str().unwrap(), p["value"].as_f64().unwrap()))
        .collect();
    assert_eq!(members, [("bent.south.stiffness", 0.8)]);
    assert_eq!(
        assert_equation_23(&dir, parameters),
        index["free_dofs"].as_u64().unwrap() as usize
    );
}
