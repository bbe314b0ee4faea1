//! The daemon's zenoh session: subscribers that push raw messages into the
//! bounded ingest queue, the `<prefix>/{updating,monitoring,health}/latest`
//! queryables, the `<prefix>/alive` liveliness token, and the publishing of
//! result messages.

use crate::config::Config;
use crate::io::wire::Encoding;
use crate::outputs::publisher::zenoh_result_key;
use anyhow::{anyhow, Result};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use tokio::sync::mpsc;
use zenoh::Wait;

/// Capacity of the ingest queue, in messages.
pub const INGEST_QUEUE: usize = 4096;

/// The input key expressions under `<prefix>/`, and whether they carry
/// pre-computed FRFs (else channel blocks).
const INPUTS: [(&str, bool); 4] = [
    ("accel/*", false),
    ("force/*", false),
    ("temperature/*", false),
    ("frf/**", true),
];

/// A message as it arrived, not yet decoded.
pub(super) struct RawMessage {
    pub(super) encoding: Option<Encoding>,
    pub(super) payload: Vec<u8>,
    /// A pre-computed FRF (`<prefix>/frf/**`) rather than a channel block.
    pub(super) frf: bool,
    /// The key it arrived on.
    pub(super) key: String,
}

/// The queryables `<prefix>/<segment>/latest`, each replying with the last
/// message of its kind (`{}` before the first): what a dashboard or
/// `splinewatch fleet` asks for.
#[derive(Debug, Clone, Copy)]
pub(super) enum Latest {
    /// The last `updating/parameters` message.
    Updating = 0,
    /// The last `monitoring/status` message.
    Monitoring = 1,
    /// The last `health` message.
    Health = 2,
}

impl Latest {
    const ALL: [Latest; 3] = [Latest::Updating, Latest::Monitoring, Latest::Health];

    fn segment(self) -> &'static str {
        crate::service::fleet::LATEST_KINDS[self as usize]
    }
}

/// The open session and what the daemon declared on it.
pub(super) struct ZenohLink {
    session: zenoh::Session,
    subscribers: Vec<zenoh::pubsub::Subscriber<()>>,
    queryables: Vec<zenoh::query::Queryable<()>>,
    /// `<prefix>/alive`, declared once the queryables are: a dashboard or
    /// `fleet` that sees it may ask (the router got the queryables' declarations
    /// first, on the same ordered link).
    alive: zenoh::liveliness::LivelinessToken,
    /// The bodies of the replies to `<prefix>/<Latest::segment>/latest`.
    latest: [Arc<Mutex<Vec<u8>>>; 3],
    prefix: String,
    /// Messages the full ingest queue refused (counted in the callbacks).
    ingest_drops: Arc<AtomicU64>,
}

/// The TLS files in use, once at start; certificates near expiry as warnings.
fn log_tls(report: &crate::config::TlsReport) {
    for file in &report.files {
        tracing::info!(mutual = report.mutual, "zenoh TLS: {file}");
    }
    for file in report.expiring() {
        tracing::warn!("zenoh TLS certificate expires soon, renew it: {file}");
    }
}

impl ZenohLink {
    /// Opens the session, subscribes to the inputs (`INPUTS`) and declares
    /// the `latest` queryables; returns the ingest queue.
    pub(super) async fn open(config: &Config) -> Result<(Self, mpsc::Receiver<RawMessage>)> {
        let prefix = config.topic_prefix();
        let (zenoh_config, tls) = config.zenoh.to_zenoh_with_tls()?;
        log_tls(&tls);
        let session = zenoh::open(zenoh_config)
            .await
            .map_err(|e| anyhow!("cannot open the zenoh session: {e}"))?;
        let (tx, rx) = mpsc::channel::<RawMessage>(INGEST_QUEUE);
        let ingest_drops = Arc::new(AtomicU64::new(0));
        let mut subscribers = Vec::new();
        for (segment, frf) in INPUTS {
            let key = format!("{prefix}/{segment}");
            let (tx, drops) = (tx.clone(), Arc::clone(&ingest_drops));
            let sub = session
                .declare_subscriber(&key)
                .callback(move |sample| {
                    let msg = RawMessage {
                        encoding: wire_encoding(sample.encoding()),
                        payload: sample.payload().to_bytes().into_owned(),
                        frf,
                        key: sample.key_expr().to_string(),
                    };
                    if tx.try_send(msg).is_err() {
                        drops.fetch_add(1, Ordering::Relaxed);
                    }
                })
                .await
                .map_err(|e| anyhow!("cannot subscribe to {key}: {e}"))?;
            subscribers.push(sub);
        }
        drop(tx);
        let mut queryables = Vec::new();
        let mut latest = Vec::new();
        for which in Latest::ALL {
            let key = format!("{prefix}/{}/latest", which.segment());
            let (queryable, body) = declare_latest(&session, key).await?;
            queryables.push(queryable);
            latest.push(body);
        }
        let alive_key = format!("{prefix}/{}", crate::service::fleet::ALIVE);
        let alive = session
            .liveliness()
            .declare_token(&alive_key)
            .await
            .map_err(|e| anyhow!("cannot declare the liveliness token {alive_key}: {e}"))?;
        let link = Self {
            session,
            subscribers,
            queryables,
            alive,
            latest: latest.try_into().expect("one body per Latest"),
            prefix,
            ingest_drops,
        };
        Ok((link, rx))
    }

    /// Publishes a result message already serialised to JSON under its key;
    /// a failure is logged.
    pub(super) fn publish_json(&self, suffix: &str, json: Vec<u8>) {
        let key = zenoh_result_key(&self.prefix, suffix);
        if let Err(e) = self
            .session
            .put(&key, json)
            .encoding(zenoh::bytes::Encoding::APPLICATION_JSON)
            .wait()
        {
            tracing::warn!(message = "cannot publish", key = %key, error = %e);
        }
    }

    /// The key expressions the daemon subscribes to, for the log.
    pub(super) fn inputs(&self) -> String {
        INPUTS
            .map(|(segment, _)| format!("{}/{segment}", self.prefix))
            .join(", ")
    }

    /// Replaces the reply to `<prefix>/<which>/latest`.
    pub(super) fn set_latest(&self, which: Latest, body: Vec<u8>) {
        if let Ok(mut l) = self.latest[which as usize].lock() {
            *l = body;
        }
    }

    /// Messages dropped by the full ingest queue so far.
    pub(super) fn ingest_drops(&self) -> u64 {
        self.ingest_drops.load(Ordering::Relaxed)
    }

    pub(super) async fn close(self) -> Result<()> {
        drop(self.alive);
        drop(self.queryables);
        drop(self.subscribers);
        self.session
            .close()
            .await
            .map_err(|e| anyhow!("closing the zenoh session: {e}"))
    }
}

/// A queryable on `key` replying with the body behind the returned lock
/// (`{}` until one is set).
async fn declare_latest(
    session: &zenoh::Session,
    key: String,
) -> Result<(zenoh::query::Queryable<()>, Arc<Mutex<Vec<u8>>>)> {
    let body: Arc<Mutex<Vec<u8>>> = Arc::new(Mutex::new(b"{}".to_vec()));
    let reply = Arc::clone(&body);
    let reply_key = key.clone();
    let queryable = session
        .declare_queryable(&key)
        .callback(move |query| {
            let body = reply.lock().map(|b| b.clone()).unwrap_or_default();
            let _ = query
                .reply(&reply_key, body)
                .encoding(zenoh::bytes::Encoding::APPLICATION_JSON)
                .wait();
        })
        .await
        .map_err(|e| anyhow!("cannot declare {key}: {e}"))?;
    Ok((queryable, body))
}

/// The wire encoding a zenoh sample declares, if it is one of ours.
fn wire_encoding(e: &zenoh::bytes::Encoding) -> Option<Encoding> {
    if *e == zenoh::bytes::Encoding::APPLICATION_CBOR {
        Some(Encoding::Cbor)
    } else if *e == zenoh::bytes::Encoding::APPLICATION_JSON {
        Some(Encoding::Json)
    } else {
        None
    }
}
