//! The statistical layer end to end: months of pre-computed FRF windows
//! with temperatures made by the simulator, replayed through the pipeline
//! (with a restart in the middle), re-scored offline by `monitor`, and live
//! over zenoh with temperature topics.

use crate::common::{fresh_dir, TestDir};
use splinewatch::config::{load_config, Config};
use splinewatch::io::monitoring_json::StatusMessage;
use splinewatch::io::recording::RecordingWriter;
use splinewatch::io::wire::Encoding;
use splinewatch::outputs::results::ResultsWriter;
use splinewatch::pipeline::{rescore, Training};
use splinewatch::service::replay::{replay, ReplayOptions};
use splinewatch::service::rescore::read_statuses;
use splinewatch::studies::frf_windows::{simulate_frf_windows, FrfRecord, FrfWindowOptions};
use splinewatch::studies::simulation::parse_scenario;
use std::io::Cursor;
use std::path::{Path, PathBuf};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn temp(name: &str) -> TestDir {
    fresh_dir(&format!("monitoring-{name}"))
}

/// Simulates hourly FRF windows of the bundled two-week scenario (its text
/// changed by `edit`) into one recording per entry of `split` (window
/// counts), in `dir`.
fn simulate(cfg: &Config, dir: &Path, split: &[usize], edit: impl Fn(String) -> String) -> Vec<PathBuf> {
    let text = std::fs::read_to_string(root().join("config/scenarios/two-weeks-bearing-loss.toml")).unwrap();
    let scenario = parse_scenario(&edit(text)).unwrap();
    let windows: usize = split.iter().sum();
    let options = FrfWindowOptions {
        windows,
        window_seconds: 3600.0,
        start_ns: 1_795_255_200_000_000_000,
        noise: 0.02,
        step_hz: 0.25,
        seed: 1,
    };
    let prefix = cfg.topic_prefix();
    let paths: Vec<PathBuf> = (0..split.len()).map(|k| dir.join(format!("frf-{k}.mcap"))).collect();
    let mut writers: Vec<_> = paths
        .iter()
        .map(|p| Some(RecordingWriter::create(p, Encoding::Cbor).unwrap()))
        .collect();
    let (mut file, mut frf_in_file, pairs) = (0, 0, 12);
    simulate_frf_windows(cfg, &scenario, &options, &mut |record| {
        let w = writers[file].as_mut().unwrap();
        match record {
            FrfRecord::Temperature(block) => {
                w.write_block(&prefix, &block)?;
            }
            FrfRecord::Frf { key, time_ns, payload } => {
                w.write_json(&format!("{prefix}/{key}"), time_ns, &payload)?;
                frf_in_file += 1;
                if frf_in_file == split[file] * pairs && file + 1 < split.len() {
                    writers[file].take().unwrap().finish()?;
                    (file, frf_in_file) = (file + 1, 0);
                }
            }
        }
        Ok(())
    })
    .unwrap();
    for w in writers.into_iter().flatten() {
        w.finish().unwrap();
    }
    paths
}

/// Publishes an FRF-window recording live in file order: temperature
/// blocks, and the FRF messages, calling `after_set(n)` once the n-th
/// complete set (12 messages) is out. Returns the messages published.
fn publish_recording(
    publisher: &mut splinewatch::outputs::publisher::Publisher,
    prefix: &str,
    bytes: &[u8],
    mut after_set: impl FnMut(usize),
) -> anyhow::Result<u64> {
    let (mut sent, mut frfs) = (0, 0);
    for message in splinewatch::io::recording::mcap_messages(bytes, false)? {
        let message = message?;
        let suffix = message.channel.topic.strip_prefix(&format!("{prefix}/")).unwrap();
        if suffix.starts_with("frf/") {
            publisher.publish_json(suffix, message.data.to_vec())?;
            frfs += 1;
            if frfs % 12 == 0 {
                after_set(frfs / 12);
            }
        } else {
            for b in splinewatch::io::wire::decode(&message.data, Encoding::Cbor, &Default::default())? {
                publisher.publish(&b)?;
            }
        }
        sent += 1;
    }
    Ok(sent)
}

/// Replays `recording` into a results file in memory, resuming from and
/// keeping `state` (and the monitor file beside it).
fn replay_with_state(cfg: &Config, recording: &Path, state: &Path) -> Vec<u8> {
    let bytes = std::fs::read(recording).unwrap();
    let mut writer = ResultsWriter::new(Cursor::new(Vec::new()), &cfg.topic_prefix()).unwrap();
    let options = ReplayOptions {
        initial: splinewatch::outputs::state::load_state(state).unwrap(),
        state_path: Some(state),
        ..Default::default()
    };
    replay(cfg, &[&bytes], &mut writer, options, &mut |_, _| {}).unwrap();
    writer.finish().unwrap().into_inner()
}

/// The two-week scenario the acceptance test below reads for its two
/// checks (about 70 s of CPU to simulate and replay): hourly FRF windows, east.k2
/// 20 % softer from hour 200 and replaced at hour 260 (`repair_minute`),
/// replayed in two recordings with a restart after window 167, the notify
/// command appending what it is given to a file.
struct TwoWeeks {
    dir: TestDir,
    cfg: Config,
    /// The first run's results file.
    first: Vec<u8>,
    /// The monitor file's training windows after the first recording.
    reference_windows: Option<usize>,
    /// The second run's results file.
    second: Vec<u8>,
    statuses: Vec<StatusMessage>,
    /// What the notify command received, in order.
    received: Vec<StatusMessage>,
}

fn two_weeks() -> TwoWeeks {
    let dir = temp("two-weeks");
    let (cfg, notified) = notifying_config(&dir);
    let recordings = simulate(&cfg, &dir, &[168, 168], |t| {
        t.replace("factor = 0.8", "factor = 0.8\nrepair_minute = 15600.0      # hour 260")
    });
    let state = dir.join("state.json");
    let first = replay_with_state(&cfg, &recordings[0], &state);
    let saved = splinewatch::outputs::state::load_monitor(&dir.join("monitoring.json"))
        .unwrap()
        .unwrap();
    let reference_windows = saved.reference().map(|r| r.windows);
    let second = replay_with_state(&cfg, &recordings[1], &state);
    let statuses = read_statuses(&[&first, &second], &cfg.topic_prefix()).unwrap();
    let received = std::fs::read_to_string(&notified)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    TwoWeeks {
        dir,
        cfg,
        first,
        reference_windows,
        second,
        statuses,
        received,
    }
}

/// What the notifier must send over the two runs of [`two_weeks`]: each
/// run's changes ([`notified_changes`]), in order.
fn notified_per_run(statuses: &[StatusMessage]) -> Vec<StatusMessage> {
    let mut expected = notified_changes(&statuses[..168]);
    expected.extend(notified_changes(&statuses[168..]));
    expected
}

/// The issue's acceptance scenario: two weeks of hourly windows (daily
/// ±8 °C, warming 0.6 °C a day, a cold spell to about −11 °C inside the
/// training span; deck moduli −0.4 %/°C, supports +5 %/°C below 0 °C),
/// trained on the first 100 updates, east.k2 20 % softer from window 200
/// (replaced at 260: the issue-33 check at the end); replayed in two
/// recordings with a restart after window 167 ([`two_weeks`]).
/// - No alarm in the undamaged windows 100–199; the alarm within 12
///   windows of the damage (measured: 2); windows warmer than the training
///   range are flagged `outside_training_range`, not scored.
/// - The restart resumed the reference (no second training).
/// - `monitor` re-scoring the two results files reproduces every status
///   bit for bit.
/// - Scored on the raw parameters with the textbook limits, the undamaged
///   windows alarm (why the layer exists).
#[test]
fn two_weeks_of_windows_alarm_on_a_bearing_loss_and_never_on_temperature() {
    let fixture = two_weeks();
    let TwoWeeks {
        dir,
        cfg,
        first,
        reference_windows,
        second,
        statuses,
        received,
    } = &fixture;
    assert_eq!(*reference_windows, Some(100));
    assert_eq!(statuses.len(), 336);
    // FRF sets are numbered from 0 in each recording: the second file's
    // windows are 0–167 again; order tells them apart.
    let states: Vec<&str> = statuses.iter().map(|s| s.state.as_str()).collect();
    assert!(states[..100].iter().all(|&s| s == "training"));
    assert!(
        states[100..].iter().all(|&s| s != "training"),
        "the restart must not retrain"
    );
    let undamaged = &states[100..200];
    assert_eq!(undamaged.iter().filter(|&&s| s == "alarm").count(), 0, "{undamaged:?}");
    assert!(undamaged.iter().filter(|&&s| s == "normal").count() >= 80);
    let detection = states[200..]
        .iter()
        .position(|&s| s == "alarm")
        .expect("an alarm after the damage");
    assert!(detection < 12, "alarm {detection} windows after the onset");
    let largest = statuses[200 + detection]
        .residuals
        .iter()
        .max_by(|a, b| a.standardised.abs().total_cmp(&b.standardised.abs()))
        .unwrap();
    assert_eq!(largest.name, "east.k2");
    assert!(statuses
        .iter()
        .any(|s| s.state == "outside_training_range" && s.flags.iter().any(|f| f == "outside_training_range:T1")));
    // The command got exactly the changes into and out of an alarm or the
    // outside-range state (each run's first status too when it is one),
    // in order, the alarm's raise among them.
    let expected = notified_per_run(statuses);
    assert!(expected.iter().any(|s| s.state == "alarm"));
    assert_eq!(
        serde_json::to_string(received).unwrap(),
        serde_json::to_string(&expected).unwrap()
    );
    let health = mcap::MessageStream::new(second)
        .unwrap()
        .map(Result::unwrap)
        .filter(|m| m.channel.topic.ends_with("/health"))
        .last()
        .map(|m| serde_json::from_slice::<serde_json::Value>(&m.data).unwrap())
        .unwrap();
    let second_run = expected.len() - expected.iter().filter(|s| statuses[..168].contains(s)).count();
    assert_eq!(
        health["notifications_sent"].as_u64().unwrap_or(0),
        second_run as u64,
        "{health}"
    );
    // `monitor` reproduces the statuses bit for bit.
    let settings = cfg.monitoring.clone().unwrap();
    let again = rescore(&settings, statuses, Training::FirstWindows(100), false).unwrap();
    let again: Vec<StatusMessage> = again.into_iter().map(|o| o.status).collect();
    assert_eq!(
        serde_json::to_string(&again).unwrap(),
        serde_json::to_string(statuses).unwrap()
    );
    // Raw parameters, textbook limits: false alarms on temperature alone.
    let raw = splinewatch::config::MonitoringConfig {
        limits: splinewatch_core::monitoring::LimitMethod::Theoretical,
        ..settings
    };
    let raw = rescore(&raw, statuses, Training::FirstWindows(100), true).unwrap();
    let false_alarms = raw[100..200].iter().filter(|o| o.status.state == "alarm").count();
    assert!(
        false_alarms > 20,
        "raw parameters: {false_alarms} alarm windows before the damage"
    );
    // The owner's report of the two runs' results: the alarm raised and
    // cleared (the repair) over the whole period, still on at a time inside it.
    let files = [dir.join("first.mcap"), dir.join("second.mcap")];
    std::fs::write(&files[0], first).unwrap();
    std::fs::write(&files[1], second).unwrap();
    let files: Vec<&str> = files.iter().map(|p| p.to_str().unwrap()).collect();
    let alarmed = &statuses[200 + detection];
    assert_eq!(alarmed.state, "alarm");
    crate::report::monitoring_report(dir, &files, &alarmed.time);
    issue_33_a_notify_command_receives_the_raise_and_the_clear_of_an_alarm(&fixture);
}

/// Live over zenoh on loopback, with temperature topics: 14 hourly FRF
/// windows of a calm day (pre-computed FRFs on `frf/**`, temperature blocks on
/// `temperature/T1`) to a daemon training on the first 10: every status
/// arrives on `<prefix>/monitoring/status`, `monitoring/latest` answers
/// with the last, the Rerun file holds the control charts. A restart with
/// 6 more windows resumes the reference (no training). `monitor` over the
/// two runs' results files reproduces the live statuses bit for bit.
#[test]
fn live_monitoring_with_temperature_topics_survives_a_restart() {
    use std::sync::{Arc, Mutex};
    use zenoh::Wait;
    let out = temp("live");
    let text = std::fs::read_to_string(root().join("config/sinello-monitoring.toml"))
        .unwrap()
        .replace("training_windows = 100", "training_windows = 10");
    let cfg = Config::from_toml(&text).unwrap();
    // A calm day (±0.5 °C): ten training hours cover the range.
    let recordings = simulate(&cfg, &out, &[14, 6], |t| {
        t.replace("daily_amplitude_c = 8.0", "daily_amplitude_c = 0.5")
    });
    let run = |recording: PathBuf| {
        let received: Arc<Mutex<Vec<StatusMessage>>> = Arc::default();
        let latest: Arc<Mutex<Option<StatusMessage>>> = Arc::default();
        let (sink, reply) = (Arc::clone(&received), Arc::clone(&latest));
        let summary =
            splinewatch::service::demo::run_with_source(cfg.clone(), &out, 0.0, usize::MAX, move |cfg, publisher| {
                let prefix = cfg.topic_prefix();
                let seen = Arc::clone(&sink);
                let _subscriber = publisher
                    .session()
                    .declare_subscriber(format!("{prefix}/monitoring/status"))
                    .callback(move |s| {
                        let v = serde_json::from_slice(&s.payload().to_bytes()).expect("a status");
                        seen.lock().unwrap().push(v);
                    })
                    .wait()
                    .map_err(|e| anyhow::anyhow!("{e}"))?;
                let bytes = std::fs::read(&recording)?;
                let sent = publish_recording(publisher, &prefix, &bytes, |sets| {
                    // One update at a time: the next set waits for this one's status.
                    let start = std::time::Instant::now();
                    while sink.lock().unwrap().len() < sets && start.elapsed().as_secs() < 120 {
                        std::thread::sleep(std::time::Duration::from_millis(20));
                    }
                })?;
                let replies = publisher
                    .session()
                    .get(format!("{prefix}/monitoring/latest"))
                    .wait()
                    .map_err(|e| anyhow::anyhow!("{e}"))?;
                if let Ok(r) = replies.recv() {
                    let body = r.result().map_err(|e| anyhow::anyhow!("{e:?}"))?.payload().to_bytes();
                    *reply.lock().unwrap() = Some(serde_json::from_slice(&body)?);
                }
                Ok(sent)
            })
            .unwrap();
        assert!(summary.updates.iter().all(|u| u.result.is_ok()));
        let received = received.lock().unwrap().clone();
        let latest = latest.lock().unwrap().clone();
        (received, latest)
    };
    let (first, latest) = run(recordings[0].clone());
    assert_eq!(first.len(), 14, "statuses over zenoh");
    assert!(first[..10].iter().all(|s| s.state == "training"));
    assert!(
        first[10..].iter().all(|s| s.state == "normal"),
        "{:?}",
        first.iter().map(|s| &s.state).collect::<Vec<_>>()
    );
    assert!(first.iter().all(|s| s.temperature_c.is_some()));
    assert_eq!(latest.as_ref(), first.last(), "monitoring/latest");
    let rrd = splinewatch::outputs::rerun::inspect_rrd(&std::fs::read(out.join("results.rrd")).unwrap()).unwrap();
    for entity in [
        "/monitoring/charts/t2",
        "/monitoring/charts/mewma",
        "/monitoring/temperature/east.k2",
        "/deck/monitoring_residual",
    ] {
        assert!(
            rrd.entities.iter().any(|e| e == entity),
            "{entity} not in {:?}",
            rrd.entities
        );
    }
    let (second, _) = run(recordings[1].clone());
    assert_eq!(second.len(), 6);
    assert!(
        second.iter().all(|s| s.state == "normal"),
        "the restart must not retrain"
    );
    // The daemon never overwrites a results file: the second run wrote results-1.mcap.
    let files: Vec<Vec<u8>> = ["results.mcap", "results-1.mcap"]
        .iter()
        .map(|f| std::fs::read(out.join(f)).unwrap())
        .collect();
    let saved = read_statuses(&[&files[0], &files[1]], &cfg.topic_prefix()).unwrap();
    let live: Vec<StatusMessage> = first.into_iter().chain(second).collect();
    assert_eq!(saved, live);
    let again = rescore(
        cfg.monitoring.as_ref().unwrap(),
        &saved,
        Training::FirstWindows(10),
        false,
    )
    .unwrap();
    let again: Vec<StatusMessage> = again.into_iter().map(|o| o.status).collect();
    assert_eq!(
        serde_json::to_string(&again).unwrap(),
        serde_json::to_string(&live).unwrap()
    );
}

/// The time-domain simulator with an `[environment]`: a temperature block
/// every minute on each channel (the air temperature plus sensor noise,
/// here none), in time order with the data; at −5 °C the supports are 25 %
/// stiffer and the deck's moduli 6 % higher (the factors the simulated
/// truth is built with).
#[test]
fn the_time_domain_simulator_records_temperatures() {
    use splinewatch::io::wire::ChannelQuantity;
    use splinewatch::studies::simulation::{simulate, SimulationOptions};
    let cfg = load_config(&root().join("config/sinello-monitoring.toml")).unwrap();
    let scenario = parse_scenario(
        "[environment]\nchannels = [\"T1\", \"T2\"]\nmean_c = -5.0\nnoise_c = 0.0\nsupport_stiffening_per_c = 0.05\n\
         deck_modulus_per_c = -0.004\n",
    )
    .unwrap();
    let environment = scenario.environment.clone().unwrap();
    assert!((environment.support_factor(-5.0) - 1.25).abs() < 1e-12);
    assert!((environment.modulus_factor(-5.0) - 1.06).abs() < 1e-12);
    let options = SimulationOptions {
        scenario: Some(scenario),
        ..SimulationOptions::random_excitation(&cfg, 150.0, 2)
    };
    let mut temperatures = Vec::new();
    let mut last_start = i128::MIN;
    simulate(&cfg, &options, &mut |block| {
        assert!(block.start_ns >= last_start, "blocks in time order");
        last_start = block.start_ns;
        if block.quantity == ChannelQuantity::Temperature {
            temperatures.push(block);
        }
        Ok(())
    })
    .unwrap();
    // Samples at 0, 60 and 120 s on both channels.
    assert_eq!(temperatures.len(), 6);
    for b in &temperatures {
        assert_eq!((b.data.len(), b.fs, b.unit.as_str()), (1, 1.0 / 60.0, "°C"));
        assert_eq!(b.data[0], -5.0);
    }
    assert_eq!(temperatures[2].start_ns - temperatures[0].start_ns, 60_000_000_000);
}

/// The daemon's raw recorder keeps pre-computed FRF messages and
/// temperature blocks, and the replay of its files gives the live
/// statuses.
#[test]
fn the_raw_recording_of_frf_windows_replays_to_the_live_statuses() {
    let out = temp("raw");
    let text = std::fs::read_to_string(root().join("config/sinello-monitoring.toml"))
        .unwrap()
        .replace("training_windows = 100", "training_windows = 10");
    let mut cfg = Config::from_toml(&text).unwrap();
    cfg.output.raw = splinewatch::config::RawRecordingConfig {
        enabled: true,
        dir: out.join("raw"),
        rotate_minutes: 24.0 * 60.0,
        rotate_megabytes: 512.0,
    };
    let recording = simulate(&cfg, &out, &[12], |t| {
        t.replace("daily_amplitude_c = 8.0", "daily_amplitude_c = 0.5")
    })
    .remove(0);
    let bytes = std::fs::read(&recording).unwrap();
    let live =
        splinewatch::service::demo::run_with_source(cfg.clone(), &out, 0.0, usize::MAX, move |cfg, publisher| {
            publish_recording(publisher, &cfg.topic_prefix(), &bytes, |_| {
                // Let the update run before the next set (one waiting job at most).
                std::thread::sleep(std::time::Duration::from_millis(1500));
            })
        })
        .unwrap();
    assert_eq!(live.updates.len(), 12);
    let live_results = std::fs::read(out.join("results.mcap")).unwrap();
    let live_statuses = read_statuses(&[&live_results], &cfg.topic_prefix()).unwrap();
    assert_eq!(live_statuses.len(), 12);
    let raw: Vec<PathBuf> = std::fs::read_dir(out.join("raw"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "mcap"))
        .collect();
    assert_eq!(raw.len(), 1, "{raw:?}");
    let mut replay_cfg = cfg.clone();
    replay_cfg.output.raw.enabled = false;
    std::fs::create_dir_all(out.join("replay")).unwrap();
    let replayed = replay_with_state(&replay_cfg, &raw[0], &out.join("replay/state.json"));
    let replayed = read_statuses(&[&replayed], &cfg.topic_prefix()).unwrap();
    // The live run's FRF spans came from the messages, so the temperatures
    // and the training agree; the parameters may differ in the last bits
    // (the live worker warm-starts a job that waited from the latest result).
    assert_eq!(replayed.len(), 12);
    for (a, b) in replayed.iter().zip(&live_statuses) {
        assert_eq!(
            (a.window, &a.state, &a.temperatures),
            (b.window, &b.state, &b.temperatures)
        );
        for (x, y) in a.features.iter().zip(&b.features) {
            assert!(
                (x.value - y.value).abs() <= 1e-6 * y.value.abs(),
                "{}: {} vs {}",
                x.name,
                x.value,
                y.value
            );
        }
    }
}

/// The daemon as a systemd `Type=notify` service, on a real notification
/// socket: READY=1 at start, a STATUS per accepted update ending with the
/// monitoring state (`training` for the first 10, then `normal`), and
/// STOPPING=1 on SIGTERM. Twelve FRF windows are published live over zenoh,
/// one set at a time.
#[cfg(unix)]
#[test]
fn systemd_status_ends_with_the_monitoring_state() {
    use std::os::unix::net::UnixDatagram;
    use std::sync::{Arc, Mutex};
    let dir = temp("systemd");
    let endpoint = crate::common::free_endpoint();
    let text = std::fs::read_to_string(root().join("config/sinello-monitoring.toml"))
        .unwrap()
        .replace("training_windows = 100", "training_windows = 10")
        + &format!("\n[zenoh]\nlisten = [\"{endpoint}\"]\nmulticast_scouting = false\n");
    let config = dir.join("config.toml");
    std::fs::write(&config, &text).unwrap();
    let cfg = Config::from_toml(&text).unwrap();
    let recording = simulate(&cfg, &dir, &[12], |t| {
        t.replace("daily_amplitude_c = 8.0", "daily_amplitude_c = 0.5")
    })
    .remove(0);
    let socket_path = dir.join("notify.sock");
    let socket = UnixDatagram::bind(&socket_path).unwrap();
    socket
        .set_read_timeout(Some(std::time::Duration::from_millis(200)))
        .unwrap();
    let notes: Arc<Mutex<Vec<String>>> = Arc::default();
    let stop = Arc::new(std::sync::atomic::AtomicBool::new(false));
    let reader = {
        let (notes, stop) = (Arc::clone(&notes), Arc::clone(&stop));
        std::thread::spawn(move || {
            let mut buffer = [0u8; 4096];
            while !stop.load(std::sync::atomic::Ordering::Relaxed) {
                if let Ok(n) = socket.recv(&mut buffer) {
                    notes
                        .lock()
                        .unwrap()
                        .push(String::from_utf8_lossy(&buffer[..n]).into_owned());
                }
            }
        })
    };
    let daemon = crate::common::KillOnDrop(Some(
        std::process::Command::new(env!("CARGO_BIN_EXE_splinewatch"))
            .args(["run", "--config", config.to_str().unwrap(), "--state"])
            .arg(dir.join("state.json"))
            .arg("--out")
            .arg(dir.join("results.mcap"))
            .env("NOTIFY_SOCKET", &socket_path)
            .env("RUST_LOG", "warn")
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap(),
    ));
    let statuses = || -> Vec<String> {
        let notes = notes.lock().unwrap();
        notes
            .iter()
            .flat_map(|n| n.lines())
            .filter_map(|l| l.strip_prefix("STATUS="))
            .map(str::to_string)
            .collect()
    };
    let wait = |what: &dyn Fn() -> bool| {
        let start = std::time::Instant::now();
        while !what() && start.elapsed().as_secs() < 120 {
            std::thread::sleep(std::time::Duration::from_millis(20));
        }
    };
    wait(&|| notes.lock().unwrap().iter().any(|n| n.contains("READY=1")));
    let mut z = cfg.zenoh.clone();
    z.connect = std::mem::take(&mut z.listen);
    z.mode = "client".into();
    let mut publisher =
        splinewatch::outputs::publisher::Publisher::open(&z, cfg.topic_prefix(), Encoding::Cbor, 0.0).unwrap();
    std::thread::sleep(std::time::Duration::from_millis(500));
    let bytes = std::fs::read(&recording).unwrap();
    publish_recording(&mut publisher, &cfg.topic_prefix(), &bytes, |sets| {
        wait(&|| statuses().len() >= sets);
    })
    .unwrap();
    publisher.close().unwrap();
    let (status, log) = crate::common::terminate(daemon.take());
    assert!(status.success(), "{log}");
    wait(&|| notes.lock().unwrap().iter().any(|n| n.contains("STOPPING=1")));
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    reader.join().unwrap();
    let statuses = statuses();
    assert_eq!(statuses.len(), 12, "{statuses:?}\n{log}");
    for (k, s) in statuses.iter().enumerate() {
        let state = if k < 10 { "training" } else { "normal" };
        assert!(
            s.starts_with(&format!("window {k}: relative residual ")) && s.ends_with(&format!("monitoring: {state}")),
            "{s}"
        );
    }
    let notes = notes.lock().unwrap();
    assert!(notes[0].contains("READY=1"), "{notes:?}");
    assert!(notes.last().unwrap().contains("STOPPING=1"), "{notes:?}");
}

/// Issue 31: a burst of pre-computed FRF windows (a logger uploading a
/// backlog of 24 at once, faster than the updates run) loses no window
/// silently: each is either updated or recorded on `updating/failures` as
/// skipped with the reason (dropped by the full queue, counted in
/// `queue_drops`, or still waiting when the daemon stopped).
#[test]
fn a_burst_of_frf_windows_is_updated_or_recorded_as_skipped() {
    let out = temp("burst");
    let text = std::fs::read_to_string(root().join("config/sinello-monitoring.toml"))
        .unwrap()
        .replace("training_windows = 100", "training_windows = 10");
    let cfg = Config::from_toml(&text).unwrap();
    let recording = simulate(&cfg, &out, &[24], |t| t).remove(0);
    let bytes = std::fs::read(&recording).unwrap();
    let live =
        splinewatch::service::demo::run_with_source(cfg.clone(), &out, 0.0, usize::MAX, move |cfg, publisher| {
            publish_recording(publisher, &cfg.topic_prefix(), &bytes, |_| {})
        })
        .unwrap();
    let results = std::fs::read(out.join("results.mcap")).unwrap();
    let (mut updated, mut skipped) = (Vec::new(), Vec::new());
    let (mut queue_drops, mut overflow, mut health) = (0, 0, serde_json::Value::Null);
    for m in mcap::MessageStream::new(&results).unwrap() {
        let m = m.unwrap();
        let v: serde_json::Value = serde_json::from_slice(&m.data).unwrap();
        let topic = m
            .channel
            .topic
            .rsplit_once(&format!("{}/", cfg.topic_prefix()))
            .unwrap()
            .1
            .to_string();
        match topic.as_str() {
            "updating/parameters" => updated.push(v["window"].as_u64().unwrap()),
            "updating/failures" => {
                assert_eq!(v["skipped"], true, "{v}");
                let reason = v["error"].as_str().unwrap();
                assert!(reason.starts_with("update skipped: "), "{v}");
                // Dropped by the full queue, or still waiting at shutdown.
                overflow += usize::from(reason.contains("the update queue holds 16"));
                skipped.push(v["window"].as_u64().unwrap());
            }
            "health" => {
                queue_drops = v["queue_drops"].as_u64().unwrap();
                health = v;
            }
            _ => {}
        }
    }
    let mut every: Vec<u64> = updated.iter().chain(&skipped).copied().collect();
    every.sort_unstable();
    assert_eq!(
        every,
        (0..24).collect::<Vec<u64>>(),
        "updated {updated:?}, skipped {skipped:?}"
    );
    assert_eq!(live.updates.len(), updated.len());
    assert!(!updated.is_empty());
    assert_eq!(queue_drops, overflow as u64, "the overflow skips are the counted drops");
    // Issue 48: updates add up as messages do, in the last health message.
    let count = |reason: &str| health["updates_skipped"][reason].as_u64().unwrap_or(0);
    assert_eq!(count("queue_full"), overflow as u64, "{health}");
    assert_eq!(count("shutdown"), (skipped.len() - overflow) as u64, "{health}");
    assert_eq!(
        health["update_runs"].as_u64().unwrap() + count("queue_full") + count("shutdown"),
        24,
        "{health}"
    );
}

/// The bundled monitoring config whose notify command (issue 33) appends
/// every status it is given, one a line, to the returned file in `dir`.
fn notifying_config(dir: &Path) -> (Config, PathBuf) {
    let mut cfg = load_config(&root().join("config/sinello-monitoring.toml")).unwrap();
    let notified = dir.join("notified.jsonl");
    cfg.monitoring.as_mut().unwrap().notify = Some(splinewatch::config::NotifyConfig {
        // The status on stdin; the report's subject line and whether its
        // file is a whole page, one line each, beside.
        command: vec![
            "sh".into(),
            "-c".into(),
            format!(
                "cat >> '{0}' && printf '%s\\t%s\\n' \"$SPLINEWATCH_SUBJECT\" \"$(grep -c '</html>' \"$SPLINEWATCH_REPORT\")\" >> '{0}.subjects'",
                notified.display()
            ),
        ],
        retries: 2,
        timeout_seconds: 10.0,
        ..Default::default()
    });
    (cfg, notified)
}

/// What the notifier must send for one run's statuses: each change into or
/// out of an alarm or the outside-range state (the run's first status too
/// when it is one), in order.
fn notified_changes(run: &[StatusMessage]) -> Vec<StatusMessage> {
    let changes = |s: &str| s == "alarm" || s == "outside_training_range";
    let mut expected = Vec::new();
    let mut previous: Option<&str> = None;
    for s in run {
        if previous != Some(s.state.as_str()) && (changes(&s.state) || previous.is_some_and(changes)) {
            expected.push(s.clone());
        }
        previous = Some(s.state.as_str());
    }
    expected
}

/// Issue 33: a notify command receives the raise **and** the clear of an
/// alarm. The two-week case of [`two_weeks`], whose softened bearing is
/// replaced at hour 260 (`repair_minute`): the alarm raised after hour 200
/// clears after the repair, and the command gets both, in order, with
/// nothing in between but state changes. Checked at the end of the
/// two-week test, on its fixture (a test of its own would hold a test
/// thread idle while the other one computes the fixture).
fn issue_33_a_notify_command_receives_the_raise_and_the_clear_of_an_alarm(fixture: &TwoWeeks) {
    let TwoWeeks { statuses, received, .. } = fixture;
    let states: Vec<&str> = statuses.iter().map(|s| s.state.as_str()).collect();
    let raised = 200
        + states[200..]
            .iter()
            .position(|&s| s == "alarm")
            .expect("an alarm after the damage");
    let last_alarm = states.iter().rposition(|&s| s == "alarm").unwrap();
    let cleared = last_alarm
        + states[last_alarm..]
            .iter()
            .position(|&s| s == "normal")
            .expect("the alarm clears");
    eprintln!("alarm raised at window {raised}, cleared at window {cleared} (the repair: window 260)");
    assert!(raised < 212 && cleared > 260, "raised {raised}, cleared {cleared}");
    // The command got exactly the changes (the two-week test compares them
    // in full): the raise and the clear among them.
    let received: Vec<(u64, String)> = received.iter().map(|s| (s.window, s.state.clone())).collect();
    assert!(
        received.contains(&(statuses[raised].window, "alarm".into())),
        "{received:?}"
    );
    assert!(
        received.contains(&(statuses[cleared].window, "normal".into())),
        "{received:?}"
    );
    // Each notification carried the owner's report of what the run had
    // written: the raise says to inspect, naming the softened bearing; the
    // clear, to review the alarm raised and cleared.
    let subjects = std::fs::read_to_string(fixture.dir.join("notified.jsonl.subjects")).unwrap();
    let subjects: Vec<&str> = subjects.lines().collect();
    assert_eq!(subjects.len(), received.len(), "{subjects:?}");
    assert!(
        subjects.iter().all(|s| s.ends_with("\t1")),
        "a whole page each: {subjects:?}"
    );
    let at = |window: u64, state: &str| subjects[received.iter().position(|r| *r == (window, state.into())).unwrap()];
    let raise = at(statuses[raised].window, "alarm");
    assert!(
        raise.starts_with("sinello-span2-monitoring: High: inspect: In alarm since")
            && raise.contains("east: support stiffness, coefficient 2"),
        "{raise}"
    );
    let clear = at(statuses[cleared].window, "normal");
    assert!(
        clear.starts_with("sinello-span2-monitoring: Medium: review: ")
            && clear.contains("alarm(s) raised in the period"),
        "{clear}"
    );
}
