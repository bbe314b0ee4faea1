//! Pre-computed FRFs from loggers that make them: collected per
//! force → acceleration pair until a complete set becomes an update job.

use super::{Pipeline, UpdateJob};
use crate::io::frf_json::FrfFile;

impl Pipeline {
    /// Takes a pre-computed FRF message (the FRF JSON object, usually with a
    /// single entry) received or recorded at `time_ns`. Once every force →
    /// acceleration pair of the config has arrived on the same frequency
    /// axis, the set becomes an update job (a window, numbered from 0 in
    /// arrival order) and the inbox empties. A message on another axis
    /// starts a new set. The set's span runs from the earliest
    /// `start_timestamp` to the latest `end_timestamp` of its messages; a
    /// message without them ends at `time_ns` and lasts
    /// `frf.window_seconds`. Returns the job, if any.
    /// An output-only config has no force sensor to pair: its FRF messages
    /// are rejected as `frf_without_force_sensor`.
    pub fn ingest_frf(&mut self, payload: &[u8], time_ns: i128) -> Option<UpdateJob> {
        let job = self.collect_frf(payload, time_ns);
        self.hand_out(usize::from(job.is_some()));
        job
    }

    fn collect_frf(&mut self, payload: &[u8], time_ns: i128) -> Option<UpdateJob> {
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
        let stamp = |t: &Option<String>| t.as_deref().map(crate::io::wire::parse_timestamp);
        let end = match stamp(&file.end_timestamp) {
            None => time_ns,
            Some(Some(t)) => t,
            Some(None) => {
                self.health.reject("bad_frf_timestamp");
                return None;
            }
        };
        let start = match stamp(&file.start_timestamp) {
            None => end - (self.config.frf.window_seconds * 1e9).round() as i128,
            Some(Some(t)) if t < end => t,
            Some(_) => {
                self.health.reject("bad_frf_timestamp");
                return None;
            }
        };
        let axis = (file.quantity, file.frequency_hz.clone());
        if self.frf_axis.as_ref() != Some(&axis) {
            self.frf_inbox.clear();
            self.frf_axis = Some(axis);
            self.frf_span = None;
        }
        self.frf_span = Some(match self.frf_span {
            Some((s, e)) => (s.min(start), e.max(end)),
            None => (start, end),
        });
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
            start_timestamp: None,
            end_timestamp: None,
        };
        let span = self.frf_span.take().expect("set above");
        Some(self.job(self.frf_sets - 1, span, super::Measured::Frf(measured)))
    }
}
