//! An event's record read, checked and put on one grid.

use super::*;
use crate::service::records::{align_event, Record};

/// An event read and put on one grid, or why it could not be.
pub struct Loaded {
    pub name: String,
    pub(super) event: Result<(Event, Vec<GroundInputPlan>)>,
    /// Its first sample's time when its record was read (an event skipped
    /// for a missing or bad channel keeps its place in time).
    pub(super) first_sample_ns: Option<i128>,
}

impl Loaded {
    /// The record's start (ns since the epoch); `None` when it could not be read.
    pub fn start_ns(&self) -> Option<i128> {
        match &self.event {
            Ok((e, _)) => Some(e.start_ns),
            Err(_) => self.first_sample_ns,
        }
    }

    /// Whether its input could not be read at all (a missing or unreadable
    /// file, not a record: no start time, no blocks).
    pub fn unreadable(&self) -> bool {
        self.start_ns().is_none()
    }

    /// With what reading the record found (a recorder placed by its
    /// channels' motion, channels cut) first among the event's notes.
    pub fn noted(mut self, notes: &[String]) -> Self {
        if let Ok((event, _)) = &mut self.event {
            event.notes.splice(0..0, notes.iter().cloned());
        }
        self
    }
}

/// The event `name` of `record` (or the error reading it) checked and
/// aligned on the config's ground inputs `plan` ([`GroundParts::plan`]):
/// every ground channel, the deck's, no dead or clipped channel, long
/// enough.
pub fn load(cfg: &Config, plan: &[GroundInputPlan], name: String, record: Result<Record>) -> Loaded {
    let first_sample_ns = record.as_ref().ok().and_then(Record::start_ns);
    let event = (|| {
        let record = record?;
        // A ground channel the record lacks is borrowed (the mean of the
        // groups measured along its axis, as `predict` does) and said in the
        // event's notes: the event is judged, not skipped.
        let mut plan = plan.to_vec();
        let event = align_event(cfg, &mut plan, record)?;
        if event.deck.is_empty() {
            bail!("the record holds none of the config's deck sensors");
        }
        check_channels(cfg, &event, &plan)?;
        Ok((event, plan))
    })();
    Loaded {
        name,
        event,
        first_sample_ns,
    }
}

/// Samples of a clipped channel: this many in a row at its extreme value.
const CLIPPED_RUN: usize = 5;

/// A dead channel (constant), a clipped one (a run at its extreme) or a
/// record too short for the identification and the Welch segments.
fn check_channels(cfg: &Config, event: &Event, plan: &[GroundInputPlan]) -> Result<()> {
    let (oma, _) = cfg.oma_settings_at(event.fs)?;
    let (welch, _) = cfg.welch_settings(event.fs)?;
    for i in ground_sensors(plan).into_iter().chain(event.deck.iter().copied()) {
        let x = event.channels[i].as_deref().unwrap_or_default();
        let name = &cfg.sensors[i].name;
        let needed = (2 * welch.segment).max(4 * oma.block_rows * oma.batches.max(1));
        if x.len() < needed {
            bail!(
                "{name}: {:.1} s ({} samples at {} Hz), shorter than the {:.1} s the identification (4 horizons of {} samples per batch, {} batches) and two Welch segments need{}",
                x.len() as f64 / event.fs,
                x.len(),
                event.fs,
                needed as f64 / event.fs,
                oma.block_rows,
                oma.batches.max(1),
                if cfg.oma().horizon_seconds.is_none() {
                    " ([oma] block_rows counts samples: horizon_seconds keeps it in seconds at any rate)"
                } else {
                    ""
                }
            );
        }
        let (lo, hi) = x
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(*v), b.max(*v)));
        if hi - lo <= 1e-12 * hi.abs().max(lo.abs()).max(1e-300) {
            bail!("{name}: a dead channel (every sample {lo})");
        }
        for extreme in [lo, hi] {
            let run = x.split(|v| *v != extreme).map(<[f64]>::len).max().unwrap_or(0);
            if run >= CLIPPED_RUN {
                bail!("{name}: clipped ({run} samples in a row at its extreme {extreme})");
            }
        }
    }
    Ok(())
}
