//! A column on a footing: six-component springs at a beam's base
//! (`ElasticSupport::at_beam_nodes`) against the closed form of a rod on an
//! axial spring, the fixed base as the springs' stiff limit, and the
//! sparse path against the dense one.

use splinewatch_core::model::beam::{BeamMaterial, Section};
use splinewatch_core::model::elastic_supports::{ElasticSupport, SupportComponent};
use splinewatch_core::model::members::{BeamBase, BeamMember, BeamNet};
use splinewatch_core::model::BridgeModel;
use splinewatch_core::solvers::modal::Modes;
use splinewatch_core::solvers::sparse_model::SparseModel;

const LENGTH: f64 = 7.32;
const GLOBAL: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

fn material() -> BeamMaterial {
    BeamMaterial::isotropic(2.8e10, 0.2, 2400.0).unwrap()
}

/// A vertical 1.524 m column in `elements` elements, its base held as
/// `base`, on the six-component springs `footing` at its base if given.
fn column(elements: usize, base: BeamBase, footing: Option<Vec<(SupportComponent, f64)>>) -> BridgeModel {
    let section = Section::circle(1.524, 0.2).unwrap();
    let member = BeamMember::new(
        "column",
        ([0.0, 0.0, 0.0], [0.0, 0.0, LENGTH]),
        [1.0, 0.0, 0.0],
        section,
        material(),
        elements,
        base,
    )
    .unwrap();
    let beams = BeamNet::new(vec![member], 1e-6).unwrap();
    let base_node = beams.member_nodes(0)[0];
    BridgeModel {
        beams,
        elastic_supports: footing
            .map(|c| vec![ElasticSupport::at_beam_nodes("footing", vec![base_node], GLOBAL, c).unwrap()])
            .unwrap_or_default(),
        ..BridgeModel::default()
    }
}

/// Every component at `stiff`, but `z` at `k_z`.
fn footing(stiff: f64, k_z: f64) -> Vec<(SupportComponent, f64)> {
    SupportComponent::ALL
        .iter()
        .map(|&c| {
            (
                c,
                if c == SupportComponent::Translation(2) {
                    k_z
                } else {
                    stiff
                },
            )
        })
        .collect()
}

fn modes(model: &BridgeModel) -> Modes {
    model.assemble().unwrap().modes().unwrap()
}

/// The first mode whose top moves mostly along the column's axis.
fn first_axial_hz(model: &BridgeModel, modes: &Modes) -> f64 {
    let dofs = model.dof_map();
    let top = *model.beams.member_nodes(0).last().unwrap();
    let first = dofs.node_dofs(dofs.beam_node(top)).start;
    (0..modes.len())
        .find(|&i| {
            let at = |d: usize| modes.shapes[(first + d, i)].powi(2);
            at(2) > 10.0 * (at(0) + at(1))
        })
        .map(|i| modes.frequency_hz(i))
        .expect("an axial mode")
}

/// A rod on an axial spring `k` at its base, free at the top:
/// `u = cos β(L − x)`, `E A u'(0) = k u(0)`, so `E A β tan βL = k`; its
/// first root by bisection on `(0, π/2)`, `ω = β √(E/ρ)`.
fn rod_on_spring_hz(k: f64) -> f64 {
    let m = material();
    let area = Section::circle(1.524, 0.2).unwrap().area;
    let residual = |beta: f64| m.young * area * beta * (beta * LENGTH).tan() - k;
    let (mut lo, mut hi) = (1e-12, std::f64::consts::FRAC_PI_2 / LENGTH * (1.0 - 1e-15));
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if residual(mid) > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    0.5 * (lo + hi) * (m.young / m.density).sqrt() / (2.0 * std::f64::consts::PI)
}

/// The axial mode of a column on a vertical spring (the footing's piles):
/// against the rod's closed form within 1e-4 for a spring as stiff as the
/// column (`E A / L`, 7e9 N/m) and a tenth of it (the linear axial
/// interpolation converges as h²: 60 elements, measured 8.6e-6 and
/// 1.1e-6); with every component 1e17 the column's first eight frequencies
/// are the fixed base's within 1e-5 (measured 7e-8: a base flexibility of
/// 1e-17 against the column's 1e-10 m/N).
#[test]
fn a_column_on_a_footing_has_the_closed_form_axial_mode_and_the_fixed_limit() {
    let area = Section::circle(1.524, 0.2).unwrap().area;
    let axial = material().young * area / LENGTH;
    for k_z in [axial, 0.1 * axial] {
        let model = column(60, BeamBase::Free, Some(footing(1e17, k_z)));
        let found = first_axial_hz(&model, &modes(&model));
        let expected = rod_on_spring_hz(k_z);
        assert!(
            (found / expected - 1.0).abs() < 1e-4,
            "k_z {k_z:e}: {found} Hz against {expected} Hz"
        );
    }
    let fixed = modes(&column(12, BeamBase::Fixed, None));
    let on_springs = modes(&column(12, BeamBase::Free, Some(footing(1e17, 1e17))));
    for i in 0..8 {
        let (a, b) = (fixed.frequency_hz(i), on_springs.frequency_hz(i));
        assert!((b / a - 1.0).abs() < 1e-5, "mode {i}: {b} Hz on springs, {a} Hz fixed");
    }
}

/// The sparse path assembles the footing's springs as the dense one: the
/// first eight frequencies of a column on soft springs in every component
/// within 1e-8 (measured 4e-12).
#[test]
fn the_sparse_path_takes_a_footing_as_the_dense_one() {
    let soft: Vec<(SupportComponent, f64)> = SupportComponent::ALL.iter().map(|&c| (c, 3e9)).collect();
    let model = column(12, BeamBase::Free, Some(soft));
    let dense = modes(&model);
    let sparse = SparseModel::assemble(&model).unwrap();
    let theta = sparse.field_coefficients.clone();
    let partial = sparse.modes_below(&sparse.spring_stiffness, &theta, 200.0).unwrap();
    assert!(partial.len() >= 8, "{} modes below 200 Hz", partial.len());
    for i in 0..8 {
        let (a, b) = (dense.frequency_hz(i), partial.frequency_hz(i));
        assert!((b / a - 1.0).abs() < 1e-8, "mode {i}: sparse {b} Hz, dense {a} Hz");
    }
}
