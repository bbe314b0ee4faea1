//! Time-domain response by modal superposition with exact per-mode
//! recursions.
//!
//! Each mode obeys `q̈ + 2ζω q̇ + ω² q = Σ_j a_{in_j} f_j(t)` (mass-normalised,
//! forces at one or more points of the model's sensor list; several
//! uncorrelated forces are the ambient excitation of output-only tests). With the force linear between samples (first-order
//! hold), the exact discrete update is
//! `z_{k+1} = Φ z_k + Γ0 f_k + Γ1 (f_{k+1} - f_k)`, `z = (q, q̇)`, with
//! `Φ = e^{AΔt}`, `Γ0 = ∫₀^Δt e^{Aτ} B dτ` and
//! `Γ1 = (1/Δt) ∫₀^Δt e^{A(Δt-τ)} B τ dτ`, all read off the exponential of
//! the augmented 4×4 matrix `[[A, B, 0], [0, 0, 1/Δt], [0, 0, 0]] Δt`
//! (Nigam & Jennings 1969 in matrix form). This is exact for any ω,
//! including rigid modes (ω = 0). Accelerations at the sensors are
//! `ẍ_r = Σ_i a_{r,i} (a_in,i f - 2ζ_i ω_i q̇_i - ω_i² q_i)`.
//!
//! A first-order hold attenuates the band by `sinc²(π f Δt)`; callers
//! simulate at an oversampled rate and decimate (see `decimate` in the
//! application) so the error is negligible.

use crate::response::frf::ModalState;
use faer::Mat;
use std::f64::consts::PI;

/// The kept modes' recursions, one array per coefficient (mode `i` at
/// index `i`): a step runs down each array, which the compiler vectorises.
#[derive(Debug, Clone, Default)]
struct Recursions {
    /// `Φ` row by row: `Φ00, Φ01, Φ10, Φ11`.
    phi: [Vec<f64>; 4],
    /// `Γ0` and `Γ1`, the displacement's and the velocity's rows.
    g0: [Vec<f64>; 2],
    g1: [Vec<f64>; 2],
    omega2: Vec<f64>,
    two_zeta_omega: Vec<f64>,
    /// The state `(q, q̇)`.
    q: Vec<f64>,
    v: Vec<f64>,
}

impl Recursions {
    fn push(&mut self, omega2: f64, two_zeta_omega: f64, dt: f64) {
        let (phi, g0, g1) = discretise(omega2, two_zeta_omega, dt);
        for (array, value) in self.phi.iter_mut().zip([phi[0][0], phi[0][1], phi[1][0], phi[1][1]]) {
            array.push(value);
        }
        for (array, value) in self.g0.iter_mut().zip(g0).chain(self.g1.iter_mut().zip(g1)) {
            array.push(value);
        }
        self.omega2.push(omega2);
        self.two_zeta_omega.push(two_zeta_omega);
        self.q.push(0.0);
        self.v.push(0.0);
    }

    fn len(&self) -> usize {
        self.q.len()
    }
}

/// Simulates accelerations at every sensor for forces at some of them.
#[derive(Debug, Clone)]
pub struct ModalSimulator {
    modes: Recursions,
    /// `a_{in_j,i}`, input by input (`j · modes + i`): a step sums each
    /// active input over all modes at once.
    input_gains: Vec<f64>,
    /// The sensor amplitudes, mode by mode (`i · sensors + s`).
    output_gains: Vec<f64>,
    /// Per mode, the modal force `Σ_j a_{in_j,i} f_j` at the step's start,
    /// its increment and its end (the last is the modal force the
    /// acceleration at the current time includes).
    modal_inputs: [Vec<f64>; 3],
    /// Modes kept (indices into the modal state), for re-basing.
    kept: Vec<usize>,
    dt: f64,
    sensors: usize,
    last_forces: Vec<f64>,
    /// The inputs active over the last step (a buffer, reused).
    active: Vec<usize>,
    /// Inputs straight to the outputs (`sensors × inputs`; ground motion's
    /// quasi-static part), none for forces.
    feedthrough: Option<Mat<f64>>,
}

impl ModalSimulator {
    /// `input` is the sensor index where the force acts; `dt` the step.
    #[track_caller]
    pub fn new(state: &ModalState, sensors: usize, input: usize, dt: f64) -> Self {
        Self::with_inputs(state, sensors, &[input], dt)
    }

    /// Forces at the sensor indices `inputs` (one force each, see
    /// [`Self::step_forces`]). Modes no input excites (every `|a_in|` below
    /// 1e-12 of the largest) are skipped.
    #[track_caller]
    pub fn with_inputs(state: &ModalState, sensors: usize, inputs: &[usize], dt: f64) -> Self {
        assert!(!inputs.is_empty(), "at least one input");
        let gains = Mat::from_fn(state.modes.len(), inputs.len(), |i, j| state.amplitude(inputs[j], i));
        Self::with_gains(state, sensors, &gains, None, dt)
    }

    /// Inputs of any kind: `gains[(i, j)]` multiplies input `j` in mode `i`'s
    /// equation (`q̈_i + 2ζω q̇_i + ω² q_i = Σ_j gains_ij u_j`), and the
    /// accelerations at the first `sensors` sensors are `feedthrough u + Σ_i a_{r,i} q̈_i`
    /// (ground inputs: [`crate::response::support_motion`]). Modes with every
    /// gain below 1e-12 of the largest are skipped.
    #[track_caller]
    pub fn with_gains(
        state: &ModalState,
        sensors: usize,
        gains: &Mat<f64>,
        feedthrough: Option<Mat<f64>>,
        dt: f64,
    ) -> Self {
        assert!(dt > 0.0 && dt.is_finite(), "time step must be positive");
        assert!(gains.ncols() > 0, "at least one input");
        assert_eq!(gains.nrows(), state.modes.len(), "a gain row per mode");
        if let Some(f) = &feedthrough {
            assert_eq!(
                (f.nrows(), f.ncols()),
                (sensors, gains.ncols()),
                "feedthrough: sensors × inputs"
            );
        }
        let nm = state.modes.len();
        let largest = (0..nm)
            .flat_map(|i| (0..gains.ncols()).map(move |j| gains[(i, j)].abs()))
            .fold(0.0, f64::max);
        let mut modes = Recursions::default();
        let mut kept = Vec::new();
        for i in 0..nm {
            if (0..gains.ncols()).all(|j| gains[(i, j)].abs() <= 1e-12 * largest) {
                continue;
            }
            let omega2 = state.modes.omega2[i].max(0.0);
            let two_zeta_omega = 2.0 * state.zeta[i] * omega2.sqrt();
            modes.push(omega2, two_zeta_omega, dt);
            kept.push(i);
        }
        let input_gains = (0..gains.ncols())
            .flat_map(|j| kept.iter().map(move |&i| gains[(i, j)]))
            .collect();
        let output_gains = kept
            .iter()
            .flat_map(|&i| (0..sensors).map(move |s| state.amplitude(s, i)))
            .collect();
        let modal_inputs = std::array::from_fn(|_| vec![0.0; kept.len()]);
        Self {
            modes,
            input_gains,
            output_gains,
            modal_inputs,
            kept,
            dt,
            sensors,
            last_forces: vec![0.0; gains.ncols()],
            active: Vec::with_capacity(gains.ncols()),
            feedthrough,
        }
    }

    /// Sensors (points) the accelerations are written for.
    pub fn sensor_count(&self) -> usize {
        self.sensors
    }

    pub fn time_step(&self) -> f64 {
        self.dt
    }

    /// Advances one step to force `f_next` (a single-input simulator) and
    /// writes the accelerations at the new time into `out` (one per sensor).
    #[track_caller]
    pub fn step(&mut self, f_next: f64, out: &mut [f64]) {
        self.step_forces(&[f_next], out);
    }

    /// Advances one step to the forces `f_next` (one per input) and writes
    /// the accelerations at the new time into `out` (one per sensor).
    #[track_caller]
    pub fn step_forces(&mut self, f_next: &[f64], out: &mut [f64]) {
        self.advance(f_next);
        self.accelerations(out);
    }

    /// Advances one step to the forces `f_next` without forming the
    /// accelerations: an oversampled simulation keeps one step in several,
    /// and the outputs (modes × sensors) cost more than the recursion.
    /// [`Self::accelerations`] then gives exactly what [`Self::step_forces`]
    /// would have written.
    #[track_caller]
    pub fn advance(&mut self, f_next: &[f64]) {
        assert_eq!(f_next.len(), self.last_forces.len());
        // Many inputs are idle at any instant (traffic): sum only the active ones.
        self.active.clear();
        self.active
            .extend((0..f_next.len()).filter(|&j| f_next[j] != 0.0 || self.last_forces[j] != 0.0));
        let modes = self.modes.len();
        let [u0, du, u1] = &mut self.modal_inputs;
        for u in [&mut *u0, &mut *du, &mut *u1] {
            u.fill(0.0);
        }
        for &j in &self.active {
            let gains = &self.input_gains[j * modes..(j + 1) * modes];
            let (f0, f1) = (self.last_forces[j], f_next[j]);
            for (((&g, u0), du), u1) in gains.iter().zip(u0.iter_mut()).zip(du.iter_mut()).zip(u1.iter_mut()) {
                *u0 += g * f0;
                *du += g * (f1 - f0);
                *u1 += g * f1;
            }
        }
        let r = &mut self.modes;
        let n = r.len();
        let [p00, p01, p10, p11] = r.phi.each_ref().map(|a| &a[..n]);
        let ([a0, b0], [a1, b1]) = (r.g0.each_ref().map(|a| &a[..n]), r.g1.each_ref().map(|a| &a[..n]));
        let (q, v, u0, du) = (&mut r.q[..n], &mut r.v[..n], &u0[..n], &du[..n]);
        for i in 0..n {
            let (qi, vi) = (q[i], v[i]);
            q[i] = p00[i] * qi + p01[i] * vi + a0[i] * u0[i] + a1[i] * du[i];
            v[i] = p10[i] * qi + p11[i] * vi + b0[i] * u0[i] + b1[i] * du[i];
        }
        self.last_forces.copy_from_slice(f_next);
    }

    /// The accelerations at the current time, one per sensor, into `out`.
    #[track_caller]
    pub fn accelerations(&self, out: &mut [f64]) {
        assert_eq!(out.len(), self.sensors);
        out.fill(0.0);
        let r = &self.modes;
        let force = &self.modal_inputs[2];
        for (i, gains) in self.output_gains.chunks_exact(self.sensors.max(1)).enumerate() {
            let acc = force[i] - r.two_zeta_omega[i] * r.v[i] - r.omega2[i] * r.q[i];
            for (o, g) in out.iter_mut().zip(gains) {
                *o += g * acc;
            }
        }
        if let Some(f) = &self.feedthrough {
            let forces = &self.last_forces;
            for (r, o) in out.iter_mut().enumerate() {
                *o += (0..forces.len()).map(|j| f[(r, j)] * forces[j]).sum::<f64>();
            }
        }
    }

    /// Physical displacement and velocity `Φ q`, `Φ q̇` of the full model.
    pub fn physical_state(&self, state: &ModalState) -> (Vec<f64>, Vec<f64>) {
        let shapes = &state.modes.shapes;
        let n = shapes.nrows();
        let (mut x, mut v) = (vec![0.0; n], vec![0.0; n]);
        let r = &self.modes;
        for (k, &i) in self.kept.iter().enumerate() {
            for d in 0..n {
                x[d] += shapes[(d, i)] * r.q[k];
                v[d] += shapes[(d, i)] * r.v[k];
            }
        }
        (x, v)
    }

    /// Continues from a physical state on a new modal model (a parameter
    /// change during the simulation): `q' = Φ'ᵀ M x`, given the products
    /// `M x` and `M v` of the state `(x, v)` with the model's mass
    /// ([`crate::response::frf::FrfModel::mass_times`]).
    pub fn set_physical_state(&mut self, state: &ModalState, mass_x: &[f64], mass_v: &[f64]) {
        let shapes = &state.modes.shapes;
        let n = shapes.nrows();
        let r = &mut self.modes;
        for (k, &i) in self.kept.iter().enumerate() {
            r.q[k] = (0..n).map(|d| shapes[(d, i)] * mass_x[d]).sum();
            r.v[k] = (0..n).map(|d| shapes[(d, i)] * mass_v[d]).sum();
        }
    }

    /// Carries the last force sample over (a single-input simulator; used
    /// with `set_physical_state`).
    pub fn last_force(&self) -> f64 {
        self.last_forces[0]
    }

    pub fn set_last_force(&mut self, f: f64) {
        self.set_last_forces(&[f]);
    }

    /// The last force of every input.
    pub fn last_forces(&self) -> &[f64] {
        &self.last_forces
    }

    /// Carries the last forces over to a re-based simulator.
    #[track_caller]
    pub fn set_last_forces(&mut self, forces: &[f64]) {
        self.last_forces.copy_from_slice(forces);
    }
}

/// `Φ`, `Γ0`, `Γ1` for `A = [[0, 1], [-ω², -2ζω]]`, `B = (0, 1)`.
fn discretise(omega2: f64, two_zeta_omega: f64, dt: f64) -> ([[f64; 2]; 2], [f64; 2], [f64; 2]) {
    let mut m = [[0.0; 4]; 4];
    m[0][1] = dt;
    m[1][0] = -omega2 * dt;
    m[1][1] = -two_zeta_omega * dt;
    m[1][2] = dt;
    m[2][3] = 1.0;
    let e = expm4(m);
    // e = [[Φ, Γ0, Γ1·(Δt)/Δt], …]: the (1/Δt) of the augmented block is folded
    // into the ramp input, whose increment over a step is df.
    (
        [[e[0][0], e[0][1]], [e[1][0], e[1][1]]],
        [e[0][2], e[1][2]],
        [e[0][3], e[1][3]],
    )
}

/// Matrix exponential of a 4×4 matrix: scaling and squaring with a
/// degree-18 Taylor polynomial (ample for `‖M‖ ≤ 1` after scaling).
fn expm4(m: [[f64; 4]; 4]) -> [[f64; 4]; 4] {
    let norm = m
        .iter()
        .map(|r| r.iter().map(|v| v.abs()).sum::<f64>())
        .fold(0.0, f64::max);
    let squarings = if norm > 0.5 {
        (norm / 0.5).log2().ceil() as i32
    } else {
        0
    };
    let scale = 0.5f64.powi(squarings);
    let a: [[f64; 4]; 4] = m.map(|r| r.map(|v| v * scale));
    let mul = |x: &[[f64; 4]; 4], y: &[[f64; 4]; 4]| {
        let mut z = [[0.0; 4]; 4];
        for i in 0..4 {
            for j in 0..4 {
                z[i][j] = (0..4).map(|k| x[i][k] * y[k][j]).sum();
            }
        }
        z
    };
    let mut result = [[0.0; 4]; 4];
    let mut term = [[0.0; 4]; 4];
    for i in 0..4 {
        result[i][i] = 1.0;
        term[i][i] = 1.0;
    }
    for k in 1..=18 {
        term = mul(&term, &a).map(|r| r.map(|v| v / k as f64));
        for i in 0..4 {
            for j in 0..4 {
                result[i][j] += term[i][j];
            }
        }
    }
    for _ in 0..squarings {
        result = mul(&result, &result);
    }
    result
}

/// Linear chirp from `f0` to `f1` Hz over `n` samples at `fs`, unit amplitude.
pub fn swept_sine(f0: f64, f1: f64, fs: f64, n: usize) -> Vec<f64> {
    let duration = n as f64 / fs;
    let rate = (f1 - f0) / duration;
    (0..n)
        .map(|k| {
            let t = k as f64 / fs;
            (2.0 * PI * (f0 * t + 0.5 * rate * t * t)).sin()
        })
        .collect()
}

/// Half-sine hammer pulses of `width` seconds and unit peak at the given
/// start times, on `n` samples at `fs`.
pub fn hammer_impacts(starts: &[f64], width: f64, fs: f64, n: usize) -> Vec<f64> {
    let mut out = vec![0.0; n];
    for &t0 in starts {
        for (k, o) in out.iter_mut().enumerate() {
            let t = k as f64 / fs - t0;
            if (0.0..=width).contains(&t) {
                *o += (PI * t / width).sin();
            }
        }
    }
    out
}

/// Keeps the spectrum of `x` (sampled at `fs`) within `[f_lo, f_hi]` Hz and
/// zeroes the rest (FFT brick-wall; `x` is treated as one period).
pub fn band_limit(x: &mut [f64], fs: f64, f_lo: f64, f_hi: f64) {
    let n = x.len();
    if n < 2 {
        return;
    }
    let mut planner = realfft::RealFftPlanner::<f64>::new();
    let forward = planner.plan_fft_forward(n);
    let inverse = planner.plan_fft_inverse(n);
    let mut spectrum = forward.make_output_vec();
    forward.process(x, &mut spectrum).expect("sized by the plan");
    for (k, c) in spectrum.iter_mut().enumerate() {
        let f = k as f64 * fs / n as f64;
        if f < f_lo || f > f_hi {
            *c = faer::c64::new(0.0, 0.0);
        }
    }
    // Real-signal constraints of the inverse transform.
    spectrum[0].im = 0.0;
    if n % 2 == 0 {
        spectrum[n / 2].im = 0.0;
    }
    inverse.process(&mut spectrum, x).expect("sized by the plan");
    for v in x.iter_mut() {
        *v /= n as f64;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sdof_step_response_matches_closed_form() {
        // q̈ + 2ζω q̇ + ω² q = 1 (unit step, exactly linear between samples).
        let (omega, zeta, dt) = (2.0 * PI * 3.0, 0.05, 0.01);
        let (phi, g0, g1) = discretise(omega * omega, 2.0 * zeta * omega, dt);
        let mut z = [0.0, 0.0];
        let wd = omega * (1.0 - zeta * zeta).sqrt();
        for k in 1..=200 {
            z = [
                phi[0][0] * z[0] + phi[0][1] * z[1] + g0[0],
                phi[1][0] * z[0] + phi[1][1] * z[1] + g0[1],
            ];
            let _ = g1;
            let t = k as f64 * dt;
            let exact = (1.0 - (-zeta * omega * t).exp() * ((wd * t).cos() + zeta * omega / wd * (wd * t).sin()))
                / (omega * omega);
            assert!((z[0] - exact).abs() < 1e-12 / (omega * omega), "t={t}");
        }
    }

    #[test]
    fn ramp_input_is_exact_too() {
        // Rigid mode (ω = 0): q̈ = f with f = t gives q = t³/6.
        let dt = 0.1;
        let (phi, g0, g1) = discretise(0.0, 0.0, dt);
        let mut z = [0.0, 0.0];
        for k in 0..50 {
            let f0 = k as f64 * dt;
            let df = dt;
            z = [
                phi[0][0] * z[0] + phi[0][1] * z[1] + g0[0] * f0 + g1[0] * df,
                phi[1][0] * z[0] + phi[1][1] * z[1] + g0[1] * f0 + g1[1] * df,
            ];
        }
        let t: f64 = 5.0;
        assert!((z[0] - t.powi(3) / 6.0).abs() < 1e-10);
        assert!((z[1] - t * t / 2.0).abs() < 1e-10);
    }

    #[test]
    fn band_limit_removes_out_of_band_tones() {
        let fs = 100.0;
        let mut x: Vec<f64> = (0..1000)
            .map(|k| {
                let t = k as f64 / fs;
                (2.0 * PI * 5.0 * t).sin() + (2.0 * PI * 30.0 * t).sin()
            })
            .collect();
        band_limit(&mut x, fs, 1.0, 10.0);
        for (k, v) in x.iter().enumerate() {
            let t = k as f64 / fs;
            assert!((v - (2.0 * PI * 5.0 * t).sin()).abs() < 1e-9);
        }
    }
}
