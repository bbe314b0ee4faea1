//! Frames of beam members against OpenSees (ElasticTimoshenkoBeam with its
//! consistent mass, `tests/fixtures/make_opensees_frames.py`): the members
//! cut into the same elements in both programs.

use splinewatch_core::model::beam::{BeamMaterial, Section};
use splinewatch_core::model::members::{BeamBase, BeamMember, BeamNet};
use splinewatch_core::model::ShellModel;
use splinewatch_core::solvers::sparse_model::SparseModel;

fn fixture() -> serde_json::Value {
    serde_json::from_str(include_str!("../fixtures/opensees_frames.json")).unwrap()
}

fn vector(v: &serde_json::Value) -> [f64; 3] {
    std::array::from_fn(|d| v[d].as_f64().unwrap())
}

/// The fixture's frame `case` as beam members, and OpenSees's frequencies.
fn frame(case: &str) -> (ShellModel, Vec<f64>) {
    let fixture = fixture();
    let m = &fixture["material"];
    let material = BeamMaterial::isotropic(
        m["young"].as_f64().unwrap(),
        m["poisson"].as_f64().unwrap(),
        m["density"].as_f64().unwrap(),
    )
    .unwrap();
    let case = &fixture["cases"][case];
    let members = case["members"]
        .as_array()
        .unwrap()
        .iter()
        .map(|b| {
            let s = &b["section"];
            let value = |key: &str| s[key].as_f64().unwrap();
            let section = Section::new(
                value("area"),
                value("iy"),
                value("iz"),
                value("torsion"),
                value("shear_area_y"),
                value("shear_area_z"),
            )
            .unwrap();
            let base = match b["base"].as_str().unwrap() {
                "fixed" => BeamBase::Fixed,
                "pinned" => BeamBase::Pinned,
                _ => BeamBase::Free,
            };
            BeamMember::new(
                b["name"].as_str().unwrap(),
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
    let model = ShellModel {
        beams: BeamNet::new(members, 1e-6).unwrap(),
        ..ShellModel::default()
    };
    let reference = case["frequency_hz"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f.as_f64().unwrap())
        .collect();
    (model, reference)
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
    let worst = ours
        .iter()
        .zip(&reference)
        .map(|(a, b)| (a / b - 1.0).abs())
        .fold(0.0, f64::max);
    eprintln!("portal frame: ours {ours:.4?}\n opensees {reference:.4?}\n worst {worst:.2e}");
    assert!(worst < 1e-8, "worst relative error {worst:.2e}");
    let sparse = SparseModel::assemble(&model)
        .unwrap()
        .modes_below(&[], &[], 1.2 * reference[reference.len() - 1])
        .unwrap();
    for (a, b) in sparse.frequencies_hz().iter().zip(ours) {
        assert!((a / b - 1.0).abs() < 1e-9, "sparse {a} dense {b}");
    }
    assert!(sparse.len() >= reference.len());
}
