//! Strong-motion stations' archives as the CESMD distributes them: the
//! recorders of a station put on one time line, whatever their clocks.

use super::common::fresh_dir;
use super::import::{channels, root, Channel};
use splinewatch::io::wire::parse_timestamp;
use std::path::Path;
use std::process::Command;

/// Imports `zip` with a config naming `names` (vertical sensors, the
/// direction does not matter to import): the channels and stderr.
fn import_named(dir: &Path, zip: &Path, names: &[&str]) -> (Vec<Channel>, String, Vec<u8>) {
    let config = dir.join("station.toml");
    let sensors: String = names
        .iter()
        .map(|c| format!("[[sensors]]\nname = \"{c}\"\ndirection = \"z\"\n\n"))
        .collect();
    std::fs::write(&config, format!("[structure]\nname = \"station\"\n\n{sensors}")).unwrap();
    let out = dir.join("station.mcap");
    let o = Command::new(env!("CARGO_BIN_EXE_splinewatch"))
        .args(["import", "--config", config.to_str().unwrap(), "--format", "v2"])
        .arg(zip)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "{stderr}");
    (channels(&out), stderr, std::fs::read(&out).unwrap())
}

/// Recorders whose clock the header flags (`(*LoQ*)`) are placed on the
/// trusted recorders' time line by cross-correlating ground channels along
/// one direction (tests/fixtures/make_v2_fixtures.py, `clocks`):
/// - synthetic, the truth known: recorder B0002's header says 10:00:31.37,
///   its channels truly start at 10:00:02.0 and see the same ground motion as
///   B0001's free field; read right, the grid starts at 10:00:02.0 (to 5 ms,
///   half a sample) and ch4 equals ch1's motion (the 1 % noise and the
///   resampling: 3 %). Read by the header's clock, the grid started at
///   10:00:31.37 and ch1 and ch4 were uncorrelated.
/// - real, Meloland 7 July 2010 (trimmed): recorder E0784's start moves by
///   scipy's cross-correlation shift to within 0.015 s (a sample and a
///   half at 100 Hz: scipy's is the plain correlation's peak on the sample,
///   ours the normalised one's refined between samples), so the grid starts
///   where E0784's corrected start puts it.
///
/// What was done is said on stderr and kept in the MCAP file's metadata.
#[test]
fn recorders_whose_clock_is_flagged_are_placed_by_their_ground_channels() {
    let dir = fresh_dir("import-v2-loq");
    let fixtures = root().join("tests/fixtures");
    let (got, stderr, bytes) = import_named(
        &dir,
        &fixtures.join("v2/loq_like.zip"),
        &["ch1", "ch2", "ch3", "ch4", "ch5"],
    );
    assert!(
        stderr.contains("recorder B0002's clock is flagged low quality (*LoQ*)") && stderr.contains("-29.37"),
        "{stderr}"
    );
    let truth = parse_timestamp("2026-11-23T10:00:02Z").unwrap();
    for (name, _, fs, start_ns, _) in &got {
        assert_eq!(*fs, 100.0, "{name}");
        assert!(
            (start_ns - truth).abs() <= 5_000_000,
            "{name}: starts {} ns from the truth",
            start_ns - truth
        );
    }
    let series = |n: &str| &got.iter().find(|c| c.0 == n).unwrap().4;
    let (ground, footing) = (series("ch1"), series("ch4"));
    let rms = |x: &[f64]| (x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64).sqrt();
    let difference: Vec<f64> = ground.iter().zip(footing).map(|(a, b)| a - b).collect();
    let relative = rms(&difference) / rms(ground);
    assert!(
        relative < 0.03,
        "ch4 differs from ch1's motion by {relative:.3} of its rms"
    );
    let text = String::from_utf8_lossy(&bytes);
    assert!(
        text.contains("splinewatch.import") && text.contains("recorder B0002's clock is flagged"),
        "the MCAP file keeps the note"
    );

    let expected: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(fixtures.join("v2/expected_loq.json")).unwrap()).unwrap();
    let (got, stderr, _) = import_named(
        &dir,
        &fixtures.join("meloland/borrego_2010_loq.zip"),
        &["ch2", "ch4", "ch11", "ch12", "ch25", "ch26"],
    );
    assert!(stderr.contains("recorder E0784's clock is flagged"), "{stderr}");
    let corrected = expected["flagged_header_start_s"].as_f64().unwrap() + expected["median_shift_s"].as_f64().unwrap();
    for (name, _, fs, start_ns, _) in &got {
        assert_eq!(*fs, 100.0, "{name}");
        let off = *start_ns as f64 * 1e-9 - corrected;
        assert!(off.abs() <= 0.015, "{name}: starts {off:.4} s from scipy's alignment");
    }
}
