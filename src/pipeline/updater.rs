//! The update side of the pipeline: the last accepted parameters, the model
//! at them and the monitor. Jobs are rebased on it and their outcomes
//! applied to it in window order. It is a value of its own so that updates
//! can run on another thread than the ingest (`Pipeline::split_updater`)
//! and give exactly the results of running them in line.

use super::monitoring::{self, Monitoring, MonitoringOutcome};
use super::{AcceptedParameters, Health, StateParameter, UpdateJob, UpdateOutcome};
use crate::config::FrfSetup;
use anyhow::{bail, Result};
use splinewatch_core::monitoring::Monitor;
use splinewatch_core::response::frf::ModalState;
use splinewatch_core::updating::frf_residual::ModelPoint;
use splinewatch_core::updating::Parameter;
use std::collections::BTreeMap;
use std::sync::mpsc::{channel, Receiver, RecvError, Sender};
use std::sync::Arc;

/// The health counters only the update side moves.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct UpdateCounters {
    pub update_runs: u64,
    pub update_failures: u64,
    /// Updates the monitor could not score.
    pub monitoring_errors: u64,
}

impl Health {
    /// This health with the update side's counters.
    pub fn set_updates(&mut self, counters: UpdateCounters) {
        self.update_runs = counters.update_runs;
        self.update_failures = counters.update_failures;
        self.monitoring_errors = counters.monitoring_errors;
    }
}

/// The model's modes at the last accepted parameters, as the update side
/// sends them back after each job to an ingest that identifies output-only
/// windows on another thread (the error is the modal solve's).
pub(super) type PairingState = Result<Arc<ModalState>, String>;

/// The ingest's end of that link (`Pipeline::split_updater`): a window's
/// modes are paired once every job handed out before the window closed has
/// been applied, which is the state an in-line replay pairs with (its jobs
/// run between two ingest calls).
pub(super) struct PairingLink {
    states: Receiver<PairingState>,
    /// Jobs handed out whose state has not come back yet.
    outstanding: usize,
    /// The state after the last applied job; `None` before any.
    latest: Option<PairingState>,
}

impl PairingLink {
    pub(super) fn handed_out(&mut self, jobs: usize) {
        self.outstanding += jobs;
    }

    /// The state once every job handed out has been applied: `Ok(None)`
    /// when none was (the initial model holds), `Err` when the update side
    /// stopped.
    pub(super) fn settled(&mut self) -> Result<Option<PairingState>, RecvError> {
        while self.outstanding > 0 {
            self.latest = Some(self.states.recv()?);
            self.outstanding -= 1;
        }
        Ok(self.latest.clone())
    }
}

#[derive(Clone)]
pub struct Updater {
    setup: Arc<FrfSetup>,
    parameters: Vec<Parameter>,
    last: Option<AcceptedParameters>,
    /// The model at `last`, when the update that produced it ran here.
    last_point: Option<Arc<ModelPoint>>,
    /// The model's modes at `last` (output-only pairing; computed when first
    /// needed).
    model_state: Option<Arc<ModalState>>,
    monitoring: Option<Monitoring>,
    counters: UpdateCounters,
    /// Where the model state goes after each applied job (split
    /// output-only: [`PairingLink`]).
    pairing: Option<Sender<PairingState>>,
}

impl Updater {
    pub(super) fn new(
        setup: Arc<FrfSetup>,
        parameters: Vec<Parameter>,
        last: Option<AcceptedParameters>,
        monitoring: Option<Monitoring>,
    ) -> Self {
        Self {
            setup,
            parameters,
            last,
            last_point: None,
            model_state: None,
            monitoring,
            counters: UpdateCounters::default(),
            pairing: None,
        }
    }

    /// A copy of this updater that sends the model state back after each
    /// applied job, and the ingest's end of the link.
    pub(super) fn linked(&self) -> (Self, PairingLink) {
        let (sender, states) = channel();
        let updater = Self {
            pairing: Some(sender),
            ..self.clone()
        };
        let link = PairingLink {
            states,
            outstanding: 0,
            latest: None,
        };
        (updater, link)
    }

    pub fn counters(&self) -> UpdateCounters {
        self.counters
    }

    /// The last accepted parameters, if any update succeeded (or a state was loaded).
    pub fn accepted(&self) -> Option<&AcceptedParameters> {
        self.last.as_ref()
    }

    pub(super) fn last_point(&self) -> Option<Arc<ModelPoint>> {
        self.last_point.clone()
    }

    /// The last accepted parameters (the config's values for those never
    /// updated).
    pub(super) fn start_values(&self) -> Vec<f64> {
        let base = splinewatch_core::updating::base_values(
            &self.parameters,
            &self.setup.kappa,
            self.setup.model.field_coefficients(),
            &self.setup.damping,
        );
        match &self.last {
            Some(last) => self
                .parameters
                .iter()
                .zip(base)
                .map(|(p, b)| last.parameters.iter().find(|s| s.name == p.name).map_or(b, |s| s.value))
                .collect(),
            None => base,
        }
    }

    /// The model's modal state at the last accepted parameters (cached).
    pub(super) fn model_state(&mut self) -> Result<Arc<ModalState>> {
        if let Some(s) = &self.model_state {
            return Ok(Arc::clone(s));
        }
        let (state, _) = splinewatch_core::updating::modal_state_at(
            &self.setup.model,
            &self.parameters,
            &self.setup.kappa,
            &self.setup.damping,
            &self.start_values(),
        )?;
        let state = Arc::new(state);
        self.model_state = Some(Arc::clone(&state));
        Ok(state)
    }

    /// Moves a job made earlier (one that waited while another update ran,
    /// or made ahead on the ingest thread) to start from the parameters
    /// accepted since: every update starts from the latest result, however
    /// the updates were scheduled, so the live daemon gives the replay's
    /// parameters even when its updates queue.
    pub fn rebase(&self, job: &mut UpdateJob) {
        job.start = self.start_values();
        job.previous = self.last_point.clone();
    }

    /// Records an update's outcome: accepted parameters replace the last
    /// good ones; a failure keeps them. With `[monitoring]`, an accepted
    /// update is scored: the status (and alarm) messages are returned.
    pub fn apply(&mut self, outcome: &mut UpdateOutcome) -> Option<MonitoringOutcome> {
        let scored = self.record(outcome);
        if let Some(link) = self.pairing.clone() {
            let state = self.model_state().map_err(|e| format!("{e:#}"));
            // A closed link: the ingest has finished and pairs no more.
            let _ = link.send(state);
        }
        scored
    }

    fn record(&mut self, outcome: &mut UpdateOutcome) -> Option<MonitoringOutcome> {
        self.counters.update_runs += 1;
        let Ok(report) = &outcome.result else {
            self.counters.update_failures += 1;
            return None;
        };
        let mut values: BTreeMap<String, f64> = report
            .result
            .parameters
            .iter()
            .map(|p| (p.name.clone(), p.value))
            .collect();
        if let (Some(pairs), Some(state)) = (&report.fit.modes, &outcome.state) {
            let pairs: Vec<(usize, f64)> = pairs
                .iter()
                .map(|p| (p.model_mode, p.identified_frequency_hz))
                .collect();
            values.extend(monitoring::identified_frequencies(&pairs, state));
        }
        let scored = self.score(outcome, &values);
        self.last_point = outcome.point.take();
        self.model_state = outcome
            .state
            .take()
            .or_else(|| self.last_point.as_ref().map(|p| Arc::new(p.state().clone())));
        self.last = Some(AcceptedParameters {
            window: outcome.window,
            time: crate::io::wire::format_timestamp(outcome.time_ns),
            parameters: report
                .result
                .parameters
                .iter()
                .map(|p| StateParameter {
                    name: p.name.clone(),
                    value: p.value,
                    std: p.std,
                })
                .collect(),
        });
        scored
    }

    /// Scores an accepted update (its features by name: parameters, and
    /// output-only the identified frequencies; an absent one is missing)
    /// measured in the outcome's environment; `None` without `[monitoring]`.
    fn score(&mut self, outcome: &UpdateOutcome, values: &BTreeMap<String, f64>) -> Option<MonitoringOutcome> {
        let monitoring = self.monitoring.as_mut()?;
        match monitoring.score(outcome.window, outcome.time_ns, values, &outcome.environment) {
            Ok(scored) => Some(scored),
            Err(e) => {
                // Another feature count than the reference (a resumed
                // monitor of another config is refused earlier): counted.
                self.counters.monitoring_errors += 1;
                tracing::warn!("monitoring: {e}");
                None
            }
        }
    }

    /// The monitor (`[monitoring]`), to persist its reference and state.
    pub fn monitor(&self) -> Option<&Monitor> {
        self.monitoring.as_ref().map(|m| &m.monitor)
    }

    /// Resumes a persisted monitor (a restart does not retrain); refused
    /// when it does not fit this config's parameters and channels.
    pub(super) fn restore_monitor(&mut self, monitor: Monitor) -> Result<()> {
        let Some(current) = self.monitoring.as_mut() else {
            bail!("the config has no [monitoring] section");
        };
        if monitor.settings().temperature_channels != current.monitor.settings().temperature_channels {
            bail!("the saved monitor has another number of temperature channels");
        }
        if let Some(r) = monitor.reference() {
            if r.features != self.parameters.len() {
                bail!(
                    "the saved reference scores {} features, this config updates {} parameters",
                    r.features,
                    self.parameters.len()
                );
            }
        }
        current.monitor = monitor;
        Ok(())
    }
}
