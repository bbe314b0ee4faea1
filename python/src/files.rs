//! Files the application writes, read by its own readers: raw-input
//! recordings (channel blocks) and results files (JSON messages).

use crate::errors::{bad, OrPy};
use anyhow::Context;
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use splinewatch::io::recording::{mcap_messages, read_recording as read_blocks, RecordedBlock};
use splinewatch::io::results_topics::{EVENT_TOPICS, MONITORING_TOPICS, TOPICS};
use splinewatch::io::wire::Limits;
use std::collections::BTreeMap;
use std::path::PathBuf;

/// The longest channel grid `read_recording` builds (2 GiB of samples): a
/// block time-stamped decades off would otherwise ask for terabytes.
const MAX_GRID_SAMPLES: usize = 1 << 28;

fn read(path: &PathBuf) -> PyResult<Vec<u8>> {
    std::fs::read(path)
        .with_context(|| format!("cannot read {}", path.display()))
        .or_py()
}

/// Every channel of a raw-input recording on its own sample grid: a list
/// of {name, data, fs, start_ns, quantity, unit, blocks, missing}, samples
/// between blocks NaN (`missing` counts them), and the messages that could
/// not be decoded as (topic, log time, error).
#[pyfunction]
pub fn read_recording<'py>(py: Python<'py>, path: PathBuf) -> PyResult<(Bound<'py, PyList>, Bound<'py, PyList>)> {
    let bytes = read(&path)?;
    let (blocks, rejected) = read_blocks(&bytes, &Limits::default())
        .with_context(|| format!("reading {}", path.display()))
        .or_py()?;
    let mut by_channel: BTreeMap<(String, &'static str), Vec<&RecordedBlock>> = BTreeMap::new();
    for b in &blocks {
        by_channel
            .entry((b.block.name.clone(), b.block.quantity.wire_name()))
            .or_default()
            .push(b);
    }
    let channels = PyList::empty(py);
    for ((name, quantity), mut run) in by_channel {
        run.sort_by_key(|b| b.block.start_ns);
        let first = &run[0].block;
        let fs = first.fs;
        if let Some(other) = run.iter().find(|b| b.block.fs != fs) {
            return Err(bad(format!(
                "{}: channel {name:?} changes rate from {fs} Hz to {} Hz",
                path.display(),
                other.block.fs
            )));
        }
        let offset = |b: &RecordedBlock| ((b.block.start_ns - first.start_ns) as f64 * fs / 1e9).round() as usize;
        let samples = run.iter().map(|b| offset(b) + b.block.data.len()).max().unwrap_or(0);
        if samples > MAX_GRID_SAMPLES {
            let last = run.last().expect("a channel has a block");
            return Err(bad(format!(
                "{}: channel {name:?} spans {:.0} s from its first block to its last ({} samples at {fs} Hz, \
                 more than {MAX_GRID_SAMPLES} on one grid): a block with a wrong time? Split the recording",
                path.display(),
                (last.block.start_ns - first.start_ns) as f64 / 1e9,
                samples
            )));
        }
        let mut data = vec![f64::NAN; samples];
        for b in &run {
            let at = offset(b);
            data[at..at + b.block.data.len()].copy_from_slice(&b.block.data);
        }
        let missing = data.iter().filter(|v| v.is_nan()).count();
        let channel = PyDict::new(py);
        channel.set_item("name", name)?;
        channel.set_item("data", PyArray1::from_vec(py, data))?;
        channel.set_item("fs", fs)?;
        channel.set_item("start_ns", first.start_ns as i64)?;
        channel.set_item("quantity", quantity)?;
        channel.set_item("unit", first.unit.clone())?;
        channel.set_item("blocks", run.len())?;
        channel.set_item("missing", missing)?;
        channels.append(channel)?;
    }
    let skipped = PyList::empty(py);
    for r in rejected {
        skipped.append((r.topic, r.log_time, r.error.to_string()))?;
    }
    Ok((channels, skipped))
}

/// Every JSON message of a results file, in file order: (topic, log time
/// in ns, JSON text).
#[pyfunction]
pub fn read_results(py: Python<'_>, path: PathBuf) -> PyResult<Vec<(String, u64, String)>> {
    let bytes = read(&path)?;
    py.detach(|| -> anyhow::Result<Vec<_>> {
        let mut out = Vec::new();
        for message in mcap_messages(&bytes, false).with_context(|| path.display().to_string())? {
            let message = message.with_context(|| format!("{}: corrupt MCAP record", path.display()))?;
            if message.channel.message_encoding != "json" {
                continue;
            }
            let text = String::from_utf8(message.data.into_owned())
                .with_context(|| format!("{}: a {} message is not UTF-8", path.display(), message.channel.topic))?;
            out.push((message.channel.topic.clone(), message.log_time, text));
        }
        Ok(out)
    })
    .or_py()
}

/// Every topic a results file may hold, as suffixes of `<prefix>/` (what
/// the application writes them under).
#[pyfunction]
pub fn result_topics() -> Vec<&'static str> {
    TOPICS
        .iter()
        .chain(&MONITORING_TOPICS)
        .chain(&EVENT_TOPICS)
        .map(|(topic, _)| *topic)
        .collect()
}
