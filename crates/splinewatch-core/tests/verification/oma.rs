//! Output-only identification (SSI-cov) on simulated ambient vibration of
//! the Sinello deck: four uncorrelated band-limited random forces at points
//! that carry no sensor, twelve vertical accelerometers, 2 % noise.

use super::common::{gaussian, in_parallel, sinello_model, sinello_sensors, true_kappa};
use faer::c64;
use splinewatch_core::identification::oma::shape::mac_real;
use splinewatch_core::identification::oma::{
    identify, IdentifiedMode, OmaResult, OmaSettings, OutputCorrelations, UncertaintyMethod,
};
use splinewatch_core::model::damping::DampingCurve;
use splinewatch_core::response::frf::{FrfModel, ModalState, SensorPoint};
use splinewatch_core::response::simulate::{band_limit, ModalSimulator};
use splinewatch_core::solvers::modal::ModeKind;

const FS: f64 = 256.0;
/// The paper's vertical accelerometers ([`sinello_sensors`]); the force
/// points follow them as sensors `SENSORS..`.
const SENSORS: usize = 12;
const OVERSAMPLE: usize = 4;
/// Unmeasured force points (x, y) in metres, away from the sensors.
const FORCE_XY: [(f64, f64); 4] = [(2.0, 1.0), (7.5, 6.5), (13.0, 3.5), (10.0, 8.2)];

/// The modal state of the model with the force points appended to the
/// sensors (sensors `SENSORS..`).
fn ambient_state() -> ModalState {
    let mut points = sinello_sensors();
    points.extend(FORCE_XY.iter().map(|&(x, y)| SensorPoint {
        patch: 0,
        xi: x / 16.0,
        eta: y / 9.0,
        tau: 0.5,
        direction: [0.0, 0.0, 1.0],
    }));
    let model = FrfModel::new(sinello_model().assemble().unwrap(), &points).unwrap();
    let damping = DampingCurve::new(2, vec![0.01; 7], 0.0, 80.0).unwrap();
    model.modal_state(&true_kappa(), &damping).unwrap()
}

/// `seconds` of accelerations at the `SENSORS` sensors.
fn ambient_record(state: &ModalState, seconds: f64, seed: u64) -> Vec<Vec<f64>> {
    let n = (seconds * FS) as usize;
    let fine = n * OVERSAMPLE;
    let forces: Vec<Vec<f64>> = (0..FORCE_XY.len())
        .map(|j| {
            let mut f = gaussian(fine, seed * 101 + j as u64);
            band_limit(&mut f, FS * OVERSAMPLE as f64, 0.5, 88.0);
            f
        })
        .collect();
    // Accelerations at the sensors only, not at the force points.
    let inputs: Vec<usize> = (SENSORS..SENSORS + FORCE_XY.len()).collect();
    let mut sim = ModalSimulator::with_inputs(state, SENSORS, &inputs, 1.0 / (FS * OVERSAMPLE as f64));
    let mut acc = vec![0.0; SENSORS];
    let mut f_now = vec![0.0; FORCE_XY.len()];
    let mut out: Vec<Vec<f64>> = (0..SENSORS).map(|_| Vec::with_capacity(n)).collect();
    for k in 0..fine {
        for (f, src) in f_now.iter_mut().zip(&forces) {
            *f = src[k];
        }
        sim.advance(&f_now);
        if (k + 1) % OVERSAMPLE == 0 {
            sim.accelerations(&mut acc);
            for (o, a) in out.iter_mut().zip(&acc) {
                o.push(*a);
            }
        }
    }
    for (c, channel) in out.iter_mut().enumerate() {
        let rms = (channel.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
        let noise = gaussian(n, seed * 977 + 500 + c as u64);
        channel.iter_mut().zip(noise).for_each(|(v, e)| *v += 0.02 * rms * e);
    }
    out
}

fn run(record: &[Vec<f64>], settings: &OmaSettings) -> OmaResult {
    let views: Vec<&[f64]> = record.iter().map(Vec::as_slice).collect();
    let correlations = OutputCorrelations::from_samples(&views, &[], settings.max_lag(), settings.batches).unwrap();
    identify(&correlations, FS, settings).unwrap()
}

/// The model's bending modes below 80 Hz: (frequency, shape at the sensors).
fn exact_modes(state: &ModalState) -> Vec<(f64, Vec<f64>)> {
    (0..state.modes.len())
        .filter(|&i| state.modes.kinds[i] == ModeKind::Bending && state.modes.frequency_hz(i) < 80.0)
        .map(|i| {
            (
                state.modes.frequency_hz(i),
                (0..SENSORS).map(|s| state.amplitude(s, i)).collect(),
            )
        })
        .collect()
}

/// The identified mode paired with each exact one (largest MAC).
fn paired<'a>(result: &'a OmaResult, exact: &[(f64, Vec<f64>)]) -> Vec<&'a IdentifiedMode> {
    exact
        .iter()
        .map(|(_, shape)| {
            result
                .modes
                .iter()
                .max_by(|a, b| mac_real(&a.shape, shape).total_cmp(&mac_real(&b.shape, shape)))
                .expect("at least one mode")
        })
        .collect()
}

/// Acceptance of the output-only issue: all 18 bending modes below 80 Hz,
/// frequency within 0.5 %, MAC > 0.9, damping within 30 %. Reached (seed 1):
/// frequencies within 0.03 %, MAC ≥ 0.996 (the closest pair, 73.49 and
/// 73.99 Hz, included), damping within 10 % of the true 1 %.
#[test]
fn twenty_minutes_of_ambient_data_give_the_bending_modes() {
    let state = ambient_state();
    let record = ambient_record(&state, 1200.0, 1);
    let result = run(&record, &OmaSettings::default());
    let exact = exact_modes(&state);
    assert_eq!(exact.len(), 18);
    assert_eq!(result.modes.len(), 18, "no spurious mode in the band");
    for ((f, shape), mode) in exact.iter().zip(paired(&result, &exact)) {
        let mac = mac_real(&mode.shape, shape);
        assert!((mode.frequency_hz / f - 1.0).abs() < 0.005, "{f} Hz: {mode:?}");
        assert!(mac > 0.9, "{f} Hz: MAC {mac}");
        assert!((mode.damping_ratio / 0.01 - 1.0).abs() < 0.3, "{f} Hz: {mode:?}");
        let std = mode.frequency_std_hz.expect("every replicate finds a mode this clear");
        assert!(
            (mode.frequency_hz - f).abs() < 4.0 * std,
            "{f} Hz: error beyond 4 std: {mode:?}"
        );
    }
    // Each identified mode is a different exact mode.
    let distinct: std::collections::BTreeSet<u64> = paired(&result, &exact)
        .iter()
        .map(|m| m.frequency_hz.to_bits())
        .collect();
    assert_eq!(distinct.len(), 18);
}

/// Monte Carlo check of both uncertainty methods (issue 32): `RECORDS`
/// independent 5-minute records (shorter than the acceptance's 10–20 min
/// to keep the suite fast; the estimators are the same), each identified
/// with first-order replicates (the default), every other one also with
/// the exact jackknife (four times the cost of the first-order method).
/// Per mode, the mean reported std of frequency, damping and shape is
/// within a factor of 2 of the scatter over all the records (the Monte
/// Carlo truth), for both methods; and on the records both identified, the
/// two methods' mean stds agree within 25 % (a record's jackknife std
/// carries ~18 % sampling error of its own with 16 batches, `1/√(2·15)`;
/// averaged over 50 records 2.5 %: what is left is the first-order
/// method's own approximation).
#[test]
fn both_uncertainty_methods_match_the_scatter_over_independent_records() {
    const RECORDS: u64 = 100;
    let state = ambient_state();
    let exact = exact_modes(&state);
    let first_order = OmaSettings::default();
    let jackknife = OmaSettings {
        uncertainty: UncertaintyMethod::Jackknife,
        ..OmaSettings::default()
    };
    // Per mode: frequencies, damping ratios, and the reported (frequency
    // std, damping std) and RMS over sensors of the shape std, each of the
    // first-order method on every record, of the jackknife, and of the
    // first-order method on the jackknife's records.
    let mut found = vec![
        (
            Vec::new(),
            Vec::new(),
            [Vec::new(), Vec::new(), Vec::new()],
            [Vec::new(), Vec::new(), Vec::new()]
        );
        exact.len()
    ];
    // The identified shapes (largest component 1 + 0i), per mode.
    let mut shapes: Vec<Vec<Vec<c64>>> = vec![Vec::new(); exact.len()];
    // The records are independent: identified on every core (each its own
    // seed, so the results do not depend on the thread count), then taken
    // in seed order.
    let identified = in_parallel(RECORDS, |seed| {
        let record = ambient_record(&state, 300.0, 1000 + seed);
        let views: Vec<&[f64]> = record.iter().map(Vec::as_slice).collect();
        let correlations = OutputCorrelations::from_samples(&views, &[], first_order.max_lag(), 16).unwrap();
        let ours = identify(&correlations, FS, &first_order).unwrap();
        let jack = (seed % 2 == 0).then(|| identify(&correlations, FS, &jackknife).unwrap());
        (ours, jack)
    });
    for (ours, jack) in &identified {
        let a = paired(ours, &exact);
        let b: Vec<Option<&IdentifiedMode>> = match jack {
            Some(jack) => paired(jack, &exact).into_iter().map(Some).collect(),
            None => vec![None; exact.len()],
        };
        for (m, ((_, shape), (x, y))) in exact.iter().zip(a.into_iter().zip(b)).enumerate() {
            if let Some(y) = y {
                assert_eq!(x.frequency_hz, y.frequency_hz, "the methods differ in the std only");
            }
            if mac_real(&x.shape, shape) > 0.9 {
                let entry = &mut found[m];
                entry.0.push(x.frequency_hz);
                entry.1.push(x.damping_ratio);
                shapes[m].push(x.shape.clone());
                let reports = [Some(x), y, y.and(Some(x))];
                for (k, mode) in reports.into_iter().enumerate() {
                    if let Some((Some(f), Some(z), Some(d))) =
                        mode.map(|mode| (mode.frequency_std_hz, mode.damping_std, &mode.shape_std))
                    {
                        entry.2[k].push((f, z));
                        entry.3[k].push((d.iter().map(|v| v * v).sum::<f64>() / d.len() as f64).sqrt());
                    }
                }
            }
        }
    }
    let std_of = |v: &[f64]| {
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
    };
    let mean_of = |v: &[(f64, f64)], pick: fn(&(f64, f64)) -> f64| v.iter().map(pick).sum::<f64>() / v.len() as f64;
    // The scatter of a shape: each record's shape scaled by the complex
    // factor that best fits it to the exact one (largest component 1), as
    // the replicates are to the reported shape; per sensor the std of the
    // component over the records, RMS over the sensors (the reported shape
    // std's measure).
    let shape_scatter = |shapes: &[Vec<c64>], exact: &[f64]| {
        let peak = exact.iter().fold(0.0f64, |m, v| if v.abs() > m.abs() { *v } else { m });
        let reference: Vec<c64> = exact.iter().map(|v| c64::new(v / peak, 0.0)).collect();
        let aligned: Vec<Vec<c64>> = shapes
            .iter()
            .map(|s| {
                let num: c64 = s.iter().zip(&reference).map(|(a, r)| a.conj() * r).sum();
                let alpha = num / s.iter().map(|a| a.norm_sqr()).sum::<f64>();
                s.iter().map(|a| a * alpha).collect()
            })
            .collect();
        let n = aligned.len() as f64;
        let var: f64 = (0..reference.len())
            .map(|k| {
                let mean = aligned.iter().map(|s| s[k]).sum::<c64>() / n;
                aligned.iter().map(|s| (s[k] - mean).norm_sqr()).sum::<f64>() / (n - 1.0)
            })
            .sum();
        (var / reference.len() as f64).sqrt()
    };
    for (((f_exact, exact_shape), (frequencies, dampings, reported, shape_stds)), shapes) in
        exact.iter().zip(&found).zip(&shapes)
    {
        // The closest pair (73.49 / 73.99 Hz, 0.7 % apart) is not always
        // separated in 5 minutes; everything else is found (MAC > 0.9 with
        // the exact shape) in nearly every record.
        let needed = if (73.0..74.5).contains(f_exact) { 60 } else { 95 };
        assert!(
            frequencies.len() >= needed,
            "{f_exact:.3} Hz found in only {}",
            frequencies.len()
        );
        let (sf, sz) = (std_of(frequencies), std_of(dampings));
        // The jackknife ran on half the records.
        let [ours, jack, ours_on_jack] = [(0, 1), (1, 2), (2, 2)].map(|(k, share)| {
            assert!(
                reported[k].len() >= needed * 9 / 10 / share,
                "{f_exact:.3} Hz: std missing"
            );
            (mean_of(&reported[k], |r| r.0), mean_of(&reported[k], |r| r.1))
        });
        eprintln!(
            "{f_exact:7.3} Hz ({:3}): frequency scatter {sf:.5}, first order {:.5}, jackknife {:.5}; \
             damping scatter {sz:.5}, first order {:.5}, jackknife {:.5}",
            frequencies.len(),
            ours.0,
            jack.0,
            ours.1,
            jack.1
        );
        for (name, claimed, truth) in [
            ("first-order frequency", ours.0, sf),
            ("jackknife frequency", jack.0, sf),
            ("first-order damping", ours.1, sz),
            ("jackknife damping", jack.1, sz),
        ] {
            let ratio = claimed / truth;
            assert!(
                (0.5..=2.0).contains(&ratio),
                "{f_exact:.3} Hz: {name} std / scatter {ratio:.2}"
            );
        }
        let [shape_ours, shape_jack] = [0, 1].map(|k| shape_stds[k].iter().sum::<f64>() / shape_stds[k].len() as f64);
        let sp = shape_scatter(shapes, exact_shape);
        eprintln!(
            "{f_exact:7.3} Hz: shape (RMS over sensors) scatter {sp:.5}, first order {shape_ours:.5}, jackknife {shape_jack:.5}"
        );
        for (name, claimed) in [("first-order shape", shape_ours), ("jackknife shape", shape_jack)] {
            let ratio = claimed / sp;
            assert!(
                (0.5..=2.0).contains(&ratio),
                "{f_exact:.3} Hz: {name} std / scatter {ratio:.2}"
            );
        }
        for (what, a, b) in [
            ("frequency", ours_on_jack.0, jack.0),
            ("damping", ours_on_jack.1, jack.1),
        ] {
            assert!(
                (a / b - 1.0).abs() < 0.25,
                "{f_exact:.3} Hz: {what} std {a} (first order) vs {b} (jackknife)"
            );
        }
    }
}

/// Peer check: the committed fixture (tests/fixtures/make_oma_peer_fixture.py)
/// holds 300 s of simulated ambient data at 128 Hz and the modes KOMA
/// (koma-python `covssi`, `find_stable_poles`, `PoleClusterer`) identified
/// in it with the same block rows, orders and stability criteria. Every
/// KOMA mode has a splinewatch mode within 0.2 % and every splinewatch mode
/// a KOMA one (KOMA's HDBSCAN splits 23.80 Hz into two clusters; both match
/// the one splinewatch mode).
#[test]
fn koma_finds_the_same_modes_in_the_committed_fixture() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/fixtures");
    let meta: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("oma_peer.json")).unwrap()).unwrap();
    let bytes = std::fs::read(dir.join("oma_peer_data.i16")).unwrap();
    let samples = meta["samples"].as_u64().unwrap() as usize;
    let scales: Vec<f64> = meta["scales"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert_eq!(bytes.len(), 2 * samples * scales.len());
    let channels: Vec<Vec<f64>> = scales
        .iter()
        .enumerate()
        .map(|(c, scale)| {
            (0..samples)
                .map(|k| {
                    let at = 2 * (c * samples + k);
                    f64::from(i16::from_le_bytes([bytes[at], bytes[at + 1]])) * scale
                })
                .collect()
        })
        .collect();
    let settings = OmaSettings {
        block_rows: meta["block_rows"].as_u64().unwrap() as usize,
        min_order: 2,
        max_order: 80,
        band: [0.5, 55.0],
        ..OmaSettings::default()
    };
    let views: Vec<&[f64]> = channels.iter().map(Vec::as_slice).collect();
    let correlations = OutputCorrelations::from_samples(&views, &[], settings.max_lag(), settings.batches).unwrap();
    let ours = identify(&correlations, meta["fs_hz"].as_f64().unwrap(), &settings)
        .unwrap()
        .modes;
    let koma: Vec<f64> = meta["koma_modes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m["frequency_hz"].as_f64().unwrap())
        .collect();
    let nearest =
        |f: f64, list: &mut dyn Iterator<Item = f64>| list.map(|g| (g / f - 1.0).abs()).fold(f64::INFINITY, f64::min);
    for &f in &koma {
        let gap = nearest(f, &mut ours.iter().map(|m| m.frequency_hz));
        eprintln!("KOMA {f:8.4} Hz: splinewatch within {:.4} %", 100.0 * gap);
        assert!(
            gap < 0.002,
            "KOMA's {f:.4} Hz: nearest splinewatch mode {:.3} % away",
            100.0 * gap
        );
    }
    for m in &ours {
        let gap = nearest(m.frequency_hz, &mut koma.iter().copied());
        assert!(
            gap < 0.002,
            "splinewatch's {:.4} Hz: no KOMA mode within 0.2 %",
            m.frequency_hz
        );
    }
    assert!(ours.len() >= 9, "{} modes", ours.len());
}
