//! The frequency axis cut into contiguous runs of whole
//! [`FREQUENCY_BLOCK`]s, one per thread. An FRF, a transmissibility and
//! their sensitivities at a line do not depend on the other lines, and a
//! run of whole blocks is computed block by block exactly as in one
//! sequential call: the results are the same bit for bit whatever the
//! thread count.

use super::FREQUENCY_BLOCK;
use faer::c64;
use std::ops::Range;

/// Runs of lines, each computed on its own thread.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LineRuns {
    lines: usize,
    runs: Vec<Range<usize>>,
}

impl LineRuns {
    /// `lines` lines on at most `threads` threads (at least one run, whole
    /// blocks in each but the last).
    pub fn new(lines: usize, threads: usize) -> Self {
        let blocks = lines.div_ceil(FREQUENCY_BLOCK);
        let threads = threads.clamp(1, blocks.max(1));
        let per_thread = blocks.div_ceil(threads).max(1) * FREQUENCY_BLOCK;
        let mut runs: Vec<Range<usize>> = (0..lines)
            .step_by(per_thread)
            .map(|a| a..(a + per_thread).min(lines))
            .collect();
        if runs.is_empty() {
            runs.push(0..0);
        }
        Self { lines, runs }
    }

    /// The runs, in line order.
    pub fn runs(&self) -> &[Range<usize>] {
        &self.runs
    }

    /// `work` of every run, in run order: the first on the caller's
    /// thread, the others on scoped threads.
    pub fn map<T: Send>(&self, work: impl Fn(Range<usize>) -> T + Sync) -> Vec<T> {
        let (first, rest) = self.runs.split_first().expect("at least one run");
        if rest.is_empty() {
            return vec![work(first.clone())];
        }
        std::thread::scope(|scope| {
            let work = &work;
            let handles: Vec<_> = rest
                .iter()
                .map(|run| {
                    let run = run.clone();
                    scope.spawn(move || work(run))
                })
                .collect();
            let mut all = vec![work(first.clone())];
            all.extend(
                handles
                    .into_iter()
                    .map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e))),
            );
            all
        })
    }

    /// The runs' values, each laid out `[row * run_length + k]` (rows of
    /// the same count in every part), as one `[row * lines + line]`.
    pub fn merge(&self, mut parts: Vec<Vec<c64>>) -> Vec<c64> {
        assert_eq!(parts.len(), self.runs.len(), "one part per run");
        if parts.len() == 1 {
            return parts.pop().expect("one part");
        }
        let rows = match self.runs.iter().zip(&parts).find(|(run, _)| !run.is_empty()) {
            Some((run, part)) => part.len() / run.len(),
            None => 0,
        };
        let mut all = vec![c64::new(0.0, 0.0); rows * self.lines];
        for (run, part) in self.runs.iter().zip(&parts) {
            let n = run.len();
            assert_eq!(part.len(), rows * n, "every part holds the same rows");
            for row in 0..rows {
                all[row * self.lines + run.start..][..n].copy_from_slice(&part[row * n..][..n]);
            }
        }
        all
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn runs_cover_the_lines_in_whole_blocks() {
        let runs = LineRuns::new(100, 2);
        assert_eq!(runs.runs(), &[0..64, 64..100]);
        assert_eq!(LineRuns::new(100, 1).runs(), std::slice::from_ref(&(0..100)));
        // More threads than blocks: one run per block.
        assert_eq!(LineRuns::new(40, 8).runs(), &[0..32, 32..40]);
        assert_eq!(LineRuns::new(0, 4).runs(), std::slice::from_ref(&(0..0)));
    }

    #[test]
    fn merge_puts_each_runs_rows_in_place() {
        let runs = LineRuns::new(40, 2);
        // Two rows: value = 1000 row + line.
        let parts = runs.map(|run| {
            (0..2)
                .flat_map(|row| run.clone().map(move |k| c64::new((1000 * row + k) as f64, 0.0)))
                .collect::<Vec<_>>()
        });
        let all = runs.merge(parts);
        let expected: Vec<c64> = (0..2)
            .flat_map(|row| (0..40).map(move |k| c64::new((1000 * row + k) as f64, 0.0)))
            .collect();
        assert_eq!(all, expected);
    }
}
