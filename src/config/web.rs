//! `[web]`: the daemon's read-only status page.

use super::{err, ConfigError};
use serde::{Deserialize, Serialize};

/// `[web]`: present, the daemon serves its status page (`/`), its JSON
/// (`/status.json`) and the owner's report of what it has written
/// (`/report`), read-only.
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct WebConfig {
    /// `address:port` to serve on; loopback unless the operator says
    /// otherwise (and then a `token_file` is required).
    #[serde(default = "default_listen")]
    pub listen: String,
    /// A file whose first line is the token every request must carry
    /// (`Authorization: Bearer <token>`, or `?token=<token>` from a
    /// browser); read at each request, so a rotated token needs no restart.
    #[serde(default)]
    pub token_file: Option<std::path::PathBuf>,
    /// Seconds between the page's refreshes in the browser.
    #[serde(default = "default_refresh")]
    pub refresh_seconds: u32,
}

impl Default for WebConfig {
    fn default() -> Self {
        Self {
            listen: default_listen(),
            token_file: None,
            refresh_seconds: default_refresh(),
        }
    }
}

fn default_listen() -> String {
    "127.0.0.1:9465".into()
}

fn default_refresh() -> u32 {
    10
}

impl WebConfig {
    /// An `address:port`, not the metrics' one, a token on any address but
    /// loopback, a token file that can be read, a refresh of 1 s to a day.
    pub fn check(&self, metrics: Option<&str>) -> Result<(), ConfigError> {
        let address: std::net::SocketAddr = self.listen.parse().map_err(|e| {
            err(
                "web.listen",
                format!(
                    "{:?} is not an address:port (e.g. \"127.0.0.1:9465\"): {e}",
                    self.listen
                ),
            )
        })?;
        if metrics == Some(self.listen.as_str()) && address.port() != 0 {
            return Err(err(
                "web.listen",
                format!(
                    "{} is [metrics] listen too: give the page a port of its own",
                    self.listen
                ),
            ));
        }
        match &self.token_file {
            None if !address.ip().is_loopback() => {
                return Err(err(
                    "web.token_file",
                    format!("the page listens on {} (not loopback): give a token_file", self.listen),
                ))
            }
            Some(path) => {
                let token = std::fs::read_to_string(path)
                    .map_err(|e| err("web.token_file", format!("cannot read {}: {e}", path.display())))?;
                if token.lines().next().is_none_or(|l| l.trim().is_empty()) {
                    return Err(err(
                        "web.token_file",
                        format!("{}: its first line is empty", path.display()),
                    ));
                }
            }
            None => {}
        }
        if !(1..=86_400).contains(&self.refresh_seconds) {
            return Err(err(
                "web.refresh_seconds",
                format!("must be 1 to 86400, got {}", self.refresh_seconds),
            ));
        }
        Ok(())
    }
}
