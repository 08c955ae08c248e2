//! Integrator tests: the white furnace (z-test against the analytic answer), pbrt's maxdepth
//! semantics, bit-identical images across thread counts, and budgets and cancellation.

use super::*;
use crate::geometry::Ray;
use crate::math::Vec2;
use crate::scene::Scene;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

pub(crate) fn render_with(
    scene: &Scene,
    integrator: &dyn Integrator,
    budget: Budget,
    seed: u64,
    threads: usize,
) -> RenderOutput {
    let cancel = AtomicBool::new(false);
    let control = RenderControl::new(&cancel, &|_| {});
    integrator.render(scene, &RenderSettings { budget, seed, threads }, &control).expect("the scene renders")
}

/// Mean and standard error of the mean of a set of independent per-pixel estimates.
pub(crate) fn mean_and_se(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// Pixels whose four corners all hit (`true`) or all miss (`false`) the unit sphere at the origin.
pub(crate) fn classify_furnace_pixels(scene: &Scene) -> (Vec<usize>, Vec<usize>) {
    let (w, h) = (scene.film.width, scene.film.height);
    let hits = |x: f32, y: f32| {
        let ray: Ray = scene.camera.generate_ray(Vec2::new(x, y), Vec2::splat(0.5));
        let b = ray.o.dot(ray.d);
        b * b - (ray.o.length_squared() - 1.0) > 0.0
    };
    let (mut sphere, mut sky) = (Vec::new(), Vec::new());
    for y in 0..h {
        for x in 0..w {
            let (fx, fy) = (x as f32, y as f32);
            let corners = [hits(fx, fy), hits(fx + 1.0, fy), hits(fx, fy + 1.0), hits(fx + 1.0, fy + 1.0)];
            let i = (y * w + x) as usize;
            if corners.iter().all(|&c| c) {
                sphere.push(i);
            } else if corners.iter().all(|&c| !c) {
                sky.push(i);
            }
        }
    }
    (sphere, sky)
}

fn check_furnace(integrator: &dyn Integrator, spp: u32) {
    let scene = crate::scenes::furnace(0.8, 48, 48).build().unwrap();
    let out = render_with(&scene, integrator, Budget::Samples(spp), 1, 0);
    let (sphere, sky) = classify_furnace_pixels(&scene);
    assert!(sphere.len() > 200 && sky.len() > 200, "the furnace camera must see both sphere and sky");
    for &i in &sky {
        assert!(
            (out.image.pixels[i] - Rgb::ONE).abs().max_element() < 1e-5,
            "sky pixel {i} is {}",
            out.image.pixels[i]
        );
    }
    for c in 0..3 {
        let values: Vec<f64> = sphere.iter().map(|&i| f64::from(out.image.pixels[i][c])).collect();
        let (mean, se) = mean_and_se(&values);
        assert!(
            (mean - 0.8).abs() < 4.0 * se + 1e-4,
            "{}: sphere channel {c} = {mean} ± {se}, expected 0.8",
            integrator.name()
        );
    }
    assert_eq!(out.stats.invalid_samples, 0);
}

#[test]
fn path_tracer_passes_the_white_furnace() {
    check_furnace(&PathIntegrator::new(8), 16);
    // One scattering event suffices for a convex sphere: direct light only must agree.
    check_furnace(&PathIntegrator::new(1), 16);
}

use crate::math::Rgb;

#[test]
fn maxdepth_zero_shows_only_emitters() {
    let scene = crate::scenes::cornell_box(32, 32).build().unwrap();
    let out = render_with(&scene, &PathIntegrator::new(0), Budget::Samples(4), 3, 0);
    let lit: Vec<usize> = (0..out.image.pixels.len()).filter(|&i| out.image.pixels[i].max_element() > 0.0).collect();
    assert!(!lit.is_empty() && lit.len() < 40, "only the small light may be visible, {} pixels lit", lit.len());
    assert!(lit.iter().all(|&i| i / 32 < 6), "lit pixels must be the ceiling light at the top of the frame");
    // The light faces down: the ceiling beside it needs two scattering events (ceiling, then
    // a lit wall or floor), the floor only one.
    let ceiling = |img: &crate::texture::Image| img.get(3, 1).max_element();
    let floor = |img: &crate::texture::Image| img.get(16, 30).max_element();
    let one = render_with(&scene, &PathIntegrator::new(1), Budget::Samples(16), 3, 0);
    assert_eq!(ceiling(&one.image), 0.0, "maxdepth 1: no light reaches the ceiling");
    assert!(floor(&one.image) > 0.0, "maxdepth 1: direct light on the floor");
    let two = render_with(&scene, &PathIntegrator::new(2), Budget::Samples(16), 3, 0);
    assert!(ceiling(&two.image) > 0.0, "maxdepth 2: indirect light on the ceiling");
}

#[test]
fn same_seed_is_bit_identical_at_any_thread_count() {
    let scene = crate::scenes::default_scene();
    let mut scene = scene.build().unwrap();
    scene.set_resolution(40, 30);
    let integrator = PathIntegrator::new(6);
    let a = render_with(&scene, &integrator, Budget::Samples(6), 11, 1);
    let b = render_with(&scene, &integrator, Budget::Samples(6), 11, 2);
    let c = render_with(&scene, &integrator, Budget::Samples(6), 11, 3);
    assert!(a.image.pixels == b.image.pixels && b.image.pixels == c.image.pixels);
    assert_eq!(a.stats.rays, b.stats.rays);
    let d = render_with(&scene, &integrator, Budget::Samples(6), 12, 2);
    assert!(a.image.pixels != d.image.pixels, "a different seed must change the image");
}

#[test]
fn time_budget_renders_every_pixel_and_cancellation_stops_early() {
    let scene = crate::scenes::cornell_box(32, 32).build().unwrap();
    let integrator = PathIntegrator::new(5);
    let out = render_with(&scene, &integrator, Budget::Time(std::time::Duration::from_millis(200)), 1, 0);
    assert!(out.stats.spp_completed >= 1);
    assert!(out.image.pixels.iter().filter(|p| p.max_element() > 0.0).count() > 1000);

    let cancel = AtomicBool::new(false);
    let done = AtomicU64::new(0);
    let on_progress = |n: u64| {
        if done.fetch_add(n, Ordering::Relaxed) + n > 32 * 32 * 3 {
            cancel.store(true, Ordering::Relaxed);
        }
    };
    let control = RenderControl::new(&cancel, &on_progress);
    let settings = RenderSettings { budget: Budget::Samples(1 << 20), seed: 1, threads: 2 };
    let out = integrator.render(&scene, &settings, &control).unwrap();
    assert!(out.stats.cancelled);
    assert!(out.stats.pixel_samples < 32 * 32 * 64, "stopped long before the budget");
    assert!(out.image.pixels.iter().all(|p| p.is_finite()));
    assert!(out.image.pixels.iter().filter(|p| p.max_element() > 0.0).count() > 1000, "what was rendered is kept");
}

/// Per-block means of an image and their standard errors (pixels as independent estimates).
pub(crate) fn block_stats(img: &crate::texture::Image, block: usize) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    for by in (0..img.height).step_by(block) {
        for bx in (0..img.width).step_by(block) {
            let mut values = Vec::new();
            for y in by..(by + block).min(img.height) {
                for x in bx..(bx + block).min(img.width) {
                    values.push(f64::from(crate::math::luminance(img.get(x, y))));
                }
            }
            out.push(mean_and_se(&values));
        }
    }
    out
}

#[test]
fn next_event_estimation_agrees_with_bsdf_sampling_on_a_cornell_box() {
    let scene = crate::scenes::cornell_box(32, 32).build().unwrap();
    let mis = render_with(&scene, &PathIntegrator::new(5), Budget::Samples(128), 5, 0);
    let bsdf_only = PathIntegrator { max_depth: 5, next_event: false };
    let plain = render_with(&scene, &bsdf_only, Budget::Samples(512), 6, 0);
    let (a, b) = (block_stats(&mis.image, 8), block_stats(&plain.image, 8));
    for (i, ((ma, sa), (mb, sb))) in a.iter().zip(&b).enumerate() {
        let se = (sa * sa + sb * sb).sqrt();
        assert!((ma - mb).abs() < 4.5 * se + 1e-3, "block {i}: MIS {ma} vs BSDF-only {mb} (se {se})");
    }
    let mean = |s: &[(f64, f64)]| s.iter().map(|v| v.0).sum::<f64>() / s.len() as f64;
    let (ma, mb) = (mean(&a), mean(&b));
    assert!((ma / mb - 1.0).abs() < 0.03, "image means {ma} vs {mb}");
}

/// Compares two renders block by block (z-test on block means) and by image mean.
pub(crate) fn assert_agree(
    name: &str,
    a: &crate::texture::Image,
    b: &crate::texture::Image,
    block: usize,
    mean_tol: f64,
) {
    let (ba, bb) = (block_stats(a, block), block_stats(b, block));
    let mut beyond = 0;
    for ((ma, sa), (mb, sb)) in ba.iter().zip(&bb) {
        let se = (sa * sa + sb * sb).sqrt();
        if (ma - mb).abs() > 4.0 * se + 1e-3 {
            beyond += 1;
        }
    }
    assert!(beyond == 0, "{name}: {beyond} of {} blocks differ beyond 4σ", ba.len());
    // The image mean, with its standard error propagated from the blocks: a z-test, plus a
    // relative bound.
    let mean = |s: &[(f64, f64)]| s.iter().map(|v| v.0).sum::<f64>() / s.len() as f64;
    let se = |s: &[(f64, f64)]| s.iter().map(|v| v.1 * v.1).sum::<f64>().sqrt() / s.len() as f64;
    let (ma, mb) = (mean(&ba), mean(&bb));
    let z = (ma - mb).abs() / (se(&ba).powi(2) + se(&bb).powi(2)).sqrt();
    assert!(z < 4.0 || (ma / mb - 1.0).abs() < mean_tol, "{name}: image means {ma} vs {mb} (z = {z:.1})");
}

#[test]
fn bdpt_passes_the_white_furnace() {
    check_furnace(&BdptIntegrator::new(8), 16);
}

#[test]
fn bdpt_agrees_with_the_path_tracer_on_a_cornell_box() {
    let scene = crate::scenes::cornell_box(32, 32).build().unwrap();
    let bdpt = render_with(&scene, &BdptIntegrator::new(5), Budget::Samples(64), 21, 0);
    let path = render_with(&scene, &PathIntegrator::new(5), Budget::Samples(256), 22, 0);
    assert_eq!(bdpt.stats.invalid_samples, 0);
    assert_agree("bdpt vs path", &bdpt.image, &path.image, 8, 0.01);
}

#[test]
fn light_tracing_alone_agrees_with_path_tracing_alone_in_the_furnace() {
    // Environment light: exercises emission from the disk covering the scene.
    let scene = crate::scenes::furnace(0.8, 32, 32).build().unwrap();
    let (sphere, _) = classify_furnace_pixels(&scene);
    let lt = BdptIntegrator { strategies: Strategies::Only(2, 1), ..BdptIntegrator::new(1) };
    let out = render_with(&scene, &lt, Budget::Samples(64), 3, 0);
    let values: Vec<f64> = sphere.iter().map(|&i| f64::from(out.image.pixels[i].y)).collect();
    let (mean, se) = mean_and_se(&values);
    assert!((mean - 0.8).abs() < 4.0 * se + 2e-3, "light tracing alone: {mean} ± {se}, expected 0.8");
}

#[test]
fn light_tracing_alone_agrees_with_path_tracing_alone() {
    let scene = crate::scenes::cornell_box(24, 24).build().unwrap();
    let lt = BdptIntegrator { strategies: Strategies::LightTracing, ..BdptIntegrator::new(4) };
    let pt = BdptIntegrator { strategies: Strategies::PathTracing, ..BdptIntegrator::new(4) };
    let a = render_with(&scene, &lt, Budget::Samples(128), 31, 0);
    let b = render_with(&scene, &pt, Budget::Samples(512), 32, 0);
    assert_agree("light tracing vs path tracing", &a.image, &b.image, 8, 0.03);
}

/// A Cornell box with a perfect mirror sphere and a smooth glass sphere.
fn delta_box() -> Scene {
    use crate::geometry::{Shape, Sphere};
    use crate::material::{ConductorFresnel, ConductorMaterial, DielectricMaterial, Material, Roughness};
    let mut b = crate::scenes::cornell_box(32, 32);
    let mirror = b.add_material(Material::Conductor(ConductorMaterial {
        fresnel: ConductorFresnel::Reflectance(Rgb::splat(0.9).into()),
        roughness: Roughness::alpha(0.0),
        tint: 1.0.into(),
    }));
    let glass = b.add_material(Material::Dielectric(DielectricMaterial { eta: 1.5, roughness: Roughness::alpha(0.0) }));
    b.add_shape(
        Shape::Sphere(Sphere {
            center: crate::math::Vec3::new(-0.45, 0.3, 0.3),
            radius: 0.3,
            reverse_orientation: false,
        }),
        mirror,
        None,
    );
    b.add_shape(
        Shape::Sphere(Sphere {
            center: crate::math::Vec3::new(0.4, 1.2, 0.2),
            radius: 0.25,
            reverse_orientation: false,
        }),
        glass,
        None,
    );
    b.build().unwrap()
}

#[test]
fn bdpt_renders_delta_materials_like_the_path_tracer() {
    let scene = delta_box();
    let bdpt = render_with(&scene, &BdptIntegrator::new(6), Budget::Samples(64), 41, 0);
    let path = render_with(&scene, &PathIntegrator::new(6), Budget::Samples(256), 42, 0);
    assert_agree("delta box", &bdpt.image, &path.image, 8, 0.02);
}

/// A Cornell box with pbrt-v4's layered materials: a rough coat with a scattering slab over a
/// diffuse base, and a glossy coat over a rough gold conductor.
fn coated_box() -> Scene {
    use crate::geometry::{Shape, Sphere};
    use crate::material::{
        ConductorFresnel, ConductorMaterial, LayeredBaseMaterial, LayeredMaterial, Material, Roughness,
    };
    let mut b = crate::scenes::cornell_box(32, 32);
    let layered = |base, roughness, albedo: f32| LayeredMaterial {
        base,
        roughness: Roughness::alpha(roughness),
        eta: 1.5,
        thickness: 0.1.into(),
        albedo: Rgb::splat(albedo).into(),
        g: 0.3.into(),
        max_depth: 10,
        samples: 1,
    };
    let diffuse = LayeredBaseMaterial::Diffuse(Rgb::new(0.7, 0.3, 0.2).into());
    let gold = LayeredBaseMaterial::Conductor(ConductorMaterial {
        fresnel: ConductorFresnel::Reflectance(Rgb::new(0.9, 0.7, 0.3).into()),
        roughness: Roughness::alpha(0.3),
        tint: 1.0.into(),
    });
    for (material, center, radius) in [
        (layered(diffuse, 0.2, 0.5), crate::math::Vec3::new(-0.45, 0.3, 0.3), 0.3),
        (layered(gold, 0.08, 0.0), crate::math::Vec3::new(0.4, 0.3, -0.2), 0.3),
    ] {
        let id = b.add_material(Material::Layered(material));
        b.add_shape(Shape::Sphere(Sphere { center, radius, reverse_orientation: false }), id, None);
    }
    b.build().unwrap()
}

/// Layered BSDFs render alike in BDPT (every strategy, MIS on their estimated density) and in
/// light tracing alone (importance transport through the walk) as in the path tracer. (Using
/// the walk's proportional density for MIS instead was not caught here: on this box the two
/// densities weight the strategies too similarly to move the image beyond its noise.)
#[test]
fn layered_materials_render_alike_with_every_strategy() {
    let scene = coated_box();
    let path = render_with(&scene, &PathIntegrator::new(5), Budget::Samples(512), 51, 0);
    let bdpt = render_with(&scene, &BdptIntegrator::new(5), Budget::Samples(96), 52, 0);
    assert_eq!(bdpt.stats.invalid_samples, 0);
    assert_agree("coated box, bdpt vs path", &bdpt.image, &path.image, 8, 0.01);
    let lt = BdptIntegrator { strategies: Strategies::LightTracing, ..BdptIntegrator::new(5) };
    let light = render_with(&scene, &lt, Budget::Samples(192), 53, 0);
    assert_agree("coated box, light tracing vs path", &light.image, &path.image, 8, 0.03);
}

#[test]
fn bdpt_is_bit_identical_at_any_thread_count() {
    let mut scene = crate::scenes::default_scene().build().unwrap();
    scene.set_resolution(32, 24);
    let integrator = BdptIntegrator::new(5);
    let a = render_with(&scene, &integrator, Budget::Samples(4), 5, 1);
    let b = render_with(&scene, &integrator, Budget::Samples(4), 5, 2);
    let c = render_with(&scene, &integrator, Budget::Samples(4), 5, 3);
    assert!(
        a.image.pixels == b.image.pixels && b.image.pixels == c.image.pixels,
        "splats must merge deterministically"
    );
}

/// Snapshots of a time-budget render: one per requested time, in order, each later than its
/// time, with growing sample counts and an image that already estimates the right brightness.
fn check_snapshots(integrator: &dyn Integrator, reference_mean: f64) {
    use std::sync::Mutex;
    use std::time::Duration;
    let scene = crate::scenes::cornell_box(24, 24).build().unwrap();
    let cancel = AtomicBool::new(false);
    let taken: Mutex<Vec<(usize, RenderStats, f64)>> = Mutex::new(Vec::new());
    let mean =
        |img: &crate::texture::Image| img.pixels.iter().map(|p| f64::from(p.y)).sum::<f64>() / img.pixels.len() as f64;
    let on_snapshot = |i: usize, out: &RenderOutput| {
        assert!(out.image.pixels.iter().all(|p| p.is_finite() && p.min_element() >= 0.0));
        taken.lock().unwrap().push((i, out.stats.clone(), mean(&out.image)));
    };
    let times = [Duration::from_millis(150), Duration::from_millis(300), Duration::from_millis(450)];
    let control = RenderControl::new(&cancel, &|_| {}).with_snapshots(&times, &on_snapshot);
    let settings = RenderSettings { budget: Budget::Time(Duration::from_millis(700)), seed: 3, threads: 2 };
    let out = integrator.render(&scene, &settings, &control).unwrap();
    let taken = taken.into_inner().unwrap();
    let name = integrator.name();
    assert_eq!(taken.iter().map(|t| t.0).collect::<Vec<_>>(), vec![0, 1, 2], "{name}");
    for (i, stats, m) in &taken {
        assert!(stats.seconds >= times[*i].as_secs_f64(), "{name}: snapshot {i} at {} s", stats.seconds);
        assert!(stats.pixel_samples > 0 && stats.pixel_samples <= out.stats.pixel_samples, "{name}");
        assert!((m / reference_mean - 1.0).abs() < 0.1, "{name}: snapshot {i} mean {m} vs {reference_mean}");
    }
    assert!(taken.windows(2).all(|w| w[0].1.pixel_samples <= w[1].1.pixel_samples), "{name}");
    // A sample budget takes no snapshots.
    let count = AtomicU64::new(0);
    let on_snapshot = |_: usize, _: &RenderOutput| {
        count.fetch_add(1, Ordering::Relaxed);
    };
    let control = RenderControl::new(&cancel, &|_| {}).with_snapshots(&times, &on_snapshot);
    integrator.render(&scene, &RenderSettings { budget: Budget::Samples(1), seed: 3, threads: 2 }, &control).unwrap();
    assert_eq!(count.load(Ordering::Relaxed), 0, "{name}");
}

#[test]
fn time_budget_renders_deliver_snapshots() {
    let scene = crate::scenes::cornell_box(24, 24).build().unwrap();
    let reference = render_with(&scene, &BdptIntegrator::new(4), Budget::Samples(256), 9, 0);
    let mean = reference.image.pixels.iter().map(|p| f64::from(p.y)).sum::<f64>() / reference.image.pixels.len() as f64;
    check_snapshots(&PathIntegrator::new(4), mean);
    check_snapshots(&BdptIntegrator::new(4), mean);
    check_snapshots(&MmltIntegrator { bootstrap: 20_000, chains: 8, ..MmltIntegrator::new(4) }, mean);
}
