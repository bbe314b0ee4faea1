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
const ROLES: [&str; 3] = ["logger", "splinewatch", "dashboard"];

/// How the site's clients prove who they are.
enum Transport {
    /// TCP with user/password: config/zenoh/router-acl.json5 and the
    /// `*-client.json5` files; passwords `pw-<role>`.
    Password,
    /// Mutual TLS: config/zenoh/router-tls.json5 and the `*-client-tls.json5`
    /// files with certificates made here (`pki`).
    MutualTls { pki: PathBuf },
}

impl Transport {
    fn endpoint(&self) -> String {
        let tcp = free_endpoint();
        match self {
            Transport::Password => tcp,
            Transport::MutualTls { .. } => tcp.replacen("tcp/", "tls/", 1),
        }
    }

    /// The router exactly as in its example file, with a test endpoint and
    /// test credentials (a user file, or the test PKI's files).
    fn router(&self, dir: &Path, endpoint: &str) -> zenoh::Config {
        let file = match self {
            Transport::Password => "router-acl.json5",
            Transport::MutualTls { .. } => "router-tls.json5",
        };
        let mut rc = zenoh::Config::from_file(root().join("config/zenoh").join(file)).unwrap();
        rc.insert_json5("listen/endpoints", &format!("[\"{endpoint}\"]"))
            .unwrap();
        match self {
            Transport::Password => {
                let users = dir.join("users.txt");
                let lines: String = ROLES.iter().map(|r| format!("{r}:pw-{r}\n")).collect();
                std::fs::write(&users, lines).unwrap();
                rc.insert_json5("transport/auth/usrpwd/dictionary_file", &json_path(&users))
                    .unwrap();
            }
            Transport::MutualTls { pki } => {
                for (key, file) in [
                    ("root_ca_certificate", "ca.pem"),
                    ("listen_certificate", "router.pem"),
                    ("listen_private_key", "router.key"),
                ] {
                    rc.insert_json5(&format!("transport/link/tls/{key}"), &json_path(&pki.join(file)))
                        .unwrap();
                }
            }
        }
        rc
    }

    /// A copy of `role`'s example client file in `dir`, with its test
    /// credentials, for a process or a [`ZenohConfig`] (which add the endpoint).
    fn client_file(&self, dir: &Path, role: &str) -> PathBuf {
        let text = match self {
            Transport::Password => {
                let example = if role == "logger" {
                    "logger-client.json5"
                } else {
                    "splinewatch-client.json5"
                };
                let text = std::fs::read_to_string(root().join("config/zenoh").join(example)).unwrap();
                let start = text.find("usrpwd: {").expect("an usrpwd section");
                let end = start + text[start..].find('}').unwrap() + 1;
                format!(
                    "{}usrpwd: {{ user: {role:?}, password: \"pw-{role}\" }}{}",
                    &text[..start],
                    &text[end..]
                )
            }
            Transport::MutualTls { pki } => {
                let example = format!("{role}-client-tls.json5");
                let text = std::fs::read_to_string(root().join("config/zenoh").join(example)).unwrap();
                // "/etc/<who>/tls/<file>" → "<pki>/<file>".
                let folder = format!("/etc/{}/tls/", if role == "splinewatch" { "splinewatch" } else { role });
                assert!(text.contains(&folder), "{role}'s example names {folder}");
                text.replace(&folder, &format!("{}/", pki.display()))
            }
        };
        let path = dir.join(format!("{role}-client.json5"));
        std::fs::write(&path, text).unwrap();
        path
    }

    /// A session of `role` pointed at `endpoint`.
    fn client(&self, dir: &Path, role: &str, endpoint: &str) -> zenoh::Config {
        let mut c = zenoh::Config::from_file(self.client_file(dir, role)).unwrap();
        c.insert_json5("connect/endpoints", &format!("[\"{endpoint}\"]"))
            .unwrap();
        c
    }

    /// Clients the router must refuse, each with what is wrong with it.
    fn intruders(&self, dir: &Path, endpoint: &str) -> Vec<(&'static str, zenoh::Config)> {
        let tls = |c: &mut zenoh::Config, key: &str, value: String| {
            c.insert_json5(&format!("transport/link/tls/{key}"), &value).unwrap();
        };
        match self {
            Transport::Password => {
                let mut wrong = self.client(dir, "splinewatch", endpoint);
                wrong
                    .insert_json5("transport/auth/usrpwd/password", "\"guess\"")
                    .unwrap();
                let mut unknown = self.client(dir, "splinewatch", endpoint);
                unknown
                    .insert_json5("transport/auth/usrpwd/user", "\"mallory\"")
                    .unwrap();
                vec![("a wrong password", wrong), ("an unknown user", unknown)]
            }
            Transport::MutualTls { pki } => {
                let mut none = self.client(dir, "logger", endpoint);
                tls(&mut none, "enable_mtls", "false".into());
                let mut other_ca = self.client(dir, "logger", endpoint);
                tls(
                    &mut other_ca,
                    "connect_certificate",
                    json_path(&pki.join("other-ca/logger.pem")),
                );
                tls(
                    &mut other_ca,
                    "connect_private_key",
                    json_path(&pki.join("other-ca/logger.key")),
                );
                let mut expired = self.client(dir, "logger", endpoint);
                tls(
                    &mut expired,
                    "connect_certificate",
                    json_path(&pki.join("expired/logger.pem")),
                );
                tls(
                    &mut expired,
                    "connect_private_key",
                    json_path(&pki.join("expired/logger.key")),
                );
                // The client checks the router too: trusting another CA (and
                // the web PKI's roots) it refuses the router.
                let mut untrusting = self.client(dir, "logger", endpoint);
                tls(
                    &mut untrusting,
                    "root_ca_certificate",
                    json_path(&pki.join("other-ca/ca.pem")),
                );
                vec![
                    ("no client certificate", none),
                    ("a certificate from another CA", other_ca),
                    ("an expired certificate", expired),
                    ("a client that trusts another CA", untrusting),
                ]
            }
        }
    }

    /// What must never appear in a log.
    fn secrets(&self) -> Vec<String> {
        match self {
            Transport::Password => ROLES.iter().map(|r| format!("pw-{r}")).collect(),
            Transport::MutualTls { pki } => ROLES
                .iter()
                .map(|r| {
                    let key = std::fs::read_to_string(pki.join(format!("{r}.key"))).unwrap();
                    key.lines().nth(1).unwrap().to_string()
                })
                .collect(),
        }
    }
}

fn json_path(path: &Path) -> String {
    format!("{:?}", path.to_str().unwrap())
}

/// A site PKI made now in `dir`: `ca.pem`; `router.{pem,key}` for 127.0.0.1
/// and localhost; `<role>.{pem,key}` with CN = role; `other-ca/logger.*`
/// from an unrelated CA (`other-ca/ca.pem`); `expired/logger.*` from the site CA, expired.
fn make_test_pki(dir: &Path) {
    use rcgen::{BasicConstraints, CertificateParams, CertifiedIssuer, DnType, IsCa, KeyPair, KeyUsagePurpose};
    let ca = |name: &str| {
        let mut p = CertificateParams::new(Vec::<String>::new()).unwrap();
        p.is_ca = IsCa::Ca(BasicConstraints::Unconstrained);
        p.distinguished_name.push(DnType::CommonName, name);
        p.key_usages = vec![KeyUsagePurpose::KeyCertSign, KeyUsagePurpose::CrlSign];
        CertifiedIssuer::self_signed(p, KeyPair::generate().unwrap()).unwrap()
    };
    let leaf = |issuer: &CertifiedIssuer<'_, KeyPair>, folder: &Path, cn: &str, expired: bool| {
        let names = if cn == "router" {
            vec!["localhost".to_string(), "127.0.0.1".to_string()]
        } else {
            vec![]
        };
        let mut p = CertificateParams::new(names).unwrap();
        p.distinguished_name.push(DnType::CommonName, cn);
        if expired {
            p.not_before = time::OffsetDateTime::now_utc() - time::Duration::days(30);
            p.not_after = time::OffsetDateTime::now_utc() - time::Duration::days(1);
        }
        let key = KeyPair::generate().unwrap();
        let cert = p.signed_by(&key, issuer).unwrap();
        std::fs::create_dir_all(folder).unwrap();
        std::fs::write(folder.join(format!("{cn}.pem")), cert.pem()).unwrap();
        std::fs::write(folder.join(format!("{cn}.key")), key.serialize_pem()).unwrap();
    };
    let site = ca("splinewatch test site CA");
    std::fs::create_dir_all(dir).unwrap();
    std::fs::write(dir.join("ca.pem"), site.pem()).unwrap();
    for cn in ["router", "logger", "splinewatch", "dashboard"] {
        leaf(&site, dir, cn, false);
    }
    leaf(&site, &dir.join("expired"), "logger", true);
    let other = ca("another CA");
    leaf(&other, &dir.join("other-ca"), "logger", false);
    std::fs::write(dir.join("other-ca/ca.pem"), other.pem()).unwrap();
}

#[test]
fn authenticated_clients_and_access_control_keep_forged_data_out() {
    secured_site(&fresh_dir("security"), Transport::Password);
}

#[test]
fn mutual_tls_admits_the_site_ca_clients_only_and_keeps_the_access_control() {
    let dir = fresh_dir("security-tls");
    let pki = dir.join("pki");
    make_test_pki(&pki);
    secured_site(&dir, Transport::MutualTls { pki });
}

/// The two router examples enforce the same rules: only how a subject is
/// recognised differs (user name or certificate common name).
#[test]
fn the_tls_router_example_has_the_same_access_control_as_the_password_one() {
    let read = |file: &str| zenoh::Config::from_file(root().join("config/zenoh").join(file)).unwrap();
    let (password, tls) = (read("router-acl.json5"), read("router-tls.json5"));
    for key in [
        "access_control/enabled",
        "access_control/default_permission",
        "access_control/rules",
        "access_control/policies",
    ] {
        assert_eq!(password.get_json(key).unwrap(), tls.get_json(key).unwrap(), "{key}");
    }
    let subjects = |c: &zenoh::Config, field: &str| -> Vec<(String, String)> {
        let v: serde_json::Value = serde_json::from_str(&c.get_json("access_control/subjects").unwrap()).unwrap();
        v.as_array()
            .unwrap()
            .iter()
            .map(|s| {
                (
                    s["id"].as_str().unwrap().to_string(),
                    s[field][0].as_str().unwrap().to_string(),
                )
            })
            .collect()
    };
    assert_eq!(subjects(&password, "usernames"), subjects(&tls, "cert_common_names"));
}

/// A router from the example file, the daemon, a logger and a dashboard as
/// its clients over `transport`: intruders refused, forged data dropped by
/// the access control, the logger's data analysed, results delivered.
fn secured_site(dir: &Path, transport: Transport) {
    let endpoint = transport.endpoint();
    let router = zenoh::open(transport.router(dir, &endpoint)).wait().unwrap();

    // Intruders cannot even connect.
    let intruders = transport.intruders(dir, &endpoint);
    for (what, c) in &intruders {
        assert!(zenoh::open(c.clone()).wait().is_err(), "{what} was let in");
    }

    // The daemon, authenticated as `splinewatch` through its config_file.
    let zenoh_file = transport.client_file(dir, "splinewatch");
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
    let dashboard = zenoh::open(transport.client(dir, "dashboard", &endpoint))
        .wait()
        .unwrap();
    let parameters = dashboard
        .declare_subscriber(format!("{PREFIX}/updating/parameters"))
        .wait()
        .unwrap();
    std::thread::sleep(Duration::from_millis(1500));

    let cfg = load_config(&config).unwrap();
    let blocks = bundled_blocks();
    let zenoh_as = |role: &str| ZenohConfig {
        mode: "client".into(),
        connect: vec![endpoint.clone()],
        config_file: Some(transport.client_file(dir, role)),
        ..ZenohConfig::default()
    };
    // The dashboard, authenticated but not a logger, forges measurements
    // (valid blocks, a minute before the real ones) and a result: the
    // router drops them.
    let mut forger = Publisher::open(&zenoh_as("dashboard"), cfg.topic_prefix(), Encoding::Cbor, 0.0).unwrap();
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
    let mut logger = Publisher::open(&zenoh_as("logger"), cfg.topic_prefix(), Encoding::Cbor, 20.0).unwrap();
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
    // The dashboard may query the latest result. It waits for the right
    // event, the daemon's liveliness token (declared after its queryables,
    // on the same ordered link to the router), then asks once; every ask is
    // answered on its own (issue 48: a TLS link's concurrent read and write
    // raced in zenoh-link-tls and closed the link now and then, finalising
    // an ask in flight with no reply; patched in vendor/zenoh-link-tls).
    // `benches/tls_asks.sh` asks 10 000 times (SPLINEWATCH_TLS_ASKS).
    let alive = dashboard
        .liveliness()
        .declare_subscriber(format!("{PREFIX}/alive"))
        .history(true)
        .wait()
        .unwrap();
    let token = alive.recv_timeout(Duration::from_secs(30)).unwrap();
    assert!(token.is_some(), "the daemon's liveliness token never arrived");
    let asks: u64 = std::env::var("SPLINEWATCH_TLS_ASKS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1);
    let started = std::time::Instant::now();
    for ask in 1..=asks {
        let replies: Vec<_> = dashboard
            .get(format!("{PREFIX}/updating/latest"))
            .timeout(Duration::from_secs(20))
            .wait()
            .unwrap()
            .into_iter()
            .collect();
        if replies.len() != 1 {
            // Issue 48: keep what the daemon saw for the missing reply.
            let log = std::fs::read_to_string(dir.join("daemon.log")).unwrap_or_default();
            let tail: Vec<&str> = log.lines().rev().take(80).collect();
            let tail: Vec<&str> = tail.into_iter().rev().collect();
            panic!(
                "ask {ask} of {asks} got {} replies; the daemon log's last lines:\n{}",
                replies.len(),
                tail.join("\n")
            );
        }
        let body: serde_json::Value =
            serde_json::from_slice(&replies[0].result().unwrap().payload().to_bytes()).unwrap();
        assert!(body["parameters"].is_array(), "ask {ask}: {body}");
    }
    // The benchmark's figure (`benches/tls_asks.sh`).
    eprintln!(
        "{asks} asks, each answered on its first ask, in {:.2} s",
        started.elapsed().as_secs_f64()
    );
    // So may `splinewatch fleet` with the dashboard's credentials, asked
    // once: its liveliness and wildcard queries (bridge/*/…) pass the access
    // control, and the expected span answers.
    let fleet = std::process::Command::new(env!("CARGO_BIN_EXE_splinewatch"))
        .args([
            "fleet",
            "--json",
            "--connect",
            &endpoint,
            "--expect",
            "sinello-span2",
            "--zenoh-config",
        ])
        .arg(transport.client_file(dir, "dashboard"))
        .output()
        .unwrap();
    let fleet_out = String::from_utf8_lossy(&fleet.stdout).into_owned();
    assert!(fleet.status.success(), "{}", String::from_utf8_lossy(&fleet.stderr));
    let span: serde_json::Value = serde_json::from_str(fleet_out.trim()).unwrap();
    assert_eq!(span["summary"]["name"], "sinello-span2", "{span}");
    assert_eq!(span["summary"]["reachability"], "answering", "{span}");
    assert_eq!(span["latest"]["alive"], true, "{span}");
    assert_eq!(span["summary"]["parameters"].as_array().unwrap().len(), 15, "{span}");

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

    // No password or private key in the daemon's log, even at debug level
    // (zenoh's own debug output included).
    assert!(
        log.lines().any(|l| l.contains("DEBUG") && l.contains("zenoh")),
        "debug logging was off"
    );
    for secret in transport.secrets() {
        assert!(!log.contains(&secret), "the log shows a secret");
    }
    eprintln!(
        "security: {} intruders refused, 28 forged messages dropped, {} blocks and {} results delivered",
        intruders.len(),
        blocks.len(),
        received.len()
    );
    dashboard.close().wait().unwrap();
    router.close().wait().unwrap();
}

/// `check-config` reads every TLS file the zenoh session names: a valid set is
/// listed with each certificate's expiry; a missing, expired or wrong file is
/// refused naming the JSON5 key and the file, and the daemon does not start.
#[test]
fn check_config_reads_every_tls_file_and_names_the_key_of_a_bad_one() {
    let dir = fresh_dir("security-check");
    let pki = dir.join("pki");
    make_test_pki(&pki);
    let transport = Transport::MutualTls { pki: pki.clone() };
    let zenoh_file = transport.client_file(&dir, "splinewatch");
    let config = dir.join("config.toml");
    let text = std::fs::read_to_string(root().join("config/sinello.toml")).unwrap()
        + &format!(
            "\n[zenoh]\nmode = \"client\"\nconnect = [\"tls/127.0.0.1:7447\"]\nconfig_file = {:?}\n",
            zenoh_file.to_str().unwrap()
        );
    std::fs::write(&config, text).unwrap();
    let splinewatch = |command: &str| {
        let mut c = std::process::Command::new(env!("CARGO_BIN_EXE_splinewatch"));
        c.arg(command);
        if command == "run" {
            c.arg("--config").arg(&config);
            c.arg("--state")
                .arg(dir.join("s.json"))
                .arg("--out")
                .arg(dir.join("r.mcap"));
        } else {
            c.arg(&config);
        }
        c.output().unwrap()
    };
    let out = splinewatch("check-config");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(stdout.contains("zenoh transport: mutual TLS"), "{stdout}");
    for key in ["root_ca_certificate", "connect_certificate", "connect_private_key"] {
        assert!(
            stdout.contains(&format!("transport/link/tls/{key} = ")),
            "{key}: {stdout}"
        );
    }
    assert!(stdout.contains("CN=splinewatch, expires"), "{stdout}");

    let good = std::fs::read_to_string(&zenoh_file).unwrap();
    let cert = pki.join("splinewatch.pem");
    for (replacement, key, complaint) in [
        (dir.join("nowhere.pem"), "connect_certificate", "cannot read"),
        (pki.join("expired/logger.pem"), "connect_certificate", "expired on"),
        (
            pki.join("splinewatch.key"),
            "connect_certificate",
            "holds no PEM certificate",
        ),
    ] {
        std::fs::write(
            &zenoh_file,
            good.replace(cert.to_str().unwrap(), replacement.to_str().unwrap()),
        )
        .unwrap();
        for command in ["check-config", "run"] {
            let out = splinewatch(command);
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert!(!out.status.success(), "{command} accepted {}", replacement.display());
            let expected = format!(
                "zenoh.config_file {}: transport/link/tls/{key}: {}: ",
                zenoh_file.display(),
                replacement.display()
            );
            assert!(
                stderr.contains(&expected) && stderr.contains(complaint),
                "{command}: {stderr}"
            );
        }
    }
    // A tls/ endpoint with mutual TLS and no client certificate at all.
    let without: String = good
        .lines()
        .filter(|l| !l.contains("connect_certificate:"))
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(&zenoh_file, without).unwrap();
    let out = splinewatch("check-config");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.contains("transport/link/tls/connect_certificate: missing"),
        "{stderr}"
    );
}
