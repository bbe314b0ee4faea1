//! Zenoh publishing: channel blocks (the simulator, the demo, the soak) paced
//! at a multiple of real time, and the keys result messages go out on.

use crate::config::ZenohConfig;
use crate::io::wire::{self, Encoding};
use anyhow::{anyhow, Result};
use zenoh::Wait;

/// The zenoh key of a result message. FRF results go under
/// `<prefix>/updating/frf/…`: `<prefix>/frf/**` is an input (pre-computed
/// FRFs), and the daemon must not receive its own output there.
pub fn zenoh_result_key(prefix: &str, suffix: &str) -> String {
    match suffix.strip_prefix("frf/") {
        Some(rest) => format!("{prefix}/updating/frf/{rest}"),
        None => format!("{prefix}/{suffix}"),
    }
}

/// Publishes blocks on zenoh (`simulate --publish`), pacing them at `speed`
/// times real time (0 = as fast as possible).
pub struct Publisher {
    session: zenoh::Session,
    prefix: String,
    encoding: Encoding,
    speed: f64,
    origin: Option<(i128, std::time::Instant)>,
    /// Called before each block; may block ([`Self::hold_back_with`]).
    gate: Option<Box<dyn FnMut() + Send>>,
}

impl Publisher {
    pub fn open(zenoh: &ZenohConfig, prefix: String, encoding: Encoding, speed: f64) -> Result<Self> {
        let session = zenoh::open(zenoh.to_zenoh()?)
            .wait()
            .map_err(|e| anyhow!("cannot open the zenoh session: {e}"))?;
        Ok(Self {
            session,
            prefix,
            encoding,
            speed,
            origin: None,
            gate: None,
        })
    }

    /// Calls `gate` before each block: it may block, holding the publisher
    /// back (the demo, while its daemon has updates waiting). The pace
    /// resumes where it stopped rather than catching up in a burst.
    pub fn hold_back_with(&mut self, gate: impl FnMut() + Send + 'static) {
        self.gate = Some(Box::new(gate));
    }

    /// The publisher's zenoh session (e.g. to subscribe to results on the same link).
    pub fn session(&self) -> &zenoh::Session {
        &self.session
    }

    pub fn publish(&mut self, block: &wire::ChannelBlock) -> Result<()> {
        if let Some(gate) = self.gate.as_mut() {
            let held = std::time::Instant::now();
            gate();
            if let Some((_, start)) = self.origin.as_mut() {
                *start += held.elapsed();
            }
        }
        if self.speed > 0.0 {
            let (t0, w0) = *self.origin.get_or_insert((block.start_ns, std::time::Instant::now()));
            let due = std::time::Duration::from_secs_f64(((block.start_ns - t0) as f64 / 1e9 / self.speed).max(0.0));
            if let Some(wait) = due.checked_sub(w0.elapsed()) {
                std::thread::sleep(wait);
            }
        }
        let key = block.topic(&self.prefix);
        let zenc = match self.encoding {
            Encoding::Cbor => zenoh::bytes::Encoding::APPLICATION_CBOR,
            Encoding::Json => zenoh::bytes::Encoding::APPLICATION_JSON,
        };
        // Blocking while the link is congested: zenoh's default for a put
        // drops the message silently under congestion, which lost a message
        // now and then when the daemon fell behind (the demo then waited
        // out its drain limit, the message never taken).
        self.session
            .put(&key, wire::encode(block, self.encoding))
            .encoding(zenc)
            .congestion_control(zenoh::qos::CongestionControl::Block)
            .wait()
            .map_err(|e| anyhow!("cannot publish on {key}: {e}"))
    }

    /// Publishes raw JSON bytes on `<prefix>/<suffix>` (e.g. a pre-computed
    /// FRF). Blocks while the link is congested rather than dropping: an FRF
    /// set missing one message would never become an update.
    pub fn publish_json(&mut self, suffix: &str, bytes: Vec<u8>) -> Result<()> {
        let key = format!("{}/{suffix}", self.prefix);
        self.session
            .put(&key, bytes)
            .encoding(zenoh::bytes::Encoding::APPLICATION_JSON)
            .congestion_control(zenoh::qos::CongestionControl::Block)
            .wait()
            .map_err(|e| anyhow!("cannot publish on {key}: {e}"))
    }

    /// Publishes a message's bytes as they are on `<prefix>/<suffix>`, in
    /// `encoding` (a logger's own encoder, a damaged message in a test),
    /// blocking while the link is congested rather than dropping.
    pub fn publish_bytes(&mut self, suffix: &str, bytes: Vec<u8>, encoding: Encoding) -> Result<()> {
        let key = format!("{}/{suffix}", self.prefix);
        let zenc = match encoding {
            Encoding::Cbor => zenoh::bytes::Encoding::APPLICATION_CBOR,
            Encoding::Json => zenoh::bytes::Encoding::APPLICATION_JSON,
        };
        self.session
            .put(&key, bytes)
            .encoding(zenc)
            .congestion_control(zenoh::qos::CongestionControl::Block)
            .wait()
            .map_err(|e| anyhow!("cannot publish on {key}: {e}"))
    }

    pub fn close(self) -> Result<()> {
        self.session
            .close()
            .wait()
            .map_err(|e| anyhow!("closing the zenoh session: {e}"))
    }
}
