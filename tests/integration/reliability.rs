//! Fault injection: SIGKILL at seeded random moments of a replay, and of
//! the live daemon fed over zenoh, with a state file. After every kill the
//! state file is the old or the new complete version, the results MCAP is
//! recoverable, and the recovered results hold every update the state file
//! says was accepted; the live daemon restarts warm from that state.
//! Also: results files on a full disk, and their rotation.

use rand::{Rng, SeedableRng};
use splinewatch::outputs::state::load_state;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Instant;

use crate::common::{bundled_blocks, free_endpoint, fresh_dir, spawn_daemon};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn sigkill_during_replay_loses_nothing_that_was_reported() {
    let dir = fresh_dir("kill");
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(2026);
    // How long an uninterrupted replay takes here, to spread the kills over it.
    let t0 = Instant::now();
    let full = Command::new(env!("CARGO_BIN_EXE_splinewatch"))
        .args(["replay", "--config"])
        .arg(root().join("config/sinello.toml"))
        .arg(root().join("recordings/sinello-demo.mcap"))
        .arg("--out")
        .arg(dir.join("full.mcap"))
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .unwrap();
    assert!(full.success());
    let span = t0.elapsed();
    let mut killed_with_state = 0;
    for round in 0..8 {
        let results = dir.join(format!("results-{round}.mcap"));
        let state = dir.join(format!("state-{round}.json"));
        let mut child = Command::new(env!("CARGO_BIN_EXE_splinewatch"))
            .args(["replay", "--config"])
            .arg(root().join("config/sinello.toml"))
            .arg(root().join("recordings/sinello-demo.mcap"))
            .arg("--out")
            .arg(&results)
            .arg("--state")
            .arg(&state)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let delay = span.mul_f64(rng.random_range(0.05..0.95));
        std::thread::sleep(delay);
        let _ = Command::new("kill").args(["-KILL", &child.id().to_string()]).status();
        let _ = child.wait();
        // (a) the state file, if any, is a complete version.
        let saved = load_state(&state).unwrap_or_else(|e| panic!("round {round}: state file damaged: {e:#}"));
        // (b) the results are recoverable ...
        let bytes = std::fs::read(&results).unwrap();
        let (report, recovered) =
            splinewatch::io::recover::recover(&bytes, std::io::Cursor::new(Vec::new())).expect("recoverable");
        let recovered = recovered.into_inner();
        assert!(mcap::Summary::read(&recovered).unwrap().is_some(), "round {round}");
        // (c) ... and hold the update the state file reports: the results
        // are flushed before the state is renamed into place.
        if let Some(saved) = saved {
            killed_with_state += 1;
            let windows: Vec<u64> = mcap::MessageStream::new(&recovered)
                .unwrap()
                .map(|m| m.unwrap())
                .filter(|m| m.channel.topic.ends_with("updating/parameters"))
                .map(|m| {
                    serde_json::from_slice::<serde_json::Value>(&m.data).unwrap()["window"]
                        .as_u64()
                        .unwrap()
                })
                .collect();
            assert!(
                windows.contains(&saved.window),
                "round {round}: the state says window {} was accepted, the recovered results have {windows:?} ({report:?})",
                saved.window
            );
        }
    }
    eprintln!("8 kills, {killed_with_state} after at least one accepted update");
    assert!(
        killed_with_state >= 2,
        "the kills should not all land before the first update"
    );
}

/// A file on a disk that fills up after `limit` bytes.
struct FillingDisk {
    data: std::sync::Arc<std::sync::Mutex<Vec<u8>>>,
    position: u64,
    limit: usize,
}

impl std::io::Write for FillingDisk {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let mut data = self.data.lock().unwrap();
        let at = self.position as usize;
        if at + buf.len() > self.limit {
            return Err(std::io::Error::new(
                std::io::ErrorKind::StorageFull,
                "no space left on device",
            ));
        }
        if data.len() < at + buf.len() {
            data.resize(at + buf.len(), 0);
        }
        data[at..at + buf.len()].copy_from_slice(buf);
        self.position += buf.len() as u64;
        Ok(buf.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

impl std::io::Seek for FillingDisk {
    fn seek(&mut self, pos: std::io::SeekFrom) -> std::io::Result<u64> {
        let len = self.data.lock().unwrap().len() as i64;
        self.position = match pos {
            std::io::SeekFrom::Start(p) => p as i64,
            std::io::SeekFrom::End(d) => len + d,
            std::io::SeekFrom::Current(d) => self.position as i64 + d,
        } as u64;
        Ok(self.position)
    }
}

#[test]
fn results_survive_a_full_disk() {
    use splinewatch::outputs::results::ResultsSink;
    type Disk = std::sync::Arc<std::sync::Mutex<Vec<u8>>>;
    let files: std::sync::Arc<std::sync::Mutex<Vec<Disk>>> = Default::default();
    let opened = files.clone();
    // File 0 fills the disk at 64 kB; opening file 1 fails (still full);
    // file 2 gets space again.
    let open = Box::new(move |index: u32| -> anyhow::Result<FillingDisk> {
        if index == 1 {
            anyhow::bail!("no space left on device");
        }
        let data: Disk = Default::default();
        opened.lock().unwrap().push(data.clone());
        Ok(FillingDisk {
            data,
            position: 0,
            limit: if index == 0 { 64_000 } else { usize::MAX },
        })
    });
    let mut sink = ResultsSink::new("bridge/test", open).unwrap();
    // Incompressible-enough messages, flushed every 10 like the daemon's
    // per-update flushes.
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let messages: Vec<serde_json::Value> = (0..400)
        .map(|k| serde_json::json!({"k": k, "noise": (0..40).map(|_| rng.random::<f64>()).collect::<Vec<_>>()}))
        .collect();
    let mut flushed = 0;
    for (k, m) in messages.iter().enumerate() {
        sink.write("windows", k as i128, m);
        if k % 10 == 9 {
            sink.flush();
            if sink.errors == 0 {
                flushed = k + 1;
            }
        }
    }
    // One failed write on the full file, one failed open of the next.
    assert_eq!(sink.errors, 2);
    let last = sink.finish().expect("the last file finishes");
    let disks = files.lock().unwrap();
    assert_eq!(disks.len(), 2, "file 0 and file 2");
    // File 0: everything flushed before the disk filled is recoverable.
    let first = disks[0].lock().unwrap().clone();
    let (report, _) = splinewatch::io::recover::recover(&first, std::io::Cursor::new(Vec::new())).unwrap();
    assert!(flushed >= 10, "the disk filled too early for the test");
    assert!(report.messages as usize >= flushed, "{report:?}, {flushed} flushed");
    // File 2: finalised, holding the tail of the stream up to the last message.
    drop(last);
    let second = disks[1].lock().unwrap().clone();
    let summary = mcap::Summary::read(&second).unwrap().expect("finalised");
    let count = summary.stats.unwrap().message_count as usize;
    let ks: Vec<u64> = mcap::MessageStream::new(&second)
        .unwrap()
        .map(|m| {
            serde_json::from_slice::<serde_json::Value>(&m.unwrap().data).unwrap()["k"]
                .as_u64()
                .unwrap()
        })
        .collect();
    assert_eq!(ks.len(), count);
    assert_eq!(*ks.last().unwrap(), 399);
    assert!(ks.windows(2).all(|w| w[1] == w[0] + 1), "no gaps once space is back");
    eprintln!(
        "full disk: {} messages recovered from the full file, {} in the new one, {} lost",
        report.messages,
        count,
        400 - report.messages as usize - count
    );
}

#[test]
fn results_rotate_by_measurement_time_with_one_unfinalised_file_at_most() {
    use splinewatch::outputs::results::{results_files, ResultsSink};
    let tmp = fresh_dir("rotate");
    let dir = tmp.join("results");
    let hour: i128 = 3_600_000_000_000;
    let start: i128 = 1_790_000_000 * 1_000_000_000;
    let mut sink = ResultsSink::new("bridge/test", results_files(&dir.join("results.mcap")))
        .unwrap()
        .rotate_every(hour);
    let finalised = |name: &str| {
        let bytes = std::fs::read(dir.join(name)).unwrap_or_default();
        mcap::Summary::read(&bytes).ok().flatten().is_some()
    };
    // A health message before any data (time 0) stays in the first file;
    // then one message every 10 minutes of measurement time for 3.5 h.
    sink.write("health", 0, &serde_json::json!({"k": -1}));
    let times: Vec<i128> = (0..=21).map(|k| start + k * hour / 6).collect();
    for (k, &t) in times.iter().enumerate() {
        sink.write("windows", t, &serde_json::json!({"k": k}));
        sink.flush();
        // Every file but the one being written is finalised at all times.
        let current = sink.rotations as usize;
        for f in 0..current {
            let name = if f == 0 {
                "results.mcap".to_string()
            } else {
                format!("results-{f}.mcap")
            };
            assert!(finalised(&name), "{name} not finalised after message {k}");
        }
    }
    assert_eq!(sink.errors, 0);
    assert_eq!(sink.rotations, 3, "3.5 h in files of 1 h");
    sink.finish().expect("last file finishes");
    let mut seen = Vec::new();
    for name in ["results.mcap", "results-1.mcap", "results-2.mcap", "results-3.mcap"] {
        let bytes = std::fs::read(dir.join(name)).unwrap();
        let summary = mcap::Summary::read(&bytes).unwrap().expect("finalised");
        let stats = summary.stats.unwrap();
        // Timed messages of one file span less than the rotation period.
        let timed: Vec<u64> = mcap::MessageStream::new(&bytes)
            .unwrap()
            .map(|m| m.unwrap().log_time)
            .filter(|&t| t > 0)
            .collect();
        assert!(timed.last().unwrap() - timed.first().unwrap() < hour as u64, "{name}");
        assert_eq!(
            stats.message_count as usize,
            mcap::MessageStream::new(&bytes).unwrap().count()
        );
        for m in mcap::MessageStream::new(&bytes).unwrap() {
            let v: serde_json::Value = serde_json::from_slice(&m.unwrap().data).unwrap();
            seen.push(v["k"].as_i64().unwrap());
        }
    }
    assert!(!dir.join("results-4.mcap").exists());
    // Every message, once, in order.
    assert_eq!(seen, (-1..=21).collect::<Vec<i64>>());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Parameter messages `(window, time)` in recovered results.
fn recovered_updates(recovered: &[u8]) -> Vec<(u64, String)> {
    mcap::MessageStream::new(recovered)
        .unwrap()
        .map(|m| m.unwrap())
        .filter(|m| m.channel.topic.ends_with("updating/parameters"))
        .map(|m| {
            let v: serde_json::Value = serde_json::from_slice(&m.data).unwrap();
            (v["window"].as_u64().unwrap(), v["time"].as_str().unwrap().to_string())
        })
        .collect()
}

#[test]
fn sigkill_of_the_live_daemon_loses_nothing_that_was_reported() {
    let dir = fresh_dir("livekill");
    let endpoint = free_endpoint();
    let text = std::fs::read_to_string(root().join("config/sinello.toml")).unwrap()
        + &format!("\n[zenoh]\nmode = \"peer\"\nlisten = [\"{endpoint}\"]\nmulticast_scouting = false\n");
    let config = dir.join("config.toml");
    std::fs::write(&config, text).unwrap();
    let cfg = splinewatch::config::load_config(&config).unwrap();
    let logger = splinewatch::config::ZenohConfig {
        mode: "client".into(),
        listen: Vec::new(),
        connect: vec![endpoint.clone()],
        ..cfg.zenoh.clone()
    };
    let blocks: Vec<_> = bundled_blocks().into_iter().map(|b| b.block).collect();
    let state = dir.join("state.json");
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(2027);
    let mut before = None;
    let (mut kills, mut saved_updates, mut warm_starts) = (0, 0, 0);
    for round in 0..6 {
        let results = dir.join(format!("results-{round}.mcap"));
        let log = dir.join(format!("daemon-{round}.log"));
        let log_file = std::fs::File::create(&log).unwrap();
        let daemon = spawn_daemon(&config, &state, &results, "info,zenoh=warn", log_file.into());
        std::thread::sleep(std::time::Duration::from_millis(1500));
        // The logger streams the recording at 20x (6 s) while the daemon is
        // killed at a random moment of it.
        let (logger, prefix, blocks) = (logger.clone(), cfg.topic_prefix(), blocks.clone());
        let publisher = std::thread::spawn(move || {
            let mut p = splinewatch::outputs::publisher::Publisher::open(
                &logger,
                prefix,
                splinewatch::io::wire::Encoding::Cbor,
                20.0,
            )
            .unwrap();
            for b in &blocks {
                p.publish(b).unwrap();
            }
            p.close().unwrap();
        });
        std::thread::sleep(std::time::Duration::from_secs_f64(rng.random_range(0.3..6.5)));
        let mut child = daemon.take();
        assert!(Command::new("kill")
            .args(["-KILL", &child.id().to_string()])
            .status()
            .unwrap()
            .success());
        let _ = child.wait();
        kills += 1;
        publisher.join().unwrap();
        let text = std::fs::read_to_string(&log).unwrap();
        if before.is_some() {
            assert!(
                text.contains("warm start from the state file"),
                "round {round}: no warm start\n{text}"
            );
            warm_starts += 1;
        }
        // (a) the state is a complete version.
        let saved = load_state(&state).unwrap_or_else(|e| panic!("round {round}: state file damaged: {e:#}"));
        // (b) the results are recoverable.
        let (_, recovered) =
            splinewatch::io::recover::recover(&std::fs::read(&results).unwrap(), std::io::Cursor::new(Vec::new()))
                .unwrap_or_else(|e| panic!("round {round}: results not recoverable: {e:#}"));
        let recovered = recovered.into_inner();
        // (c) an update this run saved in the state is in its results.
        if saved != before {
            let s = saved.clone().expect("a state once written stays");
            let updates = recovered_updates(&recovered);
            assert!(
                updates.contains(&(s.window, s.time.clone())),
                "round {round}: the state says window {} at {} was accepted; the results have {updates:?}",
                s.window,
                s.time
            );
            saved_updates += 1;
        }
        before = saved;
    }
    eprintln!("live daemon: {kills} SIGKILLs, {saved_updates} of them after a newly saved update, {warm_starts} warm restarts");
    assert!(saved_updates >= 2, "the kills should not all land before an update");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_daemons_results_never_overwrite_an_existing_file() {
    use splinewatch::outputs::results::{results_files, ResultsSink};
    let dir = fresh_dir("no-overwrite");
    // Results of an earlier run under the same name, and its first rotation.
    std::fs::write(dir.join("results.mcap"), b"earlier run").unwrap();
    std::fs::write(dir.join("results-1.mcap"), b"earlier run, rotated").unwrap();
    let mut sink = ResultsSink::new("bridge/test", results_files(&dir.join("results.mcap"))).unwrap();
    sink.write("windows", 1, &serde_json::json!({"k": 1}));
    sink.finish().expect("finished");
    assert_eq!(std::fs::read(dir.join("results.mcap")).unwrap(), b"earlier run");
    assert_eq!(
        std::fs::read(dir.join("results-1.mcap")).unwrap(),
        b"earlier run, rotated"
    );
    let new = std::fs::read(dir.join("results-2.mcap")).unwrap();
    assert!(mcap::Summary::read(&new).unwrap().is_some());
    std::fs::remove_dir_all(&dir).unwrap();
}
