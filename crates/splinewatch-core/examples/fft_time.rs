use realfft::RealFftPlanner;
fn main() {
    for n in [1024usize, 8000, 8192] {
        let fft = RealFftPlanner::<f64>::new().plan_fft_forward(n);
        let mut input: Vec<f64> = (0..n).map(|k| (k as f64 * 0.37).sin()).collect();
        let mut out = fft.make_output_vec();
        let mut scratch = fft.make_scratch_vec();
        let reps = 20_000_000 / n;
        let t = std::time::Instant::now();
        for _ in 0..reps {
            fft.process_with_scratch(&mut input, &mut out, &mut scratch).unwrap();
        }
        let e = t.elapsed().as_secs_f64() / reps as f64;
        println!(
            "n={n}: {:.1} us per FFT, {:.2} ns per sample with 50% overlap",
            e * 1e6,
            2.0 * e * 1e9 / n as f64
        );
    }
}
