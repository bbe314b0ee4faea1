//! Output-only identification (SSI-cov) of one 10-minute window of 12
//! channels at 256 Hz of simulated ambient data on the bundled deck:
//! correlations (16 batches), the block Hankel SVD, poles at orders 2–120,
//! stabilisation, clustering and the jackknife (16 replicate SVDs).
//! Compare with `python3 benches/oma_koma.py` (koma-python on the same file).
//! Run: `cargo bench --bench oma`.

use splinewatch::config::load_config;
use splinewatch::io::recording::read_recording;
use splinewatch::io::wire::Limits;
use splinewatch::pipeline::oma::identify_span;
use splinewatch::studies::simulation::{simulate, SimulationOptions};
use std::path::Path;

#[divan::bench(sample_count = 5, sample_size = 1)]
fn ssi_cov_10_minutes_12_channels(bencher: divan::Bencher) {
    let config = load_config(&Path::new(env!("CARGO_MANIFEST_DIR")).join("config/sinello.toml")).unwrap();
    let options = SimulationOptions::ambient_excitation(&config, 600.0, 11);
    let mut writer = splinewatch::io::recording::RecordingWriter::new(
        std::io::Cursor::new(Vec::new()),
        splinewatch::io::wire::Encoding::Cbor,
    )
    .unwrap();
    let prefix = config.topic_prefix();
    simulate(&config, &options, &mut |b| writer.write_block(&prefix, &b).map(|_| ())).unwrap();
    let bytes = writer.finish().unwrap().into_inner();
    if let Ok(path) = std::env::var("SPLINEWATCH_BENCH_OMA_MCAP") {
        std::fs::write(path, &bytes).unwrap();
    }
    let (blocks, _) = read_recording(&bytes, &Limits::default()).unwrap();
    bencher.bench(|| {
        identify_span(&config, &blocks, None, None, false)
            .unwrap()
            .result
            .modes
            .len()
    });
}

fn main() {
    divan::main();
}
