//! Bytes in and out: the console (never fatal), the wire format of channel blocks, MCAP recordings, FRF and identified-modes
//! files, loggers' CSV and UFF 58 files, strong-motion Volume 2 files, output-file creation and numbering,
//! the results files' topics and schemas, and salvaging unfinished MCAP.
//! Room: the bottom of the application. May import: the core crate only.

pub mod console;
pub mod cosmos_v2;
pub mod files;
pub mod frf_json;
pub mod import;
pub mod matrix_market;
pub mod modes_json;
pub mod monitoring_json;
pub mod named_value;
pub mod recording;
pub mod recover;
pub mod results_file;
pub mod results_topics;
pub mod uff;
pub mod wire;
