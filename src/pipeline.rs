//! The monitoring pipeline shared by the live daemon and offline replay:
//! decoded channel blocks in, windowed FRFs and warm-started updates out.
//!
//! - **Alignment.** The sample grid is anchored at the first accepted block;
//!   every channel must sit on it (within 1 % of a sample). A missing stretch
//!   (gap, late or silent channel) is filled with NaN so that the Welch gates
//!   reject exactly the segments it touches; a block that goes back in time
//!   is rejected. Nothing is buffered beyond `max_lag_seconds` per channel.
//! - **Windows.** Aligned samples stream into a Welch estimator; at each
//!   window end the FRFs are estimated and the window is accepted, or
//!   skipped with a reason (too few clean segments, low coherence).
//! - **Updating.** Every `update_every_windows` accepted windows an update
//!   job is produced (warm-started from the last accepted parameters, the
//!   config's values at first). The caller runs it (inline for replay, on a
//!   blocking worker live) and hands the outcome back; a failed or
//!   non-converged run keeps the last good parameters.

use crate::commands::{self, FrfSetup};
use crate::config::Config;
use crate::frf_json::{FrfEntry, FrfFile};
use crate::wire::{ChannelBlock, ChannelQuantity, WireError};
use anyhow::{bail, Result};
use serde::{Deserialize, Serialize};
use splinewatch_core::damping::DampingCurve;
use splinewatch_core::frf::Quantity;
use splinewatch_core::modal::ModeKind;
use splinewatch_core::updating::{ModelPoint, Parameter, UpdateProblem, UpdateResult, UpdateSettings};
use splinewatch_core::welch::{Estimator, WelchEstimator, WelchSettings};
use std::collections::{BTreeMap, VecDeque};
use std::sync::Arc;

/// Scheduling and quality settings (`[schedule]`).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ScheduleConfig {
    /// Run the updating after this many accepted windows.
    pub update_every_windows: u64,
    /// If set, run the updating instead at the first accepted window ending at
    /// least this many minutes (of measurement time) after the previous update
    /// (or the first sample); `update_every_windows` is then ignored.
    pub update_every_minutes: Option<f64>,
    /// Skip a window whose FRFs have a mean coherence in the band below this.
    pub min_coherence: f64,
    /// Skip a window with fewer clean segments than this fraction of the possible ones.
    pub min_segment_fraction: f64,
    /// A channel may lag the others by at most this; beyond, its missing samples count as a gap.
    pub max_lag_seconds: f64,
}

impl Default for ScheduleConfig {
    fn default() -> Self {
        Self {
            update_every_windows: 1,
            update_every_minutes: None,
            min_coherence: 0.6,
            min_segment_fraction: 0.5,
            max_lag_seconds: 30.0,
        }
    }
}

/// Counters published on `<prefix>/health`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Health {
    pub blocks: u64,
    pub samples: u64,
    /// Rejected messages and blocks by reason.
    pub rejected: BTreeMap<String, u64>,
    pub gaps: u64,
    pub gap_samples: u64,
    pub segments_accepted: u64,
    pub segments_rejected: u64,
    pub windows_accepted: u64,
    pub windows_skipped: BTreeMap<String, u64>,
    pub update_runs: u64,
    pub update_failures: u64,
    pub queue_drops: u64,
    /// Raw-input recording errors (write failures, full disk); the block
    /// is still analysed.
    #[serde(default)]
    pub recording_errors: u64,
    /// Results MCAP errors (write failures; a new file is opened).
    #[serde(default)]
    pub results_errors: u64,
    /// Rerun output errors (e.g. a rotated `.rrd` that cannot be created).
    #[serde(default)]
    pub rerun_errors: u64,
}

impl Health {
    pub fn reject(&mut self, reason: &str) {
        *self.rejected.entry(reason.to_string()).or_insert(0) += 1;
    }
}

/// The last accepted parameters (persisted in the state file).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AcceptedParameters {
    pub window: u64,
    pub time: String,
    pub parameters: Vec<StateParameter>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StateParameter {
    pub name: String,
    pub value: f64,
    pub std: Option<f64>,
}

/// A closed analysis window.
#[derive(Debug, Clone)]
pub struct WindowReport {
    pub index: u64,
    pub start_ns: i128,
    pub end_ns: i128,
    pub segments_accepted: u64,
    pub segments_rejected: u64,
    /// Mean coherence in the band per FRF.
    pub mean_coherence: Vec<f64>,
    /// `None` when accepted.
    pub skipped: Option<String>,
    pub frf: Option<FrfFile>,
}

/// An updating run to do: owns everything it needs, so it can run on
/// another thread.
pub struct UpdateJob {
    pub window: u64,
    pub time_ns: i128,
    pub measured: FrfFile,
    setup: Arc<FrfSetup>,
    parameters: Vec<Parameter>,
    settings: UpdateSettings,
    start: Vec<f64>,
    /// The model at the last accepted parameters, if known: the solve starts
    /// from it instead of re-evaluating the model there.
    previous: Option<Arc<ModelPoint>>,
}

/// What an update produced.
#[derive(Debug, Clone)]
pub struct UpdateOutcome {
    pub window: u64,
    pub time_ns: i128,
    pub measured: FrfFile,
    pub result: Result<UpdateReport, String>,
    /// The model at the identified parameters, taken by [`Pipeline::apply`]
    /// for the next warm start (kept outcomes do not hold it: ~2 MB).
    point: Option<Arc<ModelPoint>>,
}

/// How many bending mode shapes an update report carries (for the views).
pub const BENDING_MODES_KEPT: usize = 4;

/// A mode of the updated model with its shape on every (full) dof.
#[derive(Debug, Clone)]
pub struct ModeShape {
    pub frequency_hz: f64,
    pub damping_ratio: f64,
    pub shape: Vec<f64>,
}

#[derive(Debug, Clone)]
pub struct UpdateReport {
    pub result: UpdateResult,
    /// Model FRFs at the identified parameters, on the measured lines.
    pub model: FrfFile,
    /// `(frequency Hz, damping ratio, kind)` of the updated model below the band's top.
    pub modes: Vec<(f64, f64, ModeKind)>,
    /// The first [`BENDING_MODES_KEPT`] bending modes, with their shapes.
    pub bending_modes: Vec<ModeShape>,
    /// `|h_x - h_a| / |h_x|` per FRF and line.
    pub residue: Vec<Vec<f64>>,
    /// The identified spring coefficients (per field) and damping curve.
    pub kappa: Vec<Vec<f64>>,
    pub damping: DampingCurve,
}

impl UpdateJob {
    pub fn run(self) -> UpdateOutcome {
        let (result, point) = match self.compute() {
            Ok((report, point)) => (Ok(report), Some(Arc::new(point))),
            Err(e) => (Err(format!("{e:#}")), None),
        };
        UpdateOutcome {
            window: self.window,
            time_ns: self.time_ns,
            measured: self.measured,
            result,
            point,
        }
    }

    fn compute(&self) -> Result<(UpdateReport, ModelPoint)> {
        let measured = self.measured.to_measured(&self.setup.sensor_names)?;
        let problem = UpdateProblem::new(
            &self.setup.model,
            self.setup.kappa.clone(),
            self.setup.damping.clone(),
            self.parameters.clone(),
            &measured,
            self.settings.clone(),
        )?;
        let solution = problem.solve_from(&self.start, self.previous.as_deref(), &mut |_| {})?;
        let (result, point) = (solution.result, solution.point);
        if result.parameters.iter().any(|p| !p.value.is_finite()) {
            bail!("non-finite parameters");
        }
        if !result.converged {
            bail!("the updating did not converge ({:?})", result.stop_reason);
        }
        let (state, h) = (point.state(), point.frfs());
        let lines = problem.line_frequencies().to_vec();
        let sel = problem.line_indices();
        let nl = lines.len();
        let mut model_entries = Vec::new();
        let mut residue = Vec::new();
        for (b, m) in measured.frfs().iter().enumerate() {
            let hs = &h[b * nl..(b + 1) * nl];
            model_entries.push(FrfEntry {
                input: self.setup.sensor_names[m.input].clone(),
                output: self.setup.sensor_names[m.output].clone(),
                re: hs.iter().map(|v| v.re).collect(),
                im: hs.iter().map(|v| v.im).collect(),
                coherence: None,
                n_averages: None,
            });
            residue.push(
                sel.iter()
                    .zip(hs)
                    .map(|(&i, a)| {
                        let x = m.values[i];
                        (x - a).norm() / x.norm().max(f64::MIN_POSITIVE)
                    })
                    .collect(),
            );
        }
        let (kappa, damping) = (point.kappa().to_vec(), point.damping().clone());
        let top = lines.last().copied().unwrap_or(0.0);
        let modes = (0..state.modes.len())
            .filter(|&i| state.modes.frequency_hz(i) <= top)
            .map(|i| (state.modes.frequency_hz(i), state.zeta[i], state.modes.kinds[i]))
            .collect();
        let bending_modes = (0..state.modes.len())
            .filter(|&i| state.modes.kinds[i] == ModeKind::Bending)
            .take(BENDING_MODES_KEPT)
            .map(|i| ModeShape {
                frequency_hz: state.modes.frequency_hz(i),
                damping_ratio: state.zeta[i],
                shape: (0..state.modes.shapes.nrows())
                    .map(|d| state.modes.shapes[(d, i)])
                    .collect(),
            })
            .collect();
        let report = UpdateReport {
            result,
            model: FrfFile {
                quantity: self.measured.quantity,
                frequency_hz: lines,
                frfs: model_entries,
            },
            modes,
            bending_modes,
            residue,
            kappa,
            damping,
        };
        Ok((report, point))
    }
}

/// Two sampling rates are the same to 1e-9 relative.
fn same_rate(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * a
}

struct ChannelQueue {
    /// Grid index of the first buffered sample.
    first: i64,
    data: VecDeque<f64>,
    seen: bool,
}

impl ChannelQueue {
    fn end(&self) -> i64 {
        self.first + self.data.len() as i64
    }
}

/// The pipeline state machine.
pub struct Pipeline {
    config: Config,
    schedule: ScheduleConfig,
    setup: Arc<FrfSetup>,
    parameters: Vec<Parameter>,
    settings: UpdateSettings,
    force: usize,
    accels: Vec<usize>,
    /// Channel identities in queue order: force first.
    channels: Vec<(String, ChannelQuantity)>,
    queues: Vec<ChannelQueue>,
    fs: Option<f64>,
    t0: Option<i128>,
    /// Blocks held until the sampling rate and time origin are agreed on
    /// (`establish_reference`).
    pending: Vec<ChannelBlock>,
    /// Welch settings and FRF estimator, once the rate is known.
    welch: Option<(WelchSettings, Estimator)>,
    /// Windows being estimated (several when they overlap), oldest first:
    /// window `k` spans grid samples `[k·hop, k·hop + window_samples)`.
    open: VecDeque<(u64, WelchEstimator)>,
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
    frf_sets: u64,
    /// Measurement time of the last update (or the first sample).
    last_update_ns: Option<i128>,
    last: Option<AcceptedParameters>,
    /// The model at `last`, when the update that produced it ran here.
    last_point: Option<Arc<ModelPoint>>,
    health: Health,
}

impl Pipeline {
    pub fn new(config: &Config, schedule: ScheduleConfig, state: Option<AcceptedParameters>) -> Result<Self> {
        let setup = Arc::new(commands::frf_setup(config)?);
        let parameters = config.build_parameters()?;
        let settings = config.update_settings()?;
        let (force, accels) = config.channel_roles()?;
        if schedule.update_every_windows == 0 {
            bail!("config: schedule.update_every_windows: must be at least 1");
        }
        if let Some(m) = schedule.update_every_minutes {
            if !(m.is_finite() && m > 0.0) {
                bail!("config: schedule.update_every_minutes: must be positive, got {m}");
            }
        }
        if let Some(s) = &state {
            for p in &s.parameters {
                if !parameters.iter().any(|q| q.name == p.name) {
                    bail!(
                        "state: parameter {:?} is not an updating parameter of this config",
                        p.name
                    );
                }
            }
        }
        let names: Vec<String> = config.sensors.iter().map(|s| s.name.clone()).collect();
        let mut channels = vec![(names[force].clone(), ChannelQuantity::Force)];
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
        Ok(Self {
            config: config.clone(),
            schedule,
            setup,
            parameters,
            settings,
            force,
            accels,
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
            frf_sets: 0,
            last_update_ns: None,
            last: state,
            last_point: None,
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
        self.last.as_ref()
    }

    pub fn parameters(&self) -> &[Parameter] {
        &self.parameters
    }

    /// Takes a pre-computed FRF message (the FRF JSON object, usually with a
    /// single entry). Once every force → acceleration pair of the config has
    /// arrived on the same frequency axis, the set becomes an update job
    /// (numbered after the windows, from 1 000 000) and the inbox empties. A
    /// message on another axis starts a new set. Returns the job, if any.
    pub fn ingest_frf(&mut self, payload: &[u8], time_ns: i128) -> Option<UpdateJob> {
        let file = match std::str::from_utf8(payload).ok().and_then(|t| FrfFile::parse(t).ok()) {
            Some(f) => f,
            None => {
                self.health.reject("bad_frf");
                return None;
            }
        };
        let known = |n: &str| self.setup.sensor_names.iter().any(|s| s == n);
        if file.frfs.is_empty()
            || file.frfs.iter().any(|e| {
                !known(&e.input)
                    || !known(&e.output)
                    || e.re.len() != file.frequency_hz.len()
                    || e.im.len() != e.re.len()
            })
        {
            self.health.reject("bad_frf");
            return None;
        }
        let axis = (file.quantity, file.frequency_hz.clone());
        if self.frf_axis.as_ref() != Some(&axis) {
            self.frf_inbox.clear();
            self.frf_axis = Some(axis);
        }
        for e in file.frfs {
            self.frf_inbox.insert((e.input.clone(), e.output.clone()), e);
        }
        let force = self.setup.sensor_names[self.force].clone();
        let wanted: Vec<(String, String)> = self
            .accels
            .iter()
            .map(|&i| (force.clone(), self.setup.sensor_names[i].clone()))
            .collect();
        if !wanted.iter().all(|k| self.frf_inbox.contains_key(k)) {
            return None;
        }
        let (quantity, frequency_hz) = self.frf_axis.clone().expect("set above");
        let frfs = wanted
            .iter()
            .map(|k| self.frf_inbox.remove(k).expect("checked"))
            .collect();
        self.frf_inbox.clear();
        self.frf_sets += 1;
        let measured = FrfFile {
            quantity,
            frequency_hz,
            frfs,
        };
        Some(self.job(1_000_000 + self.frf_sets - 1, time_ns, measured))
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
        if self.channel_of(&block).is_none() {
            self.health.reject("unknown_channel");
            return (windows, jobs);
        }
        if self.fs.is_none() {
            self.pending.push(block);
            if self.pending.len() >= 2 * self.channels.len() {
                self.establish_reference(&mut windows, &mut jobs);
            }
            return (windows, jobs);
        }
        self.ingest_block(block, &mut windows, &mut jobs);
        (windows, jobs)
    }

    /// Ends the stream: blocks still held for the reference
    /// (`establish_reference`) are decided on with what arrived.
    pub fn finish(&mut self) -> (Vec<WindowReport>, Vec<UpdateJob>) {
        let mut windows = Vec::new();
        let mut jobs = Vec::new();
        self.establish_reference(&mut windows, &mut jobs);
        (windows, jobs)
    }

    fn channel_of(&self, block: &ChannelBlock) -> Option<usize> {
        self.channels
            .iter()
            .position(|(n, q)| *n == block.name && *q == block.quantity)
    }

    /// Agrees on the sampling rate and the time origin from the first
    /// `2 × channels` blocks instead of trusting the first one, which could
    /// be bad (a wrong rate, a timestamp in 2099) and would then make every
    /// valid block after it look wrong. The most common rate wins (ties: the
    /// one seen first); among the blocks at that rate, those within the
    /// far-future horizon of the median start are inliers and the earliest
    /// inlier is the origin. The held blocks then go through the usual checks
    /// in time order, so the outliers are counted by reason like any others.
    fn establish_reference(&mut self, windows: &mut Vec<WindowReport>, jobs: &mut Vec<UpdateJob>) {
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
        match self.config.welch_settings(fs) {
            Ok((settings, estimator)) => {
                self.window_samples = (self.config.frf.window_seconds * fs).round() as i64;
                self.hop_samples = self
                    .config
                    .frf
                    .window_hop_seconds
                    .map_or(self.window_samples, |hop| ((hop * fs).round() as i64).max(1));
                self.welch = Some((settings, estimator));
            }
            Err(_) => {
                for _ in &pending {
                    self.health.reject("bad_fs_for_frf_settings");
                }
                return;
            }
        }
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
    fn ingest_block(&mut self, block: ChannelBlock, windows: &mut Vec<WindowReport>, jobs: &mut Vec<UpdateJob>) {
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
        queue.data.extend(block.data.iter().copied());
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

    /// Feeds every sample available on all channels to the open windows,
    /// opening and closing windows on the way.
    fn feed(&mut self, windows: &mut Vec<WindowReport>, jobs: &mut Vec<UpdateJob>) {
        loop {
            let next_start = self.window_index as i64 * self.hop_samples;
            if next_start == self.fed {
                let (settings, _) = self.welch.as_ref().expect("set with the reference");
                let estimator = WelchEstimator::new(settings.clone(), self.accels.len()).expect("validated");
                self.open.push_back((self.window_index, estimator));
                self.window_index += 1;
                continue;
            }
            let frontier = self
                .queues
                .iter()
                .map(|q| if q.seen { q.end() } else { self.fed })
                .min()
                .unwrap_or(self.fed);
            let oldest_end = self
                .open
                .front()
                .map_or(i64::MAX, |(k, _)| *k as i64 * self.hop_samples + self.window_samples);
            let until = frontier.min(next_start).min(oldest_end);
            if until > self.fed {
                let n = (until - self.fed) as usize;
                let mut take = |q: &mut ChannelQueue| -> Vec<f64> {
                    let skip = (self.fed - q.first).max(0) as usize;
                    q.data.drain(..skip.min(q.data.len()));
                    q.first += skip as i64;
                    let v: Vec<f64> = q.data.drain(..n.min(q.data.len())).collect();
                    q.first += v.len() as i64;
                    v
                };
                let cols: Vec<Vec<f64>> = self.queues.iter_mut().map(&mut take).collect();
                let outputs: Vec<&[f64]> = cols[1..].iter().map(|v| v.as_slice()).collect();
                for (_, welch) in &mut self.open {
                    welch.push(&cols[0], &outputs).expect("equal lengths by construction");
                }
                self.fed = until;
            }
            if self.fed == oldest_end {
                let (index, welch) = self.open.pop_front().expect("an open window ends here");
                let report = self.close_window(index, welch);
                if report.skipped.is_none() {
                    self.accepted_since_update += 1;
                    let since = *self
                        .last_update_ns
                        .get_or_insert(self.t0.expect("set with the reference"));
                    let due = match self.schedule.update_every_minutes {
                        Some(minutes) => (report.end_ns - since) as f64 >= minutes * 60e9,
                        None => self.accepted_since_update >= self.schedule.update_every_windows,
                    };
                    if due {
                        self.accepted_since_update = 0;
                        self.last_update_ns = Some(report.end_ns);
                        if let Some(frf) = &report.frf {
                            jobs.push(self.job(report.index, report.end_ns, frf.clone()));
                        }
                    }
                }
                windows.push(report);
                continue;
            }
            break;
        }
    }

    fn close_window(&mut self, index: u64, welch: WelchEstimator) -> WindowReport {
        let fs = self.fs.expect("set with the reference");
        let t0 = self.t0.expect("set with the reference");
        let start = index as i64 * self.hop_samples;
        let start_ns = t0 + (start as f64 * 1e9 / fs).round() as i128;
        let end_ns = t0 + ((start + self.window_samples) as f64 * 1e9 / fs).round() as i128;
        let (_, estimator) = self.welch.as_ref().expect("set with the reference");
        let counts = welch.counts();
        self.health.segments_accepted += counts.accepted;
        self.health.segments_rejected += counts.rejected();
        let settings: &WelchSettings = welch.settings();
        let possible = ((self.window_samples as usize).saturating_sub(settings.segment) / settings.step() + 1) as f64;
        let mut report = WindowReport {
            index,
            start_ns,
            end_ns,
            segments_accepted: counts.accepted,
            segments_rejected: counts.rejected(),
            mean_coherence: Vec::new(),
            skipped: None,
            frf: None,
        };
        if (counts.accepted as f64) < self.schedule.min_segment_fraction * possible || counts.accepted == 0 {
            report.skipped = Some("too_little_data".into());
        } else {
            let est = welch.spectra().frf(*estimator);
            let [lo, hi] = self.config.frf.band;
            let lines: Vec<usize> = (0..est.frequencies.len())
                .filter(|&k| est.frequencies[k] > 0.0 && est.frequencies[k] >= lo && est.frequencies[k] <= hi)
                .collect();
            report.mean_coherence = est
                .coherence
                .iter()
                .map(|c| lines.iter().map(|&k| c[k]).sum::<f64>() / lines.len().max(1) as f64)
                .collect();
            if report
                .mean_coherence
                .iter()
                .any(|c| !(c.is_finite() && *c >= self.schedule.min_coherence))
            {
                report.skipped = Some("low_coherence".into());
            } else {
                report.frf = crate::estimate::frf_file(&self.config, &est, self.force, &self.accels);
                if report.frf.is_none() {
                    report.skipped = Some("no_lines_in_band".into());
                }
            }
        }
        match &report.skipped {
            None => self.health.windows_accepted += 1,
            Some(reason) => *self.health.windows_skipped.entry(reason.clone()).or_insert(0) += 1,
        }
        report
    }

    fn job(&self, window: u64, time_ns: i128, measured: FrfFile) -> UpdateJob {
        UpdateJob {
            window,
            time_ns,
            measured,
            setup: Arc::clone(&self.setup),
            parameters: self.parameters.clone(),
            settings: self.settings.clone(),
            start: self.start_values(),
            previous: self.last_point.clone(),
        }
    }

    /// The last accepted parameters (the config's values for those never
    /// updated).
    fn start_values(&self) -> Vec<f64> {
        let base = splinewatch_core::updating::base_values(&self.parameters, &self.setup.kappa, &self.setup.damping);
        match &self.last {
            Some(last) => self
                .parameters
                .iter()
                .zip(base)
                .map(|(p, b)| last.parameters.iter().find(|s| s.name == p.name).map_or(b, |s| s.value))
                .collect(),
            None => base,
        }
    }

    /// Moves a job made earlier (one that waited while another update ran)
    /// to start from the parameters accepted since: every update starts
    /// from the latest result, however the updates were scheduled, so the
    /// live daemon gives the replay's parameters even when its updates queue.
    pub fn rebase(&self, job: &mut UpdateJob) {
        job.start = self.start_values();
        job.previous = self.last_point.clone();
    }

    /// Records an update's outcome: accepted parameters replace the last
    /// good ones; a failure keeps them.
    pub fn apply(&mut self, outcome: &mut UpdateOutcome) {
        self.health.update_runs += 1;
        match &outcome.result {
            Ok(report) => {
                self.last_point = outcome.point.take();
                self.last = Some(AcceptedParameters {
                    window: outcome.window,
                    time: crate::wire::format_timestamp(outcome.time_ns),
                    parameters: report
                        .result
                        .parameters
                        .iter()
                        .map(|p| StateParameter {
                            name: p.name.clone(),
                            value: p.value,
                            std: p.std,
                        })
                        .collect(),
                });
            }
            Err(_) => self.health.update_failures += 1,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::wire::parse_timestamp;

    fn config() -> Config {
        let text = include_str!("../config/sinello.toml").replace("window_seconds = 20.0", "window_seconds = 8.0");
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
}
