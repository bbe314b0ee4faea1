//! What a running process has written, kept for the report a notification
//! carries: the events' summaries and the latest statuses, alarms, updates
//! and health, bounded, read as `splinewatch report` reads a results file.

use super::{render, Report, Selection};
use crate::config::Config;
use crate::io::results_file::ResultsContents;

/// Statuses, updates and failures kept (the oldest dropped first): a month
/// of 10-minute windows.
const KEEP: usize = 4_500;

pub struct History {
    contents: ResultsContents,
}

impl History {
    /// An empty history of `config`'s bridge, with its provenance.
    pub fn new(config: &Config) -> Self {
        Self {
            contents: ResultsContents {
                prefix: config.topic_prefix(),
                provenance: vec![crate::outputs::results::provenance(config)],
                files: vec!["(this run's results)".into()],
                ..Default::default()
            },
        }
    }

    /// Keeps a results message written on `suffix` (the ones a report reads).
    pub fn record(&mut self, suffix: &str, json: &[u8]) {
        if !ResultsContents::reads(suffix) {
            return;
        }
        if let Err(e) = self.contents.add(suffix, json) {
            tracing::warn!(message = "a results message the report cannot read", suffix, error = %e);
        }
        let c = &mut self.contents;
        trim(&mut c.statuses);
        trim(&mut c.updates);
        trim(&mut c.failures);
        trim(&mut c.alarms);
        trim(&mut c.events);
    }

    /// What is kept, as a results file's contents.
    pub fn contents(&self) -> &ResultsContents {
        &self.contents
    }

    /// The report of the last event when there are events, else of the
    /// period kept.
    pub fn report(&self) -> Option<Report> {
        render(&self.contents, &Selection::Latest).ok()
    }
}

fn trim<T>(v: &mut Vec<T>) {
    if v.len() > KEEP {
        v.drain(..v.len() - KEEP);
    }
}
