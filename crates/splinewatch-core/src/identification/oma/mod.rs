//! Operational (output-only) modal analysis: covariance-driven SSI with
//! automatic pole selection and jackknife uncertainty.
//!
//! Data flow: samples → [`OutputCorrelations`] (batched, FFT) → block Hankel
//! and its SVD ([`SubspaceModel`]) → poles at every order of
//! [`OmaSettings::orders`] → stable and physical poles
//! ([`stabilisation::stable_flags`]) → modes by clustering
//! ([`stabilisation::cluster`]) → standard deviations
//! ([`uncertainty::jackknife`]). A mode's frequency and damping are the
//! medians over its cluster's poles (one per order), its shape that of the
//! medoid (the pole at the median frequency); the jackknife recomputes the
//! same medians on every replicate, so it measures the spread of exactly
//! what is reported (the median over orders scatters less than any one
//! order's pole: a jackknife at one order overstated the scatter by up to
//! 2.9× at 5 minutes).

pub mod correlation;
pub mod shape;
pub mod spectrum;
pub mod ssi;
pub mod stabilisation;
pub mod uncertainty;

pub use correlation::OutputCorrelations;
pub use spectrum::{spectral_singular_values, SpectralSingularValues};
pub use ssi::{Pole, SubspaceModel};
pub use stabilisation::{ClusterCriteria, StabilityCriteria};
pub use uncertainty::UncertaintyMethod;

use faer::c64;
use serde::{Deserialize, Serialize};
use thiserror::Error;

#[derive(Debug, Clone, PartialEq, Error)]
pub enum OmaError {
    #[error("no channels to analyse")]
    NoChannels,
    #[error("channel {channel} has {len} samples, the first has {expected}")]
    UnequalLengths {
        channel: usize,
        len: usize,
        expected: usize,
    },
    #[error("channel {channel} holds an infinity (a NaN marks a missing sample)")]
    NonFinite { channel: usize },
    #[error("reference channel {index} does not exist ({channels} channels)")]
    BadReference { index: usize, channels: usize },
    #[error("the window is too short: {samples} samples, at least {needed} needed for these block rows and batches")]
    TooShort { samples: usize, needed: usize },
    #[error("{block_rows} block rows need correlations up to lag {}", 2 * block_rows)]
    TooFewLags { block_rows: usize },
    #[error("the SVD of the block Hankel matrix did not converge")]
    SvdFailed,
    #[error("the block Hankel matrix is singular at order {order} (no signal, or fewer modes than the order)")]
    SingularHankel { order: usize },
    #[error("model order {order} is above the largest this Hankel matrix supports ({max})")]
    OrderTooHigh { order: usize, max: usize },
    #[error("the eigenvalues of the state matrix at order {order} did not converge")]
    EigenFailed { order: usize },
    #[error("no physical mode: {stable} stable poles, none in a cluster of at least {min_poles}")]
    NoModes { stable: usize, min_poles: usize },
    #[error("invalid OMA settings: {0}")]
    InvalidSettings(String),
}

/// `f` of every item, on up to four threads, gathered in item order: each
/// result is `f` of its item alone, so it does not depend on the thread
/// count or on which thread computed it. Workers take the next item from
/// the end (the callers' items cost the same or grow with their index, as
/// the model orders do: largest first balances the threads, where a fixed
/// round-robin gave one of two threads 7 % more of the orders' `Σ n³`).
pub(crate) fn ordered_map<T: Sync, R: Send>(items: &[T], f: impl Fn(&T) -> R + Sync) -> Vec<R> {
    let threads = std::thread::available_parallelism()
        .map_or(1, |t| t.get())
        .clamp(1, 4)
        .min(items.len().max(1));
    if threads == 1 {
        return items.iter().map(f).collect();
    }
    let remaining = std::sync::atomic::AtomicUsize::new(items.len());
    let take = || {
        remaining
            .fetch_update(
                std::sync::atomic::Ordering::Relaxed,
                std::sync::atomic::Ordering::Relaxed,
                |n| n.checked_sub(1),
            )
            .ok()
            .map(|n| n - 1)
    };
    let mut results: Vec<Option<R>> = std::iter::repeat_with(|| None).take(items.len()).collect();
    std::thread::scope(|scope| {
        let workers: Vec<_> = (0..threads)
            .map(|_| {
                let (f, take) = (&f, &take);
                scope.spawn(move || std::iter::from_fn(take).map(|i| (i, f(&items[i]))).collect::<Vec<_>>())
            })
            .collect();
        for worker in workers {
            for (i, r) in worker.join().expect("a worker of ordered_map panicked") {
                results[i] = Some(r);
            }
        }
    });
    results
        .into_iter()
        .map(|r| r.expect("every item is taken once"))
        .collect()
}

/// Checks that there are channels and that all are as long as the first;
/// returns that length.
pub(crate) fn channel_length(channels: &[&[f64]]) -> Result<usize, OmaError> {
    let n = channels.first().ok_or(OmaError::NoChannels)?.len();
    match channels.iter().position(|c| c.len() != n) {
        Some(bad) => Err(OmaError::UnequalLengths {
            channel: bad,
            len: channels[bad].len(),
            expected: n,
        }),
        None => Ok(n),
    }
}

/// [`channel_length`], and no sample infinite (a NaN marks a missing one):
/// the records the correlations and SRIM's data matrices are made of.
pub(crate) fn sample_length(channels: &[&[f64]]) -> Result<usize, OmaError> {
    let n = channel_length(channels)?;
    match channels.iter().position(|c| c.iter().any(|v| v.is_infinite())) {
        Some(bad) => Err(OmaError::NonFinite { channel: bad }),
        None => Ok(n),
    }
}

/// Settings of one identification (the `[oma]` config section).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct OmaSettings {
    /// `p`: the Hankel matrix has `p + 1` block rows and `p` block columns.
    pub block_rows: usize,
    /// Model orders `min_order, min_order + order_step, …, ≤ max_order`.
    pub min_order: usize,
    pub max_order: usize,
    pub order_step: usize,
    /// Frequency band of the reported modes (Hz).
    pub band: [f64; 2],
    pub stability: StabilityCriteria,
    pub clustering: ClusterCriteria,
    /// Correlation batches for the uncertainty (≥ 2; more batches, a better
    /// variance estimate, one replicate each).
    pub batches: usize,
    /// How the replicates' poles are obtained (default first order).
    pub uncertainty: UncertaintyMethod,
}

impl Default for OmaSettings {
    fn default() -> Self {
        Self {
            block_rows: 40,
            min_order: 2,
            max_order: 120,
            order_step: 2,
            band: [0.5, 80.0],
            stability: StabilityCriteria::default(),
            clustering: ClusterCriteria::default(),
            batches: 16,
            uncertainty: UncertaintyMethod::FirstOrder,
        }
    }
}

impl OmaSettings {
    /// Rejects settings no data can satisfy.
    pub fn check(&self) -> Result<(), OmaError> {
        let bad = |what: &str| Err(OmaError::InvalidSettings(what.into()));
        if self.block_rows == 0 || self.order_step == 0 || self.min_order == 0 {
            return bad("block_rows, min_order and order_step must be positive");
        }
        if self.min_order > self.max_order {
            return bad("min_order must not exceed max_order");
        }
        if !(self.band[0] >= 0.0 && self.band[1] > self.band[0] && self.band[1].is_finite()) {
            return bad("band must be [low, high] with 0 <= low < high");
        }
        if self.batches < 2 {
            return bad("batches must be at least 2 (the jackknife needs them)");
        }
        let s = &self.stability;
        let c = &self.clustering;
        if [
            s.frequency,
            s.damping,
            s.mac,
            s.max_damping,
            c.distance,
            c.replicate_distance(),
        ]
        .iter()
        .any(|v| !(v.is_finite() && *v > 0.0))
            || !(0.0..=1.0).contains(&s.min_mpc)
            || !(0.0..=1.0).contains(&c.min_fraction)
        {
            return bad("stability and clustering tolerances must be positive (min_mpc, min_fraction in [0, 1])");
        }
        Ok(())
    }

    /// Correlation lags the Hankel matrix needs: `2p`.
    pub fn max_lag(&self) -> usize {
        2 * self.block_rows
    }

    /// The orders to compute, capped at what the model supports.
    pub fn orders(&self, supported: usize) -> Vec<usize> {
        (self.min_order..=self.max_order.min(supported))
            .step_by(self.order_step)
            .collect()
    }
}

/// One identified mode.
#[derive(Debug, Clone, PartialEq)]
pub struct IdentifiedMode {
    pub frequency_hz: f64,
    pub damping_ratio: f64,
    /// Jackknife standard deviations; `None` when fewer than two replicates
    /// found the mode.
    pub frequency_std_hz: Option<f64>,
    pub damping_std: Option<f64>,
    /// At every channel, largest component `1 + 0i`.
    pub shape: Vec<c64>,
    pub shape_std: Option<Vec<f64>>,
    pub mpc: f64,
    /// Order of the reported pole and number of orders the mode was stable at.
    pub order: usize,
    pub stable_orders: usize,
}

/// A pole of the stabilisation diagram.
#[derive(Debug, Clone, PartialEq)]
pub struct DiagramPole {
    pub order: usize,
    pub frequency_hz: f64,
    pub damping_ratio: f64,
    pub stable: bool,
    /// Index into [`OmaResult::modes`] when the pole belongs to a mode.
    pub mode: Option<usize>,
}

/// What one identification produced.
#[derive(Debug, Clone)]
pub struct OmaResult {
    pub modes: Vec<IdentifiedMode>,
    pub diagram: Vec<DiagramPole>,
    /// Singular values of the block Hankel matrix.
    pub singular_values: Vec<f64>,
}

/// Identifies the modes of `correlations` (sampled at `fs`); see the module
/// documentation for the steps.
pub fn identify(correlations: &OutputCorrelations, fs: f64, settings: &OmaSettings) -> Result<OmaResult, OmaError> {
    settings.check()?;
    let model = SubspaceModel::new(
        &correlations.estimate(),
        correlations.channels(),
        correlations.references().len(),
        settings.block_rows,
        settings.max_order,
        fs,
    )?;
    let source = uncertainty::HankelReplicates {
        correlations,
        block_rows: settings.block_rows,
    };
    identify_model(&model, &source, fs, settings)
}

/// The steps after the subspace model, shared by every subspace method
/// (SSI-cov above; SRIM in the `srim` module beside this one): poles at every
/// order of `settings`, stable and physical poles, modes by clustering, their
/// medians and spreads over the replicates of `source`, the diagram.
pub fn identify_model(
    model: &SubspaceModel,
    source: &dyn uncertainty::ReplicateSource,
    fs: f64,
    settings: &OmaSettings,
) -> Result<OmaResult, OmaError> {
    let mut orders = settings.orders(model.max_order());
    let (mut by_order, mut eigens) = (Vec::new(), Vec::new());
    // One eigenvalue problem per order, independent: on both cores. The
    // eigendecompositions are kept for the first-order uncertainty.
    for result in ordered_map(&orders, |&order| model.eigen(order)) {
        match result {
            Ok(eigen) => {
                by_order.push(model.poles_of(&eigen));
                eigens.push(eigen);
            }
            // Fewer modes in the data than the order: stop at the last one.
            Err(OmaError::SingularHankel { .. }) if !by_order.is_empty() => break,
            Err(e) => return Err(e),
        }
    }
    orders.truncate(by_order.len());
    let flags = stabilisation::stable_flags(&by_order, &settings.stability, settings.band);
    let stable: Vec<(usize, usize)> = flags
        .iter()
        .enumerate()
        .flat_map(|(o, f)| f.iter().enumerate().filter(|(_, s)| **s).map(move |(j, _)| (o, j)))
        .collect();
    let stable_poles: Vec<&Pole> = stable.iter().map(|&(o, j)| &by_order[o][j]).collect();
    let clusters = stabilisation::cluster(&stable_poles, &settings.clustering, by_order.len());
    if clusters.is_empty() {
        return Err(OmaError::NoModes {
            stable: stable.len(),
            min_poles: settings.clustering.min_poles(by_order.len()),
        });
    }
    let modes = summarise(
        source,
        (model, &eigens),
        fs,
        settings,
        &orders,
        &clusters,
        &stable_poles,
    );
    let mut mode_of = std::collections::HashMap::new();
    for (m, members) in clusters.iter().enumerate() {
        for &i in members {
            mode_of.insert(stable[i], m);
        }
    }
    let diagram = by_order
        .iter()
        .enumerate()
        .flat_map(|(o, poles)| poles.iter().enumerate().map(move |(j, p)| (o, j, p)))
        .map(|(o, j, p)| DiagramPole {
            order: p.order,
            frequency_hz: p.frequency_hz,
            damping_ratio: p.damping_ratio,
            stable: flags[o][j],
            mode: mode_of.get(&(o, j)).copied(),
        })
        .collect();
    Ok(OmaResult {
        modes,
        diagram,
        singular_values: model.singular_values().to_vec(),
    })
}

/// The reported modes of the clusters, with their jackknife spreads.
///
/// The medians use each cluster's poles at every `stride`-th computed order
/// (about 15 orders), so a jackknife replicate recomputes poles at about 15
/// orders rather than all (the eigenvalue problems dominate its cost).
fn summarise(
    source: &dyn uncertainty::ReplicateSource,
    (model, eigens): (&SubspaceModel, &[ssi::OrderEigen]),
    fs: f64,
    settings: &OmaSettings,
    orders: &[usize],
    clusters: &[Vec<usize>],
    stable_poles: &[&Pole],
) -> Vec<IdentifiedMode> {
    let stride = orders.len().div_ceil(15).max(1);
    let sampled: Vec<usize> = orders.iter().copied().step_by(stride).collect();
    let poles_of: Vec<uncertainty::ModePoles<'_>> = clusters
        .iter()
        .map(|c| {
            let all: Vec<&Pole> = c.iter().map(|&i| stable_poles[i]).collect();
            let mut members: Vec<&Pole> = all.iter().copied().filter(|p| sampled.contains(&p.order)).collect();
            if members.is_empty() {
                members = all;
            }
            uncertainty::ModePoles {
                medoid: members[members.len() / 2],
                members,
            }
        })
        .collect();
    let spreads = uncertainty::spreads(
        settings.uncertainty,
        source,
        (model, eigens),
        fs,
        &poles_of,
        settings.clustering.replicate_distance(),
    );
    poles_of
        .iter()
        .zip(spreads)
        .zip(clusters)
        .map(|((mode, spread), cluster)| {
            let (frequency_hz, damping_ratio) = mode.medians();
            IdentifiedMode {
                frequency_hz,
                damping_ratio,
                frequency_std_hz: spread.as_ref().map(|s| s.frequency_std_hz),
                damping_std: spread.as_ref().map(|s| s.damping_std),
                shape: mode.medoid.shape.clone(),
                shape_std: spread.map(|s| s.shape_std),
                mpc: mode.medoid.mpc,
                order: mode.medoid.order,
                stable_orders: cluster.len(),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Items of very unequal cost come back in order, each its own result.
    #[test]
    fn ordered_map_keeps_the_items_order() {
        let items: Vec<u64> = (0..37).collect();
        let got = ordered_map(&items, |&i| {
            // Work that grows with the index, so threads finish out of order.
            (0..i * 2_000).fold(i, |acc, k| acc.wrapping_mul(31).wrapping_add(k)) % 1_000 + 1_000 * i
        });
        let want: Vec<u64> = items
            .iter()
            .map(|&i| (0..i * 2_000).fold(i, |acc, k| acc.wrapping_mul(31).wrapping_add(k)) % 1_000 + 1_000 * i)
            .collect();
        assert_eq!(got, want);
        assert!(ordered_map(&[] as &[u64], |&i| i).is_empty());
    }
}
