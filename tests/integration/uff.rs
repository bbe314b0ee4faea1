//! Universal files (UFF 58/58b) against pyuff: FRFs pyuff wrote (committed
//! fixtures, tests/fixtures/make_uff_fixtures.py: a campaign with two
//! references, coherences, a sensor written along -z) read to the bit, and
//! `update --frf FILE.uff` giving the parameters of the equivalent FRF JSON.

use splinewatch::config::load_config;
use splinewatch::io::frf_json::FrfFile;
use splinewatch::studies::update::read_frf_file;
use std::path::{Path, PathBuf};

use crate::common::fresh_dir;

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/uff")
        .join(name)
}

const PAIRS: [(&str, &str); 2] = [
    ("campaign_ascii.unv", "campaign_from_ascii.json"),
    ("campaign_binary.uff", "campaign_from_binary.json"),
];

#[test]
fn pyuff_frfs_read_to_the_bit_with_coherence_and_direction_signs() {
    let cfg = load_config(&fixture("campaign.toml")).unwrap();
    for (uff, json) in PAIRS {
        let from_uff = read_frf_file(&cfg, &std::fs::read(fixture(uff)).unwrap()).unwrap();
        let expected = FrfFile::parse(&std::fs::read_to_string(fixture(json)).unwrap()).unwrap();
        assert_eq!(from_uff.frfs.len(), 12, "{uff}");
        assert!(from_uff.frfs.iter().all(|e| e.coherence.is_some()), "{uff}");
        // Structural equality of f64 vectors: every value to the bit.
        assert_eq!(from_uff, expected, "{uff}");
    }
}

fn update(config: &Path, frf: &Path) -> String {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_splinewatch"))
        .args(["update", "--json", "--config"])
        .arg(config)
        .arg("--frf")
        .arg(frf)
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8(out.stdout).unwrap()
}

#[test]
fn update_from_a_universal_file_equals_update_from_the_same_frf_json() {
    let config = fixture("campaign.toml");
    for (uff, json) in PAIRS {
        let a = update(&config, &fixture(uff));
        let b = update(&config, &fixture(json));
        assert!(a.contains("\"parameters\""), "{a}");
        assert_eq!(a, b, "{uff}: the parameters differ from the FRF JSON's");
    }
}

/// What is wrong with a file or its mapping is named: an unclaimed node, a
/// direction no sensor at the node measures, a truncated binary block.
#[test]
fn universal_file_errors_name_the_dataset_and_what_is_wrong() {
    let dir = fresh_dir("uff-errors");
    let text = std::fs::read_to_string(fixture("campaign.toml")).unwrap();
    let bytes = std::fs::read(fixture("campaign_ascii.unv")).unwrap();
    let error = |config_text: &str, bytes: &[u8]| -> String {
        let path = dir.join("c.toml");
        std::fs::write(&path, config_text).unwrap();
        let cfg = load_config(&path).unwrap();
        format!("{:#}", read_frf_file(&cfg, bytes).unwrap_err())
    };
    let e = error(&text.replace("uff_node = 106\n", ""), &bytes);
    assert!(e.contains("response node 106: no sensor has uff_node = 106"), "{e}");
    let (head, tail) = text.split_at(text.find("uff_node = 102").unwrap());
    let p2_along_x = format!("{head}{}", tail.replacen("direction = \"z\"", "direction = \"x\"", 1));
    let e = error(&p2_along_x, &bytes);
    assert!(e.contains("node 102 direction -3 (-z)") && e.contains("P2"), "{e}");

    let binary = std::fs::read(fixture("campaign_binary.uff")).unwrap();
    let e = error(&text, &binary[..binary.len() / 2]);
    assert!(
        e.contains("58b") && e.contains("not followed by the -1 delimiter"),
        "{e}"
    );
    let e = error(
        &text,
        b"    -1\n    15\n         1         0         0         0  0.0  0.0  0.0\n    -1\n",
    );
    assert!(e.contains("no dataset 58 frequency response function"), "{e}");
}

/// Largest difference between two FRF sets, relative to each FRF's peak.
fn frf_difference(a: &FrfFile, b: &FrfFile) -> f64 {
    assert_eq!(a.frfs.len(), b.frfs.len());
    for (x, y) in a.frequency_hz.iter().zip(&b.frequency_hz) {
        assert!((x - y).abs() <= 1e-5 * y.abs(), "frequency {x} vs {y}");
    }
    let mut worst: f64 = 0.0;
    for e in &a.frfs {
        let f = b
            .frfs
            .iter()
            .find(|f| f.output == e.output && f.input == e.input)
            .unwrap();
        let peak = f.re.iter().zip(&f.im).map(|(r, i)| r.hypot(*i)).fold(0.0, f64::max);
        for k in 0..e.re.len() {
            worst = worst.max((e.re[k] - f.re[k]).hypot(e.im[k] - f.im[k]) / peak);
        }
        match (&e.coherence, &f.coherence) {
            (Some(c), Some(d)) => assert!(c.iter().zip(d).all(|(c, d)| (c - d).abs() < 1e-12)),
            (None, None) => {}
            _ => panic!("coherence present in one set only"),
        }
    }
    worst
}

fn dataset_count(text: &str, kind: &str) -> usize {
    let lines: Vec<&str> = text.lines().collect();
    lines
        .windows(2)
        .filter(|w| w[0].trim() == "-1" && w[1].trim() == kind)
        .count()
}

/// A file we write (FRFs with coherences, the model's modes) reads back to
/// the same FRFs (E20.12: 13 significant digits), and `update` accepts it.
#[test]
fn universal_files_we_write_read_back_and_update() {
    use splinewatch::studies::exchange::{uff_file, UffContent};
    let cfg = load_config(&fixture("campaign.toml")).unwrap();
    let frf = FrfFile::parse(&std::fs::read_to_string(fixture("campaign_from_binary.json")).unwrap()).unwrap();
    let text = uff_file(
        &cfg,
        &UffContent {
            frfs: Some((&frf, "measured")),
            model_modes_below_hz: Some(40.0),
            ..Default::default()
        },
    )
    .unwrap();
    for (kind, count) in [("164", 1), ("15", 1), ("82", 1), ("58", 24)] {
        assert_eq!(dataset_count(&text, kind), count, "dataset {kind}");
    }
    // The deck's elastic modes below 40 Hz: 6.68, 8.97, 21.63 Hz, …
    assert!(dataset_count(&text, "55") >= 5, "model modes");
    let back = read_frf_file(&cfg, text.as_bytes()).unwrap();
    let worst = frf_difference(&back, &frf);
    assert!(worst < 1e-12, "round trip {worst:e}");
    let dir = fresh_dir("uff-write");
    std::fs::write(dir.join("ours.unv"), &text).unwrap();
    let a = update(&fixture("campaign.toml"), &dir.join("ours.unv"));
    assert!(a.contains("\"parameters\""), "{a}");
}

/// `frf --format uff` on the bundled recording (sensors without uff_node:
/// nodes 1, 2, … in list order) matches `frf`'s JSON; `export` writes a
/// replay's last update (measured FRFs, model modes at its parameters).
#[test]
fn frf_and_export_write_universal_files() {
    use crate::common::splinewatch;
    let dir = fresh_dir("uff-cli");
    let (json, uff) = (dir.join("frf.json"), dir.join("frf.unv"));
    for (format, out) in [("json", &json), ("uff", &uff)] {
        let o = splinewatch(&[
            "frf",
            "--config",
            "config/sinello.toml",
            "recordings/sinello-demo.mcap",
            "--to",
            "40",
            "--format",
            format,
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let cfg = load_config(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("config/sinello.toml")
            .as_path(),
    )
    .unwrap();
    let from_json = FrfFile::parse(&std::fs::read_to_string(&json).unwrap()).unwrap();
    let from_uff = read_frf_file(&cfg, &std::fs::read(&uff).unwrap()).unwrap();
    assert!(frf_difference(&from_uff, &from_json) < 1e-12);

    let results = dir.join("results.mcap");
    let o = splinewatch(&[
        "replay",
        "--config",
        "config/sinello.toml",
        "recordings/sinello-demo.mcap",
        "--out",
        results.to_str().unwrap(),
        "--state",
        dir.join("state.json").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let exported = dir.join("last.unv");
    let o = splinewatch(&[
        "export",
        "--config",
        "config/sinello.toml",
        results.to_str().unwrap(),
        "--out",
        exported.to_str().unwrap(),
    ]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{stderr}");
    assert!(stderr.contains("window 5: 12 FRFs"), "{stderr}");
    let text = std::fs::read_to_string(&exported).unwrap();
    assert!(dataset_count(&text, "55") >= 10, "model modes below the band's top");
    let bytes = std::fs::read(&results).unwrap();
    let last = splinewatch::service::export::window_results(&bytes, "bridge/sinello-span2", None).unwrap();
    let measured = last.measured.unwrap();
    assert!(frf_difference(&read_frf_file(&cfg, text.as_bytes()).unwrap(), &measured) < 1e-12);
    // A window that was never updated is named.
    let o = splinewatch(&[
        "export",
        "--config",
        "config/sinello.toml",
        results.to_str().unwrap(),
        "--window",
        "99",
        "--out",
        exported.to_str().unwrap(),
    ]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("window 99 was not updated"));
}
