//! Where results go: the results MCAP, the state file, Rerun (`.rrd` files
//! and a live viewer), the raw-input recorder, zenoh publishing, the
//! owner's report, the metrics and the status page.
//! Room: below the services. May import: `pipeline`, `config`, `io`, the core crate.

pub mod metrics;
pub mod notify;
pub mod publisher;
pub mod raw_recorder;
pub mod report;
pub mod rerun;
pub mod results;
pub mod state;
pub mod web;
