//! Where each loss factor acts: the spring coefficients and stiffness-field
//! coefficients whose strain energy it weighs ([`crate::model::damping`],
//! modal strain energy, Johnson & Kienholz 1982).
//!
//! A site is a set of spring coefficients, numbered flat over the model's
//! spring fields in order (field 0's coefficients, then field 1's, …), and
//! of stiffness-field coefficients, numbered flat over the stiffness fields
//! (the deck's, then the beam members' multipliers): a whole support (every
//! coefficient of its field), one component of it (an abutment's lateral
//! springs, not its vertical ones), the same component of several supports
//! that share one loss factor, a patch's stiffness field, or a member's
//! multiplier (its part of the stiffness: `K_s = Σ_k θ_k ∂K/∂θ_k`, `K`
//! linear in `θ`). Sites are disjoint; a coefficient in no site is lossless.

use thiserror::Error;

#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum LossSitesError {
    #[error("loss site {site} weighs no coefficient")]
    Empty { site: usize },
    #[error(
        "{kind} coefficient {coefficient} is in loss sites {first} and {second}: a coefficient has one loss factor"
    )]
    Shared {
        kind: &'static str,
        coefficient: usize,
        first: usize,
        second: usize,
    },
    #[error("loss site {site} weighs {kind} coefficient {coefficient}, but the model has {count}")]
    Outside {
        kind: &'static str,
        site: usize,
        coefficient: usize,
        count: usize,
    },
}

/// The coefficients one loss factor weighs (flat indices).
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct LossSite {
    /// Spring coefficients `κ_j`.
    pub springs: Vec<usize>,
    /// Stiffness-field coefficients `θ_k`.
    pub fields: Vec<usize>,
}

impl LossSite {
    /// A site of spring coefficients alone.
    pub fn springs(springs: Vec<usize>) -> Self {
        Self {
            springs,
            fields: Vec::new(),
        }
    }

    /// A site of stiffness-field coefficients alone.
    pub fn fields(fields: Vec<usize>) -> Self {
        Self {
            springs: Vec::new(),
            fields,
        }
    }
}

/// Disjoint, non-empty loss sites, one per loss factor.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LossSites {
    sites: Vec<LossSite>,
}

impl LossSites {
    /// Checks that every site weighs a coefficient and no coefficient is in
    /// two sites (whether each exists is the model's check,
    /// [`Self::site_of`]).
    pub fn new(sites: Vec<LossSite>) -> Result<Self, LossSitesError> {
        let mut owners = [std::collections::BTreeMap::new(), std::collections::BTreeMap::new()];
        for (site, s) in sites.iter().enumerate() {
            if s.springs.is_empty() && s.fields.is_empty() {
                return Err(LossSitesError::Empty { site });
            }
            for ((kind, coefficients), owner) in [("spring", &s.springs), ("stiffness-field", &s.fields)]
                .into_iter()
                .zip(owners.iter_mut())
            {
                for &coefficient in coefficients {
                    if let Some(first) = owner.insert(coefficient, site) {
                        return Err(LossSitesError::Shared {
                            kind,
                            coefficient,
                            first,
                            second: site,
                        });
                    }
                }
            }
        }
        Ok(Self { sites })
    }

    /// One site per spring field, each holding every coefficient of its
    /// field (`field_sizes`: the fields' coefficient counts).
    pub fn per_field(field_sizes: &[usize]) -> Self {
        let mut start = 0;
        let sites = field_sizes
            .iter()
            .map(|&n| {
                let site = LossSite::springs((start..start + n).collect());
                start += n;
                site
            })
            .collect();
        Self { sites }
    }

    pub fn len(&self) -> usize {
        self.sites.len()
    }

    pub fn is_empty(&self) -> bool {
        self.sites.is_empty()
    }

    /// Site `s`.
    pub fn site(&self, s: usize) -> &LossSite {
        &self.sites[s]
    }

    /// Whether any site weighs stiffness-field coefficients.
    pub fn has_fields(&self) -> bool {
        self.sites.iter().any(|s| !s.fields.is_empty())
    }

    /// For each of `springs` spring coefficients and `fields` stiffness-field
    /// coefficients, the site it is in (`None`: lossless); a site naming a
    /// coefficient beyond them is refused.
    pub fn site_of(&self, springs: usize, fields: usize) -> Result<SiteOf, LossSitesError> {
        let mut out = SiteOf {
            springs: vec![None; springs],
            fields: vec![None; fields],
        };
        for (site, s) in self.sites.iter().enumerate() {
            for (kind, coefficients, slots) in [
                ("spring", &s.springs, &mut out.springs),
                ("stiffness-field", &s.fields, &mut out.fields),
            ] {
                let count = slots.len();
                for &coefficient in coefficients {
                    let slot = slots.get_mut(coefficient).ok_or(LossSitesError::Outside {
                        kind,
                        site,
                        coefficient,
                        count,
                    })?;
                    *slot = Some(site);
                }
            }
        }
        Ok(out)
    }
}

/// The loss site of every spring and stiffness-field coefficient.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SiteOf {
    pub springs: Vec<Option<usize>>,
    pub fields: Vec<Option<usize>>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sites_are_disjoint_non_empty_and_inside_the_model() {
        let springs = |v: Vec<usize>| LossSite::springs(v);
        assert_eq!(
            LossSites::new(vec![springs(vec![0]), LossSite::default()]),
            Err(LossSitesError::Empty { site: 1 })
        );
        assert_eq!(
            LossSites::new(vec![springs(vec![0, 3]), springs(vec![2, 3])]),
            Err(LossSitesError::Shared {
                kind: "spring",
                coefficient: 3,
                first: 0,
                second: 1
            })
        );
        // A spring and a field coefficient of the same number are different.
        let sites = LossSites::new(vec![springs(vec![1, 4]), springs(vec![2]), LossSite::fields(vec![1])]).unwrap();
        let found = sites.site_of(5, 2).unwrap();
        assert_eq!(found.springs, vec![None, Some(0), Some(1), None, Some(0)]);
        assert_eq!(found.fields, vec![None, Some(2)]);
        assert_eq!(
            sites.site_of(4, 2),
            Err(LossSitesError::Outside {
                kind: "spring",
                site: 0,
                coefficient: 4,
                count: 4
            })
        );
        assert!(matches!(
            sites.site_of(5, 1),
            Err(LossSitesError::Outside {
                kind: "stiffness-field",
                site: 2,
                ..
            })
        ));
        assert!(sites.has_fields());
    }

    #[test]
    fn one_site_per_field_holds_the_fields_coefficients() {
        let sites = LossSites::per_field(&[2, 0, 3]);
        assert_eq!(sites.len(), 3);
        assert_eq!(sites.site(0).springs, vec![0, 1]);
        assert!(sites.site(1).springs.is_empty());
        assert_eq!(sites.site(2).springs, vec![2, 3, 4]);
        assert!(!sites.has_fields());
    }
}
