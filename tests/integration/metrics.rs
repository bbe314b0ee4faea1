//! Issue 48: `[metrics]`. A daemon fed the bundled recording over zenoh
//! (loopback) serves `/metrics`: it parses with a Prometheus text parser
//! (`prometheus-parse`), no counter goes down from scrape to scrape while
//! the daemon runs, and the counters equal the health message they come
//! from (the one at `splinewatch_health_time_seconds`) in the results file.

use crate::common::{bundled_blocks, fresh_dir, results_by_topic};
use std::collections::BTreeMap;
use std::path::Path;

/// `name{labels}` → value of every sample of a scrape.
fn scrape(url: &str, bridge: &str) -> (String, BTreeMap<String, f64>) {
    let mut response = ureq::get(url).call().expect("GET /metrics");
    let content_type = response
        .headers()
        .get("content-type")
        .and_then(|v| v.to_str().ok())
        .unwrap_or_default()
        .to_string();
    let text = response.body_mut().read_to_string().unwrap();
    assert!(text.ends_with("# EOF\n"), "OpenMetrics text ends with # EOF");
    let parsed = prometheus_parse::Scrape::parse(text.lines().map(|l| Ok(l.to_string()))).expect("Prometheus text");
    let mut samples = BTreeMap::new();
    for s in parsed.samples {
        let value = match s.value {
            prometheus_parse::Value::Counter(v)
            | prometheus_parse::Value::Gauge(v)
            | prometheus_parse::Value::Untyped(v) => v,
            _ => continue,
        };
        assert_eq!(s.labels.get("bridge"), Some(bridge), "{}", s.metric);
        let mut labels: Vec<String> = s
            .labels
            .iter()
            .filter(|(k, _)| k.as_str() != "bridge")
            .map(|(k, v)| format!("{k}={v}"))
            .collect();
        labels.sort();
        samples.insert(format!("{}{{{}}}", s.metric, labels.join(",")), value);
    }
    (content_type, samples)
}

#[test]
fn issue_48_metrics_parse_never_go_down_and_equal_the_health_message() {
    let dir = fresh_dir("metrics");
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut cfg = splinewatch::config::load_config(&root.join("config/sinello.toml")).unwrap();
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    cfg.metrics = Some(splinewatch::config::MetricsConfig {
        listen: format!("127.0.0.1:{port}"),
    });
    // The status page beside the metrics, behind a token (see `web_page`).
    let web_port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    std::fs::write(dir.join("web-token"), "page-t0ken\n").unwrap();
    cfg.web = Some(splinewatch::config::WebConfig {
        listen: format!("127.0.0.1:{web_port}"),
        token_file: Some(dir.join("web-token")),
        refresh_seconds: 5,
        tls: None,
    });
    let pages = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
    let kept_pages = std::sync::Arc::clone(&pages);
    let url = format!("http://127.0.0.1:{port}/metrics");
    let bridge = cfg.structure.name.clone();
    let scrapes = std::sync::Arc::new(std::sync::Mutex::new(Vec::new()));
    let kept = std::sync::Arc::clone(&scrapes);
    splinewatch::service::demo::run_with_source(cfg, &dir, 20.0, usize::MAX, move |_, publisher| {
        let blocks = bundled_blocks();
        let mut sent = 0;
        for (k, b) in blocks.iter().enumerate() {
            publisher.publish(&b.block)?;
            sent += 1;
            if k % 40 == 0 {
                kept.lock().unwrap().push(scrape(&url, &bridge));
            }
        }
        kept_pages.lock().unwrap().push(web_page(web_port));
        // Two more health ticks (every 10 s) after the last block.
        let until = std::time::Instant::now() + std::time::Duration::from_secs(21);
        while std::time::Instant::now() < until {
            kept.lock().unwrap().push(scrape(&url, &bridge));
            std::thread::sleep(std::time::Duration::from_millis(500));
        }
        Ok(sent)
    })
    .unwrap();
    let scrapes = scrapes.lock().unwrap();
    assert!(scrapes.len() > 40, "{} scrapes", scrapes.len());
    assert_eq!(
        pages.lock().unwrap().len(),
        1,
        "the status page was checked while the daemon ran"
    );
    assert!(
        scrapes[0].0.starts_with("application/openmetrics-text"),
        "{}",
        scrapes[0].0
    );
    // Counters never go down (a series may appear, never vanish).
    for pair in scrapes.windows(2) {
        let (before, after) = (&pair[0].1, &pair[1].1);
        for (name, value) in before.iter().filter(|(n, _)| n.contains("_total")) {
            let now = after.get(name).unwrap_or_else(|| panic!("{name} vanished"));
            assert!(now >= value, "{name} went down: {value} -> {now}");
        }
    }
    let last = &scrapes.last().unwrap().1;
    assert!(last["splinewatch_blocks_accepted_total{}"] > 0.0);
    assert!(last["splinewatch_update_runs_total{}"] > 0.0);
    assert!(
        last.contains_key("splinewatch_update_duration_seconds_count{}"),
        "{last:?}"
    );
    assert!(last["splinewatch_update_duration_seconds_count{}"] >= 1.0);
    assert!(last["splinewatch_result_latency_seconds_count{}"] >= 1.0);
    assert!(last
        .keys()
        .any(|k| k.starts_with("splinewatch_parameter_value{parameter=")));
    // The counters are the health message's at their time.
    let time = last["splinewatch_health_time_seconds{}"];
    let results = results_by_topic(&std::fs::read(dir.join("results.mcap")).unwrap());
    let matching: Vec<&serde_json::Value> = results["health"]
        .iter()
        .filter(|h| {
            let t = splinewatch::io::wire::parse_timestamp(h["time"].as_str().unwrap()).unwrap();
            (t as f64 * 1e-9 - time).abs() < 1e-3
        })
        .collect();
    assert!(!matching.is_empty(), "no health message at {time}");
    let health = matching.last().unwrap();
    for (metric, field) in [
        ("splinewatch_blocks_accepted_total{}", "blocks"),
        ("splinewatch_samples_accepted_total{}", "samples"),
        ("splinewatch_windows_accepted_total{}", "windows_accepted"),
        ("splinewatch_update_runs_total{}", "update_runs"),
        ("splinewatch_update_failures_total{}", "update_failures"),
        ("splinewatch_queue_drops_total{}", "queue_drops"),
        ("splinewatch_gaps_total{}", "gaps"),
        ("splinewatch_segments_total{outcome=accepted}", "segments_accepted"),
        ("splinewatch_segments_total{outcome=rejected}", "segments_rejected"),
    ] {
        assert_eq!(
            last[metric],
            health[field].as_f64().unwrap(),
            "{metric} vs health.{field}"
        );
    }
    for (reason, count) in health["rejected"].as_object().unwrap() {
        assert_eq!(
            last[&format!("splinewatch_rejected_total{{reason={reason}}}")],
            count.as_f64().unwrap()
        );
    }
}

/// One HTTP/1.0 request to the status page on `port`: the status code and
/// the body.
fn http(port: u16, request: &str) -> (u16, String) {
    use std::io::{Read, Write};
    let mut stream = std::net::TcpStream::connect(("127.0.0.1", port)).unwrap();
    stream.write_all(request.as_bytes()).unwrap();
    let mut answer = String::new();
    stream.read_to_string(&mut answer).unwrap();
    let status = answer.split(' ').nth(1).and_then(|c| c.parse().ok()).unwrap_or(0);
    let body = answer.split_once("\r\n\r\n").map_or("", |(_, b)| b).to_string();
    (status, body)
}

/// `[web]`, the daemon's status page, while the daemon runs (after the
/// bundled recording's blocks): nothing without the token; read-only (no
/// method but GET and HEAD); the page, its JSON (the daemon's last update
/// and health) and the owner's report with the token, from a header or the
/// query. Returns the page.
fn web_page(port: u16) -> String {
    let (status, body) = http(port, "GET / HTTP/1.0\r\n\r\n");
    assert_eq!(status, 401, "{body}");
    assert!(!body.contains("verdict"));
    let (status, _) = http(port, "GET /status.json?token=wrong HTTP/1.0\r\n\r\n");
    assert_eq!(status, 401);
    for method in ["POST", "PUT", "DELETE", "PATCH"] {
        let (status, _) = http(
            port,
            &format!("{method} / HTTP/1.0\r\nAuthorization: Bearer page-t0ken\r\nContent-Length: 0\r\n\r\n"),
        );
        assert_eq!(status, 405, "{method}");
    }
    let (status, page) = http(port, "GET / HTTP/1.0\r\nAuthorization: Bearer page-t0ken\r\n\r\n");
    assert_eq!(status, 200, "{page}");
    crate::report::check_page(&page);
    assert!(page.contains("<meta http-equiv=\"refresh\" content=\"5\">"));
    let (status, json) = http(port, "GET /status.json?token=page-t0ken HTTP/1.0\r\n\r\n");
    assert_eq!(status, 200, "{json}");
    let json: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(json["bridge"], "sinello-span2");
    assert!(json["last_update"]["window"].is_u64(), "{json}");
    assert!(json["priority"].is_string() && json["verdict"].is_string(), "{json}");
    let (status, report) = http(port, "GET /report?token=page-t0ken HTTP/1.0\r\n\r\n");
    assert_eq!(status, 200);
    crate::report::check_self_contained(&report);
    page
}

/// `replay --metrics`: the endpoint of a replay, read during its
/// `--metrics-linger`, holds the final health message's counters.
#[test]
fn issue_48_replay_serves_the_final_counters_while_it_lingers() {
    let dir = fresh_dir("metrics-replay");
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let config = dir.join("sinello-metrics.toml");
    let text = std::fs::read_to_string(root.join("config/sinello.toml")).unwrap();
    std::fs::write(&config, format!("{text}\n[metrics]\nlisten = \"127.0.0.1:{port}\"\n")).unwrap();
    let out = dir.join("replay.mcap");
    let child = std::process::Command::new(env!("CARGO_BIN_EXE_splinewatch"))
        .args(["replay", "--config"])
        .arg(&config)
        .arg(root.join("recordings/sinello-demo.mcap"))
        .arg("--out")
        .arg(&out)
        .args(["--metrics", "--metrics-linger", "30"])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let mut child = crate::common::KillOnDrop(Some(child));
    // The results file is complete when the linger begins.
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(120);
    let finished = |p: &Path| std::fs::read(p).is_ok_and(|b| b.ends_with(b"\x89MCAP0\r\n"));
    while !finished(&out) {
        assert!(std::time::Instant::now() < deadline, "the replay did not finish");
        std::thread::sleep(std::time::Duration::from_millis(200));
    }
    let cfg = splinewatch::config::load_config(&config).unwrap();
    let (_, metrics) = scrape(&format!("http://127.0.0.1:{port}/metrics"), &cfg.structure.name);
    let results = results_by_topic(&std::fs::read(&out).unwrap());
    let health = results["health"].last().unwrap();
    for (metric, field) in [
        ("splinewatch_blocks_accepted_total{}", "blocks"),
        ("splinewatch_windows_accepted_total{}", "windows_accepted"),
        ("splinewatch_update_runs_total{}", "update_runs"),
    ] {
        assert_eq!(metrics[metric], health[field].as_f64().unwrap(), "{metric}");
    }
    assert_eq!(
        metrics["splinewatch_update_duration_seconds_count{}"],
        health["update_runs"].as_f64().unwrap()
    );
    assert!(metrics["splinewatch_messages_received_total{}"] >= metrics["splinewatch_blocks_accepted_total{}"]);
    let _ = child.0.as_mut().unwrap().kill();
}

/// The metric families a scrape describes (`# TYPE` lines), with the
/// sample names each allows (`_total`, `_bucket`, `_sum`, `_count`).
fn described_families(text: &str) -> std::collections::BTreeSet<String> {
    let mut names = std::collections::BTreeSet::new();
    for line in text.lines() {
        let mut words = line.split_whitespace();
        if let (Some("#"), Some("TYPE"), Some(name), Some(kind)) =
            (words.next(), words.next(), words.next(), words.next())
        {
            match kind {
                "counter" => {
                    names.insert(format!("{name}_total"));
                }
                "histogram" => {
                    for suffix in ["_bucket", "_sum", "_count"] {
                        names.insert(format!("{name}{suffix}"));
                    }
                }
                _ => {
                    names.insert(name.to_string());
                }
            }
        }
    }
    names
}

/// Every metric the Grafana dashboard (`deploy/grafana/splinewatch.json`,
/// made by `make_dashboard.py` there) queries is one a daemon describes,
/// even before it has anything to say (a fresh process, no monitoring).
#[test]
fn issue_48_the_grafana_dashboard_queries_only_metrics_the_daemon_serves() {
    let metrics = splinewatch::outputs::metrics::Metrics::serve("127.0.0.1:0", "test").unwrap();
    let text = ureq::get(format!("http://{}/metrics", metrics.address()))
        .call()
        .unwrap()
        .body_mut()
        .read_to_string()
        .unwrap();
    let described = described_families(&text);
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dashboard: serde_json::Value =
        serde_json::from_slice(&std::fs::read(root.join("deploy/grafana/splinewatch.json")).unwrap()).unwrap();
    let mut queried = Vec::new();
    let mut exprs: Vec<String> = Vec::new();
    for panel in dashboard["panels"].as_array().unwrap() {
        for target in panel["targets"].as_array().into_iter().flatten() {
            exprs.push(target["expr"].as_str().unwrap().to_string());
        }
    }
    for v in dashboard["templating"]["list"].as_array().unwrap() {
        if let Some(q) = v["query"].as_str().filter(|q| q.starts_with("label_values")) {
            exprs.push(q.to_string());
        }
    }
    for expr in &exprs {
        for (start, _) in expr.match_indices("splinewatch_") {
            let name: String = expr[start..]
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                .collect();
            queried.push(name);
        }
    }
    assert!(queried.len() > 20, "{queried:?}");
    for name in &queried {
        assert!(
            described.contains(name),
            "the dashboard queries {name}, which is not served: {described:?}"
        );
    }
    // And the endpoint answers only GET /metrics.
    let other = ureq::get(format!("http://{}/other", metrics.address())).call();
    assert!(matches!(other, Err(ureq::Error::StatusCode(404))), "{other:?}");
}
