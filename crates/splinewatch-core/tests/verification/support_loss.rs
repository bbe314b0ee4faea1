//! Damping that follows the structure: loss factors on the supports,
//! weighed by each mode's strain energy in them (modal strain energy,
//! Johnson & Kienholz 1982), against the complex modes of the hysteretic
//! model and their sensitivities against central differences.

use faer::{c64, Mat, Side};
use splinewatch_core::geometry::knots::KnotVector;
use splinewatch_core::model::damping::DampingCurve;
use splinewatch_core::model::elastic_supports::{ElasticSupport, SupportComponent};
use splinewatch_core::model::loss_sites::{LossSite, LossSites};
use splinewatch_core::model::material::OrthotropicMaterial;
use splinewatch_core::model::shell::Shell;
use splinewatch_core::model::stiffness_field::StiffnessField;
use splinewatch_core::model::BridgeModel;
use splinewatch_core::response::frf::{FrfModel, FrfRequest, ModalState, Quantity, SensorPoint};
use splinewatch_core::solvers::modal::ModeKind;
use splinewatch_core::updating::modal_residual::{modal_residue, pair_modes, ObservedMode};
use splinewatch_core::updating::{model_at, Parameter, ParameterKind};

const GLOBAL: [[f64; 3]; 3] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// A 12 m × 3 m × 0.3 m deck on two abutments: line supports along its
/// ends, stiff along and across it, soft vertically and against rotation,
/// so that some modes keep much of their strain energy in them and others
/// little. The abutments differ, so no two modes coincide.
fn deck_on_abutments() -> (FrfModel, Vec<Vec<f64>>) {
    deck_with_fields(Vec::new())
}

/// [`deck_on_abutments`] with stiffness fields on the deck.
fn deck_with_fields(fields: Vec<StiffnessField>) -> (FrfModel, Vec<Vec<f64>>) {
    let (model, sensors) = deck_model(fields);
    let kappa = model.spring_coefficients();
    (FrfModel::new(model.assemble().unwrap(), &sensors).unwrap(), kappa)
}

/// The abutments' components: west, then east (`x`, `y`, `z`, `ry`).
fn abutment_components(vertical: f64, rotation: f64) -> Vec<(SupportComponent, f64)> {
    vec![
        (SupportComponent::Translation(0), 2e9),
        (SupportComponent::Translation(1), 1e9),
        (SupportComponent::Translation(2), vertical),
        (SupportComponent::Rotation(1), rotation),
    ]
}

/// The deck of [`deck_on_abutments`] and its three sensors.
fn deck_model(fields: Vec<StiffnessField>) -> (BridgeModel, Vec<SensorPoint>) {
    use splinewatch_core::model::constraints::Edge;
    deck_on_supports(
        fields,
        vec![
            ("west", Edge::Xi0, abutment_components(3e8, 2e8)),
            ("east", Edge::Xi1, abutment_components(5e8, 6e7)),
        ],
    )
}

/// A line support along an edge of the deck: its name, edge and components.
type LineSupport<'a> = (
    &'a str,
    splinewatch_core::model::constraints::Edge,
    Vec<(SupportComponent, f64)>,
);

/// The deck on line supports along its ends.
fn deck_on_supports(fields: Vec<StiffnessField>, supports: Vec<LineSupport<'_>>) -> (BridgeModel, Vec<SensorPoint>) {
    let shell = Shell::rectangular_plate(12.0, 3.0, 0.3, [3, 3], [8, 4]).unwrap();
    let material = OrthotropicMaterial::isotropic(30e9, 0.2, 2500.0).unwrap();
    let mut model = BridgeModel::new(shell, material);
    model.stiffness_fields = fields;
    model.elastic_supports = supports
        .into_iter()
        .map(|(name, edge, components)| ElasticSupport::along_edge(name, (0, edge), GLOBAL, components).unwrap())
        .collect();
    let sensors: Vec<SensorPoint> = [
        (0.3, 0.2, [0.0, 0.0, 1.0]),
        (0.71, 0.8, [0.0, 1.0, 0.0]),
        (0.05, 0.5, [0.0, 0.0, 1.0]),
    ]
    .into_iter()
    .map(|(xi, eta, direction)| SensorPoint {
        patch: 0,
        xi,
        eta,
        tau: 0.5,
        direction,
    })
    .collect();
    (model, sensors)
}

/// `Σ_j η_j κ_j B_j`, the supports' hysteretic stiffness, on the
/// generalised dofs, with `eta[j]` the loss factor of spring coefficient
/// `j` (flat over the fields).
fn hysteretic(frf: &FrfModel, kappa: &[Vec<f64>], eta: &[f64]) -> Mat<f64> {
    let n = frf.dense().unwrap().mass.nrows();
    let mut d = Mat::<f64>::zeros(n, n);
    let mut flat = 0;
    for (s, blocks) in frf.spring_blocks().iter().enumerate() {
        for (j, block) in blocks.iter().enumerate() {
            for (a, &da) in block.dofs.iter().enumerate() {
                for (b, &db) in block.dofs.iter().enumerate() {
                    d[(da, db)] += eta[flat] * kappa[s][j] * block.values[(a, b)];
                }
            }
            flat += 1;
        }
    }
    d
}

/// The damping of the complex modes of `K + j Σ_s η_s K_s − λ M` (each
/// complex eigenvalue `μ = ω²(1 + j η_eq)`, `ζ = η_eq / 2`) against the
/// modal-strain-energy damping of the same modes: agreement to `O(η²)`.
/// With η = 0.2 and 0.1 on the two abutments the worst relative difference
/// over the first eight bending modes must stay below 5 % (what the method
/// promises for η ≤ 0.2); the supports' shares must equal the strain
/// energy fractions `Modes::spring_energy_share` computes on its own.
#[test]
fn loss_factors_damp_each_mode_as_the_complex_modes_of_the_hysteretic_model() {
    let (frf, kappa) = deck_on_abutments();
    let curve = DampingCurve::new(1, vec![0.0, 0.0], 0.0, 100.0)
        .unwrap()
        .with_loss_factors(vec![0.2, 0.1])
        .unwrap();
    // Four components per abutment.
    let eta: Vec<f64> = [[0.2; 4], [0.1; 4]].concat();
    check_against_complex_modes(&frf, &kappa, &curve, (&eta, &[]));
}

/// Loss factors on some components only (loss sites): 0.2 on the west
/// abutment's vertical and rotational springs, 0.15 on the east one's
/// rotational springs, none elsewhere; the same check as whole supports'.
#[test]
fn loss_factors_on_some_components_damp_as_the_complex_modes() {
    let (frf, kappa) = deck_on_abutments();
    let sites = LossSites::new(vec![LossSite::springs(vec![2, 3]), LossSite::springs(vec![7])]).unwrap();
    let curve = DampingCurve::new(1, vec![0.0, 0.0], 0.0, 100.0)
        .unwrap()
        .with_loss_factors(vec![0.2, 0.15])
        .unwrap()
        .with_loss_sites(sites)
        .unwrap();
    let eta = [0.0, 0.0, 0.2, 0.2, 0.0, 0.0, 0.0, 0.15];
    check_against_complex_modes(&frf, &kappa, &curve, (&eta, &[]));
}

/// The complex-modes check of the tests above: `curve`'s loss factors act
/// on spring coefficient `j` with `eta[j]` and on stiffness-field
/// coefficient `k`'s part with `eta_fields[k]` (the model's own field
/// coefficients).
fn check_against_complex_modes(
    frf: &FrfModel,
    kappa: &[Vec<f64>],
    curve: &DampingCurve,
    (eta, eta_fields): (&[f64], &[f64]),
) {
    let state = frf.modal_state(kappa, curve).unwrap();
    let dense = frf.dense().unwrap();
    let reduction = &dense.reduction;
    let theta: Vec<f64> = dense.field_coefficients.iter().flatten().copied().collect();
    let k = reduction.reduce(&dense.stiffness_with_fields(kappa, &dense.field_coefficients).unwrap());
    let mut full = hysteretic(frf, kappa, eta);
    for (matrix, (e, t)) in dense.field_matrices.iter().flatten().zip(eta_fields.iter().zip(&theta)) {
        full += (e * t) * matrix;
    }
    let d = reduction.reduce(&full);
    let m = reduction.reduce(&dense.mass);
    // M^{-1/2} (K + jD) M^{-1/2}: the same eigenvalues.
    let eigen = m.self_adjoint_eigen(Side::Lower).unwrap();
    let (u, s) = (eigen.U(), eigen.S().column_vector());
    let root = Mat::from_fn(m.nrows(), m.nrows(), |i, j| {
        (0..m.nrows()).map(|l| u[(i, l)] * u[(j, l)] / s[l].sqrt()).sum::<f64>()
    });
    let (kr, dr) = (&root * &k * &root, &root * &d * &root);
    let a = Mat::from_fn(kr.nrows(), kr.ncols(), |i, j| c64::new(kr[(i, j)], dr[(i, j)]));
    let mu = a.eigenvalues().unwrap();
    let bending: Vec<usize> = (0..state.modes.len())
        .filter(|&i| state.modes.kinds[i] == ModeKind::Bending)
        .take(8)
        .collect();
    let mut worst: f64 = 0.0;
    for &i in &bending {
        let lambda = state.modes.omega2[i];
        // Modes' own shares against the independent strain-energy fractions,
        // summed over each site's coefficients.
        let shares: Vec<f64> = frf
            .spring_blocks()
            .iter()
            .zip(kappa)
            .flat_map(|(blocks, k)| (0..blocks.len()).map(move |j| (&blocks[j..=j], &k[j..=j])))
            .map(|(b, k)| state.modes.spring_energy_share(i, b, k))
            .collect();
        let field_shares = state.modes.field_energy_shares(&dense.field_coefficients, |k, x| {
            dense.field_matrices.iter().flatten().nth(k).unwrap() * x
        });
        let sites = curve.loss_sites(&frf.spring_field_sizes());
        for s in 0..sites.len() {
            let site = sites.site(s);
            let share: f64 = site.springs.iter().map(|&j| shares[j]).sum::<f64>()
                + site.fields.iter().map(|&k| field_shares[(i, k)]).sum::<f64>();
            let found = state.support_energy(i, s).unwrap();
            assert!(
                (found - share).abs() <= 1e-12 * share.max(1.0),
                "mode {i} site {s}: {found} vs {share}"
            );
        }
        let expected = c64::new(lambda, 2.0 * lambda * state.zeta[i]);
        let nearest = mu
            .iter()
            .min_by(|a, b| (**a - expected).norm().total_cmp(&(**b - expected).norm()))
            .unwrap();
        let complex = nearest.im / (2.0 * nearest.re);
        let error = (state.zeta[i] / complex - 1.0).abs();
        eprintln!(
            "mode {i}: {:.2} Hz, ζ = {:.4} (strain energy) vs {complex:.4} (complex modes), {error:.1e}",
            state.modes.frequency_hz(i),
            state.zeta[i]
        );
        worst = worst.max(error);
        assert!(error < 0.05, "mode {i}: ζ {} vs complex {complex}", state.zeta[i]);
    }
    // The supports must matter on these modes (else the check is empty).
    assert!(bending.iter().any(|&i| state.zeta[i] > 0.02));
    eprintln!("modal strain energy vs complex modes: worst relative difference {worst:.1e}");
}

/// Central difference of `f` in its scalar argument, Richardson-extrapolated
/// from steps `h` and `h/2` (truncation O(h⁴)).
fn richardson<T: Fn(f64) -> Vec<c64>>(f: T, h: f64) -> Vec<c64> {
    let central = |h: f64| -> Vec<c64> {
        let (plus, minus) = (f(h), f(-h));
        plus.iter().zip(&minus).map(|(p, m)| (p - m) / (2.0 * h)).collect()
    };
    let (coarse, fine) = (central(h), central(0.5 * h));
    fine.iter().zip(&coarse).map(|(f, c)| (4.0 * f - c) / 3.0).collect()
}

fn column_error(analytic: &[c64], fd: &[c64]) -> f64 {
    let num: f64 = analytic.iter().zip(fd).map(|(a, b)| (a - b).norm_sqr()).sum();
    let den: f64 = fd.iter().map(|b| b.norm_sqr()).sum();
    (num / den).sqrt()
}

/// With loss factors the FRFs' sensitivities to every spring coefficient
/// (the supports' share of ζ_i moving with each mode's shape and
/// eigenvalue), to the loss factors themselves, and the modes' `∂ζ_i/∂κ_j`
/// against central differences of the whole evaluation (modes re-solved):
/// 1e-6 relative per column, as for the springs without loss factors.
/// The damping curve of the sensitivity checks: ζ(f) quadratic on
/// [0, 120] Hz, loss factors 0.15 and 0.08 on the two abutments.
fn lossy_curve() -> DampingCurve {
    DampingCurve::new(2, vec![0.01, 0.03, 0.005, 0.02], 0.0, 120.0)
        .unwrap()
        .with_loss_factors(vec![0.15, 0.08])
        .unwrap()
}

/// The sensor pairs the checks compare (a driving point, a transfer, the
/// other input's transfer).
const PAIRS: [(usize, usize); 3] = [(0, 0), (1, 0), (2, 1)];

fn accelerances(frequencies_hz: &[f64]) -> FrfRequest<'_> {
    FrfRequest {
        frequencies_hz,
        pairs: &PAIRS,
        quantity: Quantity::Accelerance,
    }
}

/// The first `count` bending modes of `state`.
fn first_bending(state: &ModalState, count: usize) -> Vec<usize> {
    (0..state.modes.len())
        .filter(|&i| state.modes.kinds[i] == ModeKind::Bending)
        .take(count)
        .collect()
}

#[test]
fn loss_factor_sensitivities_match_central_differences() {
    let (frf, kappa) = deck_on_abutments();
    let worst = check_spring_and_loss_sensitivities(&frf, &kappa, &lossy_curve());
    eprintln!("loss factors: worst relative column error {worst:.1e}");
}

/// The central-difference checks of the test above for `curve` on `frf`
/// (its own stiffness-field coefficients): the worst relative error.
fn check_spring_and_loss_sensitivities(frf: &FrfModel, kappa: &[Vec<f64>], curve: &DampingCurve) -> f64 {
    let kappa = kappa.to_vec();
    let curve = curve.clone();
    let state = frf.modal_state(&kappa, &curve).unwrap();
    let freqs = [3.0, 7.7, 12.4, 19.0, 26.5, 41.0, 63.0];
    let request = accelerances(&freqs);
    let eval = frf.evaluate(&state, request, true);
    let bending = first_bending(&state, 6);
    let modal = frf.modal_sensitivities(&state, &bending);
    let mut worst: f64 = 0.0;
    let mut flat = 0;
    for s in 0..kappa.len() {
        for j in 0..kappa[s].len() {
            let at_kappa = |delta: f64| {
                let mut k = kappa.clone();
                k[s][j] += delta;
                frf.modal_state(&k, &curve).unwrap()
            };
            let fd = richardson(|d| frf.evaluate(&at_kappa(d), request, false).h, 1e-3 * kappa[s][j]);
            let scale = eval.h.iter().map(|v| v.norm()).fold(0.0, f64::max) / kappa[s][j];
            if fd.iter().all(|v| v.norm() <= 1e-12 * scale) {
                // A component the sensors do not see (the deck's in-plane
                // stiffness along it, under vertical and transverse sensors):
                // both must vanish.
                assert!(eval.dh_dkappa[flat].iter().all(|v| v.norm() <= 1e-12 * scale));
            } else {
                let e = column_error(&eval.dh_dkappa[flat], &fd);
                worst = worst.max(e);
                assert!(e < 1e-6, "∂H/∂κ support {s} component {j}: relative error {e:e}");
            }
            let zeta_fd = richardson(
                |d| {
                    let st = at_kappa(d);
                    bending.iter().map(|&i| c64::new(st.zeta[i], 0.0)).collect()
                },
                // A step of 1 %: with a loss factor on the deck's stiffness
                // each ζ_i carries the field's energy share, whose membrane
                // part cancels to ~1e-11 relative in the eigen-solve; at 0.1 %
                // that noise alone reached 1e-5 (it falls with the step, so
                // no term is missing; Richardson's O(h⁴) is ~1e-8 here).
                1e-2 * kappa[s][j],
            );
            for (row, fd) in zeta_fd.iter().enumerate() {
                let analytic = modal.damping_ratio[(row, flat)];
                let e = (analytic - fd.re).abs() / fd.re.abs().max(1e-3 * state.zeta[bending[row]] / kappa[s][j]);
                assert!(
                    e < 1e-5,
                    "∂ζ/∂κ mode {} support {s} component {j}: {analytic} vs {}",
                    bending[row],
                    fd.re
                );
            }
            flat += 1;
        }
    }
    // The loss factors: columns after the curve's.
    let nz = curve.coefficients().len();
    for s in 0..curve.loss_factors().len() {
        let at = |delta: f64| {
            let mut eta = curve.loss_factors().to_vec();
            eta[s] += delta;
            let lossy = curve.with_loss_factors(eta).unwrap();
            frf.evaluate(&frf.restate(&state, &lossy), request, false).h
        };
        let fd = richardson(at, 1e-4);
        let e = column_error(&eval.dh_dgamma[nz + s], &fd);
        worst = worst.max(e);
        assert!(e < 1e-6, "∂H/∂η_{s}: relative error {e:e}");
    }
    worst
}

/// The deck's stiffness-field sensitivities with loss factors on the
/// abutments: a change of the deck's stiffness moves each mode's share of
/// strain energy in the supports (their stiffness held), so ζ_i moves with
/// it. `∂H/∂θ` and `∂ζ_i/∂θ` against central differences, 1e-6 relative
/// per column as the springs'.
#[test]
fn loss_factors_follow_the_deck_stiffness_in_its_sensitivities() {
    let worst = check_field_sensitivities(&lossy_curve());
    eprintln!("loss factors and deck stiffness: worst relative error {worst:.1e}");
}

/// The deck with one stiffness field (six coefficients) on two abutments.
fn deck_with_one_field(theta: Vec<f64>) -> (FrfModel, Vec<Vec<f64>>) {
    let knots = |n| KnotVector::uniform(1, n, 0.0, 1.0).unwrap();
    deck_with_fields(vec![StiffnessField::new(knots(3), knots(2), theta).unwrap()])
}

/// The central-difference checks of the test above for `curve`: the worst
/// relative error.
fn check_field_sensitivities(curve: &DampingCurve) -> f64 {
    let (frf, kappa) = deck_with_one_field(vec![1.0; 6]);
    let curve = curve.clone();
    let theta = vec![vec![1.0, 0.9, 1.1, 0.8, 1.05, 1.2]];
    let state = frf.modal_state_with_fields(&kappa, &theta, &curve).unwrap();
    let freqs = [3.0, 7.7, 12.4, 19.0, 26.5, 41.0, 63.0];
    let request = accelerances(&freqs);
    let analytic = frf.field_frf_sensitivities(&state, &curve, request);
    let bending = first_bending(&state, 6);
    let modal = frf.field_sensitivities(&state, &bending);
    let mut worst: f64 = 0.0;
    for k in 0..theta[0].len() {
        let at = |delta: f64| {
            let mut t = theta.clone();
            t[0][k] += delta;
            frf.modal_state_with_fields(&kappa, &t, &curve).unwrap()
        };
        let fd = richardson(|d| frf.evaluate(&at(d), request, false).h, 1e-3);
        let e = column_error(&analytic[k], &fd);
        worst = worst.max(e);
        assert!(e < 1e-6, "∂H/∂θ_{k}: relative error {e:e}");
        let zeta_fd = richardson(
            |d| bending.iter().map(|&i| c64::new(at(d).zeta[i], 0.0)).collect(),
            1e-3,
        );
        for (row, fd) in zeta_fd.iter().enumerate() {
            let found = modal.damping_ratio[(row, k)];
            let e = (found - fd.re).abs() / fd.re.abs().max(1e-3 * state.zeta[bending[row]]);
            worst = worst.max(e);
            assert!(e < 1e-5, "∂ζ/∂θ_{k} mode {}: {found} vs {}", bending[row], fd.re);
        }
    }
    worst
}

/// A loss factor on the deck's own stiffness (a stiffness field's part,
/// `K_s = Σ_k θ_k ∂K/∂θ_k`) beside one on the west abutment: the damping
/// against the complex modes of `K + j (η_w K_w + η_d K_d)` (as the
/// supports' above, 5 %), and every sensitivity against central
/// differences (`∂H/∂κ`, `∂ζ/∂κ`, `∂H/∂η`, `∂H/∂θ`, `∂ζ/∂θ`, the
/// tolerances above): with `∂K_s/∂θ_k ≠ 0` the field's own coefficient
/// enters `∂ζ_i/∂θ_k` directly.
#[test]
fn a_loss_factor_on_the_decks_stiffness_damps_and_differentiates_exactly() {
    let theta = vec![1.0, 0.9, 1.1, 0.8, 1.05, 1.2];
    let (frf, kappa) = deck_with_one_field(theta);
    let sites = LossSites::new(vec![
        LossSite::springs((0..4).collect()),
        LossSite::fields((0..6).collect()),
    ])
    .unwrap();
    let with_sites = |curve: DampingCurve, eta: Vec<f64>| {
        curve
            .with_loss_factors(eta)
            .unwrap()
            .with_loss_sites(sites.clone())
            .unwrap()
    };
    let flat = DampingCurve::new(1, vec![0.0, 0.0], 0.0, 100.0).unwrap();
    let eta_springs = [[0.2; 4], [0.0; 4]].concat();
    check_against_complex_modes(
        &frf,
        &kappa,
        &with_sites(flat, vec![0.2, 0.1]),
        (&eta_springs, &[0.1; 6]),
    );
    let curve = with_sites(
        DampingCurve::new(2, vec![0.01, 0.03, 0.005, 0.02], 0.0, 120.0).unwrap(),
        vec![0.15, 0.08],
    );
    let springs = check_spring_and_loss_sensitivities(&frf, &kappa, &curve);
    let fields = check_field_sensitivities(&curve);
    eprintln!(
        "a loss factor on the deck's stiffness: worst relative error {springs:.1e} (springs), {fields:.1e} (fields)"
    );
}

/// The modal residue with loss factors among the parameters: its damping
/// rows move with the supports' stiffness (through each mode's share of
/// strain energy) and with the loss factors (`½ e_{i,s}`); every column
/// against central differences of the residue, within 1e-5 of the
/// column's largest entry (as the residue's other checks).
#[test]
fn the_modal_residue_updates_loss_factors_with_exact_columns() {
    // One loss factor on the west abutment, then one shared by both (a run).
    for (name, count) in [("west.eta", 1), ("both.eta", 2)] {
        check_modal_residue_with_loss_factor(name, count);
    }
}

fn check_modal_residue_with_loss_factor(name: &str, count: usize) {
    let (frf, kappa) = deck_on_abutments();
    let curve = DampingCurve::new(1, vec![0.01, 0.02], 0.0, 120.0)
        .unwrap()
        .with_loss_factors(vec![0.15, 0.15])
        .unwrap();
    let parameters = vec![
        Parameter {
            name: "west.z".into(),
            kind: ParameterKind::Spring {
                field: 0,
                coefficient: 2,
            },
            lower: 1e6,
            upper: 1e10,
        },
        Parameter {
            name: "east.ry".into(),
            kind: ParameterKind::Spring {
                field: 1,
                coefficient: 3,
            },
            lower: 1e6,
            upper: 1e10,
        },
        Parameter {
            name: name.into(),
            kind: ParameterKind::LossFactor { field: 0, count },
            lower: 0.0,
            upper: 1.0,
        },
        Parameter {
            name: "damping.g1".into(),
            kind: ParameterKind::Damping { coefficient: 0 },
            lower: 0.0,
            upper: 0.1,
        },
    ];
    let at = |p: &[f64]| {
        let (k, d) = model_at(&parameters, &kappa, &curve, p).unwrap();
        frf.modal_state(&k, &d).unwrap()
    };
    let p0 = vec![kappa[0][2], kappa[1][3], 0.12, 0.01];
    let state = at(&p0);
    let truth = at(&[0.8 * kappa[0][2], 1.3 * kappa[1][3], 0.2, 0.012]);
    let bending: Vec<usize> = (0..truth.modes.len())
        .filter(|&i| truth.modes.kinds[i] == ModeKind::Bending)
        .take(6)
        .collect();
    let observed: Vec<ObservedMode> = bending
        .iter()
        .map(|&i| ObservedMode {
            frequency_hz: truth.modes.frequency_hz(i),
            frequency_std_hz: 1e-3 * truth.modes.frequency_hz(i),
            damping_ratio: truth.zeta[i],
            damping_std: 5e-4,
            shape: (0..3).map(|s| (s, c64::new(truth.amplitude(s, i), 0.0))).collect(),
            shape_std: 0.02,
        })
        .collect();
    let pairs = pair_modes(&state, &observed, 0.5, 0.3);
    assert!(pairs.len() >= 4, "{pairs:?}");
    let base = modal_residue(&frf, &state, &observed, &pairs, &parameters, true);
    let mut worst: f64 = 0.0;
    for c in 0..parameters.len() {
        let h = if c < 2 { 1e-4 * p0[c] } else { 1e-5 };
        let residue = |sign: f64| {
            let mut p = p0.clone();
            p[c] += sign * h;
            modal_residue(&frf, &at(&p), &observed, &pairs, &parameters, false).residual
        };
        let (plus, minus) = (residue(1.0), residue(-1.0));
        let scale = (0..base.jacobian.nrows())
            .map(|r| base.jacobian[(r, c)].abs())
            .fold(0.0, f64::max);
        assert!(scale > 0.0, "{}: an empty column", parameters[c].name);
        for r in 0..base.jacobian.nrows() {
            let fd = (plus[r] - minus[r]) / (2.0 * h);
            let error = (base.jacobian[(r, c)] - fd).abs() / scale;
            worst = worst.max(error);
            assert!(
                error < 1e-5,
                "row {r}, {}: {} vs {fd}",
                parameters[c].name,
                base.jacobian[(r, c)]
            );
        }
    }
    eprintln!("modal residue with loss factor {name}: worst column error {worst:.1e}");
}

/// On a truncated model the loss factors' share of ζ moves with the kept
/// modes and, through the eigenvector derivatives, with the discarded ones:
/// a line support's stiffness couples each mode with them strongly (the
/// sum over modes converges slowly), so their part comes from the
/// discarded modes' flexibility at the spring dofs (first order, Wang
/// 1991). `∂H/∂κ` and `∂H/∂η` of the deck truncated at 60 Hz against
/// central differences of its own evaluation (which also exercises the
/// partial eigensolver on a model too small for a Krylov subspace):
/// `∂H/∂η` exact (1e-6); `∂H/∂κ` within 4.6e-3 per column (test 1e-2),
/// where the same deck without loss factors is within 3e-3 (the truncation
/// of the damping curve's part) and without the discarded modes' part the
/// loss factors' columns were 23 % off.
#[test]
fn loss_factors_on_a_truncated_model_are_close_to_exact() {
    let (model, sensors) = deck_model(Vec::new());
    let kappa = model.spring_coefficients();
    let frf = FrfModel::truncated(&model, &sensors, 60.0).unwrap();
    let curve = lossy_curve();
    let state = frf.modal_state(&kappa, &curve).unwrap();
    let freqs = [3.0, 7.7, 12.4, 19.0, 26.5, 41.0];
    let request = accelerances(&freqs);
    let eval = frf.evaluate(&state, request, true);
    let mut worst: f64 = 0.0;
    let mut flat = 0;
    for s in 0..kappa.len() {
        for j in 0..kappa[s].len() {
            let at = |d: f64| {
                let mut k = kappa.clone();
                k[s][j] += d;
                frf.evaluate(&frf.modal_state(&k, &curve).unwrap(), request, false).h
            };
            let fd = richardson(at, 1e-3 * kappa[s][j]);
            let scale = eval.h.iter().map(|v| v.norm()).fold(0.0, f64::max) / kappa[s][j];
            // Components the sensors barely see (in-plane, along and across
            // the deck: their modes lie above the cut-off) are skipped.
            if fd.iter().any(|v| v.norm() > 1e-3 * scale) {
                let e = column_error(&eval.dh_dkappa[flat], &fd);
                worst = worst.max(e);
                assert!(e < 1e-2, "∂H/∂κ support {s} component {j}: relative error {e:e}");
            }
            flat += 1;
        }
    }
    let nz = curve.coefficients().len();
    for s in 0..2 {
        let at = |d: f64| {
            let mut eta = curve.loss_factors().to_vec();
            eta[s] += d;
            let lossy = curve.with_loss_factors(eta).unwrap();
            frf.evaluate(&frf.modal_state(&kappa, &lossy).unwrap(), request, false)
                .h
        };
        let e = column_error(&eval.dh_dgamma[nz + s], &richardson(at, 1e-4));
        worst = worst.max(e);
        assert!(e < 1e-6, "∂H/∂η_{s}: relative error {e:e}");
    }
    eprintln!("loss factors on the truncated model: worst relative column error {worst:.1e}");
}

/// A loss factor on some components of a support is the physics of that
/// support cut in two with the loss factor on the part holding those
/// components, one per spring field (the case the checks above verify
/// against the complex modes and central differences): the two models' ζ_i,
/// `∂ζ_i/∂κ_j` and the FRFs' sensitivities to every spring coefficient,
/// damping coefficient and loss factor agree to round-off (1e-9 relative:
/// the two assemble the same K in another order).
#[test]
fn a_loss_factor_on_some_components_acts_as_a_support_cut_in_two() {
    use splinewatch_core::model::constraints::Edge;
    let west = abutment_components(3e8, 2e8);
    let east = abutment_components(5e8, 6e7);
    let curve = DampingCurve::new(2, vec![0.01, 0.03, 0.005, 0.02], 0.0, 120.0).unwrap();
    // West's y and z (coefficients 1, 2) at 0.15, east's ry (7) at 0.08.
    let (whole_model, sensors) = deck_model(Vec::new());
    let whole = FrfModel::new(whole_model.assemble().unwrap(), &sensors).unwrap();
    let sited = curve
        .with_loss_factors(vec![0.15, 0.08])
        .unwrap()
        .with_loss_sites(LossSites::new(vec![LossSite::springs(vec![1, 2]), LossSite::springs(vec![7])]).unwrap())
        .unwrap();
    // West (x, ry), west's soil (y, z), east (x, y, z), east's soil (ry).
    let (cut_model, _) = deck_on_supports(
        Vec::new(),
        vec![
            ("west", Edge::Xi0, vec![west[0], west[3]]),
            ("west_soil", Edge::Xi0, west[1..3].to_vec()),
            ("east", Edge::Xi1, east[..3].to_vec()),
            ("east_soil", Edge::Xi1, east[3..].to_vec()),
        ],
    );
    let cut = FrfModel::new(cut_model.assemble().unwrap(), &sensors).unwrap();
    let per_field = curve.with_loss_factors(vec![0.0, 0.15, 0.0, 0.08]).unwrap();
    // The whole model's spring coefficient j is the cut one's `moved[j]`.
    let moved = [0, 2, 3, 1, 4, 5, 6, 7];
    let a = whole.modal_state(&whole_model.spring_coefficients(), &sited).unwrap();
    let b = cut.modal_state(&cut_model.spring_coefficients(), &per_field).unwrap();
    let bending = first_bending(&a, 8);
    assert_eq!(bending, first_bending(&b, 8));
    let mut worst: f64 = 0.0;
    let mut compare = |found: f64, expected: f64, scale: f64, what: &str| {
        let e = (found - expected).abs() / scale;
        worst = worst.max(e);
        assert!(e < 1e-9, "{what}: {found} vs {expected}");
    };
    for &i in &bending {
        compare(a.zeta[i], b.zeta[i], b.zeta[i], &format!("ζ_{i}"));
    }
    // The supports must matter on these modes (else the check is empty).
    assert!(bending.iter().any(|&i| a.support_zeta(i) > 0.01));
    let (sa, sb) = (
        whole.modal_sensitivities(&a, &bending),
        cut.modal_sensitivities(&b, &bending),
    );
    for (row, &i) in bending.iter().enumerate() {
        let scale = (0..8).map(|j| sb.damping_ratio[(row, j)].abs()).fold(0.0, f64::max);
        for (j, &m) in moved.iter().enumerate() {
            let what = format!("∂ζ_{i}/∂κ_{j}");
            compare(sa.damping_ratio[(row, j)], sb.damping_ratio[(row, m)], scale, &what);
        }
    }
    let freqs = [3.0, 7.7, 12.4, 19.0, 26.5, 41.0, 63.0];
    let (ea, eb) = (
        whole.evaluate(&a, accelerances(&freqs), true),
        cut.evaluate(&b, accelerances(&freqs), true),
    );
    let mut columns: Vec<(&[c64], &[c64], String)> = moved
        .iter()
        .enumerate()
        .map(|(j, &m)| {
            (
                ea.dh_dkappa[j].as_slice(),
                eb.dh_dkappa[m].as_slice(),
                format!("∂H/∂κ_{j}"),
            )
        })
        .collect();
    let nz = curve.coefficients().len();
    for z in 0..nz {
        columns.push((&ea.dh_dgamma[z], &eb.dh_dgamma[z], format!("∂H/∂γ_{z}")));
    }
    for (site, field) in [(0, 1), (1, 3)] {
        let what = format!("∂H/∂η of site {site}");
        columns.push((&ea.dh_dgamma[nz + site], &eb.dh_dgamma[nz + field], what));
    }
    let norm = |c: &[c64]| c.iter().map(|v| v.norm_sqr()).sum::<f64>().sqrt();
    for (found, expected, what) in columns {
        if norm(expected) == 0.0 {
            // A component the sensors do not see (the deck's in-plane
            // stiffness along it): both vanish.
            assert_eq!(norm(found), 0.0, "{what}");
            continue;
        }
        let e = column_error(found, expected);
        worst = worst.max(e);
        assert!(e < 1e-9, "{what}: relative error {e:e}");
    }
    let h = column_error(&ea.h, &eb.h);
    assert!(h < 1e-9, "H: relative error {h:e}");
    eprintln!("loss sites against the support cut in two: worst relative difference {worst:.1e}");
}

/// A loss factor on the deck's stiffness field on a truncated model (modes
/// below 60 Hz, the field's part from its sparse operators): each kept
/// mode's ζ_i equals the dense model's for the same mode (1e-8: the two
/// eigen-solvers' agreement), and `∂H/∂η` of the field's site is exact
/// against central differences of the truncated model's own evaluation
/// (1e-6).
#[test]
fn a_loss_factor_on_the_decks_stiffness_holds_on_a_truncated_model() {
    let knots = |n| KnotVector::uniform(1, n, 0.0, 1.0).unwrap();
    let field = StiffnessField::new(knots(3), knots(2), vec![1.0, 0.9, 1.1, 0.8, 1.05, 1.2]).unwrap();
    let (model, sensors) = deck_model(vec![field]);
    let kappa = model.spring_coefficients();
    let truncated = FrfModel::truncated(&model, &sensors, 60.0).unwrap();
    let dense = FrfModel::new(model.assemble().unwrap(), &sensors).unwrap();
    let sites = LossSites::new(vec![
        LossSite::springs((0..4).collect()),
        LossSite::fields((0..6).collect()),
    ])
    .unwrap();
    let curve = DampingCurve::new(2, vec![0.01, 0.03, 0.005, 0.02], 0.0, 120.0)
        .unwrap()
        .with_loss_factors(vec![0.15, 0.08])
        .unwrap()
        .with_loss_sites(sites)
        .unwrap();
    let (kept, all) = (
        truncated.modal_state(&kappa, &curve).unwrap(),
        dense.modal_state(&kappa, &curve).unwrap(),
    );
    // The bending modes below the cut-off (five), the same in both.
    let bending = first_bending(&kept, 6);
    assert!(bending.len() >= 4 && bending == first_bending(&all, bending.len()));
    for &i in &bending {
        let (found, expected) = (kept.zeta[i], all.zeta[i]);
        assert!(
            (found - expected).abs() <= 1e-8 * expected,
            "ζ_{i}: {found} vs {expected}"
        );
    }
    let freqs = [3.0, 7.7, 12.4, 19.0, 26.5, 41.0];
    let request = accelerances(&freqs);
    let eval = truncated.evaluate(&kept, request, true);
    let nz = curve.coefficients().len();
    let at = |d: f64| {
        let lossy = curve.with_loss_factors(vec![0.15, 0.08 + d]).unwrap();
        truncated
            .evaluate(&truncated.modal_state(&kappa, &lossy).unwrap(), request, false)
            .h
    };
    let e = column_error(&eval.dh_dgamma[nz + 1], &richardson(at, 1e-4));
    assert!(e < 1e-6, "∂H/∂η of the field's site: relative error {e:e}");
}
