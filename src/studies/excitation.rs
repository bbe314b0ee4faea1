//! Unmeasured excitation for output-only data: ambient forces at points of
//! the deck and traffic crossing it.
//!
//! - **Ambient**: `sources` uncorrelated Gaussian forces, each band-limited
//!   to the simulation band and scaled to `force_rms`, vertical at points
//!   drawn uniformly over ξ, η ∈ [0.05, 0.95] (or given in metres).
//! - **Traffic**: two lanes (η = 0.3 eastbound, 0.7 westbound) discretised
//!   in 33 points; vehicles arrive at random (Poisson, `vehicles_per_minute`
//!   over both lanes), weigh 10–400 kN (log-uniform) and cross at
//!   `speed_kmh`. A vehicle's load is its weight times `1 + 0.1 n(t)`, `n` the
//!   lane's band-limited unit-RMS roughness signal (the dynamic wheel
//!   load); a load between two lane points is shared linearly between them.
//!   Between vehicles only noise is recorded, as on a real deck.

use crate::config::{Config, GeometryConfig};
use anyhow::{bail, Result};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rand_distr::StandardNormal;
use splinewatch_core::geometry::surface::BSplineSurface;
use splinewatch_core::response::frf::SensorPoint;
use splinewatch_core::response::simulate::band_limit;

/// Kind of excitation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Excitation {
    /// Band-limited Gaussian random force.
    Random,
    /// Repeated linear sweeps across the band.
    Sweep,
    /// Hammer impacts (2 ms half-sines) at jittered intervals.
    Impact,
    /// Output-only: uncorrelated band-limited random forces at unmeasured
    /// points (`--sources`, `--source-at`); no force channel is recorded.
    Ambient,
    /// Output-only: vehicles crossing the deck in two lanes at random
    /// arrivals (`--speed-kmh`, `--vehicles-per-minute`); no force recorded.
    Traffic,
}

impl Excitation {
    /// The force is not measured (output-only data).
    pub fn is_unmeasured(self) -> bool {
        matches!(self, Excitation::Ambient | Excitation::Traffic)
    }
}

/// What the unmeasured sources need of the simulation options.
#[derive(Debug, Clone)]
pub struct SourceOptions {
    pub excitation: Excitation,
    /// Simulation rate (Hz) and force band (Hz).
    pub fs_sim: f64,
    pub band: (f64, f64),
    /// Ambient: RMS of each source (N), number of random points, or the points (x, y) in metres.
    pub force_rms: f64,
    pub sources: usize,
    pub source_xy: Vec<(f64, f64)>,
    /// Traffic.
    pub speed_kmh: f64,
    pub vehicles_per_minute: f64,
}

/// Lane positions across the deck (η) and their direction along ξ.
const LANES: [(f64, f64); 2] = [(0.3, 1.0), (0.7, -1.0)];
const LANE_POINTS: usize = 33;

/// The points where unmeasured forces act (appended to the model's sensors).
/// The length (m) traffic crosses: the deck's (single patch), or the first
/// patch's along ξ on its centre line.
fn deck_length(config: &Config) -> Result<f64> {
    if let Some(GeometryConfig::RectangularPlate { length, .. } | GeometryConfig::CylindricalPanel { length, .. }) =
        config.model.geometry
    {
        return Ok(length);
    }
    let patches = config.build_model_patches()?;
    let surface = patches[0].shell.surface();
    let steps = 64;
    let at = |k: usize| surface.evaluate(k as f64 / steps as f64, 0.5).r;
    Ok((0..steps)
        .map(|k| {
            let (a, b) = (at(k), at(k + 1));
            ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
        })
        .sum())
}

/// Where unmeasured forces act: on the first patch (the deck slab of a
/// deck of several).
pub fn source_points(
    options: &SourceOptions,
    surface: &BSplineSurface,
    rng: &mut ChaCha8Rng,
) -> Result<Vec<SensorPoint>> {
    let vertical = |xi: f64, eta: f64| SensorPoint {
        patch: 0,
        xi,
        eta,
        tau: 0.5,
        direction: [0.0, 0.0, 1.0],
    };
    match options.excitation {
        Excitation::Ambient if !options.source_xy.is_empty() => options
            .source_xy
            .iter()
            .map(|&(x, y)| match surface.locate_xy(x, y) {
                Some((xi, eta)) => Ok(vertical(xi, eta)),
                None => bail!("--source-at {x},{y}: the point is not on the deck"),
            })
            .collect(),
        Excitation::Ambient => Ok((0..options.sources.max(1))
            .map(|_| vertical(rng.random_range(0.05..0.95), rng.random_range(0.05..0.95)))
            .collect()),
        Excitation::Traffic => Ok(LANES
            .iter()
            .flat_map(|&(eta, _)| (0..LANE_POINTS).map(move |k| (k as f64 / (LANE_POINTS - 1) as f64, eta)))
            .map(|(xi, eta)| vertical(xi, eta))
            .collect()),
        _ => Ok(Vec::new()),
    }
}

/// `n` samples of Gaussian noise at `fs`, band-limited to `band` (FFT brick
/// wall) and scaled to the RMS `rms`: the random force of every simulated
/// excitation (measured or not).
pub fn band_limited_noise(rng: &mut ChaCha8Rng, n: usize, fs: f64, band: (f64, f64), rms: f64) -> Vec<f64> {
    let mut x: Vec<f64> = (0..n).map(|_| rng.sample::<f64, _>(StandardNormal)).collect();
    band_limit(&mut x, fs, band.0, band.1);
    let actual = (x.iter().map(|v| v * v).sum::<f64>() / n as f64).sqrt();
    x.iter().map(|v| v * rms / actual).collect()
}

/// One crossing vehicle.
#[derive(Debug, Clone)]
struct Vehicle {
    lane: usize,
    /// Time it enters the deck, s.
    enters: f64,
    weight: f64,
}

/// Forces of the unmeasured sources at the simulation rate, chunk by chunk.
pub struct UnmeasuredSources {
    excitation: Excitation,
    fs_sim: f64,
    band: (f64, f64),
    rms: f64,
    /// Ambient: one signal per source; traffic: one roughness signal per lane.
    chunk: Vec<Vec<f64>>,
    position: usize,
    /// Simulation steps before the current chunk.
    offset: usize,
    /// Traffic.
    crossing_seconds: f64,
    arrivals_per_second: f64,
    vehicles: Vec<Vehicle>,
    next_arrival: f64,
    signals: usize,
}

impl UnmeasuredSources {
    const CHUNK: usize = 1 << 16;

    pub fn new(options: &SourceOptions, config: &Config, points: usize, rng: &mut ChaCha8Rng) -> Result<Self> {
        let speed = options.speed_kmh / 3.6;
        if options.excitation == Excitation::Traffic
            && !(speed.is_finite()
                && speed > 0.0
                && options.vehicles_per_minute.is_finite()
                && options.vehicles_per_minute > 0.0)
        {
            bail!("--speed-kmh and --vehicles-per-minute must be positive");
        }
        let length = deck_length(config)?;
        let arrivals_per_second = options.vehicles_per_minute / 60.0;
        let mut sources = Self {
            excitation: options.excitation,
            fs_sim: options.fs_sim,
            band: options.band,
            rms: options.force_rms,
            chunk: Vec::new(),
            position: 0,
            offset: 0,
            crossing_seconds: length / speed,
            arrivals_per_second,
            vehicles: Vec::new(),
            next_arrival: 0.0,
            signals: if options.excitation == Excitation::Traffic {
                LANES.len()
            } else {
                points
            },
        };
        sources.next_arrival = sources.draw_gap(rng);
        Ok(sources)
    }

    fn draw_gap(&self, rng: &mut ChaCha8Rng) -> f64 {
        -(1.0 - rng.random::<f64>()).ln() / self.arrivals_per_second
    }

    /// The forces at the next simulation step, one per source point.
    pub fn next(&mut self, rng: &mut ChaCha8Rng, out: &mut [f64]) {
        if self.position == self.chunk.first().map_or(0, Vec::len) {
            self.offset += self.position;
            self.chunk = (0..self.signals)
                .map(|_| band_limited_noise(rng, Self::CHUNK, self.fs_sim, self.band, 1.0))
                .collect();
            self.position = 0;
        }
        let k = self.position;
        self.position += 1;
        match self.excitation {
            Excitation::Traffic => self.traffic(rng, k, out),
            _ => {
                for (o, signal) in out.iter_mut().zip(&self.chunk) {
                    *o = self.rms * signal[k];
                }
            }
        }
    }

    fn traffic(&mut self, rng: &mut ChaCha8Rng, k: usize, out: &mut [f64]) {
        let t = (self.offset + k) as f64 / self.fs_sim;
        while self.next_arrival <= t {
            self.vehicles.push(Vehicle {
                lane: rng.random_range(0..LANES.len()),
                enters: self.next_arrival,
                weight: (10e3f64.ln() + rng.random::<f64>() * (400e3f64 / 10e3).ln()).exp(),
            });
            self.next_arrival += self.draw_gap(rng);
        }
        let crossing = self.crossing_seconds;
        self.vehicles.retain(|v| t - v.enters <= crossing);
        out.fill(0.0);
        for v in &self.vehicles {
            let progress = (t - v.enters) / crossing;
            let along = if LANES[v.lane].1 > 0.0 {
                progress
            } else {
                1.0 - progress
            };
            let s = along.clamp(0.0, 1.0) * (LANE_POINTS - 1) as f64;
            let left = (s.floor() as usize).min(LANE_POINTS - 2);
            let share = s - left as f64;
            // Downward load: −z.
            let load = -v.weight * (1.0 + 0.1 * self.chunk[v.lane][k]);
            let base = v.lane * LANE_POINTS;
            out[base + left] += load * (1.0 - share);
            out[base + left + 1] += load * share;
        }
    }
}
