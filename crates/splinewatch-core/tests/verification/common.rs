//! Shared fixtures: the paper's Sinello deck and its sensors.

use splinewatch_core::constraints::{Edge, EdgeConstraint, SupportKind};
use splinewatch_core::frf::SensorPoint;
use splinewatch_core::knots::KnotVector;
use splinewatch_core::material::{OrthotropicMaterial, OrthotropicParameters};
use splinewatch_core::model::ShellModel;
use splinewatch_core::shell::Shell;
use splinewatch_core::springs::{Face, SpringDirection, SpringField};

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

pub fn sinello_model() -> ShellModel {
    ShellModel {
        shell: Shell::rectangular_plate(16.0, 9.0, 1.6, [4, 4], [13, 5]).unwrap(),
        material: sinello_material(),
        springs: sinello_springs(),
        stiffness_fields: vec![],
        constraints: vec![],
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
            xi: x / 16.0,
            eta: y / 9.0,
            tau: 0.5,
            direction: [0.0, 0.0, 1.0],
        })
        .collect()
}

/// A clamped cylindrical panel on the Sinello springs: curved, so nothing
/// decouples (2 × 3 m, R = 3 m, 0.6 rad, 5 cm, 7 × 6 cubic net).
pub fn clamped_curved_panel() -> ShellModel {
    ShellModel {
        shell: Shell::cylindrical_panel(2.0, 3.0, 0.6, 0.05, [3, 3], [7, 6]).unwrap(),
        material: sinello_material(),
        springs: sinello_springs(),
        stiffness_fields: vec![],
        constraints: vec![EdgeConstraint {
            edge: Edge::Eta0,
            kind: SupportKind::Clamped,
        }],
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
