//! Model FRFs: direct vs modal, reciprocity, phase through a resonance, and
//! sensitivities against central finite differences.

use super::common::{sinello_model, sinello_sensors, true_kappa};
use faer::c64;
use splinewatch_core::model::constraints::{Edge, EdgeConstraint, SupportKind};
use splinewatch_core::model::damping::DampingCurve;
use splinewatch_core::model::material::OrthotropicMaterial;
use splinewatch_core::model::shell::Shell;
use splinewatch_core::model::BridgeModel;
use splinewatch_core::response::frf::{FrfModel, FrfRequest, Quantity, SensorPoint};

fn damping() -> DampingCurve {
    DampingCurve::new(2, vec![0.03, 0.012, 0.02, 0.015, 0.025, 0.018, 0.03], 0.0, 80.0).unwrap()
}

fn sinello_frf_model() -> FrfModel {
    FrfModel::new(sinello_model().assemble().unwrap(), &sinello_sensors()).unwrap()
}

/// Central difference of the model FRFs of `request` in spring coefficient
/// `(field, j)`, Richardson-extrapolated from steps 1e-3 and 5e-4 of its
/// value (truncation O(h⁴)). The step is that large because the modal
/// solve's round-off enters divided by it: with steps of 1e-5, 1e-4 and
/// 1e-3 the worst column differs from the analytic one by 3.6e-5, 1.1e-6
/// and 2.8e-7, falling as 1/h.
fn spring_difference(
    model: &FrfModel,
    kappa: &[Vec<f64>],
    curve: &DampingCurve,
    request: FrfRequest<'_>,
    (field, j): (usize, usize),
) -> Vec<c64> {
    let at = |delta: f64| {
        let mut k = kappa.to_vec();
        k[field][j] += delta;
        model.evaluate(&model.modal_state(&k, curve).unwrap(), request, false).h
    };
    let central = |h: f64| -> Vec<c64> {
        let (plus, minus) = (at(h), at(-h));
        plus.iter().zip(&minus).map(|(p, m)| (p - m) / (2.0 * h)).collect()
    };
    let h = 1e-3 * kappa[field][j];
    let (coarse, fine) = (central(h), central(0.5 * h));
    fine.iter().zip(&coarse).map(|(f, c)| (4.0 * f - c) / 3.0).collect()
}

/// A damping curve with steep slopes (ζ from 0.5 % to 8 % and back within
/// 25 Hz): the modal damping's share of `∂H/∂κ` is large here (without it,
/// eq. 33 with the damping matrix fixed, a column is 12 % off).
fn steep_damping() -> DampingCurve {
    DampingCurve::new(2, vec![0.005, 0.005, 0.08, 0.01, 0.07, 0.005, 0.05], 0.0, 80.0).unwrap()
}

fn rel(a: c64, b: c64) -> f64 {
    (a - b).norm() / b.norm()
}

#[test]
fn direct_and_modal_superposition_agree() {
    let model = sinello_frf_model();
    let kappa = true_kappa();
    let state = model.modal_state(&kappa, &damping()).unwrap();
    let freqs = [0.7, 3.3, 6.68, 17.7, 41.2, 66.6, 79.9];
    let pairs = [(0, 0), (1, 0), (5, 0), (11, 3)];
    let mut worst: f64 = 0.0;
    for quantity in [Quantity::Receptance, Quantity::Mobility, Quantity::Accelerance] {
        let eval = model.evaluate(
            &state,
            FrfRequest {
                frequencies_hz: &freqs,
                pairs: &pairs,
                quantity,
            },
            false,
        );
        for (p, &pair) in pairs.iter().enumerate() {
            for (l, &f) in freqs.iter().enumerate() {
                let direct = model.direct(&kappa, &state, f, pair, quantity).unwrap();
                let e = rel(eval.h[p * freqs.len() + l], direct);
                worst = worst.max(e);
                assert!(
                    e < 1e-8,
                    "{quantity:?} {pair:?} {f} Hz: modal {} vs direct {direct} ({e:e})",
                    eval.h[p * freqs.len() + l]
                );
            }
        }
    }
    eprintln!("direct vs modal: worst relative difference {worst:.1e}");
}

#[test]
fn reciprocity_of_the_direct_path() {
    let model = sinello_frf_model();
    let kappa = true_kappa();
    let state = model.modal_state(&kappa, &damping()).unwrap();
    for f in [2.0, 9.1, 55.5] {
        for (r, s) in [(1, 0), (7, 4), (11, 2)] {
            let a = model.direct(&kappa, &state, f, (r, s), Quantity::Receptance).unwrap();
            let b = model.direct(&kappa, &state, f, (s, r), Quantity::Receptance).unwrap();
            assert!(rel(a, b) < 1e-9, "H_{r}{s} = {a} vs H_{s}{r} = {b} at {f} Hz");
        }
    }
}

#[test]
fn receptance_phase_goes_from_0_to_minus_180_through_an_isolated_resonance() {
    // A simply supported square plate: the first mode (1,1) is 2.5 times
    // below the next ones, so near it the driving-point FRF is SDOF-like.
    let plate = BridgeModel {
        springs: vec![],
        stiffness_fields: vec![],
        member_stiffness: Vec::new(),
        constraints: [Edge::Xi0, Edge::Xi1, Edge::Eta0, Edge::Eta1]
            .into_iter()
            .map(|edge| EdgeConstraint {
                edge,
                kind: SupportKind::SimplySupported,
                patch: 0,
            })
            .collect(),
        ..BridgeModel::new(
            Shell::rectangular_plate(4.0, 4.0, 0.1, [3, 3], [10, 10]).unwrap(),
            OrthotropicMaterial::isotropic(30e9, 0.2, 2400.0).unwrap(),
        )
    };
    let sensor = SensorPoint {
        patch: 0,
        xi: 0.41,
        eta: 0.37,
        tau: 0.5,
        direction: [0.0, 0.0, 1.0],
    };
    let model = FrfModel::new(plate.assemble().unwrap(), &[sensor]).unwrap();
    let state = model
        .modal_state(&[], &DampingCurve::new(1, vec![0.02, 0.02], 0.0, 100.0).unwrap())
        .unwrap();
    let first_bending = (0..state.modes.len())
        .find(|&i| state.amplitude(0, i).abs() > 1e-6)
        .expect("a mode moves the sensor");
    let f1 = state.modes.frequency_hz(first_bending);
    let freqs = [0.3 * f1, f1, 1.4 * f1];
    let eval = model.evaluate(
        &state,
        FrfRequest {
            frequencies_hz: &freqs,
            pairs: &[(0, 0)],
            quantity: Quantity::Receptance,
        },
        false,
    );
    let phase: Vec<f64> = eval.h.iter().map(|h| h.arg().to_degrees()).collect();
    assert!(phase[0] <= 0.0 && phase[0] > -2.0, "below resonance: {}", phase[0]);
    assert!((phase[1] + 90.0).abs() < 2.0, "at resonance: {}", phase[1]);
    assert!(phase[2] < -170.0 || phase[2] > 179.9, "above resonance: {}", phase[2]);
    // Receptance below resonance is positive (stiffness-controlled).
    assert!(eval.h[0].re > 0.0);
}

#[test]
fn sensitivities_match_central_differences() {
    let model = sinello_frf_model();
    let kappa = true_kappa();
    let curve = steep_damping();
    let state = model.modal_state(&kappa, &curve).unwrap();
    // Lines off and on resonances (6.68, 8.97, 21.63 Hz are modes).
    let freqs = [4.1, 6.5, 6.68, 8.97, 21.6, 23.0, 47.3, 71.9];
    let pairs = [(0, 0), (3, 0)];
    let quantity = Quantity::Accelerance;
    let request = FrfRequest {
        frequencies_hz: &freqs,
        pairs: &pairs,
        quantity,
    };
    let eval = model.evaluate(&state, request, true);
    let column_error = |analytic: &[c64], fd: &[c64]| {
        let num: f64 = analytic.iter().zip(fd).map(|(a, b)| (a - b).norm_sqr()).sum();
        let den: f64 = fd.iter().map(|b| b.norm_sqr()).sum();
        (num / den).sqrt()
    };
    // Spring coefficients: the derivative of exactly the modal superposition
    // `evaluate` computes, modes re-solved and ζ_i = ζ(f_i) following them
    // (eq. 33's fixed damping matrix plus the modal damping's share: the
    // curve's slope ζ'(f_i) ∂f_i/∂κ and the eigenvector derivatives).
    let mut worst: f64 = 0.0;
    let mut flat = 0;
    for field in 0..kappa.len() {
        for j in 0..kappa[field].len() {
            let fd = spring_difference(&model, &kappa, &curve, request, (field, j));
            let e = column_error(&eval.dh_dkappa[flat], &fd);
            worst = worst.max(e);
            assert!(e < 1e-6, "∂H/∂κ field {field} coefficient {j}: relative error {e:e}");
            flat += 1;
        }
    }
    // Damping coefficients: exact, checked on the modal path (modes fixed).
    for z in 0..curve.coefficients().len() {
        let h = 1e-6;
        let at = |delta: f64| {
            let mut g = curve.coefficients().to_vec();
            g[z] += delta;
            let s = model.restate(&state, &curve.with_coefficients(g).unwrap());
            model.evaluate(&s, request, false).h
        };
        let (plus, minus) = (at(h), at(-h));
        let fd: Vec<c64> = plus.iter().zip(&minus).map(|(p, m)| (p - m) / (2.0 * h)).collect();
        if fd.iter().all(|v| v.norm() == 0.0) {
            // γ_z whose support holds no mode of the band: both must vanish.
            assert!(eval.dh_dgamma[z].iter().all(|v| v.norm() == 0.0));
            continue;
        }
        let e = column_error(&eval.dh_dgamma[z], &fd);
        worst = worst.max(e);
        assert!(e < 1e-5, "∂H/∂γ_{z}: relative error {e:e}");
    }
    eprintln!("sensitivities vs central differences: worst relative column error {worst:.1e}");
}

#[test]
fn blocked_evaluation_matches_line_by_line() {
    // evaluate() works on blocks of FREQUENCY_BLOCK lines; several blocks, a
    // partial last block and two input sensors must give the same numbers as
    // one call per line (only the GEMM summation order differs).
    let model = sinello_frf_model();
    let state = model.modal_state(&true_kappa(), &damping()).unwrap();
    let freqs: Vec<f64> = (0..2 * splinewatch_core::response::frf::FREQUENCY_BLOCK + 7)
        .map(|k| 0.5 + 0.57 * k as f64)
        .collect();
    let pairs = [(0, 0), (3, 0), (5, 2), (0, 2)];
    let request = |freqs: &[f64]| {
        model.evaluate(
            &state,
            FrfRequest {
                frequencies_hz: freqs,
                pairs: &pairs,
                quantity: Quantity::Mobility,
            },
            true,
        )
    };
    let all = request(&freqs);
    let nf = freqs.len();
    let mut worst: f64 = 0.0;
    for (l, f) in freqs.iter().enumerate() {
        let one = request(std::slice::from_ref(f));
        let columns = std::iter::once((&all.h, &one.h))
            .chain(all.dh_dkappa.iter().zip(&one.dh_dkappa))
            .chain(all.dh_dgamma.iter().zip(&one.dh_dgamma));
        for (a, b) in columns {
            for p in 0..pairs.len() {
                let scale = (0..nf).map(|k| a[p * nf + k].norm()).fold(0.0, f64::max);
                let e = (a[p * nf + l] - b[p]).norm() / scale.max(f64::MIN_POSITIVE);
                worst = worst.max(e);
            }
        }
    }
    eprintln!("blocked vs line by line: worst difference {worst:.1e} of the column's peak");
    assert!(worst < 1e-12, "blocked evaluation differs by {worst:e}");
}

#[test]
fn threaded_evaluation_is_the_sequential_one_bit_for_bit() {
    // Whole blocks per thread: 13 blocks (the paper's 796 lines) over 2, 3
    // and 20 threads (more threads than blocks), with sensitivities.
    let model = sinello_frf_model();
    let state = model.modal_state(&true_kappa(), &damping()).unwrap();
    let freqs: Vec<f64> = (0..796).map(|k| 0.5 + 0.1 * k as f64).collect();
    let pairs = [(0, 0), (3, 0), (7, 0), (5, 2)];
    let request = FrfRequest {
        frequencies_hz: &freqs,
        pairs: &pairs,
        quantity: Quantity::Accelerance,
    };
    let bits = |e: &splinewatch_core::response::frf::FrfEvaluation| -> Vec<u64> {
        std::iter::once(&e.h)
            .chain(&e.dh_dkappa)
            .chain(&e.dh_dgamma)
            .flat_map(|column| column.iter().flat_map(|v| [v.re.to_bits(), v.im.to_bits()]))
            .collect()
    };
    let sequential = bits(&model.evaluate(&state, request, true));
    for threads in [2, 3, 20] {
        let threaded = bits(&model.evaluate_on_threads(&state, request, true, threads));
        assert!(sequential == threaded, "{threads} threads differ");
    }
    let h_only = model.evaluate_on_threads(&state, request, false, 2);
    assert!(h_only.dh_dkappa.is_empty() && h_only.dh_dgamma.is_empty());
    assert_eq!(bits(&h_only), bits(&model.evaluate(&state, request, false)));
}
