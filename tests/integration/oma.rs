//! Output-only identification end to end: `simulate --excitation ambient`
//! (and traffic) → MCAP → `splinewatch oma`, its JSON contract, and bad input.

use crate::common::{fresh_dir, loss_scenario, parameter, results_by_topic, splinewatch};
use splinewatch::config::{frf_setup, load_config};
use splinewatch::io::modes_json::ModesFile;
use splinewatch_core::c64;
use splinewatch_core::identification::oma::shape::mac;
use splinewatch_core::solvers::modal::ModeKind;
use std::path::Path;
use std::process::Output;

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// `splinewatch simulate` on the bundled config into `out`; asserts success.
fn simulate(out: &Path, excitation: &str, seconds: &str, seed: &str, extra: &[&str]) {
    let mut args = vec![
        "simulate",
        "--config",
        "config/sinello.toml",
        "--duration",
        seconds,
        "--excitation",
        excitation,
        "--seed",
        seed,
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let sim = splinewatch(&args);
    assert!(sim.status.success(), "{}", stderr(&sim));
}

/// The bundled model's bending modes below 80 Hz at the twelve sensors.
fn model_modes() -> Vec<(f64, Vec<c64>)> {
    let cfg = load_config(&Path::new(env!("CARGO_MANIFEST_DIR")).join("config/sinello.toml")).unwrap();
    let setup = frf_setup(&cfg).unwrap();
    let state = setup.model.modal_state(&setup.kappa, &setup.damping).unwrap();
    (0..state.modes.len())
        .filter(|&i| state.modes.kinds[i] == ModeKind::Bending && state.modes.frequency_hz(i) < 80.0)
        .map(|i| {
            let shape = (0..12).map(|s| c64::new(state.amplitude(s, i), 0.0)).collect();
            (state.modes.frequency_hz(i), shape)
        })
        .collect()
}

/// Every identified mode of `file` paired with the model mode of largest MAC:
/// (model frequency, identified frequency, MAC).
fn pairs(file: &ModesFile) -> Vec<(f64, f64, f64)> {
    let exact = model_modes();
    file.modes
        .iter()
        .map(|m| {
            let shape: Vec<c64> = m.shape.iter().map(|s| c64::new(s.re, s.im)).collect();
            let (f, value) = exact
                .iter()
                .map(|(f, e)| (*f, mac(&shape, e)))
                .max_by(|a, b| a.1.total_cmp(&b.1))
                .unwrap();
            (f, m.frequency_hz, value)
        })
        .collect()
}

/// The deck's κ after the scenario's loss (`east.k2` at 60 %).
const DAMAGED_KAPPA: [(&str, f64); 8] = [
    ("west.k1", 0.4e9),
    ("west.k2", 1.5e9),
    ("west.k3", 1.8e9),
    ("west.k4", 0.6e9),
    ("east.k1", 1.5e9),
    ("east.k2", 0.24e9),
    ("east.k3", 0.5e9),
    ("east.k4", 1.8e9),
];

/// `splinewatch replay` of `rec` with the bundled output-only config in
/// `window_seconds` windows (plus `extra` sections), results and state in
/// `dir`; asserts success.
fn replay_output_only(
    dir: &Path,
    rec: &Path,
    window_seconds: f64,
    extra: &str,
) -> (std::path::PathBuf, std::path::PathBuf) {
    let config = dir.join("output-only.toml");
    let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("config/sinello-ambient.toml"))
        .unwrap()
        .replace(
            "window_seconds = 1200.0",
            &format!("window_seconds = {window_seconds:.1}"),
        );
    std::fs::write(&config, text + extra).unwrap();
    let (results, state) = (dir.join("results.mcap"), dir.join("state.json"));
    let o = splinewatch(&[
        "replay",
        "--config",
        config.to_str().unwrap(),
        rec.to_str().unwrap(),
        "--out",
        results.to_str().unwrap(),
        "--state",
        state.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    (results, state)
}

/// Relative error of parameter `name` in a `parameters` list (results
/// message or state file).
fn relative_error(parameters: &serde_json::Value, name: &str, truth: f64) -> f64 {
    parameter(parameters, name)["value"].as_f64().unwrap() / truth - 1.0
}

#[test]
fn ambient_recording_to_oma_json_gives_the_model_modes() {
    let dir = fresh_dir("oma-ambient");
    let rec = dir.join("ambient.mcap");
    simulate(&rec, "ambient", "600", "4", &[]);
    let out = dir.join("modes.json");
    let o = splinewatch(&[
        "oma",
        "--config",
        "config/sinello.toml",
        rec.to_str().unwrap(),
        "--json",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    // The JSON contract: modes with these keys, shapes named by sensor.
    let value: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let first = &value["modes"][0];
    for key in [
        "frequency_hz",
        "damping_ratio",
        "frequency_std_hz",
        "damping_std",
        "shape",
    ] {
        assert!(first.get(key).is_some(), "missing {key} in {first}");
    }
    assert_eq!(first["shape"][0]["sensor"], "P1");
    assert!(first["shape"][0]["re"].is_number() && first["shape"][0]["im"].is_number());
    let file: ModesFile = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(file, ModesFile::read(&out).unwrap(), "--out holds the same modes");
    // 10 minutes: every bending mode below 80 Hz but possibly the closest
    // pair (73.49/73.99 Hz), each within 0.5 % and MAC > 0.9.
    let found = pairs(&file);
    for (f_model, f, value) in &found {
        assert!(*value > 0.9, "mode at {f} Hz pairs with {f_model} Hz at MAC {value}");
        assert!((f / f_model - 1.0).abs() < 0.005, "{f} Hz vs model {f_model} Hz");
    }
    // Each mode names the model mode nearest it by shape: this test's own
    // MAC against the bending modes is at most the CLI's over every
    // flexible mode, and equal where the nearest is a bending mode.
    // The update pairs them (MAC ≥ 0.8, within 10 %; a model mode claimed
    // twice by the closest pair goes to one).
    let mut paired = 0;
    for (m, (f_model, f, value)) in file.modes.iter().zip(&found) {
        let near = m.model.as_ref().expect("the bundled config has a model");
        assert!(near.mac >= value - 1e-9, "{f} Hz: {near:?} against MAC {value}");
        if (near.frequency_hz - f_model).abs() < 1e-9 * f_model {
            assert!((near.mac - value).abs() < 1e-9, "{f} Hz: {near:?} against MAC {value}");
        }
        if near.pairs {
            assert!(near.mac >= 0.8 && near.frequency_gap.abs() <= 0.1, "{f} Hz: {near:?}");
            paired += 1;
        }
    }
    assert!(paired >= 17, "{paired} modes pair: {file:?}");
    let distinct: std::collections::BTreeSet<u64> = found.iter().map(|p| p.0.to_bits()).collect();
    assert!(
        distinct.len() >= 17,
        "{} of 18 model modes found: {found:?}",
        distinct.len()
    );
    // --from/--to select a span: 5 minutes still give the lower modes.
    let rrd = dir.join("oma.rrd");
    let o = splinewatch(&[
        "oma",
        "--config",
        "config/sinello.toml",
        rec.to_str().unwrap(),
        "--from",
        "60",
        "--to",
        "360",
        "--rerun-save",
        rrd.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    // The Rerun file is finalised and holds the stabilisation diagram and the modes.
    let summary = splinewatch::outputs::rerun::inspect_rrd(&std::fs::read(&rrd).unwrap()).unwrap();
    assert!(summary.footer);
    for entity in [
        "/oma/stabilisation",
        "/oma/stabilisation/first_singular_value",
        "/oma/singular_values",
        "/oma/modes/1/frequency_hz",
        "/oma/modes/1/damping_percent",
    ] {
        assert!(
            summary.entities.contains(entity),
            "{entity} missing: {:?}",
            summary.entities
        );
    }
    assert!(
        stderr(&o).contains("76800 samples (300.0 s at 256 Hz)"),
        "{}",
        stderr(&o)
    );
    assert!(String::from_utf8_lossy(&o.stdout).contains("frequency Hz"));
}

#[test]
fn traffic_recording_gives_the_lower_modes() {
    let dir = fresh_dir("oma-traffic");
    let rec = dir.join("traffic.mcap");
    simulate(&rec, "traffic", "600", "2", &[]);
    let o = splinewatch(&[
        "oma",
        "--config",
        "config/sinello.toml",
        rec.to_str().unwrap(),
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let file: ModesFile = serde_json::from_slice(&o.stdout).unwrap();
    let good: Vec<(f64, f64, f64)> = pairs(&file).into_iter().filter(|p| p.2 > 0.9).collect();
    // Moving loads excite the lower modes best; the first three must be there.
    for f_model in model_modes().iter().take(3).map(|m| m.0) {
        let hit = good.iter().find(|p| p.0 == f_model);
        assert!(
            hit.is_some_and(|p| (p.1 / p.0 - 1.0).abs() < 0.005),
            "{f_model} Hz not identified: {good:?}"
        );
    }
}

#[test]
fn bad_oma_input_is_a_clear_error() {
    let dir = fresh_dir("oma-bad");
    let rec = dir.join("short.mcap");
    simulate(&rec, "ambient", "5", "0", &[]);
    let o = splinewatch(&["oma", "--config", "config/sinello.toml", rec.to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("too short"), "{}", stderr(&o));
    assert!(!stderr(&o).contains("panicked"));
    // A reference that is not an acceleration sensor, and a bad setting.
    let base = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("config/sinello.toml")).unwrap();
    for (extra, expected) in [
        ("\n[oma]\nreferences = [\"P99\"]\n", "oma.references"),
        (
            "\n[oma]\nmin_order = 50\nmax_order = 10\n",
            "min_order must not exceed max_order",
        ),
        ("\n[oma]\nblock_row = 4\n", "unknown field"),
    ] {
        let cfg = dir.join("bad.toml");
        std::fs::write(&cfg, format!("{base}{extra}")).unwrap();
        let o = splinewatch(&["oma", "--config", cfg.to_str().unwrap(), rec.to_str().unwrap()]);
        assert!(!o.status.success());
        assert!(stderr(&o).contains(expected), "{extra}: {}", stderr(&o));
    }
    // An output-only config runs in the daemon's pipeline: a recording
    // shorter than one (default 10-minute) window closes none, and says so.
    let cfg = dir.join("output-only.toml");
    std::fs::write(
        &cfg,
        base.replace(
            "quantity = [\"force\", \"acceleration\"]",
            "quantity = \"acceleration\"",
        ),
    )
    .unwrap();
    let r = splinewatch(&[
        "replay",
        "--config",
        cfg.to_str().unwrap(),
        rec.to_str().unwrap(),
        "--out",
        dir.join("r.mcap").to_str().unwrap(),
    ]);
    assert!(
        r.status.success() && stderr(&r).contains("0 windows (0 accepted), 0 updates"),
        "{}",
        stderr(&r)
    );
    let o = splinewatch(&["oma", "--config", "config/sinello.toml", "Cargo.toml"]);
    assert!(
        !o.status.success() && !stderr(&o).contains("panicked"),
        "{}",
        stderr(&o)
    );
}

/// Output-only updating end to end: 20 minutes of traffic, then of ambient
/// data of the deck with `east.k2` at 60 % (the bundled bearing-damage
/// scenario's loss, here from the start) → `oma --out` → `update --modes`:
/// from the undamaged config values `east.k2` is found within 10 % of its
/// new value and every other κ within 15 % (the issue's targets; reached:
/// see the guide). Traffic's spurious modes (43 and 49 Hz, ζ 4–5 %) stay
/// unpaired thanks to the frequency gate.
#[test]
fn oma_then_update_modes_finds_the_bearing_loss() {
    let dir = fresh_dir("oma-update");
    let scenario = loss_scenario(&dir, -1.0, 0.0, 1200.0);
    let modes = dir.join("modes.json");
    for excitation in ["traffic", "ambient"] {
        let rec = dir.join(format!("{excitation}.mcap"));
        simulate(
            &rec,
            excitation,
            "1200",
            "5",
            &["--scenario", scenario.to_str().unwrap()],
        );
        let o = splinewatch(&[
            "oma",
            "--config",
            "config/sinello.toml",
            rec.to_str().unwrap(),
            "--out",
            modes.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let u = splinewatch(&[
            "update",
            "--config",
            "config/sinello.toml",
            "--modes",
            modes.to_str().unwrap(),
            "--json",
        ]);
        assert!(u.status.success(), "{}", stderr(&u));
        let result: serde_json::Value = serde_json::from_slice(&u.stdout).unwrap();
        for (name, value) in DAMAGED_KAPPA {
            let error = relative_error(&result["parameters"], name, value);
            let allowed = if name == "east.k2" { 0.10 } else { 0.15 };
            assert!(error.abs() < allowed, "{excitation}: {name}: {:+.1} %", 100.0 * error);
        }
        assert_eq!(result["converged"], true, "{excitation}");
    }
    // The table names the pairs.
    let t = splinewatch(&[
        "update",
        "--config",
        "config/sinello.toml",
        "--modes",
        modes.to_str().unwrap(),
    ]);
    assert!(String::from_utf8_lossy(&t.stdout).contains("paired modes"));
    // --frf and --modes exclude each other; a modes file naming an unknown sensor is an error.
    let both = splinewatch(&[
        "update",
        "--config",
        "config/sinello.toml",
        "--modes",
        "x.json",
        "--frf",
        "y.json",
    ]);
    assert!(!both.status.success());
    let bad = dir.join("bad.json");
    std::fs::write(
        &bad,
        std::fs::read_to_string(&modes).unwrap().replace("\"P3\"", "\"P99\""),
    )
    .unwrap();
    let b = splinewatch(&[
        "update",
        "--config",
        "config/sinello.toml",
        "--modes",
        bad.to_str().unwrap(),
    ]);
    assert!(!b.status.success() && stderr(&b).contains("P99"), "{}", stderr(&b));
}

/// The monitoring pipeline output-only (`replay` of an output-only config,
/// the daemon's code path): 40 minutes of ambient data where `east.k2` loses
/// 40 % between minutes 19 and 20, in 10-minute windows, each identified
/// and updated (warm-started). Before the loss `east.k2` stays within 10 %
/// of its value, after it within 10 % of the new one, every other κ within
/// 15 % throughout; every window publishes `oma/modes` with its pairing.
#[test]
fn output_only_replay_follows_the_bearing_damage() {
    let dir = fresh_dir("oma-replay");
    let scenario = loss_scenario(&dir, 19.0, 20.0, 30.0);
    let rec = dir.join("ambient.mcap");
    simulate(
        &rec,
        "ambient",
        "2400",
        "7",
        &["--scenario", scenario.to_str().unwrap()],
    );
    let (results, _) = replay_output_only(&dir, &rec, 600.0, "");
    let by_topic = results_by_topic(&std::fs::read(&results).unwrap());
    assert!(!by_topic.contains_key("frf/measured") && !by_topic.contains_key("frf/model"));
    let windows = &by_topic["windows"];
    assert_eq!(windows.len(), 4);
    assert!(windows
        .iter()
        .all(|w| w["skipped"].is_null() && w["valid_fraction"] == 1.0));
    let identified = &by_topic["oma/modes"];
    assert_eq!(identified.len(), 4);
    for w in identified {
        let modes = w["modes"].as_array().unwrap();
        let paired = modes.iter().filter(|m| m["model_mode"].is_u64()).count();
        assert!(
            paired >= 15,
            "window {}: {paired} of {} modes paired",
            w["window"],
            modes.len()
        );
        for m in modes.iter().filter(|m| m["model_mode"].is_u64()) {
            assert!(m["mac"].as_f64().unwrap() >= 0.8);
            assert!(m["frequency_std_hz"].as_f64().unwrap() > 0.0);
            assert_eq!(m["shape"].as_array().unwrap().len(), 12);
        }
    }
    // Saved as a file, an oma/modes message is an `update --modes` input.
    let file: ModesFile = serde_json::from_value(identified[0].clone()).unwrap();
    file.check().unwrap();
    let residue = &by_topic["updating/residue"];
    assert!(residue.iter().all(|r| r["modes"].as_array().unwrap().len() >= 15));
    let updates = &by_topic["updating/parameters"];
    assert_eq!(updates.len(), 4);
    let truth = [
        ("west.k1", 0.4e9),
        ("west.k2", 1.5e9),
        ("west.k3", 1.8e9),
        ("west.k4", 0.6e9),
        ("east.k1", 1.5e9),
        ("east.k3", 0.5e9),
        ("east.k4", 1.8e9),
    ];
    for (k, u) in updates.iter().enumerate() {
        assert_eq!(u["converged"], true);
        let value = |name: &str| parameter(&u["parameters"], name)["value"].as_f64().unwrap();
        let k2 = if k < 2 { 0.4e9 } else { 0.24e9 };
        let error = value("east.k2") / k2 - 1.0;
        assert!(error.abs() < 0.10, "window {k}: east.k2 {:+.1} %", 100.0 * error);
        for (name, v) in truth {
            let error = value(name) / v - 1.0;
            assert!(error.abs() < 0.15, "window {k}: {name} {:+.1} %", 100.0 * error);
        }
    }
}

/// Traffic (12 vehicles a minute, two lanes) needs longer windows than
/// ambient excitation: one 60-minute window of a deck whose `east.k2` lost
/// 40 % before the record, updated from the undamaged config values,
/// finds `east.k2` within 10 % and every other κ within 15 % (the guide
/// gives the seeds and the 30-minute figures).
#[test]
fn output_only_replay_of_traffic_in_an_hour_window_finds_the_loss() {
    let dir = fresh_dir("oma-traffic-replay");
    let scenario = loss_scenario(&dir, -1.0, 0.0, 3600.0);
    let rec = dir.join("traffic.mcap");
    simulate(
        &rec,
        "traffic",
        "3600",
        "8",
        &["--scenario", scenario.to_str().unwrap()],
    );
    let (_, state) = replay_output_only(&dir, &rec, 3600.0, "");
    let accepted: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&state).unwrap()).unwrap();
    for (name, value) in DAMAGED_KAPPA {
        let error = relative_error(&accepted["parameters"], name, value);
        let allowed = if name == "east.k2" { 0.10 } else { 0.15 };
        assert!(error.abs() < allowed, "{name}: {:+.1} %", 100.0 * error);
    }
}

/// Output-only monitoring: 16 ambient windows of 150 s on the undamaged
/// deck, the first 10 train. Every window's features are the 15 updated
/// parameters and one identified frequency per model bending mode in the
/// band (`mode_<n>_frequency_hz`, `null` where that mode was not identified:
/// short windows miss some); the reference keeps those identified in ≥ 80 %
/// of the training windows, a later window missing one is scored on the
/// others (flagged), no alarm; `splinewatch monitor` re-makes the statuses
/// bit for bit, nulls included.
#[test]
fn output_only_monitoring_scores_the_identified_frequencies() {
    let dir = fresh_dir("oma-monitoring");
    let rec = dir.join("ambient.mcap");
    simulate(&rec, "ambient", "2400", "7", &[]);
    let (results, _) = replay_output_only(&dir, &rec, 150.0, "\n[monitoring]\ntraining_windows = 10\n");
    let statuses = |path: &Path| -> Vec<Vec<u8>> {
        let bytes = std::fs::read(path).unwrap();
        mcap::MessageStream::new(&bytes)
            .unwrap()
            .map(Result::unwrap)
            .filter(|m| m.channel.topic.ends_with("monitoring/status"))
            .map(|m| m.data.into_owned())
            .collect()
    };
    let raw = statuses(&results);
    assert_eq!(raw.len(), 16);
    let parsed: Vec<serde_json::Value> = raw.iter().map(|m| serde_json::from_slice(m).unwrap()).collect();
    let names: Vec<&str> = parsed[0]["features"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["name"].as_str().unwrap())
        .collect();
    let frequencies: Vec<String> = (1..=18).map(|n| format!("mode_{n}_frequency_hz")).collect();
    assert_eq!(names.len(), 15 + 18);
    assert_eq!(&names[15..], frequencies.iter().map(String::as_str).collect::<Vec<_>>());
    let gaps = parsed
        .iter()
        .flat_map(|s| s["features"].as_array().unwrap().iter())
        .filter(|f| f["value"].is_null())
        .count();
    assert!(
        gaps > 0,
        "every mode identified in every window: nothing missing to test"
    );
    let (mut flagged, mut scored_frequencies) = (0, 0);
    for s in &parsed[10..] {
        assert_eq!(s["state"], "normal", "{s}");
        assert!(s["t2"].as_f64().unwrap().is_finite() && s["mewma"].as_f64().unwrap().is_finite());
        let residuals = s["residuals"].as_array().unwrap();
        scored_frequencies += residuals
            .iter()
            .filter(|r| r["name"].as_str().unwrap().starts_with("mode_"))
            .count();
        flagged += usize::from(
            s["flags"]
                .as_array()
                .unwrap()
                .iter()
                .any(|f| f.as_str().unwrap().starts_with("feature_missing:mode_")),
        );
    }
    assert!(
        scored_frequencies >= 6 * 12,
        "{scored_frequencies} frequency residuals in 6 windows"
    );
    assert!(flagged >= 1, "no scored window missed a kept frequency");
    let rescored = dir.join("rescored.mcap");
    let o = splinewatch(&[
        "monitor",
        "--config",
        dir.join("output-only.toml").to_str().unwrap(),
        results.to_str().unwrap(),
        "--out",
        rescored.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(statuses(&rescored), raw);
}

/// Issue 30: the bundled overpass (nine patches, 5 740 dofs, the sparse
/// path below 40 Hz) under ambient excitation for 40 minutes, its three
/// bent bearings 50 % stiffer vertically from minute 20
/// (`config/scenarios/overpass-bent-stiffening.toml`): `replay` identifies
/// the modes below 20 Hz in each 20-minute window, pairs them with the
/// model's and updates the bent's nine stiffnesses from the config's
/// values. Each bent bearing's `kz` is found within 8 % of 2e9 N/m in the
/// first window and of 3e9 in the second (measured: 1–6 %, σ about 1.5 %).
#[test]
fn the_overpass_replay_finds_its_bent_bearings_stiffening() {
    let dir = fresh_dir("issue_30_overpass");
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let (config, scenario) = (
        root.join("config/overpass.toml"),
        root.join("config/scenarios/overpass-bent-stiffening.toml"),
    );
    let (rec, results) = (dir.join("overpass.mcap"), dir.join("results.mcap"));
    let o = splinewatch(&[
        "simulate",
        "--config",
        config.to_str().unwrap(),
        "--excitation",
        "ambient",
        "--duration",
        "2400",
        "--scenario",
        scenario.to_str().unwrap(),
        "--out",
        rec.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = splinewatch(&[
        "replay",
        "--config",
        config.to_str().unwrap(),
        rec.to_str().unwrap(),
        "--out",
        results.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut by_topic = results_by_topic(&std::fs::read(&results).unwrap());
    let updates = by_topic.remove("updating/parameters").unwrap_or_default();
    let identified = by_topic.remove("oma/modes").unwrap_or_default();
    assert_eq!(updates.len(), 2, "one update per 20-minute window");
    for w in &identified {
        let paired = w["modes"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|m| m["model_mode"].is_u64())
            .count();
        assert!(paired >= 8, "window {}: {paired} modes paired", w["window"]);
    }
    for (u, truth) in updates.iter().zip([2e9, 3e9]) {
        assert_eq!(u["converged"], true, "{u}");
        for name in ["bent_south.kz", "bent_middle.kz", "bent_north.kz"] {
            let p = parameter(&u["parameters"], name);
            let error = p["value"].as_f64().unwrap() / truth - 1.0;
            assert!(
                error.abs() < 0.08,
                "window {}: {name} {:+.1} % of {truth:e}",
                u["window"],
                100.0 * error
            );
        }
    }
}

/// Issue 33: `oma` needs no model. A config of `[structure]` and the
/// bundled sensors only identifies the same modes, bit for bit, as the
/// bundled config on the same ambient recording; `modes` on it says there
/// is no deck.
#[test]
fn issue_33_oma_runs_on_a_config_without_a_model() {
    let dir = fresh_dir("oma-no-model");
    let rec = dir.join("ambient.mcap");
    simulate(&rec, "ambient", "300", "5", &[]);
    let bundled = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("config/sinello.toml")).unwrap();
    let sensors: String = bundled
        .split("\n[[sensors]]")
        .skip(1)
        .map(|s| format!("\n[[sensors]]{}", s.split("\n[").next().unwrap()))
        .collect();
    let config = dir.join("sensors-only.toml");
    std::fs::write(&config, format!("[structure]\nname = \"sinello-span2\"\n{sensors}")).unwrap();
    let identify = |cfg: &str| {
        let o = splinewatch(&["oma", "--config", cfg, rec.to_str().unwrap(), "--json"]);
        assert!(o.status.success(), "{cfg}: {}", stderr(&o));
        o.stdout
    };
    let without = identify(config.to_str().unwrap());
    let with = identify("config/sinello.toml");
    let file: ModesFile = serde_json::from_slice(&without).unwrap();
    assert!(file.modes.len() >= 10, "{} modes", file.modes.len());
    assert!(file.modes.iter().all(|m| m.model.is_none()), "no model, no match");
    // With the model, each mode also names its nearest model mode; the
    // identification is the same, bit for bit.
    let mut compared: ModesFile = serde_json::from_slice(&with).unwrap();
    for mode in &mut compared.modes {
        assert!(mode.model.take().is_some(), "the bundled config has a model");
    }
    assert_eq!(file, compared, "the model plays no part in the identification");
    let o = splinewatch(&["modes", "--config", config.to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("model: no deck"), "{}", stderr(&o));
    let o = splinewatch(&["check-config", config.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = String::from_utf8(o.stdout).unwrap();
    assert!(text.contains("no model: 12 sensors"), "{text}");
}
