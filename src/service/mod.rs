//! The shells that wire sources to the pipeline and the outputs: the live
//! daemon (zenoh), the offline replay (MCAP), the demo and the soak test.
//! Room: above the pipeline and outputs. May import: `outputs`, `pipeline`, `studies`, `config`, `io`, the core crate.

pub mod daemon;
pub mod demo;
pub mod replay;
pub mod rescore;
pub mod soak;

use std::collections::VecDeque;

/// Appends `item`, dropping the oldest beyond `keep`.
pub(crate) fn keep_latest<T>(list: &mut VecDeque<T>, item: T, keep: usize) {
    if keep == 0 {
        return;
    }
    if list.len() == keep {
        list.pop_front();
    }
    list.push_back(item);
}
