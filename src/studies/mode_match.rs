//! Identified modes against the configured model's: each identified mode's
//! nearest model mode by shape (MAC at its sensors), that mode's frequency
//! and the relative difference, and whether updating would pair them. What
//! tells which model mode an identified one is before any updating: a mode
//! that pairs by frequency alone may be another mode by shape.

use crate::config::Config;
use crate::io::modes_json::{ModeEntry, ModelMatch, ModesFile};
use crate::io::named_value::NamedValue;
use anyhow::Result;
use splinewatch_core::response::frf::ModalState;
use splinewatch_core::updating::modal_residual::{nearest_by_shape, pair_modes};

/// Sets every mode of `file` its [`ModelMatch`] against `config`'s model
/// with the `named` updating parameters set (every other one at the
/// config's value). `file`'s sensors must be the config's deck sensors.
pub fn match_with_model(config: &Config, file: &mut ModesFile, named: &[NamedValue]) -> Result<()> {
    let (setup, state) = super::parameters::modal_state_of(config, named)?;
    match_modes(config, &state, &setup.sensor_names, &mut file.modes)
}

/// Sets every one of `modes` its [`ModelMatch`] against `state`, whose
/// sensors are `sensor_names`; `config`'s `[updating]` says what pairs.
pub fn match_modes(
    config: &Config,
    state: &ModalState,
    sensor_names: &[String],
    modes: &mut [ModeEntry],
) -> Result<()> {
    let observed = ModesFile::of(modes.to_vec()).to_observed(sensor_names)?;
    let paired = pair_modes(
        state,
        &observed,
        config.updating.min_mac,
        config.updating.max_frequency_gap,
    );
    for (mode, nearest) in modes.iter_mut().zip(nearest_by_shape(state, &observed)) {
        mode.model = nearest.map(|n| {
            let frequency_hz = state.modes.frequency_hz(n.model);
            ModelMatch {
                mode: n.model + 1,
                frequency_hz,
                damping_ratio: state.zeta[n.model],
                mac: n.mac,
                frequency_gap: (frequency_hz - mode.frequency_hz) / mode.frequency_hz,
                pairs: paired.iter().any(|p| p.observed == n.observed && p.model == n.model),
            }
        });
    }
    Ok(())
}
