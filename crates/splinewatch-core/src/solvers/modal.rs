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
//! Repeated solves ([`ModalSolver`], the updating loop): the transform above
//! is done once per exactly decoupled block of the pencil, `K(κ)` enters as
//! a low-rank update of the transformed matrix, and blocks no spring reaches
//! keep their modes. For the Sinello deck this solves 195 of 325 dofs per
//! evaluation instead of all 325, about a fifth of the dense cost.
//!
//! Classification: `rigid` when `ω < 1e-6 ω_max` (the round-off level of a
//! zero eigenvalue after the Cholesky transform is `~1e-16 ω²_max`);
//! otherwise `bending` when most of the translational kinetic energy is
//! along the directors `v3` (out of the surface) and `membrane` when most is
//! tangential. Energies use the row-sum lumped mass per control point.

use super::mode_motion::{DeckAxes, MotionShares};
use crate::geometry::vec3::{dot, Vec3};
use crate::linalg::symmetric_part;
use crate::model::constraints::DofReduction;
use crate::model::shell::{Frame, DOFS_PER_CONTROL_POINT};
use crate::model::springs::LowRankBlock;
use faer::diag::Diag;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::evd::{self, ComputeEigenvectors, SelfAdjointEvdParams};
use faer::linalg::matmul::matmul;
use faer::{Accum, Auto, Mat, Par, Side, Spec};
use std::borrow::Cow;
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
    /// Per mode, the shares of its lumped translational kinetic energy along
    /// the global x, y and z axes (they sum to 1): a deck's vertical mode is
    /// mostly z, a transverse one mostly the horizontal axis across the span.
    pub translation_shares: Vec<[f64; 3]>,
    /// The shell control points' lumped translational masses (kg), which
    /// weigh the shares.
    pub lumped: Vec<f64>,
}

impl Modes {
    /// The modes `(ω², Φ)` of a model whose lumped translational masses per
    /// control point are `lumped` and whose control points sit in `frames`:
    /// each mode classified ([`ModeKind`]) and its translation shares taken,
    /// so every solver path finishes its modes the same way.
    pub(crate) fn classified(omega2: Vec<f64>, shapes: Mat<f64>, lumped: &[f64], frames: &[Frame]) -> Self {
        let kinds = classify_lumped(&omega2, &shapes, lumped, frames);
        let translation_shares = translation_shares(&shapes, lumped);
        Self {
            omega2,
            shapes,
            kinds,
            translation_shares,
            lumped: lumped.to_vec(),
        }
    }

    /// The deck's axes and stations for [`Self::motion`], with `positions`
    /// the shell's control points in global order (`None` for a deck
    /// without mass or extent in plan).
    pub fn deck_axes(&self, positions: &[Vec3]) -> Option<DeckAxes> {
        DeckAxes::new(positions, &self.lumped)
    }

    /// The share of mode `i`'s strain energy stored in one spring field
    /// (a field, a bearing or a line support: its `∂K/∂κ_j` blocks and
    /// coefficients κ_j, on the generalised dofs): `Σ_j κ_j φ_iᵀ B_j φ_i /
    /// ω_i²`, since `K` is linear in κ and `φ_iᵀ K φ_i = ω_i²` for a
    /// mass-normalised mode (the modal strain energy fraction); zero for a
    /// rigid mode.
    pub fn spring_energy_share(&self, i: usize, blocks: &[LowRankBlock], coefficients: &[f64]) -> f64 {
        if self.kinds[i] == ModeKind::Rigid || self.omega2[i] <= 0.0 {
            return 0.0;
        }
        let energy: f64 = blocks
            .iter()
            .zip(coefficients)
            .map(|(b, k)| k * b.quadratic_form(|d| self.shapes[(d, i)]))
            .sum();
        energy / self.omega2[i]
    }

    /// Each mode's share of its strain energy in each stiffness-field
    /// coefficient's part of the stiffness, `θ_k φ_iᵀ B_k φ_i / ω_i²`
    /// (`B_k = ∂K/∂θ_k`, `K` linear in θ; fields flattened), with
    /// `times(k, Φ) = B_k Φ` on the generalised dofs: modes × coefficients,
    /// zero for a rigid mode.
    pub fn field_energy_shares(&self, theta: &[Vec<f64>], times: impl Fn(usize, &Mat<f64>) -> Mat<f64>) -> Mat<f64> {
        let theta: Vec<f64> = theta.iter().flatten().copied().collect();
        let mut out = Mat::zeros(self.len(), theta.len());
        for (k, &t) in theta.iter().enumerate() {
            let product = times(k, &self.shapes);
            for i in 0..self.len() {
                if self.kinds[i] == ModeKind::Rigid || self.omega2[i] <= 0.0 {
                    continue;
                }
                let energy: f64 = (0..self.shapes.nrows())
                    .map(|r| self.shapes[(r, i)] * product[(r, i)])
                    .sum();
                out[(i, k)] = t * energy / self.omega2[i];
            }
        }
        out
    }

    /// Where mode `i` moves the deck: its energy along, across, vertical
    /// and in torsion ([`super::mode_motion`]).
    pub fn motion(&self, axes: &DeckAxes, i: usize) -> MotionShares {
        axes.shares(|cp| {
            let b = DOFS_PER_CONTROL_POINT * cp;
            [self.shapes[(b, i)], self.shapes[(b + 1, i)], self.shapes[(b + 2, i)]]
        })
    }

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

/// Solves eq. (27) for all modes of the constrained model in one dense
/// eigenproblem. Reference path: the updating loop uses [`ModalSolver`],
/// which gives the same modes faster.
pub fn solve(
    stiffness: &Mat<f64>,
    mass: &Mat<f64>,
    reduction: &DofReduction,
    frames: &[Frame],
) -> Result<Modes, ModalError> {
    let n = reduction.free_count();
    if n == 0 {
        return Err(ModalError::NoFreeDofs);
    }
    let all: Vec<usize> = (0..n).collect();
    let pencil = ScaledPencil::new(&reduction.reduce(stiffness), &reduction.reduce(mass), &all)?;
    let (omega2, y) = symmetric_eigen(&pencil.a_free)?;
    let shapes = reduction.expand(&pencil.back_transform(y));
    Ok(Modes::classified(
        omega2,
        shapes,
        &lumped_mass(mass, frames.len()),
        frames,
    ))
}

/// One diagonal block `(K_c, M_c)` of the reduced pencil, transformed to a
/// standard problem. Jacobi scaling `S = diag(M_c)^{-1/2}` first: rotational
/// dofs carry t²/12 of the translational inertia, and without scaling the
/// Cholesky transform loses cond(M)·eps of accuracy in the low modes. Then
/// `S M_c S = L Lᵀ` and `A = L⁻¹ S K_c S L⁻ᵀ`.
#[derive(Debug, Clone)]
struct ScaledPencil {
    scale: Vec<f64>,
    l: Mat<f64>,
    a_free: Mat<f64>,
}

impl ScaledPencil {
    /// `kr`, `mr` are the full reduced matrices; `dofs` selects the block.
    fn new(kr: &Mat<f64>, mr: &Mat<f64>, dofs: &[usize]) -> Result<Self, ModalError> {
        let n = dofs.len();
        let mut scale = vec![0.0; n];
        for (i, &d) in dofs.iter().enumerate() {
            let m = mr[(d, d)];
            if !(m > 0.0 && m.is_finite()) {
                return Err(ModalError::MassNotPositiveDefinite { index: d });
            }
            scale[i] = 1.0 / m.sqrt();
        }
        let m = Mat::from_fn(n, n, |i, j| mr[(dofs[i], dofs[j])] * scale[i] * scale[j]);
        let llt = m.llt(Side::Lower).map_err(|e| match e {
            faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot { index } => {
                ModalError::MassNotPositiveDefinite { index: dofs[index] }
            }
        })?;
        let l = llt.L().to_owned();
        // A = L⁻¹ K L⁻ᵀ, formed as L⁻¹ (L⁻¹ K)ᵀ since K is symmetric.
        let mut x = Mat::from_fn(n, n, |i, j| kr[(dofs[i], dofs[j])] * scale[i] * scale[j]);
        l.solve_lower_triangular_in_place(x.as_mut());
        let mut a = x.transpose().to_owned();
        l.solve_lower_triangular_in_place(a.as_mut());
        let a_free = symmetric_part(&a);
        Ok(Self { scale, l, a_free })
    }

    /// `L⁻¹ S X S L⁻ᵀ` of a symmetric `X` on the block's dofs (how `K`
    /// enters the standard problem), symmetrised.
    fn congruence(&self, x: Mat<f64>) -> Mat<f64> {
        let y = self.forward(x);
        symmetric_part(&self.forward(y.transpose().to_owned()))
    }

    /// `L⁻¹ S X` for rows `X` on the block's dofs.
    fn forward(&self, mut x: Mat<f64>) -> Mat<f64> {
        for j in 0..x.ncols() {
            for i in 0..x.nrows() {
                x[(i, j)] *= self.scale[i];
            }
        }
        self.l.solve_lower_triangular_in_place(x.as_mut());
        x
    }

    /// Eigenvectors `y` of `A` to mass-normalised block shapes `S L⁻ᵀ y`.
    fn back_transform(&self, mut y: Mat<f64>) -> Mat<f64> {
        self.l.transpose().solve_upper_triangular_in_place(y.as_mut());
        for k in 0..y.ncols() {
            for i in 0..y.nrows() {
                y[(i, k)] *= self.scale[i];
            }
        }
        y
    }
}

/// Eq. (27) prepared for many spring coefficient vectors `κ`: only
/// `ΔK(κ) = Σ_j κ_j ∂K/∂κ_j` changes between solves (eq. 22–23).
///
/// At construction the reduced dofs are split into the connected components
/// of the union sparsity pattern of `K_f`, `M` and every `∂K/∂κ_j` (a flat
/// deck on vertical springs splits exactly into its in-plane and its
/// out-of-plane dofs), and each component gets its `ScaledPencil` once. A
/// component that no spring reaches has κ-independent modes: solved once.
/// Per `κ`, every other component forms `A = A_f + W Δ(κ) Wᵀ` with
/// `W = L⁻¹ S Tᵀ E_U` (`U`: the spring dofs, `|U|` columns) and calls the
/// symmetric eigensolver on its own size. The eigenpairs of a block-diagonal
/// pencil are those of its blocks, so this is exact, not an approximation.
///
/// Stiffness fields of the deck ([`crate::model::stiffness_field`]) change `K_f`
/// itself, `K_f(θ) = K_f + Σ_k (θ_k − 1) ∂K/∂θ_k`: no longer low rank, but
/// still linear, so each `∂K/∂θ_k` is transformed once per component,
/// `A_k = L⁻¹ S Tᵀ ∂K/∂θ_k T S L⁻ᵀ`, and a solve adds `Σ (θ_k − 1) A_k` to
/// `A`: one weighted sum of dense blocks and the eigensolver, never a new
/// Cholesky factorisation or re-assembly (the mass does not depend on θ).
#[derive(Debug, Clone)]
pub struct ModalSolver {
    free: usize,
    /// Stiffness-field coefficients (`∂K/∂θ_k`), flattened over fields.
    field_count: usize,
    /// Positions in `U` and values of every `∂K/∂κ_j`, flattened over fields.
    blocks: Vec<(Vec<usize>, Mat<f64>)>,
    spring_dof_count: usize,
    components: Vec<Component>,
}

#[derive(Debug, Clone)]
struct Component {
    /// Reduced dof indices, ascending.
    dofs: Vec<usize>,
    pencil: ScaledPencil,
    /// Positions in `U` of the spring dofs reaching this component.
    springs: Vec<usize>,
    /// `L⁻¹ S (Tᵀ E_U)[dofs, springs]`.
    w: Mat<f64>,
    /// Transformed `∂K/∂θ_k` reaching this component: `(k, A_k)`.
    fields: Vec<(usize, Mat<f64>)>,
    /// Eigenvalues and block shapes when no spring or field reaches the component.
    fixed: Option<(Vec<f64>, Mat<f64>)>,
}

impl ModalSolver {
    pub fn new(
        free_stiffness: &Mat<f64>,
        mass: &Mat<f64>,
        spring_blocks: &[&LowRankBlock],
        reduction: &DofReduction,
    ) -> Result<Self, ModalError> {
        Self::with_fields(free_stiffness, mass, spring_blocks, &[], reduction)
    }

    /// As [`Self::new`], with the derivative matrices `∂K/∂θ_k` of stiffness
    /// fields (unconstrained dofs, flattened over fields).
    #[allow(
        clippy::too_many_lines,
        reason = "the preparation steps (components, Jacobi scaling, Cholesky of M, transformed K_f, spring columns, field blocks) share the per-component index maps"
    )]
    pub fn with_fields(
        free_stiffness: &Mat<f64>,
        mass: &Mat<f64>,
        spring_blocks: &[&LowRankBlock],
        field_matrices: &[&Mat<f64>],
        reduction: &DofReduction,
    ) -> Result<Self, ModalError> {
        let n = reduction.free_count();
        if n == 0 {
            return Err(ModalError::NoFreeDofs);
        }
        let (kr, mr) = (reduction.reduce(free_stiffness), reduction.reduce(mass));
        let fields_reduced: Vec<Mat<f64>> = field_matrices.iter().map(|m| reduction.reduce(m)).collect();
        // Rows of T: the reduced dofs (and weights) each full dof enters.
        let mut rows_of: Vec<Vec<(usize, f64)>> = vec![Vec::new(); reduction.full_count()];
        for (c, col) in reduction.columns().iter().enumerate() {
            for &(d, t) in col {
                rows_of[d].push((c, t));
            }
        }
        let mut spring_dofs: Vec<usize> = spring_blocks.iter().flat_map(|b| b.dofs.iter().copied()).collect();
        spring_dofs.sort_unstable();
        spring_dofs.dedup();
        let blocks: Vec<(Vec<usize>, Mat<f64>)> = spring_blocks
            .iter()
            .map(|b| {
                let pos = b
                    .dofs
                    .iter()
                    .map(|d| spring_dofs.binary_search(d).expect("in the union"))
                    .collect();
                (pos, b.values.clone())
            })
            .collect();
        // Connected components of the union pattern.
        let mut sets = DisjointSets::new(n);
        for j in 0..n {
            for i in j + 1..n {
                if kr[(i, j)] != 0.0 || kr[(j, i)] != 0.0 || mr[(i, j)] != 0.0 || mr[(j, i)] != 0.0 {
                    sets.union(i, j);
                }
            }
        }
        for b in spring_blocks {
            for (a, &da) in b.dofs.iter().enumerate() {
                for (c, &dc) in b.dofs.iter().enumerate() {
                    if b.values[(a, c)] == 0.0 {
                        continue;
                    }
                    for &(ra, _) in &rows_of[da] {
                        for &(rc, _) in &rows_of[dc] {
                            sets.union(ra, rc);
                        }
                    }
                }
            }
        }
        let mut members: Vec<Vec<usize>> = Vec::new();
        let mut slot = vec![usize::MAX; n];
        for d in 0..n {
            let root = sets.find(d);
            if slot[root] == usize::MAX {
                slot[root] = members.len();
                members.push(Vec::new());
            }
            members[slot[root]].push(d);
        }
        let mut components = Vec::with_capacity(members.len());
        for dofs in members {
            let pencil = ScaledPencil::new(&kr, &mr, &dofs)?;
            let springs: Vec<usize> = (0..spring_dofs.len())
                .filter(|&u| {
                    rows_of[spring_dofs[u]]
                        .iter()
                        .any(|(r, _)| dofs.binary_search(r).is_ok())
                })
                .collect();
            let reach = Mat::from_fn(dofs.len(), springs.len(), |i, k| {
                rows_of[spring_dofs[springs[k]]]
                    .iter()
                    .filter(|(r, _)| *r == dofs[i])
                    .map(|(_, t)| t)
                    .sum()
            });
            let w = pencil.forward(reach);
            let fields: Vec<(usize, Mat<f64>)> = fields_reduced
                .iter()
                .enumerate()
                .filter_map(|(k, m)| {
                    let block = Mat::from_fn(dofs.len(), dofs.len(), |i, j| m[(dofs[i], dofs[j])]);
                    (block.norm_max() > 0.0).then(|| (k, pencil.congruence(block)))
                })
                .collect();
            let fixed = if springs.is_empty() && fields.is_empty() {
                let (omega2, y) = symmetric_eigen(&pencil.a_free)?;
                Some((omega2, pencil.back_transform(y)))
            } else {
                None
            };
            components.push(Component {
                dofs,
                pencil,
                springs,
                w,
                fields,
                fixed,
            });
        }
        Ok(Self {
            free: n,
            field_count: field_matrices.len(),
            blocks,
            spring_dof_count: spring_dofs.len(),
            components,
        })
    }

    /// Number of independent diagonal blocks of the pencil.
    pub fn component_sizes(&self) -> Vec<usize> {
        self.components.iter().map(|c| c.dofs.len()).collect()
    }

    /// Eigenvalues (ascending) and reduced mass-normalised shapes for the
    /// spring coefficients `kappa`, flattened in block order.
    #[track_caller]
    pub fn solve(&self, kappa: &[f64]) -> Result<(Vec<f64>, Mat<f64>), ModalError> {
        self.solve_with_fields(kappa, &vec![1.0; self.field_count])
    }

    /// [`Self::solve`] with stiffness-field coefficients `theta` (flattened
    /// over fields; 1 = nominal).
    #[track_caller]
    pub fn solve_with_fields(&self, kappa: &[f64], theta: &[f64]) -> Result<(Vec<f64>, Mat<f64>), ModalError> {
        assert_eq!(kappa.len(), self.blocks.len(), "one coefficient per spring block");
        assert_eq!(
            theta.len(),
            self.field_count,
            "one coefficient per stiffness-field block"
        );
        let nu = self.spring_dof_count;
        let mut delta = Mat::<f64>::zeros(nu, nu);
        for ((pos, values), &k) in self.blocks.iter().zip(kappa) {
            for (a, &pa) in pos.iter().enumerate() {
                for (b, &pb) in pos.iter().enumerate() {
                    delta[(pa, pb)] += k * values[(a, b)];
                }
            }
        }
        // Eigenpairs per component: kept ones borrowed, the others solved.
        let mut eigen: Vec<Cow<(Vec<f64>, Mat<f64>)>> = Vec::with_capacity(self.components.len());
        for c in &self.components {
            eigen.push(match &c.fixed {
                Some(fixed) => Cow::Borrowed(fixed),
                None => {
                    let d = Mat::from_fn(c.springs.len(), c.springs.len(), |a, b| {
                        delta[(c.springs[a], c.springs[b])]
                    });
                    let wd = &c.w * &d;
                    let mut a = c.pencil.a_free.clone();
                    matmul(a.as_mut(), Accum::Add, wd.as_ref(), c.w.transpose(), 1.0, Par::Seq);
                    for (k, ak) in &c.fields {
                        let deviation = theta[*k] - 1.0;
                        if deviation != 0.0 {
                            a += ak * deviation;
                        }
                    }
                    let (omega2, y) = symmetric_eigen(&a)?;
                    Cow::Owned((omega2, c.pencil.back_transform(y)))
                }
            });
        }
        let mut pairs: Vec<(f64, usize, usize)> = eigen
            .iter()
            .enumerate()
            .flat_map(|(ci, e)| e.0.iter().enumerate().map(move |(k, &w2)| (w2, ci, k)))
            .collect();
        pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut shapes = Mat::<f64>::zeros(self.free, self.free);
        for (col, &(_, ci, k)) in pairs.iter().enumerate() {
            let phi = &eigen[ci].1;
            for (r, &d) in self.components[ci].dofs.iter().enumerate() {
                shapes[(d, col)] = phi[(r, k)];
            }
        }
        Ok((pairs.iter().map(|p| p.0).collect(), shapes))
    }

    /// All modes for `kappa` (and the fields' `theta`, flattened; empty:
    /// nominal): [`Self::solve_with_fields`], expanded and classified.
    pub fn modes(
        &self,
        kappa: &[f64],
        theta: &[f64],
        reduction: &DofReduction,
        mass: &Mat<f64>,
        frames: &[Frame],
    ) -> Result<Modes, ModalError> {
        let nominal;
        let theta = if theta.is_empty() {
            nominal = vec![1.0; self.field_count];
            &nominal
        } else {
            theta
        };
        let (omega2, y) = self.solve_with_fields(kappa, theta)?;
        let shapes = reduction.expand(&y);
        Ok(Modes::classified(
            omega2,
            shapes,
            &lumped_mass(mass, frames.len()),
            frames,
        ))
    }
}

/// Union–find with path halving.
struct DisjointSets {
    parent: Vec<usize>,
}

impl DisjointSets {
    fn new(n: usize) -> Self {
        Self {
            parent: (0..n).collect(),
        }
    }

    fn find(&mut self, mut i: usize) -> usize {
        while self.parent[i] != i {
            self.parent[i] = self.parent[self.parent[i]];
            i = self.parent[i];
        }
        i
    }

    fn union(&mut self, a: usize, b: usize) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            self.parent[ra.max(rb)] = ra.min(rb);
        }
    }
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

/// Row-sum lumped translational mass of each of `cps` control points (their
/// x rows of `mass`).
fn lumped_mass(mass: &Mat<f64>, cps: usize) -> Vec<f64> {
    (0..cps)
        .map(|cp| {
            let r = DOFS_PER_CONTROL_POINT * cp;
            (0..cps).map(|c| mass[(r, DOFS_PER_CONTROL_POINT * c)]).sum()
        })
        .collect()
}

/// [`Modes::translation_shares`]: per mode `Σ_cp m_cp u_d²` along each
/// global axis `d` over their sum, with `lumped` the control points'
/// lumped translational mass (zeros for a mode without translation).
fn translation_shares(shapes: &Mat<f64>, lumped: &[f64]) -> Vec<[f64; 3]> {
    (0..shapes.ncols())
        .map(|k| {
            let mut energy = [0.0; 3];
            for (cp, m) in lumped.iter().enumerate() {
                let b = DOFS_PER_CONTROL_POINT * cp;
                for (d, e) in energy.iter_mut().enumerate() {
                    *e += m * shapes[(b + d, k)] * shapes[(b + d, k)];
                }
            }
            let total: f64 = energy.iter().sum();
            if total > 0.0 {
                energy.map(|e| e / total)
            } else {
                [0.0; 3]
            }
        })
        .collect()
}

/// Rigid (`ω² < 1e-12 ω²_max`), bending (the lumped-mass-weighted normal
/// motion dominates) or membrane, with `lumped` the row-sum translational
/// mass of every control point.
fn classify_lumped(omega2: &[f64], shapes: &Mat<f64>, lumped: &[f64], frames: &[Frame]) -> Vec<ModeKind> {
    let max = omega2.iter().copied().fold(0.0f64, f64::max);
    let cps = frames.len();
    (0..omega2.len())
        .map(|k| {
            if omega2[k] < 1e-12 * max {
                return ModeKind::Rigid;
            }
            let (mut normal, mut tangential) = (0.0, 0.0);
            for cp in 0..cps {
                let b = DOFS_PER_CONTROL_POINT * cp;
                let u: Vec3 = [shapes[(b, k)], shapes[(b + 1, k)], shapes[(b + 2, k)]];
                let un = dot(u, frames[cp].v3);
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Two control points of lumped masses 1 and 3: a shape moving the first
    /// by 1 along x and the second by 2 along z holds energies 1 and 12; a
    /// shape of rotations alone holds no translational energy.
    #[test]
    fn translation_shares_weigh_each_axis_by_the_lumped_mass() {
        let mut shapes = Mat::<f64>::zeros(2 * DOFS_PER_CONTROL_POINT, 2);
        shapes[(0, 0)] = 1.0;
        shapes[(DOFS_PER_CONTROL_POINT + 2, 0)] = 2.0;
        shapes[(3, 1)] = 5.0;
        let shares = translation_shares(&shapes, &[1.0, 3.0]);
        assert_eq!(shares[0], [1.0 / 13.0, 0.0, 12.0 / 13.0]);
        assert_eq!(shares[1], [0.0; 3]);
    }
}
