//! `predict` and `simulate --ground`: the deck driven by recorded ground
//! motion (issue 44).

use crate::config::{load_config, Config, GroundInputPlan};
use crate::io::console::{errln, outln};
use crate::io::recording::RecordingWriter;
use crate::io::wire::{ChannelBlock, ChannelQuantity, Encoding};
use crate::outputs::rerun::prediction::PredictedChannel;
use crate::service::records::{align_event, read_records, Event, Record};
use crate::studies::ground_motion::GroundModel;
use crate::studies::predict::{predict as predict_event, Prediction};
use anyhow::{bail, Context, Result};
use clap::Args;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct PredictArgs {
    /// Configuration file (TOML) with ground sensors (`support = "<group>"`).
    #[arg(long)]
    pub config: PathBuf,
    /// The record: a station's .zip or .V2 files (one event), raw-input MCAP recordings, or a logger's CSV/UFF 58 file.
    #[arg(required = true, num_args = 1..)]
    pub record: Vec<PathBuf>,
    /// The record's first sample, RFC 3339: over the time a station's or logger's file gives (a file
    /// without one, or a recorder whose clock was wrong).
    #[arg(long, value_parser = parse_start)]
    pub start: Option<i128>,
    /// Parameters of an update (`update --json` output): the model at those values.
    #[arg(long, conflicts_with = "state")]
    pub parameters: Option<PathBuf>,
    /// The daemon's state file: the model at its last accepted parameters; for a config without a
    /// model, the state `events --state` wrote: the record forecast by the realization it holds.
    #[arg(long)]
    pub state: Option<PathBuf>,
    /// Write the predicted deck accelerations (channels `<sensor>_predicted`) and the record as MCAP.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Write an SVG per deck channel (measured, predicted and the "deck = nearest ground" baseline).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Print the figures as JSON.
    #[arg(long)]
    pub json: bool,
    /// Save the measured, predicted and baseline series of every deck channel as a Rerun recording (.rrd).
    #[arg(long)]
    pub rerun_save: Option<PathBuf>,
}

/// The records' record ([`read_records`]), what the import did to it said
/// on stderr.
fn read_records_said(cfg: &Config, paths: &[PathBuf], start_ns: Option<i128>) -> Result<Record> {
    let records = read_records(cfg, paths, start_ns)?;
    for note in &records.notes {
        errln!("{note}");
    }
    Ok(records.record)
}

/// The record on one grid with the config's deck channels it holds (none:
/// nothing to compare a prediction with).
fn deck_event(cfg: &Config, plan: &mut Vec<GroundInputPlan>, record: Record) -> Result<Event> {
    let event = align_event(cfg, plan, record)?;
    if event.deck.is_empty() {
        bail!("the record holds none of the config's deck sensors: nothing to compare the prediction with");
    }
    Ok(event)
}

/// `--start`: an RFC 3339 timestamp, as ns since the epoch.
pub fn parse_start(text: &str) -> Result<i128, String> {
    crate::io::wire::parse_timestamp(text)
        .ok_or_else(|| format!("{text:?} is not an RFC 3339 timestamp (e.g. 2022-12-20T10:34:01Z)"))
}

/// The record and its prediction: by the model (at the config's values,
/// an update's or a state's), or, without a model, by the realization of
/// an events state.
fn predicted_event(cfg: &Config, a: &PredictArgs) -> Result<(Event, Prediction)> {
    Ok(if cfg.has_model() {
        let named = match (&a.parameters, &a.state) {
            (Some(p), _) | (None, Some(p)) => crate::studies::update::named_values_of_file(p)?,
            (None, None) => Vec::new(),
        };
        let mut model = GroundModel::new(cfg, &named)?;
        let record = read_records_said(cfg, &a.record, a.start)?;
        let event = deck_event(cfg, &mut model.plan, record)?;
        let channel = |i: usize| event.channels[i].as_deref().expect("aligned above");
        let mut prediction = predict_event(cfg, &model, &event.deck, channel, event.fs);
        prediction.report.start = Some(crate::io::wire::format_timestamp(event.start_ns));
        (event, prediction)
    } else {
        // Without a model: the realization `events --state` kept.
        let Some(state) = &a.state else {
            bail!(
                    "{} has no [model]: predict forecasts with the realization of an events state: give --state (the file `splinewatch events --state` wrote on this station's records)",
                    a.config.display()
                );
        };
        let mut plan = cfg.ground_plan_of_sensors()?;
        let record = read_records_said(cfg, &a.record, a.start)?;
        let event = deck_event(cfg, &mut plan, record)?;
        let (prediction, notes) = crate::service::events::predict_by_realization(cfg, state, (&event, &plan))?;
        for note in notes {
            errln!("{note}");
        }
        (event, prediction)
    })
}

pub fn predict(a: PredictArgs) -> Result<()> {
    let cfg = load_config(&a.config)?;
    let (event, prediction) = predicted_event(&cfg, &a)?;
    if let Some(dir) = &a.plot {
        plot(&cfg, &prediction, event.fs, dir)?;
    }
    if let Some(out) = &a.out {
        write_prediction(&cfg, &event, &prediction, out)?;
    }
    if let Some(path) = &a.rerun_save {
        let targets = crate::outputs::rerun::RerunTargets {
            save: Some(path.clone()),
            connect: None,
        };
        let mut rerun = crate::outputs::rerun::RerunOutput::open(&cfg, &targets)?;
        let channels: Vec<PredictedChannel<'_>> = prediction
            .sensors
            .iter()
            .enumerate()
            .map(|(k, &s)| PredictedChannel {
                sensor: &cfg.sensors[s].name,
                measured: &prediction.measured[k],
                predicted: &prediction.predicted[k],
                baseline: &prediction.baseline[k],
            })
            .collect();
        rerun.log_prediction(event.start_ns, event.fs, &channels)?;
        rerun.finish()?;
    }
    let r = &prediction.report;
    if a.json {
        outln!("{}", serde_json::to_string(r)?);
        return Ok(());
    }
    outln!(
        "{} +{:.1} s at {} Hz; strong motion (5–95 % of the ground's energy) {:.2}–{:.2} s",
        r.start.as_deref().unwrap_or("?"),
        r.record_seconds,
        r.fs,
        r.strong_span_s[0],
        r.strong_span_s[1]
    );
    outln!("sensor\tnrmse\tnrmse_strong\tcorrelation\tpeak_ratio\t| baseline (deck = nearest ground): nrmse_strong\tground");
    for (c, b) in r.channels.iter().zip(&r.baseline) {
        outln!(
            "{}\t{:.3}\t{:.3}\t{:.3}\t{:.3}\t| {:.3}\t{}",
            c.sensor,
            c.nrmse,
            c.nrmse_strong,
            c.correlation,
            c.peak_ratio,
            b.score.nrmse_strong,
            b.ground
        );
    }
    Ok(())
}

/// The predicted deck channels (`<sensor>_predicted`) and the record's
/// aligned channels, in 10-s blocks.
fn write_prediction(cfg: &Config, event: &Event, prediction: &Prediction, out: &Path) -> Result<()> {
    let mut series: Vec<(String, &[f64])> = Vec::new();
    for (i, c) in event.channels.iter().enumerate() {
        if let Some(c) = c {
            series.push((cfg.sensors[i].name.clone(), c));
        }
    }
    for (k, &s) in prediction.sensors.iter().enumerate() {
        series.push((format!("{}_predicted", cfg.sensors[s].name), &prediction.predicted[k]));
    }
    write_series(cfg, &series, event.fs, event.start_ns, Encoding::Cbor, out)
}

/// Series written as acceleration blocks of 10 s, in time order.
fn write_series(
    cfg: &Config,
    series: &[(String, &[f64])],
    fs: f64,
    start_ns: i128,
    encoding: Encoding,
    out: &Path,
) -> Result<()> {
    let prefix = cfg.topic_prefix();
    let mut writer = RecordingWriter::create(out, encoding)?;
    let samples = series.first().map_or(0, |s| s.1.len());
    let block = (10.0 * fs).round().max(1.0) as usize;
    for from in (0..samples).step_by(block) {
        let to = (from + block).min(samples);
        for (name, data) in series {
            writer.write_block(
                &prefix,
                &ChannelBlock {
                    name: name.clone(),
                    quantity: ChannelQuantity::Acceleration,
                    unit: "m/s^2".into(),
                    fs,
                    start_ns: start_ns + (from as f64 * 1e9 / fs).round() as i128,
                    data: data[from..to].to_vec(),
                },
            )?;
        }
    }
    writer.finish()?;
    Ok(())
}

/// `simulate --ground RECORD…`: the deck's response to the record's ground
/// channels at the config's values, with noise, written with the ground
/// channels as a raw-input recording.
pub fn simulate_ground(
    cfg: &Config,
    record: &[PathBuf],
    noise: f64,
    seed: u64,
    encoding: Encoding,
    out: &Path,
) -> Result<()> {
    if !(noise.is_finite() && noise >= 0.0) {
        bail!("--noise must be >= 0, got {noise}");
    }
    let mut model = GroundModel::new(cfg, &[])?;
    let read = read_records_said(cfg, record, None)?;
    let event = align_event(cfg, &mut model.plan, read)?;
    let channel = |i: usize| event.channels[i].as_deref().expect("aligned above");
    let mut deck = model.respond(channel, event.fs);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    for series in &mut deck {
        let rms = (series.iter().map(|v| v * v).sum::<f64>() / series.len().max(1) as f64).sqrt();
        if noise > 0.0 && rms > 0.0 {
            let normal = Normal::new(0.0, noise * rms).context("noise level")?;
            for v in series.iter_mut() {
                *v += normal.sample(&mut rng);
            }
        }
    }
    let mut series: Vec<(String, &[f64])> = model
        .ground_sensors()
        .into_iter()
        .map(|i| (cfg.sensors[i].name.clone(), channel(i)))
        .collect();
    for (name, data) in model.outputs.iter().zip(&deck) {
        series.push((name.clone(), data));
    }
    write_series(cfg, &series, event.fs, event.start_ns, encoding, out)?;
    errln!(
        "{:.1} s of {} deck channels driven by {} ground inputs written to {}",
        deck.first().map_or(0, Vec::len) as f64 / event.fs,
        deck.len(),
        model.plan.len(),
        out.display()
    );
    Ok(())
}

/// One SVG per deck channel: measured, predicted and the baseline over time
/// (top) and their amplitude spectra up to 25 Hz (bottom, logarithmic).
fn plot(cfg: &Config, prediction: &Prediction, fs: f64, dir: &Path) -> Result<()> {
    use plotters::prelude::*;
    let fail = |e: &dyn std::fmt::Display| anyhow::anyhow!("plotting: {e}");
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    for (k, &s) in prediction.sensors.iter().enumerate() {
        let name = &cfg.sensors[s].name;
        let path = dir.join(format!("{name}.svg"));
        let root = SVGBackend::new(&path, (1100, 760)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| fail(&e))?;
        let (upper, lower) = root.split_vertically(420);
        let m = &prediction.measured[k];
        let p = &prediction.predicted[k];
        let b = &prediction.baseline[k];
        let curves = [
            (b, RGBColor(170, 170, 170), "deck = nearest ground"),
            (m, BLACK, "measured"),
            (p, RED, "predicted"),
        ];
        let peak = m.iter().chain(p).fold(0.0f64, |a, v| a.max(v.abs())).max(1e-12);
        let score = &prediction.report.channels[k];
        let mut chart = ChartBuilder::on(&upper)
            .caption(
                format!(
                    "{name}: NRMSE {:.2} (strong motion {:.2}), baseline {:.2}",
                    score.nrmse, score.nrmse_strong, prediction.report.baseline[k].score.nrmse_strong
                ),
                ("sans-serif", 18),
            )
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..m.len() as f64 / fs, -1.1 * peak..1.1 * peak)
            .map_err(|e| fail(&e))?;
        chart
            .configure_mesh()
            .x_desc("time (s)")
            .y_desc("acceleration (m/s²)")
            .draw()
            .map_err(|e| fail(&e))?;
        for (data, colour, label) in curves {
            let points = data.iter().enumerate().map(|(i, v)| (i as f64 / fs, *v));
            chart
                .draw_series(LineSeries::new(points, colour))
                .map_err(|e| fail(&e))?
                .label(label)
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour));
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .map_err(|e| fail(&e))?;
        let spectra: Vec<Vec<(f64, f64)>> = curves.iter().map(|(x, _, _)| amplitude_spectrum(x, fs, 25.0)).collect();
        let top = spectra.iter().flatten().map(|&(_, a)| a).fold(1e-12, f64::max);
        let mut spectrum = ChartBuilder::on(&lower)
            .margin(10)
            .x_label_area_size(35)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..25.0, (top * 1e-4..top * 2.0).log_scale())
            .map_err(|e| fail(&e))?;
        spectrum
            .configure_mesh()
            .x_desc("frequency (Hz)")
            .y_desc("|FFT| (m/s²·s)")
            .draw()
            .map_err(|e| fail(&e))?;
        for (points, (_, colour, _)) in spectra.into_iter().zip(curves) {
            let points = points.into_iter().map(|(f, a)| (f, a.max(top * 1e-4)));
            spectrum
                .draw_series(LineSeries::new(points, colour))
                .map_err(|e| fail(&e))?;
        }
        root.present().map_err(|e| fail(&e))?;
    }
    Ok(())
}

/// `|X(f)| / fs` of `x` (its Fourier transform's amplitude, m/s²·s) up to `f_max` Hz.
fn amplitude_spectrum(x: &[f64], fs: f64, f_max: f64) -> Vec<(f64, f64)> {
    let mut planner = realfft::RealFftPlanner::<f64>::new();
    let fft = planner.plan_fft_forward(x.len());
    let mut input = x.to_vec();
    let mut out = fft.make_output_vec();
    if fft.process(&mut input, &mut out).is_err() {
        return Vec::new();
    }
    out.iter()
        .enumerate()
        .map(|(k, v)| (k as f64 * fs / x.len() as f64, v.norm() / fs))
        .take_while(|(f, _)| *f <= f_max)
        .collect()
}

#[derive(Args)]
pub struct IdentifyArgs {
    /// Configuration file (TOML): its ground sensors (or force sensor) are the inputs, its deck
    /// acceleration sensors the outputs; `[oma]` sets the horizon (`block_rows`), orders, band and
    /// stabilisation.
    #[arg(long)]
    pub config: PathBuf,
    /// The record: a station's .zip or .V2 files (one event), raw-input MCAP recordings, or a logger's CSV/UFF 58 file.
    #[arg(required = true, num_args = 1..)]
    pub record: Vec<PathBuf>,
    /// The record's first sample, RFC 3339: over the time a station's or logger's file gives (a file
    /// without one, or a recorder whose clock was wrong).
    #[arg(long, value_parser = parse_start)]
    pub start: Option<i128>,
    #[command(flatten)]
    pub output: super::identified::ModesOutput,
    #[command(flatten)]
    pub comparison: super::identified::ModelComparison,
    /// Also write the multi-input H1 transmissibilities (inputs to every output, with the multiple
    /// coherence and the inputs' condition number per line; `[frf] segment_seconds` and `overlap`) as JSON.
    #[arg(long)]
    pub transmissibility: Option<PathBuf>,
}

/// `splinewatch identify`: input–output identification (SRIM) of a record
/// with measured inputs: every ground sensor the record holds (or the force
/// sensor) against every deck acceleration sensor it holds.
pub fn identify(a: IdentifyArgs) -> Result<()> {
    let cfg = load_config(&a.config)?;
    let record = read_records_said(&cfg, &a.record, a.start)?;
    let recorded = |i: usize| record.recorded(&cfg, i);
    let (force, inputs): (Option<usize>, Vec<usize>) = if cfg.has_ground_sensors() {
        let ground: Vec<usize> = (cfg.deck_sensor_count()..cfg.sensors.len())
            .filter(|&i| recorded(i))
            .collect();
        (None, ground)
    } else {
        let (force, _) = cfg.channel_roles()?;
        (Some(force), vec![force])
    };
    if inputs.is_empty() {
        bail!("the record holds none of the config's ground sensors: no measured input to identify with");
    }
    let outputs: Vec<usize> = cfg.output_channels()?.into_iter().filter(|&i| recorded(i)).collect();
    if outputs.is_empty() {
        bail!("the record holds none of the config's deck acceleration sensors");
    }
    let input_quantity = if force.is_some() {
        ChannelQuantity::Force
    } else {
        ChannelQuantity::Acceleration
    };
    let wanted: Vec<(usize, ChannelQuantity)> = inputs
        .iter()
        .map(|&i| (i, input_quantity))
        .chain(outputs.iter().map(|&i| (i, ChannelQuantity::Acceleration)))
        .collect();
    let span = record.span(&cfg, &wanted)?;
    let views: Vec<&[f64]> = span.channels.iter().map(Vec::as_slice).collect();
    let (input_views, output_views) = views.split_at(inputs.len());
    if let Some(path) = &a.transmissibility {
        write_transmissibility(&cfg, (&inputs, input_views), (&outputs, output_views), span.fs, path)?;
    }
    let input_channels: Vec<(usize, &[f64])> = inputs.iter().copied().zip(input_views.iter().copied()).collect();
    let output_channels: Vec<(usize, &[f64])> = outputs.iter().copied().zip(output_views.iter().copied()).collect();
    let record = crate::service::frequency_domain::identify_record(
        &cfg,
        &input_channels,
        &output_channels,
        span.fs,
        span.start_ns,
    )?;
    for note in &record.notes {
        errln!("{note}");
    }
    let names = |list: &[usize]| {
        list.iter()
            .map(|&i| cfg.sensors[i].name.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    };
    errln!(
        "{} samples ({:.1} s at {} Hz) from {}: inputs {}; outputs {}; {} modes (SRIM{}, horizon {}){}",
        span.samples,
        span.samples as f64 / span.fs,
        span.fs,
        crate::io::wire::format_timestamp(span.start_ns),
        names(&inputs),
        names(&outputs),
        record.report.result.modes.len(),
        if record.rate < span.fs {
            format!(" at {} Hz, resampled", crate::service::records::rate_text(record.rate))
        } else {
            String::new()
        },
        record.settings.block_rows,
        if record.fitted.is_empty() {
            String::new()
        } else {
            format!("; {} fitted in the frequency domain", record.fitted.len())
        }
    );
    super::identified::write_identified(&cfg, &record.report, &record.fitted, &a.output, &a.comparison)
}

/// The multi-input H1 estimates of `identify --transmissibility` as JSON:
/// `{"quantity": "transmissibility", "frequency_hz", "inputs", "frfs": [{"input",
/// "output", "re", "im", "coherence"}], "condition", "n_averages"}`; a group of
/// inputs too coherent to separate is one input named `a+b` (and said so).
fn write_transmissibility(
    cfg: &Config,
    (inputs, input_views): (&[usize], &[&[f64]]),
    (outputs, output_views): (&[usize], &[&[f64]]),
    fs: f64,
    path: &Path,
) -> Result<()> {
    let (welch, _) = cfg.welch_settings(fs)?;
    let segment = welch.segment.min(input_views[0].len());
    let overlap = welch.overlap.min(segment / 2);
    let est =
        splinewatch_core::identification::transmissibility::estimate(input_views, output_views, fs, segment, overlap)
            .map_err(|e| anyhow::anyhow!("transmissibility: {e}"))?;
    let names: Vec<String> = est
        .combined
        .iter()
        .map(|g| {
            g.iter()
                .map(|&i| cfg.sensors[inputs[i]].name.as_str())
                .collect::<Vec<_>>()
                .join("+")
        })
        .collect();
    for (g, name) in est.combined.iter().zip(&names) {
        if g.len() > 1 {
            errln!(
                "inputs {name} are coherent above {} over the band: combined into one (their mean)",
                splinewatch_core::identification::transmissibility::COMBINE_COHERENCE
            );
        }
    }
    let mut frfs = Vec::new();
    for (o, &sensor) in outputs.iter().enumerate() {
        for (i, name) in names.iter().enumerate() {
            frfs.push(serde_json::json!({
                "input": name,
                "output": cfg.sensors[sensor].name,
                "re": est.h[o][i].iter().map(|v| v.re).collect::<Vec<_>>(),
                "im": est.h[o][i].iter().map(|v| v.im).collect::<Vec<_>>(),
                "coherence": est.coherence[o],
            }));
        }
    }
    let finite = |v: &f64| {
        if v.is_finite() {
            serde_json::json!(v)
        } else {
            serde_json::Value::Null
        }
    };
    let json = serde_json::json!({
        "quantity": "transmissibility",
        "frequency_hz": est.frequencies_hz,
        "inputs": names,
        "frfs": frfs,
        "condition": est.condition.iter().map(finite).collect::<Vec<_>>(),
        "n_averages": est.averages,
    });
    std::fs::write(path, serde_json::to_string(&json)?).with_context(|| format!("cannot write {}", path.display()))
}
