//! What an event reports: its line of `events --json` and its parts.

use super::*;

/// One event's line of `events --json` (and its `events/summary` message).
#[derive(Debug, Clone, Serialize)]
pub struct EventLine {
    pub event: String,
    /// The event's number in its chain: 0 for the first event a state has
    /// seen, skipped events counted; the same from `events` and the daemon,
    /// and it goes on after a restart or a `--state` resume (the status
    /// message's `window`).
    pub number: u64,
    pub start: Option<String>,
    pub pga_ground: Option<f64>,
    pub peak_deck: Option<f64>,
    /// The RMS of every deck channel over the strong motion (5–95 % of the
    /// ground's energy), m/s².
    pub rms_deck: Option<f64>,
    pub modes: Vec<ModeEntry>,
    pub parameters: Vec<ParameterEstimate>,
    pub forecast: Option<PredictionReport>,
    /// The parameters the forecast's model had (`[events] forecast`).
    pub forecast_model: Vec<NamedValue>,
    /// The deck channels the forecast's headline medians (the table, the
    /// Rerun timeline, the status message) are taken over: `[events]
    /// outputs`, the channels the update fits, or every deck channel scored.
    pub forecast_channels: Vec<String>,
    pub verdict: Option<VerdictLine>,
    pub skipped: Option<String>,
    /// The update's relative residual and iterations; ground inputs combined.
    pub update: Option<UpdateLine>,
    /// What a stage could not do without skipping the event (an
    /// identification that found no mode).
    pub notes: Vec<String>,
}

impl EventLine {
    /// The event's amplitude as `[events] amplitude` measures it.
    pub fn amplitude(&self, kind: EventAmplitude) -> Option<f64> {
        match kind {
            EventAmplitude::PgaGround => self.pga_ground,
            EventAmplitude::RmsDeck => self.rms_deck,
        }
    }

    pub fn new(event: String) -> Self {
        Self {
            event,
            number: 0,
            start: None,
            pga_ground: None,
            peak_deck: None,
            rms_deck: None,
            modes: Vec::new(),
            parameters: Vec::new(),
            forecast: None,
            forecast_model: Vec::new(),
            forecast_channels: Vec::new(),
            verdict: None,
            skipped: None,
            update: None,
            notes: Vec::new(),
        }
    }

    /// An event recorded at `start_ns` and not processed, for `reason`.
    pub fn skipped(event: String, start_ns: i128, reason: String) -> Self {
        Self {
            start: Some(format_timestamp(start_ns)),
            skipped: Some(reason),
            ..Self::new(event)
        }
    }
}

#[derive(Debug, Clone, Serialize)]
pub struct UpdateLine {
    /// The updated model's dominant mode over the fitted channels (Hz).
    pub model_mode_hz: Option<f64>,
    /// Its standard deviation from the parameters' covariance (Hz).
    pub model_mode_std_hz: Option<f64>,
    pub relative_residual: f64,
    pub iterations: usize,
    pub converged: bool,
    /// Why the solver stopped (as `update --json` says it).
    pub stop_reason: StopReason,
    /// Residual evaluations, rejected trial steps included.
    pub evaluations: usize,
    /// The Bates–Watts relative offset at the solution.
    pub relative_offset: Option<f64>,
    pub combined_inputs: Vec<String>,
    /// What the update fitted (`[events] residues`, or `first_residues` on a chain's first event).
    pub residues: &'static str,
    /// The identified modes it fitted, with the model's they paired with.
    pub paired_modes: Vec<PairedMode>,
}

/// The verdict: `state` ("insufficient history", "normal", "alarm"), the
/// features outside their bands and every band.
#[derive(Debug, Clone, Serialize)]
pub struct VerdictLine {
    pub state: String,
    pub outside: Vec<String>,
    pub bands: Vec<BandLine>,
}

#[derive(Debug, Clone, Serialize)]
pub struct BandLine {
    pub feature: String,
    pub value: Option<f64>,
    pub band: Option<FeatureBand>,
}
