//! Undamped modes: the generalised eigenproblem `K φ = ω² M φ` (eq. 27).
//!
//! Dense path: on the reduced, Jacobi-scaled matrices (`S Tᵀ K T S`,
//! `S Tᵀ M T S`, `S = diag(Tᵀ M T)^{-1/2}`), factor
//! `M = L Lᵀ`, solve the standard symmetric problem `L⁻¹ K L⁻ᵀ y = ω² y`,
//! and back-transform `φ = T S L⁻ᵀ y`. Modes come out mass-normalised
//! (`φᵀ M φ = 1`) with eigenvalues ascending. Cost is `O(n³)`: about a second
//! for 3 000 dofs. For much larger nets the plan is a sparse shift-invert
//! Lanczos on the banded `K - σM` (faer's sparse Cholesky), computing only the
//! modes below the band's upper frequency; see ARCHITECTURE.md.
//!
//! Classification: `rigid` when `ω < 1e-6 ω_max` (the round-off level of a
//! zero eigenvalue after the Cholesky transform is `~1e-16 ω²_max`);
//! otherwise `bending` when most of the translational kinetic energy is
//! along the directors `v3` (out of the surface) and `membrane` when most is
//! tangential. Energies use the row-sum lumped mass per control point.

use crate::constraints::DofReduction;
use crate::shell::{Shell, DOFS_PER_CONTROL_POINT};
use crate::vec3::{dot, Vec3};
use faer::diag::Diag;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::evd::{self, ComputeEigenvectors, SelfAdjointEvdParams};
use faer::{Auto, Mat, Par, Side, Spec};
use std::f64::consts::PI;
use thiserror::Error;

#[derive(Debug, Clone, PartialEq, Error)]
pub enum ModalError {
    #[error("the mass matrix is not positive definite (dof {index}): check density and thickness")]
    MassNotPositiveDefinite { index: usize },
    #[error("the symmetric eigensolver did not converge")]
    NoConvergence,
    #[error("the model has no free dofs: every dof is constrained")]
    NoFreeDofs,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ModeKind {
    Rigid,
    Membrane,
    Bending,
}

/// Mass-normalised modes of a model.
#[derive(Debug, Clone)]
pub struct Modes {
    /// `ω_i²`, ascending (rad²/s²); may be slightly negative for rigid modes.
    pub omega2: Vec<f64>,
    /// Full generalised mode shapes, one per column (`ndof × nmodes`).
    pub shapes: Mat<f64>,
    pub kinds: Vec<ModeKind>,
}

impl Modes {
    /// Natural frequency in Hz of mode `i`: `f_i = ω_i / 2π` (zero for
    /// a rigid mode with a round-off negative eigenvalue).
    pub fn frequency_hz(&self, i: usize) -> f64 {
        self.omega2[i].max(0.0).sqrt() / (2.0 * PI)
    }

    pub fn frequencies_hz(&self) -> Vec<f64> {
        (0..self.omega2.len()).map(|i| self.frequency_hz(i)).collect()
    }

    pub fn len(&self) -> usize {
        self.omega2.len()
    }

    pub fn is_empty(&self) -> bool {
        self.omega2.is_empty()
    }
}

/// Solves eq. (27) for all modes of the constrained model.
pub fn solve(
    stiffness: &Mat<f64>,
    mass: &Mat<f64>,
    reduction: &DofReduction,
    shell: &Shell,
) -> Result<Modes, ModalError> {
    let n = reduction.free_count();
    if n == 0 {
        return Err(ModalError::NoFreeDofs);
    }
    // Jacobi scaling S = diag(M)^{-1/2}: rotational dofs carry t²/12 of the
    // translational inertia, and without scaling the Cholesky transform loses
    // cond(M)·eps of accuracy in the low modes.
    let (mut kr, mut mr) = (reduction.reduce(stiffness), reduction.reduce(mass));
    let mut s = vec![0.0; n];
    for i in 0..n {
        let d = mr[(i, i)];
        if !(d > 0.0 && d.is_finite()) {
            return Err(ModalError::MassNotPositiveDefinite { index: i });
        }
        s[i] = 1.0 / d.sqrt();
    }
    for j in 0..n {
        for i in 0..n {
            let f = s[i] * s[j];
            kr[(i, j)] *= f;
            mr[(i, j)] *= f;
        }
    }
    let llt = mr.llt(Side::Lower).map_err(|e| match e {
        faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot { index } => {
            ModalError::MassNotPositiveDefinite { index }
        }
    })?;
    let l = llt.L();
    // A = L⁻¹ K L⁻ᵀ, formed as L⁻¹ (L⁻¹ K)ᵀ since K is symmetric.
    let mut x = kr;
    l.solve_lower_triangular_in_place(x.as_mut());
    let mut a = x.transpose().to_owned();
    l.solve_lower_triangular_in_place(a.as_mut());
    let a = Mat::from_fn(n, n, |i, j| 0.5 * (a[(i, j)] + a[(j, i)]));
    let (omega2, mut y) = symmetric_eigen(&a)?;
    l.transpose().solve_upper_triangular_in_place(y.as_mut());
    for i in 0..n {
        for k in 0..n {
            y[(i, k)] *= s[i];
        }
    }
    let shapes = reduction.expand(&y);
    let kinds = classify(&omega2, &shapes, mass, shell);
    Ok(Modes { omega2, shapes, kinds })
}

/// Eigenvalues (ascending) and orthonormal eigenvectors of a symmetric matrix
/// (lower triangle read) by tridiagonalisation and the implicit QR algorithm.
///
/// faer's default switches to divide and conquer at n ≥ 128; on our graded
/// matrices that path returned residuals `‖Ay - λy‖ ≈ 1e-7 ‖A‖`, a million
/// times the round-off level, so the recursion is disabled here. The QR path
/// meets `1e-13 ‖A‖` and still takes only 0.25 s for n = 1000.
pub fn symmetric_eigen(a: &Mat<f64>) -> Result<(Vec<f64>, Mat<f64>), ModalError> {
    let n = a.nrows();
    let mut params = <SelfAdjointEvdParams as Auto<f64>>::auto();
    params.recursion_threshold = usize::MAX;
    let params: Spec<SelfAdjointEvdParams, f64> = params.into();
    let mut s = Diag::<f64>::zeros(n);
    let mut u = Mat::<f64>::zeros(n, n);
    let mut buffer = MemBuffer::new(evd::self_adjoint_evd_scratch::<f64>(
        n,
        ComputeEigenvectors::Yes,
        Par::Seq,
        params,
    ));
    evd::self_adjoint_evd(
        a.as_ref(),
        s.as_mut(),
        Some(u.as_mut()),
        Par::Seq,
        MemStack::new(&mut buffer),
        params,
    )
    .map_err(|_| ModalError::NoConvergence)?;
    Ok(((0..n).map(|i| s[i]).collect(), u))
}

fn classify(omega2: &[f64], shapes: &Mat<f64>, mass: &Mat<f64>, shell: &Shell) -> Vec<ModeKind> {
    let max = omega2.iter().copied().fold(0.0f64, f64::max);
    let cps = shell.control_point_count();
    // Row-sum lumped translational mass per control point (x rows).
    let lumped: Vec<f64> = (0..cps)
        .map(|cp| {
            let r = DOFS_PER_CONTROL_POINT * cp;
            (0..cps).map(|c| mass[(r, DOFS_PER_CONTROL_POINT * c)]).sum()
        })
        .collect();
    (0..omega2.len())
        .map(|k| {
            if omega2[k] < 1e-12 * max {
                return ModeKind::Rigid;
            }
            let (mut normal, mut tangential) = (0.0, 0.0);
            for cp in 0..cps {
                let b = DOFS_PER_CONTROL_POINT * cp;
                let u: Vec3 = [shapes[(b, k)], shapes[(b + 1, k)], shapes[(b + 2, k)]];
                let un = dot(u, shell.frames()[cp].v3);
                normal += lumped[cp] * un * un;
                tangential += lumped[cp] * (dot(u, u) - un * un);
            }
            if normal >= tangential {
                ModeKind::Bending
            } else {
                ModeKind::Membrane
            }
        })
        .collect()
}
