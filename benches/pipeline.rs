//! Replay throughput of the bundled recording (with its updates), of one
//! simulated hour on the FRF path and output-only, and the ingest cost of
//! the pipeline per 1000 samples (decode + align + Welch, no updates).
//! Run: `cargo bench --bench pipeline`.

use splinewatch::config::load_config;
use splinewatch::config::ScheduleConfig;
use splinewatch::io::recording::{read_recording, RecordingWriter};
use splinewatch::io::wire::{self, Encoding, Limits};
use splinewatch::outputs::results::ResultsWriter;
use splinewatch::pipeline::Pipeline;
use splinewatch::service::replay::replay;
use splinewatch::studies::simulation::{simulate, SimulationOptions};
use std::io::Cursor;
use std::path::Path;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// A simulated recording, in memory (CBOR blocks in MCAP).
fn recording(cfg: &splinewatch::config::Config, options: &SimulationOptions) -> Vec<u8> {
    let mut writer = RecordingWriter::new(Cursor::new(Vec::new()), Encoding::Cbor).unwrap();
    let prefix = cfg.topic_prefix();
    simulate(cfg, options, &mut |b| writer.write_block(&prefix, &b).map(|_| ())).unwrap();
    writer.finish().unwrap().into_inner()
}

#[divan::bench(sample_count = 3, sample_size = 1)]
fn replay_bundled_recording(bencher: divan::Bencher) {
    let cfg = load_config(&root().join("config/sinello.toml")).unwrap();
    let bytes = std::fs::read(root().join("recordings/sinello-demo.mcap")).unwrap();
    bencher.bench(|| {
        let mut w = ResultsWriter::new(Cursor::new(Vec::new()), &cfg.topic_prefix()).unwrap();
        replay(&cfg, &[&bytes], &mut w, Default::default(), &mut |_, _| {}).unwrap()
    });
}

/// One hour of the deck (simulated once, in memory) replayed with the usual
/// 10-minute analysis windows and an update per window: six warm-started
/// updates. Throughput = 3600 s / the time shown.
#[divan::bench(sample_count = 3, sample_size = 1)]
fn replay_one_hour_ten_minute_windows(bencher: divan::Bencher) {
    let mut cfg = load_config(&root().join("config/sinello.toml")).unwrap();
    cfg.frf.window_seconds = 600.0;
    let bytes = recording(&cfg, &SimulationOptions::random_excitation(&cfg, 3600.0, 7));
    bencher.bench(|| {
        let mut w = ResultsWriter::new(Cursor::new(Vec::new()), &cfg.topic_prefix()).unwrap();
        let summary = replay(&cfg, &[&bytes], &mut w, Default::default(), &mut |_, _| {}).unwrap();
        assert_eq!(summary.updates.len(), 6);
        summary
    });
}

/// One hour of output-only ambient data (twelve accelerations, four
/// unmeasured forces; simulated once, in memory) replayed with the bundled
/// output-only config in 10-minute windows: per window SSI-cov with its
/// jackknife, the pairing, and a warm-started modal-residue update.
#[divan::bench(sample_count = 3, sample_size = 1)]
fn replay_one_hour_output_only(bencher: divan::Bencher) {
    let mut cfg = load_config(&root().join("config/sinello-ambient.toml")).unwrap();
    cfg.oma_section.get_or_insert_with(Default::default).window_seconds = Some(600.0);
    let bytes = recording(&cfg, &SimulationOptions::ambient_excitation(&cfg, 3600.0, 7));
    bencher.bench(|| {
        let mut w = ResultsWriter::new(Cursor::new(Vec::new()), &cfg.topic_prefix()).unwrap();
        let summary = replay(&cfg, &[&bytes], &mut w, Default::default(), &mut |_, _| {}).unwrap();
        assert_eq!(summary.updates.len(), 6);
        summary
    });
}

/// Decoding and ingesting the 13 × 30 720 samples of the recording without
/// updates (the pipeline made beforehand); divide by 399.36 for the cost per
/// 1000 samples.
#[divan::bench(sample_count = 10, sample_size = 1)]
fn ingest_without_updates(bencher: divan::Bencher) {
    let cfg = load_config(&root().join("config/sinello.toml")).unwrap();
    let bytes = std::fs::read(root().join("recordings/sinello-demo.mcap")).unwrap();
    let payloads: Vec<Vec<u8>> = mcap::MessageStream::new(&bytes)
        .unwrap()
        .map(|m| m.unwrap().data.into_owned())
        .collect();
    let (blocks, _) = read_recording(&bytes, &Limits::default()).unwrap();
    let samples: usize = blocks.iter().map(|b| b.block.data.len()).sum();
    assert_eq!(samples, 13 * 30_720);
    let schedule = ScheduleConfig {
        update_every_windows: u64::MAX,
        ..ScheduleConfig::default()
    };
    // The pipeline (its model assembled) is made outside the timing: only
    // decoding, alignment and Welch are measured.
    bencher
        .with_inputs(|| Pipeline::new(&cfg, schedule.clone(), None).unwrap())
        .bench_local_values(|mut p| {
            for payload in &payloads {
                for block in wire::decode(payload, Encoding::Cbor, &Limits::default()).unwrap() {
                    p.ingest(block);
                }
            }
            assert_eq!(p.health().windows_accepted, 6);
            p // dropped after the timing
        });
}

/// Decoding alone, the 13 × 30 720 samples of the recording (1560 CBOR
/// messages, float64 typed arrays): the typed decoder `decode` uses, and
/// the generic value-tree decoder it falls back to, side by side.
#[divan::bench(args = ["typed", "generic"], sample_count = 20, sample_size = 1)]
fn decode_bundled_recording(bencher: divan::Bencher, decoder: &str) {
    let bytes = std::fs::read(root().join("recordings/sinello-demo.mcap")).unwrap();
    let payloads: Vec<Vec<u8>> = mcap::MessageStream::new(&bytes)
        .unwrap()
        .map(|m| m.unwrap().data.into_owned())
        .collect();
    let decode = match decoder {
        "typed" => wire::decode,
        _ => wire::decode_generic,
    };
    bencher.bench(|| {
        let mut samples = 0;
        for payload in &payloads {
            for block in decode(payload, Encoding::Cbor, &Limits::default()).unwrap() {
                samples += block.data.len();
            }
        }
        assert_eq!(samples, 13 * 30_720);
        samples
    });
}

fn main() {
    divan::main();
}
