//! The `splinewatch` command line; everything lives in [`splinewatch::cli`].
#![forbid(unsafe_code)]

/// The allocator: mimalloc keeps the large matrices a solve frees for the
/// next instead of returning them to the system and faulting their pages
/// in again (glibc's behaviour above its mmap threshold).
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn main() -> std::process::ExitCode {
    splinewatch::cli::main()
}
