//! The updating loop on the paper's 12-sensor case: one model evaluation
//! (modes + 12 FRFs × 796 lines + 15 sensitivities) and a whole updating;
//! and one earthquake's update of the whole Painter Street bridge.
//! Run: `cargo bench --bench updating`.

use splinewatch::studies::paper::{bundled_configs, run, EXPERIMENTS};
use splinewatch_core::response::frf::{FrfEvaluation, FrfRequest, ModalState, Quantity};
use std::path::Path;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

#[divan::bench(sample_count = 20)]
fn eigen_solve(bencher: divan::Bencher) {
    let (_, model) = bundled_configs(root()).unwrap();
    let setup = splinewatch::config::frf_setup(&model).unwrap();
    bencher.bench(|| setup.model.modal_state(&setup.kappa, &setup.damping).unwrap());
}

/// The paper's 12-sensor case: accelerances P1 → P1…P12 on 0.5–80 Hz every
/// 0.1 Hz (796 lines), with all sensitivities.
fn paper_case(setup: &splinewatch::config::FrfSetup, state: &ModalState) -> FrfEvaluation {
    let freqs: Vec<f64> = (0..796).map(|k| 0.5 + 0.1 * k as f64).collect();
    let pairs: Vec<(usize, usize)> = (0..12).map(|r| (r, 0)).collect();
    setup.model.evaluate(
        state,
        FrfRequest {
            frequencies_hz: &freqs,
            pairs: &pairs,
            quantity: Quantity::Accelerance,
        },
        true,
    )
}

#[divan::bench(sample_count = 20)]
fn frfs_and_sensitivities(bencher: divan::Bencher) {
    let (_, model) = bundled_configs(root()).unwrap();
    let setup = splinewatch::config::frf_setup(&model).unwrap();
    let state = setup.model.modal_state(&setup.kappa, &setup.damping).unwrap();
    bencher.bench(|| paper_case(&setup, &state));
}

/// The target: one model + sensitivity evaluation (modes, then 12
/// FRFs × 796 lines × 15 parameters) under 20 ms on one core.
#[divan::bench(sample_count = 20)]
fn one_evaluation(bencher: divan::Bencher) {
    let (_, model) = bundled_configs(root()).unwrap();
    let setup = splinewatch::config::frf_setup(&model).unwrap();
    bencher.bench(|| {
        let state = setup.model.modal_state(&setup.kappa, &setup.damping).unwrap();
        paper_case(&setup, &state)
    });
}

/// The same evaluation with a 4 × 2 stiffness field of the deck updated
/// too: 8 κ + 8 θ + 7 γ columns (the θ columns by the modal chain,
/// `FrfModel::field_frf_sensitivities`, over every mode).
#[divan::bench(sample_count = 10)]
fn one_evaluation_with_a_stiffness_field(bencher: divan::Bencher) {
    let (_, mut model) = bundled_configs(root()).unwrap();
    model.model.stiffness_fields.push(
        toml::from_str(
            "name = \"deck\"\nknots_xi = [0.0, 0.25, 0.5, 0.75, 1.0]\ndegree_xi = 0\n\
             knots_eta = [0.0, 0.5, 1.0]\ndegree_eta = 0\nbounds = [0.3, 1.5]",
        )
        .unwrap(),
    );
    let setup = splinewatch::config::frf_setup(&model).unwrap();
    let theta = setup.model.field_coefficients().to_vec();
    let freqs: Vec<f64> = (0..796).map(|k| 0.5 + 0.1 * k as f64).collect();
    let pairs: Vec<(usize, usize)> = (0..12).map(|r| (r, 0)).collect();
    bencher.bench(|| {
        let state = setup
            .model
            .modal_state_with_fields(&setup.kappa, &theta, &setup.damping)
            .unwrap();
        let mut e = paper_case(&setup, &state);
        let request = FrfRequest {
            frequencies_hz: &freqs,
            pairs: &pairs,
            quantity: Quantity::Accelerance,
        };
        e.dh_dtheta = setup.model.field_frf_sensitivities(&state, &setup.damping, request);
        e
    });
}

#[divan::bench(sample_count = 5, sample_size = 1)]
fn whole_updating_12_sensors(bencher: divan::Bencher) {
    let (truth, model) = bundled_configs(root()).unwrap();
    bencher.bench(|| run(&truth, &model, &EXPERIMENTS[0]).unwrap());
}

/// One earthquake's update of the whole bridge
/// (`config/painter-street-bridge.toml`: columns, cap, integral abutments;
/// the abutments' `y`, `ry` and loss factors, the footings' `z` and ζ(f))
/// on the committed 28 January 2015 Painter Street record, from the
/// config's values: the Ritz-basis search and the finish on the complete
/// model, as `events` runs it for each record (the model built once).
#[divan::bench(sample_count = 5, sample_size = 1)]
fn event_update_whole_bridge(bencher: divan::Bencher) {
    use splinewatch::config::{ground_signals, load_config};
    use splinewatch::service::records::{align_event, read_records};
    use splinewatch::studies::event_update::{update_on_event, EventSignals};
    use splinewatch::studies::ground_motion::GroundParts;
    let cfg = load_config(&root().join("config/painter-street-bridge.toml")).unwrap();
    let zip = root().join("tests/fixtures/painter-street/ferndale_28jan2015_72387946_ce89324p.zip");
    let records = read_records(&cfg, &[zip], None).unwrap();
    let parts = GroundParts::new(&cfg).unwrap();
    let mut plan = parts.plan.clone();
    let event = align_event(&cfg, &mut plan, records.record).unwrap();
    let channel = |i: usize| event.channels[i].as_deref().unwrap();
    let inputs = ground_signals(&plan, channel);
    let outputs: Vec<Vec<f64>> = event.deck.iter().map(|&i| channel(i).to_vec()).collect();
    let signals = EventSignals {
        plan: &plan,
        inputs: &inputs,
        deck: &event.deck,
        outputs: &outputs,
        fs: event.fs,
        modes: &[],
    };
    // The record alone (`[events] residues`), as every update after a
    // chain's first.
    let residues = cfg.events().residues;
    bencher.bench(|| update_on_event(&cfg, &parts, &signals, (&[], residues), &mut |_| {}).unwrap());
}

fn main() {
    divan::main();
}
