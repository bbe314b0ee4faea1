//! A beam's `stiffness` and `tie`: a multiplier θ on part of a member's
//! stiffness ([`splinewatch_core::model::member_stiffness`]), held or
//! updated, one parameter `<beam>.stiffness` shared by the beams tied to it.

use super::substructure::BeamConfig;
use super::*;
use splinewatch_core::model::beam::StiffnessPart;
use splinewatch_core::model::member_stiffness::MemberStiffness;
use splinewatch_core::updating::{Parameter, ParameterKind};

impl crate::config::tie::Tied for BeamConfig {
    fn name(&self) -> &str {
        &self.name
    }

    fn tie(&self) -> Option<&str> {
        self.tie.as_deref()
    }
}

impl BeamConfig {
    /// Why `self` cannot be tied to `leader`, if it cannot.
    fn tie_mismatch(&self, leader: &BeamConfig) -> Option<String> {
        let (Some(own), Some(lead)) = (&self.stiffness, &leader.stiffness) else {
            return Some(format!(
                "a tied beam and {:?} both give `stiffness` (it is what they share)",
                leader.name
            ));
        };
        if own.bounds.is_some() {
            Some(format!(
                "a tied beam takes the bounds of {:?}: remove its own",
                leader.name
            ))
        } else if own.update != lead.update {
            Some(format!(
                "update both beams or neither, as {:?} (held ones tied share their loss factor)",
                leader.name
            ))
        } else if own.value != lead.value || own.scales != lead.scales {
            Some(format!(
                "give the same `value` and `scales` as {:?} ({} of {:?})",
                leader.name, lead.value, lead.scales
            ))
        } else {
            None
        }
    }
}

impl Config {
    /// Every beam that is not tied, with the number of beams tied to it
    /// after it, plus one.
    fn beam_runs(&self) -> Result<Vec<(usize, usize)>, ConfigError> {
        crate::config::tie::tied_runs(&self.model.beams, "model.beams", "beam", BeamConfig::tie_mismatch)
    }

    /// The multipliers of the beams that give `stiffness`, in config order.
    pub(super) fn build_member_stiffness(&self) -> Result<Vec<MemberStiffness>, ConfigError> {
        let mut out = Vec::new();
        for (member, b) in self.model.beams.iter().enumerate() {
            let Some(s) = &b.stiffness else { continue };
            let key = |k: &str| format!("model.beams[{member}].stiffness.{k}");
            let part = StiffnessPart::parse(&s.scales).ok_or_else(|| {
                err(
                    key("scales"),
                    format!("{:?} is not one of {:?}", s.scales, StiffnessPart::NAMES),
                )
            })?;
            if let Some([lower, upper]) = s.bounds {
                if !(lower.is_finite() && upper.is_finite() && 0.0 < lower && lower < upper) {
                    return Err(err(key("bounds"), "must be finite with 0 < lower < upper"));
                }
            }
            out.push(MemberStiffness::new(member, part, s.value).map_err(|e| err(key("value"), e))?);
        }
        self.beam_runs()?;
        Ok(out)
    }

    /// `<beam>.stiffness` for every beam whose `stiffness` is updated (the
    /// beams tied to it share it), on fields after the deck's
    /// `stiffness_fields`.
    pub(crate) fn member_stiffness_parameters(&self) -> Result<Vec<Parameter>, ConfigError> {
        let first = self.model.stiffness_fields.len();
        let beams = &self.model.beams;
        let mut out = Vec::new();
        for (b, count) in self.beam_runs()? {
            let Some(s) = beams[b].stiffness.as_ref().filter(|s| s.update) else {
                continue;
            };
            let [lower, upper] = s.bounds.ok_or_else(|| {
                err(
                    format!("model.beams[{b}].stiffness.bounds"),
                    "required when it is updated",
                )
            })?;
            let field = first + beams[..b].iter().filter(|o| o.stiffness.is_some()).count();
            out.push(Parameter {
                name: format!("{}.stiffness", beams[b].name),
                kind: if count == 1 {
                    ParameterKind::Stiffness { field, coefficient: 0 }
                } else {
                    ParameterKind::StiffnessRun {
                        field,
                        count,
                        coefficient: 0,
                    }
                },
                lower,
                upper,
            });
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use crate::config::Config;
    use splinewatch_core::model::beam::StiffnessPart;
    use splinewatch_core::updating::ParameterKind;

    /// The deck on a bent, its two columns' bending stiffness one parameter
    /// (the north column tied to the south one).
    fn columns() -> String {
        include_str!("../../../config/examples/deck-on-bent.toml")
            .replacen(
                "base = \"fixed\"\n",
                "base = \"fixed\"\nstiffness = { value = 0.7, scales = \"bending\", bounds = [0.2, 1.5] }\n",
                1,
            )
            .replacen(
                "elements = 8\nbase = \"fixed\"\nsupport = \"bent\"\n\n[[model.rigid]]",
                "elements = 8\nbase = \"fixed\"\nsupport = \"bent\"\nstiffness = { value = 0.7, scales = \"bending\" }\ntie = \"bent.south\"\n\n[[model.rigid]]",
                1,
            )
    }

    fn message(text: &str) -> String {
        let outcome = Config::from_toml(text).and_then(|c| c.build_model().and_then(|_| c.build_parameters()));
        outcome.err().map(|e| e.to_string()).unwrap_or_default()
    }

    /// The tied pair is one parameter over two consecutive fields after the
    /// deck's (none here), at the start value, bending only; the model's
    /// first modes soften; errors name their key.
    #[test]
    fn beams_stiffness_is_a_parameter_tied_across_columns() {
        let text = columns();
        let config = Config::from_toml(&text).unwrap();
        let model = config.build_model().unwrap();
        let parts: Vec<(usize, StiffnessPart, f64)> = model
            .member_stiffness
            .iter()
            .map(|m| (m.member(), m.part(), m.factor()))
            .collect();
        assert_eq!(
            parts,
            [(0, StiffnessPart::Bending, 0.7), (1, StiffnessPart::Bending, 0.7)]
        );
        let parameters = config.build_parameters().unwrap();
        assert_eq!(parameters.len(), 1);
        assert_eq!(parameters[0].name, "bent.south.stiffness");
        assert_eq!(
            parameters[0].kind,
            ParameterKind::StiffnessRun {
                field: 0,
                count: 2,
                coefficient: 0
            }
        );
        assert_eq!((parameters[0].lower, parameters[0].upper), (0.2, 1.5));
        assert_eq!(config.parameter_unit("bent.south.stiffness"), "-");
        let nominal = Config::from_toml(include_str!("../../../config/examples/deck-on-bent.toml"))
            .unwrap()
            .build_model()
            .unwrap();
        let (cracked, uncracked) = (
            model.assemble().unwrap().modes().unwrap().frequencies_hz(),
            nominal.assemble().unwrap().modes().unwrap().frequencies_hz(),
        );
        assert!(cracked
            .iter()
            .zip(&uncracked)
            .take(6)
            .all(|(a, b)| a <= &(b * (1.0 + 1e-9))));
        assert!(cracked.iter().zip(&uncracked).take(6).any(|(a, b)| a < &(b * 0.99)));
        let cases = [
            (
                text.replacen("\"bending\" }\ntie", "\"axial\" }\ntie", 1),
                "model.beams[1].tie",
            ),
            (
                text.replacen("\"bending\", bounds", "\"shear\", bounds", 1),
                "model.beams[0].stiffness.scales",
            ),
            (
                text.replacen("[0.2, 1.5]", "[0.0, 1.5]", 1),
                "model.beams[0].stiffness.bounds",
            ),
            (
                text.replacen(
                    "value = 0.7, scales = \"bending\", bounds",
                    "value = -1.0, scales = \"bending\", bounds",
                    1,
                ),
                "model.beams[0].stiffness.value",
            ),
            (
                text.replacen(", bounds = [0.2, 1.5]", "", 1),
                "model.beams[0].stiffness.bounds",
            ),
            (
                text.replacen("stiffness = { value = 0.7, scales = \"bending\" }\n", "", 1),
                "model.beams[1].tie",
            ),
            (
                text.replacen("tie = \"bent.south\"", "tie = \"cap\"", 1),
                "model.beams[1].tie",
            ),
        ];
        for (text, key) in cases {
            let e = message(&text);
            assert!(e.contains(key), "{key}: {e}");
        }
    }
}
