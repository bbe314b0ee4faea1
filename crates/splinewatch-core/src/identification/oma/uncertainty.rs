//! Uncertainty of identified modes by delete-one-batch replicates
//! (the jackknife, Efron & Stein 1981) over the correlation batches, each
//! replicate either re-identified exactly or continued to first order.
//!
//! Each identified quantity is a smooth function of the mean correlations,
//! `θ = g(R̄)`. Döhler & Mevel (2013) propagate the sample covariance of the
//! batch correlations through the first-order sensitivity of `g`; the
//! jackknife estimates the same first-order variance without deriving it:
//! with `θ_(b)` computed from the correlations of all batches but `b`,
//! `var θ ≈ (B−1)/B Σ_b (θ_(b) − θ̄)²`, and it is asymptotically equal to
//! the delta method for a smooth `g`. Each replicate uses almost all the
//! data, so it keeps the full window's bias (unlike re-identifying on short
//! sub-windows). Two ways to get a replicate's poles
//! ([`UncertaintyMethod`]):
//! - `jackknife`: its own SVD and eigenvalue problems at the orders of the
//!   reported modes, each member matched to the nearest pole (the exact
//!   replicate; 16 SVDs and ~15 eigenvalue problems each);
//! - `first_order` (default): the replicate's Hankel matrix on the full
//!   window's right singular vectors ([`SubspaceModel::replicate`]) and each
//!   member's eigenpair continued to first order
//!   ([`SubspaceModel::continued`]): the first-order propagation of Döhler
//!   & Mevel (2013) evaluated on the batch deviations, which is the delta
//!   method with the batches' covariance; the eigendecompositions are the
//!   identification's own, and a replicate costs one product, one small
//!   Cholesky solve per order and `O(n)` per pole (`O(n²)` per shape). Both recompute the same
//!   medians per replicate; `tests/verification/oma.rs` compares both with
//!   the scatter over independent records.

use super::correlation::OutputCorrelations;
use super::ssi::{block_hankel, Continuation, OrderEigen, Pole, SubspaceModel};
use super::stabilisation::{median, pole_distance};
use super::OmaError;
use faer::{c64, Mat};
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, BTreeSet};

/// How the replicates' poles are obtained (`[oma] uncertainty`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum UncertaintyMethod {
    /// Each replicate continued to first order from the full window.
    #[default]
    FirstOrder,
    /// Each replicate re-identified (SVD, eigenvalue problems, matching).
    Jackknife,
}

/// Where the delete-one-batch replicates come from: the matrix the model
/// was identified from ([`SubspaceModel::from_matrix`]), made again from
/// every batch but one. The block Hankel matrix of the output correlations
/// (SSI-cov, [`HankelReplicates`]) and SRIM's information matrix (the
/// `srim` module beside `oma`) are two.
pub trait ReplicateSource: Sync {
    /// Batches (replicates); fewer than two give no spread.
    fn batches(&self) -> usize;
    /// The matrix of every batch but `left_out`.
    fn matrix_without(&self, left_out: usize) -> Result<Mat<f64>, OmaError>;
    /// The subspace model of a replicate's `matrix`, made as the record's
    /// was: by default its SVD ([`SubspaceModel::from_matrix`]).
    fn model(&self, matrix: &Mat<f64>, channels: usize, max_order: usize, fs: f64) -> Result<SubspaceModel, OmaError> {
        SubspaceModel::from_matrix(matrix, channels, max_order, fs)
    }
}

/// SSI-cov's replicates: the block Hankel matrix of the correlations of all
/// batches but one.
pub struct HankelReplicates<'a> {
    pub correlations: &'a OutputCorrelations,
    pub block_rows: usize,
}

impl ReplicateSource for HankelReplicates<'_> {
    fn batches(&self) -> usize {
        self.correlations.batches()
    }

    fn matrix_without(&self, left_out: usize) -> Result<Mat<f64>, OmaError> {
        let c = self.correlations;
        block_hankel(
            &c.estimate_without(Some(left_out)),
            c.channels(),
            c.references().len(),
            self.block_rows,
        )
    }
}

/// Standard deviations of `modes` (identified by `full`, with the
/// eigendecompositions `eigens` of its orders, at `fs`) by `method` over the
/// replicates of `source`; see the module documentation.
pub fn spreads(
    method: UncertaintyMethod,
    source: &dyn ReplicateSource,
    (full, eigens): (&SubspaceModel, &[OrderEigen]),
    fs: f64,
    modes: &[ModePoles<'_>],
    max_distance: f64,
) -> Vec<Option<Spread>> {
    match method {
        UncertaintyMethod::FirstOrder => first_order(source, full, eigens, modes),
        UncertaintyMethod::Jackknife => jackknife(source, full.channels(), fs, modes, max_distance),
    }
}

/// Jackknife standard deviations of one mode.
#[derive(Debug, Clone, PartialEq)]
pub struct Spread {
    pub frequency_std_hz: f64,
    pub damping_std: f64,
    /// Per sensor, of the shape scaled as the reported one.
    pub shape_std: Vec<f64>,
    /// Replicates in which the mode was found (of `batches`).
    pub replicates: usize,
}

/// A mode as the estimator reports it: the medians of frequency and damping
/// over its poles (one per order) and the shape of its medoid.
#[derive(Debug, Clone)]
pub struct ModePoles<'a> {
    /// The cluster's poles, one per order.
    pub members: Vec<&'a Pole>,
    /// The member at the median frequency.
    pub medoid: &'a Pole,
}

impl ModePoles<'_> {
    /// `(median frequency, median damping)` of the members.
    pub fn medians(&self) -> (f64, f64) {
        (
            median(self.members.iter().map(|p| p.frequency_hz).collect()),
            median(self.members.iter().map(|p| p.damping_ratio).collect()),
        )
    }
}

/// Spreads of `modes`: every replicate is re-identified and recomputes
/// each member's pole (the nearest at its order within `max_distance`, see
/// [`pole_distance`]) and the same medians, so the spread is that of
/// exactly what is reported.
pub fn jackknife(
    source: &dyn ReplicateSource,
    channels: usize,
    fs: f64,
    modes: &[ModePoles<'_>],
    max_distance: f64,
) -> Vec<Option<Spread>> {
    let batches = source.batches();
    if batches < 2 {
        return vec![None; modes.len()];
    }
    // Replicates only need poles up to the highest order any mode uses.
    let max_order = modes
        .iter()
        .flat_map(|m| m.members.iter().chain([&m.medoid]).map(|p| p.order))
        .max()
        .unwrap_or(1);
    // Replicates are independent: on up to four threads, in batch order.
    let left_out: Vec<usize> = (0..batches).collect();
    gather(
        super::ordered_map(&left_out, |&b| {
            replicate_modes(source, b, channels, fs, max_order, modes, max_distance)
        }),
        modes.len(),
    )
}

/// Spreads of `modes` from first-order replicates (see the module
/// documentation): the eigendecompositions of the orders the modes' poles
/// come from (`eigens`, the identification's own) are inverted once, each
/// replicate continues exactly the members' eigenvalues and the medoids'
/// shapes.
pub fn first_order(
    source: &dyn ReplicateSource,
    full: &SubspaceModel,
    eigens: &[OrderEigen],
    modes: &[ModePoles<'_>],
) -> Vec<Option<Spread>> {
    let batches = source.batches();
    if batches < 2 {
        return vec![None; modes.len()];
    }
    let orders: BTreeSet<usize> = modes
        .iter()
        .flat_map(|m| m.members.iter().chain([&m.medoid]).map(|p| p.order))
        .collect();
    let wanted: Vec<&OrderEigen> = eigens.iter().filter(|e| orders.contains(&e.order)).collect();
    let bases: Vec<Option<Continuation>> = super::ordered_map(&wanted, |e| full.continuation((*e).clone()).ok());
    let base_of = |order: usize| bases.iter().flatten().find(|b| b.order() == order);
    // Per mode, (order, eigenvalue index) of each member and the medoid.
    let index = |p: &Pole| {
        let eigen = wanted.iter().find(|e| e.order == p.order)?;
        full.eigen_index(eigen, p).map(|j| (p.order, j))
    };
    let located: Vec<Option<Located>> = modes
        .iter()
        .map(|m| {
            Some((
                m.members.iter().map(|p| index(p)).collect::<Option<Vec<_>>>()?,
                index(m.medoid)?,
            ))
        })
        .collect();
    // Per order, the members' and the medoids' eigenvalue indices.
    let mut needed: BTreeMap<usize, (BTreeSet<usize>, BTreeSet<usize>)> = BTreeMap::new();
    for (members, medoid) in located.iter().flatten() {
        for &(order, j) in members {
            needed.entry(order).or_default().0.insert(j);
        }
        needed.entry(medoid.0).or_default().1.insert(medoid.1);
    }
    let left_out: Vec<usize> = (0..batches).collect();
    let per_batch = super::ordered_map(&left_out, |&b| {
        let Ok(model) = source.matrix_without(b).and_then(|h| {
            if h.ncols() == full.right_rows() {
                full.replicate_matrix(&h)
            } else {
                Err(OmaError::SvdFailed)
            }
        }) else {
            return vec![None; modes.len()];
        };
        let mut values: BTreeMap<PoleAt, (f64, f64)> = BTreeMap::new();
        let mut shapes: BTreeMap<PoleAt, Vec<c64>> = BTreeMap::new();
        for (&order, (members, medoids)) in &needed {
            let (members, medoids): (Vec<usize>, Vec<usize>) =
                (members.iter().copied().collect(), medoids.iter().copied().collect());
            let Some(poles) = base_of(order).and_then(|base| model.continued(base, &members, &medoids)) else {
                continue;
            };
            for (&j, pole) in members.iter().zip(&poles) {
                values.insert((order, j), (pole.frequency_hz, pole.damping_ratio));
            }
            for (&j, pole) in medoids.iter().zip(&poles[members.len()..]) {
                shapes.extend(pole.shape.clone().map(|s| ((order, j), s)));
            }
        }
        located
            .iter()
            .zip(modes)
            .map(|(at, mode)| {
                let (members, medoid) = at.as_ref()?;
                let pairs: Vec<(f64, f64)> = members.iter().map(|m| values.get(m).copied()).collect::<Option<_>>()?;
                let f = median(pairs.iter().map(|p| p.0).collect());
                let zeta = median(pairs.iter().map(|p| p.1).collect());
                Some((f, zeta, aligned(shapes.get(medoid)?, &mode.medoid.shape)))
            })
            .collect()
    });
    gather(per_batch, modes.len())
}

/// A pole as `(order, eigenvalue index)`; a mode as its members' and its
/// medoid's.
type PoleAt = (usize, usize);
type Located = (Vec<PoleAt>, PoleAt);

/// Each mode's spread over the replicates that found it: none unless more
/// than half of them did (and at least two). A delete-one jackknife over
/// the few replicates that kept a mode is no jackknife: on the 2014
/// Painter Street record 3 of 8 kept the 4.77 Hz mode and agreed to
/// 0.0003 Hz.
fn gather(per_batch: Vec<Vec<Option<Replicate>>>, modes: usize) -> Vec<Option<Spread>> {
    let replicates = per_batch.len();
    let mut found: Vec<Vec<Replicate>> = vec![Vec::new(); modes];
    for replicate in per_batch {
        for (m, found_here) in replicate.into_iter().enumerate() {
            if let Some(v) = found_here {
                found[m].push(v);
            }
        }
    }
    found
        .into_iter()
        .map(|reps| (reps.len() >= 2 && 2 * reps.len() > replicates).then(|| spread(&reps)))
        .collect()
}

/// A mode in one replicate: frequency, damping ratio, aligned shape.
type Replicate = (f64, f64, Vec<c64>);

/// One delete-one-batch replicate (batch `left_out`): per mode, the
/// medians of its poles' nearest replicate poles and the medoid's shape,
/// or `None` when the replicate lost the mode (or its SVD failed).
fn replicate_modes(
    source: &dyn ReplicateSource,
    left_out: usize,
    channels: usize,
    fs: f64,
    max_order: usize,
    modes: &[ModePoles<'_>],
    max_distance: f64,
) -> Vec<Option<Replicate>> {
    let Ok(model) = source
        .matrix_without(left_out)
        .and_then(|h| source.model(&h, channels, max_order, fs))
    else {
        return vec![None; modes.len()];
    };
    let mut by_order: BTreeMap<usize, Vec<Pole>> = BTreeMap::new();
    modes
        .iter()
        .map(|mode| {
            let mut nearest = |reference: &Pole| -> Option<Pole> {
                let poles = by_order
                    .entry(reference.order)
                    .or_insert_with(|| model.poles(reference.order).unwrap_or_default());
                poles
                    .iter()
                    .map(|p| (pole_distance(p, reference), p))
                    .min_by(|a, b| a.0.total_cmp(&b.0))
                    .filter(|(d, _)| *d <= max_distance)
                    .map(|(_, p)| p.clone())
            };
            let medoid = nearest(mode.medoid)?;
            let matched: Vec<Pole> = mode.members.iter().filter_map(|p| nearest(p)).collect();
            let replicate = ModePoles {
                members: matched.iter().collect(),
                medoid: &medoid,
            };
            let (f, zeta) = replicate.medians();
            Some((f, zeta, aligned(&medoid.shape, &mode.medoid.shape)))
        })
        .collect()
}

/// `shape` scaled by the complex factor that best fits it to `reference`.
fn aligned(shape: &[c64], reference: &[c64]) -> Vec<c64> {
    let num: c64 = shape.iter().zip(reference).map(|(s, r)| s.conj() * r).sum();
    let den: f64 = shape.iter().map(|s| s.norm_sqr()).sum();
    let alpha = if den > 0.0 { num / den } else { c64::new(1.0, 0.0) };
    shape.iter().map(|s| s * alpha).collect()
}

/// Jackknife variance `(n−1)/n Σ (θ_i − θ̄)²` of each quantity.
fn spread(reps: &[(f64, f64, Vec<c64>)]) -> Spread {
    let n = reps.len() as f64;
    let factor = (n - 1.0) / n;
    let std_of = |values: &mut dyn Iterator<Item = f64>| {
        let v: Vec<f64> = values.collect();
        let mean = v.iter().sum::<f64>() / n;
        (factor * v.iter().map(|x| (x - mean).powi(2)).sum::<f64>()).sqrt()
    };
    let sensors = reps[0].2.len();
    let shape_std = (0..sensors)
        .map(|s| {
            let mean: c64 = reps.iter().map(|r| r.2[s]).sum::<c64>() / n;
            (factor * reps.iter().map(|r| (r.2[s] - mean).norm_sqr()).sum::<f64>()).sqrt()
        })
        .collect();
    Spread {
        frequency_std_hz: std_of(&mut reps.iter().map(|r| r.0)),
        damping_std: std_of(&mut reps.iter().map(|r| r.1)),
        shape_std,
        replicates: reps.len(),
    }
}
