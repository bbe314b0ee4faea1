//! Windows: aligned samples stream into the open Welch estimators; a window
//! that ends is accepted or skipped with a reason, and may trigger an update.

use super::align::ChannelQueue;
use super::{Pipeline, UpdateJob, WindowReport};
use splinewatch_core::welch::{WelchEstimator, WelchSettings};

impl Pipeline {
    /// Feeds every sample available on all channels to the open windows,
    /// opening and closing windows on the way.
    pub(super) fn feed(&mut self, windows: &mut Vec<WindowReport>, jobs: &mut Vec<UpdateJob>) {
        loop {
            let next_start = self.window_index as i64 * self.hop_samples;
            if next_start == self.fed {
                let (settings, _) = self.welch.as_ref().expect("set with the reference");
                let estimator = WelchEstimator::new(settings.clone(), self.accels.len()).expect("validated");
                self.open.push_back((self.window_index, estimator));
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
                let n = (until - self.fed) as usize;
                let mut take = |q: &mut ChannelQueue| -> Vec<f64> {
                    let skip = (self.fed - q.first).max(0) as usize;
                    q.data.drain(..skip.min(q.data.len()));
                    q.first += skip as i64;
                    let v: Vec<f64> = q.data.drain(..n.min(q.data.len())).collect();
                    q.first += v.len() as i64;
                    v
                };
                let cols: Vec<Vec<f64>> = self.queues.iter_mut().map(&mut take).collect();
                let outputs: Vec<&[f64]> = cols[1..].iter().map(|v| v.as_slice()).collect();
                for (_, welch) in &mut self.open {
                    welch.push(&cols[0], &outputs).expect("equal lengths by construction");
                }
                self.fed = until;
            }
            if self.fed == oldest_end {
                let (index, welch) = self.open.pop_front().expect("an open window ends here");
                let report = self.close_window(index, welch);
                if report.skipped.is_none() {
                    self.accepted_since_update += 1;
                    let since = *self
                        .last_update_ns
                        .get_or_insert(self.t0.expect("set with the reference"));
                    let due = match self.schedule.update_every_minutes {
                        Some(minutes) => (report.end_ns - since) as f64 >= minutes * 60e9,
                        None => self.accepted_since_update >= self.schedule.update_every_windows,
                    };
                    if due {
                        self.accepted_since_update = 0;
                        self.last_update_ns = Some(report.end_ns);
                        if let Some(frf) = &report.frf {
                            jobs.push(self.job(report.index, report.end_ns, frf.clone()));
                        }
                    }
                }
                windows.push(report);
                continue;
            }
            break;
        }
    }

    fn close_window(&mut self, index: u64, welch: WelchEstimator) -> WindowReport {
        let fs = self.fs.expect("set with the reference");
        let t0 = self.t0.expect("set with the reference");
        let start = index as i64 * self.hop_samples;
        let start_ns = t0 + (start as f64 * 1e9 / fs).round() as i128;
        let end_ns = t0 + ((start + self.window_samples) as f64 * 1e9 / fs).round() as i128;
        let (_, estimator) = self.welch.as_ref().expect("set with the reference");
        let counts = welch.counts();
        self.health.segments_accepted += counts.accepted;
        self.health.segments_rejected += counts.rejected();
        let settings: &WelchSettings = welch.settings();
        let possible = ((self.window_samples as usize).saturating_sub(settings.segment) / settings.step() + 1) as f64;
        let mut report = WindowReport {
            index,
            start_ns,
            end_ns,
            segments_accepted: counts.accepted,
            segments_rejected: counts.rejected(),
            mean_coherence: Vec::new(),
            skipped: None,
            frf: None,
        };
        if (counts.accepted as f64) < self.schedule.min_segment_fraction * possible || counts.accepted == 0 {
            report.skipped = Some("too_little_data".into());
        } else {
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
                report.skipped = Some("low_coherence".into());
            } else {
                report.frf = super::estimate::frf_file(&self.config, &est, self.force, &self.accels);
                if report.frf.is_none() {
                    report.skipped = Some("no_lines_in_band".into());
                }
            }
        }
        match &report.skipped {
            None => self.health.windows_accepted += 1,
            Some(reason) => *self.health.windows_skipped.entry(reason.clone()).or_insert(0) += 1,
        }
        report
    }
}
