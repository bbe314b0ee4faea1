//! A prediction of a shaken deck (`predict --rerun-save`): per deck channel the
//! measured, predicted and "deck = nearest ground" accelerations as time
//! series on the record's own time line (`measurement_time`), sent by columns.

use super::{rerun_error, RerunOutput};
use anyhow::Result;

/// One deck channel of a prediction.
pub struct PredictedChannel<'a> {
    pub sensor: &'a str,
    pub measured: &'a [f64],
    pub predicted: &'a [f64],
    pub baseline: &'a [f64],
}

impl RerunOutput {
    /// Logs `channels` sampled at `fs` from `start_ns` under
    /// `predict/<sensor>/{measured,predicted,baseline}`.
    pub fn log_prediction(&mut self, start_ns: i128, fs: f64, channels: &[PredictedChannel<'_>]) -> Result<()> {
        for c in channels {
            let times = || {
                rerun::TimeColumn::new_timestamp_nanos_since_epoch(
                    "measurement_time",
                    (0..c.measured.len()).map(|k| {
                        let t = start_ns + (k as f64 * 1e9 / fs).round() as i128;
                        t.clamp(0, i64::MAX as i128) as i64
                    }),
                )
            };
            for (what, data) in [
                ("measured", c.measured),
                ("predicted", c.predicted),
                ("baseline", c.baseline),
            ] {
                let columns = rerun::Scalars::update_fields()
                    .with_scalars(data.iter().copied())
                    .columns_of_unit_batches()
                    .map_err(|e| anyhow::anyhow!("Rerun output: {e}"))?;
                self.rec
                    .send_columns(format!("predict/{}/{what}", c.sensor), [times()], columns)
                    .map_err(rerun_error)?;
            }
        }
        Ok(())
    }
}
