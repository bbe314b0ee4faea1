//! The model's loss sites: every `loss_factor` of the springs, bearings,
//! supports, stiffness fields and beams with the spring or stiffness-field
//! coefficients it weighs ([`splinewatch_core::model::loss_sites`]).

use super::loss_factor::{ComponentLossFactor, LossFactorConfig};
use super::tie::Tied;
use super::{err, Config, ConfigError};
use std::collections::BTreeMap;

/// One loss factor of the model: its value, and the spring coefficients
/// (flat over the model's spring fields: springs, bearings, supports) and
/// stiffness-field coefficients (flat over the deck's fields, then the
/// beams' multipliers) whose strain energy it weighs.
#[derive(Debug, Clone, PartialEq)]
pub struct LossSite {
    /// The updating parameter's prefix: `<support>`, `<support>.<component>`,
    /// `<field>` or `<beam>`.
    pub name: String,
    /// Where it is given (`model.supports[0].loss_factor.y`).
    pub key: String,
    pub factor: LossFactorConfig,
    pub springs: Vec<usize>,
    pub fields: Vec<usize>,
}

impl LossSite {
    /// The core's site.
    pub fn core(&self) -> splinewatch_core::model::loss_sites::LossSite {
        splinewatch_core::model::loss_sites::LossSite {
            springs: self.springs.clone(),
            fields: self.fields.clone(),
        }
    }
}

impl Config {
    /// Every loss factor of the model with where it acts, in the order of
    /// the springs, bearings and supports: a spring field's on its
    /// coefficients; a bearing's or support's on all its components or on
    /// the ones named; a tied bearing or support joins its leader's sites
    /// (one η for both) and may not give its own. A value must be finite
    /// and non-negative, within its bounds when updated, and needs
    /// `[model.damping]` (the curve it adds to).
    pub fn loss_sites(&self) -> Result<Vec<LossSite>, ConfigError> {
        let m = &self.model;
        let order = super::kappa_order::KappaOrder::of(m);
        let mut sites = Vec::new();
        for (i, spring) in m.springs.iter().enumerate() {
            let first = order.spring_coefficient(i);
            if let Some(factor) = spring.loss_factor {
                sites.push(LossSite {
                    name: spring.name.clone(),
                    key: format!("model.springs[{i}].loss_factor"),
                    factor,
                    springs: (first..first + spring.stiffness.len()).collect(),
                    fields: Vec::new(),
                });
            }
        }
        let bearings = Entries {
            section: "model.bearings",
            what: "bearing",
            components: &|_| super::patches::BEARING_AXES.to_vec(),
            loss: &|b: &super::patches::BearingConfig| b.loss_factor.as_ref(),
        };
        bearings.add_sites(&m.bearings, &|b| order.bearing_coefficient(b), &mut sites)?;
        let supports = Entries {
            section: "model.supports",
            what: "support",
            components: &|s: &super::model::substructure::SupportConfig| s.component_names(),
            loss: &|s| s.loss_factor.as_ref(),
        };
        supports.add_sites(&m.supports, &|s| order.support_coefficient(s), &mut sites)?;
        self.add_field_sites(&mut sites)?;
        for site in &sites {
            site.factor.check(&site.key)?;
            if m.damping.is_none() {
                return Err(err(
                    &site.key,
                    "needs [model.damping]: the support's damping adds to the curve's",
                ));
            }
        }
        Ok(sites)
    }

    /// The stiffness fields' and beams' loss sites, on their multipliers'
    /// coefficients (the deck's fields in order, then one per beam giving
    /// `stiffness`); a tied field or beam joins its leader's site.
    fn add_field_sites(&self, sites: &mut Vec<LossSite>) -> Result<(), ConfigError> {
        let m = &self.model;
        let mut offset = 0;
        let mut leader: Option<usize> = None;
        for (i, field) in m.stiffness_fields.iter().enumerate() {
            let count = field.knots_xi.len().saturating_sub(field.degree_xi + 1)
                * field.knots_eta.len().saturating_sub(field.degree_eta + 1);
            let key = format!("model.stiffness_fields[{i}].loss_factor");
            add_field_site(
                sites,
                &mut leader,
                (field, key),
                field.loss_factor,
                offset..offset + count,
            )?;
            offset += count;
        }
        leader = None;
        for (b, beam) in m.beams.iter().enumerate() {
            let key = format!("model.beams[{b}].loss_factor");
            if beam.stiffness.is_none() {
                if beam.loss_factor.is_some() {
                    return Err(err(
                        key,
                        "needs `stiffness`: the loss factor damps the part of the member's stiffness it scales \
                         (`stiffness = { update = false }` holds it at 1)",
                    ));
                }
                continue;
            }
            add_field_site(sites, &mut leader, (beam, key), beam.loss_factor, offset..offset + 1)?;
            offset += 1;
        }
        Ok(())
    }
}

/// The site of `entry`'s `loss_factor` over the field coefficients
/// `coefficients`: a new one, or for a tied entry its leader's (`leader`:
/// the site of the last entry not tied, if it has one).
fn add_field_site<T: Tied>(
    sites: &mut Vec<LossSite>,
    leader: &mut Option<usize>,
    (entry, key): (&T, String),
    loss_factor: Option<LossFactorConfig>,
    coefficients: std::ops::Range<usize>,
) -> Result<(), ConfigError> {
    if let Some(name) = entry.tie() {
        if loss_factor.is_some() {
            return Err(err(
                key,
                format!("a tied entry takes the loss factor of {name:?}: remove it"),
            ));
        }
        if let Some(site) = *leader {
            sites[site].fields.extend(coefficients);
        }
        return Ok(());
    }
    *leader = loss_factor.map(|factor| {
        sites.push(LossSite {
            name: entry.name().to_string(),
            key,
            factor,
            springs: Vec::new(),
            fields: coefficients.collect(),
        });
        sites.len() - 1
    });
    Ok(())
}

/// A loss factor of a bearing or support: on one component (`None`: all),
/// its value, and its key.
type ComponentLoss = (Option<&'static str>, LossFactorConfig, String);

/// A list of bearings or supports as loss sites see it.
struct Entries<'a, T> {
    section: &'a str,
    what: &'a str,
    /// Its components' names, in the order of its spring coefficients.
    components: &'a dyn Fn(&T) -> Vec<&'static str>,
    loss: &'a dyn Fn(&T) -> Option<&ComponentLossFactor>,
}

impl<T: Tied> Entries<'_, T> {
    /// Adds the sites of `items`, item `i`'s coefficients starting at
    /// `first(i)`, to `sites`.
    fn add_sites(
        &self,
        items: &[T],
        first: &dyn Fn(usize) -> usize,
        sites: &mut Vec<LossSite>,
    ) -> Result<(), ConfigError> {
        // The sites of the last entry not tied, by component (None: whole).
        let mut leader: Vec<(usize, Option<&'static str>)> = Vec::new();
        for (i, item) in items.iter().enumerate() {
            let offset = first(i);
            let key = format!("{}[{i}].loss_factor", self.section);
            let components = (self.components)(item);
            let own = (self.loss)(item);
            if let Some(name) = item.tie() {
                if own.is_some() {
                    return Err(err(
                        key,
                        format!("a tied {} takes the loss factor of {name:?}: remove it", self.what),
                    ));
                }
                for &(site, component) in &leader {
                    sites[site]
                        .springs
                        .extend(self.coefficients(offset, &components, component));
                }
            } else {
                leader.clear();
                let named: Vec<ComponentLoss> = match own {
                    None => Vec::new(),
                    Some(ComponentLossFactor::Whole(factor)) => vec![(None, *factor, key.clone())],
                    Some(ComponentLossFactor::Components(table)) => self.components_named(table, &components, &key)?,
                };
                for (component, factor, key) in named {
                    leader.push((sites.len(), component));
                    sites.push(LossSite {
                        name: component.map_or_else(|| item.name().to_string(), |c| format!("{}.{c}", item.name())),
                        key,
                        factor,
                        springs: self.coefficients(offset, &components, component),
                        fields: Vec::new(),
                    });
                }
            }
        }
        Ok(())
    }

    /// The flat spring coefficients of `component` (None: every one) of an
    /// entry whose coefficients start at `offset`.
    fn coefficients(&self, offset: usize, components: &[&str], component: Option<&str>) -> Vec<usize> {
        (0..components.len())
            .filter(|&c| component.is_none_or(|name| components[c] == name))
            .map(|c| offset + c)
            .collect()
    }

    /// The components a per-component table names, each checked against
    /// the entry's own, in the entry's order.
    fn components_named(
        &self,
        table: &BTreeMap<String, LossFactorConfig>,
        components: &[&'static str],
        key: &str,
    ) -> Result<Vec<ComponentLoss>, ConfigError> {
        if table.is_empty() {
            return Err(err(
                key,
                "names no component: give a number, { value, bounds } or { <component> = η }",
            ));
        }
        for name in table.keys() {
            if components.contains(&name.as_str()) {
                continue;
            }
            let why = if matches!(name.as_str(), "value" | "bounds" | "update") {
                "an updated loss factor is { value, bounds } (both), or { update = false } beside them".to_string()
            } else {
                format!(
                    "{name:?} is not a component of this {} (it has {})",
                    self.what,
                    components.join(", ")
                )
            };
            return Err(err(format!("{key}.{name}"), why));
        }
        Ok(components
            .iter()
            .filter_map(|&c| table.get(c).map(|factor| (Some(c), *factor, format!("{key}.{c}"))))
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use crate::config::Config;
    use splinewatch_core::updating::ParameterKind;

    const BRIDGE: &str = include_str!("../../config/painter-street-bridge.toml");
    const WHOLE: &str = "loss_factor = { value = 0.3, bounds = [0.0, 1.5] }";

    /// Painter Street's whole bridge with the abutments' `loss_factor`
    /// (both given alike) replaced by `loss`.
    fn with_loss(loss: &str) -> Result<Config, String> {
        assert_eq!(BRIDGE.matches(WHOLE).count(), 2);
        let config = Config::from_toml(&BRIDGE.replace(WHOLE, loss)).map_err(|e| format!("{e:#}"))?;
        config.validate().map_err(|e| e.to_string())?;
        Ok(config)
    }

    /// `loss_factor = { y = …, z = … }` on a support: one loss site per
    /// component named, over that component's springs only, each its own
    /// parameter `<support>.<component>.eta` when updated; the other
    /// components lossless.
    #[test]
    fn a_support_takes_a_loss_factor_per_component() {
        let config = with_loss("loss_factor = { y = { value = 0.4, bounds = [0.0, 1.5] }, ry = 0.05 }").unwrap();
        let m = &config.model;
        let springs: usize = m.springs.iter().map(|s| s.stiffness.len()).sum::<usize>() + 3 * m.bearings.len();
        // x, y, z, ry: y is the second, ry the fourth; two abutments.
        let sites = config.loss_sites().unwrap();
        let found: Vec<(&str, Vec<usize>)> = sites.iter().map(|s| (s.name.as_str(), s.springs.clone())).collect();
        assert_eq!(
            found,
            vec![
                ("west_abutment.y", vec![springs + 1]),
                ("west_abutment.ry", vec![springs + 3]),
                ("east_abutment.y", vec![springs + 5]),
                ("east_abutment.ry", vec![springs + 7]),
            ]
        );
        assert_eq!(config.build_damping().unwrap().loss_factors(), &[0.4, 0.05, 0.4, 0.05]);
        let eta: Vec<_> = config
            .build_parameters()
            .unwrap()
            .into_iter()
            .filter(|p| p.name.ends_with(".eta"))
            .map(|p| (p.name, p.kind))
            .collect();
        assert_eq!(
            eta,
            vec![
                (
                    "west_abutment.y.eta".to_string(),
                    ParameterKind::LossFactor { field: 0, count: 1 }
                ),
                (
                    "east_abutment.y.eta".to_string(),
                    ParameterKind::LossFactor { field: 2, count: 1 }
                ),
            ]
        );
        assert_eq!(
            config.parameter_family("west_abutment.y.eta"),
            Some(crate::config::ParameterFamily::LossFactor)
        );
        // A component the support does not have is no parameter of it.
        assert_eq!(config.parameter_family("west_abutment.kz.eta"), None);
    }

    /// A tied support's components join its leader's sites: one η per
    /// component over both abutments.
    #[test]
    fn a_tied_support_shares_its_leaders_component_loss_factors() {
        let east = "name = \"east_abutment\"\nedge = { patch = \"bottom_slab.span2\", edge = \"xi1\" }\nsupport = \"east\"\nstiffness = { x = 1.556e+08, y = 3.113e+07, z = 3.891e+09, ry = 1.297e+10 }\nbounds = [1.0e5, 1.0e12]\nupdate = [\"y\", \"ry\"]\n";
        let tied = BRIDGE
            .replacen(WHOLE, "loss_factor = { y = { value = 0.4, bounds = [0.0, 1.5] } }", 1)
            .replacen(
                &format!("{east}{WHOLE}\n"),
                &east.replace("bounds = [1.0e5, 1.0e12]", "tie = \"west_abutment\""),
                1,
            );
        assert!(!tied.contains(WHOLE));
        let config = Config::from_toml(&tied).unwrap();
        config.validate().unwrap();
        let m = &config.model;
        let springs: usize = m.springs.iter().map(|s| s.stiffness.len()).sum::<usize>() + 3 * m.bearings.len();
        let sites = config.loss_sites().unwrap();
        assert_eq!(sites.len(), 1);
        assert_eq!(sites[0].springs, vec![springs + 1, springs + 5]);
    }

    /// Each bad per-component table is refused by its key, nothing built.
    #[test]
    fn bad_component_loss_factors_are_refused_by_key() {
        for (loss, key, why) in [
            (
                "loss_factor = { rx = 0.1 }",
                "model.supports[0].loss_factor.rx",
                "not a component of this support (it has x, y, z, ry)",
            ),
            (
                "loss_factor = { value = 0.1 }",
                "model.supports[0].loss_factor.value",
                "an updated loss factor is { value, bounds }",
            ),
            (
                "loss_factor = {}",
                "model.supports[0].loss_factor",
                "names no component",
            ),
            (
                "loss_factor = { y = -0.1 }",
                "model.supports[0].loss_factor.y",
                "must be a finite loss factor >= 0",
            ),
            (
                "loss_factor = { y = { value = 2.0, bounds = [0.0, 1.0] } }",
                "model.supports[0].loss_factor.y",
                "outside its bounds",
            ),
        ] {
            let message = with_loss(loss).unwrap_err();
            assert!(message.contains(key) && message.contains(why), "{loss}: {message}");
        }
        // A bearing's axes are kx, ky, kz.
        let deck = include_str!("../../config/painter-street.toml");
        let bearing = deck.replacen(
            "name = \"west_south\"",
            "name = \"west_south\"\nloss_factor = { ky = 0.2, z = 0.1 }",
            1,
        );
        let message = Config::from_toml(&bearing).unwrap().validate().unwrap_err().to_string();
        assert!(
            message.contains(".loss_factor.z") && message.contains("(it has kx, ky, kz)"),
            "{message}"
        );
    }

    /// Painter Street's whole bridge with `south` and `north` added to its
    /// columns' entries and a held stiffness field (η = 0.02) on one slab.
    fn columns(south: &str, north: &str) -> String {
        let field = "\n[[model.stiffness_fields]]\nname = \"deck\"\npatch = \"top_slab.span1\"\nknots_xi = [0.0, 0.0, 1.0, 1.0]\ndegree_xi = 1\nknots_eta = [0.0, 1.0]\ndegree_eta = 0\nupdate = false\nloss_factor = 0.02\n";
        let (s, n) = ("name = \"bent.south\"\n", "name = \"bent.north\"\n");
        BRIDGE
            .replacen(s, &format!("{s}{south}"), 1)
            .replacen(n, &format!("{n}{north}"), 1)
            + field
    }

    /// Two held columns tied share one loss factor (no stiffness
    /// parameter); one held and one updated are refused by key.
    #[test]
    fn held_columns_tied_share_their_loss_factor() {
        let held = columns(
            "stiffness = { update = false }\nloss_factor = 0.05\n",
            "stiffness = { update = false }\ntie = \"bent.south\"\n",
        );
        let config = Config::from_toml(&held).unwrap();
        config.validate().unwrap();
        let sites = config.loss_sites().unwrap();
        let columns_site = sites.iter().find(|s| s.name == "bent.south").unwrap();
        assert_eq!(columns_site.fields, vec![2, 3]);
        assert!(config
            .build_parameters()
            .unwrap()
            .iter()
            .all(|p| !p.name.starts_with("bent.")));
        let mixed = columns(
            "stiffness = { update = false }\nloss_factor = 0.05\n",
            "stiffness = {}\ntie = \"bent.south\"\n",
        );
        let message = Config::from_toml(&mixed).unwrap().validate().unwrap_err().to_string();
        assert!(
            message.contains("model.beams[1]") && message.contains("update both beams or neither"),
            "{message}"
        );
    }

    /// A loss factor on a deck's stiffness field and on a bent's columns
    /// (their multipliers' part of the stiffness): each a site on its
    /// coefficients in the assembled models' order (the deck's fields, then
    /// one per beam giving `stiffness`), the tied column joining its
    /// leader's; a beam without `stiffness`, or a tied one giving its own,
    /// refused by key.
    #[test]
    fn stiffness_fields_and_beams_take_a_loss_factor_on_their_part() {
        let text = columns(
            "stiffness = { bounds = [0.3, 1.5] }\nloss_factor = { value = 0.05, bounds = [0.0, 0.3] }\n",
            "stiffness = {}\ntie = \"bent.south\"\n",
        );
        let config = Config::from_toml(&text).unwrap();
        config.validate().unwrap();
        let theta = config.build_model().unwrap().field_coefficients();
        // The deck's field (2 × 1 coefficients), then the two columns'.
        assert_eq!(theta.iter().map(Vec::len).collect::<Vec<_>>(), vec![2, 1, 1]);
        let sites = config.loss_sites().unwrap();
        let found: Vec<(&str, &[usize])> = sites
            .iter()
            .filter(|s| s.springs.is_empty())
            .map(|s| (s.name.as_str(), s.fields.as_slice()))
            .collect();
        assert_eq!(found, vec![("deck", &[0, 1][..]), ("bent.south", &[2, 3][..])]);
        let eta: Vec<String> = config
            .build_parameters()
            .unwrap()
            .into_iter()
            .filter(|p| p.name.ends_with(".eta"))
            .map(|p| p.name)
            .collect();
        assert!(eta.contains(&"bent.south.eta".to_string()), "{eta:?}");
        assert!(!eta.iter().any(|n| n == "deck.eta"), "held: {eta:?}");
        let damping = config.build_damping().unwrap();
        assert!(damping.has_field_sites());
        for (text, key, why) in [
            (
                columns("loss_factor = 0.05\n", ""),
                "model.beams[0].loss_factor",
                "needs `stiffness`",
            ),
            (
                columns(
                    "stiffness = { bounds = [0.3, 1.5] }\nloss_factor = 0.05\n",
                    "stiffness = {}\ntie = \"bent.south\"\nloss_factor = 0.05\n",
                ),
                "model.beams[1].loss_factor",
                "takes the loss factor of \"bent.south\"",
            ),
            (
                columns("", "").replace("loss_factor = 0.02", "loss_factor = -0.02"),
                "model.stiffness_fields[0].loss_factor",
                "must be a finite loss factor >= 0",
            ),
        ] {
            let message = Config::from_toml(&text).unwrap().validate().unwrap_err().to_string();
            assert!(message.contains(key) && message.contains(why), "{message}");
        }
    }
}
