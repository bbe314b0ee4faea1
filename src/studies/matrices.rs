//! `splinewatch matrices`: the configured model's matrices for other tools
//! (scipy, OpenSees, a commercial code): `K_f`, `M`, `K` at the config's
//! values and every `∂K/∂parameter` in Matrix Market, on the free
//! coordinates the eigenproblem is solved on, with a JSON index of what
//! every row is (control point, its position, the generalised dofs it
//! combines).

use crate::config::Config;
use crate::io::files::create_output_file;
use crate::io::matrix_market::write_symmetric;
use anyhow::{Context, Result};
use serde::Serialize;
use splinewatch_core::model::shell::DOFS_PER_CONTROL_POINT;
use splinewatch_core::model::sparse::SparseSymmetric;
use splinewatch_core::solvers::sparse_model::SparseModel;
use std::io::{BufWriter, Write};
use std::path::Path;
use std::time::Instant;

/// The generalised dofs of a control point, in order (eq. 4).
const DOF_NAMES: [&str; DOFS_PER_CONTROL_POINT] = ["u", "v", "w", "alpha", "beta"];

#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Component {
    pub dof: &'static str,
    pub weight: f64,
}

/// What one row (and column) of the matrices is.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct DofEntry {
    /// 1-based, as in the Matrix Market files.
    pub row: usize,
    /// The patch the control point belongs to (`"deck"` for a model of one).
    pub patch: String,
    /// The control point's number within its patch (η fastest).
    pub control_point: usize,
    /// The control point's indices `(i, j)` in its patch's net (ξ, η).
    pub net_index: [usize; 2],
    /// The control point's position, m.
    pub position: [f64; 3],
    /// The free coordinate as a combination of the point's generalised
    /// dofs (`u, v, w` global translations, `alpha`, `beta` director
    /// rotations): a single dof with weight 1 unless a support constrains
    /// a direction.
    pub components: Vec<Component>,
}

#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct ParameterMatrix {
    pub name: String,
    /// `"spring"` (κ_j), `"bearing"` (a bearing's `k_x, k_y, k_z`),
    /// `"support"` (a line support's components) or `"stiffness_field"` (θ_k).
    pub kind: &'static str,
    /// The config's value.
    pub value: f64,
    pub file: String,
    pub nnz_lower: usize,
}

/// `index.json`.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct MatrixIndex {
    pub structure: String,
    pub format: &'static str,
    /// `K = K_f + Σ_k (θ_k − 1) ∂K/∂θ_k + Σ_j κ_j ∂K/∂κ_j` (eq. 23).
    pub relation: &'static str,
    pub free_dofs: usize,
    pub generalised_dofs: usize,
    pub stiffness: String,
    pub free_stiffness: String,
    pub mass: String,
    pub parameters: Vec<ParameterMatrix>,
    pub dofs: Vec<DofEntry>,
}

/// Writes the matrices and `index.json` into `dir`; returns the index and
/// the assembly time (s).
pub fn export_matrices(config: &Config, dir: &Path) -> Result<(MatrixIndex, f64)> {
    let model = config.build_model()?;
    let start = Instant::now();
    let sparse = SparseModel::assemble(&model).context("assembling the sparse model")?;
    let seconds = start.elapsed().as_secs_f64();
    let theta = sparse.field_coefficients.clone();
    let k = sparse.stiffness_with_fields(&sparse.spring_stiffness, &theta)?;
    let name = &config.structure.name;
    let write = |file: &str, m: &SparseSymmetric, what: &str| -> Result<usize> {
        let path = dir.join(file);
        let mut out = BufWriter::new(create_output_file(&path)?);
        let comment = [format!(
            "{what} of {name} (splinewatch matrices; SI units, free coordinates)"
        )];
        write_symmetric(&mut out, m, &comment).with_context(|| format!("writing {}", path.display()))?;
        out.flush().with_context(|| format!("writing {}", path.display()))?;
        Ok(m.pattern().nnz())
    };
    write("K.mtx", &k, "stiffness K at the config's parameters")?;
    write("K_f.mtx", &sparse.free_stiffness, "free stiffness K_f (eq. 16)")?;
    write("M.mtx", &sparse.mass, "consistent mass M (eq. 17)")?;
    let mut parameters = Vec::new();
    // κ holds the spring fields' coefficients, then the bearings', then
    // the line supports' (`ShellModel::spring_coefficients`).
    let springs = config.model.springs.iter().map(|s| (s.name.as_str(), "spring"));
    let bearings = config.model.bearings.iter().map(|b| (b.name.as_str(), "bearing"));
    let supports = config.model.supports.iter().map(|s| (s.name.as_str(), "support"));
    let fields = config
        .model
        .stiffness_fields
        .iter()
        .map(|f| (f.name.as_str(), "stiffness_field"));
    let terms = springs
        .chain(bearings)
        .chain(supports)
        .chain(fields)
        .zip(sparse.spring_terms.iter().chain(&sparse.field_terms));
    let values = sparse.spring_stiffness.iter().chain(&theta);
    for (((field, kind), terms), values) in terms.zip(values) {
        for (j, (term, &value)) in terms.iter().zip(values).enumerate() {
            let parameter = match kind {
                "bearing" => format!("{field}.{}", ["kx", "ky", "kz"][j]),
                "support" => {
                    let support = config.model.supports.iter().find(|s| s.name == field);
                    let component = support.map_or("", |s| s.component_names()[j]);
                    format!("{field}.{component}")
                }
                "spring" => format!("{field}.k{}", j + 1),
                _ => format!("{field}.s{}", j + 1),
            };
            let file = format!("dK_d{parameter}.mtx");
            let matrix = term.to_matrix(&sparse.pattern);
            write(&file, &matrix, &format!("∂K/∂{parameter}"))?;
            parameters.push(ParameterMatrix {
                name: parameter,
                kind,
                value,
                file,
                nnz_lower: lower_nnz(&matrix),
            });
        }
    }
    let index = MatrixIndex {
        structure: name.clone(),
        format: "Matrix Market coordinate real symmetric, lower triangle, 1-based",
        relation: "K = K_f + sum_k (theta_k - 1) dK/dtheta_k + sum_j kappa_j dK/dkappa_j",
        free_dofs: sparse.free_count(),
        generalised_dofs: sparse.dof_count(),
        stiffness: "K.mtx".into(),
        free_stiffness: "K_f.mtx".into(),
        mass: "M.mtx".into(),
        parameters,
        dofs: dof_entries(&sparse),
    };
    let path = dir.join("index.json");
    let mut out = BufWriter::new(create_output_file(&path)?);
    serde_json::to_writer_pretty(&mut out, &index)?;
    writeln!(out)?;
    out.flush().with_context(|| format!("writing {}", path.display()))?;
    Ok((index, seconds))
}

fn lower_nnz(m: &SparseSymmetric) -> usize {
    let p = m.pattern();
    (0..m.dim())
        .map(|c| {
            (p.col_ptr()[c]..p.col_ptr()[c + 1])
                .filter(|&e| p.row_idx()[e] >= c && m.values()[e] != 0.0)
                .count()
        })
        .sum()
}

fn dof_entries(sparse: &SparseModel) -> Vec<DofEntry> {
    // Per global control point: its patch and its number there.
    let owners: Vec<(usize, usize)> = sparse
        .patches
        .iter()
        .enumerate()
        .flat_map(|(k, p)| (0..p.shell.control_point_count()).map(move |cp| (k, cp)))
        .collect();
    sparse
        .reduction
        .columns()
        .iter()
        .enumerate()
        .map(|(row, column)| {
            let (k, cp) = owners[column[0].0 / DOFS_PER_CONTROL_POINT];
            let surface = sparse.patches[k].shell.surface();
            let n = surface.net_size().1;
            DofEntry {
                row: row + 1,
                patch: sparse.patches[k].name().to_owned(),
                control_point: cp,
                net_index: [cp / n, cp % n],
                position: surface.points()[cp],
                components: column
                    .iter()
                    .map(|&(d, weight)| Component {
                        dof: DOF_NAMES[d % DOFS_PER_CONTROL_POINT],
                        weight,
                    })
                    .collect(),
            }
        })
        .collect()
}
