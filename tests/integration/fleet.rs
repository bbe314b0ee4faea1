//! A fleet of spans: three daemons (each its own `structure.name`) as
//! clients of one zenoh router, each fed by its own logger; `splinewatch
//! fleet` lists every span from the daemons' `latest` queryables. Real
//! router, daemon processes and publishers on loopback.

use splinewatch::config::ZenohConfig;
use splinewatch::outputs::state::load_state;
use std::path::Path;
use std::time::{Duration, Instant};
use zenoh::Wait;

use crate::common::{free_endpoint, fresh_dir, publish_bundled, spawn_daemon, terminate, wait_for_file};

const SPANS: [&str; 3] = ["span-a", "span-b", "span-c"];

fn fleet(endpoint: &str, json: bool) -> (bool, String, String) {
    let mut command = std::process::Command::new(env!("CARGO_BIN_EXE_splinewatch"));
    command.args(["fleet", "--connect", endpoint]);
    if json {
        command.arg("--json");
    }
    let out = command.output().unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn fleet_lists_every_span_behind_one_router() {
    let dir = fresh_dir("fleet");
    let endpoint = free_endpoint();
    let mut rc = zenoh::Config::default();
    rc.insert_json5("mode", "\"router\"").unwrap();
    rc.insert_json5("listen/endpoints", &format!("[\"{endpoint}\"]"))
        .unwrap();
    rc.insert_json5("scouting/multicast/enabled", "false").unwrap();
    let router = zenoh::open(rc).wait().unwrap();

    // Nobody there yet: a clear error, not an empty success.
    let (ok, _, stderr) = fleet(&endpoint, false);
    assert!(!ok && stderr.contains("no span answered"), "{stderr}");

    let bundled = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("config/sinello.toml")).unwrap();
    let mut daemons = Vec::new();
    for span in SPANS {
        let text = bundled.replacen("name = \"sinello-span2\"", &format!("name = \"{span}\""), 1)
            + &format!("\n[zenoh]\nmode = \"client\"\nconnect = [\"{endpoint}\"]\n");
        let config = dir.join(format!("{span}.toml"));
        std::fs::write(&config, text).unwrap();
        let log = std::fs::File::create(dir.join(format!("{span}.log"))).unwrap();
        let state = dir.join(format!("{span}-state.json"));
        let results = dir.join(format!("{span}.mcap"));
        daemons.push((
            span,
            state.clone(),
            spawn_daemon(&config, &state, &results, "info", log.into()),
        ));
    }
    std::thread::sleep(Duration::from_millis(1500));
    // One logger per span, all at once.
    std::thread::scope(|s| {
        for span in SPANS {
            let endpoint = endpoint.clone();
            s.spawn(move || {
                let zenoh = ZenohConfig {
                    mode: "client".into(),
                    listen: Vec::new(),
                    connect: vec![endpoint],
                    ..ZenohConfig::default()
                };
                publish_bundled(&zenoh, format!("bridge/{span}"));
            });
        }
    });
    for (span, state, _) in &daemons {
        assert!(wait_for_file(state), "{span} never updated");
    }

    // Every span has updated and reported its health (every 10 s).
    let deadline = Instant::now() + Duration::from_secs(40);
    let lines = loop {
        let (ok, stdout, stderr) = fleet(&endpoint, true);
        assert!(ok, "{stderr}");
        let lines: Vec<serde_json::Value> = stdout.lines().map(|l| serde_json::from_str(l).unwrap()).collect();
        let reported = lines.iter().filter(|l| !l["latest"]["health"].is_null()).count();
        if reported == SPANS.len() || Instant::now() > deadline {
            break lines;
        }
        std::thread::sleep(Duration::from_millis(500));
    };
    let (ok, text, stderr) = fleet(&endpoint, false);
    assert!(ok, "{stderr}");
    eprintln!("splinewatch fleet --connect {endpoint}\n{text}");

    // A span whose daemon is alive but answers nothing (a token without
    // queryables), and one expected that is not running: both reported by
    // name, the exit status 1; the answering spans still listed.
    let mute = zenoh::open({
        let mut c = zenoh::Config::default();
        c.insert_json5("mode", "\"client\"").unwrap();
        c.insert_json5("connect/endpoints", &format!("[\"{endpoint}\"]"))
            .unwrap();
        c.insert_json5("scouting/multicast/enabled", "false").unwrap();
        c
    })
    .wait()
    .unwrap();
    let token = mute
        .liveliness()
        .declare_token("bridge/span-mute/alive")
        .wait()
        .unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_splinewatch"))
        .args([
            "fleet",
            "--connect",
            &endpoint,
            "--expect",
            "span-gone",
            "--expect",
            "span-a",
            "--report",
            dir.join("fleet.html").to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    assert!(!out.status.success(), "{stdout}");
    assert!(stdout.lines().any(|l| l == "span-mute  no reply"), "{stdout}");
    assert!(stdout.lines().any(|l| l == "span-gone  not running"), "{stdout}");
    assert_eq!(
        stdout.lines().filter(|l| l.contains("health: ok")).count(),
        SPANS.len(),
        "{stdout}"
    );
    assert!(stderr.contains("span-gone, span-mute did not answer"), "{stderr}");
    // The fleet's page, written although two spans did not answer: the
    // silent ones first (to review), then the three answering spans (not
    // judged: the bundled config has no [monitoring]), by name.
    let page = std::fs::read_to_string(dir.join("fleet.html")).unwrap();
    crate::report::check_page(&page);
    let order: Vec<usize> = ["span-gone", "span-mute", "span-a", "span-b", "span-c"]
        .iter()
        .map(|n| {
            page.find(&format!("<td>{n}</td>"))
                .unwrap_or_else(|| panic!("{n} in the page"))
        })
        .collect();
    assert!(order.windows(2).all(|w| w[0] < w[1]), "{order:?}");
    assert!(
        stderr.contains("Medium: review: 5 spans: 2 to review, 3 not judged."),
        "{stderr}"
    );
    token.undeclare().wait().unwrap();
    mute.close().wait().unwrap();

    let mut statuses = Vec::new();
    for (span, state, daemon) in daemons {
        let (status, _) = terminate(daemon.take());
        statuses.push(status);
        let state = load_state(&state).unwrap().unwrap();
        // The span's line holds its daemon's latest parameters, as saved.
        let line = lines
            .iter()
            .find(|l| l["summary"]["name"] == span)
            .unwrap_or_else(|| panic!("{span} missing from {lines:?}"));
        let summary = &line["summary"];
        let parameters = summary["parameters"].as_array().unwrap();
        assert_eq!(parameters.len(), state.parameters.len(), "{span}");
        for (p, saved) in parameters.iter().zip(&state.parameters) {
            assert_eq!(p["name"], saved.name.as_str(), "{span}");
            assert_eq!(p["value"].as_f64().unwrap(), saved.value, "{span}: {p}");
        }
        assert!(summary["last_update"].is_string(), "{span}: {summary}");
        assert_eq!(summary["health"], "ok", "{span}: {line}");
        assert!(summary["monitoring"].is_null(), "{span} has no [monitoring]");
        let text_line = text.lines().find(|l| l.starts_with(&format!("{span}  "))).unwrap();
        assert!(
            text_line.contains("updated ") && text_line.contains("west.k1=") && text_line.contains("health: ok"),
            "{text_line}"
        );
    }
    assert_eq!(lines.len(), SPANS.len(), "{lines:?}");
    assert_eq!(text.lines().count(), SPANS.len(), "{text}");
    assert!(statuses.iter().all(|s| s.success()), "{statuses:?}");
    router.close().wait().unwrap();
}
