//! The quadrature of eq. (16)–(17) and the assembly of a shell's stiffness
//! and mass into dense, sparse or offset targets.

use super::{Shell, ShellError, ShellPoint, DOFS_PER_CONTROL_POINT};
use crate::geometry::quadrature::GaussLegendre;
use crate::geometry::vec3::{axpy, cross, det_inverse, dot, mat_vec, normalize, scale, Vec3};
use crate::model::material::OrthotropicMaterial;
use crate::model::sparse::{Pattern, SparseAccumulator, SparseError, SparseSymmetric};
use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, Par};
use std::sync::Arc;

/// Unconstrained stiffness `K_f` (eq. 16) and consistent mass `M` (eq. 17).
#[derive(Debug, Clone)]
pub struct ShellMatrices {
    pub stiffness: Mat<f64>,
    pub mass: Mat<f64>,
}

/// Lamina frame at a point: rows `e1, e2, e3`, `e3` normal to the lamina and
/// `e1` the material axis (the `ξ` tangent rotated by `angle` about `e3`).
fn lamina_frame(jac: &[Vec3; 3], angle: f64) -> Option<[Vec3; 3]> {
    let e3 = normalize(cross(jac[0], jac[1]))?;
    let r1 = normalize(axpy(jac[0], -dot(jac[0], e3), e3))?;
    let r2 = cross(e3, r1);
    let (s, c) = angle.sin_cos();
    let e1 = axpy(scale(r1, c), s, r2);
    let e2 = cross(e3, e1);
    Some([e1, e2, e3])
}

/// What the quadrature of eq. (16)–(17) gives at one point: the strain rows
/// `B` (6 × n, lamina frame), `E' B`, the displacement rows `N` (3 × n) and
/// the global dof of every column.
pub(crate) struct PointRows {
    pub(crate) b: Mat<f64>,
    pub(crate) eb: Mat<f64>,
    pub(crate) n: Mat<f64>,
    pub(crate) dofs: Vec<usize>,
}

/// Gauss points per direction: `extra` more than the `p + 1` that integrate
/// eq. (16)–(17) of a flat shell exactly (a stiffness field of degree `d`
/// multiplies the integrand by a polynomial of degree `d`: `⌈d/2⌉` more).
pub(crate) struct Quadrature {
    pub(crate) extra: (usize, usize),
    /// Cuts of the ξ and η domains besides the shell's own breakpoints.
    pub(crate) cuts: (Vec<f64>, Vec<f64>),
    /// Only the ξ spans `[a, b)` (indices among the cut spans); `None`: all.
    pub(crate) xi_spans: Option<(usize, usize)>,
}

/// A step of the quadrature loop ([`integrate`]).
pub(crate) enum QuadratureStep<'a> {
    /// A Gauss point at `(ξ, η)` with volume weight `w`; `layer` is 0 or 1,
    /// the thickness Gauss point (the two layers of one `(ξ, η)` come in a row).
    Point {
        xi: f64,
        eta: f64,
        layer: usize,
        w: f64,
        rows: &'a PointRows,
    },
    /// The end of a span whose local columns map to `dofs`.
    SpanEnd { dofs: &'a [usize] },
}

/// The quadrature loop of eq. (16)–(17): every knot span of the shell (cut
/// further at `quadrature.cuts`), every Gauss point, then the span's end.
#[allow(
    clippy::too_many_lines,
    reason = "the quadrature loop of eq. (16)-(17): span, Gauss point, local frame and strain rows read as one nest"
)]
pub(crate) fn integrate(
    shell: &Shell,
    material: &OrthotropicMaterial,
    quadrature: &Quadrature,
    mut visit: impl FnMut(QuadratureStep<'_>),
) -> Result<(), ShellError> {
    let (p, q) = (shell.surface.xi().degree(), shell.surface.eta().degree());
    let (gx, ge, gt) = (
        GaussLegendre::new(p + 1 + quadrature.extra.0),
        GaussLegendre::new(q + 1 + quadrature.extra.1),
        GaussLegendre::new(2),
    );
    let nloc = DOFS_PER_CONTROL_POINT * (p + 1) * (q + 1);
    let e_local = material.local_matrix();
    let mut rows = PointRows {
        b: Mat::<f64>::zeros(6, nloc),
        eb: Mat::<f64>::zeros(6, nloc),
        n: Mat::<f64>::zeros(3, nloc),
        dofs: vec![0usize; nloc],
    };
    let mut pt = ShellPoint::new_empty();
    let cut = |own: Vec<f64>, extra: &[f64]| {
        let (a, b) = (own[0], own[own.len() - 1]);
        let mut all: Vec<f64> = own;
        all.extend(extra.iter().copied().filter(|&k| k > a && k < b));
        all.sort_by(f64::total_cmp);
        all.dedup();
        all
    };
    let bx = cut(shell.surface.xi().breakpoints(), &quadrature.cuts.0);
    let be = cut(shell.surface.eta().breakpoints(), &quadrature.cuts.1);
    for (ix, wx) in bx.windows(2).enumerate() {
        if quadrature.xi_spans.is_some_and(|(a, b)| ix < a || ix >= b) {
            continue;
        }
        for we in be.windows(2) {
            for (xi, wxi) in gx.mapped(wx[0], wx[1]) {
                for (eta, weta) in ge.mapped(we[0], we[1]) {
                    for (layer, (tau, wt)) in gt.mapped(0.0, 1.0).enumerate() {
                        shell.evaluate_into(xi, eta, tau, &mut pt);
                        let (det, jinv) = det_inverse(&pt.jacobian);
                        let frame = lamina_frame(&pt.jacobian, material.angle_rad());
                        let Some(frame) = frame.filter(|_| det > 0.0 && det.is_finite()) else {
                            return Err(ShellError::InvertedJacobian { xi, eta, tau });
                        };
                        for k in 0..pt.count {
                            for (d, s) in shell.dof_shapes(&pt, k).into_iter().enumerate() {
                                let col = DOFS_PER_CONTROL_POINT * k + d;
                                rows.dofs[col] = s.dof;
                                // G = g ⊗ ∇ψ; in the lamina frame G' = (R g) ⊗ (R ∇ψ).
                                let grad = mat_vec(&jinv, s.dpsi);
                                let a = mat_vec(&frame, s.g);
                                let c = mat_vec(&frame, grad);
                                let strain = [
                                    a[0] * c[0],
                                    a[1] * c[1],
                                    a[2] * c[2],
                                    a[0] * c[1] + a[1] * c[0],
                                    a[1] * c[2] + a[2] * c[1],
                                    a[0] * c[2] + a[2] * c[0],
                                ];
                                for r in 0..6 {
                                    rows.b[(r, col)] = strain[r];
                                    rows.eb[(r, col)] = (0..6).map(|s| e_local[r][s] * strain[s]).sum();
                                }
                                let nc = scale(s.g, s.psi);
                                for r in 0..3 {
                                    rows.n[(r, col)] = nc[r];
                                }
                            }
                        }
                        visit(QuadratureStep::Point {
                            xi,
                            eta,
                            layer,
                            w: wxi * weta * wt * det,
                            rows: &rows,
                        });
                    }
                }
            }
            visit(QuadratureStep::SpanEnd { dofs: &rows.dofs });
        }
    }
    Ok(())
}

/// `target[dofs, dofs] += local`.
pub(crate) fn scatter(target: &mut Mat<f64>, local: &Mat<f64>, dofs: &[usize]) {
    for (r, &dr) in dofs.iter().enumerate() {
        for (c, &dc) in dofs.iter().enumerate() {
            target[(dr, dc)] += local[(r, c)];
        }
    }
}

/// Where assembled element matrices go: a dense matrix, or a sparse one on
/// the control net's pattern ([`crate::model::sparse`]).
pub trait Assembly {
    /// `self[dofs, dofs] += local`.
    fn add_local(&mut self, local: &Mat<f64>, dofs: &[usize]) -> Result<(), SparseError>;
}

impl<A: Assembly + ?Sized> Assembly for &mut A {
    fn add_local(&mut self, local: &Mat<f64>, dofs: &[usize]) -> Result<(), SparseError> {
        (**self).add_local(local, dofs)
    }
}

impl Assembly for Mat<f64> {
    fn add_local(&mut self, local: &Mat<f64>, dofs: &[usize]) -> Result<(), SparseError> {
        scatter(self, local, dofs);
        Ok(())
    }
}

impl Assembly for SparseSymmetric {
    fn add_local(&mut self, local: &Mat<f64>, dofs: &[usize]) -> Result<(), SparseError> {
        SparseSymmetric::add_local(self, local, dofs)
    }
}

impl Assembly for SparseAccumulator {
    fn add_local(&mut self, local: &Mat<f64>, dofs: &[usize]) -> Result<(), SparseError> {
        SparseAccumulator::add_local(self, local, dofs)
    }
}

/// An assembly target whose element dofs are shifted by `offset`: a
/// patch's own numbering placed in a model of several patches.
#[derive(Debug, Clone)]
pub struct Offset<A> {
    pub inner: A,
    pub offset: usize,
}

impl<A> Offset<A> {
    pub fn new(inner: A, offset: usize) -> Self {
        Self { inner, offset }
    }
}

impl<A: Assembly> Assembly for Offset<A> {
    fn add_local(&mut self, local: &Mat<f64>, dofs: &[usize]) -> Result<(), SparseError> {
        if self.offset == 0 {
            return self.inner.add_local(local, dofs);
        }
        let shifted: Vec<usize> = dofs.iter().map(|d| d + self.offset).collect();
        self.inner.add_local(local, &shifted)
    }
}

/// Assembles eq. (16) and eq. (17) over every knot span.
pub fn assemble(shell: &Shell, material: &OrthotropicMaterial) -> Result<ShellMatrices, ShellError> {
    let ndof = shell.dof_count();
    let mut stiffness = Mat::<f64>::zeros(ndof, ndof);
    let mut mass = Mat::<f64>::zeros(ndof, ndof);
    assemble_into(shell, material, &mut stiffness, &mut mass)?;
    Ok(ShellMatrices { stiffness, mass })
}

/// Eq. (16) and (17) on the shell's sparse pattern: memory and time linear
/// in the number of control points.
pub fn assemble_sparse(
    shell: &Shell,
    material: &OrthotropicMaterial,
    pattern: &Arc<Pattern>,
) -> Result<(SparseSymmetric, SparseSymmetric), ShellError> {
    assemble_sparse_patches(&[(shell, material, 0)], pattern)
}

/// [`assemble_sparse`] of several patches, each `(shell, material, offset)`
/// with its dofs from `offset` in `pattern`, into one `K` and one `M`.
pub fn assemble_sparse_patches(
    patches: &[(&Shell, &OrthotropicMaterial, usize)],
    pattern: &Arc<Pattern>,
) -> Result<(SparseSymmetric, SparseSymmetric), ShellError> {
    // Two threads, each on half of every patch's ξ spans into matrices of
    // its own, added at the end: a fixed split, so the sums do not depend
    // on the machine.
    let part = |second_half: bool| -> Result<(SparseSymmetric, SparseSymmetric), ShellError> {
        let mut stiffness = SparseSymmetric::zeros(Arc::clone(pattern));
        let mut mass = SparseSymmetric::zeros(Arc::clone(pattern));
        for &(shell, material, offset) in patches {
            let spans = shell.surface.xi().breakpoints().len() - 1;
            let half = spans / 2;
            let range = if second_half { (half, spans) } else { (0, half) };
            let (mut k, mut m) = (Offset::new(&mut stiffness, offset), Offset::new(&mut mass, offset));
            assemble_spans(shell, material, &mut k, &mut m, Some(range))?;
        }
        Ok((stiffness, mass))
    };
    let (first, second) = std::thread::scope(|scope| {
        let other = scope.spawn(|| part(true));
        let first = part(false);
        (first, other.join().expect("assembly thread"))
    });
    let ((mut stiffness, mut mass), (k2, m2)) = (first?, second?);
    stiffness.add_scaled(&k2, 1.0);
    mass.add_scaled(&m2, 1.0);
    Ok((stiffness, mass))
}

/// Eq. (16) into `stiffness` and eq. (17) into `mass`, span by span.
pub fn assemble_into<A: Assembly>(
    shell: &Shell,
    material: &OrthotropicMaterial,
    stiffness: &mut A,
    mass: &mut A,
) -> Result<(), ShellError> {
    assemble_spans(shell, material, stiffness, mass, None)
}

/// [`assemble_into`] over the ξ spans `[a, b)` only (`None`: all).
fn assemble_spans<A: Assembly>(
    shell: &Shell,
    material: &OrthotropicMaterial,
    stiffness: &mut A,
    mass: &mut A,
    xi_spans: Option<(usize, usize)>,
) -> Result<(), ShellError> {
    let (p, q) = (shell.surface.xi().degree(), shell.surface.eta().degree());
    let nloc = DOFS_PER_CONTROL_POINT * (p + 1) * (q + 1);
    let rho = material.density();
    let mut k_loc = Mat::<f64>::zeros(nloc, nloc);
    let mut m_loc = Mat::<f64>::zeros(nloc, nloc);
    let exact = Quadrature {
        extra: (0, 0),
        cuts: (Vec::new(), Vec::new()),
        xi_spans,
    };
    let mut outcome = Ok(());
    integrate(shell, material, &exact, |step| match step {
        QuadratureStep::Point { w, rows, .. } => {
            matmul(
                k_loc.as_mut(),
                Accum::Add,
                rows.b.transpose(),
                rows.eb.as_ref(),
                w,
                Par::Seq,
            );
            matmul(
                m_loc.as_mut(),
                Accum::Add,
                rows.n.transpose(),
                rows.n.as_ref(),
                rho * w,
                Par::Seq,
            );
        }
        QuadratureStep::SpanEnd { dofs } => {
            if outcome.is_ok() {
                outcome = stiffness
                    .add_local(&k_loc, dofs)
                    .and_then(|()| mass.add_local(&m_loc, dofs));
            }
            k_loc.fill(0.0);
            m_loc.fill(0.0);
        }
    })?;
    outcome.map_err(ShellError::Sparse)
}
