//! Offline replay of the bundled recording: outputs, determinism, state.

use crate::common::{bundled_blocks, fresh_dir, simulated_recording};
use splinewatch::config::load_config;
use splinewatch::config::Config;
use splinewatch::outputs::results::ResultsWriter;
use splinewatch::outputs::state::{load_state, save_state};
use splinewatch::service::replay::{replay, ReplayOptions};
use std::io::Cursor;
use std::path::Path;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn config() -> Config {
    load_config(&root().join("config/sinello.toml")).unwrap()
}

fn run(cfg: &Config, state: Option<&Path>) -> (Vec<u8>, splinewatch::service::replay::ReplaySummary) {
    let bytes = std::fs::read(root().join("recordings/sinello-demo.mcap")).unwrap();
    let initial = state.and_then(|p| load_state(p).unwrap());
    let mut writer = ResultsWriter::new(Cursor::new(Vec::new()), &cfg.topic_prefix()).unwrap();
    let options = ReplayOptions {
        initial,
        state_path: state,
        ..ReplayOptions::default()
    };
    let summary = replay(cfg, &[&bytes], &mut writer, options, &mut |_, _| {}).unwrap();
    (writer.finish().unwrap().into_inner(), summary)
}

#[test]
fn replay_of_the_demo_recording_tracks_the_bearing_damage_and_writes_every_topic() {
    let cfg = config();
    let (mcap_bytes, summary) = run(&cfg, None);
    assert_eq!(summary.windows.len(), 6);
    assert!(summary.windows.iter().all(|w| w.skipped.is_none()));
    assert_eq!(summary.updates.len(), 6);
    let k2 = |o: &splinewatch::pipeline::UpdateOutcome| {
        o.result
            .as_ref()
            .unwrap()
            .result
            .parameters
            .iter()
            .find(|p| p.name == "east.k2")
            .unwrap()
            .value
    };
    // Before the damage (0:00–0:40) east.k2 ≈ 0.4e9; after it (1:20–2:00) ≈ 0.24e9.
    let first = k2(&summary.updates[0]);
    let last = k2(&summary.updates[5]);
    assert!((first - 0.4e9).abs() < 0.1 * 0.4e9, "first {first}");
    assert!((last - 0.24e9).abs() < 0.1 * 0.24e9, "last {last}");
    // Every result topic is present in the MCAP file, with a JSON Schema.
    let summary_rec = mcap::Summary::read(&mcap_bytes).unwrap().unwrap();
    let stats = summary_rec.stats.unwrap();
    for (suffix, _) in splinewatch::outputs::results::TOPICS {
        let topic = format!("bridge/sinello-span2/{suffix}");
        let channel = summary_rec
            .channels
            .values()
            .find(|c| c.topic == topic)
            .unwrap_or_else(|| panic!("{topic}"));
        assert_eq!(channel.schema.as_ref().unwrap().encoding, "jsonschema");
        let count = stats.channel_message_counts.get(&channel.id).copied().unwrap_or(0);
        // No failure here, and no output-only identification on the FRF path.
        if !matches!(suffix, "updating/failures" | "oma/modes") {
            assert!(count > 0, "{topic} has no messages");
        }
    }
    for m in mcap::MessageStream::new(&mcap_bytes).unwrap() {
        let m = m.unwrap();
        if m.channel.topic.ends_with("updating/parameters") {
            let v: serde_json::Value = serde_json::from_slice(&m.data).unwrap();
            assert_eq!(v["parameters"].as_array().unwrap().len(), 15);
            assert!(v["relative_residual"].as_f64().unwrap() < 0.2);
        }
    }
}

#[test]
fn replay_is_deterministic() {
    let cfg = config();
    let (a, _) = run(&cfg, None);
    let (b, _) = run(&cfg, None);
    assert_eq!(a, b, "same input, byte-identical results");
}

/// The daemon's pipeline on a truncated model (`[model.solver] modes =
/// "truncated"`: the modes below 160 Hz, the rest as residual): the replay
/// is byte-identical between runs, every update reports its truncation
/// (cut-off, 73 modes kept, the fitted FRFs within 1e-3 of the every-mode
/// model's), and the identified springs stay within 2 % of the every-mode
/// replay's (the truncation error moves the fit a little; 1-sigma standard
/// errors are 2–10 % here).
#[test]
fn a_truncated_model_replays_deterministically_and_reports_its_truncation() {
    let mut cfg = config();
    cfg.model.solver.modes = splinewatch::config::ModesChoice::Truncated;
    let (a, truncated) = run(&cfg, None);
    let (b, _) = run(&cfg, None);
    assert_eq!(a, b, "same input, byte-identical results");
    let (_, every) = run(&config(), None);
    assert_eq!(truncated.updates.len(), every.updates.len());
    for (t, e) in truncated.updates.iter().zip(&every.updates) {
        let (t, e) = (t.result.as_ref().unwrap(), e.result.as_ref().unwrap());
        let report = t.truncation.as_ref().expect("a truncated update reports it");
        assert_eq!((report.cutoff_hz, report.modes_kept), (160.0, 73));
        assert!(report.frf_error.unwrap() <= 1e-3, "{report:?}");
        assert!(e.truncation.is_none());
        springs_within_two_percent(&t.result.parameters, &e.result.parameters);
    }
    let with_truncation = mcap::MessageStream::new(&a)
        .unwrap()
        .map(Result::unwrap)
        .filter(|m| m.channel.topic.ends_with("updating/parameters"))
        .filter(|m| serde_json::from_slice::<serde_json::Value>(&m.data).unwrap()["truncation"]["modes_kept"] == 73)
        .count();
    assert_eq!(
        with_truncation, 6,
        "every updating/parameters message carries the truncation"
    );
}

/// Every spring coefficient (`*.k*`) of a truncated update within 2 % of
/// the every-mode update's.
fn springs_within_two_percent(
    truncated: &[splinewatch_core::updating::ParameterEstimate],
    every: &[splinewatch_core::updating::ParameterEstimate],
) {
    for (p, q) in truncated.iter().zip(every) {
        assert_eq!(p.name, q.name);
        if p.name.contains(".k") {
            assert!(
                (p.value - q.value).abs() <= 0.02 * q.value,
                "{}: {} vs {}",
                p.name,
                p.value,
                q.value
            );
        }
    }
}

/// A global modulus scale updated with the springs on a truncated model
/// (its sensitivities from the kept modes and the residual on every dof):
/// every update reports its truncation (the fitted FRFs within 1e-3 of the
/// every-mode model's, θ included), `deck.s1` stays within a tenth of
/// its standard error (measured: 3.7e-7, σ 8.8e-5) and the springs within
/// 2 % of the every-mode replay's (the truncation error
/// moves the fit a little, as for the springs alone).
#[test]
fn a_stiffness_field_is_updated_on_a_truncated_model() {
    let text = format!(
        "{}\n[[model.stiffness_fields]]\nname = \"deck\"\nknots_xi = [0.0, 1.0]\ndegree_xi = 0\n\
         knots_eta = [0.0, 1.0]\ndegree_eta = 0\nbounds = [0.5, 1.5]\n",
        std::fs::read_to_string(root().join("config/sinello.toml")).unwrap()
    );
    let every_mode = Config::from_toml(&text).unwrap();
    let mut truncated = every_mode.clone();
    truncated.model.solver.modes = splinewatch::config::ModesChoice::Truncated;
    let (_, kept) = run(&truncated, None);
    let (_, every) = run(&every_mode, None);
    assert_eq!(kept.updates.len(), every.updates.len());
    let mut worst_scale = 0.0f64;
    for (t, e) in kept.updates.iter().zip(&every.updates) {
        let (t, e) = (t.result.as_ref().unwrap(), e.result.as_ref().unwrap());
        let report = t.truncation.as_ref().expect("a truncated update reports it");
        assert_eq!((report.cutoff_hz, report.modes_kept), (160.0, 73));
        assert!(report.frf_error.unwrap() <= 1e-3, "{report:?}");
        for (p, q) in t.result.parameters.iter().zip(&e.result.parameters) {
            assert_eq!(p.name, q.name);
            if p.name == "deck.s1" {
                worst_scale = worst_scale.max((p.value - q.value).abs());
                let std = q.std.expect("identifiable");
                assert!(
                    (p.value - q.value).abs() <= 0.1 * std,
                    "deck.s1: {} vs {}, σ {std}",
                    p.value,
                    q.value
                );
            }
        }
        springs_within_two_percent(&t.result.parameters, &e.result.parameters);
    }
    let last = &kept.updates.back().unwrap().result.as_ref().unwrap().result.parameters;
    let scale = last.iter().find(|p| p.name == "deck.s1").unwrap();
    eprintln!(
        "truncated vs every-mode replay with a modulus scale: deck.s1 = {} (std {:?}), within {worst_scale:.1e}",
        scale.value, scale.std
    );
}

#[test]
fn the_state_file_warm_starts_a_restart() {
    let cfg = config();
    let tmp = fresh_dir("state");
    let dir = tmp.join("state");
    let state = dir.join("state.json");
    let (_, first) = run(&cfg, Some(&state));
    let saved = load_state(&state).unwrap().expect("written");
    assert_eq!(saved, first.accepted.clone().unwrap());
    // A restart from the saved state starts where the last run ended: the
    // first update's iteration 0 is the saved parameters, not the config's.
    let (_, second) = run(&cfg, Some(&state));
    let start = &second.updates[0].result.as_ref().unwrap().result.iterations[0].parameters;
    let saved_values: Vec<f64> = saved.parameters.iter().map(|p| p.value).collect();
    assert_eq!(start, &saved_values);
    let cold = &first.updates[0].result.as_ref().unwrap().result.iterations[0].parameters;
    assert_ne!(cold, &saved_values);
    // Atomic write: no temporary file left behind, and a rewrite replaces it whole.
    save_state(&state, &saved).unwrap();
    let names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    assert_eq!(names, vec!["state.json".to_string()]);
}

#[test]
fn time_based_scheduling_updates_every_t_minutes() {
    let text = std::fs::read_to_string(root().join("config/sinello.toml"))
        .unwrap()
        .replace(
            "update_every_windows = 1",
            "update_every_windows = 1\nupdate_every_minutes = 0.9",
        );
    let cfg = Config::from_toml(&text).unwrap();
    let (_, summary) = run(&cfg, None);
    // 20 s windows end at 20, 40, … 120 s: updates at 60 s (≥ 54 s) and 120 s (≥ 60 + 54 s).
    let windows: Vec<u64> = summary.updates.iter().map(|u| u.window).collect();
    assert_eq!(windows, vec![2, 5]);
}

#[test]
fn replay_writes_a_rerun_recording_with_every_view() {
    let cfg = config();
    let dir = fresh_dir("rrd");
    let path = dir.join("replay.rrd");
    let targets = splinewatch::outputs::rerun::RerunTargets {
        save: Some(path.clone()),
        connect: None,
    };
    let summary = replay_into_rerun(&cfg, &targets);
    assert!(summary.updates.iter().any(|u| u.result.is_ok()));
    // Read back with Rerun's own decoder: complete (footer) and holding the
    // trends, the latest FRFs, ζ(f), the deck, the modes and the health.
    let rrd = splinewatch::outputs::rerun::inspect_rrd(&std::fs::read(&path).unwrap()).unwrap();
    assert!(rrd.footer, "the .rrd footer is missing");
    let mut expected: Vec<String> = summary.updates[0]
        .result
        .as_ref()
        .unwrap()
        .result
        .parameters
        .iter()
        .map(|p| {
            let group = if p.name.starts_with("damping.") {
                "damping"
            } else {
                "springs"
            };
            format!("/parameters/{group}/{}", p.name)
        })
        .collect();
    for sensor in ["P2", "P12"] {
        for what in ["magnitude", "phase"] {
            for which in ["measured", "model"] {
                expected.push(format!("/frf/{sensor}/{what}/{which}"));
            }
        }
    }
    expected.extend(
        [
            "/residual/relative",
            "/damping/zeta",
            "/damping/coefficients",
            "/deck/springs",
            "/deck/sensors",
            "/deck/model",
            "/deck/model/elements",
            "/modes/1",
            "/modes/4",
            "/health/blocks",
            "/health/queue_drops",
        ]
        .map(String::from),
    );
    for entity in &expected {
        assert!(
            rrd.entities.contains(entity),
            "{entity} missing from {:?}",
            rrd.entities
        );
    }
}

/// `--rerun-connect`: the replay streams to a Rerun gRPC server. The server
/// is Rerun's own (`re_grpc_server`, the code the `rerun` CLI runs), started
/// in-process on a loopback port, so the test needs no Python.
#[test]
fn replay_streams_to_a_rerun_server_over_grpc() {
    let cfg = config();
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .enable_all()
        .build()
        .unwrap();
    let (stop, shutdown) = re_grpc_server::shutdown::shutdown();
    let addr: std::net::SocketAddr = ([127, 0, 0, 1], port).into();
    let (received, _proxy) = {
        let _inside = runtime.enter();
        re_grpc_server::spawn_with_recv(addr, re_grpc_server::ServerOptions::default(), shutdown)
    };
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(30);
    while std::net::TcpStream::connect(("127.0.0.1", port)).is_err() {
        assert!(std::time::Instant::now() < deadline, "the Rerun server did not start");
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    let targets = splinewatch::outputs::rerun::RerunTargets {
        save: None,
        connect: Some(format!("rerun+http://127.0.0.1:{port}/proxy")),
    };
    // `finish` flushes the stream: everything was sent when this returns.
    replay_into_rerun(&cfg, &targets);
    let mut rrd = splinewatch::outputs::rerun::RrdSummary::default();
    let wanted = [
        "/parameters/springs/east.k2",
        "/frf/P12/magnitude/model",
        "/deck/springs",
    ];
    while !wanted.iter().all(|e| rrd.entities.contains(*e)) {
        let left = deadline.saturating_duration_since(std::time::Instant::now());
        let Ok(message) = received.recv_timeout(left) else {
            break;
        };
        if let re_log_channel::SmartMessagePayload::Msg(re_log_channel::DataSourceMessage::LogMsg(msg)) =
            message.payload
        {
            rrd.add(&msg).unwrap();
        }
    }
    stop.stop();
    for entity in wanted {
        assert!(
            rrd.entities.contains(entity),
            "{entity} not received: {:?}",
            rrd.entities
        );
    }
}

#[test]
fn rerun_files_rotate_by_measurement_time_and_each_stands_alone() {
    let mut cfg = config();
    cfg.output.rerun_rotate_hours = 0.01; // 36 s of data per file
    let dir = fresh_dir("rrd-rotate");
    let targets = splinewatch::outputs::rerun::RerunTargets {
        save: Some(dir.join("trend.rrd")),
        connect: None,
    };
    replay_into_rerun(&cfg, &targets);
    let files: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().path()).collect();
    // Updates every 20 s over two minutes, a new file every 36 s.
    assert!(files.len() >= 3, "{files:?}");
    for f in &files {
        let rrd = splinewatch::outputs::rerun::inspect_rrd(&std::fs::read(f).unwrap()).unwrap();
        assert!(rrd.footer, "{f:?} not finalised");
        for entity in ["/deck/sensors", "/deck/springs", "/parameters/springs/east.k2"] {
            assert!(rrd.entities.contains(entity), "{f:?} lacks {entity}");
        }
    }
}

/// Replays the bundled recording with a Rerun output to `targets`, closed
/// at the end.
fn replay_into_rerun(
    cfg: &Config,
    targets: &splinewatch::outputs::rerun::RerunTargets,
) -> splinewatch::service::replay::ReplaySummary {
    let mut viewer = splinewatch::outputs::rerun::RerunOutput::open(cfg, targets).unwrap();
    let bytes = std::fs::read(root().join("recordings/sinello-demo.mcap")).unwrap();
    let mut writer = ResultsWriter::new(Cursor::new(Vec::new()), &cfg.topic_prefix()).unwrap();
    let options = ReplayOptions {
        viewer: Some(&mut viewer),
        ..ReplayOptions::default()
    };
    let summary = replay(cfg, &[&bytes], &mut writer, options, &mut |_, _| {}).unwrap();
    viewer.finish().unwrap();
    summary
}

/// An update that fails (here: no convergence within one iteration) is
/// rejected: the last good parameters stay, in memory and in the state
/// file, and the failure is reported with its reason.
#[test]
fn failed_updates_keep_the_last_good_parameters_and_say_why() {
    let dir = fresh_dir("failures");
    let state = dir.join("state.json");
    run(&config(), Some(&state));
    let good = load_state(&state).unwrap().expect("six good updates saved a state");
    let good_text = std::fs::read(&state).unwrap();

    // A residue band above the FRFs' lines: every update fails outright.
    let mut cfg = config();
    cfg.updating.band = Some([200.0, 300.0]);
    let (bytes, summary) = run(&cfg, Some(&state));
    assert_eq!(summary.updates.len(), 6);
    for o in &summary.updates {
        let e = o.result.as_ref().expect_err("no line to fit");
        assert!(e.contains("no frequency line"), "{e}");
    }
    assert_eq!(
        summary.accepted.as_ref(),
        Some(&good),
        "the last good parameters are kept"
    );
    assert_eq!(std::fs::read(&state).unwrap(), good_text, "the state file is untouched");
    let mut failures = 0;
    let mut parameters = 0;
    let mut health = serde_json::Value::Null;
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        let v: serde_json::Value = serde_json::from_slice(&m.data).unwrap();
        match m.channel.topic.rsplit_once("sinello-span2/").unwrap().1 {
            "updating/failures" => {
                failures += 1;
                assert!(v["error"].as_str().unwrap().contains("no frequency line"), "{v}");
            }
            "updating/parameters" => parameters += 1,
            "health" => health = v,
            _ => {}
        }
    }
    assert_eq!((failures, parameters), (6, 0));
    assert_eq!(
        (health["update_runs"].as_u64(), health["update_failures"].as_u64()),
        (Some(6), Some(6))
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Issue 31: an update stopped by `max_iterations` that lowered the residual
/// is published (`"converged": false`, its stop reason), not lost, and the
/// next window starts from it (the state file holds it).
#[test]
fn issue_31_an_unconverged_update_that_lowered_the_residual_is_published() {
    let dir = fresh_dir("unconverged");
    let state = dir.join("state.json");
    let mut cfg = config();
    cfg.updating.max_iterations = 1;
    cfg.updating.offset_tolerance = 1e-300;
    cfg.updating.cost_tolerance = 1e-300;
    cfg.updating.step_tolerance = 1e-300;
    let (bytes, summary) = run(&cfg, Some(&state));
    assert_eq!(summary.updates.len(), 6);
    for o in &summary.updates {
        let r = o.result.as_ref().expect("an improving iteration is an update");
        assert!(!r.result.converged);
        let (first, last) = (&r.result.iterations[0], r.result.iterations.last().unwrap());
        assert!(last.cost < first.cost, "{} → {}", first.cost, last.cost);
    }
    let mut published = Vec::new();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        let v: serde_json::Value = serde_json::from_slice(&m.data).unwrap();
        match m.channel.topic.rsplit_once("sinello-span2/").unwrap().1 {
            "updating/failures" => panic!("no update may fail here: {v}"),
            "updating/parameters" => published.push(v),
            _ => {}
        }
    }
    assert_eq!(published.len(), 6);
    for v in &published {
        assert_eq!(v["converged"], false);
        assert_eq!(v["stop_reason"], "max_iterations");
    }
    // The state holds the last one's parameters: the next window's start.
    let saved = load_state(&state).unwrap().expect("a state after accepted updates");
    let last = &published[5]["parameters"];
    for (p, s) in last.as_array().unwrap().iter().zip(&saved.parameters) {
        assert_eq!(p["name"], s.name.as_str());
        assert_eq!(p["value"].as_f64().unwrap(), s.value);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A long replay keeps only the latest windows and outcomes in its summary
/// (months of data would otherwise fill memory); the counts cover them all.
#[test]
fn the_summary_keeps_only_the_latest_outcomes() {
    let cfg = config();
    let bytes = std::fs::read(root().join("recordings/sinello-demo.mcap")).unwrap();
    let mut writer = ResultsWriter::new(Cursor::new(Vec::new()), &cfg.topic_prefix()).unwrap();
    let options = ReplayOptions {
        keep_latest: 2,
        ..ReplayOptions::default()
    };
    let summary = replay(&cfg, &[&bytes], &mut writer, options, &mut |_, _| {}).unwrap();
    assert_eq!(
        (summary.window_count, summary.windows_accepted, summary.update_count),
        (6, 6, 6)
    );
    assert_eq!((summary.windows.len(), summary.updates.len()), (2, 2));
    let (_, all) = run(&cfg, None);
    assert_eq!(summary.updates[1].window, all.updates[5].window);
    assert_eq!(summary.accepted, all.accepted);
}

/// Overlapping windows (`frf.window_hop_seconds` < `window_seconds`): 20 s
/// windows every 10 s over the two minutes give 11 windows; every other one
/// is exactly a window of the back-to-back replay (each window has its own
/// estimator fed the same samples), the ones in between are new.
#[test]
fn overlapping_windows_every_hop() {
    let plain = config();
    let mut overlapping = config();
    overlapping.frf.window_hop_seconds = Some(10.0);
    let bytes = std::fs::read(root().join("recordings/sinello-demo.mcap")).unwrap();
    let windows = |cfg: &Config| {
        let mut w = ResultsWriter::new(Cursor::new(Vec::new()), &cfg.topic_prefix()).unwrap();
        let options = ReplayOptions {
            keep_latest: usize::MAX,
            ..ReplayOptions::default()
        };
        replay(cfg, &[&bytes], &mut w, options, &mut |_, _| {}).unwrap()
    };
    let (a, b) = (windows(&plain), windows(&overlapping));
    assert_eq!((a.window_count, b.window_count), (6, 11));
    assert_eq!(b.update_count, 11);
    let t0 = a.windows[0].start_ns;
    for (k, w) in b.windows.iter().enumerate() {
        assert_eq!(w.index, k as u64);
        assert_eq!(w.start_ns - t0, k as i128 * 10_000_000_000);
        assert_eq!(w.end_ns - w.start_ns, 20_000_000_000);
        assert!(w.skipped.is_none(), "window {k}: {:?}", w.skipped);
        if k % 2 == 0 {
            let same = &a.windows[k / 2];
            assert_eq!((same.start_ns, same.end_ns), (w.start_ns, w.end_ns));
            assert_eq!(same.frf, w.frf, "window {k}");
        } else {
            assert_ne!(a.windows[k / 2].frf, w.frf);
        }
    }
}

/// Live, an update that arrives while another runs waits; its job was made
/// before that update's result existed. Rebased when it starts, it warm-starts
/// from that result and gives the replay's parameters bit for bit.
#[test]
fn a_job_that_waited_starts_from_the_latest_result() {
    use splinewatch::pipeline::Pipeline;
    let cfg = config();
    // Every job made before any update ran, as when updates queue up live.
    let mut pipeline = Pipeline::new(&cfg, cfg.schedule.clone(), None).unwrap();
    let mut jobs = Vec::new();
    for recorded in bundled_blocks() {
        jobs.extend(pipeline.ingest(recorded.block).1);
    }
    jobs.extend(pipeline.finish().1);
    assert_eq!(jobs.len(), 6);
    let (_, inline) = run(&cfg, None);
    let values = |o: &splinewatch::pipeline::UpdateOutcome| -> Vec<f64> {
        let report = o.result.as_ref().expect("update succeeded");
        report.result.parameters.iter().map(|p| p.value).collect()
    };
    let mut jobs = jobs.into_iter();
    let mut first = jobs.next().unwrap().run();
    pipeline.apply(&mut first);
    assert_eq!(values(&first), values(&inline.updates[0]));
    let mut second = jobs.next().unwrap();
    pipeline.rebase(&mut second);
    let second = second.run();
    assert_eq!(values(&second), values(&inline.updates[1]));
    // Not rebased, the third job starts from the config's values instead of
    // the second result: a different warm start, different last digits.
    let stale = jobs.next().unwrap().run();
    let (stale, fresh) = (values(&stale), values(&inline.updates[2]));
    assert_ne!(stale, fresh);
    // Both end within a tenth of a standard deviation of the same optimum.
    let report = inline.updates[2].result.as_ref().unwrap();
    for ((a, b), p) in stale.iter().zip(&fresh).zip(&report.result.parameters) {
        let std = p.std.expect("identifiable");
        assert!((a - b).abs() < 0.1 * std, "{}: {a} vs {b}, σ {std}", p.name);
    }
}

/// A config with a global modulus scale (one stiffness-field coefficient,
/// updated with the springs) replays the bundled recording: `deck.s1` is on
/// the parameters topic with the most correlated pairs, near 1 (the data
/// were simulated with the nominal material), and the .rrd has the
/// multiplier's trend and its deck view.
#[test]
fn a_global_modulus_scale_is_updated_reported_and_drawn() {
    let text = format!(
        "{}\n[[model.stiffness_fields]]\nname = \"deck\"\nknots_xi = [0.0, 1.0]\ndegree_xi = 0\n\
         knots_eta = [0.0, 1.0]\ndegree_eta = 0\nbounds = [0.5, 1.5]\n",
        std::fs::read_to_string(root().join("config/sinello.toml")).unwrap()
    );
    let cfg = Config::from_toml(&text).unwrap();
    let dir = fresh_dir("modulus-scale");
    let path = dir.join("replay.rrd");
    let targets = splinewatch::outputs::rerun::RerunTargets {
        save: Some(path.clone()),
        connect: None,
    };
    let summary = replay_into_rerun(&cfg, &targets);
    let last = summary.updates.back().unwrap().result.as_ref().unwrap();
    let scale = last.result.parameters.iter().find(|p| p.name == "deck.s1").unwrap();
    assert!((scale.value - 1.0).abs() < 0.02, "deck.s1 = {}", scale.value);
    assert!(!last.result.correlations.is_empty());
    assert_eq!(last.theta, vec![vec![scale.value]]);
    let rrd = splinewatch::outputs::rerun::inspect_rrd(&std::fs::read(&path).unwrap()).unwrap();
    for entity in [
        "/parameters/fields/deck.s1",
        "/deck/stiffness",
        "/deck/stiffness_change",
    ] {
        assert!(rrd.entities.contains(entity), "{entity} missing: {:?}", rrd.entities);
    }
}

/// The results file of a replay with a state file, pipelined or in line.
fn replay_bytes(cfg: &Config, recording: &[u8], pipelined: bool, state: &Path) -> Vec<u8> {
    let mut writer = ResultsWriter::new(Cursor::new(Vec::new()), &cfg.topic_prefix()).unwrap();
    let options = ReplayOptions {
        state_path: Some(state),
        pipelined,
        ..ReplayOptions::default()
    };
    replay(cfg, &[recording], &mut writer, options, &mut |_, _| {}).unwrap();
    writer.finish().unwrap().into_inner()
}

/// The three-stage replay (reading, ingest, updates on their own threads)
/// writes exactly the bytes of the in-line one: on the bundled recording
/// (six updates, an update per 20-second window) and on a simulated hour
/// in 10-minute windows, and the same hour in 2-minute windows with
/// `[monitoring]` (trained on 10 updates, 20 scored: status messages and
/// the monitor file too); with identification, where the ingest identifies
/// a window while the update stage runs the previous job and pairs it with
/// the model that stage sends back: 40 minutes of ambient data on the
/// output-only config (four windows, modal-residue updates) and the hour
/// with a force sensor and `[oma]`, both paths updated jointly; the state
/// files match.
#[test]
fn the_pipelined_replay_writes_the_bytes_of_the_in_line_one() {
    let dir = fresh_dir("pipelined-replay");
    let bundled = std::fs::read(root().join("recordings/sinello-demo.mcap")).unwrap();
    let mut hour = config();
    hour.frf.window_seconds = 600.0;
    let text = std::fs::read_to_string(root().join("config/sinello.toml")).unwrap()
        + "\n[monitoring]\ntraining_windows = 10\n";
    let mut monitored = Config::from_toml(&text).unwrap();
    monitored.frf.window_seconds = 120.0;
    let simulated = simulated_recording(
        &hour,
        &splinewatch::studies::simulation::SimulationOptions::random_excitation(&hour, 3600.0, 7),
        splinewatch::io::wire::Encoding::Cbor,
    );
    let mut ambient = load_config(&root().join("config/sinello-ambient.toml")).unwrap();
    ambient.frf.window_seconds = 600.0;
    let ambient_recording = simulated_recording(
        &ambient,
        &splinewatch::studies::simulation::SimulationOptions::ambient_excitation(&ambient, 2400.0, 5),
        splinewatch::io::wire::Encoding::Cbor,
    );
    let sinello = std::fs::read_to_string(root().join("config/sinello.toml")).unwrap();
    let method = "method = \"levenberg_marquardt\"\n";
    let both = Config::from_toml(
        &(sinello.replace(method, &format!("residues = \"both\"\n{method}")) + "\n[oma]\nwindow_seconds = 600.0\n"),
    )
    .unwrap();
    for (name, cfg, recording) in [
        ("bundled", config(), &bundled),
        ("hour", hour, &simulated),
        ("monitored", monitored, &simulated),
        ("output-only", ambient, &ambient_recording),
        ("both paths", both, &simulated),
    ] {
        // Apart: the monitor file goes beside the state file.
        let (a, b) = (
            dir.join(format!("{name}-a/state.json")),
            dir.join(format!("{name}-b/state.json")),
        );
        std::fs::create_dir_all(a.parent().unwrap()).unwrap();
        std::fs::create_dir_all(b.parent().unwrap()).unwrap();
        let in_line = replay_bytes(&cfg, recording, false, &a);
        let pipelined = replay_bytes(&cfg, recording, true, &b);
        assert!(in_line.len() > 10_000, "{name}: {} bytes", in_line.len());
        assert!(in_line == pipelined, "{name}: the pipelined results differ");
        assert_eq!(
            std::fs::read(&a).unwrap(),
            std::fs::read(&b).unwrap(),
            "{name}: state files"
        );
        let monitor = |p: &Path| cfg.monitor_file(p).and_then(|m| std::fs::read(m).ok());
        assert_eq!(monitor(&a), monitor(&b), "{name}: monitor files");
        assert_eq!(monitor(&a).is_some(), name == "monitored");
    }
}

/// A bridge's columns are drawn with its deck: the saved file holds each
/// member as a line through its nodes (`deck/model/beams`) and its base
/// (`deck/model/beam_bases`) beside the patches.
#[test]
fn a_bridge_s_columns_are_drawn_with_its_deck() {
    let dir = fresh_dir("rrd-beams");
    let path = dir.join("deck-on-bent.rrd");
    let config = load_config(Path::new("config/examples/deck-on-bent.toml")).unwrap();
    let targets = splinewatch::outputs::rerun::RerunTargets {
        save: Some(path.clone()),
        connect: None,
    };
    splinewatch::outputs::rerun::RerunOutput::open(&config, &targets)
        .unwrap()
        .finish()
        .unwrap();
    let rrd = splinewatch::outputs::rerun::inspect_rrd(&std::fs::read(&path).unwrap()).unwrap();
    for entity in ["/deck/model", "/deck/model/beams", "/deck/model/beam_bases"] {
        assert!(
            rrd.entities.contains(entity),
            "{entity} missing from {:?}",
            rrd.entities
        );
    }
}
