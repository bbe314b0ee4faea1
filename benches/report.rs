//! The owner's report: reading a bridge's results and writing the HTML, for
//! an event judged against 20 events (each with 8 deck channels scored, 6
//! features banded, 4 parameters, 2 modes) and for two weeks of hourly
//! monitoring (336 updates of 16 parameters with statuses and an alarm).
//! The results are synthetic in shape, real in format (MCAP written by the
//! results writer); the sizes are printed first.
//! Run: `cargo bench --bench report`.

use serde_json::json;
use splinewatch::io::results_file::read_results;
use splinewatch::outputs::report::{render, Selection};
use splinewatch::outputs::results::ResultsWriter;
use std::io::Cursor;

const HOUR_NS: i128 = 3_600_000_000_000;
const T0: i128 = 1_700_000_000_000_000_000;

fn time(t: i128) -> String {
    splinewatch::io::wire::format_timestamp(t)
}

/// Twenty events of a bridge, the last one alarmed.
fn events() -> Vec<u8> {
    let mut w = ResultsWriter::new(Cursor::new(Vec::new()), "bridge/bench").unwrap();
    for k in 0..20i128 {
        let a = 0.2 + 0.07 * k as f64;
        let f = |x: f64| x * (1.0 + 0.01 * ((k * 7 % 5) as f64 - 2.0));
        let channels: Vec<_> = (4..12)
            .map(|c| json!({"sensor": format!("ch{c}"), "nrmse": 0.6, "nrmse_strong": f(0.5), "correlation": 0.8, "peak_ratio": 1.1}))
            .collect();
        let baseline: Vec<_> = (4..12)
            .map(|c| json!({"sensor": format!("ch{c}"), "nrmse": 0.8, "nrmse_strong": f(0.8), "correlation": 0.6, "peak_ratio": 0.9, "ground": "ch15"}))
            .collect();
        let features = [
            "mode1_hz",
            "mode2_hz",
            "log10_west.ky",
            "log10_bent.ky",
            "log10_east.ky",
            "log10_damping.g1",
        ];
        let values = [f(3.4), f(4.8), f(9.1), f(7.9), f(8.6), f(-1.1)];
        let bands: Vec<_> = features
            .iter()
            .zip(values)
            .map(|(name, v)| json!({"feature": name, "value": v, "band": if k >= 5 { json!({"predicted": v, "lower": v - 0.1, "upper": v + 0.1, "events": k}) } else { json!(null) }}))
            .collect();
        let parameters: Vec<_> = ["west.ky", "bent.ky", "east.ky", "damping.g1"]
            .iter()
            .map(|n| json!({"name": n, "value": f(1.0e8), "std": 1.0e6, "lower": 1.0e6, "upper": 1.0e11}))
            .collect();
        let summary = json!({
            "event": format!("event{k:02}.zip"), "number": k, "start": time(T0 + k * 30 * 24 * HOUR_NS),
            "pga_ground": a, "peak_deck": 2.0 * a, "rms_deck": 0.4 * a,
            "modes": [{"frequency_hz": f(3.4), "damping_ratio": 0.02, "frequency_std_hz": 0.02, "damping_std": 0.004, "shape": []},
                      {"frequency_hz": f(4.8), "damping_ratio": 0.015, "frequency_std_hz": 0.03, "damping_std": 0.005, "shape": []}],
            "parameters": parameters,
            "forecast": if k > 0 { json!({"channels": channels, "baseline": baseline, "strong_span_s": [5.0, 25.0]}) } else { json!(null) },
            "forecast_model": [], "forecast_channels": ["ch4", "ch7", "ch9"],
            "verdict": {"state": if k == 19 { "alarm" } else if k >= 5 { "normal" } else { "insufficient history" }, "outside": if k == 19 { json!(["log10_bent.ky"]) } else { json!([]) }, "bands": bands},
            "skipped": null,
            "update": {"model_mode_hz": f(4.1), "relative_residual": 0.4, "iterations": 9, "converged": true, "stop_reason": "relative_offset", "residues": "frf"},
            "notes": []
        });
        w.write_json("events/summary", T0 + k, summary.to_string().as_bytes())
            .unwrap();
    }
    w.finish().unwrap().into_inner()
}

/// Two weeks of hourly updates of 16 parameters with their statuses, in
/// alarm from hour 200.
fn two_weeks() -> Vec<u8> {
    let mut w = ResultsWriter::new(Cursor::new(Vec::new()), "bridge/bench").unwrap();
    for h in 0..336i128 {
        let t = T0 + h * HOUR_NS;
        let parameters: Vec<_> = (0..16)
            .map(|p| json!({"name": format!("field.k{p}"), "value": 1.0e9 * (1.0 + 0.001 * ((h * (p + 3)) % 11) as f64), "std": 1.0e6, "lower": 1.0e7, "upper": 5.0e9}))
            .collect();
        let update = json!({"time": time(t), "window": h, "converged": true, "relative_residual": 0.02, "parameters": parameters});
        w.write_json("updating/parameters", t, update.to_string().as_bytes())
            .unwrap();
        let state = if h < 100 {
            "training"
        } else if h < 200 {
            "normal"
        } else {
            "alarm"
        };
        let status = json!({"window": h, "time": time(t), "state": state, "t2": 10.0 + h as f64, "t2_limit": 60.0,
            "mewma": 5.0, "mewma_limit": 40.0, "temperature_c": 10.0, "residuals": [{"name": "field.k2", "standardised": 1.0}]});
        w.write_json("monitoring/status", t, status.to_string().as_bytes())
            .unwrap();
        if h == 200 {
            let alarm = json!({"window": h, "time": time(t), "state": "alarm", "previous": "normal", "t2": 210.0, "mewma": 60.0,
                "largest_residuals": [{"name": "field.k2", "standardised": -12.0}]});
            w.write_json("monitoring/alarm", t, alarm.to_string().as_bytes())
                .unwrap();
        }
    }
    w.finish().unwrap().into_inner()
}

fn write(bytes: &[u8], selection: &Selection) -> String {
    let contents = read_results(&[("results.mcap".into(), bytes)]).unwrap();
    render(&contents, selection).unwrap().html
}

#[divan::bench(sample_count = 10)]
fn event_among_20(bencher: divan::Bencher) {
    let bytes = events();
    bencher.bench(|| write(&bytes, &Selection::Latest));
}

#[divan::bench(sample_count = 10)]
fn period_of_20_events(bencher: divan::Bencher) {
    let bytes = events();
    let all = Selection::Period { from: None, to: None };
    bencher.bench(|| write(&bytes, &all));
}

#[divan::bench(sample_count = 5)]
fn two_weeks_of_monitoring(bencher: divan::Bencher) {
    let bytes = two_weeks();
    bencher.bench(|| write(&bytes, &Selection::Latest));
}

fn main() {
    let all = Selection::Period { from: None, to: None };
    for (name, html) in [
        ("event among 20", write(&events(), &Selection::Latest)),
        ("period of 20 events", write(&events(), &all)),
        ("two weeks of monitoring", write(&two_weeks(), &Selection::Latest)),
    ] {
        println!("{name}: {} kB", html.len() / 1024);
    }
    divan::main();
}
