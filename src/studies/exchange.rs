//! Universal files for modal-testing software: the config's sensors as UFF
//! points, and a whole file (units, geometry, FRFs, model and identified
//! modes) for `frf --format uff` and `splinewatch export`.

use crate::config::Config;
use crate::io::frf_json::FrfFile;
use crate::io::named_value::NamedValue;
use crate::io::uff::write::{UffMode, UffWriter};
use crate::io::uff::UffPoint;
use anyhow::{bail, Context, Result};
use splinewatch_core::c64;
use splinewatch_core::response::frf::Sensor;
use splinewatch_core::solvers::modal::ModeKind;

/// The config's sensors as universal-file points: node `uff_node` (default:
/// the sensor's place in the list, 1, 2, …), position on the deck surface,
/// measuring axis. Two sensors at one node along one axis are an error.
pub fn uff_points(config: &Config) -> Result<Vec<UffPoint>> {
    let model = config.build_model()?;
    let sensors = config.build_sensors(&model)?;
    let mut points: Vec<UffPoint> = Vec::with_capacity(sensors.len());
    for (k, (c, (name, p))) in config.sensors.iter().zip(sensors).enumerate() {
        let point = UffPoint {
            name,
            node: c.uff_node.unwrap_or(k as i64 + 1),
            position: match p {
                Sensor::Shell(p) => model.patches[p.patch].shell.surface().evaluate(p.xi, p.eta).r,
                Sensor::Beam(b) => b.at,
            },
            axis: axis_of(match p {
                Sensor::Shell(p) => p.direction,
                Sensor::Beam(b) => b.direction,
            }),
        };
        if let Some(other) = points
            .iter()
            .find(|o| o.node == point.node && o.axis.map(|a| a.0) == point.axis.map(|a| a.0))
        {
            bail!(
                "config: sensors: {} and {} share uff_node {} and measuring axis: give each its own uff_node",
                other.name,
                point.name,
                point.node
            );
        }
        points.push(point);
    }
    Ok(points)
}

/// The global axis (0 x, 1 y, 2 z) and sign of a direction along one.
fn axis_of(direction: [f64; 3]) -> Option<(usize, f64)> {
    let d = splinewatch_core::geometry::vec3::normalize(direction)?;
    (0..3).find(|&k| d[k].abs() > 1.0 - 1e-9).map(|k| (k, d[k].signum()))
}

/// A mode identified from measurements: frequency, damping ratio and its
/// complex shape by sensor name.
#[derive(Debug, Clone, PartialEq)]
pub struct IdentifiedMode {
    pub frequency_hz: f64,
    pub damping_ratio: f64,
    pub shape: Vec<(String, c64)>,
}

/// What goes into a universal file besides the geometry.
#[derive(Debug, Clone, Default)]
pub struct UffContent<'a> {
    /// FRFs (dataset 58) and what they are ("measured", "model").
    pub frfs: Option<(&'a FrfFile, &'a str)>,
    /// The model's modes below this frequency (Hz) at the sensors (dataset
    /// 55, normal modes), at `parameters` (name, value) over the config's
    /// values; `None`: no model modes.
    pub model_modes_below_hz: Option<f64>,
    pub parameters: &'a [NamedValue],
    /// Identified modes (dataset 55, complex modes).
    pub identified: &'a [IdentifiedMode],
}

/// A universal file of the config's deck: units (164), its sensors as nodes
/// (15) on a trace line (82), then `content`.
pub fn uff_file(config: &Config, content: &UffContent<'_>) -> Result<String> {
    let points = uff_points(config)?;
    let mut w = UffWriter::new();
    w.nodes(&points);
    w.trace_line(1, &format!("{} sensors", config.structure.name), &points);
    if let Some((frf, what)) = content.frfs {
        w.frfs(frf, &points, what).map_err(anyhow::Error::msg)?;
    }
    if let Some(below) = content.model_modes_below_hz {
        let modes = model_modes(config, content.parameters, below)?;
        w.normal_modes(&modes, &points, &format!("{} model modes", config.structure.name));
    }
    if !content.identified.is_empty() {
        let modes = content
            .identified
            .iter()
            .map(|m| identified_shape(m, &points))
            .collect::<Result<Vec<_>>>()?;
        w.complex_modes(&modes, &points, &format!("{} identified modes", config.structure.name));
    }
    Ok(w.finish())
}

/// The model's elastic modes up to `below_hz` with `parameters` set, their
/// mass-normalised shapes at the sensors and ζ(f).
fn model_modes(config: &Config, parameters: &[NamedValue], below_hz: f64) -> Result<Vec<UffMode>> {
    let (setup, state) = super::parameters::modal_state_of(config, parameters)?;
    let sensors = setup.sensor_names.len();
    Ok((0..state.modes.len())
        .filter(|&i| {
            state.modes.frequency_hz(i) <= below_hz
                && state.modes.frequency_hz(i) > 0.0
                && state.modes.kinds[i] != ModeKind::Rigid
        })
        .map(|i| UffMode {
            frequency_hz: state.modes.frequency_hz(i),
            damping_ratio: state.zeta[i],
            shape: (0..sensors).map(|s| c64::new(state.amplitude(s, i), 0.0)).collect(),
        })
        .collect())
}

/// An identified mode's shape on the file's points (zero where a sensor was
/// not identified).
fn identified_shape(mode: &IdentifiedMode, points: &[UffPoint]) -> Result<UffMode> {
    let mut shape = vec![c64::new(0.0, 0.0); points.len()];
    for (sensor, value) in &mode.shape {
        let k = points
            .iter()
            .position(|p| &p.name == sensor)
            .with_context(|| format!("identified mode at {} Hz: unknown sensor {sensor:?}", mode.frequency_hz))?;
        shape[k] = *value;
    }
    Ok(UffMode {
        frequency_hz: mode.frequency_hz,
        damping_ratio: mode.damping_ratio,
        shape,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 30: on a deck of several patches a sensor's universal-file
    /// node is its point in space: the web sensor at the web's bottom edge.
    #[test]
    fn uff_points_of_a_deck_of_patches_are_in_three_dimensions() {
        let config = Config::from_toml(include_str!("../../tests/fixtures/slab_on_webs.toml")).unwrap();
        let points = uff_points(&config).unwrap();
        let slab = points[0].position;
        assert!((slab[0] - 10.0).abs() < 1e-9 && (slab[1] + 2.0).abs() < 1e-9 && slab[2].abs() < 1e-9);
        let web = points[1].position;
        assert!(
            (web[0] - 10.0).abs() < 1e-9 && (web[1] - 2.0).abs() < 1e-9 && (web[2] + 1.5).abs() < 1e-9,
            "{web:?}"
        );
    }
}
