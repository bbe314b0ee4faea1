//! MCAP recordings of raw input: one channel per topic
//! (`<prefix>/accel/<name>`, `<prefix>/force/<name>`), message encoding
//! `cbor` or `json` (the wire format), `log_time` = block start in ns since
//! the epoch, zstd-compressed chunks. JSON channels carry a JSON Schema so
//! Foxglove can plot them.

use crate::io::wire::{self, ChannelBlock, Encoding, Limits, WireError};
use anyhow::{Context, Result};
use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufReader, BufWriter, Read, Seek, Write};
use std::path::Path;

/// JSON Schema of a channel block (for `json` channels).
pub const BLOCK_JSON_SCHEMA: &str = r#"{
  "$schema": "https://json-schema.org/draft/2020-12/schema",
  "title": "splinewatch channel block (SEP005 style)",
  "type": "object",
  "required": ["name", "quantity", "fs", "start_timestamp", "data"],
  "properties": {
    "name": {"type": "string"},
    "quantity": {"enum": ["acceleration", "force", "temperature"]},
    "unit_str": {"type": "string"},
    "fs": {"type": "number", "exclusiveMinimum": 0},
    "start_timestamp": {"type": "string", "format": "date-time"},
    "data": {"type": "array", "items": {"type": "number"}}
  }
}"#;

/// The MCAP writer settings of every file splinewatch writes: zstd chunks
/// compressed in the writing thread (zstd's own worker threads only
/// competed with the replay's stages, which already keep both cores busy:
/// 0.47–0.49 s against 0.47–0.59 s on the bearing hour) at zstd's level 1
/// (ZSTD_fast; level 3's double-fast search spent 6 % of the bearing hour's
/// replay compressing its results file), profile and library named.
pub fn mcap_options() -> mcap::WriteOptions {
    mcap::WriteOptions::new()
        .compression(Some(mcap::Compression::Zstd))
        .compression_level(1)
        .compression_threads(0)
        .profile("splinewatch")
        .library(concat!("splinewatch ", env!("CARGO_PKG_VERSION")))
}

/// Writes raw-input recordings.
pub struct RecordingWriter<W: Write + Seek> {
    writer: mcap::Writer<W>,
    encoding: Encoding,
    schema_id: u16,
    channels: BTreeMap<String, u16>,
    sequence: u32,
}

impl RecordingWriter<BufWriter<File>> {
    pub fn create(path: &Path, encoding: Encoding) -> Result<Self> {
        Self::new(BufWriter::new(crate::io::files::create_output_file(path)?), encoding)
    }
}

impl<W: Write + Seek> RecordingWriter<W> {
    pub fn new(w: W, encoding: Encoding) -> Result<Self> {
        let mut writer = mcap_options().create(w).context("cannot start the MCAP file")?;
        let schema_id = match encoding {
            Encoding::Json => writer
                .add_schema("splinewatch.ChannelBlock", "jsonschema", BLOCK_JSON_SCHEMA.as_bytes())
                .context("cannot add the MCAP schema")?,
            Encoding::Cbor => 0,
        };
        Ok(Self {
            writer,
            encoding,
            schema_id,
            channels: BTreeMap::new(),
            sequence: 0,
        })
    }

    /// Appends one block on its topic under `prefix`; returns the size of
    /// the encoded message in bytes.
    pub fn write_block(&mut self, prefix: &str, block: &ChannelBlock) -> Result<usize> {
        let topic = block.topic(prefix);
        let channel_id = match self.channels.get(&topic) {
            Some(&id) => id,
            None => {
                let metadata = BTreeMap::from([
                    ("quantity".to_string(), format!("{:?}", block.quantity).to_lowercase()),
                    ("unit".to_string(), block.unit.clone()),
                    ("fs".to_string(), block.fs.to_string()),
                ]);
                let id = self
                    .writer
                    .add_channel(self.schema_id, &topic, self.encoding.mcap_name(), &metadata)
                    .with_context(|| format!("cannot add MCAP channel {topic}"))?;
                self.channels.insert(topic.clone(), id);
                id
            }
        };
        let data = wire::encode(block, self.encoding);
        self.write_message(channel_id, block.start_ns, &data)
            .with_context(|| format!("cannot write to {topic}"))?;
        Ok(data.len())
    }

    /// Appends a JSON message (a pre-computed FRF) on `topic` at `time_ns`.
    pub fn write_json(&mut self, topic: &str, time_ns: i128, payload: &[u8]) -> Result<usize> {
        let channel_id = match self.channels.get(topic) {
            Some(&id) => id,
            None => {
                let id = self
                    .writer
                    .add_channel(0, topic, "json", &BTreeMap::new())
                    .with_context(|| format!("cannot add MCAP channel {topic}"))?;
                self.channels.insert(topic.to_string(), id);
                id
            }
        };
        self.write_message(channel_id, time_ns, payload)
            .with_context(|| format!("cannot write to {topic}"))?;
        Ok(payload.len())
    }

    /// What an import said of the data it wrote (a recorder placed by its
    /// channels' motion, channels cut to a common span): an MCAP metadata
    /// record `splinewatch.import` with the source and one `note.N` per
    /// sentence, which readers (Foxglove, `mcap info`) show beside the data.
    pub fn write_import_notes(&mut self, source: &str, notes: &[String]) -> Result<()> {
        let mut metadata = BTreeMap::from([("source".to_string(), source.to_string())]);
        for (i, note) in notes.iter().enumerate() {
            metadata.insert(format!("note.{}", i + 1), note.clone());
        }
        self.writer
            .write_metadata(&mcap::records::Metadata {
                name: "splinewatch.import".into(),
                metadata,
            })
            .context("cannot write the import's notes to the MCAP file")
    }

    /// One message at `time_ns` (log and publish time).
    fn write_message(&mut self, channel_id: u16, time_ns: i128, data: &[u8]) -> Result<()> {
        let log_time = u64::try_from(time_ns).context("timestamps before 1970 cannot be recorded")?;
        self.sequence = self.sequence.wrapping_add(1);
        self.writer.write_to_known_channel(
            &mcap::records::MessageHeader {
                channel_id,
                sequence: self.sequence,
                log_time,
                publish_time: log_time,
            },
            data,
        )?;
        Ok(())
    }

    /// Writes the summary and index; the file is complete after this.
    pub fn finish(mut self) -> Result<W> {
        self.writer.finish().context("cannot finish the MCAP file")?;
        Ok(self.writer.into_inner())
    }
}

/// A block read back from a recording.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordedBlock {
    pub topic: String,
    pub log_time: u64,
    pub block: ChannelBlock,
}

impl RecordedBlock {
    /// `block` as if recorded on its topic under `prefix` at its own start
    /// (imported files, a live daemon's blocks).
    pub fn at_its_start(block: ChannelBlock, prefix: &str) -> Self {
        Self {
            topic: block.topic(prefix),
            log_time: u64::try_from(block.start_ns.max(0)).unwrap_or(0),
            block,
        }
    }
}

/// A message that could not be used, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct RejectedMessage {
    pub topic: String,
    pub log_time: u64,
    pub error: WireError,
}

/// The largest record (message or chunk) a recording may hold: far above
/// what splinewatch or the usual MCAP writers produce, small enough that a
/// damaged length field cannot make the reader ask for gigabytes.
pub const MAX_RECORD_BYTES: usize = 256 << 20;

/// The messages of an in-memory MCAP file in file order, chunk CRCs checked
/// and record lengths bounded by [`MAX_RECORD_BYTES`]. (`mcap::MessageStream`
/// trusts a damaged length field inside a chunk and the process aborts
/// trying to allocate it.) `salvage` reads a file that has no end (a killed
/// writer) up to its last complete record.
pub fn mcap_messages(
    bytes: &[u8],
    salvage: bool,
) -> Result<impl Iterator<Item = mcap::McapResult<mcap::Message<'static>>> + '_> {
    check_magic(bytes)?;
    Ok(mcap::io::MessageReader::new_with_options(
        bytes,
        reader_options(salvage),
    ))
}

fn check_magic(bytes: &[u8]) -> Result<()> {
    if !bytes.starts_with(mcap::MAGIC) {
        anyhow::bail!("not an MCAP file (no MCAP magic at the start)");
    }
    Ok(())
}

fn reader_options(salvage: bool) -> mcap::sans_io::LinearReaderOptions {
    mcap::sans_io::LinearReaderOptions::default()
        .with_record_length_limit(MAX_RECORD_BYTES)
        .with_validate_chunk_crcs(true)
        .with_skip_end_magic(salvage)
}

/// One MCAP message as read (its data decompressed and owned).
pub type McapMessage = mcap::McapResult<mcap::Message<'static>>;

/// A recording to read in file order: bytes in memory, or a file read as
/// it goes (memory bounded by the largest chunk, not the file), with the
/// message count of its summary for progress (0 without one).
pub struct RecordingSource<'a> {
    source: Box<dyn Read + Send + 'a>,
    message_count: u64,
}

impl<'a> RecordingSource<'a> {
    pub fn from_bytes(bytes: &'a [u8]) -> Result<Self> {
        check_magic(bytes)?;
        let message_count = mcap::Summary::read(bytes)
            .ok()
            .flatten()
            .and_then(|s| s.stats.map(|st| st.message_count))
            .unwrap_or(0);
        Ok(Self {
            source: Box::new(bytes),
            message_count,
        })
    }

    pub fn message_count(&self) -> u64 {
        self.message_count
    }

    /// The messages, CRCs checked and record lengths bounded as
    /// [`mcap_messages`].
    pub fn messages(self) -> impl Iterator<Item = McapMessage> + Send + 'a {
        mcap::io::MessageReader::new_with_options(self.source, reader_options(false))
    }
}

impl RecordingSource<'static> {
    /// Opens a recording file: refused, naming it, when it is not MCAP.
    pub fn open(path: &Path) -> Result<Self> {
        let mut file = File::open(path).with_context(|| format!("cannot read {}", path.display()))?;
        let mut magic = [0u8; mcap::MAGIC.len()];
        let head = match file.read_exact(&mut magic) {
            Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => None, // shorter than the magic
            read => Some(read.with_context(|| format!("cannot read {}", path.display()))?),
        };
        if head.is_none() || magic != *mcap::MAGIC {
            anyhow::bail!(
                "{} is not an MCAP file (it does not start with the MCAP magic)",
                path.display()
            );
        }
        let message_count = summary_message_count(&mut file).unwrap_or(0);
        file.rewind()
            .with_context(|| format!("cannot read {}", path.display()))?;
        Ok(Self {
            source: Box::new(BufReader::with_capacity(1 << 20, file)),
            message_count,
        })
    }
}

/// The message count in a file's summary (read from its end).
fn summary_message_count(file: &mut File) -> Option<u64> {
    use mcap::sans_io::summary_reader::{SummaryReadEvent, SummaryReader};
    let mut reader = SummaryReader::new();
    while let Some(event) = reader.next_event() {
        match event.ok()? {
            SummaryReadEvent::ReadRequest(need) => {
                let read = file.read(reader.insert(need)).ok()?;
                reader.notify_read(read);
            }
            SummaryReadEvent::SeekRequest(to) => reader.notify_seeked(file.seek(to).ok()?),
        }
    }
    reader.finish()?.stats.map(|s| s.message_count)
}

/// Reads every raw-input block of a recording, in file order. Messages on
/// topics that are not `…/accel/…` or `…/force/…`, or with another encoding,
/// are skipped; undecodable ones are returned in the second list.
pub fn read_recording(bytes: &[u8], limits: &Limits) -> Result<(Vec<RecordedBlock>, Vec<RejectedMessage>)> {
    let mut blocks = Vec::new();
    let mut rejected = Vec::new();
    for message in mcap_messages(bytes, false)? {
        let message = message.context("corrupt MCAP record")?;
        let topic = &message.channel.topic;
        if !(topic.contains("/accel/") || topic.contains("/force/")) {
            continue;
        }
        let Some(encoding) = Encoding::from_name(&message.channel.message_encoding) else {
            continue;
        };
        match wire::decode(&message.data, encoding, limits) {
            Ok(decoded) => blocks.extend(decoded.into_iter().map(|block| RecordedBlock {
                topic: topic.clone(),
                log_time: message.log_time,
                block,
            })),
            Err(error) => rejected.push(RejectedMessage {
                topic: topic.clone(),
                log_time: message.log_time,
                error,
            }),
        }
    }
    Ok((blocks, rejected))
}
