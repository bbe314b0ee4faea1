//! Welch estimation against scipy.signal (committed fixture made by
//! tests/fixtures/make_welch_fixture.py).

use splinewatch_core::identification::welch::{Averaging, Detrend, Gates, WelchEstimator, WelchSettings, Window};

#[test]
fn csd_welch_and_coherence_match_scipy() {
    let fixture: serde_json::Value = serde_json::from_str(include_str!("../fixtures/welch_scipy.json")).unwrap();
    let series = |k: &str| -> Vec<f64> {
        fixture[k]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect()
    };
    let (f, x) = (series("f"), series("x"));
    let fs = fixture["fs"].as_f64().unwrap();
    let mut worst: f64 = 0.0;
    for case in fixture["cases"].as_array().unwrap() {
        let vec = |k: &str| -> Vec<f64> {
            case[k]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_f64().unwrap())
                .collect()
        };
        let window = match case["window"].as_str().unwrap() {
            "hann" => Window::Hann,
            "hamming" => Window::Hamming,
            "blackman" => Window::Blackman,
            "flattop" => Window::FlatTop,
            "boxcar" => Window::Rectangular,
            other => panic!("window {other}"),
        };
        let settings = WelchSettings {
            fs,
            segment: case["nperseg"].as_u64().unwrap() as usize,
            overlap: case["noverlap"].as_u64().unwrap() as usize,
            input_window: window,
            output_window: window,
            detrend: if case["detrend"] == "constant" {
                Detrend::Constant
            } else {
                Detrend::None
            },
            averaging: Averaging::Linear,
            gates: Gates::default(),
        };
        let mut est = WelchEstimator::new(settings, 1).unwrap();
        est.push(&f, &[&x]).unwrap();
        let sp = est.spectra();
        let coherence = &sp.frf(splinewatch_core::identification::welch::Estimator::H1).coherence[0];
        let (pff, pxx, re, im, coh, freqs) = (
            vec("pff"),
            vec("pxx"),
            vec("pfx_re"),
            vec("pfx_im"),
            vec("coherence"),
            vec("frequencies"),
        );
        assert_eq!(sp.frequencies.len(), freqs.len());
        let rel = |a: f64, b: f64, scale: f64| (a - b).abs() / scale;
        // Relative to each spectrum's peak: bins near a zero of the window's
        // response carry no relative precision in either implementation.
        let peak = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let (sff, sxx) = (peak(&pff), peak(&pxx));
        let sfx = re.iter().zip(&im).map(|(a, b)| a.hypot(*b)).fold(0.0, f64::max);
        for k in 0..freqs.len() {
            let errs = [
                rel(sp.frequencies[k], freqs[k], fs),
                rel(sp.s_ff[k], pff[k], sff),
                rel(sp.s_xx[0][k], pxx[k], sxx),
                rel(sp.s_fx[0][k].re, re[k], sfx),
                rel(sp.s_fx[0][k].im, im[k], sfx),
                rel(coherence[k], coh[k], 1.0),
            ];
            let e = errs.iter().fold(0.0f64, |m, v| m.max(*v));
            worst = worst.max(e);
            assert!(e < 1e-9, "{} bin {k}: errors {errs:?}", case["window"]);
        }
    }
    eprintln!(
        "Welch vs scipy {}: worst relative difference {worst:.1e}",
        fixture["scipy_version"]
    );
}
