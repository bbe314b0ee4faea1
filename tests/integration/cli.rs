//! End-to-end tests of the `splinewatch` binary on the bundled configuration.

use crate::common::{fresh_dir, parameter, splinewatch};
use std::path::{Path, PathBuf};

/// Writes a test input into the test's folder.
fn temp_config(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn modes_json_on_the_bundled_config() {
    let out = splinewatch(&["modes", "--config", "config/sinello.toml", "--count", "30", "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let modes = v["modes"].as_array().unwrap();
    assert_eq!(modes.len(), 30);
    assert_eq!(modes[0]["index"], 1);
    let kinds: Vec<&str> = modes.iter().map(|m| m["kind"].as_str().unwrap()).collect();
    assert_eq!(kinds.iter().filter(|k| **k == "rigid").count(), 3);
    assert_eq!(kinds.iter().filter(|k| **k == "bending").count(), 18);
    let f: Vec<f64> = modes.iter().map(|m| m["frequency_hz"].as_f64().unwrap()).collect();
    assert!(f.windows(2).all(|w| w[0] <= w[1]));
    assert!(f[29] < 80.0 && f[3] > 1.0);
    // Where each mode moves: on this flat deck (normal z) a bending mode's
    // translational energy is along z, a membrane mode's in the plane; the
    // shares sum to 1.
    for m in &modes[3..] {
        let shares: Vec<f64> = m["translation_shares"]
            .as_array()
            .unwrap()
            .iter()
            .map(|s| s.as_f64().unwrap())
            .collect();
        assert!((shares.iter().sum::<f64>() - 1.0).abs() < 1e-12, "{m}");
        let vertical = shares[2] > 0.5;
        assert_eq!(vertical, m["kind"] == "bending", "{m}");
        // Named by where it moves the deck: a bending mode of this flat
        // deck bends or twists it, a membrane mode moves it in its plane.
        let motion = &m["motion_shares"];
        let sum: f64 = ["longitudinal", "transverse", "vertical", "torsion"]
            .iter()
            .map(|k| motion[k].as_f64().unwrap())
            .sum();
        assert!((sum - 1.0).abs() < 1e-12, "{m}");
        let named = m["motion"].as_str().unwrap();
        assert_eq!(["vertical", "torsion"].contains(&named), m["kind"] == "bending", "{m}");
    }
}

/// On the bundled overpass (a box girder along x) the first mode named
/// vertical and the first named transverse are the ones the shapes say:
/// the vertical one's translational energy is almost all along z, the
/// transverse one's mostly along y, and no earlier mode moves more along
/// its axis.
#[test]
fn modes_of_the_overpass_name_its_first_vertical_and_transverse_modes() {
    let out = splinewatch(&["modes", "--config", "config/overpass.toml", "--count", "8", "--json"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let modes = v["modes"].as_array().unwrap();
    let first = |motion: &str| modes.iter().position(|m| m["motion"] == motion).unwrap();
    let share = |i: usize, axis: usize| modes[i]["translation_shares"][axis].as_f64().unwrap();
    let (vertical, transverse) = (first("vertical"), first("transverse"));
    assert_eq!(vertical, 0, "{v}");
    assert!(share(vertical, 2) > 0.9, "{v}");
    assert!(share(transverse, 1) > 0.5, "{v}");
    assert!((0..transverse).all(|i| share(i, 1) < share(transverse, 1)), "{v}");
    // The shapes at the sensors say the same: the vertical mode's largest
    // component (1) on a vertical sensor and its two transverse sensors
    // nearly still (measured 0.010 and 0.015); the transverse mode moves a
    // transverse sensor as much as any (measured 0.96; its largest, 1, is a
    // vertical sensor on the deck's edge: the mode twists the box).
    let shape = |i: usize| -> Vec<(String, f64)> {
        modes[i]["shape"]
            .as_array()
            .unwrap()
            .iter()
            .map(|e| (e["sensor"].as_str().unwrap().to_string(), e["re"].as_f64().unwrap()))
            .collect()
    };
    let across = |i: usize| {
        shape(i)
            .into_iter()
            .filter(|(s, _)| s.contains("transverse"))
            .fold(0.0f64, |m, (_, x)| m.max(x.abs()))
    };
    let largest = shape(vertical)
        .into_iter()
        .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
        .unwrap();
    assert_eq!(shape(vertical).len(), 8, "{v}");
    assert_eq!(largest.1, 1.0, "{v}");
    assert!(!largest.0.contains("transverse"), "{v}");
    assert!(across(vertical) < 0.1, "{v}");
    assert!(across(transverse) > 0.5, "{v}");
}

/// A support's share of a mode's strain energy is `(dω²/dα) / ω²` with its
/// coefficients scaled by α, at α = 1 (`K` is linear in κ, so the share is
/// exactly that sensitivity): checked against central differences of the
/// frequencies `modes --json` prints with the west spring field scaled by
/// 1 ± 1e-3 (truncation error ~1e-7 of the share; tolerance 1e-6).
#[test]
fn support_shares_are_the_frequencies_sensitivity_to_the_support() {
    let dir = fresh_dir("support-shares");
    let good = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/config/sinello.toml")).unwrap();
    let west = "stiffness = [0.4e9, 1.5e9, 1.8e9, 0.6e9]";
    assert!(good.contains(west));
    let modes = |text: &str, name: &str| -> Vec<serde_json::Value> {
        let path = temp_config(&dir, name, text);
        let out = splinewatch(&["modes", "--config", path.to_str().unwrap(), "--count", "14", "--json"]);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        v["modes"].as_array().unwrap().clone()
    };
    let scaled = |factor: f64| {
        let k: Vec<String> = [0.4e9, 1.5e9, 1.8e9, 0.6e9]
            .iter()
            .map(|k| format!("{:e}", k * factor))
            .collect();
        good.replace(west, &format!("stiffness = [{}]", k.join(", ")))
    };
    let h = 1e-3;
    let (base, up, down) = (
        modes(&good, "base.toml"),
        modes(&scaled(1.0 + h), "up.toml"),
        modes(&scaled(1.0 - h), "down.toml"),
    );
    let f = |m: &[serde_json::Value], i: usize| m[i]["frequency_hz"].as_f64().unwrap();
    for i in 3..base.len() {
        let shares = base[i]["support_shares"].as_array().unwrap();
        assert_eq!(shares[0]["support"], "west", "{}", base[i]);
        let west = shares[0]["share"].as_f64().unwrap();
        let fd = (f(&up, i).powi(2) - f(&down, i).powi(2)) / (2.0 * h * f(&base, i).powi(2));
        assert!(
            (west - fd).abs() < 1e-6,
            "mode {}: share {west}, central difference {fd}",
            i + 1
        );
        let total: f64 = shares.iter().map(|s| s["share"].as_f64().unwrap()).sum();
        assert!((0.0..1.0).contains(&total) && west >= 0.0, "{}", base[i]);
    }
    // A loss factor η on the west field adds ½ η × its share to every
    // mode's ζ (modal strain energy), the curve's ζ(f_i) unchanged.
    let lossy = modes(
        &good.replacen(
            "bounds = [1.0e7, 5.0e9]",
            "bounds = [1.0e7, 5.0e9]\nloss_factor = 0.3",
            1,
        ),
        "lossy.toml",
    );
    let zeta = |m: &[serde_json::Value], i: usize| m[i]["damping_ratio"].as_f64().unwrap();
    for i in 3..base.len() {
        let west = base[i]["support_shares"][0]["share"].as_f64().unwrap();
        let added = zeta(&lossy, i) - zeta(&base, i);
        assert!(
            (added - 0.15 * west).abs() < 1e-12,
            "mode {}: ζ grew by {added}, ½ η e = {}",
            i + 1,
            0.15 * west
        );
    }
    assert!((3..base.len()).any(|i| zeta(&lossy, i) > zeta(&base, i) + 0.01));
}

/// The sparse path on a model too small for a Krylov subspace of the modes
/// wanted (Sinello below 400 Hz: most of its modes) solves them densely
/// instead of failing, and agrees with the dense path.
#[test]
fn the_sparse_path_answers_for_a_small_model_and_a_high_cutoff() {
    let frequencies = |extra: &[&str]| -> Vec<f64> {
        let mut args = vec!["modes", "--config", "config/sinello.toml", "--count", "20", "--json"];
        args.extend_from_slice(extra);
        let out = splinewatch(&args);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        v["modes"]
            .as_array()
            .unwrap()
            .iter()
            .map(|m| m["frequency_hz"].as_f64().unwrap())
            .collect()
    };
    let (dense, sparse) = (frequencies(&[]), frequencies(&["--cutoff", "400"]));
    assert_eq!(dense.len(), sparse.len());
    for (d, s) in dense.iter().zip(&sparse).skip(3) {
        assert!((d - s).abs() <= 1e-6 * d, "dense {d} Hz, sparse {s} Hz");
    }
}

#[test]
fn modes_table_is_human_readable() {
    let out = splinewatch(&["modes", "--config", "config/sinello.toml", "--count", "5"]);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 6);
    assert!(
        lines[0].contains("frequency Hz") && lines[0].ends_with("long %  tran %  vert %  tors %  supp %     ζ %"),
        "{text}"
    );
    // Mode 4, the first bending mode: all of it vertical; mode 5 twists
    // the deck.
    assert!(
        lines[4].trim_start().starts_with('4')
            && lines[4].contains("bending   vertical")
            && lines[4].contains("0       0     100       0  "),
        "{text}"
    );
    assert!(lines[5].contains("bending   torsion"), "{text}");
}

#[test]
fn bad_config_is_a_clear_error_not_a_panic() {
    let dir = fresh_dir("cli");
    let good = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/config/sinello.toml")).unwrap();
    let west_bounds = "bounds = [1.0e7, 5.0e9]";
    let cases = [
        (
            "negative-thickness.toml",
            good.replace("thickness = 1.6", "thickness = -1.6"),
            "thickness",
        ),
        (
            "negative-loss-factor.toml",
            good.replacen(west_bounds, &format!("{west_bounds}\nloss_factor = -0.1"), 1),
            "model.springs[0].loss_factor: -0.1 must be a finite loss factor >= 0",
        ),
        (
            "loss-factor-outside-bounds.toml",
            good.replacen(
                west_bounds,
                &format!("{west_bounds}\nloss_factor = {{ value = 0.7, bounds = [0.0, 0.5] }}"),
                1,
            ),
            "model.springs[0].loss_factor: value 0.7 lies outside its bounds [0, 0.5]",
        ),
        (
            "unknown-key.toml",
            good.replace("[model.material]", "[model.material]\nyoung = 1.0"),
            "unknown field `young`",
        ),
        (
            "knots.toml",
            good.replacen(
                "[0.0, 0.0, 0.0, 0.5, 1.0, 1.0, 1.0]",
                "[0.0, 0.0, 0.0, 0.7, 0.5, 1.0, 1.0, 1.0]",
                1,
            ),
            "model.springs[0].knots_eta: not non-decreasing at index 4",
        ),
        ("not-toml.toml", "this is = = not toml".to_string(), "line 1"),
        (
            "hop-longer-than-window.toml",
            good.replace(
                "window_seconds = 20.0",
                "window_seconds = 20.0\nwindow_hop_seconds = 30.0",
            ),
            "frf.window_hop_seconds: must be between one sample and frf.window_seconds (20 s), got 30",
        ),
        (
            "quic-endpoint.toml",
            good.clone() + "\n[zenoh]\nlisten = [\"quic/127.0.0.1:7447\"]\n",
            "zenoh.listen[0]: \"quic/127.0.0.1:7447\": this build speaks zenoh over TCP and TLS only",
        ),
    ];
    for (name, text, expected) in cases {
        let path = temp_config(&dir, name, &text);
        for args in [
            vec!["modes", "--config", path.to_str().unwrap()],
            vec!["check-config", path.to_str().unwrap()],
        ] {
            let out = splinewatch(&args);
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(1), "{name}: {stderr}");
            assert!(stderr.contains(expected), "{name}: {stderr}");
            assert!(!stderr.contains("panicked"), "{name}: {stderr}");
        }
    }
}

/// Each kind of error a newcomer met names the key (or the file), once:
/// a value of the wrong type, an unknown key (with its section), a geometry
/// error, no doubled `invalid config file …: config:` prefix, and `replay`
/// on a file that is not MCAP.
#[test]
fn config_errors_name_the_key_path() {
    let dir = fresh_dir("cli");
    let good = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/config/sinello.toml")).unwrap();
    let cases = [
        (
            "wrong-type.toml",
            good.replace("density = ", "density = \"975\" # was "),
            "config: model.material.density: invalid type: string \"975\", expected f64 (line ",
        ),
        (
            "unknown-key-section.toml",
            good.replace("[model.material]", "[model.material]\nyoung = 1.0"),
            "config: model.material.young: unknown field `young`, expected one of `e1`",
        ),
        (
            "thickness.toml",
            good.replace("thickness = 1.6", "thickness = -1.6"),
            "config: model.geometry.thickness: thickness must be finite and positive, got -1.6",
        ),
        (
            "spring-type.toml",
            good.replacen("degree_xi = 0", "degree_xi = \"zero\"", 1),
            "config: model.springs[0].degree_xi: invalid type: string \"zero\"",
        ),
    ];
    for (name, text, expected) in cases {
        assert_ne!(text, good, "{name}: the edit did not apply");
        let path = temp_config(&dir, name, &text);
        let out = splinewatch(&["check-config", path.to_str().unwrap()]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{name}: {stderr}");
        assert!(
            stderr.starts_with(&format!("error: {}: config: ", path.display())),
            "{name}: {stderr}"
        );
        assert!(stderr.contains(expected), "{name}: {stderr}");
        assert_eq!(stderr.matches("config:").count(), 1, "{name}: doubled prefix: {stderr}");
        assert!(!stderr.contains("invalid config file"), "{name}: {stderr}");
    }
    let not_mcap = temp_config(&dir, "not-a-recording.mcap", "hello");
    let out = splinewatch(&["replay", "--config", "config/sinello.toml", not_mcap.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains(&format!("{} is not an MCAP file", not_mcap.display())),
        "{stderr}"
    );
}

#[test]
fn check_config_validates_the_zenoh_settings_too() {
    let dir = fresh_dir("cli");
    let good = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/config/sinello.toml")).unwrap();
    let missing = temp_config(
        &dir,
        "zenoh-file-missing.toml",
        &(good.clone() + "\n[zenoh]\nconfig_file = \"/nonexistent/zenoh.json5\"\n"),
    );
    let out = splinewatch(&["check-config", missing.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("zenoh.config_file /nonexistent/zenoh.json5"),
        "{stderr}"
    );
    // The example site configuration passes.
    let example = concat!(env!("CARGO_MANIFEST_DIR"), "/config/zenoh/splinewatch-client.json5");
    let ok = temp_config(
        &dir,
        "zenoh-example.toml",
        &(good
            + &format!(
                "\n[zenoh]\nmode = \"client\"\nconnect = [\"tcp/192.0.2.10:7447\"]\nconfig_file = {example:?}\n"
            )),
    );
    let out = splinewatch(&["check-config", ok.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
}

#[test]
fn synth_then_update_round_trip_json() {
    let dir = fresh_dir("cli-rt");
    let frf = dir.join("frf.json");
    let out = splinewatch(&[
        "synth",
        "--config",
        "config/sinello-truth.toml",
        "--inputs",
        "P1",
        "--outputs",
        "P1,P2,P3,P4",
        "--from",
        "1",
        "--to",
        "60",
        "--step",
        "0.25",
        "--out",
        frf.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let out = splinewatch(&[
        "update",
        "--config",
        "config/sinello.toml",
        "--frf",
        frf.to_str().unwrap(),
        "--json",
    ]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("iteration   0"), "progress lines: {stderr}");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["converged"], true);
    let params = v["parameters"].as_array().unwrap();
    assert_eq!(params.len(), 15);
    assert_eq!(params[0]["name"], "west.k1");
    assert_eq!(params[14]["name"], "damping.g7");
    for p in params {
        assert!(p["value"].is_f64() && p["lower"].is_f64() && p["upper"].is_f64() && p["std"].is_f64());
    }
    assert!(v["iterations"][0]["relative_residual"].is_f64());
    assert!(v["relative_residual"].as_f64().unwrap() < 0.01);
    // Warm start from the result: converges again, in fewer iterations.
    let start = dir.join("result.json");
    std::fs::write(&start, &out.stdout).unwrap();
    let again = splinewatch(&[
        "update",
        "--config",
        "config/sinello.toml",
        "--frf",
        frf.to_str().unwrap(),
        "--start",
        start.to_str().unwrap(),
        "--json",
    ]);
    assert!(again.status.success());
    let w: serde_json::Value = serde_json::from_slice(&again.stdout).unwrap();
    assert!(w["iterations"].as_array().unwrap().len() < v["iterations"].as_array().unwrap().len());
}

#[test]
fn bad_frf_files_are_clear_errors_not_panics() {
    let dir = fresh_dir("cli-bad");
    let good = serde_json::json!({
        "quantity": "accelerance",
        "frequency_hz": [1.0, 2.0, 3.0],
        "frfs": [{"input": "P1", "output": "P2", "re": [0.1, 0.2, 0.3], "im": [0.0, 0.1, 0.2]}]
    });
    let variant = |f: &dyn Fn(&mut serde_json::Value)| {
        let mut v = good.clone();
        f(&mut v);
        v.to_string()
    };
    let cases: Vec<(&str, String, &str)> = vec![
        (
            "unknown-sensor",
            variant(&|v| v["frfs"][0]["output"] = "P99".into()),
            "unknown sensor \"P99\"",
        ),
        (
            "lengths",
            variant(&|v| v["frfs"][0]["re"] = serde_json::json!([0.1, 0.2])),
            "re has 2 values, im has 3",
        ),
        (
            "freq-lengths",
            variant(&|v| v["frequency_hz"] = serde_json::json!([1.0, 2.0])),
            "has 3 values, frequency_hz has 2",
        ),
        (
            "non-increasing",
            variant(&|v| v["frequency_hz"] = serde_json::json!([1.0, 3.0, 2.0])),
            "not strictly increasing at index 2",
        ),
        (
            "empty-band",
            variant(&|v| v["frequency_hz"] = serde_json::json!([90.0, 91.0, 92.0])),
            "no frequency line is left",
        ),
        ("nan", good.to_string().replace("0.2]", "NaN]"), "not valid FRF JSON"),
        (
            "infinite",
            good.to_string().replace("0.3]", "1e999]"),
            "not valid FRF JSON",
        ),
        (
            "quantity",
            variant(&|v| v["quantity"] = "compliance".into()),
            "unknown variant `compliance`",
        ),
        ("not-json", "{{{".to_string(), "not valid FRF JSON"),
    ];
    for (name, text, expected) in cases {
        let path = dir.join(format!("{name}.json"));
        std::fs::write(&path, text).unwrap();
        let out = splinewatch(&[
            "update",
            "--config",
            "config/sinello.toml",
            "--frf",
            path.to_str().unwrap(),
        ]);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{name}: {stderr}");
        assert!(stderr.contains(expected), "{name}: expected {expected:?} in {stderr}");
        assert!(!stderr.contains("panicked"), "{name}: {stderr}");
    }
}

/// Issue 30: a deck of several patches. `check-config` lists the bundled
/// overpass's patches and the 14 joints it finds (seven webs under the top
/// slab and on the soffit); `modes` on a slab on two webs with no sensor
/// lists its joints on stderr and its modes on stdout.
#[test]
fn issue_30_decks_of_several_patches_list_their_joints() {
    let out = splinewatch(&["check-config", "config/overpass.toml"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = String::from_utf8(out.stdout).unwrap();
    assert_eq!(text.lines().filter(|l| l.starts_with("patch ")).count(), 9, "{text}");
    let joints: Vec<&str> = text.lines().filter(|l| l.starts_with("joint: ")).collect();
    assert_eq!(joints.len(), 14, "{text}");
    assert!(
        joints.contains(&"joint: web_4 edge eta0 on top_slab, 80.800 m"),
        "{text}"
    );

    let dir = fresh_dir("issue_30_modes");
    let deck =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/slab_on_webs.toml")).unwrap();
    let no_sensors = deck.split("[[sensors]]").next().unwrap();
    let path = temp_config(&dir, "deck.toml", no_sensors);
    let out = splinewatch(&["modes", "--config", path.to_str().unwrap(), "--count", "6", "--json"]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains("joint: web_south edge eta0 on slab, 20.000 m"),
        "{stderr}"
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let f: Vec<f64> = v["modes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["frequency_hz"].as_f64().unwrap())
        .collect();
    assert_eq!(f.len(), 6);
    assert!(f[0] > 1.0 && f.windows(2).all(|w| w[0] <= w[1]), "{f:?}");
}

/// Issue 30: FRF updating on a deck of several patches. The slab on two webs
/// with its first bearing stiffened from 2e9 to 3e9 N/m vertically: `synth`
/// (1 % noise) then `update` from the config's values finds `west_south.kz`
/// within 0.5 % and keeps the horizontal stiffnesses near their value.
#[test]
fn issue_30_a_stiffened_bearing_is_found_on_a_deck_of_patches() {
    let dir = fresh_dir("issue_30_bearing");
    let start = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/fixtures/slab_on_webs_measured.toml"
    ))
    .unwrap();
    let truth = start.replacen(
        "stiffness = [1e8, 1e8, 2e9]\nbounds",
        "stiffness = [1e8, 1e8, 3e9]\nbounds",
        1,
    );
    assert_ne!(truth, start);
    let (start, truth) = (
        temp_config(&dir, "start.toml", &start),
        temp_config(&dir, "truth.toml", &truth),
    );
    let frf = dir.join("frf.json");
    let out = splinewatch(&[
        "synth",
        "--config",
        truth.to_str().unwrap(),
        "--inputs",
        "P1",
        "--outputs",
        "P1,P2,P3,P4",
        "--from",
        "2",
        "--to",
        "40",
        "--step",
        "0.1",
        "--noise",
        "0.01",
        "--seed",
        "3",
        "--out",
        frf.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let out = splinewatch(&[
        "update",
        "--config",
        start.to_str().unwrap(),
        "--frf",
        frf.to_str().unwrap(),
        "--json",
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let value = |name: &str| parameter(&v["parameters"], name)["value"].as_f64().unwrap();
    assert_eq!(v["converged"], true);
    assert!((value("west_south.kz") / 3e9 - 1.0).abs() < 5e-3, "{v}");
    assert!((value("west_south.kx") / 1e8 - 1.0).abs() < 0.02, "{v}");
}
