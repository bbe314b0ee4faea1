//! `tie`: an entry of a list (bearings, supports, stiffness fields) that
//! takes the parameters and the loss factor of the entry before it (its
//! loss factor: [`super::loss_factor`]).

use super::{err, ConfigError};

/// An entry that may be tied to another by name.
pub(crate) trait Tied {
    fn name(&self) -> &str;
    /// The name of the entry it is tied to, if any.
    fn tie(&self) -> Option<&str>;
}

/// Every entry of `items` (the list `section`, each a `what`) that is not
/// tied, with the number of entries tied to it after it, plus one; a tied
/// entry must come just after its leader or an entry tied to it, and pass
/// `mismatch` against the leader, or it is refused by its `tie` key.
pub(crate) fn tied_runs<T: Tied>(
    items: &[T],
    section: &str,
    what: &str,
    mismatch: impl Fn(&T, &T) -> Option<String>,
) -> Result<Vec<(usize, usize)>, ConfigError> {
    let mut runs: Vec<(usize, usize)> = Vec::new();
    for (i, item) in items.iter().enumerate() {
        let Some(leader) = item.tie() else {
            runs.push((i, 1));
            continue;
        };
        let key = format!("{section}[{i}].tie");
        let run = runs
            .last_mut()
            .filter(|(l, count)| items[*l].name() == leader && l + *count == i)
            .ok_or_else(|| {
                err(
                    &key,
                    format!("{leader:?} must be the {what} just before this one (or before {what}s tied to it)"),
                )
            })?;
        if let Some(why) = mismatch(item, &items[run.0]) {
            return Err(err(&key, why));
        }
        run.1 += 1;
    }
    Ok(runs)
}
