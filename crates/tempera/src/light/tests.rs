//! Chi-square tests of light sampling against the claimed solid-angle densities, and checks that
//! sampled radiance matches what a ray towards the sample sees.

use super::*;
use crate::geometry::{Disk, Geometry, Ray, RayShear, Shape, Sphere, TriangleMesh};
use crate::light::SceneSphere;
use crate::math::Mat3;
use crate::math::frame::Frame;
use crate::testing::{Binning, chi2_directions, chi2_p_value, chi2_sphere};
use crate::texture::Image;
use std::sync::Arc;

fn emitter_geometry() -> Geometry {
    let tri = TriangleMesh::new(
        vec![Vec3::new(-1.0, 2.0, -0.5), Vec3::new(1.5, 2.5, 0.0), Vec3::new(0.0, 1.5, 1.5)],
        vec![[0, 1, 2]],
        None,
        None,
    )
    .unwrap();
    Geometry::new(vec![
        Shape::Mesh(tri),
        Shape::Sphere(Sphere { center: Vec3::new(0.5, 0.3, 2.0), radius: 0.7, reverse_orientation: false }),
        Shape::Disk(Disk::new(Vec3::new(-1.0, -1.0, 0.5), Vec3::new(0.3, 1.0, 0.2), 0.8)),
        Shape::Sphere(Sphere { center: Vec3::new(0.0, 0.0, 0.0), radius: 3.0, reverse_orientation: true }),
    ])
}

/// Solid-angle density of `light` towards direction `w` from `reference` (0 on a miss).
fn area_pdf(geometry: &Geometry, light: &AreaLight, reference: Vec3, w: Vec3) -> f64 {
    let ray = Ray::new(reference, w);
    let prim = light.prim;
    match geometry.intersect_prim(prim, &ray, &RayShear::new(&ray), f32::INFINITY) {
        Some(hit) => f64::from(light.pdf_li(geometry, reference, &geometry.surface(&ray, &hit))),
        None => 0.0,
    }
}

fn light_on(prim: u32) -> AreaLight {
    AreaLight { prim, radiance: Rgb::ONE.into(), scale: 1.0, two_sided: true }
}

const REFERENCE: Vec3 = Vec3::new(0.1, -0.2, 0.05);

#[test]
fn sphere_light_cone_sampling_matches_pdf() {
    let geometry = emitter_geometry();
    let light = light_on(1);
    let (center, radius) = (Vec3::new(0.5, 0.3, 2.0), 0.7f64);
    let axis = (center - REFERENCE).normalize();
    let sin2 = radius * radius / f64::from((center - REFERENCE).length_squared());
    let binning = Binning::Cap { frame: Frame::from_z(axis), cos_min: (1.0 - sin2).sqrt() };
    let r = chi2_directions(
        binning,
        300_000,
        1,
        |u, _| light.sample_li(&geometry, REFERENCE, u).map(|s| s.wi),
        |w| area_pdf(&geometry, &light, REFERENCE, w),
    );
    assert!(r.p_value > 1e-4, "sphere cone: {r:?}");
    assert!((r.pdf_integral - 1.0).abs() < 0.01, "sphere cone: {r:?}");
}

#[test]
fn sphere_light_sampled_from_inside_matches_pdf() {
    let geometry = emitter_geometry();
    let light = light_on(3);
    let r = chi2_sphere(
        300_000,
        2,
        |u, _| light.sample_li(&geometry, REFERENCE, u).map(|s| s.wi),
        |w| area_pdf(&geometry, &light, REFERENCE, w),
    );
    assert!(r.p_value > 1e-4 && (r.pdf_integral - 1.0).abs() < 0.01, "inside sphere: {r:?}");
}

/// Samples points on `light` and bins them in a parametrisation where uniform area sampling
/// is uniform; returns the chi-square p-value.
fn area_domain_p_value(
    geometry: &Geometry,
    light: &AreaLight,
    to_unit: impl Fn(Vec3) -> Vec2,
    expected: &[f64],
    grid: usize,
) -> f64 {
    let mut rng = crate::math::rng::Pcg32::new(u64::from(light.prim), 9);
    let mut counts = vec![0u64; grid * grid];
    let n = expected.iter().sum::<f64>().round() as usize;
    for _ in 0..n {
        let s = light.sample_li(geometry, REFERENCE, Vec2::new(rng.next_f32(), rng.next_f32())).unwrap();
        let q = to_unit(s.p);
        let (i, j) = (((q.x * grid as f32) as usize).min(grid - 1), ((q.y * grid as f32) as usize).min(grid - 1));
        counts[j * grid + i] += 1;
    }
    chi2_p_value(&counts, expected)
}

#[test]
fn triangle_and_disk_lights_sample_area_uniformly() {
    let geometry = emitter_geometry();
    let (n, grid) = (200_000.0, 16);
    // Triangle: barycentrics (b1, b2) are uniform on the lower-left half of the unit square.
    let [p0, p1, p2] = match &geometry.shapes[0] {
        Shape::Mesh(m) => m.vertices(0),
        _ => unreachable!(),
    };
    let barycentric = |p: Vec3| {
        let (v0, v1, v2) = (p1 - p0, p2 - p0, p - p0);
        let (d00, d01, d11, d20, d21) = (v0.dot(v0), v0.dot(v1), v1.dot(v1), v2.dot(v0), v2.dot(v1));
        let denom = d00 * d11 - d01 * d01;
        Vec2::new((d11 * d20 - d01 * d21) / denom, (d00 * d21 - d01 * d20) / denom)
    };
    let expected: Vec<f64> = (0..grid * grid)
        .map(|k| {
            let (i, j) = (k % grid, k / grid);
            let cell = 1.0 / (grid * grid) as f64;
            match (i + j + 1).cmp(&grid) {
                std::cmp::Ordering::Less => n * cell * 2.0,
                std::cmp::Ordering::Equal => n * cell,
                std::cmp::Ordering::Greater => 0.0,
            }
        })
        .collect();
    let p = area_domain_p_value(&geometry, &light_on(0), barycentric, &expected, grid);
    assert!(p > 1e-4, "triangle area sampling: p = {p:e}");

    // Disk: (r/R)² and φ/2π are uniform.
    let Shape::Disk(disk) = geometry.shapes[2] else { unreachable!() };
    let polar = |p: Vec3| {
        let l = disk.frame.to_local(p - disk.center);
        let phi = crate::math::warp::spherical_phi(Vec3::new(l.x, l.y, 0.0));
        Vec2::new((l.x * l.x + l.y * l.y) / (disk.radius * disk.radius), phi / (2.0 * std::f32::consts::PI))
    };
    let expected = vec![n / (grid * grid) as f64; grid * grid];
    let p = area_domain_p_value(&geometry, &light_on(2), polar, &expected, grid);
    assert!(p > 1e-4, "disk area sampling: p = {p:e}");
}

#[test]
fn area_to_solid_angle_conversion_recovers_the_subtended_solid_angle() {
    // E[1 / pdf] over samples is the solid angle the light subtends.
    let geometry = emitter_geometry();
    let expected_triangle = {
        let [a, b, c] = match &geometry.shapes[0] {
            Shape::Mesh(m) => m.vertices(0).map(|v| (v - REFERENCE).as_dvec3()),
            _ => unreachable!(),
        };
        let (la, lb, lc) = (a.length(), b.length(), c.length());
        let num = a.dot(b.cross(c)).abs();
        let den = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
        2.0 * num.atan2(den)
    };
    let expected_disk = {
        let Shape::Disk(d) = geometry.shapes[2] else { unreachable!() };
        let (nr, np) = (400, 400);
        let mut sum = 0.0f64;
        for i in 0..nr {
            let r = (f64::from(i) + 0.5) / f64::from(nr) * f64::from(d.radius);
            for j in 0..np {
                let phi = (f64::from(j) + 0.5) / f64::from(np) * std::f64::consts::TAU;
                let p = d.center.as_dvec3() + (d.frame.s.as_dvec3() * phi.cos() + d.frame.t.as_dvec3() * phi.sin()) * r;
                let w = p - REFERENCE.as_dvec3();
                sum += d.frame.n.as_dvec3().dot(w).abs() / w.length().powi(3) * r;
            }
        }
        sum * f64::from(d.radius) / f64::from(nr) * std::f64::consts::TAU / f64::from(np)
    };
    let sphere_cap = {
        let sin2 = 0.49 / f64::from((Vec3::new(0.5, 0.3, 2.0) - REFERENCE).length_squared());
        std::f64::consts::TAU * (1.0 - (1.0 - sin2).sqrt())
    };
    for (prim, want) in [(0, expected_triangle), (1, sphere_cap), (2, expected_disk)] {
        let light = light_on(prim);
        let mut rng = crate::math::rng::Pcg32::new(3, u64::from(prim));
        let n = 200_000;
        let mut sum = 0.0f64;
        for _ in 0..n {
            let s = light.sample_li(&geometry, REFERENCE, Vec2::new(rng.next_f32(), rng.next_f32())).unwrap();
            assert!((f64::from(s.pdf) - area_pdf(&geometry, &light, REFERENCE, s.wi)).abs() < 1e-3 * f64::from(s.pdf));
            sum += 1.0 / f64::from(s.pdf);
        }
        let got = sum / f64::from(n);
        assert!((got - want).abs() < 0.01 * want, "primitive {prim}: solid angle {got} vs {want}");
    }
}

fn test_image() -> Arc<Image> {
    let (w, h) = (32, 16);
    let pixels = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let hot = if (x, y) == (5, 3) || (x, y) == (20, 12) { 200.0 } else { 0.0 };
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
        assert!(r.p_value > 1e-4, "environment {i}: chi-square p = {:e}", r.p_value);
        assert!((r.pdf_integral - 1.0).abs() < 0.01, "environment {i}: ∫pdf = {}", r.pdf_integral);
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
    let disk_light = AreaLight { prim: 2, radiance: Rgb::ONE.into(), scale: 2.0, two_sided: false };
    let n = Vec3::new(0.3, 1.0, 0.2).normalize();
    let front = Vec3::new(-1.0, -1.0, 0.5) + n * 2.0;
    let back = Vec3::new(-1.0, -1.0, 0.5) - n * 2.0;
    let u = Vec2::new(0.4, 0.4);
    assert_eq!(disk_light.sample_li(&geometry, front, u).unwrap().li, Rgb::splat(2.0));
    assert_eq!(disk_light.sample_li(&geometry, back, u).unwrap().li, Rgb::ZERO);
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

#[test]
fn textured_area_light_radiance_follows_uv() {
    use crate::texture::{Checkerboard, Texture, UvMapping};
    let geometry = emitter_geometry();
    let radiance = Texture::Checkerboard(Box::new(Checkerboard {
        even: Rgb::new(4.0, 0.0, 0.0).into(),
        odd: Rgb::new(0.0, 0.0, 2.0).into(),
        mapping: UvMapping { su: 2.0, sv: 1.0, du: 0.0, dv: 0.0 },
    }));
    let light = AreaLight { prim: 2, radiance, scale: 0.5, two_sided: true };
    let mut seen = [false; 2];
    let mut rng = crate::math::rng::Pcg32::new(1, 2);
    for _ in 0..200 {
        let s = light.sample_li(&geometry, REFERENCE, Vec2::new(rng.next_f32(), rng.next_f32())).unwrap();
        let Shape::Disk(d) = geometry.shapes[2] else { unreachable!() };
        let u = d.surface(s.p).uv.x;
        let want = if u < 0.5 { Rgb::new(2.0, 0.0, 0.0) } else { Rgb::new(0.0, 0.0, 1.0) };
        assert_eq!(s.li, want);
        seen[usize::from(u >= 0.5)] = true;
    }
    assert!(seen[0] && seen[1]);
    // Power uses the texture's average: (4 + 2)/2 channels' luminance, times area, π and two sides.
    let avg = crate::math::luminance(Rgb::new(2.0, 0.0, 1.0)) * 0.5;
    let want = avg * geometry.area(2) * std::f32::consts::PI * 2.0;
    assert!((light.power(&geometry) - want).abs() < 1e-4 * want);
}

#[test]
fn emission_sampling_is_consistent_and_carries_the_emitted_power() {
    use std::f64::consts::PI;
    let geometry = emitter_geometry();
    let sphere = SceneSphere { center: Vec3::new(0.2, 0.1, 0.0), radius: 5.0 };
    let area = |prim: u32, l: f32, two_sided: bool| {
        Light::Area(AreaLight { prim, radiance: Rgb::splat(l).into(), scale: 1.0, two_sided })
    };
    let a = |prim: u32| f64::from(geometry.area(prim));
    let r2 = 25.0;
    let cases: Vec<(&str, Light, f64)> = vec![
        ("triangle", area(0, 2.0, false), PI * a(0) * 2.0),
        ("disk two-sided", area(2, 1.0, true), 2.0 * PI * a(2)),
        ("sphere", area(1, 1.5, false), PI * a(1) * 1.5),
        ("point", Light::Point(PointLight { position: Vec3::ONE, intensity: Rgb::splat(3.0) }), 4.0 * PI * 3.0),
        (
            "spot",
            Light::Spot(SpotLight::new(Vec3::ZERO, Vec3::Z, Rgb::ONE, 30.0, 0.0)),
            2.0 * PI * (1.0 - (PI / 6.0).cos()),
        ),
        ("distant", Light::Distant(DistantLight { to_light: Vec3::Y, radiance: Rgb::splat(2.0) }), PI * r2 * 2.0),
        ("infinite", Light::Infinite(InfiniteLight::uniform(Rgb::ONE)), 4.0 * PI * PI * r2),
    ];
    let mut rng = crate::math::rng::Pcg32::new(12, 1);
    for (name, light, want) in cases {
        let n = 200_000;
        let (mut sum, mut sum2) = (0.0f64, 0.0f64);
        for _ in 0..n {
            let u1 = Vec2::new(rng.next_f32(), rng.next_f32());
            let u2 = Vec2::new(rng.next_f32(), rng.next_f32());
            let Some(s) = light.sample_le(&geometry, sphere, u1, u2) else { continue };
            let cos = if s.n == Vec3::ZERO { 1.0 } else { s.n.dot(s.ray.d).abs() };
            let v = f64::from(crate::math::luminance(s.le) * cos / (s.pdf_pos * s.pdf_dir));
            sum += v;
            sum2 += v * v;
            let (pp, pd) = light.pdf_le(&geometry, sphere, s.ray.d, s.n);
            if !light.is_delta_position() {
                assert!((pp - s.pdf_pos).abs() <= 1e-3 * s.pdf_pos, "{name}: pdf_pos {pp} vs {}", s.pdf_pos);
            }
            if !light.is_delta_direction() {
                assert!((pd - s.pdf_dir).abs() <= 1e-3 * s.pdf_dir, "{name}: pdf_dir {pd} vs {}", s.pdf_dir);
            }
        }
        let mean = sum / f64::from(n);
        let se = ((sum2 / f64::from(n) - mean * mean).max(0.0) / f64::from(n)).sqrt();
        assert!((mean - want).abs() < 4.0 * se + 1e-3 * want, "{name}: power {mean} ± {se}, expected {want}");
    }
}

/// The inverse mappings give numbers that emit the same ray again (area lights on triangles,
/// one- and two-sided, point and spot lights), choose the same light and the same point for
/// next-event estimation; shapes and lights without one give `None`.
#[test]
fn inverted_emission_samples_emit_the_same_ray() {
    let geometry = emitter_geometry();
    let sphere = SceneSphere { center: Vec3::ZERO, radius: 5.0 };
    let area = |prim: u32, two_sided: bool| Light::Area(AreaLight { two_sided, ..light_on(prim) });
    let lights = [
        area(0, false),
        area(0, true),
        Light::Point(PointLight { position: Vec3::ONE, intensity: Rgb::ONE }),
        Light::Spot(SpotLight::new(Vec3::ZERO, Vec3::new(0.3, 1.0, 0.2), Rgb::ONE, 25.0, 5.0)),
    ];
    let mut rng = crate::math::rng::Pcg32::new(13, 1);
    let mut next = || Vec2::new(rng.next_f32(), rng.next_f32());
    for (i, light) in lights.iter().enumerate() {
        let mut flipped = 0;
        for _ in 0..5000 {
            let (u_pos, u_dir) = (next(), next());
            let Some(s) = light.sample_le(&geometry, sphere, u_pos, u_dir) else { continue };
            let (pos, dir) = light.sample_le_inverse(&geometry, s.ray.o, s.ray.d).expect("invertible");
            let again = light.sample_le(&geometry, sphere, pos.unwrap_or(next()), dir).expect("emits again");
            assert!((again.ray.o - s.ray.o).length() < 1e-4, "light {i}: {} vs {}", again.ray.o, s.ray.o);
            assert!((again.ray.d - s.ray.d).length() < 1e-3, "light {i}: {} vs {}", again.ray.d, s.ray.d);
            flipped += usize::from(s.n.dot(s.ray.d) < 0.0);
            if let Light::Area(_) = light {
                let q = light.sample_li(&geometry, REFERENCE, u_pos).expect("seen");
                let u = light.sample_li_inverse(&geometry, q.p).expect("triangle").expect("a sample");
                let back = light.sample_li(&geometry, REFERENCE, u).expect("seen again");
                assert!((back.p - q.p).length() < 1e-4);
            }
        }
        // The two-sided light was inverted on both sides.
        assert_eq!(flipped > 500, i == 1, "light {i}: {flipped} emitted below the normal");
    }
    assert!(area(1, false).sample_le_inverse(&geometry, Vec3::ZERO, Vec3::Z).is_none());
    assert!(area(1, false).sample_li_inverse(&geometry, Vec3::ZERO).is_none());
    let sampler = LightSampler::new(&[1.0, 3.0, 0.0, 2.0]);
    for light in [0, 1, 3] {
        let (lo, hi) = sampler.interval(light);
        assert!(hi > lo);
        for f in [0.0, 0.3, 0.999] {
            assert_eq!(sampler.sample(lo + (hi - lo) * f).unwrap().0, light);
        }
    }
}
