//! The `splinewatch` command line; everything lives in [`splinewatch::cli`].
#![forbid(unsafe_code)]

fn main() -> std::process::ExitCode {
    splinewatch::cli::main()
}
