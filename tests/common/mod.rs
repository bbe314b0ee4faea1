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
