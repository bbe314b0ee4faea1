//! The time-domain simulator against the model FRFs: a long band-limited
//! random excitation, Welch H1, and the model accelerance around resonances.

use super::common::{sinello_model, sinello_sensors, true_kappa};
use splinewatch_core::identification::welch::{
    Averaging, Detrend, Estimator, Gates, WelchEstimator, WelchSettings, Window,
};
use splinewatch_core::model::damping::DampingCurve;
use splinewatch_core::response::frf::{FrfModel, FrfRequest, Quantity};
use splinewatch_core::response::simulate::{band_limit, hammer_impacts, ModalSimulator};
use splinewatch_core::solvers::modal::ModeKind;

/// Deterministic uniform noise in [-0.5, 0.5) (64-bit LCG, high bits).
fn noise(n: usize, mut seed: u64) -> Vec<f64> {
    (0..n)
        .map(|_| {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((seed >> 11) as f64) / ((1u64 << 53) as f64) - 0.5
        })
        .collect()
}

#[test]
fn random_excitation_h1_matches_the_model_accelerance_near_resonances() {
    let model = FrfModel::new(sinello_model().assemble().unwrap(), &sinello_sensors()).unwrap();
    let damping = DampingCurve::new(2, vec![0.02; 7], 0.0, 80.0).unwrap();
    let state = model.modal_state(&true_kappa(), &damping).unwrap();
    let (fs, oversample, seconds) = (256.0, 16usize, 600.0);
    let n_out = (fs * seconds) as usize;
    let mut force = noise(n_out * oversample, 11);
    band_limit(&mut force, fs * oversample as f64, 0.2, 90.0);
    let sensors = [0usize, 3, 6];
    let mut sim = ModalSimulator::new(&state, model.sensor_count(), 0, 1.0 / (fs * oversample as f64));
    let mut acc = vec![0.0; model.sensor_count()];
    let mut f_out = Vec::with_capacity(n_out);
    let mut x_out: Vec<Vec<f64>> = vec![Vec::with_capacity(n_out); sensors.len()];
    for (k, &f) in force.iter().enumerate() {
        sim.advance(&[f]);
        if (k + 1) % oversample == 0 {
            sim.accelerations(&mut acc);
            f_out.push(f);
            for (o, &s) in sensors.iter().enumerate() {
                x_out[o].push(acc[s]);
            }
        }
    }
    let settings = WelchSettings {
        fs,
        segment: 4096,
        overlap: 2048,
        input_window: Window::Hann,
        output_window: Window::Hann,
        detrend: Detrend::Constant,
        averaging: Averaging::Linear,
        gates: Gates::default(),
    };
    let mut est = WelchEstimator::new(settings, sensors.len()).unwrap();
    let refs: Vec<&[f64]> = x_out.iter().map(|v| v.as_slice()).collect();
    est.push(&f_out, &refs).unwrap();
    let frf = est.spectra().frf(Estimator::H1);
    // Model accelerance on the same lines.
    let pairs: Vec<(usize, usize)> = sensors.iter().map(|&s| (s, 0)).collect();
    let eval = model.evaluate(
        &state,
        FrfRequest {
            frequencies_hz: &frf.frequencies[1..],
            pairs: &pairs,
            quantity: Quantity::Accelerance,
        },
        false,
    );
    let nl = frf.frequencies.len() - 1;
    let resonances: Vec<f64> = (0..state.modes.len())
        .filter(|&i| state.modes.kinds[i] == ModeKind::Bending && state.modes.frequency_hz(i) < 60.0)
        .map(|i| state.modes.frequency_hz(i))
        .collect();
    let mut errors = Vec::new();
    for (o, _) in sensors.iter().enumerate() {
        for l in 0..nl {
            let f = frf.frequencies[l + 1];
            let near = resonances.iter().any(|r| (f - r).abs() <= 0.3);
            if !near || frf.coherence[o][l + 1] < 0.95 {
                continue;
            }
            let model_h = eval.h[o * nl + l];
            errors.push((frf.h[o][l + 1] - model_h).norm() / model_h.norm());
        }
    }
    errors.sort_by(f64::total_cmp);
    let checked = errors.len();
    let (median, p95, worst) = (errors[checked / 2], errors[checked * 95 / 100], errors[checked - 1]);
    eprintln!(
        "simulated H1 vs model accelerance: {checked} lines within 0.3 Hz of {} resonances: median {median:.4}, 95th percentile {p95:.4}, worst {worst:.4}",
        resonances.len()
    );
    // With ~70 averages and γ² ≥ 0.95 the random error of |H1| is at most
    // √((1-γ²)/(2γ² n)) ≈ 2 %; the worst of several hundred lines is a 3σ event.
    assert!(checked > 100, "{checked}");
    assert!(median < 0.01, "median {median}");
    assert!(p95 < 0.03, "95th percentile {p95}");
    assert!(worst < 0.06, "worst {worst}");
}

#[test]
fn impact_response_energy_and_peak() {
    // A single-mode check of the impulse: a short half-sine of area A on an
    // SDOF-like driving point gives q̇(0+) ≈ a_in A per mode; the velocity
    // energy after the pulse equals ½ Σ (a_in,i A)² before damping acts.
    let model = FrfModel::new(sinello_model().assemble().unwrap(), &sinello_sensors()).unwrap();
    let damping = DampingCurve::new(2, vec![0.0; 7], 0.0, 80.0).unwrap();
    let state = model.modal_state(&true_kappa(), &damping).unwrap();
    let fs = 8192.0;
    let width = 0.002;
    let n = (fs * 0.02) as usize;
    let force = hammer_impacts(&[0.001], width, fs, n);
    let area = 2.0 * width / std::f64::consts::PI;
    let mut sim = ModalSimulator::new(&state, model.sensor_count(), 0, 1.0 / fs);
    let mut acc = vec![0.0; model.sensor_count()];
    let mut peak: f64 = 0.0;
    for &f in &force {
        sim.step(f, &mut acc);
        peak = peak.max(acc[0].abs());
    }
    // Undamped: modal energy is conserved after the pulse, so compare the
    // total mechanical energy with the impulse estimate for modes much
    // slower than the pulse (ω·width ≪ 1 for modes below ~50 Hz).
    let (x, v) = sim.physical_state(&state);
    let asm = model.dense().expect("a dense model");
    let k = asm.stiffness_with(&true_kappa()).unwrap();
    let n_dof = x.len();
    let quad = |m: &splinewatch_core::Mat<f64>, a: &[f64]| -> f64 {
        (0..n_dof)
            .map(|i| a[i] * (0..n_dof).map(|j| m[(i, j)] * a[j]).sum::<f64>())
            .sum()
    };
    let energy = 0.5 * quad(&asm.mass, &v) + 0.5 * quad(&k, &x);
    // Work done by the force: ∫ f ẋ_in dt equals the energy (no damping).
    // Impulse theory for slow modes bounds it from above by ½ Σ (a_in A)².
    let impulse_bound: f64 = (0..state.modes.len())
        .map(|i| 0.5 * (state.amplitude(0, i) * area).powi(2))
        .sum();
    eprintln!("impact: energy {energy:.4e} J, impulse estimate {impulse_bound:.4e} J, peak accel {peak:.3e}");
    assert!(
        energy > 0.0 && energy <= impulse_bound * 1.0001,
        "{energy} vs {impulse_bound}"
    );
    assert!(
        energy > 0.3 * impulse_bound,
        "most modes are slow compared with the pulse"
    );
    assert!(peak.is_finite() && peak > 0.0);
}

/// An oversampled simulation advances without forming the outputs and
/// forms them on the kept steps only: the accelerations are bit for bit
/// those of stepping with outputs at every step (two inputs, one idle for
/// a while, so the active-input shortcut is crossed too).
#[test]
fn advancing_then_reading_the_accelerations_equals_stepping() {
    let model = FrfModel::new(sinello_model().assemble().unwrap(), &sinello_sensors()).unwrap();
    let damping = DampingCurve::new(2, vec![0.02; 7], 0.0, 80.0).unwrap();
    let state = model.modal_state(&true_kappa(), &damping).unwrap();
    let sensors = model.sensor_count();
    let mut stepped = ModalSimulator::with_inputs(&state, sensors, &[0, 5], 1.0 / 1024.0);
    let mut advanced = stepped.clone();
    let (a, b) = (noise(4000, 3), noise(4000, 4));
    let (mut out_stepped, mut out_advanced) = (vec![0.0; sensors], vec![0.0; sensors]);
    let mut compared = 0;
    for k in 0..a.len() {
        let forces = [a[k], if (1000..2000).contains(&k) { 0.0 } else { b[k] }];
        stepped.step_forces(&forces, &mut out_stepped);
        advanced.advance(&forces);
        if k % 4 == 3 {
            advanced.accelerations(&mut out_advanced);
            assert_eq!(out_stepped, out_advanced, "step {k}");
            compared += 1;
        }
    }
    assert_eq!(compared, 1000);
    assert!(out_stepped.iter().any(|v| v.abs() > 0.0));
}
