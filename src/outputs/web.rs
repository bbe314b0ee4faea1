//! `[web]`: the daemon's read-only status page, from a thread of its own
//! (`tiny_http`): `/` the page (the bridge's last verdict and priority, its
//! last update, monitoring state and event, its health; reloaded by the
//! browser every `refresh_seconds`), `/status.json` the same as JSON, and
//! `/report` the owner's report of what the daemon has written
//! ([`History`]). GET and HEAD only: there is no write path. With a
//! `token_file`, a request without the token gets 401 and nothing else.

use crate::config::{Config, WebConfig};
use crate::outputs::report::history::History;
use crate::outputs::report::html::{self, escape, number};
use crate::outputs::report::Report;
use anyhow::{Context, Result};
use serde_json::{json, Value};
use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

/// What the page shows: the daemon's history and its report, rendered
/// again only after something new was recorded.
struct PageState {
    history: History,
    report: Option<Report>,
    stale: bool,
}

impl PageState {
    fn report(&mut self) -> Option<&Report> {
        if self.stale {
            self.report = self.history.report();
            self.stale = false;
        }
        self.report.as_ref()
    }
}

pub struct StatusPage {
    state: Arc<Mutex<PageState>>,
    address: SocketAddr,
    stop: Arc<AtomicBool>,
    server: Option<JoinHandle<()>>,
}

impl StatusPage {
    /// Binds `[web] listen` and serves until dropped.
    pub fn serve(config: &Config, web: &WebConfig) -> Result<Self> {
        let server = tiny_http::Server::http(&web.listen)
            .map_err(|e| anyhow::anyhow!("{e}"))
            .with_context(|| format!("web: cannot listen on {}", web.listen))?;
        let address = server
            .server_addr()
            .to_ip()
            .context("web: the listener has no IP address")?;
        let state = Arc::new(Mutex::new(PageState {
            history: History::new(config),
            report: None,
            stale: true,
        }));
        let stop = Arc::new(AtomicBool::new(false));
        let settings = Settings {
            token_file: web.token_file.clone(),
            refresh: web.refresh_seconds,
            bridge: config.structure.name.clone(),
        };
        let (thread_state, thread_stop) = (Arc::clone(&state), Arc::clone(&stop));
        let handle = std::thread::Builder::new()
            .name("web".into())
            .spawn(move || serve_loop(&server, &thread_state, &settings, &thread_stop))
            .context("web: cannot start the server thread")?;
        tracing::info!(message = "serving the status page", url = %format!("http://{address}/"));
        Ok(Self {
            state,
            address,
            stop,
            server: Some(handle),
        })
    }

    /// Where it listens (the port chosen when `listen` gave port 0).
    pub fn address(&self) -> SocketAddr {
        self.address
    }

    /// Keeps a results message the daemon wrote.
    pub fn record(&self, suffix: &str, json: &[u8]) {
        let mut state = self.state.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        state.history.record(suffix, json);
        state.stale = true;
    }
}

impl Drop for StatusPage {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(h) = self.server.take() {
            let _ = h.join();
        }
    }
}

struct Settings {
    token_file: Option<PathBuf>,
    refresh: u32,
    bridge: String,
}

impl Settings {
    /// Whether the request carries the token (always, without one).
    fn allows(&self, request: &tiny_http::Request) -> bool {
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
            .iter()
            .find(|h| h.field.equiv("Authorization"))
            .and_then(|h| {
                h.value
                    .as_str()
                    .strip_prefix("Bearer ")
                    .map(str::trim)
                    .map(str::to_string)
            });
        let query = query_token(request.url());
        bearer.as_deref() == Some(token.as_str()) || query.as_deref() == Some(token.as_str())
    }
}

/// The `token` of a URL's query.
fn query_token(url: &str) -> Option<String> {
    url.split_once('?')?
        .1
        .split('&')
        .find_map(|pair| pair.strip_prefix("token=").map(str::to_string))
}

fn header(name: &str, value: &str) -> tiny_http::Header {
    tiny_http::Header::from_bytes(name.as_bytes(), value.as_bytes()).expect("a valid header")
}

fn serve_loop(server: &tiny_http::Server, state: &Mutex<PageState>, settings: &Settings, stop: &AtomicBool) {
    while !stop.load(Ordering::Relaxed) {
        let request = match server.recv_timeout(Duration::from_millis(100)) {
            Ok(Some(r)) => r,
            Ok(None) => continue,
            Err(e) => {
                tracing::warn!(message = "web: a request could not be read", error = %e);
                continue;
            }
        };
        let response = respond(&request, state, settings);
        if let Err(e) = request.respond(response) {
            tracing::debug!(message = "web: the browser went away", error = %e);
        }
    }
}

type Response = tiny_http::Response<std::io::Cursor<Vec<u8>>>;

fn text(status: u16, body: &str) -> Response {
    tiny_http::Response::from_string(body)
        .with_status_code(status)
        .with_header(header("Content-Type", "text/plain; charset=utf-8"))
}

fn respond(request: &tiny_http::Request, state: &Mutex<PageState>, settings: &Settings) -> Response {
    use tiny_http::Method;
    if !matches!(request.method(), Method::Get | Method::Head) {
        return text(405, "read-only: GET and HEAD only\n").with_header(header("Allow", "GET, HEAD"));
    }
    if !settings.allows(request) {
        return text(401, "a token is required\n").with_header(header("WWW-Authenticate", "Bearer"));
    }
    let html = |body: String| {
        tiny_http::Response::from_data(body.into_bytes())
            .with_header(header("Content-Type", "text/html; charset=utf-8"))
            .with_header(header("Cache-Control", "no-store"))
    };
    let token = query_token(request.url());
    let mut state = state.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    match request.url().split('?').next().unwrap_or_default() {
        "/" => html(page(&mut state, settings, token.as_deref())),
        "/status.json" => tiny_http::Response::from_data(status_json(&mut state, settings).to_string().into_bytes())
            .with_header(header("Content-Type", "application/json"))
            .with_header(header("Cache-Control", "no-store")),
        "/report" => match state.report() {
            Some(r) => html(r.html.clone()),
            None => text(404, "no results yet: the report comes with the first update or event\n"),
        },
        _ => text(404, "splinewatch status page: GET /, /status.json, /report\n"),
    }
}

/// The page's figures as JSON: the verdict and priority, the last update,
/// monitoring state and event, the last health message.
fn status_json(state: &mut PageState, settings: &Settings) -> Value {
    let (priority, verdict) = state
        .report()
        .map_or((None, None), |r| (Some(r.priority.label()), Some(r.verdict.clone())));
    let c = state.history.contents();
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

fn page(state: &mut PageState, settings: &Settings, token: Option<&str>) -> String {
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
    let body = format!(
        "<header><p class=\"subtitle\">{} · {} · refreshed every {} s</p><h1>Status</h1></header>\
<div id=\"verdict\" class=\"{class}\" role=\"status\"><span class=\"priority\">{}</span><p id=\"verdict-text\">{}</p></div>{}",
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
