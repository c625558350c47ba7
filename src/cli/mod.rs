//! Command-line interface. Each subcommand lives in its own file and
//! returns `Result<(), String>`; errors print to stderr with a non-zero exit.

pub mod build;
pub mod check;
pub mod pattern;
pub mod simulate;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// origami-fmu: origami folding dynamics (iso-ANCF shells) as FMI 2.0 co-simulation FMUs.
#[derive(Parser, Debug)]
#[command(name = "origami-fmu", version, about)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Write a generated crease pattern (Miura-ori, Kresling, ...) as a FOLD file.
    Pattern(pattern::PatternArgs),
    /// Validate a FOLD scene and print its mesh, variables and warnings.
    Check(check::CheckArgs),
    /// Build an FMI 2.0 co-simulation FMU of a scene.
    Build(build::BuildArgs),
    /// Simulate a scene with the built-in model and write outputs to CSV.
    Simulate(simulate::SimulateArgs),
}

/// Run the CLI with the process arguments.
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    let result: Result<(), String> = match cli.command {
        Command::Pattern(args) => pattern::run(args),
        Command::Check(args) => check::run(args),
        Command::Build(args) => build::run(&args),
        Command::Simulate(args) => simulate::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(msg) => {
            eprintln!("error: {msg}");
            ExitCode::FAILURE
        }
    }
}
