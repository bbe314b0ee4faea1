//! Rerun output (0.36): trends and the latest update, to a `.rrd` file
//! and/or a live viewer, with a blueprint sent from here.
//!
//! Timelines: `measurement_time` (the data's own clock) and `update` (the
//! update index). Entities:
//! - `parameters/springs/<name>`, `parameters/damping/<name>`: the value and
//!   ±1σ as three series; `residual/relative`; `health/<counter>`;
//! - `frf/<output>/magnitude/{measured,model}` (dB) and
//!   `frf/<output>/phase/{measured,model}` (degrees), bar charts over the
//!   frequency lines; `damping/zeta` (ζ(f) in %) and
//!   `damping/coefficients` (γ_z at their Greville abscissae);
//! - `deck/springs`: the deck mesh coloured by the identified spring field
//!   r33 (N/m³); `deck/sensors`; `modes/<k>`: the first bending modes.

use crate::commands::{self, FrfSetup};
use crate::config::Config;
use crate::frf_json::FrfFile;
use crate::pipeline::{Health, UpdateOutcome};
use anyhow::{anyhow, Context, Result};
use rerun::blueprint::BarChartView;
use rerun::blueprint::{
    Blueprint, BlueprintActivation, ContainerLike, Horizontal, Spatial3DView, Tabs, TimeSeriesView, Vertical,
};
use splinewatch_core::frf::SensorPoint;
use splinewatch_core::model::ShellModel;
use splinewatch_core::vec3::Vec3;
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

pub struct RerunOutput {
    rec: rerun::RecordingStream,
    setup: FrfSetup,
    model: ShellModel,
    grid: DeckGrid,
    updates: i64,
    /// Parameter series already given their static names and colours.
    named: std::collections::BTreeSet<String>,
    targets: RerunTargets,
    sensors: Vec<(String, SensorPoint)>,
    rotate_ns: i128,
    /// Measurement time of the open file's first message.
    file_start_ns: Option<i128>,
}

impl RerunOutput {
    pub fn open(config: &Config, targets: &RerunTargets) -> Result<Self> {
        let rec = rerun::RecordingStreamBuilder::new("splinewatch")
            .buffered()
            .map_err(|e| anyhow!("cannot start the Rerun stream: {e}"))?;
        let setup = commands::frf_setup(config)?;
        let model = config.build_model()?;
        let sensors = config.build_sensors(&model.shell)?;
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
            rotate_ns: (config.output.rerun_rotate_hours * 3600e9) as i128,
            file_start_ns: None,
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
            crate::files::create_output_file(p)?;
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
        // The mesh topology never changes: logged once per file, static;
        // updates only carry vertex positions and colours.
        let mesh_paths =
            std::iter::once("deck/springs".to_string()).chain((1..=MODES_SHOWN).map(|k| format!("modes/{k}")));
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
                let stamp = crate::wire::format_timestamp(time_ns).replace(':', "-");
                self.attach_sinks(Some(&stamp))?;
            }
            Some(_) => {}
        }
        Ok(())
    }

    fn send_blueprint(&self) -> Result<()> {
        let frf_tabs = |what: &str| -> ContainerLike {
            Tabs::new(self.setup.sensor_names.iter().map(|o| {
                BarChartView::new(format!("{o} {what}"))
                    .with_origin(format!("/frf/{o}/{what}"))
                    .into()
            }))
            .into()
        };
        let mode_tabs = Tabs::new((1..=MODES_SHOWN).map(|k| {
            Spatial3DView::new(format!("mode {k}"))
                .with_origin(format!("/modes/{k}"))
                .into()
        }));
        let blueprint = Blueprint::new(Horizontal::new([
            Vertical::new([
                TimeSeriesView::new("Spring coefficients (N/m³, ±1σ)")
                    .with_origin("/parameters/springs")
                    .into(),
                TimeSeriesView::new("Damping coefficients (±1σ)")
                    .with_origin("/parameters/damping")
                    .into(),
                TimeSeriesView::new("Relative residual").with_origin("/residual").into(),
                TimeSeriesView::new("Health").with_origin("/health").into(),
            ])
            .into(),
            Vertical::new([
                Spatial3DView::new("Deck: spring field r33").with_origin("/deck").into(),
                mode_tabs.into(),
            ])
            .into(),
            Vertical::new([
                frf_tabs("magnitude"),
                frf_tabs("phase"),
                BarChartView::new("ζ(f) in %").with_origin("/damping").into(),
            ])
            .into(),
        ]));
        blueprint
            .send(
                &self.rec,
                BlueprintActivation {
                    make_active: true,
                    make_default: true,
                },
            )
            .map_err(|e| anyhow!("sending the Rerun blueprint: {e}"))
    }

    fn log_sensors(&self, sensors: &[(String, SensorPoint)]) -> Result<()> {
        let shell = &self.model.shell;
        let positions: Vec<[f32; 3]> = sensors
            .iter()
            .map(|(_, s)| f32x3(shell.position(s.xi, s.eta, 1.0)))
            .collect();
        let labels: Vec<String> = sensors.iter().map(|(name, _)| name.clone()).collect();
        self.rec
            .log_static(
                "deck/sensors",
                &rerun::Points3D::new(positions).with_labels(labels).with_radii([0.15]),
            )
            .map_err(rerun_error)
    }

    fn set_time(&self, time_ns: i128) {
        self.rec
            .set_timestamp_nanos_since_epoch("measurement_time", time_ns.clamp(0, i64::MAX as i128) as i64);
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
        for p in &report.result.parameters {
            let group = if p.name.starts_with("damping.") {
                "damping"
            } else {
                "springs"
            };
            let path = format!("parameters/{group}/{}", p.name);
            let sigma = p.std.unwrap_or(0.0);
            if self.named.insert(path.clone()) {
                self.rec
                    .log_static(
                        path.as_str(),
                        &rerun::SeriesLines::new()
                            .with_names(["value", "+1σ", "−1σ"])
                            .with_colors([
                                rerun::Color::from_rgb(30, 110, 200),
                                rerun::Color::from_rgb(150, 180, 220),
                                rerun::Color::from_rgb(150, 180, 220),
                            ]),
                    )
                    .map_err(rerun_error)?;
            }
            self.rec
                .log(
                    path.as_str(),
                    &rerun::Scalars::new([p.value, p.value + sigma, p.value - sigma]),
                )
                .map_err(rerun_error)?;
        }
        self.rec
            .log(
                "residual/relative",
                &rerun::Scalars::new([report.result.relative_residual]),
            )
            .map_err(rerun_error)?;
        self.log_frfs(&outcome.measured, "measured")?;
        self.log_frfs(&report.model, "model")?;
        // ζ(f) over its band, in %, and the control coefficients.
        let (f0, f1) = report.damping.band();
        let n = 161;
        let fs: Vec<f64> = (0..n).map(|k| f0 + (f1 - f0) * k as f64 / (n - 1) as f64).collect();
        let zeta: Vec<f64> = fs.iter().map(|&f| 100.0 * report.damping.zeta(f)).collect();
        self.rec
            .log(
                "damping/zeta",
                &rerun::BarChart::new(zeta.as_slice())
                    .with_abscissa(fs.as_slice())
                    .with_widths([((f1 - f0) / (n - 1) as f64) as f32]),
            )
            .map_err(rerun_error)?;
        let at = report.damping.coefficient_frequencies();
        let gamma: Vec<f64> = report.damping.coefficients().iter().map(|g| 100.0 * g).collect();
        self.rec
            .log(
                "damping/coefficients",
                &rerun::BarChart::new(gamma.as_slice())
                    .with_abscissa(at.as_slice())
                    .with_widths([((f1 - f0) / (4 * gamma.len().max(1)) as f64) as f32]),
            )
            .map_err(rerun_error)?;
        // The identified spring field on the deck.
        let r33 = self.grid.spring_field(&self.model, &report.kappa);
        let top = r33.iter().copied().fold(0.0f64, f64::max).max(f64::MIN_POSITIVE);
        let colors: Vec<rerun::Color> = r33.iter().map(|&v| colormap(v / top)).collect();
        self.rec
            .log(
                "deck/springs",
                &rerun::Mesh3D::update_fields()
                    .with_vertex_positions(self.grid.positions.clone())
                    .with_vertex_colors(colors),
            )
            .map_err(rerun_error)?;
        self.log_modes(report)?;
        Ok(())
    }

    fn log_frfs(&self, frfs: &FrfFile, which: &str) -> Result<()> {
        let frequencies: Vec<f32> = frfs.frequency_hz.iter().map(|&f| f as f32).collect();
        let width = frfs
            .frequency_hz
            .windows(2)
            .map(|w| w[1] - w[0])
            .fold(f64::INFINITY, f64::min);
        let width = if width.is_finite() { width as f32 } else { 1.0 };
        for entry in &frfs.frfs {
            let magnitude: Vec<f64> = entry
                .re
                .iter()
                .zip(&entry.im)
                .map(|(re, im)| 20.0 * re.hypot(*im).max(1e-300).log10())
                .collect();
            let phase: Vec<f64> = entry
                .re
                .iter()
                .zip(&entry.im)
                .map(|(re, im)| im.atan2(*re).to_degrees())
                .collect();
            for (what, values) in [("magnitude", magnitude), ("phase", phase)] {
                self.rec
                    .log(
                        format!("frf/{}/{what}/{which}", entry.output).as_str(),
                        &rerun::BarChart::new(values.as_slice())
                            .with_abscissa(frequencies.as_slice())
                            .with_widths([width]),
                    )
                    .map_err(rerun_error)?;
            }
        }
        Ok(())
    }

    fn log_modes(&self, report: &crate::pipeline::UpdateReport) -> Result<()> {
        for (k, mode) in report.bending_modes.iter().enumerate() {
            let w = self.grid.normal_displacement(&self.model, |dof| mode.shape[dof]);
            let peak = w.iter().map(|v| v.abs()).fold(0.0f64, f64::max).max(f64::MIN_POSITIVE);
            let scale = 0.1 * self.grid.span / peak;
            let positions: Vec<[f32; 3]> = self
                .grid
                .positions
                .iter()
                .zip(&self.grid.normals)
                .zip(&w)
                .map(|((p, n), w)| {
                    [
                        p[0] + (scale * w) as f32 * n[0],
                        p[1] + (scale * w) as f32 * n[1],
                        p[2] + (scale * w) as f32 * n[2],
                    ]
                })
                .collect();
            let colors: Vec<rerun::Color> = w.iter().map(|v| colormap(0.5 + 0.5 * v / peak)).collect();
            let label = format!("{:.2} Hz, ζ = {:.2} %", mode.frequency_hz, 100.0 * mode.damping_ratio);
            let path = format!("modes/{}", k + 1);
            self.rec
                .log(
                    path.as_str(),
                    &rerun::Mesh3D::update_fields()
                        .with_vertex_positions(positions)
                        .with_vertex_colors(colors),
                )
                .map_err(rerun_error)?;
            self.rec
                .log(format!("{path}/label").as_str(), &rerun::TextDocument::new(label))
                .map_err(rerun_error)?;
        }
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

fn rerun_error(e: rerun::RecordingStreamError) -> anyhow::Error {
    anyhow!("Rerun output: {e}")
}

fn f32x3(v: Vec3) -> [f32; 3] {
    [v[0] as f32, v[1] as f32, v[2] as f32]
}

/// A blue → green → yellow ramp for `t ∈ [0, 1]`.
fn colormap(t: f64) -> rerun::Color {
    let t = t.clamp(0.0, 1.0);
    let (r, g, b) = if t < 0.5 {
        let u = 2.0 * t;
        (0.15 * (1.0 - u), 0.2 + 0.55 * u, 0.7 * (1.0 - u) + 0.35 * u)
    } else {
        let u = 2.0 * t - 1.0;
        (0.95 * u, 0.75 + 0.2 * u, 0.35 * (1.0 - u))
    };
    rerun::Color::from_rgb((255.0 * r) as u8, (255.0 * g) as u8, (255.0 * b) as u8)
}

/// The deck's mid-surface sampled on a (ξ, η) grid that includes every
/// spring field's knots, so narrow spring strips are visible.
struct DeckGrid {
    params: Vec<(f64, f64)>,
    positions: Vec<[f32; 3]>,
    normals: Vec<[f32; 3]>,
    triangles: Vec<[u32; 3]>,
    /// Largest extent of the deck, for scaling mode shapes.
    span: f64,
}

impl DeckGrid {
    fn new(model: &ShellModel) -> Self {
        let axis = |n: usize, knots: &mut dyn Iterator<Item = f64>| -> Vec<f64> {
            let mut v: Vec<f64> = (0..n).map(|k| k as f64 / (n - 1) as f64).collect();
            v.extend(knots.filter(|u| (0.0..=1.0).contains(u)));
            v.sort_by(f64::total_cmp);
            v.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
            v
        };
        let xs = axis(GRID.0, &mut model.springs.iter().flat_map(|s| s.xi().knots().to_vec()));
        let ys = axis(GRID.1, &mut model.springs.iter().flat_map(|s| s.eta().knots().to_vec()));
        let shell = &model.shell;
        let mut params = Vec::with_capacity(xs.len() * ys.len());
        let mut positions = Vec::with_capacity(params.capacity());
        let mut normals = Vec::with_capacity(params.capacity());
        for &x in &xs {
            for &y in &ys {
                params.push((x, y));
                let p = shell.position(x, y, 0.5);
                let q = shell.position(x, y, 1.0);
                let d = [q[0] - p[0], q[1] - p[1], q[2] - p[2]];
                let norm = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt().max(f64::MIN_POSITIVE);
                positions.push(f32x3(p));
                normals.push([(d[0] / norm) as f32, (d[1] / norm) as f32, (d[2] / norm) as f32]);
            }
        }
        let ny = ys.len();
        let mut triangles = Vec::new();
        for i in 0..xs.len() - 1 {
            for j in 0..ny - 1 {
                let a = (i * ny + j) as u32;
                let b = ((i + 1) * ny + j) as u32;
                triangles.push([a, b, b + 1]);
                triangles.push([a, b + 1, a + 1]);
            }
        }
        let extent = |k: usize| {
            let (lo, hi) = positions
                .iter()
                .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), p| {
                    (lo.min(p[k]), hi.max(p[k]))
                });
            f64::from(hi - lo)
        };
        let span = extent(0).max(extent(1)).max(extent(2));
        Self {
            params,
            positions,
            normals,
            triangles,
            span,
        }
    }

    /// Σ over spring fields of the stiffness per unit area at each vertex.
    fn spring_field(&self, model: &ShellModel, kappa: &[Vec<f64>]) -> Vec<f64> {
        self.params
            .iter()
            .map(|&(x, y)| {
                model
                    .springs
                    .iter()
                    .zip(kappa)
                    .map(|(s, k)| s.value_with(k, x, y))
                    .sum()
            })
            .collect()
    }

    /// Displacement along the surface normal at each vertex of the shape
    /// with generalised dof values `shape(dof)`.
    fn normal_displacement(&self, model: &ShellModel, shape: impl Fn(usize) -> f64) -> Vec<f64> {
        self.params
            .iter()
            .zip(&self.normals)
            .map(|(&(x, y), n)| {
                model
                    .shell
                    .shape_functions(x, y, 0.5)
                    .into_iter()
                    .map(|(dof, col)| {
                        shape(dof) * (col[0] * f64::from(n[0]) + col[1] * f64::from(n[1]) + col[2] * f64::from(n[2]))
                    })
                    .sum()
            })
            .collect()
    }
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

/// What a `.rrd` file holds, read back with Rerun's own decoder.
#[derive(Debug, Clone, Default)]
pub struct RrdSummary {
    /// Entity paths with data in the recording (blueprint excluded).
    pub entities: std::collections::BTreeSet<String>,
    pub chunks: usize,
    /// Whether the file ends with its footer (written when the stream is
    /// closed cleanly).
    pub footer: bool,
}

/// Decodes a whole `.rrd` file.
pub fn inspect_rrd(bytes: &[u8]) -> Result<RrdSummary> {
    use rerun::external::re_log_encoding::DecoderApp;
    use rerun::external::re_log_types::{LogMsg, StoreKind};
    let mut messages = DecoderApp::decode_eager(std::io::BufReader::new(bytes)).context("not an .rrd file")?;
    let mut summary = RrdSummary::default();
    for msg in messages.by_ref() {
        if let LogMsg::ArrowMsg(store, arrow) = msg.context("corrupt .rrd message")? {
            if store.kind() != StoreKind::Recording {
                continue;
            }
            let chunk = rerun::log::Chunk::from_arrow_msg(&arrow).context("corrupt .rrd chunk")?;
            summary.entities.insert(chunk.entity_path().to_string());
            summary.chunks += 1;
        }
    }
    summary.footer = !messages.rrd_manifests().context("reading the .rrd footer")?.is_empty();
    Ok(summary)
}
