//! `tempera render`: load (or build) a scene, render it with the chosen integrator under a sample
//! or time budget, and write the image in the formats the output names ask for. Ctrl-C stops the
//! render and still writes what was rendered.

use anyhow::{Context, Result, bail};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};
use tempera::bidir::Heuristic;
use tempera::integrator::{self, Budget, RenderControl, RenderSettings};
use tempera::scene::Scene;
use tempera_image::{WriteOptions, write_image};

use crate::scene;

#[derive(Args, Debug)]
pub struct RenderArgs {
    /// Scene file (.pbrt or .xml); omitted renders the embedded default scene.
    pub scene: Option<PathBuf>,
    /// Light-transport algorithm (default: the scene's, else path).
    #[arg(long, value_parser = clap::builder::PossibleValuesParser::new(integrator::INTEGRATORS))]
    pub integrator: Option<String>,
    /// Samples per pixel (default: the scene's).
    #[arg(long, conflicts_with = "time", value_parser = clap::value_parser!(u32).range(1..))]
    pub spp: Option<u32>,
    /// MCMC integrators: mutations per pixel (deterministic for a seed at any thread count).
    #[arg(long, conflicts_with_all = ["spp", "time"], value_parser = clap::value_parser!(u32).range(1..))]
    pub mpp: Option<u32>,
    /// MMLT: bootstrap samples per path depth.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=100_000_000))]
    pub bootstrap: Option<u64>,
    /// MMLT: independent chains per path depth.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=1_000_000))]
    pub chains: Option<u64>,
    /// MMLT: probability of a large step.
    #[arg(long, value_parser = parse_probability)]
    pub large_step: Option<f32>,
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
    /// Maximum number of scattering events per path (pbrt's maxdepth; default: the scene's).
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=100_000))]
    pub maxdepth: Option<u32>,
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
    /// BDPT: multiple importance sampling heuristic.
    #[arg(long, default_value = "power", value_parser = ["power", "balance"])]
    pub mis: String,
    /// BDPT: write one EXR per strategy (s, t) with its MIS-weighted contribution into DIR.
    #[arg(long, value_name = "DIR")]
    pub strategy_images: Option<PathBuf>,
    /// Tempered MMLT: replicas per ensemble (default 5; 1 is plain MMLT).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=32))]
    pub replicas: Option<u64>,
    /// Tempered MMLT: how replicas exchange states.
    #[arg(long, default_value = "neighbor", value_parser = tempera::integrator::Swap::NAMES.to_vec())]
    pub swap: String,
    /// Tempered MMLT: fixed roughening ladder a1,a2,… of replicas 1 … K−1 (increasing, positive).
    #[arg(long, value_parser = parse_ladder)]
    pub ladder: Option<Ladder>,
    /// Tempered MMLT: burn-in sweeps that tune each depth's shared ladder (0: keep the
    /// default ladder untuned; ignored with --ladder).
    #[arg(long, value_parser = clap::value_parser!(u64).range(0..=10_000_000))]
    pub burn_in: Option<u64>,
    /// Tempered MMLT: neighbour-swap acceptance the ladder tuning aims at.
    #[arg(long, value_parser = parse_probability)]
    pub swap_target: Option<f32>,
    /// Tempered MMLT: MIS weights of tempered replicas from the roughened or the original
    /// densities.
    #[arg(long, default_value = "original", value_parser = ["roughened", "original"])]
    pub tempered_mis: String,
    /// Tempered MMLT: every replica contributes to the image, weighted by the balance heuristic
    /// over the replicas' normalised targets (the default).
    #[arg(long, overrides_with = "no_reuse_replicas")]
    pub reuse_replicas: bool,
    /// Tempered MMLT: replica 0 alone writes the image (as in Šik & Křivánek 2016).
    #[arg(long, overrides_with = "reuse_replicas")]
    pub no_reuse_replicas: bool,
    /// Tempered MMLT: sweeps (one mutation per replica) between swap steps.
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..=1_000_000))]
    pub swap_every: Option<u64>,
    /// Treat scene-loading warnings (unknown directives, unused parameters, approximations) as
    /// errors.
    #[arg(long)]
    pub strict: bool,
}

fn parse_seconds(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("expected a positive number of seconds, got '{s}'")),
    }
}

fn parse_probability(s: &str) -> Result<f32, String> {
    match s.parse::<f32>() {
        Ok(v) if v > 0.0 && v <= 1.0 => Ok(v),
        _ => Err(format!("expected a probability in (0, 1], got '{s}'")),
    }
}

/// A roughening ladder from the command line.
#[derive(Clone, Debug)]
pub struct Ladder(pub Vec<f32>);

fn parse_ladder(s: &str) -> Result<Ladder, String> {
    let values: Result<Vec<f32>, _> = s.split(',').map(|v| v.trim().parse::<f32>()).collect();
    let values = values.map_err(|_| format!("expected comma-separated numbers such as 0.02,0.06,0.18, got '{s}'"))?;
    if values.is_empty() || values.iter().any(|v| !v.is_finite() || *v <= 0.0 || *v > 10.0) {
        return Err(format!("ladder values must lie in (0, 10], got '{s}'"));
    }
    if values.windows(2).any(|w| w[1] <= w[0]) {
        return Err(format!("ladder values must increase, got '{s}'"));
    }
    Ok(Ladder(values))
}

pub fn parse_resolution(s: &str) -> Result<(u32, u32), String> {
    let err = || format!("expected WIDTHxHEIGHT such as 640x480, got '{s}'");
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(err)?;
    let (w, h): (u32, u32) = (w.trim().parse().map_err(|_| err())?, h.trim().parse().map_err(|_| err())?);
    if w == 0 || h == 0 || w > 65_536 || h > 65_536 {
        return Err(format!("resolution must be between 1x1 and 65536x65536, got '{s}'"));
    }
    Ok((w, h))
}

pub static CANCEL: AtomicBool = AtomicBool::new(false);

/// Ctrl-C asks the render to stop and write what it has; a second Ctrl-C exits at once.
pub fn install_interrupt_handler() {
    let installed = ctrlc::set_handler(|| {
        if CANCEL.swap(true, Ordering::SeqCst) {
            std::process::exit(130);
        }
    });
    if let Err(e) = installed {
        eprintln!("warning: Ctrl-C will not stop the render cleanly: {e}");
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
        Some(name) if tempera_image::Format::from_path(Path::new(name)).is_some() => vec![PathBuf::from(name)],
        _ => vec![PathBuf::from("tempera.exr"), PathBuf::from("tempera.png")],
    }
}

/// The integrator to use: the command line's, else the scene's when Tempera has it, else path.
pub fn integrator_name(args: &RenderArgs, scene: &Scene) -> String {
    if let Some(name) = &args.integrator {
        return name.clone();
    }
    match &scene.defaults.integrator {
        Some(name) if integrator::INTEGRATORS.contains(&name.as_str()) => name.clone(),
        Some(name) => {
            eprintln!("warning: the scene asks for integrator \"{name}\", which is not available; using path");
            "path".to_owned()
        }
        None => "path".to_owned(),
    }
}

/// A progress bar for a render of `pixels` pixels under `budget`, labelled `label` when given;
/// hidden when `quiet` or when standard error is not a terminal.
pub fn progress_bar(quiet: bool, budget: Budget, pixels: u64, label: Option<&str>) -> ProgressBar {
    if quiet || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let (len, template) = match budget {
        Budget::Samples(spp) => {
            (pixels * u64::from(spp), "{prefix}{elapsed_precise} [{wide_bar}] {percent}% (eta {eta})")
        }
        Budget::Time(d) => (d.as_millis() as u64, "{prefix}{elapsed_precise} [{wide_bar}] {msg}"),
    };
    let bar = ProgressBar::new(len);
    bar.set_style(ProgressStyle::with_template(template).expect("valid template").progress_chars("=> "));
    if let Some(label) = label {
        bar.set_prefix(format!("{label} "));
    }
    bar
}

/// Moves `bar` on for `n` more pixel samples (sample budgets) or to the time elapsed since
/// `start` (time budgets): what a render's progress callback does.
pub fn advance(bar: &ProgressBar, budget: Budget, start: Instant, n: u64) {
    match budget {
        Budget::Samples(_) => bar.inc(n),
        Budget::Time(_) => bar.set_position(start.elapsed().as_millis() as u64),
    }
}

/// The integrator `name` with the options `args` give (the scene's maximum depth unless
/// `--maxdepth` overrides it).
pub fn build_integrator(args: &RenderArgs, scene: &Scene, name: &str) -> Result<Box<dyn integrator::Integrator>> {
    let max_depth = args.maxdepth.unwrap_or(scene.defaults.max_depth);
    let heuristic = if args.mis == "balance" { Heuristic::Balance } else { Heuristic::Power };
    // A ladder fixes the number of replicas; both given must agree.
    let replicas = match (args.replicas, &args.ladder) {
        (Some(r), Some(l)) if r as usize != l.0.len() + 1 => {
            bail!("--ladder gives {} values, so --replicas must be {} (it is {r})", l.0.len(), l.0.len() + 1)
        }
        (Some(r), _) => r as usize,
        (None, Some(l)) => l.0.len() + 1,
        (None, None) => 0,
    };
    if args.swap == "permutation" && replicas > tempera::integrator::tempered::Permutation::MAX_REPLICAS {
        bail!(
            "--swap permutation enumerates all K! permutations: use at most {} replicas",
            tempera::integrator::tempered::Permutation::MAX_REPLICAS
        );
    }
    let options = integrator::IntegratorOptions {
        max_depth,
        strategy_images: args.strategy_images.is_some(),
        heuristic,
        bootstrap: args.bootstrap.unwrap_or(0) as usize,
        chains: args.chains.unwrap_or(0) as usize,
        large_step: args.large_step,
        replicas,
        swap: tempera::integrator::Swap::parse(&args.swap).unwrap_or_default(),
        ladder: args.ladder.as_ref().map_or_else(Vec::new, |l| l.0.clone()),
        roughen_mis: Some(args.tempered_mis == "roughened"),
        burn_in: args.burn_in,
        swap_target: args.swap_target.map(f64::from),
        reuse_replicas: if args.reuse_replicas {
            Some(true)
        } else if args.no_reuse_replicas {
            Some(false)
        } else {
            None
        },
        swap_every: args.swap_every,
    };
    integrator::create(name, &options).with_context(|| format!("unknown integrator '{name}'"))
}

pub fn run(args: RenderArgs) -> Result<()> {
    check_outputs(&args.output)?;
    let loaded = scene::load(args.scene.as_deref(), args.strict)?;
    scene::print_warnings(&loaded.warnings, 20);
    let mut scene = loaded.scene;
    if let Some((w, h)) = args.resolution {
        scene.set_resolution(w, h);
    }
    let outputs = outputs(&args, &scene);
    let name = integrator_name(&args, &scene);
    if args.strategy_images.is_some() && name != "bdpt" {
        bail!("--strategy-images needs --integrator bdpt");
    }
    let integrator = build_integrator(&args, &scene, &name)?;
    let budget = match args.time {
        Some(t) => Budget::Time(Duration::from_secs_f64(t)),
        None => Budget::Samples(args.mpp.or(args.spp).unwrap_or(scene.defaults.spp)),
    };
    let settings = RenderSettings { budget, seed: args.seed, threads: args.threads };
    let pixels = u64::from(scene.film.width) * u64::from(scene.film.height);
    let bar = progress_bar(args.quiet, budget, pixels, None);
    let start = Instant::now();
    let on_progress = |n: u64| advance(&bar, budget, start, n);
    install_interrupt_handler();
    let control = RenderControl::new(&CANCEL, &on_progress);
    let out = integrator.render(&scene, &settings, &control).map_err(anyhow::Error::msg)?;
    bar.finish_and_clear();

    let options = WriteOptions { exposure: args.exposure };
    for path in &outputs {
        write_image(path, &out.image, &options)?;
    }
    if let Some(dir) = &args.strategy_images {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
        for (name, layer) in integrator.layer_names().iter().zip(&out.layers) {
            write_image(&dir.join(format!("{name}.exr")), layer, &options)?;
        }
    }
    if !args.quiet {
        summary(&args, &scene, integrator.name(), &out.stats, &outputs, !out.chains.is_empty());
        crate::stats::print_table(&out);
    }
    if let Some(path) = &args.stats {
        crate::stats::write(path, integrator.name(), &out)?;
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
