//! `[metrics]`: Prometheus/OpenMetrics text at `/metrics` for the
//! operator's dashboard (issue 48), served by the daemon (and by `replay
//! --metrics`) from a thread of its own (`tiny_http`), encoded by
//! `prometheus-client`, never by hand.
//!
//! The counters mirror the health message: the daemon hands its [`Health`]
//! to [`Metrics::record_health`] whenever it writes one (every 10 s and at
//! shutdown), so a scrape's counters are exactly the latest health
//! message's (`splinewatch_health_time_seconds` says which) and never go
//! down while the process runs. Gauges and histograms are set as things
//! happen: queue depths, the last update's residual and time, the
//! monitoring state and standardised residuals, the update duration and the
//! ingest-to-result latency. Every series carries the `bridge` label (the
//! config's `[bridge] name`).

use crate::io::monitoring_json::StatusMessage;
use crate::pipeline::{AcceptedParameters, Health, UpdateOutcome};
use anyhow::{Context, Result};
use prometheus_client::collector::Collector;
use prometheus_client::encoding::{DescriptorEncoder, EncodeMetric};
use prometheus_client::metrics::counter::ConstCounter;
use prometheus_client::metrics::gauge::ConstGauge;
use prometheus_client::metrics::histogram::{exponential_buckets, Histogram};
use prometheus_client::registry::{Registry, Unit};
use splinewatch_core::monitoring::MonitorState;
use std::net::SocketAddr;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, SystemTime};

/// The OpenMetrics text content type `prometheus-client` encodes.
pub const CONTENT_TYPE: &str = "application/openmetrics-text; version=1.0.0; charset=utf-8";

/// What the collector reads at each scrape.
#[derive(Debug, Default, Clone)]
pub struct Snapshot {
    /// The latest health message's counters and its measurement time.
    pub health: Health,
    pub health_time_ns: Option<i128>,
    /// Messages taken off the ingest queue (the daemon's `RunSummary::messages`).
    pub messages_received: u64,
    /// Update jobs waiting behind the running one, and whether one runs.
    pub update_queue_depth: usize,
    pub update_running: bool,
    /// Raw messages waiting in the ingest queue.
    pub ingest_queue_depth: usize,
    /// Wall time of the last update result, and the last accepted one's relative residual.
    pub last_update: Option<SystemTime>,
    pub last_relative_residual: Option<f64>,
    /// The last accepted parameters (name, value).
    pub parameters: Vec<(String, f64)>,
    /// `[monitoring]`: the latest status and each feature's standardised
    /// (compensated) residual.
    pub monitoring_state: Option<String>,
    pub residuals: Vec<(String, f64)>,
}

#[derive(Debug)]
struct SnapshotCollector(Arc<Mutex<Snapshot>>);

/// The metrics of one process: the snapshot the daemon fills, the
/// histograms it observes into, and the server thread.
pub struct Metrics {
    snapshot: Arc<Mutex<Snapshot>>,
    update_duration: Histogram,
    result_latency: Histogram,
    address: SocketAddr,
    stop: Arc<AtomicBool>,
    server: Option<JoinHandle<()>>,
}

impl Metrics {
    /// Binds `listen` and serves `/metrics` until dropped.
    pub fn serve(listen: &str, bridge: &str) -> Result<Self> {
        let server = tiny_http::Server::http(listen)
            .map_err(|e| anyhow::anyhow!("{e}"))
            .with_context(|| format!("metrics: cannot listen on {listen}"))?;
        let address = server
            .server_addr()
            .to_ip()
            .context("metrics: the listener has no IP address")?;
        let snapshot = Arc::new(Mutex::new(Snapshot::default()));
        // Update durations from 10 ms to ~80 s; latencies likewise.
        let update_duration = Histogram::new(exponential_buckets(0.01, 2.0, 14));
        let result_latency = Histogram::new(exponential_buckets(0.01, 2.0, 14));
        let mut registry = Registry::with_prefix_and_labels(
            "splinewatch",
            [(
                std::borrow::Cow::Borrowed("bridge"),
                std::borrow::Cow::Owned(bridge.to_string()),
            )]
            .into_iter(),
        );
        registry.register_with_unit(
            "update_duration",
            "Wall time of one model update (the solve and its outputs' preparation)",
            Unit::Seconds,
            update_duration.clone(),
        );
        registry.register_with_unit(
            "result_latency",
            "From the moment the window's last block was taken to its update's results written",
            Unit::Seconds,
            result_latency.clone(),
        );
        registry.register_collector(Box::new(SnapshotCollector(Arc::clone(&snapshot))));
        let stop = Arc::new(AtomicBool::new(false));
        let thread_stop = Arc::clone(&stop);
        let handle = std::thread::Builder::new()
            .name("metrics".into())
            .spawn(move || serve_loop(&server, &registry, &thread_stop))
            .context("metrics: cannot start the server thread")?;
        tracing::info!(message = "serving metrics", url = %format!("http://{address}/metrics"));
        Ok(Self {
            snapshot,
            update_duration,
            result_latency,
            address,
            stop,
            server: Some(handle),
        })
    }

    /// Where it listens (the port chosen when `listen` gave port 0).
    pub fn address(&self) -> SocketAddr {
        self.address
    }

    /// Changes the snapshot (under its lock, held only for `change`).
    pub fn update(&self, change: impl FnOnce(&mut Snapshot)) {
        let mut snapshot = self.snapshot.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        change(&mut snapshot);
    }

    /// The counters of the health message just written at `time_ns`.
    pub fn record_health(&self, time_ns: i128, health: &Health, messages_received: u64) {
        self.update(|s| {
            s.health = health.clone();
            s.health_time_ns = Some(time_ns);
            s.messages_received = messages_received;
        });
    }

    /// An update's outcome, its outputs written: the duration and latency
    /// histograms, the last update's time and residual, the parameters
    /// accepted so far.
    pub fn record_update(&self, outcome: &UpdateOutcome, accepted: Option<&AcceptedParameters>) {
        self.update_duration.observe(outcome.duration.as_secs_f64());
        self.result_latency.observe(outcome.created.elapsed().as_secs_f64());
        self.update(|s| {
            s.last_update = Some(SystemTime::now());
            if let Ok(r) = &outcome.result {
                s.last_relative_residual = Some(r.result.relative_residual);
            }
            if let Some(a) = accepted {
                s.parameters = a.parameters.iter().map(|p| (p.name.clone(), p.value)).collect();
            }
        });
    }

    /// A monitoring status: its state and standardised residuals.
    pub fn record_monitoring(&self, status: &StatusMessage) {
        self.update(|s| {
            s.monitoring_state = Some(status.state.clone());
            s.residuals = status
                .residuals
                .iter()
                .map(|r| (r.name.clone(), r.standardised))
                .collect();
        });
    }
}

impl Drop for Metrics {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(h) = self.server.take() {
            let _ = h.join();
        }
    }
}

fn serve_loop(server: &tiny_http::Server, registry: &Registry, stop: &AtomicBool) {
    while !stop.load(Ordering::Relaxed) {
        let request = match server.recv_timeout(Duration::from_millis(100)) {
            Ok(Some(r)) => r,
            Ok(None) => continue,
            Err(e) => {
                tracing::warn!(message = "metrics: a request could not be read", error = %e);
                continue;
            }
        };
        let path = request.url().split('?').next().unwrap_or_default();
        let response = if request.method() != &tiny_http::Method::Get {
            tiny_http::Response::from_string("only GET\n").with_status_code(405)
        } else if path == "/metrics" {
            let mut body = String::new();
            match prometheus_client::encoding::text::encode(&mut body, registry) {
                Ok(()) => tiny_http::Response::from_string(body).with_header(
                    tiny_http::Header::from_bytes(&b"Content-Type"[..], CONTENT_TYPE.as_bytes())
                        .expect("a valid header"),
                ),
                Err(_) => tiny_http::Response::from_string("encoding failed\n").with_status_code(500),
            }
        } else {
            tiny_http::Response::from_string("splinewatch metrics: GET /metrics\n").with_status_code(404)
        };
        if let Err(e) = request.respond(response) {
            tracing::debug!(message = "metrics: the scraper went away", error = %e);
        }
    }
}

/// One constant metric: a descriptor and its value (or one value per label set).
fn counter(e: &mut DescriptorEncoder, name: &str, help: &str, value: u64) -> std::fmt::Result {
    let c = ConstCounter::new(value);
    c.encode(e.encode_descriptor(name, help, None, c.metric_type())?)
}

fn counters_by(
    e: &mut DescriptorEncoder,
    name: &str,
    help: &str,
    label: &str,
    values: &[(String, u64)],
) -> std::fmt::Result {
    let mut family = e.encode_descriptor(name, help, None, prometheus_client::metrics::MetricType::Counter)?;
    for (key, value) in values {
        let labels = [(label, key.as_str())];
        ConstCounter::new(*value).encode(family.encode_family(&labels)?)?;
    }
    Ok(())
}

/// A gauge; without a value (nothing to say yet) its family is still
/// described, so a scrape always lists every metric the process exports.
fn gauge(
    e: &mut DescriptorEncoder,
    name: &str,
    help: &str,
    unit: Option<&Unit>,
    value: impl Into<Option<f64>>,
) -> std::fmt::Result {
    let encoder = e.encode_descriptor(name, help, unit, prometheus_client::metrics::MetricType::Gauge)?;
    match value.into() {
        Some(v) => ConstGauge::new(v).encode(encoder),
        None => Ok(()),
    }
}

fn gauges_by(
    e: &mut DescriptorEncoder,
    name: &str,
    help: &str,
    label: &str,
    values: &[(String, f64)],
) -> std::fmt::Result {
    let mut family = e.encode_descriptor(name, help, None, prometheus_client::metrics::MetricType::Gauge)?;
    for (key, value) in values {
        let labels = [(label, key.as_str())];
        ConstGauge::new(*value).encode(family.encode_family(&labels)?)?;
    }
    Ok(())
}

fn listed(map: &std::collections::BTreeMap<String, u64>) -> Vec<(String, u64)> {
    map.iter().map(|(k, v)| (k.clone(), *v)).collect()
}

impl Collector for SnapshotCollector {
    fn encode(&self, mut e: DescriptorEncoder) -> std::fmt::Result {
        let s = self.0.lock().unwrap_or_else(std::sync::PoisonError::into_inner).clone();
        encode_counters(&s, &mut e)?;
        encode_gauges(&s, &mut e)
    }
}

/// A counter of the health message: name (without `splinewatch_` and
/// `_total`), help, and its value.
type PlainCounter = (&'static str, &'static str, fn(&Health) -> u64);

const PLAIN_COUNTERS: &[PlainCounter] = &[
    ("blocks_accepted", "Channel blocks taken by the pipeline", |h| h.blocks),
    ("samples_accepted", "Samples of the blocks taken", |h| h.samples),
    (
        "event_blocks",
        "Acceleration blocks taken by the event chain ([events])",
        |h| h.event_blocks,
    ),
    ("temperature_blocks", "Temperature blocks taken ([monitoring])", |h| {
        h.temperature_blocks
    }),
    ("queue_drops", "Messages and update jobs dropped by full queues", |h| {
        h.queue_drops
    }),
    ("gaps", "Gaps in a channel's samples", |h| h.gaps),
    ("gap_samples", "Samples missing in those gaps", |h| h.gap_samples),
    ("windows_accepted", "Analysis windows accepted", |h| h.windows_accepted),
    ("update_runs", "Model updates run (failed ones included)", |h| {
        h.update_runs
    }),
    (
        "update_failures",
        "Model updates that failed (the last parameters kept)",
        |h| h.update_failures,
    ),
];

/// A counter by label: name, help, label, and its values by label value.
type LabelledCounter = (
    &'static str,
    &'static str,
    &'static str,
    fn(&Health) -> Vec<(String, u64)>,
);

const LABELLED_COUNTERS: &[LabelledCounter] = &[
    ("rejected", "Messages and blocks rejected, by reason", "reason", |h| {
        listed(&h.rejected)
    }),
    (
        "windows_skipped",
        "Analysis windows skipped, by reason",
        "reason",
        |h| listed(&h.windows_skipped),
    ),
    ("updates_skipped", "Update jobs never run, by reason", "reason", |h| {
        listed(&h.updates_skipped)
    }),
    ("segments", "Welch segments, by outcome", "outcome", |h| {
        named(&[("accepted", h.segments_accepted), ("rejected", h.segments_rejected)])
    }),
    (
        "output_errors",
        "Output failures the daemon went on after, by output",
        "output",
        |h| {
            named(&[
                ("recording", h.recording_errors),
                ("results", h.results_errors),
                ("rerun", h.rerun_errors),
                ("log", h.log_writes_dropped),
            ])
        },
    ),
    (
        "notifications",
        "[monitoring.notify]: command runs and requests (attempts), deliveries (sent), given up (failed)",
        "outcome",
        |h| {
            named(&[
                ("attempts", h.notification_attempts),
                ("sent", h.notifications_sent),
                ("failed", h.notification_failures),
            ])
        },
    ),
    (
        "events",
        "[events]: bursts run through the event chain, by outcome",
        "outcome",
        |h| named(&[("processed", h.events_processed), ("skipped", h.events_skipped)]),
    ),
];

fn named(values: &[(&str, u64)]) -> Vec<(String, u64)> {
    values.iter().map(|(k, v)| ((*k).to_string(), *v)).collect()
}

/// The health message's counters, and the messages received.
fn encode_counters(s: &Snapshot, e: &mut DescriptorEncoder) -> std::fmt::Result {
    counter(
        e,
        "messages_received",
        "Messages taken off the ingest queue",
        s.messages_received,
    )?;
    for (name, help, value) in PLAIN_COUNTERS {
        counter(e, name, help, value(&s.health))?;
    }
    for (name, help, label, values) in LABELLED_COUNTERS {
        counters_by(e, name, help, label, &values(&s.health))?;
    }
    Ok(())
}

/// The gauges: the health message's time, queues, the last update, the
/// parameters and the monitoring.
fn encode_gauges(s: &Snapshot, e: &mut DescriptorEncoder) -> std::fmt::Result {
    gauge(
        e,
        "health_time",
        "Measurement time of the health message the counters are from",
        Some(&Unit::Seconds),
        s.health_time_ns.map(|t| t as f64 * 1e-9),
    )?;
    gauge(
        e,
        "update_queue_depth",
        "Update jobs waiting behind the running one",
        None,
        s.update_queue_depth as f64,
    )?;
    gauge(
        e,
        "update_running",
        "1 while an update runs",
        None,
        f64::from(u8::from(s.update_running)),
    )?;
    gauge(
        e,
        "ingest_queue_depth",
        "Raw messages waiting in the ingest queue",
        None,
        s.ingest_queue_depth as f64,
    )?;
    let since = |t: SystemTime| {
        t.duration_since(SystemTime::UNIX_EPOCH)
            .unwrap_or_default()
            .as_secs_f64()
    };
    gauge(
        e,
        "last_update_timestamp",
        "Wall time of the last update result",
        Some(&Unit::Seconds),
        s.last_update.map(since),
    )?;
    gauge(
        e,
        "last_update_age",
        "Seconds since the last update result",
        Some(&Unit::Seconds),
        s.last_update
            .map(|at| SystemTime::now().duration_since(at).unwrap_or_default().as_secs_f64()),
    )?;
    gauge(
        e,
        "last_update_relative_residual",
        "Relative residual of the last accepted update",
        None,
        s.last_relative_residual,
    )?;
    gauges_by(
        e,
        "parameter_value",
        "The last accepted updating parameters",
        "parameter",
        &s.parameters,
    )?;
    encode_monitoring(s, e)
}

/// `[monitoring]`: the latest state (one-hot and the alarm flag) and each
/// feature's standardised residual.
fn encode_monitoring(s: &Snapshot, e: &mut DescriptorEncoder) -> std::fmt::Result {
    let state = s.monitoring_state.as_deref();
    let one_hot: Vec<(String, f64)> = match state {
        Some(state) => MonitorState::ALL
            .iter()
            .map(|m| (m.name().to_string(), f64::from(u8::from(state == m.name()))))
            .collect(),
        None => Vec::new(),
    };
    gauges_by(
        e,
        "monitoring_state",
        "1 for the latest monitoring state",
        "state",
        &one_hot,
    )?;
    gauge(
        e,
        "alarm",
        "1 while the monitoring is in alarm",
        None,
        state.map(|s| f64::from(u8::from(s == "alarm"))),
    )?;
    gauges_by(
        e,
        "monitoring_residual",
        "Each monitored feature's standardised residual after compensation",
        "feature",
        &s.residuals,
    )
}
