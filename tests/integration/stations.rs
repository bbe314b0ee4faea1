//! Strong-motion stations' archives as the CESMD distributes them: the
//! recorders of a station put on one time line, whatever their clocks.

use super::common::{assert_rrd_without_deck, fresh_dir, painter_street_record, splinewatch};
use super::import::{channels, root, write_naming_config, Channel};
use splinewatch::io::wire::parse_timestamp;
use std::path::Path;
use std::process::Command;

/// Imports `zip` with a config naming `names` (vertical sensors, the
/// direction does not matter to import): the channels and stderr.
fn import_named(dir: &Path, zip: &Path, names: &[&str]) -> (Vec<Channel>, String, Vec<u8>) {
    let config = dir.join("station.toml");
    write_naming_config(&config, "station", names);
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

/// The frequencies of the modes fitted in the frequency domain among `modes`.
fn fitted_frequencies(modes: &serde_json::Value) -> Vec<f64> {
    modes
        .as_array()
        .unwrap()
        .iter()
        .filter(|m| m["method"] == "pole_residue")
        .map(|m| m["frequency_hz"].as_f64().unwrap())
        .collect()
}

/// `station` writes a starter config from a station's records: Painter
/// Street's 2012 and 2015 records and its 1980 one (another layout, other
/// descriptions of the same channel numbers). Every channel by station
/// number, `Tran`/`Long`/`Up` on y/x/z, the ground channels (locations
/// naming the ground) in one support group per location, the records that
/// lack a channel and the other descriptions noted; the config is valid
/// without a model; `identify` and `events` run with it, the frequency-domain
/// fit of the transverse channels among the modes.
#[test]
fn station_writes_a_starter_config_that_identify_runs_with() {
    let dir = fresh_dir("station");
    let config = dir.join("painter.toml");
    let records = [
        "RioDell_14Sep2012_71842255_ce89324p.zip",
        "ferndale_28jan2015_72387946_ce89324p.zip",
        "trinidad-offshore_08nov1980_ce89324p.zip",
    ]
    .map(painter_street_record);
    let mut args = vec!["station", "--out", config.to_str().unwrap()];
    args.extend(records.iter().map(String::as_str));
    let o = splinewatch(&args);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    let text = std::fs::read_to_string(&config).unwrap();
    assert!(
        text.contains("# CSMIP station 89324: Rio Dell - Hwy 101/Painter St. Overpass"),
        "{text}"
    );
    let entry = |name: &str| -> String {
        let at = text
            .find(&format!("name = \"{name}\"\n"))
            .unwrap_or_else(|| panic!("{name} in {text}"));
        text[at..].split("\n\n").next().unwrap().to_string()
    };
    assert!(entry("ch7").contains("direction = \"y\"") && !entry("ch7").contains("support"));
    assert!(entry("ch5").contains("direction = \"z\""));
    assert!(
        entry("ch4").contains("not in trinidad-offshore_08nov1980"),
        "{}",
        entry("ch4")
    );
    // The 1980 free field, an azimuth without --axis: on compass axes, said.
    assert!(entry("ch12").contains("direction = \"-y\"") && entry("ch12").contains("support = \"free_field\""));
    assert!(stderr.contains("ch12 points at 270°: without --axis"), "{stderr}");
    assert!(entry("ch11").contains("direction = \"x\""));
    assert!(
        entry("ch3").contains("support = \"middle_bent_column\""),
        "{}",
        entry("ch3")
    );
    assert!(entry("ch17").contains("support = \"east_abutment\""));
    assert!(entry("ch20").contains("support = \"west_abutment\""));
    assert!(
        entry("ch1").contains("some records describe it as \"270 DEG"),
        "{}",
        entry("ch1")
    );
    let o = splinewatch(&["check-config", config.to_str().unwrap()]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        out.contains("4 support groups (east_abutment, free_field, middle_bent_column, west_abutment)"),
        "{out}"
    );
    let identified_rrd = dir.join("identify.rrd");
    let o = splinewatch(&[
        "identify",
        "--config",
        config.to_str().unwrap(),
        &records[1],
        "--json",
        "--rerun-save",
        identified_rrd.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    // `--rerun-save` without a model: the identification alone (diagram,
    // singular values, SRIM's and the fitted modes), no deck, read back with
    // Rerun's own decoder.
    assert_rrd_without_deck(
        &identified_rrd,
        &[
            "/oma/stabilisation",
            "/oma/singular_values",
            "/oma/modes/1/frequency_hz",
            "/oma/stabilisation/fitted",
            "/oma/fitted/1/damping_percent",
        ],
    );
    // The starter's `[oma] resample_hz = 50`: the 100 Hz record identified
    // at half its rate (exactly its points over the same span).
    assert!(
        stderr.contains("(SRIM at 50.006 Hz, resampled, horizon 50)"),
        "{stderr}"
    );
    let modes: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(!modes["modes"].as_array().unwrap().is_empty(), "{modes}");
    assert!(modes["modes"][0].get("model").is_none(), "no model, no match: {modes}");
    // The transverse modes fitted from the bent's transverse ground to the
    // structure's transverse channels: the one near 4 Hz among them.
    assert!(
        text.contains(
            "inputs = [\"ch3\"]            # Middle Bent: Column at Grnd Level\noutputs = [\"ch4\", \"ch7\", \"ch9\"]"
        ),
        "{text}"
    );
    let fitted = fitted_frequencies(&modes["modes"]);
    assert!(fitted.iter().any(|f| (3.0..=4.6).contains(f)), "{fitted:?}");
    let o = splinewatch(&[
        "identify",
        "--config",
        config.to_str().unwrap(),
        &records[1],
        "--parameters",
        "state.json",
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success());
    assert!(
        stderr.contains("--parameters state.json: the config has no [model] to compare the modes with"),
        "{stderr}"
    );
    // `events` without a model: an event identified and judged on its
    // modes (no update, and no forecast for the first); the 1980 record
    // (19.7 s at 50 Hz) is shorter than the horizon's 32 s at any rate, and
    // says so in seconds.
    let state = dir.join("chain.json");
    let events = |records: &[&str]| -> Vec<serde_json::Value> {
        let mut args = vec![
            "events",
            "--config",
            config.to_str().unwrap(),
            "--state",
            state.to_str().unwrap(),
        ];
        args.push("--json");
        args.extend(records);
        let o = splinewatch(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        crate::common::json_lines(&o.stdout)
    };
    let lines = events(&[&records[1], &records[2]]);
    assert_eq!(lines.len(), 2);
    for line in &lines[1..] {
        assert!(line["skipped"].is_null(), "{line}");
        assert!(!line["modes"].as_array().unwrap().is_empty(), "{line}");
        assert!(
            line["forecast"].is_null() && line["parameters"].as_array().unwrap().is_empty(),
            "{line}"
        );
        assert_eq!(line["verdict"]["state"], "insufficient history", "{line}");
        // The fitted transverse modes, as `identify` fitted them on the record.
        let from_events = fitted_frequencies(&line["modes"]);
        assert_eq!(from_events.len(), fitted.len(), "{line}");
        for (a, b) in from_events.iter().zip(&fitted) {
            assert!((a - b).abs() <= 1e-9 * b, "{from_events:?} vs identify's {fitted:?}");
        }
    }
    let skipped = lines[0]["skipped"].as_str().unwrap_or_default();
    assert!(
        skipped.contains("19.7 s (985 samples at 50 Hz), shorter than the 32.0 s"),
        "{skipped}"
    );
    // The realization of an event forecasts the next: kept in the state
    // file, it forecasts the 2015 record given again (its own fit, the
    // state's round trip; forecasting another record is the core's
    // verification, and `benches/painter_street_mdof.py` on the 20
    // records) better than "deck = ground" on each transverse channel
    // (measured 0.36 against 0.65 on ch4), and names where it came from.
    let saved: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&state).unwrap()).unwrap();
    assert_eq!(
        saved["realization"]["realization"]["a"].as_array().unwrap().len(),
        12,
        "{saved}"
    );
    let line = events(&[&records[1]]).remove(0);
    let forecast = &line["forecast"];
    let score = |list: &serde_json::Value, sensor: &str| -> f64 {
        let entry = list.as_array().unwrap().iter().find(|c| c["sensor"] == sensor).unwrap();
        entry["nrmse_strong"].as_f64().unwrap()
    };
    for sensor in ["ch4", "ch7", "ch9"] {
        let (ours, baseline) = (
            score(&forecast["channels"], sensor),
            score(&forecast["baseline"], sensor),
        );
        assert!(ours < baseline, "{sensor}: {ours} against the baseline's {baseline}");
    }
    let notes = line["notes"].to_string();
    assert!(
        notes.contains(
            "forecast by the realization of ferndale_28jan2015_72387946_ce89324p.zip (order 12, identified at 50.006 Hz)"
        ),
        "{notes}"
    );
    // `--rerun-save` without a model: the events' timeline alone (no deck
    // views), read back with Rerun's own decoder.
    let rrd = dir.join("events.rrd");
    let o = splinewatch(&[
        "events",
        "--config",
        config.to_str().unwrap(),
        "--rerun-save",
        rrd.to_str().unwrap(),
        &records[1],
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_rrd_without_deck(
        &rrd,
        &["/events/pga_ground", "/events/frequency/identified", "/events/verdict"],
    );
    // `predict` without a model forecasts by the state's realization, with
    // the figures `events` gave the same record; without `--state` it says
    // what it needs.
    let o = splinewatch(&[
        "predict",
        "--config",
        config.to_str().unwrap(),
        "--state",
        state.to_str().unwrap(),
        "--json",
        &records[1],
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(
        stderr.contains("forecast by the realization of ferndale_28jan2015"),
        "{stderr}"
    );
    let predicted: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    for sensor in ["ch4", "ch7", "ch9"] {
        assert_eq!(
            score(&predicted["channels"], sensor),
            score(&forecast["channels"], sensor),
            "{sensor}"
        );
    }
    let o = splinewatch(&["predict", "--config", config.to_str().unwrap(), &records[1]]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && stderr.contains("give --state"), "{stderr}");
}

/// A station's record `station` cannot read as a bridge's: each problem one
/// line on stderr and a comment in the file, nothing left out silently (a
/// channel whose orientation is not read stays in the file, commented); a
/// record of ground channels only is refused.
#[test]
fn station_says_what_it_cannot_read_once() {
    let dir = fresh_dir("station-bad");
    let channel = |number: u32, direction: &str, location: &str| {
        format!(
            "Corrected accelerogram   99999-X0001-26327.01       Chan  {number}: {direction}\n\
             Station No. 99999   37.000N, 122.000W    Test  s/n 1\n\
             Test Building   CGS\n\
             Chan  {number}: {direction}   Location: {location}\n\
             Rcrd of Mon Nov 23, 2026 10:00:00.0 UTC\n\
             \x20    3 points of accel data equally spaced at  0.010 sec, in cm/sec2. (8f10.5)\n\
             \x20  1.00000   2.00000   3.00000\n"
        )
    };
    let building = dir.join("building.V2");
    std::fs::write(
        &building,
        [channel(1, "Up", "Roof"), channel(2, "Radial", "3rd Floor")]
            .join("/&  ---------- End of data for channel  1 ----------\n"),
    )
    .unwrap();
    let o = splinewatch(&["station", building.to_str().unwrap()]);
    let (stdout, stderr) = (String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert!(o.status.success(), "{stderr}");
    for said in [
        "ch2: its orientation \"Radial\" is none of Up, Tran, Long or an azimuth",
        "no channel's location names the ground",
        "is this a building's station?",
    ] {
        assert_eq!(stderr.matches(said).count(), 1, "{said} once in {stderr}");
        assert_eq!(stdout.matches(said).count(), 1, "{said} once in the file: {stdout}");
    }
    assert!(stdout.contains("# name = \"ch2\""), "{stdout}");
    let ground = dir.join("ground.V2");
    std::fs::write(&ground, channel(1, "Up", "Freefield")).unwrap();
    let o = splinewatch(&["station", ground.to_str().unwrap()]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && stderr.contains("every channel of the records is on the ground"),
        "{stderr}"
    );
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
}
