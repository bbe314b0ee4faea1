//! Support motion (issue 44): the deck driven by its grounds against closed
//! forms, the relative formulation solved directly, superposition of groups
//! and the time recursion.

use super::common::{clamped_curved_panel, grounded, sinello_model, sinello_sensors, true_kappa};
use faer::c64;
use splinewatch_core::geometry::knots::KnotVector;
use splinewatch_core::model::constraints::{Edge, EdgeConstraint, SupportKind};
use splinewatch_core::model::damping::DampingCurve;
use splinewatch_core::model::material::{OrthotropicMaterial, OrthotropicParameters};
use splinewatch_core::model::shell::Shell;
use splinewatch_core::model::stiffness_field::StiffnessField;
use splinewatch_core::model::supports::{SupportError, SupportGroups};
use splinewatch_core::model::BridgeModel;
use splinewatch_core::response::frf::{FrfModel, ModalState, Quantity, SensorPoint};
use splinewatch_core::response::support_motion::{GroundInput, GroundedStructure, SupportMotion};
use splinewatch_core::solvers::modal::ModeKind;
use std::f64::consts::PI;

const VERTICAL: GroundInput = GroundInput { group: 0, axis: 2 };

/// The motion for `inputs` of `frf`, the model of `structure` on `groups`,
/// at spring coefficients `kappa` (no stiffness field) where `state` was
/// solved.
fn ground_motion(
    (frf, structure, groups): (&FrfModel, &BridgeModel, &SupportGroups),
    kappa: &[Vec<f64>],
    state: &ModalState,
    inputs: &[GroundInput],
) -> Result<SupportMotion, SupportError> {
    SupportMotion::new((frf, &grounded(structure, groups)), kappa, &[], state, inputs)
}

fn damping() -> DampingCurve {
    DampingCurve::new(1, vec![0.02, 0.03], 0.0, 200.0).unwrap()
}

/// The relative formulation solved directly, independent of the modal sums:
/// `T = N R + ω² N (TᵀZT)⁻¹ Tᵀ M R` with `R` the rigid translation (uniform
/// excitation): the model's direct `Z(ω)` solve ([`FrfModel::direct`]) from
/// the load row `M R` appended to the sensors.
fn direct_uniform(model: &FrfModel, kappa: &[Vec<f64>], state: &ModalState, axis: usize, f: f64) -> Vec<c64> {
    let n = state.modes.shapes.nrows();
    let rigid: Vec<f64> = (0..n).map(|d| if d % 5 == axis { 1.0 } else { 0.0 }).collect();
    let load: Vec<(usize, f64)> = model.mass_times(&rigid).into_iter().enumerate().collect();
    let loads = model.with_extra_rows(vec![load]);
    let w = 2.0 * PI * f;
    (0..model.sensor_count())
        .map(|r| {
            let quasi_static: f64 = model.sensor_rows()[r].iter().map(|&(d, v)| v * rigid[d]).sum();
            let h = loads
                .direct(kappa, state, f, (r, model.sensor_count()), Quantity::Receptance)
                .unwrap();
            c64::new(quasi_static, 0.0) + h * (w * w)
        })
        .collect()
}

fn max_relative_error(a: &[c64], b: &[c64]) -> f64 {
    let scale = b.iter().map(|v| v.norm()).fold(0.0, f64::max);
    a.iter().zip(b).map(|(x, y)| (x - y).norm()).fold(0.0, f64::max) / scale
}

/// Transmissibilities of `motion` at every sensor for input 0.
fn at_sensors(motion: &SupportMotion, state: &ModalState, sensors: usize, f: f64) -> Vec<c64> {
    let pairs: Vec<(usize, usize)> = (0..sensors).map(|s| (s, 0)).collect();
    motion.transmissibility(state, &pairs, &[f])
}

#[test]
fn a_rigid_deck_on_springs_has_the_single_dof_transmissibility() {
    // The Sinello plate 10⁶ times stiffer, on equal springs at both ends:
    // its bounce is a rigid body on springs, the first bending mode it drives
    // 450 times higher; at the centre the pitch and roll modes have a node.
    let stiff = |e: f64| e * 1e6;
    let material = OrthotropicMaterial::new(OrthotropicParameters {
        e1: stiff(5.5e9),
        e2: stiff(9.6e8),
        g12: stiff(4.3e8),
        g13: stiff(4.3e8),
        g23: stiff(4.3e8),
        nu12: 0.3,
        density: 975.0,
        angle_deg: 0.0,
        shear_correction: 5.0 / 6.0,
    })
    .unwrap();
    let plate = BridgeModel {
        springs: sinello_model().springs,
        ..BridgeModel::new(
            Shell::rectangular_plate(16.0, 9.0, 1.6, [4, 4], [13, 5]).unwrap(),
            material,
        )
    };
    let centre = SensorPoint {
        patch: 0,
        xi: 0.5,
        eta: 0.5,
        tau: 0.5,
        direction: [0.0, 0.0, 1.0],
    };
    let model = FrfModel::new(plate.assemble().unwrap(), &[centre]).unwrap();
    let kappa = vec![vec![1.0e9; 4], vec![1.0e9; 4]];
    let damping = damping();
    let state = model.modal_state(&kappa, &damping).unwrap();
    let groups = SupportGroups::uniform(&plate);
    let motion = ground_motion((&model, &plate, &groups), &kappa, &state, &[VERTICAL]).unwrap();
    let bounce = (0..state.modes.len())
        .filter(|&i| state.modes.kinds[i] != ModeKind::Rigid)
        .max_by(|&a, &b| {
            motion
                .participation(a, 0)
                .abs()
                .total_cmp(&motion.participation(b, 0).abs())
        })
        .unwrap();
    let wn = state.modes.omega2[bounce].sqrt();
    let zeta = state.zeta[bounce];
    // Every other mode the ground drives (pitch and roll are not driven: the
    // springs are symmetric) lies far above the bounce.
    let driven = |i: usize| motion.participation(i, 0).abs() > 1e-3 * motion.participation(bounce, 0).abs();
    let next = (0..state.modes.len())
        .filter(|&i| i != bounce && driven(i))
        .map(|i| state.modes.omega2[i])
        .fold(f64::MAX, f64::min);
    assert!(
        next.sqrt() > 400.0 * wn,
        "the deck is not rigid enough: {} vs {wn} rad/s",
        next.sqrt()
    );
    for ratio in [0.1, 0.5, 0.9, 1.0, 1.1, 2.0, 3.0] {
        let w = ratio * wn;
        let closed = c64::new(wn * wn, 2.0 * zeta * wn * w) / c64::new(wn * wn - w * w, 2.0 * zeta * wn * w);
        let t = motion.transmissibility(&state, &[(0, 0)], &[w / (2.0 * PI)])[0];
        // The bending modes add ≈ (ω/ω_b)² ≈ 5e-5 of their participation at 3 ω_n.
        assert!(
            (t - closed).norm() <= 1e-4 * closed.norm(),
            "r = {ratio}: {t} vs the closed form {closed}"
        );
    }
}

#[test]
fn the_absolute_formulation_gives_the_relative_one_on_the_sinello_deck_and_a_clamped_panel() {
    // Sinello: vertical springs, no constraint. Curved panel: clamped edge and
    // springs (the constraint's lift and the springs' ground forces together).
    let panel_sensors: Vec<SensorPoint> = [(0.3, 0.7), (0.8, 0.4), (0.55, 0.9)]
        .iter()
        .map(|&(xi, eta)| SensorPoint {
            patch: 0,
            xi,
            eta,
            tau: 0.5,
            direction: [0.2, 0.3, 0.9],
        })
        .collect();
    for (shell_model, sensors, axes) in [
        (sinello_model(), sinello_sensors(), vec![2]),
        (clamped_curved_panel(), panel_sensors, vec![0, 1, 2]),
    ] {
        let model = FrfModel::new(shell_model.assemble().unwrap(), &sensors).unwrap();
        let kappa = true_kappa();
        let state = model.modal_state(&kappa, &damping()).unwrap();
        let groups = SupportGroups::uniform(&shell_model);
        for axis in axes {
            let input = GroundInput { group: 0, axis };
            let motion = ground_motion((&model, &shell_model, &groups), &kappa, &state, &[input]).unwrap();
            // Γ = R: the quasi-static response is the rigid translation, and the
            // participations are Φᵀ M R.
            let n = state.modes.shapes.nrows();
            let rigid: Vec<f64> = (0..n).map(|d| if d % 5 == axis { 1.0 } else { 0.0 }).collect();
            let m_rigid = model.mass_times(&rigid);
            for (s, point) in sensors.iter().enumerate() {
                let norm = point.direction.iter().map(|v| v * v).sum::<f64>().sqrt();
                let expected = point.direction[axis] / norm;
                assert!(
                    (motion.quasi_static(s, 0) - expected).abs() <= 1e-8,
                    "axis {axis}, sensor {s}: N Γ = {} vs N R = {expected}",
                    motion.quasi_static(s, 0)
                );
            }
            let largest = (0..state.modes.len())
                .map(|i| motion.participation(i, 0).abs())
                .fold(0.0, f64::max);
            for i in 0..state.modes.len() {
                let direct: f64 = (0..n).map(|d| state.modes.shapes[(d, i)] * m_rigid[d]).sum();
                assert!(
                    (motion.participation(i, 0) - direct).abs() <= 1e-8 * largest,
                    "axis {axis}, mode {i}: L = {} vs Φᵀ M R = {direct}",
                    motion.participation(i, 0)
                );
            }
            for f in [1.0, 7.3, 23.0, 61.0] {
                let modal = at_sensors(&motion, &state, sensors.len(), f);
                let direct = direct_uniform(&model, &kappa, &state, axis, f);
                let e = max_relative_error(&modal, &direct);
                // Two exact solutions in double precision: round-off of the
                // eigen-solve and of the direct complex LU.
                assert!(e <= 1e-8, "axis {axis}, {f} Hz: modal vs direct {e:.2e}");
            }
        }
    }
}

#[test]
fn the_groups_of_a_deck_add_up_to_uniform_excitation() {
    // The clamped edge on one ground, each spring field on another: moving the
    // three grounds together is uniform excitation (superposition).
    let shell_model = clamped_curved_panel();
    let sensors: Vec<SensorPoint> = [(0.3, 0.7), (0.8, 0.4), (0.55, 0.9), (0.1, 0.2)]
        .iter()
        .map(|&(xi, eta)| SensorPoint {
            patch: 0,
            xi,
            eta,
            tau: 0.5,
            direction: [0.0, 0.0, 1.0],
        })
        .collect();
    let model = FrfModel::new(shell_model.assemble().unwrap(), &sensors).unwrap();
    let kappa = true_kappa();
    let state = model.modal_state(&kappa, &damping()).unwrap();
    let names = vec!["edge".to_string(), "west".to_string(), "east".to_string()];
    let groups = SupportGroups::new(names, vec![1, 2], vec![0], &shell_model).unwrap();
    let inputs: Vec<GroundInput> = (0..3).map(|group| GroundInput { group, axis: 2 }).collect();
    let motion = ground_motion((&model, &shell_model, &groups), &kappa, &state, &inputs).unwrap();
    let uniform = ground_motion(
        (&model, &shell_model, &SupportGroups::uniform(&shell_model)),
        &kappa,
        &state,
        &[VERTICAL],
    )
    .unwrap();
    for f in [0.5, 9.0, 40.0] {
        for s in 0..sensors.len() {
            let parts = motion.transmissibility(&state, &[(s, 0), (s, 1), (s, 2)], &[f]);
            let sum = parts.iter().fold(c64::new(0.0, 0.0), |a, b| a + b);
            let whole = uniform.transmissibility(&state, &[(s, 0)], &[f])[0];
            assert!(
                (sum - whole).norm() <= 1e-8 * whole.norm().max(1.0),
                "{f} Hz, sensor {s}: Σ groups {sum} vs uniform {whole}"
            );
            // Each group alone is a genuinely different input.
            assert!(parts.iter().all(|p| (p - whole).norm() > 1e-3 * whole.norm()));
        }
    }
    // A ground input naming no group is refused, not indexed.
    let bad = ground_motion(
        (&model, &shell_model, &groups),
        &kappa,
        &state,
        &[GroundInput { group: 3, axis: 2 }],
    );
    assert!(matches!(bad, Err(SupportError::Input { group: 3, .. })), "{bad:?}");
}

/// Two clamped edges meeting at a corner, each on its own ground: the
/// corner cannot follow both, and the grounded structure is refused once,
/// naming the two groups, before any evaluation.
#[test]
fn a_node_held_by_two_grounds_is_refused() {
    let mut panel = clamped_curved_panel();
    panel.constraints.push(EdgeConstraint {
        edge: Edge::Xi0,
        kind: SupportKind::Clamped,
        patch: 0,
    });
    let names = vec!["springs".to_string(), "south".to_string(), "west".to_string()];
    let springs = vec![0; panel.support_count()];
    let groups = SupportGroups::new(names, springs, vec![1, 2], &panel).unwrap();
    match GroundedStructure::new(panel, groups) {
        Err(e @ SupportError::TwoGrounds { .. }) => {
            let message = e.to_string();
            assert!(
                message.contains("\"south\"") && message.contains("\"west\""),
                "{message}"
            );
        }
        other => panic!("a corner on two grounds was accepted or refused otherwise: {other:?}"),
    }
}

#[test]
fn ground_motion_along_an_axis_no_support_holds_leaves_the_deck_still() {
    // The Sinello springs are vertical: nothing holds the deck along x.
    let shell_model = sinello_model();
    let model = FrfModel::new(shell_model.assemble().unwrap(), &sinello_sensors()).unwrap();
    let kappa = true_kappa();
    let state = model.modal_state(&kappa, &damping()).unwrap();
    let groups = SupportGroups::uniform(&shell_model);
    let input = GroundInput { group: 0, axis: 0 };
    // Uniform x motion has no ground force at all: Γ = 0 is the (trivial)
    // answer, and the deck does not follow.
    let motion = ground_motion((&model, &shell_model, &groups), &kappa, &state, &[input]).unwrap();
    assert!((0..12).all(|s| motion.quasi_static(s, 0).abs() < 1e-12));
}

#[test]
fn the_recursion_driven_by_the_ground_reaches_the_transmissibility() {
    let shell_model = sinello_model();
    let sensors = sinello_sensors();
    let model = FrfModel::new(shell_model.assemble().unwrap(), &sensors).unwrap();
    let kappa = true_kappa();
    let state = model.modal_state(&kappa, &damping()).unwrap();
    let groups = SupportGroups::uniform(&shell_model);
    let motion = ground_motion((&model, &shell_model, &groups), &kappa, &state, &[VERTICAL]).unwrap();
    let (f, fs) = (7.0, 2048.0);
    let mut sim = motion.simulator(&state, 1.0 / fs);
    let n = (60.0 * fs) as usize;
    let mut out = vec![0.0; sensors.len()];
    let (mut re, mut im) = (vec![0.0; sensors.len()], vec![0.0; sensors.len()]);
    let last = (10.0 * fs) as usize; // 70 periods after 50 s of settling
    for k in 1..=n {
        let t = k as f64 / fs;
        sim.step_forces(&[(2.0 * PI * f * t).sin()], &mut out);
        if k > n - last {
            for s in 0..sensors.len() {
                re[s] += out[s] * (2.0 * PI * f * t).sin() * 2.0 / last as f64;
                im[s] += out[s] * (2.0 * PI * f * t).cos() * 2.0 / last as f64;
            }
        }
    }
    let t = at_sensors(&motion, &state, sensors.len(), f);
    for s in 0..sensors.len() {
        let measured = c64::new(re[s], im[s]);
        // The first-order hold's sinc² at f/fs = 0.0034 (4e-5) and the leakage
        // of the remaining transient (e^{-ζω·50 s} ≈ 1e-19).
        assert!(
            (measured - t[s]).norm() <= 1e-3 * t[s].norm(),
            "sensor {s}: recursion {measured} vs T {}",
            t[s]
        );
    }
}

/// `∂T/∂p` of the Sinello deck with a 2 × 2 stiffness field on three
/// grounds (each spring strip its own, and a group with no support, whose
/// `Γ` is zero), against five-point central differences of `T` rebuilt at
/// every perturbed point (influence, modes, damping): every spring
/// coefficient, field coefficient and damping coefficient, within 1e-6 of
/// the largest `|∂T|` of each pair. Steps: 1e-3 of κ and γ, 1e-4 of θ (whose
/// resonances move most), where the stencil's truncation (≈ h⁴) and the
/// eigen-solve's round-off in `T` over the step are both below 1e-7. (On the
/// clamped curved panel the round-off floor of such differences is 1e-6 to
/// 1e-5: measured, not a fault of the derivative, whose formula is the same.)
#[test]
fn transmissibility_sensitivities_match_central_differences() {
    let knots = |n| KnotVector::uniform(1, n, 0.0, 1.0).unwrap();
    let field = StiffnessField::new(knots(2), knots(2), vec![1.0; 4]).unwrap();
    let shell_model = BridgeModel {
        stiffness_fields: vec![field],
        member_stiffness: Vec::new(),
        ..sinello_model()
    };
    let sensors: Vec<SensorPoint> = sinello_sensors()[..3].to_vec();
    let frf = FrfModel::new(shell_model.assemble().unwrap(), &sensors).unwrap();
    let names = vec!["still".to_string(), "west".to_string(), "east".to_string()];
    let groups = SupportGroups::new(names, vec![1, 2], vec![], &shell_model).unwrap();
    let inputs = [
        GroundInput { group: 1, axis: 2 },
        GroundInput { group: 0, axis: 2 },
        GroundInput { group: 2, axis: 2 },
    ];
    let kappa = true_kappa();
    let theta = vec![vec![1.0, 0.9, 1.1, 0.95]];
    let gamma = vec![0.02, 0.03, 0.025];
    let curve = |g: &[f64]| DampingCurve::new(2, g.to_vec(), 0.0, 200.0).unwrap();
    let lines: Vec<f64> = (1..=120).map(|k| 0.5 * k as f64).collect();
    let pairs: Vec<(usize, usize)> = (0..3).flat_map(|r| (0..3).map(move |c| (r, c))).collect();
    let transmissibility = |kappa: &[Vec<f64>], theta: &[Vec<f64>], gamma: &[f64]| {
        let state = frf.modal_state_with_fields(kappa, theta, &curve(gamma)).unwrap();
        let motion =
            SupportMotion::new((&frf, &grounded(&shell_model, &groups)), kappa, theta, &state, &inputs).unwrap();
        motion.transmissibility(&state, &pairs, &lines)
    };
    let state = frf.modal_state_with_fields(&kappa, &theta, &curve(&gamma)).unwrap();
    let motion = SupportMotion::new(
        (&frf, &grounded(&shell_model, &groups)),
        &kappa,
        &theta,
        &state,
        &inputs,
    )
    .unwrap();
    let loads = frf.with_extra_rows(motion.load_rows());
    let analytic = motion.sensitivities(&frf, &loads, &groups, &state, &curve(&gamma), &pairs, &lines);
    let nf = lines.len();
    // f'(x) ≈ (−f(x+2h) + 8 f(x+h) − 8 f(x−h) + f(x−2h)) / 12h.
    let check = |what: String, analytic: &[c64], at: &dyn Fn(f64) -> Vec<c64>, h: f64| {
        let (p2, p1, m1, m2) = (at(2.0 * h), at(h), at(-h), at(-2.0 * h));
        for p in 0..pairs.len() {
            let fd: Vec<c64> = (0..nf)
                .map(|k| {
                    let i = p * nf + k;
                    (m2[i] - p2[i] + (p1[i] - m1[i]) * 8.0) / (12.0 * h)
                })
                .collect();
            let largest = fd.iter().map(|v| v.norm()).fold(0.0, f64::max).max(1e-300);
            for k in 0..nf {
                let error = (analytic[p * nf + k] - fd[k]).norm() / largest;
                assert!(
                    error <= 1e-6,
                    "{what}, pair {:?}, {} Hz: {} vs {} ({error:.1e})",
                    pairs[p],
                    lines[k],
                    analytic[p * nf + k],
                    fd[k]
                );
            }
        }
    };
    let mut flat = 0;
    for f in 0..kappa.len() {
        for j in 0..kappa[f].len() {
            let at = |step: f64| {
                let mut k = kappa.clone();
                k[f][j] += step;
                transmissibility(&k, &theta, &gamma)
            };
            check(format!("κ[{f}][{j}]"), &analytic.dkappa[flat], &at, 1e-3 * kappa[f][j]);
            flat += 1;
        }
    }
    assert_eq!(analytic.dtheta.len(), 4);
    for j in 0..4 {
        let at = |step: f64| {
            let mut t = theta.clone();
            t[0][j] += step;
            transmissibility(&kappa, &t, &gamma)
        };
        check(format!("θ{j}"), &analytic.dtheta[j], &at, 1e-4);
    }
    for z in 0..gamma.len() {
        let at = |step: f64| {
            let mut g = gamma.clone();
            g[z] += step;
            transmissibility(&kappa, &theta, &g)
        };
        check(format!("γ{z}"), &analytic.dgamma[z], &at, 1e-3 * gamma[z]);
    }
}

/// The truncated path (modes below 100 Hz of the sparse model, the rest as
/// residual) against every mode of the dense one, on the Sinello deck whose
/// two spring strips stand on two grounds: the influence `Γ` at the sensors
/// within 1e-6 (measured 1.4e-8: the static solve brought from the
/// eigen-solve's shift to zero), and the transmissibilities from 0.5 to
/// 60 Hz within 2e-3 of each one's largest value (measured 1.3e-3, with 38 of
/// 325 modes kept: the residual's approximation of the discarded modes, as
/// on the FRF path).
#[test]
fn the_truncated_path_agrees_with_every_mode() {
    let shell_model = sinello_model();
    let sensors = sinello_sensors();
    let dense = FrfModel::new(shell_model.assemble().unwrap(), &sensors).unwrap();
    let truncated = FrfModel::truncated(&shell_model, &sensors, 100.0).unwrap();
    let names = vec!["west".to_string(), "east".to_string()];
    let groups = SupportGroups::new(names, vec![0, 1], vec![], &shell_model).unwrap();
    let inputs = [GroundInput { group: 0, axis: 2 }, GroundInput { group: 1, axis: 2 }];
    let kappa = true_kappa();
    let lines: Vec<f64> = (1..=120).map(|k| 0.5 * k as f64).collect();
    let pairs: Vec<(usize, usize)> = (0..sensors.len()).flat_map(|r| (0..2).map(move |c| (r, c))).collect();
    let run = |frf: &FrfModel| {
        let state = frf.modal_state(&kappa, &damping()).unwrap();
        let motion = ground_motion((frf, &shell_model, &groups), &kappa, &state, &inputs).unwrap();
        let loads = frf.with_extra_rows(motion.load_rows());
        let load_state = loads.modal_state(&kappa, &damping()).unwrap();
        let t = motion.transmissibility_with_residual(frf, &loads, &load_state, &pairs, &lines);
        let statics: Vec<f64> = pairs.iter().map(|&(r, c)| motion.quasi_static(r, c)).collect();
        (t, statics, state.modes.len())
    };
    let (t_dense, s_dense, all) = run(&dense);
    let (t_trunc, s_trunc, kept) = run(&truncated);
    assert!(kept < all / 4, "{kept} of {all} modes kept");
    for (k, (a, b)) in s_trunc.iter().zip(&s_dense).enumerate() {
        assert!(
            (a - b).abs() <= 1e-6 * b.abs().max(1.0),
            "pair {:?}: NΓ {a} vs {b}",
            pairs[k]
        );
    }
    let nf = lines.len();
    // The dense path's two evaluations are the same sum.
    let state = dense.modal_state(&kappa, &damping()).unwrap();
    let motion = ground_motion((&dense, &shell_model, &groups), &kappa, &state, &inputs).unwrap();
    let direct = motion.transmissibility(&state, &pairs, &lines);
    assert!(max_relative_error(&t_dense, &direct) <= 1e-10);
    let mut worst = (0.0f64, 0.0f64);
    for (a, b) in s_trunc.iter().zip(&s_dense) {
        worst.0 = worst.0.max((a - b).abs() / b.abs().max(1.0));
    }
    for (p, pair) in pairs.iter().enumerate() {
        let range = p * nf..(p + 1) * nf;
        let e = max_relative_error(&t_trunc[range.clone()], &t_dense[range]);
        worst.1 = worst.1.max(e);
        assert!(e <= 2e-3, "pair {pair:?}: truncated vs dense {e:.1e}");
    }
    eprintln!(
        "truncated vs dense: NΓ {:.1e}, T {:.1e} ({kept} of {all} modes)",
        worst.0, worst.1
    );
    // The state and the motion from one eigen-solve equal the two solves'
    // (the ground forces' static responses from the modes' factorisation).
    for frf in [&dense, &truncated] {
        let state = frf.modal_state(&kappa, &damping()).unwrap();
        let motion = ground_motion((frf, &shell_model, &groups), &kappa, &state, &inputs).unwrap();
        let (one_state, one_motion) = SupportMotion::with_state(
            (frf, &grounded(&shell_model, &groups)),
            (&kappa, &[], &damping()),
            &inputs,
        )
        .unwrap();
        assert_eq!(one_state.modes.omega2, state.modes.omega2);
        for (r, c) in pairs.iter().copied() {
            assert_eq!(
                one_motion.quasi_static(r, c),
                motion.quasi_static(r, c),
                "pair ({r}, {c})"
            );
        }
        for i in 0..state.modes.len() {
            for c in 0..inputs.len() {
                assert_eq!(one_motion.participation(i, c), motion.participation(i, c), "mode {i}");
            }
        }
    }
}
