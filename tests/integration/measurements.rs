//! Measurements end to end: MCAP written by another tool, round trips,
//! deterministic simulation, and simulate → Welch → update.

use crate::common::simulated_recording;
use splinewatch::config::load_config;
use splinewatch::config::Config;
use splinewatch::io::recording::{read_recording, RecordedBlock};
use splinewatch::io::wire::{parse_timestamp, ChannelQuantity, Encoding, Limits};
use splinewatch::pipeline::estimate::estimate;
use splinewatch::studies;
use splinewatch::studies::simulation::{parse_scenario, SimulationOptions};
use std::path::Path;

fn config() -> Config {
    load_config(&Path::new(env!("CARGO_MANIFEST_DIR")).join("config/sinello.toml")).unwrap()
}

fn options(seconds: f64, seed: u64) -> SimulationOptions {
    SimulationOptions::random_excitation(&config(), seconds, seed)
}

#[test]
fn reads_a_recording_written_by_the_python_mcap_package() {
    let bytes =
        std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/python_recording.mcap")).unwrap();
    let (blocks, rejected) = read_recording(&bytes, &Limits::default()).unwrap();
    assert!(rejected.is_empty());
    assert_eq!(blocks.len(), 6);
    let force: Vec<&RecordedBlock> = blocks
        .iter()
        .filter(|b| b.block.quantity == ChannelQuantity::Force)
        .collect();
    assert_eq!(force.len(), 3);
    assert_eq!(force[1].topic, "bridge/fixture/force/P1");
    assert_eq!(force[1].block.data, vec![4.0, 5.0, 6.0, 7.0]);
    assert_eq!(
        force[1].block.start_ns,
        parse_timestamp("2026-11-21T10:00:00.5Z").unwrap()
    );
    assert_eq!(force[1].log_time as i128, force[1].block.start_ns);
    let accel = blocks
        .iter()
        .find(|b| b.block.name == "P2" && b.log_time == force[2].log_time)
        .unwrap();
    assert_eq!(accel.block.data, vec![4.0, 4.5, 5.0, 5.5]);
}

#[test]
fn recordings_round_trip_in_both_encodings_and_are_deterministic() {
    let cfg = config();
    for encoding in [Encoding::Cbor, Encoding::Json] {
        let bytes = simulated_recording(&cfg, &options(6.0, 7), encoding);
        let again = simulated_recording(&cfg, &options(6.0, 7), encoding);
        assert_eq!(bytes, again, "same seed, same bytes");
        let (blocks, rejected) = read_recording(&bytes, &Limits::default()).unwrap();
        assert!(rejected.is_empty());
        // 6 one-second blocks for the force and 12 accelerometers.
        assert_eq!(blocks.len(), 6 * 13);
        let p5: Vec<&RecordedBlock> = blocks.iter().filter(|b| b.block.name == "P5").collect();
        assert_eq!(p5.len(), 6);
        assert!(p5
            .iter()
            .all(|b| b.block.data.len() == 256 && b.topic == "bridge/sinello-span2/accel/P5"));
        assert!(p5
            .windows(2)
            .all(|w| w[1].block.start_ns - w[0].block.start_ns == 1_000_000_000));
        let other = simulated_recording(&cfg, &options(6.0, 8), encoding);
        assert_ne!(bytes, other, "another seed, other data");
    }
    // The summary section is present: the file is finalised.
    let bytes = simulated_recording(&cfg, &options(2.0, 1), Encoding::Cbor);
    let summary = mcap::Summary::read(&bytes).unwrap().expect("summary");
    assert_eq!(summary.channels.len(), 13);
}

#[test]
fn simulate_estimate_and_update_recover_the_springs() {
    let cfg = config();
    let bytes = simulated_recording(&cfg, &options(300.0, 3), Encoding::Cbor);
    let (blocks, _) = read_recording(&bytes, &Limits::default()).unwrap();
    let report = estimate(&cfg, &blocks, None, None).unwrap();
    assert_eq!(report.frf.frfs.len(), 12);
    assert!(report.segments.accepted >= 70);
    let start = serde_json::json!({"parameters": (1..=4).flat_map(|j| [format!("west.k{j}"), format!("east.k{j}")])
        .map(|n| serde_json::json!({"name": n, "value": 1e9})).collect::<Vec<_>>()})
    .to_string();
    let (result, _) = studies::update(
        &cfg,
        &serde_json::to_vec(&report.frf).unwrap(),
        Some(&start),
        &mut |_| {},
    )
    .unwrap();
    assert!(result.converged);
    let truth: Vec<f64> = cfg
        .model
        .springs
        .iter()
        .flat_map(|s| s.stiffness.iter().copied())
        .collect();
    for (p, t) in result.parameters.iter().zip(&truth) {
        let e = (p.value - t).abs() / t;
        assert!(e < 0.02, "{}: {} vs {t} ({e:.4})", p.name, p.value);
    }
}

/// East bearing 2 at 60 % of its stiffness from minute 1 to 2 (the model
/// changes every 5 s, the motion carried over by `q' = Φ'ᵀ M x`): the
/// springs identified before and after show it, on the every-mode model
/// and on a truncated one (`[model.solver] modes = "truncated"`: the modes
/// below 160 Hz, the sparse mass for the state transfer).
#[test]
fn a_bearing_damage_scenario_shows_in_the_identified_springs() {
    let mut truncated = config();
    truncated.model.solver.modes = splinewatch::config::ModesChoice::Truncated;
    for cfg in [config(), truncated] {
        bearing_damage_shows(&cfg);
    }
}

fn bearing_damage_shows(cfg: &Config) {
    let scenario = parse_scenario(
        "update_seconds = 5.0\n[[change]]\nparameter = \"east.k2\"\nstart_minute = 1.0\nend_minute = 2.0\nfactor = 0.6\n",
    )
    .unwrap();
    let opts = SimulationOptions {
        scenario: Some(scenario),
        ..options(420.0, 5)
    };
    let bytes = simulated_recording(cfg, &opts, Encoding::Cbor);
    let (blocks, _) = read_recording(&bytes, &Limits::default()).unwrap();
    let t0 = parse_timestamp("2026-11-21T10:00:00Z").unwrap();
    let minutes = |m: f64| Some(t0 + (m * 60e9) as i128);
    let identify = |from: f64, to: f64| {
        let report = estimate(cfg, &blocks, minutes(from), minutes(to)).unwrap();
        let (result, _) = studies::update(cfg, &serde_json::to_vec(&report.frf).unwrap(), None, &mut |_| {}).unwrap();
        result.parameters.iter().find(|p| p.name == "east.k2").unwrap().value
    };
    let before = identify(0.0, 1.0);
    let after = identify(2.5, 7.0);
    let truth = 0.4e9;
    assert!((before - truth).abs() < 0.1 * truth, "before {before}");
    assert!((after - 0.6 * truth).abs() < 0.1 * 0.6 * truth, "after {after}");
}

#[test]
fn gaps_and_missing_channels_are_clear_errors() {
    let cfg = config();
    let bytes = simulated_recording(&cfg, &options(20.0, 9), Encoding::Cbor);
    let (mut blocks, _) = read_recording(&bytes, &Limits::default()).unwrap();
    // Drop second 5 of P3: a gap.
    let t5 = parse_timestamp("2026-11-21T10:00:05Z").unwrap();
    blocks.retain(|b| !(b.block.name == "P3" && b.block.start_ns == t5));
    let e = estimate(&cfg, &blocks, None, None).unwrap_err().to_string();
    assert!(
        e.contains("channel \"P3\": gap of 1.000 s at 2026-11-21T10:00:06Z"),
        "{e}"
    );
    // The span after the gap is fine.
    assert!(estimate(&cfg, &blocks, Some(t5 + 1_000_000_000), None).is_ok());
    blocks.retain(|b| b.block.name != "P7");
    let e = estimate(&cfg, &blocks, Some(t5 + 1_000_000_000), None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("no Acceleration data for channel \"P7\""), "{e}");
}

#[test]
fn raw_recorder_rotates_by_size_and_survives_an_unusable_folder() {
    use splinewatch::{config::RawRecordingConfig, outputs::raw_recorder::RawRecorder};
    let tmp = crate::common::fresh_dir("recorder");
    let dir = tmp.join("raw");
    let bytes = std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("recordings/sinello-demo.mcap")).unwrap();
    let (blocks, _) = read_recording(&bytes, &Limits::default()).unwrap();
    let settings = RawRecordingConfig {
        enabled: true,
        dir: dir.clone(),
        rotate_minutes: 60.0,
        rotate_megabytes: 0.2,
    };
    let mut recorder = RawRecorder::new(&dir, "bridge/sinello-span2", &settings).unwrap();
    let (first, rest) = blocks.split_at(blocks.len() / 2);
    for b in first {
        recorder.record(&b.block).unwrap();
    }
    // The folder is replaced by a file (a failed mount, a full or read-only
    // disk look the same to us: creating or renaming fails). Recording
    // fails at the next rotation, with an error and no panic, and keeps
    // failing while the folder is unusable.
    std::fs::remove_dir_all(&dir).unwrap();
    std::fs::write(&dir, b"not a folder").unwrap();
    let (broken, rest) = rest.split_at(200);
    let failures = broken.iter().filter(|b| recorder.record(&b.block).is_err()).count();
    assert!(failures >= 100, "only {failures} of 200 writes failed");
    // The folder comes back: recording resumes with a new file.
    std::fs::remove_file(&dir).unwrap();
    std::fs::create_dir_all(&dir).unwrap();
    for b in rest {
        recorder.record(&b.block).unwrap();
    }
    recorder.close().unwrap();
    let mut files: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().path()).collect();
    files.sort();
    // 0.2 MB of messages per file: the rest (≈ 1.1 MB of CBOR) spans
    // several files, each complete and readable, holding every block written
    // since the folder came back.
    assert!(files.len() >= 4, "{files:?}");
    let mut read_back = 0;
    for f in &files {
        assert_eq!(f.extension().unwrap(), "mcap", "{f:?} unfinished");
        let (b, rejected) = read_recording(&std::fs::read(f).unwrap(), &Limits::default()).unwrap();
        assert!(rejected.is_empty());
        read_back += b.len();
    }
    assert_eq!(read_back, rest.len());
}
