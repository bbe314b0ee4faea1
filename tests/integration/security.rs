//! Transport security with the example zenoh configurations of
//! `config/zenoh/`: a router with user/password authentication and access
//! control, the daemon and a logger as authenticated clients, a dashboard
//! that may only read results. Real sessions on loopback, the real binary.

use splinewatch::config::load_config;
use splinewatch::config::ZenohConfig;
use splinewatch::io::wire::Encoding;
use splinewatch::outputs::publisher::Publisher;
use splinewatch::outputs::state::load_state;
use std::path::{Path, PathBuf};
use std::time::Duration;
use zenoh::Wait;

use crate::common::{bundled_blocks, free_endpoint, fresh_dir, spawn_daemon, terminate, wait_for_file};

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

const PREFIX: &str = "bridge/sinello-span2";

/// A session from one of the example files, pointed at `endpoint`, with
/// `user`'s credentials replaced by `password`.
fn client_config(file: &str, endpoint: &str, user: &str, password: &str) -> zenoh::Config {
    let mut c = zenoh::Config::from_file(root().join("config/zenoh").join(file)).unwrap();
    c.insert_json5("connect/endpoints", &format!("[\"{endpoint}\"]"))
        .unwrap();
    c.insert_json5("transport/auth/usrpwd/user", &format!("\"{user}\""))
        .unwrap();
    c.insert_json5("transport/auth/usrpwd/password", &format!("\"{password}\""))
        .unwrap();
    c
}

/// A copy of one of the example files in `dir/name` with `user`'s
/// credentials, for a process or a [`ZenohConfig`] (which add the endpoint).
fn client_file(dir: &Path, name: &str, file: &str, user: &str, password: &str) -> PathBuf {
    let text = std::fs::read_to_string(root().join("config/zenoh").join(file)).unwrap();
    let start = text.find("usrpwd: {").expect("an usrpwd section");
    let end = start + text[start..].find('}').unwrap() + 1;
    let text = format!(
        "{}usrpwd: {{ user: {user:?}, password: {password:?} }}{}",
        &text[..start],
        &text[end..]
    );
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn authenticated_clients_and_access_control_keep_forged_data_out() {
    let dir = fresh_dir("security");
    let endpoint = free_endpoint();

    // The router exactly as in config/zenoh/router-acl.json5, with a test
    // endpoint and a user file holding test passwords.
    let users = dir.join("users.txt");
    std::fs::write(
        &users,
        "logger:pw-logger\nsplinewatch:pw-daemon\ndashboard:pw-dashboard\n",
    )
    .unwrap();
    let mut rc = zenoh::Config::from_file(root().join("config/zenoh/router-acl.json5")).unwrap();
    rc.insert_json5("listen/endpoints", &format!("[\"{endpoint}\"]"))
        .unwrap();
    rc.insert_json5(
        "transport/auth/usrpwd/dictionary_file",
        &format!("{:?}", users.to_str().unwrap()),
    )
    .unwrap();
    let router = zenoh::open(rc).wait().unwrap();

    // A wrong password or an unknown user cannot even connect.
    for (user, password) in [("splinewatch", "guess"), ("mallory", "pw-daemon")] {
        let c = client_config("splinewatch-client.json5", &endpoint, user, password);
        assert!(zenoh::open(c).wait().is_err(), "{user}/{password} was let in");
    }

    // The daemon, authenticated as `splinewatch` through its config_file.
    let zenoh_file = client_file(
        &dir,
        "daemon-zenoh.json5",
        "splinewatch-client.json5",
        "splinewatch",
        "pw-daemon",
    );
    let text = std::fs::read_to_string(root().join("config/sinello.toml")).unwrap()
        + &format!(
            "\n[zenoh]\nmode = \"client\"\nconnect = [\"{endpoint}\"]\nconfig_file = {:?}\n",
            zenoh_file.to_str().unwrap()
        );
    let config = dir.join("config.toml");
    std::fs::write(&config, text).unwrap();
    let state = dir.join("state.json");
    let results = dir.join("results.mcap");
    // Everything at debug level, to a file (a pipe could fill and stall it).
    let log_file = std::fs::File::create(dir.join("daemon.log")).unwrap();
    let daemon = spawn_daemon(&config, &state, &results, "debug", log_file.into());

    // The dashboard reads the results.
    let dashboard = zenoh::open(client_config(
        "splinewatch-client.json5",
        &endpoint,
        "dashboard",
        "pw-dashboard",
    ))
    .wait()
    .unwrap();
    let parameters = dashboard
        .declare_subscriber(format!("{PREFIX}/updating/parameters"))
        .wait()
        .unwrap();
    std::thread::sleep(Duration::from_millis(1500));

    let cfg = load_config(&config).unwrap();
    let blocks = bundled_blocks();
    let zenoh_as = |user: &str, password: &str| ZenohConfig {
        mode: "client".into(),
        connect: vec![endpoint.clone()],
        config_file: Some(client_file(
            &dir,
            &format!("{user}.json5"),
            "logger-client.json5",
            user,
            password,
        )),
        ..ZenohConfig::default()
    };
    // The dashboard, authenticated but not a logger, forges measurements
    // (valid blocks, a minute before the real ones) and a result: the
    // router drops them.
    let mut forger = Publisher::open(
        &zenoh_as("dashboard", "pw-dashboard"),
        cfg.topic_prefix(),
        Encoding::Cbor,
        0.0,
    )
    .unwrap();
    for b in blocks.iter().take(26) {
        let mut forged = b.block.clone();
        forged.start_ns -= 60_000_000_000;
        forger.publish(&forged).unwrap();
    }
    forger
        .publish_json("updating/parameters", br#"{"forged": true}"#.to_vec())
        .unwrap();
    forger.close().unwrap();

    // The logger publishes the recording.
    let mut logger = Publisher::open(
        &zenoh_as("logger", "pw-logger"),
        cfg.topic_prefix(),
        Encoding::Cbor,
        20.0,
    )
    .unwrap();
    // A logger may not publish results either.
    logger
        .publish_json("updating/parameters", br#"{"forged": true}"#.to_vec())
        .unwrap();
    // A garbled measurement from the logger gets through the router and is
    // rejected (and logged) by the daemon.
    logger.publish_json("accel/P3", b"{garbled".to_vec()).unwrap();
    for b in &blocks {
        logger.publish(&b.block).unwrap();
    }
    logger.close().unwrap();

    wait_for_file(&state);
    // The dashboard may query the latest result.
    let replies: Vec<_> = dashboard
        .get(format!("{PREFIX}/updating/latest"))
        .wait()
        .unwrap()
        .into_iter()
        .collect();

    let (status, _) = terminate(daemon.take());
    let log = std::fs::read_to_string(dir.join("daemon.log")).unwrap();
    assert!(status.success(), "{log}");
    assert!(state.exists(), "no update through the secured router\n{log}");
    assert_eq!(load_state(&state).unwrap().unwrap().parameters.len(), 15);

    // Exactly the logger's blocks reached the daemon: none of the forged ones.
    let results_bytes = std::fs::read(&results).unwrap();
    let last_health = mcap::MessageStream::new(&results_bytes)
        .unwrap()
        .map(|m| m.unwrap())
        .filter(|m| m.channel.topic == format!("{PREFIX}/health"))
        .last()
        .expect("a health message");
    let health: serde_json::Value = serde_json::from_slice(&last_health.data).unwrap();
    assert_eq!(health["blocks"].as_u64().unwrap(), blocks.len() as u64, "{health}");
    assert_eq!(health["rejected"], serde_json::json!({"malformed": 1}), "{health}");
    assert!(
        log.contains("input rejected since the last report"),
        "the rejection was not logged"
    );

    // The dashboard got the daemon's parameters and none of the forged ones.
    let received: Vec<serde_json::Value> = parameters
        .drain()
        .map(|s| serde_json::from_slice(&s.payload().to_bytes()).unwrap())
        .collect();
    assert!(!received.is_empty(), "the dashboard received no parameters");
    assert!(received
        .iter()
        .all(|v| v.get("forged").is_none() && v["parameters"].is_array()));
    let reply = replies.first().expect("a reply to the latest query").result().unwrap();
    let latest: serde_json::Value = serde_json::from_slice(&reply.payload().to_bytes()).unwrap();
    assert!(latest["parameters"].is_array(), "{latest}");

    // No password in the daemon's log, even at debug level (zenoh's own
    // debug output included).
    assert!(
        log.lines().any(|l| l.contains("DEBUG") && l.contains("zenoh")),
        "debug logging was off"
    );
    for secret in ["pw-daemon", "pw-logger", "pw-dashboard"] {
        assert!(!log.contains(secret), "the log shows a password");
    }
    eprintln!(
        "security: 2 bad logins refused, 28 forged messages dropped, {} blocks and {} results delivered",
        blocks.len(),
        received.len()
    );
    dashboard.close().wait().unwrap();
    router.close().wait().unwrap();
    let _ = std::fs::remove_dir_all(&dir);
}
