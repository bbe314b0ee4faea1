//! Alignment: the stream's sample grid (rate and origin agreed on from the
//! first blocks), per-channel queues on it, gaps filled with NaN.

use super::{Pipeline, UpdateJob, WindowReport};
use crate::io::wire::ChannelBlock;
use std::collections::VecDeque;

/// Two sampling rates are the same to 1e-9 relative.
pub(super) fn same_rate(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * a
}

pub(super) struct ChannelQueue {
    /// Grid index of the first buffered sample.
    pub(super) first: i64,
    pub(super) data: VecDeque<f64>,
    pub(super) seen: bool,
}

impl ChannelQueue {
    pub(super) fn end(&self) -> i64 {
        self.first + self.data.len() as i64
    }
}

impl Pipeline {
    /// Agrees on the sampling rate and the time origin from the first
    /// `2 × channels` blocks instead of trusting the first one, which could
    /// be bad (a wrong rate, a timestamp in 2099) and would then make every
    /// valid block after it look wrong. The most common rate wins (ties: the
    /// one seen first); among the blocks at that rate, those within the
    /// far-future horizon of the median start are inliers and the earliest
    /// inlier is the origin. The held blocks then go through the usual checks
    /// in time order, so the outliers are counted by reason like any others.
    pub(super) fn establish_reference(&mut self, windows: &mut Vec<WindowReport>, jobs: &mut Vec<UpdateJob>) {
        let mut pending = std::mem::take(&mut self.pending);
        if pending.is_empty() {
            return;
        }
        let mut rates: Vec<(f64, usize)> = Vec::new();
        for b in &pending {
            match rates.iter_mut().find(|(f, _)| same_rate(*f, b.fs)) {
                Some(entry) => entry.1 += 1,
                None => rates.push((b.fs, 1)),
            }
        }
        let most = rates.iter().map(|r| r.1).max().unwrap_or(0);
        let fs = rates.iter().find(|r| r.1 == most).expect("non-empty").0;
        let (window_seconds, hop_seconds) = self.config.analysis_window();
        if self.force.is_some() {
            match self.config.welch_settings(fs) {
                Ok(welch) => self.welch = Some(welch),
                Err(_) => {
                    for _ in &pending {
                        self.health.reject("bad_fs_for_frf_settings");
                    }
                    return;
                }
            }
        }
        self.window_samples = ((window_seconds * fs).round() as i64).max(1);
        self.hop_samples = hop_seconds.map_or(self.window_samples, |hop| ((hop * fs).round() as i64).max(1));
        let mut starts: Vec<i128> = pending
            .iter()
            .filter(|b| same_rate(b.fs, fs))
            .map(|b| b.start_ns)
            .collect();
        starts.sort_unstable();
        let median = starts[starts.len() / 2];
        let horizon_ns = (self.far_future_samples(fs) as f64 / fs * 1e9) as i128;
        let t0 = starts
            .iter()
            .copied()
            .find(|&s| (s - median).abs() <= horizon_ns)
            .unwrap_or(median);
        self.fs = Some(fs);
        self.t0 = Some(t0);
        pending.sort_by_key(|b| b.start_ns);
        for block in pending {
            self.ingest_block(block, windows, jobs);
        }
    }

    /// How far (samples) a channel may lag the others before its missing
    /// stretch counts as a gap.
    fn max_lag_samples(&self, fs: f64) -> i64 {
        (self.schedule.max_lag_seconds * fs) as i64
    }

    /// A block further ahead of its channel than this many samples is
    /// rejected as `far_future`.
    fn far_future_samples(&self, fs: f64) -> i64 {
        self.window_samples.max(self.max_lag_samples(fs)) * 4
    }

    /// [`Self::ingest`] once the reference is set.
    pub(super) fn ingest_block(
        &mut self,
        block: ChannelBlock,
        windows: &mut Vec<WindowReport>,
        jobs: &mut Vec<UpdateJob>,
    ) {
        let c = self.channel_of(&block).expect("checked on arrival");
        let fs = self.fs.expect("set by establish_reference");
        if !same_rate(fs, block.fs) {
            self.health.reject("rate_mismatch");
            return;
        }
        let t0 = self.t0.expect("set by establish_reference");
        let position = (block.start_ns - t0) as f64 * fs / 1e9;
        let index = position.round();
        if (position - index).abs() > 0.01 {
            self.health.reject("misaligned");
            return;
        }
        let index = index as i64;
        let horizon = self.far_future_samples(fs);
        let max_lag = self.max_lag_samples(fs);
        let queue = &mut self.queues[c];
        let expected = if queue.seen { queue.end() } else { self.fed };
        if index < expected {
            // Backwards, duplicated or overlapping, or before what was already analysed.
            self.health.reject("time_overlap");
            return;
        }
        if index - expected > horizon {
            self.health.reject("far_future");
            return;
        }
        if !queue.seen {
            queue.first = self.fed;
            queue.seen = true;
        }
        if index > expected {
            self.health.gaps += 1;
            self.health.gap_samples += (index - expected) as u64;
            queue
                .data
                .extend(std::iter::repeat_n(f64::NAN, (index - expected) as usize));
        }
        queue.data.extend(&block.data);
        self.health.blocks += 1;
        self.health.samples += block.data.len() as u64;
        // Channels too far behind the leader: their missing stretch is a gap.
        let leader = self.queues.iter().map(|q| q.end()).max().unwrap_or(0);
        for q in &mut self.queues {
            let behind = leader - q.end().max(self.fed);
            if behind > max_lag {
                let fill = behind - max_lag;
                if !q.seen {
                    q.first = self.fed;
                    q.seen = true;
                }
                q.data.extend(std::iter::repeat_n(f64::NAN, fill as usize));
                self.health.gaps += 1;
                self.health.gap_samples += fill as u64;
            }
        }
        self.feed(windows, jobs);
    }
}
