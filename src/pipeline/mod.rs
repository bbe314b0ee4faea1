//! The monitoring pipeline shared by the live daemon and offline replay:
//! decoded channel blocks in, windowed FRFs and warm-started updates out.
//! Room: below the outputs and services. May import: `config`, `io`, the core crate.
//!
//! - **Alignment.** The sample grid is anchored at the first accepted block;
//!   every channel must sit on it (within 1 % of a sample). A missing stretch
//!   (gap, late or silent channel) is filled with NaN so that the Welch gates
//!   reject exactly the segments it touches; a block that goes back in time
//!   is rejected. Nothing is buffered beyond `max_lag_seconds` per channel.
//! - **Windows.** Aligned samples stream into a Welch estimator; at each
//!   window end the FRFs are estimated and the window is accepted, or
//!   skipped with a reason (too few clean segments, low coherence).
//!   Output-only (no force sensor): the window keeps its samples, and at
//!   its end SSI-cov identifies its modes (`oma.rs`), which are paired with
//!   the model's at the last accepted parameters; a window is skipped for
//!   too little valid data, too few stable poles, a singular Hankel matrix
//!   or no pairable mode. Identification runs where the window closes
//!   (about 1 s for 10 minutes of 12 channels, well under the window).
//! - **Updating.** Every `update_every_windows` accepted windows an update
//!   job is produced (warm-started from the last accepted parameters, the
//!   config's values at first). The caller runs it (inline for replay, on a
//!   blocking worker live) and hands the outcome back; a failed or
//!   non-converged run keeps the last good parameters.

mod align;
pub mod estimate;
mod frf_inbox;
mod job;
mod monitoring;
pub mod oma;
mod reports;
mod updater;
mod windows;

pub use job::{Fit, Measured, ModeShape, PairedMode, UpdateJob, UpdateOutcome, UpdateReport, BENDING_MODES_KEPT};
pub use monitoring::{rescore, Environment, MonitoringOutcome, Training};
pub use oma::{ModelPair, WindowModes};
pub use reports::{AcceptedParameters, Health, StateParameter, WindowReport};
pub use updater::{UpdateCounters, Updater};

use crate::config::{Config, FrfSetup, ScheduleConfig};
use crate::io::frf_json::FrfEntry;
use crate::io::wire::{ChannelBlock, ChannelQuantity, Limits, WireError};
use align::ChannelQueue;
use anyhow::{bail, Result};
use oma::Identification;
use splinewatch_core::identification::welch::{Estimator, WelchSettings};
use splinewatch_core::response::frf::{ModalState, Quantity};
use splinewatch_core::updating::{Parameter, UpdateSettings};
use std::collections::{BTreeMap, VecDeque};
use std::sync::Arc;

/// The decoder limits for blocks this config's pipeline takes: at most
/// `frf.max_block_samples` samples per block, the other limits as default.
pub fn block_limits(config: &Config) -> Limits {
    Limits {
        max_samples: config.frf.max_block_samples,
        ..Limits::default()
    }
}

/// The pipeline state machine.
pub struct Pipeline {
    config: Config,
    schedule: ScheduleConfig,
    setup: Arc<FrfSetup>,
    parameters: Vec<Parameter>,
    settings: UpdateSettings,
    /// The force sensor; `None` for an output-only config.
    force: Option<usize>,
    accels: Vec<usize>,
    /// How windows are identified (output-only, or both paths).
    identification: Option<Identification>,
    /// What the updates fit (`[updating] residues`).
    residues: crate::config::Residues,
    /// Channel identities in queue order: force first (if any).
    channels: Vec<(String, ChannelQuantity)>,
    queues: Vec<ChannelQueue>,
    fs: Option<f64>,
    t0: Option<i128>,
    /// Blocks held until the sampling rate and time origin are agreed on
    /// (`establish_reference`).
    pending: Vec<ChannelBlock>,
    /// Welch settings and FRF estimator, once the rate is known (FRF path).
    welch: Option<(WelchSettings, Estimator)>,
    /// Windows being estimated (several when they overlap), oldest first:
    /// window `k` spans grid samples `[k·hop, k·hop + window_samples)`.
    open: VecDeque<(u64, windows::WindowData)>,
    window_samples: i64,
    hop_samples: i64,
    /// Grid index fed to the estimators so far.
    fed: i64,
    /// The next window to open.
    window_index: u64,
    accepted_since_update: u64,
    /// Pre-computed FRFs received on `<prefix>/frf/<input>/<output>`, by pair,
    /// all on one frequency axis; a complete set becomes an update job.
    frf_inbox: BTreeMap<(String, String), FrfEntry>,
    frf_axis: Option<(Quantity, Vec<f64>)>,
    /// The span of the set being collected (ns).
    frf_span: Option<(i128, i128)>,
    frf_sets: u64,
    /// Measurement time of the last update (or the first sample).
    last_update_ns: Option<i128>,
    /// `[monitoring]`: temperatures per window.
    temperatures: Option<monitoring::TemperatureStore>,
    /// The last accepted parameters, the model at them, the monitor.
    updater: Updater,
    /// Whether `updater` was handed to another thread (`split_updater`).
    split: bool,
    /// Split with identification: the model states coming back from the
    /// update side, for pairing.
    pairing: Option<updater::PairingLink>,
    health: Health,
}

impl Pipeline {
    /// The FRF model of the config, built once ([`crate::config::frf_setup`]).
    pub fn frf_setup(&self) -> Arc<FrfSetup> {
        Arc::clone(&self.setup)
    }

    pub fn new(config: &Config, schedule: ScheduleConfig, state: Option<AcceptedParameters>) -> Result<Self> {
        let setup = Arc::new(crate::config::frf_setup(config)?);
        let parameters = config.build_parameters()?;
        let settings = config.update_settings()?;
        let (force, accels) = if config.is_output_only() {
            (None, config.output_channels()?)
        } else {
            let (force, accels) = config.channel_roles()?;
            (Some(force), accels)
        };
        let identification = config.runs_oma().then(|| Identification::new(config)).transpose()?;
        let residues = config.residues()?;
        check_schedule_and_state(&schedule, state.as_ref(), &parameters)?;
        let names: Vec<String> = config.sensors.iter().map(|s| s.name.clone()).collect();
        let mut channels: Vec<_> = force
            .iter()
            .map(|&f| (names[f].clone(), ChannelQuantity::Force))
            .collect();
        channels.extend(
            accels
                .iter()
                .map(|&i| (names[i].clone(), ChannelQuantity::Acceleration)),
        );
        let queues = channels
            .iter()
            .map(|_| ChannelQueue {
                first: 0,
                data: VecDeque::new(),
                seen: false,
            })
            .collect();
        let (temperatures, monitoring) = monitoring::for_config(config, &parameters, &setup)?;
        let updater = Updater::new(Arc::clone(&setup), parameters.clone(), state, monitoring);
        Ok(Self {
            config: config.clone(),
            schedule,
            setup,
            parameters,
            settings,
            force,
            accels,
            identification,
            residues,
            channels,
            queues,
            fs: None,
            t0: None,
            pending: Vec::new(),
            welch: None,
            open: VecDeque::new(),
            window_samples: 0,
            hop_samples: 0,
            fed: 0,
            window_index: 0,
            accepted_since_update: 0,
            frf_inbox: BTreeMap::new(),
            frf_axis: None,
            frf_span: None,
            frf_sets: 0,
            last_update_ns: None,
            updater,
            split: false,
            pairing: None,
            temperatures,
            health: Health::default(),
        })
    }

    pub fn health(&self) -> &Health {
        &self.health
    }

    pub fn health_mut(&mut self) -> &mut Health {
        &mut self.health
    }

    /// The last accepted parameters, if any update succeeded (or a state was loaded).
    pub fn accepted(&self) -> Option<&AcceptedParameters> {
        self.updater.accepted()
    }

    /// The update side's health counters.
    pub fn update_counters(&self) -> UpdateCounters {
        self.updater.counters()
    }

    /// Output-only windows' reports also carry the spectral singular values
    /// (the stabilisation diagram's backdrop), for a Rerun output that
    /// draws them; without one they are not computed (60 ms a 10-minute,
    /// 12-channel window).
    pub fn draw_spectra(&mut self) {
        if let Some(identification) = self.identification.as_mut() {
            identification.with_spectrum = true;
        }
    }

    /// Hands the update side to the caller, for updates on another thread
    /// than the ingest: the caller rebases each job on it, runs it and
    /// applies the outcome to it, in order, and stamps health messages with
    /// [`Health::set_updates`]. Jobs from this pipeline then start from its
    /// initial parameters until rebased. With identification (output-only
    /// or both paths), a window's modes are paired with the model at the
    /// last update: the updater sends the model back after each job, and
    /// the ingest identifies a window (the costly part, which needs no
    /// model) while the update side works, then waits for every job it
    /// handed out before that window closed, exactly the state the in-line
    /// replay pairs with. The caller must apply every job handed out.
    pub fn split_updater(&mut self) -> Updater {
        self.split = true;
        if self.identification.is_none() {
            return self.updater.clone();
        }
        let (updater, link) = self.updater.linked();
        self.pairing = Some(link);
        updater
    }

    /// Measurement time up to which every channel's samples have been
    /// analysed; `None` before the stream's rate and origin are agreed on.
    pub fn measured_until(&self) -> Option<i128> {
        let (fs, t0) = (self.fs?, self.t0?);
        Some(t0 + (self.fed as f64 * 1e9 / fs).round() as i128)
    }

    pub fn parameters(&self) -> &[Parameter] {
        &self.parameters
    }

    /// Counts a message the decoder rejected.
    pub fn reject_message(&mut self, error: &WireError) {
        self.health.reject(error.reason());
    }

    /// Takes one decoded block; returns the windows it closed and the update
    /// jobs they triggered.
    pub fn ingest(&mut self, block: ChannelBlock) -> (Vec<WindowReport>, Vec<UpdateJob>) {
        let mut windows = Vec::new();
        let mut jobs = Vec::new();
        if block.quantity == ChannelQuantity::Temperature {
            self.ingest_temperature(&block);
        } else if self.channel_of(&block).is_none() {
            self.health.reject("unknown_channel");
        } else if self.fs.is_none() {
            self.pending.push(block);
            if self.pending.len() >= 2 * self.channels.len() {
                self.establish_reference(&mut windows, &mut jobs);
            }
        } else {
            self.ingest_block(block, &mut windows, &mut jobs);
        }
        self.hand_out(jobs.len());
        (windows, jobs)
    }

    /// Ends the stream: blocks still held for the reference
    /// (`establish_reference`) are decided on with what arrived.
    pub fn finish(&mut self) -> (Vec<WindowReport>, Vec<UpdateJob>) {
        let mut windows = Vec::new();
        let mut jobs = Vec::new();
        self.establish_reference(&mut windows, &mut jobs);
        self.hand_out(jobs.len());
        (windows, jobs)
    }

    /// Counts jobs leaving the pipeline (split with identification: the
    /// pairing waits for them).
    fn hand_out(&mut self, jobs: usize) {
        if let Some(link) = self.pairing.as_mut() {
            link.handed_out(jobs);
        }
    }

    /// The model's modes at the last accepted parameters, to pair a
    /// window's identified modes with (split: once the update side has
    /// applied every job handed out); the error is the window's skip reason.
    fn pairing_state(&mut self) -> Result<Arc<ModalState>, String> {
        let settled = match self.pairing.as_mut().map(|link| link.settled()).transpose() {
            Ok(settled) => settled.flatten(),
            // The update side stopped: the replay ends with its error, and
            // nothing reads this window.
            Err(_) => return Err("update_stage_stopped".into()),
        };
        let state = match settled {
            Some(state) => state,
            None => self.updater.model_state().map_err(|e| format!("{e:#}")),
        };
        state.map_err(|e| {
            tracing::warn!(message = "the model's modes at the last parameters failed", error = %e);
            "model_failed".to_string()
        })
    }

    fn channel_of(&self, block: &ChannelBlock) -> Option<usize> {
        self.channels
            .iter()
            .position(|(n, q)| *n == block.name && *q == block.quantity)
    }

    /// An update job on what was measured over `span` (ns).
    fn job(&mut self, window: u64, span: (i128, i128), measured: Measured) -> UpdateJob {
        UpdateJob {
            window,
            time_ns: span.1,
            environment: self.environment(span.0, span.1),
            measured,
            pairing: (self.config.updating.min_mac, self.config.updating.max_frequency_gap),
            setup: Arc::clone(&self.setup),
            parameters: self.parameters.clone(),
            settings: self.settings.clone(),
            start: self.updater.start_values(),
            previous: self.updater.last_point(),
            created: std::time::Instant::now(),
        }
    }

    /// Moves a job made earlier to start from the parameters accepted since
    /// ([`Updater::rebase`]).
    pub fn rebase(&self, job: &mut UpdateJob) {
        self.updater.rebase(job);
    }

    /// Records an update's outcome ([`Updater::apply`]): accepted parameters
    /// replace the last good ones; a failure keeps them. With `[monitoring]`,
    /// an accepted update is scored: the status (and alarm) messages are
    /// returned.
    pub fn apply(&mut self, outcome: &mut UpdateOutcome) -> Option<MonitoringOutcome> {
        debug_assert!(!self.split, "outcomes go to the split-off updater");
        let scored = self.updater.apply(outcome);
        self.health.set_updates(self.updater.counters());
        scored
    }

    /// The monitor (`[monitoring]`), to persist its reference and state.
    pub fn monitor(&self) -> Option<&splinewatch_core::monitoring::Monitor> {
        self.updater.monitor()
    }

    /// Resumes a persisted monitor (a restart does not retrain); refused
    /// when it does not fit this config's parameters and channels.
    pub fn restore_monitor(&mut self, monitor: splinewatch_core::monitoring::Monitor) -> Result<()> {
        self.updater.restore_monitor(monitor)
    }
}

/// The schedule's values, and a persisted state's parameters against the
/// config's.
fn check_schedule_and_state(
    schedule: &ScheduleConfig,
    state: Option<&AcceptedParameters>,
    parameters: &[Parameter],
) -> Result<()> {
    if schedule.update_every_windows == 0 {
        bail!("config: schedule.update_every_windows: must be at least 1");
    }
    if let Some(m) = schedule.update_every_minutes {
        if !(m.is_finite() && m > 0.0) {
            bail!("config: schedule.update_every_minutes: must be positive, got {m}");
        }
    }
    for p in state.iter().flat_map(|s| &s.parameters) {
        if !parameters.iter().any(|q| q.name == p.name) {
            bail!(
                "state: parameter {:?} is not an updating parameter of this config",
                p.name
            );
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::wire::parse_timestamp;

    fn config() -> Config {
        let text = include_str!("../../config/sinello.toml").replace("window_seconds = 20.0", "window_seconds = 8.0");
        Config::from_toml(&text).unwrap()
    }

    fn block(name: &str, quantity: ChannelQuantity, second: f64, n: usize, fs: f64) -> ChannelBlock {
        ChannelBlock {
            name: name.into(),
            quantity,
            unit: String::new(),
            fs,
            start_ns: parse_timestamp("2026-11-21T10:00:00Z").unwrap() + (second * 1e9) as i128,
            data: (0..n).map(|k| ((k * 7 + name.len()) % 13) as f64 - 6.0).collect(),
        }
    }

    fn all_channels(p: &mut Pipeline, second: f64) -> usize {
        let mut closed = p
            .ingest(block("P1", ChannelQuantity::Force, second, 256, 256.0))
            .0
            .len();
        for i in 1..=12 {
            closed += p
                .ingest(block(
                    &format!("P{i}"),
                    ChannelQuantity::Acceleration,
                    second,
                    256,
                    256.0,
                ))
                .0
                .len();
        }
        closed
    }

    #[test]
    fn bad_blocks_are_counted_by_reason_and_valid_ones_still_used() {
        let mut p = Pipeline::new(&config(), ScheduleConfig::default(), None).unwrap();
        // Two blocks per channel set the grid's rate and origin.
        all_channels(&mut p, 0.0);
        all_channels(&mut p, 1.0);
        p.ingest(block("P99", ChannelQuantity::Acceleration, 1.0, 256, 256.0));
        p.ingest(block("P2", ChannelQuantity::Acceleration, 1.0, 256, 200.0));
        p.ingest(block("P2", ChannelQuantity::Acceleration, 0.5, 256, 256.0));
        p.ingest(block(
            "P2",
            ChannelQuantity::Acceleration,
            1.0 + 0.5 / 256.0,
            256,
            256.0,
        ));
        p.ingest(block("P2", ChannelQuantity::Acceleration, 1e6, 256, 256.0));
        let h = p.health().clone();
        for reason in [
            "unknown_channel",
            "rate_mismatch",
            "time_overlap",
            "misaligned",
            "far_future",
        ] {
            assert_eq!(h.rejected.get(reason), Some(&1), "{reason}: {:?}", h.rejected);
        }
        // The valid stream continues: 8 s windows close.
        let mut closed = 0;
        for s in 2..16 {
            closed += all_channels(&mut p, s as f64);
        }
        assert_eq!(closed, 2);
        assert_eq!(p.health().blocks, 16 * 13);
    }

    #[test]
    fn a_gap_becomes_nan_samples_that_the_welch_gates_reject() {
        let mut p = Pipeline::new(&config(), ScheduleConfig::default(), None).unwrap();
        let mut windows = Vec::new();
        for s in 0..16 {
            let mut w = p.ingest(block("P1", ChannelQuantity::Force, s as f64, 256, 256.0)).0;
            for i in 1..=12 {
                // P5 misses seconds 3 and 4.
                if i == 5 && (s == 3 || s == 4) {
                    continue;
                }
                w.extend(
                    p.ingest(block(
                        &format!("P{i}"),
                        ChannelQuantity::Acceleration,
                        s as f64,
                        256,
                        256.0,
                    ))
                    .0,
                );
            }
            windows.extend(w);
        }
        let h = p.health();
        assert_eq!(h.gaps, 1);
        assert_eq!(h.gap_samples, 512);
        assert_eq!(windows.len(), 2);
        // Window 0 (0–8 s): 4 s segments with 2 s hop; those touching 3–5 s are rejected.
        assert!(windows[0].segments_rejected >= 2, "{:?}", windows[0].segments_rejected);
        assert_eq!(windows[1].segments_rejected, 0);
    }

    /// The bundled output-only config with one-minute windows and a smaller
    /// Hankel matrix, so a window is quick to identify.
    fn output_only_config() -> Config {
        let text = include_str!("../../config/sinello-ambient.toml")
            .replace("window_seconds = 1200.0", "window_seconds = 60.0")
            .replace("block_rows = 40", "block_rows = 20")
            .replace("max_order = 120", "max_order = 40");
        Config::from_toml(&text).unwrap()
    }

    /// Feeds `seconds` of one-second blocks on P1–P12 with `value(channel, t)`,
    /// but no block where `missing(channel, second)`; returns the closed windows.
    fn feed_outputs(
        p: &mut Pipeline,
        seconds: usize,
        missing: &dyn Fn(usize, usize) -> bool,
        value: &mut dyn FnMut(usize, usize) -> f64,
    ) -> Vec<WindowReport> {
        let mut windows = Vec::new();
        let mut t = 0;
        for s in 0..seconds {
            for c in (0..12).filter(|&c| !missing(c, s)) {
                let mut b = block(
                    &format!("P{}", c + 1),
                    ChannelQuantity::Acceleration,
                    s as f64,
                    256,
                    256.0,
                );
                b.data = (0..256).map(|k| value(c, t + k)).collect();
                windows.extend(p.ingest(b).0);
            }
            t += 256;
        }
        windows
    }

    /// A small deterministic generator (xorshift) of standard normal values.
    fn normal(state: &mut u64) -> f64 {
        let mut uniform = || {
            *state ^= *state << 13;
            *state ^= *state >> 7;
            *state ^= *state << 17;
            (*state >> 11) as f64 / (1u64 << 53) as f64
        };
        let (u, v) = (uniform().max(1e-300), uniform());
        (-2.0 * u.ln()).sqrt() * (2.0 * std::f64::consts::PI * v).cos()
    }

    #[test]
    fn output_only_windows_are_skipped_with_their_reason() {
        // A silent deck: the Hankel matrix is singular.
        let mut p = Pipeline::new(&output_only_config(), ScheduleConfig::default(), None).unwrap();
        let w = feed_outputs(&mut p, 61, &|_, _| false, &mut |_, _| 0.0);
        assert_eq!(w.len(), 1);
        assert_eq!(w[0].skipped.as_deref(), Some("singular_hankel"), "{:?}", w[0].skipped);

        // P5 silent for 40 of the 60 seconds: too little valid data.
        let mut p = Pipeline::new(&output_only_config(), ScheduleConfig::default(), None).unwrap();
        let mut rng = 7u64;
        let windows = feed_outputs(&mut p, 61, &|c, s| c == 4 && (10..50).contains(&s), &mut |_, _| {
            normal(&mut rng)
        });
        assert_eq!(windows[0].skipped.as_deref(), Some("too_little_data"));
        assert!(
            windows[0].valid_fraction.unwrap() < 0.4,
            "{:?}",
            windows[0].valid_fraction
        );

        // One lightly damped 2 Hz mode, the same at every sensor: identified,
        // but no model mode is near it.
        let mut p = Pipeline::new(&output_only_config(), ScheduleConfig::default(), None).unwrap();
        let (dt, f, zeta) = (1.0 / 256.0, 2.0, 0.02);
        let w0 = 2.0 * std::f64::consts::PI * f;
        let (a1, a2) = (
            2.0 * (-zeta * w0 * dt).exp() * (w0 * dt).cos(),
            -(-2.0 * zeta * w0 * dt).exp(),
        );
        let (mut y1, mut y2, mut rng) = (0.0, 0.0, 11u64);
        let mut mode = Vec::new();
        for _ in 0..61 * 256 {
            let y = a1 * y1 + a2 * y2 + normal(&mut rng);
            (y2, y1) = (y1, y);
            mode.push(y);
        }
        let mut noise = 13u64;
        let w = feed_outputs(&mut p, 61, &|_, _| false, &mut |_, t| {
            mode[t] + 0.05 * normal(&mut noise)
        });
        assert_eq!(w[0].skipped.as_deref(), Some("no_pairable_mode"), "{:?}", w[0].skipped);
        let h = p.health();
        assert_eq!(h.windows_accepted, 0);
        assert_eq!(h.windows_skipped.get("no_pairable_mode"), Some(&1));
    }
}
