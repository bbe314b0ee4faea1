//! Automatic pole selection: stabilisation across model orders, hard
//! criteria, and clustering of the stable poles into physical modes.
//!
//! Stability (Kvåle et al. 2017, as KOMA's `find_stable_poles`): a pole at
//! order `n_i` is stable when, for each of the `level` orders below it, the
//! pole nearest in frequency there differs by at most `frequency` (relative),
//! `damping` (relative) and has `MAC ≥ 1 − mac`. Hard criteria (Reynders,
//! Houbrechts & De Roeck 2012) reject poles with `ζ ∉ (0, max_damping)`,
//! `MPC < min_mpc` or a frequency outside the band. Clustering is single
//! linkage on `d = |f₁ − f₂|/max(f₁, f₂) + (1 − MAC)` with threshold
//! `distance` (as pyOMA2's hierarchical clustering, with one distance that
//! separates close modes by shape), then one pole per order per cluster
//! (the one nearest the cluster's median frequency) and at least
//! `min_poles` poles for a cluster to count as a physical mode.

use super::shape::mac;
use super::ssi::Pole;
use serde::{Deserialize, Serialize};

/// When a pole is stable and physical.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StabilityCriteria {
    /// Number of consecutive lower orders a pole must recur at.
    pub level: usize,
    /// Relative frequency tolerance between orders.
    pub frequency: f64,
    /// Relative damping tolerance between orders.
    pub damping: f64,
    /// `1 − MAC` tolerance between orders.
    pub mac: f64,
    /// Largest plausible damping ratio.
    pub max_damping: f64,
    /// Smallest modal phase collinearity of a structural mode.
    pub min_mpc: f64,
}

impl Default for StabilityCriteria {
    fn default() -> Self {
        Self {
            level: 3,
            frequency: 0.01,
            damping: 0.25,
            mac: 0.02,
            max_damping: 0.2,
            min_mpc: 0.7,
        }
    }
}

/// How stable poles group into modes.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ClusterCriteria {
    /// Single-linkage threshold on `Δf/f + (1 − MAC)`.
    pub distance: f64,
    /// Fewest poles (distinct orders) of a physical mode, as a fraction of
    /// the orders computed.
    pub min_fraction: f64,
    /// A jackknife replicate (the record less one batch) has found a mode
    /// when its nearest pole at a member's order is within this distance
    /// (`Δf/f + 1 − MAC`) of the full record's; `None`: `distance`. SRIM's
    /// replicates of short earthquake records move more than that (issue
    /// 45: at 0.02 the Painter Street mode near 4 Hz got a spread in 1 of
    /// 11 records, at 0.1 in 6); on long ambient records 0.1 let a close
    /// pair's replicates take each other's poles (shape spreads twice the
    /// Monte Carlo scatter), so it stays a per-config choice.
    pub replicate_distance: Option<f64>,
}

impl Default for ClusterCriteria {
    fn default() -> Self {
        Self {
            distance: 0.02,
            min_fraction: 0.2,
            replicate_distance: None,
        }
    }
}

impl ClusterCriteria {
    /// The distance within which a replicate's pole is the mode's.
    pub fn replicate_distance(&self) -> f64 {
        self.replicate_distance.unwrap_or(self.distance)
    }

    /// Fewest poles a physical mode needs when `orders_computed` orders
    /// were computed (at least 2).
    pub fn min_poles(&self, orders_computed: usize) -> usize {
        ((self.min_fraction * orders_computed as f64).ceil() as usize).max(2)
    }
}

/// Distance between two poles used by clustering and by pairing.
pub fn pole_distance(a: &Pole, b: &Pole) -> f64 {
    (a.frequency_hz - b.frequency_hz).abs() / a.frequency_hz.max(b.frequency_hz) + (1.0 - mac(&a.shape, &b.shape))
}

/// Passes the hard criteria (damping, phase collinearity, band).
pub fn is_physical(pole: &Pole, criteria: &StabilityCriteria, band: [f64; 2]) -> bool {
    pole.damping_ratio > 0.0
        && pole.damping_ratio < criteria.max_damping
        && pole.mpc >= criteria.min_mpc
        && (band[0]..=band[1]).contains(&pole.frequency_hz)
}

/// `stable[o][j]`: pole `j` of order index `o` is stable and physical.
pub fn stable_flags(by_order: &[Vec<Pole>], criteria: &StabilityCriteria, band: [f64; 2]) -> Vec<Vec<bool>> {
    let level = criteria.level;
    by_order
        .iter()
        .enumerate()
        .map(|(o, poles)| {
            poles
                .iter()
                .map(|pole| {
                    o >= level
                        && is_physical(pole, criteria, band)
                        && (1..=level).all(|back| recurs(pole, &by_order[o - back], criteria))
                })
                .collect()
        })
        .collect()
}

/// The nearest-frequency pole of `lower` agrees with `pole`.
fn recurs(pole: &Pole, lower: &[Pole], c: &StabilityCriteria) -> bool {
    let Some(near) = lower.iter().min_by(|a, b| {
        (a.frequency_hz - pole.frequency_hz)
            .abs()
            .total_cmp(&(b.frequency_hz - pole.frequency_hz).abs())
    }) else {
        return false;
    };
    (pole.frequency_hz - near.frequency_hz).abs() <= c.frequency * near.frequency_hz
        && (pole.damping_ratio - near.damping_ratio).abs() <= c.damping * near.damping_ratio.abs()
        && mac(&pole.shape, &near.shape) >= 1.0 - c.mac
}

/// Clusters `poles` (the stable ones, any order); returns, per physical mode
/// in ascending frequency, the indices of its poles (one per order).
pub fn cluster(poles: &[&Pole], criteria: &ClusterCriteria, orders_computed: usize) -> Vec<Vec<usize>> {
    let n = poles.len();
    let mut by_frequency: Vec<usize> = (0..n).collect();
    by_frequency.sort_by(|&a, &b| poles[a].frequency_hz.total_cmp(&poles[b].frequency_hz));
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    // Only poles within `distance` in relative frequency can be linked.
    for (s, &a) in by_frequency.iter().enumerate() {
        for &b in &by_frequency[s + 1..] {
            let (fa, fb) = (poles[a].frequency_hz, poles[b].frequency_hz);
            if fb - fa > criteria.distance * fb {
                break;
            }
            if pole_distance(poles[a], poles[b]) <= criteria.distance {
                let (ra, rb) = (root(&mut parent, a), root(&mut parent, b));
                parent[ra] = rb;
            }
        }
    }
    let mut groups: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
    for &i in &by_frequency {
        groups.entry(root(&mut parent, i)).or_default().push(i);
    }
    let min_poles = criteria.min_poles(orders_computed);
    let mut modes: Vec<Vec<usize>> = groups
        .into_values()
        .map(|members| one_per_order(poles, members))
        .filter(|members| members.len() >= min_poles)
        .collect();
    modes.sort_by(|a, b| poles[a[0]].frequency_hz.total_cmp(&poles[b[0]].frequency_hz));
    modes
}

/// Keeps, for each order, the member nearest the cluster's median frequency;
/// the result is sorted by frequency.
fn one_per_order(poles: &[&Pole], members: Vec<usize>) -> Vec<usize> {
    let median = median(members.iter().map(|&i| poles[i].frequency_hz).collect());
    let mut best: std::collections::BTreeMap<usize, usize> = Default::default();
    for i in members {
        let slot = best.entry(poles[i].order).or_insert(i);
        if (poles[i].frequency_hz - median).abs() < (poles[*slot].frequency_hz - median).abs() {
            *slot = i;
        }
    }
    let mut kept: Vec<usize> = best.into_values().collect();
    kept.sort_by(|&a, &b| poles[a].frequency_hz.total_cmp(&poles[b].frequency_hz));
    kept
}

/// Median of a non-empty list (mean of the middle two for an even count).
pub fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let m = v.len() / 2;
    if v.len() % 2 == 1 {
        v[m]
    } else {
        0.5 * (v[m - 1] + v[m])
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::c64;

    fn pole(order: usize, f: f64, zeta: f64, shape: &[f64]) -> Pole {
        Pole {
            order,
            frequency_hz: f,
            damping_ratio: zeta,
            shape: shape.iter().map(|&v| c64::new(v, 0.0)).collect(),
            mpc: 1.0,
        }
    }

    #[test]
    fn a_recurring_pole_is_stable_and_a_wandering_one_is_not() {
        let a = [1.0, 0.5, -0.2];
        let by_order: Vec<Vec<Pole>> = (0..6)
            .map(|o| {
                vec![
                    pole(2 * o + 2, 10.0 * (1.0 + 1e-4 * o as f64), 0.02, &a),
                    pole(2 * o + 2, 20.0 + 0.5 * o as f64, 0.02, &[0.0, 1.0, 1.0]),
                ]
            })
            .collect();
        let flags = stable_flags(&by_order, &StabilityCriteria::default(), [0.0, 100.0]);
        assert_eq!(flags[2], vec![false, false], "below the stability level");
        assert_eq!(flags[5], vec![true, false]);
        let out_of_band = stable_flags(&by_order, &StabilityCriteria::default(), [12.0, 100.0]);
        assert!(!out_of_band[5][0]);
    }

    #[test]
    fn close_modes_with_different_shapes_stay_apart() {
        let (a, b) = ([1.0, 1.0, 0.0], [1.0, -1.0, 0.3]);
        let poles: Vec<Pole> = (0..10)
            .flat_map(|o| [pole(o, 73.5 + 0.001 * o as f64, 0.01, &a), pole(o, 74.0, 0.01, &b)])
            .collect();
        let refs: Vec<&Pole> = poles.iter().collect();
        let modes = cluster(&refs, &ClusterCriteria::default(), 10);
        assert_eq!(modes.len(), 2);
        assert!(modes.iter().all(|m| m.len() == 10));
        assert!(modes[0].iter().all(|&i| poles[i].frequency_hz < 73.8));
    }

    #[test]
    fn a_rare_cluster_is_noise_and_orders_count_once() {
        let a = [1.0, 0.0, 0.0];
        let mut poles: Vec<Pole> = (0..10).map(|o| pole(o, 5.0, 0.01, &a)).collect();
        poles.push(pole(3, 5.0001, 0.01, &a)); // a second pole at order 3
        poles.push(pole(4, 30.0, 0.01, &a)); // a lone pole
        let refs: Vec<&Pole> = poles.iter().collect();
        let modes = cluster(&refs, &ClusterCriteria::default(), 10);
        assert_eq!(modes.len(), 1);
        assert_eq!(modes[0].len(), 10);
        assert!(
            !modes[0].contains(&10),
            "the extra order-3 pole is further from the median"
        );
    }
}
