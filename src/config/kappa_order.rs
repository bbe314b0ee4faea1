//! Where each support's spring coefficients κ lie in the assembled model,
//! written down here alone on the config's side, before the model is
//! built, in the order the core's `BridgeModel::supports` gives them: the
//! spring fields, then the bearings, then the supports
//! (`[[model.supports]]`), each in config order.

use super::model::ModelConfig;
use super::patches::BEARING_AXES;

/// The κ layout of a model section: its fields (one κ vector per spring
/// field, bearing or support) and their flat coefficients.
pub(crate) struct KappaOrder {
    /// Coefficients of each spring field.
    springs: Vec<usize>,
    bearings: usize,
    /// Components of each support.
    supports: Vec<usize>,
}

impl KappaOrder {
    pub(crate) fn of(model: &ModelConfig) -> Self {
        Self {
            springs: model.springs.iter().map(|s| s.stiffness.len()).collect(),
            bearings: model.bearings.len(),
            supports: model.supports.iter().map(|s| s.component_names().len()).collect(),
        }
    }

    /// The κ field of bearing `b`.
    pub(crate) fn bearing_field(&self, b: usize) -> usize {
        self.springs.len() + b
    }

    /// The κ field of support `s`.
    pub(crate) fn support_field(&self, s: usize) -> usize {
        self.springs.len() + self.bearings + s
    }

    /// The first flat coefficient of spring field `i`.
    pub(crate) fn spring_coefficient(&self, i: usize) -> usize {
        self.springs[..i].iter().sum()
    }

    /// The first flat coefficient of bearing `b`.
    pub(crate) fn bearing_coefficient(&self, b: usize) -> usize {
        self.springs.iter().sum::<usize>() + BEARING_AXES.len() * b
    }

    /// The first flat coefficient of support `s`.
    pub(crate) fn support_coefficient(&self, s: usize) -> usize {
        self.bearing_coefficient(self.bearings) + self.supports[..s].iter().sum::<usize>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::Config;

    /// The layout agrees with the κ vectors the built model chains, on
    /// every bundled config with bearings or supports.
    #[test]
    fn the_order_is_the_built_models() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        for name in [
            "config/painter-street-bridge.toml",
            "config/overpass.toml",
            "config/examples/deck-on-bent.toml",
        ] {
            let config = Config::from_toml(&std::fs::read_to_string(root.join(name)).unwrap()).unwrap();
            let order = KappaOrder::of(&config.model);
            let kappa = config.build_model().unwrap().spring_coefficients();
            let starts: Vec<usize> = kappa
                .iter()
                .scan(0, |next, field| {
                    let start = *next;
                    *next += field.len();
                    Some(start)
                })
                .collect();
            let m = &config.model;
            for (i, &start) in starts.iter().enumerate().take(m.springs.len()) {
                assert_eq!(order.spring_coefficient(i), start, "{name}: spring {i}");
            }
            for b in 0..m.bearings.len() {
                let field = order.bearing_field(b);
                assert_eq!(kappa[field].len(), BEARING_AXES.len(), "{name}: bearing {b}");
                assert_eq!(order.bearing_coefficient(b), starts[field], "{name}: bearing {b}");
            }
            for s in 0..m.supports.len() {
                let field = order.support_field(s);
                assert_eq!(order.support_coefficient(s), starts[field], "{name}: support {s}");
            }
            assert_eq!(
                order.support_field(m.supports.len()),
                kappa.len(),
                "{name}: every field"
            );
        }
    }
}
