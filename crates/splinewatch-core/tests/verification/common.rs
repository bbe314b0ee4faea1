//! Shared fixtures: the paper's Sinello deck and its sensors.

use splinewatch_core::geometry::knots::KnotVector;
use splinewatch_core::model::constraints::{Edge, EdgeConstraint, SupportKind};
use splinewatch_core::model::material::{OrthotropicMaterial, OrthotropicParameters};
use splinewatch_core::model::shell::Shell;
use splinewatch_core::model::springs::{Face, SpringDirection, SpringField};
use splinewatch_core::model::BridgeModel;
use splinewatch_core::response::frf::{ModalState, SensorPoint};
use splinewatch_core::response::modal_sensitivity::ModalSensitivities;
use splinewatch_core::response::support_motion::GroundedStructure;
use splinewatch_core::solvers::modal::ModeKind;
use splinewatch_core::updating::{Parameter, ParameterKind};

pub fn sinello_material() -> OrthotropicMaterial {
    OrthotropicMaterial::new(OrthotropicParameters {
        e1: 5.5e9,
        e2: 9.6e8,
        g12: 4.3e8,
        g13: 4.3e8,
        g23: 4.3e8,
        nu12: 0.3,
        density: 975.0,
        angle_deg: 0.0,
        shear_correction: 5.0 / 6.0,
    })
    .unwrap()
}

pub fn sinello_springs() -> Vec<SpringField> {
    let eta = || KnotVector::new(vec![0.0, 0.0, 0.0, 0.5, 1.0, 1.0, 1.0], 2).unwrap();
    let z = SpringDirection::fixed([0.0, 0.0, 1.0]).unwrap();
    vec![
        SpringField::new(
            KnotVector::new(vec![0.0, 0.03], 0).unwrap(),
            eta(),
            vec![0.4e9, 1.5e9, 1.8e9, 0.6e9],
            z,
            Face::Bottom,
        )
        .unwrap(),
        SpringField::new(
            KnotVector::new(vec![0.97, 1.0], 0).unwrap(),
            eta(),
            vec![1.5e9, 0.4e9, 0.5e9, 1.8e9],
            z,
            Face::Bottom,
        )
        .unwrap(),
    ]
}

/// The paper's true spring coefficients (eq. 47), per field.
pub fn true_kappa() -> Vec<Vec<f64>> {
    vec![vec![0.4e9, 1.5e9, 1.8e9, 0.6e9], vec![1.5e9, 0.4e9, 0.5e9, 1.8e9]]
}

pub fn sinello_model() -> BridgeModel {
    BridgeModel {
        springs: sinello_springs(),
        stiffness_fields: vec![],
        member_stiffness: Vec::new(),
        constraints: vec![],
        ..BridgeModel::new(
            Shell::rectangular_plate(16.0, 9.0, 1.6, [4, 4], [13, 5]).unwrap(),
            sinello_material(),
        )
    }
}

/// The twelve sensor positions (x, y) in metres used for the paper's
/// experiments (also in config/sinello.toml): spread over the deck, off its
/// symmetry lines, P1 is the driving point.
pub const SENSOR_XY: [(f64, f64); 12] = [
    (3.1, 2.2),
    (12.7, 6.9),
    (8.3, 7.4),
    (14.2, 1.6),
    (1.3, 5.6),
    (5.7, 4.3),
    (10.6, 3.1),
    (15.1, 5.2),
    (4.4, 8.1),
    (6.9, 0.9),
    (11.8, 8.4),
    (9.4, 5.7),
];

/// Vertical sensors on the mid-surface of the 16 m × 9 m deck.
pub fn sinello_sensors() -> Vec<SensorPoint> {
    SENSOR_XY
        .iter()
        .map(|&(x, y)| SensorPoint {
            patch: 0,
            xi: x / 16.0,
            eta: y / 9.0,
            tau: 0.5,
            direction: [0.0, 0.0, 1.0],
        })
        .collect()
}

/// A clamped cylindrical panel on the Sinello springs: curved, so nothing
/// decouples (2 × 3 m, R = 3 m, 0.6 rad, 5 cm, 7 × 6 cubic net).
pub fn clamped_curved_panel() -> BridgeModel {
    BridgeModel {
        springs: sinello_springs(),
        stiffness_fields: vec![],
        member_stiffness: Vec::new(),
        constraints: vec![EdgeConstraint {
            edge: Edge::Eta0,
            kind: SupportKind::Clamped,
            patch: 0,
        }],
        ..BridgeModel::new(
            Shell::cylindrical_panel(2.0, 3.0, 0.6, 0.05, [3, 3], [7, 6]).unwrap(),
            sinello_material(),
        )
    }
}

/// Gaussian samples (64-bit LCG and Box–Muller): deterministic per seed.
pub fn gaussian(n: usize, seed: u64) -> Vec<f64> {
    let mut state = seed.wrapping_mul(0x9E3779B97F4A7C15) | 1;
    let mut uniform = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((state >> 11) as f64 + 0.5) / ((1u64 << 53) as f64)
    };
    (0..n)
        .map(|_| {
            let (u1, u2) = (uniform(), uniform());
            (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
        })
        .collect()
}

/// The eight spring coefficients of the Sinello deck as updating
/// parameters (`f<field>.k<j>`, bounds 1e7–5e9 N/m³).
pub fn spring_parameters() -> Vec<Parameter> {
    (0..2)
        .flat_map(|field| {
            (0..4).map(move |coefficient| Parameter {
                name: format!("f{field}.k{}", coefficient + 1),
                kind: ParameterKind::Spring { field, coefficient },
                lower: 1e7,
                upper: 5e9,
            })
        })
        .collect()
}

/// The second coefficient of both strips as one parameter (`SpringRun`,
/// bounds 1e7–5e9 N/m³).
pub fn tied_second_coefficients() -> Parameter {
    Parameter {
        name: "k2 of both".into(),
        kind: ParameterKind::SpringRun {
            field: 0,
            count: 2,
            coefficient: 1,
        },
        lower: 1e7,
        upper: 5e9,
    }
}

/// The bending modes of `state` below 80 Hz.
pub fn bending_modes_below_80_hz(state: &ModalState) -> Vec<usize> {
    (0..state.modes.len())
        .filter(|&i| state.modes.kinds[i] == ModeKind::Bending && state.modes.frequency_hz(i) < 80.0)
        .collect()
}

/// Column `column` of `analytic` (`∂λ` and `∂a` at the sensors of `state`'s
/// modes `analytic.modes`) against central differences of the states
/// `plus` and `minus` at the parameter ± `h`. `unit` is the parameter's
/// size (κ for a spring, 1 for a multiplier θ): `∂λ` must be within
/// 1e-7 λ/unit and `∂a` within 1e-6 of the mode's largest amplitude/unit
/// (mass-normalised shapes are aligned in sign with `state`'s first).
/// Returns the worst errors in those units.
pub fn check_eigen_derivatives(
    state: &ModalState,
    (plus, minus): (&ModalState, &ModalState),
    h: f64,
    unit: f64,
    analytic: &ModalSensitivities,
    column: usize,
) -> (f64, f64) {
    let sensors = analytic.amplitude.first().map_or(0, |a| a.nrows());
    let (mut worst_lambda, mut worst_shape) = (0.0f64, 0.0f64);
    for (row, &i) in analytic.modes.iter().enumerate() {
        let fd = (plus.modes.omega2[i] - minus.modes.omega2[i]) / (2.0 * h);
        let got = analytic.eigenvalue[(row, column)];
        let scale = state.modes.omega2[i] / unit;
        worst_lambda = worst_lambda.max((got - fd).abs() / scale);
        assert!((got - fd).abs() <= 1e-7 * scale, "λ{i}, column {column}: {got} vs {fd}");
        let sign = |s: &ModalState| {
            let d: f64 = (0..sensors).map(|r| s.amplitude(r, i) * state.amplitude(r, i)).sum();
            d.signum()
        };
        let (sp, sm) = (sign(plus), sign(minus));
        let largest = (0..sensors).map(|r| state.amplitude(r, i).abs()).fold(0.0, f64::max) / unit;
        for r in 0..sensors {
            let fd = (sp * plus.amplitude(r, i) - sm * minus.amplitude(r, i)) / (2.0 * h);
            let got = analytic.amplitude[row][(r, column)];
            worst_shape = worst_shape.max((got - fd).abs() / largest);
            assert!(
                (got - fd).abs() <= 1e-6 * largest,
                "a({r},{i}), column {column}: {got} vs {fd}"
            );
        }
    }
    (worst_lambda, worst_shape)
}

/// `job(0..count)` on every available core, in order of the argument.
pub fn in_parallel<T: Send>(count: u64, job: impl Fn(u64) -> T + Sync) -> Vec<T> {
    let threads = std::thread::available_parallelism().map_or(1, usize::from) as u64;
    let mut slots: Vec<Option<T>> = (0..count).map(|_| None).collect();
    std::thread::scope(|scope| {
        let job = &job;
        let workers: Vec<_> = (0..threads)
            .map(|t| {
                scope.spawn(move || {
                    (t..count)
                        .step_by(threads as usize)
                        .map(|i| (i, job(i)))
                        .collect::<Vec<_>>()
                })
            })
            .collect();
        for worker in workers {
            for (i, value) in worker.join().unwrap_or_else(|e| std::panic::resume_unwind(e)) {
                slots[i as usize] = Some(value);
            }
        }
    });
    slots.into_iter().map(|v| v.expect("every record identified")).collect()
}

/// `model` on `groups`, as [`SupportMotion`](splinewatch_core::response::support_motion::SupportMotion) takes them.
pub fn grounded(model: &BridgeModel, groups: &splinewatch_core::model::supports::SupportGroups) -> GroundedStructure {
    GroundedStructure::new(model.clone(), groups.clone()).unwrap()
}
