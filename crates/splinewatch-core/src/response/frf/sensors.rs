//! Where the sensors are: points of the shell patches (eq. 32) and points
//! on beam members or beside them, each a sparse row on the generalised
//! dofs that gives the motion it measures.

use super::FrfError;
use crate::geometry::vec3::{dot, normalize, Vec3};
use crate::model::dofs::DofMap;
use crate::model::members::BeamNet;
use crate::model::patch::Patch;

/// A measurement point `P = s(ξ, η, τ)` and direction (eq. 32).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorPoint {
    /// The patch the point lies on ([`crate::model::patch`]).
    pub patch: usize,
    pub xi: f64,
    pub eta: f64,
    /// 0 the bottom face, ½ the mid-surface, 1 the top; beyond them a
    /// point off the shell on its director (a girder's soffit, a
    /// barrier's top), carried rigidly by the section's rotation: eq.
    /// (2)–(3) are linear in τ, so the rigid transfer is exact.
    pub tau: f64,
    pub direction: Vec3,
}
/// A measurement point on a beam member (a column, a pier) and direction:
/// the member's axis point nearest `at` moves by its element's
/// interpolation and `at` follows it rigidly (`u + θ × r`), so a sensor
/// on a column's face or top is measured as placed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BeamSensor {
    /// The member ([`BeamNet::members`]).
    pub member: usize,
    /// The point (m, global axes).
    pub at: Vec3,
    pub direction: Vec3,
}

/// A sensor on a shell patch or on a beam member.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Sensor {
    Shell(SensorPoint),
    Beam(BeamSensor),
}

impl Sensor {
    /// The direction it measures along (as given, not normalised).
    pub fn direction(&self) -> Vec3 {
        match self {
            Self::Shell(p) => p.direction,
            Self::Beam(b) => b.direction,
        }
    }
}

impl From<SensorPoint> for Sensor {
    fn from(point: SensorPoint) -> Self {
        Self::Shell(point)
    }
}

impl From<BeamSensor> for Sensor {
    fn from(point: BeamSensor) -> Self {
        Self::Beam(point)
    }
}

/// The sparse rows `N_ψ(P_s)` of the sensors (eq. 32) on the generalised dofs.
pub fn sensor_rows(patches: &[Patch], sensors: &[SensorPoint]) -> Result<Vec<Vec<(usize, f64)>>, FrfError> {
    let dofs = DofMap::of_patches(patches);
    sensors
        .iter()
        .enumerate()
        .map(|(index, s)| shell_row(patches, &dofs, index, s))
        .collect()
}

/// Sensor `index`'s row `N_ψ(P)` on a patch, on the generalised dofs `dofs`.
fn shell_row(patches: &[Patch], dofs: &DofMap, index: usize, s: &SensorPoint) -> Result<Vec<(usize, f64)>, FrfError> {
    let Some(shell) = patches.get(s.patch).map(|p| &p.shell) else {
        return Err(FrfError::SensorPatch {
            index,
            patch: s.patch,
            count: patches.len(),
        });
    };
    let (kx, ke) = (shell.surface().xi(), shell.surface().eta());
    if !(kx.contains(s.xi) && ke.contains(s.eta) && s.tau.is_finite()) {
        return Err(FrfError::SensorOutside {
            index,
            xi: s.xi,
            eta: s.eta,
            tau: s.tau,
        });
    }
    let dir = normalize(s.direction).ok_or(FrfError::SensorDirection { index })?;
    Ok(shell
        .shape_functions(s.xi, s.eta, s.tau)
        .into_iter()
        .map(|(dof, col)| (dofs.first_dof(s.patch) + dof, dot(dir, col)))
        .filter(|(_, v)| *v != 0.0)
        .collect())
}

/// The rows of `sensors` on the patches and beams of a model: each
/// sensor's row on a patch (eq. 32), [`BeamNet::sensor_row`] on a
/// member.
pub(super) fn rows(
    patches: &[Patch],
    beams: &BeamNet,
    sensors: &[impl Into<Sensor> + Copy],
) -> Result<Vec<Vec<(usize, f64)>>, FrfError> {
    let dofs = DofMap::of_model(patches, beams.node_count(), 0);
    sensors
        .iter()
        .enumerate()
        .map(|(index, &s)| match s.into() {
            Sensor::Shell(point) => shell_row(patches, &dofs, index, &point),
            Sensor::Beam(b) => {
                let direction = normalize(b.direction).ok_or(FrfError::SensorDirection { index })?;
                beams
                    .sensor_row(b.member, b.at, direction, &dofs)
                    .ok_or(FrfError::SensorMember {
                        index,
                        member: b.member,
                        count: beams.members().len(),
                    })
            }
        })
        .collect()
}

/// The rows of `sensors` on `model`'s patches and beams.
pub fn sensor_rows_of(
    model: &crate::model::BridgeModel,
    sensors: &[impl Into<Sensor> + Copy],
) -> Result<Vec<Vec<(usize, f64)>>, FrfError> {
    rows(&model.patches, &model.beams, sensors)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::shell::Shell;

    /// A sensor `d` off a plate's mid-surface (τ = ½ + d/t, beyond the
    /// faces too) reads `d θ` along x under a rigid rotation `θ` about y
    /// (every β = θ), and the translation as it is.
    #[test]
    fn a_sensor_off_the_mid_surface_follows_the_section_rigidly() {
        let shell = Shell::rectangular_plate(6.0, 3.0, 0.2, [3, 2], [6, 5]).unwrap();
        let t = 0.2;
        let material = crate::model::material::OrthotropicMaterial::isotropic(30e9, 0.2, 2500.0).unwrap();
        let patches = [Patch::new("deck", shell, material).unwrap()];
        let dofs = DofMap::of_model(&patches, 0, 0);
        for d in [-1.1, -0.1, 0.0, 0.35] {
            let point = SensorPoint {
                patch: 0,
                xi: 0.3,
                eta: 0.7,
                tau: 0.5 + d / t,
                direction: [1.0, 0.0, 0.0],
            };
            let row = shell_row(&patches, &dofs, 0, &point).unwrap();
            let read = |q: &dyn Fn(usize) -> f64| row.iter().map(|&(dof, v)| v * q(dof)).sum::<f64>();
            let theta = 1e-3;
            let rotated = read(&|dof| if dof % 5 == 4 { theta } else { 0.0 });
            assert!((rotated - d * theta).abs() < 1e-15, "offset {d}: {rotated}");
            let translated = read(&|dof| f64::from(dof % 5 == 0));
            assert!((translated - 1.0).abs() < 1e-12, "offset {d}: {translated}");
        }
        let nowhere = SensorPoint {
            patch: 0,
            xi: 0.3,
            eta: 0.7,
            tau: f64::NAN,
            direction: [1.0, 0.0, 0.0],
        };
        assert!(matches!(
            shell_row(&patches, &dofs, 2, &nowhere),
            Err(FrfError::SensorOutside { index: 2, .. })
        ));
    }
}
