//! Recorders whose clock the CGS flags as low quality (`Start time: …
//! (*LoQ*)`: no time signal reached the recorder, and its clock may be off
//! by a minute) placed on the others' time line by cross-correlating
//! channels that see the same motion: two ground channels along the same
//! direction (the lag of the largest normalised cross-correlation over lags
//! that keep half the shorter record, refined by a parabola through its
//! neighbours).

use super::placement::{Orientation, Placement};
use super::V2Channel;
use splinewatch_core::identification::resample::fourier_resample;
use std::collections::BTreeMap;

/// The recorder of a channel and whether the CGS trusts its clock.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct Recorder {
    /// The recorder part of the record's id (`E0784` in `01336-E0784-10190.09`).
    pub(super) id: String,
    pub(super) clock: Clock,
}

/// What the header says of a recorder's clock.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Clock {
    Trusted,
    /// `(*LoQ*)`: the start time may be off.
    Flagged,
}

/// The smallest normalised cross-correlation taken as the same motion.
const SAME_MOTION: f64 = 0.5;

/// One pair's best lag.
struct Match {
    flagged: usize,
    reference: usize,
    /// Seconds to add to the flagged channel's start.
    shift: f64,
    correlation: f64,
}

/// Moves the start of every channel of a flagged recorder so that its
/// channels line up with a trusted recorder's (the largest flagged
/// recorder is the reference when none is trusted); returns what it did,
/// a sentence per flagged recorder, for stderr and the recording's notes.
/// A recorder that shares no direction with the others, or whose best pair
/// correlates below [`SAME_MOTION`], keeps its header's clock, and says so.
pub(super) fn align_flagged_recorders(channels: &mut [V2Channel]) -> Vec<String> {
    let mut recorders: BTreeMap<&str, (Clock, Vec<usize>)> = BTreeMap::new();
    for (i, c) in channels.iter().enumerate() {
        if let Some(r) = &c.recorder {
            let entry = recorders.entry(r.id.as_str()).or_insert((r.clock, Vec::new()));
            if r.clock == Clock::Flagged {
                entry.0 = Clock::Flagged;
            }
            entry.1.push(i);
        }
    }
    let flagged: Vec<&str> = recorders
        .iter()
        .filter(|(_, (clock, _))| *clock == Clock::Flagged)
        .map(|(id, _)| *id)
        .collect();
    if flagged.is_empty() {
        return Vec::new();
    }
    if recorders.len() == 1 {
        return vec![format!(
            "recorder {}'s clock is flagged low quality (*LoQ*): the record's start time may be off (its channels keep their common time)",
            flagged[0]
        )];
    }
    let trusted: Vec<usize> = recorders
        .values()
        .filter(|(clock, _)| *clock == Clock::Trusted)
        .flat_map(|(_, members)| members.iter().copied())
        .collect();
    let (reference, reference_note) = if trusted.is_empty() {
        let (id, (_, members)) = recorders
            .iter()
            .max_by_key(|(_, (_, members))| members.len())
            .expect("two recorders or more");
        (
            members.clone(),
            Some(format!(
                "no recorder's clock is trusted: the others are placed on recorder {id}'s"
            )),
        )
    } else {
        (trusted, None)
    };
    let mut notes: Vec<String> = reference_note.into_iter().collect();
    let moves: Vec<(String, Vec<usize>)> = recorders
        .iter()
        .filter(|(_, (clock, members))| *clock == Clock::Flagged && !members.iter().any(|m| reference.contains(m)))
        .map(|(id, (_, members))| ((*id).to_string(), members.clone()))
        .collect();
    for (id, members) in moves {
        notes.push(place(channels, &id, &members, &reference));
    }
    notes
}

/// Places recorder `id`'s channels `members` on the time line of
/// `reference`; the sentence that says how.
fn place(channels: &mut [V2Channel], id: &str, members: &[usize], reference: &[usize]) -> String {
    let flag = format!("recorder {id}'s clock is flagged low quality (*LoQ*)");
    let pairs: Vec<(usize, usize)> = members
        .iter()
        .flat_map(|&f| reference.iter().map(move |&r| (f, r)))
        .filter(|&(f, r)| {
            let (a, b) = (&channels[f], &channels[r]);
            a.start_ns.is_some()
                && b.start_ns.is_some()
                && matches!(
                    (Orientation::parse(&a.direction), Orientation::parse(&b.direction)),
                    (Some(x), Some(y)) if x.same_as(y)
                )
        })
        .collect();
    let on_ground = |i: usize| Placement::of(&channels[i].location) == Some(Placement::Ground);
    let ground: Vec<(usize, usize)> = pairs
        .iter()
        .copied()
        .filter(|&(f, r)| on_ground(f) && on_ground(r))
        .collect();
    let (pairs, kind) = if ground.is_empty() {
        (pairs, "channels")
    } else {
        (ground, "ground channels")
    };
    if pairs.is_empty() {
        return format!("{flag} and it shares no direction with the other recorders: its channels stay where its header's clock puts them, which may be off");
    }
    let matches: Vec<Match> = pairs
        .iter()
        .map(|&(f, r)| best_lag(&channels[f], &channels[r], f, r))
        .collect();
    let best = matches
        .iter()
        .max_by(|a, b| a.correlation.total_cmp(&b.correlation))
        .expect("a pair or more");
    let name = |i: usize| {
        let c = &channels[i];
        format!("ch{} ({}, {})", c.number, c.direction, c.location)
    };
    if best.correlation < SAME_MOTION {
        return format!(
            "{flag}: no pair of its {kind} with the others' correlates (best {:.2}, {} with {}): its channels stay where its header's clock puts them, which may be off",
            best.correlation,
            name(best.flagged),
            name(best.reference)
        );
    }
    // The median over the pairs that see the same motion: robust to one
    // pair whose sensors move differently (a footing rocking).
    let mut same: Vec<&Match> = matches.iter().filter(|m| m.correlation >= SAME_MOTION).collect();
    same.sort_by(|a, b| a.shift.total_cmp(&b.shift));
    let shift = same[same.len() / 2].shift;
    let spread = same[same.len() - 1].shift - same[0].shift;
    let weakest = same.iter().map(|m| m.correlation).fold(f64::INFINITY, f64::min);
    let note = format!(
        "{flag}: its channels placed by cross-correlating its {kind} with the others' along the same direction: {shift:+.3} s from its header's start (the median of {} of {} pairs correlating {weakest:.2}–{:.2}, their shifts within {spread:.3} s; best {} with {})",
        same.len(),
        matches.len(),
        best.correlation,
        name(best.flagged),
        name(best.reference)
    );
    let shift_ns = (shift * 1e9).round() as i128;
    for &m in members {
        if let Some(start) = channels[m].start_ns.as_mut() {
            *start += shift_ns;
        }
    }
    note
}

/// The shift of `a`'s start (seconds) that best lines it up with `b`, and
/// the normalised cross-correlation there; both brought to the coarser
/// time step first.
fn best_lag(a: &V2Channel, b: &V2Channel, ia: usize, ib: usize) -> Match {
    let dt = a.time_step.max(b.time_step);
    let on_grid = |c: &V2Channel| {
        let x = if (c.time_step - dt).abs() <= 1e-9 * dt {
            c.values.clone()
        } else {
            let n = (c.values.len() as f64 * c.time_step / dt).round() as usize;
            fourier_resample(&c.values, n.max(2))
        };
        let mean = x.iter().sum::<f64>() / x.len() as f64;
        x.into_iter().map(|v| v - mean).collect::<Vec<f64>>()
    };
    let (x, y) = (on_grid(a), on_grid(b));
    let (lag, correlation) = normalised_peak(&x, &y);
    let starts = (b.start_ns.unwrap_or(0) - a.start_ns.unwrap_or(0)) as f64 * 1e-9;
    Match {
        flagged: ia,
        reference: ib,
        // x_i lies at y_{i+lag}: x's first sample is at y's start + lag·dt.
        shift: starts + lag * dt,
        correlation,
    }
}

/// The lag `m` (in samples, refined below one) where
/// `Σ_i x_i y_{i+m} / √(Σ x_i² Σ y_{i+m}²)` over the overlap is largest,
/// among lags whose overlap keeps half the shorter series, and that value.
fn normalised_peak(x: &[f64], y: &[f64]) -> (f64, f64) {
    let (nx, ny) = (x.len(), y.len());
    let length = nx + ny;
    let mut planner = realfft::RealFftPlanner::<f64>::new();
    let forward = planner.plan_fft_forward(length);
    let spectrum = |s: &[f64]| {
        let mut padded = vec![0.0; length];
        padded[..s.len()].copy_from_slice(s);
        let mut out = forward.make_output_vec();
        forward.process(&mut padded, &mut out).expect("lengths from the plan");
        out
    };
    let (fx, fy) = (spectrum(x), spectrum(y));
    let mut product: Vec<_> = fx.iter().zip(&fy).map(|(a, b)| a.conj() * b).collect();
    product[0].im = 0.0;
    if length % 2 == 0 {
        let last = product.len() - 1;
        product[last].im = 0.0;
    }
    let inverse = planner.plan_fft_inverse(length);
    let mut sums = inverse.make_output_vec();
    inverse.process(&mut product, &mut sums).expect("lengths from the plan");
    let cumulative = |s: &[f64]| {
        std::iter::once(0.0)
            .chain(s.iter().scan(0.0, |acc, v| {
                *acc += v * v;
                Some(*acc)
            }))
            .collect::<Vec<f64>>()
    };
    let (ex, ey) = (cumulative(x), cumulative(y));
    let least = (nx.min(ny) / 2).max(2) as i64;
    let coefficient = |m: i64| -> Option<f64> {
        let from = 0.max(-m);
        let to = (nx as i64).min(ny as i64 - m);
        if to - from < least {
            return None;
        }
        let energy_x = ex[to as usize] - ex[from as usize];
        let energy_y = ey[(to + m) as usize] - ey[(from + m) as usize];
        let sum = sums[m.rem_euclid(length as i64) as usize] / length as f64;
        (energy_x > 0.0 && energy_y > 0.0).then(|| sum / (energy_x * energy_y).sqrt())
    };
    let (mut best, mut value) = (0i64, f64::NEG_INFINITY);
    for m in -(nx as i64 - 1)..ny as i64 {
        if let Some(c) = coefficient(m) {
            if c > value {
                (best, value) = (m, c);
            }
        }
    }
    let refined = match (coefficient(best - 1), coefficient(best + 1)) {
        (Some(left), Some(right)) => {
            let curvature = left - 2.0 * value + right;
            if curvature < 0.0 {
                best as f64 + 0.5 * (left - right) / curvature
            } else {
                best as f64
            }
        }
        _ => best as f64,
    };
    (refined, value)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A broadband pulse train (the same at any lag: no periodicity).
    fn motion(n: usize, seed: u64) -> Vec<f64> {
        let mut state = seed;
        (0..n)
            .map(|i| {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let noise = ((state >> 11) as f64 / (1u64 << 53) as f64) - 0.5;
                let envelope = (-(((i as f64) - n as f64 / 3.0) / (n as f64 / 8.0)).powi(2)).exp();
                noise * envelope
            })
            .collect()
    }

    #[test]
    fn the_peak_is_at_the_lag_of_a_delayed_copy() {
        let y = motion(2000, 7);
        // x is y from sample 137 on: x_i = y_{i+137}.
        let x = y[137..1700].to_vec();
        let (lag, c) = normalised_peak(&x, &y);
        assert!((lag - 137.0).abs() < 1e-6, "{lag}");
        assert!((c - 1.0).abs() < 1e-9, "{c}");
        // And the other way round: y_i = x_{i-137}.
        let (lag, _) = normalised_peak(&y[..1500], &x);
        assert!((lag + 137.0).abs() < 1e-6, "{lag}");
    }

    fn channel(
        number: u32,
        recorder: &str,
        clock: Clock,
        direction: &str,
        start_s: f64,
        values: Vec<f64>,
    ) -> V2Channel {
        V2Channel {
            number,
            file: format!("{recorder}/CHAN{number:03}.V2"),
            direction: direction.into(),
            location: "Freefield".into(),
            time_step: 0.01,
            unit: "cm/s^2".into(),
            start_ns: Some((start_s * 1e9) as i128),
            recorder: Some(Recorder {
                id: recorder.into(),
                clock,
            }),
            station: None,
            values,
        }
    }

    /// With no trusted clock the largest recorder is the reference (said);
    /// a flagged recorder that shares no direction keeps its clock (said);
    /// one of pure noise against the other correlates below the floor and
    /// keeps its clock (said). Nothing moves silently.
    #[test]
    fn flagged_recorders_without_a_match_keep_their_clock_and_say_so() {
        let ground = motion(3000, 3);
        let mut channels = vec![
            channel(1, "A", Clock::Flagged, "Tran", 0.0, ground[..2000].to_vec()),
            channel(2, "A", Clock::Flagged, "Up", 0.0, motion(2000, 4)),
            channel(3, "B", Clock::Flagged, "Tran", 7.0, ground[500..2500].to_vec()),
        ];
        let notes = align_flagged_recorders(&mut channels);
        assert!(
            notes[0].contains("no recorder's clock is trusted") && notes[0].contains("recorder A's"),
            "{notes:?}"
        );
        // B's first sample is A's sample 500: 5 s after A's start, not 7.
        let start = channels[2].start_ns.unwrap() as f64 * 1e-9;
        assert!((start - 5.0).abs() < 1e-6, "{start} {notes:?}");
        let mut channels = vec![
            channel(1, "A", Clock::Trusted, "Tran", 0.0, ground[..2000].to_vec()),
            channel(2, "B", Clock::Flagged, "Long", 3.0, ground[..2000].to_vec()),
        ];
        let notes = align_flagged_recorders(&mut channels);
        assert!(
            notes[0].contains("shares no direction") && channels[1].start_ns == Some(3_000_000_000),
            "{notes:?}"
        );
        let mut channels = vec![
            channel(1, "A", Clock::Trusted, "Tran", 0.0, ground[..2000].to_vec()),
            channel(2, "B", Clock::Flagged, "Tran", 3.0, motion(2000, 9)),
        ];
        let notes = align_flagged_recorders(&mut channels);
        assert!(
            notes[0].contains("no pair") && channels[1].start_ns == Some(3_000_000_000),
            "{notes:?}"
        );
        assert_eq!(notes.len(), 1);
    }
}
