//! The FRF JSON format, shared by `synth`, `update` and (later) `frf`:
//!
//! ```json
//! {"quantity":"receptance|mobility|accelerance","frequency_hz":[…],
//!  "frfs":[{"input":"P1","output":"P2","re":[…],"im":[…],
//!           "coherence":[…],"n_averages":N}]}
//! ```
//! `coherence` and `n_averages` are optional. Sensor names refer to the
//! config's `[[sensors]]`. A recorded or published FRF message may carry
//! `start_timestamp` and `end_timestamp` (RFC 3339): the span it was
//! estimated over.

use serde::{Deserialize, Serialize};
use splinewatch_core::c64;
use splinewatch_core::response::frf::Quantity;
use splinewatch_core::updating::frf_residual::{MeasuredFrf, MeasuredSet};
use splinewatch_core::updating::UpdateError;
use thiserror::Error;

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrfFile {
    pub quantity: Quantity,
    pub frequency_hz: Vec<f64>,
    pub frfs: Vec<FrfEntry>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub start_timestamp: Option<String>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub end_timestamp: Option<String>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrfEntry {
    pub input: String,
    pub output: String,
    pub re: Vec<f64>,
    pub im: Vec<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub coherence: Option<Vec<f64>>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub n_averages: Option<f64>,
}

#[derive(Debug, Error)]
pub enum FrfFileError {
    #[error("not valid FRF JSON: {0}")]
    Json(#[from] serde_json::Error),
    #[error("frfs[{index}].{field}: unknown sensor {name:?} (config sensors: {known})")]
    UnknownSensor {
        index: usize,
        field: &'static str,
        name: String,
        known: String,
    },
    #[error("frfs[{index}]: re has {re} values, im has {im}")]
    Lengths { index: usize, re: usize, im: usize },
    #[error("{0}")]
    Data(#[from] UpdateError),
}

/// The `end_timestamp` of an FRF message (ns), if it has a valid one: the
/// measurement time a recorder files it under.
pub fn message_end_ns(payload: &[u8]) -> Option<i128> {
    #[derive(Deserialize)]
    struct End {
        end_timestamp: Option<String>,
    }
    let end: End = serde_json::from_slice(payload).ok()?;
    crate::io::wire::parse_timestamp(&end.end_timestamp?)
}

impl FrfFile {
    pub fn parse(text: &str) -> Result<Self, FrfFileError> {
        Ok(serde_json::from_str(text)?)
    }

    /// Resolves sensor names against `sensor_names` and validates the data.
    pub fn to_measured(&self, sensor_names: &[String]) -> Result<MeasuredSet, FrfFileError> {
        let index_of = |index: usize, field: &'static str, name: &str| {
            sensor_names
                .iter()
                .position(|n| n == name)
                .ok_or_else(|| FrfFileError::UnknownSensor {
                    index,
                    field,
                    name: name.to_string(),
                    known: sensor_names.join(", "),
                })
        };
        let mut frfs = Vec::with_capacity(self.frfs.len());
        for (index, e) in self.frfs.iter().enumerate() {
            if e.re.len() != e.im.len() {
                return Err(FrfFileError::Lengths {
                    index,
                    re: e.re.len(),
                    im: e.im.len(),
                });
            }
            frfs.push(MeasuredFrf {
                output: index_of(index, "output", &e.output)?,
                input: index_of(index, "input", &e.input)?,
                values: e.re.iter().zip(&e.im).map(|(&r, &i)| c64::new(r, i)).collect(),
                coherence: e.coherence.clone(),
                n_averages: e.n_averages,
            });
        }
        Ok(MeasuredSet::new(self.quantity, self.frequency_hz.clone(), frfs)?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    const GOOD: &str = r#"{"quantity":"accelerance","frequency_hz":[1.0,2.0],"frfs":[{"input":"P1","output":"P2","re":[0.1,0.2],"im":[0.0,0.1],"coherence":[0.9,1.0],"n_averages":4}]}"#;

    #[test]
    fn good_file_resolves_sensor_names() {
        let names = vec!["P1".to_string(), "P2".to_string()];
        let set = FrfFile::parse(GOOD).unwrap().to_measured(&names).unwrap();
        assert_eq!(set.frfs()[0].output, 1);
        assert_eq!(set.frfs()[0].input, 0);
    }

    proptest! {
        #[test]
        fn arbitrary_text_never_panics(text in ".{0,300}") {
            let names = vec!["P1".to_string(), "P2".to_string()];
            if let Ok(f) = FrfFile::parse(&text) {
                let _ = f.to_measured(&names);
            }
        }

        #[test]
        fn mutated_files_never_panic(flips in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 1..6)) {
            let mut bytes = GOOD.as_bytes().to_vec();
            for (i, b) in &flips {
                let k = i.index(bytes.len());
                bytes[k] = *b;
            }
            if let Ok(text) = std::str::from_utf8(&bytes) {
                if let Ok(f) = FrfFile::parse(text) {
                    let _ = f.to_measured(&["P1".to_string(), "P2".to_string()]);
                }
            }
        }
    }
}
