//! The live path over real zenoh on loopback (multi-thread runtime): a
//! simulated logger publishes, the daemon windows, updates and writes results.

use splinewatch::config::load_config;
use splinewatch::outputs::results::ResultsWriter;
use splinewatch::outputs::state::load_state;
use splinewatch::service::demo::{demo_plan, run_live, run_recording_live};
use splinewatch::service::replay::replay;
use splinewatch::studies;
use std::io::Cursor;
use std::path::{Path, PathBuf};

use crate::common::{
    bundled_blocks, free_endpoint, fresh_dir, publish_bundled, publish_bundled_to, spawn_daemon, terminate,
    wait_for_file, KillOnDrop, TestDir,
};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn temp(name: &str) -> TestDir {
    fresh_dir(&format!("live-{name}"))
}

#[test]
fn live_zenoh_run_tracks_a_bearing_damage() {
    let out = temp("damage");
    let duration = 300.0;
    let cfg = load_config(&root().join("config/sinello.toml")).unwrap();
    let plan = demo_plan(&cfg, Some(duration)).unwrap();
    let summary = run_live(cfg, &plan, &out, 40.0, 11).unwrap();
    let value = |u: &splinewatch::pipeline::UpdateOutcome, name: &str| {
        estimates(u).iter().find(|p| p.name == name).unwrap().value
    };
    let ok: Vec<_> = summary.updates.iter().filter(|u| u.result.is_ok()).collect();
    assert!(ok.len() >= 10, "{} updates", ok.len());
    // The damage ramps between 40 % and 60 % of the run.
    let (first, last) = (ok[0], ok[ok.len() - 1]);
    assert!(
        (value(first, "east.k2") - 0.4e9).abs() < 0.1 * 0.4e9,
        "before: {}",
        value(first, "east.k2")
    );
    assert!(
        (value(last, "east.k2") - 0.24e9).abs() < 0.1 * 0.24e9,
        "after: {}",
        value(last, "east.k2")
    );
    let cfg = load_config(&root().join("config/sinello.toml")).unwrap();
    let truth: Vec<(String, f64)> = cfg
        .model
        .springs
        .iter()
        .flat_map(|s| {
            s.stiffness
                .iter()
                .enumerate()
                .map(move |(j, &k)| (format!("{}.k{}", s.name, j + 1), k))
        })
        .collect();
    for (name, t) in truth.iter().filter(|(n, _)| n != "east.k2") {
        assert!(
            (value(last, name) - t).abs() < 0.1 * t,
            "{name}: {} vs {t}",
            value(last, name)
        );
    }
    // The demo's Rerun recording is finalised and has the trends.
    let rrd = splinewatch::outputs::rerun::inspect_rrd(&std::fs::read(out.join("results.rrd")).unwrap()).unwrap();
    assert!(rrd.footer && rrd.entities.contains("/residual/relative"));
    // Every output channel is in the results file, which is finalised.
    let bytes = std::fs::read(out.join("results.mcap")).unwrap();
    let s = mcap::Summary::read(&bytes)
        .unwrap()
        .expect("summary written on shutdown");
    let counts = s.stats.unwrap().channel_message_counts;
    for (suffix, _) in splinewatch::outputs::results::TOPICS {
        // No failure here, and no output-only identification on the FRF path.
        if matches!(suffix, "updating/failures" | "oma/modes") {
            continue;
        }
        let topic = format!("{}/{suffix}", cfg.topic_prefix());
        let ch = s.channels.values().find(|c| c.topic == topic).unwrap();
        assert!(counts.get(&ch.id).copied().unwrap_or(0) > 0, "{suffix}");
    }
    // The state file holds the last accepted parameters.
    let state = load_state(&out.join("state.json")).unwrap().unwrap();
    assert_eq!(
        state.parameters.iter().find(|p| p.name == "east.k2").unwrap().value,
        value(last, "east.k2")
    );
}

#[test]
fn live_and_replay_agree_on_the_bundled_recording() {
    let out = temp("agree");
    let recording = root().join("recordings/sinello-demo.mcap");
    let live = run_recording_live(&root().join("config/sinello.toml"), &recording, &out, 10.0).unwrap();
    let cfg = load_config(&root().join("config/sinello.toml")).unwrap();
    let bytes = std::fs::read(&recording).unwrap();
    let mut writer = ResultsWriter::new(Cursor::new(Vec::new()), &cfg.topic_prefix()).unwrap();
    let offline = replay(&cfg, &[&bytes], &mut writer, Default::default(), &mut |_, _| {}).unwrap();
    assert_eq!(live.updates.len(), offline.updates.len());
    for (a, b) in live.updates.iter().zip(&offline.updates) {
        assert_eq!(parameter_values(a), parameter_values(b), "window {}", a.window);
    }
}

/// The parameter estimates of an accepted update.
fn estimates(u: &splinewatch::pipeline::UpdateOutcome) -> &[splinewatch_core::updating::ParameterEstimate] {
    &u.result.as_ref().unwrap().result.parameters
}

/// The identified values of an accepted update, in parameter order.
fn parameter_values(u: &splinewatch::pipeline::UpdateOutcome) -> Vec<f64> {
    estimates(u).iter().map(|p| p.value).collect()
}

#[cfg(unix)]
#[test]
fn sigterm_finalises_the_results_and_a_restart_warm_starts() {
    use std::process::{Command, Stdio};
    let dir = temp("sigterm");
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let text = std::fs::read_to_string(root().join("config/sinello.toml")).unwrap()
        + &format!("\n[zenoh]\nmode = \"peer\"\nlisten = [\"tcp/127.0.0.1:{port}\"]\nmulticast_scouting = false\n");
    let config = dir.join("config.toml");
    std::fs::write(&config, text).unwrap();
    let state = dir.join("state.json");
    let start = |results: &str| {
        Command::new(env!("CARGO_BIN_EXE_splinewatch"))
            .args([
                "run",
                "--config",
                config.to_str().unwrap(),
                "--state",
                state.to_str().unwrap(),
                "--out",
            ])
            .arg(dir.join(results))
            .arg("--rerun-save")
            .arg(dir.join(results).with_extension("rrd"))
            .env("RUST_LOG", "info,zenoh=warn")
            .stderr(Stdio::piped())
            .spawn()
            .unwrap()
    };
    let daemon = start("first.mcap");
    std::thread::sleep(std::time::Duration::from_millis(1500));
    // Publish the bundled recording until the first update has been saved.
    publish_bundled_to(&config);
    assert!(wait_for_file(&state), "no update was saved");
    let (status, log) = terminate(daemon);
    assert!(status.success(), "exit status {status:?}\n{log}");
    let results = std::fs::read(dir.join("first.mcap")).unwrap();
    let summary = mcap::Summary::read(&results)
        .unwrap()
        .expect("MCAP finalised with a summary");
    assert!(summary.stats.unwrap().message_count > 0);
    let saved = load_state(&state).unwrap().expect("state file");
    assert_eq!(saved.parameters.len(), 15);
    // Outputs carry explicit permissions (rw-r-----), whatever the umask.
    {
        use std::os::unix::fs::PermissionsExt;
        for f in [dir.join("first.mcap"), state.clone(), dir.join("first.rrd")] {
            let mode = std::fs::metadata(&f).unwrap().permissions().mode() & 0o777;
            assert_eq!(
                mode,
                splinewatch::io::files::OUTPUT_FILE_MODE,
                "{}: {mode:o}",
                f.display()
            );
        }
    }
    // The .rrd is complete (footer) and holds the update.
    let rrd = splinewatch::outputs::rerun::inspect_rrd(&std::fs::read(dir.join("first.rrd")).unwrap()).unwrap();
    assert!(rrd.footer, "the .rrd was not finalised");
    assert!(
        rrd.entities.contains("/parameters/springs/east.k2"),
        "{:?}",
        rrd.entities
    );
    // Restart with the same --out and --rerun-save: the daemon warm-starts
    // from the state, stops cleanly again, and leaves the first run's files
    // as they were (its own go to the next free numbers).
    let first_rrd = std::fs::read(dir.join("first.rrd")).unwrap();
    let again = start("first.mcap");
    std::thread::sleep(std::time::Duration::from_millis(1500));
    let (status, log) = terminate(again);
    assert!(status.success(), "{log}");
    assert!(log.contains("warm start from the state file"), "{log}");
    assert_eq!(std::fs::read(dir.join("first.mcap")).unwrap(), results);
    assert_eq!(std::fs::read(dir.join("first.rrd")).unwrap(), first_rrd);
    assert!(mcap::Summary::read(&std::fs::read(dir.join("first-1.mcap")).unwrap())
        .unwrap()
        .is_some());
    assert!(
        splinewatch::outputs::rerun::inspect_rrd(&std::fs::read(dir.join("first-1.rrd")).unwrap())
            .unwrap()
            .footer
    );
}

#[test]
fn precomputed_frfs_on_the_frf_topic_drive_an_update() {
    // A logger that computes FRFs itself publishes one FRF per message on
    // <prefix>/frf/<input>/<output>; a complete set triggers an update.
    let out = temp("frf-topic");
    let cfg = load_config(&root().join("config/sinello.toml")).unwrap();
    let truth = load_config(&root().join("config/sinello-truth.toml")).unwrap();
    let outputs: Vec<String> = (1..=12).map(|i| format!("P{i}")).collect();
    let file = studies::synth(
        &truth,
        &studies::SynthOptions {
            inputs: vec!["P1".into()],
            outputs,
            quantity: splinewatch_core::response::frf::Quantity::Accelerance,
            f_min: 0.5,
            f_max: 80.0,
            step: 0.25,
            noise: 0.0,
            seed: 0,
        },
    )
    .unwrap();
    let summary = splinewatch::service::demo::run_with_source(cfg, &out, 0.0, usize::MAX, move |_, publisher| {
        publisher.publish_json("frf/P1/P1", b"{not json".to_vec())?;
        for e in &file.frfs {
            let one = splinewatch::io::frf_json::FrfFile {
                quantity: file.quantity,
                frequency_hz: file.frequency_hz.clone(),
                frfs: vec![e.clone()],
                start_timestamp: None,
                end_timestamp: None,
            };
            publisher.publish_json(&format!("frf/{}/{}", e.input, e.output), serde_json::to_vec(&one)?)?;
        }
        Ok(file.frfs.len() as u64 + 1)
    })
    .unwrap();
    assert_eq!(summary.updates.len(), 1);
    let result = &summary.updates[0].result.as_ref().unwrap().result;
    assert!(result.converged);
    let k2 = result.parameters.iter().find(|p| p.name == "east.k2").unwrap().value;
    assert!((k2 - 0.4e9).abs() < 0.01 * 0.4e9, "{k2}");
}

#[test]
fn raw_input_recording_rotates_and_replays_to_the_live_results() {
    let out = temp("raw");
    let mut cfg = load_config(&root().join("config/sinello.toml")).unwrap();
    cfg.output.raw = splinewatch::config::RawRecordingConfig {
        enabled: true,
        dir: out.join("raw"),
        rotate_minutes: 0.5,
        rotate_megabytes: 512.0,
    };
    let bytes = std::fs::read(root().join("recordings/sinello-demo.mcap")).unwrap();
    let (blocks, _) = splinewatch::io::recording::read_recording(&bytes, &Default::default()).unwrap();
    let sent = blocks.len() as u64;
    let live = splinewatch::service::demo::run_with_source(cfg.clone(), &out, 10.0, usize::MAX, move |_, publisher| {
        for b in &blocks {
            publisher.publish(&b.block)?;
        }
        Ok(sent)
    })
    .unwrap();
    // Every block arrived, and nothing else (the daemon's own results must
    // not come back through its subscriptions).
    assert_eq!(live.messages, 1560);
    // Two minutes rotated every 30 s of measurement time: four complete
    // files, none left unfinished.
    let mut files: Vec<PathBuf> = std::fs::read_dir(out.join("raw"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    assert!(files.iter().all(|f| f.extension().unwrap() == "mcap"), "{files:?}");
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        for f in &files {
            let mode = std::fs::metadata(f).unwrap().permissions().mode() & 0o777;
            assert_eq!(
                mode,
                splinewatch::io::files::OUTPUT_FILE_MODE,
                "{}: {mode:o}",
                f.display()
            );
        }
    }
    assert_eq!(files.len(), 4, "{files:?}");
    // Replaying the rotated files reproduces the live parameters exactly.
    let recorded: Vec<Vec<u8>> = files.iter().map(|f| std::fs::read(f).unwrap()).collect();
    let recorded: Vec<&[u8]> = recorded.iter().map(Vec::as_slice).collect();
    let mut writer = ResultsWriter::new(Cursor::new(Vec::new()), &cfg.topic_prefix()).unwrap();
    let offline = replay(&cfg, &recorded, &mut writer, Default::default(), &mut |_, _| {}).unwrap();
    assert_eq!(live.updates.len(), offline.updates.len());
    assert!(!live.updates.is_empty());
    for (a, b) in live.updates.iter().zip(&offline.updates) {
        assert_eq!(parameter_values(a), parameter_values(b), "window {}", a.window);
    }
}

/// Client mode through a real zenoh router (in-process, router mode, on
/// loopback): the daemon and the logger both connect to the router only.
#[cfg(unix)]
#[test]
fn client_mode_through_a_zenoh_router() {
    use zenoh::Wait;
    let dir = temp("router");
    let endpoint = free_endpoint();
    let router = open_router(&endpoint);
    let (daemon, config, state) = spawn_client_daemon(&dir, &endpoint);
    std::thread::sleep(std::time::Duration::from_millis(1500));
    let cfg = load_config(&config).unwrap();
    publish_bundled(&cfg.zenoh, cfg.topic_prefix());
    wait_for_file(&state);
    let (status, log) = terminate(daemon.take());
    assert!(status.success(), "{log}");
    assert!(state.exists(), "no update arrived through the router\n{log}");
    let saved = load_state(&state).unwrap().unwrap();
    assert_eq!(saved.parameters.len(), 15);
    router.close().wait().unwrap();
}

/// The router between logger and daemon goes away and comes back on the same
/// endpoint: the daemon (a zenoh client) reconnects by itself and updates
/// from the data sent after the return, without a restart.
#[cfg(unix)]
#[test]
fn the_daemon_resumes_after_its_router_returns() {
    use zenoh::Wait;
    let dir = temp("router-loss");
    let endpoint = free_endpoint();
    let router = open_router(&endpoint);
    let (daemon, config, state) = spawn_client_daemon(&dir, &endpoint);
    std::thread::sleep(std::time::Duration::from_millis(1500));
    let cfg = load_config(&config).unwrap();
    let blocks = bundled_blocks();
    let (first, second) = blocks.split_at(blocks.len() / 2);
    let send = |part: &[splinewatch::io::recording::RecordedBlock]| {
        let mut publisher = splinewatch::outputs::publisher::Publisher::open(
            &cfg.zenoh,
            cfg.topic_prefix(),
            splinewatch::io::wire::Encoding::Cbor,
            20.0,
        )
        .unwrap();
        std::thread::sleep(std::time::Duration::from_millis(500));
        for b in part {
            publisher.publish(&b.block).unwrap();
        }
        publisher.close().unwrap();
    };
    let wait_for_window = |at_least: u64| {
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs(60);
        loop {
            if let Ok(Some(s)) = load_state(&state) {
                if s.window >= at_least {
                    return s.window;
                }
            }
            assert!(std::time::Instant::now() < deadline, "no update for window {at_least}");
            std::thread::sleep(std::time::Duration::from_millis(100));
        }
    };
    send(first);
    let before = wait_for_window(0);
    // The router goes away, and comes back on the same endpoint.
    router.close().wait().unwrap();
    drop(router);
    std::thread::sleep(std::time::Duration::from_secs(2));
    let router = open_router(&endpoint);
    std::thread::sleep(std::time::Duration::from_secs(3));
    send(second);
    // The second minute holds windows 3–5: an update for one of them proves
    // the data after the return arrived.
    let after = wait_for_window(3);
    let (status, log) = terminate(daemon.take());
    assert!(status.success(), "{log}");
    eprintln!("updated window {before} before the router loss and window {after} after its return");
    router.close().wait().unwrap();
}

/// An in-process zenoh router listening on `endpoint`.
fn open_router(endpoint: &str) -> zenoh::Session {
    use zenoh::Wait;
    let mut c = zenoh::Config::default();
    c.insert_json5("mode", "\"router\"").unwrap();
    c.insert_json5("listen/endpoints", &format!("[\"{endpoint}\"]"))
        .unwrap();
    c.insert_json5("scouting/multicast/enabled", "false").unwrap();
    zenoh::open(c).wait().unwrap()
}

/// `splinewatch run` as a zenoh client of `endpoint`, with its config,
/// state and results in `dir`; returns the process, config and state paths.
#[cfg(unix)]
fn spawn_client_daemon(dir: &Path, endpoint: &str) -> (KillOnDrop, PathBuf, PathBuf) {
    let text = std::fs::read_to_string(root().join("config/sinello.toml")).unwrap()
        + &format!("\n[zenoh]\nmode = \"client\"\nconnect = [\"{endpoint}\"]\nmulticast_scouting = false\n");
    let config = dir.join("config.toml");
    std::fs::write(&config, text).unwrap();
    let state = dir.join("state.json");
    let results = dir.join("results.mcap");
    let daemon = spawn_daemon(
        &config,
        &state,
        &results,
        "info,zenoh=warn",
        std::process::Stdio::piped(),
    );
    (daemon, config, state)
}

/// Output-only over zenoh on loopback: 10 minutes of ambient data (no force
/// channel) published live to the daemon of the bundled output-only config
/// (5-minute windows): each window's identified modes arrive on
/// `<prefix>/oma/modes`, every window is updated, and the live parameters
/// equal the offline replay's of the same blocks.
#[test]
fn live_output_only_run_publishes_modes_and_agrees_with_replay() {
    use std::sync::{Arc, Mutex};
    use zenoh::Wait;
    let out = temp("output-only");
    let rec = out.join("ambient.mcap");
    let sim = crate::common::splinewatch(&[
        "simulate",
        "--config",
        "config/sinello-ambient.toml",
        "--duration",
        "600",
        "--excitation",
        "ambient",
        "--seed",
        "3",
        "--out",
        rec.to_str().unwrap(),
    ]);
    assert!(sim.status.success(), "{}", String::from_utf8_lossy(&sim.stderr));
    let text = std::fs::read_to_string(root().join("config/sinello-ambient.toml"))
        .unwrap()
        .replace("window_seconds = 1200.0", "window_seconds = 300.0");
    let cfg = splinewatch::config::Config::from_toml(&text).unwrap();
    let bytes = std::fs::read(&rec).unwrap();
    let (blocks, _) =
        splinewatch::io::recording::read_recording(&bytes, &splinewatch::io::wire::Limits::default()).unwrap();
    let received: Arc<Mutex<Vec<serde_json::Value>>> = Arc::default();
    let sink = Arc::clone(&received);
    let live =
        splinewatch::service::demo::run_with_source(cfg.clone(), &out, 40.0, usize::MAX, move |cfg, publisher| {
            let seen = Arc::clone(&sink);
            let _subscriber = publisher
                .session()
                .declare_subscriber(format!("{}/oma/modes", cfg.topic_prefix()))
                .callback(move |s| {
                    let v = serde_json::from_slice(&s.payload().to_bytes()).expect("a JSON message");
                    seen.lock().unwrap().push(v);
                })
                .wait()
                .map_err(|e| anyhow::anyhow!("{e}"))?;
            for b in &blocks {
                publisher.publish(&b.block)?;
            }
            // The last window is identified after its last block: wait for it.
            let start = std::time::Instant::now();
            while sink.lock().unwrap().len() < 2 && start.elapsed().as_secs() < 60 {
                std::thread::sleep(std::time::Duration::from_millis(100));
            }
            Ok(blocks.len() as u64)
        })
        .unwrap();
    let received = received.lock().unwrap();
    assert_eq!(received.len(), 2, "oma/modes messages over zenoh");
    for m in received.iter() {
        assert!(m["modes"].as_array().unwrap().len() >= 15, "{}", m["window"]);
    }
    assert_eq!(live.updates.len(), 2);
    // Rerun: the stabilisation diagram, trends and shapes by model mode, per-mode residues.
    let rrd = splinewatch::outputs::rerun::inspect_rrd(&std::fs::read(out.join("results.rrd")).unwrap()).unwrap();
    for prefix in [
        "/oma/stabilisation",
        "/oma/stabilisation/first_singular_value",
        "/oma/trends/mode_4/frequency_hz",
        "/oma/shapes/mode_4/identified",
        "/oma/shapes/mode_4/model",
        "/residual/modes/mode_4",
        "/parameters/springs/east.k2",
    ] {
        assert!(
            rrd.entities.iter().any(|e| e == prefix),
            "{prefix} not in {:?}",
            rrd.entities
        );
    }
    let mut writer = ResultsWriter::new(Cursor::new(Vec::new()), &cfg.topic_prefix()).unwrap();
    let offline = replay(&cfg, &[&bytes], &mut writer, Default::default(), &mut |_, _| {}).unwrap();
    assert_eq!(offline.updates.len(), 2);
    for (a, b) in live.updates.iter().zip(&offline.updates) {
        assert_eq!(parameter_values(a), parameter_values(b), "window {}", a.window);
    }
}
