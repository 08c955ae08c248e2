//! Chi-square tests of light sampling against the claimed solid-angle densities, and checks that
//! sampled radiance matches what a ray towards the sample sees.

use super::*;
use crate::geometry::{Disk, Geometry, Ray, RayShear, Shape, Sphere, TriangleMesh};
use crate::math::Mat3;
use crate::testing::chi2_sphere;
use crate::texture::Image;
use std::sync::Arc;

fn emitter_geometry() -> Geometry {
    let tri = TriangleMesh::new(
        vec![
            Vec3::new(-1.0, 2.0, -0.5),
            Vec3::new(1.5, 2.5, 0.0),
            Vec3::new(0.0, 1.5, 1.5),
        ],
        vec![[0, 1, 2]],
        None,
        None,
    )
    .unwrap();
    Geometry::new(vec![
        Shape::Mesh(tri),
        Shape::Sphere(Sphere {
            center: Vec3::new(0.5, 0.3, 2.0),
            radius: 0.7,
            reverse_orientation: false,
        }),
        Shape::Disk(Disk::new(
            Vec3::new(-1.0, -1.0, 0.5),
            Vec3::new(0.3, 1.0, 0.2),
            0.8,
        )),
        Shape::Sphere(Sphere {
            center: Vec3::new(0.0, 0.0, 0.0),
            radius: 3.0,
            reverse_orientation: true,
        }),
    ])
}

#[test]
fn area_light_sampling_matches_pdf() {
    let geometry = emitter_geometry();
    let reference = Vec3::new(0.1, -0.2, 0.05);
    for prim in 0..geometry.prims.len() as u32 {
        let light = AreaLight {
            prim,
            radiance: Rgb::ONE.into(),
            scale: 1.0,
            two_sided: true,
        };
        let r = chi2_sphere(
            300_000,
            u64::from(prim) + 10,
            |u, _| light.sample_li(&geometry, reference, u).map(|s| s.wi),
            |w| {
                let ray = Ray::new(reference, w);
                match geometry.intersect_prim(prim, &ray, &RayShear::new(&ray), f32::INFINITY) {
                    Some((t, b)) => {
                        let hit = geometry.surface(&ray, &crate::geometry::PrimHit { prim, t, b });
                        f64::from(light.pdf_li(&geometry, reference, &hit))
                    }
                    None => 0.0,
                }
            },
        );
        assert!(
            r.p_value > 1e-4,
            "primitive {prim}: chi-square p = {:e}",
            r.p_value
        );
        assert!(
            (r.pdf_integral - 1.0).abs() < 0.01,
            "primitive {prim}: ∫pdf = {}",
            r.pdf_integral
        );
    }
}

fn test_image() -> Arc<Image> {
    let (w, h) = (32, 16);
    let pixels = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let hot = if (x, y) == (5, 3) || (x, y) == (20, 12) {
                200.0
            } else {
                0.0
            };
            Rgb::new(0.1 + x as f32 * 0.02 + hot, 0.2, 0.05 + y as f32 * 0.03)
        })
        .collect();
    Arc::new(Image::new(w, h, pixels))
}

#[test]
fn environment_sampling_matches_pdf() {
    let rotation = Mat3::from_axis_angle(Vec3::new(1.0, 2.0, 0.5).normalize(), 0.7);
    let lights = [
        InfiniteLight::uniform(Rgb::ONE),
        InfiniteLight::image(test_image(), EnvironmentMap::LatLong, rotation, Rgb::ONE),
        InfiniteLight::image(test_image(), EnvironmentMap::EqualArea, rotation, Rgb::ONE),
    ];
    for (i, light) in lights.iter().enumerate() {
        let r = chi2_sphere(
            400_000,
            i as u64,
            |u, _| light.sample_li(Vec3::ZERO, u).map(|s| s.wi),
            |w| f64::from(light.pdf_dir(w)),
        );
        assert!(
            r.p_value > 1e-4,
            "environment {i}: chi-square p = {:e}",
            r.p_value
        );
        assert!(
            (r.pdf_integral - 1.0).abs() < 0.01,
            "environment {i}: ∫pdf = {}",
            r.pdf_integral
        );
        // The sampled radiance is what an escaping ray in that direction sees, and the density
        // is proportional to it (up to the parametrisation's Jacobian).
        let s = light.sample_li(Vec3::ZERO, Vec2::new(0.3, 0.6)).unwrap();
        assert_eq!(s.li, light.le(s.wi));
        assert!((light.pdf_dir(s.wi) - s.pdf).abs() < 1e-3 * s.pdf);
    }
}

#[test]
fn light_selection_follows_power() {
    let sampler = LightSampler::new(&[1.0, 3.0, 0.0]);
    assert_eq!(sampler.pmf(0), 0.25);
    assert_eq!(sampler.pmf(1), 0.75);
    assert_eq!(sampler.pmf(2), 0.0);
    assert!(LightSampler::new(&[]).sample(0.5).is_none());
}

#[test]
fn one_sided_area_lights_emit_on_the_normal_side_only() {
    let geometry = emitter_geometry();
    let disk_light = AreaLight {
        prim: 2,
        radiance: Rgb::ONE.into(),
        scale: 2.0,
        two_sided: false,
    };
    let n = Vec3::new(0.3, 1.0, 0.2).normalize();
    let front = Vec3::new(-1.0, -1.0, 0.5) + n * 2.0;
    let back = Vec3::new(-1.0, -1.0, 0.5) - n * 2.0;
    let u = Vec2::new(0.4, 0.4);
    assert_eq!(
        disk_light.sample_li(&geometry, front, u).unwrap().li,
        Rgb::splat(2.0)
    );
    assert_eq!(
        disk_light.sample_li(&geometry, back, u).unwrap().li,
        Rgb::ZERO
    );
}

#[test]
fn spotlight_falls_off_smoothly() {
    let spot = SpotLight::new(Vec3::ZERO, Vec3::Z, Rgb::ONE, 30.0, 10.0);
    assert_eq!(spot.i(Vec3::Z), Rgb::ONE);
    let edge = Vec3::new(31f32.to_radians().sin(), 0.0, 31f32.to_radians().cos());
    assert_eq!(spot.i(edge), Rgb::ZERO);
    let mid = Vec3::new(25f32.to_radians().sin(), 0.0, 25f32.to_radians().cos());
    assert!(spot.i(mid).x > 0.0 && spot.i(mid).x < 1.0);
}
