//! Without a model: each event is forecast by the realization identified on
//! the event before it (SRIM's `A`, `C` over `[oma]`'s horizon, `B`, `D` by
//! least squares; stable by construction, see
//! [`splinewatch_core::identification::realization`]), driven by this
//! event's ground inputs and scored as `predict` scores a model's forecast;
//! then this event's own realization is kept for the next.

use super::*;
use crate::service::records::{at_identification_rate, rate_text};
use crate::studies::predict::{score_forecast, GroundsOf, Prediction};
use splinewatch_core::identification::realization::Realization;
use splinewatch_core::identification::srim;

/// A realization as the chain keeps it (`--state`): its channels by name,
/// so that a record with other channels is not forecast by it.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub(super) struct SavedRealization {
    /// The event it was identified on.
    event: String,
    /// The ground inputs (the plan's, group and axis), in order.
    inputs: Vec<String>,
    /// The deck sensors, in order.
    outputs: Vec<String>,
    realization: Realization,
}

/// What the stage without a model found: the forecast and what it said.
#[derive(Debug, Default)]
pub(super) struct Realized {
    pub(super) forecast: Option<PredictionReport>,
    pub(super) notes: Vec<String>,
}

/// The event (`name`, starting at `start`) forecast by the previous
/// event's realization (none for the first, or when the channels differ:
/// said in the notes), then this event's realization kept (when it cannot
/// be identified, said, and the previous one kept): what it found, and
/// whether it finished.
pub(super) fn forecast_and_realize(
    cfg: &Config,
    (event, plan): (&Event, &[GroundInputPlan]),
    chain: &mut Chain,
    (name, start): (&str, &Option<String>),
) -> (Realized, Result<()>) {
    let mut realized = Realized::default();
    let finished = realize_into(cfg, (event, plan), chain, (name, start), &mut realized);
    (realized, finished)
}

fn realize_into(
    cfg: &Config,
    (event, plan): (&Event, &[GroundInputPlan]),
    chain: &mut Chain,
    (name, start): (&str, &Option<String>),
    realized: &mut Realized,
) -> Result<()> {
    let channel = |i: usize| event.channels[i].as_deref().expect("aligned");
    let signals = ground_signals(plan, channel);
    let inputs: Vec<&[f64]> = signals.iter().map(Vec::as_slice).collect();
    let outputs: Vec<&[f64]> = event.deck.iter().map(|&i| channel(i)).collect();
    let input_names: Vec<String> = plan.iter().map(|p| p.name.clone()).collect();
    let output_names: Vec<String> = event.deck.iter().map(|&i| cfg.sensors[i].name.clone()).collect();
    if let Some(saved) = &chain.realization {
        forecast(cfg, saved, (event, plan), &inputs, (start, realized))?;
    }
    let record = at_identification_rate(cfg, &inputs, &outputs, event.fs);
    let (settings, _) = cfg.oma_settings_at(record.fs)?;
    let order = cfg.events().realization_order;
    match srim::realization(
        &record.inputs(),
        &record.outputs(),
        record.fs,
        settings.block_rows,
        order,
    ) {
        Ok(realization) => {
            chain.realization = Some(SavedRealization {
                event: name.to_string(),
                inputs: input_names,
                outputs: output_names,
                realization,
            });
        }
        Err(e) => realized.notes.push(format!(
            "no realization of order {order} from this record ({e}): the next event is forecast by {}",
            chain
                .realization
                .as_ref()
                .map_or_else(|| "none".to_string(), |s| format!("the realization of {}", s.event))
        )),
    }
    Ok(())
}

/// The event forecast by `saved` on the deck channels both have (a record
/// may lack one; the others are still forecast, the missing ones named);
/// none when the ground inputs differ (said).
fn forecast(
    cfg: &Config,
    saved: &SavedRealization,
    (event, plan): (&Event, &[GroundInputPlan]),
    inputs: &[&[f64]],
    (start, realized): (&Option<String>, &mut Realized),
) -> Result<()> {
    match prediction_by(cfg, saved, (event, plan), inputs)? {
        Err(why) => realized.notes.push(format!("not forecast: {why}")),
        Ok((mut prediction, notes)) => {
            prediction.report.start = start.clone();
            realized.notes.extend(notes);
            realized.forecast = Some(prediction.report);
        }
    }
    Ok(())
}

/// `predict` without a model: `event` forecast by the realization the
/// events' state holds (`--state` of `events` on the same config), scored
/// as a model's prediction; what it says goes to stderr.
pub fn predict_by_realization(
    cfg: &Config,
    state: &Path,
    (event, plan): (&Event, &[GroundInputPlan]),
) -> Result<(Prediction, Vec<String>)> {
    if !state.exists() {
        bail!(
            "{}: no such events state (run `splinewatch events --state` on the station's records first)",
            state.display()
        );
    }
    let chain = Chain::resume(Some(state))?;
    let Some(saved) = &chain.realization else {
        bail!(
            "{}: the events' state holds no realization (run `splinewatch events --state` on a config without a model first)",
            state.display()
        );
    };
    let channel = |i: usize| event.channels[i].as_deref().expect("aligned");
    let signals = ground_signals(plan, channel);
    let inputs: Vec<&[f64]> = signals.iter().map(Vec::as_slice).collect();
    prediction_by(cfg, saved, (event, plan), &inputs)?.map_err(|why| anyhow::anyhow!("not forecast: {why}"))
}

/// A realization's forecast with its notes, or why there is none.
type ForecastOrWhy = std::result::Result<(Prediction, Vec<String>), String>;

/// The forecast by `saved` with its notes, or why there is none.
fn prediction_by(
    cfg: &Config,
    saved: &SavedRealization,
    (event, plan): (&Event, &[GroundInputPlan]),
    inputs: &[&[f64]],
) -> Result<ForecastOrWhy> {
    let channel = |i: usize| event.channels[i].as_deref().expect("aligned");
    let input_names: Vec<&str> = plan.iter().map(|p| p.name.as_str()).collect();
    if saved.inputs != input_names {
        return Ok(Err(format!(
            "the realization of {} is driven by other ground inputs ({}) than this record's ({})",
            saved.event,
            saved.inputs.join(", "),
            input_names.join(", ")
        )));
    }
    let realization = &saved.realization;
    if realization.inputs() != saved.inputs.len() || realization.outputs() != saved.outputs.len() {
        bail!(
            "the realization of {} in the events' state has {} inputs and {} outputs for {} and {} names",
            saved.event,
            realization.inputs(),
            realization.outputs(),
            saved.inputs.len(),
            saved.outputs.len()
        );
    }
    let (deck, rows): (Vec<usize>, Vec<usize>) = event
        .deck
        .iter()
        .filter_map(|&i| {
            let name = &cfg.sensors[i].name;
            saved.outputs.iter().position(|o| o == name).map(|row| (i, row))
        })
        .unzip();
    let missing: Vec<&str> = event
        .deck
        .iter()
        .map(|&i| cfg.sensors[i].name.as_str())
        .filter(|name| !saved.outputs.iter().any(|o| o == name))
        .collect();
    if deck.is_empty() {
        return Ok(Err(format!(
            "the realization of {} has none of this record's deck channels",
            saved.event
        )));
    }
    let all = realization
        .simulate_at(inputs, event.fs)
        .context("the forecast by the previous event's realization")?;
    let predicted: Vec<Vec<f64>> = rows.iter().map(|&row| all[row].clone()).collect();
    let grounds = GroundsOf { plan, anchors: &[] };
    let mut prediction = score_forecast(cfg, &grounds, &deck, channel, event.fs, predicted);
    prediction.report.start = Some(format_timestamp(event.start_ns));
    let mut notes = vec![format!(
        "forecast by the realization of {} (order {}, identified at {} Hz)",
        saved.event,
        realization.states(),
        rate_text(realization.fs())
    )];
    if !missing.is_empty() {
        notes.push(format!(
            "not forecast: {} (not in the record the realization of {} was identified on)",
            missing.join(", "),
            saved.event
        ));
    }
    Ok(Ok((prediction, notes)))
}
