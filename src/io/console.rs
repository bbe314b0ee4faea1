//! The console: standard output, standard error and the log, written so that
//! a closed pipe or terminal never takes the work down. A failed write ends
//! the printing on that stream (nothing more is tried), never the run; a
//! failed log write is dropped and counted (`health.log_writes_dropped`).
//! Nothing here panics, unlike `println!`/`eprintln!` on a closed pipe.

use std::fmt;
use std::io::{self, Write};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

static STDOUT_CLOSED: AtomicBool = AtomicBool::new(false);
static STDERR_CLOSED: AtomicBool = AtomicBool::new(false);
static LOG_WRITES_DROPPED: AtomicU64 = AtomicU64::new(0);

/// Log lines that could not be written (stderr closed or failing).
pub fn log_writes_dropped() -> u64 {
    LOG_WRITES_DROPPED.load(Ordering::Relaxed)
}

/// Runs `write` unless the stream is marked closed; a failure marks it.
fn unless_closed(closed: &AtomicBool, write: impl FnOnce() -> io::Result<()>) {
    if !closed.load(Ordering::Relaxed) && write().is_err() {
        closed.store(true, Ordering::Relaxed);
    }
}

/// Writes to standard output; once a write failed, nothing more is tried.
pub fn out(args: fmt::Arguments<'_>) {
    unless_closed(&STDOUT_CLOSED, || {
        let mut w = io::stdout().lock();
        w.write_fmt(args).and_then(|()| w.flush())
    });
}

/// Writes to standard error; once a write failed, nothing more is tried.
pub fn err(args: fmt::Arguments<'_>) {
    unless_closed(&STDERR_CLOSED, || {
        let mut w = io::stderr().lock();
        w.write_fmt(args).and_then(|()| w.flush())
    });
}

/// `println!` that never panics: a closed stdout ends the printing.
#[cfg_attr(not(feature = "daemon"), allow(unused_macros))]
macro_rules! outln {
    ($($arg:tt)*) => { $crate::io::console::out(format_args!("{}\n", format_args!($($arg)*))) };
}

/// `eprintln!` that never panics: a closed stderr ends the printing.
#[cfg_attr(not(feature = "daemon"), allow(unused_macros))]
macro_rules! errln {
    ($($arg:tt)*) => { $crate::io::console::err(format_args!("{}\n", format_args!($($arg)*))) };
}

#[cfg_attr(not(feature = "daemon"), allow(unused_imports))]
pub(crate) use {errln, outln};

/// Standard output as a `Write` for table and JSON writers: every write
/// succeeds; after a failure the rest is dropped.
pub struct Stdout;

impl Write for Stdout {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        unless_closed(&STDOUT_CLOSED, || io::stdout().lock().write_all(buf));
        Ok(buf.len())
    }

    fn flush(&mut self) -> io::Result<()> {
        unless_closed(&STDOUT_CLOSED, || io::stdout().lock().flush());
        Ok(())
    }
}

/// The log's writer: standard error, where a failed write is dropped and
/// counted instead of reported (tracing-subscriber would `eprintln!` the
/// failure, which panics on a closed stderr).
#[derive(Clone, Copy, Default)]
pub struct LogWriter;

impl Write for LogWriter {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        if io::stderr().lock().write_all(buf).is_err() {
            LOG_WRITES_DROPPED.fetch_add(1, Ordering::Relaxed);
        }
        Ok(buf.len())
    }

    fn flush(&mut self) -> io::Result<()> {
        let _ = io::stderr().lock().flush();
        Ok(())
    }
}

#[cfg(feature = "daemon")]
impl<'a> tracing_subscriber::fmt::MakeWriter<'a> for LogWriter {
    type Writer = LogWriter;

    fn make_writer(&'a self) -> Self::Writer {
        *self
    }
}
