//! Unmeasured excitation for output-only data: ambient forces at points of
//! the deck and traffic crossing it.
//!
//! - **Ambient**: `sources` uncorrelated Gaussian forces, each band-limited
//!   to the simulation band and scaled to `force_rms`, vertical at points
//!   drawn uniformly over ξ, η ∈ [0.05, 0.95] (or given in metres) of the
//!   riding patches (`riding_patches`: the deck slabs of a deck of several).
//! - **Traffic**: two lanes (η = 0.3 eastbound, 0.7 westbound; over several
//!   riding patches straight lanes at 30 % and 70 % of the width) discretised
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
use splinewatch_core::geometry::vec3::{cross, norm, normalize, sub};
use splinewatch_core::response::frf::SensorPoint;
use splinewatch_core::response::simulate::band_limit;
use std::f64::consts::PI;

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

/// Where unmeasured forces act (appended to the model's sensors), and the
/// length (m) each traffic lane crosses.
#[derive(Debug, Clone)]
pub struct SourceLayout {
    pub points: Vec<SensorPoint>,
    lane_lengths: [f64; LANES.len()],
}

/// The patches that carry the road: every patch of a single-patch model;
/// on several, those facing up (the normal at the patch's centre within
/// 30° of vertical) with no other such patch above their centre (a box's
/// soffit is under its deck slab).
fn riding_patches(surfaces: &[&BSplineSurface]) -> Result<Vec<usize>> {
    if surfaces.len() == 1 {
        return Ok(vec![0]);
    }
    let facing_up: Vec<usize> = (0..surfaces.len())
        .filter(|&i| {
            let c = surfaces[i].evaluate(0.5, 0.5);
            normalize(cross(c.r_xi, c.r_eta)).is_some_and(|n| n[2].abs() >= (PI / 6.0).cos())
        })
        .collect();
    let covered = |i: usize| {
        let c = surfaces[i].evaluate(0.5, 0.5).r;
        facing_up.iter().any(|&j| {
            j != i
                && surfaces[j]
                    .locate_xy(c[0], c[1])
                    .is_some_and(|(xi, eta)| surfaces[j].evaluate(xi, eta).r[2] > c[2] + 1e-6)
        })
    };
    let riding: Vec<usize> = facing_up.iter().copied().filter(|&i| !covered(i)).collect();
    if riding.is_empty() {
        bail!("no patch faces up to carry the simulated traffic or ambient sources");
    }
    Ok(riding)
}

/// The riding-surface point over `(x, y)` in plan: `(patch, ξ, η)`.
fn locate_on(surfaces: &[&BSplineSurface], riding: &[usize], x: f64, y: f64) -> Option<(usize, f64, f64)> {
    riding
        .iter()
        .find_map(|&i| surfaces[i].locate_xy(x, y).map(|(xi, eta)| (i, xi, eta)))
}

/// Area of a patch (midpoint rule on a 16 × 16 grid of `|r_ξ × r_η|`).
fn patch_area(surface: &BSplineSurface) -> f64 {
    const N: usize = 16;
    let h = 1.0 / N as f64;
    (0..N * N)
        .map(|k| {
            let e = surface.evaluate((k / N) as f64 * h + 0.5 * h, (k % N) as f64 * h + 0.5 * h);
            norm(cross(e.r_xi, e.r_eta)) * h * h
        })
        .sum()
}

/// Length (m) of `surface`'s centre line along ξ (64 chords).
fn centre_line_length(surface: &BSplineSurface, eta: f64) -> f64 {
    let steps = 64;
    let at = |k: usize| surface.evaluate(k as f64 / steps as f64, eta).r;
    (0..steps).map(|k| norm(sub(at(k + 1), at(k)))).sum()
}

/// Where unmeasured forces act. Ambient sources are drawn over the riding
/// patches (a patch in proportion to its area, then ξ, η uniformly in
/// [0.05, 0.95]) or located in plan (`--source-at`). Traffic lanes run
/// along ξ at η = 0.3 and 0.7 of a single riding patch; over several
/// (a slab split at its girders, spans in series) they are straight in plan
/// along the riding surface's principal axis at 30 % and 70 % of its width,
/// from where each enters the deck to where it leaves it.
pub fn source_points(
    options: &SourceOptions,
    config: &Config,
    surfaces: &[&BSplineSurface],
    rng: &mut ChaCha8Rng,
) -> Result<SourceLayout> {
    let riding = riding_patches(surfaces)?;
    let vertical = |patch: usize, xi: f64, eta: f64| SensorPoint {
        patch,
        xi,
        eta,
        tau: 0.5,
        direction: [0.0, 0.0, 1.0],
    };
    let single = |length: f64| [length; LANES.len()];
    let points = match options.excitation {
        Excitation::Ambient if !options.source_xy.is_empty() => options
            .source_xy
            .iter()
            .map(|&(x, y)| match locate_on(surfaces, &riding, x, y) {
                Some((patch, xi, eta)) => Ok(vertical(patch, xi, eta)),
                None => bail!("--source-at {x},{y}: the point is not on the deck"),
            })
            .collect::<Result<_>>()?,
        Excitation::Ambient => {
            let areas: Vec<f64> = riding.iter().map(|&i| patch_area(surfaces[i])).collect();
            let total: f64 = areas.iter().sum();
            (0..options.sources.max(1))
                .map(|_| {
                    let patch = if riding.len() == 1 {
                        riding[0]
                    } else {
                        let mut pick = rng.random::<f64>() * total;
                        let k = areas.iter().position(|&a| {
                            pick -= a;
                            pick < 0.0
                        });
                        riding[k.unwrap_or(riding.len() - 1)]
                    };
                    vertical(patch, rng.random_range(0.05..0.95), rng.random_range(0.05..0.95))
                })
                .collect()
        }
        Excitation::Traffic if riding.len() == 1 => {
            let patch = riding[0];
            let points = LANES
                .iter()
                .flat_map(|&(eta, _)| (0..LANE_POINTS).map(move |k| (k as f64 / (LANE_POINTS - 1) as f64, eta)))
                .map(|(xi, eta)| vertical(patch, xi, eta))
                .collect();
            let length = match config.model.geometry {
                Some(
                    GeometryConfig::RectangularPlate { length, .. } | GeometryConfig::CylindricalPanel { length, .. },
                ) => length,
                _ => centre_line_length(surfaces[patch], 0.5),
            };
            return Ok(SourceLayout {
                points,
                lane_lengths: single(length),
            });
        }
        Excitation::Traffic => return straight_lanes(surfaces, &riding),
        _ => Vec::new(),
    };
    Ok(SourceLayout {
        points,
        lane_lengths: single(0.0),
    })
}

/// Traffic lanes over several riding patches: straight in plan along the
/// principal axis of the riding surface (area-weighted), at the LANES'
/// fractions of its width; each lane from its first to its last point on
/// the deck (a skewed end moves it), `LANE_POINTS` evenly between, every
/// one of which must lie on a riding patch.
fn straight_lanes(surfaces: &[&BSplineSurface], riding: &[usize]) -> Result<SourceLayout> {
    const N: usize = 17;
    let samples: Vec<([f64; 2], f64)> = riding
        .iter()
        .flat_map(|&i| {
            (0..N * N).map(move |k| {
                let e = surfaces[i].evaluate((k / N) as f64 / (N - 1) as f64, (k % N) as f64 / (N - 1) as f64);
                ([e.r[0], e.r[1]], norm(cross(e.r_xi, e.r_eta)))
            })
        })
        .collect();
    let weight: f64 = samples.iter().map(|s| s.1).sum();
    let mean = [0, 1].map(|d| samples.iter().map(|(p, w)| p[d] * w).sum::<f64>() / weight);
    let moment = |a: usize, b: usize| {
        samples
            .iter()
            .map(|(p, w)| (p[a] - mean[a]) * (p[b] - mean[b]) * w)
            .sum::<f64>()
    };
    let angle = 0.5 * (2.0 * moment(0, 1)).atan2(moment(0, 0) - moment(1, 1));
    let along = [angle.cos(), angle.sin()];
    let across = [-along[1], along[0]];
    let project = |p: [f64; 2], axis: [f64; 2]| (p[0] - mean[0]) * axis[0] + (p[1] - mean[1]) * axis[1];
    let range = |axis: [f64; 2]| {
        samples
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), (p, _)| {
                let s = project(*p, axis);
                (lo.min(s), hi.max(s))
            })
    };
    let (s0, s1) = range(along);
    let (t0, t1) = range(across);
    let plan = |s: f64, t: f64| {
        (
            mean[0] + s * along[0] + t * across[0],
            mean[1] + s * along[1] + t * across[1],
        )
    };
    let mut points = Vec::with_capacity(LANES.len() * LANE_POINTS);
    let mut lane_lengths = [0.0; LANES.len()];
    for (lane, &(fraction, _)) in LANES.iter().enumerate() {
        let t = t0 + fraction * (t1 - t0);
        const SCAN: usize = 512;
        let on_deck: Vec<f64> = (0..=SCAN)
            .map(|k| s0 + (s1 - s0) * k as f64 / SCAN as f64)
            .filter(|&s| {
                let (x, y) = plan(s, t);
                locate_on(surfaces, riding, x, y).is_some()
            })
            .collect();
        let (Some(&start), Some(&end)) = (on_deck.first(), on_deck.last()) else {
            bail!(
                "traffic: lane {} (at {:.0} % of the deck's width) misses the deck",
                lane + 1,
                fraction * 100.0
            );
        };
        lane_lengths[lane] = end - start;
        for k in 0..LANE_POINTS {
            let s = start + (end - start) * k as f64 / (LANE_POINTS - 1) as f64;
            let (x, y) = plan(s, t);
            let Some((patch, xi, eta)) = locate_on(surfaces, riding, x, y) else {
                bail!(
                    "traffic: lane {} leaves the deck at ({x:.2}, {y:.2}) m (a deck of several patches curved in \
                     plan carries straight lanes only where they stay on it)",
                    lane + 1
                );
            };
            points.push(SensorPoint {
                patch,
                xi,
                eta,
                tau: 0.5,
                direction: [0.0, 0.0, 1.0],
            });
        }
    }
    Ok(SourceLayout { points, lane_lengths })
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
    /// Per lane.
    crossing_seconds: [f64; LANES.len()],
    arrivals_per_second: f64,
    vehicles: Vec<Vehicle>,
    next_arrival: f64,
    signals: usize,
}

impl UnmeasuredSources {
    const CHUNK: usize = 1 << 16;

    pub fn new(options: &SourceOptions, layout: &SourceLayout, rng: &mut ChaCha8Rng) -> Result<Self> {
        let speed = options.speed_kmh / 3.6;
        if options.excitation == Excitation::Traffic
            && !(speed.is_finite()
                && speed > 0.0
                && options.vehicles_per_minute.is_finite()
                && options.vehicles_per_minute > 0.0)
        {
            bail!("--speed-kmh and --vehicles-per-minute must be positive");
        }
        let arrivals_per_second = options.vehicles_per_minute / 60.0;
        let mut sources = Self {
            excitation: options.excitation,
            fs_sim: options.fs_sim,
            band: options.band,
            rms: options.force_rms,
            chunk: Vec::new(),
            position: 0,
            offset: 0,
            crossing_seconds: layout.lane_lengths.map(|length| length / speed),
            arrivals_per_second,
            vehicles: Vec::new(),
            next_arrival: 0.0,
            signals: if options.excitation == Excitation::Traffic {
                LANES.len()
            } else {
                layout.points.len()
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
        self.vehicles.retain(|v| t - v.enters <= crossing[v.lane]);
        out.fill(0.0);
        for v in &self.vehicles {
            let progress = (t - v.enters) / crossing[v.lane];
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

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    const MATERIAL: &str = "[model.materials.concrete]\ne1 = 30e9\ne2 = 30e9\ng12 = 12.5e9\ng13 = 12.5e9\n\
                            g23 = 12.5e9\nnu12 = 0.2\ndensity = 2500.0\n";

    /// A config of flat or vertical quadrilateral patches (corners in the
    /// order (ξ, η) = (0, 0), (1, 0), (1, 1), (0, 1)).
    fn deck(patches: &[(&str, [[f64; 3]; 4])]) -> Config {
        let mut text = format!("[structure]\nname = \"t\"\n{MATERIAL}");
        for (name, corners) in patches {
            text += &format!(
                "[[model.patches]]\nname = \"{name}\"\nmaterial = \"concrete\"\nthickness = 0.2\n\
                 degree = [2, 2]\ncontrol_points = [6, 4]\n[model.patches.geometry]\n\
                 kind = \"quadrilateral\"\ncorners = {corners:?}\n"
            );
        }
        Config::from_toml(&text).unwrap()
    }

    fn options(excitation: Excitation, sources: usize) -> SourceOptions {
        SourceOptions {
            excitation,
            fs_sim: 1024.0,
            band: (0.5, 80.0),
            force_rms: 1e3,
            sources,
            source_xy: Vec::new(),
            speed_kmh: 60.0,
            vehicles_per_minute: 10.0,
        }
    }

    fn layout(config: &Config, options: &SourceOptions) -> Result<SourceLayout> {
        let model = config.build_model_patches().unwrap();
        let surfaces: Vec<&BSplineSurface> = model.iter().map(|p| p.shell.surface()).collect();
        source_points(options, config, &surfaces, &mut ChaCha8Rng::seed_from_u64(7))
    }

    /// The road is the deck slab: not the webs (vertical), not a box's
    /// soffit (under the slab).
    #[test]
    fn the_riding_patches_are_the_slabs_nothing_covers() {
        let config = Config::from_toml(include_str!("../../config/overpass.toml")).unwrap();
        let patches = config.build_model_patches().unwrap();
        let surfaces: Vec<&BSplineSurface> = patches.iter().map(|p| p.shell.surface()).collect();
        let riding = riding_patches(&surfaces).unwrap();
        let names: Vec<&str> = riding.iter().map(|&i| config.model.patches[i].name.as_str()).collect();
        assert_eq!(names, ["top_slab"]);
        let webs_only = deck(&[(
            "web",
            [[0.0, 0.0, 0.0], [20.0, 0.0, 0.0], [20.0, 0.0, -1.5], [0.0, 0.0, -1.5]],
        )]);
        // A single patch carries the road whatever its orientation.
        assert_eq!(
            layout(&webs_only, &options(Excitation::Ambient, 3))
                .unwrap()
                .points
                .len(),
            3
        );
        let webs = deck(&[
            (
                "web_a",
                [[0.0, 0.0, 0.0], [20.0, 0.0, 0.0], [20.0, 0.0, -1.5], [0.0, 0.0, -1.5]],
            ),
            (
                "web_b",
                [[0.0, 4.0, 0.0], [20.0, 4.0, 0.0], [20.0, 4.0, -1.5], [0.0, 4.0, -1.5]],
            ),
        ]);
        let error = layout(&webs, &options(Excitation::Ambient, 3)).unwrap_err().to_string();
        assert!(error.contains("no patch faces up"), "{error}");
    }

    /// Two spans in series (20 m and 40 m, 6 m wide): ambient sources fall
    /// on each in proportion to its area; traffic lanes run straight over
    /// both at 30 % and 70 % of the width, the whole 60 m.
    #[test]
    fn sources_and_lanes_cover_every_riding_patch() {
        let config = deck(&[
            (
                "span_1",
                [[0.0, -3.0, 0.0], [20.0, -3.0, 0.0], [20.0, 3.0, 0.0], [0.0, 3.0, 0.0]],
            ),
            (
                "span_2",
                [[20.0, -3.0, 0.0], [60.0, -3.0, 0.0], [60.0, 3.0, 0.0], [20.0, 3.0, 0.0]],
            ),
        ]);
        let ambient = layout(&config, &options(Excitation::Ambient, 600)).unwrap();
        let on_first = ambient.points.iter().filter(|p| p.patch == 0).count();
        // Binomial(600, 1/3): 200 ± 11.5; bound 3.5 standard deviations.
        assert!(
            (on_first as f64 - 200.0).abs() < 40.0,
            "{on_first} of 600 on the 20-m span"
        );
        let traffic = layout(&config, &options(Excitation::Traffic, 0)).unwrap();
        assert_eq!(traffic.points.len(), LANES.len() * LANE_POINTS);
        let patches = config.build_model_patches().unwrap();
        for (lane, &(fraction, _)) in LANES.iter().enumerate() {
            // The scan steps 60/512 m: each end is found within a step.
            assert!(
                (traffic.lane_lengths[lane] - 60.0).abs() < 0.25,
                "lane {lane}: {} m",
                traffic.lane_lengths[lane]
            );
            let points = &traffic.points[lane * LANE_POINTS..(lane + 1) * LANE_POINTS];
            let xs: Vec<f64> = points
                .iter()
                .map(|p| {
                    let r = patches[p.patch].shell.surface().evaluate(p.xi, p.eta).r;
                    // Straight, at the lane's fraction of the width (either
                    // sense of the principal axis).
                    let offset = r[1] + 3.0;
                    assert!(
                        (offset - 6.0 * fraction).abs() < 1e-6 || (offset - 6.0 * (1.0 - fraction)).abs() < 1e-6,
                        "lane {lane}: y = {}",
                        r[1]
                    );
                    assert_eq!(p.patch, usize::from(r[0] > 20.0 + 1e-9), "x = {}", r[0]);
                    r[0]
                })
                .collect();
            let spacing = 60.0 / (LANE_POINTS - 1) as f64;
            for pair in xs.windows(2) {
                assert!(((pair[1] - pair[0]).abs() - spacing).abs() < 0.01, "{pair:?}");
            }
        }
    }
}
