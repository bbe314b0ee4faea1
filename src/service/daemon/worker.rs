//! The update worker: at most one job runs (on a blocking thread) and up to
//! [`WAITING_JOBS`] wait, in window order, each started from the result
//! before it (as replay runs them). When a burst overflows the queue the
//! oldest waiting job is dropped and handed back, so the daemon records its
//! window as skipped with the reason (never a silent loss).

use crate::pipeline::{UpdateJob, UpdateOutcome};
use std::collections::VecDeque;
use tokio::task::{JoinError, JoinHandle};

/// Update jobs that may wait behind the running one: a burst of 16
/// pre-computed FRF windows (a logger uploading a backlog) is updated in full.
pub(super) const WAITING_JOBS: usize = 16;

#[derive(Default)]
pub(super) struct UpdateWorker {
    running: Option<JoinHandle<UpdateOutcome>>,
    waiting: VecDeque<UpdateJob>,
    /// Waiting jobs dropped because the queue was full.
    pub(super) drops: u64,
}

impl UpdateWorker {
    pub(super) fn is_busy(&self) -> bool {
        self.running.is_some()
    }

    /// Jobs waiting behind the running one.
    pub(super) fn waiting(&self) -> usize {
        self.waiting.len()
    }

    /// The running job's outcome; call only when [`Self::is_busy`], and
    /// then [`Self::next`] once it resolved.
    pub(super) async fn finished(&mut self) -> Result<UpdateOutcome, JoinError> {
        self.running.as_mut().expect("guarded by is_busy").await
    }

    /// Starts `job`, or queues it behind the running one; returns the oldest
    /// waiting job when the queue overflows (dropped: its window gets no
    /// update, and the caller records why).
    #[must_use]
    pub(super) fn submit(&mut self, job: UpdateJob) -> Option<UpdateJob> {
        if self.running.is_none() {
            self.start(job);
            return None;
        }
        self.waiting.push_back(job);
        if self.waiting.len() > WAITING_JOBS {
            self.drops += 1;
            return self.waiting.pop_front();
        }
        None
    }

    pub(super) fn start(&mut self, job: UpdateJob) {
        self.running = Some(tokio::task::spawn_blocking(move || job.run()));
    }

    /// After the running job finished: the next waiting job, if any, to be
    /// rebased and started.
    pub(super) fn next(&mut self) -> Option<UpdateJob> {
        self.running = None;
        self.waiting.pop_front()
    }

    /// At shutdown: the running job's outcome (it is let finish, so its
    /// result is not lost) and the jobs still waiting (not run; the caller
    /// records their windows as skipped).
    pub(super) async fn drain(&mut self) -> (Option<Result<UpdateOutcome, JoinError>>, Vec<UpdateJob>) {
        let waiting = self.waiting.drain(..).collect();
        let running = match self.running.take() {
            Some(handle) => Some(handle.await),
            None => None,
        };
        (running, waiting)
    }
}
