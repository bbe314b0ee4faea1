//! Beam members beyond the frame's geometry: a member's stiffness
//! multiplier θ against the frame built with the scaled properties and by
//! central differences, and sensors on a column against the Timoshenko
//! cantilever's closed forms.

use super::frames::{damping, fixture, frame, frame_with, material};
use splinewatch_core::model::beam::{BeamMaterial, Section, StiffnessPart};
use splinewatch_core::model::member_stiffness::MemberStiffness;
use splinewatch_core::model::members::{BeamBase, BeamMember, BeamNet};
use splinewatch_core::model::BridgeModel;
use splinewatch_core::response::frf::{BeamSensor, FrfError, FrfModel, FrfRequest, Quantity, Sensor};
use splinewatch_core::solvers::sparse_model::SparseModel;
use splinewatch_core::updating::modal_residual::frequency_gradient;
use splinewatch_core::updating::{Parameter, ParameterKind};

/// A member's stiffness multiplier θ ([`MemberStiffness`]) on the portal
/// frame: the columns' bending at 0.6, the girder's whole stiffness at 1.3.
/// - `K(θ)` equals the stiffness of the frame built with the columns' `I`
///   and shear areas × 0.6 and the girder's `E` (so `G`) × 1.3, on the
///   dense and the sparse path (round-off: 1e-12 of the largest entry);
/// - with the girder alone at 1.3 (`All`), the frequencies equal those of
///   the girder built with `E` × 1.3 (1e-10: the same matrices);
/// - each frequency's gradient in each θ (the first ten modes) matches
///   central differences (step 1e-5, truncation ~1e-10; 1e-6 of the largest).
#[test]
fn a_member_s_stiffness_multiplier_scales_its_part() {
    let (young, poisson, density) = material(&fixture());
    let scaled = |factor: f64| BeamMaterial::isotropic(young * factor, poisson, density).unwrap();
    let multiplied = |parts: &[(usize, StiffnessPart, f64)]| {
        let (mut model, _) = frame("portal");
        model.member_stiffness = parts
            .iter()
            .map(|&(member, part, factor)| MemberStiffness::new(member, part, factor).unwrap())
            .collect();
        model
    };
    let names: Vec<String> = frame("portal")
        .0
        .beams
        .members()
        .iter()
        .map(|m| m.name().to_string())
        .collect();
    let girder = names.iter().position(|n| n == "girder").unwrap();
    let columns: Vec<usize> = (0..names.len()).filter(|&m| m != girder).collect();
    let parts: Vec<(usize, StiffnessPart, f64)> = columns
        .iter()
        .map(|&c| (c, StiffnessPart::Bending, 0.6))
        .chain([(girder, StiffnessPart::All, 1.3)])
        .collect();
    let model = multiplied(&parts);
    let (reference, _) = frame_with("portal", |name, s, material| {
        if name == "girder" {
            (s, scaled(1.3))
        } else {
            let section = Section::new(
                s.area,
                0.6 * s.iy,
                0.6 * s.iz,
                s.torsion,
                0.6 * s.shear_area_y,
                0.6 * s.shear_area_z,
            )
            .unwrap();
            (section, material)
        }
    });
    let expected = reference.assemble().unwrap().free_stiffness;
    let dense = model.assemble().unwrap().stiffness_with(&[]).unwrap();
    let largest = expected.norm_max();
    eprintln!(
        "member stiffness: K(θ) against the scaled frame, {:.1e} of the largest entry",
        (&dense - &expected).norm_max() / largest
    );
    assert!((&dense - &expected).norm_max() <= 1e-12 * largest);
    let sparse = SparseModel::assemble(&model).unwrap();
    let reference_sparse = SparseModel::assemble(&reference).unwrap();
    let theta = model.field_coefficients();
    let difference = sparse.stiffness_with_fields(&[], &theta).unwrap().to_dense()
        - reference_sparse.stiffness_with_fields(&[], &[]).unwrap().to_dense();
    assert!(difference.norm_max() <= 1e-12 * largest);

    let girder_only = multiplied(&[(girder, StiffnessPart::All, 1.3)])
        .assemble()
        .unwrap()
        .modes()
        .unwrap();
    let (stiffer, _) = frame_with("portal", |name, s, material| {
        (s, if name == "girder" { scaled(1.3) } else { material })
    });
    let expected = stiffer.assemble().unwrap().modes().unwrap();
    for (a, b) in girder_only
        .frequencies_hz()
        .iter()
        .zip(expected.frequencies_hz())
        .take(10)
    {
        assert!((a / b - 1.0).abs() < 1e-10, "{a} vs {b}");
    }

    let frf = FrfModel::new(model.assemble().unwrap(), &[] as &[Sensor]).unwrap();
    let damping = damping();
    let state = frf.modal_state_with_fields(&[], &theta, &damping).unwrap();
    let parameters: Vec<Parameter> = (0..parts.len())
        .map(|field| Parameter {
            name: format!("{}.stiffness", names[parts[field].0]),
            kind: ParameterKind::Stiffness { field, coefficient: 0 },
            lower: 0.1,
            upper: 3.0,
        })
        .collect();
    let h = 1e-5;
    let mut gradients = Vec::new();
    for field in 0..parts.len() {
        let at = |sign: f64| {
            let mut t = theta.clone();
            t[field][0] += sign * h;
            frf.modal_state_with_fields(&[], &t, &damping).unwrap()
        };
        let (plus, minus) = (at(1.0), at(-1.0));
        for mode in 0..10 {
            let analytic = frequency_gradient(&frf, &state, mode, &parameters)[field];
            let fd = (plus.modes.frequency_hz(mode) - minus.modes.frequency_hz(mode)) / (2.0 * h);
            gradients.push((analytic, fd));
        }
    }
    let largest = gradients.iter().map(|g| g.1.abs()).fold(0.0, f64::max);
    assert!(largest > 0.0);
    let worst = gradients.iter().map(|(a, fd)| (a - fd).abs()).fold(0.0, f64::max) / largest;
    eprintln!("member stiffness: gradients against central differences, worst {worst:.1e} of the largest");
    for (analytic, fd) in gradients {
        assert!((analytic - fd).abs() <= 1e-6 * largest, "{analytic} vs {fd}");
    }
}

/// Sensors on a beam ([`BeamSensor`]): a column of 4 elements fixed at its
/// base, a force at its top along `y`. The receptance at 1e-4 Hz (the
/// static flexibility: every mode of the dense model, `(ω/ω₁)²` ~ 1e-12)
/// to a sensor at mid-height along `y` equals the Timoshenko cantilever's
/// `v(s) = (L s²/2 − s³/6)/(E I) + s/(G A_s)`, and to a sensor on the face
/// at mid-height (`r = R` along `y`, measuring along the axis) the plane
/// section's `−R ψ(s)`, `ψ(s) = (L s − s²/2)/(E I)`: the element's
/// interpolation and the rigid transfer, both exact under an end load
/// (1e-8 relative). A sensor on a member that does not exist is refused.
#[test]
fn sensors_on_a_column_measure_its_deflection_and_its_face() {
    let material = BeamMaterial::isotropic(30e9, 0.2, 2500.0).unwrap();
    let (diameter, length) = (1.2, 7.0);
    let section = Section::circle(diameter, 0.2).unwrap();
    let column = BeamMember::new(
        "column",
        ([0.0; 3], [0.0, 0.0, length]),
        [1.0, 0.0, 0.0],
        section,
        material,
        4,
        BeamBase::Fixed,
    )
    .unwrap();
    let model = BridgeModel {
        beams: BeamNet::new(vec![column], 1e-6).unwrap(),
        ..BridgeModel::default()
    };
    let (y, z) = ([0.0, 1.0, 0.0], [0.0, 0.0, 1.0]);
    let s = 0.5 * length;
    let radius = 0.5 * diameter;
    let sensor = |at, direction| {
        Sensor::Beam(BeamSensor {
            member: 0,
            at,
            direction,
        })
    };
    let sensors = [
        sensor([0.0, 0.0, length], y),
        sensor([0.0, 0.0, s], y),
        sensor([0.0, radius, s], z),
    ];
    let frf = FrfModel::new(model.assemble().unwrap(), &sensors).unwrap();
    let state = frf.modal_state(&[], &damping()).unwrap();
    let h = frf
        .evaluate(
            &state,
            FrfRequest {
                frequencies_hz: &[1e-4],
                pairs: &[(1, 0), (2, 0)],
                quantity: Quantity::Receptance,
            },
            false,
        )
        .h;
    let ei = material.young * section.iz;
    let psi = (length * s - s * s / 2.0) / ei;
    let deflection =
        (length * s * s / 2.0 - s.powi(3) / 6.0) / ei + s / (material.shear_modulus * section.shear_area_y);
    let face = -radius * psi;
    eprintln!(
        "beam sensors: deflection {:.6e} against {deflection:.6e}, face {:.6e} against {face:.6e}",
        h[0].re, h[1].re
    );
    assert!(
        (h[0].re / deflection - 1.0).abs() < 1e-8,
        "{} against {deflection}",
        h[0].re
    );
    assert!((h[1].re / face - 1.0).abs() < 1e-8, "{} against {face}", h[1].re);
    let missing = FrfModel::new(
        model.assemble().unwrap(),
        &[Sensor::Beam(BeamSensor {
            member: 1,
            at: [0.0; 3],
            direction: y,
        })],
    );
    assert!(matches!(
        missing,
        Err(FrfError::SensorMember {
            index: 0,
            member: 1,
            count: 1
        })
    ));
}
