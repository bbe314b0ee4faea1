//! `[zenoh]`: the session's mode and endpoints, layered over an optional
//! zenoh JSON5 file.

#[cfg(feature = "daemon")]
use anyhow::{anyhow, Result};
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

#[cfg(feature = "daemon")]
use super::{err, tls::TlsReport};

/// `[zenoh]`.
#[derive(Debug, Clone, Deserialize, Serialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields, default)]
pub struct ZenohConfig {
    /// "peer" or "client".
    pub mode: String,
    /// Endpoints to listen on, e.g. "tcp/127.0.0.1:7447".
    pub listen: Vec<String>,
    /// Endpoints to connect to (a router in client mode, peers otherwise).
    pub connect: Vec<String>,
    pub multicast_scouting: bool,
    /// A zenoh JSON5 configuration file, applied first.
    pub config_file: Option<PathBuf>,
}

impl Default for ZenohConfig {
    fn default() -> Self {
        Self {
            mode: "peer".into(),
            listen: vec!["tcp/127.0.0.1:7447".into()],
            connect: Vec::new(),
            multicast_scouting: false,
            config_file: None,
        }
    }
}

/// The zenoh session (the daemon's build only).
#[cfg(feature = "daemon")]
impl ZenohConfig {
    /// The zenoh session configuration: the JSON5 file first, then our keys;
    /// its TLS files read and checked (see [`TlsReport`]).
    pub fn to_zenoh(&self) -> Result<zenoh::Config> {
        Ok(self.to_zenoh_with_tls()?.0)
    }

    /// [`Self::to_zenoh`] and what its TLS settings and files amount to,
    /// for `check-config` and the daemon's start-up log.
    pub fn to_zenoh_with_tls(&self) -> Result<(zenoh::Config, TlsReport)> {
        let cfg = self.session_config()?;
        let report = self.inspect_tls(&cfg)?;
        Ok((cfg, report))
    }

    fn inspect_tls(&self, cfg: &zenoh::Config) -> Result<TlsReport> {
        super::tls::inspect(cfg).map_err(|e| match &self.config_file {
            // The TLS keys live in the JSON5 file: name it with the key path.
            Some(file) => anyhow!(err(
                format!("zenoh.config_file {}: {}", file.display(), e.path),
                e.message
            )),
            None => anyhow!(e),
        })
    }

    fn session_config(&self) -> Result<zenoh::Config> {
        let mut cfg = match &self.config_file {
            Some(path) => zenoh::Config::from_file(path)
                .map_err(|e| anyhow!("config: zenoh.config_file {}: {e}", path.display()))?,
            None => zenoh::Config::default(),
        };
        if !matches!(self.mode.as_str(), "peer" | "client") {
            return Err(anyhow!(
                "config: zenoh.mode: {:?} is not \"peer\" or \"client\"",
                self.mode
            ));
        }
        let set = |cfg: &mut zenoh::Config, key: &str, value: String| {
            cfg.insert_json5(key, &value)
                .map_err(|e| anyhow!("config: zenoh: {key} = {value}: {e}"))
        };
        set(&mut cfg, "mode", format!("{:?}", self.mode))?;
        // A client talks to its router and does not listen: the peer-mode
        // default endpoint is not applied in client mode (explicit ones are).
        let default_listen = self.mode == "client" && self.listen == Self::default().listen;
        if !self.listen.is_empty() && !default_listen {
            set(&mut cfg, "listen/endpoints", serde_json::to_string(&self.listen)?)?;
        }
        if !self.connect.is_empty() {
            set(&mut cfg, "connect/endpoints", serde_json::to_string(&self.connect)?)?;
        }
        set(
            &mut cfg,
            "scouting/multicast/enabled",
            self.multicast_scouting.to_string(),
        )?;
        Ok(cfg)
    }
}
