//! Issue 33: alarm notifications to a webhook, over verified TLS to a real
//! HTTPS server (rustls on a loopback socket, in a thread) with a
//! certificate of a CA made at test time (rcgen).

use crate::common::fresh_dir;
use splinewatch::config::{Config, NotifyConfig};
use splinewatch::io::monitoring_json::StatusMessage;
use splinewatch::outputs::notify::Notifier;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpListener;
use std::path::Path;
use std::sync::atomic::Ordering;
use std::sync::{Arc, Mutex};

/// One request the server received: path, Authorization and Content-Type
/// headers, the status it answered, the body.
#[derive(Debug, Clone)]
struct Received {
    path: String,
    authorization: Option<String>,
    content_type: Option<String>,
    status: u16,
    body: String,
}

/// A site CA and a server certificate for localhost and 127.0.0.1: the CA's
/// PEM is written to `ca_pem`; the server's TLS configuration is returned.
fn site_pki(ca_pem: &Path) -> Arc<rustls::ServerConfig> {
    use rcgen::{BasicConstraints, CertificateParams, CertifiedIssuer, DnType, IsCa, KeyPair, KeyUsagePurpose};
    use rustls::pki_types::{CertificateDer, PrivateKeyDer, PrivatePkcs8KeyDer};
    let mut ca = CertificateParams::new(Vec::<String>::new()).unwrap();
    ca.is_ca = IsCa::Ca(BasicConstraints::Unconstrained);
    ca.distinguished_name
        .push(DnType::CommonName, "splinewatch webhook test CA");
    ca.key_usages = vec![KeyUsagePurpose::KeyCertSign, KeyUsagePurpose::CrlSign];
    let issuer = CertifiedIssuer::self_signed(ca, KeyPair::generate().unwrap()).unwrap();
    std::fs::write(ca_pem, issuer.pem()).unwrap();
    let mut leaf = CertificateParams::new(vec!["localhost".to_string(), "127.0.0.1".to_string()]).unwrap();
    leaf.distinguished_name.push(DnType::CommonName, "hooks");
    let key = KeyPair::generate().unwrap();
    let cert = leaf.signed_by(&key, &issuer).unwrap();
    let provider = Arc::new(rustls::crypto::ring::default_provider());
    let config = rustls::ServerConfig::builder_with_provider(provider)
        .with_safe_default_protocol_versions()
        .unwrap()
        .with_no_client_auth()
        .with_single_cert(
            vec![CertificateDer::from(cert.der().to_vec())],
            PrivateKeyDer::Pkcs8(PrivatePkcs8KeyDer::from(key.serialize_der())),
        )
        .unwrap();
    Arc::new(config)
}

/// An HTTPS server on 127.0.0.1 (a thread that lives as long as the test
/// process): one request per connection, the first `fail_first` answered
/// 503, the rest 200. Its port and what it received.
fn webhook_server(tls: Arc<rustls::ServerConfig>, fail_first: usize) -> (u16, Arc<Mutex<Vec<Received>>>) {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let port = listener.local_addr().unwrap().port();
    let received = Arc::new(Mutex::new(Vec::new()));
    let log = Arc::clone(&received);
    std::thread::spawn(move || {
        for stream in listener.incoming().flatten() {
            let connection = rustls::ServerConnection::new(Arc::clone(&tls)).unwrap();
            // A client that refuses the certificate ends the handshake: no request.
            let _ = serve(rustls::StreamOwned::new(connection, stream), &log, fail_first);
        }
    });
    (port, received)
}

/// Reads one HTTP/1.1 request, records it and answers.
fn serve(
    stream: rustls::StreamOwned<rustls::ServerConnection, std::net::TcpStream>,
    log: &Mutex<Vec<Received>>,
    fail_first: usize,
) -> std::io::Result<()> {
    let mut reader = BufReader::new(stream);
    let mut line = String::new();
    reader.read_line(&mut line)?;
    let path = line.split_whitespace().nth(1).unwrap_or_default().to_string();
    let (mut length, mut authorization, mut content_type) = (0, None, None);
    loop {
        line.clear();
        reader.read_line(&mut line)?;
        let header = line.trim_end();
        if header.is_empty() {
            break;
        }
        if let Some((name, value)) = header.split_once(':') {
            let value = value.trim().to_string();
            match name.to_ascii_lowercase().as_str() {
                "content-length" => length = value.parse().unwrap_or(0),
                "authorization" => authorization = Some(value),
                "content-type" => content_type = Some(value),
                _ => {}
            }
        }
    }
    let mut body = vec![0; length];
    reader.read_exact(&mut body)?;
    let mut log = log.lock().unwrap();
    let status = if log.len() < fail_first { 503 } else { 200 };
    log.push(Received {
        path,
        authorization,
        content_type,
        status,
        body: String::from_utf8_lossy(&body).into_owned(),
    });
    drop(log);
    let mut stream = reader.into_inner();
    let reason = if status == 200 { "OK" } else { "Service Unavailable" };
    write!(
        stream,
        "HTTP/1.1 {status} {reason}\r\nContent-Length: 0\r\nConnection: close\r\n\r\n"
    )?;
    stream.flush()?;
    stream.conn.send_close_notify();
    stream.flush()
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
        let json = serde_json::to_vec(&s).unwrap();
        notifier.record("monitoring/status", &json);
        notifier.observe(&s, &json);
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
    let (port, received) = webhook_server(site_pki(&dir.join("ca.pem")), 1);
    let token = dir.join("token");
    std::fs::write(&token, "s3cret-token\n").unwrap();
    let config = NotifyConfig {
        webhook: Some(format!("https://localhost:{port}/hooks/bridge-a")),
        bearer_token_file: Some(token.clone()),
        ca_file: Some(dir.join("ca.pem")),
        retries: 2,
        timeout_seconds: 10.0,
        ..NotifyConfig::default()
    };
    // The notifier of a config (the bundled monitoring example's, with this
    // webhook): its notifications carry the owner's report.
    let mut site =
        splinewatch::config::load_config(&Path::new(env!("CARGO_MANIFEST_DIR")).join("config/sinello-monitoring.toml"))
            .unwrap();
    site.monitoring.as_mut().unwrap().notify = Some(config.clone());
    let mut notifier = Notifier::for_config(&site, None).unwrap().unwrap();
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
    let requests = received.lock().unwrap().clone();
    let seen: Vec<(u64, String, u64)> = requests
        .iter()
        .map(|r| {
            assert_eq!(r.path, "/hooks/bridge-a");
            assert_eq!(r.authorization.as_deref(), Some("Bearer s3cret-token"));
            assert_eq!(r.content_type.as_deref(), Some("application/json"));
            let body: serde_json::Value = serde_json::from_str(&r.body).unwrap();
            // The report of what the run wrote, its verdict line the subject.
            let subject = body["subject"].as_str().unwrap();
            assert!(subject.starts_with("sinello-span2-monitoring: "), "{subject}");
            let html = body["report_html"].as_str().unwrap();
            assert!(html.starts_with("<!DOCTYPE html>") && html.contains("id=\"verdict\""));
            if body["state"] == "alarm" {
                assert!(subject.contains("High: inspect: In alarm since"), "{subject}");
            }
            (
                body["window"].as_u64().unwrap(),
                body["state"].as_str().unwrap().to_string(),
                u64::from(r.status),
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
    assert_eq!(received.lock().unwrap().len(), 5, "nothing reached the server");
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
