//! Input–output identification (SRIM) on a simulated earthquake: the
//! Sinello deck, its two spring strips on two grounds moving with two
//! different band-limited random vertical accelerations (the measured
//! inputs), twelve vertical deck accelerometers, 2 % noise, one minute.

use super::common::grounded;
use super::common::{gaussian, in_parallel, sinello_model, sinello_sensors, true_kappa};
use splinewatch_core::identification::oma::OmaSettings;
use splinewatch_core::identification::srim::identify_io;
use splinewatch_core::model::damping::DampingCurve;
use splinewatch_core::model::supports::SupportGroups;
use splinewatch_core::response::frf::FrfModel;
use splinewatch_core::response::simulate::band_limit;
use splinewatch_core::response::support_motion::{GroundInput, SupportMotion};

const FS: f64 = 200.0;
const OVERSAMPLE: usize = 4;

/// The two ground records and the twelve deck records, and the model's
/// frequencies of the modes the grounds drive (participation above 5 % of
/// the largest) below 40 Hz.
pub(super) fn shaken_deck(seconds: f64, seed: u64) -> (Vec<Vec<f64>>, Vec<Vec<f64>>, Vec<f64>) {
    let shell_model = sinello_model();
    let model = FrfModel::new(shell_model.assemble().unwrap(), &sinello_sensors()).unwrap();
    let damping = DampingCurve::new(2, vec![0.02; 7], 0.0, 80.0).unwrap();
    let kappa = true_kappa();
    let state = model.modal_state(&kappa, &damping).unwrap();
    let groups = SupportGroups::new(vec!["west".into(), "east".into()], vec![0, 1], vec![], &shell_model).unwrap();
    let inputs = [GroundInput { group: 0, axis: 2 }, GroundInput { group: 1, axis: 2 }];
    let motion = SupportMotion::new((&model, &grounded(&shell_model, &groups)), &kappa, &[], &state, &inputs).unwrap();
    let n = (seconds * FS) as usize;
    let fine = n * OVERSAMPLE;
    let ground: Vec<Vec<f64>> = (0..2)
        .map(|j| {
            let mut g = gaussian(fine, seed * 31 + j);
            band_limit(&mut g, FS * OVERSAMPLE as f64, 0.5, 45.0);
            g
        })
        .collect();
    let mut sim = motion.simulator(&state, 1.0 / (FS * OVERSAMPLE as f64));
    let mut acc = vec![0.0; 12];
    let mut deck: Vec<Vec<f64>> = (0..12).map(|_| Vec::with_capacity(n)).collect();
    let mut measured_ground: Vec<Vec<f64>> = (0..2).map(|_| Vec::with_capacity(n)).collect();
    for k in 0..fine {
        sim.advance(&[ground[0][k], ground[1][k]]);
        if (k + 1) % OVERSAMPLE == 0 {
            sim.accelerations(&mut acc);
            deck.iter_mut().zip(&acc).for_each(|(d, a)| d.push(*a));
            measured_ground.iter_mut().zip(&ground).for_each(|(m, g)| m.push(g[k]));
        }
    }
    for (c, channel) in deck.iter_mut().chain(measured_ground.iter_mut()).enumerate() {
        let rms = (channel.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
        let noise = gaussian(n, seed * 977 + 500 + c as u64);
        channel.iter_mut().zip(noise).for_each(|(v, e)| *v += 0.02 * rms * e);
    }
    // A mode's share of the response: its participation times its largest
    // amplitude at the sensors.
    let share = |i: usize| {
        let l = motion.participation(i, 0).abs().max(motion.participation(i, 1).abs());
        l * (0..12).map(|s| state.amplitude(s, i).abs()).fold(0.0, f64::max)
    };
    let largest = (0..state.modes.len()).map(share).fold(0.0, f64::max);
    let driven: Vec<f64> = (0..state.modes.len())
        .filter(|&i| share(i) > 0.05 * largest)
        .map(|i| state.modes.frequency_hz(i))
        .filter(|&f| f > 1.0 && f < 40.0)
        .collect();
    (measured_ground, deck, driven)
}

/// Every mode the grounds drive is found within 1 % of the model's
/// frequency (the tolerance), its damping within 30 % of the 2 %
/// given, and each carries a standard deviation below 1 % of it.
#[test]
fn srim_finds_the_modes_of_a_deck_shaken_by_two_grounds() {
    let (ground, deck, driven) = shaken_deck(60.0, 3);
    let settings = OmaSettings {
        block_rows: 60,
        max_order: 80,
        band: [1.0, 40.0],
        batches: 8,
        ..OmaSettings::default()
    };
    let inputs: Vec<&[f64]> = ground.iter().map(Vec::as_slice).collect();
    let outputs: Vec<&[f64]> = deck.iter().map(Vec::as_slice).collect();
    let result = identify_io(&inputs, &outputs, FS, &settings).unwrap();
    assert!(driven.len() >= 3, "{driven:?}");
    for &f in &driven {
        let found = result.modes.iter().find(|m| (m.frequency_hz - f).abs() <= 0.01 * f);
        let m = found.unwrap_or_else(|| {
            panic!(
                "model mode {f:.3} Hz not identified; identified {:?}",
                result.modes.iter().map(|m| m.frequency_hz).collect::<Vec<_>>()
            )
        });
        assert!(
            (m.damping_ratio - 0.02).abs() <= 0.3 * 0.02,
            "{f:.3} Hz: ζ = {}",
            m.damping_ratio
        );
        assert!(
            m.frequency_std_hz.is_some_and(|s| s > 0.0 && s < 0.01 * f),
            "{f:.3} Hz: {m:?}"
        );
    }
}

/// The reported standard deviations (exact delete-one-batch replicates)
/// against the scatter of the estimates over independent records (different
/// grounds and noise, 50 seeds: the acceptance), for the three most
/// driven modes: within a factor 2 either way (the scatter of 50 records is
/// itself uncertain by about 10 %). Measured (2026-11-27): 1.77×, 1.54× and
/// 1.48× the scatter, each replicate's model made as the record's, by the
/// information matrix's own eigendecomposition (over the first 12 seeds
/// 2.15×, 1.75×, 1.02×). With the replicates' models through the `HᵀH` SVD
/// (which squares the range of the eigenvalues and scrambled high orders:
/// 13 of the 22 Painter Street modes without a std) it was 1.6×, 1.3× and
/// 1.3× over 12 seeds; with the first-order replicates and the `HᵀH` SVD
/// 1.8×, 2.1× and 5.2×, so `identify` uses the exact replicates.
#[test]
fn srim_spreads_match_the_scatter_over_records() {
    let settings = OmaSettings {
        block_rows: 60,
        max_order: 80,
        band: [1.0, 40.0],
        batches: 8,
        uncertainty: splinewatch_core::identification::oma::UncertaintyMethod::Jackknife,
        ..OmaSettings::default()
    };
    let targets = [6.681, 21.627, 39.276];
    let mut estimates: Vec<Vec<f64>> = vec![Vec::new(); 3];
    let mut reported: Vec<Vec<f64>> = vec![Vec::new(); 3];
    const RECORDS: usize = 50;
    // Independent records on every core, taken in seed order.
    let identified = in_parallel(RECORDS as u64, |k| {
        let (ground, deck, _) = shaken_deck(60.0, 10 + k);
        let inputs: Vec<&[f64]> = ground.iter().map(Vec::as_slice).collect();
        let outputs: Vec<&[f64]> = deck.iter().map(Vec::as_slice).collect();
        identify_io(&inputs, &outputs, FS, &settings).unwrap()
    });
    for result in &identified {
        for (k, &f) in targets.iter().enumerate() {
            if let Some(m) = result.modes.iter().find(|m| (m.frequency_hz - f).abs() <= 0.01 * f) {
                estimates[k].push(m.frequency_hz);
                reported[k].push(m.frequency_std_hz.unwrap_or(f64::NAN));
            }
        }
    }
    for k in 0..3 {
        let n = estimates[k].len() as f64;
        let mean = estimates[k].iter().sum::<f64>() / n;
        let scatter = (estimates[k].iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        let rms_reported = (reported[k].iter().map(|s| s * s).sum::<f64>() / n).sqrt();
        eprintln!(
            "{} Hz: found in {n} of {RECORDS}, scatter {scatter:.4}, reported {rms_reported:.4}",
            targets[k]
        );
        assert_eq!(n, RECORDS as f64, "{} Hz found in every record", targets[k]);
        let ratio = rms_reported / scatter;
        assert!(
            (0.5..=2.0).contains(&ratio),
            "{} Hz: reported {rms_reported} vs scatter {scatter}",
            targets[k]
        );
    }
}
