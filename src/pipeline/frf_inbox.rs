//! Pre-computed FRFs from loggers that make them: collected per
//! force → acceleration pair until a complete set becomes an update job.

use super::{Pipeline, UpdateJob};
use crate::io::frf_json::FrfFile;

impl Pipeline {
    /// Takes a pre-computed FRF message (the FRF JSON object, usually with a
    /// single entry). Once every force → acceleration pair of the config has
    /// arrived on the same frequency axis, the set becomes an update job
    /// (numbered after the windows, from 1 000 000) and the inbox empties. A
    /// message on another axis starts a new set. Returns the job, if any.
    /// An output-only config has no force sensor to pair: its FRF messages
    /// are rejected as `frf_without_force_sensor`.
    pub fn ingest_frf(&mut self, payload: &[u8], time_ns: i128) -> Option<UpdateJob> {
        let Some(force) = self.force else {
            self.health.reject("frf_without_force_sensor");
            return None;
        };
        let file = match std::str::from_utf8(payload).ok().and_then(|t| FrfFile::parse(t).ok()) {
            Some(f) => f,
            None => {
                self.health.reject("bad_frf");
                return None;
            }
        };
        let known = |n: &str| self.setup.sensor_names.iter().any(|s| s == n);
        if file.frfs.is_empty()
            || file.frfs.iter().any(|e| {
                !known(&e.input)
                    || !known(&e.output)
                    || e.re.len() != file.frequency_hz.len()
                    || e.im.len() != e.re.len()
            })
        {
            self.health.reject("bad_frf");
            return None;
        }
        let axis = (file.quantity, file.frequency_hz.clone());
        if self.frf_axis.as_ref() != Some(&axis) {
            self.frf_inbox.clear();
            self.frf_axis = Some(axis);
        }
        for e in file.frfs {
            self.frf_inbox.insert((e.input.clone(), e.output.clone()), e);
        }
        let force = self.setup.sensor_names[force].clone();
        let wanted: Vec<(String, String)> = self
            .accels
            .iter()
            .map(|&i| (force.clone(), self.setup.sensor_names[i].clone()))
            .collect();
        if !wanted.iter().all(|k| self.frf_inbox.contains_key(k)) {
            return None;
        }
        let (quantity, frequency_hz) = self.frf_axis.clone().expect("set above");
        let frfs = wanted
            .iter()
            .map(|k| self.frf_inbox.remove(k).expect("checked"))
            .collect();
        self.frf_inbox.clear();
        self.frf_sets += 1;
        let measured = FrfFile {
            quantity,
            frequency_hz,
            frfs,
        };
        Some(self.job(1_000_000 + self.frf_sets - 1, time_ns, super::Measured::Frf(measured)))
    }
}
