//! The `tempera` command-line renderer: one module per subcommand (in the `tempera_cli`
//! library).

use clap::{Parser, Subcommand};
use std::process::ExitCode;
use tempera::cluster::Cluster;
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
    // Built with MPI and started by a launcher (`mpirun`, `srun`), every process shares each
    // render; MPI is finalised when `_mpi` is dropped, at the end. Started directly, the
    // process renders alone and never initialises MPI.
    #[cfg(feature = "mpi")]
    let _mpi = match tempera_cli::mpi::launched().then(tempera_cli::mpi::initialise).transpose() {
        Ok(m) => m,
        Err(e) => {
            eprintln!("error: {e:#}");
            return ExitCode::FAILURE;
        }
    };
    #[cfg(feature = "mpi")]
    let cluster: &dyn Cluster = match &_mpi {
        Some((_, mpi)) => mpi,
        None => &tempera::cluster::SOLO,
    };
    #[cfg(not(feature = "mpi"))]
    let cluster: &dyn Cluster = &tempera::cluster::SOLO;
    let result = match cli.command {
        Command::Render(args) => render::run_on(*args, cluster),
        Command::Experiment(args) => experiment::run_on(args, cluster),
        _ if cluster.is_distributed() => {
            if cluster.is_root() {
                Err(anyhow::anyhow!(
                    "only `tempera render` and `tempera experiment` share their work among MPI ranks; run this in one process"
                ))
            } else {
                Err(render::Reported.into())
            }
        }
        Command::Info(args) => info::run(args),
        Command::Compare(args) => compare::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if e.is::<render::Reported>() => ExitCode::FAILURE,
        Err(e) if cluster.is_distributed() && !cluster.is_root() => {
            eprintln!("error (rank {}): {e:#}", cluster.rank());
            ExitCode::FAILURE
        }
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
