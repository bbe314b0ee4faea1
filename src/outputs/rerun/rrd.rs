//! Reading `.rrd` files back with Rerun's own decoder (the tests' check of
//! what a run wrote).

use anyhow::{Context, Result};
use rerun::external::re_log_types::{LogMsg, StoreKind};

/// What a `.rrd` file holds, read back with Rerun's own decoder.
#[derive(Debug, Clone, Default)]
pub struct RrdSummary {
    /// Entity paths with data in the recording (blueprint excluded).
    pub entities: std::collections::BTreeSet<String>,
    pub chunks: usize,
    /// Whether the file ends with its footer (written when the stream is
    /// closed cleanly).
    pub footer: bool,
}

/// Decodes a whole `.rrd` file.
pub fn inspect_rrd(bytes: &[u8]) -> Result<RrdSummary> {
    use rerun::external::re_log_encoding::DecoderApp;
    let mut messages = DecoderApp::decode_eager(std::io::BufReader::new(bytes)).context("not an .rrd file")?;
    let mut summary = RrdSummary::default();
    for msg in messages.by_ref() {
        summary.add(&msg.context("corrupt .rrd message")?)?;
    }
    summary.footer = !messages.rrd_manifests().context("reading the .rrd footer")?.is_empty();
    Ok(summary)
}

impl RrdSummary {
    /// Counts one message of a Rerun stream (from a file or a server).
    pub fn add(&mut self, msg: &LogMsg) -> Result<()> {
        if let LogMsg::ArrowMsg(store, arrow) = msg {
            if store.kind() == StoreKind::Recording {
                let chunk = rerun::log::Chunk::from_arrow_msg(arrow).context("corrupt .rrd chunk")?;
                self.entities.insert(chunk.entity_path().to_string());
                self.chunks += 1;
            }
        }
        Ok(())
    }
}
