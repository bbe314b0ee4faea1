//! What every `.rrd` file starts with: the blueprint (the viewer's layout)
//! and the static sensor positions.

use super::{rerun_error, RerunOutput, MODES_SHOWN};
use anyhow::{anyhow, Result};
use rerun::blueprint::BarChartView;
use rerun::blueprint::{
    Blueprint, BlueprintActivation, ContainerLike, Horizontal, Spatial2DView, Spatial3DView, Tabs, TimeSeriesView,
    Vertical,
};
use splinewatch_core::response::frf::Sensor;

impl RerunOutput {
    /// The layout: trends left, the deck in the middle, and on the right
    /// the FRFs and/or the identification ([`Self::right_column`]).
    pub(super) fn send_blueprint(&self) -> Result<()> {
        let mode_tabs = Tabs::new((1..=MODES_SHOWN).map(|k| {
            Spatial3DView::new(format!("mode {k}"))
                .with_origin(format!("/modes/{k}"))
                .into()
        }));
        let blueprint = Blueprint::new(Horizontal::new([
            Vertical::new([
                TimeSeriesView::new("Spring coefficients (N/m³, ±1σ)")
                    .with_origin("/parameters/springs")
                    .into(),
                TimeSeriesView::new("Damping coefficients (±1σ)")
                    .with_origin("/parameters/damping")
                    .into(),
                TimeSeriesView::new("Stiffness multipliers θ (±1σ)")
                    .with_origin("/parameters/fields")
                    .with_visible(!self.model.stiffness_fields.is_empty())
                    .into(),
                TimeSeriesView::new("Relative residual").with_origin("/residual").into(),
                if self.monitoring {
                    Tabs::new([
                        TimeSeriesView::new("Hotelling T² and its limit")
                            .with_origin("/monitoring/charts/t2")
                            .into(),
                        TimeSeriesView::new("MEWMA and its limit")
                            .with_origin("/monitoring/charts/mewma")
                            .into(),
                        TimeSeriesView::new("State (0 training, 1 normal, 2 outside range, 3 alarm), °C")
                            .with_origin("/monitoring")
                            .with_contents(["/monitoring/state", "/monitoring/temperature_c"])
                            .into(),
                        Spatial2DView::new("Temperature (°C) × parameter, blue → red over time")
                            .with_origin("/monitoring/temperature")
                            .into(),
                        TimeSeriesView::new("Health").with_origin("/health").into(),
                    ])
                    .into()
                } else {
                    TimeSeriesView::new("Health").with_origin("/health").into()
                },
            ])
            .into(),
            Vertical::new([self.deck_views(), mode_tabs.into()]).into(),
            Vertical::new(self.right_column()).into(),
        ]));
        blueprint
            .send(
                &self.rec,
                BlueprintActivation {
                    make_active: true,
                    make_default: true,
                },
            )
            .map_err(|e| anyhow!("sending the Rerun blueprint: {e}"))
    }

    /// The FRFs (FRF path) and the stabilisation diagram, identified-frequency
    /// trends and shapes at the sensors (windows identified output-only),
    /// then ζ(f).
    fn right_column(&self) -> Vec<ContainerLike> {
        let frf_tabs = |what: &str| -> ContainerLike {
            Tabs::new(self.setup.sensor_names.iter().map(|o| {
                BarChartView::new(format!("{o} {what}"))
                    .with_origin(format!("/frf/{o}/{what}"))
                    .into()
            }))
            .into()
        };
        let mut views = Vec::new();
        if self.frf_views {
            views.extend([frf_tabs("magnitude"), frf_tabs("phase")]);
        }
        if self.oma_views {
            views.extend([
                Spatial2DView::new(
                    "Stabilisation diagram (order × Hz) over the spectral matrix's first singular value",
                )
                .with_origin("/oma/stabilisation")
                .into(),
                TimeSeriesView::new("Identified frequencies by model mode (Hz, ±1σ)")
                    .with_origin("/oma/trends")
                    .into(),
                Spatial3DView::new("Shapes at the sensors on the deck: identified (orange), model (blue)")
                    .with_origin("/")
                    .with_contents(["/deck/springs", "/deck/sensors", "/oma/shapes/**"])
                    .into(),
            ]);
        }
        views.push(BarChartView::new("ζ(f) in %").with_origin("/damping").into());
        views
    }

    /// The deck coloured by the spring field r33 and, with stiffness
    /// fields, by the identified multiplier θ; the model's patches and
    /// element edges: one tab each.
    fn deck_views(&self) -> ContainerLike {
        let springs: ContainerLike = Spatial3DView::new("Deck: spring field r33")
            .with_origin("/deck")
            .with_contents(["/deck/springs", "/deck/sensors"])
            .into();
        let model: ContainerLike = Spatial3DView::new("Deck: patches, element edges, bearings")
            .with_origin("/deck")
            .with_contents(["/deck/model/**", "/deck/sensors"])
            .into();
        // A deck of several patches opens on its model (it seldom has spring
        // fields to colour); a single patch keeps the spring field first.
        let (mut views, last) = if self.model.patches.len() > 1 {
            (vec![model, springs], None)
        } else {
            (vec![springs], Some(model))
        };
        if self.monitoring {
            views.push(
                Spatial3DView::new("Deck: standardised residual of the field coefficients (−4 → +4)")
                    .with_origin("/deck")
                    .with_contents(["/deck/monitoring_residual", "/deck/sensors"])
                    .into(),
            );
        }
        if !self.model.stiffness_fields.is_empty() {
            views.push(
                Spatial3DView::new("Deck: stiffness multiplier θ (0.5 → 1.5)")
                    .with_origin("/deck")
                    .with_contents(["/deck/stiffness", "/deck/sensors"])
                    .into(),
            );
            views.push(
                Spatial3DView::new("Deck: change of θ since the first update (−3σ → +3σ)")
                    .with_origin("/deck")
                    .with_contents(["/deck/stiffness_change", "/deck/sensors"])
                    .into(),
            );
        }
        views.extend(last);
        Tabs::new(views).into()
    }

    pub(super) fn log_sensors(&self, sensors: &[(String, Sensor)]) -> Result<()> {
        let positions: Vec<[f32; 3]> = sensors
            .iter()
            .map(|(_, s)| super::deck::sensor_position(&self.model, s))
            .collect();
        let labels: Vec<String> = sensors.iter().map(|(name, _)| name.clone()).collect();
        self.rec
            .log_static(
                "deck/sensors",
                &rerun::Points3D::new(positions).with_labels(labels).with_radii([0.15]),
            )
            .map_err(rerun_error)
    }
}
