//! Straight three-dimensional Timoshenko beam elements: columns, piers and
//! pile extensions under a deck.
//!
//! Two nodes, six dofs each (`u_x, u_y, u_z, θ_x, θ_y, θ_z`, global axes).
//! In the element's frame (`x` from the start to the end, `y` the section's
//! orientation vector made normal to `x`, `z = x × y`) axial stretching,
//! torsion and bending in the `x–y` and `x–z` planes decouple. Bending uses
//! the interdependent interpolation of Friedman & Kosmatka (1993), which
//! makes the stiffness exact for a Timoshenko beam under end loads (shear
//! parameter `Φ = 12 E I / (G A_s L²)`) and gives the consistent mass with
//! rotary inertia from the same shape functions (Friedman & Kosmatka 1993,
//! eq. 14–20); axial and torsional mass are the linear element's.

use faer::Mat;
use thiserror::Error;

use crate::geometry::quadrature::GaussLegendre;
use crate::geometry::vec3::{axpy, cross, dot, norm, normalize, scale, sub, Vec3};

/// Dofs per beam node: three translations, three rotations.
pub const DOFS_PER_BEAM_NODE: usize = 6;

#[derive(Debug, Error, Clone, PartialEq)]
pub enum BeamError {
    #[error("the beam's section {name} must be finite and positive, got {value}")]
    Section { name: &'static str, value: f64 },
    #[error("the beam's material {name} must be finite and positive, got {value}")]
    Material { name: &'static str, value: f64 },
    #[error("the beam's poisson ratio must lie in (-1, 0.5), got {0}")]
    Poisson(f64),
    #[error("the beam element has zero length (start and end at {0:?})")]
    ZeroLength(Vec3),
    #[error("the beam's orientation {orientation:?} is parallel to its axis {axis:?}: give a vector across it")]
    Orientation { orientation: Vec3, axis: Vec3 },
}

fn positive(name: &'static str, value: f64, error: fn(&'static str, f64) -> BeamError) -> Result<f64, BeamError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(error(name, value))
    }
}

fn section_error(name: &'static str, value: f64) -> BeamError {
    BeamError::Section { name, value }
}

/// A beam's cross-section in its own axes `y, z`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Section {
    /// `A` (m²).
    pub area: f64,
    /// `I_y` (m⁴): bending in the `x–z` plane.
    pub iy: f64,
    /// `I_z` (m⁴): bending in the `x–y` plane.
    pub iz: f64,
    /// Saint-Venant torsion constant `J` (m⁴).
    pub torsion: f64,
    /// Shear area along `y`, `κ_y A` (m²).
    pub shear_area_y: f64,
    /// Shear area along `z`, `κ_z A` (m²).
    pub shear_area_z: f64,
}

impl Section {
    pub fn new(
        area: f64,
        iy: f64,
        iz: f64,
        torsion: f64,
        shear_area_y: f64,
        shear_area_z: f64,
    ) -> Result<Self, BeamError> {
        Ok(Self {
            area: positive("area", area, section_error)?,
            iy: positive("iy", iy, section_error)?,
            iz: positive("iz", iz, section_error)?,
            torsion: positive("torsion", torsion, section_error)?,
            shear_area_y: positive("shear_area_y", shear_area_y, section_error)?,
            shear_area_z: positive("shear_area_z", shear_area_z, section_error)?,
        })
    }

    /// A solid circle of diameter `d`: `J = I_p = π d⁴/32`, shear
    /// coefficient `κ = 6(1+ν)/(7+6ν)` (Cowper 1966).
    pub fn circle(diameter: f64, poisson: f64) -> Result<Self, BeamError> {
        let d = positive("circle", diameter, section_error)?;
        check_poisson(poisson)?;
        let area = std::f64::consts::PI * d * d / 4.0;
        let i = std::f64::consts::PI * d.powi(4) / 64.0;
        let shear = 6.0 * (1.0 + poisson) / (7.0 + 6.0 * poisson) * area;
        Self::new(area, i, i, 2.0 * i, shear, shear)
    }

    /// A solid rectangle `width` along `y` by `depth` along `z`: torsion
    /// `J = a b³ (1/3 − 0.21 (b/a)(1 − b⁴/(12 a⁴)))`, `a ≥ b` its sides
    /// (Roark, table 10.7, within 4 %), shear coefficient
    /// `κ = 10(1+ν)/(12+11ν)` (Cowper 1966).
    pub fn rectangle(width: f64, depth: f64, poisson: f64) -> Result<Self, BeamError> {
        let b = positive("width", width, section_error)?;
        let h = positive("depth", depth, section_error)?;
        check_poisson(poisson)?;
        let (long, short) = if b >= h { (b, h) } else { (h, b) };
        let ratio = short / long;
        let torsion = long * short.powi(3) * (1.0 / 3.0 - 0.21 * ratio * (1.0 - ratio.powi(4) / 12.0));
        let area = b * h;
        let shear = 10.0 * (1.0 + poisson) / (12.0 + 11.0 * poisson) * area;
        Self::new(area, b * h.powi(3) / 12.0, h * b.powi(3) / 12.0, torsion, shear, shear)
    }

    /// The polar moment `I_y + I_z`: the section's rotary inertia about the
    /// axis per unit density and length.
    pub fn polar(&self) -> f64 {
        self.iy + self.iz
    }
}

fn check_poisson(poisson: f64) -> Result<(), BeamError> {
    if poisson.is_finite() && poisson > -1.0 && poisson < 0.5 {
        Ok(())
    } else {
        Err(BeamError::Poisson(poisson))
    }
}

/// An isotropic beam material.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BeamMaterial {
    /// `E` (Pa).
    pub young: f64,
    /// `G = E / (2(1+ν))` (Pa).
    pub shear_modulus: f64,
    /// `ρ` (kg/m³).
    pub density: f64,
}

impl BeamMaterial {
    pub fn isotropic(young: f64, poisson: f64, density: f64) -> Result<Self, BeamError> {
        let error = |name, value| BeamError::Material { name, value };
        let young = positive("young", young, error)?;
        check_poisson(poisson)?;
        Ok(Self {
            young,
            shear_modulus: young / (2.0 * (1.0 + poisson)),
            density: positive("density", density, error)?,
        })
    }
}

/// A part of a beam's stiffness that a multiplier may scale
/// ([`crate::model::member_stiffness`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum StiffnessPart {
    /// Axial, torsional and bending stiffness together (a factor on `E`
    /// and `G`).
    #[default]
    All,
    /// `E A`: stretching along the axis.
    Axial,
    /// `G J`: twisting about the axis.
    Torsion,
    /// Bending in both planes with its shear (`E I` and `G A_s` together,
    /// so the shear parameter `Φ` stays: a cracked section's effective
    /// flexural stiffness).
    Bending,
}

impl StiffnessPart {
    pub const NAMES: [&'static str; 4] = ["all", "axial", "torsion", "bending"];

    pub fn parse(name: &str) -> Option<Self> {
        match name {
            "all" => Some(Self::All),
            "axial" => Some(Self::Axial),
            "torsion" => Some(Self::Torsion),
            "bending" => Some(Self::Bending),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        Self::NAMES[self as usize]
    }
}

/// One straight two-node Timoshenko element.
#[derive(Debug, Clone, PartialEq)]
pub struct BeamElement {
    start: Vec3,
    length: f64,
    /// Rows: the element's `x, y, z` axes in global coordinates.
    axes: [Vec3; 3],
    section: Section,
    material: BeamMaterial,
}

impl BeamElement {
    /// The element from `start` to `end`, its section's `y` axis along
    /// `orientation` made normal to the element's axis.
    pub fn new(
        start: Vec3,
        end: Vec3,
        orientation: Vec3,
        section: Section,
        material: BeamMaterial,
    ) -> Result<Self, BeamError> {
        let along = sub(end, start);
        let length = norm(along);
        if !(length.is_finite() && length > 1e-9 * norm(start).max(norm(end)).max(1.0)) {
            return Err(BeamError::ZeroLength(start));
        }
        let x = scale(along, 1.0 / length);
        let y = axpy(orientation, -dot(orientation, x), x);
        let y = normalize(y)
            .filter(|_| norm(y) > 1e-6 * norm(orientation))
            .ok_or(BeamError::Orientation { orientation, axis: x })?;
        Ok(Self {
            start,
            length,
            axes: [x, y, cross(x, y)],
            section,
            material,
        })
    }

    pub fn length(&self) -> f64 {
        self.length
    }

    pub fn start(&self) -> Vec3 {
        self.start
    }

    /// The element's `x, y, z` axes in global coordinates.
    pub fn axes(&self) -> [Vec3; 3] {
        self.axes
    }

    /// The 12 × 12 stiffness on the global dofs of its two nodes.
    pub fn stiffness(&self) -> Mat<f64> {
        self.to_global(&self.local_stiffness())
    }

    /// The 12 × 12 consistent mass on the global dofs of its two nodes.
    pub fn mass(&self) -> Mat<f64> {
        self.to_global(&self.local_mass())
    }

    /// The part `part` of the stiffness on the global dofs of its two nodes
    /// (the parts add up to [`Self::stiffness`]).
    pub fn stiffness_part(&self, part: StiffnessPart) -> Mat<f64> {
        self.to_global(&self.local_stiffness_part(part))
    }

    /// The stiffness in the element's frame.
    pub fn local_stiffness(&self) -> Mat<f64> {
        self.local_stiffness_part(StiffnessPart::All)
    }

    /// The part `part` of the stiffness in the element's frame: axial
    /// stretching, torsion and bending in the two planes decouple there.
    fn local_stiffness_part(&self, part: StiffnessPart) -> Mat<f64> {
        let (s, m, l) = (&self.section, &self.material, self.length);
        let mut k = Mat::<f64>::zeros(12, 12);
        if matches!(part, StiffnessPart::All | StiffnessPart::Axial) {
            put_pair(&mut k, [0, 6], m.young * s.area / l);
        }
        if matches!(part, StiffnessPart::All | StiffnessPart::Torsion) {
            put_pair(&mut k, [3, 9], m.shear_modulus * s.torsion / l);
        }
        if matches!(part, StiffnessPart::All | StiffnessPart::Bending) {
            let phi_y = self.shear_parameter(s.iz, s.shear_area_y);
            put_bending(&mut k, [1, 5, 7, 11], 1.0, &bending_stiffness(m.young * s.iz, l, phi_y));
            let phi_z = self.shear_parameter(s.iy, s.shear_area_z);
            put_bending(
                &mut k,
                [2, 4, 8, 10],
                -1.0,
                &bending_stiffness(m.young * s.iy, l, phi_z),
            );
        }
        k
    }

    /// The consistent mass in the element's frame.
    pub fn local_mass(&self) -> Mat<f64> {
        let (s, rho, l) = (&self.section, self.material.density, self.length);
        let mut m = Mat::<f64>::zeros(12, 12);
        put_linear_mass(&mut m, [0, 6], rho * s.area * l);
        put_linear_mass(&mut m, [3, 9], rho * s.polar() * l);
        let phi_y = self.shear_parameter(s.iz, s.shear_area_y);
        put_bending(
            &mut m,
            [1, 5, 7, 11],
            1.0,
            &bending_mass(rho * s.area, rho * s.iz, l, phi_y),
        );
        let phi_z = self.shear_parameter(s.iy, s.shear_area_z);
        put_bending(
            &mut m,
            [2, 4, 8, 10],
            -1.0,
            &bending_mass(rho * s.area, rho * s.iy, l, phi_z),
        );
        m
    }

    /// The translation and rotation of the axis at `x` (a fraction of the
    /// length from the start) in global axes, as rows on the element's 12
    /// global dofs: linear in the axial and torsional dofs, the bending
    /// planes by the interdependent interpolation that built the element
    /// (eq. 14–15 of Friedman & Kosmatka 1993), so a node's motion is its
    /// dofs exactly.
    pub fn motion_rows(&self, x: f64) -> [[f64; 12]; 6] {
        let (s, l) = (&self.section, self.length);
        let mut local = [[0.0; 12]; 6];
        local[0][0] = 1.0 - x;
        local[0][6] = x;
        local[3][3] = 1.0 - x;
        local[3][9] = x;
        // x–y plane: v and θ_z = dv/dx on (1, 5, 7, 11).
        let phi_y = self.shear_parameter(s.iz, s.shear_area_y);
        let (v, t) = (bending_displacement(x, l, phi_y), bending_rotation(x, l, phi_y));
        for (a, &dof) in [1, 5, 7, 11].iter().enumerate() {
            local[1][dof] = v[a];
            local[5][dof] = t[a];
        }
        // x–z plane: w and θ_y = −dw/dx on (2, 4, 8, 10), whose rotation
        // dofs are −dw/dx.
        let phi_z = self.shear_parameter(s.iy, s.shear_area_z);
        let (w, t) = (bending_displacement(x, l, phi_z), bending_rotation(x, l, phi_z));
        let sign = [1.0, -1.0, 1.0, -1.0];
        for (a, &dof) in [2, 4, 8, 10].iter().enumerate() {
            local[2][dof] = sign[a] * w[a];
            local[4][dof] = -sign[a] * t[a];
        }
        // Global output `Aᵀ (local)`, local dofs `A (global)` per node.
        let a = &self.axes;
        let mut rows = [[0.0; 12]; 6];
        for (r, row) in rows.iter_mut().enumerate() {
            let (block, g) = (r / 3, r % 3);
            for (c, entry) in row.iter_mut().enumerate() {
                let (node_block, k) = (c / 3, c % 3);
                for i in 0..3 {
                    for j in 0..3 {
                        *entry += a[i][g] * local[3 * block + i][3 * node_block + j] * a[j][k];
                    }
                }
            }
        }
        rows
    }

    /// `Φ = 12 E I / (G A_s L²)`.
    fn shear_parameter(&self, inertia: f64, shear_area: f64) -> f64 {
        12.0 * self.material.young * inertia / (self.material.shear_modulus * shear_area * self.length.powi(2))
    }

    /// `Tᵀ A T`, `T` the rotation to the element's frame at both nodes'
    /// translations and rotations.
    fn to_global(&self, local: &Mat<f64>) -> Mat<f64> {
        let t = Mat::<f64>::from_fn(
            12,
            12,
            |r, c| {
                if r / 3 == c / 3 {
                    self.axes[r % 3][c % 3]
                } else {
                    0.0
                }
            },
        );
        t.transpose() * local * &t
    }
}

/// `value [1 −1; −1 1]` on dofs `at`.
fn put_pair(target: &mut Mat<f64>, at: [usize; 2], value: f64) {
    for (a, &i) in at.iter().enumerate() {
        for (b, &j) in at.iter().enumerate() {
            target[(i, j)] += if a == b { value } else { -value };
        }
    }
}

/// `total/6 [2 1; 1 2]` on dofs `at`.
fn put_linear_mass(target: &mut Mat<f64>, at: [usize; 2], total: f64) {
    for (a, &i) in at.iter().enumerate() {
        for (b, &j) in at.iter().enumerate() {
            target[(i, j)] += total / 6.0 * if a == b { 2.0 } else { 1.0 };
        }
    }
}

/// A plane bending matrix on `(v₁, θ₁, v₂, θ₂)` with `θ = dv/dx` put on dofs
/// `at`; `rotation_sign` −1 where the dof's rotation is `−dv/dx` (bending in
/// the `x–z` plane: `θ_y = −dw/dx`).
fn put_bending(target: &mut Mat<f64>, at: [usize; 4], rotation_sign: f64, block: &[[f64; 4]; 4]) {
    let sign = [1.0, rotation_sign, 1.0, rotation_sign];
    for a in 0..4 {
        for b in 0..4 {
            target[(at[a], at[b])] += sign[a] * sign[b] * block[a][b];
        }
    }
}

/// Friedman & Kosmatka (1993) eq. 19: exact Timoshenko bending stiffness.
fn bending_stiffness(ei: f64, l: f64, phi: f64) -> [[f64; 4]; 4] {
    let c = ei / ((1.0 + phi) * l.powi(3));
    let (a, b) = ((4.0 + phi) * l * l, (2.0 - phi) * l * l);
    [
        [12.0 * c, 6.0 * l * c, -12.0 * c, 6.0 * l * c],
        [6.0 * l * c, a * c, -6.0 * l * c, b * c],
        [-12.0 * c, -6.0 * l * c, 12.0 * c, -6.0 * l * c],
        [6.0 * l * c, b * c, -6.0 * l * c, a * c],
    ]
}

/// The consistent mass of the interdependent interpolation (Friedman &
/// Kosmatka 1993, eq. 20), translational (`ρA`) plus rotary (`ρI`):
/// `∫ ρA N_vᵀ N_v + ρI N_θᵀ N_θ dx` with their shape functions (eq. 14–15,
/// `μ = 1/(1+Φ)`, `ξ = x/L`), integrated exactly by 4 Gauss points
/// (polynomials of degree 6).
fn bending_mass(rho_a: f64, rho_i: f64, l: f64, phi: f64) -> [[f64; 4]; 4] {
    let displacement = |x: f64| bending_displacement(x, l, phi);
    let rotation = |x: f64| bending_rotation(x, l, phi);
    let mut mass = [[0.0; 4]; 4];
    for (x, w) in GaussLegendre::new(4).mapped(0.0, 1.0) {
        let (v, t) = (displacement(x), rotation(x));
        for a in 0..4 {
            for b in 0..4 {
                mass[a][b] += w * l * (rho_a * v[a] * v[b] + rho_i * t[a] * t[b]);
            }
        }
    }
    mass
}

/// The interdependent interpolation's displacement `v(ξ)` on
/// `(v₁, θ₁, v₂, θ₂)` (Friedman & Kosmatka 1993, eq. 14; `μ = 1/(1+Φ)`).
fn bending_displacement(x: f64, l: f64, phi: f64) -> [f64; 4] {
    let mu = 1.0 / (1.0 + phi);
    [
        mu * (2.0 * x.powi(3) - 3.0 * x * x - phi * x + 1.0 + phi),
        l * mu * (x.powi(3) - (2.0 + phi / 2.0) * x * x + (1.0 + phi / 2.0) * x),
        mu * (-2.0 * x.powi(3) + 3.0 * x * x + phi * x),
        l * mu * (x.powi(3) - (1.0 - phi / 2.0) * x * x - phi / 2.0 * x),
    ]
}

/// Its section rotation `θ(ξ)` (eq. 15).
fn bending_rotation(x: f64, l: f64, phi: f64) -> [f64; 4] {
    let mu = 1.0 / (1.0 + phi);
    [
        6.0 * mu / l * (x * x - x),
        mu * (3.0 * x * x - (4.0 + phi) * x + 1.0 + phi),
        -6.0 * mu / l * (x * x - x),
        mu * (3.0 * x * x - (2.0 - phi) * x),
    ]
}

#[cfg(test)]
mod tests;
