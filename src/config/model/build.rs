//! `[model]` built into the core's `BridgeModel`: names checked, patches,
//! shell, material, springs, stiffness fields, bearings and masses, damping.

use super::*;
use crate::config::LossSite;
use splinewatch_core::model::loss_sites::LossSites;

impl Config {
    /// The cut-off when the model is truncated (`[model.solver]`), `None`
    /// for every mode.
    pub fn modal_cutoff_hz(&self) -> Result<Option<f64>, ConfigError> {
        let solver = &self.model.solver;
        let truncated = match solver.modes {
            ModesChoice::All => false,
            ModesChoice::Truncated => true,
            ModesChoice::Auto => {
                let patches = self.build_model_patches()?;
                let points: usize = patches.iter().map(|p| p.shell.control_point_count()).sum();
                points > AUTO_TRUNCATED_CONTROL_POINTS
            }
        };
        if !truncated {
            return Ok(None);
        }
        match solver.cutoff_hz {
            Some(f) if !(f.is_finite() && f > 0.0) => Err(err(
                "model.solver.cutoff_hz",
                format!("{f} must be a positive frequency in Hz"),
            )),
            Some(f) => Ok(Some(f)),
            None => {
                let top = [
                    self.updating.band.map(|b| b[1]),
                    self.oma().band.map(|b| b[1]),
                    Some(self.frf.band[1]),
                ]
                .into_iter()
                .flatten()
                .fold(0.0, f64::max);
                Ok(Some(2.0 * top))
            }
        }
    }

    /// Validates the model section into a [`BridgeModel`].
    /// The model for the dense path: refuses a net above
    /// [`MAX_DENSE_CONTROL_POINTS`] with the way out.
    pub fn build_dense_model(&self) -> Result<BridgeModel, ConfigError> {
        let model = self.build_model()?;
        let total = model.control_point_count();
        if total > MAX_DENSE_CONTROL_POINTS {
            let key = if self.model.patches.is_empty() {
                "model.discretization.control_points"
            } else {
                "model.patches"
            };
            return Err(err(
                key,
                format!(
                    "{total} control points: every mode (`[model.solver] modes = \"all\"`, `modes` without --cutoff) is solved densely for at most {MAX_DENSE_CONTROL_POINTS}; `modes = \"truncated\"` or `\"auto\"`, `modes --cutoff` and `matrices` take up to {MAX_CONTROL_POINTS}"
                ),
            ));
        }
        Ok(model)
    }

    /// The model `[model]` describes: built once per model section, then
    /// copied (validating a config builds the model its run uses). It reads
    /// `[model]` alone, which is what it is kept by.
    pub fn build_model(&self) -> Result<BridgeModel, ConfigError> {
        let section = serde_json::to_string(&self.model).ok();
        self.built_model.get_or_build(section, || self.build_model_anew())
    }

    pub(in crate::config) fn build_model_anew(&self) -> Result<BridgeModel, ConfigError> {
        let patches = self.build_model_patches()?;
        let m = &self.model;
        let index = |name: &Option<String>, key: String| patch_index(&patches, name.as_deref(), &key);
        let springs = m
            .springs
            .iter()
            .enumerate()
            .map(|(i, s)| Ok(build_spring(i, s)?.on_patch(index(&s.patch, format!("model.springs[{i}].patch"))?)))
            .collect::<Result<Vec<_>, ConfigError>>()?;
        let constraints = m
            .constraints
            .iter()
            .enumerate()
            .map(|(i, c)| {
                Ok(EdgeConstraint {
                    edge: c.edge.into(),
                    kind: match c.kind {
                        SupportConfig::SimplySupported => SupportKind::SimplySupported,
                        SupportConfig::ShearDiaphragm => SupportKind::ShearDiaphragm,
                        SupportConfig::Clamped => SupportKind::Clamped,
                    },
                    patch: index(&c.patch, format!("model.constraints[{i}].patch"))?,
                })
            })
            .collect::<Result<Vec<_>, ConfigError>>()?;
        let stiffness_fields = m
            .stiffness_fields
            .iter()
            .enumerate()
            .map(|(i, f)| {
                let patch = index(&f.patch, format!("model.stiffness_fields[{i}].patch"))?;
                Ok(build_stiffness_field(i, f, &patches[patch].shell)?.on_patch(patch))
            })
            .collect::<Result<Vec<_>, ConfigError>>()?;
        self.check_names()?;
        let (bearings, masses) = self.build_attachments(&patches)?;
        if !(m.joint_tolerance.is_finite() && m.joint_tolerance > 0.0) {
            return Err(err("model.joint_tolerance", "must be a positive distance in metres"));
        }
        if !(m.joint_penalty.is_finite() && m.joint_penalty >= 1.0) {
            return Err(err("model.joint_penalty", "must be a finite factor of at least 1"));
        }
        let beams = self.build_beams()?;
        let rigid_bodies = self.build_rigid_bodies(&patches, &beams)?;
        let elastic_supports = self.build_supports(&patches, &beams)?;
        let model = BridgeModel {
            joints: find_joints(&patches, m.joint_tolerance),
            joint_penalty: m.joint_penalty,
            patches,
            springs,
            stiffness_fields,
            member_stiffness: self.build_member_stiffness()?,
            constraints,
            bearings,
            masses,
            elastic_supports,
            beams,
            rigid_bodies,
        };
        // Surface the spring/shell compatibility errors here, with their key.
        for (i, s) in model.springs.iter().enumerate() {
            s.coefficient_matrices(&model.patches[s.patch()].shell)
                .map_err(|e| err(format!("model.springs[{i}]"), e))?;
        }
        self.check_every_patch_held(&model)?;
        self.check_rigid_bodies(&model)?;
        Ok(model)
    }

    /// The names of the model's spring fields in the assembled order of
    /// `∂K/∂κ` ([`splinewatch_core::model::BridgeModel::spring_coefficients`]):
    /// the `[[model.springs]]`, then the bearings, then the line supports.
    pub fn spring_field_names(&self) -> Vec<String> {
        let m = &self.model;
        m.springs
            .iter()
            .map(|s| s.name.clone())
            .chain(m.bearings.iter().map(|b| b.name.clone()))
            .chain(m.supports.iter().map(|s| s.name.clone()))
            .collect()
    }

    /// Names of springs, stiffness fields, bearings and line supports are
    /// distinct (they prefix the updating parameters).
    fn check_names(&self) -> Result<(), ConfigError> {
        let m = &self.model;
        let mut names: Vec<&str> = m.springs.iter().map(|s| s.name.as_str()).collect();
        let others = m
            .stiffness_fields
            .iter()
            .enumerate()
            .map(|(i, f)| (format!("model.stiffness_fields[{i}].name"), &f.name))
            .chain(
                m.bearings
                    .iter()
                    .enumerate()
                    .map(|(i, b)| (format!("model.bearings[{i}].name"), &b.name)),
            )
            .chain(
                m.supports
                    .iter()
                    .enumerate()
                    .map(|(i, s)| (format!("model.supports[{i}].name"), &s.name)),
            );
        for (key, name) in others {
            if names.contains(&name.as_str()) || name == "damping" {
                return Err(err(
                    key,
                    format!(
                        "{name:?} is already the name of a spring field, stiffness field, bearing, line support or of the damping"
                    ),
                ));
            }
            names.push(name);
        }
        Ok(())
    }

    /// The bearings and point masses, each at the nearest point of its patch.
    fn build_attachments(&self, patches: &[Patch]) -> Result<(Vec<Bearing>, Vec<PointMass>), ConfigError> {
        let m = &self.model;
        let bearings = m
            .bearings
            .iter()
            .enumerate()
            .map(|(i, b)| {
                let key = |k: &str| format!("model.bearings[{i}].{k}");
                let patch = b
                    .patch
                    .as_deref()
                    .map(|n| patch_index(patches, Some(n), &key("patch")))
                    .transpose()?;
                let at = locate(patches, patch, b.at, face_tau(b.surface), &key("at"))?;
                if let Some([lo, hi]) = b.bounds {
                    if !(lo.is_finite() && hi.is_finite() && lo >= 0.0 && lo < hi) {
                        return Err(err(
                            key("bounds"),
                            format!("[{lo}, {hi}] must satisfy 0 <= lower < upper"),
                        ));
                    }
                    if let Some(k) = b.stiffness.iter().find(|&&k| !(k >= lo && k <= hi)) {
                        return Err(err(key("stiffness"), format!("{k} lies outside bounds [{lo}, {hi}]")));
                    }
                }
                let axes = super::super::patches::support_axes(b.axes, b.skew_deg, key)?;
                Bearing::new(at, b.stiffness)
                    .map_err(|e| err(key("stiffness"), e))?
                    .with_axes(axes)
                    .map_err(|e| err(key("axes"), e))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let masses = m
            .masses
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let key = |k: &str| format!("model.masses[{i}].{k}");
                let patch = p
                    .patch
                    .as_deref()
                    .map(|n| patch_index(patches, Some(n), &key("patch")))
                    .transpose()?;
                let at = locate(patches, patch, p.at, 0.5, &key("at"))?;
                PointMass::new(at, p.mass).map_err(|e| err(key("mass"), e))
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok((bearings, masses))
    }

    /// Every patch of a deck of several is joined to another or carries a
    /// support (constraint, spring field or bearing).
    fn check_every_patch_held(&self, model: &BridgeModel) -> Result<(), ConfigError> {
        if model.patches.len() < 2 {
            return Ok(());
        }
        for (k, p) in model.patches.iter().enumerate() {
            let joined = model.joints.iter().any(|j| j.patch == k || j.other == k);
            let supported = model.constraints.iter().any(|c| c.patch == k)
                || model.springs.iter().any(|s| s.patch() == k)
                || model.bearings.iter().any(|b| b.at().patch == k)
                || model.elastic_supports.iter().any(|s| s.patch() == Some(k))
                || self.model.rigid.iter().any(|r| {
                    r.edges
                        .iter()
                        .any(|e| e.patch.as_deref().is_none_or(|name| name == p.name()))
                });
            if !(joined || supported) {
                return Err(err(
                    format!("model.patches[{k}]"),
                    format!(
                        "patch {:?} is joined to no other patch (no edge within joint_tolerance = {} m of another) and carries no support",
                        p.name(),
                        self.model.joint_tolerance
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The patches: `[[model.patches]]`, or the single-patch keys as one
    /// patch named `"deck"`.
    pub fn build_model_patches(&self) -> Result<Vec<Patch>, ConfigError> {
        let m = &self.model;
        let single = m.geometry.is_some() || m.discretization.is_some() || m.material.is_some();
        match (single, m.patches.is_empty()) {
            (true, false) => Err(err(
                "model.patches",
                "give either [[model.patches]] or [model.geometry], [model.discretization] and [model.material], not both",
            )),
            (false, true) => Err(err(
                "model",
                "no deck: give [model.geometry], [model.discretization] and [model.material], or [[model.patches]]",
            )),
            (false, false) => {
                let patches = build_patches(&m.patches, &m.materials)?;
                if let Some((a, b)) = find_overlap(&patches, m.joint_tolerance) {
                    return Err(err(
                        format!("model.patches[{a}]"),
                        format!(
                            "patch {:?} lies on patch {:?} (overlapping patches count the same material twice)",
                            patches[a].name(),
                            patches[b].name()
                        ),
                    ));
                }
                let total: usize = patches.iter().map(|p| p.shell.control_point_count()).sum();
                if total > MAX_CONTROL_POINTS {
                    return Err(err(
                        "model.patches",
                        format!("{total} control points in all: at most {MAX_CONTROL_POINTS} (the sparse path's limit)"),
                    ));
                }
                Ok(patches)
            }
            (true, true) => {
                let shell = self.build_shell()?;
                let material = self.build_material()?;
                Ok(vec![Patch::new("deck", shell, material).expect("a non-empty name")])
            }
        }
    }

    /// `[model.geometry]` on the `[model.discretization]` net, refined.
    fn build_shell(&self) -> Result<Shell, ConfigError> {
        let m = &self.model;
        let d = m
            .discretization
            .as_ref()
            .ok_or_else(|| err("model.discretization", "is required with [model.geometry]"))?;
        let geometry = m
            .geometry
            .as_ref()
            .ok_or_else(|| err("model.geometry", "is required with [model.discretization]"))?;
        // Refuse nets no path can hold rather than exhausting memory.
        let [cm, cn] = d.control_points;
        let total = cm
            .saturating_add(d.insert_knots_xi.len())
            .saturating_mul(cn.saturating_add(d.insert_knots_eta.len()));
        if total > MAX_CONTROL_POINTS {
            return Err(err(
                "model.discretization.control_points",
                format!("{total} control points (after knot insertion) exceed the supported {MAX_CONTROL_POINTS}"),
            ));
        }
        let mut shell = match *geometry {
            GeometryConfig::RectangularPlate {
                length,
                width,
                thickness,
            } => Shell::rectangular_plate(length, width, thickness, d.degree, d.control_points),
            GeometryConfig::CylindricalPanel {
                length,
                radius,
                angle_deg,
                thickness,
            } => Shell::cylindrical_panel(
                length,
                radius,
                angle_deg.to_radians(),
                thickness,
                d.degree,
                d.control_points,
            ),
        }
        .map_err(|e| err(shell_error_key(&e), e))?;
        for (key, direction, knots) in [
            ("insert_knots_xi", Direction::Xi, &d.insert_knots_xi),
            ("insert_knots_eta", Direction::Eta, &d.insert_knots_eta),
        ] {
            for (i, &u) in knots.iter().enumerate() {
                shell = shell.insert_knot(direction, u).map_err(|e| {
                    err(
                        format!("model.discretization.{key}[{i}]"),
                        format!("cannot insert {u}: {e} (knots must lie strictly inside (0, 1))"),
                    )
                })?;
            }
        }
        Ok(shell)
    }

    fn build_material(&self) -> Result<OrthotropicMaterial, ConfigError> {
        let parameters = self
            .model
            .material
            .ok_or_else(|| err("model.material", "is required with [model.geometry]"))?;
        OrthotropicMaterial::new(parameters).map_err(|e| err("model.material", e))
    }

    /// `[model.damping]` as a curve; an error if it is missing.
    pub fn build_damping(&self) -> Result<DampingCurve, ConfigError> {
        let d = self
            .model
            .damping
            .as_ref()
            .ok_or_else(|| err("model.damping", "is required for FRFs and updating"))?;
        if let Some([lo, hi]) = d.bounds {
            if !(lo.is_finite() && hi.is_finite() && lo >= 0.0 && lo < hi) {
                return Err(err(
                    "model.damping.bounds",
                    format!("[{lo}, {hi}] must satisfy 0 <= lower < upper"),
                ));
            }
            if let Some((j, g)) = d.coefficients.iter().enumerate().find(|(_, &g)| !(g >= lo && g <= hi)) {
                return Err(err(
                    "model.damping.coefficients",
                    format!("coefficient {} = {g} lies outside bounds [{lo}, {hi}]", j + 1),
                ));
            }
        }
        let curve = DampingCurve::new(d.degree, d.coefficients.clone(), d.f_start, d.f_end)
            .map_err(|e| err("model.damping", e))?;
        let sites = self.loss_sites()?;
        if sites.is_empty() {
            return Ok(curve);
        }
        let factors = sites.iter().map(|s| s.factor.value()).collect();
        let where_ = LossSites::new(sites.iter().map(LossSite::core).collect()).map_err(|e| err("model", e))?;
        curve
            .with_loss_factors(factors)
            .and_then(|c| c.with_loss_sites(where_))
            .map_err(|e| err("model", e))
    }
}

/// The key a shell construction error is about.
fn shell_error_key(e: &ShellError) -> String {
    match e {
        ShellError::Thickness { .. } | ShellError::ThicknessCount { .. } => "model.geometry.thickness".into(),
        ShellError::Dimension { name: "angle", .. } => "model.geometry.angle_deg".into(),
        ShellError::Dimension { name, .. } => format!("model.geometry.{name}"),
        ShellError::Surface(_) | ShellError::Knot(_) => "model.discretization.control_points".into(),
        _ => "model.geometry".into(),
    }
}

fn build_stiffness_field(i: usize, f: &StiffnessFieldConfig, shell: &Shell) -> Result<StiffnessField, ConfigError> {
    let key = |k: &str| format!("model.stiffness_fields[{i}].{k}");
    let scale = StiffnessScale::parse(&f.scales).ok_or_else(|| {
        err(
            key("scales"),
            format!("{:?}: expected one of {:?}", f.scales, StiffnessScale::NAMES),
        )
    })?;
    let xi = KnotVector::new(f.knots_xi.clone(), f.degree_xi).map_err(|e| err(key("knots_xi"), e))?;
    let eta = KnotVector::new(f.knots_eta.clone(), f.degree_eta).map_err(|e| err(key("knots_eta"), e))?;
    let coefficients = f
        .coefficients
        .clone()
        .unwrap_or_else(|| vec![1.0; xi.basis_count() * eta.basis_count()]);
    if let Some([lo, hi]) = f.bounds {
        if !(lo.is_finite() && hi.is_finite() && lo > 0.0 && lo < hi) {
            return Err(err(
                key("bounds"),
                format!("[{lo}, {hi}] must satisfy 0 < lower < upper"),
            ));
        }
    }
    let field = StiffnessField::new(xi, eta, coefficients)
        .map_err(|e| err(key("coefficients"), e))?
        .with_scale(scale);
    field
        .check_inside(shell)
        .map_err(|e| err(key(&format!("knots_{}", e.axis)), e))?;
    Ok(field)
}

fn build_spring(i: usize, s: &SpringConfig) -> Result<SpringField, ConfigError> {
    let key = |k: &str| format!("model.springs[{i}].{k}");
    let xi = KnotVector::new(s.knots_xi.clone(), s.degree_xi).map_err(|e| err(key("knots_xi"), e))?;
    let eta = KnotVector::new(s.knots_eta.clone(), s.degree_eta).map_err(|e| err(key("knots_eta"), e))?;
    let direction = match &s.direction {
        DirectionConfig::Named(n) => match n.as_str() {
            "x" => SpringDirection::Fixed([1.0, 0.0, 0.0]),
            "y" => SpringDirection::Fixed([0.0, 1.0, 0.0]),
            "z" => SpringDirection::Fixed([0.0, 0.0, 1.0]),
            "normal" => SpringDirection::Normal,
            other => {
                return Err(err(
                    key("direction"),
                    format!("{other:?} is not one of \"x\", \"y\", \"z\", \"normal\" or a 3-vector"),
                ))
            }
        },
        DirectionConfig::Vector(v) => SpringDirection::fixed(*v).map_err(|e| err(key("direction"), e))?,
    };
    let face = match s.surface {
        FaceConfig::Bottom => Face::Bottom,
        FaceConfig::Middle => Face::Middle,
        FaceConfig::Top => Face::Top,
    };
    if let Some([lo, hi]) = s.bounds {
        if !(lo.is_finite() && hi.is_finite() && lo >= 0.0 && lo < hi) {
            return Err(err(
                key("bounds"),
                format!("[{lo}, {hi}] must satisfy 0 <= lower < upper"),
            ));
        }
        if let Some((j, k)) = s.stiffness.iter().enumerate().find(|(_, &k)| !(k >= lo && k <= hi)) {
            return Err(err(
                key("stiffness"),
                format!("coefficient {} = {k} lies outside bounds [{lo}, {hi}]", j + 1),
            ));
        }
    }
    SpringField::new(xi, eta, s.stiffness.clone(), direction, face).map_err(|e| err(key("stiffness"), e))
}
