//! `splinewatch report`, the real binary on results files that other tests
//! make anyway (the Painter Street events, the simulated stiffness drop,
//! the two weeks of monitoring): each check here is called from the test
//! that owns its fixture. The same reports are opened in headless Chromium
//! by `tests/browser/check_reports.py` (`.ci/run`).

use crate::common::splinewatch;
use std::path::Path;

/// A report's HTML, the command's stdout; asserts it succeeded.
pub fn report(results: &[&str], extra: &[&str], out: &Path) -> (String, String) {
    let mut args = vec!["report"];
    args.extend_from_slice(results);
    args.extend_from_slice(extra);
    args.extend_from_slice(&["--out", out.to_str().unwrap()]);
    let o = splinewatch(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    (
        std::fs::read_to_string(out).unwrap(),
        String::from_utf8_lossy(&o.stdout).into_owned(),
    )
}

/// What every report must be: one self-contained page (no script, no
/// attribute that would fetch anything), the verdict and its priority
/// first, its figures inline SVG, its tables with rows, deterministic.
pub fn check_self_contained(html: &str) {
    check_page(html);
    let figures = html.matches("<figure").count();
    assert!(
        figures > 0 && html.matches("<svg").count() == figures,
        "one SVG per figure"
    );
    assert!(!html.contains("figure could not be drawn"));
    assert!(
        html.matches("<tbody><tr>").count() == html.matches("<table").count(),
        "no empty table"
    );
}

/// A page of its own (no script, nothing it would fetch, no link off the
/// page's own server), the verdict first.
pub fn check_page(html: &str) {
    assert!(html.starts_with("<!DOCTYPE html>"));
    assert!(!html.contains("<script"), "no script");
    for fetching in [" src=", "href=\"http", "href=\"//", "url(", "@import"] {
        assert!(!html.contains(fetching), "{fetching} in the report");
    }
    let verdict = html.find("id=\"verdict\"").expect("a verdict");
    assert!(
        verdict < html.find("<section").expect("sections"),
        "the verdict comes first"
    );
}

/// A bad input: the command fails with one line naming the problem and
/// writes no report.
pub fn refused(args: &[&str], out: &Path, says: &str) {
    let mut all = vec!["report"];
    all.extend_from_slice(args);
    all.extend_from_slice(&["--out", out.to_str().unwrap()]);
    let o = splinewatch(&all);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "{args:?} accepted");
    assert_eq!(stderr.trim().lines().count(), 1, "one line: {stderr}");
    assert!(stderr.contains(says), "{args:?}: {stderr}");
    assert!(!out.exists(), "no report written on {args:?}");
}

/// The Painter Street events of `events` (2012, 2015 and the unusable
/// records): the 2015 event's report, a period's, and the bad inputs.
pub fn painter_street_reports(dir: &Path, results: &str, lines: &[serde_json::Value]) {
    let out = dir.join("ferndale.html");
    let (html, stdout) = report(&[results], &["--event", "ferndale"], &out);
    check_self_contained(&html);
    let line = lines
        .iter()
        .find(|l| l["event"] == "ferndale_28jan2015_72387946_ce89324p.zip")
        .unwrap();
    // Two events judged before it at most: not judged, and said so first.
    assert!(stdout.starts_with("Not judged: Too few earlier events"), "{stdout}");
    assert!(html.contains("<span class=\"priority\">Not judged</span>"));
    // The shaking as `events --json` gave it, and every deck channel scored
    // against the baseline, the fitted ones starred.
    let pga = line["pga_ground"].as_f64().unwrap();
    assert!(html.contains(&format!("{pga:.2} m/s²")), "ground peak {pga}");
    for c in line["forecast"]["channels"].as_array().unwrap() {
        let sensor = c["sensor"].as_str().unwrap();
        assert!(
            html.contains(&format!("<td>{sensor}")),
            "{sensor} in the forecast table"
        );
    }
    assert!(html.contains("<td>ch7 ★</td>"));
    // One figure per judged feature and the forecast's.
    let bands = line["verdict"]["bands"].as_array().unwrap().len();
    assert_eq!(html.matches("<figure").count(), bands + 1);
    // The skipped records with their reasons, and what the verdict rests on.
    for skipped in ["dead.csv", "ch9: a dead channel", "missing.zip"] {
        assert!(html.contains(skipped), "{skipped} among the skipped");
    }
    assert!(html.contains("config/painter-street.toml (SHA-256"));
    // The same results, the same bytes.
    let again = dir.join("again.html");
    assert_eq!(report(&[results], &["--event", "ferndale"], &again).0, html);
    // A period: every event in it with its verdict.
    let (period, _) = report(
        &[results],
        &["--from", "2012-01-01", "--to", "2015-12-31"],
        &dir.join("p.html"),
    );
    check_self_contained(&period);
    assert!(period.contains("RioDell_14Sep2012") && period.contains("ferndale_28jan2015"));

    // Bad input: an event not in the results, another bridge's results, a
    // truncated file, a file that is not MCAP, an empty period.
    let bad = dir.join("bad.html");
    refused(
        &[results, "--event", "northridge"],
        &bad,
        "no event named \"northridge\"",
    );
    refused(&[results, "--event", "ce89324p"], &bad, "matches several events");
    let other = dir.join("other-bridge.mcap");
    let mut w = splinewatch::outputs::results::ResultsWriter::create(&other, "bridge/another").unwrap();
    w.write_json("events/summary", 1, line.to_string().as_bytes()).unwrap();
    w.finish().unwrap();
    refused(&[results, other.to_str().unwrap()], &bad, "one bridge per report");
    let bytes = std::fs::read(results).unwrap();
    let truncated = dir.join("truncated.mcap");
    std::fs::write(&truncated, &bytes[..bytes.len() * 2 / 3]).unwrap();
    refused(&[truncated.to_str().unwrap()], &bad, "is truncated or damaged");
    let state = dir.join("state.json");
    refused(&[state.to_str().unwrap()], &bad, "is not an MCAP file");
    refused(&[results, "--from", "2030-01-01"], &bad, "hold nothing between");
}

/// The simulated stiffness drop: the fifth event's report says the bent's
/// lateral stiffness fell below its band and asks for an inspection.
pub fn alarm_report(dir: &Path, results: &str, alarmed_event: &str) {
    let (html, stdout) = report(&[results], &["--event", alarmed_event], &dir.join("alarm.html"));
    check_self_contained(&html);
    assert!(
        stdout.starts_with("High: inspect: Outside the bands of the 4 earlier events at this shaking: "),
        "{stdout}"
    );
    assert!(
        stdout.contains("bent_south: stiffness across the bridge (y), below"),
        "{stdout}"
    );
    assert!(html.contains("id=\"verdict\" class=\"high\""));
    assert!(html.contains("class=\"out\""), "the feature outside its band marked");
}

/// The two weeks of monitoring (two runs' results files): over the whole
/// period the alarm was raised and cleared (the bearing's repair), a review;
/// up to `alarmed_time` it is on, an inspection naming the softened bearing;
/// the T² and MEWMA figures and one trend per updated parameter.
pub fn monitoring_report(dir: &Path, results: &[&str], alarmed_time: &str) {
    let (html, stdout) = report(results, &[], &dir.join("two-weeks.html"));
    check_self_contained(&html);
    assert!(
        stdout.starts_with("Medium: review: 1 alarm(s) raised in the period"),
        "{stdout}"
    );
    assert!(stdout.contains("east: support stiffness, coefficient 2"), "{stdout}");
    assert!(html.contains("id=\"state-t2\"") && html.contains("id=\"state-mewma\""));
    assert!(html.contains("id=\"trend-east.k2\"") && html.contains("id=\"trend-deck.s1\""));
    assert!(html.contains("id=\"alarms-table\"") && html.contains("id=\"health-table\""));
    let (html, stdout) = report(results, &["--to", alarmed_time], &dir.join("alarm.html"));
    check_self_contained(&html);
    assert!(
        stdout.starts_with("High: inspect: In alarm since")
            && stdout.contains("east: support stiffness, coefficient 2"),
        "{stdout}"
    );
}
