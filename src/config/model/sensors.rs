//! `[[sensors]]` as points of the model.

use super::*;

impl Config {
    /// The sensors as model points, in config order, with their names.
    pub fn build_sensors(&self, model: &ShellModel) -> Result<Vec<(String, SensorPoint)>, ConfigError> {
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
            let tau = face_tau(s.surface);
            let (patch, xi, eta) = self.sensor_position(model, i)?;
            let shell = &model.patches[patch].shell;
            let (kx, ke) = (shell.surface().xi(), shell.surface().eta());
            if !kx.contains(xi) || !ke.contains(eta) {
                return Err(err(
                    key("xi"),
                    format!("({xi}, {eta}) lies outside the parameter domain"),
                ));
            }
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
                            format!("{other:?} is not one of \"x\", \"y\", \"z\", \"-x\", \"-y\", \"-z\", \"normal\" or a 3-vector"),
                        ))
                    }
                },
                DirectionConfig::Vector(v) => *v,
            };
            if splinewatch_core::geometry::vec3::normalize(direction).is_none() {
                return Err(err(key("direction"), "must be a finite non-zero vector"));
            }
            out.push((
                s.name.clone(),
                SensorPoint {
                    patch,
                    xi,
                    eta,
                    tau,
                    direction,
                },
            ));
        }
        Ok(out)
    }
}

impl Config {
    /// Sensor `i`'s patch and parameters: `xi, eta` on the named (or only)
    /// patch; `x, y, z` at the nearest point of the named or nearest patch
    /// (within 0.5 m); `x, y` on a single patch, located in plan.
    fn sensor_position(&self, model: &ShellModel, i: usize) -> Result<(usize, f64, f64), ConfigError> {
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
                let at = locate(patches, patch, [x, y, z], face_tau(s.surface), &key("x"))?;
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
