//! The pencil's decoupled blocks: sets of free coordinates that no matrix
//! of the model couples to the others, each solved on a factor of its own
//! size and remembering its last solve.

use super::sparse_error;
use crate::linalg::bitwise_equal;
use crate::model::sparse::{Pattern, SparseSymmetric};
use crate::solvers::dense_model::ModelError;
use crate::solvers::partial_eigen::{PartialModes, PartialSettings, Responses, ShiftInvert};
use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};

/// A set of free coordinates no matrix of the model couples to the others
/// (a flat deck on normal springs: its in-plane and its out-of-plane dofs):
/// its eigenpairs are the pencil's, found on a factor of its own size (the
/// sparse counterpart of the dense `ModalSolver`'s blocks).
#[derive(Debug, Clone)]
pub(super) struct Block {
    /// Free coordinates, ascending.
    pub(super) dofs: Vec<usize>,
    pattern: Arc<Pattern>,
    /// Per entry of `pattern`, the position of the same entry in the model's.
    positions: Vec<usize>,
    eigen: ShiftInvert,
    /// The last solve's stiffness values, settings and modes.
    last: LastSolve,
}

/// A block's last partial solve: a block no changed parameter reaches (a
/// flat deck's in-plane dofs under vertical springs) has the same
/// stiffness at every evaluation of an update, so its modes are taken
/// from here instead of solved again. Exact: the inputs are compared bit
/// for bit, and the same inputs give the same modes.
#[derive(Debug, Default)]
struct LastSolve(Mutex<Option<Solved>>);

/// A block's solve: its inputs (stiffness values, settings, load columns)
/// and outputs (modes, static responses).
#[derive(Debug)]
struct Solved {
    stiffness: Vec<f64>,
    settings: PartialSettings,
    loads: Option<faer::Mat<f64>>,
    modes: PartialModes,
    responses: Option<Responses>,
}

impl Clone for LastSolve {
    fn clone(&self) -> Self {
        Self::default()
    }
}

impl Block {
    pub(super) fn restrict(&self, m: &SparseSymmetric) -> SparseSymmetric {
        m.restrict(&self.pattern, &self.positions)
    }

    /// The block's modes for the restricted `k`, `m` (the model's mass)
    /// and, for `loads`, the static responses at the solve's shift.
    pub(super) fn solve(
        &self,
        k: &SparseSymmetric,
        m: &SparseSymmetric,
        settings: &PartialSettings,
        loads: Option<&faer::Mat<f64>>,
    ) -> Result<(PartialModes, Option<Responses>), ModelError> {
        let same_loads = |a: Option<&faer::Mat<f64>>, b: Option<&faer::Mat<f64>>| match (a, b) {
            (None, None) => true,
            (Some(a), Some(b)) => {
                a.ncols() == b.ncols() && (0..a.ncols()).all(|c| bitwise_equal(a.col_as_slice(c), b.col_as_slice(c)))
            }
            _ => false,
        };
        let mut last = self.last.0.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        if let Some(solved) = last.as_ref() {
            if solved.settings == *settings
                && bitwise_equal(&solved.stiffness, k.values())
                && same_loads(solved.loads.as_ref(), loads)
            {
                return Ok((solved.modes.clone(), solved.responses.clone()));
            }
        }
        let (modes, responses) = self
            .eigen
            .solve_with_responses(k, m, settings, 0, loads)
            .map_err(ModelError::PartialEigen)?;
        *last = Some(Solved {
            stiffness: k.values().to_vec(),
            settings: *settings,
            loads: loads.cloned(),
            modes: modes.clone(),
            responses: responses.clone(),
        });
        Ok((modes, responses))
    }
}

/// The connected components of the coupling graph of the free coordinates
/// (an entry couples when any of the model's matrices is non-zero there).
pub(super) fn decoupled_blocks(pattern: &Arc<Pattern>, coupled: &[bool]) -> Result<Vec<Block>, ModelError> {
    let n = pattern.dim();
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    for c in 0..n {
        for e in pattern.col_ptr()[c]..pattern.col_ptr()[c + 1] {
            if coupled[e] {
                let (a, b) = (root(&mut parent, c), root(&mut parent, pattern.row_idx()[e]));
                parent[a.max(b)] = a.min(b);
            }
        }
    }
    let mut components: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    for d in 0..n {
        components.entry(root(&mut parent, d)).or_default().push(d);
    }
    components
        .into_values()
        .map(|dofs| {
            let (sub, positions) = pattern.restricted(&dofs).map_err(sparse_error)?;
            let sub = Arc::new(sub);
            Ok(Block {
                eigen: ShiftInvert::new(&sub).map_err(ModelError::PartialEigen)?,
                last: LastSolve::default(),
                dofs,
                pattern: sub,
                positions,
            })
        })
        .collect()
}
