//! `[web]`: the daemon's read-only status page, served by hyper on a thread
//! and runtime of its own: `/` the page (the bridge's last verdict and
//! priority, its last update, monitoring state and event, its health;
//! reloaded by the browser every `refresh_seconds`), `/status.json` the same
//! as JSON, and `/report` the owner's report of what the daemon has written
//! ([`History`]). GET and HEAD only: there is no write path. With a
//! `token_file`, a request without the token gets 401 and nothing else; with
//! `[web.tls]` the page is HTTPS, and with its `client_ca` a client without a
//! certificate that CA signed is refused in the handshake (mutual TLS).

use crate::config::{Config, WebConfig, WebTlsConfig};
use crate::io::results_file::ResultsContents;
use crate::outputs::report::history::{report_of, History};
use crate::outputs::report::html::{self, escape, number};
use crate::outputs::report::Report;
use anyhow::{Context, Result};
use http_body_util::Full;
use hyper::body::Bytes;
use hyper::{Method, Request, Response, StatusCode};
use hyper_util::rt::{TokioIo, TokioTimer};
use serde_json::{json, Value};
use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;
use tokio_rustls::rustls;
use tokio_rustls::rustls::pki_types::pem::PemObject;
use tokio_rustls::rustls::pki_types::{CertificateDer, PrivateKeyDer};

/// How long a client may take for the TLS handshake or a request's headers.
const CLIENT_TIMEOUT: Duration = Duration::from_secs(10);

/// The page's trends: the days before the latest result.
const RECENT_DAYS: f64 = 3.0;

/// What the page shows: the daemon's history, its report and the recent
/// trends, rendered again only after something new was recorded.
struct PageState {
    history: History,
    /// The history as of the last render: the report, the trends and the
    /// figures are all drawn from it, rendered outside the history's lock.
    contents: ResultsContents,
    report: Option<Report>,
    recent: Option<String>,
    /// The history's version they were rendered at.
    rendered: Option<u64>,
}

impl PageState {
    fn refresh(&mut self) {
        if self.rendered != Some(self.history.version()) {
            let (version, contents) = self.history.snapshot();
            self.report = report_of(&contents);
            self.recent = crate::outputs::report::recent_figures(&contents, RECENT_DAYS);
            self.contents = contents;
            self.rendered = Some(version);
        }
    }

    fn report(&mut self) -> Option<&Report> {
        self.refresh();
        self.report.as_ref()
    }
}

pub struct StatusPage {
    address: SocketAddr,
    stop: Option<tokio::sync::oneshot::Sender<()>>,
    server: Option<JoinHandle<()>>,
}

impl StatusPage {
    /// Binds `[web] listen` (and reads `[web.tls]`'s files) and serves
    /// `history` (what the daemon records into it) until dropped.
    pub fn serve(config: &Config, web: &WebConfig, history: History) -> Result<Self> {
        let tls = web.tls.as_ref().map(tls_acceptor).transpose()?;
        let listener = std::net::TcpListener::bind(&web.listen)
            .with_context(|| format!("web: cannot listen on {}", web.listen))?;
        listener.set_nonblocking(true)?;
        let address = listener.local_addr()?;
        let page = Arc::new(Page {
            state: Mutex::new(PageState {
                history,
                contents: ResultsContents::default(),
                report: None,
                recent: None,
                rendered: None,
            }),
            settings: Settings {
                token_file: web.token_file.clone(),
                refresh: web.refresh_seconds,
                bridge: config.structure.name.clone(),
            },
        });
        let runtime = tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()
            .context("web: cannot start the server's runtime")?;
        let (stop, stopped) = tokio::sync::oneshot::channel();
        let scheme = if tls.is_some() { "https" } else { "http" };
        let handle = std::thread::Builder::new()
            .name("web".into())
            .spawn(move || runtime.block_on(accept_loop(listener, tls, page, stopped)))
            .context("web: cannot start the server thread")?;
        tracing::info!(message = "serving the status page", url = %format!("{scheme}://{address}/"));
        Ok(Self {
            address,
            stop: Some(stop),
            server: Some(handle),
        })
    }

    /// Where it listens (the port chosen when `listen` gave port 0).
    pub fn address(&self) -> SocketAddr {
        self.address
    }
}

impl Drop for StatusPage {
    fn drop(&mut self) {
        if let Some(stop) = self.stop.take() {
            let _ = stop.send(());
        }
        if let Some(h) = self.server.take() {
            let _ = h.join();
        }
    }
}

/// The server's TLS from `[web.tls]`: its certificate chain and key, and
/// with `client_ca` a verifier that requires a client certificate that CA
/// signed.
fn tls_acceptor(tls: &WebTlsConfig) -> Result<tokio_rustls::TlsAcceptor> {
    let provider = Arc::new(rustls::crypto::ring::default_provider());
    let chain = CertificateDer::pem_file_iter(&tls.certificate)
        .and_then(Iterator::collect::<Result<Vec<_>, _>>)
        .with_context(|| format!("web.tls.certificate: cannot read {}", tls.certificate.display()))?;
    let key = PrivateKeyDer::from_pem_file(&tls.private_key)
        .with_context(|| format!("web.tls.private_key: cannot read {}", tls.private_key.display()))?;
    let builder = rustls::ServerConfig::builder_with_provider(Arc::clone(&provider))
        .with_safe_default_protocol_versions()
        .context("web.tls: no TLS version in common with the crypto provider")?;
    let builder = match &tls.client_ca {
        None => builder.with_no_client_auth(),
        Some(ca) => {
            let mut roots = rustls::RootCertStore::empty();
            for cert in CertificateDer::pem_file_iter(ca)
                .with_context(|| format!("web.tls.client_ca: cannot read {}", ca.display()))?
            {
                let cert = cert.with_context(|| format!("web.tls.client_ca: {}", ca.display()))?;
                roots
                    .add(cert)
                    .with_context(|| format!("web.tls.client_ca: {}", ca.display()))?;
            }
            let verifier = rustls::server::WebPkiClientVerifier::builder_with_provider(Arc::new(roots), provider)
                .build()
                .with_context(|| format!("web.tls.client_ca: {}", ca.display()))?;
            builder.with_client_cert_verifier(verifier)
        }
    };
    let mut server = builder
        .with_single_cert(chain, key)
        .context("web.tls: the certificate and private key do not make a server identity")?;
    server.alpn_protocols = vec![b"http/1.1".to_vec()];
    Ok(tokio_rustls::TlsAcceptor::from(Arc::new(server)))
}

struct Page {
    state: Mutex<PageState>,
    settings: Settings,
}

/// Accepts connections until `stopped`, each served on a task of its own.
async fn accept_loop(
    listener: std::net::TcpListener,
    tls: Option<tokio_rustls::TlsAcceptor>,
    page: Arc<Page>,
    mut stopped: tokio::sync::oneshot::Receiver<()>,
) {
    let listener = match tokio::net::TcpListener::from_std(listener) {
        Ok(l) => l,
        Err(e) => {
            tracing::error!(message = "web: the listener cannot be used: no status page", error = %e);
            return;
        }
    };
    loop {
        let (stream, peer) = tokio::select! {
            _ = &mut stopped => return,
            accepted = listener.accept() => match accepted {
                Ok(a) => a,
                Err(e) => {
                    tracing::warn!(message = "web: a connection could not be accepted", error = %e);
                    continue;
                }
            },
        };
        let (page, tls) = (Arc::clone(&page), tls.clone());
        tokio::spawn(async move {
            match tls {
                None => serve_connection(TokioIo::new(stream), page).await,
                Some(acceptor) => match tokio::time::timeout(CLIENT_TIMEOUT, acceptor.accept(stream)).await {
                    Ok(Ok(stream)) => serve_connection(TokioIo::new(stream), page).await,
                    Ok(Err(e)) => tracing::info!(message = "web: TLS handshake refused", %peer, error = %e),
                    Err(_) => tracing::info!(message = "web: TLS handshake timed out", %peer),
                },
            }
        });
    }
}

async fn serve_connection<S>(io: TokioIo<S>, page: Arc<Page>)
where
    S: tokio::io::AsyncRead + tokio::io::AsyncWrite + Unpin + Send + 'static,
{
    let service = hyper::service::service_fn(move |request: Request<hyper::body::Incoming>| {
        let page = Arc::clone(&page);
        async move { Ok::<_, std::convert::Infallible>(respond(&request, &page)) }
    });
    let served = hyper::server::conn::http1::Builder::new()
        .timer(TokioTimer::new())
        .header_read_timeout(CLIENT_TIMEOUT)
        .serve_connection(io, service)
        .await;
    if let Err(e) = served {
        tracing::debug!(message = "web: the browser went away", error = %e);
    }
}

struct Settings {
    token_file: Option<PathBuf>,
    refresh: u32,
    bridge: String,
}

impl Settings {
    /// Whether the request carries the token (always, without one).
    fn allows<B>(&self, request: &Request<B>) -> bool {
        let Some(path) = &self.token_file else {
            return true;
        };
        let Some(token) = std::fs::read_to_string(path)
            .ok()
            .and_then(|t| t.lines().next().map(|l| l.trim().to_string()))
            .filter(|t| !t.is_empty())
        else {
            tracing::warn!(message = "web: the token file cannot be read: nothing is served", file = %path.display());
            return false;
        };
        let bearer = request
            .headers()
            .get(hyper::header::AUTHORIZATION)
            .and_then(|v| v.to_str().ok())
            .and_then(|v| v.strip_prefix("Bearer "))
            .map(str::trim);
        let query = request.uri().query().and_then(query_token);
        bearer == Some(token.as_str()) || query.as_deref() == Some(token.as_str())
    }
}

/// The `token` of a URL's query.
fn query_token(query: &str) -> Option<String> {
    query
        .split('&')
        .find_map(|pair| pair.strip_prefix("token=").map(str::to_string))
}

fn reply(status: StatusCode, content_type: &str, body: impl Into<Bytes>) -> Response<Full<Bytes>> {
    let mut response = Response::new(Full::new(body.into()));
    *response.status_mut() = status;
    let headers = response.headers_mut();
    headers.insert(
        hyper::header::CONTENT_TYPE,
        content_type.parse().expect("a valid header value"),
    );
    headers.insert(
        hyper::header::CACHE_CONTROL,
        "no-store".parse().expect("a valid header value"),
    );
    response
}

fn text(status: StatusCode, body: &'static str) -> Response<Full<Bytes>> {
    reply(status, "text/plain; charset=utf-8", body)
}

fn respond<B>(request: &Request<B>, page: &Page) -> Response<Full<Bytes>> {
    let settings = &page.settings;
    if !matches!(*request.method(), Method::GET | Method::HEAD) {
        let mut response = text(StatusCode::METHOD_NOT_ALLOWED, "read-only: GET and HEAD only\n");
        response
            .headers_mut()
            .insert(hyper::header::ALLOW, "GET, HEAD".parse().expect("a valid header value"));
        return response;
    }
    if !settings.allows(request) {
        let mut response = text(StatusCode::UNAUTHORIZED, "a token is required\n");
        response.headers_mut().insert(
            hyper::header::WWW_AUTHENTICATE,
            "Bearer".parse().expect("a valid header value"),
        );
        return response;
    }
    let html = |body: String| reply(StatusCode::OK, "text/html; charset=utf-8", body);
    let token = request.uri().query().and_then(query_token);
    let mut state = page.state.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    match request.uri().path() {
        "/" => html(render_page(&mut state, settings, token.as_deref())),
        "/status.json" => reply(
            StatusCode::OK,
            "application/json",
            status_json(&mut state, settings).to_string(),
        ),
        "/report" => match state.report() {
            Some(r) => html(r.html.clone()),
            None => text(
                StatusCode::NOT_FOUND,
                "no results yet: the report comes with the first update or event\n",
            ),
        },
        _ => text(
            StatusCode::NOT_FOUND,
            "splinewatch status page: GET /, /status.json, /report\n",
        ),
    }
}

/// The page's figures as JSON: the verdict and priority, the last update,
/// monitoring state and event, the last health message.
fn status_json(state: &mut PageState, settings: &Settings) -> Value {
    let (priority, verdict) = state
        .report()
        .map_or((None, None), |r| (Some(r.priority.label()), Some(r.verdict.clone())));
    let c = &state.contents;
    json!({
        "bridge": settings.bridge,
        "prefix": c.prefix,
        "priority": priority,
        "verdict": verdict,
        "last_update": c.updates.last().map(|u| json!({
            "time": u.time, "window": u.window, "converged": u.converged, "relative_residual": u.relative_residual})),
        "monitoring": c.statuses.last().map(|s| json!({
            "time": s.time, "window": s.window, "state": s.state, "t2": s.t2, "t2_limit": s.t2_limit})),
        "last_event": c.events.last().map(|e| json!({
            "event": e.event, "start": e.start, "pga_ground": e.pga_ground,
            "verdict": e.verdict.as_ref().map(|v| v.state.clone()), "skipped": e.skipped})),
        "alarms": c.alarms.iter().filter(|a| a.state == "alarm").count(),
        "health": c.health,
    })
}

fn render_page(state: &mut PageState, settings: &Settings, token: Option<&str>) -> String {
    let status = status_json(state, settings);
    let priority = state.report().map(|r| r.priority);
    let class = priority.map_or("unjudged", |p| p.class());
    let label = priority.map_or("No results yet", |p| p.label());
    let verdict = status["verdict"]
        .as_str()
        .unwrap_or("The daemon has written no update or event yet.");
    let link = |path: &str| match token {
        Some(t) => format!("{path}?token={}", escape(t)),
        None => path.to_string(),
    };
    let cell = |v: &Value| match v {
        Value::Null => "—".to_string(),
        Value::String(s) => escape(s),
        Value::Number(n) if n.is_u64() || n.is_i64() => n.to_string(),
        Value::Number(n) => number(n.as_f64(), 4),
        other => escape(&other.to_string()),
    };
    let mut rows = Vec::new();
    for (what, key, fields) in [
        (
            "last update",
            "last_update",
            &["time", "window", "converged", "relative_residual"][..],
        ),
        ("monitoring", "monitoring", &["state", "time", "t2", "t2_limit"][..]),
        (
            "last event",
            "last_event",
            &["event", "start", "verdict", "pga_ground"][..],
        ),
    ] {
        let values: Vec<String> = fields
            .iter()
            .map(|f| format!("{f}: {}", cell(&status[key][f])))
            .collect();
        rows.push(vec![what.to_string(), values.join(" · ")]);
    }
    let health = &status["health"];
    let counters: Vec<String> = [
        "blocks",
        "windows_accepted",
        "update_runs",
        "update_failures",
        "queue_drops",
        "gaps",
        "results_errors",
    ]
    .iter()
    .map(|k| format!("{k}: {}", cell(&health[k])))
    .collect();
    rows.push(vec!["health".into(), counters.join(" · ")]);
    rows.push(vec!["health reported".into(), cell(&health["time"])]);
    state.refresh();
    let recent = state.recent.as_deref().map_or(String::new(), |figures| {
        format!(
            "<h2 id=\"recent\">The last {RECENT_DAYS} days</h2><p>Before the latest result; the whole record is in the report.</p>{figures}"
        )
    });
    let body = format!(
        "<header><p class=\"subtitle\">{} · {} · refreshed every {} s</p><h1>Status</h1></header>\
<div id=\"verdict\" class=\"{class}\" role=\"status\"><span class=\"priority\">{}</span><p id=\"verdict-text\">{}</p></div>{}{recent}",
        escape(&settings.bridge),
        escape(status["prefix"].as_str().unwrap_or_default()),
        settings.refresh,
        escape(label),
        escape(verdict),
        html::section(
            "now",
            "Now",
            &format!(
                "{}<p><a id=\"report-link\" href=\"{}\">The owner's report of what this daemon has written</a> · \
<a href=\"{}\">as JSON</a></p>",
                html::table("status-table", "The daemon's latest results", &["", "latest"], &rows),
                link("/report"),
                link("/status.json")
            ),
        )
    );
    html::refreshing_page(&format!("{} status", settings.bridge), &body, Some(settings.refresh))
}

#[cfg(test)]
mod tests {
    use super::*;
    use rcgen::{BasicConstraints, CertificateParams, CertifiedIssuer, DnType, IsCa, KeyPair, KeyUsagePurpose};
    use std::path::Path;
    use tokio::io::{AsyncReadExt, AsyncWriteExt};

    /// A site CA and another CA, made now: `ca.pem`, `server.{pem,key}` for
    /// localhost and 127.0.0.1, `client.{pem,key}` signed by the site CA,
    /// `stranger.{pem,key}` signed by the other.
    fn make_pki(dir: &Path) {
        let ca = |name: &str| {
            let mut p = CertificateParams::new(Vec::<String>::new()).unwrap();
            p.is_ca = IsCa::Ca(BasicConstraints::Unconstrained);
            p.distinguished_name.push(DnType::CommonName, name);
            p.key_usages = vec![KeyUsagePurpose::KeyCertSign, KeyUsagePurpose::CrlSign];
            CertifiedIssuer::self_signed(p, KeyPair::generate().unwrap()).unwrap()
        };
        let leaf = |issuer: &CertifiedIssuer<'_, KeyPair>, name: &str, hosts: Vec<String>| {
            let mut p = CertificateParams::new(hosts).unwrap();
            p.distinguished_name.push(DnType::CommonName, name);
            let key = KeyPair::generate().unwrap();
            let cert = p.signed_by(&key, issuer).unwrap();
            std::fs::write(dir.join(format!("{name}.pem")), cert.pem()).unwrap();
            std::fs::write(dir.join(format!("{name}.key")), key.serialize_pem()).unwrap();
        };
        let site = ca("site CA");
        std::fs::write(dir.join("ca.pem"), site.pem()).unwrap();
        leaf(&site, "server", vec!["localhost".into(), "127.0.0.1".into()]);
        leaf(&site, "client", vec![]);
        leaf(&ca("another CA"), "stranger", vec![]);
    }

    /// One request over TLS (the site CA trusted, `identity` presented):
    /// the server's whole answer, or why there was none.
    fn request_over_tls(
        address: SocketAddr,
        dir: &Path,
        identity: Option<&str>,
        request: &str,
    ) -> Result<String, String> {
        let provider = Arc::new(rustls::crypto::ring::default_provider());
        let mut roots = rustls::RootCertStore::empty();
        for cert in CertificateDer::pem_file_iter(dir.join("ca.pem")).unwrap() {
            roots.add(cert.unwrap()).unwrap();
        }
        let builder = rustls::ClientConfig::builder_with_provider(provider)
            .with_safe_default_protocol_versions()
            .unwrap()
            .with_root_certificates(roots);
        let client = match identity {
            None => builder.with_no_client_auth(),
            Some(name) => {
                let chain = CertificateDer::pem_file_iter(dir.join(format!("{name}.pem")))
                    .unwrap()
                    .collect::<Result<Vec<_>, _>>()
                    .unwrap();
                let key = PrivateKeyDer::from_pem_file(dir.join(format!("{name}.key"))).unwrap();
                builder.with_client_auth_cert(chain, key).unwrap()
            }
        };
        let connector = tokio_rustls::TlsConnector::from(Arc::new(client));
        let runtime = tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .build()
            .unwrap();
        runtime.block_on(async {
            let tcp = tokio::net::TcpStream::connect(address)
                .await
                .map_err(|e| e.to_string())?;
            let name = rustls::pki_types::ServerName::try_from("localhost").unwrap();
            let mut tls = connector.connect(name, tcp).await.map_err(|e| e.to_string())?;
            tls.write_all(request.as_bytes()).await.map_err(|e| e.to_string())?;
            let mut answer = String::new();
            tls.read_to_string(&mut answer).await.map_err(|e| e.to_string())?;
            if answer.is_empty() {
                return Err("no answer".into());
            }
            Ok(answer)
        })
    }

    #[test]
    fn with_a_client_ca_only_its_clients_are_served_and_nothing_can_be_written() {
        let dir = tempfile::tempdir().unwrap();
        make_pki(dir.path());
        let config_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("config/sinello.toml");
        let config = Config::from_toml(&std::fs::read_to_string(config_path).unwrap()).unwrap();
        let web = WebConfig {
            listen: "127.0.0.1:0".into(),
            tls: Some(WebTlsConfig {
                certificate: dir.path().join("server.pem"),
                private_key: dir.path().join("server.key"),
                client_ca: Some(dir.path().join("ca.pem")),
            }),
            ..WebConfig::default()
        };
        web.check(None).unwrap();
        let page = StatusPage::serve(&config, &web, History::new(&config)).unwrap();
        let get =
            |identity: Option<&str>, request: &str| request_over_tls(page.address(), dir.path(), identity, request);

        let answer = get(Some("client"), "GET /status.json HTTP/1.0\r\n\r\n").unwrap();
        assert!(answer.starts_with("HTTP/1.0 200"), "{answer}");
        assert!(answer.contains("\"bridge\":\"sinello-span2\""), "{answer}");
        let answer = get(Some("client"), "GET / HTTP/1.0\r\n\r\n").unwrap();
        assert!(answer.contains("<h1>Status</h1>"), "{answer}");
        for method in ["POST", "PUT", "DELETE", "PATCH"] {
            let answer = get(
                Some("client"),
                &format!("{method} / HTTP/1.0\r\nContent-Length: 0\r\n\r\n"),
            )
            .unwrap();
            assert!(answer.starts_with("HTTP/1.0 405"), "{method}: {answer}");
        }
        // Without a certificate, or with one another CA signed: no answer at
        // all (the handshake or the first read fails), not even a 401.
        for identity in [None, Some("stranger")] {
            let refused = get(identity, "GET /status.json HTTP/1.0\r\n\r\n");
            assert!(refused.is_err(), "{identity:?} was served: {refused:?}");
        }
        // The server is still up for its own clients after refusing others.
        assert!(get(Some("client"), "GET /status.json HTTP/1.0\r\n\r\n")
            .unwrap()
            .starts_with("HTTP/1.0 200"));
    }

    #[test]
    fn tls_files_are_checked_by_what_they_hold() {
        let dir = tempfile::tempdir().unwrap();
        make_pki(dir.path());
        let with = |certificate: &str, private_key: &str| WebConfig {
            listen: "0.0.0.0:9465".into(),
            tls: Some(WebTlsConfig {
                certificate: dir.path().join(certificate),
                private_key: dir.path().join(private_key),
                client_ca: Some(dir.path().join("ca.pem")),
            }),
            ..WebConfig::default()
        };
        // Off loopback, client certificates stand in for the token.
        with("server.pem", "server.key").check(None).unwrap();
        let swapped = with("server.key", "server.pem").check(None).unwrap_err().to_string();
        assert!(
            swapped.contains("web.tls.certificate") && swapped.contains("no PEM CERTIFICATE"),
            "{swapped}"
        );
        let missing = with("server.pem", "absent.key").check(None).unwrap_err().to_string();
        assert!(
            missing.contains("web.tls.private_key") && missing.contains("absent.key"),
            "{missing}"
        );
        let open = WebConfig {
            listen: "0.0.0.0:9465".into(),
            ..WebConfig::default()
        };
        let refused = open.check(None).unwrap_err().to_string();
        assert!(
            refused.contains("token_file") && refused.contains("client_ca"),
            "{refused}"
        );
    }
}
