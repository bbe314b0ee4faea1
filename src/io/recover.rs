//! `splinewatch recover`: salvages an MCAP file whose writer was killed
//! (no summary, a truncated last chunk). Every message of every complete,
//! CRC-valid chunk is copied, in order, to a new finalised file; reading
//! stops at the first damaged record, which is reported.

use anyhow::{Context, Result};
use std::io::{Seek, Write};

/// What `recover` found.
#[derive(Debug, Clone, PartialEq)]
pub struct RecoverReport {
    /// Messages copied.
    pub messages: u64,
    /// Distinct channels among them.
    pub channels: usize,
    /// The input already had its summary (it was finalised).
    pub was_complete: bool,
    /// Why reading stopped before the end of the data, if it did.
    pub stopped_at: Option<String>,
}

pub fn recover<W: Write + Seek>(bytes: &[u8], out: W) -> Result<(RecoverReport, W)> {
    let was_complete = matches!(mcap::Summary::read(bytes), Ok(Some(_)));
    let stream = crate::io::recording::mcap_messages(bytes, true)?;
    let mut writer = crate::io::recording::mcap_options()
        .library(concat!("splinewatch ", env!("CARGO_PKG_VERSION"), " (recovered)"))
        .create(out)
        .context("cannot start the recovered MCAP file")?;
    let mut report = RecoverReport {
        messages: 0,
        channels: 0,
        was_complete,
        stopped_at: None,
    };
    let mut channels = std::collections::BTreeSet::new();
    for message in stream {
        match message {
            Ok(m) => {
                channels.insert(m.channel.topic.clone());
                writer.write(&m).context("cannot write the recovered MCAP file")?;
                report.messages += 1;
            }
            Err(e) => {
                report.stopped_at = Some(e.to_string());
                break;
            }
        }
    }
    report.channels = channels.len();
    writer.finish().context("cannot finish the recovered MCAP file")?;
    Ok((report, writer.into_inner()))
}
