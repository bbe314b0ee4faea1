//! The update worker: at most one job runs (on a blocking thread) and one
//! waits; a newer job replaces the waiting one, counted as a drop.

use crate::pipeline::{UpdateJob, UpdateOutcome};
use tokio::task::{JoinError, JoinHandle};

#[derive(Default)]
pub(super) struct UpdateWorker {
    running: Option<JoinHandle<UpdateOutcome>>,
    waiting: Option<UpdateJob>,
    /// Waiting jobs replaced by newer ones.
    pub(super) drops: u64,
}

impl UpdateWorker {
    pub(super) fn is_busy(&self) -> bool {
        self.running.is_some()
    }

    /// The running job's outcome; call only when [`Self::is_busy`], and
    /// then [`Self::next`] once it resolved.
    pub(super) async fn finished(&mut self) -> Result<UpdateOutcome, JoinError> {
        self.running.as_mut().expect("guarded by is_busy").await
    }

    /// Starts `job`, or makes it the waiting job when one runs.
    pub(super) fn submit(&mut self, job: UpdateJob) {
        if self.running.is_none() {
            self.start(job);
        } else if self.waiting.replace(job).is_some() {
            self.drops += 1;
        }
    }

    pub(super) fn start(&mut self, job: UpdateJob) {
        self.running = Some(tokio::task::spawn_blocking(move || job.run()));
    }

    /// After the running job finished: the waiting job, if any, to be
    /// rebased and started.
    pub(super) fn next(&mut self) -> Option<UpdateJob> {
        self.running = None;
        self.waiting.take()
    }

    /// At shutdown: the running job's outcome (it is let finish, so its
    /// result is not lost); a waiting job is abandoned.
    pub(super) async fn drain(&mut self) -> Option<Result<UpdateOutcome, JoinError>> {
        let handle = self.running.take()?;
        Some(handle.await)
    }
}
