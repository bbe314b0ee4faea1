//! What a channel's header says of where it points and where it sits, in
//! the words strong-motion stations use: `Up`, `Tran`, `Long`, `270 Deg`;
//! `Freefield`, `Footing of Center Column`, `Deck: Middle of Bridge`.

/// The direction a channel's `Chan N:` line gives it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Orientation {
    Up,
    /// Across the structure (`Tran`).
    Transverse,
    /// Along the structure (`Long`).
    Longitudinal,
    /// A compass azimuth in degrees, in `[0, 360)` (`360 Deg` is north, 0).
    Azimuth(f64),
}

impl Orientation {
    /// `Up`, `UP`, `Vert`, `Tran`, `Long`, `270 Deg`, `360 DEG`, `90`;
    /// `None` for what is none of these.
    pub fn parse(text: &str) -> Option<Self> {
        let lower = text.trim().to_ascii_lowercase();
        let word = lower.split_whitespace().next()?;
        match word {
            "up" | "upward" | "vert" | "vertical" | "v" => Some(Self::Up),
            "tran" | "trans" | "transverse" | "t" => Some(Self::Transverse),
            "long" | "longitudinal" | "l" => Some(Self::Longitudinal),
            _ => {
                let degrees: f64 = word.trim_end_matches("deg").trim_end_matches('°').parse().ok()?;
                (degrees.is_finite() && (-360.0..=360.0).contains(&degrees))
                    .then(|| Self::Azimuth(degrees.rem_euclid(360.0)))
            }
        }
    }

    /// Whether two channels measure along the same line in the same sense
    /// (azimuths within half a degree).
    pub fn same_as(self, other: Self) -> bool {
        match (self, other) {
            (Self::Azimuth(a), Self::Azimuth(b)) => {
                let d = (a - b).rem_euclid(360.0);
                d.min(360.0 - d) < 0.5
            }
            (a, b) => a == b,
        }
    }
}

/// Where a channel sits, as far as driving the structure goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Placement {
    /// On the ground or a foundation: free field, embankment, footing,
    /// pile cap, a column's or bent's base, an abutment's seat.
    Ground,
    /// On the structure the ground drives: deck, girder, bent cap, a
    /// column's top.
    Structure,
}

/// Words of a location that put a channel on the structure; they win over
/// [`GROUND_WORDS`] (`Deck: Near South Abutment` is on the deck).
pub const STRUCTURE_WORDS: [&str; 8] = [
    "deck", "girder", "span", "midspan", "bent cap", "top", "roof", "cap beam",
];

/// Words of a location that put a channel on the ground or a foundation.
pub const GROUND_WORDS: [&str; 12] = [
    "free field",
    "freefield",
    "ground",
    "grnd",
    "bottom of",
    "embankment",
    "footing",
    "pile cap",
    "base of",
    "bent base",
    "abutment",
    "downhole",
];

impl Placement {
    /// The placement a location text gives by the rules above (each word
    /// matched at a word's start: "top" is not "stop"), `None` when it
    /// names neither.
    pub fn of(location: &str) -> Option<Self> {
        let lower = format!(
            " {}",
            location
                .to_ascii_lowercase()
                .replace(|c: char| !c.is_ascii_alphanumeric(), " ")
        );
        let has = |w: &&str| lower.contains(&format!(" {w}"));
        if STRUCTURE_WORDS.iter().any(has) {
            Some(Self::Structure)
        } else if GROUND_WORDS.iter().any(has) {
            Some(Self::Ground)
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orientations_in_the_stations_words() {
        assert_eq!(Orientation::parse("Up"), Some(Orientation::Up));
        assert_eq!(Orientation::parse("UP"), Some(Orientation::Up));
        assert_eq!(Orientation::parse("Tran"), Some(Orientation::Transverse));
        assert_eq!(Orientation::parse("Long"), Some(Orientation::Longitudinal));
        assert_eq!(Orientation::parse("270 Deg"), Some(Orientation::Azimuth(270.0)));
        assert_eq!(Orientation::parse("360 DEG"), Some(Orientation::Azimuth(0.0)));
        assert_eq!(Orientation::parse("Radial"), None);
        assert!(Orientation::parse("360 Deg")
            .unwrap()
            .same_as(Orientation::Azimuth(0.2)));
        assert!(!Orientation::Azimuth(90.0).same_as(Orientation::Azimuth(270.0)));
    }

    #[test]
    fn placements_by_the_location_words() {
        assert_eq!(Placement::of("Freefield"), Some(Placement::Ground));
        assert_eq!(
            Placement::of("Footing of Center Column: W. Edge"),
            Some(Placement::Ground)
        );
        assert_eq!(Placement::of("South Embankment"), Some(Placement::Ground));
        assert_eq!(Placement::of("Deck: Near South Abutment"), Some(Placement::Structure));
        assert_eq!(Placement::of("Abutment 1"), Some(Placement::Ground));
        assert_eq!(Placement::of("Pier 3"), None);
        assert_eq!(
            Placement::of("Middle Bent: Column at Grnd Level"),
            Some(Placement::Ground)
        );
        assert_eq!(Placement::of("Middle Bent: Top of Column"), Some(Placement::Structure));
        assert_eq!(Placement::of("Bent 4: North Column, Top"), Some(Placement::Structure));
        assert_eq!(Placement::of("Bent 4: Bottom of Column"), Some(Placement::Ground));
        assert_eq!(Placement::of("Midspan Between Bents 4 & 5"), Some(Placement::Structure));
        assert_eq!(Placement::of("On Ground: Near West Abutment"), Some(Placement::Ground));
    }
}
