//! How a mode moves the deck: the shares of its translational kinetic
//! energy (lumped at the shell's control points) along the deck's
//! longitudinal axis, across it and vertically, with the part of the motion
//! across and vertical that is a twist of the cross-sections about the
//! longitudinal axis counted as torsion.
//!
//! The longitudinal axis is the horizontal principal axis of the control
//! points' lumped mass (the direction the deck is longest in plan). The
//! deck is cut into [`STATIONS`] equal stations along it; in each, a twist
//! `θ` about the station's mass centroid moves a point at offset `s` across
//! and height `r` above the centroid by `θ s` vertically and `−θ r` across.
//! `θ` is the mass-weighted least-squares fit of the mode's motion across
//! and vertical (after the station's mean translation), and its energy
//! `θ² Σ m (s² + r²)` is the torsion share; what it explains is taken out of
//! the vertical and transverse shares. Beams and rigid bodies are not part
//! of the deck: their energy is not counted.

use crate::geometry::vec3::Vec3;

/// Stations along the deck for the twist fit.
pub const STATIONS: usize = 16;

/// Where a mode's translational energy goes (the four sum to 1).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize)]
pub struct MotionShares {
    pub longitudinal: f64,
    pub transverse: f64,
    pub vertical: f64,
    pub torsion: f64,
}

/// A mode named by where most of its energy goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Motion {
    Longitudinal,
    Transverse,
    Vertical,
    Torsion,
}

impl Motion {
    pub fn label(self) -> &'static str {
        match self {
            Self::Longitudinal => "longitudinal",
            Self::Transverse => "transverse",
            Self::Vertical => "vertical",
            Self::Torsion => "torsion",
        }
    }
}

impl MotionShares {
    /// The largest share's motion (none for a mode without translation).
    pub fn dominant(&self) -> Option<Motion> {
        let shares = [
            (Motion::Longitudinal, self.longitudinal),
            (Motion::Transverse, self.transverse),
            (Motion::Vertical, self.vertical),
            (Motion::Torsion, self.torsion),
        ];
        let (motion, share) = shares.into_iter().max_by(|a, b| a.1.total_cmp(&b.1))?;
        (share > 0.0).then_some(motion)
    }
}

/// One station: its control points with their offset across (`s`) and
/// height (`r`) from the station's mass centroid.
#[derive(Debug, Clone)]
struct Station {
    points: Vec<(usize, f64, f64)>,
    /// `Σ m (s² + r²)`: the station's polar moment about its centroid.
    polar: f64,
}

/// The deck's axes and stations, from its control points' positions and
/// lumped translational masses.
#[derive(Debug, Clone)]
pub struct DeckAxes {
    pub longitudinal: Vec3,
    pub transverse: Vec3,
    lumped: Vec<f64>,
    stations: Vec<Station>,
}

impl DeckAxes {
    /// `None` when there is no mass or the deck has no extent in plan.
    pub fn new(positions: &[Vec3], lumped: &[f64]) -> Option<Self> {
        assert_eq!(positions.len(), lumped.len(), "one mass per control point");
        let mass: f64 = lumped.iter().sum();
        if mass.is_nan() || mass <= 0.0 {
            return None;
        }
        let centroid = |axis: usize| positions.iter().zip(lumped).map(|(p, m)| m * p[axis]).sum::<f64>() / mass;
        let (cx, cy) = (centroid(0), centroid(1));
        let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
        for (p, m) in positions.iter().zip(lumped) {
            let (dx, dy) = (p[0] - cx, p[1] - cy);
            sxx += m * dx * dx;
            syy += m * dy * dy;
            sxy += m * dx * dy;
        }
        if (sxx + syy).is_nan() || sxx + syy <= 0.0 {
            return None;
        }
        // The larger eigenvalue's eigenvector of [[sxx, sxy], [sxy, syy]].
        let angle = 0.5 * (2.0 * sxy).atan2(sxx - syy);
        let longitudinal = [angle.cos(), angle.sin(), 0.0];
        let transverse = [-angle.sin(), angle.cos(), 0.0];
        let along: Vec<f64> = positions
            .iter()
            .map(|p| p[0] * longitudinal[0] + p[1] * longitudinal[1])
            .collect();
        let (lo, hi) = along
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x)));
        let width = (hi - lo).max(f64::MIN_POSITIVE) / STATIONS as f64;
        let mut members: Vec<Vec<usize>> = vec![Vec::new(); STATIONS];
        for (cp, &x) in along.iter().enumerate() {
            let k = (((x - lo) / width) as usize).min(STATIONS - 1);
            members[k].push(cp);
        }
        let stations = members
            .into_iter()
            .filter_map(|cps| {
                let m: f64 = cps.iter().map(|&c| lumped[c]).sum();
                if m.is_nan() || m <= 0.0 {
                    return None;
                }
                let across = |c: usize| positions[c][0] * transverse[0] + positions[c][1] * transverse[1];
                let s0 = cps.iter().map(|&c| lumped[c] * across(c)).sum::<f64>() / m;
                let r0 = cps.iter().map(|&c| lumped[c] * positions[c][2]).sum::<f64>() / m;
                let points: Vec<(usize, f64, f64)> =
                    cps.iter().map(|&c| (c, across(c) - s0, positions[c][2] - r0)).collect();
                let polar = points.iter().map(|&(c, s, r)| lumped[c] * (s * s + r * r)).sum();
                Some(Station { points, polar })
            })
            .collect();
        Some(Self {
            longitudinal,
            transverse,
            lumped: lumped.to_vec(),
            stations,
        })
    }

    /// The shares of a mode whose translation at control point `cp` is
    /// `translation(cp)` (global x, y, z).
    pub fn shares(&self, translation: impl Fn(usize) -> Vec3) -> MotionShares {
        let dot = |a: Vec3, b: Vec3| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let (mut along, mut across, mut vertical, mut twist) = (0.0, 0.0, 0.0, 0.0);
        let (mut twist_across, mut twist_vertical) = (0.0, 0.0);
        for station in &self.stations {
            let moved: Vec<(f64, f64, f64)> = station
                .points
                .iter()
                .map(|&(c, _, _)| {
                    let u = translation(c);
                    (dot(u, self.longitudinal), dot(u, self.transverse), u[2])
                })
                .collect();
            let mut moment = 0.0;
            for (&(c, s, r), &(l, t, w)) in station.points.iter().zip(&moved) {
                let m = self.lumped[c];
                along += m * l * l;
                across += m * t * t;
                vertical += m * w * w;
                // The centroid is the mass-weighted mean of (s, r), so the
                // station's mean translation drops out of this product.
                moment += m * (w * s - t * r);
            }
            if station.polar > 0.0 {
                let theta = moment / station.polar;
                let (s2, r2) = station.points.iter().fold((0.0, 0.0), |(a, b), &(c, s, r)| {
                    (a + self.lumped[c] * s * s, b + self.lumped[c] * r * r)
                });
                twist += theta * theta * station.polar;
                twist_vertical += theta * theta * s2;
                twist_across += theta * theta * r2;
            }
        }
        let total = along + across + vertical;
        if total.is_nan() || total <= 0.0 {
            return MotionShares::default();
        }
        // The twist's parts cannot exceed the motion they explain (a least
        // squares fit over both directions at once): clamp round-off.
        let vertical = (vertical - twist_vertical).max(0.0);
        let across = (across - twist_across).max(0.0);
        let sum = along + across + vertical + twist;
        MotionShares {
            longitudinal: along / sum,
            transverse: across / sum,
            vertical: vertical / sum,
            torsion: twist / sum,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 16 m × 9 m deck in plan, turned by `angle` about z, 16 × 9 points
    /// of unit mass (one column of points per station), at heights `z` (one
    /// layer, or a box's two slabs).
    fn deck(angle: f64, heights: &[f64]) -> Vec<Vec3> {
        let mut points = Vec::new();
        for &z in heights {
            for i in 0..16 {
                for j in 0..9 {
                    let (x, y) = (i as f64 + 0.5, j as f64 * 9.0 / 8.0 - 4.5);
                    points.push([x * angle.cos() - y * angle.sin(), x * angle.sin() + y * angle.cos(), z]);
                }
            }
        }
        points
    }

    /// A motion given in the deck's own axes: (along, across, z) at a point.
    type MotionField = dyn Fn(f64, f64, f64) -> Vec3;

    fn shares_of(points: &[Vec3], axes: &DeckAxes, u: impl Fn(f64, f64, f64) -> Vec3) -> MotionShares {
        // The motion given in the deck's own axes (along, across, z).
        let (l, t) = (axes.longitudinal, axes.transverse);
        axes.shares(|c| {
            let p = points[c];
            let (x, y) = (p[0] * l[0] + p[1] * l[1], p[0] * t[0] + p[1] * t[1]);
            let [a, b, w] = u(x, y, p[2]);
            [a * l[0] + b * t[0], a * l[1] + b * t[1], w]
        })
    }

    #[test]
    fn each_motion_is_named_on_a_turned_deck_and_a_box() {
        for angle in [0.0, 0.5, -1.2] {
            for heights in [&[0.0][..], &[-1.0, 1.0][..]] {
                let points = deck(angle, heights);
                let axes = DeckAxes::new(&points, &vec![1.0; points.len()]).unwrap();
                // The axis found is the deck's length, either way along it.
                assert!((axes.longitudinal[0] * angle.cos() + axes.longitudinal[1] * angle.sin()).abs() > 1.0 - 1e-12);
                let bend = |x: f64| (std::f64::consts::PI * x / 16.0).sin();
                let cases: [(Motion, Box<MotionField>); 4] = [
                    (Motion::Vertical, Box::new(move |x, _, _| [0.0, 0.0, bend(x)])),
                    (Motion::Transverse, Box::new(move |x, _, _| [0.0, bend(x), 0.0])),
                    (Motion::Longitudinal, Box::new(|_, _, _| [1.0, 0.0, 0.0])),
                    // A twist about the centreline: vertical with the offset
                    // across, across with the height.
                    (
                        Motion::Torsion,
                        Box::new(move |x, y, z| [0.0, -bend(x) * z, bend(x) * y]),
                    ),
                ];
                for (motion, u) in &cases {
                    let shares = shares_of(&points, &axes, u);
                    let total = shares.longitudinal + shares.transverse + shares.vertical + shares.torsion;
                    assert!((total - 1.0).abs() < 1e-12, "{shares:?}");
                    assert_eq!(shares.dominant(), Some(*motion), "{angle} {heights:?}: {shares:?}");
                    let share = match motion {
                        Motion::Longitudinal => shares.longitudinal,
                        Motion::Transverse => shares.transverse,
                        Motion::Vertical => shares.vertical,
                        Motion::Torsion => shares.torsion,
                    };
                    // Pure motions: all of it (the twist is exact per station).
                    assert!(share > 1.0 - 1e-9, "{motion:?}, {angle} {heights:?}: {shares:?}");
                }
                // On the flat deck, vertical bending plus a twist of equal
                // energy: half each (the mean of y² over a column is 8.4375).
                if heights.len() == 1 {
                    let c = 8.4375f64.sqrt();
                    let mix = shares_of(&points, &axes, |x, y, _| [0.0, 0.0, bend(x) * (1.0 + y / c)]);
                    assert!(
                        (mix.vertical - 0.5).abs() < 1e-12 && (mix.torsion - 0.5).abs() < 1e-12,
                        "{mix:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn a_deck_without_mass_or_extent_has_no_axes() {
        assert!(DeckAxes::new(&[[0.0; 3]; 3], &[0.0; 3]).is_none());
        assert!(DeckAxes::new(&[[1.0, 2.0, 0.0]; 3], &[1.0; 3]).is_none());
        assert_eq!(MotionShares::default().dominant(), None);
    }
}
