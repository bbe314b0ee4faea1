//! One simulated day of 64 channels at 2 kHz (a force and 63 accelerations: P1 measures both,
//! 1-second CBOR blocks of float64 typed arrays; `benches/sinello-64ch.toml`) through the ingest path
//! only: decoding, alignment and Welch (4-s Hann segments, 50 % overlap,
//! 10-minute windows; no updates). A second thread makes the messages (a
//! logger's part, not timed); the ingest thread's CPU time is read from
//! `/proc/thread-self/stat`, so the figures are CPU seconds per real-time
//! second and nanoseconds per sample, whatever the generator costs.
//! Run: `cargo bench --bench ingest_day` (about two minutes; set
//! `SPLINEWATCH_BENCH_HOURS` for a shorter run).

use splinewatch::config::{load_config, Config, ScheduleConfig};
use splinewatch::io::wire::{self, ChannelBlock, ChannelQuantity, Encoding, Limits};
use splinewatch::pipeline::Pipeline;
use std::path::Path;
use std::sync::mpsc::sync_channel;
use std::time::Instant;

const FS: f64 = 2000.0;
const CHANNELS: usize = 64;

/// The bundled config with 64 channels (`benches/make_64ch_config.py`).
fn config() -> Config {
    load_config(&Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/sinello-64ch.toml")).unwrap()
}

/// Thread CPU time (user + system), seconds.
fn thread_cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/thread-self/stat").unwrap();
    let fields: Vec<&str> = stat[stat.rfind(')').unwrap() + 2..].split_whitespace().collect();
    // Fields 14 and 15 of stat(5), counted from the state (field 3).
    let ticks: u64 = fields[11].parse::<u64>().unwrap() + fields[12].parse::<u64>().unwrap();
    ticks as f64 / 100.0
}

fn main() {
    let hours: f64 = std::env::var("SPLINEWATCH_BENCH_HOURS")
        .ok()
        .and_then(|h| h.parse().ok())
        .unwrap_or(24.0);
    let seconds = (hours * 3600.0) as usize;
    let cfg = config();
    let names: Vec<(String, ChannelQuantity)> = std::iter::once(("P1".to_string(), ChannelQuantity::Force))
        .chain(std::iter::once(("P1".to_string(), ChannelQuantity::Acceleration)))
        .chain((0..CHANNELS - 2).map(|k| (format!("A{k}"), ChannelQuantity::Acceleration)))
        .collect();
    let schedule = ScheduleConfig {
        update_every_windows: u64::MAX,
        ..cfg.schedule.clone()
    };
    let mut pipeline = Pipeline::new(&cfg, schedule, None).unwrap();
    let (send, received) = sync_channel::<Vec<u8>>(1024);
    let generator = std::thread::Builder::new()
        .name("generator".into())
        .spawn(move || {
            let t0 = wire::parse_timestamp("2026-11-23T00:00:00Z").unwrap();
            let mut state = 0x9e37_79b9_7f4a_7c15u64;
            let mut uniform = move || {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                (state >> 11) as f64 / (1u64 << 53) as f64 - 0.5
            };
            for s in 0..seconds {
                // Responses follow the force (each with its gain and noise), so
                // the coherence gate accepts the windows as on a bridge.
                let force: Vec<f64> = (0..FS as usize).map(|_| uniform()).collect();
                for (c, (name, quantity)) in names.iter().enumerate() {
                    let data = match c {
                        0 => force.clone(),
                        _ => force
                            .iter()
                            .map(|f| f * (1.0 + 0.01 * c as f64) + 0.2 * uniform())
                            .collect(),
                    };
                    let block = ChannelBlock {
                        name: name.clone(),
                        quantity: *quantity,
                        unit: String::new(),
                        fs: FS,
                        start_ns: t0 + s as i128 * 1_000_000_000,
                        data,
                    };
                    if send.send(wire::encode(&block, Encoding::Cbor)).is_err() {
                        return;
                    }
                }
            }
        })
        .unwrap();
    let limits = Limits::default();
    let (cpu0, wall) = (thread_cpu_seconds(), Instant::now());
    let mut samples = 0u64;
    for payload in received {
        for block in wire::decode(&payload, Encoding::Cbor, &limits).unwrap() {
            samples += block.data.len() as u64;
            pipeline.ingest(block);
        }
    }
    let (cpu, wall) = (thread_cpu_seconds() - cpu0, wall.elapsed().as_secs_f64());
    generator.join().unwrap();
    let health = pipeline.health();
    assert_eq!(samples, (seconds * CHANNELS) as u64 * FS as u64);
    assert_eq!(health.windows_accepted, (seconds / 600) as u64, "{health:?}");
    let real = seconds as f64;
    println!(
        "ingest of {hours} h of {CHANNELS} channels at {FS} Hz ({samples} samples, {} windows): \
         {cpu:.1} CPU s on the ingest thread, {:.2} ns per sample, {:.5} CPU s per real-time second \
         ({:.3} % of a core), {:.0}× real time per core; wall {wall:.1} s with the generator",
        health.windows_accepted,
        cpu * 1e9 / samples as f64,
        cpu / real,
        100.0 * cpu / real,
        real / cpu,
    );
}
