//! The `splinewatch` command line; everything lives in [`splinewatch::cli`].
#![forbid(unsafe_code)]

/// The allocator: mimalloc keeps the large matrices a solve frees for the
/// next instead of returning them to the system and faulting their pages
/// in again (glibc's behaviour above its mmap threshold). Built without
/// transparent huge pages (`no_thp`: mimalloc would advise them for its
/// arenas, and the kernel zeroes each 2 MiB page it faults in: a one-off
/// `identify` spent 0.35 s of system time on it, 0.55 s in all against
/// 0.35–0.40 s without, measured 2026-11-27).
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() -> std::process::ExitCode {
    splinewatch::cli::main()
}
