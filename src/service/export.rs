//! `splinewatch export`: one update of a results file as a universal file:
//! the window's measured (or model) FRFs, the model's modes at the
//! window's updated parameters and the modes identified in that window,
//! on the sensors' geometry (studies::exchange).

use crate::io::frf_json::FrfFile;
use crate::io::named_value::NamedValue;
use crate::studies::exchange::IdentifiedMode;
use anyhow::{bail, Context, Result};
use serde::Deserialize;
use splinewatch_core::c64;

/// What a results file holds for one window.
#[derive(Debug, Clone, Default)]
pub struct WindowResults {
    pub window: u64,
    pub parameters: Vec<NamedValue>,
    pub measured: Option<FrfFile>,
    pub model: Option<FrfFile>,
    pub identified: Vec<IdentifiedMode>,
}

#[derive(Deserialize)]
struct ParametersMessage {
    parameters: Vec<NamedValue>,
}

#[derive(Deserialize)]
struct WindowOnly {
    window: u64,
}

#[derive(Deserialize)]
struct OmaMessage {
    modes: Vec<OmaMode>,
}

#[derive(Deserialize)]
struct OmaMode {
    frequency_hz: f64,
    damping_ratio: f64,
    shape: Vec<ShapeEntry>,
}

#[derive(Deserialize)]
struct ShapeEntry {
    sensor: String,
    re: f64,
    im: f64,
}

/// The results of `window` (default: the last updated one) in the results
/// MCAP file `bytes` written under `prefix`.
pub fn window_results(bytes: &[u8], prefix: &str, window: Option<u64>) -> Result<WindowResults> {
    let topic = |suffix: &str| format!("{prefix}/{suffix}");
    let (parameters, measured, model, oma) = (
        topic("updating/parameters"),
        topic("frf/measured"),
        topic("frf/model"),
        topic("oma/modes"),
    );
    let mut messages = Vec::new();
    for message in crate::io::recording::mcap_messages(bytes, false)? {
        let message = message.context("corrupt MCAP record")?;
        let t = &message.channel.topic;
        if [&parameters, &measured, &model, &oma].contains(&t) {
            let w: WindowOnly =
                serde_json::from_slice(&message.data).with_context(|| format!("a {t} message without its window"))?;
            messages.push((t.clone(), w.window, message.data.into_owned()));
        }
    }
    let updated: Vec<u64> = messages
        .iter()
        .filter(|(t, ..)| *t == parameters)
        .map(|(_, w, _)| *w)
        .collect();
    let Some(&last) = updated.last() else {
        bail!("no {parameters} message: no update in this results file (or another [structure] name)");
    };
    let window = window.unwrap_or(last);
    if !updated.contains(&window) {
        bail!(
            "window {window} was not updated (updated windows: {} … {}, {} in all)",
            updated[0],
            last,
            updated.len()
        );
    }
    let mut out = WindowResults {
        window,
        ..WindowResults::default()
    };
    for (t, w, data) in messages.iter().filter(|(_, w, _)| *w == window) {
        let context = || format!("window {w}: {t}");
        if *t == parameters {
            let m: ParametersMessage = serde_json::from_slice(data).with_context(context)?;
            out.parameters = m.parameters;
        } else if *t == oma {
            let m: OmaMessage = serde_json::from_slice(data).with_context(context)?;
            out.identified = m
                .modes
                .into_iter()
                .map(|m| IdentifiedMode {
                    frequency_hz: m.frequency_hz,
                    damping_ratio: m.damping_ratio,
                    shape: m.shape.into_iter().map(|s| (s.sensor, c64::new(s.re, s.im))).collect(),
                })
                .collect();
        } else {
            let mut v: serde_json::Value = serde_json::from_slice(data).with_context(context)?;
            if let Some(o) = v.as_object_mut() {
                o.remove("time");
                o.remove("window");
            }
            let frf: FrfFile = serde_json::from_value(v).with_context(context)?;
            *(if *t == measured {
                &mut out.measured
            } else {
                &mut out.model
            }) = Some(frf);
        }
    }
    Ok(out)
}
