//! A triggered logger's bursts (issue 45, item 5): strong-motion recorders
//! send data only when triggered, so channel blocks that follow each other
//! with less than `[events] gap_seconds` of silence are one event.
//!
//! A burst ends when
//! - a block starts more than `gap_seconds` after the burst's last sample,
//!   or more than `gap_seconds` before its first (measurement time: a
//!   replayed or re-sent archive splits as it was recorded);
//! - nothing has arrived for `gap_seconds` plus the last block's length
//!   (wall time: a logger streaming in real time sends a block per block
//!   length, so silence is only silence beyond that);
//! - it reaches `max_seconds` (a logger that never stops does not grow the
//!   daemon's memory without bound: the span is judged as one event and the
//!   next begins);
//! - the daemon shuts down (the open burst is processed, not lost).

use crate::io::recording::RecordedBlock;
use std::time::{Duration, Instant};

/// One event's blocks, in arrival order.
#[derive(Debug, Default)]
pub struct Burst {
    /// The earliest sample and the end of the latest (ns since the epoch).
    pub start_ns: i128,
    pub end_ns: i128,
    pub blocks: Vec<RecordedBlock>,
}

impl Burst {
    pub fn seconds(&self) -> f64 {
        (self.end_ns - self.start_ns) as f64 * 1e-9
    }
}

/// The burst being collected.
#[derive(Debug)]
pub struct Bursts {
    gap_ns: i128,
    max_ns: i128,
    open: Burst,
    /// When the last block arrived and how long it was (wall-time silence).
    last_arrival: Option<(Instant, Duration)>,
}

impl Bursts {
    pub fn new(gap_seconds: f64, max_seconds: f64) -> Self {
        Self {
            gap_ns: (gap_seconds * 1e9) as i128,
            max_ns: (max_seconds * 1e9) as i128,
            open: Burst::default(),
            last_arrival: None,
        }
    }

    /// Whether a burst is open (blocks collected, not yet an event).
    pub fn is_open(&self) -> bool {
        !self.open.blocks.is_empty()
    }

    /// Adds a block arrived at `now`; returns the burst it ends, if any
    /// (the block then starts the next).
    pub fn push(&mut self, block: RecordedBlock, now: Instant) -> Option<Burst> {
        let b = &block.block;
        let length_ns = (b.data.len() as f64 * 1e9 / b.fs).round() as i128;
        let (start, end) = (b.start_ns, b.start_ns + length_ns);
        let closed = if self.is_open()
            && (start > self.open.end_ns + self.gap_ns
                || start < self.open.start_ns - self.gap_ns
                || end.max(self.open.end_ns) - self.open.start_ns > self.max_ns)
        {
            self.take()
        } else {
            None
        };
        if self.is_open() {
            self.open.start_ns = self.open.start_ns.min(start);
            self.open.end_ns = self.open.end_ns.max(end);
        } else {
            self.open.start_ns = start;
            self.open.end_ns = end;
        }
        self.open.blocks.push(block);
        self.last_arrival = Some((now, Duration::from_nanos(length_ns.clamp(0, u64::MAX as i128) as u64)));
        closed
    }

    /// The open burst when nothing arrived for `gap_seconds` plus the last
    /// block's length before `now`.
    pub fn idle(&mut self, now: Instant) -> Option<Burst> {
        let (arrived, length) = self.last_arrival?;
        let gap = Duration::from_nanos(self.gap_ns.clamp(0, u64::MAX as i128) as u64);
        if self.is_open() && now.saturating_duration_since(arrived) > gap + length {
            self.take()
        } else {
            None
        }
    }

    /// The open burst, whatever its silence (shutdown).
    pub fn take(&mut self) -> Option<Burst> {
        self.last_arrival = None;
        self.is_open().then(|| std::mem::take(&mut self.open))
    }
}

/// A recording's blocks cut into bursts by measurement time alone (a
/// triggered logger's raw-input recording, `splinewatch events`): sorted by
/// start, split where a silence exceeds `gap_seconds` or a burst would
/// exceed `max_seconds`.
pub fn split(mut blocks: Vec<RecordedBlock>, gap_seconds: f64, max_seconds: f64) -> Vec<Burst> {
    blocks.sort_by_key(|b| b.block.start_ns);
    let now = Instant::now();
    let mut bursts = Bursts::new(gap_seconds, max_seconds);
    let mut out: Vec<Burst> = blocks.into_iter().filter_map(|b| bursts.push(b, now)).collect();
    out.extend(bursts.take());
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::wire::{ChannelBlock, ChannelQuantity};

    fn block(name: &str, start_s: f64, seconds: f64) -> RecordedBlock {
        let fs = 100.0;
        RecordedBlock {
            topic: format!("b/accel/{name}"),
            log_time: 0,
            block: ChannelBlock {
                name: name.into(),
                quantity: ChannelQuantity::Acceleration,
                unit: "m/s^2".into(),
                fs,
                start_ns: (start_s * 1e9) as i128,
                data: vec![0.0; (seconds * fs) as usize],
            },
        }
    }

    #[test]
    fn a_silence_longer_than_the_gap_splits_in_measurement_time() {
        let now = Instant::now();
        let mut bursts = Bursts::new(10.0, 600.0);
        // Two channels of one event, interleaved, then one 11 s after the end.
        for (name, t) in [("a", 0.0), ("b", 0.0), ("a", 10.0), ("b", 10.0), ("a", 29.0)] {
            assert!(bursts.push(block(name, t, 10.0), now).is_none(), "{name} at {t}");
        }
        let first = bursts.push(block("a", 50.0, 10.0), now).expect("gap of 11 s");
        assert_eq!(first.blocks.len(), 5);
        assert_eq!((first.start_ns, first.end_ns), (0, 39_000_000_000));
        assert!((first.seconds() - 39.0).abs() < 1e-9);
        // An older record re-sent is another event too.
        let second = bursts.push(block("a", -1000.0, 10.0), now).expect("earlier record");
        assert_eq!(second.blocks.len(), 1);
        assert_eq!(bursts.take().expect("open").blocks.len(), 1);
        assert!(bursts.take().is_none());
    }

    #[test]
    fn wall_time_silence_counts_beyond_the_last_block_length() {
        let now = Instant::now();
        let mut bursts = Bursts::new(2.0, 600.0);
        assert!(bursts.idle(now).is_none());
        bursts.push(block("a", 0.0, 10.0), now);
        // A real-time logger's next block is 10 s away: 11 s is not silence.
        assert!(bursts.idle(now + Duration::from_secs(11)).is_none());
        let burst = bursts.idle(now + Duration::from_secs(13)).expect("silent for 13 s");
        assert_eq!(burst.blocks.len(), 1);
        assert!(!bursts.is_open());
    }

    #[test]
    fn a_logger_that_never_stops_is_cut_at_max_seconds() {
        let now = Instant::now();
        let mut bursts = Bursts::new(10.0, 60.0);
        let mut closed = Vec::new();
        for k in 0..20 {
            closed.extend(bursts.push(block("a", 10.0 * k as f64, 10.0), now));
        }
        assert_eq!(closed.len(), 3, "200 s in bursts of at most 60 s");
        assert!(closed.iter().all(|b| b.seconds() <= 60.0 + 1e-9 && b.blocks.len() == 6));
    }
}
