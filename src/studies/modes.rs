//! `splinewatch modes`: the configured model's natural frequencies and mode kinds.

use crate::config::Config;
use crate::io::modes_json::ShapeEntry;
use anyhow::{Context, Result};
use serde::Serialize;
use splinewatch_core::model::constraints::Edge;
use splinewatch_core::model::damping::DampingCurve;
use splinewatch_core::model::elastic_supports::SupportSite;
use splinewatch_core::model::members::BeamBase;
use splinewatch_core::model::springs::LowRankBlock;
use splinewatch_core::model::BridgeModel;
use splinewatch_core::response::frf::sensor_rows_of;
use splinewatch_core::solvers::modal::{ModeKind, Modes};
use splinewatch_core::solvers::mode_motion::{DeckAxes, Motion, MotionShares};
use splinewatch_core::solvers::sparse_model::SparseModel;
use std::io::Write;
use std::time::Instant;

#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct ModeRow {
    pub index: usize,
    pub frequency_hz: f64,
    pub kind: ModeKind,
    /// Shares of the mode's translational kinetic energy along x, y, z.
    pub translation_shares: [f64; 3],
    /// Where it moves the deck: along it, across, vertically, in torsion
    /// (the deck's axes from its mass in plan; they sum to 1).
    pub motion_shares: MotionShares,
    /// The largest of those (`null` for a mode that moves no mass).
    pub motion: Option<Motion>,
    /// The share of the mode's strain energy stored in each support (spring
    /// field, bearing, line support), in the config's order: how much the
    /// mode engages it.
    pub support_shares: Vec<SupportShare>,
    /// ζ_i with `[model.damping]`: the curve's ζ(f_i) and the supports'
    /// loss factors' share `½ Σ_s η_s e_{i,s}` (`null` without the curve,
    /// or for a rigid mode).
    pub damping_ratio: Option<f64>,
    /// The mode at the config's deck sensors, each along its direction,
    /// largest component 1 (`im` 0: a real mode), in the layout of the
    /// identified modes' shapes (`identify --json`), so the two compare by
    /// MAC as they are.
    pub shape: Vec<ShapeEntry>,
}

/// One support's share of a mode's strain energy.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct SupportShare {
    pub support: String,
    pub share: f64,
}

#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct ModesReport {
    pub modes: Vec<ModeRow>,
}

/// Statistics of a modal run, reported on stderr.
#[derive(Debug, Clone)]
pub struct ModalRunInfo {
    pub dofs: usize,
    pub free_dofs: usize,
    pub assembly_seconds: f64,
    pub solve_seconds: f64,
}

/// The modes of a config's model with what the rows need from its assembly.
struct Solved {
    modes: Modes,
    dofs: usize,
    free_dofs: usize,
    /// When the assembly ended.
    assembled_at: Instant,
    positions: Vec<splinewatch_core::geometry::vec3::Vec3>,
    springs: (Vec<Vec<LowRankBlock>>, Vec<Vec<f64>>),
    sensors: Sensors,
    /// Each mode's strain-energy share in each stiffness-field coefficient's
    /// part, when a loss factor weighs them.
    field_shares: Option<Vec<Vec<f64>>>,
}

/// Every mode by the dense solver.
fn solve_dense(config: &Config, field_sites: bool) -> Result<Solved> {
    let model = config.build_dense_model()?;
    let sensors = Sensors::of(config, &model)?;
    let positions = model.control_point_positions();
    let assembled = model.assemble().context("assembling the model")?;
    let assembled_at = Instant::now();
    let modes = assembled.modes().context("solving the eigenproblem")?;
    let field_shares = field_sites.then(|| {
        let matrices: Vec<_> = assembled.field_matrices.iter().flatten().collect();
        let shares = modes.field_energy_shares(&assembled.field_coefficients, |k, x| matrices[k] * x);
        (0..shares.nrows())
            .map(|i| (0..shares.ncols()).map(|k| shares[(i, k)]).collect())
            .collect()
    });
    Ok(Solved {
        dofs: assembled.dof_count(),
        free_dofs: assembled.reduction.free_count(),
        modes,
        assembled_at,
        positions,
        springs: (assembled.spring_blocks, assembled.spring_stiffness),
        sensors,
        field_shares,
    })
}

/// The modes below `cutoff` Hz by the sparse assembly and shift-invert
/// Lanczos.
fn solve_sparse(config: &Config, cutoff: f64, field_sites: bool) -> Result<Solved> {
    if !(cutoff.is_finite() && cutoff > 0.0) {
        anyhow::bail!("--cutoff must be a positive frequency in Hz, got {cutoff}");
    }
    let model = config.build_model()?;
    let sensors = Sensors::of(config, &model)?;
    let sparse = SparseModel::assemble(&model).context("assembling the sparse model")?;
    let assembled_at = Instant::now();
    let theta = sparse.field_coefficients.clone();
    let modes = sparse
        .modes_below(&sparse.spring_stiffness, &theta, cutoff)
        .context("solving the partial eigenproblem")?;
    let field_shares = field_sites.then(|| {
        let products: Vec<_> = sparse.field_products.iter().flatten().collect();
        let shares = modes.field_energy_shares(&theta, |k, x| products[k].mul(x));
        (0..shares.nrows())
            .map(|i| (0..shares.ncols()).map(|k| shares[(i, k)]).collect())
            .collect()
    });
    Ok(Solved {
        dofs: sparse.dof_count(),
        free_dofs: sparse.free_count(),
        modes,
        assembled_at,
        positions: model.control_point_positions(),
        springs: (sparse.spring_blocks, sparse.spring_stiffness),
        sensors,
        field_shares,
    })
}

/// Assembles the configured model and returns its first `count` modes:
/// every mode by the dense solver, or with `cutoff_hz` (else the cut-off
/// of a truncated `[model.solver]`) those below it by the sparse assembly
/// and shift-invert Lanczos (models of 10⁴–10⁵ dofs).
pub fn compute_modes(config: &Config, count: usize, cutoff_hz: Option<f64>) -> Result<(ModesReport, ModalRunInfo)> {
    let t0 = Instant::now();
    let cutoff_hz = match cutoff_hz {
        Some(cutoff) => Some(cutoff),
        None => config.modal_cutoff_hz()?,
    };
    let damping = config
        .model
        .damping
        .is_some()
        .then(|| config.build_damping())
        .transpose()?;
    let field_sites = damping.as_ref().is_some_and(DampingCurve::has_field_sites);
    let Solved {
        modes,
        dofs,
        free_dofs,
        assembled_at: t1,
        positions,
        springs,
        sensors,
        field_shares,
    } = match cutoff_hz {
        None => solve_dense(config, field_sites)?,
        Some(cutoff) => solve_sparse(config, cutoff, field_sites)?,
    };
    let axes = modes.deck_axes(&positions);
    let (blocks, stiffness) = springs;
    let names = config.spring_field_names();
    anyhow::ensure!(
        names.len() == blocks.len(),
        "{} support names for {} assembled spring fields",
        names.len(),
        blocks.len()
    );
    let t2 = Instant::now();
    let supports = Supports {
        names: &names,
        blocks: &blocks,
        stiffness: &stiffness,
    };
    let rows = (0..modes.len().min(count))
        .map(|i| {
            let fields: &[f64] = field_shares.as_ref().map_or(&[], |shares| &shares[i]);
            mode_row(
                &modes,
                i,
                axes.as_ref(),
                &supports,
                (damping.as_ref(), fields),
                &sensors,
            )
        })
        .collect();
    let info = ModalRunInfo {
        dofs,
        free_dofs,
        assembly_seconds: (t1 - t0).as_secs_f64(),
        solve_seconds: (t2 - t1).as_secs_f64(),
    };
    Ok((ModesReport { modes: rows }, info))
}

/// The supports' names and `∂K/∂κ` blocks at their coefficients.
struct Supports<'a> {
    names: &'a [String],
    blocks: &'a [Vec<LowRankBlock>],
    stiffness: &'a [Vec<f64>],
}

/// Mode `i`'s row: frequency, kind, motion, the supports' shares of its
/// strain energy, with a damping curve its damping ratio (the curve's and
/// the loss factors' share, as the FRF model's, with the mode's share
/// `field_shares[k]` in each stiffness-field coefficient's part when a loss
/// factor weighs them), and its shape at the sensors.
fn mode_row(
    modes: &Modes,
    i: usize,
    axes: Option<&DeckAxes>,
    supports: &Supports<'_>,
    (damping, field_shares): (Option<&DampingCurve>, &[f64]),
    sensors: &Sensors,
) -> ModeRow {
    let motion_shares = axes.map_or_else(MotionShares::default, |a| modes.motion(a, i));
    let support_shares: Vec<SupportShare> = supports
        .names
        .iter()
        .zip(supports.blocks.iter().zip(supports.stiffness))
        .map(|(name, (b, k))| SupportShare {
            support: name.clone(),
            share: modes.spring_energy_share(i, b, k),
        })
        .collect();
    let damping_ratio = damping.filter(|_| modes.kinds[i] != ModeKind::Rigid).map(|d| {
        // Each spring coefficient's share: a loss factor may weigh some of
        // a support's components only.
        let shares: Vec<f64> = supports
            .blocks
            .iter()
            .zip(supports.stiffness)
            .flat_map(|(b, k)| (0..b.len()).map(move |j| (&b[j..=j], &k[j..=j])))
            .map(|(b, k)| modes.spring_energy_share(i, b, k))
            .collect();
        let sizes: Vec<usize> = supports.blocks.iter().map(Vec::len).collect();
        d.zeta(modes.frequency_hz(i)) + 0.5 * d.support_loss((&shares, field_shares), &sizes)
    });
    ModeRow {
        index: i + 1,
        frequency_hz: modes.frequency_hz(i),
        kind: modes.kinds[i],
        translation_shares: modes.translation_shares[i],
        motion_shares,
        motion: motion_shares.dominant(),
        support_shares,
        damping_ratio,
        shape: sensors.shape(modes, i),
    }
}

/// The config's deck sensors: names and rows `N_ψ(P_s)` on the model's dofs.
struct Sensors {
    names: Vec<String>,
    rows: Vec<Vec<(usize, f64)>>,
}

impl Sensors {
    fn of(config: &Config, model: &BridgeModel) -> Result<Self> {
        let (names, points): (Vec<String>, Vec<_>) = config.build_sensors(model)?.into_iter().unzip();
        let rows = sensor_rows_of(model, &points).context("the sensors' rows")?;
        Ok(Self { names, rows })
    }

    /// Mode `i` at the sensors, its largest component `+1`.
    fn shape(&self, modes: &Modes, i: usize) -> Vec<ShapeEntry> {
        let values: Vec<f64> = self
            .rows
            .iter()
            .map(|row| row.iter().map(|&(dof, w)| w * modes.shapes[(dof, i)]).sum())
            .collect();
        let peak = values
            .iter()
            .fold(0.0f64, |m, v| if v.abs() > m.abs() { *v } else { m });
        self.names
            .iter()
            .zip(values)
            .map(|(sensor, v)| ShapeEntry {
                sensor: sensor.clone(),
                re: if peak == 0.0 { 0.0 } else { v / peak },
                im: 0.0,
                std: None,
            })
            .collect()
    }
}

/// The patches and joints of a deck of several patches (patch, edge, the
/// other patch, length), the beams, the rigid bodies and the supports
/// (where, which components), one line each; nothing for one patch alone.
pub fn describe_patches(model: &BridgeModel) -> Vec<String> {
    if model.patches.len() < 2
        && model.beams.is_empty()
        && model.rigid_bodies.is_empty()
        && model.elastic_supports.is_empty()
    {
        return Vec::new();
    }
    let mut lines: Vec<String> = model
        .patches
        .iter()
        .map(|p| {
            let (m, n) = p.shell.surface().net_size();
            format!("patch {}: {m} × {n} control points", p.name())
        })
        .collect();
    lines.extend(model.joints.iter().map(|j| {
        let edge = edge_name(j.edge);
        format!(
            "joint: {} edge {edge} on {}, {:.3} m",
            model.patches[j.patch].name(),
            model.patches[j.other].name(),
            j.length
        )
    }));
    lines.extend(model.beams.members().iter().enumerate().map(|(k, b)| {
        let base_node = model.beams.member_nodes(k)[0];
        let footing = model.elastic_supports.iter().find(|s| match s.site() {
            SupportSite::BeamNodes(nodes) => nodes.contains(&base_node),
            SupportSite::Edge { .. } | SupportSite::Point(_) => false,
        });
        let base = match (b.base(), footing) {
            (BeamBase::Fixed, _) => "fixed".to_string(),
            (BeamBase::Pinned, _) => "pinned".to_string(),
            (BeamBase::Free, Some(s)) => format!("on support {}", s.name()),
            (BeamBase::Free, None) => "free".to_string(),
        };
        format!(
            "beam {}: {:.3} m in {} elements, base {base}",
            b.name(),
            b.length(),
            b.elements()
        )
    }));
    lines.extend(model.rigid_bodies.iter().map(|r| {
        let (edges, beam_nodes) = r.counts();
        format!("rigid {}: {edges} edges, {beam_nodes} beam nodes", r.name())
    }));
    lines.extend(model.elastic_supports.iter().map(|s| {
        let site = match s.site() {
            SupportSite::Edge { patch, edge } => {
                format!("along {} edge {}", model.patches[*patch].name(), edge_name(*edge))
            }
            SupportSite::Point(at) => {
                let [x, y, z] = model.position_of(*at);
                format!("at ({x:.3}, {y:.3}, {z:.3}) m on {}", model.patches[at.patch].name())
            }
            SupportSite::BeamNodes(nodes) => format!("at {} beam bases", nodes.len()),
        };
        let components: Vec<&str> = s.components().iter().map(|c| c.name()).collect();
        format!("support {}: {site}, {}", s.name(), components.join(" "))
    }));
    lines
}

/// An edge as the configuration names it.
fn edge_name(edge: Edge) -> &'static str {
    match edge {
        Edge::Xi0 => "xi0",
        Edge::Xi1 => "xi1",
        Edge::Eta0 => "eta0",
        Edge::Eta1 => "eta1",
    }
}

/// `splinewatch modes`: a table (or JSON) on `out`.
pub fn write_modes(report: &ModesReport, json: bool, out: &mut impl Write) -> Result<()> {
    if json {
        serde_json::to_writer(&mut *out, report)?;
        writeln!(out)?;
        return Ok(());
    }
    // The kind, and where the mode moves the deck: the shares of its
    // translational kinetic energy along it, across, vertically and in
    // torsion, and the largest of them; then the share of its strain energy
    // in the supports, and the damping ratio.
    writeln!(
        out,
        "{:>5}  {:>12}  {:<8}  {:<12}  {:>6}  {:>6}  {:>6}  {:>6}  {:>6}  {:>6}",
        "mode", "frequency Hz", "kind", "motion", "long %", "tran %", "vert %", "tors %", "supp %", "ζ %"
    )?;
    for r in &report.modes {
        let kind = match r.kind {
            ModeKind::Rigid => "rigid",
            ModeKind::Membrane => "membrane",
            ModeKind::Bending => "bending",
        };
        let motion = r.motion.map_or("—", Motion::label);
        let s = &r.motion_shares;
        let [l, t, v, o] = [s.longitudinal, s.transverse, s.vertical, s.torsion].map(|x| (100.0 * x).round());
        let supports = (100.0 * r.support_shares.iter().map(|s| s.share).sum::<f64>()).round();
        let zeta = r
            .damping_ratio
            .map_or_else(|| "—".to_owned(), |z| format!("{:.2}", 100.0 * z));
        writeln!(
            out,
            "{:>5}  {:>12.4}  {kind:<8}  {motion:<12}  {l:>6}  {t:>6}  {v:>6}  {o:>6}  {supports:>6}  {zeta:>6}",
            r.index, r.frequency_hz
        )?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use crate::config::Config;

    /// A line support along the deck-on-bent example's west end.
    const WEST_ABUTMENT: &str = "
[[model.supports]]
name = \"west_abutment\"
edge = { patch = \"span1\", edge = \"xi0\" }
support = \"west\"
stiffness = { y = 2e8, ry = 5e8 }
update = false
";

    /// Every support is listed where it acts, with its components.
    #[test]
    fn the_model_s_description_lists_every_support_where_it_acts() {
        let text = format!(
            "{}{}{}",
            include_str!("../../config/examples/deck-on-bent.toml"),
            r#"
[[model.supports]]
name = "pot"
at = [30.0, 4.0, -0.2]
support = "west"
stiffness = { z = 2e9, ry = 1e9 }
update = false
"#,
            WEST_ABUTMENT
        );
        let lines = super::describe_patches(&Config::from_toml(&text).unwrap().build_model().unwrap());
        let supports: Vec<&str> = lines
            .iter()
            .filter(|l| l.starts_with("support "))
            .map(String::as_str)
            .collect();
        assert_eq!(
            supports,
            [
                "support pot: at (30.000, 4.000, -0.200) m on span2, z ry",
                "support west_abutment: along span1 edge xi0, y ry"
            ]
        );
    }

    /// `modes`' damping ratio is the FRF model's ζ_i (the curve's and every
    /// loss factor's share: a support's component, a column's multiplier),
    /// computed here from the modes' own energy shares: 1e-9 relative.
    #[test]
    fn the_damping_ratio_is_the_frf_models_with_every_loss_factor() {
        let base = include_str!("../../config/examples/deck-on-bent.toml");
        let text = base.replacen(
            "name = \"bent.south\"\n",
            "name = \"bent.south\"\nstiffness = { update = false }\nloss_factor = 0.1\n",
            1,
        ) + WEST_ABUTMENT
            + "loss_factor = { y = 0.3 }\n";
        let config = Config::from_toml(&text).unwrap();
        config.validate().unwrap();
        let (report, _) = super::compute_modes(&config, 12, None).unwrap();
        let setup = crate::config::frf_setup(&config).unwrap();
        assert!(setup.damping.has_field_sites());
        let state = setup.model.modal_state(&setup.kappa, &setup.damping).unwrap();
        let mut loaded = 0;
        for row in &report.modes {
            let (found, expected) = (row.damping_ratio.unwrap(), state.zeta[row.index - 1]);
            assert!(
                (found - expected).abs() <= 1e-9 * expected.max(1e-3),
                "mode {}: {found} vs {expected}",
                row.index
            );
            loaded += usize::from(state.support_zeta(row.index - 1) > 1e-3);
        }
        assert!(loaded > 3, "the loss factors must matter on some modes");
        // The sparse path (modes below a cut-off) computes the same shares
        // from its own operators: within the partial eigen-solve's accuracy.
        let (partial, _) = super::compute_modes(&config, 6, Some(100.0)).unwrap();
        for (row, dense) in partial.modes.iter().zip(&report.modes) {
            let (found, expected) = (row.damping_ratio.unwrap(), dense.damping_ratio.unwrap());
            assert!(
                (found - expected).abs() <= 1e-6 * expected,
                "mode {}: {found} vs {expected}",
                row.index
            );
        }
    }
}
