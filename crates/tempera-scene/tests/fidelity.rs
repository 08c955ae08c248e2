//! Held to pbrt-v4's own images: each shared scene's pbrt-v4 file rendered by Tempera's path
//! tracer at the resolution of `reference-pbrt-v4.exr` beside it (pbrt-v4's render of that very
//! file; `../shared/scenes/README.md`) and compared by luminance: the image mean, the median
//! relative difference of 8×8 block means, and every block's difference in units of the
//! combined noise. Tempera's noise comes from independent renders (seeds): a block mean's
//! variance is the sum of its pixels' variances over the seeds (pixels are independent under
//! the box filter), with hundreds of degrees of freedom per block. The reference's noise is
//! taken as Tempera's per-sample noise at the reference's sample count (both are unidirectional
//! path tracers of the same scene). Skipped, with a message, where `../shared` is absent.

mod shared;
use shared::shared_scenes;
use std::path::Path;
use std::sync::atomic::AtomicBool;
use tempera::integrator::{Budget, Integrator, PathIntegrator, RenderControl, RenderSettings};
use tempera::math::luminance;
use tempera::texture::Image;
use tempera_image::{ColorEncoding, read_image};
use tempera_scene::{LoadOptions, load};

/// What a comparison with the reference found.
#[derive(Debug)]
struct Fidelity {
    mean_ratio: f64,
    /// The standard deviation of `mean_ratio` from both images' noise.
    mean_sigma: f64,
    /// Blocks, and blocks whose difference is beyond five standard deviations of the noise.
    blocks: usize,
    beyond_5_sigma: usize,
    block_median: f64,
    /// The median over blocks of the combined noise's standard deviation relative to the
    /// reference's block mean: what `block_median` would be about (×0.67) without any bias.
    noise_median: f64,
    worst_z: f64,
    worst_block: (usize, usize),
    worst_ratio: f64,
}

/// Luminance of each pixel.
fn lum(img: &Image) -> Vec<f64> {
    img.pixels.iter().map(|&p| f64::from(luminance(p))).collect()
}

/// Compares the mean of `renders` (independent, `spp` samples per pixel each) with the
/// reference rendered at `reference_spp`, on `block`×`block` blocks (partial ones dropped).
fn fidelity(renders: &[Image], spp: u32, reference: &Image, reference_spp: u32, block: usize) -> Fidelity {
    let (w, h) = (reference.width, reference.height);
    let s = renders.len() as f64;
    let per: Vec<Vec<f64>> = renders.iter().map(lum).collect();
    let r = lum(reference);
    let n = w * h;
    let mean: Vec<f64> = (0..n).map(|i| per.iter().map(|p| p[i]).sum::<f64>() / s).collect();
    // Variance of each pixel's mean over the seeds.
    let var: Vec<f64> =
        (0..n).map(|i| per.iter().map(|p| (p[i] - mean[i]).powi(2)).sum::<f64>() / (s - 1.0) / s).collect();
    let reference_share = spp as f64 * s / f64::from(reference_spp);
    let image_mean = r.iter().sum::<f64>() / n as f64;
    let (mut relative, mut noise, mut worst) = (Vec::new(), Vec::new(), (0.0f64, (0, 0), 1.0));
    let mut beyond_5_sigma = 0;
    for by in 0..h / block {
        for bx in 0..w / block {
            let (mut a, mut b, mut v) = (0.0, 0.0, 0.0);
            for y in by * block..(by + 1) * block {
                for x in bx * block..(bx + 1) * block {
                    let i = y * w + x;
                    a += mean[i];
                    b += r[i];
                    v += var[i];
                }
            }
            let m = (block * block) as f64;
            let (a, b, v) = (a / m, b / m, v / (m * m));
            relative.push((a - b).abs() / (b + 0.01 * image_mean));
            let sigma = (v * (1.0 + reference_share)).sqrt();
            noise.push(sigma / (b + 0.01 * image_mean));
            let z = (a - b).abs() / sigma.max(1e-12);
            beyond_5_sigma += usize::from(z > 5.0);
            if z > worst.0 {
                worst = (z, (bx, by), a / b);
            }
        }
    }
    relative.sort_by(f64::total_cmp);
    noise.sort_by(f64::total_cmp);
    let mean_sigma = (var.iter().sum::<f64>() * (1.0 + reference_share)).sqrt() / r.iter().sum::<f64>();
    Fidelity {
        mean_ratio: mean.iter().sum::<f64>() / r.iter().sum::<f64>(),
        mean_sigma,
        blocks: relative.len(),
        beyond_5_sigma,
        block_median: relative[relative.len() / 2],
        noise_median: noise[noise.len() / 2],
        worst_z: worst.0,
        worst_block: worst.1,
        worst_ratio: worst.2,
    }
}

/// Renders `name`'s pbrt-v4 file with `seeds` × `spp` path-traced samples per pixel at the
/// reference's resolution and the file's own depth; compares with pbrt-v4's image.
fn against_pbrt(dir: &Path, name: &str, seeds: u64, spp: u32, reference_spp: u32) -> Fidelity {
    let folder = dir.join(name).join("pbrt-v4");
    let reference = read_image(&folder.join("reference-pbrt-v4.exr"), ColorEncoding::Linear).unwrap();
    let loaded = load(&folder.join("scene-v4.pbrt"), &LoadOptions::default()).unwrap();
    let mut scene = loaded.builder.build().unwrap();
    scene.set_resolution(reference.width as u32, reference.height as u32);
    let integrator = PathIntegrator::new(scene.defaults.max_depth);
    let cancel = AtomicBool::new(false);
    let control = RenderControl::new(&cancel, &|_| {});
    let renders: Vec<Image> = (0..seeds)
        .map(|seed| {
            let settings = RenderSettings { budget: Budget::Samples(spp), seed: 100 + seed, threads: 0 };
            integrator.render(&scene, &settings, &control).unwrap().image
        })
        .collect();
    let f = fidelity(&renders, spp, &reference, reference_spp, 8);
    eprintln!(
        "{name}: mean ratio {:.4} ± {:.4}, block median {:.2} % (noise {:.2} %), {} of {} blocks beyond 5σ, \
         worst block {:?} at {:.1}σ (ratio {:.3})",
        f.mean_ratio,
        f.mean_sigma,
        100.0 * f.block_median,
        100.0 * f.noise_median,
        f.beyond_5_sigma,
        f.blocks,
        f.worst_block,
        f.worst_z,
        f.worst_ratio
    );
    f
}

/// Every shared pbrt-v4 scene that a path tracer renders (water-caustic asks for SPPM) against
/// pbrt-v4's image: the image mean within 1 % (plus three standard deviations of both images'
/// noise), the median block within 2 % (plus the median block noise, most of it the
/// reference's own), and at most as many blocks beyond 5σ as the differences explained in the
/// README's fidelity table leave: pbrt-v4 renders spectrally, Tempera in RGB, so saturated
/// colours that light reaches after several bounces differ (the Cornell box's red wall under
/// its orange light, coffee's orange body), and the silhouettes of veach-mis's very bright
/// spheres differ at the pixel level; coffee also lacks a highlight under its carafe that
/// pbrt-v4 shows, in every integrator.
#[test]
fn shared_scenes_match_pbrt_v4s_own_renders() {
    let Some(dir) = shared_scenes() else { return };
    // name, samples per seed (four seeds), the reference's samples, blocks allowed beyond 5σ.
    let scenes = [
        ("cornell-box", 64, 4096, 70),
        ("veach-mis", 64, 2048, 28),
        ("coffee", 128, 4096, 40),
        ("classroom", 128, 1024, 5),
        ("veach-ajar", 256, 2048, 3),
    ];
    for (name, spp, reference_spp, allowed) in scenes {
        let f = against_pbrt(&dir, name, 4, spp, reference_spp);
        assert!((f.mean_ratio - 1.0).abs() < 0.01 + 3.0 * f.mean_sigma, "{name}: image mean {f:?}");
        assert!(f.block_median < 0.02 + f.noise_median, "{name}: median block {f:?}");
        assert!(f.beyond_5_sigma <= allowed, "{name}: blocks beyond 5σ {f:?}");
        assert!(f.worst_ratio > 0.5 && f.worst_ratio < 1.5, "{name}: worst block {f:?}");
    }
}
