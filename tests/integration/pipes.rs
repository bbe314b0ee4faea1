//! A closed stdout or stderr never takes the work down: `replay`, `demo` and
//! `run` whose pipes are closed before they write a line finish their work,
//! exit 0 and leave finalised files; a replay's results are byte-identical
//! to those of a run with open pipes. (Before, `demo 2>&1 | head -3` aborted
//! and left an unreadable results file, `replay | head -2` exited 101.)

use crate::common::{free_endpoint, publish_bundled_to, wait_for_file};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn splinewatch() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_splinewatch"));
    c.current_dir(root()).env("RUST_LOG", "info,zenoh=warn");
    c
}

/// Starts `cmd` with stdout and stderr pipes whose read ends are closed at
/// once: every write the process makes to either fails (EPIPE).
fn with_closed_pipes(cmd: &mut Command) -> Child {
    let mut child = cmd.stdout(Stdio::piped()).stderr(Stdio::piped()).spawn().unwrap();
    drop(child.stdout.take());
    drop(child.stderr.take());
    child
}

/// The message count of a finalised MCAP file (its summary must be there).
fn finalised_messages(path: &Path) -> u64 {
    let bytes = std::fs::read(path).unwrap();
    let summary = mcap::Summary::read(&bytes)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .unwrap_or_else(|| panic!("{} has no summary: not finalised", path.display()));
    summary.stats.expect("statistics").message_count
}

#[test]
fn a_replay_with_closed_pipes_writes_the_same_results() {
    let dir = tempfile::tempdir().unwrap();
    let replay = |out: &PathBuf| {
        let mut c = splinewatch();
        c.args([
            "replay",
            "--config",
            "config/sinello.toml",
            "recordings/sinello-demo.mcap",
            "--out",
        ])
        .arg(out);
        c
    };
    let normal = dir.path().join("normal.mcap");
    let output = replay(&normal).output().unwrap();
    assert!(output.status.success(), "{}", String::from_utf8_lossy(&output.stderr));
    assert!(!output.stdout.is_empty(), "the parameter table goes to stdout");
    let closed = dir.path().join("closed.mcap");
    let status = with_closed_pipes(&mut replay(&closed)).wait().unwrap();
    assert!(status.success(), "{status}");
    assert!(finalised_messages(&closed) > 0);
    assert!(
        std::fs::read(&normal).unwrap() == std::fs::read(&closed).unwrap(),
        "the results differ"
    );
}

/// Also: a second demo in the same folder starts fresh (no warm start from
/// the first one's state, no `results-1.mcap`) and prints the paths it wrote.
#[test]
fn a_demo_with_closed_pipes_finishes_and_leaves_valid_files() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("demo");
    let demo = || {
        let mut c = splinewatch();
        c.args(["demo", "--duration", "60", "--speed", "40", "--out"]).arg(&out);
        c
    };
    let first = demo().output().unwrap();
    let log = String::from_utf8_lossy(&first.stderr);
    assert!(first.status.success(), "{log}");
    assert!(
        log.contains(&out.join("results.mcap").display().to_string())
            && log.contains(&out.join("report.html").display().to_string()),
        "{log}"
    );
    let status = with_closed_pipes(&mut demo()).wait().unwrap();
    assert!(status.success(), "{status}");
    let mut files: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    files.sort();
    assert_eq!(files, ["report.html", "results.mcap", "results.rrd", "state.json"]);
    assert!(finalised_messages(&out.join("results.mcap")) > 0);
    let state = splinewatch::outputs::state::load_state(&out.join("state.json"))
        .unwrap()
        .expect("an update was accepted");
    assert!(!state.parameters.is_empty());
    let rrd = splinewatch::outputs::rerun::inspect_rrd(&std::fs::read(out.join("results.rrd")).unwrap()).unwrap();
    assert!(rrd.footer, "the .rrd was not closed");
}

#[cfg(unix)]
#[test]
fn a_daemon_with_closed_pipes_keeps_working_and_stops_cleanly() {
    let dir = tempfile::tempdir().unwrap();
    let endpoint = free_endpoint();
    let text = std::fs::read_to_string(root().join("config/sinello.toml")).unwrap()
        + &format!("\n[zenoh]\nmode = \"peer\"\nlisten = [\"{endpoint}\"]\nmulticast_scouting = false\n");
    let config = dir.path().join("config.toml");
    std::fs::write(&config, text).unwrap();
    let (state, results) = (dir.path().join("state.json"), dir.path().join("results.mcap"));
    let daemon = with_closed_pipes(
        splinewatch()
            .arg("run")
            .arg("--config")
            .arg(&config)
            .arg("--state")
            .arg(&state)
            .arg("--out")
            .arg(&results),
    );
    std::thread::sleep(std::time::Duration::from_millis(1500));
    publish_bundled_to(&config);
    assert!(wait_for_file(&state), "no update was saved");
    let signalled = Command::new("kill")
        .args(["-TERM", &daemon.id().to_string()])
        .status()
        .unwrap();
    assert!(signalled.success());
    let out = daemon.wait_with_output().unwrap();
    assert!(out.status.success(), "{}", out.status);
    assert!(finalised_messages(&results) > 0);
}
