//! Equal-time comparison of the path tracer, BDPT, MMLT and PSSMLT against a long BDPT reference, printing
//! relMSE = mean((I − R)² / (R² + ε)) on luminance with ε = 0.01.
//!
//! `cargo run --release --example equal_time -- [SCENE] [SECONDS] [REFERENCE_SPP] [SIZE] [SEEDS] [METHODS]`
//!
//! `METHODS` is a comma-separated list of `path`, `bdpt`, `mmlt`, `pssmlt`,
//! `tempered-neighbor`, `tempered-equi-energy`, `tempered-permutation`, each optionally with
//! `+original-mis` (untempered MIS weights in the tempered targets) and `+no-burn-in` (the
//! default ladder, untuned) (default: the first four); each runs with seeds `1 … SEEDS` (default 2), and the mean and spread of relMSE over
//! seeds are printed with the swap acceptance reached.

use std::sync::atomic::AtomicBool;
use std::time::Duration;
use tempera::integrator::{
    BdptIntegrator, Budget, Integrator, MmltIntegrator, PathIntegrator, PssmltIntegrator, RenderControl,
    RenderSettings, Swap, TemperedIntegrator,
};
use tempera::texture::Image;

fn rel_mse(image: &Image, reference: &Image) -> f64 {
    tempera_image::metrics::compare(image, reference).map_or(f64::NAN, |c| c.relmse)
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let scene_arg = args.first().filter(|a| a.as_str() != "default");
    let seconds: f64 = args.get(1).map_or(Ok(10.0), |s| s.parse())?;
    let reference_spp: u32 = args.get(2).map_or(Ok(1024), |s| s.parse())?;
    let size: u32 = args.get(3).map_or(Ok(96), |s| s.parse())?;
    let builder = match scene_arg {
        Some(path) => tempera_scene::load(std::path::Path::new(path), &Default::default())?.builder,
        None => tempera::scenes::default_scene(),
    };
    let mut scene = builder.build()?;
    let aspect = scene.film.height as f32 / scene.film.width as f32;
    scene.set_resolution(size, ((size as f32 * aspect).round() as u32).max(1));
    let depth = scene.defaults.max_depth.min(12);
    let cancel = AtomicBool::new(false);
    let control = RenderControl::new(&cancel, &|_| {});
    let render = |integrator: &dyn Integrator, budget: Budget, seed: u64| {
        integrator.render(&scene, &RenderSettings { budget, seed, threads: 0 }, &control)
    };
    let reference = render(&BdptIntegrator::new(depth), Budget::Samples(reference_spp), 1000);
    println!(
        "scene {}, {}x{}, maxdepth {depth}; reference: BDPT {reference_spp} spp in {:.1} s",
        scene_arg.map_or("default", |s| s.as_str()),
        scene.film.width,
        scene.film.height,
        reference.stats.seconds
    );
    let budget = Budget::Time(Duration::from_secs_f64(seconds));
    let seeds: u64 = args.get(4).map_or(Ok(2), |s| s.parse())?;
    let methods = args.get(5).map_or("path,bdpt,mmlt,pssmlt", |s| s.as_str());
    for name in methods.split(',') {
        let integrator: Box<dyn Integrator> = match name {
            "path" => Box::new(PathIntegrator::new(depth)),
            "bdpt" => Box::new(BdptIntegrator::new(depth)),
            "mmlt" => Box::new(MmltIntegrator::new(depth)),
            "pssmlt" => Box::new(PssmltIntegrator::new(depth)),
            other => {
                // `tempered-SWAP`, optionally with `+original-mis` (untempered MIS weights) and
                // `+no-burn-in` (the default ladder, untuned).
                let mut parts = other.split('+');
                let base = parts.next().unwrap_or_default();
                let options: Vec<&str> = parts.collect();
                match base.strip_prefix("tempered-").and_then(Swap::parse) {
                    Some(swap) => Box::new(TemperedIntegrator {
                        swap,
                        roughen_mis: !options.contains(&"original-mis"),
                        burn_in: if options.contains(&"no-burn-in") { 0 } else { 500 },
                        ..TemperedIntegrator::new(depth)
                    }),
                    None => anyhow::bail!("unknown method '{other}'"),
                }
            }
        };
        let mut errors = Vec::new();
        for seed in 1..=seeds {
            let out = render(integrator.as_ref(), budget, seed);
            let spp = out.stats.pixel_samples as f64 / f64::from(scene.film.width * scene.film.height);
            let e = rel_mse(&out.image, &reference.image);
            let swaps: Vec<String> = out
                .chains
                .iter()
                .filter_map(|d| d.swaps.as_ref().map(|s| format!("{:.2}", s.neighbor_acceptance())))
                .collect();
            let swaps = if swaps.is_empty() {
                String::new()
            } else {
                format!(", neighbour acceptance per depth {}", swaps.join(" "))
            };
            println!(
                "{name:22} seed {seed}: {spp:7.1} samples or mutations per pixel in {:.1} s, relMSE {e:.5}{swaps}",
                out.stats.seconds
            );
            errors.push(e);
        }
        let mean = errors.iter().sum::<f64>() / errors.len() as f64;
        let (lo, hi) = errors.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &e| (lo.min(e), hi.max(e)));
        println!("{name:22} relMSE mean {mean:.5}, min {lo:.5}, max {hi:.5} over {seeds} seeds");
    }
    Ok(())
}
