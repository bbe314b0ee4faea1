//! The integration tests, one binary (one link of zenoh, Rerun and faer
//! instead of one per file): real zenoh sessions on loopback, real MCAP and
//! `.rrd` files and the real binary. `common` holds the shared helpers.

mod architecture;
mod cli;
mod common;
mod corpus;
mod events;
mod fleet;
mod ground;
mod guide;
mod import;
mod live;
mod matrices;
mod measurements;
mod metrics;
mod monitoring;
mod notify;
mod oma;
mod paper;
mod pipes;
#[cfg(unix)]
mod reliability;
mod replay;
mod report;
mod robust_updating;
#[cfg(unix)]
mod security;
mod stations;
mod uff;
