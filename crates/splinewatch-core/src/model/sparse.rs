//! Symmetric sparse matrices on the control net's pattern: what `K_f`, `M`,
//! every `∂K/∂κ_j` and `∂K/∂θ_k` (eq. 16–17, 22) become at 10⁴–10⁵ dofs.
//!
//! Two control points interact only when the supports of their basis
//! functions overlap, `|i − i'| ≤ p` and `|j − j'| ≤ q` (eq. 1), so every
//! matrix of a model lives on one pattern: the control-point adjacency with
//! a dense block of dofs per pair, stored in both triangles, rows sorted per
//! column (faer's compressed sparse column format). Sharing it makes
//! `K(κ, θ) = K_f + Σ …` and the shifted `K − σM` elementwise sums of value
//! arrays, and lets one symbolic Cholesky factorisation serve every shift
//! and every parameter change ([`crate::solvers::partial_eigen`]).

use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::Mat;
use std::sync::Arc;
use thiserror::Error;

#[derive(Debug, Clone, PartialEq, Error)]
pub enum SparseError {
    #[error("entry ({row}, {col}) lies outside the control net's pattern")]
    OutsidePattern { row: usize, col: usize },
    #[error("matrix of {found} dofs on a pattern of {expected}")]
    Dimension { found: usize, expected: usize },
}

/// A symmetric sparsity pattern in compressed sparse column form (both
/// triangles), rows sorted within each column.
#[derive(Debug, Clone, PartialEq)]
pub struct Pattern {
    n: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    /// The control-point graph: per control point, the points it is coupled
    /// to (itself included), ascending.
    graph: Arc<Vec<Vec<usize>>>,
    /// The control net `(m, n)` and basis degrees `(p, q)` when the pattern
    /// is a single net's (its nested dissection follows the net).
    net: Option<((usize, usize), (usize, usize))>,
    /// The first dof of every control point (one more entry: the total).
    first: Vec<usize>,
}

impl Pattern {
    /// The pattern of a control net of `m × n` points (η fastest) with
    /// basis degrees `(p, q)`, where control point `cp` carries
    /// `dofs[cp]` consecutive dofs (numbered in control-point order).
    pub fn control_net(net: (usize, usize), degrees: (usize, usize), dofs: &[usize]) -> Self {
        let (m, n) = net;
        let (p, q) = degrees;
        assert_eq!(dofs.len(), m * n, "one dof count per control point");
        let mut graph = Vec::with_capacity(m * n);
        for i in 0..m {
            for j in 0..n {
                let mut neighbours = Vec::new();
                for i2 in i.saturating_sub(p)..=(i + p).min(m - 1) {
                    neighbours.extend((j.saturating_sub(q)..=(j + q).min(n - 1)).map(|j2| i2 * n + j2));
                }
                graph.push(neighbours);
            }
        }
        let mut pattern = Self::control_graph(Arc::new(graph), dofs);
        pattern.net = Some((net, degrees));
        pattern
    }

    /// The pattern of a control-point graph (`graph[cp]`: the points `cp`
    /// is coupled to, itself included, ascending; symmetric), where point
    /// `cp` carries `dofs[cp]` consecutive dofs: several patches and the
    /// joints between them.
    pub fn control_graph(graph: Arc<Vec<Vec<usize>>>, dofs: &[usize]) -> Self {
        assert_eq!(dofs.len(), graph.len(), "one dof count per control point");
        let mut first = Vec::with_capacity(dofs.len() + 1);
        first.push(0);
        for &d in dofs {
            first.push(first.last().copied().unwrap_or(0) + d);
        }
        let total = first[dofs.len()];
        let mut col_ptr = Vec::with_capacity(total + 1);
        col_ptr.push(0);
        let mut row_idx = Vec::new();
        for (cp, neighbours) in graph.iter().enumerate() {
            let rows: Vec<usize> = neighbours.iter().flat_map(|&o| first[o]..first[o + 1]).collect();
            for _ in 0..dofs[cp] {
                row_idx.extend_from_slice(&rows);
                col_ptr.push(row_idx.len());
            }
        }
        Self {
            n: total,
            col_ptr,
            row_idx,
            graph,
            net: None,
            first,
        }
    }

    /// The same control-point graph with `dofs[cp]` dofs per point (the
    /// free coordinates of a reduction, a decoupled block).
    pub fn with_counts(&self, dofs: &[usize]) -> Self {
        let mut pattern = Self::control_graph(Arc::clone(&self.graph), dofs);
        pattern.net = self.net;
        pattern
    }

    /// Whether the pattern is a single control net's (its dissection
    /// follows the net's geometry).
    pub fn is_single_net(&self) -> bool {
        self.net.is_some()
    }

    /// The control-point graph (per point, the points it is coupled to).
    pub fn graph(&self) -> &[Vec<usize>] {
        &self.graph
    }

    /// The control point (node) dof `dof` belongs to.
    pub fn node_of(&self, dof: usize) -> usize {
        self.first.partition_point(|&f| f <= dof) - 1
    }

    /// Dofs per control point.
    pub fn counts(&self) -> Vec<usize> {
        self.first.windows(2).map(|w| w[1] - w[0]).collect()
    }

    /// A fill-reducing order of the dofs (`order[new] = old`) by nested
    /// dissection (George 1973). On a single control net a box of control
    /// points is split across its longer side by a separator `p` (or `q`)
    /// points wide, the widest that couples the two halves, and ordered as
    /// the two halves (recursively), then the separator; a box of at most
    /// `ND_LEAF` points is ordered as it is. On a 2-D net it keeps the
    /// Cholesky factor near `O(n log n)`, where minimum degree fills more
    /// (measured on the bundled deck refined to 20 000 dofs: 2.6× fewer
    /// factor entries). Several patches: the separators are levels of
    /// the control-point graph's breadth-first level structure
    /// ([`Self::graph_dissection`]).
    pub fn nested_dissection(&self) -> Vec<usize> {
        let points = match self.net {
            Some((net, _)) => {
                let mut points = Vec::with_capacity(self.graph.len());
                self.dissect([0, net.0], [0, net.1], &mut points);
                points
            }
            None => self.graph_dissection(),
        };
        points
            .into_iter()
            .flat_map(|cp| self.first[cp]..self.first[cp + 1])
            .collect()
    }

    fn dissect(&self, rows: [usize; 2], cols: [usize; 2], out: &mut Vec<usize>) {
        let (h, w) = (rows[1] - rows[0], cols[1] - cols[0]);
        let Some(((_, n), (p, q))) = self.net else {
            unreachable!("dissect is called on a single net")
        };
        let natural = |out: &mut Vec<usize>, rows: [usize; 2], cols: [usize; 2]| {
            for i in rows[0]..rows[1] {
                out.extend((cols[0]..cols[1]).map(|j| i * n + j));
            }
        };
        if h * w <= ND_LEAF || (h <= 2 * p + 1 && w <= 2 * q + 1) {
            natural(out, rows, cols);
            return;
        }
        if h >= w && h > 2 * p + 1 {
            let mid = rows[0] + (h - p) / 2;
            self.dissect([rows[0], mid], cols, out);
            self.dissect([mid + p, rows[1]], cols, out);
            natural(out, [mid, mid + p], cols);
        } else {
            let mid = cols[0] + (w - q) / 2;
            self.dissect(rows, [cols[0], mid], out);
            self.dissect(rows, [mid + q, cols[1]], out);
            natural(out, rows, [mid, mid + q]);
        }
    }

    /// Nested dissection of the control-point graph (George & Liu 1981,
    /// §8.2): in each connected part, the breadth-first levels from a
    /// pseudo-peripheral point; the level that halves the part separates
    /// the levels before it from those after (an edge joins adjacent levels
    /// only), and is ordered after both halves, dissected in turn. Points
    /// without dofs are left out.
    pub fn graph_dissection(&self) -> Vec<usize> {
        let active: Vec<usize> = (0..self.graph.len())
            .filter(|&cp| self.first[cp + 1] > self.first[cp])
            .collect();
        let mut out = Vec::with_capacity(active.len());
        let mut marks = GraphMarks::new(self.graph.len());
        dissect_graph(&self.graph, active, &mut marks, &mut out);
        out
    }

    pub fn dim(&self) -> usize {
        self.n
    }

    /// Stored entries (both triangles).
    pub fn nnz(&self) -> usize {
        self.row_idx.len()
    }

    pub fn col_ptr(&self) -> &[usize] {
        &self.col_ptr
    }

    pub fn row_idx(&self) -> &[usize] {
        &self.row_idx
    }

    /// The position of entry `(row, col)` in the value array.
    pub fn position(&self, row: usize, col: usize) -> Option<usize> {
        let (a, b) = (self.col_ptr[col], self.col_ptr[col + 1]);
        self.row_idx[a..b].binary_search(&row).ok().map(|k| a + k)
    }

    /// The pattern of the dofs `dofs` (ascending) alone, as a control net
    /// with their counts per point, and for each of its entries the position
    /// of the same entry in `self`.
    /// Visits `(r, c, position)` for every entry `(dofs[r], dofs[c])` of an
    /// element matrix on `dofs` (an assembly's scatter). A control point's
    /// dofs are consecutive in `dofs` and in every column of the pattern, so
    /// one search finds a run of them.
    pub fn for_each_local_position(
        &self,
        dofs: &[usize],
        mut visit: impl FnMut(usize, usize, usize),
    ) -> Result<(), SparseError> {
        for (c, &dc) in dofs.iter().enumerate() {
            let column = self.col_ptr[dc]..self.col_ptr[dc + 1];
            let mut r = 0;
            while r < dofs.len() {
                let at = self.row_idx[column.clone()]
                    .binary_search(&dofs[r])
                    .map_err(|_| SparseError::OutsidePattern { row: dofs[r], col: dc })?
                    + column.start;
                // The run: rows that follow each other in `dofs` and in the column.
                let mut k = 0;
                while r + k < dofs.len() && at + k < column.end && self.row_idx[at + k] == dofs[r + k] {
                    visit(r + k, c, at + k);
                    k += 1;
                }
                r += k;
            }
        }
        Ok(())
    }

    pub fn restricted(&self, dofs: &[usize]) -> Result<(Pattern, Vec<usize>), SparseError> {
        let mut counts = vec![0usize; self.first.len() - 1];
        for &d in dofs {
            counts[self.first.partition_point(|&f| f <= d) - 1] += 1;
        }
        let sub = self.with_counts(&counts);
        let mut positions = Vec::with_capacity(sub.nnz());
        for (local, &j) in dofs.iter().enumerate() {
            for e in sub.col_ptr[local]..sub.col_ptr[local + 1] {
                let i = dofs[sub.row_idx[e]];
                positions.push(
                    self.position(i, j)
                        .ok_or(SparseError::OutsidePattern { row: i, col: j })?,
                );
            }
        }
        Ok((sub, positions))
    }

    /// faer's view of this pattern.
    pub fn symbolic(&self) -> SymbolicSparseColMatRef<'_, usize> {
        SymbolicSparseColMatRef::new_checked(self.n, self.n, &self.col_ptr, None, &self.row_idx)
    }
}

/// A symmetric matrix's non-zero entries (both triangles), for products.
#[derive(Debug, Clone, PartialEq)]
pub struct NonZeros {
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    values: Vec<f64>,
}

impl NonZeros {
    /// `y = A x` for the columns of `x`: by symmetry column `c` of `A` is
    /// its row `c`, so each `y_c` is a gather and a sum (no scattered writes).
    pub fn mul(&self, x: &Mat<f64>) -> Mat<f64> {
        let n = self.col_ptr.len() - 1;
        if x.ncols() == 1 {
            return Mat::from_fn(n, 1, |c, _| {
                let x = x.col(0);
                let (a, b) = (self.col_ptr[c], self.col_ptr[c + 1]);
                self.row_idx[a..b]
                    .iter()
                    .zip(&self.values[a..b])
                    .map(|(&r, &v)| v * x[r])
                    .sum()
            });
        }
        // Many columns: the matrix is read once, each entry against a row of
        // `x` (contiguous in its transpose); every output entry sums the
        // same products in the same order as above, from −0.0 as
        // `Iterator::sum`, so the result is the same bit for bit.
        let k = x.ncols();
        let rows = x.transpose().to_owned();
        let mut out = Mat::<f64>::zeros(k, n);
        for c in 0..n {
            let sums = out.col_as_slice_mut(c);
            sums.fill(-0.0);
            for e in self.col_ptr[c]..self.col_ptr[c + 1] {
                let v = self.values[e];
                for (sum, &x) in sums.iter_mut().zip(rows.col_as_slice(self.row_idx[e])) {
                    *sum += v * x;
                }
            }
        }
        out.transpose().to_owned()
    }

    /// `xᵀ A x`, over the columns of `A` that hold an entry only: a
    /// matrix touching few dofs (a beam member's part) costs its entries,
    /// not the model's size.
    pub fn quadratic(&self, x: &Mat<f64>) -> Mat<f64> {
        let k = x.ncols();
        let rows = x.transpose().to_owned();
        let mut out = Mat::<f64>::zeros(k, k);
        let mut y = vec![0.0; k];
        for c in 0..self.col_ptr.len() - 1 {
            let (a, b) = (self.col_ptr[c], self.col_ptr[c + 1]);
            if a == b {
                continue;
            }
            // y = (A x)_c, a row of length k.
            y.fill(0.0);
            for e in a..b {
                let v = self.values[e];
                for (sum, &x) in y.iter_mut().zip(rows.col_as_slice(self.row_idx[e])) {
                    *sum += v * x;
                }
            }
            let xc = rows.col_as_slice(c);
            for j in 0..k {
                for i in 0..k {
                    out[(i, j)] += xc[i] * y[j];
                }
            }
        }
        out
    }

    pub fn nnz(&self) -> usize {
        self.values.len()
    }
}

/// Boxes (parts) of at most this many control points are not dissected
/// further.
const ND_LEAF: usize = 16;

/// [`Pattern::graph_dissection`] of `part` into `out`.
fn dissect_graph(graph: &[Vec<usize>], part: Vec<usize>, marks: &mut GraphMarks, out: &mut Vec<usize>) {
    if part.len() <= ND_LEAF {
        out.extend(part);
        return;
    }
    for component in marks.components(graph, &part) {
        match marks.split(graph, &component) {
            Some((low, separator, high)) => {
                dissect_graph(graph, low, marks, out);
                dissect_graph(graph, high, marks, out);
                out.extend(separator);
            }
            None => out.extend(component),
        }
    }
}

/// Scratch marks of the graph dissection: which points belong to the part
/// being split, and which a search has reached (stamps, never cleared).
struct GraphMarks {
    member: Vec<u64>,
    seen: Vec<u64>,
    stamp: u64,
}

impl GraphMarks {
    fn new(points: usize) -> Self {
        Self {
            member: vec![0; points],
            seen: vec![0; points],
            stamp: 0,
        }
    }

    /// Marks `part` as the members; returns the stamp.
    fn enter(&mut self, part: &[usize]) -> u64 {
        self.stamp += 1;
        part.iter().for_each(|&v| self.member[v] = self.stamp);
        self.stamp
    }

    /// The breadth-first levels of the members from `root`.
    fn levels(&mut self, graph: &[Vec<usize>], member: u64, root: usize) -> Vec<Vec<usize>> {
        self.stamp += 1;
        let seen = self.stamp;
        self.seen[root] = seen;
        let mut levels = vec![vec![root]];
        loop {
            let mut next = Vec::new();
            for &v in levels.last().expect("one level at least") {
                for &w in &graph[v] {
                    if self.member[w] == member && self.seen[w] != seen {
                        self.seen[w] = seen;
                        next.push(w);
                    }
                }
            }
            if next.is_empty() {
                return levels;
            }
            levels.push(next);
        }
    }

    /// The connected components of `part`, each ascending.
    fn components(&mut self, graph: &[Vec<usize>], part: &[usize]) -> Vec<Vec<usize>> {
        let member = self.enter(part);
        let mut out = Vec::new();
        for &v in part {
            if self.member[v] != member {
                continue;
            }
            let mut component: Vec<usize> = self.levels(graph, member, v).concat();
            component.sort_unstable();
            // Out of the members: later searches skip it.
            self.stamp += 1;
            for &w in &component {
                self.member[w] = self.stamp;
            }
            out.push(component);
        }
        out
    }

    /// A connected part split into `(low, separator, high)` by the level
    /// halving it in the level structure from a pseudo-peripheral point
    /// (George & Liu's search: restart from a point of least degree in
    /// the last level while that deepens the structure), or `None` when
    /// the part is too small or has fewer than three levels.
    fn split(&mut self, graph: &[Vec<usize>], part: &[usize]) -> Option<(Vec<usize>, Vec<usize>, Vec<usize>)> {
        if part.len() <= ND_LEAF {
            return None;
        }
        let member = self.enter(part);
        let mut levels = self.levels(graph, member, part[0]);
        for _ in 0..PERIPHERAL_SEARCHES {
            let last = levels.last().expect("one level at least");
            let candidate = *last
                .iter()
                .min_by_key(|&&v| (graph[v].len(), v))
                .expect("non-empty level");
            let deeper = self.levels(graph, member, candidate);
            if deeper.len() <= levels.len() {
                break;
            }
            levels = deeper;
        }
        if levels.len() < 3 {
            return None;
        }
        let half = part.len() / 2;
        let mut count = 0;
        let mut at = levels.len() - 2;
        for (l, level) in levels.iter().enumerate() {
            count += level.len();
            if count >= half {
                at = l.clamp(1, levels.len() - 2);
                break;
            }
        }
        let sorted = |mut v: Vec<usize>| {
            v.sort_unstable();
            v
        };
        let low = sorted(levels[..at].concat());
        let high = sorted(levels[at + 1..].concat());
        Some((low, sorted(std::mem::take(&mut levels[at])), high))
    }
}

/// Restarts of the pseudo-peripheral point search.
const PERIPHERAL_SEARCHES: usize = 8;

/// A symmetric matrix on a shared [`Pattern`].
#[derive(Debug, Clone, PartialEq)]
pub struct SparseSymmetric {
    pattern: Arc<Pattern>,
    values: Vec<f64>,
}

impl SparseSymmetric {
    pub fn zeros(pattern: Arc<Pattern>) -> Self {
        let values = vec![0.0; pattern.nnz()];
        Self { pattern, values }
    }

    /// The matrix on a restricted pattern: `positions` (from
    /// [`Pattern::restricted`]) pick each entry's value from `self`.
    pub fn restrict(&self, pattern: &Arc<Pattern>, positions: &[usize]) -> Self {
        Self {
            pattern: Arc::clone(pattern),
            values: positions.iter().map(|&p| self.values[p]).collect(),
        }
    }

    pub fn pattern(&self) -> &Arc<Pattern> {
        &self.pattern
    }

    pub fn values(&self) -> &[f64] {
        &self.values
    }

    pub fn values_mut(&mut self) -> &mut [f64] {
        &mut self.values
    }

    pub fn dim(&self) -> usize {
        self.pattern.n
    }

    /// faer's view of this matrix.
    pub fn as_faer(&self) -> SparseColMatRef<'_, usize, f64> {
        SparseColMatRef::new(self.pattern.symbolic(), &self.values)
    }

    /// `self[dofs, dofs] += local`.
    pub fn add_local(&mut self, local: &Mat<f64>, dofs: &[usize]) -> Result<(), SparseError> {
        let values = &mut self.values;
        self.pattern
            .for_each_local_position(dofs, |r, c, at| values[at] += local[(r, c)])
    }

    /// `self += scale · other` (same pattern).
    #[track_caller]
    pub fn add_scaled(&mut self, other: &Self, scale: f64) {
        assert!(Arc::ptr_eq(&self.pattern, &other.pattern) || self.pattern == other.pattern);
        self.values
            .iter_mut()
            .zip(&other.values)
            .for_each(|(a, b)| *a += scale * b);
    }

    /// The largest absolute diagonal entry.
    pub fn max_diagonal(&self) -> f64 {
        (0..self.dim()).map(|i| self.get(i, i).abs()).fold(0.0, f64::max)
    }

    /// The entry at `(row, col)` (0 outside the pattern).
    pub fn get(&self, row: usize, col: usize) -> f64 {
        self.pattern.position(row, col).map_or(0.0, |k| self.values[k])
    }

    /// `y = A x` for column vectors stored as the columns of `x`.
    pub fn mul(&self, x: &Mat<f64>) -> Mat<f64> {
        self.nonzeros().mul(x)
    }

    /// The non-zero entries alone: the shared pattern couples every dof of
    /// two control points, but a flat deck's mass couples few of them.
    pub fn nonzeros(&self) -> NonZeros {
        let p = &self.pattern;
        let mut col_ptr = Vec::with_capacity(p.n + 1);
        col_ptr.push(0);
        let (mut row_idx, mut values) = (Vec::new(), Vec::new());
        for c in 0..p.n {
            for e in p.col_ptr[c]..p.col_ptr[c + 1] {
                if self.values[e] != 0.0 {
                    row_idx.push(p.row_idx[e]);
                    values.push(self.values[e]);
                }
            }
            col_ptr.push(row_idx.len());
        }
        NonZeros {
            col_ptr,
            row_idx,
            values,
        }
    }

    /// The dense matrix (tests and small models).
    pub fn to_dense(&self) -> Mat<f64> {
        let p = &self.pattern;
        let mut out = Mat::<f64>::zeros(p.n, p.n);
        for c in 0..p.n {
            for e in p.col_ptr[c]..p.col_ptr[c + 1] {
                out[(p.row_idx[e], c)] = self.values[e];
            }
        }
        out
    }

    /// `Tᵀ A T` on `reduced`, `T` given by its sparse columns (`(row,
    /// weight)` pairs) over `t_rows` rows: the reduction to a model's free
    /// coordinates (`DofReduction::reduce_sparse`).
    pub fn congruence(
        &self,
        t_columns: &[Vec<(usize, f64)>],
        t_rows: usize,
        reduced: &Arc<Pattern>,
    ) -> Result<Self, SparseError> {
        if t_rows != self.dim() {
            return Err(SparseError::Dimension {
                found: self.dim(),
                expected: t_rows,
            });
        }
        // Per full dof, the reduced coordinates it enters and their weights.
        let mut owners: Vec<Vec<(usize, f64)>> = vec![Vec::new(); self.dim()];
        for (i, column) in t_columns.iter().enumerate() {
            for &(d, t) in column {
                owners[d].push((i, t));
            }
        }
        let mut out = Self::zeros(Arc::clone(reduced));
        let p = &self.pattern;
        for (j, column) in t_columns.iter().enumerate() {
            for &(c, tc) in column {
                for e in p.col_ptr[c]..p.col_ptr[c + 1] {
                    // Zeros add nothing (a stiffness field's matrix is mostly
                    // zeros on the whole deck's pattern).
                    if self.values[e] == 0.0 {
                        continue;
                    }
                    let v = self.values[e] * tc;
                    for &(i, tr) in &owners[p.row_idx[e]] {
                        let k = reduced
                            .position(i, j)
                            .ok_or(SparseError::OutsidePattern { row: i, col: j })?;
                        out.values[k] += tr * v;
                    }
                }
            }
        }
        Ok(out)
    }
}

/// A symmetric matrix on a shared [`Pattern`] that stores only the columns
/// an assembly reached (a stiffness field's `∂K/∂θ_k` covers part of the
/// deck): many of them cost about their own support, not the pattern each,
/// and each becomes a [`SparseSymmetric`] (the same values, summed in the
/// same order) only when it is used.
#[derive(Debug, Clone)]
pub struct SparseAccumulator {
    pattern: Arc<Pattern>,
    /// Per column of the pattern, its values once anything was added there.
    columns: Vec<Option<Box<[f64]>>>,
}

impl SparseAccumulator {
    pub fn new(pattern: Arc<Pattern>) -> Self {
        let columns = vec![None; pattern.n];
        Self { pattern, columns }
    }

    /// `self[dofs, dofs] += local`.
    pub fn add_local(&mut self, local: &Mat<f64>, dofs: &[usize]) -> Result<(), SparseError> {
        let (p, columns) = (&self.pattern, &mut self.columns);
        p.for_each_local_position(dofs, |r, c, at| {
            let col = dofs[c];
            let (start, end) = (p.col_ptr[col], p.col_ptr[col + 1]);
            let values = columns[col].get_or_insert_with(|| vec![0.0; end - start].into_boxed_slice());
            values[at - start] += local[(r, c)];
        })
    }

    /// The matrix on the whole pattern (zero where nothing was added).
    pub fn to_matrix(&self) -> SparseSymmetric {
        let mut m = SparseSymmetric::zeros(Arc::clone(&self.pattern));
        for (col, values) in self.columns.iter().enumerate() {
            if let Some(values) = values {
                m.values[self.pattern.col_ptr[col]..self.pattern.col_ptr[col + 1]].copy_from_slice(values);
            }
        }
        m
    }
}

#[cfg(test)]
mod tests;
