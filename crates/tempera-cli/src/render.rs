//! `tempera render`: load (or build) a scene, render it with the chosen integrator under a sample
//! or time budget, and write the image in the formats the output names ask for. Ctrl-C stops the
//! render and still writes what was rendered.

use crate::flags::{IntegratorFlags, parse_resolution, parse_seconds};
use crate::run::{self, Job};
use crate::scene::{self, Loaded};
use anyhow::{Context, Result, bail};
use clap::Args;
use std::path::{Path, PathBuf};
use std::time::Duration;
use tempera::accel::AccelKind;
use tempera::cluster::Cluster;
use tempera::integrator::{self, Budget, IntegratorKind, IntegratorSettings, RenderSettings, RunStats};
use tempera::scene::Scene;
use tempera_image::{WriteOptions, write_image};

#[derive(Args, Debug)]
pub struct RenderArgs {
    /// Scene file (.pbrt or .xml); omitted renders the embedded default scene.
    pub scene: Option<PathBuf>,
    /// Light-transport algorithm (default: the scene's, else path).
    #[arg(long, value_enum)]
    pub integrator: Option<IntegratorKind>,
    /// Samples per pixel (SPPM: iterations; default: the scene's).
    #[arg(long, conflicts_with = "time", value_parser = clap::value_parser!(u32).range(1..))]
    pub spp: Option<u32>,
    /// MCMC integrators: mutations per pixel (deterministic for a seed at any thread count).
    #[arg(long, conflicts_with_all = ["spp", "time"], value_parser = clap::value_parser!(u32).range(1..))]
    pub mpp: Option<u32>,
    /// Render for this many seconds instead of a fixed sample count.
    #[arg(long, value_parser = parse_seconds, allow_hyphen_values = true)]
    pub time: Option<f64>,
    /// Seed of every random number of the render.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Worker threads (0: all cores).
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    /// Film resolution WIDTHxHEIGHT, overriding the scene's (the field of view keeps spanning the
    /// shorter axis).
    #[arg(long, value_parser = parse_resolution)]
    pub resolution: Option<(u32, u32)>,
    /// Output image(s): .exr, .pfm or .png (repeatable). Default: tempera.exr and tempera.png.
    #[arg(short, long = "output")]
    pub output: Vec<PathBuf>,
    /// Exposure in stops for PNG output.
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub exposure: f32,
    /// No progress bar and no summary.
    #[arg(long, short)]
    pub quiet: bool,
    /// Write render statistics (per-depth chain statistics for MCMC integrators) as JSON.
    #[arg(long, value_name = "FILE.json")]
    pub stats: Option<PathBuf>,
    /// BDPT: write one EXR per strategy (s, t) with its MIS-weighted contribution into DIR.
    #[arg(long, value_name = "DIR")]
    pub strategy_images: Option<PathBuf>,
    /// MMLT and tempered MMLT: write one EXR per path depth (`depth0.exr`, …), each that
    /// depth's share of the image, into DIR.
    #[arg(long, value_name = "DIR")]
    pub depth_images: Option<PathBuf>,
    #[command(flatten)]
    pub integrator_flags: IntegratorFlags,
    /// Treat scene-loading warnings (unknown directives, unused parameters, approximations) as
    /// errors.
    #[arg(long)]
    pub strict: bool,
    /// The ray-tracing accelerator: Tempera's BVH, or Intel Embree (builds with the `embree`
    /// feature).
    #[arg(long, value_enum, default_value_t = AccelKind::Bvh)]
    pub accel: AccelKind,
    /// The most memory the render may take, in GiB (default: what the machine has available);
    /// a render whose buffers would need more refuses to start.
    #[arg(long, value_name = "GIB", value_parser = parse_gib)]
    pub max_memory: Option<u64>,
}

/// A positive size in GiB, as bytes.
fn parse_gib(s: &str) -> Result<u64, String> {
    match s.parse::<f64>() {
        Ok(g) if g.is_finite() && g > 0.0 && g < 1.0e9 => Ok((g * (1u64 << 30) as f64) as u64),
        _ => Err(format!("expected a positive number of GiB, got '{s}'")),
    }
}

/// Checks the requested output files before any work is done.
fn check_outputs(paths: &[PathBuf]) -> Result<()> {
    for path in paths {
        if tempera_image::Format::from_path(path).is_none() {
            bail!("{}: unsupported output format (expected .exr, .pfm or .png)", path.display());
        }
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty())
            && !dir.is_dir()
        {
            bail!("{}: folder {} does not exist", path.display(), dir.display());
        }
    }
    Ok(())
}

/// Output files: `-o` if given, else the scene's film file name, else tempera.exr and tempera.png.
fn outputs(args: &RenderArgs, scene: &Scene) -> Vec<PathBuf> {
    if !args.output.is_empty() {
        return args.output.clone();
    }
    match &scene.defaults.output {
        Some(name) if tempera_image::Format::from_path(name).is_some() => vec![name.clone()],
        _ => vec![PathBuf::from("tempera.exr"), PathBuf::from("tempera.png")],
    }
}

/// The integrator to use: the command line's, else the scene's when Tempera has it, else path.
fn integrator_kind(args: &RenderArgs, loaded: &Loaded) -> IntegratorKind {
    if let Some(kind) = args.integrator {
        return kind;
    }
    if let Some(kind) = loaded.scene.defaults.integrator {
        return kind;
    }
    if let Some(name) = loaded.info.as_ref().and_then(|i| i.integrator.as_ref()) {
        eprintln!("warning: the scene asks for integrator \"{name}\", which is not available; using path");
    }
    IntegratorKind::Path
}

/// An error that rank 0 has already reported for every rank: the other ranks exit without
/// repeating it.
#[derive(Debug)]
pub struct Reported;

impl std::fmt::Display for Reported {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("reported by rank 0")
    }
}

impl std::error::Error for Reported {}

pub fn run(args: RenderArgs) -> Result<()> {
    run_on(args, &tempera::cluster::SOLO)
}

/// Loads the scene on every rank; every rank stops with rank 0's message when any rank could
/// not (instead of waiting for it in the first exchange).
fn load_everywhere(args: &RenderArgs, cluster: &dyn Cluster) -> Result<Loaded> {
    let loaded = scene::load(args.scene.as_deref(), args.strict, args.accel);
    if !cluster.is_distributed() {
        return loaded;
    }
    let message = loaded.as_ref().err().map(|e| format!("{e:#}")).unwrap_or_default();
    let messages = cluster.gather(message.into_bytes());
    let first = messages.iter().enumerate().find(|(_, m)| !m.is_empty());
    let failed = cluster.broadcast(first.is_some());
    if !failed {
        return loaded;
    }
    match first {
        Some((0, m)) => bail!("{}", String::from_utf8_lossy(m)),
        Some((rank, m)) => bail!("rank {rank} could not load the scene: {}", String::from_utf8_lossy(m)),
        None => Err(Reported.into()),
    }
}

/// Renders with the work shared among the processes of `cluster`; rank 0 writes the image(s),
/// the statistics and the summary.
pub fn run_on(args: RenderArgs, cluster: &dyn Cluster) -> Result<()> {
    check_outputs(&args.output)?;
    let root = cluster.is_root();
    let loaded = load_everywhere(&args, cluster)?;
    if root {
        scene::print_warnings(&loaded.warnings, 20);
    }
    let kind = integrator_kind(&args, &loaded);
    let mut scene = loaded.scene;
    if let Some((w, h)) = args.resolution {
        scene.set_resolution(w, h);
    }
    let outputs = outputs(&args, &scene);
    if args.strategy_images.is_some() && kind != IntegratorKind::Bdpt {
        bail!("--strategy-images needs --integrator bdpt");
    }
    if args.depth_images.is_some() && !matches!(kind, IntegratorKind::Mmlt | IntegratorKind::Tempered) {
        bail!("--depth-images needs --integrator mmlt or tempered");
    }
    let settings = IntegratorSettings {
        strategy_images: args.strategy_images.is_some(),
        depth_images: args.depth_images.is_some(),
        ..args.integrator_flags.settings()
    };
    let integrator =
        integrator::create(kind, &settings, &scene.defaults).map_err(|e| anyhow::anyhow!("{kind}: {e}"))?;
    let budget = match args.time {
        Some(t) => Budget::Time(Duration::from_secs_f64(t)),
        None => Budget::Samples(args.mpp.or(args.spp).unwrap_or(scene.defaults.per_pixel(kind))),
    };
    let render_settings = RenderSettings { budget, seed: args.seed, threads: args.threads };
    run::install_interrupt_handler();
    let quiet = args.quiet || !root;
    let job =
        Job { max_memory: args.max_memory, cluster, ..Job::new(&scene, integrator.as_ref(), render_settings, quiet) };
    let out = job.run()?;
    let traffic = cluster.gather(cluster.bytes_sent().to_le_bytes().to_vec());
    if !root {
        return Ok(());
    }
    let bytes_sent: Vec<u64> = if cluster.is_distributed() {
        traffic.iter().map(|b| u64::from_le_bytes(b[..8].try_into().unwrap_or([0; 8]))).collect()
    } else {
        Vec::new()
    };

    let options = WriteOptions { exposure: args.exposure };
    for path in &outputs {
        write_image(path, &out.image, &options)?;
    }
    if let Some(dir) = args.strategy_images.as_ref().or(args.depth_images.as_ref()) {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
        for (name, layer) in integrator.layer_names().iter().zip(&out.layers) {
            write_image(&dir.join(format!("{name}.exr")), layer, &options)?;
        }
    }
    let stats = RunStats { ranks: cluster.size(), bytes_sent, ..RunStats::new(integrator.name(), &out) };
    if !args.quiet {
        summary(&args, &scene, integrator.name(), &out.stats, &outputs, !out.chains.is_empty());
        crate::stats::print_table(&stats);
    }
    if let Some(path) = &args.stats {
        crate::stats::write(path, &stats)?;
    }
    Ok(())
}
fn summary(
    args: &RenderArgs,
    scene: &Scene,
    name: &str,
    s: &tempera::integrator::RenderStats,
    outputs: &[PathBuf],
    mcmc: bool,
) {
    let names: Vec<_> = outputs.iter().map(|p| p.display().to_string()).collect();
    let scene_name =
        args.scene.as_deref().map_or_else(|| "default scene".to_owned(), |p: &Path| p.display().to_string());
    let pixels = f64::from(scene.film.width) * f64::from(scene.film.height);
    let spp = s.pixel_samples as f64 / pixels;
    let status = if s.cancelled { "interrupted: " } else { "" };
    let (per_pixel, per_second) = if mcmc { ("mutations/pixel", "Mmutations/s") } else { ("spp", "Msamples/s") };
    eprintln!(
        "{status}{scene_name} ({}x{}) with {name}: {spp:.1} {per_pixel} in {:.2} s, {:.2} Mrays/s, {:.2} {per_second} -> {}",
        scene.film.width,
        scene.film.height,
        s.seconds,
        s.rays as f64 / s.seconds.max(1e-9) / 1e6,
        s.pixel_samples as f64 / s.seconds.max(1e-9) / 1e6,
        names.join(", ")
    );
    if s.invalid_samples > 0 {
        eprintln!("warning: {} samples were NaN, infinite or negative and were recorded as black", s.invalid_samples);
    }
}
