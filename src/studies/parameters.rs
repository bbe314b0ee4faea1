//! Updating parameters set by name (start values, a result's parameters).

use crate::config::{Config, FrfSetup};
use crate::io::named_value::NamedValue;
use anyhow::{Context, Result};
use splinewatch_core::response::frf::ModalState;
use splinewatch_core::updating::Parameter;

/// `base` with the `named` parameters set; `what` names them in errors (an
/// unknown name, a value that is not finite).
pub fn values_by_name(parameters: &[Parameter], base: &[f64], named: &[NamedValue], what: &str) -> Result<Vec<f64>> {
    let mut values = base.to_vec();
    for NamedValue { name, value } in named {
        let k = parameters
            .iter()
            .position(|p| &p.name == name)
            .with_context(|| format!("{what} {name:?} is not an updating parameter of this config"))?;
        if !value.is_finite() {
            anyhow::bail!("{what} {name:?} is not finite");
        }
        values[k] = *value;
    }
    Ok(values)
}

/// The configured model's frf setup and its modal state with the `named`
/// updating parameters set (every other one at the config's value).
pub fn modal_state_of(config: &Config, named: &[NamedValue]) -> Result<(FrfSetup, ModalState)> {
    let setup = crate::config::frf_setup(config)?;
    let state = modal_state_in(&setup, &config.build_parameters()?, named)?;
    Ok((setup, state))
}

/// `setup`'s modal state with the `named` ones of its updating
/// `parameters` set (every other one at the setup's value).
pub fn modal_state_in(setup: &FrfSetup, parameters: &[Parameter], named: &[NamedValue]) -> Result<ModalState> {
    let base = splinewatch_core::updating::base_values(
        parameters,
        &setup.kappa,
        setup.model.field_coefficients(),
        &setup.damping,
    );
    let values = values_by_name(parameters, &base, named, "parameter")?;
    let (state, _) =
        splinewatch_core::updating::modal_state_at(&setup.model, parameters, &setup.kappa, &setup.damping, &values)?;
    Ok(state)
}
