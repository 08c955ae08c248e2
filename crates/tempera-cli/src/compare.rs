//! `tempera compare IMAGE REFERENCE`: error metrics of an image against a reference, the ratio
//! of their mean luminances, and optionally a false-colour error map (relMSE or FLIP).

use anyhow::{Context, Result, bail};
use clap::Args;
use std::path::{Path, PathBuf};
use tempera_image::metrics::{self, METRICS};
use tempera_image::{ColorEncoding, WriteOptions, read_image, write_image};

#[derive(Args, Debug)]
pub struct CompareArgs {
    /// The image to judge (EXR or PFM).
    pub image: PathBuf,
    /// The reference (EXR or PFM).
    pub reference: PathBuf,
    /// Metrics to print (default: all).
    #[arg(long, value_parser = METRICS.to_vec())]
    pub metric: Vec<String>,
    /// Write a false-colour error map with a legend (PNG, EXR or PFM): the per-pixel FLIP error
    /// when the first `--metric` is flip, else the per-pixel relMSE.
    #[arg(long, value_name = "FILE.png")]
    pub error_map: Option<PathBuf>,
}

fn read(path: &Path) -> Result<tempera::texture::Image> {
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    if !matches!(ext.as_deref(), Some("exr" | "pfm")) {
        bail!("{}: expected an EXR or PFM image (linear radiance)", path.display());
    }
    read_image(path, ColorEncoding::Linear).with_context(|| format!("cannot read {}", path.display()))
}

pub fn run(args: CompareArgs) -> Result<()> {
    let (image, reference) = (read(&args.image)?, read(&args.reference)?);
    let c = metrics::compare(&image, &reference).map_err(anyhow::Error::msg)?;
    let names: Vec<&str> =
        if args.metric.is_empty() { METRICS.to_vec() } else { args.metric.iter().map(String::as_str).collect() };
    for name in names {
        let value = c.get(name).expect("metric names are validated by clap");
        println!("{name:7} {value:.6e}");
    }
    println!("mean ratio {:.6}", c.mean_ratio);
    if let Some(path) = &args.error_map {
        let map = if args.metric.first().is_some_and(|m| m == "flip") {
            metrics::flip_error_map(&image, &reference)
        } else {
            metrics::error_map(&image, &reference)
        };
        let map = map.map_err(anyhow::Error::msg)?;
        write_image(path, &map, &WriteOptions::default())
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    Ok(())
}
