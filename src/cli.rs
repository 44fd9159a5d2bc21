//! The command line: `dsmcosim validate FILE`, `dsmcosim run FILE --out DIR`.
//!
//! Exit codes: 0 success, 1 I/O failure, 2 bad input (scenario or arguments),
//! 3 a run that diverged or failed numerically.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

use crate::scenario;

/// Deterministic co-simulator of distributed multi-body simulations with SMC
/// stabilization and delay optimization.
#[derive(Debug, Parser)]
#[command(name = "dsmcosim", version, about, long_about = None)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The subcommands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Check a scenario file and print what it describes; writes nothing.
    Validate {
        /// Scenario file (JSON).
        scenario: PathBuf,
    },
    /// Run a scenario and write summary.json, trace.csv, epochs.csv and SVG plots.
    Run {
        /// Scenario file (JSON).
        scenario: PathBuf,
        /// Output directory (created if missing; files in it are replaced atomically).
        #[arg(long)]
        out: PathBuf,
    },
}

/// Entry point of the binary.
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    match execute(cli.command) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(e.exit_code())
        }
    }
}

/// Runs one subcommand.
pub fn execute(command: Command) -> crate::Result<()> {
    match command {
        Command::Validate { scenario } => {
            let s = scenario::load(&scenario)?;
            println!(
                "{}: ok — {} bodies, {} links, {} forces, {} steps of {} s, {} path, {} integrator",
                scenario.display(),
                s.bodies.len(),
                s.links.len(),
                s.forces.len(),
                s.steps,
                s.dt.as_secs_f64(),
                s.body_model.name(),
                s.integrator.name()
            );
            Ok(())
        }
        Command::Run { scenario, out } => {
            let s = scenario::load(&scenario)?;
            let outcome = crate::run::run(&s, &out)?;
            println!(
                "{}: {} steps in {:.3} s wall; max |w| = {:.3e} m; mean cost = {:.3e} m; digest {}",
                s.name,
                outcome.steps,
                outcome.wall_seconds,
                outcome.max_constraint_violation,
                outcome.mean_cost,
                outcome.digest
            );
            println!("wrote {}", out.display());
            Ok(())
        }
    }
}
