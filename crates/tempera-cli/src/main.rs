//! The `tempera` command-line renderer: one module per subcommand (in the `tempera_cli`
//! library).

use clap::{Parser, Subcommand};
use std::process::ExitCode;
use tempera_cli::{compare, experiment, info, render};

#[derive(Parser)]
#[command(name = "tempera", version, about = "Physically based rendering with tempered Markov-chain light transport")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene (the embedded default scene when none is given).
    Render(Box<render::RenderArgs>),
    /// Describe what a scene file contains once loaded.
    Info(info::InfoArgs),
    /// Compare an image with a reference: MSE, RMSE, relMSE, SMAPE, ratio of means, error map.
    Compare(compare::CompareArgs),
    /// Render scenes with several methods at equal time against a reference; write images,
    /// results.csv, results.json and report.html.
    Experiment(experiment::ExperimentArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Render(args) => render::run(*args),
        Command::Info(args) => info::run(args),
        Command::Compare(args) => compare::run(args),
        Command::Experiment(args) => experiment::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
