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
    /// `[web.tls]`: serve HTTPS; with `client_ca`, mutual TLS.
    #[serde(default)]
    pub tls: Option<WebTlsConfig>,
}

/// `[web.tls]`: the page over HTTPS. With `client_ca` only a browser or
/// script holding a certificate that CA signed is served (mutual TLS: the
/// site's CA, the one `root_ca_certificate` names in the zenoh JSON5 file,
/// admits the same clients as the zenoh links).
#[derive(Debug, Clone, Deserialize, Serialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct WebTlsConfig {
    /// The server's certificate chain (PEM), leaf first.
    pub certificate: std::path::PathBuf,
    /// Its private key (PEM: PKCS #8, PKCS #1 or SEC1).
    pub private_key: std::path::PathBuf,
    /// The CA (PEM) whose certificates clients must present; none: any
    /// client may connect (then a `token_file` guards the page).
    #[serde(default)]
    pub client_ca: Option<std::path::PathBuf>,
}

impl Default for WebConfig {
    fn default() -> Self {
        Self {
            listen: default_listen(),
            token_file: None,
            refresh_seconds: default_refresh(),
            tls: None,
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
    /// An `address:port`, not the metrics' one, a token or client
    /// certificates on any address but loopback, a token file that can be
    /// read, TLS files that hold a certificate and a key, a refresh of 1 s
    /// to a day.
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
        let client_certificates = self.tls.as_ref().is_some_and(|t| t.client_ca.is_some());
        match &self.token_file {
            None if !address.ip().is_loopback() && !client_certificates => {
                return Err(err(
                    "web.token_file",
                    format!(
                        "the page listens on {} (not loopback): give a token_file, or [web.tls] client_ca for client certificates",
                        self.listen
                    ),
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
        if let Some(tls) = &self.tls {
            tls.check()?;
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

impl WebTlsConfig {
    /// Each file can be read and holds what its key names (a PEM
    /// certificate, or a PEM private key).
    fn check(&self) -> Result<(), ConfigError> {
        let pem = |key: &str, path: &std::path::Path, label: &str| -> Result<(), ConfigError> {
            let text =
                std::fs::read_to_string(path).map_err(|e| err(key, format!("cannot read {}: {e}", path.display())))?;
            let found = text
                .lines()
                .any(|l| l.starts_with("-----BEGIN ") && l.contains(label) && l.ends_with("-----"));
            if !found {
                return Err(err(
                    key,
                    format!("{}: no PEM {label} in it (-----BEGIN … {label}-----)", path.display()),
                ));
            }
            Ok(())
        };
        pem("web.tls.certificate", &self.certificate, "CERTIFICATE")?;
        pem("web.tls.private_key", &self.private_key, "PRIVATE KEY")?;
        if let Some(ca) = &self.client_ca {
            pem("web.tls.client_ca", ca, "CERTIFICATE")?;
        }
        Ok(())
    }
}
