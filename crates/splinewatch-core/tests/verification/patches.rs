//! Multi-patch decks against OpenSees (ShellMITC4 on a converged mesh,
//! `tests/fixtures/make_opensees_fixtures.py`), and the joints' penalty.

use splinewatch_core::geometry::knots::KnotVector;
use splinewatch_core::geometry::surface::{BSplineSurface, Direction};
use splinewatch_core::geometry::swept::{swept_surface, Centreline};
use splinewatch_core::geometry::vec3::Vec3;
use splinewatch_core::model::constraints::{Edge, EdgeConstraint, SupportKind};
use splinewatch_core::model::joints::{find_joints, Joint};
use splinewatch_core::model::material::OrthotropicMaterial;
use splinewatch_core::model::patch::Patch;
use splinewatch_core::model::shell::Shell;
use splinewatch_core::model::BridgeModel;
use splinewatch_core::solvers::modal::ModeKind;
use splinewatch_core::solvers::sparse_model::SparseModel;

fn fixture() -> serde_json::Value {
    serde_json::from_str(include_str!("../fixtures/opensees_decks.json")).unwrap()
}

fn corners(value: &serde_json::Value) -> [Vec3; 4] {
    let c: Vec<Vec3> = serde_json::from_value(value.clone()).unwrap();
    [c[0], c[1], c[2], c[3]]
}

/// The fixture's deck as B-spline patches (degree 3, the nets given per
/// patch), knots inserted at `lines` (η values, twice: C¹ where a web meets
/// the slab), both ξ ends clamped.
fn deck(case: &str, nets: &[[usize; 2]], lines: &[Vec<f64>], penalty: f64) -> (BridgeModel, Vec<f64>) {
    let fixture = fixture();
    let patches = fixture["cases"][case]["patches"].as_array().unwrap();
    let shells = patches
        .iter()
        .zip(nets)
        .map(|(p, &net)| {
            let t = p["thickness"].as_f64().unwrap();
            Shell::quadrilateral(corners(&p["corners"]), t, [3, 3], net).unwrap()
        })
        .collect();
    deck_of(case, shells, lines, penalty)
}

/// [`deck`] from the patches' shells.
fn deck_of(case_name: &str, shells: Vec<Shell>, lines: &[Vec<f64>], penalty: f64) -> (BridgeModel, Vec<f64>) {
    let material = OrthotropicMaterial::isotropic(30e9, 0.2, 2500.0).unwrap();
    let mut model = BridgeModel::new(
        Shell::rectangular_plate(1.0, 1.0, 1.0, [1, 1], [2, 2]).unwrap(),
        material.clone(),
    );
    model.patches = shells
        .into_iter()
        .zip(lines)
        .enumerate()
        .map(|(k, (mut shell, lines))| {
            for &u in lines {
                shell = shell
                    .insert_knot(Direction::Eta, u)
                    .unwrap()
                    .insert_knot(Direction::Eta, u)
                    .unwrap();
            }
            Patch::new(format!("p{k}"), shell, material.clone()).unwrap()
        })
        .collect();
    model.constraints = (0..model.patches.len())
        .flat_map(|patch| {
            [Edge::Xi0, Edge::Xi1].map(|edge| EdgeConstraint {
                edge,
                kind: SupportKind::Clamped,
                patch,
            })
        })
        .collect();
    model.joints = find_joints(&model.patches, 1e-3);
    model.joint_penalty = penalty;
    (model, reference(case_name))
}

/// The finest OpenSees mesh of `case` extrapolated (Richardson, MITC4 ~
/// h²): its last halving still moved the frequencies by 0.2-0.4 %.
fn reference(case: &str) -> Vec<f64> {
    fixture()["cases"][case]["extrapolated_hz"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect()
}

/// The first `count` frequencies, by the sparse path (shift-invert Lanczos
/// below a cutoff, raised from 20 Hz by a quarter until `count` modes lie
/// under it).
/// The dense path's full eigendecomposition of these 3 000–4 600-dof decks
/// took 40–130 s a test; the sparse path equals it to 1e-7 in ω² on a deck
/// of several patches with joints
/// ([`the_sparse_path_matches_the_dense_one_on_several_patches`]), and both
/// assemble with the same element and joint kernels.
fn first_frequencies(model: &BridgeModel, count: usize) -> Vec<f64> {
    let sparse = SparseModel::assemble(model).unwrap();
    let mut cutoff_hz = 20.0;
    let modes = loop {
        let modes = sparse.modes_below(&[], &[], cutoff_hz).unwrap();
        if modes.len() >= count {
            break modes;
        }
        assert!(cutoff_hz < 1e3, "fewer than {count} modes below {cutoff_hz} Hz");
        cutoff_hz *= 1.25;
    };
    assert!(
        modes.kinds.iter().all(|k| *k != ModeKind::Rigid),
        "clamped decks have no rigid mode"
    );
    modes.frequencies_hz()[..count].to_vec()
}

fn worst(ours: &[f64], reference: &[f64]) -> f64 {
    ours.iter()
        .zip(reference)
        .map(|(a, b)| (a / b - 1.0).abs())
        .fold(0.0, f64::max)
}

fn slab_and_webs(penalty: f64) -> (BridgeModel, Vec<f64>) {
    // The webs hang from the slab's interior lines y = ±2 m: η = 1/6, 5/6.
    let nets = [[23, 14], [23, 6], [23, 6]];
    let lines = [vec![1.0 / 6.0, 5.0 / 6.0], vec![], vec![]];
    deck("slab_and_webs", &nets, &lines, penalty)
}

/// Two webs under a slab: each web's top edge is found on the slab's
/// interior line, 20 m long; the first ten modes within 1 % of OpenSees.
#[test]
fn a_slab_on_two_webs_matches_opensees() {
    let (model, reference) = slab_and_webs(splinewatch_core::model::joints::DEFAULT_PENALTY);
    assert_eq!(model.joints.len(), 2, "{:?}", model.joints);
    for (j, web) in model.joints.iter().zip([1, 2]) {
        assert_eq!((j.patch, j.edge, j.other), (web, Edge::Eta0, 0));
        assert!((j.length - 20.0).abs() < 1e-9);
    }
    let ours = first_frequencies(&model, 10);
    let error = worst(&ours, &reference);
    eprintln!("slab and webs: ours {ours:.4?}\n opensees {reference:.4?}\n worst {error:.2e}");
    assert!(error < 0.01, "{error}");
}

/// A plate skewed by 30°, clamped on its skewed edges: one quadrilateral
/// patch, the first ten modes within 1 % of OpenSees.
#[test]
fn a_skewed_plate_matches_opensees() {
    let (model, reference) = deck("skewed_plate", &[[19, 14]], &[vec![]], 1e4);
    assert!(model.joints.is_empty());
    let ours = first_frequencies(&model, 10);
    let error = worst(&ours, &reference);
    eprintln!("skewed plate: ours {ours:.4?}\n opensees {reference:.4?}\n worst {error:.2e}");
    assert!(error < 0.01, "{error}");
}

/// The penalty ten times larger moves the first ten modes by less than
/// 1e-4 (the coupling error decreases like 1/c).
#[test]
fn the_joints_do_not_move_the_modes_when_the_penalty_grows_tenfold() {
    let c = splinewatch_core::model::joints::DEFAULT_PENALTY;
    let base = first_frequencies(&slab_and_webs(c).0, 10);
    let stiffer = first_frequencies(&slab_and_webs(10.0 * c).0, 10);
    let weaker = first_frequencies(&slab_and_webs(0.1 * c).0, 10);
    let (up, down) = (worst(&base, &stiffer), worst(&weaker, &base));
    eprintln!("penalty ×10: {up:.2e}, ÷10: {down:.2e}");
    assert!(up < 1e-4, "{up}");
    // Unjoined, the webs fall away: the joints carry the deck.
    let (mut free, _) = slab_and_webs(c);
    free.joints = Vec::<Joint>::new();
    assert!(worst(&first_frequencies(&free, 10), &base) > 0.05);
}

/// A box girder (top slab, two webs, soffit): four patches, four joints
/// (the soffit's edges on the webs' bottom edges found once); the first ten
/// modes within 1 % of OpenSees.
#[test]
fn a_box_section_matches_opensees() {
    // Webs under the top slab at y = ±1.5 m of 5 m: η = 0.2, 0.8.
    let nets = [[27, 14], [27, 6], [27, 6], [27, 8]];
    let lines = [vec![0.2, 0.8], vec![], vec![], vec![]];
    let (model, reference) = deck(
        "box_section",
        &nets,
        &lines,
        splinewatch_core::model::joints::DEFAULT_PENALTY,
    );
    assert_eq!(model.joints.len(), 4, "{:?}", model.joints);
    let ours = first_frequencies(&model, 10);
    let error = worst(&ours, &reference);
    eprintln!("box section: ours {ours:.4?}\n opensees {reference:.4?}\n worst {error:.2e}");
    assert!(error < 0.01, "{error}");
}

/// The curved deck's three patches swept along the arc through nine points.
fn curved_swept_deck() -> BridgeModel {
    let (radius, angle) = (50.0, 25f64.to_radians());
    let arc: Vec<Vec3> = (0..9)
        .map(|i| {
            let phi = angle * f64::from(i) / 8.0;
            [radius * phi.sin(), radius * (1.0 - phi.cos()), 0.0]
        })
        .collect();
    let curve = Centreline::interpolate(&arc, 3).unwrap();
    let patch = |section: [[f64; 2]; 2], thickness: f64, net: [usize; 2]| {
        let xi = KnotVector::uniform(3, net[0], 0.0, 1.0).unwrap();
        let eta = KnotVector::uniform(3, net[1], 0.0, 1.0).unwrap();
        let surface = swept_surface(&curve, section, xi, eta).unwrap();
        Shell::new(surface, vec![thickness; net[0] * net[1]]).unwrap()
    };
    let shells = vec![
        patch([[-3.0, 0.0], [3.0, 0.0]], 0.2, [25, 14]),
        patch([[-2.0, 0.0], [-2.0, -1.5]], 0.25, [25, 6]),
        patch([[2.0, 0.0], [2.0, -1.5]], 0.25, [25, 6]),
    ];
    let lines = [vec![1.0 / 6.0, 5.0 / 6.0], vec![], vec![]];
    deck_of(
        "curved_deck",
        shells,
        &lines,
        splinewatch_core::model::joints::DEFAULT_PENALTY,
    )
    .0
}

/// A slab on two webs curved in plan (radius 50 m, 25°), twice: each patch
/// swept along the arc given by nine points ([`curved_swept_deck`]), and
/// each patch an exact NURBS: the 25° arc is one rational quadratic Bézier
/// segment (weights 1, cos 12.5°, 1; P&T eq. 7.x) raised to degree 3 in
/// homogeneous coordinates (`H₁ = (H₀ + 2H₁)/3`, `H₂ = (2H₁ + H₂)/3` of the
/// quadratic), the section a straight cubic Bézier, both refined by knot
/// insertion to the nets of the swept deck. Both decks' first ten modes
/// within 1 % of OpenSees (measured 0.44 % each), and within 1e-4 of each
/// other (measured 8e-6: the swept deck's nine-point centreline is off the
/// circle by ~1e-5 of the radius, and the two parametrisations differ).
#[test]
fn a_deck_curved_in_plan_swept_or_exact_nurbs_matches_opensees() {
    let (radius, half) = (50.0, 12.5f64.to_radians());
    let cubic = KnotVector::new(vec![0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0], 3).unwrap();
    let patch = |section: [[f64; 2]; 2], thickness: f64, net: [usize; 2]| {
        // Homogeneous control points of the arc at lateral offset a
        // (radius R − a, centre (0, R)): quadratic, then raised to cubic.
        let arc = |a: f64| {
            let r = radius - a;
            let quadratic = [
                ([0.0, radius - r], 1.0),
                ([r * half.tan(), radius - r], half.cos()),
                ([r * (2.0 * half).sin(), radius - r * (2.0 * half).cos()], 1.0),
            ];
            let h = |(p, w): ([f64; 2], f64)| [w * p[0], w * p[1], w];
            let (h0, h1, h2) = (h(quadratic[0]), h(quadratic[1]), h(quadratic[2]));
            let mix = |x: [f64; 3], y: [f64; 3]| [0, 1, 2].map(|k| (x[k] + 2.0 * y[k]) / 3.0);
            [h0, mix(h0, h1), mix(h2, h1), h2]
        };
        let mut points = Vec::new();
        let mut weights = Vec::new();
        for i in 0..4 {
            for j in 0..4 {
                let s = f64::from(j) / 3.0;
                let a = section[0][0] + s * (section[1][0] - section[0][0]);
                let b = section[0][1] + s * (section[1][1] - section[0][1]);
                let [x, y, w] = arc(a)[i];
                points.push([x / w, y / w, b]);
                weights.push(w);
            }
        }
        let surface = BSplineSurface::rational(cubic.clone(), cubic.clone(), points, weights).unwrap();
        let mut shell = Shell::new(surface, vec![thickness; 16]).unwrap();
        for (direction, count) in [(Direction::Xi, net[0]), (Direction::Eta, net[1])] {
            let spans = count - 3;
            for k in 1..spans {
                shell = shell.insert_knot(direction, k as f64 / spans as f64).unwrap();
            }
        }
        shell
    };
    let shells = vec![
        patch([[-3.0, 0.0], [3.0, 0.0]], 0.2, [25, 14]),
        patch([[-2.0, 0.0], [-2.0, -1.5]], 0.25, [25, 6]),
        patch([[2.0, 0.0], [2.0, -1.5]], 0.25, [25, 6]),
    ];
    assert!(shells.iter().all(|s| s.surface().weights().is_some()));
    assert_eq!(shells[0].surface().net_size(), (25, 14));
    let lines = [vec![1.0 / 6.0, 5.0 / 6.0], vec![], vec![]];
    let (model, reference) = deck_of(
        "curved_deck",
        shells,
        &lines,
        splinewatch_core::model::joints::DEFAULT_PENALTY,
    );
    assert_eq!(model.joints.len(), 2, "{:?}", model.joints);
    let ours = first_frequencies(&model, 10);
    let swept_deck = curved_swept_deck();
    assert_eq!(swept_deck.joints.len(), 2, "{:?}", swept_deck.joints);
    let swept = first_frequencies(&swept_deck, 10);
    let (error, swept_error) = (worst(&ours, &reference), worst(&swept, &reference));
    let apart = worst(&ours, &swept);
    eprintln!(
        "curved deck: NURBS {ours:.4?}\n swept {swept:.4?}\n opensees {reference:.4?}\n worst {error:.2e} (swept {swept_error:.2e}), apart {apart:.2e}"
    );
    assert!(error < 0.01 && swept_error < 0.01, "{error} {swept_error}");
    assert!(apart < 1e-4, "{apart}");
}

/// The sparse path on a deck of several patches: the slab on two webs with
/// a bearing under one web, a point mass, pavement on the slab, a spring
/// field on a web and a stiffness field on the slab. `K(κ, θ)` and `M`
/// equal the dense model's on the free coordinates (1e-12 of the largest
/// diagonal: only the order of the sums differs), and every mode below
/// 40 Hz matches: ω² within 1e-7. The joints' penalty raises `‖K‖` about
/// 10⁴-fold over the deck's own, and the Lanczos acceptance (residual 1e-8
/// of `‖K‖ + λ‖M‖`) is relative to it: measured 3e-8 on the lowest mode,
/// ~5e-10 on the others.
#[test]
fn the_sparse_path_matches_the_dense_one_on_several_patches() {
    use splinewatch_core::model::bearings::{Bearing, PatchPoint, PointMass};
    use splinewatch_core::model::springs::{Face, SpringDirection, SpringField};
    use splinewatch_core::model::stiffness_field::StiffnessField;
    let nets = [[11, 10], [11, 5], [11, 5]];
    let lines = [vec![1.0 / 6.0, 5.0 / 6.0], vec![], vec![]];
    let (mut model, _) = deck("slab_and_webs", &nets, &lines, 1e4);
    let material = model.patches[0].material.clone();
    model.patches[0] = Patch::new("slab", model.patches[0].shell.clone(), material)
        .unwrap()
        .with_non_structural_mass(180.0)
        .unwrap();
    // Only the slab's ends clamped: the webs hang on the joints, one on a
    // bearing and a spring strip.
    model.constraints.retain(|c| c.patch == 0);
    let at = |patch, xi, eta, tau| PatchPoint { patch, xi, eta, tau };
    model.bearings = vec![Bearing::new(at(1, 0.5, 1.0, 0.5), [2e8, 3e8, 5e8]).unwrap()];
    model.masses = vec![PointMass::new(at(0, 0.3, 0.5, 0.5), 4000.0).unwrap()];
    let strip = KnotVector::new(vec![0.0, 0.05], 0).unwrap();
    let across = KnotVector::new(vec![0.0, 0.0, 1.0, 1.0], 1).unwrap();
    let direction = SpringDirection::fixed([0.0, 0.0, 1.0]).unwrap();
    model.springs = vec![SpringField::new(strip, across, vec![1e9, 2e9], direction, Face::Bottom)
        .unwrap()
        .on_patch(2)];
    let halves = KnotVector::new(vec![0.0, 0.0, 0.5, 1.0, 1.0], 1).unwrap();
    let whole = KnotVector::new(vec![0.0, 1.0], 0).unwrap();
    model.stiffness_fields = vec![StiffnessField::new(halves, whole, vec![1.0; 3]).unwrap()];
    let dense = model.assemble().unwrap();
    let sparse = SparseModel::assemble(&model).unwrap();
    assert_eq!(sparse.free_count(), dense.reduction.free_count());
    let kappa = vec![vec![1.5e9, 0.5e9], vec![4e8, 1e8, 6e8]];
    let theta = vec![vec![0.9, 0.7, 1.1]];
    let kd = dense
        .reduction
        .reduce(&dense.stiffness_with_fields(&kappa, &theta).unwrap());
    let md = dense.reduction.reduce(&dense.mass);
    let ks = sparse.stiffness_with_fields(&kappa, &theta).unwrap().to_dense();
    let ms = sparse.mass.to_dense();
    for (name, d, s) in [("K", &kd, &ks), ("M", &md, &ms)] {
        let top = (0..d.nrows()).map(|i| d[(i, i)].abs()).fold(0.0, f64::max);
        let gap = (d - s).norm_max();
        assert!(gap <= 1e-12 * top, "{name}: {gap:e} of {top:e}");
    }
    let reference = dense.modes_with_fields(&kappa, &theta).unwrap();
    let found = sparse.modes_below(&kappa, &theta, 40.0).unwrap();
    let expected = reference.frequencies_hz().iter().filter(|&&f| f <= 40.0).count();
    assert!(expected >= 6, "{expected} modes below 40 Hz");
    assert_eq!(found.len(), expected);
    let gaps: Vec<f64> = (0..expected)
        .map(|i| (found.omega2[i] / reference.omega2[i] - 1.0).abs())
        .collect();
    let shown: Vec<String> = gaps.iter().map(|g| format!("{g:.1e}")).collect();
    eprintln!("{expected} modes below 40 Hz, relative ω² gaps {shown:?}");
    for (i, gap) in gaps.iter().enumerate() {
        assert!(*gap <= 1e-7, "mode {i}: {} vs {}", found.omega2[i], reference.omega2[i]);
        assert_eq!(found.kinds[i], reference.kinds[i], "mode {i}");
    }
}
