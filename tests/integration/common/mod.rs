//! Helpers shared by the integration tests that run real zenoh sessions
//! and `splinewatch` processes.

#![allow(dead_code)] // each test crate uses its own subset

/// A free loopback TCP endpoint.
pub fn free_endpoint() -> String {
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    format!("tcp/127.0.0.1:{port}")
}

/// Kills a child process when a failing test unwinds past it.
pub struct KillOnDrop(pub Option<std::process::Child>);

impl KillOnDrop {
    pub fn take(mut self) -> std::process::Child {
        self.0.take().expect("taken once")
    }
}

impl Drop for KillOnDrop {
    fn drop(&mut self) {
        if let Some(child) = self.0.as_mut() {
            let _ = child.kill();
            let _ = child.wait();
        }
    }
}

/// `splinewatch run --config … --state … --out …` with `RUST_LOG` set and
/// its log going to `log` (a file, or a pipe the test reads at the end).
pub fn spawn_daemon(
    config: &std::path::Path,
    state: &std::path::Path,
    results: &std::path::Path,
    rust_log: &str,
    log: std::process::Stdio,
) -> KillOnDrop {
    KillOnDrop(Some(
        std::process::Command::new(env!("CARGO_BIN_EXE_splinewatch"))
            .arg("run")
            .arg("--config")
            .arg(config)
            .arg("--state")
            .arg(state)
            .arg("--out")
            .arg(results)
            .env("RUST_LOG", rust_log)
            .stdout(std::process::Stdio::null())
            .stderr(log)
            .spawn()
            .unwrap(),
    ))
}

/// The blocks of the bundled recording, in file order.
/// Simulates into an in-memory MCAP file.
pub fn simulated_recording(
    cfg: &splinewatch::config::Config,
    options: &splinewatch::studies::simulation::SimulationOptions,
    encoding: splinewatch::io::wire::Encoding,
) -> Vec<u8> {
    let mut writer =
        splinewatch::io::recording::RecordingWriter::new(std::io::Cursor::new(Vec::new()), encoding).unwrap();
    let prefix = cfg.topic_prefix();
    splinewatch::studies::simulation::simulate(cfg, options, &mut |b| writer.write_block(&prefix, &b).map(|_| ()))
        .unwrap();
    writer.finish().unwrap().into_inner()
}

pub fn bundled_blocks() -> Vec<splinewatch::io::recording::RecordedBlock> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("recordings/sinello-demo.mcap");
    let bytes = std::fs::read(path).unwrap();
    splinewatch::io::recording::read_recording(&bytes, &Default::default())
        .unwrap()
        .0
}

/// Publishes the bundled recording, at 20× real time, to the daemon that
/// listens where the config at `config` says (a zenoh client of its
/// `listen` endpoints).
pub fn publish_bundled_to(config: &std::path::Path) {
    let cfg = splinewatch::config::load_config(config).unwrap();
    let mut z = cfg.zenoh.clone();
    z.connect = std::mem::take(&mut z.listen);
    z.mode = "client".into();
    publish_bundled(&z, cfg.topic_prefix());
}

/// Publishes the bundled recording, at 20× real time, on a session of `zenoh`.
pub fn publish_bundled(zenoh: &splinewatch::config::ZenohConfig, prefix: String) {
    let mut publisher =
        splinewatch::outputs::publisher::Publisher::open(zenoh, prefix, splinewatch::io::wire::Encoding::Cbor, 20.0)
            .unwrap();
    // Let the session connect before the first block.
    std::thread::sleep(std::time::Duration::from_millis(500));
    for b in &bundled_blocks() {
        publisher.publish(&b.block).unwrap();
    }
    publisher.close().unwrap();
}

/// Sends SIGTERM to `child` and waits for it: its exit status and what it
/// wrote to its stderr, if that was piped.
pub fn terminate(child: std::process::Child) -> (std::process::ExitStatus, String) {
    let signalled = std::process::Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(signalled.success());
    let out = child.wait_with_output().unwrap();
    (out.status, String::from_utf8_lossy(&out.stderr).into_owned())
}

/// Waits up to a minute for `path` to appear; whether it did.
pub fn wait_for_file(path: &std::path::Path) -> bool {
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(60);
    while !path.exists() && std::time::Instant::now() < deadline {
        std::thread::sleep(std::time::Duration::from_millis(100));
    }
    path.exists()
}

/// An empty folder `splinewatch-<name>-…` under the system temp folder,
/// removed with everything in it when dropped (tempfile): the tests leave
/// nothing behind. It derefs to its path.
pub fn fresh_dir(name: &str) -> TestDir {
    TestDir(
        tempfile::Builder::new()
            .prefix(&format!("splinewatch-{name}-"))
            .tempdir()
            .unwrap(),
    )
}

/// A test's temporary folder (see [`fresh_dir`]).
pub struct TestDir(tempfile::TempDir);

impl std::ops::Deref for TestDir {
    type Target = std::path::Path;

    fn deref(&self) -> &std::path::Path {
        self.0.path()
    }
}

impl AsRef<std::path::Path> for TestDir {
    fn as_ref(&self) -> &std::path::Path {
        self.0.path()
    }
}

/// Runs the `splinewatch` binary in the repository root and waits for it.
pub fn splinewatch(args: &[&str]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_splinewatch"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("the binary runs")
}

/// The entry named `name` of a `parameters` array (`update --json`, an
/// `updating/parameters` message, a state file).
pub fn parameter<'a>(parameters: &'a serde_json::Value, name: &str) -> &'a serde_json::Value {
    parameters
        .as_array()
        .expect("a parameters array")
        .iter()
        .find(|p| p["name"] == name)
        .unwrap_or_else(|| panic!("no parameter {name} in {parameters}"))
}

/// The JSON messages of a results file by topic suffix (what follows
/// `bridge/<structure>/`), in file order.
pub fn results_by_topic(bytes: &[u8]) -> std::collections::BTreeMap<String, Vec<serde_json::Value>> {
    let mut out: std::collections::BTreeMap<String, Vec<serde_json::Value>> = Default::default();
    for m in mcap::MessageStream::new(bytes).expect("an MCAP file") {
        let m = m.expect("a readable message");
        let suffix = m.channel.topic.splitn(3, '/').nth(2).unwrap_or_default().to_string();
        out.entry(suffix)
            .or_default()
            .push(serde_json::from_slice(&m.data).expect("a JSON message"));
    }
    out
}

/// A scenario in `dir/loss.toml` where `east.k2` loses 40 % between
/// `start` and `end` minutes (negative: before the record), re-solved every
/// `update_seconds`.
pub fn loss_scenario(dir: &std::path::Path, start: f64, end: f64, update_seconds: f64) -> std::path::PathBuf {
    let path = dir.join("loss.toml");
    std::fs::write(
        &path,
        format!(
            "update_seconds = {update_seconds}\n[[change]]\nparameter = \"east.k2\"\nstart_minute = {start}\nend_minute = {end}\nfactor = 0.6\n"
        ),
    )
    .unwrap();
    path
}

/// A committed Painter Street record (`tests/fixtures/painter-street`).
pub fn painter_street_record(name: &str) -> String {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/painter-street")
        .join(name)
        .to_str()
        .unwrap()
        .to_string()
}

/// One JSON value per line of a command's output (`--json` streams).
pub fn json_lines(stdout: &[u8]) -> Vec<serde_json::Value> {
    String::from_utf8_lossy(stdout)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

/// The Rerun file at `path`, read back with Rerun's own decoder: it has
/// its footer, holds every one of `entities`, and no `/deck` entity (a
/// recording of a config without a model).
pub fn assert_rrd_without_deck(path: &std::path::Path, entities: &[&str]) {
    let summary = splinewatch::outputs::rerun::inspect_rrd(&std::fs::read(path).unwrap()).unwrap();
    for entity in entities {
        assert!(summary.entities.contains(*entity), "{entity} in {:?}", summary.entities);
    }
    assert!(
        !summary.entities.iter().any(|e| e.starts_with("/deck")),
        "{:?}",
        summary.entities
    );
    assert!(summary.footer, "{} has no footer", path.display());
}

/// `lines` against the JSON lines on record in `tests/fixtures/<name>`:
/// the same keys, strings and booleans, and every number within 1e-6 of
/// it relative (1e-12 absolute), so that a change meant to keep behaviour
/// shows it did (on another CPU's vector width the last bits may differ).
/// `SPLINEWATCH_BLESS=1` writes the record instead, after a change of the
/// numerics that was meant.
pub fn assert_matches_record(name: &str, lines: &[serde_json::Value]) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name);
    if std::env::var("SPLINEWATCH_BLESS").is_ok_and(|v| v == "1") {
        let text: String = lines.iter().map(|l| format!("{l}\n")).collect();
        std::fs::write(&path, text).unwrap();
        return;
    }
    let recorded = json_lines(&std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display())));
    assert_eq!(recorded.len(), lines.len(), "{}: the number of lines", path.display());
    for (k, (was, now)) in recorded.iter().zip(lines).enumerate() {
        if let Some(at) = first_difference(was, now, String::new()) {
            panic!(
                "{} line {}: {at} differs from the record (SPLINEWATCH_BLESS=1 rewrites it after a change meant to move the numerics)",
                path.display(),
                k + 1
            );
        }
    }
}

/// Where `now` first differs from `was` (a JSON path), numbers compared
/// as [`assert_matches_record`] says.
fn first_difference(was: &serde_json::Value, now: &serde_json::Value, at: String) -> Option<String> {
    use serde_json::Value;
    match (was, now) {
        (Value::Number(a), Value::Number(b)) => {
            let (a, b) = (a.as_f64()?, b.as_f64()?);
            ((a - b).abs() > 1e-12 + 1e-6 * a.abs().max(b.abs())).then(|| format!("{at}: {a} then, {b} now"))
        }
        (Value::Array(a), Value::Array(b)) if a.len() == b.len() => a
            .iter()
            .zip(b)
            .enumerate()
            .find_map(|(i, (x, y))| first_difference(x, y, format!("{at}[{i}]"))),
        (Value::Object(a), Value::Object(b)) if a.len() == b.len() => a.iter().find_map(|(key, x)| match b.get(key) {
            Some(y) => first_difference(x, y, format!("{at}.{key}")),
            None => Some(format!("{at}.{key}: gone")),
        }),
        _ => (was != now).then(|| format!("{at}: {was} then, {now} now")),
    }
}
