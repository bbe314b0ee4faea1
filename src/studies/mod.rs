//! Offline studies of the configured model, each returning its output as a
//! value or writing to a given writer, so tests run them without a process:
//! modes, synthetic FRFs, updating against an FRF file, the paper's §4
//! experiments, the time-domain simulation of the deck, the import of
//! loggers' files and universal files for modal-testing software.
//! Room: below the services, beside the pipeline. May import: `config`, `io`, the core crate.

pub mod environment;
pub mod event_update;
pub mod exchange;
pub mod excitation;
pub mod frf_windows;
pub mod ground_motion;
pub mod import;
pub mod matrices;
pub mod mode_match;
pub mod modes;
pub mod paper;
pub mod parameters;
pub mod predict;
pub mod simulation;
pub mod station;
pub mod synth;
pub mod update;

pub use modes::{compute_modes, write_modes, ModalRunInfo, ModeRow, ModesReport};
pub use synth::{synth, SynthOptions};
pub use update::{start_values, update, write_parameter_header, write_parameter_row, write_update_table};
