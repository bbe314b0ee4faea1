//! Results outputs: an MCAP file of JSON messages with JSON Schemas (read by
//! Foxglove and the Python `mcap` package), rotated by measurement time.

use crate::config::Config;
use crate::io::frf_json::FrfFile;
use crate::io::wire::format_timestamp;
use crate::pipeline::{Health, MonitoringOutcome, UpdateOutcome, WindowModes, WindowReport};
use anyhow::{Context, Result};
use serde::Serialize;
use serde_json::{json, Value};
use splinewatch_core::response::frf::Quantity;
use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufWriter, Seek, Write};
use std::path::Path;

pub use crate::io::results_topics::{Provenance, EVENT_TOPICS, MONITORING_TOPICS, PROVENANCE_METADATA, TOPICS};

/// The messages of a scored update: `monitoring/status`, and
/// `monitoring/alarm` when the state entered or left alarm.
pub fn monitoring_messages(m: &MonitoringOutcome) -> Vec<(&'static str, Value)> {
    let mut out = vec![(
        "monitoring/status",
        serde_json::to_value(&m.status).expect("plain data"),
    )];
    if let Some(alarm) = &m.alarm {
        out.push(("monitoring/alarm", serde_json::to_value(alarm).expect("plain data")));
    }
    out
}

/// The messages of a closed window, as `(topic suffix, message)`: `windows`,
/// and `oma/modes` when the window identified modes output-only.
pub fn window_messages(w: &WindowReport) -> Vec<(&'static str, Value)> {
    let mut window = json!({
        "index": w.index,
        "start": format_timestamp(w.start_ns),
        "end": format_timestamp(w.end_ns),
        "segments_accepted": w.segments_accepted,
        "segments_rejected": w.segments_rejected,
        "mean_coherence": w.mean_coherence,
        "skipped": w.skipped,
    });
    if let Some(f) = w.valid_fraction {
        window["valid_fraction"] = json!(f);
    }
    // Both paths: each path's own outcome (null: it produced its part).
    if w.frf_skipped.is_some() || w.oma_skipped.is_some() || (w.frf.is_some() && w.modes.is_some()) {
        window["frf_skipped"] = json!(w.frf_skipped);
        window["oma_skipped"] = json!(w.oma_skipped);
    }
    let mut out = vec![("windows", window)];
    if let Some(modes) = &w.modes {
        out.push(("oma/modes", oma_modes_message(w, modes)));
    }
    out
}

/// `oma/modes`: the modes file of the window (so a message saved as a file
/// is an `update --modes` input) with, per mode, its paired model mode
/// (1-based, as the `modes` topic's `index`), that mode's frequency and the MAC.
fn oma_modes_message(w: &WindowReport, modes: &WindowModes) -> Value {
    let mut v = serde_json::to_value(modes.report.modes_file()).expect("plain data");
    v["time"] = json!(format_timestamp(w.end_ns));
    v["window"] = json!(w.index);
    if let Some(entries) = v["modes"].as_array_mut() {
        for (entry, pair) in entries.iter_mut().zip(&modes.pairs) {
            entry["model_mode"] = json!(pair.as_ref().map(|p| p.model_mode + 1));
            entry["model_frequency_hz"] = json!(pair.as_ref().map(|p| p.model_frequency_hz));
            entry["mac"] = json!(pair.as_ref().map(|p| p.mac));
        }
    }
    v
}

/// A result message: a JSON value, or a typed one for the large FRF
/// messages (serialised straight from the FRFs, no value tree); both give
/// the same bytes.
#[derive(Debug, Serialize)]
#[serde(untagged)]
pub enum ResultMessage<'a> {
    Json(Value),
    Frf(FrfMessage<'a>),
}

/// `frf/measured` and `frf/model`: the FRF file with the update's time and
/// window. Fields in key order, as a JSON object value writes them.
#[derive(Debug, Serialize)]
pub struct FrfMessage<'a> {
    #[serde(skip_serializing_if = "Option::is_none")]
    end_timestamp: Option<&'a str>,
    frequency_hz: &'a [f64],
    frfs: Vec<FrfMessageEntry<'a>>,
    quantity: Quantity,
    #[serde(skip_serializing_if = "Option::is_none")]
    start_timestamp: Option<&'a str>,
    time: &'a str,
    window: u64,
}

/// One FRF of [`FrfMessage`], fields in key order.
#[derive(Debug, Serialize)]
struct FrfMessageEntry<'a> {
    #[serde(skip_serializing_if = "Option::is_none")]
    coherence: Option<&'a [f64]>,
    im: &'a [f64],
    input: &'a str,
    #[serde(skip_serializing_if = "Option::is_none")]
    n_averages: Option<f64>,
    output: &'a str,
    re: &'a [f64],
}

fn frf_message<'a>(time: &'a str, window: u64, frf: &'a FrfFile) -> ResultMessage<'a> {
    ResultMessage::Frf(FrfMessage {
        end_timestamp: frf.end_timestamp.as_deref(),
        frequency_hz: &frf.frequency_hz,
        frfs: frf
            .frfs
            .iter()
            .map(|e| FrfMessageEntry {
                coherence: e.coherence.as_deref(),
                im: &e.im,
                input: &e.input,
                n_averages: e.n_averages,
                output: &e.output,
                re: &e.re,
            })
            .collect(),
        quantity: frf.quantity,
        start_timestamp: frf.start_timestamp.as_deref(),
        time,
        window,
    })
}

/// The messages of an update outcome, as `(topic suffix, message)`;
/// `time` is the outcome's time, formatted (`format_timestamp`).
pub fn update_messages<'a>(o: &'a UpdateOutcome, time: &'a str) -> Vec<(&'static str, ResultMessage<'a>)> {
    let mut out = Vec::new();
    if let Some(frf) = o.measured.frf() {
        out.push(("frf/measured", frf_message(time, o.window, frf)));
    }
    match &o.result {
        Ok(r) => {
            let mut parameters = json!({
                "time": time,
                "window": o.window,
                "converged": r.result.converged,
                "relative_residual": r.result.relative_residual,
                "iterations": r.result.iterations.len() - 1,
                "stop_reason": r.result.stop_reason,
                "condition_number": if r.result.condition_number.is_finite() { json!(r.result.condition_number) } else { Value::Null },
                "relative_offset": r.result.relative_offset,
                "parameters": r.result.parameters,
                "correlations": r.result.correlations,
                "held": r.result.held,
            });
            if let Some(truncation) = &r.truncation {
                parameters["truncation"] = json!(truncation);
            }
            parameters["residues"] = json!(o.measured.residues());
            if let Some([frf, modes]) = &r.fit.blocks {
                parameters["blocks"] = json!({
                    "frf": {"residues": frf.residues, "chi_square": frf.chi_square},
                    "modes": {"residues": modes.residues, "chi_square": modes.chi_square},
                });
            }
            out.push(("updating/parameters", ResultMessage::Json(parameters)));
            let mut residue = json!({"time": time, "window": o.window});
            if let Some(frf) = &r.fit.frf {
                residue["frequency_hz"] = json!(frf.model.frequency_hz);
                residue["frfs"] = frf
                    .model
                    .frfs
                    .iter()
                    .zip(&frf.residue)
                    .map(|(f, res)| json!({"input": f.input, "output": f.output, "relative_residue": res}))
                    .collect();
            }
            if let Some(pairs) = &r.fit.modes {
                residue["modes"] = pairs.iter().map(|p| json!({
                    "identified": p.identified + 1,
                    "model_mode": p.model_mode + 1,
                    "identified_frequency_hz": p.identified_frequency_hz,
                    "model_frequency_hz": p.model_frequency_hz,
                    "relative_frequency_error": (p.model_frequency_hz - p.identified_frequency_hz) / p.identified_frequency_hz,
                    "normalised_frequency_residue": (p.model_frequency_hz - p.identified_frequency_hz) / p.frequency_std_hz,
                    "identified_damping": p.identified_damping,
                    "model_damping": p.model_damping,
                    "mac": p.mac,
                })).collect();
            }
            out.push(("updating/residue", ResultMessage::Json(residue)));
            if let Some(frf) = &r.fit.frf {
                out.push(("frf/model", frf_message(time, o.window, &frf.model)));
            }
            out.push((
                "modes",
                ResultMessage::Json(json!({
                    "time": time,
                    "window": o.window,
                    "modes": r.modes.iter().enumerate().map(|(i, (f, z, k))| json!({
                        "index": i + 1, "frequency_hz": f, "damping_ratio": z, "kind": k
                    })).collect::<Vec<_>>(),
                })),
            ));
        }
        Err(e) => out.push((
            "updating/failures",
            ResultMessage::Json(json!({"time": time, "window": o.window, "error": e})),
        )),
    }
    out
}

pub fn health_message(time_ns: i128, h: &Health) -> Value {
    let mut v = serde_json::to_value(h).expect("plain data");
    v["time"] = json!(format_timestamp(time_ns));
    v
}

/// The results MCAP file.
pub struct ResultsWriter<W: Write + Seek> {
    writer: mcap::Writer<W>,
    prefix: String,
    channels: BTreeMap<&'static str, u16>,
    sequence: u32,
}

/// Adds `<prefix>/<suffix>` (JSON, with its JSON schema) to `writer`: its
/// channel id.
fn register<W: Write + Seek>(writer: &mut mcap::Writer<W>, prefix: &str, suffix: &str, schema: &str) -> Result<u16> {
    let schema_id = writer.add_schema(&format!("splinewatch.{suffix}"), "jsonschema", schema.as_bytes())?;
    Ok(writer.add_channel(schema_id, &format!("{prefix}/{suffix}"), "json", &BTreeMap::new())?)
}

impl ResultsWriter<BufWriter<File>> {
    pub fn create(path: &Path, prefix: &str) -> Result<Self> {
        Self::new(create_buffered(path)?, prefix)
    }

    /// A results file at `path` for `config`, its provenance recorded.
    pub fn create_for(path: &Path, config: &Config) -> Result<Self> {
        Self::create(path, &config.topic_prefix())?.with_provenance(Some(&provenance(config)))
    }
}

/// What a results file made with `config` rests on: this software's
/// version, the bridge's topic prefix and, when the config was read from a
/// file, its path, SHA-256 and text.
pub fn provenance(config: &Config) -> Provenance {
    use sha2::Digest;
    let (path, text) = config
        .source
        .as_ref()
        .map(|s| (s.path.display().to_string(), s.text.clone()))
        .unwrap_or_default();
    let sha256 = if text.is_empty() {
        String::new()
    } else {
        sha2::Sha256::digest(text.as_bytes())
            .iter()
            .map(|b| format!("{b:02x}"))
            .collect()
    };
    Provenance {
        version: env!("CARGO_PKG_VERSION").into(),
        prefix: config.topic_prefix(),
        structure: config.structure.name.clone(),
        config_path: path,
        config_sha256: sha256,
        config_toml: text,
    }
}

impl<W: Write + Seek> ResultsWriter<W> {
    pub fn new(w: W, prefix: &str) -> Result<Self> {
        let mut writer = crate::io::recording::mcap_options()
            .create(w)
            .context("cannot start the results MCAP file")?;
        let mut channels = BTreeMap::new();
        for (suffix, schema) in TOPICS {
            channels.insert(suffix, register(&mut writer, prefix, suffix, schema)?);
        }
        Ok(Self {
            writer,
            prefix: prefix.to_string(),
            channels,
            sequence: 0,
        })
    }

    pub fn prefix(&self) -> &str {
        &self.prefix
    }

    /// Records what made the file (its `splinewatch` metadata record).
    pub fn with_provenance(mut self, provenance: Option<&Provenance>) -> Result<Self> {
        if let Some(p) = provenance {
            self.writer
                .write_metadata(&mcap::records::Metadata {
                    name: PROVENANCE_METADATA.into(),
                    metadata: p.to_metadata(),
                })
                .context("cannot write the results file's provenance")?;
        }
        Ok(self)
    }

    /// Writes `message` on `<prefix>/<suffix>` at `time_ns`.
    pub fn write<M: Serialize + ?Sized>(&mut self, suffix: &str, time_ns: i128, message: &M) -> Result<()> {
        self.write_json(suffix, time_ns, &serde_json::to_vec(message)?)
    }

    /// Writes a message already serialised to JSON.
    pub fn write_json(&mut self, suffix: &str, time_ns: i128, json: &[u8]) -> Result<()> {
        if !self.channels.contains_key(suffix) {
            if let Some((name, schema)) = MONITORING_TOPICS
                .iter()
                .chain(&EVENT_TOPICS)
                .find(|(n, _)| *n == suffix)
            {
                let id = register(&mut self.writer, &self.prefix, name, schema)?;
                self.channels.insert(name, id);
            }
        }
        let channel_id = *self
            .channels
            .get(suffix)
            .with_context(|| format!("unknown result topic {suffix}"))?;
        let log_time = u64::try_from(time_ns.max(0)).unwrap_or(u64::MAX);
        self.sequence = self.sequence.wrapping_add(1);
        self.writer.write_to_known_channel(
            &mcap::records::MessageHeader {
                channel_id,
                sequence: self.sequence,
                log_time,
                publish_time: log_time,
            },
            json,
        )?;
        Ok(())
    }

    /// Closes the current chunk and hands it to the OS: a process killed
    /// after this loses nothing written before it (see `recover`).
    pub fn flush(&mut self) -> Result<()> {
        self.writer.flush().context("cannot flush the results MCAP file")
    }

    /// Writes the summary and index and flushes the underlying writer.
    pub fn finish(mut self) -> Result<W> {
        self.writer.finish().context("cannot finish the results MCAP file")?;
        let mut inner = self.writer.into_inner();
        inner.flush().context("cannot flush the results MCAP file")?;
        Ok(inner)
    }
}

/// The daemon's results files, surviving write errors (full or read-only
/// disk): a failing file is abandoned as it is (its completed chunks stay
/// recoverable with `splinewatch recover`), the error is counted and logged,
/// and the next message opens a new file (`open(1)`, `open(2)`, …). A
/// message that cannot be written anywhere is counted, never fatal.
///
/// With [`Self::rotate_every`], a file is also finalised (summary and
/// index written) once its messages span that much measurement time, and
/// the next message opens a new file, so at most one file is ever
/// unfinalised and a crash costs at most the unflushed tail of that one.
pub struct ResultsSink<W: Write + Seek> {
    open: Box<dyn FnMut(u32) -> Result<W> + Send>,
    prefix: String,
    provenance: Option<Provenance>,
    writer: Option<ResultsWriter<W>>,
    index: u32,
    /// Measurement time one file may span, ns.
    rotate_ns: Option<i128>,
    /// Measurement time of the open file's first timed message.
    file_start_ns: Option<i128>,
    /// Write, flush or open errors so far.
    pub errors: u64,
    /// Files finalised by rotation so far.
    pub rotations: u64,
}

impl<W: Write + Seek> ResultsSink<W> {
    /// Opens the first file (`open(0)`); failing here is an error, since a
    /// daemon that cannot write its first results file is misconfigured.
    pub fn new(prefix: &str, mut open: Box<dyn FnMut(u32) -> Result<W> + Send>) -> Result<Self> {
        let writer = ResultsWriter::new(open(0)?, prefix)?;
        Ok(Self {
            open,
            prefix: prefix.to_string(),
            provenance: None,
            writer: Some(writer),
            index: 0,
            rotate_ns: None,
            file_start_ns: None,
            errors: 0,
            rotations: 0,
        })
    }

    /// Records `provenance` in the open file and in every later one.
    pub fn with_provenance(mut self, provenance: Provenance) -> Result<Self> {
        if let Some(w) = self.writer.take() {
            self.writer = Some(w.with_provenance(Some(&provenance))?);
        }
        self.provenance = Some(provenance);
        Ok(self)
    }

    /// Finalise a file once its messages span `span_ns` of measurement time.
    pub fn rotate_every(mut self, span_ns: i128) -> Self {
        self.rotate_ns = Some(span_ns.max(1));
        self
    }

    /// Finalises the open file if the message at `time_ns` falls outside its
    /// span; untimed messages (`time_ns <= 0`, health before any data) stay
    /// in the current file.
    fn rotate_if_due(&mut self, time_ns: i128) {
        if time_ns <= 0 {
            return;
        }
        let due = match (self.file_start_ns, self.rotate_ns) {
            (Some(start), Some(span)) => time_ns - start >= span,
            _ => false,
        };
        if due {
            if let Some(w) = self.writer.take() {
                match w.finish() {
                    Ok(_) => self.rotations += 1,
                    Err(e) => self.fail("finish", e),
                }
            }
            self.file_start_ns = None;
        }
        if self.file_start_ns.is_none() {
            self.file_start_ns = Some(time_ns);
        }
    }

    fn fail(&mut self, what: &str, e: anyhow::Error) {
        self.writer = None;
        self.file_start_ns = None;
        self.errors += 1;
        if self.errors % 100 == 1 {
            tracing::warn!(message = "results file error; continuing with a new file", what, errors = self.errors, error = %format!("{e:#}"));
        }
    }

    fn writer(&mut self) -> Option<&mut ResultsWriter<W>> {
        if self.writer.is_none() {
            self.index += 1;
            let opened = (self.open)(self.index)
                .and_then(|w| ResultsWriter::new(w, &self.prefix))
                .and_then(|w| w.with_provenance(self.provenance.as_ref()));
            match opened {
                Ok(w) => self.writer = Some(w),
                Err(e) => {
                    self.fail("open", e);
                    return None;
                }
            }
        }
        self.writer.as_mut()
    }

    pub fn write<M: Serialize + ?Sized>(&mut self, suffix: &str, time_ns: i128, message: &M) {
        match serde_json::to_vec(message) {
            Ok(json) => self.write_json(suffix, time_ns, &json),
            Err(e) => self.fail("write", e.into()),
        }
    }

    /// Writes a message already serialised to JSON.
    pub fn write_json(&mut self, suffix: &str, time_ns: i128, json: &[u8]) {
        self.rotate_if_due(time_ns);
        if let Some(w) = self.writer() {
            if let Err(e) = w.write_json(suffix, time_ns, json) {
                self.fail("write", e);
            }
        }
    }

    pub fn flush(&mut self) {
        if let Some(w) = self.writer.as_mut() {
            if let Err(e) = w.flush() {
                self.fail("flush", e);
            }
        }
    }

    /// Finishes the open file; returns it (none if the last one failed).
    pub fn finish(mut self) -> Option<W> {
        let w = self.writer.take()?;
        match w.finish() {
            Ok(inner) => Some(inner),
            Err(e) => {
                self.fail("finish", e);
                None
            }
        }
    }
}

/// Opens results files for a [`ResultsSink`]: `path` first, then
/// `<stem>-1.<ext>`, `<stem>-2.<ext>`, … An existing file is never
/// overwritten (a daemon restarted with the same `--out` keeps the earlier
/// results): its number is skipped.
pub fn results_files(path: &Path) -> Box<dyn FnMut(u32) -> Result<BufWriter<File>> + Send> {
    let path = path.to_path_buf();
    let mut next = 0;
    Box::new(move |index| {
        let (number, target) = crate::io::files::first_free_from(&path, u32::max(next, index));
        next = number + 1;
        create_buffered(&target)
    })
}

/// Creates `path` (and its folder) for buffered writing.
fn create_buffered(path: &Path) -> Result<BufWriter<File>> {
    Ok(BufWriter::new(crate::io::files::create_output_file(path)?))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::frf_json::FrfEntry;

    /// The typed FRF message writes exactly the bytes of the JSON value it
    /// replaced (the FRF file's value with `time` and `window` added: keys
    /// sorted), with and without the optional fields.
    #[test]
    fn the_typed_frf_message_writes_the_bytes_of_the_value_tree() {
        let entry = |coherence: Option<Vec<f64>>, n_averages| FrfEntry {
            input: "P1".into(),
            output: "P7".into(),
            re: vec![1.5, -2.25e-7, f64::NAN],
            im: vec![0.0, 3.0e12, -0.1],
            coherence,
            n_averages,
        };
        let files = [
            FrfFile {
                quantity: Quantity::Accelerance,
                frequency_hz: vec![0.25, 0.5, 80.0],
                frfs: vec![entry(Some(vec![0.9, 1.0, 0.5]), Some(12.0)), entry(None, None)],
                start_timestamp: Some("2026-11-23T10:00:00Z".into()),
                end_timestamp: Some("2026-11-23T10:10:00Z".into()),
            },
            FrfFile {
                quantity: Quantity::Receptance,
                frequency_hz: vec![1.0],
                frfs: vec![entry(None, Some(3.0))],
                start_timestamp: None,
                end_timestamp: None,
            },
        ];
        for frf in &files {
            let mut tree = serde_json::to_value(frf).unwrap();
            tree["time"] = json!("2026-11-23T10:10:00Z");
            tree["window"] = json!(7);
            let typed = frf_message("2026-11-23T10:10:00Z", 7, frf);
            assert_eq!(
                String::from_utf8(serde_json::to_vec(&typed).unwrap()).unwrap(),
                String::from_utf8(serde_json::to_vec(&tree).unwrap()).unwrap()
            );
        }
    }
}
