//! `events --plot DIR`: every identified mode's frequency against the
//! event's amplitude (`[events] amplitude`: the ground's peak acceleration
//! or the deck's strong-motion RMS; log axis), with its ±1σ bar (dots),
//! and the updated model's dominant mode with its ±1σ (squares); alarmed
//! events in red.
//! The frequency axis spans the points (with their bars) within the band
//! the update fits (`[updating] band`, else `[frf] band`); the modes
//! outside the band are counted in the caption.

use crate::config::EventAmplitude;
use anyhow::{Context, Result};
use std::path::Path;

/// One identified mode of an event: the event's amplitude (m/s²), the
/// frequency and its standard deviation (Hz), and whether the event raised
/// an alarm.
pub struct ModePoint {
    pub amplitude: f64,
    pub frequency_hz: f64,
    pub std_hz: f64,
    pub alarmed: bool,
    /// The updated model's mode, not an identified one.
    pub model: bool,
}

pub fn frequency_vs_amplitude(modes: &[ModePoint], band: [f64; 2], kind: EventAmplitude, dir: &Path) -> Result<()> {
    use plotters::prelude::*;
    let fail = |e: &dyn std::fmt::Display| anyhow::anyhow!("plotting: {e}");
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let path = dir.join("frequency_vs_amplitude.svg");
    let inside: Vec<&ModePoint> = modes
        .iter()
        .filter(|m| (band[0]..=band[1]).contains(&m.frequency_hz))
        .collect();
    let outside = modes.len() - inside.len();
    let points: Vec<(f64, f64, f64, bool)> = inside
        .iter()
        .map(|m| (m.amplitude, m.frequency_hz, m.std_hz, m.alarmed))
        .collect();
    let model: Vec<bool> = inside.iter().map(|m| m.model).collect();
    let (mut x0, mut x1) = points
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), p| (a.min(p.0), b.max(p.0)));
    let (mut y0, mut y1) = (band[0], band[1]);
    if points.is_empty() {
        (x0, x1) = (0.01, 1.0);
    } else {
        let (low, high) = points.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p.1 - p.2), b.max(p.1 + p.2))
        });
        let pad = (0.1 * (high - low)).max(0.25);
        (y0, y1) = ((low - pad).max(band[0]), (high + pad).min(band[1]));
    }
    let caption = format!(
        "frequency against the ground's peak: identified (dots, ±1σ), updated model (squares); red: alarm{}",
        match outside {
            0 => String::new(),
            n => format!("; {n} outside {}–{} Hz not shown", band[0], band[1]),
        }
    );
    let root = SVGBackend::new(&path, (900, 560)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| fail(&e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(caption, ("sans-serif", 16))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(
            (x0 / 1.5..x1 * 1.5)
                .log_scale()
                .with_key_points(log_ticks(x0 / 1.5, x1 * 1.5)),
            y0..y1,
        )
        .map_err(|e| fail(&e))?;
    chart
        .configure_mesh()
        .x_desc(match kind {
            EventAmplitude::PgaGround => "ground peak acceleration (m/s²)",
            EventAmplitude::RmsDeck => "deck RMS over the strong motion (m/s²)",
        })
        .y_desc("frequency (Hz)")
        .x_label_formatter(&|v| tick(*v))
        .draw()
        .map_err(|e| fail(&e))?;
    for (&(x, f, s, alarmed), &is_model) in points.iter().zip(&model) {
        let colour = match (alarmed, is_model) {
            (true, _) => RED,
            (false, true) => BLUE,
            (false, false) => BLACK,
        };
        let bar = vec![(x, (f - s).max(y0)), (x, (f + s).min(y1))];
        chart
            .draw_series(std::iter::once(PathElement::new(bar, colour.stroke_width(2))))
            .map_err(|e| fail(&e))?;
        if is_model {
            let square = EmptyElement::at((x, f)) + Rectangle::new([(-4, -4), (4, 4)], colour.stroke_width(2));
            chart.draw_series(std::iter::once(square)).map_err(|e| fail(&e))?;
            continue;
        }
        chart
            .draw_series(std::iter::once(Circle::new((x, f), 4, colour.filled())))
            .map_err(|e| fail(&e))?;
    }
    root.present().map_err(|e| fail(&e))?;
    Ok(())
}

/// The ticks of a log axis from `low` to `high`: 1, 2 and 5 times the
/// powers of ten between them.
fn log_ticks(low: f64, high: f64) -> Vec<f64> {
    let (first, last) = (low.log10().floor() as i32, high.log10().ceil() as i32);
    (first..=last)
        .flat_map(|k| [1.0, 2.0, 5.0].map(|m| m * 10f64.powi(k)))
        .filter(|v| (low..=high).contains(v))
        .collect()
}

/// A tick's label: three significant digits, no trailing zeros (a log
/// axis's ticks are sums of floating-point steps: 0.30000000000000004).
fn tick(v: f64) -> String {
    if v <= 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let decimals = (2 - v.log10().floor() as i32).max(0) as usize;
    let text = format!("{v:.decimals$}");
    if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        text
    }
}

#[cfg(test)]
mod tests {
    /// A log axis is ticked at 1, 2 and 5 per decade inside its range.
    #[test]
    fn a_log_axis_is_ticked_at_one_two_and_five() {
        let ticks = super::log_ticks(0.045, 0.9);
        let expected = [0.05, 0.1, 0.2, 0.5];
        assert_eq!(ticks.len(), expected.len(), "{ticks:?}");
        for (t, e) in ticks.iter().zip(expected) {
            assert!((t / e - 1.0).abs() < 1e-12, "{ticks:?}");
        }
    }

    /// Ticks read as a person writes them.
    #[test]
    fn ticks_have_three_significant_digits_at_most() {
        let cases = [
            (0.30000000000000004, "0.3"),
            (0.05, "0.05"),
            (1.0, "1"),
            (2.5, "2.5"),
            (12.345, "12.3"),
            (150.0, "150"),
        ];
        for (v, text) in cases {
            assert_eq!(super::tick(v), text, "{v}");
        }
    }
}
