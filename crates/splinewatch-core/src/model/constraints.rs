//! Rigid edge supports, imposed by eliminating dofs: `δ = T q`, where the
//! columns of `T` span the displacements the supports allow. Reduced matrices
//! are `Tᵀ K T` and `Tᵀ M T`; mode shapes are expanded with `T`.
//!
//! At a control point on a supported edge (clamped knot vectors make the
//! edge curve depend on its edge control points only):
//! - `simply_supported` ("hard" Navier support): the translation along the
//!   director `v3` and the rotation whose axis is normal to the edge are
//!   zero. On a `ξ` edge that is `α` (axis `v1`), on an `η` edge `β` (axis `v2`).
//! - `shear_diaphragm`: simply supported plus zero translation along the
//!   edge tangent (`v2` on a `ξ` edge, `v1` on an `η` edge); the classical
//!   support of shell-theory closed forms.
//! - `clamped`: all five dofs are zero.

use crate::geometry::vec3::{axpy, dot, normalize, Vec3};
use crate::model::shell::{Shell, DOFS_PER_CONTROL_POINT};
use crate::model::sparse::{Pattern, SparseError, SparseSymmetric};
use faer::Mat;
use std::sync::Arc;

/// An edge of the parametric square.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Edge {
    /// `ξ = 0`
    Xi0,
    /// `ξ = 1` (end of the `ξ` domain)
    Xi1,
    /// `η = 0`
    Eta0,
    /// `η = 1`
    Eta1,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SupportKind {
    SimplySupported,
    ShearDiaphragm,
    Clamped,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EdgeConstraint {
    pub edge: Edge,
    pub kind: SupportKind,
    /// The patch whose edge is supported ([`crate::model::patch`]).
    pub patch: usize,
}

/// The sparse map `δ = T q` from free coordinates to generalised dofs.
#[derive(Debug, Clone, PartialEq)]
pub struct DofReduction {
    full: usize,
    /// Column `c` of `T` as `(dof, value)` pairs.
    columns: Vec<Vec<(usize, f64)>>,
}

impl Edge {
    /// The control points of the edge, by their index in `shell`'s net
    /// (clamped knots: the edge curve depends on these only).
    pub fn control_points(self, shell: &Shell) -> Vec<usize> {
        let (m, n) = shell.surface().net_size();
        match self {
            Edge::Xi0 => (0..n).collect(),
            Edge::Xi1 => (0..n).map(|j| (m - 1) * n + j).collect(),
            Edge::Eta0 => (0..m).map(|i| i * n).collect(),
            Edge::Eta1 => (0..m).map(|i| i * n + n - 1).collect(),
        }
    }
}

impl EdgeConstraint {
    /// The control points of the supported edge ([`Edge::control_points`]).
    pub fn control_points(&self, shell: &Shell) -> Vec<usize> {
        self.edge.control_points(shell)
    }
}

impl DofReduction {
    pub fn new(shell: &Shell, constraints: &[EdgeConstraint]) -> Self {
        let cps = shell.control_point_count();
        let mut fixed_translations: Vec<Vec<Vec3>> = vec![Vec::new(); cps];
        let mut fixed_rotations = vec![[false; 2]; cps];
        for c in constraints {
            let on_edge = c.control_points(shell);
            let xi_edge = matches!(c.edge, Edge::Xi0 | Edge::Xi1);
            for cp in on_edge {
                let f = shell.frames()[cp];
                match c.kind {
                    SupportKind::Clamped => {
                        fixed_translations[cp].extend([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]);
                        fixed_rotations[cp] = [true, true];
                    }
                    SupportKind::SimplySupported | SupportKind::ShearDiaphragm => {
                        fixed_translations[cp].push(f.v3);
                        fixed_rotations[cp][if xi_edge { 0 } else { 1 }] = true;
                        if c.kind == SupportKind::ShearDiaphragm {
                            fixed_translations[cp].push(if xi_edge { f.v2 } else { f.v1 });
                        }
                    }
                }
            }
        }
        let mut columns = Vec::with_capacity(shell.dof_count());
        for cp in 0..cps {
            let base = DOFS_PER_CONTROL_POINT * cp;
            for dir in free_directions(&fixed_translations[cp]) {
                columns.push((0..3).filter(|&d| dir[d] != 0.0).map(|d| (base + d, dir[d])).collect());
            }
            for r in 0..2 {
                if !fixed_rotations[cp][r] {
                    columns.push(vec![(base + 3 + r, 1.0)]);
                }
            }
        }
        Self {
            full: shell.dof_count(),
            columns,
        }
    }

    /// The reductions of several patches side by side: `T = diag(T_k)`.
    pub fn block_diagonal(parts: Vec<DofReduction>) -> Self {
        let mut full = 0;
        let mut columns = Vec::new();
        for part in parts {
            columns.extend(
                part.columns
                    .into_iter()
                    .map(|c| c.into_iter().map(|(d, w)| (d + full, w)).collect::<Vec<_>>()),
            );
            full += part.full;
        }
        Self { full, columns }
    }

    /// `T = I` without the columns of the `held` dofs (ascending): each
    /// held dof is zero, the others free.
    pub fn holding(full: usize, held: &[usize]) -> Self {
        Self {
            full,
            columns: (0..full)
                .filter(|d| held.binary_search(d).is_err())
                .map(|d| vec![(d, 1.0)])
                .collect(),
        }
    }

    /// The same `T` with the `slaves` dofs following `master` rigidly: each
    /// slave's own column (which must be the identity's: a free dof) is
    /// removed and `extra[c]`, the slaves' motion under a unit component `c`
    /// of the master, joins the master's column `c` (after its own entry).
    /// On conflict, the first slave dof that is held or already tied.
    pub fn tie(mut self, master: [usize; 6], extra: [Vec<(usize, f64)>; 6], slaves: &[usize]) -> Result<Self, usize> {
        let mut column_of = vec![None; self.full];
        for (c, column) in self.columns.iter().enumerate() {
            if let [(d, w)] = column.as_slice() {
                if *w == 1.0 {
                    column_of[*d] = Some(c);
                }
            }
        }
        let mut drop = vec![false; self.columns.len()];
        for &s in slaves {
            match column_of[s] {
                Some(c) if !drop[c] => drop[c] = true,
                _ => return Err(s),
            }
        }
        for (m, extra) in master.iter().zip(extra) {
            let c = column_of[*m].ok_or(*m)?;
            self.columns[c].extend(extra);
        }
        let mut keep = drop.iter().map(|d| !d);
        self.columns.retain(|_| keep.next().expect("one flag per column"));
        Ok(self)
    }

    /// No constraints: `T = I`.
    pub fn identity(full: usize) -> Self {
        Self {
            full,
            columns: (0..full).map(|d| vec![(d, 1.0)]).collect(),
        }
    }

    pub fn full_count(&self) -> usize {
        self.full
    }

    pub fn free_count(&self) -> usize {
        self.columns.len()
    }

    /// The columns of `T`, sparse: `(full dof, weight)` pairs.
    pub fn columns(&self) -> &[Vec<(usize, f64)>] {
        &self.columns
    }

    /// `Tᵀ A T`.
    #[track_caller]
    pub fn reduce(&self, a: &Mat<f64>) -> Mat<f64> {
        assert_eq!((a.nrows(), a.ncols()), (self.full, self.full));
        let nf = self.free_count();
        let mut at = Mat::<f64>::zeros(self.full, nf);
        for (c, col) in self.columns.iter().enumerate() {
            for &(d, t) in col {
                for r in 0..self.full {
                    at[(r, c)] += a[(r, d)] * t;
                }
            }
        }
        let mut out = Mat::<f64>::zeros(nf, nf);
        for (r, col) in self.columns.iter().enumerate() {
            for &(d, t) in col {
                for c in 0..nf {
                    out[(r, c)] += t * at[(d, c)];
                }
            }
        }
        out
    }

    /// `Tᵀ A T` of a sparse matrix on the pattern of the free coordinates
    /// ([`DofReduction::reduced_pattern`]): each column of `T` lies on one
    /// control point, so that pattern is the control net's with fewer dofs
    /// per point.
    pub fn reduce_sparse(&self, a: &SparseSymmetric, reduced: &Arc<Pattern>) -> Result<SparseSymmetric, SparseError> {
        a.congruence(&self.columns, self.full, reduced)
    }

    /// The pattern of the free coordinates: `full`'s (the generalised
    /// dofs', node by node) with each node's free count.
    pub fn reduced_pattern(&self, full: &Pattern) -> Pattern {
        let mut dofs = vec![0usize; full.counts().len()];
        for column in &self.columns {
            dofs[full.node_of(column[0].0)] += 1;
        }
        full.with_counts(&dofs)
    }

    /// `Tᵀ v` for full-length column vectors `v`.
    #[track_caller]
    pub fn reduce_vector(&self, v: &Mat<f64>) -> Mat<f64> {
        assert_eq!(v.nrows(), self.full);
        Mat::from_fn(self.free_count(), v.ncols(), |r, k| {
            self.columns[r].iter().map(|&(d, t)| t * v[(d, k)]).sum()
        })
    }

    /// `T Q` for a matrix of reduced vectors stored by columns.
    #[track_caller]
    pub fn expand(&self, q: &Mat<f64>) -> Mat<f64> {
        assert_eq!(q.nrows(), self.free_count());
        let mut out = Mat::<f64>::zeros(self.full, q.ncols());
        // Vector by vector (each a contiguous column); every entry takes the
        // same terms in the same order as row by row.
        for k in 0..q.ncols() {
            let (reduced, full) = (q.col(k), out.col_as_slice_mut(k));
            for (r, col) in self.columns.iter().enumerate() {
                let value = reduced[r];
                for &(d, t) in col {
                    full[d] += t * value;
                }
            }
        }
        out
    }
}

/// Orthonormal basis of the translations orthogonal to every vector in `fixed`.
fn free_directions(fixed: &[Vec3]) -> Vec<Vec3> {
    let mut basis: Vec<Vec3> = Vec::new();
    for &f in fixed {
        let mut v = f;
        for b in &basis {
            v = axpy(v, -dot(v, *b), *b);
        }
        if let Some(u) = normalize(v).filter(|_| crate::geometry::vec3::norm(v) > 1e-8) {
            basis.push(u);
        }
    }
    let rank = basis.len();
    let mut free = Vec::new();
    for e in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]] {
        if free.len() + rank == 3 {
            break;
        }
        let mut v: Vec3 = e;
        for b in basis.iter().chain(free.iter()) {
            v = axpy(v, -dot(v, *b), *b);
        }
        // Snap round-off so axis-aligned supports keep axis-aligned columns.
        for x in &mut v {
            if x.abs() < 1e-15 {
                *x = 0.0;
            }
        }
        if crate::geometry::vec3::norm(v) > 1e-6 {
            free.push(normalize(v).expect("non-zero by the check above"));
        }
    }
    free
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn free_directions_complement_the_fixed_ones() {
        assert_eq!(
            free_directions(&[[0.0, 0.0, 1.0]]),
            vec![[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
        );
        assert!(free_directions(&[[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, 1.0]]).is_empty());
        let tilted = normalize([0.0, 1.0, 1.0]).unwrap();
        let free = free_directions(&[tilted]);
        assert_eq!(free.len(), 2);
        for f in &free {
            assert!(dot(*f, tilted).abs() < 1e-15);
        }
    }

    #[test]
    fn simply_supported_plate_counts() {
        let shell = Shell::rectangular_plate(2.0, 1.0, 0.01, [2, 2], [4, 3]).unwrap();
        let all = [Edge::Xi0, Edge::Xi1, Edge::Eta0, Edge::Eta1].map(|edge| EdgeConstraint {
            edge,
            kind: SupportKind::SimplySupported,
            patch: 0,
        });
        let r = DofReduction::new(&shell, &all);
        // 12 control points, 10 on the boundary lose w; xi edges (6 cps) lose α,
        // eta edges (8 cps) lose β.
        assert_eq!(r.free_count(), 60 - 10 - 6 - 8);
        let clamped = DofReduction::new(
            &shell,
            &[EdgeConstraint {
                edge: Edge::Xi0,
                kind: SupportKind::Clamped,
                patch: 0,
            }],
        );
        assert_eq!(clamped.free_count(), 60 - 15);
    }
}
