//! The TLS files of a zenoh session, checked before the session opens.
//!
//! zenoh reads the certificates and keys named under `transport/link/tls`
//! only when a link is made, and then reports a missing file as a failed
//! connection. Here every file is read first, each certificate parsed and
//! its validity checked, and any problem names the JSON5 key path and the
//! file: `check-config` and every role (daemon, simulator, logger) refuse to
//! start on it. What a `tls/…` endpoint needs:
//! - listening: `listen_certificate` and `listen_private_key`, and with
//!   `enable_mtls` the `root_ca_certificate` that signs the clients'
//!   certificates (the only roots a listener trusts for clients);
//! - connecting: with `enable_mtls`, `connect_certificate` and
//!   `connect_private_key`; `root_ca_certificate` is added to the web PKI
//!   roots (zenoh always keeps them for the server's certificate).

use std::fmt;
use std::path::PathBuf;
use time::OffsetDateTime;
use x509_parser::pem::Pem;

use super::{err, ConfigError};

/// Days before a certificate's expiry from which it is reported as expiring.
pub const EXPIRY_WARNING_DAYS: i64 = 30;

const PREFIX: &str = "transport/link/tls";

/// One file named under `transport/link/tls`, read and checked.
#[derive(Debug, Clone, PartialEq)]
pub struct TlsFile {
    /// The JSON5 key path, e.g. `transport/link/tls/connect_certificate`.
    pub key: String,
    pub path: PathBuf,
    /// The first certificate's subject and expiry; `None` for a private key.
    pub certificate: Option<CertificateSummary>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct CertificateSummary {
    pub subject: String,
    pub not_after: OffsetDateTime,
    /// Whole days from now to `not_after`.
    pub days_left: i64,
}

/// What the session's TLS settings amount to.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TlsReport {
    /// Whether any listen or connect endpoint is `tls/…`.
    pub endpoints: bool,
    pub mutual: bool,
    pub files: Vec<TlsFile>,
}

impl TlsReport {
    /// The certificates that expire within [`EXPIRY_WARNING_DAYS`].
    pub fn expiring(&self) -> impl Iterator<Item = &TlsFile> {
        self.files.iter().filter(|f| {
            f.certificate
                .as_ref()
                .is_some_and(|c| c.days_left < EXPIRY_WARNING_DAYS)
        })
    }
}

impl fmt::Display for TlsFile {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} = {}", self.key, self.path.display())?;
        if let Some(c) = &self.certificate {
            let date = c.not_after.date();
            write!(f, ": {}, expires {date} (in {} days)", c.subject, c.days_left)?;
        }
        Ok(())
    }
}

/// Reads and checks every TLS file `cfg` names (see the module comment).
pub fn inspect(cfg: &zenoh::Config) -> Result<TlsReport, ConfigError> {
    let listen = tls_endpoints(cfg, "listen/endpoints")?;
    let connect = tls_endpoints(cfg, "connect/endpoints")?;
    let mutual = get_string(cfg, "enable_mtls")?.is_some_and(|v| v == "true");
    let mut report = TlsReport {
        endpoints: listen || connect,
        mutual,
        files: Vec::new(),
    };
    let mut required: Vec<&str> = Vec::new();
    if listen {
        required.extend(["listen_certificate", "listen_private_key"]);
        if mutual {
            required.push("root_ca_certificate");
        }
    }
    if connect && mutual {
        required.extend(["connect_certificate", "connect_private_key"]);
    }
    for name in [
        "root_ca_certificate",
        "listen_certificate",
        "listen_private_key",
        "connect_certificate",
        "connect_private_key",
    ] {
        let key = format!("{PREFIX}/{name}");
        let inline = get_string(cfg, &format!("{name}_base64"))?.is_some();
        match get_string(cfg, name)? {
            Some(path) => report.files.push(check_file(&key, PathBuf::from(path), name)?),
            None if required.contains(&name) && !inline => {
                return Err(err(
                    key,
                    "missing: a tls/ endpoint with these settings needs it (a PEM file path)",
                ))
            }
            None => {}
        }
    }
    Ok(report)
}

/// Whether any endpoint under `key` (a list, or per mode) is `tls/…`.
fn tls_endpoints(cfg: &zenoh::Config, key: &str) -> Result<bool, ConfigError> {
    let json = cfg.get_json(key).map_err(|e| err(key, e))?;
    let value: serde_json::Value = serde_json::from_str(&json).map_err(|e| err(key, e))?;
    fn any_tls(v: &serde_json::Value) -> bool {
        match v {
            serde_json::Value::String(s) => s.starts_with("tls/"),
            serde_json::Value::Array(a) => a.iter().any(any_tls),
            serde_json::Value::Object(o) => o.values().any(any_tls),
            _ => false,
        }
    }
    Ok(any_tls(&value))
}

/// `transport/link/tls/<name>` as a string (booleans too), if set.
fn get_string(cfg: &zenoh::Config, name: &str) -> Result<Option<String>, ConfigError> {
    let key = format!("{PREFIX}/{name}");
    let json = cfg.get_json(&key).map_err(|e| err(&key, e))?;
    match serde_json::from_str(&json).map_err(|e| err(&key, e))? {
        serde_json::Value::Null => Ok(None),
        serde_json::Value::String(s) => Ok(Some(s)),
        other => Ok(Some(other.to_string())),
    }
}

fn check_file(key: &str, path: PathBuf, name: &str) -> Result<TlsFile, ConfigError> {
    let where_ = |message: String| err(key, format!("{}: {message}", path.display()));
    let bytes = std::fs::read(&path).map_err(|e| where_(format!("cannot read: {e}")))?;
    let mut blocks = Vec::new();
    for pem in Pem::iter_from_buffer(&bytes) {
        blocks.push(pem.map_err(|e| where_(format!("not a PEM file: {e}")))?);
    }
    if name.ends_with("private_key") {
        if !blocks.iter().any(|p| p.label.ends_with("PRIVATE KEY")) {
            return Err(where_("holds no PEM private key".into()));
        }
        return Ok(TlsFile {
            key: key.to_string(),
            path,
            certificate: None,
        });
    }
    let mut first = None;
    for pem in blocks.iter().filter(|p| p.label == "CERTIFICATE") {
        let cert = pem
            .parse_x509()
            .map_err(|e| where_(format!("not a valid X.509 certificate: {e}")))?;
        let summary = validity(&cert).map_err(where_)?;
        first.get_or_insert(summary);
    }
    let Some(summary) = first else {
        return Err(where_("holds no PEM certificate".into()));
    };
    Ok(TlsFile {
        key: key.to_string(),
        path,
        certificate: Some(summary),
    })
}

/// The certificate's subject and expiry; an error if it is not valid now.
fn validity(cert: &x509_parser::certificate::X509Certificate<'_>) -> Result<CertificateSummary, String> {
    let subject = cert.subject().to_string();
    let not_before = cert.validity().not_before.to_datetime();
    let not_after = cert.validity().not_after.to_datetime();
    let now = OffsetDateTime::now_utc();
    if now < not_before {
        return Err(format!(
            "certificate {subject} is not valid before {}",
            not_before.date()
        ));
    }
    if now > not_after {
        return Err(format!("certificate {subject} expired on {}", not_after.date()));
    }
    Ok(CertificateSummary {
        subject,
        not_after,
        days_left: (not_after - now).whole_days(),
    })
}
