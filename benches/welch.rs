//! Welch H1 for 12 outputs × 1 h at 256 Hz (8 s Hann segments, 50 %
//! overlap): cross spectra, auto spectra and the estimator. Compare with
//! `python3 benches/welch_scipy.py` (scipy.signal.csd/welch on the same sizes).
//! Run: `cargo bench --bench welch`.

use splinewatch_core::identification::welch::{
    Averaging, Detrend, Estimator, Gates, WelchEstimator, WelchSettings, Window,
};

const FS: f64 = 256.0;
const SAMPLES: usize = 3600 * 256;

fn signals() -> (Vec<f64>, Vec<Vec<f64>>) {
    let mut seed = 1u64;
    let mut next = move || {
        seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((seed >> 11) as f64) / ((1u64 << 53) as f64) - 0.5
    };
    let f: Vec<f64> = (0..SAMPLES).map(|_| next()).collect();
    let x = (0..12)
        .map(|k| f.iter().map(|v| v * (k + 1) as f64 + next()).collect())
        .collect();
    (f, x)
}

#[divan::bench(sample_count = 5, sample_size = 1)]
fn h1_12_outputs_1_hour(bencher: divan::Bencher) {
    let (f, x) = signals();
    let refs: Vec<&[f64]> = x.iter().map(|v| v.as_slice()).collect();
    let settings = WelchSettings {
        fs: FS,
        segment: 2048,
        overlap: 1024,
        input_window: Window::Hann,
        output_window: Window::Hann,
        detrend: Detrend::Constant,
        averaging: Averaging::Linear,
        gates: Gates::default(),
    };
    bencher.bench(|| {
        let mut est = WelchEstimator::new(settings.clone(), 12).unwrap();
        est.push(&f, &refs).unwrap();
        est.spectra().frf(Estimator::H1)
    });
}

fn main() {
    divan::main();
}
