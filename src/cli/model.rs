//! `modes`, `synth`, `update`, `paper`, `check-config`: the model's own
//! commands (no measurement stream).

use super::parse_quantity;
use crate::config::load_config;
use crate::io::console::{errln, outln};
use crate::studies::{self, paper, SynthOptions};
use anyhow::{Context, Result};
use clap::Args;
use splinewatch_core::response::frf::Quantity;
use splinewatch_core::updating::IterationRecord;
use std::io::Write;
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct ModesArgs {
    /// Configuration file (TOML).
    #[arg(long)]
    pub config: PathBuf,
    /// How many modes to list, lowest first.
    #[arg(long, default_value_t = 30)]
    pub count: usize,
    /// Print `{"modes":[{"index","frequency_hz","kind"}…]}` instead of a table.
    #[arg(long)]
    pub json: bool,
    /// Only the modes below this frequency (Hz), by sparse assembly and
    /// shift-invert Lanczos: for models of 10⁴–10⁵ dofs.
    #[arg(long)]
    pub cutoff: Option<f64>,
}

#[derive(Args)]
pub struct MatricesArgs {
    /// Configuration file (TOML).
    #[arg(long)]
    pub config: PathBuf,
    /// Folder for the `.mtx` files and `index.json` (created if missing).
    #[arg(long)]
    pub out: PathBuf,
}

#[derive(Args)]
pub struct SynthArgs {
    /// Configuration file (TOML).
    #[arg(long)]
    pub config: PathBuf,
    /// Input (force) sensors, comma-separated.
    #[arg(long, value_delimiter = ',', required = true)]
    pub inputs: Vec<String>,
    /// Output (response) sensors, comma-separated.
    #[arg(long, value_delimiter = ',', required = true)]
    pub outputs: Vec<String>,
    /// receptance, mobility or accelerance.
    #[arg(long, default_value = "accelerance", value_parser = parse_quantity)]
    pub quantity: Quantity,
    /// Lowest frequency line, Hz.
    #[arg(long, default_value_t = 0.5)]
    pub from: f64,
    /// Highest frequency line, Hz.
    #[arg(long, default_value_t = 80.0)]
    pub to: f64,
    /// Line spacing, Hz.
    #[arg(long, default_value_t = 0.1)]
    pub step: f64,
    /// Complex Gaussian noise, standard deviation as a fraction of each FRF's RMS.
    #[arg(long, default_value_t = 0.0)]
    pub noise: f64,
    /// Seed of the noise generator (ChaCha8).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Output file (FRF JSON).
    #[arg(long)]
    pub out: PathBuf,
}

#[derive(Args)]
pub struct UpdateArgs {
    /// Configuration file (TOML).
    #[arg(long)]
    pub config: PathBuf,
    /// Measured FRFs (FRF JSON).
    #[arg(long, required_unless_present = "modes", conflicts_with = "modes")]
    pub frf: Option<PathBuf>,
    /// Identified modes (`splinewatch oma --json` output): output-only,
    /// modal-residue updating.
    #[arg(long)]
    pub modes: Option<PathBuf>,
    /// Start from a previous result (`update --json` output) instead of the config's values.
    #[arg(long)]
    pub start: Option<PathBuf>,
    /// Print the result as JSON on stdout.
    #[arg(long)]
    pub json: bool,
}

#[derive(Args)]
pub struct PaperArgs {
    /// Output folder (outside the source tree by default; `--out docs/guide/src/paper`
    /// refreshes the committed report).
    #[arg(long, default_value = "out/paper")]
    pub out: PathBuf,
}

#[derive(Args)]
pub struct CheckConfigArgs {
    /// Configuration file (TOML).
    pub config: PathBuf,
}

pub fn modes(a: ModesArgs) -> Result<()> {
    let cfg = load_config(&a.config)?;
    let (report, info) = studies::compute_modes(&cfg, a.count, a.cutoff)?;
    for line in studies::modes::describe_patches(&cfg.build_model()?) {
        errln!("{line}");
    }
    errln!(
        "{}: {} dofs ({} free), assembly {:.3} s, eigen-solve {:.3} s",
        cfg.structure.name,
        info.dofs,
        info.free_dofs,
        info.assembly_seconds,
        info.solve_seconds
    );
    let mut out = crate::io::console::Stdout;
    studies::write_modes(&report, a.json, &mut out)?;
    out.flush()?;
    Ok(())
}

pub fn matrices(a: MatricesArgs) -> Result<()> {
    let cfg = load_config(&a.config)?;
    let (index, seconds) = studies::matrices::export_matrices(&cfg, &a.out)?;
    errln!(
        "{}: {} free dofs ({} generalised), sparse assembly {seconds:.3} s; K, K_f, M and {} ∂K/∂parameter matrices in {}",
        index.structure,
        index.free_dofs,
        index.generalised_dofs,
        index.parameters.len(),
        a.out.display()
    );
    Ok(())
}

pub fn synth(a: SynthArgs) -> Result<()> {
    let cfg = load_config(&a.config)?;
    let options = SynthOptions {
        inputs: a.inputs,
        outputs: a.outputs,
        quantity: a.quantity,
        f_min: a.from,
        f_max: a.to,
        step: a.step,
        noise: a.noise,
        seed: a.seed,
    };
    let file = studies::synth(&cfg, &options)?;
    let text = serde_json::to_string(&file)?;
    std::fs::write(&a.out, text).with_context(|| format!("cannot write {}", a.out.display()))?;
    errln!(
        "wrote {} FRFs × {} lines to {}",
        file.frfs.len(),
        file.frequency_hz.len(),
        a.out.display()
    );
    Ok(())
}

pub fn update(a: UpdateArgs) -> Result<()> {
    let cfg = load_config(&a.config)?;
    let start_text = a
        .start
        .as_ref()
        .map(|p| std::fs::read_to_string(p).with_context(|| format!("cannot read start file {}", p.display())))
        .transpose()?;
    let mut progress = |it: &IterationRecord| {
        errln!(
            "iteration {:3}  relative residual {:.4e}  step {:.3e}  damping {:.3e}  rejected {}",
            it.iteration,
            it.relative_residual,
            it.step_norm,
            it.damping,
            it.rejected_steps
        );
    };
    let mut out = crate::io::console::Stdout;
    let (result, pairs) = match (&a.frf, &a.modes) {
        (Some(frf), _) => {
            let frf_bytes = std::fs::read(frf).with_context(|| format!("cannot read FRF file {}", frf.display()))?;
            let (result, truncation) = studies::update(&cfg, &frf_bytes, start_text.as_deref(), &mut progress)
                .with_context(|| format!("updating against {}", frf.display()))?;
            if let Some(t) = truncation {
                let error = t.frf_error.map_or("not evaluated (a large model)".to_string(), |e| {
                    format!("{e:.2e} of each FRF's peak")
                });
                errln!(
                    "modal truncation: {} modes below {} Hz, the rest as residual flexibility; FRF error against every mode: {error}",
                    t.modes_kept,
                    t.cutoff_hz
                );
            }
            (result, None)
        }
        (None, Some(modes)) => {
            let file = crate::io::modes_json::ModesFile::read(modes)?;
            let solution = studies::update::update_from_modes(&cfg, &file, start_text.as_deref(), &mut progress)
                .with_context(|| format!("updating against {}", modes.display()))?;
            (solution.result, Some((file, solution.pairs)))
        }
        (None, None) => anyhow::bail!("give --frf FILE or --modes FILE"),
    };
    if a.json {
        serde_json::to_writer(&mut out, &result)?;
        writeln!(out)?;
    } else {
        studies::write_update_table(&cfg, &result, &mut out)?;
        if let Some((file, pairs)) = pairs {
            writeln!(out, "paired modes (identified → model, MAC):")?;
            for p in pairs {
                writeln!(
                    out,
                    "  {:9.4} Hz → model mode {:3}  MAC {:.3}",
                    file.modes[p.observed].frequency_hz,
                    p.model + 1,
                    p.mac
                )?;
            }
        }
    }
    out.flush()?;
    Ok(())
}

pub fn paper(a: PaperArgs) -> Result<()> {
    let out = a.out;
    let (truth, model) = paper::bundled_configs(Path::new("."))?;
    std::fs::create_dir_all(&out).with_context(|| format!("cannot create {}", out.display()))?;
    let mut outcomes = Vec::new();
    for (k, e) in paper::EXPERIMENTS.iter().enumerate() {
        errln!("running {} (paper §{})", e.name, e.section);
        let o = paper::run(&truth, &model, e)?;
        let svg = out.join(format!("damping-{}.svg", k + 1));
        paper::plot_damping(&o, &svg)?;
        outcomes.push(o);
    }
    let report = paper::report_markdown(&outcomes);
    std::fs::write(out.join("report.md"), &report)?;
    crate::io::console::out(format_args!("{report}"));
    Ok(())
}

pub fn check_config(a: CheckConfigArgs) -> Result<()> {
    let cfg = load_config(&a.config)?;
    // The zenoh session settings too: the JSON5 file and our keys on top,
    // with every TLS file read and its certificates' validity checked.
    let (_, tls) = cfg.zenoh.to_zenoh_with_tls()?;
    outln!("{}: configuration is valid", cfg.structure.name);
    if cfg.has_model() {
        let model = cfg.build_model()?;
        for line in studies::modes::describe_patches(&model) {
            outln!("{line}");
        }
        if cfg.has_ground_sensors() {
            let groups = cfg.support_groups(&model)?;
            outln!("support groups: {}", groups.names().join(", "));
            outln!("ground inputs (support motion):");
            for input in cfg.ground_plan(&groups)? {
                outln!("  {}", input.describe(&cfg));
            }
        }
    } else if cfg.has_ground_sensors() {
        let ground = cfg.sensors.len() - cfg.deck_sensor_count();
        let mut groups: Vec<&str> = cfg.sensors.iter().filter_map(|s| s.support.as_deref()).collect();
        groups.sort_unstable();
        groups.dedup();
        outln!(
            "no model: {} structure sensors and {ground} ground sensors in {} support groups ({}) for identification (identify: input-output; oma: output-only; events: modes and verdicts; import, frf); predict, the events' forecast and update, and the model's commands need [model]",
            cfg.deck_sensor_count(),
            groups.len(),
            groups.join(", ")
        );
    } else {
        outln!(
            "no model: {} sensors for output-only identification (oma, import, frf); the model's commands need [model]",
            cfg.sensors.len()
        );
    }
    if cfg.has_model() && !cfg.sensors.is_empty() {
        let paths = match (cfg.is_output_only(), cfg.runs_oma()) {
            (true, _) => "identified modes (output-only)",
            (false, true) => "FRFs and identified modes (a force sensor and [oma])",
            (false, false) => "FRFs",
        };
        outln!("per window: {paths}; updates fit {}", cfg.residues()?.as_str());
    }
    if tls.endpoints {
        let kind = if tls.mutual { "mutual TLS" } else { "TLS" };
        outln!("zenoh transport: {kind}");
    }
    for file in &tls.files {
        outln!("  {file}");
    }
    for file in tls.expiring() {
        errln!(
            "warning: {} expires within {} days: renew it (guide: docs/guide/src/deployment/tls.md)",
            file.path.display(),
            crate::config::EXPIRY_WARNING_DAYS
        );
    }
    Ok(())
}
