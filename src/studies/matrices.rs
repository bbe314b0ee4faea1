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
use splinewatch_core::model::dofs::DofKind;
use splinewatch_core::model::sparse::SparseSymmetric;
use splinewatch_core::model::BridgeModel;
use splinewatch_core::solvers::sparse_model::SparseModel;
use std::io::{BufWriter, Write};
use std::path::Path;
use std::time::Instant;

#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Component {
    pub dof: &'static str,
    pub weight: f64,
}

/// What one row (and column) of the matrices is: a free coordinate on a
/// shell control point, a beam node or a rigid body's reference node.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct DofEntry {
    /// 1-based, as in the Matrix Market files.
    pub row: usize,
    /// The patch the control point belongs to (`"deck"` for a model of one).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub patch: Option<String>,
    /// The control point's number within its patch (η fastest).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub control_point: Option<usize>,
    /// The control point's indices `(i, j)` in its patch's net (ξ, η).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub net_index: Option<[usize; 2]>,
    /// A beam node: the first member through it, and the node's number
    /// along that member from its start.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub beam: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub beam_node: Option<usize>,
    /// A rigid body's reference node: the body's name (its coordinate also
    /// moves every node the body holds).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rigid_body: Option<String>,
    /// The node's position, m.
    pub position: [f64; 3],
    /// The free coordinate as a combination of the node's generalised dofs
    /// (`u, v, w` global translations; `alpha`, `beta` a control point's
    /// director rotations; `rx, ry, rz` a beam or rigid node's rotations
    /// about the global axes): a single dof with weight 1 unless a support
    /// constrains a direction.
    pub components: Vec<Component>,
}

#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct ParameterMatrix {
    pub name: String,
    /// `"spring"` (κ_j), `"bearing"` (a bearing's `k_x, k_y, k_z`),
    /// `"support"` (a line support's components), `"stiffness_field"` (θ_k) or
    /// `"member_stiffness"` (a beam's θ).
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

/// Who owns each vector of κ and then of θ, with its kind: κ holds the
/// spring fields' coefficients, then the bearings', then the line
/// supports' (`BridgeModel::spring_coefficients`); θ the stiffness fields',
/// then the beams' multipliers (`BridgeModel::field_coefficients`).
fn coefficient_owners(config: &Config) -> Vec<(&str, &'static str)> {
    let m = &config.model;
    let springs = m.springs.iter().map(|s| (s.name.as_str(), "spring"));
    let bearings = m.bearings.iter().map(|b| (b.name.as_str(), "bearing"));
    let supports = m.supports.iter().map(|s| (s.name.as_str(), "support"));
    let fields = m.stiffness_fields.iter().map(|f| (f.name.as_str(), "stiffness_field"));
    let members = m
        .beams
        .iter()
        .filter(|b| b.stiffness.is_some())
        .map(|b| (b.name.as_str(), "member_stiffness"));
    springs
        .chain(bearings)
        .chain(supports)
        .chain(fields)
        .chain(members)
        .collect()
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
    let terms = coefficient_owners(config)
        .into_iter()
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
                "member_stiffness" => format!("{field}.stiffness"),
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
        dofs: dof_entries(&sparse, &model),
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

fn dof_entries(sparse: &SparseModel, model: &BridgeModel) -> Vec<DofEntry> {
    let dofs = model.dof_map();
    // Per global control point: its patch and its number there.
    let owners: Vec<(usize, usize)> = model
        .patches
        .iter()
        .enumerate()
        .flat_map(|(k, p)| (0..p.shell.control_point_count()).map(move |cp| (k, cp)))
        .collect();
    let dof_name = |d: usize| match dofs.kind(d) {
        DofKind::Translation(a) => ["u", "v", "w"][a],
        DofKind::DirectorRotation(r) => ["alpha", "beta"][r],
        DofKind::Rotation(a) => ["rx", "ry", "rz"][a],
    };
    sparse
        .reduction
        .columns()
        .iter()
        .enumerate()
        .map(|(row, column)| {
            let node = dofs.node_of(column[0].0);
            let components = column
                .iter()
                .filter(|&&(d, _)| dofs.node_of(d) == node)
                .map(|&(d, weight)| Component {
                    dof: dof_name(d),
                    weight,
                })
                .collect();
            let mut entry = DofEntry {
                row: row + 1,
                patch: None,
                control_point: None,
                net_index: None,
                beam: None,
                beam_node: None,
                rigid_body: None,
                position: [0.0; 3],
                components,
            };
            if dofs.is_control_point(node) {
                let (k, cp) = owners[node];
                let surface = model.patches[k].shell.surface();
                let n = surface.net_size().1;
                entry.patch = Some(model.patches[k].name().to_owned());
                entry.control_point = Some(cp);
                entry.net_index = Some([cp / n, cp % n]);
                entry.position = surface.points()[cp];
            } else if node - dofs.control_point_count() < dofs.beam_node_count() {
                let b = node - dofs.control_point_count();
                let beams = &model.beams;
                if let Some((m, at)) = (0..beams.members().len())
                    .find_map(|m| beams.member_nodes(m).iter().position(|&n| n == b).map(|at| (m, at)))
                {
                    entry.beam = Some(beams.members()[m].name().to_owned());
                    entry.beam_node = Some(at);
                }
                entry.position = beams.position(b);
            } else {
                let r = node - dofs.control_point_count() - dofs.beam_node_count();
                let body = &model.rigid_bodies[r];
                entry.rigid_body = Some(body.name().to_owned());
                entry.position = body
                    .reference(&model.patches, &model.beams, &dofs)
                    .expect("a model whose reduction was built");
            }
            entry
        })
        .collect()
}
