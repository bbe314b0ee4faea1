//! Universal file format (UFF, `.uff`/`.unv`). Read: FRFs from dataset 58 (ASCII) and
//! 58b (binary) function type 4 (frequency response function), with the
//! ordinary coherence of the same pair (function type 6) when the file has
//! it, and dataset 164's units; time responses (function type 1) from
//! either for `import` ([`read_time_responses`]). The lingua franca of modal-testing software
//! (Simcenter Testlab, ME'scope, pyuff, sdypy).
//!
//! Response and reference are mapped to the config's sensors by node
//! (`[[sensors]] uff_node`) and direction: codes ±1/±2/±3 are ±x/±y/±z, a
//! negative code flips the sign of the data. Values are converted to SI with
//! dataset 164's length and force factors raised to the ordinate's unit
//! exponents (numerator minus denominator); without a dataset 164 the file
//! is taken as SI.
//!
//! Write ([`mod@write`]): units (164), the sensors as nodes (15) and a trace
//! line through them (82), FRFs and coherences (58), and mode shapes at the
//! nodes (55), so modal-testing software shows and animates them.

mod read;
pub mod write;

pub use read::{looks_like_uff, read_frfs, read_time_responses, TimeResponse, UffError};

/// A measurement point: a sensor's node, position (m) and measuring axis.
#[derive(Debug, Clone, PartialEq)]
pub struct UffPoint {
    pub name: String,
    pub node: i64,
    pub position: [f64; 3],
    /// The global axis (0 x, 1 y, 2 z) and sign; `None` for an oblique
    /// sensor, which has no UFF direction code.
    pub axis: Option<(usize, f64)>,
}

impl UffPoint {
    /// The UFF direction code: ±1/±2/±3 for ±x/±y/±z.
    pub(crate) fn direction_code(&self) -> Result<i64, String> {
        match self.axis {
            Some((axis, sign)) => Ok((axis as i64 + 1) * if sign < 0.0 { -1 } else { 1 }),
            None => Err(format!(
                "sensor {:?} measures along no global axis: a universal file has no direction code for it",
                self.name
            )),
        }
    }

    /// The unit vector the sensor measures along.
    pub(crate) fn direction(&self) -> [f64; 3] {
        let mut d = [0.0; 3];
        if let Some((axis, sign)) = self.axis {
            d[axis] = sign;
        }
        d
    }
}

/// Fixed-width field `[from, to)` of a record (shorter records pad).
pub(crate) fn field(line: &str, from: usize, to: usize) -> &str {
    line.get(from.min(line.len())..to.min(line.len())).unwrap_or("").trim()
}

/// A Fortran real: `E` or `D` exponent.
pub(crate) fn fortran_real(token: &str) -> Option<f64> {
    token.replace(['D', 'd'], "E").parse().ok()
}

/// Every whitespace-separated real of a dataset's data records; on failure
/// the record's offset and the token.
pub(crate) fn record_values(records: &[&str]) -> Result<Vec<f64>, (usize, String)> {
    let mut data = Vec::new();
    for (k, line) in records.iter().enumerate() {
        for token in line.split_whitespace() {
            data.push(fortran_real(token).ok_or_else(|| (k, token.to_string()))?);
        }
    }
    Ok(data)
}
