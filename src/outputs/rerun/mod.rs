//! Rerun output (0.36): trends and the latest update, to a `.rrd` file
//! and/or a live viewer, with a blueprint sent from here.
//!
//! Timelines: `measurement_time` (the data's own clock) and `update` (the
//! update index). Entities:
//! - `parameters/springs/<name>`, `parameters/fields/<name>` (stiffness
//!   multipliers θ), `parameters/damping/<name>`: the value and ±1σ as three
//!   series; `residual/relative`; `health/<counter>`;
//! - `frf/<output>/magnitude/{measured,model}` (dB) and
//!   `frf/<output>/phase/{measured,model}` (degrees), bar charts over the
//!   frequency lines; `damping/zeta` (ζ(f) in %) and
//!   `damping/coefficients` (γ_z at their Greville abscissae);
//! - `deck/springs`: the deck mesh coloured by the identified spring field
//!   r33 (N/m³); `deck/stiffness` (with stiffness fields): coloured by the
//!   identified multiplier θ (0.5 → 1.5), `deck/stiffness_change`: by the
//!   standardised change of θ since the first update (−3σ → +3σ); `deck/sensors`; `modes/<k>`: the
//!   first bending modes; `deck/model`: every patch in its own colour, with
//!   `elements` (the knot lines of the analysis nets), `bearings`, `masses`;
//! - `oma/stabilisation` (poles: frequency × order; its child
//!   `first_singular_value`: the output spectral matrix's, log scale mapped
//!   onto the order axis), `oma/singular_values` (Hankel),
//!   `oma/modes/<k>/{frequency_hz,damping_percent}` (value, ±1σ), and
//!   with `[oma.frequency_domain]` the fitted modes' vertical lines
//!   `oma/stabilisation/fitted` (frequency ±1σ) and
//!   `oma/fitted/<k>/{frequency_hz,damping_percent}`: an identification
//!   (`splinewatch oma` or `identify --rerun-save`, and every
//!   output-only window of the daemon and replay); per window also
//!   `oma/trends/mode_<m>/{frequency_hz,damping_percent}` (value, ±1σ, by
//!   the paired model mode `m`, so a trend follows one physical mode) and
//!   `oma/shapes/mode_<m>/{identified,model}`: arrows at the sensors along
//!   their directions, identified (real part, phase-aligned) and model
//!   shape scaled to it;
//! - `residual/modes/mode_<m>`: relative frequency error (%) per paired mode
//!   of a modal-residue update.

mod blueprint;
mod deck;
pub mod events;
mod monitoring;
mod oma;
pub mod prediction;
mod rrd;
mod update;

pub use oma::IdentificationFile;
pub use rrd::{inspect_rrd, RrdSummary};

use crate::config::{Config, FrfSetup};
use crate::pipeline::{Health, UpdateOutcome};
use anyhow::{anyhow, Result};
use deck::DeckGrid;
use splinewatch_core::model::BridgeModel;
use splinewatch_core::response::frf::Sensor;
use std::path::{Path, PathBuf};

/// Where the Rerun stream goes.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RerunTargets {
    /// A `.rrd` file.
    pub save: Option<PathBuf>,
    /// A viewer's gRPC proxy, e.g. `rerun+http://127.0.0.1:9876/proxy`.
    pub connect: Option<String>,
}

impl RerunTargets {
    pub fn is_empty(&self) -> bool {
        self.save.is_none() && self.connect.is_none()
    }
}

/// Mode shapes shown per update.
const MODES_SHOWN: usize = crate::pipeline::BENDING_MODES_KEPT;
/// Grid of the deck mesh along ξ and η (spring knots are added to it).
const GRID: (usize, usize) = (49, 25);

/// θ and σ per stiffness field and coefficient.
type FieldReference = (Vec<Vec<f64>>, Vec<Vec<f64>>);

pub struct RerunOutput {
    rec: rerun::RecordingStream,
    setup: FrfSetup,
    model: BridgeModel,
    grid: DeckGrid,
    updates: i64,
    /// Parameter series already given their static names and colours.
    named: std::collections::BTreeSet<String>,
    targets: RerunTargets,
    sensors: Vec<(String, Sensor)>,
    rotate_ns: i128,
    /// The blueprint's right column: FRF views with a force sensor, OMA
    /// views when windows are identified (output-only, or both paths).
    frf_views: bool,
    oma_views: bool,
    /// Names of the stiffness fields (their parameters are `<name>.s<j>`).
    field_names: Vec<String>,
    /// θ and σ of the first update with stiffness fields: the reference of
    /// the standardised change.
    first_fields: Option<FieldReference>,
    /// Measurement time of the open file's first message.
    file_start_ns: Option<i128>,
    /// Names of the spring fields (their parameters are `<name>.k<j>`).
    spring_names: Vec<String>,
    /// Each updating parameter's trend group ([`update::parameter_group`]).
    parameter_groups: std::collections::BTreeMap<String, &'static str>,
    /// `[monitoring]`: temperature and feature values of the latest windows.
    scatter: std::collections::VecDeque<(f64, Vec<f64>)>,
    /// Whether the config has `[monitoring]` (the blueprint shows its charts).
    monitoring: bool,
}

impl RerunOutput {
    pub fn open(config: &Config, targets: &RerunTargets) -> Result<Self> {
        Self::open_rotating(config, targets, true)
    }

    /// [`Self::open`], with the saved file rotated by measurement time
    /// (`[output] rerun_rotate_hours`) or not: a run over records years
    /// apart (`events`) keeps one file.
    pub fn open_rotating(config: &Config, targets: &RerunTargets, rotate: bool) -> Result<Self> {
        let rec = rerun::RecordingStreamBuilder::new("splinewatch")
            .buffered()
            .map_err(|e| anyhow!("cannot start the Rerun stream: {e}"))?;
        let model = crate::config::solver_model(config)?;
        let setup = crate::config::frf_setup_of(config, &model, &[])?;
        let sensors = config.build_sensors(&model)?;
        let grid = DeckGrid::new(&model);
        let mut out = Self {
            rec,
            setup,
            model,
            grid,
            updates: 0,
            named: Default::default(),
            targets: targets.clone(),
            sensors,
            rotate_ns: if rotate {
                (config.output.rerun_rotate_hours * 3600e9) as i128
            } else {
                i128::MAX
            },
            frf_views: !config.is_output_only(),
            oma_views: config.runs_oma(),
            field_names: config.model.stiffness_fields.iter().map(|f| f.name.clone()).collect(),
            first_fields: None,
            file_start_ns: None,
            spring_names: config.model.springs.iter().map(|s| s.name.clone()).collect(),
            parameter_groups: config
                .build_parameters()?
                .into_iter()
                .map(|p| {
                    let group = update::parameter_group(config.parameter_family(&p.name));
                    (p.name, group)
                })
                .collect(),
            scatter: Default::default(),
            monitoring: config.monitoring.is_some(),
        };
        out.attach_sinks(None)?;
        Ok(out)
    }

    /// Points the stream at its targets; with `stamp`, the file is
    /// `<stem>-<stamp>.rrd` (rotation). Each file gets the blueprint and the
    /// static data, so it opens on its own.
    fn attach_sinks(&mut self, stamp: Option<&str>) -> Result<()> {
        let path = self.targets.save.as_ref().map(|p| match stamp {
            None => p.clone(),
            Some(stamp) => {
                let stem = p
                    .file_stem()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_default();
                p.with_file_name(format!("{stem}-{stamp}.rrd"))
            }
        });
        // Created first with our permissions; the sink truncates and keeps them.
        let file = |p: &PathBuf| {
            crate::io::files::create_output_file(p)?;
            rerun::sink::FileSink::new(p).map_err(|e| anyhow!("Rerun file {}: {e}", p.display()))
        };
        let grpc = |url: &String| -> Result<rerun::sink::GrpcSink> {
            let uri = url
                .parse::<rerun::external::re_uri::ProxyUri>()
                .map_err(|e| anyhow!("rerun_connect {url:?}: {e}"))?;
            Ok(rerun::sink::GrpcSink::new(uri))
        };
        match (&path, &self.targets.connect) {
            (Some(p), None) => self.rec.set_sink(Box::new(file(p)?)),
            (None, Some(url)) => self.rec.set_sink(Box::new(grpc(url)?)),
            (Some(p), Some(url)) => self.rec.set_sinks((file(p)?, grpc(url)?)),
            (None, None) => return Err(anyhow!("no Rerun target (rerun_save or rerun_connect)")),
        }
        self.send_blueprint()?;
        self.log_sensors(&self.sensors)?;
        deck::log_model(&self.rec, &self.model, &self.grid).map_err(rerun_error)?;
        // The mesh topology never changes: logged once per file, static;
        // updates only carry vertex positions and colours.
        let mesh_paths = [
            "deck/springs",
            "deck/stiffness",
            "deck/stiffness_change",
            "deck/monitoring_residual",
        ]
        .map(String::from)
        .into_iter()
        .chain((1..=MODES_SHOWN).map(|k| format!("modes/{k}")));
        for path in mesh_paths {
            self.rec
                .log_static(
                    path.as_str(),
                    &rerun::Mesh3D::update_fields().with_triangle_indices(self.grid.triangles.clone()),
                )
                .map_err(rerun_error)?;
        }
        self.named.clear();
        Ok(())
    }

    /// Starts a new `.rrd` file once the current one spans `rerun_rotate_hours`
    /// of measurement time: the SDK keeps an index of every chunk of an open
    /// file in memory until its footer is written.
    fn rotate_if_due(&mut self, time_ns: i128) -> Result<()> {
        // No file to rotate, or no measurement time yet (health before data).
        if self.targets.save.is_none() || time_ns <= 0 {
            return Ok(());
        }
        match self.file_start_ns {
            None => self.file_start_ns = Some(time_ns),
            Some(start) if time_ns - start >= self.rotate_ns => {
                self.file_start_ns = Some(time_ns);
                let stamp = crate::io::wire::format_timestamp(time_ns).replace(':', "-");
                self.attach_sinks(Some(&stamp))?;
            }
            Some(_) => {}
        }
        Ok(())
    }

    fn set_time(&self, time_ns: i128) {
        set_measurement_time(&self.rec, time_ns);
        self.rec.set_time_sequence("update", self.updates);
    }

    /// Logs one update: trends, FRFs, ζ(f), the spring field and modes.
    pub fn log_update(&mut self, outcome: &UpdateOutcome) -> Result<()> {
        self.rotate_if_due(outcome.time_ns)?;
        self.updates += 1;
        self.set_time(outcome.time_ns);
        let report = match &outcome.result {
            Ok(r) => r,
            Err(_) => {
                self.rec
                    .log("residual/failed_updates", &rerun::Scalars::new([1.0]))
                    .map_err(rerun_error)?;
                return Ok(());
            }
        };
        self.log_parameters(report)?;
        if let Some(frf) = outcome.measured.frf() {
            self.log_frfs(frf, "measured")?;
        }
        if let Some(frf) = &report.fit.frf {
            self.log_frfs(&frf.model, "model")?;
        }
        for p in report.fit.modes.iter().flatten() {
            let error = 100.0 * (p.model_frequency_hz - p.identified_frequency_hz) / p.identified_frequency_hz;
            self.rec
                .log(
                    format!("residual/modes/mode_{}", p.model_mode + 1).as_str(),
                    &rerun::Scalars::new([error]),
                )
                .map_err(rerun_error)?;
        }
        self.log_damping(&report.damping)?;
        self.log_spring_field(&report.kappa)?;
        self.log_stiffness_field(report)?;
        self.log_modes(report)?;
        Ok(())
    }

    /// Logs the health counters.
    pub fn log_health(&mut self, time_ns: i128, health: &Health) -> Result<()> {
        self.rotate_if_due(time_ns)?;
        self.set_time(time_ns);
        let rejected: u64 = health.rejected.values().sum();
        let skipped: u64 = health.windows_skipped.values().sum();
        for (name, value) in [
            ("blocks", health.blocks),
            ("rejected", rejected),
            ("gaps", health.gaps),
            ("windows_accepted", health.windows_accepted),
            ("windows_skipped", skipped),
            ("update_runs", health.update_runs),
            ("update_failures", health.update_failures),
            ("queue_drops", health.queue_drops),
            ("recording_errors", health.recording_errors),
            ("results_errors", health.results_errors),
            ("rerun_errors", health.rerun_errors),
            ("log_writes_dropped", health.log_writes_dropped),
        ] {
            self.rec
                .log(format!("health/{name}").as_str(), &rerun::Scalars::new([value as f64]))
                .map_err(rerun_error)?;
        }
        Ok(())
    }

    /// Flushes every sink and closes the stream (the `.rrd` gets its footer).
    pub fn finish(self) -> Result<()> {
        self.rec
            .flush_blocking()
            .map_err(|e| anyhow!("flushing the Rerun output: {e}"))?;
        drop(self.rec);
        Ok(())
    }
}

/// A recording saved to `path` alone (no viewer) with `layout` sent: the
/// recordings of a config without a model ([`events::EventTimeline`],
/// [`IdentificationFile`]).
fn saved_recording(path: &Path, layout: &rerun::blueprint::Blueprint) -> Result<rerun::RecordingStream> {
    let rec = rerun::RecordingStreamBuilder::new("splinewatch")
        .buffered()
        .map_err(|e| anyhow!("cannot start the Rerun stream: {e}"))?;
    crate::io::files::create_output_file(path)?;
    let sink = rerun::sink::FileSink::new(path).map_err(|e| anyhow!("Rerun file {}: {e}", path.display()))?;
    rec.set_sink(Box::new(sink));
    layout
        .send(&rec, rerun::blueprint::BlueprintActivation::default())
        .map_err(|e| anyhow!("Rerun blueprint: {e}"))?;
    Ok(rec)
}

/// `rec`'s `measurement_time` at `time_ns` (clamped to what Rerun holds).
fn set_measurement_time(rec: &rerun::RecordingStream, time_ns: i128) {
    rec.set_timestamp_nanos_since_epoch("measurement_time", time_ns.clamp(0, i64::MAX as i128) as i64);
}

fn rerun_error(e: rerun::RecordingStreamError) -> anyhow::Error {
    anyhow!("Rerun output: {e}")
}

/// The Rerun targets for a run: command-line flags first, then `[output]`;
/// relative paths resolve against the output folder.
pub fn targets(config: &Config, save: Option<&Path>, connect: Option<&str>) -> RerunTargets {
    let dir = config.output_dir();
    let resolve = |p: &Path| if p.is_absolute() { p.to_path_buf() } else { dir.join(p) };
    RerunTargets {
        save: save
            .map(Path::to_path_buf)
            .or_else(|| config.output.rerun_save.as_deref().map(resolve)),
        connect: connect
            .map(str::to_string)
            .or_else(|| config.output.rerun_connect.clone()),
    }
}
