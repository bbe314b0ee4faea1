//! Updating parameters set by name (start values, a result's parameters).

use anyhow::{Context, Result};
use splinewatch_core::updating::Parameter;

/// `base` with the `named` parameters set; `what` names them in errors (an
/// unknown name, a value that is not finite).
pub fn values_by_name(parameters: &[Parameter], base: &[f64], named: &[(String, f64)], what: &str) -> Result<Vec<f64>> {
    let mut values = base.to_vec();
    for (name, value) in named {
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
