//! Participating media in the path tracer: a slab of known optical depth (transmittance
//! analytic), a non-absorbing medium in a uniformly lit enclosure (every pixel exactly the
//! sky's radiance), next-event estimation through media and interfaces agreeing with BSDF and
//! phase sampling alone; BDPT on the same analytic scenes and against the path tracer, and the
//! Markov-chain integrators against BDPT.

use super::tests::{assert_agree, mean_and_se, render_with};
use super::*;
use crate::camera::CameraDesc;
use crate::film::FilmDesc;
use crate::geometry::{Shape, Sphere};
use crate::light::{InfiniteLight, Light};
use crate::material::Material;
use crate::math::{Rgb, Vec3};
use crate::medium::{Medium, MediumInterface};
use crate::scene::{AreaEmission, SceneBuilder};
use crate::scenes::oriented_quad;

/// A camera looking down −z through a slab `−1 < z < 1` of `medium` (two interface planes)
/// at an emitter of radiance 1 at `z = −2`.
fn slab(medium: Medium) -> crate::scene::Scene {
    let mut b = SceneBuilder::new();
    let interface = b.add_material(Material::Interface);
    let black = b.add_material(Material::diffuse(Rgb::ZERO));
    let m = b.add_medium(medium);
    for z in [1.0f32, -1.0] {
        let normal = Vec3::new(0.0, 0.0, z.signum());
        b.add_shape(oriented_quad(Vec3::new(0.0, 0.0, z), normal, Vec3::X, 50.0, 50.0), interface, None);
        b.set_shape_medium(b.shape_count() - 1, MediumInterface { inside: Some(m), outside: None });
    }
    let emission = AreaEmission { radiance: Rgb::ONE.into(), scale: 1.0, two_sided: false };
    b.add_shape(oriented_quad(Vec3::new(0.0, 0.0, -2.0), Vec3::Z, Vec3::X, 50.0, 50.0), black, Some(emission));
    b.set_camera(CameraDesc::look_at(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y, 8.0));
    b.set_film(FilmDesc { width: 16, height: 16, ..FilmDesc::default() });
    b.build().unwrap()
}

/// A unit sphere of non-absorbing chromatic medium (asymmetry `g`) bounded by an interface,
/// under a uniform sky of radiance 1, seen whole.
fn medium_sphere_under_sky(g: f32) -> crate::scene::Scene {
    let mut b = SceneBuilder::new();
    let interface = b.add_material(Material::Interface);
    let m = b.add_medium(Medium { sigma_a: Rgb::ZERO, sigma_s: Rgb::new(0.5, 1.0, 2.0), g });
    b.add_shape(Shape::Sphere(Sphere { center: Vec3::ZERO, radius: 1.0, reverse_orientation: false }), interface, None);
    b.set_shape_medium(0, MediumInterface { inside: Some(m), outside: None });
    b.add_light(Light::Infinite(InfiniteLight::uniform(Rgb::ONE)));
    b.set_camera(CameraDesc::look_at(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, Vec3::Y, 30.0));
    b.set_film(FilmDesc { width: 16, height: 16, ..FilmDesc::default() });
    b.build().unwrap()
}

/// Asserts each channel's pixel mean is `expected(c)` within four standard errors plus
/// `slack(expected)`.
fn assert_channel_means(
    name: &str,
    image: &crate::texture::Image,
    expected: impl Fn(usize) -> f64,
    slack: impl Fn(f64) -> f64,
) {
    for c in 0..3 {
        let values: Vec<f64> = image.pixels.iter().map(|p| f64::from(p[c])).collect();
        let (mean, se) = mean_and_se(&values);
        let e = expected(c);
        assert!((mean - e).abs() < 4.0 * se + slack(e), "{name}, channel {c}: {mean} ± {se}, expected {e}");
    }
}

/// Seen through a purely absorbing slab of thickness 2, the emitter's radiance is
/// `exp(−2σa/cos θ)` per channel; a scattering-only slab lets through `exp(−2σs/cos θ)`
/// directly and more by scattering, never more than the emitter.
#[test]
fn a_slab_of_known_optical_depth_transmits_its_analytic_fraction() {
    let sigma_a = Rgb::new(0.1, 0.4, 1.0);
    let scene = slab(Medium { sigma_a, sigma_s: Rgb::ZERO, g: 0.0 });
    let out = render_with(&scene, &PathIntegrator::new(4), Budget::Samples(64), 3, 0);
    // The fov is 8°: 1/cos θ stays below 1.002 over the film.
    assert_channel_means("path, absorbing slab", &out.image, |c| f64::from((-2.0 * sigma_a[c]).exp()), |e| 0.002 * e);
    let scattering = slab(Medium { sigma_a: Rgb::ZERO, sigma_s: Rgb::splat(0.5), g: 0.7 });
    let out = render_with(&scattering, &PathIntegrator::new(50), Budget::Samples(64), 4, 0);
    let values: Vec<f64> = out.image.pixels.iter().map(|p| f64::from(p.y)).collect();
    let (mean, _) = mean_and_se(&values);
    assert!(mean > f64::from((-1.0f32).exp()) * 1.05 && mean < 1.0, "scattering slab: {mean}");
}

/// A sphere of non-absorbing medium (any `g`) under a uniform sky of radiance 1 is radiance 1
/// everywhere: light is only redistributed. Each pixel that sees the sphere is 1 within noise.
#[test]
fn a_non_absorbing_medium_under_a_uniform_sky_is_the_sky() {
    for g in [0.0f32, 0.6] {
        let scene = medium_sphere_under_sky(g);
        let out = render_with(&scene, &PathIntegrator::new(1000), Budget::Samples(64), 5, 0);
        assert_channel_means(&format!("path, g {g}"), &out.image, |_| 1.0, |_| 1e-3);
    }
}

/// A Cornell box filled with a scattering, absorbing medium (the camera inside it too):
/// next-event estimation through the medium, MIS-weighted, agrees with finding the light by
/// phase and BSDF sampling alone.
#[test]
fn next_event_estimation_through_media_agrees_with_sampling_alone() {
    let mut b = crate::scenes::cornell_box(16, 16);
    let m = b.add_medium(Medium { sigma_a: Rgb::splat(0.2), sigma_s: Rgb::new(0.8, 0.6, 0.4), g: 0.3 });
    let interface = b.add_material(Material::Interface);
    b.add_shape(
        Shape::Sphere(Sphere { center: Vec3::new(0.0, 1.0, 0.0), radius: 3.0, reverse_orientation: false }),
        interface,
        None,
    );
    b.set_shape_medium(b.shape_count() - 1, MediumInterface { inside: Some(m), outside: None });
    b.set_camera_medium(Some(m));
    let scene = b.build().unwrap();
    let nee = render_with(&scene, &PathIntegrator::new(6), Budget::Samples(256), 7, 0);
    let alone = PathIntegrator { max_depth: 6, next_event: false };
    let plain = render_with(&scene, &alone, Budget::Samples(2048), 8, 0);
    let mean = |img: &crate::texture::Image| {
        let v: Vec<f64> = img.pixels.iter().map(|p| f64::from(p.y)).collect();
        mean_and_se(&v)
    };
    let ((a, sa), (b, sb)) = (mean(&nee.image), mean(&plain.image));
    assert!(a > 0.0 && (a - b).abs() < 4.0 * (sa * sa + sb * sb).sqrt(), "with NEE {a} ± {sa}, without {b} ± {sb}");
    assert_eq!(nee.stats.invalid_samples, 0);
}

/// BDPT through media: the absorbing slab's analytic transmittance (every strategy, through
/// two interface surfaces), and radiance 1 inside a non-absorbing medium under a uniform sky
/// (light subpaths from the sky enter the medium through its boundary).
#[test]
fn bdpt_transmits_the_slab_analytically_and_keeps_the_sky_in_a_non_absorbing_medium() {
    let sigma_a = Rgb::new(0.1, 0.4, 1.0);
    let scene = slab(Medium { sigma_a, sigma_s: Rgb::ZERO, g: 0.0 });
    let out = render_with(&scene, &BdptIntegrator::new(4), Budget::Samples(32), 3, 0);
    assert_channel_means("bdpt, absorbing slab", &out.image, |c| f64::from((-2.0 * sigma_a[c]).exp()), |e| 0.002 * e);
    let out = render_with(&medium_sphere_under_sky(0.6), &BdptIntegrator::new(100), Budget::Samples(32), 5, 0);
    assert_channel_means("bdpt, g 0.6", &out.image, |_| 1.0, |_| 2e-3);
}

/// BDPT in a scattering medium agrees with the path tracer block by block, and so does the
/// light-tracing strategy alone (medium vertices connected to the lens).
#[test]
fn bdpt_agrees_with_the_path_tracer_in_a_scattering_medium() {
    let scene = crate::testing::foggy_cornell_box(24);
    let path = render_with(&scene, &PathIntegrator::new(6), Budget::Samples(512), 11, 0);
    let bdpt = render_with(&scene, &BdptIntegrator::new(6), Budget::Samples(128), 12, 0);
    assert_eq!(bdpt.stats.invalid_samples, 0);
    assert_agree("bdpt vs path in a medium", &bdpt.image, &path.image, 8, 0.01);
    let lt = BdptIntegrator { strategies: crate::integrator::bdpt::Strategies::LightTracing, ..BdptIntegrator::new(6) };
    let light_tracing = render_with(&scene, &lt, Budget::Samples(256), 13, 0);
    assert_agree("light tracing vs path in a medium", &light_tracing.image, &path.image, 8, 0.03);
}

/// The Markov-chain integrators in a scattering medium agree with BDPT (the image mean of eight
/// seeds within three of its standard errors of a 4096-spp BDPT render's, plus 1 % for the
/// reference's own error; every 8×8 block of one seed within the noise of a 512-spp render plus
/// 5 %). One seed of PSSMLT at 1024 mutations per pixel spreads by about 2 % in its image mean
/// here, MMLT's by a few tenths of a percent.
#[test]
fn markov_chain_integrators_agree_with_bdpt_in_a_scattering_medium() {
    let scene = crate::testing::foggy_cornell_box(16);
    let bdpt = render_with(&scene, &BdptIntegrator::new(6), Budget::Samples(512), 21, 0);
    let reference = super::tests::block_stats(&bdpt.image, 8);
    let mean = |s: &[(f64, f64)]| s.iter().map(|v| v.0).sum::<f64>() / s.len() as f64;
    let fine = render_with(&scene, &BdptIntegrator::new(6), Budget::Samples(4096), 31, 0);
    let b = mean(&super::tests::block_stats(&fine.image, 8));
    for integrator in [
        &MmltIntegrator { bootstrap: 100_000, ..MmltIntegrator::new(6) } as &dyn Integrator,
        &PssmltIntegrator::new(6),
        &TemperedIntegrator { ensembles_below: 0, bdpt_above: None, ..TemperedIntegrator::new(6) },
    ] {
        let out = render_with(&scene, integrator, Budget::Samples(1024), 22, 0);
        let name = integrator.name();
        assert!(out.chains.iter().all(|d| d.invalid == 0), "{name}: invalid samples");
        let blocks = super::tests::block_stats(&out.image, 8);
        let others = (23..30).map(|seed| render_with(&scene, integrator, Budget::Samples(1024), seed, 0));
        let ratios: Vec<f64> = std::iter::once(mean(&blocks))
            .chain(others.map(|o| mean(&super::tests::block_stats(&o.image, 8))))
            .map(|a| a / b)
            .collect();
        let (ratio, se) = mean_and_se(&ratios);
        assert!((ratio - 1.0).abs() < 0.01 + 3.0 * se, "{name}: image mean over bdpt's {ratio} ± {se} ({ratios:?})");
        for (i, ((ma, _), (mb, sb))) in blocks.iter().zip(&reference).enumerate() {
            assert!((ma - mb).abs() < 4.0 * sb + 0.05 * mb, "{name}, block {i}: {ma} vs bdpt {mb} ± {sb}");
        }
    }
}
