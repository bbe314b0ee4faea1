//! Fault injection: SIGKILL at seeded random moments of a replay with a
//! state file. After every kill the state file is the old or the new
//! complete version, the results MCAP is recoverable, and the recovered
//! results hold every update the state file says was accepted.

#![cfg(unix)]

use rand::{Rng, SeedableRng};
use splinewatch::results::load_state;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::Instant;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn sigkill_during_replay_loses_nothing_that_was_reported() {
    let dir = std::env::temp_dir().join(format!("splinewatch-kill-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
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
            splinewatch::recover::recover(&bytes, std::io::Cursor::new(Vec::new())).expect("recoverable");
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
