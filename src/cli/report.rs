//! `report`: the owner's report of an event or a period, one self-contained
//! HTML file, from a bridge's results files.

use crate::io::console::outln;
use crate::io::results_file::read_results;
use crate::io::wire::parse_timestamp;
use crate::outputs::report::{self, Selection};
use anyhow::{bail, Context, Result};
use std::io::Write;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct ReportArgs {
    /// Results MCAP files of one bridge, in time order (`events --out`, a
    /// daemon's or `replay`'s results, rotated files one after the other).
    #[arg(required = true)]
    pub inputs: Vec<PathBuf>,
    /// The event to report: its name as `events` prints it, or a part of it
    /// no other event's name contains (default: the last event, or the
    /// whole period when the results hold no event).
    #[arg(long, conflicts_with_all = ["from", "to"])]
    pub event: Option<String>,
    /// A period report from this time (RFC 3339, or a date: 2026-03-01).
    #[arg(long)]
    pub from: Option<String>,
    /// A period report up to this time (RFC 3339, or a date: the whole day).
    #[arg(long)]
    pub to: Option<String>,
    /// The HTML file to write.
    #[arg(long)]
    pub out: PathBuf,
}

/// An RFC 3339 time, or a date (its start; with `end_of_day`, its end).
fn parse_time(flag: &str, s: &str, end_of_day: bool) -> Result<i128> {
    if let Some(t) = parse_timestamp(s) {
        return Ok(t);
    }
    let day = parse_timestamp(&format!("{s}T00:00:00Z")).with_context(|| {
        format!("--{flag} {s:?} is neither an RFC 3339 time (2026-03-01T12:00:00Z) nor a date (2026-03-01)")
    })?;
    Ok(if end_of_day { day + 86_400_000_000_000 - 1 } else { day })
}

pub fn report(a: ReportArgs) -> Result<()> {
    let selection = match (&a.event, &a.from, &a.to) {
        (Some(name), _, _) => Selection::Event(name.clone()),
        (None, None, None) => Selection::Latest,
        (None, from, to) => Selection::Period {
            from: from.as_deref().map(|s| parse_time("from", s, false)).transpose()?,
            to: to.as_deref().map(|s| parse_time("to", s, true)).transpose()?,
        },
    };
    if let Selection::Period {
        from: Some(f),
        to: Some(t),
    } = selection
    {
        if f > t {
            bail!("--from is after --to: no period");
        }
    }
    let bytes = a
        .inputs
        .iter()
        .map(|p| std::fs::read(p).with_context(|| format!("cannot read {}", p.display())))
        .collect::<Result<Vec<_>>>()?;
    let files: Vec<(String, &[u8])> = a
        .inputs
        .iter()
        .zip(&bytes)
        .map(|(p, b)| (p.display().to_string(), b.as_slice()))
        .collect();
    let contents = read_results(&files)?;
    let report = report::render(&contents, &selection)?;
    write_whole(&a.out, &report.html)?;
    outln!("{}: {}", report.priority.label(), report.verdict);
    outln!(
        "{} written ({} kB): {}",
        a.out.display(),
        report.html.len() / 1024,
        report.title
    );
    Ok(())
}

/// Writes `html` to `path` whole or not at all (a `.part` file renamed): a
/// failed run leaves no half report.
pub(super) fn write_whole(path: &std::path::Path, html: &str) -> Result<()> {
    let partial = path.with_extension("html.part");
    let mut file = crate::io::files::create_output_file(&partial)?;
    file.write_all(html.as_bytes())
        .and_then(|()| file.sync_all())
        .with_context(|| format!("cannot write {}", partial.display()))?;
    std::fs::rename(&partial, path).with_context(|| format!("cannot write {}", path.display()))
}
