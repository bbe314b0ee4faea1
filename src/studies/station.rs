//! `splinewatch station`: a starter config written from a strong-motion
//! station's Volume 2 headers, for identification before any model exists.
//!
//! Every channel of the records becomes a `[[sensors]]` entry named by its
//! station channel (`ch7`), pointing along the structure's axes: `Up` is
//! `z`, `Long` is `x`, `Tran` is `y`; an azimuth is turned onto them by the
//! longitudinal axis' azimuth (`--axis`), or, without it, onto compass axes
//! (x north, y east), said as a guess. A channel whose location names the
//! ground or a foundation (see [`GROUND_WORDS`]; a structure word such as
//! "deck" wins) measures a support group's ground, one group per location
//! text; the rest are the structure's outputs.

use crate::io::cosmos_v2::placement::{Orientation, Placement, GROUND_WORDS, STRUCTURE_WORDS};
use crate::io::cosmos_v2::{Station, V2Summary};
use anyhow::{bail, Result};
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// One record's channels, as `import --list` reads them, and its file.
pub struct StationRecord {
    pub file: String,
    pub channels: Vec<V2Summary>,
}

/// The config's text and what it had to guess (also in its comments).
pub struct StarterConfig {
    pub toml: String,
    pub guesses: Vec<String>,
}

/// A channel as the records describe it (the most common description when
/// they differ) and the records that lack it.
struct ChannelEntry<'a> {
    summary: &'a V2Summary,
    missing_from: Vec<&'a str>,
    other_descriptions: Vec<String>,
}

/// The channels by their role in the config.
struct Roles<'a> {
    structure: Vec<&'a ChannelEntry<'a>>,
    /// With the support group of each.
    ground: Vec<(String, &'a ChannelEntry<'a>)>,
    /// Orientation not read: commented in the file.
    unreadable: Vec<&'a ChannelEntry<'a>>,
}

/// Each channel's role by its orientation and location (what was guessed
/// pushed to `guesses`).
fn roles<'a>(channels: &'a [ChannelEntry<'a>], guesses: &mut Vec<String>) -> Roles<'a> {
    let mut roles = Roles {
        structure: Vec::new(),
        ground: Vec::new(),
        unreadable: Vec::new(),
    };
    for entry in channels {
        let c = entry.summary;
        if Orientation::parse(&c.direction).is_none() {
            guesses.push(format!(
                "ch{}: its orientation {:?} is none of Up, Tran, Long or an azimuth: left out (commented in the file); give its direction",
                c.channel, c.direction
            ));
            roles.unreadable.push(entry);
            continue;
        }
        match Placement::of(&c.location) {
            Some(Placement::Ground) => roles.ground.push((group_name(&c.location), entry)),
            Some(Placement::Structure) => roles.structure.push(entry),
            None => {
                guesses.push(format!(
                    "ch{}: its location {:?} names neither the ground nor the structure: taken as on the structure",
                    c.channel, c.location
                ));
                roles.structure.push(entry);
            }
        }
    }
    roles
}

/// The starter config of the station the `records` are of; `axis_deg` the
/// azimuth of the structure's longitudinal axis (x), when known.
pub fn starter_config(records: &[StationRecord], axis_deg: Option<f64>) -> Result<StarterConfig> {
    if let Some(axis) = axis_deg {
        if !axis.is_finite() {
            bail!("--axis must be an azimuth in degrees, got {axis}");
        }
    }
    let station = one_station(records)?;
    let channels = union_of_channels(records);
    let mut guesses = Vec::new();
    let Roles {
        structure,
        ground,
        unreadable,
    } = roles(&channels, &mut guesses);
    if ground.is_empty() {
        guesses.push(
            "no channel's location names the ground or a foundation: the config serves output-only identification (oma); input-output needs ground sensors (support = \"<group>\")"
                .into(),
        );
    }
    if structure.is_empty() {
        bail!("every channel of the records is on the ground: nothing measures the structure's response");
    }
    if !channels.iter().any(|e| {
        let lower = e.summary.location.to_ascii_lowercase();
        ["deck", "bent", "abut", "span", "pier", "column", "girder"]
            .iter()
            .any(|w| lower.contains(w))
    }) {
        guesses.push("no channel's location reads as a bridge's (deck, bent, abutment, span, pier, column): is this a building's station? The rules are a bridge's".into());
    }
    let mut toml = header(&station, records, axis_deg);
    let mut transverse = Transverse::default();
    let mut sensor = |entry: &ChannelEntry, support: Option<&str>, toml: &mut String, guesses: &mut Vec<String>| {
        let c = entry.summary;
        let direction = axis_of(c, axis_deg, guesses);
        if direction == "y" {
            let name = format!("\"ch{}\"", c.channel);
            match support {
                Some(_) => transverse.ground.push((name, c.location.clone())),
                None => transverse.structure.push(name),
            }
        }
        let _ = writeln!(toml, "[[sensors]]                 # {}: {}", c.direction, c.location);
        let _ = writeln!(toml, "name = \"ch{}\"", c.channel);
        let _ = writeln!(toml, "direction = \"{direction}\"");
        if let Some(group) = support {
            let _ = writeln!(toml, "support = \"{group}\"");
        }
        for note in entry_notes(entry) {
            let _ = writeln!(toml, "# {note}");
        }
        toml.push('\n');
    };
    toml.push_str("# The structure: the outputs of identification.\n\n");
    for entry in &structure {
        sensor(entry, None, &mut toml, &mut guesses);
    }
    if !ground.is_empty() {
        toml.push_str("# The ground: each location one support group, its channels the inputs.\n\n");
        for (group, entry) in &ground {
            sensor(entry, Some(group), &mut toml, &mut guesses);
        }
    }
    commented_out(&unreadable, &mut toml);
    toml.push_str(&analysis_sections(&structure));
    toml.push_str(&transverse.section());
    if !guesses.is_empty() {
        toml.push_str("\n# What `splinewatch station` guessed:\n");
        for g in &guesses {
            let _ = writeln!(toml, "# - {g}");
        }
    }
    Ok(StarterConfig { toml, guesses })
}

/// The channels whose orientation was not read, as commented entries.
fn commented_out(unreadable: &[&ChannelEntry], toml: &mut String) {
    for entry in unreadable {
        let c = entry.summary;
        let _ = writeln!(
            toml,
            "# [[sensors]]               # {}: {} (orientation not read)",
            c.direction, c.location
        );
        let _ = writeln!(toml, "# name = \"ch{}\"", c.channel);
        let _ = writeln!(toml, "# direction = \"?\"\n");
    }
}

/// The station all records are of (refused when they name several).
fn one_station(records: &[StationRecord]) -> Result<Station> {
    let mut seen: BTreeMap<String, (Station, Vec<&str>)> = BTreeMap::new();
    for r in records {
        for c in &r.channels {
            if let Some(s) = &c.station {
                // `01336` and `1336` (the older layout) are one station.
                let number = s.number.trim_start_matches('0').to_string();
                let entry = seen.entry(number).or_insert_with(|| (s.clone(), Vec::new()));
                if !entry.1.contains(&r.file.as_str()) {
                    entry.1.push(&r.file);
                }
            }
        }
    }
    match seen.len() {
        0 => bail!("the records name no station (no \"Station No.\" line in their headers)"),
        1 => Ok(seen.into_values().next().expect("one").0),
        _ => bail!(
            "the records are of several stations: {}; give one station's records",
            seen.iter()
                .map(|(n, (_, files))| format!("{n} ({})", files.join(", ")))
                .collect::<Vec<_>>()
                .join("; ")
        ),
    }
}

/// Every channel of the records, by station channel: the description most
/// records give, the records without it and the other descriptions.
fn union_of_channels(records: &[StationRecord]) -> Vec<ChannelEntry<'_>> {
    let mut by_channel: BTreeMap<u32, Vec<(&str, &V2Summary)>> = BTreeMap::new();
    for r in records {
        for c in &r.channels {
            by_channel.entry(c.channel).or_default().push((&r.file, c));
        }
    }
    by_channel
        .into_values()
        .map(|copies| {
            let describe = |c: &V2Summary| format!("{}: {}", c.direction, c.location);
            let mut counts: BTreeMap<String, usize> = BTreeMap::new();
            for (_, c) in &copies {
                *counts.entry(describe(c)).or_default() += 1;
            }
            let common = counts
                .iter()
                .max_by_key(|(_, n)| **n)
                .map(|(d, _)| d.clone())
                .unwrap_or_default();
            let summary = copies.iter().find(|(_, c)| describe(c) == common).expect("counted").1;
            let present: Vec<&str> = copies.iter().map(|(f, _)| *f).collect();
            ChannelEntry {
                summary,
                missing_from: records
                    .iter()
                    .map(|r| r.file.as_str())
                    .filter(|f| !present.contains(f))
                    .collect(),
                other_descriptions: counts.keys().filter(|d| **d != common).cloned().collect(),
            }
        })
        .collect()
}

/// What to say of a channel in a comment: records that lack it, other
/// descriptions.
fn entry_notes(entry: &ChannelEntry) -> Vec<String> {
    let mut notes = Vec::new();
    if !entry.missing_from.is_empty() {
        let names: Vec<&str> = entry
            .missing_from
            .iter()
            .map(|f| f.rsplit(['/', '\\']).next().unwrap_or(f))
            .collect();
        notes.push(format!("not in {}", names.join(", ")));
    }
    for d in &entry.other_descriptions {
        notes.push(format!("some records describe it as {d:?}"));
    }
    notes
}

/// The support group of a ground location: its words less the generic ones,
/// joined by `_` (`On Ground: Near East Abutment` → `east_abutment`).
pub fn group_name(location: &str) -> String {
    const GENERIC: [&str; 10] = ["on", "ground", "grnd", "level", "at", "of", "the", "near", "in", "and"];
    let words: Vec<String> = location
        .to_ascii_lowercase()
        .split(|c: char| !c.is_ascii_alphanumeric())
        .filter(|w| !w.is_empty() && !GENERIC.contains(w))
        .map(str::to_string)
        .collect();
    if words.is_empty() {
        "ground".into()
    } else {
        words.join("_")
    }
}

/// The config's direction of a channel: `z`, `x`, `y`, or an azimuth turned
/// onto the nearest of `±x`, `±y` (a guess said when it is more than a
/// degree off, or when no axis was given).
fn axis_of(c: &V2Summary, axis_deg: Option<f64>, guesses: &mut Vec<String>) -> &'static str {
    match Orientation::parse(&c.direction).expect("read above") {
        Orientation::Up => "z",
        Orientation::Longitudinal => "x",
        Orientation::Transverse => "y",
        Orientation::Azimuth(azimuth) => {
            let reference = axis_deg.unwrap_or(0.0);
            let relative = (azimuth - reference).rem_euclid(360.0);
            let quarter = ((relative / 90.0).round() as usize) % 4;
            let off = (relative - 90.0 * (relative / 90.0).round()).abs();
            let direction = ["x", "y", "-x", "-y"][quarter];
            if axis_deg.is_none() {
                guesses.push(format!(
                    "ch{} points at {azimuth}°: without --axis (the azimuth of the longitudinal axis) taken on compass axes, x north and y east: {direction}",
                    c.channel
                ));
            } else if off > 1.0 {
                guesses.push(format!(
                    "ch{} points at {azimuth}°, {off:.0}° off the structure's axes (x at {reference}°): taken as {direction}",
                    c.channel
                ));
            }
            direction
        }
    }
}

/// The file's opening comment and `[structure]`.
fn header(station: &Station, records: &[StationRecord], axis_deg: Option<f64>) -> String {
    let mut text = String::new();
    let _ = writeln!(
        text,
        "# CSMIP station {}: {} ({:.3}°, {:.3}°)",
        station.number, station.name, station.latitude, station.longitude
    );
    let _ = writeln!(
        text,
        "# A starter config written by `splinewatch station` from {} record{}:",
        records.len(),
        if records.len() == 1 { "" } else { "s" }
    );
    for r in records {
        let _ = writeln!(text, "#   {}", r.file);
    }
    let _ = writeln!(
        text,
        "# Axes: x along the structure (Long), y across it (Tran), z up{}.",
        axis_deg.map_or(String::new(), |a| format!("; the longitudinal axis points at {a}°"))
    );
    let _ = writeln!(
        text,
        "# Ground channels: a location naming {} (unless it names {}).",
        GROUND_WORDS.join(", "),
        STRUCTURE_WORDS.join(", ")
    );
    text.push_str("# It serves `identify` (input-output, from the ground channels), `oma` and `events`\n");
    text.push_str("# (each event identified, judged on its modes, and forecast by the previous event's\n");
    text.push_str("# realization) as it is; `predict` and `update` need a [model] of the structure.\n\n");
    let _ = writeln!(text, "[structure]\nname = \"station-{}\"\n", station.number);
    text
}

/// `[oma]` (SRIM of an earthquake record: the settings measured on the
/// Painter Street records, the horizon in seconds so that records at any
/// rate share it, resampled to 50 Hz: a bridge's modes lie below 25 Hz) and `[events]` (the structure's horizontal channels).
fn analysis_sections(structure: &[&ChannelEntry]) -> String {
    let horizontal: Vec<String> = structure
        .iter()
        .filter(|e| !matches!(Orientation::parse(&e.summary.direction), Some(Orientation::Up)))
        .map(|e| format!("\"ch{}\"", e.summary.channel))
        .collect();
    let mut text = String::new();
    text.push_str("[oma]                       # SRIM of an earthquake record: a horizon of 1 s at any rate,\n");
    text.push_str("horizon_seconds = 1.0       # eight batches for the standard deviations, orders 2-60 by 2\n");
    text.push_str("resample_hz = 50.0          # records resampled to 50 Hz: the modes sought below 25 Hz\n");
    text.push_str("batches = 8\nmax_order = 60\norder_step = 2\n\n");
    text.push_str("[oma.clustering]            # every mode found keeps its std across the batches\n");
    text.push_str("replicate_distance = 0.1\n\n");
    if !horizontal.is_empty() {
        text.push_str("[events]                    # the structure's horizontal channels\n");
        let _ = writeln!(text, "outputs = [{}]", horizontal.join(", "));
    }
    text
}

/// The transverse (`y`) channels, for the frequency-domain fit.
#[derive(Default)]
struct Transverse {
    /// Quoted names.
    structure: Vec<String>,
    /// Quoted names and locations.
    ground: Vec<(String, String)>,
}

impl Transverse {
    /// `[oma.frequency_domain]`: the structure's transverse channels per
    /// one transverse ground channel (a bent's, pier's or column's when
    /// there is one: the support that moves most of the deck's mass; the
    /// first otherwise), one estimate each (few averages in an earthquake
    /// record do not separate several coherent grounds); empty without them.
    fn section(&self) -> String {
        let below = ["bent", "pier", "column"];
        let input = self
            .ground
            .iter()
            .find(|(_, location)| {
                let lower = location.to_ascii_lowercase();
                below.iter().any(|w| lower.contains(w))
            })
            .or(self.ground.first());
        let Some((input, location)) = input.filter(|_| !self.structure.is_empty()) else {
            return String::new();
        };
        let mut text = String::new();
        text.push_str(
            "\n[oma.frequency_domain]      # the transverse modes from the transmissibilities (a pole-residue fit),\n",
        );
        text.push_str("band = [1.0, 10.0]          # two in 1-10 Hz: narrow the band around the mode once the first\n");
        text.push_str("modes = 2                   # records show it (a band that holds it and little else)\n");
        let _ = writeln!(
            text,
            "inputs = [{input}]{:pad$}# {location}",
            "",
            pad = 17usize.saturating_sub(input.len())
        );
        let _ = writeln!(text, "outputs = [{}]", self.structure.join(", "));
        text
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ground_locations_become_groups_by_their_own_words() {
        assert_eq!(group_name("On Ground: Near East Abutment"), "east_abutment");
        assert_eq!(group_name("Middle Bent: Column at Grnd Level"), "middle_bent_column");
        assert_eq!(group_name("Abutment 1"), "abutment_1");
        assert_eq!(
            group_name("FOOTING OF CENTER COLUMN: W. EDGE"),
            "footing_center_column_w_edge"
        );
        assert_eq!(group_name("On Ground"), "ground");
    }

    /// An azimuth is turned onto the structure's axes by the longitudinal
    /// axis' azimuth: with x at 270° (west), a channel at 0° (north) is +y
    /// only if y is 90° clockwise from x, which it is (x west, y north).
    #[test]
    fn azimuths_turn_onto_the_structures_axes() {
        let channel = |direction: &str| V2Summary {
            channel: 1,
            direction: direction.into(),
            location: "Freefield".into(),
            rate_hz: 100.0,
            points: 10,
            peak: 1.0,
            unit: "cm/s^2".into(),
            file: "a.V2".into(),
            station: None,
        };
        let mut guesses = Vec::new();
        assert_eq!(axis_of(&channel("360 Deg"), Some(270.0), &mut guesses), "y");
        assert_eq!(axis_of(&channel("270 Deg"), Some(270.0), &mut guesses), "x");
        assert_eq!(axis_of(&channel("90 Deg"), Some(270.0), &mut guesses), "-x");
        assert!(guesses.is_empty(), "{guesses:?}");
        assert_eq!(axis_of(&channel("20 Deg"), Some(270.0), &mut guesses), "y");
        assert!(guesses[0].contains("20° off"), "{guesses:?}");
        assert_eq!(axis_of(&channel("Up"), None, &mut guesses), "z");
        assert_eq!(guesses.len(), 1);
    }
}
