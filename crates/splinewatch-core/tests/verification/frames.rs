//! Frames of beam members against OpenSees (ElasticTimoshenkoBeam with its
//! consistent mass, `tests/fixtures/make_opensees_frames.py`): the members
//! cut into the same elements in both programs.

use super::common::grounded;
use splinewatch_core::model::beam::{BeamMaterial, Section, StiffnessPart};
use splinewatch_core::model::bearings::PatchPoint;
use splinewatch_core::model::constraints::{Edge, EdgeConstraint, SupportKind};
use splinewatch_core::model::damping::DampingCurve;
use splinewatch_core::model::elastic_supports::{ElasticSupport, SupportComponent};
use splinewatch_core::model::joints::find_joints;
use splinewatch_core::model::material::OrthotropicMaterial;
use splinewatch_core::model::member_stiffness::MemberStiffness;
use splinewatch_core::model::members::{BeamBase, BeamMember, BeamNet};
use splinewatch_core::model::patch::Patch;
use splinewatch_core::model::rigid::{RigidBody, RigidError};
use splinewatch_core::model::shell::Shell;
use splinewatch_core::model::supports::SupportGroups;
use splinewatch_core::model::BridgeModel;
use splinewatch_core::response::frf::{FrfModel, ModalState, SensorPoint};
use splinewatch_core::response::support_motion::{GroundInput, SupportMotion};
use splinewatch_core::solvers::dense_model::ModelError;
use splinewatch_core::solvers::modal::ModeKind;
use splinewatch_core::solvers::sparse_model::SparseModel;

pub(crate) fn fixture() -> serde_json::Value {
    serde_json::from_str(include_str!("../fixtures/opensees_frames.json")).unwrap()
}

fn vector(v: &serde_json::Value) -> [f64; 3] {
    std::array::from_fn(|d| v[d].as_f64().unwrap())
}

/// The largest `|a / b − 1|` over the pairs.
fn worst_relative_error(ours: &[f64], reference: &[f64]) -> f64 {
    ours.iter()
        .zip(reference)
        .map(|(a, b)| (a / b - 1.0).abs())
        .fold(0.0, f64::max)
}

fn numbers(v: &serde_json::Value) -> Vec<f64> {
    v.as_array().unwrap().iter().map(|f| f.as_f64().unwrap()).collect()
}

/// The fixture's `young, poisson, density`.
pub(crate) fn material(fixture: &serde_json::Value) -> (f64, f64, f64) {
    let value = |key: &str| fixture["material"][key].as_f64().unwrap();
    (value("young"), value("poisson"), value("density"))
}

/// A section given by its six properties.
fn section(s: &serde_json::Value) -> Section {
    let value = |key: &str| s[key].as_f64().unwrap();
    Section::new(
        value("area"),
        value("iy"),
        value("iz"),
        value("torsion"),
        value("shear_area_y"),
        value("shear_area_z"),
    )
    .unwrap()
}

/// The fixture's frame `case` as beam members, and OpenSees's frequencies.
pub(crate) fn frame(case: &str) -> (BridgeModel, Vec<f64>) {
    frame_with(case, |_, section, material| (section, material))
}

/// The fixture's frame `case`, each member's section and material as
/// `properties` (its name, the fixture's section and material) makes them.
pub(crate) fn frame_with(
    case: &str,
    properties: impl Fn(&str, Section, BeamMaterial) -> (Section, BeamMaterial),
) -> (BridgeModel, Vec<f64>) {
    let fixture = fixture();
    let (young, poisson, density) = material(&fixture);
    let nominal = BeamMaterial::isotropic(young, poisson, density).unwrap();
    let case = &fixture["cases"][case];
    let members = case["members"]
        .as_array()
        .unwrap()
        .iter()
        .map(|b| {
            let name = b["name"].as_str().unwrap();
            let (section, material) = properties(name, section(&b["section"]), nominal);
            let base = match b["base"].as_str().unwrap() {
                "fixed" => BeamBase::Fixed,
                "pinned" => BeamBase::Pinned,
                _ => BeamBase::Free,
            };
            BeamMember::new(
                name,
                (vector(&b["start"]), vector(&b["end"])),
                vector(&b["orientation"]),
                section,
                material,
                b["elements"].as_u64().unwrap() as usize,
                base,
            )
            .unwrap()
        })
        .collect();
    let model = BridgeModel {
        beams: BeamNet::new(members, 1e-6).unwrap(),
        ..BridgeModel::default()
    };
    (model, numbers(&case["frequency_hz"]))
}

/// A portal frame (two columns, one fixed and one pinned, and a girder):
/// the first ten modes, sway, out of plane, torsion and bending, against
/// OpenSees on the same elements. Both build the interdependent-
/// interpolation element (Friedman & Kosmatka 1993) with rotary inertia,
/// so the frequencies agree to round-off (1e-8), not to a mesh limit; the
/// sparse path equals the dense one to 1e-9.
#[test]
fn a_portal_frame_matches_opensees() {
    let (model, reference) = frame("portal");
    let dense = model.assemble().unwrap().modes().unwrap();
    let ours = &dense.frequencies_hz()[..reference.len()];
    let worst = worst_relative_error(ours, &reference);
    eprintln!("portal frame: ours {ours:.4?}\n opensees {reference:.4?}\n worst {worst:.2e}");
    assert!(worst < 1e-8, "worst relative error {worst:.2e}");
    let sparse = sparse_frequencies(&model, 1.2 * reference[reference.len() - 1]);
    for (a, b) in sparse.iter().zip(ours) {
        assert!((a / b - 1.0).abs() < 1e-9, "sparse {a} dense {b}");
    }
    assert!(sparse.len() >= reference.len());
}

/// The portal frame with both columns on footings: six uncoupled springs
/// at each base along the global axes (OpenSees: `zeroLength` elements to a
/// fixed node, one `Elastic` material per direction), each component its
/// own stiffness so that one mapped to the wrong axis shows. splinewatch's
/// `ElasticSupport::at_beam_nodes` on the members' free bases: the first ten
/// modes to round-off (1e-8, as the fixed portal), the sparse path equal to
/// the dense one (1e-9).
#[test]
fn a_portal_on_footing_springs_matches_opensees() {
    let (mut model, reference) = frame("portal_on_footings");
    let footing = &fixture()["cases"]["portal_on_footings"]["footing"];
    let bases = vec![model.beams.member_nodes(0)[0], model.beams.member_nodes(1)[0]];
    let components = SupportComponent::ALL
        .iter()
        .zip(["x", "y", "z", "rx", "ry", "rz"])
        .map(|(&c, name)| (c, footing[name].as_f64().unwrap()))
        .collect();
    let global = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    model.elastic_supports = vec![ElasticSupport::at_beam_nodes("footings", bases, global, components).unwrap()];
    let kappa = model.spring_coefficients();
    let dense = model.assemble().unwrap().modes_with(&kappa).unwrap();
    let ours = &dense.frequencies_hz()[..reference.len()];
    let worst = worst_relative_error(ours, &reference);
    eprintln!("portal on footings: ours {ours:.4?}\n opensees {reference:.4?}\n worst {worst:.2e}");
    assert!(worst < 1e-8, "worst relative error {worst:.2e}");
    let sparse = sparse_frequencies(&model, 1.2 * reference[reference.len() - 1]);
    for (a, b) in sparse.iter().zip(ours) {
        assert!((a / b - 1.0).abs() < 1e-9, "sparse {a} dense {b}");
    }
    // The footings matter: the sway mode 10 % below the portal's on a fixed
    // and a pinned base.
    let (_, held) = frame("portal");
    assert!(reference[0] < 0.95 * held[0], "{} vs {}", reference[0], held[0]);
}

/// The sparse path's frequencies below `top` Hz, at the model's own spring
/// and field coefficients.
fn sparse_frequencies(model: &BridgeModel, top: f64) -> Vec<f64> {
    let sparse = SparseModel::assemble(model).unwrap();
    let kappa = model.spring_coefficients();
    sparse
        .modes_below(&kappa, &sparse.field_coefficients, top)
        .unwrap()
        .frequencies_hz()
}

/// The fixture's deck on a bent: two slab patches meeting at the bent, its
/// ends simply supported, the bent's cap a rigid body holding both patches'
/// edges there and the two column tops (0.5 m below the mid-surface).
fn deck_on_bent(net: [usize; 2]) -> (BridgeModel, Vec<f64>) {
    deck_on_bent_case("deck_on_bent", net)
}

/// The fixture's case `name`, a deck on a bent: its ends held, or on line
/// springs where the case gives `abutment_springs` (per metre, global axes).
fn deck_on_bent_case(name: &str, net: [usize; 2]) -> (BridgeModel, Vec<f64>) {
    let fixture = fixture();
    let case = &fixture["cases"][name];
    let value = |key: &str| case[key].as_f64().unwrap();
    let (length, width, bent) = (value("length"), value("width"), value("bent_x"));
    let (young, poisson, density) = material(&fixture);
    let slab = OrthotropicMaterial::isotropic(young, poisson, density).unwrap();
    let patches = [(0.0, bent), (bent, length)]
        .iter()
        .enumerate()
        .map(|(k, &(x0, x1))| {
            let corners = [[x0, 0.0, 0.0], [x1, 0.0, 0.0], [x1, width, 0.0], [x0, width, 0.0]];
            let shell = Shell::quadrilateral(corners, value("thickness"), [3, 3], net).unwrap();
            Patch::new(format!("span{}", k + 1), shell, slab.clone()).unwrap()
        })
        .collect::<Vec<_>>();
    let concrete = BeamMaterial::isotropic(young, poisson, density).unwrap();
    let section = section(&case["column"]);
    let columns = case["columns_y"]
        .as_array()
        .unwrap()
        .iter()
        .enumerate()
        .map(|(k, y)| {
            let y = y.as_f64().unwrap();
            BeamMember::new(
                format!("column{k}"),
                ([bent, y, value("column_base")], [bent, y, value("column_top")]),
                [1.0, 0.0, 0.0],
                section,
                concrete,
                case["column_elements"].as_u64().unwrap() as usize,
                BeamBase::Fixed,
            )
            .unwrap()
        })
        .collect();
    let beams = BeamNet::new(columns, 1e-6).unwrap();
    let tops = (0..2).map(|k| *beams.member_nodes(k).last().unwrap()).collect();
    let cap = RigidBody::new("bent", vec![(0, Edge::Xi1), (1, Edge::Xi0)], tops).unwrap();
    let ends = [(0, Edge::Xi0), (1, Edge::Xi1)];
    let springs = &case["abutment_springs"];
    let (constraints, elastic_supports) = if springs.is_null() {
        let held = |(patch, edge)| EdgeConstraint {
            edge,
            kind: SupportKind::SimplySupported,
            patch,
        };
        (ends.map(held).to_vec(), Vec::new())
    } else {
        let global = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let components: Vec<(SupportComponent, f64)> = SupportComponent::ALL
            .iter()
            .zip(["x", "y", "z", "rx", "ry"])
            .map(|(&c, name)| (c, springs[name].as_f64().unwrap()))
            .collect();
        let abutment = |(k, end)| ElasticSupport::along_edge(format!("abutment{k}"), end, global, components.clone());
        (
            Vec::new(),
            ends.into_iter()
                .enumerate()
                .map(abutment)
                .collect::<Result<_, _>>()
                .unwrap(),
        )
    };
    let model = BridgeModel {
        joints: find_joints(&patches, 1e-3),
        constraints,
        elastic_supports,
        patches,
        beams,
        rigid_bodies: vec![cap],
        ..BridgeModel::default()
    };
    (model, numbers(&case["extrapolated_hz"]))
}

/// A two-span slab on a two-column bent with a rigid cap and rigid offsets
/// against OpenSees (ShellMITC4 converged and extrapolated,
/// ElasticTimoshenkoBeam, rigidLink): the first ten modes within 1 % (the
/// fixture's mesh still moved them by 0.14 % on its last halving, and
/// OpenSees's shell mass lacks the rotary inertia, below 0.3 % here). On
/// 12 × 6 control nets per span they are within 0.61 %, on 20 × 10 within
/// 0.10 % (a 9 s dense solve): the difference is our mesh's and shrinks
/// under refinement. The sparse path equals the dense one to 1e-8.
#[test]
fn a_deck_on_a_bent_with_a_rigid_cap_matches_opensees() {
    let (model, reference) = deck_on_bent([12, 6]);
    let sparse = sparse_frequencies(&model, 1.2 * reference[reference.len() - 1]);
    let ours = &sparse[..reference.len()];
    let worst = worst_relative_error(ours, &reference);
    eprintln!("deck on bent: ours {ours:.4?}\n opensees {reference:.4?}\n worst {worst:.2e}");
    assert!(worst < 1e-2, "worst relative error {worst:.2e}");
    let dense = model.assemble().unwrap().modes().unwrap().frequencies_hz();
    for (a, b) in ours.iter().zip(&dense) {
        assert!((a / b - 1.0).abs() < 1e-8, "sparse {a} dense {b}");
    }
}

/// The same deck on integral abutments: both ends on line springs in five
/// components (x, y, z, rx, ry per metre, each its own value; OpenSees:
/// `zeroLength` elements at the edge nodes, each the per-metre stiffness
/// times its share of the edge, converged and extrapolated as the deck).
/// The first ten modes within 1 % as the held deck's: 0.53 % on 12 × 6
/// control nets per span, 0.048 % on 20 × 10 (our mesh's difference, as
/// for the held deck); the sparse path equals the dense one (1e-8). The
/// springs matter: the first mode at least 10 % away from the held deck's
/// (2.08 Hz against 1.00).
#[test]
fn a_deck_on_integral_abutment_springs_matches_opensees() {
    let (model, reference) = deck_on_bent_case("deck_on_abutment_springs", [12, 6]);
    let sparse = sparse_frequencies(&model, 1.2 * reference[reference.len() - 1]);
    let ours = &sparse[..reference.len()];
    let worst = worst_relative_error(ours, &reference);
    eprintln!("deck on abutment springs: ours {ours:.4?}\n opensees {reference:.4?}\n worst {worst:.2e}");
    assert!(worst < 1e-2, "worst relative error {worst:.2e}");
    let kappa = model.spring_coefficients();
    let dense = model.assemble().unwrap().modes_with(&kappa).unwrap().frequencies_hz();
    for (a, b) in ours.iter().zip(&dense) {
        assert!((a / b - 1.0).abs() < 1e-8, "sparse {a} dense {b}");
    }
    let (_, held) = deck_on_bent([12, 6]);
    assert!(
        (reference[0] / held[0] - 1.0).abs() > 0.1,
        "{} vs {}",
        reference[0],
        held[0]
    );
}

/// A free slab on a free column, tied by a rigid body: six rigid modes and
/// no more. A wrong weight in the ties (a lever arm, a director rotation's
/// sign) would strain the structure under a rigid motion and leave fewer.
#[test]
fn a_rigid_body_keeps_the_six_rigid_motions_of_a_free_structure() {
    let (mut model, _) = deck_on_bent([6, 4]);
    model.constraints.clear();
    let members = model.beams.members().to_vec();
    let free: Vec<BeamMember> = members.iter().map(|m| m.clone().with_base(BeamBase::Free)).collect();
    model.beams = BeamNet::new(free, 1e-6).unwrap();
    let modes = model.assemble().unwrap().modes().unwrap();
    let rigid = modes.kinds.iter().filter(|k| **k == ModeKind::Rigid).count();
    assert_eq!(rigid, 6, "frequencies {:.3?}", &modes.frequencies_hz()[..8]);
    assert!(modes.frequency_hz(6) > 0.5);
}

/// A rigid body with nothing in it, or holding an edge a support already
/// holds, is refused by its name.
#[test]
fn bad_rigid_bodies_are_refused_by_name() {
    assert!(matches!(
        RigidBody::new("cap", vec![], vec![]),
        Err(RigidError::Empty(ref name)) if name == "cap"
    ));
    let (mut model, _) = deck_on_bent([6, 4]);
    model
        .rigid_bodies
        .push(RigidBody::new("abutment", vec![(0, Edge::Xi0)], vec![]).unwrap());
    assert!(matches!(
        model.reduction(),
        Err(ModelError::Rigid(RigidError::Conflict { ref name, .. })) if name == "abutment"
    ));
    model.rigid_bodies[1] = RigidBody::new("abutment", vec![(7, Edge::Xi0)], vec![]).unwrap();
    assert!(matches!(
        model.reduction(),
        Err(ModelError::Rigid(RigidError::UnknownPatch { patch: 7, .. }))
    ));
}

/// The deck on a bent driven by three grounds (the west and east abutments
/// and the columns' footings): at every sensor the quasi-static responses
/// to the three grounds moving together add up to the rigid translation
/// (the sensor's direction along the axis), for every axis; the footings'
/// ground alone moves the deck (through the columns and the cap).
#[test]
fn the_grounds_of_a_deck_on_a_bent_add_up_to_a_rigid_translation() {
    let (model, _) = deck_on_bent([6, 4]);
    let sensors = deck_sensors();
    let frf = FrfModel::new(model.assemble().unwrap(), &sensors).unwrap();
    let state = frf.modal_state(&[], &damping()).unwrap();
    let groups = three_grounds(&model);
    assert_three_grounds_translate_rigidly((&frf, &model, &groups), &[], &state, &sensors);
}

/// For every axis: the three grounds of `groups` moved together translate
/// every one of `sensors` rigidly (1e-9), and the third (the footings')
/// alone moves some sensor.
fn assert_three_grounds_translate_rigidly(
    (frf, model, groups): (&FrfModel, &BridgeModel, &SupportGroups),
    kappa: &[Vec<f64>],
    state: &ModalState,
    sensors: &[SensorPoint],
) {
    for axis in 0..3 {
        let inputs: Vec<GroundInput> = (0..3).map(|group| GroundInput { group, axis }).collect();
        let motion = SupportMotion::new((frf, &grounded(model, groups)), kappa, &[], state, &inputs).unwrap();
        for (s, sensor) in sensors.iter().enumerate() {
            let sum: f64 = (0..3).map(|g| motion.quasi_static(s, g)).sum();
            let rigid = sensor.direction[axis];
            assert!(
                (sum - rigid).abs() < 1e-9,
                "axis {axis}, sensor {s}: Σ {sum} vs {rigid}"
            );
        }
        let footings = (0..sensors.len())
            .map(|s| motion.quasi_static(s, 2).abs())
            .fold(0.0, f64::max);
        assert!(footings > 1e-3, "axis {axis}: the footings' ground moves no sensor");
    }
}

/// The same with the columns on footings (six-component springs at their
/// free bases, on the bent's ground) and a point support on the second
/// span's soffit (its translations follow the section's rotation) on the
/// bent's ground too: the three grounds together still translate every
/// sensor rigidly (1e-9), one of them 0.8 m below the deck's mid-surface,
/// and the bent's ground alone moves the deck through the footings'
/// springs.
#[test]
fn grounds_through_footing_springs_add_up_to_a_rigid_translation() {
    let (mut model, _) = deck_on_bent([6, 4]);
    let members: Vec<BeamMember> = model
        .beams
        .members()
        .iter()
        .map(|m| m.clone().with_base(BeamBase::Free))
        .collect();
    model.beams = BeamNet::new(members, 1e-6).unwrap();
    let bases = vec![model.beams.member_nodes(0)[0], model.beams.member_nodes(1)[0]];
    let components = SupportComponent::ALL.iter().map(|&c| (c, 5e9)).collect();
    let global = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let soffit = PatchPoint {
        patch: 1,
        xi: 0.5,
        eta: 0.5,
        tau: 0.0,
    };
    let pot = SupportComponent::ALL[..5].iter().map(|&c| (c, 2e9)).collect();
    model.elastic_supports = vec![
        ElasticSupport::at_beam_nodes("footings", bases, global, components).unwrap(),
        ElasticSupport::at_point("pot", soffit, global, pot).unwrap(),
    ];
    let mut sensors = deck_sensors();
    let faces = [0.0, 1.0].map(|tau| model.patches[0].shell.position(0.3, 0.6, tau));
    let thickness = (0..3).map(|d| (faces[1][d] - faces[0][d]).powi(2)).sum::<f64>().sqrt();
    sensors.push(SensorPoint {
        patch: 0,
        xi: 0.3,
        eta: 0.6,
        tau: 0.5 - 0.8 / thickness,
        direction: [0.0, 0.6, 0.8],
    });
    let frf = FrfModel::new(model.assemble().unwrap(), &sensors).unwrap();
    let kappa = model.spring_coefficients();
    let state = frf.modal_state(&kappa, &damping()).unwrap();
    let names = ["west", "east", "bent"].map(String::from).to_vec();
    let groups = SupportGroups::new(names, vec![2, 2], vec![0, 1], &model).unwrap();
    assert_three_grounds_translate_rigidly((&frf, &model, &groups), &kappa, &state, &sensors);
}

/// Four deck points along the axes and one oblique direction.
fn deck_sensors() -> Vec<SensorPoint> {
    let directions = [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.6, 0.8, 0.0]];
    [(0, 0.5, 1.0), (1, 0.5, 0.0), (0, 0.9, 0.5), (1, 0.2, 0.7)]
        .iter()
        .zip(directions)
        .map(|(&(patch, xi, eta), direction)| SensorPoint {
            patch,
            xi,
            eta,
            tau: 0.5,
            direction,
        })
        .collect()
}

pub(crate) fn damping() -> DampingCurve {
    DampingCurve::new(1, vec![0.02, 0.02], 0.0, 20.0).unwrap()
}

/// The deck on a bent's three grounds: each end's, and the columns' bases'.
fn three_grounds(model: &BridgeModel) -> SupportGroups {
    let names = ["west", "east", "bent"].map(String::from).to_vec();
    SupportGroups::new(names, vec![], vec![0, 1], model)
        .unwrap()
        .with_beam_bases(vec![2, 2], model)
        .unwrap()
}

/// The columns' ground driving the deck on the truncated path (modes below
/// 60 Hz of the sparse model, the rest as the static residual: the held
/// bases' lift `−K ℓ` from the columns' elements alone, and with the
/// columns' bending stiffness multiplied by 0.6 its `(θ − 1) ∂K/∂θ ℓ`)
/// against every mode of the dense one: the influence at the sensors within
/// 1e-6 (the static solve brought from the eigen-solve's shift to zero, as
/// for springs) and the transmissibilities from 0.25 to 30 Hz within 2e-3 of
/// the input's largest (measured 6e-5: the residual's approximation of the
/// discarded modes).
#[test]
fn a_bent_s_ground_drives_the_truncated_model_as_the_dense_one() {
    for cracked in [false, true] {
        let (mut model, _) = deck_on_bent([6, 4]);
        if cracked {
            model.member_stiffness = (0..2)
                .map(|m| MemberStiffness::new(m, StiffnessPart::Bending, 0.6).unwrap())
                .collect();
        }
        check_truncated_ground(&model, cracked);
    }
}

fn check_truncated_ground(model: &BridgeModel, cracked: bool) {
    let sensors = deck_sensors();
    let dense = FrfModel::new(model.assemble().unwrap(), &sensors).unwrap();
    let truncated = FrfModel::truncated(model, &sensors, 60.0).unwrap();
    let groups = three_grounds(model);
    let theta = model.field_coefficients();
    let inputs: Vec<GroundInput> = (0..3).map(|axis| GroundInput { group: 2, axis }).collect();
    let lines: Vec<f64> = (1..=120).map(|k| 0.25 * k as f64).collect();
    let pairs: Vec<(usize, usize)> = (0..sensors.len()).flat_map(|r| (0..3).map(move |c| (r, c))).collect();
    let run = |frf: &FrfModel| {
        let (state, motion) =
            SupportMotion::with_state((frf, &grounded(model, &groups)), (&[], &theta, &damping()), &inputs).unwrap();
        let loads = frf.with_extra_rows(motion.load_rows());
        let load_state = loads.modal_state_with_fields(&[], &theta, &damping()).unwrap();
        let t = motion.transmissibility_with_residual(frf, &loads, &load_state, &pairs, &lines);
        let statics: Vec<f64> = pairs.iter().map(|&(r, c)| motion.quasi_static(r, c)).collect();
        (t, statics, state.modes.len())
    };
    let (t_dense, s_dense, all) = run(&dense);
    let (t_trunc, s_trunc, kept) = run(&truncated);
    assert!(kept < all / 2, "{kept} of {all} modes kept");
    assert!(
        s_dense.iter().any(|v| v.abs() > 1e-3),
        "the bent's ground moves the deck"
    );
    for (k, (a, b)) in s_trunc.iter().zip(&s_dense).enumerate() {
        assert!(
            (a - b).abs() <= 1e-6 * b.abs().max(1.0),
            "cracked {cracked}, pair {:?}: NΓ {a} vs {b}",
            pairs[k]
        );
    }
    let nf = lines.len();
    // Per input, the largest transmissibility over the sensors and lines:
    // pairs that vanish by symmetry (a transverse sensor under the vertical
    // ground) are measured against it, not against their own round-off.
    let largest = |c: usize| {
        (0..pairs.len())
            .filter(|&p| pairs[p].1 == c)
            .flat_map(|p| t_dense[p * nf..(p + 1) * nf].iter().map(|v| v.norm()))
            .fold(0.0, f64::max)
    };
    for (p, pair) in pairs.iter().enumerate() {
        let (a, b) = (&t_trunc[p * nf..(p + 1) * nf], &t_dense[p * nf..(p + 1) * nf]);
        let e = a.iter().zip(b).map(|(x, y)| (x - y).norm()).fold(0.0, f64::max) / largest(pair.1);
        assert!(
            e <= 2e-3,
            "cracked {cracked}, pair {pair:?}: truncated vs dense {e:.1e}"
        );
    }
}

/// `∂T/∂k` of the line supports' components (translations and the end
/// rotation `ry`) of a deck on a bent whose ends stand on line supports
/// (the abutments' grounds) and whose columns stand on the bent's, every
/// ground driving it along y and z, against five-point central differences
/// of `T` rebuilt at each perturbed point (modes, influence with the
/// footings' lift): within 5e-6 of the coefficient's largest `|∂T|` over
/// the pairs, measured 5e-8 to 1.9e-6 with a step of 1e-3 of each
/// stiffness. The worst sit at 4 Hz, on a resonance damped 2 %, and are the
/// differences' round-off: a step five times smaller makes them larger
/// (3e-7 → 2.6e-6 on the west abutment's z), not smaller.
#[test]
fn line_support_sensitivities_on_a_bent_match_central_differences() {
    let (bare, _) = deck_on_bent([5, 4]);
    let abutment = |name: &str, patch: usize, edge: Edge| {
        let axes = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let components = vec![
            (SupportComponent::Translation(1), 4e7),
            (SupportComponent::Translation(2), 2e8),
            (SupportComponent::Rotation(1), 5e7),
        ];
        ElasticSupport::along_edge(name, (patch, edge), axes, components).unwrap()
    };
    let model = BridgeModel {
        constraints: vec![],
        elastic_supports: vec![abutment("west", 0, Edge::Xi0), abutment("east", 1, Edge::Xi1)],
        ..bare
    };
    let sensors = deck_sensors();
    let frf = FrfModel::new(model.assemble().unwrap(), &sensors).unwrap();
    let names = ["west", "east", "bent"].map(String::from).to_vec();
    let groups = SupportGroups::new(names, vec![0, 1], vec![], &model)
        .unwrap()
        .with_beam_bases(vec![2, 2], &model)
        .unwrap();
    let inputs: Vec<GroundInput> = (0..3)
        .flat_map(|group| [1, 2].map(|axis| GroundInput { group, axis }))
        .collect();
    let kappa = model.spring_coefficients();
    let lines: Vec<f64> = (1..=60).map(|k| 0.5 * k as f64).collect();
    let pairs: Vec<(usize, usize)> = (0..sensors.len())
        .flat_map(|r| (0..inputs.len()).map(move |c| (r, c)))
        .collect();
    let transmissibility = |kappa: &[Vec<f64>]| {
        let state = frf.modal_state(kappa, &damping()).unwrap();
        let motion = SupportMotion::new((&frf, &grounded(&model, &groups)), kappa, &[], &state, &inputs).unwrap();
        motion.transmissibility(&state, &pairs, &lines)
    };
    let state = frf.modal_state(&kappa, &damping()).unwrap();
    let motion = SupportMotion::new((&frf, &grounded(&model, &groups)), &kappa, &[], &state, &inputs).unwrap();
    let loads = frf.with_extra_rows(motion.load_rows());
    let analytic = motion.sensitivities(&frf, &loads, &groups, &state, &damping(), &pairs, &lines);
    let nf = lines.len();
    let mut flat = 0;
    for (f, coefficients) in kappa.iter().enumerate() {
        for j in 0..coefficients.len() {
            let h = 1e-3 * kappa[f][j];
            let at = |step: f64| {
                let mut k = kappa.clone();
                k[f][j] += step;
                transmissibility(&k)
            };
            let (p2, p1, m1, m2) = (at(2.0 * h), at(h), at(-h), at(-2.0 * h));
            let fd: Vec<_> = (0..pairs.len() * nf)
                .map(|i| (m2[i] - p2[i] + (p1[i] - m1[i]) * 8.0) / (12.0 * h))
                .collect();
            // Against the coefficient's largest `|∂T|` over every pair: pairs
            // that vanish by symmetry leave round-off only.
            let largest = fd.iter().map(|v| v.norm()).fold(0.0, f64::max);
            assert!(largest > 0.0, "support {f} component {j} moves no transmissibility");
            let (worst, at_index) = (0..fd.len())
                .map(|i| ((analytic.dkappa[flat][i] - fd[i]).norm() / largest, i))
                .fold((0.0, 0), |a, b| if b.0 > a.0 { b } else { a });
            assert!(
                worst <= 5e-6,
                "support {f} component {j}, pair {:?}, {} Hz: {worst:.1e}",
                pairs[at_index / nf],
                lines[at_index % nf]
            );
            flat += 1;
        }
    }
    assert_eq!(flat, 6);
}
