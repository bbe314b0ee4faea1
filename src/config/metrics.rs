//! `[metrics]`: the Prometheus endpoint of the daemon and of `replay
//! --metrics` (issue 48).

use super::{err, ConfigError};
use serde::{Deserialize, Serialize};

/// `[metrics]`: present, the daemon serves `/metrics`.
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MetricsConfig {
    /// `address:port` to serve on; loopback unless the operator says
    /// otherwise (port 9464, OpenTelemetry's Prometheus exporter port).
    #[serde(default = "default_listen")]
    pub listen: String,
}

impl Default for MetricsConfig {
    fn default() -> Self {
        Self {
            listen: default_listen(),
        }
    }
}

fn default_listen() -> String {
    "127.0.0.1:9464".into()
}

impl MetricsConfig {
    pub fn check(&self) -> Result<(), ConfigError> {
        self.listen.parse::<std::net::SocketAddr>().map(|_| ()).map_err(|e| {
            err(
                "metrics.listen",
                format!(
                    "{:?} is not an address:port (e.g. \"127.0.0.1:9464\"): {e}",
                    self.listen
                ),
            )
        })
    }
}
