//! A name and a value, as every results message and state file writes them
//! (`{"name": …, "value": …}`).

use serde::{Deserialize, Serialize};

/// A named value: a feature's (`null`, NaN in memory, when the window lacks
/// it: an identified frequency whose mode was not found) or a parameter's
/// (an event's forecast model, the chain's state, a fleet's summary).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NamedValue {
    pub name: String,
    #[serde(deserialize_with = "nan_for_null")]
    pub value: f64,
}

impl NamedValue {
    pub fn new(name: impl Into<String>, value: f64) -> Self {
        Self {
            name: name.into(),
            value,
        }
    }
}

fn nan_for_null<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Option::<f64>::deserialize(d).map(|v| v.unwrap_or(f64::NAN))
}
