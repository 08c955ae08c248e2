//! SPPM against analytic answers and BDPT, with uniform and with MCMC photons: power
//! conservation in a closed glowing box, agreement with BDPT on a Cornell box, and the same
//! image at any thread count.

use super::*;
use crate::camera::CameraDesc;
use crate::film::FilmDesc;
use crate::integrator::tests::{block_stats, mean_and_se, render_with};
use crate::integrator::{BdptIntegrator, Budget};
use crate::material::Material;
use crate::scene::{AreaEmission, SceneBuilder};
use crate::scenes::oriented_quad;

/// Inside a closed box whose walls all emit `L_e = 1` and reflect diffusely with albedo `ρ`,
/// radiance is `L_e·Σ_{k ≤ D} ρ^k` everywhere for paths of at most `D` bounces: the direct
/// estimate carries `k = 0, 1` and the photons every `k ≥ 2`, so their power must be exact.
#[test]
fn sppm_conserves_power_in_a_closed_glowing_box() {
    let rho = 0.5f32;
    let depth = 6;
    let mut b = SceneBuilder::new();
    let wall = b.add_material(Material::diffuse(Rgb::splat(rho)));
    let emission = AreaEmission { radiance: Rgb::ONE.into(), scale: 1.0, two_sided: false };
    for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
        for s in [-1.0f32, 1.0] {
            let up = if axis == Vec3::Y { Vec3::Z } else { Vec3::Y };
            // Each wall faces the inside.
            b.add_shape(oriented_quad(axis * s, -axis * s, up, 1.0, 1.0), wall, Some(emission.clone()));
        }
    }
    b.set_camera(CameraDesc::look_at(Vec3::ZERO, Vec3::new(0.0, 0.0, -1.0), Vec3::Y, 40.0));
    b.set_film(FilmDesc { width: 12, height: 12, ..FilmDesc::default() });
    let scene = b.build().unwrap();
    let expected: f64 = (0..=depth).map(|k| f64::from(rho).powi(k as i32)).sum();
    for photon_sampler in [PhotonSampler::Uniform, PhotonSampler::Mcmc] {
        let sppm = SppmIntegrator { photons: 20_000, radius: 0.05, photon_sampler, ..SppmIntegrator::new(depth) };
        let out = render_with(&scene, &sppm, Budget::Samples(24), 3, 0);
        let values: Vec<f64> = out.image.pixels.iter().map(|p| f64::from(p.y)).collect();
        let (mean, se) = mean_and_se(&values);
        let name = format!("{photon_sampler:?}");
        assert!((mean - expected).abs() < 4.0 * se + 0.02 * expected, "{name}: {mean} ± {se}, expected {expected}");
        assert_eq!(out.stats.spp_completed, 24);
        assert!(out.image.pixels.iter().all(|p| p.is_finite()));
    }
}

/// SPPM converges to BDPT's image on a Cornell box (its bias shrinks with the radius): image
/// means within 3 %, every 8×8 block within its noise plus 8 %.
#[test]
fn sppm_agrees_with_bdpt_on_a_cornell_box() {
    let scene = crate::scenes::cornell_box(16, 16).build().unwrap();
    let bdpt = render_with(&scene, &BdptIntegrator::new(5), Budget::Samples(256), 1, 0);
    let b = block_stats(&bdpt.image, 8);
    let mean = |s: &[(f64, f64)]| s.iter().map(|v| v.0).sum::<f64>() / s.len() as f64;
    for photon_sampler in [PhotonSampler::Uniform, PhotonSampler::Mcmc] {
        let sppm = SppmIntegrator { photons: 20_000, radius: 0.05, photon_sampler, ..SppmIntegrator::new(5) };
        let out = render_with(&scene, &sppm, Budget::Samples(64), 2, 0);
        let a = block_stats(&out.image, 8);
        let name = format!("{photon_sampler:?}");
        assert!((mean(&a) / mean(&b) - 1.0).abs() < 0.03, "{name}: image means {} vs {}", mean(&a), mean(&b));
        for (i, ((ma, sa), (mb, sb))) in a.iter().zip(&b).enumerate() {
            let se = (sa * sa + sb * sb).sqrt();
            assert!((ma - mb).abs() < 4.0 * se + 0.08 * mb, "{name}, block {i}: sppm {ma} vs bdpt {mb} (se {se})");
        }
    }
}

/// Photon sums add up in fixed point, every number comes from a hash and the photon chains
/// are as many whatever the threads: 1, 2 and 3 threads give the same image bit for bit.
#[test]
fn sppm_renders_the_same_image_at_any_thread_count() {
    let scene = crate::scenes::default_scene().build().unwrap();
    let mut scene = scene;
    scene.set_resolution(24, 24);
    for photon_sampler in [PhotonSampler::Uniform, PhotonSampler::Mcmc] {
        let sppm = SppmIntegrator { photons: 3000, radius: 0.1, photon_sampler, ..SppmIntegrator::new(5) };
        let images: Vec<Vec<[u32; 3]>> = [1, 2, 3]
            .iter()
            .map(|&threads| {
                let out = render_with(&scene, &sppm, Budget::Samples(3), 9, threads);
                out.image.pixels.iter().map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()]).collect()
            })
            .collect();
        assert!(images[0].iter().any(|p| p[1] != 0), "something was rendered");
        assert_eq!(images[0], images[1], "{photon_sampler:?}");
        assert_eq!(images[0], images[2], "{photon_sampler:?}");
    }
}
