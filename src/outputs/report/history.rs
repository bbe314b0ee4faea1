//! What a running process has written, kept for the report a notification
//! carries and the status page shows: the events' summaries and the latest
//! statuses, alarms, updates and health, bounded, read as `splinewatch
//! report` reads a results file.

use super::{render, Report, Selection};
use crate::config::Config;
use crate::io::results_file::ResultsContents;
use std::sync::{Arc, Mutex};

/// Statuses, updates and failures kept (the oldest dropped first): a month
/// of 10-minute windows.
const KEEP: usize = 4_500;

/// One run's kept results, shared: the notifier and the status page of a
/// daemon hold clones of one history (each message parsed once).
#[derive(Clone)]
pub struct History {
    kept: Arc<Mutex<Kept>>,
}

struct Kept {
    contents: ResultsContents,
    /// Messages kept so far: a reader renders again only when it grew.
    version: u64,
}

impl History {
    /// An empty history of `config`'s bridge, with its provenance.
    pub fn new(config: &Config) -> Self {
        let contents = ResultsContents {
            prefix: config.topic_prefix(),
            provenance: vec![crate::outputs::results::provenance(config)],
            files: vec!["(this run's results)".into()],
            ..Default::default()
        };
        Self {
            kept: Arc::new(Mutex::new(Kept { contents, version: 0 })),
        }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Kept> {
        self.kept.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    /// Keeps a results message written on `suffix` (the ones a report reads).
    pub fn record(&self, suffix: &str, json: &[u8]) {
        if !ResultsContents::reads(suffix) {
            return;
        }
        let mut kept = self.lock();
        if let Err(e) = kept.contents.add(suffix, json) {
            tracing::warn!(message = "a results message the report cannot read", suffix, error = %e);
        }
        kept.version += 1;
        let c = &mut kept.contents;
        trim(&mut c.statuses);
        trim(&mut c.updates);
        trim(&mut c.failures);
        trim(&mut c.alarms);
        trim(&mut c.events);
    }

    /// Messages kept so far (it grows with each one).
    pub fn version(&self) -> u64 {
        self.lock().version
    }

    /// What is kept now and its version, copied out under the lock once:
    /// rendering it then holds up no `record` (a copy takes less than a
    /// render), and everything drawn from one snapshot agrees.
    pub fn snapshot(&self) -> (u64, ResultsContents) {
        let kept = self.lock();
        (kept.version, kept.contents.clone())
    }

    /// The report of the last event when there are events, else of the
    /// period kept.
    pub fn report(&self) -> Option<Report> {
        report_of(&self.snapshot().1)
    }
}

/// The report of `contents`' last event when it has events, else of its
/// period.
pub fn report_of(contents: &ResultsContents) -> Option<Report> {
    render(contents, &Selection::Latest).ok()
}

fn trim<T>(v: &mut Vec<T>) {
    if v.len() > KEEP {
        v.drain(..v.len() - KEEP);
    }
}
