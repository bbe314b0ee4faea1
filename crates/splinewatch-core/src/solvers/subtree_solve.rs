//! Triangular solves with a supernodal Cholesky factor, two subtrees of its
//! elimination tree at once.
//!
//! A supernode's forward step (`L x = b`) reads its own rows and subtracts
//! from the rows of its pattern, all of them in its ancestors; the backward
//! step (`Lᵀ x = b`) reads its ancestors' rows and writes its own. So two
//! disjoint subtrees of the supernodal elimination tree are independent
//! once (forward) their common ancestors' rows are kept apart, or (backward)
//! the ancestors are solved first: the classic subtree-to-thread mapping of
//! parallel sparse triangular solves (George, Heath & Liu 1986; Gupta &
//! Kumar 1995). A nested-dissection ordering makes the two halves of the
//! deck two subtrees of about the same work under its top separator.
//!
//! The solves are memory bound (a single right-hand side reads the whole
//! factor, ~100 MB at 20 000 dofs, for ~2 flops per entry), and this
//! machine's second core brings its own bandwidth: two solves at once take
//! about as long as one. The split is fixed by the structure alone, so the
//! results are the same at every run; they differ from faer's sequential
//! solve in the last bits only (the two subtrees' contributions to their
//! common ancestors are summed apart, then added).

use faer::linalg::matmul::matmul_with_conj;
use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place_with_conj, solve_upper_triangular_in_place_with_conj,
};
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::linalg::cholesky::supernodal::{SupernodalLltRef, SymbolicSupernodalCholesky};
use faer::{Accum, Conj, Mat, MatMut, Par};

/// The supernodes of a factor split into two independent groups of
/// subtrees and their common ancestors.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SubtreeSplit {
    /// Two groups of whole subtrees, no supernode of one an ancestor or a
    /// descendant of a supernode of the other; ascending.
    groups: [Vec<usize>; 2],
    /// Every other supernode (ancestors of the groups' roots), ascending.
    top: Vec<usize>,
    /// The dimension of the factor.
    dim: usize,
    /// Its supernodes.
    supernodes: usize,
}

/// Descents tried from the roots towards a balanced split.
const MAX_DESCENTS: usize = 64;

/// Factors of fewer entries are solved on one thread. Two million entries
/// (16 MB) outgrow the caches, and a solve reads them from memory (about
/// 1 ms): there a second core's bandwidth pays. A smaller factor stays in
/// cache, and a thread's start and hand-off cost more than they save:
/// measured on the Painter Street model (251 775 entries, split at the
/// earlier 200 000), an event's update took 2.99 s with the split and 2.27 s
/// on one thread (2026-11-27), and on grid factors of 14 000–1 000 000
/// entries the split saved at most 8 %.
const MIN_SPLIT_ENTRIES: usize = 2_000_000;

impl SubtreeSplit {
    /// The split of `symbolic`'s supernodal elimination tree that minimises
    /// the work on the longer path (the common ancestors, then the larger
    /// group), measured in factor entries; none (one thread) for a factor
    /// of fewer than two million entries (`MIN_SPLIT_ENTRIES`).
    pub fn new(symbolic: &SymbolicSupernodalCholesky<usize>) -> Self {
        Self::with_threshold(symbolic, MIN_SPLIT_ENTRIES)
    }

    /// [`Self::new`] with the smallest factor (in entries) worth splitting.
    fn with_threshold(symbolic: &SymbolicSupernodalCholesky<usize>, min_entries: usize) -> Self {
        let n_super = symbolic.n_supernodes();
        let begin = symbolic.supernode_begin();
        let end = symbolic.supernode_end();
        let dim = symbolic.nrows();
        // The supernode holding each column.
        let mut owner = vec![0; dim];
        for s in 0..n_super {
            owner[begin[s]..end[s]].fill(s);
        }
        let mut parent = vec![None; n_super];
        let mut work = vec![0usize; n_super];
        let mut children = vec![Vec::new(); n_super];
        for s in 0..n_super {
            let pattern = symbolic.supernode(s).pattern();
            let size = end[s] - begin[s];
            work[s] = size * (size + pattern.len());
            // The first row of the pattern belongs to the parent (the
            // supernodal elimination tree).
            if let Some(&first) = pattern.iter().min() {
                parent[s] = Some(owner[first]);
                children[owner[first]].push(s);
            }
        }
        // Subtree work; a parent has a larger index than its children.
        let mut subtree = work.clone();
        for s in 0..n_super {
            if let Some(p) = parent[s] {
                subtree[p] += subtree[s];
            }
        }
        if work.iter().sum::<usize>() < min_entries {
            return Self {
                groups: [Vec::new(), Vec::new()],
                top: (0..n_super).collect(),
                dim,
                supernodes: n_super,
            };
        }
        let mut roots: Vec<usize> = (0..n_super).filter(|&s| parent[s].is_none()).collect();
        let mut top_work = 0;
        let mut top = Vec::new();
        let mut best: Option<(usize, Vec<usize>, [Vec<usize>; 2])> = None;
        for _ in 0..MAX_DESCENTS {
            let (span, bins) = longest_processing_time(&roots, &subtree);
            let makespan = top_work + span;
            if best.as_ref().is_none_or(|(m, _, _)| makespan < *m) {
                best = Some((makespan, top.clone(), bins));
            }
            // Descend into the heaviest subtree: its root becomes an
            // ancestor solved alone, its children candidates.
            let Some(heaviest) = roots
                .iter()
                .copied()
                .filter(|&r| !children[r].is_empty())
                .max_by_key(|&r| subtree[r])
            else {
                break;
            };
            roots.retain(|&r| r != heaviest);
            roots.extend_from_slice(&children[heaviest]);
            top.push(heaviest);
            top_work += work[heaviest];
        }
        let (_, mut top, bins) = best.expect("at least one split is tried");
        top.sort_unstable();
        let groups = bins.map(|roots| {
            let mut members = Vec::new();
            let mut stack = roots;
            while let Some(s) = stack.pop() {
                members.push(s);
                stack.extend_from_slice(&children[s]);
            }
            members.sort_unstable();
            members
        });
        Self {
            groups,
            top,
            dim,
            supernodes: n_super,
        }
    }

    /// Solves `L x = rhs` in place.
    pub fn l_solve(&self, llt: SupernodalLltRef<'_, usize, f64>, mut rhs: MatMut<'_, f64>) {
        self.check(llt, &rhs);
        if self.groups.iter().any(Vec::is_empty) {
            forward(llt, 0..self.supernodes, rhs);
            return;
        }
        let begin = llt.symbolic().supernode_begin();
        let end = llt.symbolic().supernode_end();
        // The second group starts its ancestors' rows from zero: it
        // gathers only its own contributions there.
        let mut second = rhs.to_owned();
        for &s in &self.top {
            second.subrows_mut(begin[s], end[s] - begin[s]).fill(0.0);
        }
        self.on_both_groups(llt, rhs.rb_mut(), &mut second, |group, x| {
            forward(llt, group.iter().copied(), x);
        });
        for &s in &self.top {
            let rows = end[s] - begin[s];
            let mut mine = rhs.rb_mut().subrows_mut(begin[s], rows);
            mine += second.subrows(begin[s], rows);
        }
        forward(llt, self.top.iter().copied(), rhs);
    }

    /// Solves `Lᵀ x = rhs` in place.
    pub fn l_transpose_solve(&self, llt: SupernodalLltRef<'_, usize, f64>, mut rhs: MatMut<'_, f64>) {
        self.check(llt, &rhs);
        if self.groups.iter().any(Vec::is_empty) {
            backward(llt, (0..self.supernodes).rev(), rhs);
            return;
        }
        backward(llt, self.top.iter().rev().copied(), rhs.rb_mut());
        let mut second = rhs.to_owned();
        self.on_both_groups(llt, rhs, &mut second, |group, x| {
            backward(llt, group.iter().rev().copied(), x);
        });
    }

    /// `solve` on the first group in `rhs` and, on a second thread, on the
    /// second group in `second`; then the second group's rows of `rhs` taken
    /// from `second` (the first group never writes them).
    fn on_both_groups(
        &self,
        llt: SupernodalLltRef<'_, usize, f64>,
        mut rhs: MatMut<'_, f64>,
        second: &mut Mat<f64>,
        solve: impl Fn(&[usize], MatMut<'_, f64>) + Sync,
    ) {
        std::thread::scope(|scope| {
            let other = scope.spawn(|| solve(&self.groups[1], second.as_mut()));
            solve(&self.groups[0], rhs.rb_mut());
            other.join().unwrap_or_else(|e| std::panic::resume_unwind(e));
        });
        let begin = llt.symbolic().supernode_begin();
        let end = llt.symbolic().supernode_end();
        for &s in &self.groups[1] {
            let rows = end[s] - begin[s];
            rhs.rb_mut()
                .subrows_mut(begin[s], rows)
                .copy_from(second.subrows(begin[s], rows));
        }
    }
}

impl SubtreeSplit {
    /// The factor is the one the split was made for, the right-hand side
    /// of its size.
    #[track_caller]
    fn check(&self, llt: SupernodalLltRef<'_, usize, f64>, rhs: &MatMut<'_, f64>) {
        assert_eq!(
            (llt.symbolic().nrows(), llt.symbolic().n_supernodes()),
            (self.dim, self.supernodes),
            "a factor of another structure"
        );
        assert_eq!(rhs.nrows(), self.dim, "right-hand side of the wrong size");
    }
}

/// Roots into two bins, heaviest first into the lighter bin (Graham's LPT
/// rule); the heavier bin's work and the bins.
fn longest_processing_time(roots: &[usize], subtree: &[usize]) -> (usize, [Vec<usize>; 2]) {
    let mut order = roots.to_vec();
    order.sort_by_key(|&r| (std::cmp::Reverse(subtree[r]), r));
    let mut bins: [Vec<usize>; 2] = [Vec::new(), Vec::new()];
    let mut load = [0usize; 2];
    for r in order {
        let lighter = usize::from(load[1] < load[0]);
        bins[lighter].push(r);
        load[lighter] += subtree[r];
    }
    (load[0].max(load[1]), bins)
}

/// The forward steps of `supernodes` (in an order children first), as
/// faer's `l_solve_with_conj`.
fn forward(
    llt: SupernodalLltRef<'_, usize, f64>,
    supernodes: impl Iterator<Item = usize> + Clone,
    mut x: MatMut<'_, f64>,
) {
    let k = x.ncols();
    let mut buffer = Mat::<f64>::zeros(longest_pattern(llt, supernodes.clone()), k);
    for s in supernodes {
        let node = llt.supernode(s);
        let matrix = node.val();
        let size = matrix.ncols();
        let (diagonal, below) = matrix.split_at_row(size);
        let mut top = x.rb_mut().subrows_mut(node.start(), size);
        solve_lower_triangular_in_place_with_conj(diagonal, Conj::No, top.rb_mut(), Par::Seq);
        let mut update = buffer.as_mut().subrows_mut(0, node.pattern().len());
        matmul_with_conj(
            update.rb_mut(),
            Accum::Replace,
            below,
            Conj::No,
            top.rb(),
            Conj::No,
            1.0,
            Par::Seq,
        );
        for j in 0..k {
            for (idx, &i) in node.pattern().iter().enumerate() {
                x[(i, j)] -= update[(idx, j)];
            }
        }
    }
}

/// The backward steps of `supernodes` (in an order parents first), as
/// faer's `l_transpose_solve_with_conj`.
fn backward(
    llt: SupernodalLltRef<'_, usize, f64>,
    supernodes: impl Iterator<Item = usize> + Clone,
    mut x: MatMut<'_, f64>,
) {
    let k = x.ncols();
    let mut buffer = Mat::<f64>::zeros(longest_pattern(llt, supernodes.clone()), k);
    for s in supernodes {
        let node = llt.supernode(s);
        let matrix = node.val();
        let size = matrix.ncols();
        let (diagonal, below) = matrix.split_at_row(size);
        let mut gathered = buffer.as_mut().subrows_mut(0, node.pattern().len());
        for j in 0..k {
            for (idx, &i) in node.pattern().iter().enumerate() {
                gathered[(idx, j)] = x[(i, j)];
            }
        }
        let mut top = x.rb_mut().subrows_mut(node.start(), size);
        matmul_with_conj(
            top.rb_mut(),
            Accum::Add,
            below.transpose(),
            Conj::No,
            gathered.rb(),
            Conj::No,
            -1.0,
            Par::Seq,
        );
        solve_upper_triangular_in_place_with_conj(diagonal.transpose(), Conj::No, top.rb_mut(), Par::Seq);
    }
}

/// The longest off-diagonal pattern among `supernodes`.
fn longest_pattern(llt: SupernodalLltRef<'_, usize, f64>, supernodes: impl Iterator<Item = usize>) -> usize {
    supernodes.map(|s| llt.supernode(s).pattern().len()).max().unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::sparse::linalg::cholesky::{
        factorize_symbolic_cholesky, CholeskySymbolicParams, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
    };
    use faer::sparse::linalg::SupernodalThreshold;
    use faer::sparse::{SparseColMat, Triplet};
    use faer::Side;

    /// The 5-point Laplacian of an `nx × ny` grid plus the identity (SPD),
    /// its supernodal symbolic factorisation (AMD order) and factor values.
    fn grid_factor(nx: usize, ny: usize) -> (SymbolicCholesky<usize>, Vec<f64>) {
        let n = nx * ny;
        let mut triplets = Vec::new();
        for i in 0..nx {
            for j in 0..ny {
                let a = i * ny + j;
                triplets.push(Triplet::new(a, a, 5.0));
                for (di, dj) in [(1, 0), (0, 1)] {
                    if i + di < nx && j + dj < ny {
                        let b = (i + di) * ny + j + dj;
                        triplets.push(Triplet::new(a, b, -1.0));
                        triplets.push(Triplet::new(b, a, -1.0));
                    }
                }
            }
        }
        let matrix = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &triplets).unwrap();
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
            ..Default::default()
        };
        let symbolic =
            factorize_symbolic_cholesky(matrix.symbolic(), Side::Lower, SymmetricOrdering::Amd, params).unwrap();
        let mut values = vec![0.0; symbolic.len_val()];
        let req = symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default());
        symbolic
            .factorize_numeric_llt(
                &mut values,
                matrix.as_ref(),
                Side::Lower,
                Default::default(),
                Par::Seq,
                MemStack::new(&mut MemBuffer::new(req)),
                Default::default(),
            )
            .unwrap();
        (symbolic, values)
    }

    fn supernodal(symbolic: &SymbolicCholesky<usize>) -> &SymbolicSupernodalCholesky<usize> {
        match symbolic.raw() {
            SymbolicCholeskyRaw::Supernodal(s) => s,
            SymbolicCholeskyRaw::Simplicial(_) => panic!("forced supernodal"),
        }
    }

    /// Every supernode is in exactly one part; a group's supernode has its
    /// parent in its own group or among the common ancestors, and the
    /// common ancestors' parents are common ancestors: the two groups never
    /// write to each other's rows.
    #[test]
    fn the_groups_are_independent_subtrees() {
        let (symbolic, _) = grid_factor(40, 30);
        let tree = supernodal(&symbolic);
        let split = SubtreeSplit::with_threshold(tree, 0);
        assert!(split.groups.iter().all(|g| !g.is_empty()), "a 40 × 30 grid splits");
        let n = tree.n_supernodes();
        let mut part = vec![None; n];
        for (p, list) in [&split.groups[0], &split.groups[1], &split.top].into_iter().enumerate() {
            for &s in list {
                assert!(part[s].replace(p).is_none(), "supernode {s} twice");
            }
        }
        assert!(part.iter().all(Option::is_some));
        for s in 0..n {
            for &row in tree.supernode(s).pattern() {
                let owner = (0..n)
                    .find(|&t| (tree.supernode_begin()[t]..tree.supernode_end()[t]).contains(&row))
                    .unwrap();
                let (from, to) = (part[s].unwrap(), part[owner].unwrap());
                assert!(to == from || to == 2, "supernode {s} (part {from}) writes to part {to}");
            }
        }
    }

    /// Both solves equal faer's sequential ones to roundoff (1e-13 of the
    /// largest entry: the two groups' sums into their ancestors are formed
    /// apart), on three right-hand sides at once.
    #[test]
    fn the_split_solves_match_faers_sequential_ones() {
        let (symbolic, values) = grid_factor(40, 30);
        let tree = supernodal(&symbolic);
        let llt = SupernodalLltRef::new(tree, &values);
        let split = SubtreeSplit::with_threshold(tree, 0);
        let n = tree.nrows();
        let rhs = Mat::<f64>::from_fn(n, 3, |i, j| ((i * 31 + j * 17) % 23) as f64 - 11.0);
        let req = symbolic.solve_in_place_scratch::<f64>(3, Par::Seq);
        let mut buffer = MemBuffer::new(req);
        for transpose in [false, true] {
            let (mut ours, mut theirs) = (rhs.clone(), rhs.clone());
            if transpose {
                split.l_transpose_solve(llt, ours.as_mut());
                llt.l_transpose_solve_with_conj(Conj::No, theirs.as_mut(), Par::Seq, MemStack::new(&mut buffer));
            } else {
                split.l_solve(llt, ours.as_mut());
                llt.l_solve_with_conj(Conj::No, theirs.as_mut(), Par::Seq, MemStack::new(&mut buffer));
            }
            let scale = theirs.norm_max();
            let difference = (&ours - &theirs).norm_max();
            assert!(
                difference <= 1e-13 * scale,
                "transpose {transpose}: {difference:e} of {scale:e}"
            );
        }
    }

    /// A small factor is not split (one thread), and then the solves are
    /// faer's operations in faer's order: the same bits.
    #[test]
    fn a_small_factor_is_solved_on_one_thread_as_faer_does() {
        let (symbolic, values) = grid_factor(12, 10);
        let tree = supernodal(&symbolic);
        let llt = SupernodalLltRef::new(tree, &values);
        let split = SubtreeSplit::new(tree);
        assert!(split.groups.iter().all(Vec::is_empty), "{split:?}");
        let rhs = Mat::<f64>::from_fn(tree.nrows(), 2, |i, j| ((i * 7 + j) % 5) as f64 - 2.0);
        let mut buffer = MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(2, Par::Seq));
        let (mut ours, mut theirs) = (rhs.clone(), rhs);
        split.l_solve(llt, ours.as_mut());
        split.l_transpose_solve(llt, ours.as_mut());
        llt.l_solve_with_conj(Conj::No, theirs.as_mut(), Par::Seq, MemStack::new(&mut buffer));
        llt.l_transpose_solve_with_conj(Conj::No, theirs.as_mut(), Par::Seq, MemStack::new(&mut buffer));
        assert!(ours == theirs);
    }
}
