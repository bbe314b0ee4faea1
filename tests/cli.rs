//! End-to-end tests of the `splinewatch` binary on the bundled configuration.

use std::path::PathBuf;
use std::process::{Command, Output};

fn splinewatch(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_splinewatch"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("the binary runs")
}

fn temp_config(name: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("splinewatch-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
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
}

#[test]
fn modes_table_is_human_readable() {
    let out = splinewatch(&["modes", "--config", "config/sinello.toml", "--count", "5"]);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 6);
    assert!(lines[0].contains("frequency Hz"));
    assert!(lines[4].trim_start().starts_with('4') && lines[4].ends_with("bending"));
}

#[test]
fn bad_config_is_a_clear_error_not_a_panic() {
    let good = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/config/sinello.toml")).unwrap();
    let cases = [
        (
            "negative-thickness.toml",
            good.replace("thickness = 1.6", "thickness = -1.6"),
            "thickness",
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
    ];
    for (name, text, expected) in cases {
        let path = temp_config(name, &text);
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
