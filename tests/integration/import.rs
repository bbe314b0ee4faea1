//! `splinewatch import`: loggers' CSV/TSV and UFF 58 files into recordings.
//! The committed fixtures (tests/fixtures/make_import_fixtures.py) were
//! written by pyuff and in a logger's CSV style; the round trips write the
//! bundled recording out as CSV and UFF 58 and check that the imported
//! recording replays to the same parameters.

use crate::common::{bundled_blocks, fresh_dir};
use splinewatch::config::load_config;
use splinewatch::io::recording::{read_recording, RecordedBlock};
use splinewatch::io::wire::{parse_timestamp, ChannelQuantity};
use splinewatch::outputs::results::ResultsWriter;
use splinewatch::service::replay::{replay, ReplayOptions};
use std::path::Path;
use std::process::Command;

pub(super) fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn import(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_splinewatch"))
        .arg("import")
        .args(["--config", "config/sinello.toml"])
        .args(args)
        .current_dir(root())
        .output()
        .unwrap()
}

/// The blocks of an imported recording, per channel, concatenated.
/// An imported channel: name, quantity, rate, start, samples.
pub(super) type Channel = (String, ChannelQuantity, f64, i128, Vec<f64>);

/// A config of vertical sensors named `names`, for `import` (which reads
/// names only), written to `path`.
pub(super) fn write_naming_config(path: &Path, structure: &str, names: &[&str]) {
    let sensors: String = names
        .iter()
        .map(|c| format!("[[sensors]]\nname = \"{c}\"\ndirection = \"z\"\n\n"))
        .collect();
    std::fs::write(path, format!("[structure]\nname = \"{structure}\"\n\n{sensors}")).unwrap();
}

pub(super) fn channels(path: &Path) -> Vec<Channel> {
    let (blocks, rejected) = read_recording(&std::fs::read(path).unwrap(), &Default::default()).unwrap();
    assert!(rejected.is_empty());
    let mut out: Vec<Channel> = Vec::new();
    for b in blocks.iter().map(|b| &b.block) {
        match out.iter_mut().find(|c| c.0 == b.name && c.1 == b.quantity) {
            Some(c) => c.4.extend_from_slice(&b.data),
            None => out.push((b.name.clone(), b.quantity, b.fs, b.start_ns, b.data.clone())),
        }
    }
    out
}

/// The fixtures' formulas: P1 force 100 sin(2π·3t) N, P2 0.5 cos(2π·5t) m/s².
fn check_fixture_channels(path: &Path, tolerance: f64) {
    let start = parse_timestamp("2026-11-21T10:00:00Z").unwrap();
    let got = channels(path);
    assert_eq!(got.len(), 2, "{:?}", got.iter().map(|c| &c.0).collect::<Vec<_>>());
    let t = |k: usize| k as f64 / 256.0;
    for (name, quantity, fs, start_ns, data) in &got {
        assert_eq!((*fs, *start_ns, data.len()), (256.0, start, 512), "{name}");
        let expected = |k: usize| match quantity {
            ChannelQuantity::Force => 100.0 * (2.0 * std::f64::consts::PI * 3.0 * t(k)).sin(),
            ChannelQuantity::Acceleration => 0.5 * (2.0 * std::f64::consts::PI * 5.0 * t(k)).cos(),
            ChannelQuantity::Temperature => unreachable!("no temperature column"),
        };
        let expected_name = match quantity {
            ChannelQuantity::Force => "P1",
            ChannelQuantity::Acceleration => "P2",
            ChannelQuantity::Temperature => unreachable!("no temperature column"),
        };
        assert_eq!(name, expected_name);
        let worst = (0..512).map(|k| (data[k] - expected(k)).abs()).fold(0.0, f64::max);
        assert!(worst <= tolerance, "{name}: worst error {worst:e}");
    }
}

/// Imports a committed fixture starting at 2026-11-21T10:00:00Z; the recording.
fn import_fixture(dir: &Path, format: &str, fixture: &str) -> std::path::PathBuf {
    let out = dir.join(format!("{format}.mcap"));
    let o = import(&[
        "--format",
        format,
        fixture,
        "--start",
        "2026-11-21T10:00:00Z",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    out
}

#[test]
fn a_uff58_file_written_by_pyuff_imports() {
    let dir = fresh_dir("import-uff");
    let out = import_fixture(&dir, "uff", "tests/fixtures/pyuff_time58.uff");
    // pyuff writes 12 significant digits (E20.12): 1e-10 of the amplitudes.
    check_fixture_channels(&out, 1e-9);
}

/// The same channels as binary dataset 58b (little-endian doubles, as
/// pyuff writes them): exact to the formulas' round-off.
#[test]
fn a_binary_uff58b_file_written_by_pyuff_imports() {
    let dir = fresh_dir("import-uff58b");
    let out = import_fixture(&dir, "uff", "tests/fixtures/pyuff_time58b.uff");
    check_fixture_channels(&out, 1e-12);
}

#[test]
fn a_logger_csv_with_semicolons_decimal_commas_and_units_imports() {
    let dir = fresh_dir("import-csv");
    let out = import_fixture(&dir, "csv", "tests/fixtures/logger_semicolon.csv");
    // kN and g converted to N and m/s² (printed at full precision: rounding only).
    check_fixture_channels(&out, 1e-12);
}

#[test]
fn import_errors_name_the_column_or_what_is_missing() {
    let dir = fresh_dir("import-errors");
    let write = |name: &str, text: &str| {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p.to_str().unwrap().to_string()
    };
    let out = dir.join("x.mcap");
    let out = out.to_str().unwrap();
    let cases = [
        (
            write("unknown.csv", "time,P1:force,P99\n0,1,2\n0.5,1,2\n"),
            vec!["--start", "2026-11-21T10:00:00Z", "--strict"],
            "column \"P99\" matches no [[sensors]] name",
        ),
        (
            write("ambiguous.csv", "time,P1\n0,1\n0.5,1\n"),
            vec!["--start", "2026-11-21T10:00:00Z"],
            "sensor \"P1\" measures force and acceleration; name the column P1:force or P1:acceleration",
        ),
        (
            write("no-rate.csv", "P2,P3\n1,2\n1,2\n"),
            vec!["--start", "2026-11-21T10:00:00Z"],
            "no sampling rate (no time column): pass --fs",
        ),
        (
            write("no-start.csv", "time,P2\n0,1\n0.5,1\n"),
            vec![],
            "no absolute start time: pass --start",
        ),
        (
            write("text.csv", "time,P2\n0,1\n0.5,abc\n1.0,2\n"),
            vec!["--start", "2026-11-21T10:00:00Z"],
            "line 3, column \"P2\": \"abc\" is not a number",
        ),
        (
            write("uneven.csv", "time,P2\n0,1\n0.5,1\n1.2,1\n"),
            vec!["--start", "2026-11-21T10:00:00Z"],
            "time column \"time\": not evenly sampled",
        ),
        (
            write("unit.csv", "time,P2\ns,furlong\n0,1\n0.5,1\n"),
            vec!["--start", "2026-11-21T10:00:00Z"],
            "column \"P2\": unit \"furlong\" is not a known unit",
        ),
        (
            write("velocity.csv", "time,P2\ns,mm/s\n0,1\n0.5,1\n"),
            vec!["--start", "2026-11-21T10:00:00Z"],
            "column \"P2\": unit \"mm/s\" is a velocity; sensors record force or acceleration",
        ),
        (
            write("nothing.csv", "time,Q1,Q2\n0,1,2\n0.5,1,2\n"),
            vec!["--start", "2026-11-21T10:00:00Z"],
            "no column names a [[sensors]] entry of the config (columns: Q1, Q2)",
        ),
        (
            write("units-flag.csv", "time,P2\n0,1\n0.5,1\n"),
            vec!["--start", "2026-11-21T10:00:00Z", "--units", "furlong"],
            "--units \"furlong\": unit \"furlong\" is not a known unit",
        ),
    ];
    for (file, extra, expected) in cases {
        let mut args = vec!["--format", "csv", file.as_str(), "--out", out];
        args.extend(extra);
        let o = import(&args);
        let stderr = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{file}: {stderr}");
        assert!(stderr.contains(expected), "{file}: {stderr}");
        assert!(stderr.contains(&file), "{file}: the error names the file: {stderr}");
    }
}

/// A column of a written-out file: name, unit, samples.
type Column = (String, &'static str, Vec<f64>);

/// The bundled recording's channels, concatenated, with CSV/UFF names.
fn bundled_columns() -> (i128, Vec<Column>) {
    let blocks: Vec<RecordedBlock> = bundled_blocks();
    let start = blocks.iter().map(|b| b.block.start_ns).min().unwrap();
    let mut columns: Vec<Column> = Vec::new();
    for b in blocks.iter().map(|b| &b.block) {
        let (name, unit) = match b.quantity {
            ChannelQuantity::Force => (format!("{}:force", b.name), "N"),
            ChannelQuantity::Acceleration if b.name == "P1" => (format!("{}:acceleration", b.name), "m/s^2"),
            ChannelQuantity::Acceleration => (b.name.clone(), "m/s^2"),
            ChannelQuantity::Temperature => unreachable!("the bundled recording has no temperature"),
        };
        match columns.iter_mut().find(|c| c.0 == name) {
            Some(c) => c.2.extend_from_slice(&b.data),
            None => columns.push((name, unit, b.data.clone())),
        }
    }
    (start, columns)
}

fn replay_parameters(path: &Path) -> Vec<(String, f64)> {
    let cfg = load_config(&root().join("config/sinello.toml")).unwrap();
    let bytes = std::fs::read(path).unwrap();
    let mut out = ResultsWriter::new(std::io::Cursor::new(Vec::new()), &cfg.topic_prefix()).unwrap();
    let summary = replay(&cfg, &[&bytes], &mut out, ReplayOptions::default(), &mut |_, _| {}).unwrap();
    assert_eq!(summary.update_count, 6);
    let accepted = summary.accepted.expect("updates accepted");
    accepted.parameters.into_iter().map(|p| (p.name, p.value)).collect()
}

#[test]
fn csv_and_uff_round_trips_replay_to_the_bundled_parameters() {
    let dir = fresh_dir("import-round-trip");
    let (start, columns) = bundled_columns();
    let start_text = splinewatch::io::wire::format_timestamp(start);
    let n = columns[0].2.len();
    // CSV: a time column, a units row, every value at full precision.
    let mut csv = String::from("time");
    for c in &columns {
        csv += &format!(",{}", c.0);
    }
    csv += "\ns";
    for c in &columns {
        csv += &format!(",{}", c.1);
    }
    csv += "\n";
    for k in 0..n {
        csv += &format!("{}", k as f64 / 256.0);
        for c in &columns {
            csv += &format!(",{}", c.2[k]);
        }
        csv += "\n";
    }
    // UFF 58: one dataset per channel, double precision, as pyuff writes them.
    let mut uff = String::new();
    for (i, c) in columns.iter().enumerate() {
        let (name, kind) = match c.0.split_once(':') {
            Some((s, "force")) => (s.to_string(), 13),
            Some((s, _)) => (format!("{s}:acceleration"), 12),
            None => (c.0.clone(), 12),
        };
        uff += &format!("    -1\n    58\n{name} time response\nNONE\nNONE\nNONE\nNONE\n");
        uff += &format!(
            "    1         0    0         0         {name:<10}{:>10}   3 P1                 1   3\n",
            i + 1
        );
        uff += &format!(
            "{:>10}{:>10}{:>10}{:>13.5e}{:>13.5e}{:>13.5e}\n",
            4,
            n,
            1,
            0.0,
            1.0 / 256.0,
            0.0
        );
        uff += "        17    0    0    0 NONE                 s                   \n";
        uff += &format!("{kind:>10}    0    0    0 NONE                 {:<20}\n", c.1);
        uff += "         0    0    0    0 NONE                 NONE                \n";
        uff += "         0    0    0    0 NONE                 NONE                \n";
        for chunk in c.2.chunks(4) {
            uff += &chunk.iter().map(|v| format!("{v:20.12e}")).collect::<String>();
            uff += "\n";
        }
        uff += "    -1\n";
    }
    let bundled = replay_parameters(&root().join("recordings/sinello-demo.mcap"));
    for (format, text, tolerance) in [("csv", csv, 0.0), ("uff", uff, 1e-6)] {
        let input = dir.join(format!("bundled.{format}"));
        std::fs::write(&input, text).unwrap();
        let out = dir.join(format!("{format}.mcap"));
        let o = import(&[
            "--format",
            format,
            input.to_str().unwrap(),
            "--start",
            &start_text,
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{format}: {}", String::from_utf8_lossy(&o.stderr));
        let imported = replay_parameters(&out);
        assert_eq!(imported.len(), bundled.len());
        for ((name, a), (_, b)) in imported.iter().zip(&bundled) {
            assert!(
                (a - b).abs() <= tolerance * b.abs(),
                "{format}: {name} = {a} after import, {b} from the bundled recording"
            );
        }
    }
}

/// Issue 33: a strong-motion array's CSV of 17 channels in cm/s² without a
/// units row (`--units cm/s^2`), imported against a config of 4 of its
/// sensors: the 13 other columns are skipped and listed on stderr, and the
/// 4 kept ones are converted to m/s² (× 0.01). Units convert to SI.
#[test]
fn issue_33_a_17_column_csv_in_cm_per_s2_imports_against_a_4_sensor_config() {
    let dir = fresh_dir("import-17");
    // The bundled config with only its sensors P2…P5.
    let mut cfg: toml::Table =
        toml::from_str(&std::fs::read_to_string(root().join("config/sinello.toml")).unwrap()).unwrap();
    let sensors = cfg["sensors"].as_array().unwrap();
    let kept: Vec<toml::Value> = sensors
        .iter()
        .filter(|s| ["P2", "P3", "P4", "P5"].contains(&s["name"].as_str().unwrap()))
        .cloned()
        .collect();
    assert_eq!(kept.len(), 4);
    cfg.insert("sensors".into(), toml::Value::Array(kept));
    let config = dir.join("four.toml");
    std::fs::write(&config, toml::to_string(&cfg).unwrap()).unwrap();
    // Channels ch1…ch17; ch3…ch6 are P2…P5 (renamed in the header, as a user
    // maps a station's channels to the config's sensors).
    let names: Vec<String> = (1..=17)
        .map(|c| match c {
            3..=6 => format!("P{}", c - 1),
            _ => format!("ch{c}"),
        })
        .collect();
    let value = |k: usize, c: usize| (c as f64) * 10.0 + (k as f64 * 0.37).sin();
    let mut text = format!("time,{}\n", names.join(","));
    for k in 0..512 {
        let row: Vec<String> = (1..=17).map(|c| format!("{:.6}", value(k, c))).collect();
        text += &format!("{},{}\n", k as f64 / 256.0, row.join(","));
    }
    let csv = dir.join("array.csv");
    std::fs::write(&csv, text).unwrap();
    let out = dir.join("array.mcap");
    let o = Command::new(env!("CARGO_BIN_EXE_splinewatch"))
        .args(["import", "--config", config.to_str().unwrap(), "--format", "csv"])
        .arg(&csv)
        .args([
            "--out",
            out.to_str().unwrap(),
            "--start",
            "2026-11-21T10:00:00Z",
            "--units",
            "cm/s^2",
        ])
        .current_dir(root())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    let skipped: Vec<String> = names.iter().filter(|n| n.starts_with("ch")).cloned().collect();
    assert_eq!(skipped.len(), 13);
    assert!(
        stderr.contains(&format!(
            "skipped 13 columns that name no sensor of the config: {}",
            skipped.join(", ")
        )),
        "{stderr}"
    );
    let got = channels(&out);
    assert_eq!(got.len(), 4);
    for (name, quantity, fs, _, data) in &got {
        assert_eq!(
            (*quantity, *fs, data.len()),
            (ChannelQuantity::Acceleration, 256.0, 512),
            "{name}"
        );
        let column = names.iter().position(|n| n == name).unwrap() + 1;
        for (k, v) in data.iter().enumerate() {
            let expected = 0.01 * format!("{:.6}", value(k, column)).parse::<f64>().unwrap();
            assert!(
                (v - expected).abs() <= 1e-15 * expected.abs().max(1.0),
                "{name}[{k}]: {v} vs {expected}"
            );
        }
    }
    // With --strict the same file is refused, naming the first stray column.
    let o = Command::new(env!("CARGO_BIN_EXE_splinewatch"))
        .args(["import", "--config", config.to_str().unwrap(), "--format", "csv"])
        .arg(&csv)
        .args([
            "--out",
            out.to_str().unwrap(),
            "--start",
            "2026-11-21T10:00:00Z",
            "--strict",
        ])
        .current_dir(root())
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("column \"ch1\" matches no [[sensors]] name"));
}

/// Every unit a logger or strong-motion file writes converts to SI: the
/// same column in each unit imports to the same m/s² (or N).
#[test]
fn issue_33_units_convert_to_si() {
    let dir = fresh_dir("import-units");
    let cases: [(&str, &str, f64); 11] = [
        ("P2", "m/s^2", 1.0),
        ("P2", "m/s²", 1.0),
        ("P2", "cm/s^2", 0.01),
        ("P2", "cm/s²", 0.01),
        ("P2", "gal", 0.01),
        ("P2", "mm/s^2", 1e-3),
        ("P2", "g", 9.806_65),
        ("P2", "mg", 1e-3 * 9.806_65),
        ("P2", "in/s^2", 0.0254),
        ("P2", "ft/s^2", 0.3048),
        ("P1:force", "kN", 1e3),
    ];
    for (column, unit, factor) in cases {
        let csv = dir.join("u.csv");
        std::fs::write(&csv, format!("time,{column}\ns,{unit}\n0,2.5\n0.5,-4\n1.0,1\n")).unwrap();
        let out = dir.join("u.mcap");
        let o = import(&[
            "--format",
            "csv",
            csv.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--start",
            "2026-11-21T10:00:00Z",
        ]);
        assert!(o.status.success(), "{unit}: {}", String::from_utf8_lossy(&o.stderr));
        let got = channels(&out);
        assert_eq!(got[0].4, [2.5 * factor, -4.0 * factor, factor], "{unit}");
    }
}

/// Issue 33: CSMIP/COSMOS Volume 2 files (tests/fixtures/make_v2_fixtures.py,
/// checked there with quakeio) import as the channels `ch<N>` of a config
/// naming them (here an output-only config of three of the four: the
/// fourth is skipped and listed): one file per channel, the station's zip,
/// or the station's channels in one file give the same recording, the
/// values quakeio read × 0.01 (cm/sec2 → m/s²), at 100 Hz from the record's
/// `Rcrd of` time; a file with another unit, a short channel or a
/// different time step is an error naming it.
#[test]
fn issue_33_a_v2_file_set_imports() {
    let dir = fresh_dir("import-v2");
    let config = dir.join("channels.toml");
    let sensors: String = (1..=3)
        .map(|c| format!("[[sensors]]\nname = \"ch{c}\"\nquantity = \"acceleration\"\ndirection = \"z\"\n\n"))
        .collect();
    std::fs::write(&config, format!("[structure]\nname = \"v2-station\"\n\n{sensors}")).unwrap();
    let expected: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(root().join("tests/fixtures/v2/expected.json")).unwrap())
            .unwrap();
    let fixture = |f: &str| root().join("tests/fixtures/v2").join(f).to_str().unwrap().to_string();
    let run = |label: &str, inputs: &[String]| {
        let out = dir.join(format!("{label}.mcap"));
        let o = Command::new(env!("CARGO_BIN_EXE_splinewatch"))
            .args(["import", "--config", config.to_str().unwrap(), "--format", "v2"])
            .args(inputs)
            .args(["--out", out.to_str().unwrap()])
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&o.stderr).into_owned();
        assert!(o.status.success(), "{label}: {stderr}");
        assert!(
            stderr.contains("skipped 1 columns that name no sensor of the config: ch4"),
            "{label}: {stderr}"
        );
        channels(&out)
    };
    let per_file: Vec<String> = (1..=4).map(|c| fixture(&format!("CHAN{c:03}.V2"))).collect();
    let recordings = [
        run("per-file", &per_file),
        run("zip", &[fixture("station.zip")]),
        run("station", &[fixture("station.V2")]),
    ];
    let start = parse_timestamp("2026-11-23T10:00:00Z").unwrap();
    for got in &recordings {
        assert_eq!(got.len(), 3);
        for (name, quantity, fs, start_ns, data) in got {
            assert_eq!(
                (*quantity, *fs, *start_ns),
                (ChannelQuantity::Acceleration, 100.0, start),
                "{name}"
            );
            let reference = expected[name]["accel"].as_array().unwrap();
            assert_eq!(expected[name]["time_step"], 0.01);
            assert_eq!(expected[name]["units"], "cm/sec2");
            assert_eq!(data.len(), reference.len(), "{name}");
            for (k, (v, r)) in data.iter().zip(reference).enumerate() {
                let r = r.as_f64().unwrap() * 0.01;
                assert!(
                    (v - r).abs() <= 1e-15 * r.abs().max(1e-3),
                    "{name}[{k}]: {v} vs quakeio {r}"
                );
            }
        }
    }
    assert_eq!(recordings[0], recordings[1]);
    assert_eq!(recordings[0], recordings[2]);

    // Errors name the file and channel.
    let text = std::fs::read_to_string(fixture("CHAN001.V2")).unwrap();
    let bad = |label: &str, content: String| {
        let path = dir.join(format!("{label}.V2"));
        std::fs::write(&path, content).unwrap();
        let o = Command::new(env!("CARGO_BIN_EXE_splinewatch"))
            .args(["import", "--config", config.to_str().unwrap(), "--format", "v2"])
            .args([path.to_str().unwrap(), &fixture("CHAN002.V2")])
            .args(["--out", dir.join("bad.mcap").to_str().unwrap()])
            .output()
            .unwrap();
        assert!(!o.status.success(), "{label}");
        String::from_utf8_lossy(&o.stderr).into_owned()
    };
    let lines: Vec<&str> = text.lines().collect();
    // The header (45 lines), the accel line and 100 of its 188 data lines.
    let short: String = lines[..146].join("\n");
    let e = bad("short", short);
    assert!(
        e.contains("short.V2, channel 1") && e.contains("of the 1500 accel values"),
        "{e}"
    );
    let e = bad("unit", text.replace("in cm/sec2.", "in furlongs."));
    assert!(e.contains("furlongs"), "{e}");
    // A second copy of channel 2 that differs from CHAN002.V2 (one value).
    let changed = std::fs::read_to_string(fixture("CHAN002.V2"))
        .unwrap()
        .lines()
        .enumerate()
        .map(|(i, l)| {
            if i == 46 {
                format!("{}9{}", &l[..9], &l[10..])
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n");
    let e = bad("twice", changed);
    assert!(
        e.contains("twice.V2") && e.contains("channel 2 is also in") && e.contains("another record"),
        "{e}"
    );
    // The list of files is never printed: each error names its own file.
    assert!(!e.contains("CHAN002.V2, "), "{e}");
}

/// Issue 44: stations of several recorders (tests/fixtures/make_v2_fixtures.py,
/// each file checked there with quakeio). Seven recorders of four channels
/// whose `Chan k:` restart at 1 import as the 28 station channels
/// (`Sta Chn: N`); two recorders at 100 and 200 Hz starting half a second
/// apart come on one 100 Hz grid over their common span, the faster one
/// resampled as scipy.signal.resample does; `import --list` shows each
/// channel's direction, location and rate.
#[test]
fn issue_44_stations_of_several_recorders_import_by_station_channel() {
    let dir = fresh_dir("import-v2-stations");
    let expected: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(root().join("tests/fixtures/v2/expected_stations.json")).unwrap(),
    )
    .unwrap();
    let fixture = |f: &str| root().join("tests/fixtures/v2").join(f).to_str().unwrap().to_string();
    let import_station = |label: &str, channels_count: usize| {
        let config = dir.join(format!("{label}.toml"));
        let sensors: String = (1..=channels_count)
            .map(|c| format!("[[sensors]]\nname = \"ch{c}\"\ndirection = \"z\"\n\n"))
            .collect();
        std::fs::write(&config, format!("[structure]\nname = \"{label}\"\n\n{sensors}")).unwrap();
        let out = dir.join(format!("{label}.mcap"));
        let o = Command::new(env!("CARGO_BIN_EXE_splinewatch"))
            .args(["import", "--config", config.to_str().unwrap(), "--format", "v2"])
            .arg(fixture(&format!("{label}.zip")))
            .args(["--out", out.to_str().unwrap()])
            .output()
            .unwrap();
        assert!(o.status.success(), "{label}: {}", String::from_utf8_lossy(&o.stderr));
        channels(&out)
    };
    let meloland = import_station("meloland_like", 28);
    assert_eq!(meloland.len(), 28);
    for (name, _, fs, _, data) in &meloland {
        assert_eq!(*fs, 100.0, "{name}");
        let reference = expected["meloland_like"][name]["accel"].as_array().unwrap();
        assert_eq!(data.len(), reference.len(), "{name}");
        for (v, r) in data.iter().zip(reference) {
            let r = r.as_f64().unwrap() * 0.01;
            assert!((v - r).abs() <= 1e-15 * r.abs().max(1e-3), "{name}: {v} vs quakeio {r}");
        }
    }
    let hayward = import_station("hayward_like", 8);
    let start = parse_timestamp("2026-11-23T10:00:00.5Z").unwrap();
    for (name, _, fs, start_ns, data) in &hayward {
        assert_eq!((*fs, *start_ns, data.len()), (100.0, start, 1450), "{name}");
        let grid = expected["hayward_like"][name]["grid"].as_array().unwrap();
        // The 100 Hz channels are cut exactly; the 200 Hz ones resampled by an
        // FFT of 2900 points (round-off of the two FFTs, 1e-12 of the peak).
        let peak = grid.iter().map(|r| r.as_f64().unwrap().abs()).fold(0.0, f64::max) * 0.01;
        for (k, (v, r)) in data.iter().zip(grid).enumerate() {
            let r = r.as_f64().unwrap() * 0.01;
            assert!((v - r).abs() <= 1e-12 * peak, "{name}[{k}]: {v} vs scipy {r}");
        }
    }
    let o = Command::new(env!("CARGO_BIN_EXE_splinewatch"))
        .args(["import", "--format", "v2", "--list", &fixture("hayward_like.zip")])
        .output()
        .unwrap();
    let listing = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(listing.lines().count(), 9, "{listing}");
    assert!(
        listing
            .lines()
            .any(|l| l.starts_with("ch6\t90 Deg\tDeck midspan\t200\t3200\t")),
        "{listing}"
    );
}

/// Issue 44: the real records of the Painter Street Overpass
/// (tests/fixtures/painter-street) list by station channel with their
/// locations, as `channel_conf.py` of mdof names them (inputs 3, 17, 20 and
/// outputs 7, 9, 4 transverse), and a damaged zip is one clear error.
#[test]
fn issue_44_a_real_station_lists_its_channels() {
    let zip = root().join("tests/fixtures/painter-street/RioDell_14Sep2012_71842255_ce89324p.zip");
    let o = Command::new(env!("CARGO_BIN_EXE_splinewatch"))
        .args(["import", "--format", "v2", "--list", zip.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let listing = String::from_utf8_lossy(&o.stdout);
    let columns: Vec<&str> = listing.lines().skip(1).map(|l| l.split('\t').next().unwrap()).collect();
    let expected: Vec<String> = [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 15, 16, 17, 18, 19, 20]
        .iter()
        .map(|c| format!("ch{c}"))
        .collect();
    assert_eq!(columns, expected);
    assert!(
        listing.contains("ch17\tTran\tOn Ground: Near East Abutment\t200\t11980\t"),
        "{listing}"
    );
    assert!(
        listing.contains("ch7\tTran\tMiddle Bent: Top of Column\t200\t"),
        "{listing}"
    );
    let dir = fresh_dir("import-v2-damaged");
    let mut bytes = std::fs::read(&zip).unwrap();
    bytes.truncate(bytes.len() / 2);
    let damaged = dir.join("damaged.zip");
    std::fs::write(&damaged, bytes).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_splinewatch"))
        .args(["import", "--format", "v2", "--list", damaged.to_str().unwrap()])
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && e.contains("damaged.zip") && e.lines().count() <= 3,
        "{e}"
    );
}

/// Station archives as they come (tests/fixtures/make_v2_fixtures.py,
/// `archives`): a real record of 1980 in the CDMG's upper-case layout (two
/// recorders of 1100 and 985 points at 50 Hz, one trigger time) imports on
/// one grid from its trigger time, every value as quakeio reads it and the
/// longer channels' cut said on stderr; a zip holding the station's combined
/// file and its per-channel files imports as the combined file alone, and is
/// refused, naming both files, where a copy differs.
#[test]
fn station_archives_as_they_come_import_or_are_refused_by_name() {
    let dir = fresh_dir("import-v2-archives");
    let expected: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(root().join("tests/fixtures/v2/expected_archives.json")).unwrap(),
    )
    .unwrap();
    let expected = &expected["trinidad_1980"];
    let names: Vec<String> = expected.as_object().unwrap().keys().cloned().collect();
    assert_eq!(names.len(), 18);
    let config = dir.join("painter.toml");
    write_naming_config(
        &config,
        "painter",
        &names.iter().map(String::as_str).collect::<Vec<_>>(),
    );
    let zip = root().join("tests/fixtures/painter-street/trinidad-offshore_08nov1980_ce89324p.zip");
    let import = |inputs: &[&Path], out: &Path| {
        Command::new(env!("CARGO_BIN_EXE_splinewatch"))
            .args(["import", "--config", config.to_str().unwrap(), "--format", "v2"])
            .args(inputs)
            .arg("--out")
            .arg(out)
            .output()
            .unwrap()
    };
    let out = dir.join("trinidad.mcap");
    let o = import(&[&zip], &out);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    // The 1100-point channels are cut to the 985 points all share, and it is said.
    assert!(
        stderr.contains("the channels share 19.70 s") && stderr.contains("ch1 (22.00 s)") && !stderr.contains("ch12 ("),
        "{stderr}"
    );
    let got = channels(&out);
    assert_eq!(got.len(), 18);
    let start = parse_timestamp("1980-11-08T10:27:55.4Z").unwrap();
    for (name, _, fs, start_ns, data) in &got {
        assert_eq!((*fs, *start_ns, data.len()), (50.0, start, 985), "{name}");
        assert_eq!(expected[name]["time_step"], 0.02, "{name}");
        let reference = expected[name]["accel"].as_array().unwrap();
        for (k, (v, r)) in data.iter().zip(reference).enumerate() {
            let r = r.as_f64().unwrap() * 0.01;
            assert!(
                (v - r).abs() <= 1e-15 * r.abs().max(1e-3),
                "{name}[{k}]: {v} vs quakeio {r}"
            );
        }
    }
    let o = Command::new(env!("CARGO_BIN_EXE_splinewatch"))
        .args(["import", "--format", "v2", "--list"])
        .arg(&zip)
        .output()
        .unwrap();
    let listing = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        listing.contains("ch11\t270 DEG\tDECK, NEAR EAST ABUTMENT\t50\t1100\t"),
        "{listing}"
    );

    // The combined file and the channel files of one station in one zip.
    let fixture = |f: &str| root().join("tests/fixtures/v2").join(f);
    let sensors: String = (1..=4)
        .map(|c| format!("[[sensors]]\nname = \"ch{c}\"\ndirection = \"z\"\n\n"))
        .collect();
    std::fs::write(&config, format!("[structure]\nname = \"v2\"\n\n{sensors}")).unwrap();
    let (both, alone) = (dir.join("both.mcap"), dir.join("alone.mcap"));
    let o = import(&[&fixture("combined_and_channels.zip")], &both);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = import(&[&fixture("station.V2")], &alone);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(channels(&both), channels(&alone));
    let o = import(&[&fixture("combined_differs.zip")], &dir.join("differs.mcap"));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success()
            && e.contains("combined_differs.zip:CHAN002.V2")
            && e.contains("channel 2 is also in")
            && e.contains("combined_differs.zip:26001.V2"),
        "{e}"
    );
    assert_eq!(e.lines().filter(|l| !l.trim().is_empty()).count(), 1, "{e}");
}
