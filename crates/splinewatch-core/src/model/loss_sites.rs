//! Where each loss factor acts: the spring coefficients whose strain energy
//! it weighs ([`crate::model::damping`], modal strain energy, Johnson &
//! Kienholz 1982).
//!
//! A site is a set of spring coefficients, numbered flat over the model's
//! spring fields in order (field 0's coefficients, then field 1's, …): a
//! whole support (every coefficient of its field), one component of it (an
//! abutment's lateral springs, not its vertical ones), or the same
//! component of several supports that share one loss factor. Sites are
//! disjoint; a coefficient in no site is lossless.

use thiserror::Error;

#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum LossSitesError {
    #[error("loss site {site} weighs no spring coefficient")]
    Empty { site: usize },
    #[error(
        "spring coefficient {coefficient} is in loss sites {first} and {second}: a coefficient has one loss factor"
    )]
    Shared {
        coefficient: usize,
        first: usize,
        second: usize,
    },
    #[error("loss site {site} weighs spring coefficient {coefficient}, but the model has {count}")]
    Outside {
        site: usize,
        coefficient: usize,
        count: usize,
    },
}

/// Disjoint, non-empty sets of spring coefficients (flat indices), one per
/// loss factor.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LossSites {
    sites: Vec<Vec<usize>>,
}

impl LossSites {
    /// Checks that every site weighs a coefficient and no coefficient is in
    /// two sites (whether each exists is the model's check,
    /// [`Self::site_of`]).
    pub fn new(sites: Vec<Vec<usize>>) -> Result<Self, LossSitesError> {
        let mut owner = std::collections::BTreeMap::new();
        for (site, coefficients) in sites.iter().enumerate() {
            if coefficients.is_empty() {
                return Err(LossSitesError::Empty { site });
            }
            for &coefficient in coefficients {
                if let Some(first) = owner.insert(coefficient, site) {
                    return Err(LossSitesError::Shared {
                        coefficient,
                        first,
                        second: site,
                    });
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
                let site = (start..start + n).collect();
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

    /// The coefficients of site `s`.
    pub fn coefficients(&self, s: usize) -> &[usize] {
        &self.sites[s]
    }

    /// For each of `count` spring coefficients, the site it is in (`None`:
    /// lossless); a site naming a coefficient beyond `count` is refused.
    pub fn site_of(&self, count: usize) -> Result<Vec<Option<usize>>, LossSitesError> {
        let mut out = vec![None; count];
        for (site, coefficients) in self.sites.iter().enumerate() {
            for &coefficient in coefficients {
                let slot = out.get_mut(coefficient).ok_or(LossSitesError::Outside {
                    site,
                    coefficient,
                    count,
                })?;
                *slot = Some(site);
            }
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sites_are_disjoint_non_empty_and_inside_the_model() {
        assert_eq!(
            LossSites::new(vec![vec![0], vec![]]),
            Err(LossSitesError::Empty { site: 1 })
        );
        assert_eq!(
            LossSites::new(vec![vec![0, 3], vec![2, 3]]),
            Err(LossSitesError::Shared {
                coefficient: 3,
                first: 0,
                second: 1
            })
        );
        let sites = LossSites::new(vec![vec![1, 4], vec![2]]).unwrap();
        assert_eq!(sites.site_of(5).unwrap(), vec![None, Some(0), Some(1), None, Some(0)]);
        assert_eq!(
            sites.site_of(4),
            Err(LossSitesError::Outside {
                site: 0,
                coefficient: 4,
                count: 4
            })
        );
    }

    #[test]
    fn one_site_per_field_holds_the_fields_coefficients() {
        let sites = LossSites::per_field(&[2, 0, 3]);
        assert_eq!(sites.len(), 3);
        assert_eq!(sites.coefficients(0), &[0, 1]);
        assert!(sites.coefficients(1).is_empty());
        assert_eq!(sites.coefficients(2), &[2, 3, 4]);
    }
}
