//! Matrix Market files (NIST's exchange format, read by scipy's `mmread`,
//! MATLAB, Julia, OpenSees' and commercial codes' importers): symmetric
//! sparse matrices as `coordinate real symmetric`, the lower triangle,
//! 1-based, every value printed so that it reads back bit for bit.

use anyhow::{bail, Context, Result};
use splinewatch_core::model::sparse::SparseSymmetric;
use std::io::{BufRead, Write};

/// Writes the lower triangle of `matrix` with `comment` lines after the banner.
pub fn write_symmetric(out: &mut impl Write, matrix: &SparseSymmetric, comment: &[String]) -> Result<()> {
    let pattern = matrix.pattern();
    let (col_ptr, row_idx, values) = (pattern.col_ptr(), pattern.row_idx(), matrix.values());
    let lower = |c: usize| (col_ptr[c]..col_ptr[c + 1]).filter(move |&e| row_idx[e] >= c && values[e] != 0.0);
    let n = matrix.dim();
    let nnz: usize = (0..n).map(|c| lower(c).count()).sum();
    writeln!(out, "%%MatrixMarket matrix coordinate real symmetric")?;
    for line in comment {
        writeln!(out, "% {line}")?;
    }
    writeln!(out, "{n} {n} {nnz}")?;
    for c in 0..n {
        for e in lower(c) {
            // `{:e}` is the shortest representation that reads back exactly.
            writeln!(out, "{} {} {:e}", row_idx[e] + 1, c + 1, values[e])?;
        }
    }
    Ok(())
}

/// `(row, col, value)`, 0-based.
pub type Entry = (usize, usize, f64);

/// A symmetric Matrix Market file read back: its size and the entries of
/// its stored (lower) triangle.
pub fn read_symmetric(input: impl BufRead) -> Result<(usize, Vec<Entry>)> {
    let mut lines = input.lines();
    let banner = lines.next().context("empty file")??;
    if !banner
        .to_lowercase()
        .starts_with("%%matrixmarket matrix coordinate real symmetric")
    {
        bail!("not a real symmetric coordinate Matrix Market file: {banner:?}");
    }
    let mut size = None;
    let mut entries = Vec::new();
    for (number, line) in lines.enumerate() {
        let line = line?;
        if line.starts_with('%') || line.trim().is_empty() {
            continue;
        }
        let fields: Vec<&str> = line.split_whitespace().collect();
        let bad = || format!("line {}: {line:?}", number + 2);
        match size {
            None => {
                let n: usize = fields.first().and_then(|f| f.parse().ok()).with_context(bad)?;
                size = Some(n);
            }
            Some(_) => {
                let [r, c, v] = fields[..] else { bail!(bad()) };
                let (r, c): (usize, usize) = (r.parse().with_context(bad)?, c.parse().with_context(bad)?);
                if r == 0 || c == 0 {
                    bail!(bad());
                }
                entries.push((r - 1, c - 1, v.parse().with_context(bad)?));
            }
        }
    }
    Ok((size.context("no size line")?, entries))
}

#[cfg(test)]
mod tests {
    use super::*;
    use splinewatch_core::model::sparse::Pattern;
    use std::sync::Arc;

    #[test]
    fn a_matrix_reads_back_bit_for_bit() {
        let pattern = Arc::new(Pattern::control_net((3, 2), (1, 1), &[2; 6]));
        let mut m = SparseSymmetric::zeros(Arc::clone(&pattern));
        for (k, v) in m.values_mut().iter_mut().enumerate() {
            *v = (k as f64 + 0.1).sqrt() * 1e9 / 3.0;
        }
        let mut bytes = Vec::new();
        write_symmetric(&mut bytes, &m, &["a test".into()]).unwrap();
        let (n, entries) = read_symmetric(std::io::Cursor::new(bytes)).unwrap();
        assert_eq!(n, 12);
        for (r, c, v) in entries {
            assert!(r >= c);
            assert_eq!(v, m.get(r, c));
        }
    }
}
