//! The runs of an experiment: one render per (scene, method, seed) whose images at every
//! recorded time are compared with the reference.

use super::config::Config;
use super::reference::Reference;
use super::scenes::{PreparedMethod, PreparedScene};
use crate::run::Job as RenderJob;
use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Duration;
use tempera::integrator::{Budget, RenderOutput, RenderSettings, RunStats};
use tempera::mcmc::DepthStats;
use tempera_image::metrics;
use tempera_image::{WriteOptions, write_image};

/// One line of results: a run's image at one time, compared with the reference.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Row {
    pub scene: String,
    pub method: String,
    pub seed: u64,
    /// The recorded time (a budget or a snapshot), seconds.
    pub time: f64,
    /// When the image was actually taken, seconds after the render started.
    pub seconds: f64,
    pub mse: f64,
    pub rmse: f64,
    pub relmse: f64,
    pub smape: f64,
    pub flip: f64,
    pub mean_ratio: f64,
    /// Samples (path tracing, BDPT) or main-chain mutations (MCMC) per pixel.
    pub samples_per_pixel: f64,
    /// Markov-chain acceptance over all depths (MCMC only).
    pub acceptance: Option<f64>,
    /// Neighbour-swap acceptance over all depths (tempered MMLT only).
    pub neighbor_acceptance: Option<f64>,
    /// The image files of this row (relative to the output folder), when it was a budget.
    pub image: Option<String>,
    /// The render statistics, as `tempera render --stats` writes them.
    pub stats: RunStats,
}

/// A finished run: what it was and its rows.
#[derive(Debug, Serialize, Deserialize)]
pub struct Record {
    pub key: serde_json::Value,
    pub rows: Vec<Row>,
}

/// Every depth's chain statistics merged into one row.
fn merged(chains: &[DepthStats]) -> DepthStats {
    let mut all = DepthStats::default();
    for d in chains {
        all.merge(d);
    }
    all
}

fn acceptance(all: &DepthStats) -> Option<f64> {
    (all.large_steps_proposed + all.small_steps_proposed > 0).then(|| all.acceptance())
}

fn neighbor_acceptance(all: &DepthStats) -> Option<f64> {
    all.swaps.as_ref().filter(|s| s.neighbor_counts().0 > 0).map(|s| s.neighbor_acceptance())
}

/// A time as it appears in file names: `10`, `0.5`.
pub fn time_label(t: f64) -> String {
    format!("{t}")
}

/// One (scene, method, seed) of an experiment.
pub struct Job<'a> {
    pub config: &'a Config,
    pub scene: &'a PreparedScene,
    pub method: &'a PreparedMethod,
    pub seed: u64,
    pub reference: &'a Reference,
}

impl Job<'_> {
    fn record_path(&self) -> PathBuf {
        self.config
            .output
            .join("runs")
            .join(&self.scene.entry.name)
            .join(&self.method.method.name)
            .join(format!("seed-{}.json", self.seed))
    }

    /// Everything that decides what the run computes: a record with another key is stale.
    fn key(&self) -> serde_json::Value {
        let film = &self.scene.scene.film;
        serde_json::json!({
            "tempera": env!("CARGO_PKG_VERSION"),
            "integrator": self.method.method.integrator,
            "settings": self.method.method.settings,
            "scene_file": self.scene.entry.file.as_ref().map(|p| p.display().to_string()),
            "resolution": [film.width, film.height],
            "maxdepth": self.scene.scene.defaults.max_depth,
            "times": self.config.times(),
            "budgets": self.config.budget.seconds,
            "samples": self.config.budget.samples,
            "seed": self.seed,
            "reference": self.reference.key,
        })
    }

    /// The run's record if it exists and describes this run.
    pub fn existing(&self) -> Option<Record> {
        let text = std::fs::read_to_string(self.record_path()).ok()?;
        let record: Record = serde_json::from_str(&text).ok()?;
        (record.key == self.key()).then_some(record)
    }

    /// The existing record, or a fresh render (`None` when Ctrl-C stopped it).
    pub fn existing_or_run(&self, index: usize, total: usize, quiet: bool) -> Result<Option<Record>> {
        let label =
            format!("[{index}/{total}] {} · {} · seed {}", self.scene.entry.name, self.method.method.name, self.seed);
        if let Some(record) = self.existing() {
            eprintln!("{label}: finished earlier");
            return Ok(Some(record));
        }
        let record = self.render(&label, quiet)?;
        if let Some(record) = &record {
            let path = self.record_path();
            super::create_folder(path.parent().expect("record paths have a folder"))?;
            let text = serde_json::to_string_pretty(record).expect("records serialise");
            tempera_image::write_file_atomically(&path, text.as_bytes())
                .with_context(|| format!("cannot write {}", path.display()))?;
            if let Some(last) = record.rows.last() {
                eprintln!(
                    "{label}: relMSE {:.4e}, FLIP {:.4}, {:.1} samples or mutations/pixel in {:.1} s",
                    last.relmse, last.flip, last.samples_per_pixel, last.seconds
                );
            }
        }
        Ok(record)
    }

    fn render(&self, label: &str, quiet: bool) -> Result<Option<Record>> {
        if self.config.fixed() {
            return self.render_fixed(label, quiet);
        }
        let times = self.config.times();
        let longest = *times.last().expect("a budget exists");
        let snapshot_times: Vec<Duration> =
            times[..times.len() - 1].iter().map(|&t| Duration::from_secs_f64(t)).collect();
        let taken: Mutex<Vec<(usize, RenderOutput)>> = Mutex::new(Vec::new());
        let on_snapshot = |i: usize, out: &RenderOutput| {
            taken.lock().unwrap_or_else(std::sync::PoisonError::into_inner).push((i, out.clone()));
        };
        let budget = Budget::Time(Duration::from_secs_f64(longest));
        let settings = RenderSettings { budget, seed: self.seed, threads: self.config.threads };
        let integrator = self.method.integrator.as_ref();
        let out = RenderJob {
            label: Some(label),
            snapshots: &snapshot_times,
            on_snapshot: &on_snapshot,
            ..RenderJob::new(&self.scene.scene, integrator, settings, quiet)
        }
        .run()
        .with_context(|| label.to_owned())?;
        if out.stats.cancelled {
            eprintln!("{label}: interrupted; not recorded");
            return Ok(None);
        }
        let mut taken = taken.into_inner().unwrap_or_else(std::sync::PoisonError::into_inner);
        taken.push((times.len() - 1, out));
        let mut rows = Vec::new();
        for (i, output) in &taken {
            rows.push(self.row(times[*i], output, integrator.name())?);
        }
        Ok(Some(Record { key: self.key(), rows }))
    }

    /// One render per per-pixel budget (`[budget] samples`).
    fn render_fixed(&self, label: &str, quiet: bool) -> Result<Option<Record>> {
        let integrator = self.method.integrator.as_ref();
        let mut rows = Vec::new();
        for &n in &self.config.budget.samples {
            let settings = RenderSettings { budget: Budget::Samples(n), seed: self.seed, threads: self.config.threads };
            let out =
                RenderJob { label: Some(label), ..RenderJob::new(&self.scene.scene, integrator, settings, quiet) }
                    .run()
                    .with_context(|| label.to_owned())?;
            if out.stats.cancelled {
                eprintln!("{label}: interrupted; not recorded");
                return Ok(None);
            }
            rows.push(self.row(f64::from(n), &out, integrator.name())?);
        }
        Ok(Some(Record { key: self.key(), rows }))
    }

    fn row(&self, time: f64, out: &RenderOutput, integrator: &str) -> Result<Row> {
        let c = metrics::compare(&out.image, &self.reference.image).map_err(anyhow::Error::msg)?;
        let pixels = f64::from(self.scene.scene.film.width) * f64::from(self.scene.scene.film.height);
        let all = merged(&out.chains);
        let image = if self.config.budgets().contains(&time) { Some(self.write_images(time, out)?) } else { None };
        Ok(Row {
            scene: self.scene.entry.name.clone(),
            method: self.method.method.name.clone(),
            seed: self.seed,
            time,
            seconds: out.stats.seconds,
            mse: c.mse,
            rmse: c.rmse,
            relmse: c.relmse,
            smape: c.smape,
            flip: c.flip,
            mean_ratio: c.mean_ratio,
            samples_per_pixel: out.stats.pixel_samples as f64 / pixels.max(1.0),
            acceptance: acceptance(&all),
            neighbor_acceptance: neighbor_acceptance(&all),
            image,
            stats: RunStats::new(integrator, out),
        })
    }

    /// Writes the image (EXR and PNG) and its relMSE and FLIP maps; returns the stem of the
    /// files, relative to the output folder.
    fn write_images(&self, time: f64, out: &RenderOutput) -> Result<String> {
        let stem = image_stem(self.config, &self.scene.entry.name, &self.method.method.name, self.seed, time);
        let base = self.config.output.join(&stem);
        super::create_folder(base.parent().expect("image paths have a folder"))?;
        let options = WriteOptions::default();
        let with = |suffix: &str| PathBuf::from(format!("{}{suffix}", base.display()));
        write_image(&with(".exr"), &out.image, &options)?;
        write_image(&with(".png"), &out.image, &options)?;
        let reference = &self.reference.image;
        let relmse = metrics::error_map(&out.image, reference).map_err(anyhow::Error::msg)?;
        write_image(&with("-relmse.png"), &relmse, &options)?;
        let flip = metrics::flip_error_map(&out.image, reference).map_err(anyhow::Error::msg)?;
        write_image(&with("-flip.png"), &flip, &options)?;
        Ok(stem)
    }
}

/// Where the images of a run at budget `time` go, relative to the output folder, without suffix.
pub fn image_stem(config: &Config, scene: &str, method: &str, seed: u64, time: f64) -> String {
    format!("images/{scene}/{method}/seed-{seed}-{}{}", time_label(time), config.unit())
}

fn csv_field(v: Option<f64>) -> String {
    v.map_or_else(String::new, |v| format!("{v}"))
}

/// `results.csv` (one row per run and time, no statistics) and `results.json` (rows with the
/// statistics).
pub fn write_results(config: &Config, rows: &[&Row]) -> Result<()> {
    let mut csv = String::from(
        "scene,method,seed,time,seconds,mse,rmse,relmse,smape,flip,mean_ratio,samples_per_pixel,acceptance,neighbor_acceptance\n",
    );
    for r in rows {
        csv.push_str(&format!(
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n",
            r.scene,
            r.method,
            r.seed,
            r.time,
            r.seconds,
            r.mse,
            r.rmse,
            r.relmse,
            r.smape,
            r.flip,
            r.mean_ratio,
            r.samples_per_pixel,
            csv_field(r.acceptance),
            csv_field(r.neighbor_acceptance)
        ));
    }
    let write = |name: &str, text: &str| {
        let path: &Path = &config.output.join(name);
        tempera_image::write_file_atomically(path, text.as_bytes())
            .with_context(|| format!("cannot write {}", path.display()))
    };
    write("results.csv", &csv)?;
    write("results.json", &serde_json::to_string_pretty(rows).expect("rows serialise"))
}
