//! `splinewatch station`: a starter config from a station's records.

use crate::io::console::{errln, outln};
use crate::studies::station::{starter_config, StationRecord};
use anyhow::{Context, Result};
use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
pub struct StationArgs {
    /// The station's records: each a CESMD `.zip` of Volume 2 files (or one `.V2` file); several records
    /// of one station give one config, the union of their channels.
    #[arg(required = true, num_args = 1..)]
    pub record: Vec<PathBuf>,
    /// Write the config here (default: stdout).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// The azimuth (degrees clockwise from north) of the structure's longitudinal axis: channels given
    /// as azimuths are turned onto the structure's x (along) and y (across).
    #[arg(long)]
    pub axis: Option<f64>,
}

pub fn station(a: StationArgs) -> Result<()> {
    let mut records = Vec::new();
    for path in &a.record {
        let bytes = std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))?;
        let file = path.display().to_string();
        let channels = crate::io::cosmos_v2::list_v2(&[(bytes, file.clone())])?;
        records.push(StationRecord { file, channels });
    }
    let config = starter_config(&records, a.axis)?;
    for guess in &config.guesses {
        errln!("guessed: {guess}");
    }
    match &a.out {
        Some(out) => {
            std::fs::write(out, &config.toml).with_context(|| format!("cannot write {}", out.display()))?;
            errln!("starter config written to {}", out.display());
        }
        None => outln!("{}", config.toml.trim_end()),
    }
    Ok(())
}
