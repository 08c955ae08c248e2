//! The real scenes in `../shared/scenes` (when present): every pbrt-v4 scene loads without
//! errors and renders, and the path-traced Cornell box agrees with Bitterli's Tungsten reference.

mod shared;
use shared::shared_scenes;
use std::sync::atomic::AtomicBool;
use tempera::integrator::{Budget, Integrator, PathIntegrator, RenderControl, RenderSettings};
use tempera::math::{Rgb, luminance};
use tempera::scene::Scene;
use tempera::texture::Image;
use tempera_scene::{LoadOptions, load};

fn render(scene: &Scene, max_depth: u32, spp: u32) -> Image {
    let cancel = AtomicBool::new(false);
    let control = RenderControl::new(&cancel, &|_| {});
    let settings = RenderSettings { budget: Budget::Samples(spp), seed: 7, threads: 0 };
    PathIntegrator::new(max_depth).render(scene, &settings, &control).expect("the scene renders").image
}

#[test]
fn every_real_scene_file_loads_and_renders() {
    let Some(dir) = shared_scenes() else { return };
    let (mut pbrt, mut mitsuba) = (0, 0);
    for entry in std::fs::read_dir(&dir).unwrap() {
        let scene_dir = entry.unwrap().path();
        for (file, counter) in [("pbrt-v4/scene-v4.pbrt", &mut pbrt), ("mitsuba/scene_v0.6.xml", &mut mitsuba)] {
            let file = scene_dir.join(file);
            if !file.is_file() {
                continue;
            }
            let loaded = load(&file, &LoadOptions::default()).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
            let mut scene = loaded.builder.build().unwrap_or_else(|e| panic!("{}: {e}", file.display()));
            scene.set_resolution(24, 16);
            let img = render(&scene, 5, 4);
            assert!(img.pixels.iter().all(|p| p.is_finite()), "{}", file.display());
            // water-caustic's Mitsuba file gives its outward-facing walls one-sided BSDFs, which
            // Mitsuba 0.6 renders black from inside; its floor is lit only through the water.
            let known_dark = file.ends_with("water-caustic/mitsuba/scene_v0.6.xml");
            assert!(known_dark || img.pixels.iter().any(|p| p.max_element() > 0.0), "{} renders black", file.display());
            *counter += 1;
        }
    }
    assert!(pbrt >= 5 && mitsuba >= 4, "expected five pbrt-v4 and four Mitsuba 0.6 scenes, found {pbrt} and {mitsuba}");
}

/// Averages `factor`×`factor` blocks.
fn downsample(img: &Image, factor: usize) -> Image {
    let (w, h) = (img.width / factor, img.height / factor);
    let mut px = vec![Rgb::ZERO; w * h];
    for y in 0..h * factor {
        for x in 0..w * factor {
            px[(y / factor) * w + x / factor] += img.get(x, y) / (factor * factor) as f32;
        }
    }
    Image::new(w, h, px)
}

#[test]
fn cornell_box_agrees_with_the_tungsten_reference() {
    let Some(dir) = shared_scenes() else { return };
    let dir = dir.join("cornell-box/pbrt-v4");
    let mut scene = load(&dir.join("scene-v4.pbrt"), &LoadOptions::default()).unwrap().builder.build().unwrap();
    let reference =
        tempera_image::read_image(&dir.join("TungstenRender.exr"), tempera_image::ColorEncoding::Linear).unwrap();
    let n = 128;
    scene.set_resolution(n as u32, n as u32);
    let ours = render(&scene, scene.defaults.max_depth, 128);
    let reference = downsample(&reference, reference.width / n);
    let block = 16;
    let (mut worst, mut sum_ours, mut sum_ref) = (0.0f64, 0.0f64, 0.0f64);
    for by in (0..n).step_by(block) {
        for bx in (0..n).step_by(block) {
            let values: Vec<f64> = (by..by + block)
                .flat_map(|y| (bx..bx + block).map(move |x| (x, y)))
                .map(|(x, y)| f64::from(luminance(ours.get(x, y))))
                .collect();
            let mean = values.iter().sum::<f64>() / values.len() as f64;
            let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (values.len() - 1) as f64;
            let se = (var / values.len() as f64).sqrt();
            let r: f64 = (by..by + block)
                .flat_map(|y| (bx..bx + block).map(move |x| (x, y)))
                .map(|(x, y)| f64::from(luminance(reference.get(x, y))))
                .sum::<f64>()
                / values.len() as f64;
            sum_ours += mean;
            sum_ref += r;
            // Relative deviation beyond noise: what the model differences cost per block.
            let excess = ((mean - r).abs() - 3.0 * se).max(0.0) / r.max(1e-3);
            worst = worst.max(excess);
        }
    }
    let ratio = sum_ours / sum_ref;
    eprintln!(
        "cornell-box: image mean ratio ours/tungsten = {ratio:.4}; worst block excess beyond 3σ = {:.2}%",
        worst * 100.0
    );
    assert!((ratio - 1.0).abs() < 0.03, "image means differ by {:.2}%", (ratio - 1.0) * 100.0);
    assert!(worst < 0.05, "a block deviates {:.1}% beyond noise", worst * 100.0);
}

/// Mean luminance of `block`×`block` blocks, with standard errors from the per-pixel spread.
fn blocks(img: &Image, block: usize) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    for by in (0..img.height - block + 1).step_by(block) {
        for bx in (0..img.width - block + 1).step_by(block) {
            let v: Vec<f64> = (by..by + block)
                .flat_map(|y| (bx..bx + block).map(move |x| (x, y)))
                .map(|(x, y)| f64::from(luminance(img.get(x, y))))
                .collect();
            let n = v.len() as f64;
            let mean = v.iter().sum::<f64>() / n;
            let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
            out.push((mean, (var / n).sqrt()));
        }
    }
    out
}

#[test]
fn mitsuba_files_render_like_their_pbrt_counterparts() {
    let Some(dir) = shared_scenes() else { return };
    // (scene, strict agreement expected). Known differences between the files: the classroom's
    // Mitsuba file uses sunsky where the pbrt-v4 file has a distant light and an equal-area sky
    // image (see its PROVENANCE.md); veach-mis's pbrt-v4 conversion dropped the plates'
    // `specularReflectance` of 0.3 (see the Tungsten test below, which the Mitsuba file matches);
    // water-caustic's Mitsuba file gives its outward-facing walls one-sided `diffuse` BSDFs
    // without `twosided`, which Mitsuba 0.6 (and Tempera) render black from inside the room.
    for (name, strict) in [("cornell-box", true), ("veach-mis", false), ("water-caustic", false), ("classroom", false)]
    {
        let (pbrt, xml) = (dir.join(name).join("pbrt-v4/scene-v4.pbrt"), dir.join(name).join("mitsuba/scene_v0.6.xml"));
        if !pbrt.is_file() || !xml.is_file() {
            continue;
        }
        let render_file = |f: &std::path::Path| {
            let mut s = load(f, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}")).builder.build().unwrap();
            let (w, h) = (s.film.width, s.film.height);
            s.set_resolution(96, 96 * h / w);
            render(&s, 5, 64)
        };
        let (a, b) = (render_file(&pbrt), render_file(&xml));
        let (ba, bb) = (blocks(&a, 8), blocks(&b, 8));
        let mean = |v: &[(f64, f64)]| v.iter().map(|x| x.0).sum::<f64>() / v.len() as f64;
        let ratio = mean(&bb) / mean(&ba);
        let beyond = ba
            .iter()
            .zip(&bb)
            .filter(|((ma, sa), (mb, sb))| (ma - mb).abs() > 4.0 * (sa * sa + sb * sb).sqrt() + 0.02 * ma.max(*mb))
            .count();
        eprintln!(
            "{name}: image mean ratio mitsuba/pbrt = {ratio:.4}; {beyond} of {} blocks differ beyond noise",
            ba.len()
        );
        if strict {
            assert!((ratio - 1.0).abs() < 0.03, "{name}: means differ by {:.1}%", (ratio - 1.0) * 100.0);
            assert!(beyond * 20 <= ba.len(), "{name}: {beyond} blocks differ beyond noise");
        }
    }
}

#[test]
fn veach_mis_mitsuba_file_agrees_with_the_tungsten_reference() {
    let Some(dir) = shared_scenes() else { return };
    let d = dir.join("veach-mis");
    let reference =
        tempera_image::read_image(&d.join("pbrt-v4/TungstenRender.exr"), tempera_image::ColorEncoding::Linear).unwrap();
    let factor = reference.width / 128;
    let reference = downsample(&reference, factor);
    let mut scene = load(&d.join("mitsuba/scene_v0.6.xml"), &LoadOptions::default()).unwrap().builder.build().unwrap();
    scene.set_resolution(reference.width as u32, reference.height as u32);
    // Mitsuba's maxDepth 3 is two scattering events in Tempera's (pbrt's) count.
    assert_eq!(scene.defaults.max_depth, 2);
    let img = render(&scene, scene.defaults.max_depth, 64);
    // 16×16 blocks with 10% slack: the reference has noise of its own, and the plates' Beckmann
    // lobes are rendered as GGX lobes of the same alpha (longer tails).
    let (a, b) = (blocks(&img, 16), blocks(&reference, 16));
    let mean = |v: &[(f64, f64)]| v.iter().map(|x| x.0).sum::<f64>() / v.len() as f64;
    let ratio = mean(&a) / mean(&b);
    let beyond = a.iter().zip(&b).filter(|((ma, sa), (mb, _))| (ma - mb).abs() > 4.0 * sa + 0.1 * mb).count();
    for (i, ((ma, sa), (mb, _))) in a.iter().zip(&b).enumerate() {
        if (ma - mb).abs() > 4.0 * sa + 0.1 * mb {
            eprintln!("  block {i} (row {}, col {}): tempera {ma:.4} ± {sa:.4}, tungsten {mb:.4}", i / 8, i % 8);
        }
    }
    eprintln!(
        "veach-mis (Mitsuba file): image mean ratio tempera/tungsten = {ratio:.4}; {beyond} of {} blocks beyond noise",
        a.len()
    );
    assert!((ratio - 1.0).abs() < 0.03, "means differ by {:.1}%", (ratio - 1.0) * 100.0);
    // The floor corners come out brighter: GGX's longer tails spread more of the plates'
    // reflections there than Beckmann's (documented approximation).
    assert!(beyond * 5 <= a.len(), "{beyond} blocks differ beyond noise");
}
