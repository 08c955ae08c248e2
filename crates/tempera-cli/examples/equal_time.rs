//! Equal-time comparison of the path tracer, BDPT, MMLT and PSSMLT against a long BDPT reference, printing
//! relMSE = mean((I − R)² / (R² + ε)) on luminance with ε = 0.01.
//!
//! `cargo run --release --example equal_time -- [SCENE] [SECONDS] [REFERENCE_SPP] [SIZE]`

use std::sync::atomic::AtomicBool;
use std::time::Duration;
use tempera::integrator::{
    BdptIntegrator, Budget, Integrator, MmltIntegrator, PathIntegrator, PssmltIntegrator, RenderControl, RenderSettings,
};
use tempera::math::luminance;
use tempera::texture::Image;

const EPSILON: f64 = 0.01;

fn rel_mse(image: &Image, reference: &Image) -> f64 {
    let sum: f64 = image
        .pixels
        .iter()
        .zip(&reference.pixels)
        .map(|(i, r)| {
            let (i, r) = (f64::from(luminance(*i)), f64::from(luminance(*r)));
            (i - r).powi(2) / (r * r + EPSILON)
        })
        .sum();
    sum / image.pixels.len() as f64
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
    let control = RenderControl { cancel: &cancel, on_progress: &|_| {} };
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
    for (name, integrator) in [
        ("path", &PathIntegrator::new(depth) as &dyn Integrator),
        ("bdpt", &BdptIntegrator::new(depth) as &dyn Integrator),
        ("mmlt", &MmltIntegrator::new(depth) as &dyn Integrator),
        ("pssmlt", &PssmltIntegrator::new(depth) as &dyn Integrator),
    ] {
        for seed in 1..=2 {
            let out = render(integrator, budget, seed);
            let spp = out.stats.pixel_samples as f64 / f64::from(scene.film.width * scene.film.height);
            println!(
                "{name:6} seed {seed}: {spp:7.1} samples or mutations per pixel in {:.1} s, relMSE {:.5}",
                out.stats.seconds,
                rel_mse(&out.image, &reference.image)
            );
        }
    }
    Ok(())
}
