//! Windows: aligned samples stream into the open windows (Welch estimators,
//! or, output-only, the samples themselves); a window that ends is accepted
//! or skipped with a reason, and may trigger an update.

use super::{Measured, Pipeline, UpdateJob, WindowModes, WindowReport};
use crate::config::Residues;
use crate::io::frf_json::FrfFile;
use splinewatch_core::identification::welch::{WelchEstimator, WelchSettings};
use std::sync::Arc;

/// What an open window accumulates: the FRF path's Welch estimator (force
/// first), the output-only path's samples per output channel (NaN where
/// missing), or both.
pub(super) struct WindowData {
    welch: Option<Box<WelchEstimator>>,
    samples: Option<Vec<Vec<f64>>>,
}

impl Pipeline {
    fn open_window(&self) -> WindowData {
        WindowData {
            welch: self.welch.as_ref().map(|(settings, _)| {
                Box::new(WelchEstimator::new(settings.clone(), self.accels.len()).expect("validated"))
            }),
            samples: self
                .identification
                .is_some()
                .then(|| vec![Vec::with_capacity(self.window_samples as usize); self.accels.len()]),
        }
    }

    /// Feeds every sample available on all channels to the open windows,
    /// opening and closing windows on the way.
    pub(super) fn feed(&mut self, windows: &mut Vec<WindowReport>, jobs: &mut Vec<UpdateJob>) {
        loop {
            let next_start = self.window_index as i64 * self.hop_samples;
            if next_start == self.fed {
                let data = self.open_window();
                self.open.push_back((self.window_index, data));
                self.window_index += 1;
                continue;
            }
            let frontier = self
                .queues
                .iter()
                .map(|q| if q.seen { q.end() } else { self.fed })
                .min()
                .unwrap_or(self.fed);
            let oldest_end = self
                .open
                .front()
                .map_or(i64::MAX, |(k, _)| *k as i64 * self.hop_samples + self.window_samples);
            let until = frontier.min(next_start).min(oldest_end);
            if until > self.fed {
                self.push_samples((until - self.fed) as usize);
                self.fed = until;
            }
            if self.fed == oldest_end {
                let (index, data) = self.open.pop_front().expect("an open window ends here");
                let report = self.close_window(index, data);
                if report.skipped.is_none() {
                    self.schedule_update(&report, jobs);
                }
                windows.push(report);
                continue;
            }
            break;
        }
    }

    /// Moves the next `n` aligned samples of every channel into the open
    /// windows, straight from the channel queues (made contiguous; no copy
    /// in between).
    fn push_samples(&mut self, n: usize) {
        let fed = self.fed;
        for q in &mut self.queues {
            let skip = ((fed - q.first).max(0) as usize).min(q.data.len());
            q.data.drain(..skip);
            q.first += skip as i64;
            q.data.make_contiguous();
        }
        let cols: Vec<&[f64]> = self
            .queues
            .iter()
            .map(|q| {
                let (front, _) = q.data.as_slices();
                &front[..n.min(front.len())]
            })
            .collect();
        let first_output = usize::from(self.force.is_some());
        let outputs = &cols[first_output..];
        for (_, data) in &mut self.open {
            if let Some(welch) = &mut data.welch {
                welch.push(cols[0], outputs).expect("equal lengths by construction");
            }
            if let Some(samples) = &mut data.samples {
                for (s, c) in samples.iter_mut().zip(outputs) {
                    s.extend_from_slice(c);
                }
            }
        }
        for q in &mut self.queues {
            let taken = n.min(q.data.len());
            q.data.drain(..taken);
            q.first += taken as i64;
        }
    }

    /// An accepted window counts towards the schedule; a due update becomes a job.
    fn schedule_update(&mut self, report: &WindowReport, jobs: &mut Vec<UpdateJob>) {
        self.accepted_since_update += 1;
        let since = *self
            .last_update_ns
            .get_or_insert(self.t0.expect("set with the reference"));
        let due = match self.schedule.update_every_minutes {
            Some(minutes) => (report.end_ns - since) as f64 >= minutes * 60e9,
            None => self.accepted_since_update >= self.schedule.update_every_windows,
        };
        if !due {
            return;
        }
        self.accepted_since_update = 0;
        self.last_update_ns = Some(report.end_ns);
        // `[updating] residues`; with both, a window that produced one part
        // is updated on that part (`updating/parameters` says which).
        let modes = || report.modes.as_ref().map(|m| m.report.modes_file());
        let measured = match (self.residues, report.frf.clone(), modes()) {
            (Residues::Frf, Some(frf), _) => Measured::Frf(frf),
            (Residues::Modes, _, Some(modes)) => Measured::Modes(modes),
            (Residues::Both, Some(frf), Some(modes)) => Measured::Both(frf, modes),
            (Residues::Both, Some(frf), None) => Measured::Frf(frf),
            (Residues::Both, None, Some(modes)) => Measured::Modes(modes),
            _ => return,
        };
        jobs.push(self.job(report.index, (report.start_ns, report.end_ns), measured));
    }

    /// `(start, end)` of window `index` in measurement time (ns).
    fn window_span(&self, index: u64) -> (i128, i128) {
        let fs = self.fs.expect("set with the reference");
        let t0 = self.t0.expect("set with the reference");
        let start = index as i64 * self.hop_samples;
        let start_ns = t0 + (start as f64 * 1e9 / fs).round() as i128;
        let end_ns = t0 + ((start + self.window_samples) as f64 * 1e9 / fs).round() as i128;
        (start_ns, end_ns)
    }

    /// A window that ended: its FRFs (FRF path) and its identified modes
    /// (output-only path), each produced or failed with a reason. The
    /// window is skipped when the updates get nothing to fit from it; with
    /// both paths, a path that failed says why in `frf_skipped` /
    /// `oma_skipped` (and `window_paths_skipped` counts it).
    fn close_window(&mut self, index: u64, data: WindowData) -> WindowReport {
        let (start_ns, end_ns) = self.window_span(index);
        let mut report = WindowReport {
            index,
            start_ns,
            end_ns,
            segments_accepted: 0,
            segments_rejected: 0,
            mean_coherence: Vec::new(),
            skipped: None,
            frf: None,
            valid_fraction: None,
            modes: None,
            frf_skipped: None,
            oma_skipped: None,
        };
        let frf = data.welch.map(|welch| self.estimate_frfs(&mut report, *welch));
        let modes = data.samples.map(|samples| self.identify_window(&mut report, &samples));
        let both = frf.is_some() && modes.is_some();
        let frf_failed = frf.and_then(|r| r.map(|f| report.frf = Some(f)).err());
        let oma_failed = modes.and_then(|r| r.map(|m| report.modes = Some(Arc::new(m))).err());
        report.skipped = match self.residues {
            _ if !both => frf_failed.clone().or_else(|| oma_failed.clone()),
            Residues::Frf => frf_failed.clone(),
            Residues::Modes => oma_failed.clone(),
            Residues::Both => frf_failed.clone().filter(|_| oma_failed.is_some()),
        };
        if both {
            for (path, failed) in [("frf", &frf_failed), ("oma", &oma_failed)] {
                if let Some(reason) = failed {
                    *self
                        .health
                        .window_paths_skipped
                        .entry(format!("{path}:{reason}"))
                        .or_insert(0) += 1;
                }
            }
            (report.frf_skipped, report.oma_skipped) = (frf_failed, oma_failed);
        }
        self.count_window(&report);
        report
    }

    /// The FRF path: enough clean segments and coherence, then the FRFs in
    /// the band; the error is the reason.
    fn estimate_frfs(&mut self, report: &mut WindowReport, welch: WelchEstimator) -> Result<FrfFile, String> {
        let (_, estimator) = self.welch.as_ref().expect("set with the reference");
        let counts = welch.counts();
        self.health.segments_accepted += counts.accepted;
        self.health.segments_rejected += counts.rejected();
        (report.segments_accepted, report.segments_rejected) = (counts.accepted, counts.rejected());
        let settings: &WelchSettings = welch.settings();
        let possible = ((self.window_samples as usize).saturating_sub(settings.segment) / settings.step() + 1) as f64;
        if (counts.accepted as f64) < self.schedule.min_segment_fraction * possible || counts.accepted == 0 {
            return Err("too_little_data".into());
        }
        let est = welch.spectra().frf(*estimator);
        let [lo, hi] = self.config.frf.band;
        let lines: Vec<usize> = (0..est.frequencies.len())
            .filter(|&k| est.frequencies[k] > 0.0 && est.frequencies[k] >= lo && est.frequencies[k] <= hi)
            .collect();
        report.mean_coherence = est
            .coherence
            .iter()
            .map(|c| lines.iter().map(|&k| c[k]).sum::<f64>() / lines.len().max(1) as f64)
            .collect();
        if report
            .mean_coherence
            .iter()
            .any(|c| !(c.is_finite() && *c >= self.schedule.min_coherence))
        {
            return Err("low_coherence".into());
        }
        let force = self.force.expect("the FRF path has a force sensor");
        super::estimate::frf_file(&self.config, &est, force, &self.accels).ok_or_else(|| "no_lines_in_band".into())
    }

    /// The output-only path: enough valid instants, then SSI-cov and the
    /// pairing with the model's modes at the last update (see `oma.rs`); the
    /// error is the reason.
    fn identify_window(&mut self, report: &mut WindowReport, samples: &[Vec<f64>]) -> Result<WindowModes, String> {
        let n = samples.first().map_or(0, Vec::len);
        let valid = (0..n).filter(|&t| samples.iter().all(|c| !c[t].is_nan())).count();
        let fraction = valid as f64 / n.max(1) as f64;
        report.valid_fraction = Some(fraction);
        if fraction < self.schedule.min_segment_fraction || valid == 0 {
            return Err("too_little_data".into());
        }
        let (fs, start_ns) = (self.fs.expect("set with the reference"), report.start_ns);
        let identify = |p: &Self| {
            let identification = p.identification.as_ref().expect("the output-only path");
            identification.identify_window(samples, start_ns, fs)
        };
        // Split, the identification runs first, while the update side may
        // still apply earlier jobs, and the pairing waits for the model; in
        // line the model comes first (no identification without it). Either
        // way a failed model is the reason before a failed identification.
        let early = self.pairing.is_some().then(|| identify(self));
        let state = self.pairing_state()?;
        let identified = early.unwrap_or_else(|| identify(self));
        let identification = self.identification.as_ref().expect("the output-only path");
        identification
            .pair(identified?, &state, &self.setup.sensor_names)
            .map_err(String::from)
    }

    fn count_window(&mut self, report: &WindowReport) {
        match &report.skipped {
            None => self.health.windows_accepted += 1,
            Some(reason) => *self.health.windows_skipped.entry(reason.clone()).or_insert(0) += 1,
        }
    }
}
