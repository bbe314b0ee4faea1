//! The report's words: the verdict as a sentence an owner reads, the
//! inspection priority, and what each feature and parameter name means.

use crate::io::results_file::{EventSummary, FeatureBandLine};

/// How urgently the bridge should be looked at, highest first (after
/// ShakeCast's inspection priorities, from what the bridge's own sensors
/// and model say rather than from fragility curves).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Priority {
    /// An alarm: something moved outside what the bridge's history allows.
    High,
    /// An alarm raised and cleared within the period, or data outside the
    /// range the reference was trained on: an engineer should look.
    Medium,
    /// Nothing was judged (too little history, or the record unusable).
    NotJudged,
    /// Judged, and within the bands.
    Low,
}

impl Priority {
    pub fn label(self) -> &'static str {
        match self {
            Priority::High => "High: inspect",
            Priority::Medium => "Medium: review",
            Priority::NotJudged => "Not judged",
            Priority::Low => "Low: no change found",
        }
    }

    /// The CSS class of its badge.
    pub fn class(self) -> &'static str {
        match self {
            Priority::High => "high",
            Priority::Medium => "medium",
            Priority::NotJudged => "unjudged",
            Priority::Low => "low",
        }
    }
}

/// What a parameter or feature name means, in words (the name kept beside).
pub fn describe(name: &str) -> String {
    let name = name.strip_prefix("log10_").unwrap_or(name);
    if let Some(n) = name.strip_prefix("mode").and_then(|r| r.strip_suffix("_hz")) {
        return format!("frequency of identified mode {n}");
    }
    if let Some(n) = name.strip_prefix("mode_").and_then(|r| r.strip_suffix("_frequency_hz")) {
        return format!("identified frequency of model mode {n}");
    }
    let Some((element, what)) = name.rsplit_once('.') else {
        return name.to_string();
    };
    let what = match what {
        "kx" => "stiffness along the bridge (x)".to_string(),
        "ky" => "stiffness across the bridge (y)".to_string(),
        "kz" => "vertical stiffness (z)".to_string(),
        "krx" | "kry" | "krz" => format!("rotational stiffness about {}", &what[2..]),
        w if w.starts_with('k') && w[1..].parse::<u32>().is_ok() => {
            format!("support stiffness, coefficient {}", &w[1..])
        }
        w if w.starts_with('g') && element == "damping" => format!("damping ratio ζ(f), coefficient {}", &w[1..]),
        w if w.starts_with('s') && w[1..].parse::<u32>().is_ok() => {
            format!("material stiffness scale, coefficient {}", &w[1..])
        }
        w => w.to_string(),
    };
    if element == "damping" {
        what
    } else {
        format!("{element}: {what}")
    }
}

/// A feature's value in its own units: the verdict judges stiffnesses and
/// damping on a log10 scale (`log10_<name>`); the owner reads the value.
pub fn feature_value(feature: &str, v: f64) -> f64 {
    if feature.starts_with("log10_") {
        10f64.powf(v)
    } else {
        v
    }
}

/// Whether the feature's values read better on a log axis.
pub fn feature_is_logarithmic(feature: &str) -> bool {
    feature.starts_with("log10_")
}

/// An out-of-band feature and where it went.
fn moved(band: &FeatureBandLine) -> String {
    let what = describe(&band.feature);
    match (band.value, band.band) {
        (Some(v), Some(b)) if v < b.lower => format!("{what}, below"),
        (Some(v), Some(b)) if v > b.upper => format!("{what}, above"),
        _ => what,
    }
}

/// An event's verdict in words and its priority. `min_events` is what the
/// config asks before judging, when the results file says.
pub fn event_verdict(e: &EventSummary, min_events: Option<usize>) -> (String, Priority) {
    if let Some(reason) = &e.skipped {
        return (
            format!("The record could not be used ({reason}). An engineer should look at it."),
            Priority::NotJudged,
        );
    }
    let Some(v) = &e.verdict else {
        return (
            "The event was not compared with earlier ones.".into(),
            Priority::NotJudged,
        );
    };
    let earlier = v
        .bands
        .iter()
        .filter_map(|b| b.band.map(|b| b.events))
        .max()
        .unwrap_or(0);
    match v.state.as_str() {
        "alarm" => {
            let moved: Vec<String> = v
                .bands
                .iter()
                .filter(|b| v.outside.contains(&b.feature))
                .map(moved)
                .collect();
            (
                format!(
                    "Outside the bands of the {earlier} earlier events at this shaking: {}.",
                    moved.join("; ")
                ),
                Priority::High,
            )
        }
        "normal" => (
            format!(
                "No change beyond the band of the {earlier} earlier events: every feature judged ({}) is within what they predict at this shaking.",
                v.bands.iter().filter(|b| b.band.is_some()).count()
            ),
            Priority::Low,
        ),
        _ => (
            match min_events {
                Some(n) => format!(
                    "Too few earlier events to judge this one: a band needs {n} earlier events judged normal, and this is event {} of the bridge's chain.",
                    e.number + 1
                ),
                None => "Too few earlier events to judge this one.".into(),
            },
            Priority::NotJudged,
        ),
    }
}

/// "a", "a and b", "a, b and c".
pub fn join_words(items: &[String]) -> String {
    match items {
        [] => String::new(),
        [one] => one.clone(),
        [init @ .., last] => format!("{} and {last}", init.join(", ")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_read_as_words() {
        assert_eq!(
            describe("log10_bent_south.ky"),
            "bent_south: stiffness across the bridge (y)"
        );
        assert_eq!(describe("mode2_hz"), "frequency of identified mode 2");
        assert_eq!(describe("damping.g1"), "damping ratio ζ(f), coefficient 1");
        assert_eq!(describe("east.k2"), "east: support stiffness, coefficient 2");
        assert_eq!(describe("deck.s1"), "deck: material stiffness scale, coefficient 1");
        assert_eq!(join_words(&["a".into(), "b".into(), "c".into()]), "a, b and c");
        assert!((feature_value("log10_x.ky", 8.0) - 1e8).abs() < 1e-3);
    }
}
