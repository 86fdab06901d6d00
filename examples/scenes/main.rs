//! The scene runner: the papers' experiments, sinew's models beside rapier's own soft bodies,
//! one process, one run each.
//!
//! ```text
//! cargo run --release --example scenes -- <scene> [--dim 2|3] [--model M ...] [--res N]
//!     [--dt S] [--seconds S] [--young PA] [--poisson NU] [--mass KG ...] [--iterations 1|2|3|polar ...]
//!     [--strikes N] [--k-over-m K ...] [--rrd DIR] [--json]
//! ```
//!
//! Scenes: `fall`, `limb`, `crush`, `manipulator`, `dt-sweep`, `rotation-error`, `cantilever` (see
//! `docs/STABILITY.md` for what each measures and the tables they print).

mod cli;

use std::process::ExitCode;

fn main() -> ExitCode {
    // Help, the version and bad arguments the way clap's parsers answer them: help on stdout
    // with status 0, a usage error on stderr with status 2.
    if let Err(e) = cli::parse(std::env::args_os()) {
        e.exit();
    }
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    match cli::run(std::env::args_os(), &mut out) {
        Ok(_) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("{e}");
            ExitCode::FAILURE
        }
    }
}
