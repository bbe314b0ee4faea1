//! Issue 33: alarm notifications to a webhook, over verified TLS to a real
//! HTTPS server (Python's, a child process) with a certificate of a site CA
//! made at test time.

use crate::common::fresh_dir;
use crate::security::make_test_pki;
use splinewatch::config::{Config, NotifyConfig};
use splinewatch::io::monitoring_json::StatusMessage;
use splinewatch::outputs::notify::Notifier;
use std::io::BufRead;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::sync::atomic::Ordering;

/// The webhook server on 127.0.0.1 with the site's `router` certificate
/// (valid for localhost), failing its first `fail_first` requests; its
/// child and port.
fn webhook_server(pki: &Path, log: &Path, fail_first: u32) -> (Child, u16) {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/integration/webhook_server.py");
    let mut child = Command::new("python3")
        .arg(script)
        .args(["--cert", pki.join("router.pem").to_str().unwrap()])
        .args(["--key", pki.join("router.key").to_str().unwrap()])
        .args(["--log", log.to_str().unwrap()])
        .args(["--fail-first", &fail_first.to_string()])
        .stdout(Stdio::piped())
        .spawn()
        .expect("python3 runs the webhook server");
    let mut line = String::new();
    std::io::BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    let port = line
        .trim()
        .parse()
        .unwrap_or_else(|_| panic!("the server's port, got {line:?}"));
    (child, port)
}

fn status(window: u64, state: &str) -> StatusMessage {
    serde_json::from_value(serde_json::json!({
        "window": window, "time": "2026-11-24T00:00:00Z", "state": state,
        "t2": null, "t2_limit": null, "mewma": null, "mewma_limit": null,
        "temperature_c": null, "residuals": []
    }))
    .unwrap()
}

/// Every state of `states` observed in turn, then the queue delivered.
fn notify_all(notifier: &mut Notifier, states: &[&str]) {
    for (w, state) in states.iter().enumerate() {
        let s = status(w as u64, state);
        notifier.observe(&s, &serde_json::to_vec(&s).unwrap());
    }
    notifier.finish();
}

/// The raise and clear of an alarm, and the entry into and exit from the
/// outside-range state, are POSTed to the webhook with the bearer token,
/// each once, in order; a 503 is retried. Without the site CA (the Mozilla
/// roots) the server's certificate is refused: nothing reaches it, and the
/// notification is counted as failed after its retries.
#[test]
fn a_webhook_receives_the_alarm_state_changes_over_verified_tls() {
    let dir = fresh_dir("notify-webhook");
    let pki = dir.join("pki");
    make_test_pki(&pki);
    let log = dir.join("requests.jsonl");
    let (mut server, port) = webhook_server(&pki, &log, 1);
    let token = dir.join("token");
    std::fs::write(&token, "s3cret-token\n").unwrap();
    let config = NotifyConfig {
        webhook: Some(format!("https://localhost:{port}/hooks/bridge-a")),
        bearer_token_file: Some(token.clone()),
        ca_file: Some(pki.join("ca.pem")),
        retries: 2,
        timeout_seconds: 10.0,
        ..NotifyConfig::default()
    };
    let mut notifier = Notifier::start(&config).unwrap();
    let states = [
        "training",
        "normal",
        "alarm",
        "alarm",
        "normal",
        "outside_training_range",
        "normal",
    ];
    notify_all(&mut notifier, &states);
    let counts = notifier.counts();
    assert_eq!(counts.attempts.load(Ordering::Relaxed), 5, "one retry after the 503");
    assert_eq!(counts.sent.load(Ordering::Relaxed), 4);
    assert_eq!(counts.failures.load(Ordering::Relaxed), 0);
    let requests: Vec<serde_json::Value> = std::fs::read_to_string(&log)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let seen: Vec<(u64, String, u64)> = requests
        .iter()
        .map(|r| {
            assert_eq!(r["path"], "/hooks/bridge-a");
            assert_eq!(r["authorization"], "Bearer s3cret-token");
            assert_eq!(r["content_type"], "application/json");
            let body: serde_json::Value = serde_json::from_str(r["body"].as_str().unwrap()).unwrap();
            (
                body["window"].as_u64().unwrap(),
                body["state"].as_str().unwrap().to_string(),
                r["status"].as_u64().unwrap(),
            )
        })
        .collect();
    let expected = [
        (2, "alarm", 503),
        (2, "alarm", 200),
        (4, "normal", 200),
        (5, "outside_training_range", 200),
        (6, "normal", 200),
    ];
    let expected: Vec<(u64, String, u64)> = expected.iter().map(|&(w, s, c)| (w, s.to_string(), c)).collect();
    assert_eq!(seen, expected);

    // The Mozilla roots do not know the site CA: the TLS handshake fails.
    let untrusted = NotifyConfig {
        ca_file: None,
        retries: 1,
        ..config
    };
    let mut notifier = Notifier::start(&untrusted).unwrap();
    notify_all(&mut notifier, &["alarm"]);
    let counts = notifier.counts();
    assert_eq!(counts.attempts.load(Ordering::Relaxed), 2);
    assert_eq!(counts.sent.load(Ordering::Relaxed), 0);
    assert_eq!(counts.failures.load(Ordering::Relaxed), 1);
    assert_eq!(
        std::fs::read_to_string(&log).unwrap().lines().count(),
        5,
        "nothing reached the server"
    );
    server.kill().unwrap();
    server.wait().unwrap();
}

/// Bad `[monitoring.notify]` settings are refused by name.
#[test]
fn bad_notify_settings_are_refused_by_name() {
    let base =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("config/sinello-monitoring.toml")).unwrap();
    let dir = fresh_dir("notify-config");
    let empty = dir.join("empty-token");
    std::fs::write(&empty, "\n").unwrap();
    for (section, key, says) in [
        ("retries = 2\n", "monitoring.notify", "give a command"),
        (
            "webhook = \"http://hooks.example.org/x\"\n",
            "monitoring.notify.webhook",
            "https://",
        ),
        ("webhook = \"https:///x\"\n", "monitoring.notify.webhook", "with a host"),
        (
            "command = [\"/bin/true\"]\nca_file = \"ca.pem\"\n",
            "monitoring.notify",
            "are for a webhook",
        ),
        (
            &format!(
                "webhook = \"https://h.example.org/x\"\nbearer_token_file = {:?}\n",
                empty.to_str().unwrap()
            ),
            "monitoring.notify.bearer_token_file",
            "holds no token",
        ),
        (
            "webhook = \"https://h.example.org/x\"\nca_file = \"/nonexistent/ca.pem\"\n",
            "monitoring.notify.ca_file",
            "/nonexistent/ca.pem",
        ),
    ] {
        let text = format!("{base}\n[monitoring.notify]\n{section}");
        let e = Config::from_toml(&text)
            .and_then(|c| c.validate())
            .unwrap_err()
            .to_string();
        assert!(e.contains(key) && e.contains(says), "{section}: {e}");
    }
}
