//! The configured deck driven by recorded ground accelerations (issue 44):
//! `simulate --ground` and `predict`.
//!
//! The model's ground inputs come from the config's ground sensors
//! ([`crate::config::GroundInputPlan`]); the deck's absolute accelerations at
//! its sensors follow from the exact modal recursion of
//! [`splinewatch_core::response::support_motion`], run at the record's own
//! rate with the ground acceleration linear between samples (first-order
//! hold: exact for that input; a strong-motion record's corrected
//! acceleration is band-limited well below its Nyquist frequency). On a
//! truncated model (`[model.solver]`) the recursion runs over the kept modes
//! and the quasi-static part `N Γ ü_g` is exact (the static solve of every
//! mode); the discarded modes' dynamic share is left out.

use super::parameters::values_by_name;
use crate::config::{frf_setup_of, ground_signals, solver_model, Config, FrfSetup, GroundInputPlan};
use crate::io::named_value::NamedValue;
use anyhow::{bail, Result};
use splinewatch_core::model::supports::SupportGroups;
use splinewatch_core::model::BridgeModel;
use splinewatch_core::response::frf::ModalState;
use splinewatch_core::response::support_motion::{GroundedStructure, SupportMotion};
use splinewatch_core::updating::{base_values, fields_at, model_at, Parameter};
use std::sync::Arc;

/// The model at one parameter point, ready to be driven by its grounds.
pub struct GroundModel {
    pub plan: Vec<GroundInputPlan>,
    pub state: ModalState,
    pub motion: SupportMotion,
    /// The deck sensors' names (the outputs, in config order).
    pub outputs: Vec<String>,
    /// Each support group's name and where it holds the model
    /// ([`SupportGroups::anchors`]).
    pub anchors: Vec<(String, Option<[f64; 3]>)>,
}

impl GroundModel {
    /// At the config's values, with the `named` updating parameters set
    /// (an update's result).
    pub fn new(config: &Config, named: &[NamedValue]) -> Result<Self> {
        Self::at(&GroundParts::new(config)?, named)
    }

    /// The model of `parts` with the `named` updating parameters set.
    pub fn at(parts: &GroundParts, named: &[NamedValue]) -> Result<Self> {
        let GroundParts {
            setup,
            grounded,
            plan,
            parameters,
        } = parts;
        let theta0 = setup.model.field_coefficients().to_vec();
        let base = base_values(parameters, &setup.kappa, &theta0, &setup.damping);
        let values = values_by_name(parameters, &base, named, "parameter")?;
        let (kappa, damping) = model_at(parameters, &setup.kappa, &setup.damping, &values)?;
        let theta = fields_at(parameters, &theta0, &values);
        let inputs: Vec<_> = plan.iter().map(|p| p.input).collect();
        let (state, motion) = SupportMotion::with_state((&setup.model, grounded), (&kappa, &theta, &damping), &inputs)
            .map_err(|e| anyhow::anyhow!("the model's modes and support motion: {e}"))?;
        Ok(Self {
            plan: plan.clone(),
            state,
            motion,
            outputs: setup.sensor_names.clone(),
            anchors: (grounded.groups().names().iter().cloned())
                .zip(grounded.groups().anchors(grounded.structure()))
                .collect(),
        })
    }

    /// The config indices of the ground sensors the plan reads.
    pub fn ground_sensors(&self) -> Vec<usize> {
        crate::config::ground_sensors(&self.plan)
    }

    /// The deck's absolute accelerations (one series per deck sensor) for
    /// the ground sensors' accelerations `ground(i)` of `[[sensors]]` entry
    /// `i`, sampled at `fs`, from rest.
    pub fn respond<'a>(&self, ground: impl Fn(usize) -> &'a [f64], fs: f64) -> Vec<Vec<f64>> {
        let inputs = ground_signals(&self.plan, ground);
        let samples = inputs.first().map_or(0, Vec::len);
        let mut sim = self.motion.simulator(&self.state, 1.0 / fs);
        let sensors = self.outputs.len();
        let mut out: Vec<Vec<f64>> = (0..sensors).map(|_| Vec::with_capacity(samples)).collect();
        let mut now = vec![0.0; self.state.sensor_count()];
        let mut u = vec![0.0; inputs.len()];
        // The recursion starts at rest with the ground at its first sample.
        let first: Vec<f64> = inputs.iter().map(|x| x[0]).collect();
        sim.set_last_forces(&first);
        for t in 0..samples {
            for (v, x) in u.iter_mut().zip(&inputs) {
                *v = x[t];
            }
            if t == 0 {
                // At rest: the absolute acceleration is the quasi-static part.
                for (r, series) in out.iter_mut().enumerate() {
                    let qs: f64 = (0..u.len()).map(|c| self.motion.quasi_static(r, c) * u[c]).sum();
                    series.push(qs);
                }
                continue;
            }
            sim.step_forces(&u, &mut now);
            for (series, v) in out.iter_mut().zip(&now) {
                series.push(*v);
            }
        }
        out
    }
}

/// What a config's ground-driven model is made of, whatever its
/// parameters' values: assembled once and shared by every event of a run
/// (the forecast's model, [`GroundModel::at`], and the update,
/// [`super::event_update::update_on_event`]).
#[derive(Debug)]
pub struct GroundParts {
    pub setup: Arc<FrfSetup>,
    /// The structure on its support groups, their constraint lifts found
    /// once.
    pub grounded: GroundedStructure,
    /// The config's ground inputs (every one: a record's own is kept to
    /// the sensors it holds).
    pub plan: Vec<GroundInputPlan>,
    pub parameters: Vec<Parameter>,
}

impl GroundParts {
    pub fn new(config: &Config) -> Result<Self> {
        Self::sharing(config, None)
    }

    /// As [`Self::new`], with `setup`, the FRF model already built from the
    /// same config (the daemon's pipeline's, [`crate::config::frf_setup`]),
    /// shared instead of built again.
    pub fn sharing(config: &Config, setup: Option<Arc<FrfSetup>>) -> Result<Self> {
        // The model once, for the FRF model and the grounds.
        let (shell, groups, plan) = ground_setup(config)?;
        let setup = match setup {
            Some(setup) => setup,
            None => Arc::new(frf_setup_of(config, &shell, &[])?),
        };
        Ok(Self {
            setup,
            grounded: GroundedStructure::new(shell, groups)
                .map_err(|e| anyhow::anyhow!("the model's supports: {e}"))?,
            plan,
            parameters: config.build_parameters()?,
        })
    }
}

/// The shell model, its support groups and the config's ground inputs.
fn ground_setup(config: &Config) -> Result<(BridgeModel, SupportGroups, Vec<GroundInputPlan>)> {
    if !config.has_ground_sensors() {
        bail!("config: sensors: no ground sensor (a [[sensors]] entry with support = \"<group>\"): nothing drives the deck");
    }
    let model = solver_model(config)?;
    let groups = config.support_groups(&model)?;
    let plan = config.ground_plan(&groups)?;
    Ok((model, groups, plan))
}
