//! `tempera experiment CONFIG.toml`: renders scenes × methods × seeds at equal time against a
//! reference, recording each run's image at every budget and snapshot time, and writes
//! `results.csv`, `results.json`, the images and `report.html` into one output folder.
//!
//! Every run gets all threads and runs alone (under `mpirun`, one rank's threads; the runs are
//! dealt among the ranks: [`run_on`]). A run's record (`runs/SCENE/METHOD/seed-N.json`)
//! is written when it finishes; a later invocation skips runs whose record exists and still
//! describes the same run (method, scene, resolution, times, reference), so an interrupted
//! experiment resumes where it stopped. References are cached the same way.

pub mod config;
mod plot;
mod reference;
mod report;
mod runs;
mod scenes;

use anyhow::{Context, Result};
use clap::Args;
use std::path::PathBuf;
use tempera::cluster::Cluster;

pub use config::Config;

#[derive(Args, Debug)]
pub struct ExperimentArgs {
    /// The experiment file (TOML; keys in the README).
    pub config: PathBuf,
    /// Only rebuild results.csv, results.json and report.html from the finished runs.
    #[arg(long)]
    pub report_only: bool,
    /// No progress bars.
    #[arg(long, short)]
    pub quiet: bool,
    /// Ctrl-C stops the experiment through a signal handler installed here (callers that
    /// watch for it themselves, such as the Python module, set `run::CANCEL` instead).
    #[arg(skip = true)]
    pub handle_interrupts: bool,
}

/// Creates `folder` (and its parents), naming it in the error.
pub(crate) fn create_folder(folder: &std::path::Path) -> Result<()> {
    std::fs::create_dir_all(folder).with_context(|| format!("cannot create the folder {}", folder.display()))
}

pub fn run(args: ExperimentArgs) -> Result<()> {
    run_on(args, &tempera::cluster::SOLO)
}

/// The prefix of the folders in which ranks claim runs.
const CLAIMS: &str = ".claims-";

/// A number that tells this invocation's claims from an earlier one's.
fn claim_token() -> i64 {
    let nanos = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_nanos());
    (nanos as i64 ^ (i64::from(std::process::id()) << 32)) & i64::MAX
}

/// Removes the claim folders an interrupted or failed invocation left behind.
fn remove_old_claims(output: &std::path::Path) {
    let Ok(entries) = std::fs::read_dir(output) else { return };
    for entry in entries.flatten() {
        if entry.file_name().to_string_lossy().starts_with(CLAIMS) {
            let _ = std::fs::remove_dir_all(entry.path());
        }
    }
}

/// Claims run `i` for this rank: true for exactly one rank (the file is created exclusively).
fn claim(claims: &std::path::Path, i: usize) -> Result<bool> {
    let path = claims.join(i.to_string());
    match std::fs::OpenOptions::new().write(true).create_new(true).open(&path) {
        Ok(_) => Ok(true),
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Ok(false),
        Err(e) => Err(anyhow::Error::new(e).context(format!("cannot claim a run in {}", claims.display()))),
    }
}

/// Runs the experiment with the processes of `cluster` (MPI ranks sharing a file system): every
/// reference is rendered once, by all ranks together (rank 0 writes it); each rank then takes
/// the next run no rank has claimed yet, on its own threads (equal time stays equal
/// resources), and writes the records of its runs; rank 0 then reads every record and writes the results and
/// the report. A rank that dies loses its unfinished run only: the next invocation skips every
/// finished one, whichever rank wrote it.
pub fn run_on(args: ExperimentArgs, cluster: &dyn Cluster) -> Result<()> {
    let root = cluster.is_root();
    let config = Config::load(&args.config)?;
    create_folder(&config.output)?;
    if root {
        let stale = tempera_image::remove_stale_partials(&config.output);
        if stale > 0 {
            eprintln!(
                "removed {stale} temporary file(s) that an interrupted experiment left in {}",
                config.output.display()
            );
        }
    }
    // Runs are claimed through files in a folder of this invocation's own (on the shared file
    // system), so a rank takes the next unclaimed run as soon as it is free.
    let mut token = [0_i64];
    if root {
        remove_old_claims(&config.output);
        token[0] = claim_token();
    }
    // The other ranks write nothing before rank 0 has cleaned up.
    cluster.sum(&mut token);
    let claims = config.output.join(format!("{CLAIMS}{}", token[0]));
    if cluster.is_distributed() && root {
        create_folder(&claims)?;
    }
    cluster.barrier();
    if args.handle_interrupts {
        crate::run::install_interrupt_handler();
    }
    let scenes = scenes::prepare_scenes(&config)?;
    let quiet = args.quiet || !root;
    let mut references = Vec::new();
    for scene in &scenes {
        let reference = if args.report_only {
            reference::cached(&config, scene)?
        } else {
            Some(reference::obtain(&config, scene, quiet, cluster)?)
        };
        if reference.is_none() && root {
            eprintln!("{}: no reference yet; skipped in the report", scene.entry.name);
        }
        references.push(reference);
    }
    let total = scenes.len() * config.methods.len() * config.budget.seeds.len();
    let mut jobs = Vec::new();
    for (scene, reference) in scenes.iter().zip(&references) {
        let Some(reference) = reference else { continue };
        for method in &scene.methods {
            for &seed in &config.budget.seeds {
                jobs.push(runs::Job { config: &config, scene, method, seed, reference });
            }
        }
    }
    let mut records = Vec::new();
    for (i, job) in jobs.iter().enumerate() {
        let record = if args.report_only {
            job.existing()
        } else if crate::run::cancelled() || (cluster.is_distributed() && !claim(&claims, i)?) {
            None
        } else {
            job.existing_or_run(i + 1, total, args.quiet)?
        };
        records.extend(record);
    }
    if cluster.is_distributed() && crate::run::cancelled() {
        // Said before the barrier: when a rank died, mpirun ends the job before it is passed.
        eprintln!(
            "rank {}: interrupted (Ctrl-C, or mpirun ending the job because a rank stopped); finished runs are kept: run the same command again to finish the rest",
            cluster.rank()
        );
    }
    if cluster.is_distributed() {
        // Once every rank's records are written, rank 0 reads them all.
        cluster.barrier();
        if !root {
            return Ok(());
        }
        let _ = std::fs::remove_dir_all(&claims);
        records = jobs.iter().filter_map(runs::Job::existing).collect();
    }
    let references: Vec<_> =
        scenes.iter().zip(references).filter_map(|(scene, r)| r.map(|r| (scene.entry.name.clone(), r.image))).collect();
    let rows: Vec<&runs::Row> = records.iter().flat_map(|r| &r.rows).collect();
    runs::write_results(&config, &rows)?;
    let path = report::write(&config, &scenes, &records, &references)?;
    eprintln!("{} runs; results in {}, report {}", records.len(), config.output.display(), path.display());
    if crate::run::cancelled() {
        eprintln!("interrupted: finished runs are kept; run the same command again to finish the rest");
    }
    Ok(())
}
