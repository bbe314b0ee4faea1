//! `[[sensors]]` as points of the model.

use super::super::patches::{locate_within, MAX_DISTANCE};
use super::*;
use splinewatch_core::response::frf::{BeamSensor, Sensor};

impl Config {
    /// The sensors as model points, in config order, with their names: on
    /// a patch, or on the beam `beam` names.
    pub fn build_sensors(&self, model: &BridgeModel) -> Result<Vec<(String, Sensor)>, ConfigError> {
        let mut out = Vec::with_capacity(self.sensors.len());
        for (i, s) in self.sensors.iter().enumerate().take(self.deck_sensor_count()) {
            let key = |k: &str| format!("sensors[{i}].{k}");
            for q in s.quantity.as_slice() {
                if !matches!(q.as_str(), "acceleration" | "force" | "displacement" | "velocity") {
                    return Err(err(
                        key("quantity"),
                        format!("{q:?} is not one of acceleration, force, displacement, velocity"),
                    ));
                }
            }
            let sensor = match &s.beam {
                Some(beam) => Sensor::Beam(self.beam_sensor(model, i, beam)?),
                None => Sensor::Shell(self.shell_sensor(model, i)?),
            };
            out.push((s.name.clone(), sensor));
        }
        Ok(out)
    }

    /// Sensor `i` on a patch.
    fn shell_sensor(&self, model: &BridgeModel, i: usize) -> Result<SensorPoint, ConfigError> {
        let s = &self.sensors[i];
        let key = |k: &str| format!("sensors[{i}].{k}");
        if let Some(offset) = s.offset {
            if s.surface != FaceConfig::Middle {
                return Err(err(key("offset"), "give `surface` or `offset`, not both"));
            }
            if !offset.is_finite() {
                return Err(err(
                    key("offset"),
                    format!("{offset}: must be a finite distance in metres"),
                ));
            }
        }
        let (patch, xi, eta) = self.sensor_position(model, i)?;
        let shell = &model.patches[patch].shell;
        let (kx, ke) = (shell.surface().xi(), shell.surface().eta());
        if !kx.contains(xi) || !ke.contains(eta) {
            return Err(err(
                key("xi"),
                format!("({xi}, {eta}) lies outside the parameter domain"),
            ));
        }
        let tau = match s.offset {
            // The faces' distance: `|Σ N_i t_i v3_i|`, what one unit of τ
            // moves a point along the director (eq. 2).
            Some(offset) => {
                let faces = [0.0, 1.0].map(|tau| shell.position(xi, eta, tau));
                0.5 + offset
                    / splinewatch_core::geometry::vec3::norm(splinewatch_core::geometry::vec3::sub(faces[1], faces[0]))
            }
            None => face_tau(s.surface),
        };
        let direction = match &s.direction {
            named @ DirectionConfig::Named(n) => match (named.axis_vector(), n.as_str()) {
                (Some(axis), _) => axis,
                (None, "normal") => {
                    let e = shell.surface().evaluate(xi, eta);
                    splinewatch_core::geometry::vec3::cross(e.r_xi, e.r_eta)
                }
                (None, other) => {
                    return Err(err(
                        key("direction"),
                        format!(
                        "{other:?} is not one of \"x\", \"y\", \"z\", \"-x\", \"-y\", \"-z\", \"normal\" or a 3-vector"
                    ),
                    ))
                }
            },
            DirectionConfig::Vector(v) => *v,
        };
        if splinewatch_core::geometry::vec3::normalize(direction).is_none() {
            return Err(err(key("direction"), "must be a finite non-zero vector"));
        }
        Ok(SensorPoint {
            patch,
            xi,
            eta,
            tau,
            direction,
        })
    }

    /// Sensor `i` on beam `beam`: at `x, y, z`, within 0.5 m of the
    /// member's section (its axis point nearest moves it rigidly).
    fn beam_sensor(&self, model: &BridgeModel, i: usize, beam: &str) -> Result<BeamSensor, ConfigError> {
        let s = &self.sensors[i];
        let key = |k: &str| format!("sensors[{i}].{k}");
        let members = model.beams.members();
        let member = members.iter().position(|m| m.name() == beam).ok_or_else(|| {
            let names: Vec<&str> = members.iter().map(|m| m.name()).collect();
            err(
                key("beam"),
                format!("{beam:?} is not a [[model.beams]] name ({names:?})"),
            )
        })?;
        if s.patch.is_some()
            || s.xi.is_some()
            || s.eta.is_some()
            || s.surface != FaceConfig::Middle
            || s.offset.is_some()
        {
            return Err(err(
                key("beam"),
                "a sensor on a beam takes x, y and z: leave out patch, xi, eta, surface and offset",
            ));
        }
        let (Some(x), Some(y), Some(z)) = (s.x, s.y, s.z) else {
            return Err(err(key("beam"), "a sensor on a beam needs x, y and z (metres)"));
        };
        let at = [x, y, z];
        let reach = MAX_DISTANCE + members[member].section().area.sqrt();
        let on_axis = model.beams.nearest_on_axis(member, at).expect("the member exists");
        let distance = splinewatch_core::geometry::vec3::norm(splinewatch_core::geometry::vec3::sub(at, on_axis));
        if distance.is_nan() || distance > reach {
            return Err(err(
                key("x"),
                format!("({x}, {y}, {z}) m is {distance:.3} m from beam {beam:?}'s axis: more than {reach:.2} m (the section and {MAX_DISTANCE} m)"),
            ));
        }
        let direction = match s.direction.axis_vector() {
            Some(axis) => axis,
            None => match &s.direction {
                DirectionConfig::Vector(v) => *v,
                DirectionConfig::Named(other) => {
                    return Err(err(
                        key("direction"),
                        format!("{other:?}: a sensor on a beam measures along \"x\", \"y\", \"z\", \"-x\", \"-y\", \"-z\" or a 3-vector"),
                    ))
                }
            },
        };
        if splinewatch_core::geometry::vec3::normalize(direction).is_none() {
            return Err(err(key("direction"), "must be a finite non-zero vector"));
        }
        Ok(BeamSensor { member, at, direction })
    }
}

impl Config {
    /// Sensor `i`'s patch and parameters: `xi, eta` on the named (or only)
    /// patch; `x, y, z` at the nearest point of the named or nearest patch
    /// (within 0.5 m, beyond the half thickness or the `offset`); `x, y`
    /// on a single patch, located in plan.
    fn sensor_position(&self, model: &BridgeModel, i: usize) -> Result<(usize, f64, f64), ConfigError> {
        let s = &self.sensors[i];
        let key = |k: &str| format!("sensors[{i}].{k}");
        let patches = &model.patches;
        let named = || patch_index(patches, s.patch.as_deref(), &key("patch"));
        match (s.xi, s.eta, s.x, s.y, s.z) {
            (Some(xi), Some(eta), None, None, None) => Ok((named()?, xi, eta)),
            (None, None, Some(x), Some(y), Some(z)) => {
                let patch = s
                    .patch
                    .as_deref()
                    .map(|n| patch_index(patches, Some(n), &key("patch")))
                    .transpose()?;
                let beyond = s.offset.map_or(0.0, f64::abs);
                let at = locate_within(patches, patch, [x, y, z], face_tau(s.surface), beyond, &key("x"))?;
                Ok((at.patch, at.xi, at.eta))
            }
            (None, None, Some(x), Some(y), None) => {
                let patch = named().map_err(|_| err(key("z"), "the model has several patches: give x, y and z"))?;
                let (xi, eta) = patches[patch].shell.surface().locate_xy(x, y).ok_or_else(|| {
                    err(
                        key("x"),
                        format!("point ({x}, {y}) m is not on the deck (outside the model's plan)"),
                    )
                })?;
                Ok((patch, xi, eta))
            }
            _ => Err(err(
                format!("sensors[{i}]"),
                "give either both xi and eta (parametric), x and y (metres, in plan on a single patch) or x, y and z",
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::config::Config;
    use splinewatch_core::response::frf::{BeamSensor, Sensor};

    /// The deck on a bent with a sensor on the north column's face.
    fn on_column(sensor: &str) -> String {
        format!(
            "{}\n[[sensors]]\nname = \"column\"\n{sensor}\n",
            include_str!("../../../config/examples/deck-on-bent.toml")
        )
    }

    /// Each `(sensor, key)`: the sensor added to the deck on a bent is
    /// refused, the error naming `key`.
    fn assert_refused_by_key(cases: &[(&str, &str)]) {
        for (sensor, key) in cases {
            let config = Config::from_toml(&on_column(sensor)).unwrap();
            let model = config.build_model().unwrap();
            let e = config.build_sensors(&model).unwrap_err().to_string();
            assert!(e.contains(key), "{key}: {e}");
        }
    }

    /// A sensor on a beam is the member by name at its point, after the
    /// deck's sensors in config order; the errors name their key.
    #[test]
    fn a_sensor_on_a_beam_is_built_at_its_point() {
        let text = on_column("beam = \"bent.north\"\nx = 20.6\ny = 6.0\nz = -3.0\ndirection = \"y\"");
        let config = Config::from_toml(&text).unwrap();
        let model = config.build_model().unwrap();
        let sensors = config.build_sensors(&model).unwrap();
        let (name, sensor) = sensors.last().unwrap();
        assert_eq!(name, "column");
        assert_eq!(
            *sensor,
            Sensor::Beam(BeamSensor {
                member: 1,
                at: [20.6, 6.0, -3.0],
                direction: [0.0, 1.0, 0.0]
            })
        );
        let cases = [
            (
                "beam = \"bent.west\"\nx = 20.6\ny = 6.0\nz = -3.0\ndirection = \"y\"",
                "sensors[4].beam",
            ),
            (
                "beam = \"bent.north\"\nx = 22.5\ny = 6.0\nz = -3.0\ndirection = \"y\"",
                "sensors[4].x",
            ),
            (
                "beam = \"bent.north\"\nx = 20.6\ny = 6.0\ndirection = \"y\"",
                "sensors[4].beam",
            ),
            (
                "beam = \"bent.north\"\nxi = 0.5\neta = 0.5\ndirection = \"y\"",
                "sensors[4].beam",
            ),
            (
                "beam = \"bent.north\"\nx = 20.6\ny = 6.0\nz = -3.0\ndirection = \"normal\"",
                "sensors[4].direction",
            ),
        ];
        assert_refused_by_key(&cases);
    }

    /// A sensor 1.2 m below the deck's mid-surface (a girder's soffit) by
    /// `offset`, given in space or in plan: its τ puts it there
    /// (`½ − 1.2 / 0.4`); beside `surface`, on a beam or not finite it is
    /// refused by key.
    #[test]
    fn a_sensor_off_the_mid_surface_sits_at_its_offset() {
        let text = on_column("x = 10.0\ny = 7.5\nz = -1.2\noffset = -1.2\ndirection = \"y\"");
        let config = Config::from_toml(&text).unwrap();
        let model = config.build_model().unwrap();
        let sensors = config.build_sensors(&model).unwrap();
        let Sensor::Shell(point) = sensors.last().unwrap().1 else {
            panic!("{sensors:?}")
        };
        assert!((point.tau - (0.5 - 1.2 / 0.4)).abs() < 1e-12, "{}", point.tau);
        let at = model.patches[point.patch]
            .shell
            .position(point.xi, point.eta, point.tau);
        assert!(
            (at[0] - 10.0).abs() < 1e-9 && (at[1] - 7.5).abs() < 1e-9 && (at[2] + 1.2).abs() < 1e-9,
            "{at:?}"
        );
        let cases = [
            ("x = 10.0\ny = 7.5\nz = -1.2\ndirection = \"y\"", "sensors[4].x"),
            (
                "x = 10.0\ny = 7.5\nz = -1.2\noffset = -1.2\nsurface = \"top\"\ndirection = \"y\"",
                "sensors[4].offset",
            ),
            (
                "beam = \"bent.north\"\nx = 20.6\ny = 6.0\nz = -3.0\noffset = 0.5\ndirection = \"y\"",
                "sensors[4].beam",
            ),
            (
                "xi = 0.5\neta = 0.5\npatch = \"span1\"\noffset = nan\ndirection = \"y\"",
                "sensors[4].offset",
            ),
        ];
        assert_refused_by_key(&cases);
    }
}
