//! Alarm notifications (`[monitoring.notify]`): a command run with the
//! monitoring status JSON on its standard input, and/or a webhook the JSON
//! is POSTed to (ureq over rustls, the server's certificate verified against
//! the Mozilla roots or the configured CA, an optional bearer token),
//! whenever the alarm state changes: an alarm raised or cleared, or a
//! window outside the training range entered or left.
//!
//! A notifier made for a config ([`Notifier::for_config`]) also carries
//! the owner's report (`splinewatch report` of what this run has written,
//! [`History`]): the command gets its subject line in `SPLINEWATCH_SUBJECT`
//! and the HTML file's path in `SPLINEWATCH_REPORT` (removed after the
//! delivery), the webhook's JSON the `subject` and `report_html` keys.
//!
//! Deliveries run on a thread of their own behind a bounded queue, so the
//! pipeline never waits for them; a target that fails (non-zero exit, no
//! start, a refused connection or certificate, a non-2xx answer, over its
//! time limit) is tried again after 0.5, 1, 2, … s up to `retries` times.
//! Every attempt, delivery and failure is counted per target
//! ([`NotifyCounts`], on the health topic).

use crate::config::NotifyConfig;
use crate::io::monitoring_json::StatusMessage;
use crate::outputs::report::history::History;
use crate::pipeline::Health;
use std::io::Write;
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{sync_channel, SyncSender, TrySendError};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Statuses waiting for delivery; beyond, a notification is counted as
/// failed at once rather than hold up the pipeline.
const QUEUE: usize = 64;

/// States whose entry or exit is notified.
const NOTIFIED: [&str; 2] = ["alarm", "outside_training_range"];

/// What the notifier did so far.
#[derive(Debug, Default)]
pub struct NotifyCounts {
    /// Command runs and webhook requests, retries included.
    pub attempts: AtomicU64,
    /// Notifications a target accepted (exit status 0, a 2xx answer), one
    /// per target.
    pub sent: AtomicU64,
    /// Notifications a target was given up on after every retry, or
    /// dropped on a full queue.
    pub failures: AtomicU64,
}

/// The owner's report a notification carries: its subject line (the
/// bridge, the priority and the verdict) and the page.
#[derive(Debug, Clone)]
pub struct Attachment {
    pub subject: String,
    pub html: String,
}

/// One notification: the status JSON and, when there is one, the report.
struct Delivery {
    status: Vec<u8>,
    report: Option<Attachment>,
}

/// Sends status changes to the configured command.
pub struct Notifier {
    queue: Option<SyncSender<Delivery>>,
    worker: Option<std::thread::JoinHandle<()>>,
    counts: Arc<NotifyCounts>,
    previous: Option<String>,
    history: Option<History>,
}

impl Notifier {
    /// Starts the delivery thread.
    pub fn start(config: &NotifyConfig) -> std::io::Result<Self> {
        let (queue, received) = sync_channel::<Delivery>(QUEUE);
        let counts = Arc::new(NotifyCounts::default());
        let (config, shared) = (config.clone(), Arc::clone(&counts));
        let agent = config
            .webhook
            .is_some()
            .then(|| webhook_agent(&config))
            .transpose()
            .map_err(std::io::Error::other)?;
        let worker = std::thread::Builder::new().name("notify".into()).spawn(move || {
            for (n, delivery) in received.into_iter().enumerate() {
                deliver(&config, agent.as_ref(), &delivery, n, &shared);
            }
        })?;
        Ok(Self {
            queue: Some(queue),
            worker: Some(worker),
            counts,
            previous: None,
            history: None,
        })
    }

    /// The notifier `[monitoring.notify]` of `config` asks for, if any. Its
    /// notifications carry the report of `history` when given (one the
    /// caller also records into and shares, e.g. with the status page),
    /// else of a history of its own.
    pub fn for_config(config: &crate::config::Config, history: Option<History>) -> std::io::Result<Option<Self>> {
        config
            .monitoring
            .as_ref()
            .and_then(|m| m.notify.as_ref())
            .map(|notify| {
                Self::start(notify).map(|mut n| {
                    n.history = Some(history.unwrap_or_else(|| History::new(config)));
                    n
                })
            })
            .transpose()
    }

    /// Keeps a results message this run wrote, for the report a later
    /// notification carries.
    pub fn record(&self, suffix: &str, json: &[u8]) {
        if let Some(h) = &self.history {
            h.record(suffix, json);
        }
    }

    /// Takes a scored window's status (and its JSON): queues it when the
    /// state changed into or out of an alarm or the outside-range state
    /// (the first status when it is one of those).
    pub fn observe(&mut self, status: &StatusMessage, json: &[u8]) {
        let previous = self.previous.replace(status.state.clone());
        if previous.as_deref() == Some(status.state.as_str()) {
            return;
        }
        let notified = |s: &str| NOTIFIED.contains(&s);
        if !(notified(&status.state) || previous.as_deref().is_some_and(notified)) {
            return;
        }
        let report = self.history.as_ref().and_then(History::report).map(|r| Attachment {
            subject: format!("{}: {}: {}", r.bridge, r.priority.label(), r.verdict),
            html: r.html,
        });
        let Some(queue) = &self.queue else { return };
        let delivery = Delivery {
            status: json.to_vec(),
            report,
        };
        if let Err(TrySendError::Full(_) | TrySendError::Disconnected(_)) = queue.try_send(delivery) {
            self.counts.failures.fetch_add(1, Ordering::Relaxed);
            tracing::warn!(
                message = "notification dropped: the notify queue is full",
                window = status.window
            );
        }
    }

    /// The counts so far.
    pub fn counts(&self) -> &NotifyCounts {
        &self.counts
    }

    /// Copies the counts into `health`.
    pub fn count_into(&self, health: &mut Health) {
        health.notification_attempts = self.counts.attempts.load(Ordering::Relaxed);
        health.notifications_sent = self.counts.sent.load(Ordering::Relaxed);
        health.notification_failures = self.counts.failures.load(Ordering::Relaxed);
    }

    /// Delivers what is queued (with its retries), then stops.
    pub fn finish(&mut self) {
        self.queue = None;
        if let Some(worker) = self.worker.take() {
            if worker.join().is_err() {
                tracing::error!(message = "the notify thread panicked");
            }
        }
    }
}

impl Drop for Notifier {
    fn drop(&mut self) {
        self.finish();
    }
}

/// Delivers one notification to every target: the command (the report in
/// a file of its own for the run, removed after), then the webhook (the
/// report in the JSON). `n` numbers the process's notifications.
fn deliver(config: &NotifyConfig, agent: Option<&ureq::Agent>, delivery: &Delivery, n: usize, counts: &NotifyCounts) {
    if !config.command.is_empty() {
        let report = delivery.report.as_ref().and_then(|r| {
            let path = std::env::temp_dir().join(format!("splinewatch-report-{}-{n}.html", std::process::id()));
            match crate::io::files::create_output_file(&path).and_then(|mut f| Ok(f.write_all(r.html.as_bytes())?)) {
                Ok(()) => Some((path, r.subject.as_str())),
                Err(e) => {
                    tracing::warn!(message = "the report could not be written for the notify command", error = %format!("{e:#}"));
                    None
                }
            }
        });
        let env = report.as_ref().map(|(path, subject)| (path.as_path(), *subject));
        deliver_to(config, "command", counts, || run_once(config, &delivery.status, env));
        if let Some((path, _)) = report {
            let _ = std::fs::remove_file(path);
        }
    }
    if let (Some(url), Some(agent)) = (&config.webhook, agent) {
        let body = with_report(&delivery.status, delivery.report.as_ref());
        deliver_to(config, "webhook", counts, || post_once(config, agent, url, &body));
    }
}

/// The status JSON with the report's `subject` and `report_html` keys.
fn with_report(status: &[u8], report: Option<&Attachment>) -> Vec<u8> {
    let Some(report) = report else {
        return status.to_vec();
    };
    match serde_json::from_slice::<serde_json::Value>(status) {
        Ok(serde_json::Value::Object(mut fields)) => {
            fields.insert("subject".into(), report.subject.clone().into());
            fields.insert("report_html".into(), report.html.clone().into());
            serde_json::to_vec(&fields).unwrap_or_else(|_| status.to_vec())
        }
        _ => status.to_vec(),
    }
}

/// Tries `once` until it succeeds or the retries are spent.
fn deliver_to(
    config: &NotifyConfig,
    target: &str,
    counts: &NotifyCounts,
    mut once: impl FnMut() -> Result<(), String>,
) {
    for attempt in 0..=config.retries {
        if attempt > 0 {
            std::thread::sleep(Duration::from_millis(500 << (attempt - 1).min(6)));
        }
        counts.attempts.fetch_add(1, Ordering::Relaxed);
        match once() {
            Ok(()) => {
                counts.sent.fetch_add(1, Ordering::Relaxed);
                return;
            }
            Err(reason) => tracing::warn!(message = "notification failed", target, attempt = attempt + 1, %reason),
        }
    }
    counts.failures.fetch_add(1, Ordering::Relaxed);
    tracing::error!(message = "notification given up", target, attempts = config.retries + 1);
}

/// The webhook's HTTP client: TLS verified against the Mozilla roots or
/// the `ca_file`'s certificates, https only, no redirect followed (a POST
/// is not re-sent elsewhere), every request within `timeout_seconds`.
fn webhook_agent(config: &NotifyConfig) -> Result<ureq::Agent, String> {
    use ureq::tls::{parse_pem, PemItem, RootCerts, TlsConfig};
    let mut tls = TlsConfig::builder();
    if let Some(path) = &config.ca_file {
        let pem = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
        let certificates: Vec<_> = parse_pem(&pem)
            .filter_map(|item| match item {
                Ok(PemItem::Certificate(c)) => Some(c),
                _ => None,
            })
            .collect();
        if certificates.is_empty() {
            return Err(format!("{}: no PEM certificate in it", path.display()));
        }
        tls = tls.root_certs(RootCerts::Specific(Arc::new(certificates)));
    }
    Ok(ureq::Agent::config_builder()
        .tls_config(tls.build())
        .https_only(true)
        .max_redirects(0)
        .timeout_global(Some(Duration::from_secs_f64(config.timeout_seconds)))
        .build()
        .into())
}

/// One POST of `status` to the webhook. The log names the host only: a
/// webhook URL often carries its secret in the path.
fn post_once(config: &NotifyConfig, agent: &ureq::Agent, url: &str, status: &[u8]) -> Result<(), String> {
    let host = url.split('/').nth(2).unwrap_or(url);
    let mut request = agent.post(url).header("Content-Type", "application/json");
    if let Some(path) = &config.bearer_token_file {
        request = request.header("Authorization", format!("Bearer {}", config.bearer_token(path)?));
    }
    match request.send(status) {
        Ok(_) => Ok(()),
        Err(ureq::Error::StatusCode(code)) => Err(format!("{host} answered {code}")),
        Err(e) => Err(format!("{host}: {e}")),
    }
}

/// One run of the command, with the report's path and subject in its
/// environment when there is one: `Err` says why it did not succeed.
fn run_once(config: &NotifyConfig, status: &[u8], report: Option<(&std::path::Path, &str)>) -> Result<(), String> {
    let (program, args) = config.command.split_first().ok_or("no command")?;
    let mut command = Command::new(program);
    if let Some((path, subject)) = report {
        command
            .env("SPLINEWATCH_REPORT", path)
            .env("SPLINEWATCH_SUBJECT", subject);
    }
    let mut child = command
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .map_err(|e| format!("cannot start {program}: {e}"))?;
    if let Some(mut stdin) = child.stdin.take() {
        // A command that exits without reading is judged by its status.
        let _ = stdin.write_all(status).and_then(|()| stdin.write_all(b"\n"));
    }
    let deadline = Instant::now() + Duration::from_secs_f64(config.timeout_seconds);
    loop {
        match child.try_wait() {
            Ok(Some(s)) if s.success() => return Ok(()),
            Ok(Some(s)) => return Err(format!("{program} exited with {s}")),
            Ok(None) if Instant::now() >= deadline => {
                let _ = child.kill();
                let _ = child.wait();
                return Err(format!("{program} ran over {} s", config.timeout_seconds));
            }
            Ok(None) => std::thread::sleep(Duration::from_millis(20)),
            Err(e) => return Err(format!("waiting for {program}: {e}")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn status(window: u64, state: &str) -> StatusMessage {
        serde_json::from_value(serde_json::json!({
            "window": window, "time": "2026-11-24T00:00:00Z", "state": state,
            "t2": null, "t2_limit": null, "mewma": null, "mewma_limit": null,
            "temperature_c": null, "residuals": []
        }))
        .unwrap()
    }

    /// A real command (`sh`) receives the raise and the clear of an alarm
    /// and the entry into the outside-range state, one status JSON per run,
    /// and nothing for windows whose state did not change; a failing
    /// command is tried `retries + 1` times and counted as a failure.
    #[test]
    fn a_command_receives_the_alarm_state_changes() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("received.jsonl");
        let config = NotifyConfig {
            command: vec!["sh".into(), "-c".into(), format!("cat >> '{}'", file.display())],
            retries: 2,
            timeout_seconds: 10.0,
            ..NotifyConfig::default()
        };
        let mut notifier = Notifier::start(&config).unwrap();
        let states = [
            "training",
            "normal",
            "normal",
            "alarm",
            "alarm",
            "normal",
            "outside_training_range",
            "normal",
        ];
        for (w, state) in states.iter().enumerate() {
            let s = status(w as u64, state);
            notifier.observe(&s, &serde_json::to_vec(&s).unwrap());
        }
        notifier.finish();
        let received: Vec<serde_json::Value> = std::fs::read_to_string(&file)
            .unwrap()
            .lines()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect();
        let seen: Vec<(u64, &str)> = received
            .iter()
            .map(|v| (v["window"].as_u64().unwrap(), v["state"].as_str().unwrap()))
            .collect();
        assert_eq!(
            seen,
            [
                (3, "alarm"),
                (5, "normal"),
                (6, "outside_training_range"),
                (7, "normal")
            ]
        );
        let counts = notifier.counts();
        assert_eq!(counts.sent.load(Ordering::Relaxed), 4);
        assert_eq!(counts.attempts.load(Ordering::Relaxed), 4);
        // Without a config's history (`Notifier::start`), no report: the
        // command's environment has none.
        assert!(received.iter().all(|v| v.get("subject").is_none()));

        let failing = NotifyConfig {
            command: vec!["sh".into(), "-c".into(), "exit 3".into()],
            retries: 2,
            timeout_seconds: 10.0,
            ..NotifyConfig::default()
        };
        let mut notifier = Notifier::start(&failing).unwrap();
        let s = status(0, "alarm");
        notifier.observe(&s, b"{}");
        notifier.finish();
        let counts = notifier.counts();
        assert_eq!(counts.attempts.load(Ordering::Relaxed), 3);
        assert_eq!(counts.sent.load(Ordering::Relaxed), 0);
        assert_eq!(counts.failures.load(Ordering::Relaxed), 1);
        let mut health = Health::default();
        notifier.count_into(&mut health);
        assert_eq!((health.notification_attempts, health.notification_failures), (3, 1));
    }
}
