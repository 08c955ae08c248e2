//! `tempera experiment CONFIG.toml`: renders scenes × methods × seeds at equal time against a
//! reference, recording each run's image at every budget and snapshot time, and writes
//! `results.csv`, `results.json`, the images and `report.html` into one output folder.
//!
//! Every run gets all threads and runs alone. A run's record (`runs/SCENE/METHOD/seed-N.json`)
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
    let config = Config::load(&args.config)?;
    create_folder(&config.output)?;
    let stale = tempera_image::remove_stale_partials(&config.output);
    if stale > 0 {
        eprintln!(
            "removed {stale} temporary file(s) that an interrupted experiment left in {}",
            config.output.display()
        );
    }
    if args.handle_interrupts {
        crate::run::install_interrupt_handler();
    }
    let scenes = scenes::prepare_scenes(&config)?;
    let mut records = Vec::new();
    let mut references = Vec::new();
    let total = scenes.len() * config.methods.len() * config.budget.seeds.len();
    let mut index = 0;
    for scene in &scenes {
        let reference = if args.report_only {
            reference::cached(&config, scene)?
        } else {
            Some(reference::obtain(&config, scene, args.quiet)?)
        };
        let Some(reference) = reference else {
            eprintln!("{}: no reference yet; skipped in the report", scene.entry.name);
            continue;
        };
        for method in &scene.methods {
            for &seed in &config.budget.seeds {
                index += 1;
                let job = runs::Job { config: &config, scene, method, seed, reference: &reference };
                let record = if args.report_only {
                    job.existing()
                } else if crate::run::cancelled() {
                    None
                } else {
                    job.existing_or_run(index, total, args.quiet)?
                };
                records.extend(record);
            }
        }
        references.push((scene.entry.name.clone(), reference.image));
    }
    let rows: Vec<&runs::Row> = records.iter().flat_map(|r| &r.rows).collect();
    runs::write_results(&config, &rows)?;
    let path = report::write(&config, &scenes, &records, &references)?;
    eprintln!("{} runs; results in {}, report {}", records.len(), config.output.display(), path.display());
    if crate::run::cancelled() {
        eprintln!("interrupted: finished runs are kept; run the same command again to finish the rest");
    }
    Ok(())
}
